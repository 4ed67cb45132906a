//! Groom file writers. Each module writes one format; [`write()`] and
//! [`animated`] pick the module from the file extension.
//!
//! Outputs go through [`groom::AtomicFile`]: a failed export never leaves a
//! partial file. Animation is streamed: [`animated`] returns a
//! [`FrameWriter`] that takes one frame at a time, so memory does not grow
//! with the number of frames.

pub mod abc;
pub mod data;
pub mod gltf;
pub mod hair;
pub mod obj;
pub mod target;
pub mod usd;

pub use target::{destination, written_in, AttributeSet, Destination, Target};

use groom::{AttributeValues, Frame, Groom, Scope, Units, UpAxis};
use std::path::{Path, PathBuf};

/// Why a file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("{}: {source}", file.display())]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}: {message}", file.display())]
    Unsupported { file: PathBuf, message: String },
    #[error("{}: cannot export: {message}", file.display())]
    Invalid { file: PathBuf, message: String },
    #[error("{}: unknown output format (known extensions: {})", file.display(), EXTENSIONS.join(", "))]
    UnknownFormat { file: PathBuf },
}

impl ExportError {
    pub fn io(file: &Path, source: std::io::Error) -> ExportError {
        ExportError::Io {
            file: file.to_path_buf(),
            source,
        }
    }
}

/// The file extensions the exporters know, lower case, without the dot.
pub const EXTENSIONS: &[&str] = &[
    "hair", "data", "obj", "gltf", "glb", "usda", "usdc", "usd", "abc",
];

/// The extensions of formats that can hold animation.
pub const ANIMATED_EXTENSIONS: &[&str] = &["gltf", "glb", "usda", "usdc", "usd", "abc"];

/// How animation is to be written.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnimationOptions {
    /// Frames per second of the time codes.
    pub fps: f64,
    /// The number of frames that will be written (formats that need it up front).
    pub frame_count: usize,
}

/// Takes the frames of an animated export one at a time.
/// `Send`: a bake or bench may hold one across its thread pool.
pub trait FrameWriter: Send {
    /// Writes one frame; its points follow the topology of the groom given to
    /// [`animated`].
    fn write_frame(&mut self, frame: &Frame) -> Result<(), ExportError>;
    /// Completes the file and renames it into place.
    fn finish(self: Box<Self>) -> Result<(), ExportError>;
}

fn check_exportable(path: &Path, groom: &Groom) -> Result<(), ExportError> {
    if let Some(problem) = groom.first_fatal_problem() {
        return Err(ExportError::Invalid {
            file: path.to_path_buf(),
            message: problem.to_string(),
        });
    }
    check_finite(path, &groom.points, None)?;
    for (index, frame) in groom.frames.iter().enumerate() {
        check_finite(path, &frame.points, Some(index))?;
    }
    Ok(())
}

/// Refuses points that are not finite (every writer stores the groom's
/// numbers as they are, in the units the caller converted it to).
fn check_finite(path: &Path, points: &[[f32; 3]], frame: Option<usize>) -> Result<(), ExportError> {
    let Some(index) = points.iter().position(|p| !p.iter().all(|c| c.is_finite())) else {
        return Ok(());
    };
    let frame = frame.map_or(String::new(), |f| format!("frame {f}, "));
    Err(ExportError::Invalid {
        file: path.to_path_buf(),
        message: format!(
            "{frame}vertex {index} {:?} is not finite in the file's units",
            points[index]
        ),
    })
}

/// A frame writer that refuses frames with values the file cannot hold.
struct CheckedFrames {
    path: PathBuf,
    frames: usize,
    inner: Box<dyn FrameWriter>,
}

impl FrameWriter for CheckedFrames {
    fn write_frame(&mut self, frame: &Frame) -> Result<(), ExportError> {
        if !frame.time.is_finite() {
            return Err(ExportError::Invalid {
                file: self.path.clone(),
                message: format!("frame {}: time is not finite", self.frames),
            });
        }
        check_finite(&self.path, &frame.points, Some(self.frames))?;
        self.frames += 1;
        self.inner.write_frame(frame)
    }

    fn finish(self: Box<Self>) -> Result<(), ExportError> {
        self.inner.finish()
    }
}

