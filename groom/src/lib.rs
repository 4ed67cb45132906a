//! The groom data model every part of groombake shares.
//!
//! A [`Groom`] is a set of strands stored as flat arrays: all points one after
//! another, and the number of points of each strand. Named attributes hang off
//! vertices or strands; optional [`Frame`]s hold time samples of the points.
//! Coordinates stay in the units and up axis the source file uses, recorded in
//! [`Groom::units`] and [`Groom::up_axis`]; [`Groom::convert_to`] changes them.

mod atomic;
mod attributes;
pub mod curves;
pub mod guides;
pub mod interpolate;
pub mod math;
pub mod source_prims;
mod units;
mod validate;

pub use atomic::AtomicFile;
pub use attributes::{Attribute, AttributeValues, Scope};
pub use units::{Units, UpAxis, ALEMBIC_UNITS_KEY};
pub use validate::{Problem, ProblemKind};

use std::path::PathBuf;

/// How the points of a strand are to be interpolated. Importers keep the
/// control points of cubic curves as they are and record the basis here.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CurveBasis {
    #[default]
    Linear,
    Bezier,
    Bspline,
    CatmullRom,
    Hermite,
    Power,
}

impl CurveBasis {
    pub fn name(self) -> &'static str {
        match self {
            CurveBasis::Linear => "linear",
            CurveBasis::Bezier => "bezier",
            CurveBasis::Bspline => "bspline",
            CurveBasis::CatmullRom => "catmull_rom",
            CurveBasis::Hermite => "hermite",
            CurveBasis::Power => "power",
        }
    }
}

/// The `Provenance::metadata` key where a reader lists the curves objects
/// it read, one per line: the object's (composed) path, a space, its strand
/// count.
pub const PRIMS_KEY: &str = "prims";

/// Where a groom came from.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Provenance {
    /// The file it was read from, if any.
    pub source: Option<PathBuf>,
    /// Short format name: `hair`, `data`, `obj`, `gltf`, `usd`, `abc`, `generated`, ...
    pub format: String,
    /// Free text a format carries (the `.hair` info field, an Alembic application name).
    pub info: String,
    /// Which rule of the units rule (see [`Units`]) gave [`Groom::units`]:
    /// `file` (the file records them), `application <name>` (an Alembic
    /// archive's writing application), `format` (the convention of a format
    /// that records none), `stated` (`--source-units` or `[groom] units`).
    pub units_source: String,
    /// Facts about the source file a reader keeps so that its writer can
    /// reproduce the file exactly (header fields the groom has no place
    /// for), keyed `<format>.<field>`. A writer honours them only while the
    /// groom still matches what they describe.
    pub metadata: std::collections::BTreeMap<String, String>,
    /// What the reader could not keep of the file (a prim it skipped, a
    /// primvar it dropped), one line each naming it (not the file, which
    /// the caller names): `convert`, `inspect` and the bake print them as
    /// warnings, and `--strict` refuses them.
    pub losses: Vec<String>,
}

/// One time sample of every point of the groom (same topology as the groom).
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Seconds.
    pub time: f64,
    pub points: Vec<[f32; 3]>,
    /// The attributes that change over time (a bake's bond rates and
    /// wetness), with their values at this frame, each as the groom's
    /// attribute of the same name would be (scope and size). Empty for
    /// attributes that hold still: those are the groom's, written once.
    pub attributes: Vec<Attribute>,
}

impl Frame {
    /// The frame's value of a time-varying attribute.
    pub fn attribute(&self, name: &str) -> Option<&Attribute> {
        self.attributes.iter().find(|a| a.name == name)
    }
}

/// A set of strands with their attributes and optional animation.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Groom {
    /// Number of points of each strand, in order.
    pub strand_vertex_counts: Vec<u32>,
    /// Every point of every strand, strand after strand (the rest or first pose).
    pub points: Vec<[f32; 3]>,
    /// Named attributes, each with one value per vertex or per strand.
    pub attributes: Vec<Attribute>,
    /// Time samples of the points; empty for a static groom.
    pub frames: Vec<Frame>,
    pub units: Units,
    pub up_axis: UpAxis,
    pub basis: CurveBasis,
    pub provenance: Provenance,
}

