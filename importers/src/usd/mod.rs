//! USD import: `.usda` text and `.usdc` crate files (`.usd` is sniffed).
//!
//! Both readers fill the same small layer model (`Stage`: prims in
//! depth-first order with their typed attributes); `to_groom` then turns
//! every defined `BasisCurves` prim into strands, with each prim's transform
//! (its `xformOpOrder`, composed through its parents) applied to the points.
//! `compose` first follows sublayers, references, payloads, inherits and
//! specializes, as either reader gives them (variants are not selected).

mod compose;
mod crate_reader;
mod frame_primvars;
mod primvars;
pub(crate) mod stream;
mod usda;

use crate::transform::{invert, multiply, scaling, transform_point, translation, Matrix, IDENTITY};
use crate::{ImportError, Place};
use groom::source_prims::{set_source_prims, SourcePrim};
use groom::{Attribute, AttributeValues, CurveBasis, Frame, Groom, Scope, Units, UpAxis};
use std::path::Path;

/// Reads a `.usda`, `.usdc` or `.usd` file, telling text from crate by the
/// first bytes rather than the extension.
pub fn read(path: &Path) -> Result<Groom, ImportError> {
    let bytes = crate::read_bytes(path)?;
    read_bytes(path, &bytes)
}

/// Reads USD from bytes already in memory; `path` names them in errors.
pub fn read_bytes(path: &Path, bytes: &[u8]) -> Result<Groom, ImportError> {
    let stage = compose::compose(path, parse_layer(path, bytes)?)?;
    let mut groom = to_groom(path, &stage)?;
    frame_primvars::add_frame_attributes(path, &stage, &mut groom)?;
    groom.provenance.format = "usd".into();
    Ok(groom)
}

/// Reads a crate file from bytes in memory the way [`crate::stream`] reads
/// one from disk: its topology, then each frame alone, in turn. `None`
/// when such a file is read whole (see [`crate::stream::FrameStream::open_usd_crate`]). For tests and fuzzing
/// of the frame-at-a-time path; `path` names the bytes in errors.
pub fn read_streamed_bytes(path: &Path, bytes: &[u8]) -> Result<Option<Groom>, ImportError> {
    let Some(opened) = stream::UsdStream::open(path, bytes)? else {
        return Ok(None);
    };
    let mut groom = opened.groom;
    for index in 0..opened.times.len() {
        groom.frames.push(opened.stream.frame(path, bytes, index)?);
    }
    Ok(Some(groom))
}

/// Reads a USD file as one groom per stretch of time with one topology
/// (see [`crate::read_sequence`]): one groom unless `curveVertexCounts`
/// change over time.
pub fn read_sequence(path: &Path) -> Result<Vec<Groom>, ImportError> {
    let bytes = crate::read_bytes(path)?;
    read_sequence_bytes(path, &bytes)
}

/// [`read_sequence`] of bytes already in memory; `path` names them in errors.
pub fn read_sequence_bytes(path: &Path, bytes: &[u8]) -> Result<Vec<Groom>, ImportError> {
    let stage = compose::compose(path, parse_layer(path, bytes)?)?;
    if !topology_is_sampled(&stage) {
        let mut groom = to_groom(path, &stage)?;
        frame_primvars::add_frame_attributes(path, &stage, &mut groom)?;
        groom.provenance.format = "usd".into();
        return Ok(vec![groom]);
    }
    topology_sequence(path, &stage)
}

/// Whether any prim's `curveVertexCounts` has time samples that differ
/// from its first value.
fn topology_is_sampled(stage: &Stage) -> bool {
    stage.prims.iter().any(|prim| {
        prim.attribute("curveVertexCounts").is_some_and(|counts| {
            let first = counts.static_value();
            counts
                .samples
                .iter()
                .any(|(_, value)| !matches!(value, Value::Blocked) && Some(value) != first)
        })
    })
}

/// Most (time code, prim) pairs a changing topology is evaluated at.
const MAX_PRIM_EVALUATIONS: usize = 100_000_000;

/// The stage evaluated at each time code where counts or points are
/// sampled, grouped into runs of one topology: each run is one groom whose
/// frames are its time codes. Values between samples are held (the last
/// sample at or before the time, else the first), as usd-core holds
/// integer arrays; `points` of equal length are interpolated linearly, as
/// usd-core does.
fn topology_sequence(path: &Path, stage: &Stage) -> Result<Vec<Groom>, ImportError> {
    let mut codes: Vec<f64> = stage
        .prims
        .iter()
        .flat_map(|prim| &prim.attributes)
        .filter(|a| a.name == "curveVertexCounts" || a.name == "points")
        .flat_map(|a| a.samples.iter().map(|(code, _)| *code))
        .filter(|code| code.is_finite())
        .collect();
    codes.sort_by(f64::total_cmp);
    codes.dedup();
    // The stage is evaluated once per time code: bound the work a small
    // file with many prims and many samples could ask for.
    if codes.len().saturating_mul(stage.prims.len()) > MAX_PRIM_EVALUATIONS {
        return Err(ImportError::malformed(
            path,
            Place::File,
            format!(
                "{} time codes of a changing topology over {} prims are more than {MAX_PRIM_EVALUATIONS} prim evaluations",
                codes.len(),
                stage.prims.len()
            ),
        ));
    }
    let codes_per_second = stage
        .time_codes_per_second
        .or(stage.frames_per_second)
        .unwrap_or(24.0);
    let mut grooms: Vec<Groom> = Vec::new();
    for code in codes {
        let mut groom = to_groom(path, &stage_at(stage, code))?;
        groom.provenance.format = "usd".into();
        let frame = Frame {
            time: code / codes_per_second,
            points: std::mem::take(&mut groom.points),
            attributes: Vec::new(),
        };
        match grooms.last_mut() {
            Some(run) if run.strand_vertex_counts == groom.strand_vertex_counts => {
                run.frames.push(frame)
            }
            _ => {
                groom.points = frame.points.clone();
                groom.frames = vec![frame];
                grooms.push(groom);
            }
        }
    }
    if grooms.is_empty() {
        return Err(ImportError::malformed(
            path,
            Place::File,
            "curveVertexCounts are time-sampled at no finite time code",
        ));
    }
    Ok(grooms)
}

