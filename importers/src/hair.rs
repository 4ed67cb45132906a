//! Cem Yuksel's `.hair` format (cyHairFile): a 128-byte header, then the
//! arrays its flags announce, in a fixed order.
//!
//! Arrays become attributes only when the file has them (thickness ->
//! `width`, transparency -> `transparency`, colours -> `color`), so that the
//! `.hair` exporter writes back the same arrays. A missing array whose header
//! default differs from cyHairFile's own default is materialised from that
//! default, so no information of the file is lost.
//!
//! The header fields the groom has no place for (the flags, the defaults,
//! the raw info bytes) go into `provenance.metadata` under the `hair.*` keys
//! below, with the counts they describe, so that the `.hair` writer can
//! reproduce any valid file byte for byte.

use crate::binary::Cursor;
use crate::ImportError;
use groom::{Attribute, AttributeValues, Groom, Units, UpAxis};
use std::path::Path;

pub const MAGIC: &[u8; 4] = b"HAIR";
pub const HEADER_SIZE: usize = 128;
pub const HAS_SEGMENTS: u32 = 1;
pub const HAS_POINTS: u32 = 2;
pub const HAS_THICKNESS: u32 = 4;
pub const HAS_TRANSPARENCY: u32 = 8;
pub const HAS_COLORS: u32 = 16;
/// cyHairFile's defaults for a header that sets none.
pub const DEFAULT_THICKNESS: f32 = 1.0;
pub const DEFAULT_TRANSPARENCY: f32 = 0.0;
pub const DEFAULT_COLOR: [f32; 3] = [1.0, 1.0, 1.0];

/// `provenance.metadata` keys. Counts and flags are decimal; defaults are
/// the bits of each f32 as `0x` hex (exact for -0.0 and NaN), colour
/// components comma-separated; `hair.info` is the hex of the 88 info bytes,
/// present only when the text before the first NUL does not say them all.
pub const META_HAIR_COUNT: &str = "hair.hair_count";
pub const META_POINT_COUNT: &str = "hair.point_count";
pub const META_FLAGS: &str = "hair.flags";
pub const META_DEFAULT_SEGMENTS: &str = "hair.default_segments";
pub const META_DEFAULT_THICKNESS: &str = "hair.default_thickness";
pub const META_DEFAULT_TRANSPARENCY: &str = "hair.default_transparency";
pub const META_DEFAULT_COLOR: &str = "hair.default_color";
pub const META_INFO: &str = "hair.info";

pub fn read(path: &Path) -> Result<Groom, ImportError> {
    let bytes = crate::read_bytes(path)?;
    parse(path, &bytes)
}

