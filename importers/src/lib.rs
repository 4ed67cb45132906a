//! Groom file readers. Each module reads one format into a [`groom::Groom`];
//! [`read`] picks the module from the file extension.
//!
//! Every reader checks counts and offsets against the bytes it has before it
//! allocates or indexes, and reports what is wrong with the file and where.

pub mod abc;
mod binary;
pub mod data;
pub mod gltf;
pub mod hair;
mod mapped;
pub mod mesh;
mod mesh_types;
pub mod obj;
mod obj_syntax;
pub mod stream;
mod transform;
pub mod usd;

use groom::Groom;
use std::fmt;
use std::path::{Path, PathBuf};

/// Where in a file a problem is.
#[derive(Debug, Clone, PartialEq)]
pub enum Place {
    /// The file as a whole.
    File,
    /// A byte offset (binary formats).
    Offset(u64),
    /// A 1-based line and column (text formats); column 0 when unknown.
    Line { line: usize, column: usize },
    /// A path inside the file's own structure (a JSON pointer, a prim or object path).
    Path(String),
}

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Place::File => Ok(()),
            Place::Offset(offset) => write!(f, ":offset {offset}"),
            Place::Line { line, column: 0 } => write!(f, ":{line}"),
            Place::Line { line, column } => write!(f, ":{line}:{column}"),
            Place::Path(path) => write!(f, ":{path}"),
        }
    }
}

/// Why a file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    #[error("{}: {source}", file.display())]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}{place}: {message}", file.display())]
    Malformed {
        file: PathBuf,
        place: Place,
        message: String,
    },
    #[error("{}: unknown groom format (known extensions: {})", file.display(), EXTENSIONS.join(", "))]
    UnknownFormat { file: PathBuf },
}

impl ImportError {
    /// A problem in a file's contents. Messages and places often quote the
    /// file (names, tokens, paths): control characters in them are escaped
    /// so that an error line stays one printable line.
    pub fn malformed(file: &Path, place: Place, message: impl Into<String>) -> ImportError {
        let place = match place {
            Place::Path(path) => Place::Path(escape_controls(&path)),
            other => other,
        };
        ImportError::Malformed {
            file: file.to_path_buf(),
            place,
            message: escape_controls(&message.into()),
        }
    }

    pub fn io(file: &Path, source: std::io::Error) -> ImportError {
        ImportError::Io {
            file: file.to_path_buf(),
            source,
        }
    }
}

