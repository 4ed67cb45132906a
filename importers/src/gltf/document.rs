//! From bytes to a glTF document whose every reference is checked before
//! use: the GLB container, the JSON parsed into the `gltf-json` types, the
//! buffers loaded, and lookups that check each index and enum taken from
//! the file and name the JSON pointer of a bad one.
//!
//! The `gltf` crate's own loading is not used: its validation
//! (`Gltf::from_slice`) indexes `accessors` with the POSITION attribute's
//! index before checking it, its wrapper types `unwrap` every index and enum
//! (an animation channel's `target.node` and `target.path`), and its GLB
//! header check subtracts 12 from the file's length field without a check.
//! Each of those is a panic on a bad file; here each is an error.

use crate::{ImportError, Place};
use base64::Engine;
use gltf::json;
use json::validation::Checked;
use std::borrow::Cow;
use std::cell::Cell;
use std::collections::BTreeMap;
use std::path::Path;

pub(super) struct Document<'a> {
    pub path: &'a Path,
    pub root: json::Root,
    /// Buffer `i`'s bytes are `blobs[blob_of_buffer[i]]`: buffers that name
    /// the same source (the GLB chunk, one file) share one copy.
    blob_of_buffer: Vec<usize>,
    blobs: Vec<Cow<'a, [u8]>>,
    /// Bytes accessors may still decode: a few times the bytes present, so
    /// that many references to one large accessor cannot multiply it.
    decode_budget: Cell<u64>,
    /// Animation channels with no `target.node` (animation, channel, path):
    /// glTF allows them for an extension's target (KHR_animation_pointer);
    /// the `gltf-json` types require a node, so they are given node 0 and
    /// an unknown path, which animates nothing here.
    pub nodeless_channels: Vec<NodelessChannel>,
}

/// An animation channel with no `target.node`: animation, channel, path.
pub(super) type NodelessChannel = (usize, usize, String);

/// The document of JSON that `gltf-json` refused only because animation
/// channels have no `target.node`, with those channels listed; `None` when
/// it has none or is still refused with them filled in.
fn nodeless_channels(json_bytes: &[u8]) -> Option<(json::Root, Vec<NodelessChannel>)> {
    let mut value: serde_json::Value = serde_json::from_slice(json_bytes).ok()?;
    let mut nodeless = Vec::new();
    let animations = value.get_mut("animations")?.as_array_mut()?;
    for (a, animation) in animations.iter_mut().enumerate() {
        let Some(channels) = animation.get_mut("channels").and_then(|c| c.as_array_mut()) else {
            continue;
        };
        for (c, channel) in channels.iter_mut().enumerate() {
            let Some(target) = channel.get_mut("target").and_then(|t| t.as_object_mut()) else {
                continue;
            };
            if target.contains_key("node") {
                continue;
            }
            let path = target
                .get("path")
                .and_then(|p| p.as_str())
                .unwrap_or("")
                .to_string();
            target.insert("node".into(), serde_json::json!(0));
            target.insert("path".into(), serde_json::json!("(no node)"));
            nodeless.push((a, c, path));
        }
    }
    if nodeless.is_empty() {
        return None;
    }
    let root = serde_json::from_value(value).ok()?;
    Some((root, nodeless))
}

/// How many times over the file's bytes (and its buffers') the accessors
/// may be decoded in all, plus a fixed allowance for small files.
const DECODE_FACTOR: u64 = 8;
const DECODE_ALLOWANCE: u64 = 64 << 20;

const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

