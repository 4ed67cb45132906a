//! Cem Yuksel's `.hair`. Mirrors the importer so that `.hair` -> `.hair`
//! gives back the file byte for byte.
//!
//! General rule: the segments array is written only when the strands differ
//! in length (otherwise the header's default segment count says it), and the
//! thickness, transparency and colour arrays only when the groom has the
//! `width`, `transparency` and `color` attributes the importer makes of them;
//! the header defaults are cyHairFile's own.
//!
//! A groom read from a `.hair` file carries that file's header in
//! `provenance.metadata` (see the importer). While the groom still has the
//! strand and point counts the header describes, the writer follows it: the
//! same flags (an array the file had is written again, a default the importer
//! materialised as an attribute goes back into the header if every value
//! still equals it), the same defaults and default segment count, the same
//! raw info bytes (if the info text is unchanged). Anything the groom no
//! longer matches falls back to the general rule.

use crate::{vertex_floats, vertex_vec3s, ExportError};
use groom::{AtomicFile, Groom};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;

const HAS_SEGMENTS: u32 = 1;
const HAS_POINTS: u32 = 2;
const HAS_THICKNESS: u32 = 4;
const HAS_TRANSPARENCY: u32 = 8;
const HAS_COLORS: u32 = 16;
const INFO_SIZE: usize = 88;
/// cyHairFile's defaults, as f32 bits.
const DEFAULT_THICKNESS: u32 = 0x3f80_0000; // 1.0
const DEFAULT_TRANSPARENCY: u32 = 0; // 0.0
const DEFAULT_COLOR: [u32; 3] = [0x3f80_0000; 3]; // white

/// The header of the file a groom was read from, as the `.hair` importer
/// records it in `provenance.metadata` (keys `hair.*`, mirrored here).
struct RecordedHeader {
    flags: u32,
    default_segments: u32,
    default_thickness: u32,
    default_transparency: u32,
    default_color: [u32; 3],
    info: Option<[u8; INFO_SIZE]>,
}

impl RecordedHeader {
    /// The recorded header, if the groom has one that is well-formed and
    /// describes the groom's strand and point counts.
    fn of(groom: &Groom) -> Option<RecordedHeader> {
        let metadata = &groom.provenance.metadata;
        let number = |key: &str| metadata.get(key)?.parse::<u64>().ok();
        if number("hair.hair_count")? != groom.strand_count() as u64
            || number("hair.point_count")? != groom.vertex_count() as u64
        {
            return None;
        }
        let color: Vec<u32> = metadata
            .get("hair.default_color")?
            .split(',')
            .map(parse_bits)
            .collect::<Option<_>>()?;
        Some(RecordedHeader {
            flags: u32::try_from(number("hair.flags")?).ok()?,
            default_segments: u32::try_from(number("hair.default_segments")?).ok()?,
            default_thickness: bits_of(metadata, "hair.default_thickness")?,
            default_transparency: bits_of(metadata, "hair.default_transparency")?,
            default_color: color.try_into().ok()?,
            info: metadata.get("hair.info").and_then(|hex| parse_info(hex)),
        })
    }

    /// Whether the file had the array of `flag`, and the header's default
    /// for it.
    fn array<T>(&self, flag: u32, default: T) -> (bool, T) {
        (self.flags & flag != 0, default)
    }
}

fn parse_bits(text: &str) -> Option<u32> {
    u32::from_str_radix(text.strip_prefix("0x")?, 16).ok()
}

fn bits_of(metadata: &BTreeMap<String, String>, key: &str) -> Option<u32> {
    parse_bits(metadata.get(key)?)
}

fn parse_info(hex: &str) -> Option<[u8; INFO_SIZE]> {
    if hex.len() != 2 * INFO_SIZE || !hex.is_ascii() {
        return None;
    }
    let mut info = [0u8; INFO_SIZE];
    for (k, byte) in info.iter_mut().enumerate() {
        *byte = u8::from_str_radix(hex.get(2 * k..2 * k + 2)?, 16).ok()?;
    }
    Some(info)
}

