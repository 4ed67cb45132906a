//! A groom as an AbcGeom scene: `/groom` (Xform, identity) holding
//! `/groom/curves` (Curves) with `P`, `.selfBnds`, `nVertices`,
//! `curveBasisAndType`, `width`, `uv` and `.arbGeomParams` with the other
//! attributes and the Unreal Engine groom attributes (`groom_*`).
//!
//! The file holds the groom's units (recorded as `groombake_units` in the
//! archive metadata, since Alembic has no unit field), Y up, the axis every
//! Alembic reader assumes: the groom is rotated to Y up before writing. The
//! `groom_*` attributes are written for [`AttributeSet::WithUnreal`] only.
//! A guide cache (`mod@guide_cache`) holds two curves objects instead,
//! `/groom/guides` (animated) and `/groom/render` (at rest).

mod guide_cache;
mod sequence;

pub use guide_cache::guide_cache;
pub use sequence::write_sequence;

use super::archive::{
    metadata, ArchiveWriter, ClosedObject, Pod, PropertyKind, PropertyWriter, TimeSampling,
};
use crate::{AnimationOptions, AttributeSet, ExportError, FrameWriter};
use groom::{AtomicFile, AttributeValues, CurveBasis, Frame, Groom, Scope, Units, UpAxis};
use std::path::{Path, PathBuf};

const CURVES_SCHEMA: &str = "AbcGeom_Curve_v2";
const GEOM_BASE: &str = "AbcGeom_GeomBase_v1";
const XFORM_SCHEMA: &str = "AbcGeom_Xform_v3";
/// The groom schema version Unreal's importer is written for.
const UNREAL_GROOM_VERSION: (i16, i16) = (1, 5);
/// Frame times closer than this to a uniform grid are written as uniform
/// sampling.
const UNIFORM_TOLERANCE: f64 = 1e-6;

/// Attributes written as the curves' `width` (the first one present).
const WIDTH_NAMES: [&str; 3] = ["width", "widths", "thickness"];
/// The per-strand attribute written as the curves' `uv`.
const ROOT_UV: &str = "root_uv";

fn io_error(path: &Path) -> impl Fn(std::io::Error) -> ExportError + '_ {
    move |e| ExportError::io(path, e)
}

/// Writes a static groom; a groom with frames is written animated, at the
/// rate its frame times give.
pub fn write(path: &Path, groom: &Groom, attributes: AttributeSet) -> Result<(), ExportError> {
    if !groom.frames.is_empty() {
        let fps = match (groom.frames.first(), groom.frames.get(1)) {
            (Some(a), Some(b)) if b.time > a.time => 1.0 / (b.time - a.time),
            _ => 24.0,
        };
        let options = AnimationOptions {
            fps,
            frame_count: groom.frames.len(),
        };
        let mut writer = animated(path, groom, options, attributes)?;
        for frame in &groom.frames {
            writer.write_frame(frame)?;
        }
        return writer.finish();
    }
    let mut export = CurvesExport::start(path, groom, None, attributes)?;
    let points = export.converted(&groom.points);
    export.add_sample(&points, Vec::new())?;
    export.finish()
}

/// Starts an animated export: `P` gets one sample per frame.
pub fn animated(
    path: &Path,
    groom: &Groom,
    options: AnimationOptions,
    attributes: AttributeSet,
) -> Result<Box<dyn FrameWriter>, ExportError> {
    if !(options.fps.is_finite() && options.fps > 0.0) {
        return Err(ExportError::Invalid {
            file: path.to_path_buf(),
            message: format!("frame rate {} is not a positive number", options.fps),
        });
    }
    Ok(Box::new(CurvesExport::start(
        path,
        groom,
        Some(options.fps),
        attributes,
    )?))
}