impl<'a> Document<'a> {
    /// Parses the JSON (or GLB) and loads every buffer, checking each holds
    /// the bytes its `byteLength` announces.
    pub fn load(path: &'a Path, bytes: &'a [u8]) -> Result<Document<'a>, ImportError> {
        let (json_bytes, bin) = if bytes.starts_with(GLB_MAGIC) {
            split_glb(path, bytes)?
        } else {
            (bytes, None)
        };
        let (root, nodeless_channels) = match serde_json::from_slice::<json::Root>(json_bytes) {
            Ok(root) => (root, Vec::new()),
            Err(e) => nodeless_channels(json_bytes).ok_or_else(|| {
                ImportError::malformed(
                    path,
                    Place::Line {
                        line: e.line(),
                        column: e.column(),
                    },
                    format!("invalid glTF JSON: {e}"),
                )
            })?,
        };
        let mut document = Document {
            path,
            root,
            nodeless_channels,
            blob_of_buffer: Vec::new(),
            blobs: Vec::new(),
            decode_budget: Cell::new(0),
        };
        document.load_buffers(bin)?;
        let present = bytes.len() as u64
            + document
                .blobs
                .iter()
                .filter(|b| matches!(b, Cow::Owned(_)))
                .map(|b| b.len() as u64)
                .sum::<u64>();
        document
            .decode_budget
            .set(present.saturating_mul(DECODE_FACTOR) + DECODE_ALLOWANCE);
        Ok(document)
    }

    fn load_buffers(&mut self, bin: Option<&'a [u8]>) -> Result<(), ImportError> {
        let mut blob_of_source: BTreeMap<Option<String>, usize> = BTreeMap::new();
        for (index, buffer) in self.root.buffers.iter().enumerate() {
            let place = Place::Path(format!("/buffers/{index}"));
            let length = buffer.byte_length.0;
            let blob = match blob_of_source.get(&buffer.uri) {
                Some(&blob) => blob,
                None => {
                    let data = match &buffer.uri {
                        None => Cow::Borrowed(bin.ok_or_else(|| {
                            ImportError::malformed(
                                self.path,
                                place.clone(),
                                "refers to a GLB BIN chunk, but there is none",
                            )
                        })?),
                        Some(uri) => Cow::Owned(load_uri(self.path, &place, uri, length)?),
                    };
                    self.blobs.push(data);
                    blob_of_source.insert(buffer.uri.clone(), self.blobs.len() - 1);
                    self.blobs.len() - 1
                }
            };
            let have = self.blobs[blob].len();
            if (have as u64) < length {
                return Err(ImportError::malformed(
                    self.path,
                    place,
                    format!("byteLength is {length} but the data has {have} bytes"),
                ));
            }
            self.blob_of_buffer.push(blob);
        }
        Ok(())
    }

    /// Takes `bytes` from the decode budget, or says the file's references
    /// ask for more than its bytes can back.
    pub fn charge(&self, bytes: u64, place: impl FnOnce() -> String) -> Result<(), ImportError> {
        let left = self.decode_budget.get();
        if bytes > left {
            return Err(self.error(
                place(),
                format!(
                    "the file's references ask to decode more than {DECODE_FACTOR} times its \
                     bytes (an accessor referenced very many times, or many keyframes of \
                     many points?)"
                ),
            ));
        }
        self.decode_budget.set(left - bytes);
        Ok(())
    }

    pub fn error(&self, place: impl Into<String>, message: impl Into<String>) -> ImportError {
        ImportError::malformed(self.path, Place::Path(place.into()), message)
    }

    /// The bytes of buffer `index` (checked against the buffers' count).
    pub fn buffer(
        &self,
        index: usize,
        from: impl FnOnce() -> String,
    ) -> Result<&[u8], ImportError> {
        match self.blob_of_buffer.get(index) {
            Some(&blob) => Ok(&self.blobs[blob]),
            None => Err(self.missing(from(), "buffer", index, self.blob_of_buffer.len())),
        }
    }

    /// `items[index]`, or an error at `from` (the JSON pointer of the
    /// reference) naming what is missing.
    pub fn get<'r, T>(
        &self,
        items: &'r [T],
        index: usize,
        what: &str,
        from: impl FnOnce() -> String,
    ) -> Result<&'r T, ImportError> {
        items
            .get(index)
            .ok_or_else(|| self.missing(from(), what, index, items.len()))
    }

    fn missing(&self, place: String, what: &str, index: usize, count: usize) -> ImportError {
        self.error(
            place,
            format!("{what} {index} does not exist (the file has {count} {what}s)"),
        )
    }

    /// The value of an enum field, or an error at `place` if the file's
    /// value is not one glTF defines.
    pub fn valid<T: Copy>(
        &self,
        value: &Checked<T>,
        what: &str,
        place: impl FnOnce() -> String,
    ) -> Result<T, ImportError> {
        match value {
            Checked::Valid(v) => Ok(*v),
            Checked::Invalid => Err(self.error(place(), format!("unknown {what}"))),
        }
    }
}