/// Whether to write an optional array (values as bits) and what default the
/// header gets for it. `recorded` is (the file had the array, its default).
fn plan_array<T: Copy + PartialEq>(
    values: Option<Vec<T>>,
    recorded: Option<(bool, T)>,
    standard: T,
) -> (Option<Vec<T>>, T) {
    match (values, recorded) {
        // No attribute: nothing for the reader to materialise either.
        (None, _) => (None, standard),
        // The importer made the attribute of a non-standard default; it is
        // still that default everywhere, so the header says it again.
        (Some(values), Some((false, default)))
            if default != standard && values.iter().all(|&v| v == default) =>
        {
            (None, default)
        }
        // The header default is unused beside an array: keep the file's.
        (Some(values), Some((_, default))) => (Some(values), default),
        (Some(values), None) => (Some(values), standard),
    }
}

pub fn write(path: &Path, groom: &Groom) -> Result<(), ExportError> {
    let invalid = |message: String| ExportError::Invalid {
        file: path.to_path_buf(),
        message,
    };
    let hair_count = u32::try_from(groom.strand_count())
        .map_err(|_| invalid("more strands than a .hair file can hold".into()))?;
    let point_count = u32::try_from(groom.vertex_count())
        .map_err(|_| invalid("more points than a .hair file can hold".into()))?;
    let recorded = RecordedHeader::of(groom);

    let counts = &groom.strand_vertex_counts;
    if let Some(strand) = counts.iter().position(|&c| c == 0) {
        return Err(invalid(format!(
            "strand {strand} has no points; .hair holds 1 or more per strand"
        )));
    }
    let uniform = counts.windows(2).all(|w| w[0] == w[1]);
    let want_segments = match &recorded {
        Some(header) if header.flags & HAS_SEGMENTS != 0 => true,
        _ => !uniform,
    };
    // The segments array holds 1 to 65536 points per strand; uniform strands
    // of any length fit in the header's u32 default instead.
    let segments: Option<Vec<u16>> = if want_segments {
        let array: Result<Vec<u16>, ExportError> = counts
            .iter()
            .enumerate()
            .map(|(strand, &count)| {
                u16::try_from(count - 1).map_err(|_| {
                    invalid(format!(
                        "strand {strand} has {count} points; .hair holds 1 to 65536 per strand \
                         when strands differ in length"
                    ))
                })
            })
            .collect();
        match array {
            Ok(array) => Some(array),
            Err(_) if uniform => None,
            Err(error) => return Err(error),
        }
    } else {
        None
    };
    let default_segments = match (&segments, &recorded) {
        (Some(_), Some(header)) => header.default_segments,
        (Some(_), None) => 0,
        // Zero strands: any default describes them; keep the file's.
        (None, Some(header)) if counts.is_empty() => header.default_segments,
        (None, _) => counts.first().map_or(0, |&c| c - 1),
    };

    let bits = |values: Vec<f32>| values.into_iter().map(f32::to_bits).collect::<Vec<_>>();
    let (thickness, default_thickness) = plan_array(
        vertex_floats(groom, "width").map(bits),
        recorded
            .as_ref()
            .map(|h| h.array(HAS_THICKNESS, h.default_thickness)),
        DEFAULT_THICKNESS,
    );
    let (transparency, default_transparency) = plan_array(
        vertex_floats(groom, "transparency").map(bits),
        recorded
            .as_ref()
            .map(|h| h.array(HAS_TRANSPARENCY, h.default_transparency)),
        DEFAULT_TRANSPARENCY,
    );
    let (colors, default_color) = plan_array(
        vertex_vec3s(groom, "color")
            .map(|values| values.into_iter().map(|c| c.map(f32::to_bits)).collect()),
        recorded
            .as_ref()
            .map(|h| h.array(HAS_COLORS, h.default_color)),
        DEFAULT_COLOR,
    );

    let mut flags = HAS_POINTS;
    for (present, flag) in [
        (segments.is_some(), HAS_SEGMENTS),
        (thickness.is_some(), HAS_THICKNESS),
        (transparency.is_some(), HAS_TRANSPARENCY),
        (colors.is_some(), HAS_COLORS),
    ] {
        if present {
            flags |= flag;
        }
    }

    let mut header = Vec::with_capacity(128);
    header.extend_from_slice(b"HAIR");
    header.extend_from_slice(&hair_count.to_le_bytes());
    header.extend_from_slice(&point_count.to_le_bytes());
    header.extend_from_slice(&flags.to_le_bytes());
    header.extend_from_slice(&default_segments.to_le_bytes());
    for value in [default_thickness, default_transparency]
        .into_iter()
        .chain(default_color)
    {
        header.extend_from_slice(&value.to_le_bytes());
    }
    header.extend_from_slice(&info_field(groom, recorded.as_ref()));

    let io = |e| ExportError::io(path, e);
    let mut out = AtomicFile::create(path).map_err(io)?;
    out.write_all(&header).map_err(io)?;
    for s in segments.iter().flatten() {
        out.write_all(&s.to_le_bytes()).map_err(io)?;
    }
    for value in groom.points.iter().flatten() {
        out.write_all(&value.to_le_bytes()).map_err(io)?;
    }
    let arrays = thickness.iter().chain(&transparency).flatten();
    for value in arrays.chain(colors.iter().flatten().flatten()) {
        out.write_all(&value.to_le_bytes()).map_err(io)?;
    }
    out.commit().map_err(io)
}

