//! USD export: `BasisCurves` prims under an `Xform` root, written as text
//! (`.usda`, `usda`) or as a binary crate file (`.usdc`/`.usd`,
//! `crate_writer`). One `Strands` prim; a groom with guides and render
//! strands gets `guides` and `render`, and one that mixes curve types or
//! wraps one prim per `PrimKey` (static and animated alike).
//!
//! Both writers take the same `CurvesScene`: the stage metadata and every
//! property of the curves prim, sorted by name so the bytes never depend on
//! the order attributes were added in.

mod crate_writer;
mod frame_values;
mod guide_cache;
mod structure;
mod usda;

use crate::{AnimationOptions, ExportError, FrameWriter};
use groom::{AttributeValues, CurveBasis, Frame, Groom, Scope};
use std::borrow::Cow;
use std::ops::Range;
use std::path::Path;

/// Name of the root `Xform` (the stage's `defaultPrim`).
pub(crate) const ROOT_PRIM: &str = "Groom";
/// Name of the `BasisCurves` prim under the root.
pub(crate) const CURVES_PRIM: &str = "Strands";
/// The prims of a groom with guides and render strands (`groom_guide` 1
/// and 0), in this order.
pub(crate) const GUIDES_PRIM: &str = "guides";
pub(crate) const RENDER_PRIM: &str = "render";

/// Frames per second used when a groom with frames is written through
/// [`crate::write`], which has no [`AnimationOptions`].
const DEFAULT_FPS: f64 = 24.0;

/// USD's two encodings: `.usda` is text, `.usdc` and `.usd` are crate files.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    Text,
    Crate,
}

/// What the strands of one `BasisCurves` prim share: curve type and basis,
/// and wrap. Strands that differ in any field go to different prims, so
/// nothing is converted on the way out; a further key (guide or render
/// hair) is one more field here and one more part of [`PrimKey::name`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) struct PrimKey {
    /// Guides (0) before render strands (1) in a groom that holds both
    /// (per-strand `groom_guide`); 0 for any other groom.
    pub role: u8,
    /// The per-strand `curve_basis` code the importers give grooms that
    /// mix bases (0 linear, 1 bezier, 2 bspline, 3 catmullRom, 4 hermite,
    /// 5 power).
    pub basis_code: i32,
    /// The per-strand `curve_wrap` code of grooms that mix wraps (0
    /// nonperiodic, 1 periodic, 2 pinned).
    pub wrap_code: i32,
}

const BASES: [CurveBasis; 6] = [
    CurveBasis::Linear,
    CurveBasis::Bezier,
    CurveBasis::Bspline,
    CurveBasis::CatmullRom,
    CurveBasis::Hermite,
    CurveBasis::Power,
];
const WRAPS: [&str; 3] = ["nonperiodic", "periodic", "pinned"];

impl PrimKey {
    fn basis(self) -> Option<CurveBasis> {
        usize::try_from(self.basis_code)
            .ok()
            .and_then(|i| BASES.get(i).copied())
    }

    fn wrap(self) -> Option<&'static str> {
        usize::try_from(self.wrap_code)
            .ok()
            .and_then(|i| WRAPS.get(i).copied())
    }

    /// The prim's name: `guides` or `render` for a groom split in roles,
    /// else `Strands`; then, for a groom that mixes curves, `_<basis>` and
    /// `_<wrap>` unless nonperiodic.
    fn name(self, split_roles: bool, mixed_curves: bool) -> String {
        let stem = match (split_roles, self.role) {
            (false, _) => CURVES_PRIM,
            (true, 0) => GUIDES_PRIM,
            (true, _) => RENDER_PRIM,
        };
        if !mixed_curves {
            return stem.to_string();
        }
        let basis = match self.basis() {
            Some(CurveBasis::CatmullRom) => "catmullRom".to_string(),
            Some(basis) => basis.name().to_string(),
            None => format!("basis{}", self.basis_code),
        };
        match self.wrap() {
            Some("nonperiodic") => format!("{stem}_{basis}"),
            Some(wrap) => format!("{stem}_{basis}_{wrap}"),
            None => format!("{stem}_{basis}_wrap{}", self.wrap_code),
        }
    }
}