/// The JSON chunk and the BIN chunk (if any) of a GLB (glTF 2.0 section 4.4).
fn split_glb<'b>(
    path: &'b Path,
    bytes: &'b [u8],
) -> Result<(&'b [u8], Option<&'b [u8]>), ImportError> {
    let error = |offset: usize, message: String| {
        ImportError::malformed(path, Place::Offset(offset as u64), message)
    };
    let mut cursor = crate::binary::Cursor::new(path, bytes);
    cursor.take(4, "GLB magic")?;
    let version = cursor.u32("GLB version")?;
    if version != 2 {
        return Err(error(
            4,
            format!("GLB version {version}, only 2 is supported"),
        ));
    }
    let length = cursor.u32("GLB length")? as usize;
    if length > bytes.len() || length < 12 {
        return Err(error(
            8,
            format!(
                "GLB length is {length} but the file has {} bytes",
                bytes.len()
            ),
        ));
    }
    let mut cursor = crate::binary::Cursor::new(path, &bytes[..length]);
    cursor.take(12, "GLB header")?;
    let mut chunk = |expected: u32, what: &str| -> Result<Option<&'b [u8]>, ImportError> {
        if cursor.remaining() == 0 && expected == CHUNK_BIN {
            return Ok(None);
        }
        let at = cursor.position();
        let size = cursor.u32(&format!("{what} chunk length"))? as usize;
        let kind = cursor.u32(&format!("{what} chunk type"))?;
        if kind != expected {
            return Err(error(
                at + 4,
                format!("chunk type {kind:#010x} where the {what} chunk belongs"),
            ));
        }
        cursor.take(size, &format!("{what} chunk")).map(Some)
    };
    let json = chunk(CHUNK_JSON, "JSON")?.unwrap_or_default();
    let bin = chunk(CHUNK_BIN, "BIN")?;
    Ok((json, bin))
}

/// A buffer's bytes from a base64 data URI or a file beside the glTF. A
/// file is read only up to `length` bytes, and only if it is a regular file
/// that holds them (not a device that never ends).
fn load_uri(path: &Path, place: &Place, uri: &str, length: u64) -> Result<Vec<u8>, ImportError> {
    let error = |message: String| ImportError::malformed(path, place.clone(), message);
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((_, payload)) = rest.split_once(";base64,") else {
            return Err(error("data URI is not base64".into()));
        };
        return base64::engine::general_purpose::STANDARD
            .decode(payload)
            .map_err(|e| error(format!("bad base64 data: {e}")));
    }
    if uri.contains("://") {
        return Err(error(format!("cannot read remote buffer {uri}")));
    }
    let file = path
        .parent()
        .unwrap_or(Path::new("."))
        .join(percent_decode(uri));
    let cannot = |e: &dyn std::fmt::Display| {
        error(format!("cannot read buffer file {}: {e}", file.display()))
    };
    let metadata = std::fs::metadata(&file).map_err(|e| cannot(&e))?;
    if !metadata.is_file() {
        return Err(cannot(&"not a regular file"));
    }
    if metadata.len() < length {
        return Err(error(format!(
            "byteLength is {length} but buffer file {} has {} bytes",
            file.display(),
            metadata.len()
        )));
    }
    let mut data = Vec::new();
    use std::io::Read;
    std::fs::File::open(&file)
        .and_then(|f| f.take(length).read_to_end(&mut data))
        .map_err(|e| cannot(&e))?;
    Ok(data)
}

/// Relative URIs may escape characters as `%XX`.
pub(super) fn percent_decode(uri: &str) -> String {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            let hex = std::str::from_utf8(&bytes[i + 1..i + 3]).unwrap_or("");
            if let Ok(v) = u8::from_str_radix(hex, 16) {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}