/// A file being written: the static properties are done, `P` and
/// `.selfBnds` take one sample per frame.
struct CurvesExport {
    path: PathBuf,
    archive: ArchiveWriter<AtomicFile>,
    /// `nVertices`, `curveBasisAndType`, `uv`, `width`: set once, repeated
    /// for every further frame.
    fixed: Vec<PropertyWriter>,
    /// The children of `.arbGeomParams`, likewise, except those a frame
    /// gives new values ([`Frame::attributes`]): a sample per frame (one
    /// that holds is stored once).
    arbitrary: Vec<PropertyWriter>,
    /// Per child of `.arbGeomParams`: the groom attribute it holds (if
    /// any), its scope, type and extent, and its first sample's bytes
    /// until the first frame (which may give its own).
    arbitrary_sources: Vec<ArbitrarySource>,
    /// The time-varying attributes every frame carries (the first sets them).
    animated: Option<Vec<String>>,
    samples: usize,
    /// The next sample of `fixed` is already set (a new topology,
    /// [`sequence`]), not a repeat.
    fixed_given: bool,
    positions: PropertyWriter,
    bounds: PropertyWriter,
    vertex_count: usize,
    /// The groom's units, which the file is written in (recorded in the
    /// archive metadata unless they are the centimetres readers assume).
    units: Units,
    /// The groom's up axis; Alembic is written Y up.
    source_up: UpAxis,
    fps: Option<f64>,
    times: Vec<f64>,
    /// The name of the animated curves object (`curves`; `guides` in a
    /// guide cache).
    object_name: &'static str,
    /// A guide cache's render hair: a second curves object beside the
    /// animated one, its rest pose only ([`mod@guide_cache`]).
    rest: Option<(&'static str, Groom, AttributeSet)>,
}

/// What a child of `.arbGeomParams` holds, for a frame to give it values.
struct ArbitrarySource {
    attribute: Option<String>,
    scope: &'static str,
    pod: Pod,
    extent: u8,
    first: Option<Vec<u8>>,
}

fn values_bytes(values: &AttributeValues) -> (Pod, u8, Vec<u8>) {
    match values {
        AttributeValues::Float(v) => (Pod::F32, 1, f32_bytes(v.iter().copied())),
        AttributeValues::Vec2(v) => (Pod::F32, 2, f32_bytes(v.iter().flatten().copied())),
        AttributeValues::Vec3(v) => (Pod::F32, 3, f32_bytes(v.iter().flatten().copied())),
        AttributeValues::Int(v) => (
            Pod::I32,
            1,
            v.iter().flat_map(|x| x.to_le_bytes()).collect(),
        ),
    }
}

fn f32_bytes(values: impl Iterator<Item = f32>) -> Vec<u8> {
    values.flat_map(f32::to_le_bytes).collect()
}

fn scope_code(scope: Scope) -> &'static str {
    match scope {
        Scope::Vertex => "vtx",
        Scope::Strand => "uni",
    }
}

/// Metadata of a non-indexed geometry parameter.
fn geom_param_metadata(scope: &str, pod: Pod, extent: u8) -> String {
    let extent_text = extent.to_string();
    let interpretation = if extent > 1 && pod == Pod::F32 {
        "vector"
    } else {
        ""
    };
    metadata(&[
        ("arrayExtent", "1"),
        ("geoScope", scope),
        ("interpretation", interpretation),
        ("isGeomParam", "true"),
        ("podExtent", &extent_text),
        ("podName", pod.name()),
    ])
}

/// Unreal's per-strand triples: the ids of the three closest guides
/// (int32) and their weights (float32), written as the Alembic library
/// writes a geometry parameter of array extent 3 (three scalars per curve),
/// which is how Unreal's importer reads them.
fn unreal_triple(name: &str, values: &AttributeValues) -> Option<(Pod, Vec<u8>)> {
    let AttributeValues::Vec3(v) = values else {
        return None;
    };
    match name {
        groom::guides::GROOM_CLOSEST_GUIDES => Some((
            Pod::I32,
            v.iter()
                .flatten()
                .flat_map(|&x| (x.round() as i32).to_le_bytes())
                .collect(),
        )),
        groom::guides::GROOM_GUIDE_WEIGHTS => {
            Some((Pod::F32, f32_bytes(v.iter().flatten().copied())))
        }
        _ => None,
    }
}