/// Whether a static or animated export of `groom` writes the prims it was
/// read from, at their paths (`structure`).
pub fn keeps_source_prims(groom: &Groom) -> bool {
    structure::writable(groom)
}

/// A per-strand code attribute (`curve_basis`, `curve_wrap`), if the groom
/// has one of the right size whose every code names a kind. Any other
/// attribute of that name (a float, per vertex, an unknown code from a
/// damaged or foreign file) is not a curve kind: it is written as the
/// primvar it is, never turned into prims (an unknown code made a prim
/// name USD refuses, and its values were lost).
fn strand_codes<'g>(groom: &'g Groom, name: &str) -> Option<&'g [i32]> {
    let kinds = if name == "curve_wrap" {
        WRAPS.len()
    } else {
        BASES.len()
    };
    match groom.attribute(name).map(|a| (&a.values, a.scope)) {
        Some((AttributeValues::Int(codes), Scope::Strand))
            if codes.len() == groom.strand_count()
                && codes
                    .iter()
                    .all(|&c| usize::try_from(c).is_ok_and(|c| c < kinds)) =>
        {
            Some(codes)
        }
        _ => None,
    }
}

/// The strands of each prim, one group per [`PrimKey`]: guides before
/// render strands, otherwise in the order of each group's first strand.
/// Also says whether roles and curve kinds were split (for the names).
fn prim_groups(groom: &Groom) -> (Vec<(PrimKey, Vec<usize>)>, bool, bool) {
    let bases = strand_codes(groom, "curve_basis");
    let wraps = strand_codes(groom, "curve_wrap");
    let roles = groom.guide_flags().filter(|_| groom.has_render_split());
    let basis_default = BASES.iter().position(|&b| b == groom.basis).unwrap_or(0) as i32;
    let wrap_default = WRAPS.iter().position(|&w| w == wrap_of(groom)).unwrap_or(0) as i32;
    let mut groups: Vec<(PrimKey, Vec<usize>)> = Vec::new();
    for strand in 0..groom.strand_count() {
        let key = PrimKey {
            role: roles.as_ref().map_or(0, |r| u8::from(!r[strand])),
            basis_code: bases.map_or(basis_default, |c| c[strand]),
            wrap_code: wraps.map_or(wrap_default, |c| c[strand]),
        };
        match groups.iter_mut().find(|(k, _)| *k == key) {
            Some((_, strands)) => strands.push(strand),
            None => groups.push((key, vec![strand])),
        }
    }
    groups.sort_by_key(|(key, _)| key.role);
    let mixed_curves = (bases.is_some() || wraps.is_some())
        && groups.iter().any(|(k, _)| {
            (k.basis_code, k.wrap_code) != (groups[0].0.basis_code, groups[0].0.wrap_code)
        });
    (groups, roles.is_some(), mixed_curves)
}

/// Writes a static groom, or an animated one when it has frames.
pub fn write(path: &Path, groom: &Groom, encoding: Encoding) -> Result<(), ExportError> {
    if groom.frames.is_empty() {
        let scene = CurvesScene::new(path, groom, None)?;
        return match encoding {
            Encoding::Text => usda::write_static(path, &scene),
            Encoding::Crate => crate_writer::write_static(path, &scene),
        };
    }
    let options = AnimationOptions {
        fps: DEFAULT_FPS,
        frame_count: groom.frames.len(),
    };
    let mut writer = animated(path, groom, options, encoding)?;
    for frame in &groom.frames {
        writer.write_frame(frame)?;
    }
    writer.finish()
}