/// Writes a groom, choosing the format by extension. A groom with frames is
/// written animated where the format can hold animation; the static formats
/// (`.hair`, `.data`, `.obj`) write its points.
pub fn write(path: &Path, groom: &Groom) -> Result<(), ExportError> {
    write_as(path, groom, AttributeSet::default())
}

/// [`write()`] with the attribute names of a destination ([`Target`]).
pub fn write_as(path: &Path, groom: &Groom, attributes: AttributeSet) -> Result<(), ExportError> {
    check_exportable(path, groom)?;
    let extension = extension_of(path);
    // `.hair` and `.data` record no axis and their readers take Y up:
    // a groom of another axis is turned to Y up as it is written.
    let y_up;
    let groom = if matches!(extension.as_str(), "hair" | "data") && groom.up_axis != UpAxis::Y {
        let mut turned = groom.clone();
        turned.convert_to(groom.units, UpAxis::Y);
        y_up = turned;
        &y_up
    } else {
        groom
    };
    match extension.as_str() {
        "hair" => hair::write(path, groom),
        "data" => data::write(path, groom),
        "obj" => obj::write(path, groom),
        "gltf" | "glb" => gltf::write(path, groom),
        "usda" => usd::write(path, groom, usd::Encoding::Text),
        "usdc" | "usd" => usd::write(path, groom, usd::Encoding::Crate),
        "abc" => abc::write(path, groom, attributes),
        _ => Err(ExportError::UnknownFormat {
            file: path.to_path_buf(),
        }),
    }
}

/// Whether writing `groom` to `path` keeps the prims it was read from (a
/// USD output of a groom read from USD whose prims still describe its
/// strands): then the attributes a prim lacked stay absent instead of
/// being written as zeros ([`groom::source_prims`]).
pub fn keeps_source_prims(path: &Path, groom: &Groom) -> bool {
    matches!(extension_of(path).as_str(), "usda" | "usdc" | "usd") && usd::keeps_source_prims(groom)
}

/// Whether the format at `path` holds curve counts that change over time
/// (USD, as time-sampled `curveVertexCounts`; Alembic, as `nVertices` per
/// sample).
pub fn holds_topology_changes(path: &Path) -> bool {
    matches!(extension_of(path).as_str(), "usda" | "usdc" | "usd" | "abc")
}

/// Writes grooms that follow each other in time with different topologies
/// (`importers::read_sequence`) to a format that holds topology changes
/// ([`holds_topology_changes`]); other formats are refused.
pub fn write_sequence(path: &Path, grooms: &[Groom]) -> Result<(), ExportError> {
    write_sequence_as(path, grooms, AttributeSet::default())
}

/// [`write_sequence`] with the attribute names of a destination.
pub fn write_sequence_as(
    path: &Path,
    grooms: &[Groom],
    attributes: AttributeSet,
) -> Result<(), ExportError> {
    for groom in grooms {
        check_exportable(path, groom)?;
    }
    match extension_of(path).as_str() {
        "usda" => usd::write_sequence(path, grooms, usd::Encoding::Text),
        "usdc" | "usd" => usd::write_sequence(path, grooms, usd::Encoding::Crate),
        "abc" => abc::curves::write_sequence(path, grooms, attributes),
        _ => Err(ExportError::Unsupported {
            file: path.to_path_buf(),
            message: "this format cannot hold curve counts that change over time".into(),
        }),
    }
}

/// Starts an animated export of `groom`'s topology and attributes.
pub fn animated(
    path: &Path,
    groom: &Groom,
    options: AnimationOptions,
) -> Result<Box<dyn FrameWriter>, ExportError> {
    animated_as(path, groom, options, AttributeSet::default())
}