/// Metadata of a geometry parameter of three scalars per element.
fn triple_metadata(scope: &str, pod: Pod) -> String {
    metadata(&[
        ("arrayExtent", "3"),
        ("geoScope", scope),
        ("interpretation", ""),
        ("isGeomParam", "true"),
        ("podExtent", "1"),
        ("podName", pod.name()),
    ])
}

/// Property names may not contain '/' or be empty.
fn property_name(name: &str) -> String {
    let cleaned: String = name
        .chars()
        .map(|c| if c == '/' { '_' } else { c })
        .collect();
    if cleaned.is_empty() {
        "unnamed".to_string()
    } else {
        cleaned
    }
}

fn basis_and_type(basis: CurveBasis) -> [u8; 4] {
    // Type 1 = linear, 0 = cubic; wrap 0 = non-periodic; then the basis twice.
    let code = match basis {
        CurveBasis::Linear => return [1, 0, 0, 0],
        CurveBasis::Bezier => 1,
        CurveBasis::Bspline => 2,
        CurveBasis::CatmullRom => 3,
        CurveBasis::Hermite => 4,
        CurveBasis::Power => 5,
    };
    [0, 0, code, code]
}

fn bounds_bytes(points: &[[f32; 3]]) -> Vec<u8> {
    let (min, max) = match groom::bounds_of(points) {
        Some((min, max)) => (min.map(f64::from), max.map(f64::from)),
        // Imath's empty box.
        None => ([f64::MAX; 3], [-f64::MAX; 3]),
    };
    min.iter()
        .chain(max.iter())
        .flat_map(|v| v.to_le_bytes())
        .collect()
}

/// One of the curves' own properties and its value for a groom.
struct FixedSample {
    name: &'static str,
    metadata: String,
    kind: PropertyKind,
    pod: Pod,
    extent: u8,
    bytes: Vec<u8>,
}

/// `nVertices`, `curveBasisAndType`, `uv` and `width` of a groom, in the
/// order they are written.
fn fixed_samples(groom: &Groom) -> Vec<FixedSample> {
    let counts: Vec<u8> = groom
        .strand_vertex_counts
        .iter()
        .flat_map(|&c| (c as i32).to_le_bytes())
        .collect();
    let mut out = vec![
        FixedSample {
            name: "nVertices",
            metadata: String::new(),
            kind: PropertyKind::Array,
            pod: Pod::I32,
            extent: 1,
            bytes: counts,
        },
        FixedSample {
            name: "curveBasisAndType",
            metadata: String::new(),
            kind: PropertyKind::Scalar,
            pod: Pod::U8,
            extent: 4,
            bytes: basis_and_type(groom.basis).to_vec(),
        },
    ];
    if let Some(uv) = root_uv(groom) {
        out.push(FixedSample {
            name: "uv",
            metadata: geom_param_metadata("uni", Pod::F32, 2),
            kind: PropertyKind::Array,
            pod: Pod::F32,
            extent: 2,
            bytes: f32_bytes(uv.iter().flatten().copied()),
        });
    }
    if let Some(width) = width_attribute(groom) {
        if let AttributeValues::Float(values) = &width.values {
            let scope = scope_code(width.scope);
            out.push(FixedSample {
                name: "width",
                metadata: geom_param_metadata(scope, Pod::F32, 1),
                kind: PropertyKind::Array,
                pod: Pod::F32,
                extent: 1,
                bytes: f32_bytes(values.iter().copied()),
            });
        }
    }
    out
}