/// Writes grooms that follow each other in time with different topologies
/// (`importers::read_sequence`), in time order: one curves prim whose
/// `curveVertexCounts`, `points`, `extent`, `widths` and primvars are time
/// samples at every frame of every groom (a groom without frames is one
/// sample at its time 0). The grooms must have the same attributes and one
/// curve type and wrap: a prim cannot split into several over time.
pub fn write_sequence(
    path: &Path,
    grooms: &[Groom],
    encoding: Encoding,
) -> Result<(), ExportError> {
    let invalid = |message: String| ExportError::Invalid {
        file: path.to_path_buf(),
        message,
    };
    let Some(first) = grooms.first() else {
        return Err(invalid("a sequence needs at least one groom".into()));
    };
    let mut scene = CurvesScene::new(path, first, Some(DEFAULT_FPS))?;
    if scene.prims.len() != 1 {
        // One source prim keeps its path; several are written as one.
        scene = CurvesScene::new_with(path, first, Some(DEFAULT_FPS), false)?;
    }
    if scene.prims.len() != 1 {
        return Err(ExportError::Unsupported {
            file: path.to_path_buf(),
            message: "curve counts that change over time are written as one curves prim; \
                      this groom needs several (curve types, wraps or guide and render strands)"
                .into(),
        });
    }
    let mut sampled: Vec<(String, Vec<PropertyValue>)> = scene.prims[0]
        .properties
        .iter()
        .filter(|p| !matches!(p.value, PropertyValue::Token(_)))
        .map(|p| (p.name.clone(), Vec::new()))
        .collect();
    let mut codes: Vec<f64> = Vec::new();
    for groom in grooms {
        let prim = curves_prim(
            path,
            groom,
            CURVES_PRIM.to_string(),
            std::iter::once(0..groom.points.len()).collect(),
            std::iter::once(0..groom.strand_count()).collect(),
        )?;
        let shape = |p: &CurvesPrim| -> Vec<(String, &'static str)> {
            p.properties
                .iter()
                .map(|q| (q.name.clone(), q.type_name))
                .collect()
        };
        if shape(&prim) != shape(&scene.prims[0]) {
            return Err(invalid(
                "the grooms of a sequence must have the same attributes".into(),
            ));
        }
        for frame in groom.frames_or_rest().iter() {
            scene.check_frame_of(path, frame, groom.points.len())?;
            let code = time_code(frame.time, DEFAULT_FPS);
            if codes.last().is_some_and(|&last| code <= last) {
                return Err(invalid(format!(
                    "frame time codes must increase (time code {code})"
                )));
            }
            codes.push(code);
            for (name, values) in &mut sampled {
                let value = match name.as_str() {
                    "points" => PropertyValue::Float3s(frame.points.clone()),
                    "extent" => PropertyValue::Float3s(
                        extent_of(&frame.points, prim.extent_padding).to_vec(),
                    ),
                    _ => prim
                        .properties
                        .iter()
                        .find(|p| &p.name == name)
                        .map(|p| p.value.clone())
                        .ok_or_else(|| invalid(format!("{name} is missing")))?,
                };
                values.push(value);
            }
        }
    }
    scene.codes = codes;
    scene.prims[0].sampled = sampled;
    match encoding {
        Encoding::Text => usda::write_static(path, &scene),
        Encoding::Crate => crate_writer::write_static(path, &scene),
    }
}

/// Starts an animated export; frames are streamed to the file.
pub fn animated(
    path: &Path,
    groom: &Groom,
    options: AnimationOptions,
    encoding: Encoding,
) -> Result<Box<dyn FrameWriter>, ExportError> {
    if !(options.fps.is_finite() && options.fps > 0.0) {
        return Err(ExportError::Invalid {
            file: path.to_path_buf(),
            message: format!("frames per second must be positive, not {}", options.fps),
        });
    }
    let scene = CurvesScene::new(path, groom, Some(options.fps))?;
    match encoding {
        Encoding::Text => Ok(Box::new(usda::AnimatedUsda::create(path, scene)?)),
        Encoding::Crate => Ok(Box::new(crate_writer::AnimatedCrate::create(path, scene)?)),
    }
}

pub use guide_cache::guide_cache;

/// The value of one property, in the element type USD stores.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum PropertyValue {
    Token(&'static str),
    Ints(Vec<i32>),
    Floats(Vec<f32>),
    Float2s(Vec<[f32; 2]>),
    Float3s(Vec<[f32; 3]>),
    Int3s(Vec<[i32; 3]>),
}