/// [`animated`] with the attribute names of a destination ([`Target`]).
pub fn animated_as(
    path: &Path,
    groom: &Groom,
    options: AnimationOptions,
    attributes: AttributeSet,
) -> Result<Box<dyn FrameWriter>, ExportError> {
    check_exportable(path, groom)?;
    // glTF keeps frame times in seconds; USD writes time codes and Alembic
    // its time sampling at `options.fps`.
    let inner = match extension_of(path).as_str() {
        "usda" => usd::animated(path, groom, options, usd::Encoding::Text),
        "usdc" | "usd" => usd::animated(path, groom, options, usd::Encoding::Crate),
        "gltf" | "glb" => gltf::animated(path, groom),
        "abc" => abc::animated(path, groom, options, attributes),
        "hair" | "data" | "obj" => Err(ExportError::Unsupported {
            file: path.to_path_buf(),
            message: "this format holds no animation; write one frame with convert --frame".into(),
        }),
        _ => Err(ExportError::UnknownFormat {
            file: path.to_path_buf(),
        }),
    }?;
    Ok(Box::new(CheckedFrames {
        path: path.to_path_buf(),
        frames: 0,
        inner,
    }))
}

/// The extensions a guide cache ([`guide_cache()`]) is written to.
pub const GUIDE_CACHE_EXTENSIONS: &[&str] = &["abc", "usdc", "usd"];

/// Starts a guide cache: the guides of `groom` animated, its render hair
/// (per-strand `groom_guide` 0, after the guides) at rest with the guides
/// and weights it follows (`groom_closest_guides`, `groom_guide_weights`).
/// Each frame gives the guides' points only. Alembic in the layout of
/// Unreal's *Guides* groom cache ([`abc::curves::guide_cache`]), USD crate
/// files as `guides` and `render` prims ([`usd::guide_cache`]).
pub fn guide_cache(
    path: &Path,
    groom: &Groom,
    options: AnimationOptions,
    attributes: AttributeSet,
) -> Result<Box<dyn FrameWriter>, ExportError> {
    check_exportable(path, groom)?;
    let inner = match extension_of(path).as_str() {
        "abc" => abc::guide_cache(path, groom, options, attributes),
        "usdc" | "usd" => usd::guide_cache(path, groom, options),
        _ => Err(ExportError::Unsupported {
            file: path.to_path_buf(),
            message: "a guide cache is written to .abc, .usdc or .usd".into(),
        }),
    }?;
    Ok(Box::new(CheckedFrames {
        path: path.to_path_buf(),
        frames: 0,
        inner,
    }))
}

/// The units a file at `path` is written in when the user names none (the
/// units rule in [`groom::Units`]' module): glTF in metres (its
/// specification), USD in the groom's own units (it records them), `.abc`
/// and `.obj` in metres (what Blender and Houdini read them as; Unreal and
/// Maya take `target = "unreal"`/`"maya"`, centimetres), and `.hair` and
/// `.data` in the centimetres their readers assume.
pub fn default_units(path: &Path, groom_units: Units) -> Units {
    match extension_of(path).as_str() {
        "gltf" | "glb" | "abc" | "obj" => Units::METERS,
        "usda" | "usdc" | "usd" => groom_units,
        _ => Units::CENTIMETERS,
    }
}

/// The units a file at `path` holds when its groom is in `units`: glTF is
/// always metres (its specification; the writer converts), every other
/// format holds the groom's units.
pub fn file_units(path: &Path, units: Units) -> Units {
    match extension_of(path).as_str() {
        "gltf" | "glb" => Units::METERS,
        _ => units,
    }
}

/// A warning for units a file at `path` cannot keep as asked: glTF in
/// anything but metres, and `.hair` and `.data` (which record no units) in
/// anything but the centimetres their readers assume. `None` when the file
/// reads back in the units asked.
pub fn units_warning(path: &Path, units: Units) -> Option<String> {
    let extension = extension_of(path);
    match extension.as_str() {
        "gltf" | "glb" if units != Units::METERS => Some(format!(
            "{}: glTF is in metres by its specification; written in m, not {units}",
            path.display()
        )),
        "hair" | "data" if units != Units::CENTIMETERS => Some(format!(
            "{}: written in {units}, which a .{extension} file cannot record; read it back with --source-units {units}",
            path.display()
        )),
        _ => None,
    }
}

/// A warning for attributes that change over an animation (`names`, as
/// [`Frame::attributes`] carries them) written to a format that cannot
/// animate them: glTF animates positions only (morph targets hold
/// positions, normals and tangents), so its frames hold the first frame's
/// values. `None` for USD and Alembic, which sample them per frame.
pub fn frame_attributes_warning<S: AsRef<str>>(path: &Path, names: &[S]) -> Option<String> {
    let gltf = matches!(extension_of(path).as_str(), "gltf" | "glb");
    if !gltf || names.is_empty() {
        return None;
    }
    let names: Vec<&str> = names.iter().map(AsRef::as_ref).collect();
    Some(format!(
        "{}: glTF cannot animate vertex attributes: {} hold their first frame's values in every \
         frame (write .usdc or .abc for them per frame, or convert one frame of those with --frame)",
        path.display(),
        names.join(", ")
    ))
}

