//! Studio files: units by destination (`target`), what a file written for a
//! program holds, and what the readers say when they cannot keep something.

use crate::util::{test_data, TestDir};
use groom::{AttributeValues, Groom, Units, UpAxis};
use std::path::Path;

fn read(path: &Path) -> Groom {
    importers::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn stderr(output: &std::process::Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// A 6-strand swatch of 24 cm strands (metres, Y up).
fn swatch(dir: &TestDir) -> Groom {
    dir.run_ok(&[
        "generate",
        "swatch",
        "-o",
        "swatch.usda",
        "--strands",
        "6",
        "--length",
        "0.24",
    ]);
    read(&dir.path("swatch.usda"))
}

fn largest_gap(a: &[[f32; 3]], b: &[[f32; 3]], scale: f32) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |i| (p[i] * scale - q[i]).abs()))
        .fold(0.0, f32::max)
}

#[test]
fn alembic_and_obj_are_written_in_metres_by_default_and_say_so() {
    let dir = TestDir::new();
    let source = swatch(&dir);
    for name in ["plain.abc", "plain.obj"] {
        let output = dir.run_ok(&["convert", "swatch.usda", name]);
        let said = stderr(&output);
        assert!(said.contains(&format!("wrote {name}: m, Y up")), "{said}");
        let back = read(&dir.path(name));
        // The numbers in the file are the metres of the source.
        assert_eq!(back.units, Units::METERS, "{name}");
        assert!(
            largest_gap(&source.points, &back.points, 1.0) < 1e-7,
            "{name}"
        );
    }
    // USD and glTF record their units: nothing to say.
    let said = stderr(&dir.run_ok(&["convert", "swatch.usda", "copy.usda"]));
    assert!(!said.contains("wrote"), "{said}");
}

#[test]
fn targets_choose_units_axis_and_attribute_names() {
    let dir = TestDir::new();
    let source = swatch(&dir);
    let said = stderr(&dir.run_ok(&["convert", "swatch.usda", "unreal.abc", "--target", "unreal"]));
    assert!(said.contains("wrote unreal.abc: cm, Y up"), "{said}");
    let unreal = read(&dir.path("unreal.abc"));
    assert_eq!(unreal.units, Units::CENTIMETERS);
    assert!(largest_gap(&source.points, &unreal.points, 100.0) < 1e-4);
    let bytes = std::fs::read(dir.path("unreal.abc")).unwrap();
    let has = |text: &str| bytes.windows(text.len()).any(|w| w == text.as_bytes());
    // Unreal's schema: the version as int16 scalars.
    assert!(has("groom_version_major") && has("int16_t"));
    // One attribute per meaning on re-reading Unreal's names.
    assert!(unreal.attribute("groom_width").is_none());
    assert!(unreal.attribute("width").is_some());
    assert!(unreal.attribute("groom_version_major").is_none());

    dir.run_ok(&["convert", "swatch.usda", "maya.abc", "--target", "maya"]);
    let bytes = std::fs::read(dir.path("maya.abc")).unwrap();
    assert!(
        !bytes.windows(6).any(|w| w == b"groom_"),
        "maya.abc has groom_*"
    );
    assert_eq!(read(&dir.path("maya.abc")).units, Units::CENTIMETERS);

    dir.run_ok(&[
        "convert",
        "swatch.usda",
        "blender.usda",
        "--target",
        "blender",
    ]);
    let blender = read(&dir.path("blender.usda"));
    assert_eq!((blender.units, blender.up_axis), (Units::METERS, UpAxis::Z));
    // Explicit units win over the preset.
    let said = stderr(&dir.run_ok(&[
        "convert",
        "swatch.usda",
        "mm.obj",
        "--target",
        "houdini",
        "--units",
        "mm",
    ]));
    assert!(said.contains("wrote mm.obj: mm, Y up"), "{said}");

    let e = dir.run_fail(&["convert", "swatch.usda", "x.abc", "--target", "nuke"], 2);
    assert!(e.contains("unknown target") && e.contains("blender"), "{e}");
}

