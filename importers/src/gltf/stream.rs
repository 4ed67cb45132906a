//! Frame-at-a-time reading of a `.glb` ([`crate::stream`]).
//!
//! Opening reads the scene as a whole read does but only checks each
//! morph target (its accessor's type, count and byte range:
//! [`Targets::Check`]), so the rest groom and the keyframe times cost the
//! topology, not the targets. Frame `k` parses the JSON again (a few
//! milliseconds next to the targets' data), walks the scene the same way,
//! reads only the targets that keyframe `k` weights with a nonzero weight,
//! and builds the frame with the whole read's [`Document::frame`]: the
//! frames equal [`super::parse`]'s (a test compares them).
//!
//! Only a GLB whose buffers are all its BIN chunk streams: a buffer in a
//! base64 data URI or an external file would be decoded or read again for
//! every frame, so such files (and `.gltf` JSON) are read whole.
//!
//! What the whole read finds in a target's values, a value that is not
//! finite or more decoding than the file's bytes allow, the stream finds
//! when a frame weights that target, with the same message; a target no
//! keyframe weights is never read, so its bad values go unnoticed.

use super::document::Document;
use super::lines::Targets;
use super::{add_losses, line_pieces, rest_groom};
use crate::{ImportError, Place};
use groom::{Frame, Groom};
use std::path::Path;

/// An open GLB whose frames are read one at a time.
pub(crate) struct GltfStream {
    frame_count: usize,
}

/// The groom a stream starts from: rest points, topology and attributes
/// (no frames), and the frames' times in seconds.
pub(crate) struct Opened {
    pub stream: GltfStream,
    pub groom: Groom,
    pub times: Vec<f64>,
}

impl GltfStream {
    /// Opens the GLB `bytes` (named `path` in errors); `None` when it is not
    /// one that streams (see the module doc), or has no strands or no
    /// animation, to be read whole.
    pub(crate) fn open(path: &Path, bytes: &[u8]) -> Result<Option<Opened>, ImportError> {
        if !bytes.starts_with(b"glTF") {
            return Ok(None);
        }
        let document = Document::load(path, bytes)?;
        if document.root.buffers.iter().any(|b| b.uri.is_some()) {
            return Ok(None);
        }
        let (decoded, pieces, skipped) = line_pieces(&document, Targets::Check)?;
        let mut groom = rest_groom(&document, &decoded, &pieces)?;
        let Some(keyframes) = document.keyframes()? else {
            return Ok(None);
        };
        // The whole read refuses frames too many to hold; so does the
        // stream, though it holds one at a time, to read the same files.
        document.check_frames(&keyframes, &decoded, &pieces)?;
        add_losses(&mut groom, &document, &pieces, &skipped);
        if groom.strand_count() == 0 {
            return Ok(None);
        }
        let times: Vec<f64> = keyframes.times.iter().map(|&t| t as f64).collect();
        Ok(Some(Opened {
            stream: GltfStream {
                frame_count: times.len(),
            },
            groom,
            times,
        }))
    }

    /// Frame `index` of the GLB `bytes` this stream was opened on.
    pub(crate) fn frame(
        &self,
        path: &Path,
        bytes: &[u8],
        index: usize,
    ) -> Result<Frame, ImportError> {
        let missing = || {
            ImportError::malformed(
                path,
                Place::File,
                format!("no frame {index}: the file has {}", self.frame_count),
            )
        };
        if index >= self.frame_count {
            return Err(missing());
        }
        let document = Document::load(path, bytes)?;
        let (mut decoded, pieces, _) = line_pieces(&document, Targets::Check)?;
        let keyframes = document.keyframes()?.ok_or_else(missing)?;
        let mut wanted: Vec<(usize, usize)> = Vec::new();
        for piece in &pieces {
            let weights = keyframes.weights(index, piece, &decoded[piece.lines]);
            wanted.extend(
                weights
                    .iter()
                    .enumerate()
                    .filter(|(_, &w)| w != 0.0)
                    .map(|(target, _)| (piece.lines, target)),
            );
        }
        for (lines, target) in wanted {
            document.read_target(&mut decoded[lines], target)?;
        }
        document.frame(&keyframes, index, &decoded, &pieces)
    }
}
