//! Exporter tests: every format written and read back through the importers,
//! every pair of formats round-tripped, lossless `.hair`, streamed glTF
//! animation.

use crate::{animated, write, AnimationOptions, ExportError};
use groom::{Attribute, AttributeValues, Frame, Groom, Units, UpAxis};
use std::path::{Path, PathBuf};

struct Scratch(tempfile::TempDir);

impl Scratch {
    fn new() -> Scratch {
        Scratch(tempfile::tempdir().unwrap())
    }
    fn path(&self, name: &str) -> PathBuf {
        self.0.path().join(name)
    }
    fn files(&self) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(self.0.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }
}

fn sample_groom() -> Groom {
    let mut groom = Groom::from_strands([
        vec![[0.0, 10.0, 0.0], [0.5, 11.0, 0.25]],
        vec![
            [1.0, 10.0, 0.0],
            [1.25, 11.0, 0.0],
            [1.5, 12.0, -0.125],
            [1.75, 13.0, 0.3],
            [2.0, 14.0, 0.7],
        ],
        vec![[-3.0, 9.0, 1.0], [-3.1, 8.0, 1.1], [-3.3, 7.0, 1.2]],
    ]);
    groom.units = Units::CENTIMETERS;
    groom.up_axis = UpAxis::Y;
    let widths = (0..groom.vertex_count()).map(|i| 0.01 * (i + 1) as f32);
    groom.set_attribute(Attribute::new(
        "width",
        AttributeValues::Float(widths.collect()),
    ));
    groom
}

/// A file of the workspace's `tests/data/`.
fn test_data(name: &str) -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/data")).join(name)
}

fn assert_points_close(a: &Groom, b: &Groom, context: &str) {
    assert_eq!(
        a.strand_vertex_counts, b.strand_vertex_counts,
        "{context}: strand counts"
    );
    assert_eq!(a.points.len(), b.points.len(), "{context}: point count");
    for (i, (p, q)) in a.points.iter().zip(&b.points).enumerate() {
        for k in 0..3 {
            let tolerance = 1e-6 * p[k].abs().max(1.0) * 4.0;
            assert!(
                (p[k] - q[k]).abs() <= tolerance,
                "{context}: point {i}: {p:?} vs {q:?}"
            );
        }
    }
}

/// Reads a file and converts it to the units and axis of `like`. Files of
/// formats that carry no units are taken to be in `like`'s units (as
/// `convert --source-units` would say).
fn read_like(path: &Path, like: &Groom) -> Groom {
    let mut groom = importers::read(path).unwrap();
    if groom.provenance.format != "gltf" {
        groom.units = like.units;
        groom.up_axis = like.up_axis;
    }
    groom.convert_to(like.units, like.up_axis);
    groom
}

const FORMATS: [&str; 5] = ["hair", "data", "obj", "glb", "gltf"];

#[test]
fn every_pair_of_formats_round_trips() {
    let dir = Scratch::new();
    for a in FORMATS {
        for b in FORMATS {
            let context = format!("{a} -> {b} -> {a}");
            let first = dir.path(&format!("first_{a}_{b}.{a}"));
            write(&first, &sample_groom()).unwrap();
            let original = importers::read(&first).unwrap();
            let middle = dir.path(&format!("middle_{a}_{b}.{b}"));
            write(&middle, &original).unwrap();
            let through_b = read_like(&middle, &original);
            let last = dir.path(&format!("last_{a}_{b}.{a}"));
            write(&last, &through_b).unwrap();
            let back = read_like(&last, &original);
            assert_points_close(&original, &back, &context);
        }
    }
}

#[test]
fn attributes_survive_hair_and_gltf() {
    let dir = Scratch::new();
    let groom = sample_groom();
    for ext in ["hair", "glb", "gltf"] {
        let path = dir.path(&format!("w.{ext}"));
        write(&path, &groom).unwrap();
        let back = read_like(&path, &groom);
        let Some(AttributeValues::Float(widths)) = back.attribute("width").map(|a| &a.values)
        else {
            panic!("{ext}: no width attribute");
        };
        let AttributeValues::Float(expected) = &groom.attribute("width").unwrap().values else {
            unreachable!()
        };
        for (w, e) in widths.iter().zip(expected) {
            assert!((w - e).abs() < 1e-6, "{ext}: width {w} vs {e}");
        }
    }
}

#[test]
fn hair_to_hair_is_byte_identical() {
    let source = test_data("hairutil_Bangs_100.hair");
    let dir = Scratch::new();
    let out = dir.path("copy.hair");
    write(&out, &importers::read(&source).unwrap()).unwrap();
    assert_eq!(
        std::fs::read(&out).unwrap(),
        std::fs::read(&source).unwrap()
    );
}

