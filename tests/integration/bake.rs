//! `groombake bake` and `validate`: the set is real (bed hair, perm, wash),
//! timelines fail early with line and column, outputs are deterministic.

use crate::util::{sample, TestDir};
use groom::Groom;
use std::path::Path;

/// Turning angle (radians) at every interior vertex of every strand.
fn turning_angles(groom: &Groom) -> Vec<Vec<f64>> {
    groom
        .strands()
        .map(|s| {
            s.windows(3)
                .map(|w| {
                    let a: Vec<f64> = (0..3).map(|k| (w[1][k] - w[0][k]) as f64).collect();
                    let b: Vec<f64> = (0..3).map(|k| (w[2][k] - w[1][k]) as f64).collect();
                    let dot: f64 = (0..3).map(|k| a[k] * b[k]).sum();
                    let na = a.iter().map(|x| x * x).sum::<f64>().sqrt();
                    let nb = b.iter().map(|x| x * x).sum::<f64>().sqrt();
                    (dot / (na * nb)).clamp(-1.0, 1.0).acos()
                })
                .collect()
        })
        .collect()
}

/// `sum sin(angle / 2)` over the chosen joints: the magnitude of the
/// Darboux vectors the set scales (METHOD G: they scale, not the angles).
fn darboux_sum(angles: &[Vec<f64>], joints: impl Fn(usize, usize) -> bool) -> f64 {
    let mut total = 0.0;
    for (s, strand) in angles.iter().enumerate() {
        for (j, a) in strand.iter().enumerate() {
            if joints(s, j) {
                total += (a / 2.0).sin();
            }
        }
    }
    total
}

fn read(path: &Path) -> Groom {
    importers::read(path).unwrap_or_else(|e| panic!("read {}: {e}", path.display()))
}

/// Bakes a wash of `duration` seconds of the state in `source` (a groom
/// exported with `what = "state"`) with the given `bonds` table, and returns
/// the turning angles of the washed rest shape.
fn washed_rest_angles(dir: &TestDir, source: &str, bonds: &str, duration: &str) -> Vec<Vec<f64>> {
    let wash = format!(
        r#"
[groom]
source = "{source}"
[material]
bonds = {bonds}
[solver]
gravity = [0.0, 0.0, 0.0]
[[stage]]
kind = "wash"
duration = {duration}
[[export]]
path = "washed_rest.glb"
what = "rest"
"#
    );
    std::fs::write(dir.path("wash.toml"), wash).unwrap();
    dir.run_ok(&["bake", "wash.toml", "-q"]);
    turning_angles(&read(&dir.path("washed_rest.glb")))
}

const BED_HAIR: &str = r#"
seed = 1
[groom]
generate = { layout = "swatch", strands = 3, length = 0.24, segment_length = 0.03, swatch_width = 0.02, head_center = [0.0, 0.30, 0.0] }
[material]
bonds = { hydrogen = 0.33, ionic = 0.30, disulfide = 0.20, peptide = 0.17 }
[solver]
gravity = [0.0, 0.0, 0.0]
[[collider]]
name = "pillow"
active = "listed"
shape = { cuboid = { half_extents = [0.1, 0.05, 0.1] } }
friction = 0.8
motion = [
  { t = 0.2, translation = [0.0, -0.1, 0.0], rotation = [0.0, 0.0, 30.0] },
  { t = 1.0, translation = [0.0, 0.09, 0.0], rotation = [0.0, 0.0, 30.0] },
]
[[stage]]
kind = "wet"
duration = 0.2
# Pressed until the hair under the pillow is still: contacts let it slide
# along the surface, and at 1.5 s it still moved while it dried, so the held
# shape was not the one the bonds remembered (0.35 instead of 0.33).
[[stage]]
kind = "press"
duration = 3.0
colliders = ["pillow"]
[[stage]]
kind = "dry"
duration = 1.0
colliders = ["pillow"]
drying_time = 0.5
[[export]]
path = "held.glb"
what = "final"
[[export]]
path = "rest.glb"
what = "rest"
[[export]]
path = "state.glb"
what = "state"
"#;

