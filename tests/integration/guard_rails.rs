//! Guard rails for a TD: the fibre radius a bake uses is said and warned
//! about outside real hair's; the watchdog's warning names a cause and a
//! remedy; `inspect` shows a collider mesh; rod radii outside the
//! documented range are refused.

use crate::util::{sample, TestDir};

const STAGE: &str =
    "[[stage]]\nkind = \"wet\"\nduration = 0.02\n[[export]]\npath = \"r.usda\"\nwhat = \"rest\"\n";

/// A 2-strand swatch whose USD `widths` are `width` metres.
fn groom_with_width(dir: &TestDir, width: &str) {
    dir.run_ok(&[
        "generate",
        "swatch",
        "-o",
        "g.usda",
        "--strands",
        "2",
        "--length",
        "0.05",
    ]);
    let text = std::fs::read_to_string(dir.path("g.usda")).unwrap();
    assert!(text.contains("0.00008"), "the generator's width changed");
    std::fs::write(dir.path("g.usda"), text.replace("0.00008", width)).unwrap();
}

#[test]
fn the_fibre_radius_is_said_and_a_display_width_warns() {
    let dir = TestDir::new();
    groom_with_width(&dir, "0.004");
    std::fs::write(
        dir.path("t.toml"),
        format!("[groom]\nsource = \"g.usda\"\n{STAGE}"),
    )
    .unwrap();
    let out = dir.run_ok(&["validate", "t.toml"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("fibre radius 2.0 mm (the groom's width / 2)\n")
            && stderr.contains("warning: fibre radius 2.0 mm (the groom's width / 2): outside real hair's 10 um - 100 um")
            && stderr.contains("set [material] radius = 4e-5"),
        "{stderr}"
    );
    let out = dir.run_ok(&["bake", "t.toml", "-q", "--report", "-"]);
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!((report["fibre_radius"]["max"].as_f64().unwrap() - 0.002).abs() < 1e-9);
    assert!(report["warnings"][0]
        .as_str()
        .unwrap()
        .starts_with("fibre radius 2.0 mm"));

    // Set in the material: said, no warning.
    std::fs::write(
        dir.path("t.toml"),
        format!("[groom]\nsource = \"g.usda\"\n[material]\nradius = 4e-5\n{STAGE}"),
    )
    .unwrap();
    let out = dir.run_ok(&["bake", "t.toml"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("fibre radius 40 um ([material] radius)\n"),
        "{stderr}"
    );
    assert!(!stderr.contains("warning"), "{stderr}");
    // A real hair's width: taken from the groom, no warning.
    groom_with_width(&dir, "0.00012");
    std::fs::write(
        dir.path("t.toml"),
        format!("[groom]\nsource = \"g.usda\"\n{STAGE}"),
    )
    .unwrap();
    let stderr = String::from_utf8_lossy(&dir.run_ok(&["validate", "t.toml"]).stderr).into_owned();
    assert!(
        stderr.contains("fibre radius 60 um (the groom's width / 2)\n"),
        "{stderr}"
    );
    assert!(!stderr.contains("warning"), "{stderr}");
}

#[test]
fn a_blow_up_warning_names_the_cause_and_the_remedy() {
    let dir = TestDir::new();
    // A pillow around the roots: they are pinned inside it.
    std::fs::write(
        dir.path("t.toml"),
        r#"[groom]
generate = { layout = "swatch", strands = 4, length = 0.1, segment_length = 0.01, swatch_width = 0.02, head_center = [0.0, 0.55, 0.0] }
[[collider]]
name = "pillow"
shape = { cuboid = { half_extents = [0.05, 0.02, 0.05] } }
motion = [{ t = 0.0, translation = [0.0, 0.55, 0.0] }]
[[stage]]
kind = "press"
duration = 0.05
[[export]]
path = "r.usda"
what = "rest"
"#,
    )
    .unwrap();
    let stderr =
        String::from_utf8_lossy(&dir.run_ok(&["bake", "t.toml", "-q"]).stderr).into_owned();
    assert!(
        stderr.contains("blew up and were put back and frozen")
            && stderr.contains(
                "likely cause: a collider inside the hair's roots (move it off the scalp"
            ),
        "{stderr}"
    );
    // The docs use the warning's words and give the remedy.
    let tuning = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/tuning.md"),
    )
    .unwrap();
    assert!(tuning.contains("likely cause: a collider inside the hair's roots"));
}

#[test]
fn inspect_shows_a_collider_mesh() {
    let dir = TestDir::new();
    let pillow = sample("pillow.glb").display().to_string();
    let out = dir.run_ok(&["inspect", &pillow]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("triangles   12\n"), "{text}");
    assert!(
        text.contains("bounds      [-0.25, -0.06, -0.175] .. [0.25, 0.06, 0.175]"),
        "{text}"
    );
    let json = dir.inspect(&pillow);
    assert_eq!(json["kind"], "mesh");
    assert_eq!(json["triangles"], 12);
    let head = dir.inspect(&sample("head.obj").display().to_string());
    assert!(head["triangles"].as_u64().unwrap() > 100, "{head}");
    // Not a mesh either: the groom reader's error stands.
    std::fs::write(dir.path("x.glb"), b"not glTF").unwrap();
    dir.run_fail(&["inspect", "x.glb"], 2);
}

#[test]
fn rod_radius_outside_the_documented_range_is_refused() {
    let dir = TestDir::new();
    let perm = std::fs::read_to_string(sample("perm.toml")).unwrap();
    assert!(perm.contains("rod = { radius = 0.01,"));
    for (radius, ok) in [
        ("0.003", false),
        ("0.005", true),
        ("0.05", true),
        ("0.08", false),
    ] {
        std::fs::write(
            dir.path("t.toml"),
            perm.replace(
                "rod = { radius = 0.01,",
                &format!("rod = {{ radius = {radius},"),
            ),
        )
        .unwrap();
        if ok {
            dir.run_ok(&["validate", "t.toml"]);
        } else {
            let stderr = dir.run_fail(&["validate", "t.toml"], 2);
            assert!(
                stderr.contains(&format!(
                    "rod radius {radius} m: outside the documented 0.005 - 0.05 m"
                )),
                "{stderr}"
            );
        }
    }
}

/// `[solver] integrator` (issue 35): `midpoint` or `backward_euler` on the
/// physical model, a different bake; any other value, or the key on the
/// paper model, refused by `validate` naming it.
#[test]
fn the_integrator_is_chosen_checked_and_refused_where_it_does_not_apply() {
    let dir = TestDir::new();
    groom_with_width(&dir, "0.00008");
    let timeline = |model: &str, integrator: &str, out: &str| {
        format!(
            "[groom]\nsource = \"g.usda\"\n[material]\nmodel = \"{model}\"\n[solver]\n{integrator}\n\
             [[stage]]\nkind = \"settle\"\nduration = 0.1\n[[export]]\npath = \"{out}\"\nwhat = \"final\"\n"
        )
    };
    let mut finals = Vec::new();
    for (integrator, out) in [
        ("integrator = \"backward_euler\"", "be.usda"),
        ("integrator = \"midpoint\"", "mid.usda"),
    ] {
        std::fs::write(dir.path("t.toml"), timeline("physical", integrator, out)).unwrap();
        dir.run_ok(&["validate", "t.toml"]);
        dir.run_ok(&["bake", "t.toml", "--out", "o", "-q"]);
        finals.push(std::fs::read(dir.path("o").join(out)).unwrap());
    }
    assert_ne!(finals[0], finals[1], "the integrator changed nothing");
    std::fs::write(
        dir.path("t.toml"),
        timeline("physical", "integrator = \"rk4\"", "x.usda"),
    )
    .unwrap();
    let stderr = dir.run_fail(&["validate", "t.toml"], 2);
    assert!(
        stderr.contains("t.toml") && stderr.contains("rk4"),
        "{stderr}"
    );
    std::fs::write(
        dir.path("t.toml"),
        timeline("paper", "integrator = \"midpoint\"", "x.usda"),
    )
    .unwrap();
    let stderr = dir.run_fail(&["validate", "t.toml"], 2);
    assert!(
        stderr.contains("`integrator` does not apply to the paper model"),
        "{stderr}"
    );
}