#[test]
fn hair_with_every_array_is_byte_identical() {
    let dir = Scratch::new();
    let mut groom = sample_groom();
    let n = groom.vertex_count();
    groom.set_attribute(Attribute::new(
        "transparency",
        AttributeValues::Float(vec![0.5; n]),
    ));
    groom.set_attribute(Attribute::new(
        "color",
        AttributeValues::Vec3((0..n).map(|i| [i as f32 / 10.0, 0.2, 0.3]).collect()),
    ));
    groom.provenance.info = "made by a test".into();
    let first = dir.path("first.hair");
    write(&first, &groom).unwrap();
    let second = dir.path("second.hair");
    write(&second, &importers::read(&first).unwrap()).unwrap();
    let bytes = std::fs::read(&first).unwrap();
    assert_eq!(bytes, std::fs::read(&second).unwrap());
    // All five arrays: 128 + 2*3 + 12n + 4n + 4n + 12n bytes.
    assert_eq!(bytes.len(), 128 + 6 + 32 * n);
    assert_eq!(&bytes[12..16], &31u32.to_le_bytes());
}

#[test]
fn data_to_data_is_byte_identical() {
    let source = test_data("hairutil_Bangs_100.data");
    let dir = Scratch::new();
    let out = dir.path("copy.data");
    write(&out, &importers::read(&source).unwrap()).unwrap();
    assert_eq!(
        std::fs::read(&out).unwrap(),
        std::fs::read(&source).unwrap()
    );
}

#[test]
fn single_point_strands_survive_data_obj_and_gltf() {
    let dir = Scratch::new();
    let mut groom = sample_groom();
    groom.attributes.clear();
    groom.strand_vertex_counts = vec![1, 1, 5, 3];
    for ext in ["data", "obj", "glb"] {
        let path = dir.path(&format!("single.{ext}"));
        write(&path, &groom).unwrap();
        let back = read_like(&path, &groom);
        assert_eq!(back.strand_vertex_counts, vec![1, 1, 5, 3], "{ext}");
        assert_points_close(&groom, &back, ext);
        if ext != "glb" {
            assert_eq!(back.points, groom.points, "{ext}");
        }
    }
}

#[test]
fn outputs_are_deterministic() {
    let dir = Scratch::new();
    let mut groom = sample_groom();
    groom.frames = animation_frames(&groom, 3);
    for ext in FORMATS {
        let a = dir.path(&format!("a.{ext}"));
        let b = dir.path(&format!("b.{ext}"));
        write(&a, &groom).unwrap();
        write(&b, &groom).unwrap();
        assert_eq!(
            std::fs::read(a).unwrap(),
            std::fs::read(b).unwrap(),
            "{ext}"
        );
    }
}

fn animation_frames(groom: &Groom, count: usize) -> Vec<Frame> {
    (0..count)
        .map(|k| Frame {
            time: k as f64 / 24.0,
            points: groom
                .points
                .iter()
                .enumerate()
                .map(|(i, p)| [p[0] + k as f32 * 0.5, p[1] - (k * i) as f32 * 0.01, p[2]])
                .collect(),
            attributes: Vec::new(),
        })
        .collect()
}

#[test]
fn gltf_animation_streams_and_reads_back_as_frames() {
    let dir = Scratch::new();
    let groom = sample_groom();
    let frames = animation_frames(&groom, 5);
    for ext in ["glb", "gltf"] {
        let path = dir.path(&format!("anim.{ext}"));
        let options = AnimationOptions {
            fps: 24.0,
            frame_count: frames.len(),
        };
        let mut writer = animated(&path, &groom, options).unwrap();
        for frame in &frames {
            writer.write_frame(frame).unwrap();
        }
        assert!(!path.exists(), "{ext}: output appeared before finish");
        writer.finish().unwrap();
        let back = read_like(&path, &groom);
        assert_points_close(&groom, &back, ext);
        assert_eq!(back.frames.len(), frames.len(), "{ext}");
        for (k, (f, b)) in frames.iter().zip(&back.frames).enumerate() {
            assert!((f.time - b.time).abs() < 1e-6, "{ext}: frame {k} time");
            let mut expected = groom.clone();
            expected.points = f.points.clone();
            let mut got = groom.clone();
            got.points = b.points.clone();
            assert_points_close(&expected, &got, &format!("{ext} frame {k}"));
        }
    }
}