impl CurvesExport {
    fn start(
        path: &Path,
        groom: &Groom,
        fps: Option<f64>,
        attributes: AttributeSet,
    ) -> Result<CurvesExport, ExportError> {
        let file = AtomicFile::create(path).map_err(io_error(path))?;
        let mut archive = ArchiveWriter::new(file).map_err(io_error(path))?;
        // Index 1 is the animation's sampling; its times are set at the end.
        let animated_sampling = match fps {
            Some(fps) => archive.add_time_sampling(TimeSampling::uniform(fps, 0.0)),
            None => 0,
        };
        let mut y_up = groom.clone();
        y_up.frames.clear();
        y_up.convert_to(groom.units, UpAxis::Y);
        let fixed = Self::fixed_properties(&mut archive, &y_up, animated_sampling)
            .map_err(io_error(path))?;
        let (mut arbitrary, mut arbitrary_sources) =
            Self::arbitrary_properties(&y_up, animated_sampling, attributes);
        // A static export has no frame to give values: its samples go in
        // now, where they always have (the file's bytes stay the same).
        if fps.is_none() {
            for (property, source) in arbitrary.iter_mut().zip(&mut arbitrary_sources) {
                if let Some(bytes) = source.first.take() {
                    property
                        .set_sample(&mut archive, &bytes)
                        .map_err(io_error(path))?;
                }
            }
        }
        Ok(CurvesExport {
            path: path.to_path_buf(),
            archive,
            fixed,
            arbitrary,
            arbitrary_sources,
            animated: None,
            samples: 0,
            fixed_given: false,
            positions: PropertyWriter::new(
                "P",
                metadata(&[("geoScope", "vtx"), ("interpretation", "point")]),
                PropertyKind::Array,
                Pod::F32,
                3,
                animated_sampling,
            ),
            bounds: PropertyWriter::new(
                ".selfBnds",
                metadata(&[("interpretation", "box")]),
                PropertyKind::Scalar,
                Pod::F64,
                6,
                animated_sampling,
            ),
            vertex_count: groom.points.len(),
            units: groom.units,
            source_up: groom.up_axis,
            fps,
            times: Vec::new(),
            object_name: "curves",
            rest: None,
        })
    }

    /// `nVertices`, `curveBasisAndType`, `width` and `uv`.
    fn fixed_properties(
        archive: &mut ArchiveWriter<AtomicFile>,
        groom: &Groom,
        sampling: u32,
    ) -> std::io::Result<Vec<PropertyWriter>> {
        let mut open = Vec::new();
        for fixed in fixed_samples(groom) {
            let mut property = PropertyWriter::new(
                fixed.name,
                fixed.metadata,
                fixed.kind,
                fixed.pod,
                fixed.extent,
                sampling,
            );
            property.set_sample(archive, &fixed.bytes)?;
            open.push(property);
        }
        Ok(open)
    }

