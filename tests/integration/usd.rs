//! USD export and import through the real binary, and hand-off of every
//! exported USD file to usd-core (`.ci/check_usd.py`).
//!
//! Expectation keys for the validator: `curves`, `points`, `first_point`,
//! `meters_per_unit`, `up_axis`, `basis`, `time_samples`, and for animated
//! files `start_time_code`, `end_time_code`, `time_codes_per_second`,
//! `sample_points` (`[time code, point index, point]` items), plus
//! `primvars` (name -> interpolation) and `widths` (interpolation).

use crate::util::{hand_to_validators, test_data, TestDir};
use groom::{Attribute, AttributeValues, Frame, Groom, Units};
use serde_json::json;

/// Bangs_100 read straight from the `.hair` bytes (Cem Yuksel's layout),
/// independently of the importers, as the reference the USD files must match.
fn bangs() -> Groom {
    let bytes = std::fs::read(test_data("hairutil_Bangs_100.hair")).unwrap();
    let u32_at = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
    let (strands, points, flags) = (u32_at(4) as usize, u32_at(8) as usize, u32_at(12));
    let default_segments = u32_at(16);
    assert_eq!(&bytes[..4], b"HAIR");
    let mut at = 128;
    let counts: Vec<u32> = if flags & 1 != 0 {
        let counts = (0..strands)
            .map(|i| u16::from_le_bytes([bytes[at + 2 * i], bytes[at + 2 * i + 1]]) as u32 + 1)
            .collect();
        at += 2 * strands;
        counts
    } else {
        vec![default_segments + 1; strands]
    };
    assert!(flags & 2 != 0, "Bangs_100 has points");
    let f32_at = |at: usize| f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
    let coordinates: Vec<[f32; 3]> = (0..points)
        .map(|i| {
            [
                f32_at(at + 12 * i),
                f32_at(at + 12 * i + 4),
                f32_at(at + 12 * i + 8),
            ]
        })
        .collect();
    let groom = Groom {
        strand_vertex_counts: counts,
        points: coordinates,
        units: Units::CENTIMETERS,
        ..Groom::default()
    };
    assert!(groom.validate().is_empty());
    groom
}

fn first_point(groom: &Groom) -> serde_json::Value {
    json!(groom.points[0])
}

#[test]
fn bangs_to_usda_and_usdc_keeps_every_point() {
    let dir = TestDir::new();
    let reference = bangs();
    assert_eq!(reference.strand_count(), 100);
    assert_eq!(reference.vertex_count(), 1165);
    let source = test_data("hairutil_Bangs_100.hair");
    let source = source.to_str().unwrap();
    dir.run_ok(&["convert", source, "bangs.usda"]);
    dir.run_ok(&["convert", source, "bangs.usdc"]);
    // Crate back to text gives the same bytes as the direct conversion.
    dir.run_ok(&["convert", "bangs.usdc", "bangs_again.usda"]);
    assert_eq!(
        std::fs::read(dir.path("bangs.usda")).unwrap(),
        std::fs::read(dir.path("bangs_again.usda")).unwrap(),
        "usda -> usdc -> usda is byte-identical"
    );
    for name in ["bangs.usda", "bangs.usdc"] {
        let summary = dir.inspect(name);
        assert_eq!(summary["strands"], 100, "{name}");
        assert_eq!(summary["vertices"], 1165, "{name}");
        assert_eq!(summary["units"], "cm", "{name}");
        assert_eq!(summary["first_point"], first_point(&reference), "{name}");
        let back = importers::read(&dir.path(name)).unwrap();
        assert_eq!(back.points, reference.points, "{name}: same coordinates");
        assert_eq!(back.strand_vertex_counts, reference.strand_vertex_counts);
        hand_to_validators(
            &dir.path(name),
            &format!("usd_bangs_{}", name.replace('.', "_")),
            json!({
                "curves": 100,
                "points": 1165,
                "first_point": first_point(&reference),
                "meters_per_unit": 0.01,
                "up_axis": "Y",
                "basis": "linear",
                "time_samples": 0,
            }),
        );
    }
}