#[test]
fn gltf_is_metres_y_up() {
    let dir = Scratch::new();
    let mut groom = sample_groom();
    groom.up_axis = UpAxis::Z;
    let path = dir.path("z.glb");
    write(&path, &groom).unwrap();
    let back = importers::read(&path).unwrap();
    assert_eq!(back.units, Units::METERS);
    assert_eq!(back.up_axis, UpAxis::Y);
    // Z-up cm (x, y, z) is Y-up m (x, z, -y) / 100.
    let p = groom.points[1];
    let q = back.points[1];
    let expected = [p[0] * 0.01, p[2] * 0.01, -p[1] * 0.01];
    for k in 0..3 {
        assert!((q[k] - expected[k]).abs() < 1e-7, "{q:?} vs {expected:?}");
    }
}

#[test]
fn bad_frames_are_refused_and_leave_no_file() {
    let dir = Scratch::new();
    let groom = sample_groom();
    let path = dir.path("bad.glb");
    let options = AnimationOptions {
        fps: 24.0,
        frame_count: 2,
    };
    let mut writer = animated(&path, &groom, options).unwrap();
    let short = Frame {
        time: 0.0,
        points: vec![[0.0; 3]; 2],
        attributes: Vec::new(),
    };
    assert!(matches!(
        writer.write_frame(&short),
        Err(ExportError::Invalid { .. })
    ));
    let mut nan = groom.points.clone();
    nan[3][1] = f32::NAN;
    let error = writer
        .write_frame(&Frame {
            time: 0.0,
            points: nan,
            attributes: Vec::new(),
        })
        .unwrap_err()
        .to_string();
    assert!(error.contains("vertex 3"), "{error}");
    writer
        .write_frame(&Frame {
            time: 1.0,
            points: groom.points.clone(),
            attributes: Vec::new(),
        })
        .unwrap();
    let error = writer
        .write_frame(&Frame {
            time: 0.5,
            points: groom.points.clone(),
            attributes: Vec::new(),
        })
        .unwrap_err()
        .to_string();
    assert!(error.contains("does not increase"), "{error}");
    drop(writer);
    assert!(dir.files().is_empty(), "{:?}", dir.files());
}

#[test]
fn static_formats_refuse_animation() {
    let dir = Scratch::new();
    let options = AnimationOptions {
        fps: 24.0,
        frame_count: 1,
    };
    for ext in ["hair", "data", "obj"] {
        let result = animated(&dir.path(&format!("a.{ext}")), &sample_groom(), options);
        assert!(
            matches!(result, Err(ExportError::Unsupported { .. })),
            "{ext}"
        );
    }
}

#[test]
fn hair_refuses_strands_it_cannot_hold() {
    let dir = Scratch::new();
    // Strands of one length fit the header's u32 default segment count...
    let long = Groom::from_strands(vec![vec![[0.0f32, 0.0, 0.0]; 70_000]; 2]);
    write(&dir.path("long.hair"), &long).unwrap();
    let back = importers::read(&dir.path("long.hair")).unwrap();
    assert_eq!(back.strand_vertex_counts, vec![70_000; 2]);
    // ...but the segments array holds at most 65536 points per strand.
    let mut mixed = long.clone();
    mixed.strand_vertex_counts = vec![70_000, 69_999, 1];
    let error = write(&dir.path("mixed.hair"), &mixed).unwrap_err();
    assert!(matches!(error, ExportError::Invalid { .. }), "{error}");
    assert!(
        error.to_string().contains("strand 0 has 70000 points"),
        "{error}"
    );
    assert_eq!(dir.files(), vec!["long.hair".to_string()]);
}

#[test]
fn attribute_types_scopes_and_names_survive_gltf() {
    let dir = Scratch::new();
    let mut groom = sample_groom();
    let n = groom.vertex_count();
    let attributes = [
        Attribute::new(
            "group",
            AttributeValues::Int((0..n as i32).map(|i| i - 3).collect()),
        ),
        // TEXCOORD_0 holds 1 - v (glTF's texture origin is top left); these
        // values are exact both ways (others come back within 6e-8).
        Attribute::per_strand(
            "root_uv",
            AttributeValues::Vec2(vec![[0.1, 0.5], [0.3, 0.75], [0.5, 0.625]]),
        ),
        // Beyond 16 bits but exact as floats; beyond 2^24: split in two u16.
        Attribute::per_strand(
            "Clump ID",
            AttributeValues::Int(vec![70_000, -1, 16_777_216]),
        ),
        Attribute::new(
            "seed",
            AttributeValues::Int((0..n as i32).map(|i| i32::MIN + i * 99_999_999).collect()),
        ),
        // Names that only case tells apart.
        Attribute::per_strand("Width", AttributeValues::Float(vec![1.0, 2.0, 3.0])),
        Attribute::per_strand(
            "tint",
            AttributeValues::Vec3(vec![[0.5; 3], [0.25; 3], [1.0; 3]]),
        ),
    ];
    for attribute in attributes {
        groom.set_attribute(attribute);
    }
    // Metres: width-like attributes are not rescaled on the way.
    groom.units = Units::METERS;
    for ext in ["glb", "gltf"] {
        let path = dir.path(&format!("attrs.{ext}"));
        write(&path, &groom).unwrap();
        let back = importers::read(&path).unwrap();
        let mut expected = groom.attributes.clone();
        let mut got = back.attributes.clone();
        expected.sort_by(|a, b| a.name.cmp(&b.name));
        got.sort_by(|a, b| a.name.cmp(&b.name));
        assert_eq!(got, expected, "{ext}");
    }
}

