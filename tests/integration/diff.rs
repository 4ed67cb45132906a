//! `groombake diff`: deviations named by strand, vertex and frame; exit codes.

use crate::util::TestDir;
use groom::{Frame, Groom, Units};

/// An animated groom of `strands` strands of 5 vertices, 3 frames, in cm.
fn animated_groom(strands: usize) -> Groom {
    let mut groom = Groom::from_strands((0..strands).map(|s| {
        let (x, z) = ((s % 400) as f32 * 0.05, (s / 400) as f32 * 0.05);
        (0..5)
            .map(|v| [x, 30.0 - v as f32 * 2.0, z])
            .collect::<Vec<_>>()
    }));
    groom.units = Units::CENTIMETERS;
    groom.frames = (0..3)
        .map(|k| Frame {
            time: k as f64 / 24.0,
            points: groom
                .points
                .iter()
                .map(|p| [p[0] + k as f32 * 0.5, p[1], p[2]])
                .collect(),
            attributes: Vec::new(),
        })
        .collect();
    groom
}

#[test]
fn finds_one_moved_vertex_among_100k_animated_strands() {
    let dir = TestDir::new();
    let tolerance = 1e-5; // metres
    let a = animated_groom(100_000);
    let mut b = a.clone();
    let (strand, vertex, frame) = (76_543usize, 3usize, 2usize);
    let index = strand * 5 + vertex;
    // 2x the tolerance, in the file's centimetres.
    b.frames[frame].points[index][2] += (2.0 * tolerance * 100.0) as f32;
    exporters::write(&dir.path("a.abc"), &a).unwrap();
    exporters::write(&dir.path("b.abc"), &b).unwrap();

    let output = dir
        .command()
        .args(["diff", "a.abc", "b.abc", "--tolerance", "1e-5", "--json"])
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(1), "{output:?}");
    let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(report["above_tolerance"], 1, "{report}");
    let d = &report["largest"][0];
    assert_eq!(d["strand"], strand);
    assert_eq!(d["vertex"], vertex);
    assert_eq!(d["frame"], frame);
    let amount = d["amount"].as_f64().unwrap();
    assert!((amount - 2e-5).abs() < 1e-6, "{amount}");

    // The text names it too.
    let text = dir
        .command()
        .args(["diff", "a.abc", "b.abc", "--tolerance", "1e-5"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&text.stdout);
    assert!(
        stdout.contains(&format!("frame {frame} strand {strand} vertex {vertex}")),
        "{stdout}"
    );
    // Above 2x the tolerance it is equal.
    dir.run_ok(&["diff", "a.abc", "b.abc", "--tolerance", "3e-5"]);
    dir.run_ok(&["diff", "a.abc", "a.abc"]);
}

#[test]
fn equal_across_formats_and_bad_input() {
    let dir = TestDir::new();
    let a = animated_groom(50);
    exporters::write(&dir.path("a.abc"), &a).unwrap();
    exporters::write(&dir.path("a.usdc"), &a).unwrap();
    // Alembic carries Unreal's groom attributes too, but they read back as
    // the groom's own (one attribute per meaning): equal.
    let out = dir.run_ok(&["diff", "a.abc", "a.usdc"]);
    assert!(String::from_utf8_lossy(&out.stdout).starts_with("equal within"));

    // A static groom against an animated one differs in its frames.
    let mut still = a.clone();
    still.frames.clear();
    exporters::write(&dir.path("still.abc"), &still).unwrap();
    let output = dir
        .command()
        .args(["diff", "a.abc", "still.abc"])
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&output.stdout).contains("frame count: 3 in A, 0 in B"));

    let stderr = dir.run_fail(&["diff", "a.abc", "missing.usda"], 2);
    assert!(stderr.contains("missing.usda"), "{stderr}");
    dir.run_fail(&["diff", "a.abc", "a.abc", "--tolerance", "-1"], 2);
}
