//! Groom file writers. Each module writes one format; [`write`] and
//! [`animated`] pick the module from the file extension.
//!
//! Outputs go through [`groom::AtomicFile`]: a failed export never leaves a
//! partial file. Animation is streamed: [`animated`] returns a
//! [`FrameWriter`] that takes one frame at a time, so memory does not grow
//! with the number of frames.

pub mod abc;

use groom::{Frame, Groom};
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
pub const EXTENSIONS: &[&str] = &["hair", "data", "obj", "gltf", "glb", "abc"];

/// How animation is to be written.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnimationOptions {
    /// Frames per second of the time codes.
    pub fps: f64,
    /// The number of frames that will be written (formats that need it up front).
    pub frame_count: usize,
}

/// Takes the frames of an animated export one at a time.
pub trait FrameWriter {
    /// Writes one frame; its points follow the topology of the groom given to
    /// [`animated`].
    fn write_frame(&mut self, frame: &Frame) -> Result<(), ExportError>;
    /// Completes the file and renames it into place.
    fn finish(self: Box<Self>) -> Result<(), ExportError>;
}

fn check_exportable(path: &Path, groom: &Groom) -> Result<(), ExportError> {
    if let Some(problem) = groom.validate().into_iter().find(|p| p.is_fatal()) {
        return Err(ExportError::Invalid {
            file: path.to_path_buf(),
            message: problem.to_string(),
        });
    }
    Ok(())
}

/// Writes a groom, choosing the format by extension. A groom with frames is
/// written animated where the format can hold animation; the static formats
/// (`.hair`, `.data`, `.obj`) write its points.
pub fn write(path: &Path, groom: &Groom) -> Result<(), ExportError> {
    check_exportable(path, groom)?;
    match extension_of(path).as_str() {
        "abc" => abc::write(path, groom),
        _ => Err(ExportError::UnknownFormat {
            file: path.to_path_buf(),
        }),
    }
}

/// Starts an animated export of `groom`'s topology and attributes.
pub fn animated(
    path: &Path,
    groom: &Groom,
    options: AnimationOptions,
) -> Result<Box<dyn FrameWriter>, ExportError> {
    check_exportable(path, groom)?;
    match extension_of(path).as_str() {
        "abc" => abc::animated(path, groom, options),
        _ => Err(ExportError::UnknownFormat {
            file: path.to_path_buf(),
        }),
    }
}

/// The lower-case extension of a path.
fn extension_of(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}