pub fn parse(path: &Path, bytes: &[u8]) -> Result<Groom, ImportError> {
    let mut cursor = Cursor::new(path, bytes);
    if bytes.len() < HEADER_SIZE {
        return Err(cursor.error_at(
            bytes.len(),
            format!(
                "file ends inside the {HEADER_SIZE}-byte .hair header ({} bytes)",
                bytes.len()
            ),
        ));
    }
    let magic = cursor.take(4, "the magic")?;
    if magic != MAGIC {
        return Err(cursor.error_at(
            0,
            format!("not a .hair file: magic is {magic:02x?}, expected \"HAIR\""),
        ));
    }
    let hair_count = cursor.u32("the hair count")?;
    let point_count = cursor.u32("the point count")?;
    let flags = cursor.u32("the flags")?;
    let default_segments = cursor.u32("the default segment count")?;
    let default_thickness = cursor.f32("the default thickness")?;
    let default_transparency = cursor.f32("the default transparency")?;
    let default_color = [
        cursor.f32("the default colour")?,
        cursor.f32("the default colour")?,
        cursor.f32("the default colour")?,
    ];
    let info_bytes = cursor.take(88, "the info field")?;
    let info_end = info_bytes.iter().position(|&b| b == 0).unwrap_or(88);
    let info = String::from_utf8_lossy(&info_bytes[..info_end]).into_owned();

    if flags & HAS_POINTS == 0 {
        return Err(cursor.error_at(
            12,
            format!("flags {flags:#x} announce no points array (bit 2): nothing to read"),
        ));
    }

    // Every array's size follows from the header: check the total against the
    // file before allocating anything.
    let mut needed = 0u64;
    if flags & HAS_SEGMENTS != 0 {
        needed += 2 * hair_count as u64;
    }
    needed += 12 * point_count as u64;
    if flags & HAS_THICKNESS != 0 {
        needed += 4 * point_count as u64;
    }
    if flags & HAS_TRANSPARENCY != 0 {
        needed += 4 * point_count as u64;
    }
    if flags & HAS_COLORS != 0 {
        needed += 12 * point_count as u64;
    }
    if needed > cursor.remaining() as u64 {
        return Err(cursor.error_at(
            bytes.len(),
            format!(
                "file too short: the header announces {hair_count} hairs and {point_count} points \
                 (flags {flags:#x}), {needed} bytes of arrays after the header, but only {} bytes follow it",
                cursor.remaining()
            ),
        ));
    }

    // Strand lengths, checked against the point count before a per-strand
    // array is allocated (without a segments array, hair_count is unchecked).
    let counts = if flags & HAS_SEGMENTS != 0 {
        let mut counts = Vec::with_capacity(hair_count as usize);
        for _ in 0..hair_count {
            counts.push(cursor.u16("the segments array")? as u32 + 1);
        }
        let total: u64 = counts.iter().map(|&c| c as u64).sum();
        if total != point_count as u64 {
            return Err(cursor.error_at(
                HEADER_SIZE,
                format!("the segments array gives strands of {total} points in all, but the header says {point_count} points"),
            ));
        }
        counts
    } else {
        let per_strand = default_segments as u64 + 1;
        let total = hair_count as u64 * per_strand;
        if total != point_count as u64 {
            return Err(cursor.error_at(
                16,
                format!(
                    "{hair_count} hairs of {default_segments} default segments make {total} points, but the header says {point_count} points"
                ),
            ));
        }
        vec![per_strand as u32; hair_count as usize]
    };

    let mut points = Vec::with_capacity(point_count as usize);
    for _ in 0..point_count {
        points.push(cursor.finite_vec3("point coordinate")?);
    }
    let mut groom = Groom {
        strand_vertex_counts: counts,
        points,
        units: Units::default(),
        up_axis: UpAxis::Y,
        ..Groom::default()
    };
    let n = point_count as usize;
    let float_array = |cursor: &mut Cursor, flag: u32, default: f32, standard: f32, what: &str| {
        if flags & flag != 0 {
            let mut values = Vec::with_capacity(n);
            for _ in 0..n {
                values.push(cursor.finite_f32(what)?);
            }
            Ok::<_, ImportError>(Some(values))
        } else if default.to_bits() != standard.to_bits() {
            Ok(Some(vec![default; n]))
        } else {
            Ok(None)
        }
    };
    if let Some(width) = float_array(
        &mut cursor,
        HAS_THICKNESS,
        default_thickness,
        DEFAULT_THICKNESS,
        "thickness",
    )? {
        groom.set_attribute(Attribute::new("width", AttributeValues::Float(width)));
    }
    if let Some(transparency) = float_array(
        &mut cursor,
        HAS_TRANSPARENCY,
        default_transparency,
        DEFAULT_TRANSPARENCY,
        "transparency",
    )? {
        groom.set_attribute(Attribute::new(
            "transparency",
            AttributeValues::Float(transparency),
        ));
    }
    let colors = if flags & HAS_COLORS != 0 {
        let mut values = Vec::with_capacity(n);
        for _ in 0..n {
            values.push(cursor.finite_vec3("colour")?);
        }
        Some(values)
    } else if default_color.map(f32::to_bits) != DEFAULT_COLOR.map(f32::to_bits) {
        Some(vec![default_color; n])
    } else {
        None
    };
    if let Some(colors) = colors {
        groom.set_attribute(Attribute::new("color", AttributeValues::Vec3(colors)));
    }
    let bits = |v: f32| format!("{:#010x}", v.to_bits());
    let metadata = &mut groom.provenance.metadata;
    metadata.insert(META_HAIR_COUNT.into(), hair_count.to_string());
    metadata.insert(META_POINT_COUNT.into(), point_count.to_string());
    metadata.insert(META_FLAGS.into(), flags.to_string());
    metadata.insert(META_DEFAULT_SEGMENTS.into(), default_segments.to_string());
    metadata.insert(META_DEFAULT_THICKNESS.into(), bits(default_thickness));
    metadata.insert(META_DEFAULT_TRANSPARENCY.into(), bits(default_transparency));
    metadata.insert(META_DEFAULT_COLOR.into(), default_color.map(bits).join(","));
    // Bytes after the terminating NUL, or text that is not UTF-8.
    let mut plain = [0u8; 88];
    plain[..info.len().min(88)].copy_from_slice(&info.as_bytes()[..info.len().min(88)]);
    if plain[..] != info_bytes[..] {
        let hex: String = info_bytes.iter().map(|b| format!("{b:02x}")).collect();
        metadata.insert(META_INFO.into(), hex);
    }
    groom.provenance.format = "hair".into();
    groom.provenance.info = info;
    Ok(groom)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `.hair` file built field by field.
    fn file(flags: u32, segments: &[u16], points: &[[f32; 3]], default_segments: u32) -> Vec<u8> {
        let mut b = Vec::new();
        b.extend_from_slice(MAGIC);
        b.extend_from_slice(&(segments.len().max(1) as u32).to_le_bytes());
        b.extend_from_slice(&(points.len() as u32).to_le_bytes());
        b.extend_from_slice(&flags.to_le_bytes());
        b.extend_from_slice(&default_segments.to_le_bytes());
        for v in [0.5f32, 0.25, 0.1, 0.2, 0.3] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        let mut info = [0u8; 88];
        info[..5].copy_from_slice(b"hello");
        b.extend_from_slice(&info);
        if flags & HAS_SEGMENTS != 0 {
            for s in segments {
                b.extend_from_slice(&s.to_le_bytes());
            }
        }
        for p in points.iter().flatten() {
            b.extend_from_slice(&p.to_le_bytes());
        }
        if flags & HAS_THICKNESS != 0 {
            for i in 0..points.len() {
                b.extend_from_slice(&(i as f32).to_le_bytes());
            }
        }
        b
    }

    fn three_points() -> Vec<[f32; 3]> {
        vec![[0.0, 0.0, 0.0], [1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]
    }

    #[test]
    fn reads_segments_points_thickness_and_info() {
        let bytes = file(
            HAS_SEGMENTS | HAS_POINTS | HAS_THICKNESS,
            &[2],
            &three_points(),
            0,
        );
        let groom = parse(Path::new("t.hair"), &bytes).unwrap();
        assert_eq!(groom.strand_vertex_counts, vec![3]);
        assert_eq!(groom.points, three_points());
        assert_eq!(
            groom.attribute("width").unwrap().values,
            AttributeValues::Float(vec![0.0, 1.0, 2.0])
        );
        // Missing arrays with non-standard defaults are materialised.
        assert_eq!(
            groom.attribute("transparency").unwrap().values,
            AttributeValues::Float(vec![0.25; 3])
        );
        assert_eq!(
            groom.attribute("color").unwrap().values,
            AttributeValues::Vec3(vec![[0.1, 0.2, 0.3]; 3])
        );
        assert_eq!(groom.provenance.info, "hello");
        assert_eq!(groom.provenance.format, "hair");
    }

    #[test]
    fn header_fields_go_to_metadata() {
        let mut bytes = file(HAS_SEGMENTS | HAS_POINTS, &[2], &three_points(), 9);
        let groom = parse(Path::new("t.hair"), &bytes).unwrap();
        let metadata = &groom.provenance.metadata;
        let get = |key: &str| metadata.get(key).map(String::as_str);
        assert_eq!(get(META_HAIR_COUNT), Some("1"));
        assert_eq!(get(META_POINT_COUNT), Some("3"));
        assert_eq!(get(META_FLAGS), Some("3"));
        assert_eq!(get(META_DEFAULT_SEGMENTS), Some("9"));
        assert_eq!(get(META_DEFAULT_THICKNESS), Some("0x3f000000"));
        assert_eq!(
            get(META_DEFAULT_COLOR),
            Some("0x3dcccccd,0x3e4ccccd,0x3e99999a")
        );
        // "hello" and zeros: the text says it all.
        assert_eq!(get(META_INFO), None);
        bytes[127] = 7;
        let groom = parse(Path::new("t.hair"), &bytes).unwrap();
        let hex = &groom.provenance.metadata[META_INFO];
        assert!(
            hex.starts_with("68656c6c6f00") && hex.ends_with("07"),
            "{hex}"
        );
        assert_eq!(groom.provenance.info, "hello");
    }

    #[test]
    fn default_segments_apply_without_array() {
        let bytes = file(HAS_POINTS, &[0], &three_points(), 2);
        let groom = parse(Path::new("t.hair"), &bytes).unwrap();
        assert_eq!(groom.strand_vertex_counts, vec![3]);
        // The default thickness 0.5 is not cyHairFile's 1.0: kept as widths.
        assert_eq!(
            groom.attribute("width").unwrap().values,
            AttributeValues::Float(vec![0.5; 3])
        );
    }

    #[test]
    fn wrong_magic_names_offset_0() {
        let mut bytes = file(HAS_POINTS, &[0], &three_points(), 2);
        bytes[0] = b'X';
        let error = parse(Path::new("t.hair"), &bytes).unwrap_err().to_string();
        assert!(
            error.starts_with("t.hair:offset 0: not a .hair file"),
            "{error}"
        );
    }

    #[test]
    fn huge_counts_are_refused_before_allocating() {
        let mut bytes = file(HAS_SEGMENTS | HAS_POINTS, &[2], &three_points(), 0);
        bytes[4..8].copy_from_slice(&u32::MAX.to_le_bytes());
        bytes[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
        let error = parse(Path::new("t.hair"), &bytes).unwrap_err().to_string();
        assert!(error.contains("file too short"), "{error}");
    }

    #[test]
    fn huge_hair_count_without_segments_is_refused_before_allocating() {
        let mut bytes = file(HAS_POINTS, &[0], &three_points(), 0);
        bytes[4..8].copy_from_slice(&u32::MAX.to_le_bytes());
        let error = parse(Path::new("t.hair"), &bytes).unwrap_err().to_string();
        assert!(error.contains(":offset 16: 4294967295 hairs"), "{error}");
    }

    #[test]
    fn segments_that_disagree_with_point_count() {
        let bytes = file(HAS_SEGMENTS | HAS_POINTS, &[5], &three_points(), 0);
        let error = parse(Path::new("t.hair"), &bytes).unwrap_err().to_string();
        assert!(error.contains(":offset 128:"), "{error}");
    }

    #[test]
    fn nan_coordinate_names_its_offset() {
        let mut points = three_points();
        points[1][1] = f32::NAN;
        let bytes = file(HAS_SEGMENTS | HAS_POINTS, &[2], &points, 0);
        let error = parse(Path::new("t.hair"), &bytes).unwrap_err().to_string();
        // header 128 + segments 2 + point 0 (12) + x of point 1 (4)
        assert!(error.contains(":offset 146:"), "{error}");
    }

    #[test]
    fn every_truncation_is_an_error_not_a_panic() {
        let bytes = file(
            HAS_SEGMENTS | HAS_POINTS | HAS_THICKNESS,
            &[2],
            &three_points(),
            0,
        );
        for cut in 0..bytes.len() {
            let error = parse(Path::new("t.hair"), &bytes[..cut]);
            assert!(error.is_err(), "cut at {cut} was accepted");
        }
    }
}