/// Text with control characters (NUL, escape, newlines, ...) written as
/// Rust escapes (`\0`, `\u{1b}`, `\n`); other characters unchanged.
pub fn escape_controls(text: &str) -> String {
    if !text.chars().any(char::is_control) {
        return text.to_string();
    }
    text.chars()
        .map(|c| {
            if c.is_control() {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

/// The file extensions [`read`] knows, lower case, without the dot.
pub const EXTENSIONS: &[&str] = &[
    "hair", "data", "obj", "gltf", "glb", "usda", "usdc", "usd", "abc",
];

/// The lower-case extension of a path.
pub fn extension_of(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

/// Reads a groom file, choosing the format by its extension. The groom's
/// provenance names the file and format.
pub fn read(path: &Path) -> Result<Groom, ImportError> {
    let mut groom: Groom = match extension_of(path).as_str() {
        "hair" => hair::read(path)?,
        "data" => data::read(path)?,
        "obj" => obj::read(path)?,
        "gltf" | "glb" => gltf::read(path)?,
        "usda" | "usdc" | "usd" => usd::read(path)?,
        "abc" => abc::read(path)?,
        _ => {
            return Err(ImportError::UnknownFormat {
                file: path.to_path_buf(),
            })
        }
    };
    if groom.strand_count() == 0 {
        refuse_mesh(path)?;
    }
    groom.provenance.source = Some(path.to_path_buf());
    if groom.provenance.units_source.is_empty() {
        // The readers that decide by a rule of their own (.obj, .abc) say so;
        // USD and glTF record units, the other formats follow their convention.
        groom.provenance.units_source = match groom.provenance.format.as_str() {
            "usd" | "gltf" => "file",
            _ => "format",
        }
        .into();
    }
    Ok(groom)
}

/// Reads a groom file as a sequence of grooms, one per stretch of time
/// with one topology (strand and point counts), in time order; each has the
/// frames of its stretch. Every file is one groom, except a USD file whose
/// `curveVertexCounts` change over time, which [`read`] refuses (`topology
/// changes at time T`): `inspect` and `convert` carry that sequence.
pub fn read_sequence(path: &Path) -> Result<Vec<Groom>, ImportError> {
    if !matches!(extension_of(path).as_str(), "usda" | "usdc" | "usd") {
        return Ok(vec![read(path)?]);
    }
    let mut grooms = usd::read_sequence(path)?;
    for groom in &mut grooms {
        if groom.strand_count() == 0 {
            refuse_mesh(path)?;
        }
        groom.provenance.source = Some(path.to_path_buf());
        groom.provenance.units_source = "file".into();
    }
    Ok(grooms)
}

/// A file with no curves that holds a triangle mesh (a head, a pillow) was
/// given where hair is expected: an error saying so, rather than an empty
/// groom that converts and bakes to nothing.
fn refuse_mesh(path: &Path) -> Result<(), ImportError> {
    if !matches!(extension_of(path).as_str(), "obj" | "gltf" | "glb") {
        return Ok(());
    }
    // No triangles either (or an unreadable mesh): an empty groom, not a mesh.
    let Ok((_, triangles)) = mesh::read_triangles(path) else {
        return Ok(());
    };
    Err(ImportError::malformed(
        path,
        Place::File,
        format!(
            "a triangle mesh ({} triangles) and no curves: hair is read from polylines \
             (.obj `l`, glTF LINES/LINE_STRIP); a mesh is a collider (`shape = {{ mesh = ... }}`)",
            triangles.len()
        ),
    ))
}

/// The largest input file read whole, bytes (groombake's resource budget
/// quotes it): a full head of 150,000 strands of 64 vertices with frames
/// is a few GB.
pub const MAX_FILE_BYTES: u64 = 8 << 30;

/// What kind of file system entry a path is, when it is not a regular file
/// (`None` for a regular file).
pub fn special_kind(metadata: &std::fs::Metadata) -> Option<&'static str> {
    use std::os::unix::fs::FileTypeExt;
    let kind = metadata.file_type();
    if kind.is_file() {
        None
    } else if kind.is_dir() {
        Some("a directory")
    } else if kind.is_char_device() {
        Some("a character device")
    } else if kind.is_block_device() {
        Some("a block device")
    } else if kind.is_fifo() {
        Some("a FIFO (named pipe)")
    } else if kind.is_socket() {
        Some("a socket")
    } else {
        Some("not a regular file")
    }
}

/// Why [`read_limited`] read nothing.
#[derive(Debug, thiserror::Error)]
pub enum ReadFailure {
    #[error("{0}")]
    Io(#[from] std::io::Error),
    #[error("{0}, not a regular file: inputs are read from regular files")]
    Special(&'static str),
    #[error("larger than {0} bytes, the most this input may be")]
    TooLarge(u64),
}

/// Reads a whole input file of at most `max_bytes`. Only a regular file
/// is read: a device (`/dev/zero`) never ends, a FIFO blocks, and either
/// would be read until memory runs out. The kind is taken from the opened
/// file (not the name, which could be replaced in between), and the read
/// stops at the bound whatever the size said.
pub fn read_limited(path: &Path, max_bytes: u64) -> Result<Vec<u8>, ReadFailure> {
    use std::io::Read;
    use std::os::unix::fs::OpenOptionsExt;
    // Non-blocking open: opening a FIFO with no writer would block.
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)?;
    let metadata = file.metadata()?;
    if let Some(kind) = special_kind(&metadata) {
        return Err(ReadFailure::Special(kind));
    }
    if metadata.len() > max_bytes {
        return Err(ReadFailure::TooLarge(max_bytes));
    }
    let mut bytes = Vec::with_capacity(metadata.len() as usize);
    file.take(max_bytes.saturating_add(1))
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max_bytes {
        return Err(ReadFailure::TooLarge(max_bytes));
    }
    Ok(bytes)
}

/// Reads a whole input file ([`read_limited`] to [`MAX_FILE_BYTES`]),
/// naming it in the error.
pub fn read_bytes(path: &Path) -> Result<Vec<u8>, ImportError> {
    read_limited(path, MAX_FILE_BYTES).map_err(|failure| match failure {
        ReadFailure::Io(e) => ImportError::io(path, e),
        other => ImportError::malformed(path, Place::File, other.to_string()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_bytes_from_a_file_are_escaped_in_its_error() {
        let cases: [(&str, &[u8], &str); 2] = [
            (
                "bad.obj",
                b"v 0 0 0\nv 1 \x1b[31mX\x00 0\nl 1 2\n",
                r"bad.obj:2:5: '\u{1b}[31mX\u{0}' is not a number",
            ),
            (
                "bad.usda",
                b"#usda 1.0\ndef BasisCurves \"a\x07b\" {\n}\n",
                r"bad.usda:2:17: 'a\u{7}b' is not a valid prim name",
            ),
        ];
        for (name, bytes, expected) in cases {
            let path = Path::new(name);
            let error = match extension_of(path).as_str() {
                "obj" => obj::parse(path, bytes).map(|_| ()),
                _ => usd::read_bytes(path, bytes).map(|_| ()),
            }
            .unwrap_err()
            .to_string();
            assert_eq!(error, expected);
            assert!(!error.chars().any(char::is_control), "{error:?}");
        }
    }
}