impl Groom {
    /// The groom's frames, or its rest pose as one frame at time 0 when it
    /// has none (a still groom in a sequence of animated ones).
    pub fn frames_or_rest(&self) -> std::borrow::Cow<'_, [Frame]> {
        if self.frames.is_empty() {
            std::borrow::Cow::Owned(vec![Frame {
                time: 0.0,
                points: self.points.clone(),
                attributes: Vec::new(),
            }])
        } else {
            std::borrow::Cow::Borrowed(&self.frames)
        }
    }

    /// A groom from strands given as separate point lists.
    pub fn from_strands<I, S>(strands: I) -> Groom
    where
        I: IntoIterator<Item = S>,
        S: AsRef<[[f32; 3]]>,
    {
        let mut groom = Groom::default();
        for strand in strands {
            let strand = strand.as_ref();
            groom.strand_vertex_counts.push(strand.len() as u32);
            groom.points.extend_from_slice(strand);
        }
        groom
    }

    pub fn strand_count(&self) -> usize {
        self.strand_vertex_counts.len()
    }

    pub fn vertex_count(&self) -> usize {
        self.points.len()
    }

    /// Index of the first point of each strand, plus the total at the end
    /// (`strand_count() + 1` entries).
    pub fn strand_offsets(&self) -> Vec<usize> {
        let mut offsets = Vec::with_capacity(self.strand_vertex_counts.len() + 1);
        let mut total = 0usize;
        offsets.push(0);
        for &count in &self.strand_vertex_counts {
            total += count as usize;
            offsets.push(total);
        }
        offsets
    }

    /// The points of each strand. Stops early if the counts overrun the points
    /// (a groom that does not pass [`Groom::validate`]).
    pub fn strands(&self) -> impl Iterator<Item = &[[f32; 3]]> + '_ {
        let mut start = 0usize;
        self.strand_vertex_counts.iter().map_while(move |&count| {
            let end = start.checked_add(count as usize)?;
            let strand = self.points.get(start..end)?;
            start = end;
            Some(strand)
        })
    }

    pub fn attribute(&self, name: &str) -> Option<&Attribute> {
        self.attributes.iter().find(|a| a.name == name)
    }

    pub fn attribute_mut(&mut self, name: &str) -> Option<&mut Attribute> {
        self.attributes.iter_mut().find(|a| a.name == name)
    }

    /// Adds an attribute, replacing one of the same name.
    pub fn set_attribute(&mut self, attribute: Attribute) {
        match self.attribute_mut(&attribute.name) {
            Some(existing) => *existing = attribute,
            None => self.attributes.push(attribute),
        }
    }

    pub fn remove_attribute(&mut self, name: &str) -> Option<Attribute> {
        let index = self.attributes.iter().position(|a| a.name == name)?;
        Some(self.attributes.remove(index))
    }

    /// Axis-aligned bounds `(min, max)` of the points and every frame; `None`
    /// when there are no points.
    pub fn bounds(&self) -> Option<([f32; 3], [f32; 3])> {
        let all = self
            .points
            .iter()
            .chain(self.frames.iter().flat_map(|f| f.points.iter()));
        bounds_of(all)
    }

    /// The groom of only the given strands (in that order), with their
    /// points, frames and attribute values. Indices past the last strand
    /// are skipped.
    pub fn select_strands(&self, strands: &[usize]) -> Groom {
        let offsets = self.strand_offsets();
        let ranges: Vec<std::ops::Range<usize>> = strands
            .iter()
            .filter(|&&s| s + 1 < offsets.len())
            .map(|&s| offsets[s]..offsets[s + 1])
            .collect();
        let kept: Vec<usize> = strands
            .iter()
            .copied()
            .filter(|&s| s + 1 < offsets.len())
            .collect();
        let pick = |points: &[[f32; 3]]| -> Vec<[f32; 3]> {
            ranges
                .iter()
                .flat_map(|r| points.get(r.clone()).unwrap_or(&[]).iter().copied())
                .collect()
        };
        let strand_ranges: Vec<std::ops::Range<usize>> = kept.iter().map(|&s| s..s + 1).collect();
        let select = |attributes: &[Attribute]| -> Vec<Attribute> {
            attributes
                .iter()
                .map(|a| Attribute {
                    name: a.name.clone(),
                    scope: a.scope,
                    values: match a.scope {
                        Scope::Vertex => a.values.select(&ranges),
                        Scope::Strand => a.values.select(&strand_ranges),
                    },
                })
                .collect()
        };
        let attributes = select(&self.attributes);
        Groom {
            strand_vertex_counts: kept.iter().map(|&s| self.strand_vertex_counts[s]).collect(),
            points: pick(&self.points),
            attributes,
            frames: self
                .frames
                .iter()
                .map(|f| Frame {
                    time: f.time,
                    points: pick(&f.points),
                    attributes: select(&f.attributes),
                })
                .collect(),
            units: self.units,
            up_axis: self.up_axis,
            basis: self.basis,
            provenance: self.provenance.clone(),
        }
    }

    /// The groom with only the pose of frame `index` as its points, no animation.
    pub fn at_frame(&self, index: usize) -> Option<Groom> {
        let frame = self.frames.get(index)?;
        let mut groom = self.clone();
        groom.points = frame.points.clone();
        for attribute in &frame.attributes {
            groom.set_attribute(attribute.clone());
        }
        groom.frames.clear();
        Some(groom)
    }

    /// Rescales and rotates the points (and every frame) to `units` and `up`.
    /// Width-like attributes (named `width`, `widths` or `groom_width`) scale
    /// with the length unit.
    pub fn convert_to(&mut self, units: Units, up: UpAxis) {
        let scale = (self.units.meters_per_unit / units.meters_per_unit) as f32;
        let from = (self.units, self.up_axis);
        convert_points(&mut self.points, from, (units, up));
        for frame in &mut self.frames {
            convert_points(&mut frame.points, from, (units, up));
        }
        if scale != 1.0 {
            for attribute in &mut self.attributes {
                if units::is_length_attribute(&attribute.name) {
                    attribute.values.scale(scale);
                }
            }
        }
        self.units = units;
        self.up_axis = up;
    }
}