#[test]
fn a_bake_export_takes_a_target_and_reports_its_units() {
    let dir = TestDir::new();
    let timeline = "[groom]\ngenerate = { strands = 2 }\n\n[[stage]]\nkind = \"settle\"\nduration = 0.02\n\n[[export]]\npath = \"unreal.abc\"\nwhat = \"final\"\ntarget = \"unreal\"\n\n[[export]]\npath = \"plain.abc\"\nwhat = \"final\"\n";
    std::fs::write(dir.path("t.toml"), timeline).unwrap();
    let output = dir.run_ok(&["bake", "t.toml", "--report", "report.json"]);
    let said = stderr(&output);
    assert!(
        said.contains("unreal.abc") && said.contains("cm, Y up)"),
        "{said}"
    );
    assert!(
        said.contains("plain.abc") && said.contains("m, Y up)"),
        "{said}"
    );
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path("report.json")).unwrap()).unwrap();
    let written: Vec<&str> = report["outputs"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|o| o["written_in"].as_str())
        .collect();
    assert_eq!(written, ["cm, Y up", "m, Y up"]);
    let unreal = read(&dir.path("unreal.abc"));
    let plain = read(&dir.path("plain.abc"));
    assert_eq!(unreal.units, Units::CENTIMETERS);
    assert!(largest_gap(&plain.points, &unreal.points, 100.0) < 1e-4);

    std::fs::write(
        dir.path("bad.toml"),
        timeline.replace("\"unreal\"", "\"nuke\""),
    )
    .unwrap();
    let e = dir.run_fail(&["validate", "bad.toml"], 2);
    assert!(
        e.contains("bad.toml:11:10") && e.contains("unknown target"),
        "{e}"
    );
}

#[test]
fn a_one_strand_groom_keeps_constant_values_constant() {
    let dir = TestDir::new();
    dir.run_ok(&[
        "generate",
        "swatch",
        "-o",
        "one.usda",
        "--strands",
        "1",
        "--length",
        "0.1",
    ]);
    dir.run_ok(&["convert", "one.usda", "one.abc", "--target", "unreal"]);
    let back = read(&dir.path("one.abc"));
    for name in ["groom_version_major", "groom_version_minor"] {
        assert!(back.attribute(name).is_none(), "{name} became per-strand");
    }
    // And a second trip writes no copies.
    dir.run_ok(&["convert", "one.abc", "two.abc", "--target", "unreal"]);
    let again = read(&dir.path("two.abc"));
    let names =
        |g: &Groom| -> Vec<String> { g.attributes.iter().map(|a| a.name.clone()).collect() };
    assert_eq!(names(&back), names(&again));
    assert!(matches!(
        again.attribute("width").map(|a| &a.values),
        Some(AttributeValues::Float(_))
    ));
}

#[test]
fn a_z_up_source_goes_to_hair_and_data_y_up_and_back_unchanged() {
    let dir = TestDir::new();
    swatch(&dir);
    dir.run_ok(&["convert", "swatch.usda", "z.usda", "--up", "z"]);
    assert_eq!(read(&dir.path("z.usda")).up_axis, UpAxis::Z);
    // And Blender's own Z-up file (its tilt is missing on one object: a warning).
    let blender = test_data("blender501_hair.usda");
    for source in ["z.usda", blender.to_str().unwrap()] {
        for name in ["back.hair", "back.data"] {
            dir.run_ok(&["convert", source, name]);
            let written = read(&dir.path(name));
            // Read as the format's readers take it: centimetres, Y up.
            assert_eq!(written.up_axis, UpAxis::Y);
            // The points: the attributes stay behind (warned about).
            let mut args = vec!["diff", source, name, "--tolerance", "1e-6"];
            for attribute in [
                "width",
                "root_uv",
                "tilt",
                "group_id",
                "curve_basis",
                "curve_wrap",
            ] {
                args.extend(["--ignore", attribute]);
            }
            let output = dir.run_ok(&args);
            assert!(String::from_utf8_lossy(&output.stdout).contains("equal within"));
        }
    }
    for name in ["z.hair", "z.data"] {
        // Asking to keep Z up cannot be kept by the format.
        let e = dir.run_fail(&["convert", "z.usda", name, "--up", "z", "--strict"], 2);
        assert!(e.contains("written Y up"), "{e}");
        assert!(!dir.path(name).exists());
    }
}

fn openusd(name: &str) -> String {
    test_data(&format!("usd/openusd/{name}"))
        .to_str()
        .unwrap()
        .to_string()
}

