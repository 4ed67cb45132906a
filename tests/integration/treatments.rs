//! Treatments a TD can trust (issue 35): the animated exports carry the
//! wetness and bond rates of every frame, drying dries where the blower's
//! air reaches, and a key that does nothing is refused.

use crate::util::{hand_to_validators, sample, TestDir};
use groom::{AttributeValues, Groom};
use serde_json::json;

/// The sample's timeline with the generator's strand count set to
/// `strands` and its exports replaced by `exports`.
fn with_exports(name: &str, strands: usize, exports: &str) -> String {
    let text = std::fs::read_to_string(sample(name)).unwrap();
    let (head, _) = text.split_at(text.find("[[export]]").expect("an export"));
    let key = "strands = ";
    let start = head.find(key).expect("a generated groom") + key.len();
    let digits = head[start..].find(|c: char| !c.is_ascii_digit()).unwrap();
    let head = format!("{}{strands}{}", &head[..start], &head[start + digits..]);
    // The sample's preview sheet is not what these tests look at.
    let head = match head.find("[preview]") {
        Some(at) => head[..at].to_string(),
        None => head,
    };
    format!("{head}{exports}")
}

fn floats<'g>(attributes: &'g [groom::Attribute], name: &str) -> &'g [f32] {
    match attributes
        .iter()
        .find(|a| a.name == name)
        .map(|a| &a.values)
    {
        Some(AttributeValues::Float(v)) => v,
        other => panic!("no float attribute {name}: {other:?}"),
    }
}

fn span(values: &[f32]) -> (f32, f32) {
    values
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        })
}

fn median(values: &[f32]) -> f32 {
    let mut sorted = values.to_vec();
    sorted.sort_by(f32::total_cmp);
    sorted[sorted.len() / 2]
}

/// bed_hair at 24 fps: frame 24 (1 s) is wet and pressed, frame 100
/// (4.2 s) is dry. Every animated format that can hold per-frame values
/// reads them back with groombake's own importers.
#[test]
fn animated_exports_carry_the_wetness_and_bonds_of_every_frame() {
    let dir = TestDir::new();
    let mut exports = String::new();
    for file in ["anim.usdc", "anim.usda", "anim.abc", "anim.glb"] {
        exports.push_str(&format!(
            "[[export]]\npath = \"{file}\"\nwhat = \"animated\"\nfps = 24\n"
        ));
    }
    std::fs::write(
        dir.path("t.toml"),
        with_exports("bed_hair.toml", 6, &exports),
    )
    .unwrap();
    dir.run_ok(&["bake", "t.toml", "-q", "--report", "r.json"]);
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path("r.json")).unwrap()).unwrap();
    let warnings: Vec<&str> = report["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|w| w.as_str())
        .collect();
    let gltf: Vec<&&str> = warnings
        .iter()
        .filter(|w| w.contains("glTF cannot animate vertex attributes"))
        .collect();
    assert_eq!(gltf.len(), 1, "{warnings:?}");
    assert!(gltf[0].contains("anim.glb") && gltf[0].contains("wetness"));

    for file in ["anim.usdc", "anim.usda", "anim.abc"] {
        let groom = importers::read(&dir.path(file)).unwrap();
        assert_eq!(groom.frames.len(), 133, "{file}");
        let wet = &groom.frames[24].attributes;
        let dry = &groom.frames[100].attributes;
        let names: Vec<&str> = wet.iter().map(|a| a.name.as_str()).collect();
        // Only what the stages change is sampled per frame.
        assert_eq!(names, ["bond_hydrogen", "wetness"], "{file}");
        let (wet_low, _) = span(floats(wet, "wetness"));
        let (_, dry_high) = span(floats(dry, "wetness"));
        let (_, broken_high) = span(floats(wet, "bond_hydrogen"));
        let (formed_low, _) = span(floats(dry, "bond_hydrogen"));
        eprintln!(
            "{file}: wetness at frame 24 >= {wet_low}, at frame 100 <= {dry_high}; \
             hydrogen at 24 <= {broken_high}, at 100 >= {formed_low}"
        );
        assert!(wet_low > 0.9 && dry_high < 0.1, "{file}");
        assert!(broken_high < 0.1 && formed_low > 0.9, "{file}");
        // `convert --frame` writes that frame's values.
        let out = format!("f24_{file}.usda");
        dir.run_ok(&["convert", file, &out, "--frame", "24"]);
        let frame = importers::read(&dir.path(&out)).unwrap();
        assert!(span(floats(&frame.attributes, "wetness")).0 > 0.9, "{file}");
    }
    let per_frame = json!({
        "wetness": [[24, "min_above", 0.9], [100, "max_below", 0.1]],
        "bond_hydrogen": [[24, "max_below", 0.1], [100, "min_above", 0.9]],
    });
    let varying = json!(["bond_hydrogen", "wetness"]);
    for file in ["anim.usdc", "anim.usda"] {
        hand_to_validators(
            &dir.path(file),
            &format!("treatments_per_frame_{}", file.replace('.', "_")),
            json!({"frame_values": per_frame, "time_varying": varying}),
        );
    }
    hand_to_validators(
        &dir.path("anim.abc"),
        "treatments_per_frame_abc",
        json!({"kind": "abc", "frame_values": per_frame, "time_varying": varying}),
    );
}

