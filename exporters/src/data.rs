//! USC-HairSalon `.data`: i32 strand count, then per strand an i32 point
//! count and its f32 points.

use crate::ExportError;
use groom::{AtomicFile, Groom};
use std::io::Write;
use std::path::Path;

pub fn write(path: &Path, groom: &Groom) -> Result<(), ExportError> {
    let invalid = |message: String| ExportError::Invalid {
        file: path.to_path_buf(),
        message,
    };
    let strand_count = i32::try_from(groom.strand_count())
        .map_err(|_| invalid("more strands than a .data file can hold".into()))?;
    let io = |e| ExportError::io(path, e);
    let mut out = AtomicFile::create(path).map_err(io)?;
    out.write_all(&strand_count.to_le_bytes()).map_err(io)?;
    for (strand, points) in groom.strands().enumerate() {
        let count = i32::try_from(points.len())
            .map_err(|_| invalid(format!("strand {strand} has too many points for .data")))?;
        out.write_all(&count.to_le_bytes()).map_err(io)?;
        for value in points.iter().flatten() {
            out.write_all(&value.to_le_bytes()).map_err(io)?;
        }
    }
    out.commit().map_err(io)
}