/// One attribute of the curves prim.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Property {
    /// Full name, e.g. `points` or `primvars:wetness`.
    pub name: String,
    /// USD type name, e.g. `point3f[]`, `texCoord2f[]`, `token`.
    pub type_name: &'static str,
    pub uniform: bool,
    pub interpolation: Option<&'static str>,
    pub value: PropertyValue,
}

/// Stage time metadata of an animated export.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Timing {
    pub fps: f64,
}

/// One `BasisCurves` prim under the root.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct CurvesPrim {
    pub name: String,
    /// The names of its `Xform` parents, root first (`Groom` for a groom
    /// written flat; the source's for one whose prims are kept).
    pub parents: Vec<String>,
    /// Groom attributes this prim leaves out (a source prim did not have
    /// them, or they stand for the prims themselves): not written, and
    /// skipped in frames.
    pub omitted: Vec<String>,
    /// Sorted by name; includes `points` and `extent` of the rest pose.
    pub properties: Vec<Property>,
    /// The groom's vertices this prim holds, in order (a frame's points
    /// for this prim are these ranges of the frame).
    pub vertex_ranges: Vec<Range<usize>>,
    /// The groom's strands this prim holds, in order (for per-strand
    /// values of a frame's attributes).
    pub strand_ranges: Vec<Range<usize>>,
    /// Each groom attribute's property: (attribute name, property name).
    pub attribute_properties: Vec<(String, String)>,
    /// Half the largest width: the extent grows by it, as USD's own
    /// `UsdGeomCurves::ComputeExtent` does.
    pub extent_padding: f32,
    /// Properties written as time samples only (no default), with one
    /// value per [`CurvesScene::codes`] entry: a groom sequence whose
    /// topology changes over time ([`write_sequence`]).
    pub sampled: Vec<(String, Vec<PropertyValue>)>,
    /// Written at rest only, with no time samples: the render hair of a
    /// guide cache ([`guide_cache()`]), which frames do not give.
    pub rest_only: bool,
}

impl CurvesPrim {
    /// The time samples of a property written as samples only.
    pub fn samples_of(&self, name: &str) -> Option<&[PropertyValue]> {
        self.sampled
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, values)| values.as_slice())
    }

    /// This prim's points of a pose of the whole groom.
    pub fn points_of<'a>(&self, points: &'a [[f32; 3]]) -> Cow<'a, [[f32; 3]]> {
        match &self.vertex_ranges[..] {
            [range] => Cow::Borrowed(points.get(range.clone()).unwrap_or(&[])),
            ranges => Cow::Owned(
                ranges
                    .iter()
                    .flat_map(|r| points.get(r.clone()).unwrap_or(&[]).iter().copied())
                    .collect(),
            ),
        }
    }

    /// The extent of this prim's part of a pose.
    pub fn extent(&self, points: &[[f32; 3]]) -> [[f32; 3]; 2] {
        extent_of(points, self.extent_padding)
    }
}

/// Everything both writers put in the file apart from the time samples.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct CurvesScene {
    pub meters_per_unit: f64,
    pub up_axis: &'static str,
    pub timing: Option<Timing>,
    /// One `Strands` prim, or `guides` and `render` when the groom holds
    /// both (per-strand `groom_guide`).
    pub prims: Vec<CurvesPrim>,
    /// Vertex count of the groom (every frame must have as many points).
    pub vertex_count: usize,
    /// Time codes of the prims' `sampled` properties (empty unless written
    /// by [`write_sequence`]).
    pub codes: Vec<f64>,
}

impl CurvesScene {
    pub fn new(path: &Path, groom: &Groom, fps: Option<f64>) -> Result<CurvesScene, ExportError> {
        Self::new_with(path, groom, fps, true)
    }

