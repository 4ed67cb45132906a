//! Cem Yuksel's `.hair`. Mirrors the importer so that `.hair` -> `.hair`
//! keeps the arrays byte for byte: the segments array is written only when
//! the strands differ in length (otherwise the header's default segment count
//! says it), and the thickness, transparency and colour arrays only when the
//! groom has the `width`, `transparency` and `color` attributes the importer
//! makes of them; missing ones get cyHairFile's defaults in the header.

use crate::{vertex_floats, vertex_vec3s, ExportError};
use groom::{AtomicFile, Groom};
use std::io::Write;
use std::path::Path;

const HAS_SEGMENTS: u32 = 1;
const HAS_POINTS: u32 = 2;
const HAS_THICKNESS: u32 = 4;
const HAS_TRANSPARENCY: u32 = 8;
const HAS_COLORS: u32 = 16;
const INFO_SIZE: usize = 88;

pub fn write(path: &Path, groom: &Groom) -> Result<(), ExportError> {
    let invalid = |message: String| ExportError::Invalid {
        file: path.to_path_buf(),
        message,
    };
    let hair_count = u32::try_from(groom.strand_count())
        .map_err(|_| invalid("more strands than a .hair file can hold".into()))?;
    let point_count = u32::try_from(groom.vertex_count())
        .map_err(|_| invalid("more points than a .hair file can hold".into()))?;
    let mut segments = Vec::with_capacity(groom.strand_count());
    for (strand, &count) in groom.strand_vertex_counts.iter().enumerate() {
        let segment_count = count
            .checked_sub(1)
            .and_then(|s| u16::try_from(s).ok())
            .ok_or_else(|| {
                invalid(format!(
                    "strand {strand} has {count} points; .hair holds 1 to 65536 per strand"
                ))
            })?;
        segments.push(segment_count);
    }
    let uniform = segments.windows(2).all(|w| w[0] == w[1]);
    let thickness = vertex_floats(groom, "width");
    let transparency = vertex_floats(groom, "transparency");
    let colors = vertex_vec3s(groom, "color");

    let mut flags = HAS_POINTS;
    let mut default_segments = 0u32;
    if uniform {
        default_segments = segments.first().copied().unwrap_or(0) as u32;
    } else {
        flags |= HAS_SEGMENTS;
    }
    if thickness.is_some() {
        flags |= HAS_THICKNESS;
    }
    if transparency.is_some() {
        flags |= HAS_TRANSPARENCY;
    }
    if colors.is_some() {
        flags |= HAS_COLORS;
    }

    let mut header = Vec::with_capacity(128);
    header.extend_from_slice(b"HAIR");
    header.extend_from_slice(&hair_count.to_le_bytes());
    header.extend_from_slice(&point_count.to_le_bytes());
    header.extend_from_slice(&flags.to_le_bytes());
    header.extend_from_slice(&default_segments.to_le_bytes());
    for value in [1.0f32, 0.0, 1.0, 1.0, 1.0] {
        header.extend_from_slice(&value.to_le_bytes());
    }
    let mut info = [0u8; INFO_SIZE];
    let text = truncate_at_char(&groom.provenance.info, INFO_SIZE);
    info[..text.len()].copy_from_slice(text.as_bytes());
    header.extend_from_slice(&info);

    let io = |e| ExportError::io(path, e);
    let mut out = AtomicFile::create(path).map_err(io)?;
    out.write_all(&header).map_err(io)?;
    if flags & HAS_SEGMENTS != 0 {
        for s in &segments {
            out.write_all(&s.to_le_bytes()).map_err(io)?;
        }
    }
    for value in groom.points.iter().flatten() {
        out.write_all(&value.to_le_bytes()).map_err(io)?;
    }
    for array in [&thickness, &transparency].into_iter().flatten() {
        for value in array {
            out.write_all(&value.to_le_bytes()).map_err(io)?;
        }
    }
    if let Some(colors) = &colors {
        for value in colors.iter().flatten() {
            out.write_all(&value.to_le_bytes()).map_err(io)?;
        }
    }
    out.commit().map_err(io)
}

/// The longest prefix of `text` of at most `max` bytes that ends on a
/// character boundary.
fn truncate_at_char(text: &str, max: usize) -> &str {
    let mut end = text.len().min(max);
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    &text[..end]
}