#[test]
fn a_prim_that_cannot_be_read_is_skipped_with_a_warning_naming_it() {
    let dir = TestDir::new();
    let file = openusd("testUsdGeomBasisCurves_basisCurves.usda");
    let output = dir.run_ok(&["convert", &file, "out.usda"]);
    let said = stderr(&output);
    for prim in [
        "/UnsetVertexCounts",
        "/BlockedVertexCounts",
        "/LinearNonperiodic",
    ] {
        assert!(
            said.contains(&format!(": skipped curves prim {prim}:")),
            "{prim}: {said}"
        );
    }
    // The readable prim is all there is: /BezierCubic, 2 strands of 5.
    let out = read(&dir.path("out.usda"));
    assert_eq!(out.strand_vertex_counts, [5, 5]);
    // --strict refuses, naming the first prim left out.
    let e = dir.run_fail(&["convert", &file, "strict.usda", "--strict"], 2);
    assert!(
        e.contains("--strict") && e.contains("/UnsetVertexCounts"),
        "{e}"
    );
    assert!(!dir.path("strict.usda").exists());

    // Nothing readable left: refused, with the first prim's problem.
    std::fs::write(
        dir.path("none.usda"),
        "#usda 1.0\ndef BasisCurves \"Empty\"\n{\n}\n",
    )
    .unwrap();
    let e = dir.run_fail(&["convert", "none.usda", "o.usda"], 2);
    assert!(e.contains("/Empty has no curveVertexCounts"), "{e}");
}

#[test]
fn varying_widths_of_cubic_curves_are_read_per_segment_end() {
    let dir = TestDir::new();
    let file = openusd("usdGeomExamples_basisCurves.usda");
    let groom = read(Path::new(&file));
    let prims = groom.provenance.metadata[groom::PRIMS_KEY].clone();
    let index = prims
        .lines()
        .position(|l| l.starts_with("/Cubic/Tubes/VaryingWidth "))
        .expect("the prim is read");
    // Every prim before it is one strand of 7 points.
    let start = index * 7;
    let Some(AttributeValues::Float(widths)) = groom.attribute("width").map(|a| &a.values) else {
        panic!("no widths");
    };
    let got = &widths[start..start + 7];
    // [0, .8, 0] at the segment ends (vertices 0, 3, 6); blended between.
    let want = [0.0, 0.8 / 3.0, 1.6 / 3.0, 0.8, 1.6 / 3.0, 0.8 / 3.0, 0.0];
    for (g, w) in got.iter().zip(want) {
        assert!((g - w).abs() < 1e-6, "{got:?}");
    }
    // Convert keeps them, and says what it cannot keep (the ribbons' normals).
    let said = stderr(&dir.run_ok(&["convert", &file, "o.usda"]));
    assert!(said.contains("normals"), "{said}");
    let back = read(&dir.path("o.usda"));
    let Some(AttributeValues::Float(back_widths)) = back.attribute("width").map(|a| &a.values)
    else {
        panic!("no widths written");
    };
    assert_eq!(&back_widths[start..start + 7], got);
}