/// The stage with every time-sampled attribute replaced by its value at
/// `code` (as a default, without samples).
fn stage_at(stage: &Stage, code: f64) -> Stage {
    let prims = stage
        .prims
        .iter()
        .map(|prim| Prim {
            attributes: prim
                .attributes
                .iter()
                .map(|attribute| UsdAttribute {
                    default: match value_at(attribute, code) {
                        Some(value) => Some(value),
                        None => attribute.default.clone(),
                    },
                    samples: Vec::new(),
                    name: attribute.name.clone(),
                    type_name: attribute.type_name.clone(),
                    interpolation: attribute.interpolation.clone(),
                    element_size: attribute.element_size,
                    place: attribute.place.clone(),
                })
                .collect(),
            path: prim.path.clone(),
            type_name: prim.type_name.clone(),
            arcs: Vec::new(),
            place: prim.place.clone(),
            ..*prim
        })
        .collect();
    Stage {
        prims,
        meters_per_unit: stage.meters_per_unit,
        up_axis: stage.up_axis.clone(),
        time_codes_per_second: stage.time_codes_per_second,
        frames_per_second: stage.frames_per_second,
        default_prim: stage.default_prim.clone(),
        sublayers: Vec::new(),
        notes: stage.notes.clone(),
        doc: stage.doc.clone(),
    }
}

/// The value of a time-sampled attribute at `code`; `None` when it has no
/// samples (its default holds).
fn value_at(attribute: &UsdAttribute, code: f64) -> Option<Value> {
    let samples: Vec<&(f64, Value)> = attribute
        .samples
        .iter()
        .filter(|(_, value)| !matches!(value, Value::Blocked))
        .collect();
    let after = samples.iter().position(|(c, _)| *c > code);
    let before = match after {
        Some(0) => return samples.first().map(|(_, v)| v.clone()),
        Some(i) => samples[i - 1],
        None => return samples.last().map(|(_, v)| v.clone()),
    };
    let next = after.and_then(|i| samples.get(i));
    match (attribute.name.as_str(), &before.1, next) {
        (
            "points",
            Value::Numbers {
                components,
                array,
                data,
            },
            Some((
                next_code,
                Value::Numbers {
                    data: next_data, ..
                },
            )),
        ) if data.len() == next_data.len() && before.0 < code => {
            let t = (code - before.0) / (next_code - before.0);
            Some(Value::Numbers {
                components: *components,
                array: *array,
                data: data
                    .iter()
                    .zip(next_data)
                    .map(|(a, b)| a + (b - a) * t)
                    .collect(),
            })
        }
        _ => Some(before.1.clone()),
    }
}

/// One layer as the file holds it, before composition.
fn parse_layer(path: &Path, bytes: &[u8]) -> Result<Stage, ImportError> {
    if bytes.starts_with(b"PXR-USDC") {
        crate_reader::read(path, bytes)
    } else if bytes.starts_with(b"#usda ") {
        usda::read(path, bytes)
    } else {
        Err(ImportError::malformed(
            path,
            Place::Offset(0),
            "not a USD file: it starts with neither `#usda` (text) nor `PXR-USDC` (crate)",
        ))
    }
}

/// A value as the readers give it: numbers widened to f64 (f32 values stay
/// exact), or text (tokens, strings, asset paths).
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Value {
    Numbers {
        /// Numbers per element: 1 for scalars, 3 for `float3`, 16 for `matrix4d`.
        components: usize,
        array: bool,
        data: Vec<f64>,
    },
    Text {
        array: bool,
        data: Vec<String>,
    },
    /// `None`: a blocked value.
    Blocked,
    /// A value of a type this importer does not interpret.
    Other,
    /// The targets of a composition arc list (`references`, `payload`,
    /// `inherits`, `specializes`, `subLayers`): `@asset@</path>` items.
    Arcs(Vec<ArcTarget>),
    /// A time sample's array left undecoded: its value rep in the crate
    /// file (only in a stage read for streaming, [`stream`]).
    Deferred(u64),
}

/// One item of a composition arc list: an asset (another layer; `None` for
/// this one) and a prim path in it (`None` for its `defaultPrim`).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ArcTarget {
    pub asset: Option<String>,
    pub prim_path: Option<String>,
    /// The layer offset the arc applies to the times it brings.
    pub offset: LayerOffset,
}

/// A layer offset (`SdfLayerOffset`): a time `t` of the layer an arc or a
/// sublayer brings is `t * scale + offset` in the layer that authors it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct LayerOffset {
    pub offset: f64,
    pub scale: f64,
}

impl Default for LayerOffset {
    fn default() -> LayerOffset {
        LayerOffset {
            offset: 0.0,
            scale: 1.0,
        }
    }
}

impl LayerOffset {
    pub(crate) fn is_identity(self) -> bool {
        self == LayerOffset::default()
    }

    pub(crate) fn apply(self, code: f64) -> f64 {
        code * self.scale + self.offset
    }
}