#[test]
fn per_strand_values_that_differ_along_a_strand_stay_per_vertex() {
    let dir = Scratch::new();
    let mut groom = sample_groom();
    groom.units = Units::METERS;
    groom.set_attribute(Attribute::per_strand(
        "level",
        AttributeValues::Float(vec![1.0, 2.0, 3.0]),
    ));
    let path = dir.path("edited.gltf");
    write(&path, &groom).unwrap();
    // Another tool edits one vertex's value but keeps the extras: 2.0 is the
    // second strand's value on its 5 vertices, and is written nowhere else.
    let text = std::fs::read_to_string(&path).unwrap();
    let mut document: serde_json::Value = serde_json::from_str(&text).unwrap();
    let accessor = document["meshes"][0]["primitives"][0]["attributes"]["_LEVEL"]
        .as_u64()
        .unwrap() as usize;
    assert_eq!(
        document["accessors"][accessor]["extras"]["groombake"]["scope"],
        "strand"
    );
    let view = document["accessors"][accessor]["bufferView"]
        .as_u64()
        .unwrap() as usize;
    let offset = document["bufferViews"][view]["byteOffset"]
        .as_u64()
        .unwrap() as usize;
    let uri = document["buffers"][0]["uri"].as_str().unwrap().to_string();
    let (prefix, payload) = uri.split_once(";base64,").unwrap();
    use base64::Engine;
    let engine = base64::engine::general_purpose::STANDARD;
    let mut bytes = engine.decode(payload).unwrap();
    // Vertex 3 is the second strand's second point.
    bytes[offset + 12..offset + 16].copy_from_slice(&9.0f32.to_le_bytes());
    document["buffers"][0]["uri"] = format!("{prefix};base64,{}", engine.encode(&bytes)).into();
    std::fs::write(&path, document.to_string()).unwrap();
    let back = importers::read(&path).unwrap();
    let level = back.attribute("level").unwrap();
    assert_eq!(level.scope, groom::Scope::Vertex);
    assert_eq!(
        level.values,
        AttributeValues::Float(vec![1.0, 1.0, 2.0, 9.0, 2.0, 2.0, 2.0, 3.0, 3.0, 3.0])
    );
}

#[test]
fn every_cut_of_every_format_is_an_error_not_a_panic() {
    let dir = Scratch::new();
    let mut groom = sample_groom();
    groom.frames = animation_frames(&groom, 2);
    for ext in FORMATS {
        let whole = dir.path(&format!("whole.{ext}"));
        write(&whole, &groom).unwrap();
        let bytes = std::fs::read(&whole).unwrap();
        let cut_path = dir.path(&format!("cut.{ext}"));
        // Every byte for the binary formats' headers, then every few bytes.
        let cuts = (0..bytes.len().min(160)).chain((160..bytes.len()).step_by(7));
        for cut in cuts {
            std::fs::write(&cut_path, &bytes[..cut]).unwrap();
            let result = importers::read(&cut_path);
            // Text formats may still parse when cut at a line end; the
            // binary ones must refuse every cut.
            if matches!(ext, "hair" | "data" | "glb") {
                assert!(result.is_err(), "{ext} cut at {cut} was accepted");
            }
        }
    }
}