#[test]
fn bed_hair_rest_keeps_the_hydrogen_share_of_the_pressed_bend() {
    let dir = TestDir::new();
    std::fs::write(dir.path("bed.toml"), BED_HAIR).unwrap();
    dir.run_ok(&["bake", "bed.toml", "-q"]);
    let held = turning_angles(&read(&dir.path("held.glb")));
    let rest = turning_angles(&read(&dir.path("rest.glb")));
    let held_sum = darboux_sum(&held, |_, _| true);
    assert!(
        held_sum > 0.3,
        "the pillow did not bend the hair (sum {held_sum})"
    );
    let ratio = darboux_sum(&rest, |_, _| true) / held_sum;
    eprintln!("bed hair: rest keeps {ratio:.4} of the pressed bend (hydrogen 0.33)");
    assert!(
        (ratio - 0.33).abs() < 0.33 * 0.05,
        "rest keeps {ratio:.4} of the pressed bend, expected 0.33"
    );
}

#[test]
fn wash_erases_bed_hair() {
    let dir = TestDir::new();
    std::fs::write(dir.path("bed.toml"), BED_HAIR).unwrap();
    dir.run_ok(&["bake", "bed.toml", "-q"]);
    let held_sum = darboux_sum(&turning_angles(&read(&dir.path("held.glb"))), |_, _| true);
    let washed = darboux_sum(
        &washed_rest_angles(
            &dir,
            "state.glb",
            "{ hydrogen = 0.33, ionic = 0.30, disulfide = 0.20, peptide = 0.17 }",
            "6.0",
        ),
        |_, _| true,
    );
    eprintln!(
        "bed hair after wash: {:.4} of the pressed bend",
        washed / held_sum
    );
    assert!(
        washed / held_sum < 0.05,
        "wash left {:.4} of the bed-hair bend",
        washed / held_sum
    );
}

const PERM: &str = r#"
seed = 1
[groom]
generate = { layout = "swatch", strands = 2, length = 0.24, segment_length = 0.01, swatch_width = 0.02, head_center = [0.0, 0.30, 0.0] }
[material]
bonds = { hydrogen = 0.35, ionic = 0.28, disulfide = 0.20, peptide = 0.17 }
[solver]
# The physical model (default): at dt 1/1000 the rest keeps 0.663 of the rod;
# at 1/360 its frames lag the rolling rod a little (0.647, open).
dt = "1/1000"
gravity = [0.0, 0.0, 0.0]
[[stage]]
kind = "perm"
duration = 3.0
gravity = false
rod = { radius = 0.02, root_gap = 0.04, phases = [0.3, 0.4, 0.8], disulfide_cut = 0.2 }
[[export]]
path = "perm_rest.glb"
what = "rest"
[[export]]
path = "perm_state.glb"
what = "state"
"#;

/// Joints wound on the rod: well inside the wound part (away from the
/// contact at the root gap and from the tip).
fn wound(_strand: usize, joint: usize) -> bool {
    (8..=20).contains(&joint)
}

fn rod_darboux(radius: f64, hair_radius: f64, edge: f64) -> f64 {
    // The chord of an arc of radius rho turns by 2 asin(l / 2 rho).
    let rho = radius + hair_radius;
    (edge / (2.0 * rho)).asin()
}

