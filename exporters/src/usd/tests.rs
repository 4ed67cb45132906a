use super::crate_writer::{encode_ints32, lz4_literal_block};
use super::*;
use groom::{Attribute, Groom, Units, UpAxis};
use std::path::PathBuf;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("groombake-usd-export-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn small_groom() -> Groom {
    let mut groom = Groom::from_strands([
        vec![[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        vec![[1.0, 0.0, 0.0], [1.0, 1.5, 0.25]],
    ]);
    groom.units = Units::CENTIMETERS;
    groom.up_axis = UpAxis::Z;
    groom.set_attribute(Attribute::new(
        "width",
        AttributeValues::Float(vec![0.1, 0.05, 0.1, 0.05]),
    ));
    groom.set_attribute(Attribute::per_strand(
        "root_uv",
        AttributeValues::Vec2(vec![[0.1, 0.2], [0.3, 0.4]]),
    ));
    groom.set_attribute(Attribute::per_strand(
        "bond rate",
        AttributeValues::Int(vec![3, 4]),
    ));
    groom
}

/// The exact text of a small static export: the layout usd-core reads
/// (checked in CI), pinned so changes to it are deliberate.
#[test]
fn usda_text_is_stable() {
    let path = scratch("small.usda");
    crate::write(&path, &small_groom()).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let expected = r#"#usda 1.0
(
    defaultPrim = "Groom"
    doc = "Written by groombake"
    metersPerUnit = 0.01
    upAxis = "Z"
)

def Xform "Groom"
{
    def BasisCurves "Strands"
    {
        int[] curveVertexCounts = [2, 2]
        float3[] extent = [(-0.05, -0.05, -0.05), (1.05, 1.55, 0.3)]
        point3f[] points = [(0, 0, 0), (0, 1, 0), (1, 0, 0), (1, 1.5, 0.25)]
        int[] primvars:bond_rate = [3, 4] (
            interpolation = "uniform"
        )
        texCoord2f[] primvars:st = [(0.1, 0.2), (0.3, 0.4)] (
            interpolation = "uniform"
        )
        uniform token type = "linear"
        float[] widths = [0.1, 0.05, 0.1, 0.05] (
            interpolation = "vertex"
        )
        uniform token wrap = "nonperiodic"
    }
}
"#;
    assert_eq!(text, expected);
}

#[test]
fn crate_file_has_bootstrap_and_sections() {
    let path = scratch("small.usdc");
    crate::write(&path, &small_groom()).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(&bytes[..8], b"PXR-USDC");
    assert_eq!(&bytes[8..11], &[0, 8, 0], "version 0.8.0");
    let toc = u64::from_le_bytes(bytes[16..24].try_into().unwrap()) as usize;
    assert!(bytes[24..88].iter().all(|&b| b == 0));
    let count = u64::from_le_bytes(bytes[toc..toc + 8].try_into().unwrap()) as usize;
    assert_eq!(
        toc + 8 + count * 32,
        bytes.len(),
        "the table of contents ends the file"
    );
    let names: Vec<String> = (0..count)
        .map(|i| {
            let raw = &bytes[toc + 8 + i * 32..toc + 8 + i * 32 + 16];
            String::from_utf8(raw.iter().copied().take_while(|&b| b != 0).collect()).unwrap()
        })
        .collect();
    assert_eq!(
        names,
        ["TOKENS", "STRINGS", "FIELDS", "FIELDSETS", "PATHS", "SPECS"]
    );
}

#[test]
fn lz4_literal_blocks() {
    assert_eq!(lz4_literal_block(b""), vec![0x00]);
    assert_eq!(lz4_literal_block(b"abc"), b"\x30abc".to_vec());
    let fifteen = [7u8; 15];
    assert_eq!(&lz4_literal_block(&fifteen)[..2], &[0xF0, 0]);
    let long = vec![1u8; 15 + 255 + 3];
    assert_eq!(&lz4_literal_block(&long)[..3], &[0xF0, 255, 3]);
    assert_eq!(lz4_literal_block(&long).len(), long.len() + 3);
}

#[test]
fn integer_coding() {
    // Deltas 1, 1, 1: all the common value, codes all zero.
    assert_eq!(encode_ints32(&[1, 2, 3]), vec![1, 0, 0, 0, 0]);
    // Deltas 0, 300, 0, -1: common 0; codes 0, 2 (i16), 0, 1 (i8).
    let coded = encode_ints32(&[0, 300, 300, 299]);
    assert_eq!(&coded[..4], &0i32.to_le_bytes());
    assert_eq!(coded[4], 0b01_00_10_00);
    assert_eq!(&coded[5..], &[0x2C, 0x01, 0xFF]);
    // Ties go to the smallest delta: 0, 5, -5 each once -> common -5.
    assert_eq!(&encode_ints32(&[0, 5, 0])[..4], &(-5i32).to_le_bytes());
}

#[test]
fn streamed_frames_are_checked() {
    let groom = small_groom();
    let options = AnimationOptions {
        fps: 24.0,
        frame_count: 2,
    };
    for ext in ["usda", "usdc"] {
        // A directory of its own, so other tests' files do not count.
        let path = scratch(&format!("checked_{ext}")).join(format!("checked.{ext}"));
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        let mut writer = crate::animated(&path, &groom, options).unwrap();
        let wrong = Frame {
            time: 0.0,
            points: vec![[0.0; 3]; 3],
            attributes: Vec::new(),
        };
        assert!(
            writer.write_frame(&wrong).is_err(),
            "{ext}: wrong point count"
        );
        let frame = Frame {
            time: 1.0,
            points: groom.points.clone(),
            attributes: Vec::new(),
        };
        writer.write_frame(&frame).unwrap();
        assert!(
            writer.write_frame(&frame).is_err(),
            "{ext}: time must increase"
        );
        drop(writer);
        assert!(!path.exists(), "{ext}: an unfinished export leaves no file");

        let writer = crate::animated(&path, &groom, options).unwrap();
        assert!(writer.finish().is_err(), "{ext}: no frames");
        assert!(!path.exists());
        let leftovers = std::fs::read_dir(path.parent().unwrap())
            .unwrap()
            .filter(|e| {
                e.as_ref()
                    .unwrap()
                    .file_name()
                    .to_string_lossy()
                    .contains(".tmp")
            })
            .count();
        assert_eq!(leftovers, 0, "{ext}: temporary files removed");
    }
}

#[test]
fn bases_usd_cannot_hold_are_refused() {
    let mut groom = small_groom();
    groom.basis = CurveBasis::Hermite;
    let error = crate::write(&scratch("hermite.usda"), &groom).unwrap_err();
    assert!(error.to_string().contains("no hermite basis"), "{error}");
}

#[test]
fn time_codes_snap_to_whole_frames() {
    assert_eq!(time_code(5.0 / 24.0, 24.0), 5.0);
    assert_eq!(time_code(0.5 / 24.0, 24.0), 0.5);
}