/// The kinds of composition arcs a prim can have.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ArcKind {
    Reference,
    Payload,
    Inherit,
    Specialize,
}

impl ArcKind {
    pub(crate) fn of_key(key: &str) -> Option<ArcKind> {
        Some(match key {
            "references" => ArcKind::Reference,
            "payload" => ArcKind::Payload,
            "inherits" => ArcKind::Inherit,
            "specializes" => ArcKind::Specialize,
            _ => return None,
        })
    }

    /// Strength within a prim, strongest 0: inherits, then references and
    /// payloads, then specializes (LIVRPS: local, inherits, variants,
    /// references, payloads, specializes).
    pub(crate) fn strength(self) -> u8 {
        match self {
            ArcKind::Inherit => 0,
            ArcKind::Reference => 1,
            ArcKind::Payload => 2,
            ArcKind::Specialize => 3,
        }
    }

    pub(crate) fn key(self) -> &'static str {
        match self {
            ArcKind::Reference => "references",
            ArcKind::Payload => "payload",
            ArcKind::Inherit => "inherits",
            ArcKind::Specialize => "specializes",
        }
    }
}

/// A composition arc authored on a prim.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Arc {
    pub kind: ArcKind,
    pub targets: Vec<ArcTarget>,
    pub place: Place,
}

impl Value {
    fn numbers(&self, components: usize) -> Option<&[f64]> {
        match self {
            Value::Numbers {
                components: c,
                data,
                ..
            } if *c == components => Some(data),
            _ => None,
        }
    }

    fn text(&self) -> Option<&[String]> {
        match self {
            Value::Text { data, .. } => Some(data),
            _ => None,
        }
    }
}

/// One attribute with its default value and time samples.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct UsdAttribute {
    pub name: String,
    pub type_name: String,
    pub default: Option<Value>,
    /// `(time code, value)`, as the file lists them.
    pub samples: Vec<(f64, Value)>,
    pub interpolation: Option<String>,
    /// Values per element of a primvar (`elementSize`), when authored.
    pub element_size: Option<f64>,
    /// Where the attribute is: line of its declaration or its path.
    pub place: Place,
}