#[test]
fn perm_rest_keeps_two_thirds_of_the_rod_and_wash_keeps_what_the_model_predicts() {
    let dir = TestDir::new();
    std::fs::write(dir.path("perm.toml"), PERM).unwrap();
    dir.run_ok(&["bake", "perm.toml", "-q"]);
    let rest = turning_angles(&read(&dir.path("perm_rest.glb")));
    let joints = rest.len() * 13;
    let per_joint_rod = rod_darboux(0.02, 4e-5, 0.01).sin();
    let per_joint = darboux_sum(&rest, wound) / joints as f64;
    let kept = per_joint / per_joint_rod;
    eprintln!("perm: rest keeps {kept:.4} of the rod's curvature (expected 0.67)");
    assert!(
        (kept - 0.67).abs() < 0.67 * 0.03,
        "perm keeps {kept:.4} of the rod's curvature, expected 0.67"
    );

    let washed = washed_rest_angles(
        &dir,
        "perm_state.glb",
        "{ hydrogen = 0.35, ionic = 0.28, disulfide = 0.20, peptide = 0.17 }",
        "30.0",
    );
    let kept_after_wash = darboux_sum(&washed, wound) / joints as f64 / per_joint_rod;
    let predicted = (0.28 + 0.2 * 0.20) / (1.0 - 0.35);
    eprintln!("perm after wash: keeps {kept_after_wash:.4} of the rod (predicted {predicted:.4})");
    assert!(
        (kept_after_wash - predicted).abs() < predicted * 0.03,
        "after wash the perm keeps {kept_after_wash:.4} of the rod, predicted {predicted:.4}"
    );
}

#[test]
fn typo_missing_file_and_negative_duration_fail_early_with_line_and_column() {
    let dir = TestDir::new();
    let good = "[groom]\ngenerate = { strands = 2 }\n\n[[stage]]\nkind = \"settle\"\nduration = 0.1\n\n[[export]]\npath = \"never.glb\"\nwhat = \"final\"\n";
    std::fs::write(dir.path("typo.toml"), good.replace("duration", "duratoin")).unwrap();
    let e = dir.run_fail(&["bake", "typo.toml", "-q"], 2);
    assert!(e.contains("typo.toml:6:1") && e.contains("duratoin"), "{e}");

    std::fs::write(
        dir.path("missing.toml"),
        good.replace("generate = { strands = 2 }", "source = \"gone.abc\""),
    )
    .unwrap();
    let e = dir.run_fail(&["bake", "missing.toml", "-q"], 2);
    assert!(
        e.contains("missing.toml:2:10") && e.contains("not found"),
        "{e}"
    );

    std::fs::write(dir.path("negative.toml"), good.replace("0.1", "-2")).unwrap();
    let e = dir.run_fail(&["bake", "negative.toml", "-q"], 2);
    assert!(
        e.contains("negative.toml:6:12") && e.contains("duration"),
        "{e}"
    );

    let e = dir.run_fail(&["validate", "negative.toml"], 2);
    assert!(e.contains("negative.toml:6:12"), "{e}");
    assert!(
        !dir.path("never.glb").exists(),
        "a failed bake wrote an output"
    );
}

#[test]
fn validate_accepts_every_sample() {
    let dir = TestDir::new();
    for name in [
        "bed_hair.toml",
        "blow_dry.toml",
        "perm.toml",
        "wind.toml",
        "bangs.toml",
        "bed_head.toml",
    ] {
        let path = sample(name);
        let output = dir.run_ok(&["validate", path.to_str().unwrap()]);
        assert!(String::from_utf8_lossy(&output.stdout).contains("ok"));
    }
}

#[test]
fn report_lists_stages_and_outputs_with_sha256() {
    let dir = TestDir::new();
    let timeline = "[groom]\ngenerate = { strands = 4, layout = \"swatch\" }\n[[stage]]\nkind = \"wet\"\nduration = 0.1\n[[stage]]\nkind = \"dry\"\nduration = 0.2\n[[export]]\npath = \"out/final.glb\"\nwhat = \"final\"\n[[export]]\npath = \"out/anim.glb\"\nwhat = \"animated\"\nfps = 30\n";
    std::fs::write(dir.path("t.toml"), timeline).unwrap();
    dir.run_ok(&["bake", "t.toml", "-q", "--report", "r.json", "--out", "o"]);
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path("r.json")).unwrap()).unwrap();
    assert_eq!(report["stages"].as_array().unwrap().len(), 2);
    assert_eq!(report["stages"][0]["kind"], "wet");
    assert_eq!(report["strands"], 4);
    let outputs = report["outputs"].as_array().unwrap();
    assert_eq!(outputs.len(), 2);
    for output in outputs {
        let path = Path::new(output["path"].as_str().unwrap());
        let bytes = std::fs::read(dir.root().join(path)).unwrap();
        assert_eq!(output["bytes"], bytes.len() as u64);
        assert_eq!(output["sha256"].as_str().unwrap().len(), 64);
    }
    // 0.3 s at 30 fps: frames 0..=9.
    assert_eq!(outputs[1]["frames"], 10);
    let anim = read(&dir.root().join("o/out/anim.glb"));
    assert_eq!(anim.frames.len(), 10);
}

