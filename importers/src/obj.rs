//! Wavefront `.obj` polylines: `v x y z [w]` vertices and `l i j k ...`
//! lines (indices 1-based, negative ones relative to the vertices read so
//! far, `i/t` texture references ignored). An `l` of more than two indices is
//! one strand; consecutive two-index `l` statements that chain (each starting
//! where the previous ended) join into one strand, as segment-per-line
//! writers produce them. A one-index `l` is a single-point strand (what the
//! `.obj` exporter writes for USC-HairSalon's empty roots). Other statements
//! (faces, normals, groups, materials) are skipped.

use crate::{ImportError, Place};
use groom::{Groom, Units, UpAxis};
use std::path::Path;

pub fn read(path: &Path) -> Result<Groom, ImportError> {
    let bytes = crate::read_bytes(path)?;
    parse(path, &bytes)
}

/// A vertex index of an `l` statement that refers past the vertices read so
/// far; checked once the file is read.
struct ForwardReference {
    index: usize,
    line: usize,
    column: usize,
}

pub fn parse(path: &Path, bytes: &[u8]) -> Result<Groom, ImportError> {
    let error = |line: usize, column: usize, message: String| {
        ImportError::malformed(path, Place::Line { line, column }, message)
    };
    let mut vertices: Vec<[f32; 3]> = Vec::new();
    let mut strands: Vec<Vec<usize>> = Vec::new();
    // The strand being chained from two-index `l` statements.
    let mut chain: Vec<usize> = Vec::new();
    let mut forward: Vec<ForwardReference> = Vec::new();

    for (line_index, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line_number = line_index + 1;
        let text = std::str::from_utf8(raw)
            .map_err(|e| error(line_number, e.valid_up_to() + 1, "not UTF-8 text".into()))?;
        let text = text.split('#').next().unwrap_or("");
        let mut tokens = tokens_with_columns(text);
        let Some((_, keyword)) = tokens.next() else {
            continue;
        };
        match keyword {
            "v" => {
                let mut point = [0.0f32; 3];
                for (k, component) in point.iter_mut().enumerate() {
                    let (column, token) = tokens.next().ok_or_else(|| {
                        error(
                            line_number,
                            text.len() + 1,
                            format!("vertex has {k} coordinates, expected 3"),
                        )
                    })?;
                    let value: f32 = token.parse().map_err(|_| {
                        error(line_number, column, format!("'{token}' is not a number"))
                    })?;
                    if !value.is_finite() {
                        return Err(error(
                            line_number,
                            column,
                            format!("coordinate {token} is not finite"),
                        ));
                    }
                    *component = value;
                }
                vertices.push(point);
            }
            "l" => {
                let mut indices = Vec::new();
                for (column, token) in tokens {
                    let number = token.split('/').next().unwrap_or("");
                    let value: i64 = number.parse().map_err(|_| {
                        error(
                            line_number,
                            column,
                            format!("'{token}' is not a vertex index"),
                        )
                    })?;
                    let index = if value > 0 {
                        (value - 1) as usize
                    } else if value < 0 && value.unsigned_abs() as usize <= vertices.len() {
                        vertices.len() - value.unsigned_abs() as usize
                    } else {
                        return Err(error(
                            line_number,
                            column,
                            format!(
                                "vertex index {value} is out of range ({} vertices so far)",
                                vertices.len()
                            ),
                        ));
                    };
                    if index >= vertices.len() {
                        forward.push(ForwardReference {
                            index,
                            line: line_number,
                            column,
                        });
                    }
                    indices.push(index);
                }
                match indices.as_slice() {
                    [] => return Err(error(line_number, 1, "'l' without vertex indices".into())),
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
    if let Some(bad) = forward.iter().find(|r| r.index >= vertices.len()) {
        return Err(error(
            bad.line,
            bad.column,
            format!(
                "vertex index {} is out of range (the file has {} vertices)",
                bad.index + 1,
                vertices.len()
            ),
        ));
    }
    let mut groom = Groom {
        units: Units::default(),
        up_axis: UpAxis::Y,
        ..Groom::default()
    };
    for strand in &strands {
        groom.strand_vertex_counts.push(strand.len() as u32);
        groom
            .points
            .extend(strand.iter().filter_map(|&i| vertices.get(i).copied()));
    }
    groom.provenance.format = "obj".into();
    Ok(groom)
}

/// Whitespace-separated tokens with their 1-based columns.
pub(crate) fn tokens_with_columns(text: &str) -> impl Iterator<Item = (usize, &str)> {
    let mut rest = text;
    let mut offset = 0usize;
    std::iter::from_fn(move || {
        let trimmed = rest.trim_start();
        offset += rest.len() - trimmed.len();
        if trimmed.is_empty() {
            return None;
        }
        let end = trimmed
            .find(|c: char| c.is_whitespace())
            .unwrap_or(trimmed.len());
        let token = &trimmed[..end];
        let column = offset + 1;
        offset += end;
        rest = &trimmed[end..];
        Some((column, token))
    })
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