fn animated_groom(frames: usize) -> Groom {
    let mut groom = Groom::from_strands([
        vec![[0.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, -2.0, 0.0]],
        vec![
            [1.0, 0.0, 0.0],
            [1.0, -1.0, 0.0],
            [1.0, -2.0, 0.0],
            [1.0, -3.0, 0.0],
        ],
    ]);
    groom.units = Units::METERS;
    groom.set_attribute(Attribute::new(
        "width",
        AttributeValues::Float(vec![0.01; 7]),
    ));
    groom.set_attribute(Attribute::new(
        "wetness",
        AttributeValues::Float((0..7).map(|i| i as f32 / 7.0).collect()),
    ));
    groom.set_attribute(Attribute::per_strand(
        "root_uv",
        AttributeValues::Vec2(vec![[0.25, 0.5], [0.75, 0.5]]),
    ));
    groom.set_attribute(Attribute::per_strand(
        "hydrogen_bonds",
        AttributeValues::Float(vec![0.35, 0.3]),
    ));
    for i in 0..frames {
        let sway = i as f32 * 0.05;
        groom.frames.push(Frame {
            time: i as f64 / 24.0,
            points: groom
                .points
                .iter()
                .map(|p| [p[0] + sway * -p[1], p[1], p[2]])
                .collect(),
            attributes: Vec::new(),
        });
    }
    groom
}

/// A bake streamed frame by frame to `.usdc` has one time sample per frame.
#[test]
fn animated_usdc_has_one_time_sample_per_frame() {
    let dir = TestDir::new();
    let frames = 12;
    let groom = animated_groom(frames);
    let mut rest = groom.clone();
    rest.frames.clear();
    let options = exporters::AnimationOptions {
        fps: 24.0,
        frame_count: frames,
    };
    let mut writer = exporters::animated(&dir.path("bake.usdc"), &rest, options).unwrap();
    for frame in &groom.frames {
        writer.write_frame(frame).unwrap();
    }
    writer.finish().unwrap();

    let summary = dir.inspect("bake.usdc");
    assert_eq!(summary["frames"], frames);
    let back = importers::read(&dir.path("bake.usdc")).unwrap();
    // Exact times from the library (serde_json's float parsing may be off
    // by an ulp, so the CLI's JSON is not compared bit for bit).
    let times: Vec<f64> = back.frames.iter().map(|f| f.time).collect();
    let expected: Vec<f64> = (0..frames).map(|i| i as f64 / 24.0).collect();
    assert_eq!(times, expected);
    assert_eq!(summary["frame_times"].as_array().unwrap().len(), frames);
    for (read, written) in back.frames.iter().zip(&groom.frames) {
        assert_eq!(read.points, written.points);
    }
    // The text form carries the same samples.
    dir.run_ok(&["convert", "bake.usdc", "bake.usda"]);
    assert_eq!(dir.inspect("bake.usda")["frames"], frames);

    let samples: Vec<_> = groom
        .frames
        .iter()
        .enumerate()
        .map(|(i, f)| json!([i as f64, 6, f.points[6]]))
        .collect();
    for name in ["bake.usdc", "bake.usda"] {
        hand_to_validators(
            &dir.path(name),
            &format!("usd_animated_{}", name.replace('.', "_")),
            json!({
                "curves": 2,
                "points": 7,
                "first_point": groom.points[0],
                "meters_per_unit": 1.0,
                "up_axis": "Y",
                "basis": "linear",
                "time_samples": frames,
                "start_time_code": 0.0,
                "end_time_code": (frames - 1) as f64,
                "time_codes_per_second": 24.0,
                "sample_points": samples,
                "widths": "vertex",
                "primvars": {
                    "st": "uniform",
                    "wetness": "vertex",
                    "hydrogen_bonds": "uniform",
                },
            }),
        );
    }
}

