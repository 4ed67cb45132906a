//! The four first formats end to end through the real binary: the shared
//! USC-HairSalon/cyHair files, lossless `.hair`, glTF handed to the Khronos
//! validator, animated glTF round trips, and truncated input.

use crate::util::{hand_to_validators, sample, test_data, TestDir};
use groom::Frame;
use serde_json::json;

const BANGS_HAIR: &str = "hairutil_Bangs_100.hair";
const BANGS_DATA: &str = "hairutil_Bangs_100.data";

#[test]
fn bangs_hair_and_data_agree_to_the_bit() {
    let dir = TestDir::new();
    for name in [BANGS_HAIR, BANGS_DATA] {
        let path = test_data(name);
        let summary = dir.inspect(path.to_str().unwrap());
        assert_eq!(summary["strands"], 100, "{name}: {summary}");
        assert_eq!(summary["vertices"], 1165, "{name}: {summary}");
        assert_eq!(summary["units"], "cm", "{name}");
        assert_eq!(summary["up_axis"], "Y", "{name}");
        let first: Vec<f64> = summary["first_point"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        for (got, expected) in first.iter().zip([164.708, 171.292, 187.976]) {
            assert!((got - expected).abs() < 5e-4, "{name}: {first:?}");
        }
    }
    let hair = importers::read(&test_data(BANGS_HAIR)).unwrap();
    let data = importers::read(&test_data(BANGS_DATA)).unwrap();
    assert_eq!(hair.strand_vertex_counts, data.strand_vertex_counts);
    let bits = |g: &groom::Groom| -> Vec<[u32; 3]> {
        g.points.iter().map(|p| p.map(f32::to_bits)).collect()
    };
    assert_eq!(bits(&hair), bits(&data));
}

#[test]
fn hair_to_hair_keeps_the_file_byte_for_byte() {
    let dir = TestDir::new();
    let source = test_data(BANGS_HAIR);
    dir.run_ok(&["convert", source.to_str().unwrap(), "copy.hair"]);
    let original = std::fs::read(&source).unwrap();
    let copy = std::fs::read(dir.path("copy.hair")).unwrap();
    assert_eq!(copy.len(), original.len());
    // Header and every array.
    assert!(copy == original, "copy.hair differs from the source");
}

#[test]
fn data_to_glb_validates() {
    let dir = TestDir::new();
    let source = test_data(BANGS_DATA);
    dir.run_ok(&["convert", source.to_str().unwrap(), "bangs.glb"]);
    let summary = dir.inspect("bangs.glb");
    assert_eq!(summary["strands"], 100);
    assert_eq!(summary["vertices"], 1165);
    assert_eq!(summary["units"], "m");
    // Centimetres became metres.
    let x = summary["first_point"][0].as_f64().unwrap();
    assert!((x - 1.64708).abs() < 1e-5, "{summary}");
    hand_to_validators(
        &dir.path("bangs.glb"),
        "formats_bangs_data",
        json!({"kind": "gltf", "primitives": 1, "vertices": 1165}),
    );
}

#[test]
fn hair_to_gltf_and_obj_keep_counts() {
    let dir = TestDir::new();
    let source = test_data(BANGS_HAIR);
    for out in ["bangs.gltf", "bangs.obj", "bangs.data"] {
        dir.run_ok(&["convert", source.to_str().unwrap(), out]);
        let summary = dir.inspect(out);
        assert_eq!(summary["strands"], 100, "{out}");
        assert_eq!(summary["vertices"], 1165, "{out}");
    }
    hand_to_validators(
        &dir.path("bangs.gltf"),
        "formats_bangs_hair",
        json!({"kind": "gltf", "primitives": 1, "vertices": 1165}),
    );
}

#[test]
fn animated_glb_round_trips_its_frames() {
    let dir = TestDir::new();
    dir.run_ok(&[
        "generate",
        "wavy",
        "-o",
        "wavy.glb",
        "--strands",
        "20",
        "--seed",
        "7",
    ]);
    let mut groom = importers::read(&dir.path("wavy.glb")).unwrap();
    // An integer per strand: written as 16-bit `_STRAND_ID`, marked per strand.
    groom.set_attribute(groom::Attribute::per_strand(
        "strand_id",
        groom::AttributeValues::Int((0..20).map(|i| i * 1000 - 5000).collect()),
    ));
    // Twelve frames of a sway, streamed through the library's frame writer.
    let frames: Vec<Frame> = (0..12)
        .map(|k| Frame {
            time: k as f64 / 24.0,
            points: groom
                .points
                .iter()
                .map(|p| [p[0] + 0.01 * (k as f32 * 0.5).sin() * p[1], p[1], p[2]])
                .collect(),
            attributes: Vec::new(),
        })
        .collect();
    let options = exporters::AnimationOptions {
        fps: 24.0,
        frame_count: frames.len(),
    };
    let mut writer = exporters::animated(&dir.path("sway.glb"), &groom, options).unwrap();
    for frame in &frames {
        writer.write_frame(frame).unwrap();
    }
    writer.finish().unwrap();

    let summary = dir.inspect("sway.glb");
    assert_eq!(summary["frames"], 12, "{summary}");
    assert_eq!(summary["strands"], 20);
    // Through the CLI once more: convert writes the frames again.
    dir.run_ok(&["convert", "sway.glb", "again.glb"]);
    for file in ["sway.glb", "again.glb"] {
        let back = importers::read(&dir.path(file)).unwrap();
        assert_eq!(back.strand_vertex_counts, groom.strand_vertex_counts);
        for name in ["strand_id", "root_uv"] {
            assert_eq!(
                back.attribute(name),
                groom.attribute(name),
                "{file}: {name}"
            );
        }
        assert_eq!(back.frames.len(), frames.len(), "{file}");
        for (k, (expected, got)) in frames.iter().zip(&back.frames).enumerate() {
            assert!((expected.time - got.time).abs() < 1e-6, "{file} frame {k}");
            for (p, q) in expected.points.iter().zip(&got.points) {
                for c in 0..3 {
                    assert!(
                        (p[c] - q[c]).abs() < 1e-6,
                        "{file} frame {k}: {p:?} vs {q:?}"
                    );
                }
            }
        }
    }
    let vertices = groom.vertex_count();
    hand_to_validators(
        &dir.path("again.glb"),
        "formats_animated",
        json!({"kind": "gltf", "primitives": 1, "vertices": vertices, "animations": 1, "morph_targets": true}),
    );
    // A single frame of it as a static .hair.
    dir.run_ok(&["convert", "sway.glb", "frame3.obj", "--frame", "3"]);
    let summary = dir.inspect("frame3.obj");
    assert_eq!(summary["frames"], 0);
}

#[test]
fn hair_cut_to_700_bytes_exits_2_naming_file_and_offset() {
    let dir = TestDir::new();
    let bytes = std::fs::read(test_data(BANGS_HAIR)).unwrap();
    std::fs::write(dir.path("cut.hair"), &bytes[..700]).unwrap();
    let stderr = dir.run_fail(&["inspect", "cut.hair"], 2);
    assert!(
        stderr.starts_with("groombake: cut.hair:offset 700: "),
        "{stderr}"
    );
    assert!(stderr.contains("too short"), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
}

#[test]
fn malformed_inputs_exit_2_without_output() {
    let dir = TestDir::new();
    let hair = std::fs::read(test_data(BANGS_HAIR)).unwrap();
    let mut wrong_magic = hair.clone();
    wrong_magic[..4].copy_from_slice(b"HIAR");
    std::fs::write(dir.path("magic.hair"), &wrong_magic).unwrap();
    let mut nan = hair.clone();
    // First coordinate: header 128 + 100 u16 segment counts.
    nan[328..332].copy_from_slice(&f32::NAN.to_le_bytes());
    std::fs::write(dir.path("nan.hair"), &nan).unwrap();
    let mut data = std::fs::read(test_data(BANGS_DATA)).unwrap();
    data[..4].copy_from_slice(&1_000_000_000i32.to_le_bytes());
    std::fs::write(dir.path("count.data"), &data).unwrap();
    std::fs::write(dir.path("bad.obj"), "v 0 0 0\nv 1 1 1\nl 1 3\n").unwrap();
    std::fs::write(dir.path("bad.glb"), b"glTF\x02\x00\x00\x00\xff\x00\x00\x00").unwrap();
    for (file, expected) in [
        ("magic.hair", "magic.hair:offset 0: not a .hair file"),
        (
            "nan.hair",
            "nan.hair:offset 328: point coordinate is not finite",
        ),
        ("count.data", "count.data:offset 4: strand count"),
        ("bad.obj", "bad.obj:3:5: vertex index 3 is out of range"),
        ("bad.glb", "bad.glb"),
    ] {
        let stderr = dir.run_fail(&["convert", file, "out.glb"], 2);
        assert!(
            stderr.starts_with(&format!("groombake: {expected}")),
            "{stderr}"
        );
        assert!(!dir.path("out.glb").exists(), "{file}: partial output");
    }
}

#[test]
fn empty_roots_of_data_survive_glb() {
    let dir = TestDir::new();
    let strands: [&[[f32; 3]]; 4] = [
        &[[0.0, 0.0, 0.0]],
        &[[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 2.0, 1.0]],
        &[[1.0, 0.0, 0.0]],
        &[[1.0, 0.0, 0.0], [1.0, 1.0, 0.0]],
    ];
    let mut bytes = (strands.len() as i32).to_le_bytes().to_vec();
    for strand in strands {
        bytes.extend_from_slice(&(strand.len() as i32).to_le_bytes());
        for c in strand.iter().flatten() {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    std::fs::write(dir.path("roots.data"), bytes).unwrap();
    dir.run_ok(&["convert", "roots.data", "roots.glb"]);
    let summary = dir.inspect("roots.glb");
    assert_eq!(summary["strands"], 4, "{summary}");
    assert_eq!(summary["single_point_strands"], 2, "{summary}");
    hand_to_validators(
        &dir.path("roots.glb"),
        "formats_empty_roots",
        json!({"kind": "gltf", "primitives": 1, "vertices": 7}),
    );
}

#[test]
fn collider_samples_load_and_the_pillow_goes_to_the_validator() {
    let (head_vertices, head) = importers::mesh::read_triangles(&sample("head.obj")).unwrap();
    assert_eq!((head_vertices.len(), head.len()), (642, 1280));
    let (pillow_vertices, pillow) = importers::mesh::read_triangles(&sample("pillow.glb")).unwrap();
    assert_eq!((pillow_vertices.len(), pillow.len()), (8, 12));
    hand_to_validators(
        &sample("pillow.glb"),
        "formats_pillow_sample",
        json!({"kind": "gltf", "primitives": 1, "vertices": 8}),
    );
}

/// A `.hair` file whose header the general rule would not write: uniform
/// strands with a segments array, a default segment count that is unused,
/// non-standard default thickness and colour without arrays, bytes after the
/// info text's NUL.
fn unusual_hair() -> Vec<u8> {
    let mut b = Vec::new();
    b.extend_from_slice(b"HAIR");
    for word in [2u32, 6, 1 | 2, 77] {
        b.extend_from_slice(&word.to_le_bytes());
    }
    for value in [0.5f32, 0.0, 0.25, 0.5, 0.75] {
        b.extend_from_slice(&value.to_le_bytes());
    }
    let mut info = [0u8; 88];
    info[..7].copy_from_slice(b"unusual");
    info[80..].copy_from_slice(b"leftover");
    b.extend_from_slice(&info);
    b.extend_from_slice(&[2, 0, 2, 0]);
    for k in 0..18 {
        b.extend_from_slice(&(k as f32 * 0.5).to_le_bytes());
    }
    b
}

#[test]
fn unusual_hair_header_survives_convert_byte_for_byte() {
    let dir = TestDir::new();
    std::fs::write(dir.path("unusual.hair"), unusual_hair()).unwrap();
    dir.run_ok(&["convert", "unusual.hair", "copy.hair"]);
    assert!(std::fs::read(dir.path("copy.hair")).unwrap() == unusual_hair());
    // Through glTF the header is gone: the general rule writes the arrays.
    dir.run_ok(&["convert", "unusual.hair", "unusual.glb", "--units", "m"]);
    dir.run_ok(&["convert", "unusual.glb", "back.hair", "--units", "cm"]);
    let back = importers::read(&dir.path("back.hair")).unwrap();
    let original = importers::read(&dir.path("unusual.hair")).unwrap();
    assert_eq!(back.strand_vertex_counts, original.strand_vertex_counts);
    assert_eq!(
        back.attribute("width").unwrap().values,
        original.attribute("width").unwrap().values
    );
}

#[test]
fn per_strand_and_wide_integer_attributes_survive_glb_and_validate() {
    use groom::{Attribute, AttributeValues, Groom, Scope};
    let dir = TestDir::new();
    let mut groom = Groom::from_strands([
        vec![[0.0, 0.0, 0.0], [0.0, 0.1, 0.0]],
        vec![[0.1, 0.0, 0.0], [0.1, 0.1, 0.0], [0.1, 0.2, 0.0]],
    ]);
    groom.units = groom::Units::METERS;
    groom.set_attribute(Attribute::per_strand(
        "Clump ID",
        AttributeValues::Int(vec![i32::MIN, 1 << 30]),
    ));
    groom.set_attribute(Attribute::per_strand(
        "Root_UV",
        AttributeValues::Vec2(vec![[0.25, 0.5], [0.75, 1.0]]),
    ));
    let path = dir.path("attributes.glb");
    exporters::write(&path, &groom).unwrap();
    // Through the binary too: convert keeps what the importer rebuilt.
    dir.run_ok(&["convert", "attributes.glb", "again.gltf"]);
    for file in ["attributes.glb", "again.gltf"] {
        let back = importers::read(&dir.path(file)).unwrap();
        for attribute in &groom.attributes {
            let got = back.attribute(&attribute.name).unwrap();
            assert_eq!(got.scope, Scope::Strand, "{file}: {}", attribute.name);
            assert_eq!(got.values, attribute.values, "{file}: {}", attribute.name);
        }
    }
    hand_to_validators(
        &path,
        "formats_strand_attributes",
        json!({"kind": "gltf", "primitives": 1, "vertices": 5}),
    );
}