/// The text of a USD export names a primvar's time samples only for the
/// attributes that change: the width and groom attributes are written once.
#[test]
fn attributes_that_hold_still_are_written_once() {
    let dir = TestDir::new();
    let exports = "[[export]]\npath = \"anim.usda\"\nwhat = \"animated\"\nfps = 24\n";
    std::fs::write(
        dir.path("t.toml"),
        with_exports("bed_hair.toml", 4, exports),
    )
    .unwrap();
    dir.run_ok(&["bake", "t.toml", "-q"]);
    let text = std::fs::read_to_string(dir.path("anim.usda")).unwrap();
    let sampled: Vec<&str> = text
        .lines()
        .filter(|l| l.contains(".timeSamples"))
        .map(str::trim)
        .collect();
    assert_eq!(
        sampled,
        [
            "point3f[] points.timeSamples = {",
            "float3[] extent.timeSamples = {",
            "float[] primvars:bond_hydrogen.timeSamples = {",
            "float[] primvars:wetness.timeSamples = {",
        ]
    );
}

/// The final wetness and hydrogen rates of a bake, and each vertex's
/// position.
fn final_groom(dir: &TestDir, timeline: String) -> Groom {
    std::fs::write(dir.path("t.toml"), timeline).unwrap();
    dir.run_ok(&["bake", "t.toml", "-q"]);
    importers::read(&dir.path("final.usda")).unwrap()
}

const FINAL: &str = "[[export]]\npath = \"final.usda\"\nwhat = \"final\"\n";

/// blow_dry: the blower's air reaches the whole swatch and dries it; the
/// same hair in the room's still air (the blower taken away) stays wet.
#[test]
fn a_blow_dry_dries_where_the_air_reaches_and_a_sheltered_control_stays_wet() {
    let dir = TestDir::new();
    let timeline = with_exports("blow_dry.toml", 6, FINAL);
    let blown = final_groom(&dir, timeline.clone());
    let wetness = floats(&blown.attributes, "wetness");
    let hydrogen = floats(&blown.attributes, "bond_hydrogen");
    let (_, wettest) = span(wetness);
    eprintln!(
        "blow_dry: wetness at most {wettest}, hydrogen median {}",
        median(hydrogen)
    );
    assert!(wettest < 0.1, "{wettest}");
    assert!(median(hydrogen) > 0.9);

    let blower_line = timeline
        .lines()
        .find(|l| l.starts_with("blower = "))
        .expect("the blower");
    let sheltered = final_groom(&dir, timeline.replace(blower_line, ""));
    let wetness = floats(&sheltered.attributes, "wetness");
    let hydrogen = floats(&sheltered.attributes, "bond_hydrogen");
    let (driest, _) = span(wetness);
    eprintln!(
        "blow_dry, no blower: wetness at least {driest}, hydrogen median {}",
        median(hydrogen)
    );
    assert!(driest > 0.5, "{driest}");
    assert!(median(hydrogen) < 0.5);
}