/// Width and height from a PNG's IHDR chunk.
fn png_size(path: &Path) -> (u32, u32) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "not a PNG");
    let be = |at: usize| u32::from_be_bytes(bytes[at..at + 4].try_into().unwrap());
    (be(16), be(20))
}

#[test]
fn bake_writes_a_sheet_before_and_after_each_stage_and_preview_draws_a_timeline() {
    let dir = TestDir::new();
    let timeline = "[groom]\ngenerate = { strands = 6, layout = \"swatch\" }\n[[stage]]\nkind = \"wet\"\nduration = 0.05\n[[stage]]\nkind = \"dry\"\nduration = 0.05\n[preview]\nsheet = \"sheet.png\"\ncolor = \"bond_hydrogen\"\nsize = [64, 48]\n";
    std::fs::write(dir.path("t.toml"), timeline).unwrap();
    dir.run_ok(&["bake", "t.toml", "-q", "--report", "r.json"]);
    // Three pictures (before, after wet, after dry) side by side, each
    // under a label strip.
    let (w, h) = png_size(&dir.path("sheet.png"));
    assert!(w >= 3 * 64 && h > 48, "sheet is {w}x{h}");
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path("r.json")).unwrap()).unwrap();
    assert!(report["outputs"]
        .as_array()
        .unwrap()
        .iter()
        .any(|o| o["what"] == "sheet"));

    dir.run_ok(&[
        "preview", "t.toml", "-o", "p.png", "--size", "40x40", "--frame", "2",
    ]);
    let (w, h) = png_size(&dir.path("p.png"));
    // --size is the whole picture: one labelled snapshot inside it.
    assert_eq!((w, h), (40, 40), "one snapshot is {w}x{h}");
    let e = dir.run_fail(&["preview", "t.toml", "-o", "q.png", "--frame", "9"], 2);
    assert!(e.contains("3 snapshots"), "{e}");
}

#[test]
fn roots_follow_the_scalp_motion() {
    let dir = TestDir::new();
    let timeline = "[groom]\ngenerate = { strands = 3, layout = \"swatch\", head_center = [0.0, 0.3, 0.0] }\nmotion = [ { t = 0.0 }, { t = 0.2, translation = [0.05, 0.1, 0.0], rotation = [0.0, 90.0, 0.0] } ]\n[[stage]]\nkind = \"settle\"\nduration = 0.3\n[[export]]\npath = \"end.glb\"\nwhat = \"final\"\n";
    std::fs::write(dir.path("t.toml"), timeline).unwrap();
    dir.run_ok(&["bake", "t.toml", "-q"]);
    let end = read(&dir.path("end.glb"));
    // The generator's swatch roots: x = -0.025, 0, 0.025 (5 cm bar) at y = 0.3.
    let start = [[-0.025f32, 0.3, 0.0], [0.0, 0.3, 0.0], [0.025, 0.3, 0.0]];
    assert_eq!(end.strand_count(), 3);
    for (a, b) in start.iter().zip(end.strands()) {
        // A quarter turn about Y maps (x, y, z) to (z, y, -x), then the shift.
        let expected = [a[2] + 0.05, a[1] + 0.1, -a[0]];
        for k in 0..3 {
            assert!(
                (b[0][k] - expected[k]).abs() < 1e-5,
                "root {:?}, expected {expected:?}",
                b[0]
            );
        }
    }
}