#[test]
fn blender_usda_imports_every_curve_with_its_transform() {
    let dir = TestDir::new();
    let source = test_data("blender501_hair.usda");
    let source = source.to_str().unwrap();
    let summary = dir.inspect(source);
    assert_eq!(summary["format"], "usd");
    assert_eq!(summary["strands"], 5, "3 HairData + 2 PolyData curves");
    assert_eq!(summary["vertices"], 20, "12 + 8 points");
    assert_eq!(
        summary["first_point"],
        json!([0.0, 0.0, 1.0]),
        "Hair's translate (0, 0, 1)"
    );
    assert_eq!(summary["basis"], "catmull_rom");
    assert_eq!(summary["units"], "m");
    assert_eq!(summary["up_axis"], "Z");
    let names: Vec<&str> = summary["attributes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a["name"].as_str().unwrap())
        .collect();
    for name in ["width", "tilt", "group_id", "curve_basis"] {
        assert!(names.contains(&name), "{name} in {names:?}");
    }
    dir.run_ok(&["convert", source, "blender.usdc"]);
    // Blender's pinned catmullRom hair and linear poly curve stay apart.
    let back = importers::read(&dir.path("blender.usdc")).unwrap();
    let codes = |name: &str| back.attribute(name).map(|a| a.values.clone());
    assert_eq!(
        codes("curve_basis"),
        Some(AttributeValues::Int(vec![3, 3, 3, 0, 0]))
    );
    assert_eq!(
        codes("curve_wrap"),
        Some(AttributeValues::Int(vec![2, 2, 2, 0, 0]))
    );
    hand_to_validators(
        &dir.path("blender.usdc"),
        "usd_blender_converted_usdc",
        json!({
            "curves": 5,
            "points": 20,
            "first_point": [0.0, 0.0, 1.0],
            "meters_per_unit": 1.0,
            "up_axis": "Z",
            "time_samples": 0,
            "widths": "vertex",
            // group_id is the reader's, made up from the prims: not written.
            "primvars": {"tilt": "vertex"},
        }),
    );
}

#[test]
fn malformed_usd_exits_2_with_the_place() {
    let dir = TestDir::new();
    std::fs::write(
        dir.path("bad.usda"),
        "#usda 1.0\ndef BasisCurves \"C\"\n{\n    int[] curveVertexCounts = [2, oops]\n}\n",
    )
    .unwrap();
    let stderr = dir.run_fail(&["inspect", "bad.usda"], 2);
    assert_eq!(
        stderr.trim_end(),
        "groombake: bad.usda:4:35: expected a number, found 'oops'"
    );

    exporters::write(&dir.path("good.usdc"), &bangs()).unwrap();
    let bytes = std::fs::read(dir.path("good.usdc")).unwrap();
    std::fs::write(dir.path("cut.usdc"), &bytes[..bytes.len() / 2]).unwrap();
    let stderr = dir.run_fail(&["inspect", "cut.usdc"], 2);
    assert!(
        stderr.starts_with("groombake: cut.usdc:offset "),
        "{stderr}"
    );

    let mut wrong = bytes.clone();
    wrong[..8].copy_from_slice(b"PXR-USDX");
    std::fs::write(dir.path("wrong.usd"), &wrong).unwrap();
    let stderr = dir.run_fail(&["convert", "wrong.usd", "out.usda"], 2);
    assert!(
        stderr.contains("wrong.usd:offset 0: not a USD file"),
        "{stderr}"
    );
    assert!(!dir.path("out.usda").exists());
}

/// A file written by usd-core (compressed arrays, nested transforms, two
/// curves prims of different bases, time samples at 30 codes per second)
/// goes through import and export and comes out valid.
#[test]
fn usd_core_file_converts_to_valid_usd() {
    let dir = TestDir::new();
    let source = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("importers/tests/data/reference.usdc");
    let source = source.to_str().unwrap();
    let summary = dir.inspect(source);
    assert_eq!(summary["strands"], 21);
    assert_eq!(summary["vertices"], 204);
    assert_eq!(summary["frames"], 3);
    for name in ["reference.usda", "reference.usdc"] {
        dir.run_ok(&["convert", source, name]);
        let back = dir.inspect(name);
        assert_eq!(back["vertices"], 204, "{name}");
        assert_eq!(back["frames"], 3, "{name}");
        if name.ends_with(".usda") {
            // The two bases stay two prims, animated too, at the source's
            // paths (/Root/Child/Curves, /Root/Other): nothing converted.
            let text = std::fs::read_to_string(dir.path(name)).unwrap();
            for prim in [
                "Xform \"Root\"",
                "Xform \"Child\"",
                "BasisCurves \"Curves\"",
                "BasisCurves \"Other\"",
            ] {
                assert!(text.contains(&format!("def {prim}")), "{prim}");
            }
        }
        hand_to_validators(
            &dir.path(name),
            &format!("usd_from_usd_core_{}", name.replace('.', "_")),
            json!({
                "curves": 21,
                "points": 204,
                "first_point": summary["first_point"],
                "meters_per_unit": 0.01,
                "up_axis": "Z",
                "time_samples": 3,
                "widths": "vertex",
                "primvars": {
                    "wetness": "vertex",
                    "clump": "uniform",
                    "st": "uniform",
                    "level": "uniform",
                    "tint": "uniform",
                },
            }),
        );
    }
}

/// The hand-written composition fixtures of `tests/data/usd/`, with the
/// strand and vertex counts usd-core composes for them (instance proxies
/// included). What groombake reads of each (counts and world points) goes to
/// `.ci/check_usd_fixtures.py`, which compares it with usd-core's reading.
///
/// The `.usdc` ones are crate layers usd-core wrote
/// (`tests/data/usd/make_crate_fixtures.py`): the same arcs in the crate's
/// encodings, and a crate layer whose payload is a text layer.
const COMPOSED_FIXTURES: [(&str, &[u32]); 16] = [
    ("reference_internal.usda", &[3, 2, 3, 2]),
    ("payload_main.usda", &[4, 3, 4, 3]),
    ("sublayer_main.usda", &[2, 2]),
    ("instancing.usda", &[3, 3, 3]),
    ("inherits.usda", &[2, 3, 2]),
    ("mixed_types.usda", &[3, 4, 4]),
    ("pinned_wrap.usda", &[4, 5]),
    ("constant_widths.usda", &[3, 2]),
    ("color3f.usda", &[2, 3]),
    ("legacy_pointfloat.usda", &[2, 3]),
    ("reference_internal.usdc", &[3, 2, 3, 2]),
    ("payload_main.usdc", &[4, 3, 4, 3]),
    ("crate_payload_text.usdc", &[4, 3, 4, 3]),
    ("sublayer_main.usdc", &[2, 2]),
    ("instancing.usdc", &[3, 3, 3]),
    ("inherits.usdc", &[2, 3, 2]),
];

fn usd_fixture(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/usd")
        .join(name)
}

/// `inspect` names each composed curves prim: instances by the path of the
/// instance, references by the prim they land on.
#[test]
fn inspect_lists_composed_prim_paths() {
    let dir = TestDir::new();
    for (name, expected) in [
        (
            "instancing.usda",
            json!([
                {"path": "/Prototypes/Tuft/Curves", "strands": 1},
                {"path": "/Tufts/A/Curves", "strands": 1},
                {"path": "/Tufts/B/Curves", "strands": 1},
            ]),
        ),
        (
            "payload_main.usda",
            json!([
                {"path": "/Character/Head/Strands", "strands": 2},
                {"path": "/Character/Beard", "strands": 2},
            ]),
        ),
    ] {
        let summary = dir.inspect(usd_fixture(name).to_str().unwrap());
        assert_eq!(summary["prims"], expected, "{name}");
    }
}

#[test]
fn composed_fixtures_read_as_usd_core_composes_them() {
    for (name, counts) in COMPOSED_FIXTURES {
        let path = usd_fixture(name);
        let groom = importers::read(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(groom.strand_vertex_counts, counts, "{name}");
        let Some(dir) = std::env::var_os("GROOMBAKE_ARTIFACTS") else {
            continue;
        };
        let dir = std::path::PathBuf::from(dir).join("usd_fixtures");
        std::fs::create_dir_all(&dir).unwrap();
        let reading = json!({
            "source": path.canonicalize().unwrap(),
            "counts": groom.strand_vertex_counts,
            "points": groom.points,
        });
        std::fs::write(
            dir.join(format!("{name}.groombake.json")),
            serde_json::to_vec(&reading).unwrap(),
        )
        .unwrap();
    }
}

/// Where a reference's layer cannot be opened, the error names the arc and
/// the missing file, exit 2.
#[test]
fn unresolvable_payload_names_the_arc_and_the_file() {
    let dir = TestDir::new();
    let source = usd_fixture("missing_payload.usda");
    let message = dir.run_fail(&["inspect", source.to_str().unwrap()], 2);
    assert!(
        message.contains("missing_payload.usda:7:")
            && message.contains("payload @./not_here.usda@</Hair>")
            && message.contains("not_here.usda: No such file"),
        "{message}"
    );
    // The same from a crate layer (the arc's place is its prim path).
    let source = usd_fixture("crate_missing_reference.usdc");
    let message = dir.run_fail(&["convert", source.to_str().unwrap(), "out.usda"], 2);
    assert!(
        message.contains("crate_missing_reference.usdc:/Head: references @./not_here.usdc@</Hair>")
            && message.contains("not_here.usdc: No such file"),
        "{message}"
    );
    assert!(!dir.path("out.usda").exists());
    let source = usd_fixture("crate_cycle_a.usdc");
    let message = dir.run_fail(&["inspect", source.to_str().unwrap()], 2);
    assert!(message.contains("a cycle?"), "{message}");
}

/// A reference cycle ends with an error, not a hang or a stack overflow.
#[test]
fn reference_cycle_is_an_error() {
    let dir = TestDir::new();
    std::fs::write(
        dir.path("a.usda"),
        "#usda 1.0\n(\n    defaultPrim = \"A\"\n)\ndef \"A\" (\n    references = @./b.usda@\n)\n{\n}\n",
    )
    .unwrap();
    std::fs::write(
        dir.path("b.usda"),
        "#usda 1.0\n(\n    defaultPrim = \"B\"\n)\ndef \"B\" (\n    references = @./a.usda@\n)\n{\n}\n",
    )
    .unwrap();
    let message = dir.run_fail(&["inspect", "a.usda"], 2);
    assert!(message.contains("a cycle?"), "{message}");
}

/// Every fixture converts to `.usda` and `.usdc` that usd-core's validators
/// pass, keeping the counts, the wrap (pinned stays pinned) and each
/// primvar's declared type (`color3f[]`, `texCoord2f[]`).
#[test]
fn fixtures_convert_keeping_wrap_and_declared_types() {
    let dir = TestDir::new();
    for (name, counts) in COMPOSED_FIXTURES {
        let source = usd_fixture(name);
        let stem = name.trim_end_matches(".usda").replace('.', "_");
        for ext in ["usda", "usdc"] {
            let out = format!("{stem}.{ext}");
            dir.run_ok(&["convert", source.to_str().unwrap(), &out]);
            let back = importers::read(&dir.path(&out)).unwrap();
            assert_eq!(back.strand_vertex_counts, counts, "{out}");
            let points: u32 = counts.iter().sum();
            hand_to_validators(
                &dir.path(&out),
                &format!("usd_fixture_{stem}_{ext}"),
                json!({"curves": counts.len(), "points": points}),
            );
        }
    }
    let text = std::fs::read_to_string(dir.path("pinned_wrap.usda")).unwrap();
    assert!(text.contains("uniform token wrap = \"pinned\""), "{text}");
    let text = std::fs::read_to_string(dir.path("color3f.usda")).unwrap();
    assert!(
        text.contains("color3f[] primvars:displayColor")
            && text.contains("texCoord2f[] primvars:st"),
        "{text}"
    );
    // Mixed curve types: the source's prims, each keeping its own type.
    let text = std::fs::read_to_string(dir.path("mixed_types.usda")).unwrap();
    assert!(
        text.contains("def BasisCurves \"Guides\"")
            && text.contains("def BasisCurves \"Render\"")
            && text.contains("uniform token type = \"linear\"")
            && text.contains("uniform token basis = \"catmullRom\""),
        "{text}"
    );
    for ext in ["usda", "usdc"] {
        let back = importers::read(&dir.path(&format!("mixed_types.{ext}"))).unwrap();
        let bases = back.attribute("curve_basis").map(|a| a.values.clone());
        assert_eq!(bases, Some(AttributeValues::Int(vec![0, 3, 3])), "{ext}");
    }
    let back = importers::read(&dir.path("color3f.usdc")).unwrap();
    assert_eq!(
        back.provenance
            .metadata
            .get("usd.type.displayColor")
            .map(String::as_str),
        Some("color3f[]")
    );
}

/// The sequence groombake reads from a fixture with time-sampled counts,
/// whose time codes (24 per second) must be `codes`; handed to
/// `.ci/check_usd_fixtures.py`, which compares counts and points at each
/// time code with usd-core's.
fn sequence_reading(name: &str, codes: &[f64]) -> Vec<Groom> {
    let source = usd_fixture(name);
    let sequence = importers::read_sequence(&source).unwrap();
    let samples: Vec<_> = sequence
        .iter()
        .flat_map(|groom| {
            groom.frames.iter().map(|frame| {
                json!({
                    "time_code": frame.time * 24.0,
                    "counts": groom.strand_vertex_counts,
                    "points": frame.points,
                })
            })
        })
        .collect();
    let read_codes: Vec<f64> = samples
        .iter()
        .map(|s| s["time_code"].as_f64().unwrap())
        .collect();
    assert_eq!(read_codes, codes, "{name}");
    if let Some(artifacts) = std::env::var_os("GROOMBAKE_ARTIFACTS") {
        let fixtures = std::path::PathBuf::from(artifacts).join("usd_fixtures");
        std::fs::create_dir_all(&fixtures).unwrap();
        let reading = json!({"source": source.canonicalize().unwrap(), "samples": samples});
        std::fs::write(
            fixtures.join(format!("{name}.groombake.json")),
            serde_json::to_vec(&reading).unwrap(),
        )
        .unwrap();
    }
    sequence
}

/// Time-sampled curve counts that change: `inspect` and `convert` carry
/// the sequence (one groom per topology), USD keeps it as time-sampled
/// `curveVertexCounts` and `points` that usd-core reads back, a format that
/// holds one topology warns (or, with --strict, refuses), and the bake
/// refuses it before simulating.
#[test]
fn time_varying_topology_is_carried_by_inspect_and_convert() {
    let dir = TestDir::new();
    let source = usd_fixture("time_sampled_counts.usda");
    let source = source.to_str().unwrap();
    let summary = dir.inspect(source);
    assert_eq!(
        summary["topology"],
        json!([
            {"from_time": 1.0 / 24.0, "strands": 2, "vertices": 4, "frames": 1},
            {"from_time": 2.0 / 24.0, "strands": 2, "vertices": 6, "frames": 1},
        ])
    );
    assert_eq!(summary["frames"], 2);
    let text = String::from_utf8(dir.run_ok(&["inspect", source]).stdout).unwrap();
    assert!(
        text.contains("topology    from 0.08333333333333333 s: 2 strands, 6 vertices"),
        "{text}"
    );

    let sequence = sequence_reading("time_sampled_counts.usda", &[1.0, 2.0]);
    // Counts held between their samples, points interpolated where their
    // lengths agree (as usd-core evaluates them), under a parent transform.
    let held = sequence_reading("time_sampled_counts_held.usda", &[0.0, 1.0, 2.0, 3.0]);
    assert_eq!(held.len(), 2);
    assert_eq!(held[0].frames[1].points, [[0.0, 5.0, 0.0], [0.0, 7.0, 0.0]]);

    for ext in ["usda", "usdc"] {
        let out = format!("growing.{ext}");
        let output = dir.run_ok(&["convert", source, &out]);
        assert!(output.stderr.is_empty(), "{out}: no warning");
        let back = importers::read_sequence(&dir.path(&out)).unwrap();
        assert_eq!(back.len(), 2, "{out}: two topologies");
        for (read, written) in back.iter().zip(&sequence) {
            assert_eq!(read.strand_vertex_counts, written.strand_vertex_counts);
            assert_eq!(read.frames, written.frames, "{out}");
        }
        hand_to_validators(
            &dir.path(&out),
            &format!("usd_time_varying_topology_{ext}"),
            json!({
                "curves": 2,
                "points": 4,
                "meters_per_unit": 0.01,
                "time_samples": 2,
                "start_time_code": 1.0,
                "end_time_code": 2.0,
                "topology": [[1.0, 2, 4], [2.0, 2, 6]],
                "sample_points": [[2.0, 5, [1.0, 2.0, 0.0]]],
            }),
        );
    }

    // A format of one topology: the first is written, with a warning.
    let output = dir.run_ok(&["convert", source, "growing.glb"]);
    let stderr = String::from_utf8(output.stderr).unwrap();
    assert!(
        stderr.contains("growing.glb: .glb cannot hold curve counts that change over time")
            && stderr.contains("up to the change at 0.08333333333333333 s"),
        "{stderr}"
    );
    let first = importers::read(&dir.path("growing.glb")).unwrap();
    assert_eq!(first.vertex_count(), 4);
    let message = dir.run_fail(&["convert", "--strict", source, "strict.glb"], 2);
    assert!(
        message.contains("--strict: strict.glb: .glb cannot hold"),
        "{message}"
    );
    assert!(!dir.path("strict.glb").exists());
    // --frame picks a frame across the sequence.
    dir.run_ok(&["convert", source, "second.obj", "--frame", "1"]);
    assert_eq!(
        importers::read(&dir.path("second.obj"))
            .unwrap()
            .vertex_count(),
        6
    );

    // The bake needs one topology: exit 2 naming the time, nothing written.
    let timeline = format!(
        "[groom]\nsource = {source:?}\n[[stage]]\nkind = \"settle\"\nduration = 0.1\n[[export]]\npath = \"baked.glb\"\nwhat = \"final\"\n"
    );
    std::fs::write(dir.path("bake.toml"), timeline).unwrap();
    let message = dir.run_fail(&["bake", "bake.toml", "-q"], 2);
    assert!(
        message.contains("time_sampled_counts.usda:13:")
            && message.contains("topology changes at time 2"),
        "{message}"
    );
    assert!(!dir.path("baked.glb").exists());
}
