//! Wavefront `.obj` polylines: every point as `v`, every strand as one `l`
//! statement. Coordinates are printed in the shortest form that reads back to
//! the same f32, so `.obj` round trips are exact. A single-point strand is
//! written as a one-index `l`, which the importer reads back as such.

use crate::ExportError;
use groom::{AtomicFile, Groom};
use std::io::Write;
use std::path::Path;

pub fn write(path: &Path, groom: &Groom) -> Result<(), ExportError> {
    let io = |e| ExportError::io(path, e);
    let mut out = AtomicFile::create(path).map_err(io)?;
    writeln!(
        out,
        "# groombake: {} strands, {} points, units {} ({} m), up {}",
        groom.strand_count(),
        groom.vertex_count(),
        groom.units,
        groom.units.meters_per_unit,
        groom.up_axis
    )
    .map_err(io)?;
    for [x, y, z] in &groom.points {
        writeln!(out, "v {x} {y} {z}").map_err(io)?;
    }
    let mut next = 1u64;
    for &count in &groom.strand_vertex_counts {
        let mut line = String::from("l");
        for index in next..next + count as u64 {
            line.push(' ');
            line.push_str(&index.to_string());
        }
        writeln!(out, "{line}").map_err(io)?;
        next += count as u64;
    }
    out.commit().map_err(io)
}