/// How far a point may move by being written as a glTF morph target and
/// read back, metres: `groombake diff`'s default tolerance.
const MORPH_TARGET_TOLERANCE: f64 = 1e-6;

/// A warning when glTF's morph targets cannot hold the frames of `groom`:
/// a frame is written as offsets from the rest pose, in metres, f32, and a
/// reader adds them back to the rest in f32, so a point far from its rest
/// position (coordinates far beyond the hair's scale) comes back rounded.
/// Computed as the writer and a reader do; `None` when every point comes
/// back within [`MORPH_TARGET_TOLERANCE`].
fn morph_target_rounding_warning(path: &Path, groom: &Groom) -> Option<String> {
    let scale = groom.units.meters_per_unit as f32;
    let metres = |p: [f32; 3]| groom.up_axis.to_y_up(p).map(|c| c * scale);
    let mut rounded = 0usize;
    let mut worst = 0.0f64;
    for frame in &groom.frames {
        for (point, rest) in frame.points.iter().zip(&groom.points) {
            let (moved, rest) = (metres(*point), metres(*rest));
            let error = (0..3)
                .map(|k| {
                    let back = rest[k] + (moved[k] - rest[k]);
                    (f64::from(back) - f64::from(moved[k])).powi(2)
                })
                .sum::<f64>()
                .sqrt();
            if error > MORPH_TARGET_TOLERANCE {
                rounded += 1;
                worst = worst.max(error);
            }
        }
    }
    (rounded > 0).then(|| {
        format!(
            "{}: glTF holds frames as offsets from the rest pose, and {rounded} point(s) far from \
             it come back rounded by up to {worst:.3e} m (write .usdc or .abc to keep them)",
            path.display()
        )
    })
}

/// One line per kind of change writing `groom` (in `units`) to `path` must
/// make to the data: units the file cannot keep, attributes the format
/// cannot hold, curve types or a wrap it cannot write. Empty when the file
/// holds the groom as it is. `convert` and the bake print these (and
/// `--strict` refuses them).
pub fn warnings(path: &Path, groom: &Groom, units: Units) -> Vec<String> {
    let extension = extension_of(path);
    let file = path.display();
    let mut warnings: Vec<String> = units_warning(path, units).into_iter().collect();
    if groom.up_axis != UpAxis::Y && matches!(extension.as_str(), "abc" | "hair" | "data") {
        warnings.push(format!(
            "{file}: .{extension} is read Y up by every reader and records no axis: written Y up, not {} up",
            groom.up_axis
        ));
    }
    if let Some(frame) = groom.frames.first() {
        let names: Vec<&str> = frame.attributes.iter().map(|a| a.name.as_str()).collect();
        warnings.extend(frame_attributes_warning(path, &names));
    }
    if matches!(extension.as_str(), "gltf" | "glb") {
        warnings.extend(morph_target_rounding_warning(path, groom));
    }
    let dropped: Vec<&str> = groom
        .attributes
        .iter()
        .map(|a| a.name.as_str())
        .filter(|name| match extension.as_str() {
            "obj" | "data" => true,
            "hair" => !matches!(
                (*name, groom.attribute(name).map(|a| &a.values)),
                ("width" | "transparency", Some(AttributeValues::Float(_)))
                    | ("color", Some(AttributeValues::Vec3(_)))
            ),
            _ => false,
        })
        .collect();
    if !dropped.is_empty() {
        warnings.push(format!(
            "{file}: .{extension} cannot hold attribute(s) {}: dropped",
            dropped.join(", ")
        ));
    }
    let usd = matches!(extension.as_str(), "usda" | "usdc" | "usd");
    if usd {
        // USD names a primvar with an identifier: any other name is
        // written changed, which a reader would not find under its name.
        let renamed: Vec<String> = groom
            .attributes
            .iter()
            .filter(|a| usd::identifier(&a.name) != a.name)
            .map(|a| format!("{:?} as {}", a.name, usd::identifier(&a.name)))
            .collect();
        if !renamed.is_empty() {
            warnings.push(format!(
                "{file}: attribute name(s) that are not USD identifiers written changed: {}",
                renamed.join(", ")
            ));
        }
    }
    let bases = groom.attribute("curve_basis").map(|a| match &a.values {
        AttributeValues::Int(codes) => codes.iter().any(|&c| Some(&c) != codes.first()),
        _ => false,
    });
    // USD writes one prim per curve type and wrap (usd::PrimKey), static
    // and animated alike.
    let grouped = usd;
    if bases == Some(true) && !grouped {
        warnings.push(format!(
            "{file}: strands of several curve types (curve_basis): all written as {}",
            groom.basis.name()
        ));
    }
    let wrap = groom
        .provenance
        .metadata
        .get("usd.wrap")
        .map(String::as_str);
    match wrap {
        Some("mixed") if !grouped => warnings.push(format!(
            "{file}: curves of several wraps: all written as nonperiodic"
        )),
        Some(wrap @ ("pinned" | "periodic")) if !usd => warnings.push(format!(
            "{file}: wrap {wrap}: .{extension} writes nonperiodic curves"
        )),
        _ => {}
    }
    warnings
}

