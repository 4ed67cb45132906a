//! The shipped samples show the set (issue 10, point 7), on the physical
//! model and under gravity. Each test bakes the sample's own timeline with
//! fewer strands (the strands of a swatch do not interact, so each behaves
//! as in the full sample) and final-pose exports in place of the sample's.

use crate::util::{sample, TestDir};
use groom::Groom;

/// The sample's timeline with `strands` strands and only a final export
/// to `final.glb`; `edit` changes the text first.
fn variant(name: &str, strands: usize, edit: impl Fn(String) -> String) -> String {
    let text = std::fs::read_to_string(sample(name)).unwrap();
    let text = edit(text);
    let (head, _) = text.split_at(text.find("[[export]]").expect("an export"));
    let head = head.replacen(
        &format!("strands = {}", if name == "perm.toml" { 100 } else { 200 }),
        &format!("strands = {strands}"),
        1,
    );
    assert!(head.contains(&format!("strands = {strands}")), "{name}");
    format!("{head}[[export]]\npath = \"final.glb\"\nwhat = \"final\"\n")
}

/// Bakes `timeline` in a fresh directory and reads its final pose.
fn bake_final(timeline: &str) -> Groom {
    let dir = TestDir::new();
    std::fs::write(dir.path("t.toml"), timeline).unwrap();
    dir.run_ok(&["bake", "t.toml", "-q"]);
    importers::read(&dir.path("final.glb")).unwrap()
}

/// Drops the `[[stage]]` of this kind.
fn without_stage(text: String, kind: &str) -> String {
    let marker = format!("[[stage]]\nkind = \"{kind}\"");
    let start = text.find(&marker).expect("the stage");
    let end = text[start + marker.len()..]
        .find("\n[[")
        .map_or(text.len(), |e| start + marker.len() + e + 1);
    format!("{}{}", &text[..start], &text[end..])
}

fn distance(a: [f32; 3], b: [f32; 3]) -> f64 {
    (0..3)
        .map(|k| (a[k] - b[k]) as f64)
        .map(|d| d * d)
        .sum::<f64>()
        .sqrt()
}

/// Mean distance of the tips from where they hang at the start: straight
/// down from the root by the strand's length (the swatch generator's
/// groom).
fn mean_tip_displacement(groom: &Groom, length: f32) -> f64 {
    let mut total = 0.0;
    let mut count = 0;
    for s in groom.strands() {
        let root = s[0];
        let start = [root[0], root[1] - length, root[2]];
        total += distance(s[s.len() - 1], start);
        count += 1;
    }
    total / count as f64
}

#[test]
fn bed_hair_keeps_its_bend_after_release_under_gravity() {
    // The largest displacement of the bake is while the pillow holds the
    // hair (it only rises, holds, then drops away): the end of the dry
    // stage, before the release.
    let pressed = bake_final(&variant("bed_hair.toml", 8, |t| {
        without_stage(t, "release")
    }));
    let released = bake_final(&variant("bed_hair.toml", 8, |t| t));
    let held = mean_tip_displacement(&pressed, 0.04);
    let kept = mean_tip_displacement(&released, 0.04);
    eprintln!(
        "bed_hair: tips {:.2} cm from the start under the pillow, {:.2} cm after release: {:.2}",
        held * 100.0,
        kept * 100.0,
        kept / held
    );
    // The pillow pressed the hair visibly (4 cm strands).
    assert!(held > 0.015, "{held}");
    assert!(kept >= 0.25 * held, "kept {kept} of {held}");
}