/// The 88 info bytes: the recorded raw bytes while they still read as the
/// groom's info text, otherwise the text, NUL-padded.
fn info_field(groom: &Groom, recorded: Option<&RecordedHeader>) -> [u8; INFO_SIZE] {
    if let Some(raw) = recorded.and_then(|h| h.info) {
        let end = raw.iter().position(|&b| b == 0).unwrap_or(INFO_SIZE);
        if String::from_utf8_lossy(&raw[..end]) == groom.provenance.info {
            return raw;
        }
    }
    let mut info = [0u8; INFO_SIZE];
    let text = truncate_at_char(&groom.provenance.info, INFO_SIZE);
    info[..text.len()].copy_from_slice(text.as_bytes());
    info
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

#[cfg(test)]
mod tests {
    use super::*;
    use groom::{Attribute, AttributeValues};

    /// A `.hair` file built field by field. Strands of `counts` points
    /// (without the segments flag all counts must be `default_segments + 1`);
    /// arrays hold distinct values so a misplaced one shows.
    struct HairFile {
        flags: u32,
        default_segments: u32,
        defaults: [f32; 5],
        counts: Vec<u16>,
        info: [u8; INFO_SIZE],
    }

    impl HairFile {
        fn bytes(&self) -> Vec<u8> {
            let points: u32 = self.counts.iter().map(|&c| c as u32).sum();
            let mut b = Vec::new();
            b.extend_from_slice(b"HAIR");
            b.extend_from_slice(&(self.counts.len() as u32).to_le_bytes());
            b.extend_from_slice(&points.to_le_bytes());
            b.extend_from_slice(&self.flags.to_le_bytes());
            b.extend_from_slice(&self.default_segments.to_le_bytes());
            for v in self.defaults {
                b.extend_from_slice(&v.to_le_bytes());
            }
            b.extend_from_slice(&self.info);
            if self.flags & HAS_SEGMENTS != 0 {
                for &c in &self.counts {
                    b.extend_from_slice(&(c - 1).to_le_bytes());
                }
            }
            let mut floats = |count: u32, scale: f32| {
                for i in 0..count {
                    b.extend_from_slice(&(i as f32 * scale + 0.125).to_le_bytes());
                }
            };
            floats(3 * points, 1.5);
            if self.flags & HAS_THICKNESS != 0 {
                floats(points, 0.01);
            }
            if self.flags & HAS_TRANSPARENCY != 0 {
                floats(points, 0.02);
            }
            if self.flags & HAS_COLORS != 0 {
                floats(3 * points, 0.03);
            }
            b
        }
    }

    fn info(text: &[u8], after_nul: &[u8]) -> [u8; INFO_SIZE] {
        let mut info = [0u8; INFO_SIZE];
        info[..text.len()].copy_from_slice(text);
        info[INFO_SIZE - after_nul.len()..].copy_from_slice(after_nul);
        info
    }

    fn round_trip(bytes: &[u8], dir: &Path, name: &str) -> Vec<u8> {
        let source = dir.join(format!("{name}.in.hair"));
        std::fs::write(&source, bytes).unwrap();
        let groom = importers::read(&source).unwrap();
        let copy = dir.join(format!("{name}.out.hair"));
        crate::write(&copy, &groom).unwrap();
        std::fs::read(&copy).unwrap()
    }

    const STANDARD: [f32; 5] = [1.0, 0.0, 1.0, 1.0, 1.0];
    const ODD: [f32; 5] = [0.5, -0.0, 0.1, 0.2, 0.3];

    #[test]
    fn every_flag_combination_and_default_comes_back_byte_for_byte() {
        let dir = tempfile::tempdir().unwrap();
        let infos = [
            info(b"plain text", b""),
            // Left-over bytes after the NUL, as C writers leave them.
            info(b"short", b"\x01garbage"),
            // Not UTF-8.
            info(b"caf\xe9 \xff", b""),
            // All 88 bytes used, no NUL.
            [b'x'; INFO_SIZE],
        ];
        let mut cases = 0;
        for optional in 0..16u32 {
            let flags = HAS_POINTS
                | if optional & 1 != 0 { HAS_SEGMENTS } else { 0 }
                | (optional & 0b1110) << 1;
            // NaN thickness default only beside a thickness array: alone it
            // would become NaN widths, which no writer takes.
            let mut defaults = vec![STANDARD, ODD];
            if flags & HAS_THICKNESS != 0 {
                defaults.push([f32::NAN, 1e-40, 0.25, -1.0, 2.0]);
            }
            let mut layouts = vec![(vec![3u16, 3, 3], 2u32), (vec![], 9)];
            if flags & HAS_SEGMENTS != 0 {
                // Uneven strands; uniform strands with an array and a
                // default segment count that says something else.
                layouts.push((vec![4, 1, 2, 7], 0));
                layouts.push((vec![2, 2], 5));
            }
            for defaults in &defaults {
                for (counts, default_segments) in &layouts {
                    for info in &infos {
                        let file = HairFile {
                            flags,
                            default_segments: *default_segments,
                            defaults: *defaults,
                            counts: counts.clone(),
                            info: *info,
                        };
                        let bytes = file.bytes();
                        let name = format!("case{cases}");
                        let copy = round_trip(&bytes, dir.path(), &name);
                        assert!(
                            copy == bytes,
                            "flags {flags:#x}, defaults {defaults:?}, counts {counts:?}, info {:?}",
                            String::from_utf8_lossy(info)
                        );
                        cases += 1;
                    }
                }
            }
        }
        // Per flag combination (4 of each thickness/segments pairing):
        // default sets x strand layouts x infos.
        assert_eq!(cases, 4 * (2 * 2 + 2 * 4 + 3 * 2 + 3 * 4) * 4);
    }

    /// Uniform strands with a segments array, odd defaults, no optional
    /// arrays (so width, transparency and colour come from the defaults),
    /// and left-over info bytes.
    fn odd_file() -> Vec<u8> {
        HairFile {
            flags: HAS_POINTS | HAS_SEGMENTS,
            default_segments: 5,
            defaults: ODD,
            counts: vec![3, 3, 3],
            info: info(b"odd", b"\x01tail"),
        }
        .bytes()
    }

    fn header(bytes: &[u8]) -> (u32, u32, [u32; 5], &[u8]) {
        let word = |k: usize| u32::from_le_bytes(bytes[k..k + 4].try_into().unwrap());
        (
            word(12),
            word(16),
            [word(20), word(24), word(28), word(32), word(36)],
            &bytes[40..128],
        )
    }

    fn write_and_read(groom: &Groom, dir: &Path, name: &str) -> (Vec<u8>, Groom) {
        let path = dir.join(name);
        crate::write(&path, groom).unwrap();
        (
            std::fs::read(&path).unwrap(),
            importers::read(&path).unwrap(),
        )
    }

    #[test]
    fn changed_topology_falls_back_to_the_general_rule() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("odd.hair"), odd_file()).unwrap();
        let original = importers::read(&dir.path().join("odd.hair")).unwrap();

        // One strand fewer: the recorded header describes another groom.
        let mut fewer = original.clone();
        fewer.strand_vertex_counts.pop();
        fewer.points.truncate(6);
        for attribute in &mut fewer.attributes {
            attribute.values = match &attribute.values {
                AttributeValues::Float(v) => AttributeValues::Float(v[..6].to_vec()),
                AttributeValues::Vec3(v) => AttributeValues::Vec3(v[..6].to_vec()),
                other => other.clone(),
            };
        }
        let (bytes, back) = write_and_read(&fewer, dir.path(), "fewer.hair");
        let (flags, default_segments, defaults, info) = header(&bytes);
        // Uniform strands: no segments array; the materialised attributes
        // are arrays now, beside cyHairFile's defaults; the info is the text.
        assert_eq!(
            flags,
            HAS_POINTS | HAS_THICKNESS | HAS_TRANSPARENCY | HAS_COLORS
        );
        assert_eq!(default_segments, 2);
        assert_eq!(defaults, STANDARD.map(f32::to_bits));
        assert_eq!(&info[..4], b"odd\0");
        assert!(info[4..].iter().all(|&b| b == 0));
        assert_eq!(back.points, fewer.points);
        assert_eq!(back.attributes, fewer.attributes);

        // Same counts, strands of other lengths: the file had an array anyway.
        let mut uneven = original.clone();
        uneven.strand_vertex_counts = vec![2, 4, 3];
        let (bytes, back) = write_and_read(&uneven, dir.path(), "uneven.hair");
        assert_eq!(header(&bytes).0 & HAS_SEGMENTS, HAS_SEGMENTS);
        assert_eq!(back.strand_vertex_counts, vec![2, 4, 3]);
    }

    #[test]
    fn dropped_or_changed_attributes_with_the_same_counts() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("odd.hair"), odd_file()).unwrap();
        let original = importers::read(&dir.path().join("odd.hair")).unwrap();
        assert_eq!(
            original.attribute("width").unwrap().values,
            AttributeValues::Float(vec![0.5; 9])
        );

        // Widths dropped: no array and cyHairFile's default, which the
        // reader does not turn into widths again.
        let mut dropped = original.clone();
        dropped.remove_attribute("width");
        let (bytes, back) = write_and_read(&dropped, dir.path(), "dropped.hair");
        let (flags, default_segments, defaults, info) = header(&bytes);
        assert_eq!(flags, HAS_POINTS | HAS_SEGMENTS);
        assert_eq!(default_segments, 5);
        assert_eq!(defaults[0], 1.0f32.to_bits());
        assert_eq!(defaults[1..], ODD.map(f32::to_bits)[1..]);
        assert_eq!(&info[84..], b"tail");
        assert!(back.attribute("width").is_none());
        assert_eq!(back.attributes, dropped.attributes);

        // Widths changed: written as an array (the file's default stays,
        // unused); a changed info text replaces the raw bytes.
        let mut changed = original.clone();
        changed.set_attribute(Attribute::new(
            "width",
            AttributeValues::Float((0..9).map(|i| i as f32).collect()),
        ));
        changed.provenance.info = "new".into();
        let (bytes, back) = write_and_read(&changed, dir.path(), "changed.hair");
        let (flags, _, defaults, info) = header(&bytes);
        assert_eq!(flags, HAS_POINTS | HAS_SEGMENTS | HAS_THICKNESS);
        assert_eq!(defaults, ODD.map(f32::to_bits));
        assert_eq!(&info[..4], b"new\0");
        assert!(info[4..].iter().all(|&b| b == 0));
        assert_eq!(back.attributes, changed.attributes);
    }

    #[test]
    fn malformed_metadata_is_ignored() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("odd.hair"), odd_file()).unwrap();
        let original = importers::read(&dir.path().join("odd.hair")).unwrap();
        for (key, value) in [
            ("hair.flags", "many"),
            ("hair.default_color", "0x3f800000,0x0"),
            ("hair.default_thickness", "1.0"),
            ("hair.point_count", "-9"),
        ] {
            let mut groom = original.clone();
            groom.provenance.metadata.insert(key.into(), value.into());
            let (bytes, back) = write_and_read(&groom, dir.path(), "bad.hair");
            // The general rule: uniform strands, no segments array.
            assert_eq!(header(&bytes).0 & HAS_SEGMENTS, 0, "{key}");
            assert_eq!(back.attributes, original.attributes, "{key}");
        }
        let mut groom = original.clone();
        groom
            .provenance
            .metadata
            .insert("hair.info".into(), "zz".repeat(INFO_SIZE));
        let (bytes, _) = write_and_read(&groom, dir.path(), "bad_info.hair");
        assert_eq!(&header(&bytes).3[..4], b"odd\0");
        assert!(header(&bytes).3[4..].iter().all(|&b| b == 0));
    }
}