    /// The scene, with the source's prims when `keep_prims` and the groom
    /// still has them, else flat.
    fn new_with(
        path: &Path,
        groom: &Groom,
        fps: Option<f64>,
        keep_prims: bool,
    ) -> Result<CurvesScene, ExportError> {
        let (groups, split_roles, mixed_curves) = prim_groups(groom);
        let source = if keep_prims {
            structure::source_prims_of(path, groom)?
        } else {
            None
        };
        let prims = if let Some(prims) = source {
            prims
        } else if groups.len() <= 1 {
            vec![curves_prim(
                path,
                groom,
                CURVES_PRIM.to_string(),
                std::iter::once(0..groom.points.len()).collect(),
                std::iter::once(0..groom.strand_count()).collect(),
            )?]
        } else {
            let offsets = groom.strand_offsets();
            let mut prims = Vec::with_capacity(groups.len());
            for (key, strands) in groups {
                let mut ranges: Vec<Range<usize>> = Vec::new();
                let mut strand_ranges: Vec<Range<usize>> = Vec::new();
                for &s in &strands {
                    let range = offsets[s]..offsets[s + 1];
                    match ranges.last_mut() {
                        Some(last) if last.end == range.start => last.end = range.end,
                        _ => ranges.push(range),
                    }
                    match strand_ranges.last_mut() {
                        Some(last) if last.end == s => last.end = s + 1,
                        _ => strand_ranges.push(s..s + 1),
                    }
                }
                let mut part = groom.select_strands(&strands);
                if mixed_curves {
                    part.basis = key.basis().unwrap_or(groom.basis);
                    // The codes the prims now say; an attribute of the
                    // same name that is no code stays.
                    if strand_codes(groom, "curve_basis").is_some() {
                        part.remove_attribute("curve_basis");
                    }
                    if strand_codes(groom, "curve_wrap").is_some() {
                        part.remove_attribute("curve_wrap");
                    }
                    let wrap = key.wrap().unwrap_or("nonperiodic");
                    part.provenance
                        .metadata
                        .insert("usd.wrap".into(), wrap.into());
                }
                let name = key.name(split_roles, mixed_curves);
                prims.push(curves_prim(path, &part, name, ranges, strand_ranges)?);
            }
            prims
        };
        Ok(CurvesScene {
            meters_per_unit: groom.units.meters_per_unit,
            up_axis: groom.up_axis.name(),
            timing: fps.map(|fps| Timing { fps }),
            prims,
            vertex_count: groom.points.len(),
            codes: Vec::new(),
        })
    }

    /// Drops the property values once a writer has written them, keeping
    /// names, types and tokens: an animated export then holds no copy of
    /// the groom's arrays while frames stream.
    pub fn forget_values(&mut self) {
        for property in self.prims.iter_mut().flat_map(|p| &mut p.properties) {
            match &mut property.value {
                PropertyValue::Token(_) => {}
                PropertyValue::Ints(v) => *v = Vec::new(),
                PropertyValue::Floats(v) => *v = Vec::new(),
                PropertyValue::Float2s(v) => *v = Vec::new(),
                PropertyValue::Float3s(v) => *v = Vec::new(),
                PropertyValue::Int3s(v) => *v = Vec::new(),
            }
        }
    }

    /// Checks a streamed frame against the groom's topology.
    pub fn check_frame(&self, path: &Path, frame: &Frame) -> Result<(), ExportError> {
        self.check_frame_of(path, frame, self.vertex_count)
    }

    /// Checks a frame of a groom of `vertex_count` points.
    fn check_frame_of(
        &self,
        path: &Path,
        frame: &Frame,
        vertex_count: usize,
    ) -> Result<(), ExportError> {
        if frame.points.len() != vertex_count {
            return Err(ExportError::Invalid {
                file: path.to_path_buf(),
                message: format!(
                    "frame at {} s has {} points, the groom has {}",
                    frame.time,
                    frame.points.len(),
                    vertex_count
                ),
            });
        }
        if !frame.time.is_finite() || frame.points.iter().flatten().any(|c| !c.is_finite()) {
            return Err(ExportError::Invalid {
                file: path.to_path_buf(),
                message: format!("frame at {} s has a value that is not finite", frame.time),
            });
        }
        Ok(())
    }
}

