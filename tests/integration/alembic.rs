//! Alembic end to end: conversions through the real binary, animated
//! exports through the library's frame writer, the shared files written by
//! other tools, and damaged files. Exported files go to the alembic3d
//! validator of `.ci/run` with what it must find in them.

use crate::util::{hand_to_validators, test_data, TestDir};
use groom::Frame;
use serde_json::json;
use std::path::Path;

const BANGS_HAIR: &str = "hairutil_Bangs_100.hair";
const BANGS_ABC: &str = "hairutil_Bangs_100.abc";
const BLENDER_ABC: &str = "blender501_hair_static.abc";

/// An archive Blender wrote (`_ai_Application=Blender`) is in metres: the
/// units rule takes the application's units where no `--source-units` is
/// given, and `inspect --json` says so. Blender's Poly curve starts at
/// (1, 0, 0) and the hair reaches 0.4 up (alembic3d reads the same numbers).
#[test]
fn blender_archive_reads_as_metres() {
    let dir = TestDir::new();
    let source = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(BLENDER_ABC);
    let source = source.to_str().unwrap();
    let summary = dir.inspect(source);
    assert_eq!(summary["units"], "m", "{summary}");
    assert_eq!(summary["units_source"], "application Blender", "{summary}");
    assert_eq!(summary["bounds"]["max"], json!([1.1f32, 0.4f32, 0.0]));
    // Converted with the defaults, it stays in metres (what Blender and
    // Houdini read Alembic as).
    dir.run_ok(&["convert", source, "default.abc"]);
    let default = importers::read(&dir.path("default.abc")).unwrap();
    assert_eq!(default.units, groom::Units::METERS);
    // For Maya: centimetres.
    dir.run_ok(&["convert", source, "cm.abc", "--target", "maya"]);
    let cm = importers::read(&dir.path("cm.abc")).unwrap();
    assert_eq!(cm.units, groom::Units::CENTIMETERS);
    let (_, max) = cm.bounds().unwrap();
    assert!(
        (max[0] - 110.0).abs() < 1e-4 && (max[1] - 40.0).abs() < 1e-4,
        "{max:?}"
    );
    // Stated units win over the application's (written in cm, as read).
    dir.run_ok(&[
        "convert",
        source,
        "stated.abc",
        "--source-units",
        "cm",
        "--units",
        "cm",
    ]);
    let (_, max) = importers::read(&dir.path("stated.abc"))
        .unwrap()
        .bounds()
        .unwrap();
    assert!((max[0] - 1.1).abs() < 1e-6, "{max:?}");
    // --units m writes metres and marks them.
    dir.run_ok(&["convert", source, "m.abc", "--units", "m"]);
    let summary = dir.inspect("m.abc");
    assert_eq!(
        (&summary["units"], &summary["units_source"]),
        (&json!("m"), &json!("file"))
    );
}

#[test]
fn bangs_hair_to_abc_reads_as_100_curves_1165_points() {
    let dir = TestDir::new();
    let source = test_data(BANGS_HAIR);
    // For Unreal: centimetres, its groom attributes.
    dir.run_ok(&[
        "convert",
        source.to_str().unwrap(),
        "bangs.abc",
        "--target",
        "unreal",
    ]);
    let summary = dir.inspect("bangs.abc");
    assert_eq!(summary["format"], "abc");
    assert_eq!(summary["strands"], 100, "{summary}");
    assert_eq!(summary["vertices"], 1165, "{summary}");
    assert_eq!(summary["basis"], "linear");
    let hair = importers::read(&source).unwrap();
    let abc = importers::read(&dir.path("bangs.abc")).unwrap();
    assert_eq!(abc.strand_vertex_counts, hair.strand_vertex_counts);
    assert_eq!(
        abc.points, hair.points,
        "the .hair is in cm, Y up: no change"
    );
    hand_to_validators(
        &dir.path("bangs.abc"),
        "alembic_bangs_100",
        json!({
            "kind": "abc",
            "curves": 100,
            "points": 1165,
            "samples": 1,
            "times": [0.0],
            "objects": ["/groom", "/groom/curves"],
            "basis": "linear",
            "unreal_groom": true,
        }),
    );
}

#[test]
fn the_same_conversion_gives_the_same_bytes() {
    let dir = TestDir::new();
    let source = test_data(BANGS_HAIR);
    let source_text = source.to_str().unwrap();
    for (input, output) in [
        (source_text, "a.abc"),
        (source_text, "b.abc"),
        ("a.abc", "c.abc"),
    ] {
        dir.run_ok(&["convert", input, output, "--target", "unreal"]);
    }
    let a = std::fs::read(dir.path("a.abc")).unwrap();
    assert!(
        a == std::fs::read(dir.path("b.abc")).unwrap(),
        "two runs differ"
    );
    let back = importers::read(&dir.path("c.abc")).unwrap();
    assert_eq!(back.points, importers::read(&source).unwrap().points);
}