/// Coherent turns of a polyline: `|sum of the rotation vectors between
/// consecutive edges| / 2 pi`. A helix counts its turns; a zig-zag, whose
/// bends cancel, counts 0.
fn turns(points: &[[f32; 3]]) -> f64 {
    let edges: Vec<[f64; 3]> = points
        .windows(2)
        .map(|w| {
            let d: [f64; 3] = std::array::from_fn(|k| (w[1][k] - w[0][k]) as f64);
            let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            d.map(|c| c / n)
        })
        .collect();
    let mut sum = [0.0f64; 3];
    for e in edges.windows(2) {
        let (a, b) = (e[0], e[1]);
        let axis = [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ];
        let sin = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
        let cos = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        if sin > 1e-12 {
            let angle = sin.atan2(cos);
            for k in 0..3 {
                sum[k] += axis[k] / sin * angle;
            }
        }
    }
    (sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]).sqrt() / std::f64::consts::TAU
}

fn mean_turns(groom: &Groom) -> f64 {
    let all: Vec<f64> = groom.strands().map(turns).collect();
    all.iter().sum::<f64>() / all.len() as f64
}

#[test]
fn turns_count_a_helix_and_not_a_zig_zag() {
    let helix: Vec<[f32; 3]> = (0..=200)
        .map(|i| {
            let a = i as f32 * 0.1;
            [a.cos(), a.sin(), 0.05 * a]
        })
        .collect();
    let expected = 20.0 / std::f64::consts::TAU;
    assert!((turns(&helix) - expected).abs() < 0.05, "{}", turns(&helix));
    // An even number of bends: they cancel pairwise.
    let zig: Vec<[f32; 3]> = (0..=41).map(|i| [i as f32, (i % 2) as f32, 0.0]).collect();
    assert!(turns(&zig) < 0.05, "{}", turns(&zig));
}

/// Also the regression of fine edges on a small rod at dt 1/360: the
/// sample's 5 mm edges on 1 cm rods blew up at that step (the solve turned
/// their light frames far past their edges; src/sim/step.rs
/// `FRAME_INERTIA_SPEED`), so the sample ran at 1/1000.
#[test]
fn perm_strands_are_coils_after_release_under_gravity() {
    let text = std::fs::read_to_string(sample("perm.toml")).unwrap();
    assert!(
        text.contains("dt = \"1/360\""),
        "perm.toml runs at dt 1/360"
    );
    assert!(
        text.contains("segment_length = 0.005"),
        "perm.toml's 5 mm edges"
    );
    // On the rod: the same timeline with the set phase running to the end
    // of the perm stage (the rods never unroll) and no release.
    let wound = bake_final(&variant("perm.toml", 4, |t| {
        let t = without_stage(t, "release");
        let t2 = t.replace("phases = [0.3, 0.4, 0.8]", "phases = [0.3, 0.4, 1.0]");
        assert_ne!(t, t2, "perm.toml's phases");
        t2
    }));
    let released = bake_final(&variant("perm.toml", 4, |t| t));
    let on_rod = mean_turns(&wound);
    let after = mean_turns(&released);
    let longest_edge = released
        .strands()
        .flat_map(|s| s.windows(2).map(|w| distance(w[0], w[1])))
        .fold(0.0f64, f64::max);
    eprintln!(
        "perm: {on_rod:.2} turns on the rod, {after:.2} after release ({:.2}); edges up to {:.1} mm",
        after / on_rod,
        longest_edge * 1000.0
    );
    assert!(on_rod > 1.5, "the rod made {on_rod} turns");
    assert!(after >= 0.5 * on_rod, "kept {after} of {on_rod} turns");
    assert!(longest_edge <= 0.01, "{longest_edge}");
    // Every edge of the wound and the released strands within 1 % of its
    // 5 mm rest length.
    let strain = [&wound, &released]
        .iter()
        .flat_map(|g| g.strands())
        .flat_map(|s| {
            s.windows(2)
                .map(|w| (distance(w[0], w[1]) / 0.005 - 1.0).abs())
        })
        .fold(0.0f64, f64::max);
    eprintln!("perm: max |edge/rest - 1| {:.3} %", strain * 100.0);
    assert!(strain <= 0.01, "edges strained {:.2} %", strain * 100.0);
}