/// The properties of one curves prim holding `groom` (all of a groom, or
/// its guides or render strands).
fn curves_prim(
    path: &Path,
    groom: &Groom,
    name: String,
    vertex_ranges: Vec<Range<usize>>,
    strand_ranges: Vec<Range<usize>>,
) -> Result<CurvesPrim, ExportError> {
    let invalid = |message: String| ExportError::Invalid {
        file: path.to_path_buf(),
        message,
    };
    let (curve_type, basis) = match groom.basis {
        CurveBasis::Linear => ("linear", None),
        CurveBasis::Bezier => ("cubic", Some("bezier")),
        CurveBasis::Bspline => ("cubic", Some("bspline")),
        CurveBasis::CatmullRom => ("cubic", Some("catmullRom")),
        other => {
            return Err(ExportError::Unsupported {
                file: path.to_path_buf(),
                message: format!("USD BasisCurves have no {} basis", other.name()),
            })
        }
    };
    let counts = groom
        .strand_vertex_counts
        .iter()
        .map(|&c| i32::try_from(c).map_err(|_| invalid(format!("strand of {c} points"))))
        .collect::<Result<Vec<i32>, ExportError>>()?;

    let mut properties = vec![
        token_property("type", curve_type),
        token_property("wrap", wrap_of(groom)),
        Property {
            name: "curveVertexCounts".into(),
            type_name: "int[]",
            uniform: false,
            interpolation: None,
            value: PropertyValue::Ints(counts),
        },
        Property {
            name: "points".into(),
            type_name: "point3f[]",
            uniform: false,
            interpolation: None,
            value: PropertyValue::Float3s(groom.points.clone()),
        },
    ];
    if let Some(basis) = basis {
        properties.push(token_property("basis", basis));
    }
    let mut max_width = 0.0f32;
    let mut attribute_properties = Vec::new();
    for attribute in &groom.attributes {
        let interpolation = match attribute.scope {
            Scope::Vertex => "vertex",
            Scope::Strand => "uniform",
        };
        let (name, type_name, value) = match (&attribute.name[..], &attribute.values) {
            ("width", AttributeValues::Float(v)) => {
                max_width = v.iter().fold(max_width, |m, &w| m.max(w.abs()));
                (
                    "widths".to_string(),
                    "float[]",
                    PropertyValue::Floats(v.clone()),
                )
            }
            ("root_uv", AttributeValues::Vec2(v)) => (
                "primvars:st".to_string(),
                "texCoord2f[]",
                PropertyValue::Float2s(v.clone()),
            ),
            // Guide indices are integers, as Unreal's Alembic schema and
            // groombake's Alembic writer store them (int32 x 3).
            (groom::guides::GROOM_CLOSEST_GUIDES, AttributeValues::Vec3(v)) => (
                format!("primvars:{}", groom::guides::GROOM_CLOSEST_GUIDES),
                "int3[]",
                PropertyValue::Int3s(v.iter().map(|g| g.map(|x| x.round() as i32)).collect()),
            ),
            (attribute_name, values) => {
                let name = format!("primvars:{}", identifier(attribute_name));
                let type_name = declared_type(groom, attribute_name, values);
                match values {
                    AttributeValues::Float(v) => {
                        (name, type_name, PropertyValue::Floats(v.clone()))
                    }
                    AttributeValues::Vec2(v) => {
                        (name, type_name, PropertyValue::Float2s(v.clone()))
                    }
                    AttributeValues::Vec3(v) => {
                        (name, type_name, PropertyValue::Float3s(v.clone()))
                    }
                    AttributeValues::Int(v) => (name, type_name, PropertyValue::Ints(v.clone())),
                }
            }
        };
        let name = unique_name(&properties, name);
        attribute_properties.push((attribute.name.clone(), name.clone()));
        properties.push(Property {
            name,
            type_name,
            uniform: false,
            interpolation: Some(interpolation),
            value,
        });
    }
    let extent_padding = max_width * 0.5;
    properties.push(Property {
        name: "extent".into(),
        type_name: "float3[]",
        uniform: false,
        interpolation: None,
        value: PropertyValue::Float3s(extent_of(&groom.points, extent_padding).to_vec()),
    });
    properties.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(CurvesPrim {
        name,
        parents: vec![ROOT_PRIM.to_string()],
        omitted: Vec::new(),
        properties,
        vertex_ranges,
        strand_ranges,
        attribute_properties,
        extent_padding,
        sampled: Vec::new(),
        rest_only: false,
    })
}