/// Rescales and rotates points from one units/up-axis convention to another
/// (a frame streamed to an exporter, or the points of a groom).
pub fn convert_points(points: &mut [[f32; 3]], from: (Units, UpAxis), to: (Units, UpAxis)) {
    let scale = (from.0.meters_per_unit / to.0.meters_per_unit) as f32;
    if scale != 1.0 || from.1 != to.1 {
        for p in points {
            *p = to.1.from_y_up(from.1.to_y_up(*p)).map(|c| c * scale);
        }
    }
}

/// Bounds `(min, max)` of a set of points; `None` when empty.
pub fn bounds_of<'a>(
    points: impl IntoIterator<Item = &'a [f32; 3]>,
) -> Option<([f32; 3], [f32; 3])> {
    let mut iter = points.into_iter();
    let first = *iter.next()?;
    let mut min = first;
    let mut max = first;
    for p in iter {
        for k in 0..3 {
            min[k] = min[k].min(p[k]);
            max[k] = max[k].max(p[k]);
        }
    }
    Some((min, max))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_strands() -> Groom {
        Groom::from_strands([
            vec![[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![[1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [1.0, 2.0, 0.0]],
        ])
    }

    #[test]
    fn strands_follow_counts() {
        let groom = two_strands();
        let strands: Vec<_> = groom.strands().collect();
        assert_eq!(strands.len(), 2);
        assert_eq!(
            strands[1],
            &[[1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [1.0, 2.0, 0.0]]
        );
        assert_eq!(groom.strand_offsets(), vec![0, 2, 5]);
    }

    #[test]
    fn bounds_cover_frames() {
        let mut groom = two_strands();
        let mut moved = groom.points.clone();
        moved[0] = [-5.0, 0.0, 0.0];
        groom.frames.push(Frame {
            time: 0.0,
            points: moved,
            attributes: Vec::new(),
        });
        assert_eq!(groom.bounds(), Some(([-5.0, 0.0, 0.0], [1.0, 2.0, 0.0])));
    }

    #[test]
    fn convert_cm_z_up_to_m_y_up() {
        let mut groom = Groom::from_strands([vec![[1.0, 2.0, 3.0]]]);
        groom.units = Units::CENTIMETERS;
        groom.up_axis = UpAxis::Z;
        groom.set_attribute(Attribute::new("width", AttributeValues::Float(vec![2.0])));
        groom.convert_to(Units::METERS, UpAxis::Y);
        let p = groom.points[0];
        // Z-up (x, y, z) is Y-up (x, z, -y).
        assert!(
            (p[0] - 0.01).abs() < 1e-7 && (p[1] - 0.03).abs() < 1e-7 && (p[2] + 0.02).abs() < 1e-7
        );
        assert_eq!(
            groom.attribute("width").unwrap().values,
            AttributeValues::Float(vec![0.02])
        );
    }
}