/// OpenUSD's own BasisCurves files (`tests/data/usd/openusd/`): what
/// groombake reads of each (its curves prims with their strand counts, the
/// counts, world points and per-point widths) goes to
/// `.ci/check_usd_fixtures.py`, which compares it prim by prim and value by
/// value with usd-core's reading. Here: the strand counts usd-core reads.
#[test]
fn openusd_test_files_read_as_usd_core_reads_them() {
    // (file, strands per readable prim, in usd-core's traversal order).
    let files: [(&str, &[usize]); 8] = [
        ("testUsdGeomBasisCurves_basisCurves.usda", &[2]),
        ("testUsdGeomExtentTransform_testCurves.usda", &[1, 1]),
        ("testUsdGeomBBoxCache_pointsAndCurves.usda", &[1, 1, 1]),
        (
            "testUsdImagingGLCurves_basicCurves.usda",
            &[1, 1, 1, 1, 1, 1, 1],
        ),
        ("testUsdImagingGLCurves_moreCurves.usda", &[1; 57]),
        ("testUsdImagingGLCurves_pinnedCurves.usda", &[4]),
        (
            "testUsdImagingGLBasisCurvesWithColor_curveWithVertexColor.usda",
            &[1],
        ),
        ("usdGeomExamples_basisCurves.usda", &[1; 10]),
    ];
    for (name, strands) in files {
        let path = test_data(&format!("usd/openusd/{name}"));
        let groom = read(&path);
        let prims: Vec<(String, usize)> = groom.provenance.metadata[groom::PRIMS_KEY]
            .lines()
            .map(|l| {
                let (p, n) = l.rsplit_once(' ').unwrap();
                (p.to_string(), n.parse().unwrap())
            })
            .collect();
        let counts: Vec<usize> = prims.iter().map(|p| p.1).collect();
        assert_eq!(counts, strands, "{name}: {prims:?}");
        let Some(dir) = std::env::var_os("GROOMBAKE_ARTIFACTS") else {
            continue;
        };
        let dir = std::path::PathBuf::from(dir).join("usd_fixtures");
        std::fs::create_dir_all(&dir).unwrap();
        let widths = groom
            .attribute("width")
            .map(|a| match (&a.values, a.scope) {
                (AttributeValues::Float(v), groom::Scope::Vertex) => v.clone(),
                (AttributeValues::Float(v), groom::Scope::Strand) => groom
                    .strand_vertex_counts
                    .iter()
                    .zip(v)
                    .flat_map(|(&n, &w)| std::iter::repeat_n(w, n as usize))
                    .collect(),
                _ => panic!("{name}: width is not float"),
            });
        let reading = serde_json::json!({
            "source": path.canonicalize().unwrap(),
            "prims": prims,
            "counts": groom.strand_vertex_counts,
            "points": groom.points,
            "widths": widths,
        });
        std::fs::write(
            dir.join(format!("openusd_{name}.groombake.json")),
            serde_json::to_vec(&reading).unwrap(),
        )
        .unwrap();
    }
}

/// Guide ids are integers in USD as in Alembic (Unreal's int32 x 3), in
/// text and crate alike, and read back as the same ids.
#[test]
fn closest_guides_are_integers_in_usd() {
    let dir = TestDir::new();
    let mut groom = swatch(&dir);
    let ids: Vec<[f32; 3]> = (0..groom.strand_count())
        .map(|i| [i as f32, (i + 1) as f32, 70000.0])
        .collect();
    groom.set_attribute(groom::Attribute::per_strand(
        groom::guides::GROOM_CLOSEST_GUIDES,
        AttributeValues::Vec3(ids.clone()),
    ));
    for name in ["guides.usda", "guides.usdc"] {
        exporters::write(&dir.path(name), &groom).unwrap();
        let back = read(&dir.path(name));
        assert_eq!(
            back.attribute(groom::guides::GROOM_CLOSEST_GUIDES)
                .map(|a| &a.values),
            Some(&AttributeValues::Vec3(ids.clone())),
            "{name}"
        );
    }
    let text = std::fs::read_to_string(dir.path("guides.usda")).unwrap();
    assert!(
        text.contains("int3[] primvars:groom_closest_guides = [(0, 1, 70000), "),
        "{text}"
    );
}

/// A file whose curve counts change over time compares with its copy
/// stretch by stretch (it used to exit 2, as a bake refuses it), and a
/// moved point in the second stretch is found there.
#[test]
fn diff_compares_a_changing_topology_stretch_by_stretch() {
    let dir = TestDir::new();
    let source = openusd("testUsdImagingGLBasisCurvesVaryingTopology_bunnyCurves.usda");
    dir.run_ok(&["convert", &source, "copy.usdc"]);
    let out = dir.run_ok(&["diff", &source, "copy.usdc"]);
    assert!(String::from_utf8_lossy(&out.stdout).starts_with("equal within"));
    let mut sequence = importers::read_sequence(Path::new(&source)).unwrap();
    assert!(sequence.len() > 1);
    sequence[1].frames[0].points[0][0] += 0.5;
    exporters::write_sequence(&dir.path("moved.usda"), &sequence).unwrap();
    let output = dir
        .command()
        .args(["diff", &source, "moved.usda"])
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(1));
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(
        text.contains("topology 1: points frame 0 strand 0"),
        "{text}"
    );
    // Against a one-topology file: a structural difference, not a refusal.
    let output = dir
        .command()
        .args([
            "diff",
            &source,
            &openusd("testUsdImagingGLCurves_pinnedCurves.usda"),
        ])
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&output.stdout).contains("topologies: A has"));
}