/// The time code of a time in seconds. Codes within 1e-9 of a whole number
/// are snapped to it, so `i / fps * fps` writes as `i`.
pub(crate) fn time_code(time: f64, fps: f64) -> f64 {
    let code = time * fps;
    let whole = code.round();
    if (code - whole).abs() < 1e-9 {
        whole
    } else {
        code
    }
}

/// The `wrap` the groom was read with (`usd.wrap` in its provenance), where
/// USD can write it for every strand; else `nonperiodic`.
fn wrap_of(groom: &Groom) -> &'static str {
    match groom
        .provenance
        .metadata
        .get("usd.wrap")
        .map(String::as_str)
    {
        Some("pinned") => "pinned",
        Some("periodic") => "periodic",
        _ => "nonperiodic",
    }
}

/// The USD type of a primvar: the one it was read with (`usd.type.<name>`
/// in the provenance) when it still fits the values, else the schema's type
/// for the names schemas define (`displayColor` is `color3f[]`), else the
/// plain type of the values.
fn declared_type(groom: &Groom, name: &str, values: &AttributeValues) -> &'static str {
    const ROLES: [&str; 11] = [
        "float[]",
        "int[]",
        "float2[]",
        "texCoord2f[]",
        "float3[]",
        "color3f[]",
        "normal3f[]",
        "vector3f[]",
        "point3f[]",
        "texCoord3f[]",
        "double[]",
    ];
    let plain = match values {
        AttributeValues::Float(_) => "float[]",
        AttributeValues::Vec2(_) => "float2[]",
        AttributeValues::Vec3(_) => "float3[]",
        AttributeValues::Int(_) => "int[]",
    };
    let fits = |type_name: &str| match values {
        AttributeValues::Float(_) => type_name == "float[]",
        AttributeValues::Vec2(_) => type_name.ends_with("2f[]"),
        AttributeValues::Vec3(_) => type_name.ends_with("3f[]"),
        AttributeValues::Int(_) => type_name == "int[]",
    };
    let recorded = groom
        .provenance
        .metadata
        .get(&format!("usd.type.{name}"))
        .and_then(|t| ROLES.iter().find(|&&r| r == t && fits(r)));
    if let Some(&type_name) = recorded {
        return type_name;
    }
    match (name, values) {
        ("displayColor", AttributeValues::Vec3(_)) => "color3f[]",
        _ => plain,
    }
}

fn token_property(name: &str, token: &'static str) -> Property {
    Property {
        name: name.into(),
        type_name: "token",
        uniform: true,
        interpolation: None,
        value: PropertyValue::Token(token),
    }
}

fn unique_name(properties: &[Property], name: String) -> String {
    let taken = |n: &str| properties.iter().any(|p| p.name == n);
    if !taken(&name) {
        return name;
    }
    (1..)
        .map(|i| format!("{name}_{i}"))
        .find(|n| !taken(n))
        .unwrap_or(name)
}

/// A valid USD identifier: letters, digits and `_`, not starting with a digit.
pub(crate) fn identifier(name: &str) -> String {
    let mut out: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if out.is_empty() || out.starts_with(|c: char| c.is_ascii_digit()) {
        out.insert(0, '_');
    }
    out
}

fn extent_of(points: &[[f32; 3]], padding: f32) -> [[f32; 3]; 2] {
    let Some(first) = points.first() else {
        return [[0.0; 3]; 2];
    };
    let (mut min, mut max) = (*first, *first);
    for p in points {
        for axis in 0..3 {
            min[axis] = min[axis].min(p[axis]);
            max[axis] = max[axis].max(p[axis]);
        }
    }
    [min.map(|c| c - padding), max.map(|c| c + padding)]
}

#[cfg(test)]
mod tests;
