//! Wavefront `.obj` polylines: `v x y z [w]` vertices and `l i j k ...`
//! lines (indices 1-based, negative ones relative to the vertices read so
//! far, `i/t` texture references ignored). An `l` of more than two indices is
//! one strand; consecutive two-index `l` statements that chain (each starting
//! where the previous ended) join into one strand, as segment-per-line
//! writers produce them. A one-index `l` is a single-point strand (what the
//! `.obj` exporter writes for USC-HairSalon's empty roots). Other statements
//! (faces, normals, groups, materials) are skipped.

use crate::obj_syntax::{statements, BadCoordinate, ForwardReferences};
use crate::ImportError;
use groom::{Groom, Units, UpAxis};
use std::path::Path;

pub fn read(path: &Path) -> Result<Groom, ImportError> {
    let bytes = crate::read_bytes(path)?;
    parse(path, &bytes)
}

pub fn parse(path: &Path, bytes: &[u8]) -> Result<Groom, ImportError> {
    let mut vertices: Vec<[f32; 3]> = Vec::new();
    let mut strands: Vec<Vec<usize>> = Vec::new();
    // The strand being chained from two-index `l` statements.
    let mut chain: Vec<usize> = Vec::new();
    let mut forward = ForwardReferences::default();

    for statement in statements(path, bytes) {
        let mut statement = statement?;
        match statement.keyword {
            "v" => {
                let point = statement.coordinates(|token, bad| match bad {
                    BadCoordinate::NotANumber => format!("'{token}' is not a number"),
                    BadCoordinate::NotFinite => format!("coordinate {token} is not finite"),
                })?;
                vertices.push(point);
            }
            "l" => {
                let indices = statement.vertex_indices(vertices.len(), i64::MAX, &mut forward)?;
                match indices.as_slice() {
                    [] => return Err(statement.error(1, "'l' without vertex indices".into())),
                    [a, b] => {
                        if chain.last() == Some(a) {
                            chain.push(*b);
                        } else {
                            if !chain.is_empty() {
                                strands.push(std::mem::take(&mut chain));
                            }
                            chain = vec![*a, *b];
                        }
                    }
                    _ => {
                        if !chain.is_empty() {
                            strands.push(std::mem::take(&mut chain));
                        }
                        strands.push(indices);
                    }
                }
            }
            _ => {}
        }
    }
    if !chain.is_empty() {
        strands.push(chain);
    }
    forward.check(path, vertices.len())?;
    let mut groom = Groom {
        units: Units::default(),
        up_axis: UpAxis::Y,
        ..Groom::default()
    };
    if let Some((units, up)) = groombake_header(bytes) {
        groom.units = units;
        groom.up_axis = up;
        groom.provenance.units_source = "file".into();
    }
    for strand in &strands {
        groom.strand_vertex_counts.push(strand.len() as u32);
        groom
            .points
            .extend(strand.iter().filter_map(|&i| vertices.get(i).copied()));
    }
    groom.provenance.format = "obj".into();
    Ok(groom)
}

/// The units and up axis the `.obj` exporter records in its first line,
/// `# groombake: N strands, M points, units cm (0.01 m), up Y`; `None` for
/// any other file (the units rule then takes the format's centimetres).
fn groombake_header(bytes: &[u8]) -> Option<(Units, UpAxis)> {
    let line = bytes.split(|&b| b == b'\n').next()?;
    let line = std::str::from_utf8(line).ok()?.trim_end();
    let rest = line.strip_prefix("# groombake:")?;
    let meters = rest.split_once("units ")?.1.split_once('(')?.1;
    let meters = meters.split_once(" m)")?.0.parse::<f64>().ok()?;
    if !(meters.is_finite() && meters > 0.0) {
        return None;
    }
    let up = rest.rsplit_once("up ")?.1.parse().ok()?;
    Some((
        Units {
            meters_per_unit: meters,
        },
        up,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_str(text: &str) -> Result<Groom, ImportError> {
        parse(Path::new("t.obj"), text.as_bytes())
    }

    #[test]
    fn polylines_chains_and_relative_indices() {
        let text = "# comment\no hair\nv 0 0 0\nv 0 1 0\nv 0 2 0\nv 1 0 0\r\nv 1 1 0\n\
                    l 1 2 3\nl 4 5\nl 5 -5\nl 1\n";
        let groom = parse_str(text).unwrap();
        // `l 4 5` and `l 5 1` chain into one strand; `l 1` is a single point.
        assert_eq!(groom.strand_vertex_counts, vec![3, 3, 1]);
        assert_eq!(groom.points[5], [0.0, 0.0, 0.0]);
        assert_eq!(groom.points[4], [1.0, 1.0, 0.0]);
        assert_eq!(groom.provenance.format, "obj");
    }

    #[test]
    fn non_chaining_segments_are_separate_strands() {
        let groom = parse_str("v 0 0 0\nv 0 1 0\nv 1 0 0\nv 1 1 0\nl 1 2\nl 3 4\n").unwrap();
        assert_eq!(groom.strand_vertex_counts, vec![2, 2]);
    }

    #[test]
    fn forward_references_resolve_at_the_end() {
        let groom = parse_str("l 1 2\nv 0 0 0\nv 0 1 0\n").unwrap();
        assert_eq!(groom.points, vec![[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    }

    #[test]
    fn errors_name_line_and_column() {
        let e = parse_str("v 0 0 0\nv 0 x 0\n").unwrap_err().to_string();
        assert!(e.starts_with("t.obj:2:5: 'x' is not a number"), "{e}");
        let e = parse_str("v 0 0 0\nv 0 nan 0\n").unwrap_err().to_string();
        assert!(
            e.starts_with("t.obj:2:5: coordinate nan is not finite"),
            "{e}"
        );
        let e = parse_str("v 0 0 0\nl 1  -2\n").unwrap_err().to_string();
        assert!(
            e.starts_with("t.obj:2:6: vertex index -2 is out of range"),
            "{e}"
        );
        let e = parse_str("v 0 0 0\nl 1 9\n").unwrap_err().to_string();
        assert!(
            e.starts_with("t.obj:2:5: vertex index 9 is out of range"),
            "{e}"
        );
        let e = parse_str("v 0 0\n").unwrap_err().to_string();
        assert!(e.starts_with("t.obj:1:6: vertex has 2 coordinates"), "{e}");
        let e = parse_str("l 0\n").unwrap_err().to_string();
        assert!(e.starts_with("t.obj:1:3:"), "{e}");
    }

    #[test]
    fn every_truncation_is_handled() {
        let text = b"v 0 0 0\nv 0 1.5 0\nv 0 2 0\nl 1 2 3\n";
        for cut in 0..text.len() {
            let _ = parse(Path::new("t.obj"), &text[..cut]);
        }
    }
}