    /// The children of `.arbGeomParams` (with `WithUnreal`, the Unreal groom
    /// attributes first, the version as int16 scalars as Unreal's Alembic
    /// groom schema gives it), then every attribute not written as `width`
    /// or `uv`, each under its own name; with their first samples' bytes
    /// (written with the first frame, or by a static export).
    fn arbitrary_properties(
        groom: &Groom,
        sampling: u32,
        attributes: AttributeSet,
    ) -> (Vec<PropertyWriter>, Vec<ArbitrarySource>) {
        let strands = groom.strand_count();
        type Param = (String, &'static str, AttributeValues, Option<String>);
        let mut params: Vec<Param> = Vec::new();
        let width = width_attribute(groom);
        if attributes == AttributeSet::WithUnreal {
            params.extend([
                (
                    "groom_guide".into(),
                    "uni",
                    AttributeValues::Int(vec![0; strands]),
                    None,
                ),
                (
                    "groom_group_id".into(),
                    "uni",
                    AttributeValues::Int(vec![0; strands]),
                    None,
                ),
            ]);
            if let Some(uv) = root_uv(groom) {
                params.push((
                    "groom_root_uv".into(),
                    "uni",
                    AttributeValues::Vec2(uv),
                    None,
                ));
            }
            if let Some(width) = width {
                params.push((
                    "groom_width".into(),
                    scope_code(width.scope),
                    width.values.clone(),
                    None,
                ));
            }
        }
        // A per-strand `root_uv` is the curves' `uv` (above); any other
        // (per vertex, as a scalp scatter writes it) is kept as a
        // parameter of its own rather than dropped without a word.
        let uv_written = root_uv(groom).is_some();
        for attribute in &groom.attributes {
            let is_width = width.is_some_and(|w| w.name == attribute.name);
            if is_width || (attribute.name == ROOT_UV && uv_written) {
                continue;
            }
            let name = property_name(&attribute.name);
            let value = (
                name,
                scope_code(attribute.scope),
                attribute.values.clone(),
                Some(attribute.name.clone()),
            );
            // A groom attribute of the same name replaces the default.
            match params.iter_mut().find(|p| p.0 == value.0) {
                Some(existing) => *existing = value,
                None => params.push(value),
            }
        }
        let mut open = Vec::new();
        let mut sources = Vec::new();
        if attributes == AttributeSet::WithUnreal {
            for (name, value) in [
                ("groom_version_major", UNREAL_GROOM_VERSION.0),
                ("groom_version_minor", UNREAL_GROOM_VERSION.1),
            ] {
                if groom.attribute(name).is_some() {
                    continue;
                }
                open.push(PropertyWriter::new(
                    name,
                    geom_param_metadata("con", Pod::I16, 1),
                    PropertyKind::Array,
                    Pod::I16,
                    1,
                    sampling,
                ));
                sources.push(ArbitrarySource {
                    attribute: None,
                    scope: "con",
                    pod: Pod::I16,
                    extent: 1,
                    first: Some(value.to_le_bytes().to_vec()),
                });
            }
        }
        for (name, scope, values, attribute) in params {
            let (pod, extent, bytes, metadata) = match unreal_triple(&name, &values) {
                Some((pod, bytes)) => (pod, 1, bytes, triple_metadata(scope, pod)),
                None => {
                    let (pod, extent, bytes) = values_bytes(&values);
                    (pod, extent, bytes, geom_param_metadata(scope, pod, extent))
                }
            };
            open.push(PropertyWriter::new(
                &name,
                metadata,
                PropertyKind::Array,
                pod,
                extent,
                sampling,
            ));
            sources.push(ArbitrarySource {
                attribute,
                scope,
                pod,
                extent,
                first: Some(bytes),
            });
        }
        (open, sources)
    }

    /// The bytes of each `.arbGeomParams` child a frame gives values to.
    fn frame_arbitrary(&self, frame: &Frame) -> Result<Vec<Option<Vec<u8>>>, ExportError> {
        let mut out: Vec<Option<Vec<u8>>> = vec![None; self.arbitrary_sources.len()];
        for attribute in &frame.attributes {
            let found = self
                .arbitrary_sources
                .iter()
                .position(|s| s.attribute.as_deref() == Some(attribute.name.as_str()));
            let invalid = |what: &str| ExportError::Invalid {
                file: self.path.clone(),
                message: format!(
                    "frame at {} s: attribute '{}' {what}",
                    frame.time, attribute.name
                ),
            };
            let Some(index) = found else {
                return Err(invalid("is not an attribute of the groom's"));
            };
            let source = &self.arbitrary_sources[index];
            let (pod, extent, bytes) = values_bytes(&attribute.values);
            if (pod, extent, scope_code(attribute.scope))
                != (source.pod, source.extent, source.scope)
            {
                return Err(invalid("is not of the groom's type and scope"));
            }
            out[index] = Some(bytes);
        }
        Ok(out)
    }

    /// Points of the groom's axis, Y up.
    fn converted(&self, points: &[[f32; 3]]) -> Vec<[f32; 3]> {
        points.iter().map(|&p| self.source_up.to_y_up(p)).collect()
    }

    /// Adds a sample of every property: `points`, and the values `arbitrary`
    /// gives the children of `.arbGeomParams` (a frame's time-varying
    /// attributes; the others repeat their first sample).
    fn add_sample(
        &mut self,
        points: &[[f32; 3]],
        arbitrary: Vec<Option<Vec<u8>>>,
    ) -> Result<(), ExportError> {
        let bytes = f32_bytes(points.iter().flatten().copied());
        let path = self.path.clone();
        self.positions
            .set_sample(&mut self.archive, &bytes)
            .map_err(io_error(&path))?;
        self.bounds
            .set_sample(&mut self.archive, &bounds_bytes(points))
            .map_err(io_error(&path))?;
        // Every property of the schema has a sample per frame; the ones that
        // do not change are stored once and repeated.
        if self.samples > 0 && !self.fixed_given {
            for property in &mut self.fixed {
                property.repeat_previous();
            }
        }
        self.fixed_given = false;
        for ((property, source), given) in self
            .arbitrary
            .iter_mut()
            .zip(&mut self.arbitrary_sources)
            .zip(arbitrary.into_iter().chain(std::iter::repeat(None)))
        {
            let first = source.first.take();
            match given.or(first) {
                Some(bytes) => property
                    .set_sample(&mut self.archive, &bytes)
                    .map_err(io_error(&path))?,
                // (A static export's one sample went in at the start.)
                None if self.samples > 0 => property.repeat_previous(),
                None => {}
            }
        }
        self.samples += 1;
        Ok(())
    }

    /// The animation's time sampling: uniform when the frames fall on the
    /// frame-rate grid, otherwise every time stored.
    fn animation_sampling(&self, fps: f64) -> TimeSampling {
        let start = self.times.first().copied().unwrap_or(0.0);
        let uniform = self
            .times
            .iter()
            .enumerate()
            .all(|(i, &t)| (t - (start + i as f64 / fps)).abs() <= UNIFORM_TOLERANCE);
        if uniform {
            TimeSampling::uniform(fps, start)
        } else {
            TimeSampling::acyclic(self.times.clone())
        }
    }

    fn finish_file(mut self) -> Result<(), ExportError> {
        let path = self.path.clone();
        let io = io_error(&path);
        if let Some(fps) = self.fps {
            let sampling = self.animation_sampling(fps);
            self.archive.set_time_sampling(1, sampling);
        }
        let archive = &mut self.archive;
        let mut children = vec![close_curves(
            archive,
            self.object_name,
            self.bounds,
            self.positions,
            std::mem::take(&mut self.fixed),
            std::mem::take(&mut self.arbitrary),
        )
        .map_err(&io)?];
        if let Some((name, rest, attributes)) = self.rest.take() {
            children
                .push(guide_cache::static_curves(archive, name, &rest, attributes).map_err(&io)?);
        }
        let mut inherits = PropertyWriter::new(
            ".inherits",
            String::new(),
            PropertyKind::Scalar,
            Pod::Bool,
            1,
            0,
        );
        inherits.set_sample(archive, &[1]).map_err(&io)?;
        let inherits = inherits.close(archive).map_err(&io)?;
        let xform = archive
            .close_compound(
                ".xform",
                &metadata(&[("schema", XFORM_SCHEMA)]),
                vec![inherits],
            )
            .map_err(&io)?;
        let xform_title = format!("{XFORM_SCHEMA}:.xform");
        let xform_metadata =
            metadata(&[("schema", XFORM_SCHEMA), ("schemaObjTitle", &xform_title)]);
        let groom = archive
            .close_object("groom", &xform_metadata, vec![xform], children)
            .map_err(&io)?;
        let application = format!("groombake {}", env!("CARGO_PKG_VERSION"));
        let alembic_version = format!(
            "Alembic {}.{}.{} (groombake writer)",
            super::archive::LIBRARY_VERSION / 10000,
            super::archive::LIBRARY_VERSION / 100 % 100,
            super::archive::LIBRARY_VERSION % 100
        );
        let fps_text = format!("{}", self.fps.unwrap_or(24.0));
        let units_name = self.units.name();
        let mut archive_fields = vec![
            ("_ai_AlembicVersion", alembic_version.as_str()),
            ("_ai_Application", application.as_str()),
            ("_ai_DCC_FPS", fps_text.as_str()),
        ];
        // Alembic has no unit field; readers assume centimetres, so only
        // other units need groombake's mark.
        if self.units != Units::CENTIMETERS {
            archive_fields.push((groom::ALEMBIC_UNITS_KEY, units_name.as_str()));
        }
        let archive_metadata = metadata(&archive_fields);
        let file = self
            .archive
            .finish(&archive_metadata, vec![groom])
            .map_err(&io)?;
        file.commit().map_err(&io)
    }
}

/// Closes a curves object: its `.geom` in the reference schema's order
/// (bounds, points, topology, then the geometry parameters).
fn close_curves(
    archive: &mut ArchiveWriter<AtomicFile>,
    name: &str,
    bounds: PropertyWriter,
    positions: PropertyWriter,
    fixed: Vec<PropertyWriter>,
    arbitrary: Vec<PropertyWriter>,
) -> std::io::Result<ClosedObject> {
    let mut geom = vec![bounds.close(archive)?, positions.close(archive)?];
    for property in fixed {
        geom.push(property.close(archive)?);
    }
    let mut closed = Vec::new();
    for property in arbitrary {
        closed.push(property.close(archive)?);
    }
    geom.push(archive.close_compound(".arbGeomParams", "", closed)?);
    let geom_metadata = metadata(&[("schema", CURVES_SCHEMA), ("schemaBaseType", GEOM_BASE)]);
    let geom = archive.close_compound(".geom", &geom_metadata, geom)?;
    let title = format!("{CURVES_SCHEMA}:.geom");
    let curves_metadata = metadata(&[
        ("schema", CURVES_SCHEMA),
        ("schemaBaseType", GEOM_BASE),
        ("schemaObjTitle", &title),
    ]);
    archive.close_object(name, &curves_metadata, vec![geom], Vec::new())
}

fn width_attribute(groom: &Groom) -> Option<&groom::Attribute> {
    WIDTH_NAMES
        .iter()
        .filter_map(|name| groom.attribute(name))
        .find(|a| matches!(a.values, AttributeValues::Float(_)))
}

fn root_uv(groom: &Groom) -> Option<Vec<[f32; 2]>> {
    match groom.attribute(ROOT_UV) {
        Some(a) if a.scope == Scope::Strand => match &a.values {
            AttributeValues::Vec2(v) => Some(v.clone()),
            _ => None,
        },
        _ => None,
    }
}

impl FrameWriter for CurvesExport {
    fn write_frame(&mut self, frame: &Frame) -> Result<(), ExportError> {
        if frame.points.len() != self.vertex_count {
            return Err(ExportError::Invalid {
                file: self.path.clone(),
                message: format!(
                    "frame at {} s has {} points, the groom has {}",
                    frame.time,
                    frame.points.len(),
                    self.vertex_count
                ),
            });
        }
        if let Some(&last) = self.times.last() {
            if frame.time.is_nan() || frame.time <= last {
                return Err(ExportError::Invalid {
                    file: self.path.clone(),
                    message: format!("frame time {} s does not follow {} s", frame.time, last),
                });
            }
        }
        let mut names = self.animated.take();
        let these: Vec<String> = frame.attributes.iter().map(|a| a.name.clone()).collect();
        if names.as_ref().is_some_and(|n| *n != these) {
            return Err(ExportError::Invalid {
                file: self.path.clone(),
                message: format!(
                    "frame at {} s animates other attributes than the first frame",
                    frame.time
                ),
            });
        }
        names.get_or_insert(these);
        self.animated = names;
        let arbitrary = self.frame_arbitrary(frame)?;
        let points = self.converted(&frame.points);
        self.add_sample(&points, arbitrary)?;
        self.times.push(frame.time);
        Ok(())
    }