/// bangs: a blower from the front dries the bangs it reaches.
#[test]
fn the_blown_bangs_end_dry() {
    let dir = TestDir::new();
    let text = std::fs::read_to_string(sample("bangs.toml")).unwrap();
    let (head, _) = text.split_at(text.find("[[export]]").unwrap());
    std::fs::copy(
        sample("hairutil_Bangs_100.hair"),
        dir.path("hairutil_Bangs_100.hair"),
    )
    .unwrap();
    let head = match head.find("[preview]") {
        Some(at) => &head[..at],
        None => head,
    };
    let bangs = final_groom(&dir, format!("{head}{FINAL}"));
    let wetness = floats(&bangs.attributes, "wetness");
    let hydrogen = floats(&bangs.attributes, "bond_hydrogen");
    let (_, wettest) = span(wetness);
    eprintln!(
        "bangs: wetness at most {wettest}, hydrogen median {} ({}..{})",
        median(hydrogen),
        span(hydrogen).0,
        span(hydrogen).1
    );
    assert!(wettest < 0.1, "{wettest}");
    assert!(median(hydrogen) > 0.9);
}

/// `stiffness` is the paper model's: on the physical model it is refused
/// with its place, before any work.
#[test]
fn a_key_the_model_does_not_use_is_refused() {
    let dir = TestDir::new();
    std::fs::write(
        dir.path("t.toml"),
        "[groom]\ngenerate = { strands = 2, layout = \"swatch\" }\n[material]\nstiffness = 0.9\n\
         [[stage]]\nkind = \"settle\"\nduration = 0.1\n",
    )
    .unwrap();
    let message = dir.run_fail(&["validate", "t.toml"], 2);
    assert!(
        message.contains("t.toml:4:13")
            && message.contains("`stiffness`")
            && message.contains("physical model"),
        "{message}"
    );
    std::fs::write(
        dir.path("p.toml"),
        "[groom]\ngenerate = { strands = 2, layout = \"swatch\" }\n[material]\nmodel = \"paper\"\n\
         youngs_modulus = 3e9\n[[stage]]\nkind = \"settle\"\nduration = 0.1\n",
    )
    .unwrap();
    let message = dir.run_fail(&["validate", "p.toml"], 2);
    assert!(
        message.contains("`youngs_modulus`") && message.contains("paper model"),
        "{message}"
    );
    std::fs::write(
        dir.path("q.toml"),
        "[groom]\ngenerate = { strands = 2, layout = \"swatch\" }\n[solver]\n\
         quaternion_mass_scale = 0.5\n[[stage]]\nkind = \"settle\"\nduration = 0.1\n",
    )
    .unwrap();
    let message = dir.run_fail(&["validate", "q.toml"], 2);
    assert!(
        message.contains("q.toml:4:25") && message.contains("`quaternion_mass_scale`"),
        "{message}"
    );
    // The drying air is a dry stage's, and not beside drying_time.
    std::fs::write(
        dir.path("d.toml"),
        "[groom]\ngenerate = { strands = 2, layout = \"swatch\" }\n\
         [[stage]]\nkind = \"dry\"\nduration = 0.1\ndrying_time = 0.05\nair_speed = 2.0\n",
    )
    .unwrap();
    let message = dir.run_fail(&["validate", "d.toml"], 2);
    assert!(
        message.contains("`air_speed`") && message.contains("drying_time"),
        "{message}"
    );
}

/// The wind stage moves the hair without the rod solver: no sag-free start,
/// so no sag-free warning.
#[test]
fn the_wind_sample_prints_no_sag_free_warning() {
    let dir = TestDir::new();
    let text = std::fs::read_to_string(sample("wind.toml")).unwrap();
    let (head, _) = text.split_at(text.find("[[export]]").unwrap());
    let head = head.replace("strands = 10199", "strands = 300");
    std::fs::write(
        dir.path("t.toml"),
        format!("{head}[[export]]\npath = \"w.usda\"\nwhat = \"final\"\n"),
    )
    .unwrap();
    let output = dir.run_ok(&["bake", "t.toml", "-q", "--report", "r.json"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    let report = std::fs::read_to_string(dir.path("r.json")).unwrap();
    assert!(!stderr.contains("cannot stand"), "{stderr}");
    assert!(!report.contains("sag-free"), "{report}");
}
