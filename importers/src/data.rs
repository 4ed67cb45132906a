//! USC-HairSalon `.data`: i32 strand count, then per strand an i32 point
//! count and that many f32 triples. No magic, so every count is checked
//! against the bytes left before anything is allocated. Strands of one point
//! ("no hair at this root") are kept; `Groom::validate` flags them.

use crate::binary::Cursor;
use crate::ImportError;
use groom::{Groom, Units, UpAxis};
use std::path::Path;

pub fn read(path: &Path) -> Result<Groom, ImportError> {
    let bytes = crate::read_bytes(path)?;
    parse(path, &bytes)
}

pub fn parse(path: &Path, bytes: &[u8]) -> Result<Groom, ImportError> {
    let mut cursor = Cursor::new(path, bytes);
    let strand_count = cursor.i32("the strand count")?;
    if strand_count < 0 {
        return Err(cursor.error_at(0, format!("negative strand count {strand_count}")));
    }
    // Each strand takes at least its 4-byte point count.
    cursor.expect_elements(strand_count as u64, 4, "strand count")?;
    let mut groom = Groom {
        units: Units::default(),
        up_axis: UpAxis::Y,
        ..Groom::default()
    };
    groom.strand_vertex_counts.reserve(strand_count as usize);
    for strand in 0..strand_count {
        let offset = cursor.position();
        let point_count = cursor.i32("a strand's point count")?;
        if point_count < 0 {
            return Err(cursor.error_at(
                offset,
                format!("strand {strand}: negative point count {point_count}"),
            ));
        }
        let strands_left = (strand_count - strand - 1) as u64;
        let needed = 12 * point_count as u64 + 4 * strands_left;
        if needed > cursor.remaining() as u64 {
            return Err(cursor.error_at(
                offset,
                format!(
                    "strand {strand}: {point_count} points and {strands_left} more strands need at least {needed} bytes, only {} are left",
                    cursor.remaining()
                ),
            ));
        }
        groom.points.reserve(point_count as usize);
        for _ in 0..point_count {
            groom.points.push(cursor.finite_vec3("point coordinate")?);
        }
        groom.strand_vertex_counts.push(point_count as u32);
    }
    if cursor.remaining() != 0 {
        return Err(cursor.error_at(
            cursor.position(),
            format!(
                "{} bytes after the last of {strand_count} strands (not a .data file?)",
                cursor.remaining()
            ),
        ));
    }
    groom.provenance.format = "data".into();
    Ok(groom)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(strands: &[Vec<[f32; 3]>]) -> Vec<u8> {
        let mut b = (strands.len() as i32).to_le_bytes().to_vec();
        for s in strands {
            b.extend_from_slice(&(s.len() as i32).to_le_bytes());
            for c in s.iter().flatten() {
                b.extend_from_slice(&c.to_le_bytes());
            }
        }
        b
    }

    fn strands() -> Vec<Vec<[f32; 3]>> {
        vec![
            vec![[1.0, 2.0, 3.0]],
            vec![[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.5, 2.0, 0.0]],
        ]
    }

    #[test]
    fn reads_strands_including_single_points() {
        let groom = parse(Path::new("t.data"), &file(&strands())).unwrap();
        assert_eq!(groom.strand_vertex_counts, vec![1, 3]);
        assert_eq!(groom.points[3], [0.5, 2.0, 0.0]);
        assert_eq!(groom.provenance.format, "data");
        assert_eq!(groom.validate().iter().filter(|p| p.is_fatal()).count(), 0);
    }

    #[test]
    fn huge_strand_count_is_refused() {
        let mut bytes = file(&strands());
        bytes[0..4].copy_from_slice(&i32::MAX.to_le_bytes());
        let error = parse(Path::new("t.data"), &bytes).unwrap_err().to_string();
        assert!(error.contains(":offset 4: strand count"), "{error}");
    }

    #[test]
    fn huge_point_count_names_its_offset() {
        let mut bytes = file(&strands());
        bytes[20..24].copy_from_slice(&i32::MAX.to_le_bytes());
        let error = parse(Path::new("t.data"), &bytes).unwrap_err().to_string();
        assert!(error.contains(":offset 20: strand 1"), "{error}");
    }

    #[test]
    fn nan_and_trailing_bytes() {
        let mut bytes = file(&strands());
        bytes[8..12].copy_from_slice(&f32::NAN.to_le_bytes());
        let error = parse(Path::new("t.data"), &bytes).unwrap_err().to_string();
        assert!(
            error.contains(":offset 8: point coordinate is not finite"),
            "{error}"
        );

        let mut bytes = file(&strands());
        bytes.push(0);
        let error = parse(Path::new("t.data"), &bytes).unwrap_err().to_string();
        assert!(error.contains("1 bytes after the last"), "{error}");
    }

    #[test]
    fn every_truncation_is_an_error_not_a_panic() {
        let bytes = file(&strands());
        for cut in 0..bytes.len() {
            assert!(
                parse(Path::new("t.data"), &bytes[..cut]).is_err(),
                "cut {cut}"
            );
        }
    }
}