    fn finish(self: Box<Self>) -> Result<(), ExportError> {
        if self.fps.is_some() && self.times.is_empty() {
            return Err(ExportError::Invalid {
                file: self.path.clone(),
                message: "an animated export needs at least one frame".into(),
            });
        }
        (*self).finish_file()
    }
}

impl CurvesExport {
    fn finish(self) -> Result<(), ExportError> {
        self.finish_file()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use groom::Attribute;

    fn two_strands() -> Groom {
        let mut groom = Groom::from_strands([
            vec![[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 2.0, 0.5]],
            vec![[1.0, 0.0, 0.0], [1.0, 1.5, 0.0]],
        ]);
        groom.set_attribute(Attribute::new(
            "width",
            AttributeValues::Float(vec![0.1, 0.09, 0.08, 0.1, 0.05]),
        ));
        groom.set_attribute(Attribute::per_strand(
            "root_uv",
            AttributeValues::Vec2(vec![[0.25, 0.5], [0.75, 0.5]]),
        ));
        groom
    }

    fn u64_at(bytes: &[u8], at: u64) -> u64 {
        let at = at as usize;
        u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap())
    }

    fn children(bytes: &[u8], group: u64) -> Vec<u64> {
        let count = u64_at(bytes, group);
        (0..count)
            .map(|i| u64_at(bytes, group + 8 + 8 * i))
            .collect()
    }

