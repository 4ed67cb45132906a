//! Time in studio files (issue 36, item 6). USD layer offsets: a
//! sublayer's, a reference's or a payload's `(offset; scale)` moves the
//! time samples it brings, and nested offsets compose, as usd-core composes
//! them (the files are written by hand per the USD spec,
//! tests/data/usd/layer_offset_*; usd-core's times for them are checked by
//! `.ci/check_usd_fixtures.py` from the readings this test leaves in
//! `GROOMBAKE_ARTIFACTS`). A topology that changes over time goes to
//! Alembic with `nVertices` per sample (checked by `.ci/check_abc.py` with
//! the Alembic library).

use crate::util::{hand_to_validators, test_data, TestDir};

#[test]
fn layer_offsets_of_sublayers_and_references_move_the_time_samples() {
    // (file, the time codes of the curves' samples at 0 and 4).
    let files = [
        // Sublayer (offset 10, scale 2) over a reference (3, 0.5): t + 16.
        ("layer_offset_sublayer.usda", [16.0, 20.0]),
        // Reference (1, 2): 2 t + 1, in text and in a crate layer.
        ("layer_offset_reference.usda", [1.0, 9.0]),
        ("layer_offset_reference.usdc", [1.0, 9.0]),
    ];
    for (name, codes) in files {
        let path = test_data(&format!("usd/{name}"));
        let groom = importers::read(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        // No timeCodesPerSecond: 24 codes a second.
        let got: Vec<f64> = groom.frames.iter().map(|f| f.time * 24.0).collect();
        assert_eq!(got.len(), 2, "{name}: {got:?}");
        for (g, want) in got.iter().zip(codes) {
            assert!(
                (g - want).abs() < 1e-9,
                "{name}: time codes {got:?}, want {codes:?}"
            );
        }
        assert_eq!(groom.frames[0].points, [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
        assert_eq!(groom.frames[1].points, [[1.0, 0.0, 0.0], [1.0, 1.0, 0.0]]);
        let Some(dir) = std::env::var_os("GROOMBAKE_ARTIFACTS") else {
            continue;
        };
        let dir = std::path::PathBuf::from(dir).join("usd_fixtures");
        std::fs::create_dir_all(&dir).unwrap();
        let samples: Vec<serde_json::Value> = groom
            .frames
            .iter()
            .zip(codes)
            .map(|(frame, code)| {
                serde_json::json!({
                    "time_code": code,
                    "counts": groom.strand_vertex_counts,
                    "points": frame.points,
                })
            })
            .collect();
        let reading = serde_json::json!({
            "source": path.canonicalize().unwrap(),
            "samples": samples,
        });
        std::fs::write(
            dir.join(format!("{name}.groombake.json")),
            serde_json::to_vec(&reading).unwrap(),
        )
        .unwrap();
    }
}

#[test]
fn a_changing_topology_goes_to_alembic_sample_by_sample() {
    let dir = TestDir::new();
    let source =
        test_data("usd/openusd/testUsdImagingGLBasisCurvesVaryingTopology_bunnyCurves.usda");
    let grooms = importers::read_sequence(&source).unwrap();
    assert!(grooms.len() > 1, "the source changes topology");
    let curves_per_sample: Vec<usize> = grooms
        .iter()
        .flat_map(|g| std::iter::repeat_n(g.strand_count(), g.frames.len().max(1)))
        .collect();
    let times: Vec<f64> = grooms
        .iter()
        .flat_map(|g| g.frames.iter().map(|f| f.time))
        .collect();
    let output = dir.run_ok(&["convert", source.to_str().unwrap(), "bunny.abc", "--strict"]);
    let said = String::from_utf8_lossy(&output.stderr);
    assert!(!said.contains("only the first topology"), "{said}");
    // groombake's own reader holds one topology: it says so, exit 2.
    let e = dir.run_fail(&["inspect", "bunny.abc"], 2);
    assert!(e.contains("topology changes"), "{e}");
    hand_to_validators(
        &dir.path("bunny.abc"),
        "varying_topology_bunny",
        serde_json::json!({
            "kind": "abc",
            "samples": curves_per_sample.len(),
            "times": times,
            "curves_per_sample": curves_per_sample,
        }),
    );
}