#[test]
fn gltf_root_uv_is_texcoord_0_and_custom_attributes_are_scalars() {
    let dir = Scratch::new();
    let mut groom = sample_groom();
    let n = groom.vertex_count();
    groom.set_attribute(Attribute::per_strand(
        "root_uv",
        AttributeValues::Vec2(vec![[0.25, 0.75], [0.5, 0.5], [1.0, 0.0]]),
    ));
    groom.set_attribute(Attribute::new(
        "flow",
        AttributeValues::Vec2((0..n).map(|i| [i as f32, -(i as f32)]).collect()),
    ));
    groom.set_attribute(Attribute::new(
        "seed",
        AttributeValues::Int((0..n as i32).map(|i| i32::MIN + i).collect()),
    ));
    let path = dir.path("uv.gltf");
    write(&path, &groom).unwrap();
    let document: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let primitive = &document["meshes"][0]["primitives"][0];
    let accessors = document["accessors"].as_array().unwrap();
    let attributes = primitive["attributes"].as_object().unwrap();
    let uv = &accessors[attributes["TEXCOORD_0"].as_u64().unwrap() as usize];
    assert_eq!(
        (uv["type"].as_str(), uv["componentType"].as_u64()),
        (Some("VEC2"), Some(5126))
    );
    for (semantic, index) in attributes {
        if semantic.starts_with('_') {
            let kind = accessors[index.as_u64().unwrap() as usize]["type"]
                .as_str()
                .unwrap();
            assert!(
                matches!(kind, "SCALAR" | "VEC3" | "VEC4"),
                "{semantic}: {kind}"
            );
        }
    }
    assert!(!attributes.contains_key("_ROOT_UV"));
    let back = importers::read(&path).unwrap();
    // V is flipped on the way out (glTF's origin is top left) and back in:
    // the values chosen are exact both ways.
    for name in ["root_uv", "flow", "seed"] {
        assert_eq!(back.attribute(name), groom.attribute(name), "{name}");
    }
}

#[test]
fn usda_writes_large_and_tiny_floats_in_exponent_form() {
    let dir = Scratch::new();
    let mut groom = Groom::from_strands([vec![[0.0, 0.0, 0.0], [1e30, 2.5e-7, -3.0e20]]]);
    groom.units = Units::METERS;
    let path = dir.path("big.usda");
    write(&path, &groom).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("(1e30, 2.5e-7, -3e20)"), "{text}");
    assert!(!text.contains("000000000000"), "{text}");
    let back = importers::read(&path).unwrap();
    assert_eq!(back.points, groom.points);
}

/// A name USD cannot hold (a damaged file's `groom_grou` and four NULs, as
/// the round-trip fuzz found) is written changed: said, never silent.
#[test]
fn an_attribute_name_usd_cannot_hold_is_warned() {
    let mut groom = sample_groom();
    let count = groom.strand_count();
    groom.attributes.push(Attribute::per_strand(
        "groom_grou\0\0\0\0",
        AttributeValues::Float(vec![1.0; count]),
    ));
    for name in ["a.usda", "a.usdc"] {
        let warnings = crate::warnings(Path::new(name), &groom, Units::METERS);
        assert!(
            warnings
                .iter()
                .any(|w| w.contains("not USD identifiers") && w.contains("groom_grou____")),
            "{warnings:?}"
        );
    }
    groom.attributes.pop();
    let warnings = crate::warnings(Path::new("a.usda"), &groom, Units::METERS);
    assert!(
        !warnings.iter().any(|w| w.contains("not USD identifiers")),
        "{warnings:?}"
    );
}

/// A point whose rest sits at 3.7e17 m (a fuzzed Alembic file) and that
/// moves to 6 cm comes back from glTF's morph targets as 0: the conversion
/// says so (found by the round-trip fuzz, seed 41, Alembic mutant 126),
/// and hair-scale motion gives no warning.
#[test]
fn gltf_warns_when_morph_targets_round_far_points() {
    let mut groom = Groom::from_strands([vec![[0.0, 0.02, 0.0], [3.7e17, 0.04, 6.4e17]]]);
    groom.frames = vec![
        Frame {
            time: 0.0,
            points: groom.points.clone(),
            attributes: Vec::new(),
        },
        Frame {
            time: 1.0 / 30.0,
            points: vec![[0.0, 0.02, 0.0], [0.0646, 0.04, 0.0446]],
            attributes: Vec::new(),
        },
    ];
    let warnings = crate::warnings(Path::new("far.glb"), &groom, Units::METERS);
    assert!(
        warnings.iter().any(|w| w.starts_with(
            "far.glb: glTF holds frames as offsets from the rest pose, and 1 point(s)"
        )),
        "{warnings:?}"
    );
    // The same motion near the rest pose: nothing lost, no warning; nor in
    // a format that writes each frame whole.
    groom.points[1] = [0.06, 0.04, 0.04];
    groom.frames[0].points[1] = [0.06, 0.04, 0.04];
    assert!(crate::warnings(Path::new("near.glb"), &groom, Units::METERS).is_empty());
    groom.points[1] = [3.7e17, 0.04, 6.4e17];
    assert!(crate::warnings(Path::new("far.abc"), &groom, Units::METERS).is_empty());
}