    fn data(bytes: &[u8], reference: u64) -> &[u8] {
        let offset = reference & !(1 << 63);
        let size = u64_at(bytes, offset) as usize;
        &bytes[offset as usize + 8..offset as usize + 8 + size]
    }

    /// The 32-byte hash trailers of the top object, `/groom` and
    /// `/groom/curves`: together they cover every property and sample.
    fn object_hashes(bytes: &[u8]) -> Vec<Vec<u8>> {
        let root = children(bytes, u64_at(bytes, 8));
        let mut group = root[2];
        let mut out = Vec::new();
        for _ in 0..3 {
            let kids = children(bytes, group);
            let headers = data(bytes, *kids.last().unwrap());
            out.push(headers[headers.len() - 32..].to_vec());
            if kids.len() > 2 {
                group = kids[1];
            }
        }
        out
    }

    /// The Alembic library itself wrote the same scene
    /// (`tests/data/make_reference.py`): every object hash, and so every
    /// property hash and sample digest under it, must be the same.
    #[test]
    fn hashes_match_the_alembic_library() {
        let dir = std::env::temp_dir().join(format!("groombake-abc-hash-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("two.abc");
        write(&path, &two_strands(), AttributeSet::default()).unwrap();
        let ours = std::fs::read(&path).unwrap();
        let reference = include_bytes!("../../tests/data/reference_static.abc");
        assert_eq!(object_hashes(&ours), object_hashes(reference));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The animated twin: 4 frames at 24 fps from 0.5 s, poses A, B, A, A
    /// (a pose written earlier is shared, trailing repeats are not stored).
    #[test]
    fn animated_hashes_match_the_alembic_library() {
        let dir = std::env::temp_dir().join(format!("groombake-abc-anim-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("anim.abc");
        let groom = two_strands();
        let pose_a = groom.points.clone();
        let pose_b: Vec<[f32; 3]> = pose_a.iter().map(|p| [p[0], p[1] + 0.5, p[2]]).collect();
        let options = AnimationOptions {
            fps: 24.0,
            frame_count: 4,
        };
        let mut writer = animated(&path, &groom, options, AttributeSet::default()).unwrap();
        for (i, pose) in [&pose_a, &pose_b, &pose_a, &pose_a].into_iter().enumerate() {
            let frame = Frame {
                time: 0.5 + i as f64 / 24.0,
                points: pose.clone(),
                attributes: Vec::new(),
            };
            writer.write_frame(&frame).unwrap();
        }
        writer.finish().unwrap();
        let ours = std::fs::read(&path).unwrap();
        let reference = include_bytes!("../../tests/data/reference_animated.abc");
        assert_eq!(object_hashes(&ours), object_hashes(reference));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn same_groom_gives_identical_bytes() {
        let dir = std::env::temp_dir().join(format!("groombake-abc-det-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (a, b) = (dir.join("a.abc"), dir.join("b.abc"));
        write(&a, &two_strands(), AttributeSet::default()).unwrap();
        write(&b, &two_strands(), AttributeSet::default()).unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