/// Combed-down scalp hair (drape 60 rad/m, 1 cm edges), settled for 1 s.
fn settle_scalp(sag_free: bool) -> String {
    format!(
        r#"
seed = 1
[groom]
generate = {{ layout = "scalp", strands = 20, length = 0.21, segment_length = 0.01, scalp_angle = 95.0, drape = 60.0 }}
[solver]
sag_free = {sag_free}
[[stage]]
kind = "settle"
duration = 1.0
[[export]]
path = "final.glb"
what = "final"
[[export]]
path = "rest.glb"
what = "rest"
"#
    )
}

fn max_distance(a: &Groom, b: &Groom) -> f64 {
    a.points
        .iter()
        .zip(&b.points)
        .map(|(p, q)| {
            (0..3)
                .map(|k| ((p[k] - q[k]) as f64).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .fold(0.0, f64::max)
}

#[test]
fn sag_free_start_keeps_the_groom_where_it_was_authored() {
    let dir = TestDir::new();
    // The groom the timeline generates.
    let groom = groombake::generate::generate(&groombake::generate::GeneratorParameters {
        strands: 20,
        length: 0.21,
        segment_length: 0.01,
        scalp_angle: 95.0,
        drape: 60.0,
        ..Default::default()
    })
    .unwrap();
    std::fs::write(dir.path("off.toml"), settle_scalp(false)).unwrap();
    dir.run_ok(&["bake", "off.toml", "-q"]);
    let sagged = max_distance(&read(&dir.path("final.glb")), &groom);
    std::fs::write(dir.path("on.toml"), settle_scalp(true)).unwrap();
    dir.run_ok(&["bake", "on.toml", "-q", "--report", "on.json"]);
    // Every strand of this groom can stand alone: no sag-free warning.
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path("on.json")).unwrap()).unwrap();
    let warnings = report["warnings"].as_array().unwrap();
    assert!(
        !warnings
            .iter()
            .any(|w| w.as_str().unwrap().starts_with("sag-free")),
        "{warnings:?}"
    );
    let kept = max_distance(&read(&dir.path("final.glb")), &groom);
    // The rest shape is the natural one (without gravity): away from it.
    let natural = max_distance(&read(&dir.path("rest.glb")), &groom);
    eprintln!(
        "scalp after 1 s: {:.3} mm from the groom with sag-free, {:.1} mm without; natural shape {:.1} mm from it",
        kept * 1e3,
        sagged * 1e3,
        natural * 1e3
    );
    assert!(kept < 1e-3, "{kept}");
    assert!(sagged > 0.01, "{sagged}");
    assert!(natural > 0.01, "{natural}");
}

#[test]
fn sag_free_bake_names_the_bangs_strands_a_lone_hair_cannot_hold() {
    // hairutil's Bangs (tests/data; mm, hanging along -X) of real 40 um
    // hair: six strands stand only as an unstable balance
    // (sim::physical_tests names them); the bake's report says so in one line.
    let dir = TestDir::new();
    let groom = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/hairutil_Bangs_100.hair");
    let timeline = format!(
        "[groom]\nsource = {:?}\nunits = \"mm\"\n[solver]\ngravity = [-9.8, 0.0, 0.0]\n[[stage]]\nkind = \"settle\"\nduration = 0.01\n[[export]]\npath = \"final.glb\"\nwhat = \"final\"\n",
        groom.to_str().unwrap()
    );
    std::fs::write(dir.path("t.toml"), timeline).unwrap();
    dir.run_ok(&["bake", "t.toml", "-q", "--report", "r.json"]);
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path("r.json")).unwrap()).unwrap();
    let named: Vec<&str> = report["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|w| w.as_str())
        .filter(|w| w.starts_with("sag-free"))
        .collect();
    eprintln!("{named:?}");
    assert_eq!(named.len(), 1, "{named:?}");
    assert!(
        named[0].contains("6 of 100 strands") && named[0].contains("(strands 0, 4, 6, 32, 58, 65)"),
        "{}",
        named[0]
    );
}
