//! The hold (`[material] hold`, per stage): it keeps the Bangs as groomed,
//! the reports say it is on, a bad value is exit 2 naming the key; and the
//! strain watchdog's warning from 5 %.

use crate::util::{sample, TestDir};
use groom::{Units, UpAxis};

/// The Bangs (samples/), settling 3 s under gravity with `material` added
/// to `[material]`, the final pose exported.
fn bangs_timeline(material: &str) -> String {
    let source = sample("hairutil_Bangs_100.hair");
    format!(
        r#"
seed = 1
[groom]
source = "{}"
units = "mm"
[material]
{material}
[solver]
gravity = [-9.8, 0.0, 0.0]
[[stage]]
kind = "settle"
name = "hold still"
duration = 3.0
[[export]]
path = "final.glb"
what = "final"
"#,
        source.display()
    )
}

/// Per strand, the largest distance of a vertex of the baked `final.glb`
/// from the Bangs as groomed, metres.
fn drifts(dir: &TestDir) -> Vec<f32> {
    let mut source = importers::read(&sample("hairutil_Bangs_100.hair")).unwrap();
    source.units = Units::MILLIMETERS;
    source.convert_to(Units::METERS, UpAxis::Y);
    let mut baked = importers::read(&dir.path("final.glb")).unwrap();
    baked.convert_to(Units::METERS, UpAxis::Y);
    assert_eq!(baked.points.len(), source.points.len());
    source
        .strands()
        .zip(baked.strands())
        .map(|(a, b)| {
            a.iter()
                .zip(b)
                .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f32>().sqrt())
                .fold(0.0, f32::max)
        })
        .collect()
}

#[test]
fn a_hold_keeps_every_bangs_strand_within_1_mm_and_the_reports_say_so() {
    let dir = TestDir::new();
    // 1e5 1/s^2 is what the Bangs need (sim/hold_tests.rs).
    std::fs::write(dir.path("held.toml"), bangs_timeline("hold = 1e5")).unwrap();
    dir.run_ok(&[
        "bake",
        "held.toml",
        "-q",
        "--report",
        "r.json",
        "--threads",
        "1",
    ]);
    let held = drifts(&dir);
    let one = std::fs::read(dir.path("final.glb")).unwrap();
    dir.run_ok(&["bake", "held.toml", "-q", "--threads", "2"]);
    let two = std::fs::read(dir.path("final.glb")).unwrap();
    assert!(one == two, "the held bake differs between 1 and 2 threads");
    dir.run_ok(&["bake", "held.toml", "-q", "--report", "r.html"]);
    std::fs::write(dir.path("free.toml"), bangs_timeline("")).unwrap();
    dir.run_ok(&["bake", "free.toml", "-q", "--report", "free.json"]);
    let free = drifts(&dir);
    let max = |d: &[f32]| d.iter().cloned().fold(0.0f32, f32::max);
    let moving = |d: &[f32]| (0..d.len()).filter(|s| d[*s] >= 1e-3).collect::<Vec<_>>();
    eprintln!(
        "bangs after 3 s: hold 1e5 1/s^2 largest drift {:.3} mm; without {:.1} mm (strands >= 1 mm {:?})",
        max(&held) * 1e3,
        max(&free) * 1e3,
        moving(&free)
    );
    assert!(max(&held) < 1e-3, "{held:?}");
    assert!(max(&free) > 0.01, "the Bangs roll over without a hold");

    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path("r.json")).unwrap()).unwrap();
    let stage = &report["stages"][0];
    assert_eq!(stage["hold"]["strength"], 1.0e5, "{stage}");
    assert_eq!(stage["hold"]["ramp"], serde_json::json!([1.0, 1.0]));
    let free: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path("free.json")).unwrap()).unwrap();
    assert!(free["stages"][0].get("hold").is_none(), "{free}");
    let html = std::fs::read_to_string(dir.path("r.html")).unwrap();
    assert!(html.contains("hold (1/s<sup>2</sup>"), "no hold column");
    assert!(html.contains("100000 &rarr; 100000"), "no hold value");
}

#[test]
fn a_bad_hold_is_exit_2_naming_the_key() {
    let dir = TestDir::new();
    for (material, key, line) in [
        ("hold = -10.0", "[material] hold", 7),
        ("hold = nan", "[material] hold", 7),
        (
            "hold = 10.0\nhold_ramp = [0.5, -1.0]",
            "[material] hold_ramp",
            8,
        ),
    ] {
        std::fs::write(dir.path("bad.toml"), bangs_timeline(material)).unwrap();
        let stderr = dir.run_fail(&["bake", "bad.toml", "-q"], 2);
        assert!(stderr.contains(key), "{material}: {stderr}");
        assert!(
            stderr.contains(&format!("bad.toml:{line}:")),
            "{material}: {stderr}"
        );
        assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
        assert!(!dir.path("final.glb").exists());
        let stderr = dir.run_fail(&["validate", "bad.toml"], 2);
        assert!(stderr.contains(key), "validate, {material}: {stderr}");
    }
}

/// A swatch of 5 mm edges hanging from roots at y 0.30, with (or
/// without) a collider filling the space above y 0.294 (a scalp placed 6 mm
/// too low: the roots inside it, the first vertex pushed out below it, so
/// the first edge is strained by 20 %), baked for a short settle; the
/// report.
fn watched(dir: &TestDir, collider: bool) -> serde_json::Value {
    let ball = if collider {
        "[[collider]]\nname = \"scalp\"\nshape = { half_space = { normal = [0.0, -1.0, 0.0] } }\nmotion = [{ t = 0.0, translation = [0.0, 0.294, 0.0] }]\n"
    } else {
        ""
    };
    let timeline = format!(
        r#"
seed = 1
[groom]
generate = {{ layout = "swatch", strands = 8, length = 0.03, segment_length = 0.005, swatch_width = 0.01, head_center = [0.0, 0.30, 0.0] }}
{ball}
[[stage]]
kind = "settle"
name = "lie down"
duration = 0.2
"#
    );
    std::fs::write(dir.path("w.toml"), timeline).unwrap();
    dir.run_ok(&["bake", "w.toml", "-q", "--report", "w.json"]);
    serde_json::from_slice(&std::fs::read(dir.path("w.json")).unwrap()).unwrap()
}

#[test]
fn a_collider_inside_the_roots_warns_of_strained_edges_naming_the_stage() {
    let dir = TestDir::new();
    let report = watched(&dir, true);
    let warnings = report["stages"][0]["warnings"].to_string();
    eprintln!("{warnings}");
    assert!(warnings.contains("stage 'lie down'"), "{warnings}");
    assert!(warnings.contains("strained beyond 5 %"), "{warnings}");
    assert!(warnings.contains("(strands 0, 1,"), "{warnings}");
    // One line for the stage, not one per step.
    let lines = report["stages"][0]["warnings"].as_array().unwrap();
    assert_eq!(
        lines
            .iter()
            .filter(|w| w.to_string().contains("strained beyond"))
            .count(),
        1
    );
    assert!(report["warnings"]
        .to_string()
        .contains("stage 0: stage 'lie down'"));
    // Without the collider: no warning of the stage.
    let quiet = watched(&dir, false);
    assert_eq!(
        quiet["stages"][0]["warnings"],
        serde_json::json!([]),
        "{quiet}"
    );
    assert!(
        !quiet["warnings"].to_string().contains("strained"),
        "{quiet}"
    );
}