/// What a format changes about strand order or the base pose of a groom
/// read from a file (`convert`), said rather than done silently: USD and
/// glTF write guides before render strands (one prim or primitive each),
/// and Alembic stores the frames only, so a base pose that is not frame 0
/// (an animated USD's default `points`) is lost.
pub fn order_and_pose_warnings(path: &Path, groom: &Groom) -> Vec<String> {
    let extension = extension_of(path);
    let file = path.display();
    let mut warnings = Vec::new();
    let splits_guides = matches!(extension.as_str(), "usda" | "usdc" | "usd" | "gltf" | "glb");
    if let (true, Some(guide)) = (splits_guides, groom.attribute(groom::guides::GROOM_GUIDE)) {
        if let (Scope::Strand, AttributeValues::Int(flags)) = (guide.scope, &guide.values) {
            let guide_after_render = flags.iter().skip_while(|&&f| f != 0).any(|&f| f != 0);
            if guide_after_render {
                warnings.push(format!(
                    "{file}: guides and render strands (groom_guide) are interleaved: \
                     .{extension} writes the guides first, so the strands are reordered"
                ));
            }
        }
    }
    if extension == "abc" {
        if let Some(first) = groom.frames.first() {
            if first.points != groom.points {
                warnings.push(format!(
                    "{file}: the base pose differs from frame 0 (at {} s): .abc stores the \
                     frames only, so the base pose is dropped",
                    first.time
                ));
            }
        }
    }
    warnings
}

fn extension_of(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

pub(crate) fn extension_is(path: &Path, extension: &str) -> bool {
    extension_of(path) == extension
}

/// A float attribute as one value per vertex (per-strand values repeated on
/// their strand); `None` when the groom has no float attribute of that name.
pub(crate) fn vertex_floats(groom: &Groom, name: &str) -> Option<Vec<f32>> {
    let attribute = groom.attribute(name)?;
    let AttributeValues::Float(values) = &attribute.values else {
        return None;
    };
    Some(per_vertex(groom, attribute.scope, values))
}

/// A vec3 attribute as one value per vertex, like [`vertex_floats`].
pub(crate) fn vertex_vec3s(groom: &Groom, name: &str) -> Option<Vec<[f32; 3]>> {
    let attribute = groom.attribute(name)?;
    let AttributeValues::Vec3(values) = &attribute.values else {
        return None;
    };
    Some(per_vertex(groom, attribute.scope, values))
}

fn per_vertex<T: Copy>(groom: &Groom, scope: Scope, values: &[T]) -> Vec<T> {
    match scope {
        Scope::Vertex => values.to_vec(),
        Scope::Strand => groom
            .strand_vertex_counts
            .iter()
            .zip(values)
            .flat_map(|(&n, &v)| std::iter::repeat_n(v, n as usize))
            .collect(),
    }
}

#[cfg(test)]
mod tests;
