//! USD structure kept (issue 36, item 4): a groom read from USD and written
//! to USD keeps its prims: their paths under the same parents, their strand
//! order, and each prim's own basis, wrap, widths and primvars (an
//! attribute a prim lacked stays absent). `.ci/check_usd_fixtures.py` reads
//! the same outputs with usd-core and compares them with the sources.

use crate::util::{test_data, TestDir};
use groom::Groom;
use std::path::Path;

/// OpenUSD's test files (tests/data/usd/openusd/) and whether groombake
/// reads each without a loss (then the round trip runs under `--strict`).
const FILES: [(&str, bool); 9] = [
    ("testUsdGeomBBoxCache_pointsAndCurves.usda", true),
    ("testUsdGeomBasisCurves_basisCurves.usda", false),
    ("testUsdGeomExtentTransform_testCurves.usda", true),
    (
        "testUsdImagingGLBasisCurvesVaryingTopology_bunnyCurves.usda",
        true,
    ),
    (
        "testUsdImagingGLBasisCurvesWithColor_curveWithVertexColor.usda",
        true,
    ),
    ("testUsdImagingGLCurves_basicCurves.usda", true),
    ("testUsdImagingGLCurves_moreCurves.usda", false),
    ("testUsdImagingGLCurves_pinnedCurves.usda", true),
    ("usdGeomExamples_basisCurves.usda", false),
];

fn read_sequence(path: &Path) -> Vec<Groom> {
    importers::read_sequence(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// What must survive: prims (path, strands), counts, points, attributes.
fn assert_same_structure(name: &str, source: &[Groom], back: &[Groom]) {
    assert_eq!(source.len(), back.len(), "{name}: stretches of time");
    for (a, b) in source.iter().zip(back) {
        assert_eq!(
            a.provenance.metadata.get(groom::PRIMS_KEY),
            b.provenance.metadata.get(groom::PRIMS_KEY),
            "{name}: prims"
        );
        assert_eq!(a.strand_vertex_counts, b.strand_vertex_counts, "{name}");
        assert_eq!(a.points.len(), b.points.len(), "{name}");
        for (p, q) in a.points.iter().zip(&b.points) {
            for axis in 0..3 {
                assert!((p[axis] - q[axis]).abs() <= 1e-5, "{name}: {p:?} {q:?}");
            }
        }
        assert_eq!(a.frames.len(), b.frames.len(), "{name}: frames");
        let names = |g: &Groom| -> Vec<String> {
            let mut n: Vec<String> = g.attributes.iter().map(|a| a.name.clone()).collect();
            n.sort();
            n
        };
        assert_eq!(names(a), names(b), "{name}: attributes");
        for attribute in &a.attributes {
            assert_eq!(
                Some(attribute),
                b.attribute(&attribute.name),
                "{name}: {}",
                attribute.name
            );
        }
    }
}

#[test]
fn usd_to_usd_keeps_prim_paths_strand_order_and_per_prim_attributes() {
    let dir = TestDir::new();
    let artifacts = std::env::var_os("GROOMBAKE_ARTIFACTS")
        .map(|d| std::path::PathBuf::from(d).join("usd_fixtures"));
    for (name, lossless) in FILES {
        let source = test_data(&format!("usd/openusd/{name}"));
        let source_text = source.to_str().unwrap();
        let stem = name.trim_end_matches(".usda");
        let out_dir = match &artifacts {
            Some(d) => d.clone(),
            None => dir.root().to_path_buf(),
        };
        std::fs::create_dir_all(&out_dir).unwrap();
        let read_source = read_sequence(&source);
        let mut outputs = Vec::new();
        for extension in ["usda", "usdc"] {
            let output = out_dir.join(format!("round_trip_{stem}.{extension}"));
            let output_text = output.to_str().unwrap();
            let mut args = vec!["convert", source_text, output_text];
            if lossless {
                args.push("--strict");
            }
            dir.run_ok(&args);
            let back = read_sequence(&output);
            assert_same_structure(&format!("{name} -> {extension}"), &read_source, &back);
            // Written again, the file is the same.
            let again = dir.path(&format!("again.{extension}"));
            dir.run_ok(&["convert", output_text, again.to_str().unwrap()]);
            assert_eq!(
                std::fs::read(&output).unwrap(),
                std::fs::read(&again).unwrap(),
                "{name}: {extension} written twice"
            );
            outputs.push(output.canonicalize().unwrap());
        }
        if let Some(artifacts) = &artifacts {
            let source = source.canonicalize().unwrap();
            let reading = serde_json::json!({
                "source": source,
                "round_trip": {"source": source, "outputs": outputs},
            });
            std::fs::write(
                artifacts.join(format!("round_trip_{stem}.groombake.json")),
                serde_json::to_vec(&reading).unwrap(),
            )
            .unwrap();
        }
    }
}

#[test]
fn a_prim_without_widths_stays_without_and_the_made_up_group_id_is_not_written() {
    let dir = TestDir::new();
    let source = test_data("usd/openusd/testUsdGeomBBoxCache_pointsAndCurves.usda");
    let source = source.to_str().unwrap();
    // USD keeps the prim without widths: nothing to refuse.
    dir.run_ok(&["convert", source, "o.usda", "--strict"]);
    let text = std::fs::read_to_string(dir.path("o.usda")).unwrap();
    let prim = text
        .split("def BasisCurves \"bezierWoWidth\"")
        .nth(1)
        .expect("the prim is written at its name");
    let prim = prim.split("def ").next().unwrap();
    assert!(!prim.contains("widths"), "{prim}");
    assert!(text.contains("def Xform \"WarningPrims\""), "{text}");
    assert!(!text.contains("group_id"), "{text}");
    // Reading it back makes the same group ids: stable.
    let a = importers::read(Path::new(source)).unwrap();
    let b = importers::read(&dir.path("o.usda")).unwrap();
    assert!(a.attribute("group_id").is_some());
    assert_eq!(a.attribute("group_id"), b.attribute("group_id"));
    // A format without prims gets the zeros, and says so.
    let e = dir.run_fail(&["convert", source, "o.abc", "--strict"], 2);
    assert!(e.contains("bezierWoWidth has no widths"), "{e}");
}

#[test]
fn a_groom_whose_strands_changed_is_written_flat() {
    let dir = TestDir::new();
    let source = test_data("usd/openusd/testUsdImagingGLCurves_basicCurves.usda");
    let mut groom = importers::read(&source).unwrap();
    let kept: Vec<usize> = (1..groom.strand_count()).collect();
    groom = groom.select_strands(&kept);
    exporters::write(&dir.path("o.usda"), &groom).unwrap();
    let text = std::fs::read_to_string(dir.path("o.usda")).unwrap();
    assert!(text.contains("def Xform \"Groom\""), "{text}");
    assert!(!text.contains("BSplineClosed"), "{text}");
}