#[test]
fn animated_export_reads_one_sample_per_frame_at_the_right_times() {
    let dir = TestDir::new();
    let mut groom = importers::read(&test_data(BANGS_HAIR)).unwrap();
    groom.set_attribute(groom::Attribute::new(
        "wetness",
        groom::AttributeValues::Float(
            (0..groom.vertex_count())
                .map(|i| (i % 10) as f32 / 10.0)
                .collect(),
        ),
    ));
    let fps = 24.0;
    let start = 2.0;
    let frames: Vec<Frame> = (0..8)
        .map(|k| Frame {
            time: start + k as f64 / fps,
            points: groom
                .points
                .iter()
                .map(|p| {
                    [
                        p[0] + 0.5 * (k as f32 * 0.7).sin(),
                        p[1] - 0.1 * k as f32,
                        p[2],
                    ]
                })
                .collect(),
            attributes: Vec::new(),
        })
        .collect();
    let options = exporters::AnimationOptions {
        fps,
        frame_count: frames.len(),
    };
    let mut writer = exporters::animated(&dir.path("sway.abc"), &groom, options).unwrap();
    for frame in &frames {
        writer.write_frame(frame).unwrap();
    }
    writer.finish().unwrap();

    let summary = dir.inspect("sway.abc");
    assert_eq!(summary["frames"], 8, "{summary}");
    let times: Vec<f64> = summary["frame_times"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_f64().unwrap())
        .collect();
    for (got, frame) in times.iter().zip(&frames) {
        assert!((got - frame.time).abs() < 1e-9, "{times:?}");
    }
    let back = importers::read(&dir.path("sway.abc")).unwrap();
    for (got, frame) in back.frames.iter().zip(&frames) {
        assert_eq!(got.points, frame.points, "frame at {}", frame.time);
    }
    assert_eq!(back.attribute("wetness"), groom.attribute("wetness"));
    // Through the CLI once more: convert writes the frames again.
    dir.run_ok(&["convert", "sway.abc", "again.abc"]);
    assert_eq!(dir.inspect("again.abc")["frames"], 8);
    hand_to_validators(
        &dir.path("sway.abc"),
        "alembic_sway_8_frames",
        json!({
            "kind": "abc",
            "curves": 100,
            "points": 1165,
            "samples": 8,
            "times": frames.iter().map(|f| f.time).collect::<Vec<_>>(),
            "basis": "linear",
            "unreal_groom": true,
        }),
    );
}

#[test]
fn hairutil_bangs_abc_matches_its_hair_file() {
    let dir = TestDir::new();
    let path = test_data(BANGS_ABC);
    let summary = dir.inspect(path.to_str().unwrap());
    assert_eq!(summary["strands"], 100);
    assert_eq!(summary["vertices"], 1165);
    let abc = importers::read(&path).unwrap();
    let hair = importers::read(&test_data(BANGS_HAIR)).unwrap();
    assert_eq!(abc.strand_vertex_counts, hair.strand_vertex_counts);
    assert_eq!(abc.points, hair.points);
}

#[test]
fn blender_static_abc_imports_with_its_counts_and_points() {
    let dir = TestDir::new();
    let path = test_data(BLENDER_ABC);
    let summary = dir.inspect(path.to_str().unwrap());
    assert_eq!(summary["strands"], 5, "{summary}");
    assert_eq!(summary["vertices"], 20, "{summary}");
    let groom = importers::read(&path).unwrap();
    assert_eq!(groom.strand_vertex_counts, vec![4, 4, 3, 4, 5]);
    // The Poly curves (x = 1 and 1.1), then the Hair curves, Y up as the
    // Alembic library reads them.
    assert_eq!(groom.points[0], [1.0, 0.0, 0.0]);
    assert_eq!(groom.points[7], [1.1, 0.3, 0.0]);
    assert_eq!(groom.points[19], [0.2, 0.4, 0.0]);
    // Converted by groombake, it reads the same in alembic3d.
    dir.run_ok(&["convert", path.to_str().unwrap(), "blender.abc"]);
    hand_to_validators(
        &dir.path("blender.abc"),
        "alembic_blender_static",
        json!({"kind": "abc", "curves": 5, "points": 20, "samples": 1, "width": "vertex"}),
    );
}

#[test]
fn truncated_abc_exits_2_naming_file_and_offset() {
    let dir = TestDir::new();
    let bytes = std::fs::read(test_data(BANGS_ABC)).unwrap();
    for cut in [0, 10, 16, 100, bytes.len() / 2, bytes.len() - 1] {
        std::fs::write(dir.path("cut.abc"), &bytes[..cut]).unwrap();
        let stderr = dir.run_fail(&["inspect", "cut.abc"], 2);
        assert!(stderr.starts_with("groombake: cut.abc:"), "{cut}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
    }
    std::fs::write(dir.path("cut.abc"), &bytes[..bytes.len() - 1]).unwrap();
    let stderr = dir.run_fail(&["convert", "cut.abc", "out.abc"], 2);
    assert!(stderr.contains("offset"), "{stderr}");
    assert!(!dir.path("out.abc").exists());
}

#[test]
fn corrupted_abc_exits_2_with_a_clear_error() {
    let dir = TestDir::new();
    let bytes = std::fs::read(test_data(BANGS_ABC)).unwrap();
    // An unfinished file: the frozen flag still 0.
    let mut unfrozen = bytes.clone();
    unfrozen[5] = 0;
    std::fs::write(dir.path("unfrozen.abc"), &unfrozen).unwrap();
    let stderr = dir.run_fail(&["inspect", "unfrozen.abc"], 2);
    assert!(
        stderr.contains("unfrozen.abc:offset 5: the file is not frozen"),
        "{stderr}"
    );
    // The root group's child count made huge.
    let root = u64::from_le_bytes(bytes[8..16].try_into().unwrap()) as usize;
    let mut huge = bytes.clone();
    huge[root + 7] = 0x7f;
    std::fs::write(dir.path("huge.abc"), &huge).unwrap();
    let stderr = dir.run_fail(&["inspect", "huge.abc"], 2);
    assert!(
        stderr.contains(&format!("huge.abc:offset {root}: group claims")),
        "{stderr}"
    );
    // The P samples cut short: the block is smaller than nVertices says.
    let mut short = bytes.clone();
    short[0x28] -= 12;
    std::fs::write(dir.path("short.abc"), &short).unwrap();
    let stderr = dir.run_fail(&["inspect", "short.abc"], 2);
    assert!(stderr.contains("short.abc:/curves/.geom/P"), "{stderr}");
}