impl UsdAttribute {
    /// The default value, or the first time sample when there is none.
    fn static_value(&self) -> Option<&Value> {
        match &self.default {
            Some(Value::Blocked) | None => self.samples.first().map(|(_, v)| v),
            Some(value) => Some(value),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Specifier {
    Def,
    Over,
    Class,
}

/// One prim spec; `parent` indexes an earlier prim of [`Stage::prims`].
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Prim {
    pub path: String,
    pub parent: Option<usize>,
    pub type_name: String,
    pub specifier: Specifier,
    /// Prims inside a variant are not part of the stage unless selected;
    /// this importer does not select variants.
    pub in_variant: bool,
    pub attributes: Vec<UsdAttribute>,
    /// Composition arcs, strongest first (`compose` follows them).
    pub arcs: Vec<Arc>,
    pub place: Place,
}

impl Prim {
    fn attribute(&self, name: &str) -> Option<&UsdAttribute> {
        self.attributes.iter().find(|a| a.name == name)
    }
}

/// The layer: stage metadata and prims, parents before children.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Stage {
    pub meters_per_unit: Option<f64>,
    pub up_axis: Option<String>,
    pub time_codes_per_second: Option<f64>,
    pub frames_per_second: Option<f64>,
    pub prims: Vec<Prim>,
    /// `defaultPrim`: the prim a reference without a prim path brings.
    pub default_prim: Option<String>,
    /// `subLayers`, strongest first, with where they are authored and
    /// their layer offsets.
    pub sublayers: Vec<(String, Place, LayerOffset)>,
    /// What the reader passed over (variant sets), for the groom's info.
    pub notes: Vec<String>,
    /// The layer's `doc` (groombake writes "Written by groombake"); `None`
    /// for a stage composed from several layers.
    pub doc: Option<String>,
}

/// The `doc` of the layers groombake writes: their prims split one groom
/// by curve kind and role, never into groups of the source.
const GROOMBAKE_DOC: &str = "Written by groombake";

/// What an element of a USD value type holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ElementKind {
    /// `components` numbers; `single` when the type is 32-bit or half float.
    Numbers {
        components: usize,
        single: bool,
    },
    Text,
}

/// The element kind of a USD type name without `[]`, e.g. `point3f`.
pub(crate) fn element_kind(type_name: &str) -> Option<ElementKind> {
    let numbers = |components, single| Some(ElementKind::Numbers { components, single });
    match type_name {
        "bool" | "uchar" | "int" | "uint" | "int64" | "uint64" => return numbers(1, false),
        "half" | "float" => return numbers(1, true),
        "double" | "timecode" => return numbers(1, false),
        "token" | "string" | "asset" => return Some(ElementKind::Text),
        "quath" | "quatf" => return numbers(4, true),
        "quatd" => return numbers(4, false),
        "matrix2d" => return numbers(4, false),
        "matrix3d" => return numbers(9, false),
        "matrix4d" | "frame4d" => return numbers(16, false),
        _ => {}
    }
    let bytes = type_name.as_bytes();
    let last = *bytes.last()?;
    if last.is_ascii_digit() {
        let components = usize::from(last - b'0');
        let prefix = type_name.get(..type_name.len() - 1)?;
        if !(2..=4).contains(&components) {
            return None;
        }
        return match prefix {
            "half" | "float" => numbers(components, true),
            "double" | "int" => numbers(components, false),
            _ => None,
        };
    }
    let digit = *bytes.get(bytes.len().checked_sub(2)?)?;
    if !digit.is_ascii_digit() {
        return None;
    }
    let components = usize::from(digit - b'0');
    let prefix = type_name.get(..type_name.len() - 2)?;
    let role_ok = match prefix {
        "point" | "normal" | "vector" | "color" => components == 3 || components == 4,
        "texCoord" => components == 2 || components == 3,
        _ => false,
    };
    if !role_ok || components == 4 && prefix != "color" {
        return None;
    }
    match last {
        b'h' | b'f' => numbers(components, true),
        b'd' => numbers(components, false),
        _ => None,
    }
}

fn rotation(axis: usize, degrees: f64) -> Matrix {
    let (s, c) = degrees.to_radians().sin_cos();
    let mut m = IDENTITY;
    let (i, j) = match axis {
        0 => (1, 2),
        1 => (2, 0),
        _ => (0, 1),
    };
    m[i][i] = c;
    m[i][j] = -s;
    m[j][i] = s;
    m[j][j] = c;
    m
}

/// The matrix of one xformOp given its kind (`translate`, `rotateXYZ`, ...)
/// and value.
fn op_matrix(kind: &str, v: &[f64]) -> Option<Matrix> {
    let axis_of = |c: u8| match c {
        b'X' => Some(0),
        b'Y' => Some(1),
        b'Z' => Some(2),
        _ => None,
    };
    match (kind, v.len()) {
        ("translate", 3) => Some(translation([v[0], v[1], v[2]])),
        ("scale", 3) => Some(scaling([v[0], v[1], v[2]])),
        ("rotateX", 1) => Some(rotation(0, v[0])),
        ("rotateY", 1) => Some(rotation(1, v[0])),
        ("rotateZ", 1) => Some(rotation(2, v[0])),
        ("orient", 4) => {
            // (real, i, j, k), normalised.
            let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            if n == 0.0 {
                return None;
            }
            let (w, x, y, z) = (v[0] / n, v[1] / n, v[2] / n, v[3] / n);
            Some([
                [
                    1.0 - 2.0 * (y * y + z * z),
                    2.0 * (x * y - z * w),
                    2.0 * (x * z + y * w),
                    0.0,
                ],
                [
                    2.0 * (x * y + z * w),
                    1.0 - 2.0 * (x * x + z * z),
                    2.0 * (y * z - x * w),
                    0.0,
                ],
                [
                    2.0 * (x * z - y * w),
                    2.0 * (y * z + x * w),
                    1.0 - 2.0 * (x * x + y * y),
                    0.0,
                ],
                [0.0, 0.0, 0.0, 1.0],
            ])
        }
        ("transform", 16) => {
            // USD matrices are row-major for row vectors: transpose.
            let mut m = IDENTITY;
            for (r, row) in m.iter_mut().enumerate() {
                for (c, cell) in row.iter_mut().enumerate() {
                    *cell = v[c * 4 + r];
                }
            }
            Some(m)
        }
        (name, 3) if name.len() == 9 && name.starts_with("rotate") => {
            // rotateABC rotates about A first, then B, then C.
            let order = &name.as_bytes()[6..];
            let mut m = IDENTITY;
            for (i, &axis) in order.iter().enumerate() {
                let axis = axis_of(axis)?;
                m = multiply(&rotation(axis, v[i]), &m);
            }
            Some(m)
        }
        _ => None,
    }
}

/// The local transform of a prim and whether it resets the parent's.
fn local_transform(file: &Path, prim: &Prim) -> Result<(Matrix, bool), ImportError> {
    let Some(order) = prim.attribute("xformOpOrder") else {
        return Ok((IDENTITY, false));
    };
    let bad = |message: String| ImportError::malformed(file, order.place.clone(), message);
    let names = match order.static_value() {
        Some(value) => value
            .text()
            .ok_or_else(|| bad("xformOpOrder is not a token array".into()))?,
        None => return Ok((IDENTITY, false)),
    };
    let mut matrix = IDENTITY;
    let mut reset = false;
    for (index, name) in names.iter().enumerate() {
        if name == "!resetXformStack!" {
            if index != 0 {
                return Err(bad(
                    "!resetXformStack! must come first in xformOpOrder".into()
                ));
            }
            reset = true;
            continue;
        }
        let (inverse, op_name) = match name.strip_prefix("!invert!") {
            Some(rest) => (true, rest),
            None => (false, name.as_str()),
        };
        let kind = op_name
            .strip_prefix("xformOp:")
            .and_then(|rest| rest.split(':').next())
            .ok_or_else(|| bad(format!("'{name}' in xformOpOrder is not an xformOp")))?;
        let attribute = prim.attribute(op_name).ok_or_else(|| {
            bad(format!(
                "xformOpOrder names '{op_name}', which the prim lacks"
            ))
        })?;
        let values = match attribute.static_value() {
            Some(Value::Numbers { data, .. }) => data.as_slice(),
            _ => {
                return Err(ImportError::malformed(
                    file,
                    attribute.place.clone(),
                    format!("{op_name} has no numeric value"),
                ))
            }
        };
        let op_error = || {
            ImportError::malformed(
                file,
                attribute.place.clone(),
                format!(
                    "{op_name}: unsupported op or wrong number of values ({})",
                    values.len()
                ),
            )
        };
        let mut op = op_matrix(kind, values).ok_or_else(op_error)?;
        if inverse {
            op = invert(&op).ok_or_else(|| bad(format!("{name}: the matrix is singular")))?;
        }
        matrix = multiply(&matrix, &op);
    }
    Ok((matrix, reset))
}

/// The strands of one BasisCurves prim.
struct CurveSet {
    counts: Vec<u32>,
    points: Vec<[f32; 3]>,
    /// `(time code, points)` for each time sample of `points`.
    samples: Vec<(f64, Vec<[f32; 3]>)>,
    basis: CurveBasis,
    /// `wrap`: nonperiodic, periodic or pinned.
    wrap: String,
    attributes: Vec<Attribute>,
    /// The USD type each attribute was declared with (`color3f[]`, ...).
    declared_types: Vec<(String, String)>,
    notes: Vec<String>,
    /// Primvars that could not be kept, with why (warnings).
    losses: Vec<String>,
}

fn to_points(values: &[f64], matrix: &Matrix) -> Vec<[f32; 3]> {
    values
        .chunks_exact(3)
        .map(|p| transform_point(matrix, [p[0], p[1], p[2]]).map(|c| c as f32))
        .collect()
}

/// Refuses a prim whose `curveVertexCounts` change over time: a groom holds
/// one topology (the whole file is refused, with where it changes, since a
/// bake cannot skip part of the hair; `read_sequence` carries the change).
fn check_one_topology(file: &Path, prim: &Prim) -> Result<(), ImportError> {
    let Some(counts_attribute) = prim.attribute("curveVertexCounts") else {
        return Ok(());
    };
    if let Some(first) = counts_attribute.static_value() {
        let changed = counts_attribute
            .samples
            .iter()
            .find(|(_, value)| !matches!(value, Value::Blocked) && value != first);
        if let Some((code, _)) = changed {
            return Err(ImportError::malformed(
                file,
                counts_attribute.place.clone(),
                format!(
                    "topology changes at time {code} (curveVertexCounts are time-sampled); \
                     a bake needs one topology (inspect and convert carry the change)"
                ),
            ));
        }
    }
    Ok(())
}

fn curve_set(file: &Path, prim: &Prim, world: &Matrix) -> Result<CurveSet, ImportError> {
    let at = |attribute: &UsdAttribute, message: String| {
        ImportError::malformed(file, attribute.place.clone(), message)
    };
    let prim_error = |message: String| ImportError::malformed(file, prim.place.clone(), message);

    let counts_attribute = prim.attribute("curveVertexCounts").ok_or_else(|| {
        prim_error(format!(
            "BasisCurves {} has no curveVertexCounts",
            prim.path
        ))
    })?;
    let counts_values = counts_attribute
        .static_value()
        .and_then(|v| v.numbers(1))
        .ok_or_else(|| {
            at(
                counts_attribute,
                "curveVertexCounts is not an int array".into(),
            )
        })?;
    let mut counts = Vec::with_capacity(counts_values.len());
    let mut total: u64 = 0;
    for &count in counts_values {
        if !(count >= 0.0 && count <= f64::from(u32::MAX) && count.fract() == 0.0) {
            return Err(at(
                counts_attribute,
                format!("curve vertex count {count} is not a count"),
            ));
        }
        counts.push(count as u32);
        total += count as u64;
    }

    let points_attribute = prim
        .attribute("points")
        .ok_or_else(|| prim_error(format!("BasisCurves {} has no points", prim.path)))?;
    let check_points = |values: &[f64], what: &str| -> Result<(), ImportError> {
        if values.len() as u128 != u128::from(total) * 3 {
            return Err(at(
                points_attribute,
                format!(
                    "{what} has {} points but curveVertexCounts add up to {total}",
                    values.len() / 3
                ),
            ));
        }
        Ok(())
    };
    let mut samples: Vec<(f64, Vec<[f32; 3]>)> = Vec::new();
    for (code, value) in &points_attribute.samples {
        if matches!(value, Value::Blocked) {
            continue;
        }
        let values = value
            .numbers(3)
            .ok_or_else(|| at(points_attribute, "points are not a point3f array".into()))?;
        check_points(values, &format!("the time sample at {code}"))?;
        if !code.is_finite() {
            return Err(at(
                points_attribute,
                format!("time code {code} is not finite"),
            ));
        }
        samples.push((*code, to_points(values, world)));
    }
    samples.sort_by(|a, b| a.0.total_cmp(&b.0));
    samples.dedup_by(|later, earlier| later.0 == earlier.0);
    let points = match &points_attribute.default {
        Some(value) if !matches!(value, Value::Blocked) => {
            let values = value
                .numbers(3)
                .ok_or_else(|| at(points_attribute, "points are not a point3f array".into()))?;
            check_points(values, "points")?;
            to_points(values, world)
        }
        _ => match samples.first() {
            Some((_, first)) => first.clone(),
            None => return Err(at(points_attribute, "points have no value".into())),
        },
    };

    let token = |name: &str| -> Option<String> {
        prim.attribute(name)
            .and_then(|a| a.static_value())
            .and_then(|v| v.text())
            .and_then(|t| t.first().cloned())
    };
    // Schema fallbacks: type cubic, basis bezier.
    let curve_type = token("type").unwrap_or_else(|| "cubic".into());
    let basis = match curve_type.as_str() {
        "linear" => CurveBasis::Linear,
        "cubic" => match token("basis").as_deref().unwrap_or("bezier") {
            "bezier" => CurveBasis::Bezier,
            "bspline" => CurveBasis::Bspline,
            "catmullRom" => CurveBasis::CatmullRom,
            other => {
                return Err(prim_error(format!(
                    "{}: unknown curve basis '{other}'",
                    prim.path
                )))
            }
        },
        other => {
            return Err(prim_error(format!(
                "{}: unknown curve type '{other}'",
                prim.path
            )))
        }
    };

    let mut set = CurveSet {
        counts,
        points,
        samples,
        basis,
        wrap: token("wrap").unwrap_or_else(|| "nonperiodic".into()),
        attributes: Vec::new(),
        declared_types: Vec::new(),
        notes: Vec::new(),
        losses: Vec::new(),
    };
    // Curve normals (ribbons) have no place in a groom: say they are left.
    if prim.attribute("normals").is_some_and(|a| {
        a.static_value()
            .is_some_and(|v| !matches!(v, Value::Blocked))
    }) {
        set.losses
            .push("skipped normals: a groom holds tubes, not oriented ribbons".into());
    }
    // By name once: a lookup per primvar was quadratic in their count.
    let by_name: std::collections::HashMap<&str, &UsdAttribute> = prim
        .attributes
        .iter()
        .map(|a| (a.name.as_str(), a))
        .collect();
    for attribute in &prim.attributes {
        let name = if attribute.name == "widths" {
            "width".to_string()
        } else if let Some(name) = attribute.name.strip_prefix("primvars:") {
            if name.ends_with(":indices") {
                continue;
            }
            if name == "st" {
                "root_uv".to_string()
            } else {
                name.to_string()
            }
        } else {
            continue;
        };
        let indices = by_name
            .get(format!("{}:indices", attribute.name).as_str())
            .and_then(|a| a.static_value())
            .and_then(|v| v.numbers(1));
        match primvars::primvar(file, attribute, &name, indices, &set)? {
            Ok(converted) => {
                set.declared_types
                    .push((name.clone(), attribute.type_name.clone()));
                set.attributes.push(converted)
            }
            Err(loss) if loss.is_empty() => {}
            Err(loss) => set.losses.push(loss),
        }
    }
    Ok(set)
}

/// Index of a basis in the per-strand `curve_basis` attribute of grooms
/// that mix bases.
fn basis_code(basis: CurveBasis) -> i32 {
    match basis {
        CurveBasis::Linear => 0,
        CurveBasis::Bezier => 1,
        CurveBasis::Bspline => 2,
        CurveBasis::CatmullRom => 3,
        CurveBasis::Hermite => 4,
        CurveBasis::Power => 5,
    }
}

fn empty_like(values: &AttributeValues, len: usize) -> AttributeValues {
    match values {
        AttributeValues::Float(_) => AttributeValues::Float(vec![0.0; len]),
        AttributeValues::Vec2(_) => AttributeValues::Vec2(vec![[0.0; 2]; len]),
        AttributeValues::Vec3(_) => AttributeValues::Vec3(vec![[0.0; 3]; len]),
        AttributeValues::Int(_) => AttributeValues::Int(vec![0; len]),
    }
}

/// Per-strand values repeated over each strand's vertices.
fn per_vertex(values: &AttributeValues, counts: &[u32]) -> AttributeValues {
    let each_vertex: Vec<std::ops::Range<usize>> = counts
        .iter()
        .enumerate()
        .flat_map(|(strand, &n)| std::iter::repeat_n(strand..strand + 1, n as usize))
        .collect();
    values.select(&each_vertex)
}

fn append(into: &mut AttributeValues, from: &AttributeValues) -> bool {
    match (into, from) {
        (AttributeValues::Float(a), AttributeValues::Float(b)) => a.extend_from_slice(b),
        (AttributeValues::Vec2(a), AttributeValues::Vec2(b)) => a.extend_from_slice(b),
        (AttributeValues::Vec3(a), AttributeValues::Vec3(b)) => a.extend_from_slice(b),
        (AttributeValues::Int(a), AttributeValues::Int(b)) => a.extend_from_slice(b),
        _ => return false,
    }
    true
}

/// Turns the layer into one groom.
pub(crate) fn to_groom(file: &Path, stage: &Stage) -> Result<Groom, ImportError> {
    let mut groom = Groom::default();
    let meters_per_unit = stage.meters_per_unit.unwrap_or(0.01);
    if !(meters_per_unit.is_finite() && meters_per_unit > 0.0) {
        return Err(ImportError::malformed(
            file,
            Place::File,
            format!("metersPerUnit {meters_per_unit} is not a positive number"),
        ));
    }
    groom.units = Units { meters_per_unit };
    groom.up_axis = match stage.up_axis.as_deref() {
        None | Some("Y") => UpAxis::Y,
        Some("Z") => UpAxis::Z,
        Some(other) => {
            return Err(ImportError::malformed(
                file,
                Place::File,
                format!("upAxis '{other}' is neither Y nor Z"),
            ))
        }
    };
    let codes_per_second = stage
        .time_codes_per_second
        .or(stage.frames_per_second)
        .unwrap_or(24.0);
    if !(codes_per_second.is_finite() && codes_per_second > 0.0) {
        return Err(ImportError::malformed(
            file,
            Place::File,
            format!("timeCodesPerSecond {codes_per_second} is not a positive number"),
        ));
    }

    // World transforms and whether each prim is on the stage (defined,
    // with defined ancestors, outside classes and variants).
    let mut worlds: Vec<Matrix> = Vec::with_capacity(stage.prims.len());
    let mut active: Vec<bool> = Vec::with_capacity(stage.prims.len());
    let mut sets: Vec<(String, CurveSet)> = Vec::new();
    let mut skipped: Vec<(String, ImportError)> = Vec::new();
    for (index, prim) in stage.prims.iter().enumerate() {
        let parent = prim.parent.filter(|&p| p < index);
        let (parent_world, parent_active) = match parent {
            Some(p) => (
                worlds.get(p).copied().unwrap_or(IDENTITY),
                active.get(p).copied().unwrap_or(false),
            ),
            None => (IDENTITY, true),
        };
        let is_active = parent_active && prim.specifier == Specifier::Def && !prim.in_variant;
        let (local, reset) = if is_active {
            local_transform(file, prim)?
        } else {
            (IDENTITY, false)
        };
        let world = if reset {
            local
        } else {
            multiply(&parent_world, &local)
        };
        worlds.push(world);
        active.push(is_active);
        if is_active && prim.type_name == "BasisCurves" {
            // A prim that cannot be read is left out, with a warning naming
            // it, as usd-core reads the others; the file is refused only
            // when no curves are left.
            if prim.attribute("points").is_some() {
                check_one_topology(file, prim)?;
            }
            match curve_set(file, prim, &world) {
                Ok(set) => sets.push((prim.path.clone(), set)),
                Err(error) => skipped.push((prim.path.clone(), error)),
            }
        }
    }
    if sets.is_empty() {
        if let Some((_, error)) = skipped.into_iter().next() {
            return Err(error);
        }
        return Err(ImportError::malformed(
            file,
            Place::File,
            "no BasisCurves prim defined in the file",
        ));
    }
    for (path, error) in &skipped {
        let why = match error {
            ImportError::Malformed { message, .. } => message.clone(),
            other => other.to_string(),
        };
        groom
            .provenance
            .losses
            .push(format!("skipped curves prim {path}: {why}"));
    }

    // Frames: every animated prim must be sampled at the same time codes;
    // static prims hold still.
    let codes: Option<Vec<f64>> = sets
        .iter()
        .find(|(_, s)| !s.samples.is_empty())
        .map(|(_, s)| s.samples.iter().map(|(c, _)| *c).collect());
    if let Some(codes) = &codes {
        for (path, set) in &sets {
            let these: Vec<f64> = set.samples.iter().map(|(c, _)| *c).collect();
            if !these.is_empty() && &these != codes {
                return Err(ImportError::malformed(
                    file,
                    Place::Path(path.clone()),
                    "points are sampled at other time codes than those of the first animated curves",
                ));
            }
        }
        groom.frames = codes
            .iter()
            .map(|&code| Frame {
                time: code / codes_per_second,
                points: Vec::new(),
                attributes: Vec::new(),
            })
            .collect();
    }

    let bases: Vec<CurveBasis> = sets.iter().map(|(_, s)| s.basis).collect();
    let mixed = bases.windows(2).any(|w| w[0] != w[1]);
    groom.basis = if mixed {
        bases
            .iter()
            .copied()
            .find(|&b| b != CurveBasis::Linear)
            .unwrap_or_default()
    } else {
        bases.first().copied().unwrap_or_default()
    };

    // The wrap and each attribute's declared type go to the provenance, for
    // the USD writer to keep them (`usd.wrap`, `usd.type.<attribute>`).
    let wraps: Vec<&str> = sets.iter().map(|(_, s)| s.wrap.as_str()).collect();
    if wraps.windows(2).any(|w| w[0] != w[1]) {
        groom
            .provenance
            .metadata
            .insert("usd.wrap".into(), "mixed".into());
    } else if let Some(&wrap) = wraps.first().filter(|&&w| w != "nonperiodic") {
        groom
            .provenance
            .metadata
            .insert("usd.wrap".into(), wrap.into());
    }
    for (_, set) in &sets {
        for (name, type_name) in &set.declared_types {
            groom
                .provenance
                .metadata
                .entry(format!("usd.type.{name}"))
                .or_insert_with(|| type_name.clone());
        }
    }

    // Each curves prim's composed path and strand count (for `inspect`,
    // and for the USD writer to write the prims again), with the
    // attributes each lacks, filled in below.
    let mut source_prims: Vec<SourcePrim> = sets
        .iter()
        .map(|(path, set)| SourcePrim {
            path: path.clone(),
            strands: set.counts.len(),
            missing: Vec::new(),
        })
        .collect();

    let several = sets.len() > 1;
    let mut group_ids = Vec::new();
    let mut basis_codes = Vec::new();
    let mut wrap_codes = Vec::new();
    let mut notes = stage.notes.clone();
    // Zeros for a prim that lacks an attribute: losses, unless the prims
    // are written back as they were (`groom::source_prims::ZERO_FILLED_KEY`).
    let mut zero_filled: Vec<String> = Vec::new();
    for (group, (path, set)) in sets.into_iter().enumerate() {
        let vertices_before = groom.points.len();
        let strands_before = groom.strand_vertex_counts.len();
        let earlier_counts = groom.strand_vertex_counts.clone();
        // The groom's attributes by name (a search each was quadratic).
        let mut index: std::collections::HashMap<String, usize> = groom
            .attributes
            .iter()
            .enumerate()
            .map(|(i, a)| (a.name.clone(), i))
            .collect();
        for attribute in set.attributes {
            let before = match attribute.scope {
                Scope::Vertex => vertices_before,
                Scope::Strand => strands_before,
            };
            let known = index.get(&attribute.name).copied();
            match known.and_then(|i| groom.attributes.get_mut(i)) {
                Some(existing) => {
                    // Interpolation is per prim: where prims differ, the
                    // groom holds the attribute per vertex.
                    if existing.scope != attribute.scope && existing.scope == Scope::Strand {
                        existing.values = per_vertex(&existing.values, &earlier_counts);
                        existing.scope = Scope::Vertex;
                    }
                    let spread;
                    let values = if existing.scope == attribute.scope {
                        &attribute.values
                    } else {
                        spread = per_vertex(&attribute.values, &set.counts);
                        &spread
                    };
                    if !append(&mut existing.values, values) {
                        return Err(ImportError::malformed(
                            file,
                            Place::Path(path.clone()),
                            format!(
                                "primvar '{}' has another type than in an earlier curves prim",
                                attribute.name
                            ),
                        ));
                    }
                }
                None => {
                    for earlier in source_prims.iter_mut().take(group) {
                        earlier.missing.push(attribute.name.clone());
                    }
                    if strands_before > 0 {
                        let loss = format!(
                            "the curves before {path} have no {}: 0 for their {strands_before} strands",
                            usd_name(&attribute.name)
                        );
                        groom.provenance.losses.push(loss.clone());
                        zero_filled.push(loss);
                    }
                    let mut values = empty_like(&attribute.values, before);
                    append(&mut values, &attribute.values);
                    index.insert(attribute.name.clone(), groom.attributes.len());
                    groom.attributes.push(Attribute {
                        values,
                        ..attribute
                    });
                }
            }
        }
        group_ids.extend(std::iter::repeat_n(group as i32, set.counts.len()));
        basis_codes.extend(std::iter::repeat_n(basis_code(set.basis), set.counts.len()));
        wrap_codes.extend(std::iter::repeat_n(wrap_code(&set.wrap), set.counts.len()));
        for (index, frame) in groom.frames.iter_mut().enumerate() {
            match set.samples.get(index) {
                Some((_, points)) => frame.points.extend_from_slice(points),
                None => frame.points.extend_from_slice(&set.points),
            }
        }
        groom.strand_vertex_counts.extend_from_slice(&set.counts);
        groom.points.extend_from_slice(&set.points);
        notes.extend(set.notes.into_iter().map(|n| format!("{path}: {n}")));
        groom
            .provenance
            .losses
            .extend(set.losses.into_iter().map(|loss| format!("{path}: {loss}")));
        // Attributes this prim lacks are zero for its strands: say so.
        let (vertices, strands) = (groom.points.len(), groom.strand_vertex_counts.len());
        for attribute in &mut groom.attributes {
            let target = match attribute.scope {
                Scope::Vertex => vertices,
                Scope::Strand => strands,
            };
            let missing = target.saturating_sub(attribute.values.len());
            if missing > 0 {
                let zeros = empty_like(&attribute.values, missing);
                append(&mut attribute.values, &zeros);
                if let Some(prim) = source_prims.get_mut(group) {
                    prim.missing.push(attribute.name.clone());
                }
                let loss = format!(
                    "{path} has no {}: 0 for its {} strands",
                    usd_name(&attribute.name),
                    set.counts.len()
                );
                groom.provenance.losses.push(loss.clone());
                zero_filled.push(loss);
            }
        }
    }
    // Two prims that are the guides and the render strands (as groombake
    // writes them: `groom_guide` 1 in the first, 0 in the second) are one
    // groom's split, told by `groom_guide`, not two groups.
    let guides_then_render = several
        && group_ids.iter().all(|&g| g <= 1)
        && groom.guide_flags().is_some_and(|flags| {
            flags
                .iter()
                .zip(&group_ids)
                .all(|(&guide, &group)| guide == (group == 0))
        });
    // Synthesised only where the file has none: a group_id primvar (as
    // groombake writes it) is the source's own and is kept. groombake's
    // own prims are one groom split by curve kind (told by `curve_basis`
    // and `curve_wrap`), not groups: a group_id there would be an
    // attribute the groom it wrote never had.
    // (Its split prims are `Strands...`; a groom written at its source's
    // prim paths is read as that source was, group ids and all.)
    let own_split = stage.doc.as_deref() == Some(GROOMBAKE_DOC)
        && source_prims.iter().all(|prim| {
            prim.path
                .rsplit('/')
                .next()
                .is_some_and(|name| name.starts_with("Strands"))
        });
    if several && !guides_then_render && !own_split && groom.attribute("group_id").is_none() {
        groom.set_attribute(Attribute::per_strand(
            "group_id",
            AttributeValues::Int(group_ids),
        ));
        groom.provenance.metadata.insert(
            groom::source_prims::GROUP_ID_KEY.into(),
            "synthesised".into(),
        );
    }
    set_source_prims(&mut groom, &source_prims);
    if !zero_filled.is_empty() {
        groom.provenance.metadata.insert(
            groom::source_prims::ZERO_FILLED_KEY.into(),
            zero_filled.join("\n"),
        );
    }
    if mixed {
        groom.set_attribute(Attribute::per_strand(
            "curve_basis",
            AttributeValues::Int(basis_codes),
        ));
        notes.push("curves of several bases: per-strand basis in 'curve_basis' (0 linear, 1 bezier, 2 bspline, 3 catmullRom)".into());
    }
    if groom
        .provenance
        .metadata
        .get("usd.wrap")
        .map(String::as_str)
        == Some("mixed")
    {
        groom.set_attribute(Attribute::per_strand(
            "curve_wrap",
            AttributeValues::Int(wrap_codes),
        ));
        notes.push("curves of several wraps: per-strand wrap in 'curve_wrap' (0 nonperiodic, 1 periodic, 2 pinned)".into());
    }
    groom.provenance.info = notes.join("; ");
    Ok(groom)
}

/// The USD name of a groom attribute, for messages.
fn usd_name(attribute: &str) -> String {
    match attribute {
        "width" => "widths".into(),
        "root_uv" => "primvars:st".into(),
        other => format!("primvars:{other}"),
    }
}

/// Index of a wrap in the per-strand `curve_wrap` attribute of grooms that
/// mix wraps.
fn wrap_code(wrap: &str) -> i32 {
    match wrap {
        "periodic" => 1,
        "pinned" => 2,
        _ => 0,
    }
}

#[cfg(test)]
mod tests;
