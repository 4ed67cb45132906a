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
    let head = with_strand_count(head, strands);
    format!("{head}[[export]]\npath = \"final.glb\"\nwhat = \"final\"\n")
}

/// `text` with the generator's `strands = N` set to `strands`.
fn with_strand_count(text: &str, strands: usize) -> String {
    let key = "strands = ";
    let start = text.find(key).expect("a generated groom") + key.len();
    let digits = text[start..]
        .find(|c: char| !c.is_ascii_digit())
        .expect("a strand count");
    format!("{}{strands}{}", &text[..start], &text[start + digits..])
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

/// Where the tips of a swatch hang at the start: straight down from the
/// root by the strand's length (the swatch generator's groom).
fn hanging_tips(groom: &Groom, length: f32) -> Vec<[f32; 3]> {
    groom
        .strands()
        .map(|s| [s[0][0], s[0][1] - length, s[0][2]])
        .collect()
}

/// How far a press moved the tips and how much of it they keep, averaged
/// over the strands: `pushed` the distance of the tips from `starts` while
/// pressed, `kept` the part of their displacement after release that lies
/// along each strand's own push (negative if the set points the other
/// way), and both displacements' mean vectors.
struct TipPush {
    strands: usize,
    pushed: f64,
    kept: f64,
    pushed_mean: [f64; 3],
    kept_mean: [f64; 3],
}

fn tip_push(starts: &[[f32; 3]], pressed: &Groom, released: &Groom) -> TipPush {
    let mut out = TipPush {
        strands: starts.len(),
        pushed: 0.0,
        kept: 0.0,
        pushed_mean: [0.0; 3],
        kept_mean: [0.0; 3],
    };
    let tips = |g: &Groom| -> Vec<[f32; 3]> { g.strands().map(|s| s[s.len() - 1]).collect() };
    let (pressed, released) = (tips(pressed), tips(released));
    assert_eq!(
        (pressed.len(), released.len()),
        (starts.len(), starts.len())
    );
    let n = starts.len() as f64;
    for ((s, p), r) in starts.iter().zip(&pressed).zip(&released) {
        let push: [f64; 3] = std::array::from_fn(|k| (p[k] - s[k]) as f64);
        let keep: [f64; 3] = std::array::from_fn(|k| (r[k] - s[k]) as f64);
        let size = distance(*p, *s);
        out.pushed += size / n;
        out.kept += (0..3).map(|k| keep[k] * push[k]).sum::<f64>() / size.max(1e-12) / n;
        for k in 0..3 {
            out.pushed_mean[k] += push[k] / n;
            out.kept_mean[k] += keep[k] / n;
        }
    }
    out
}

/// Mean distance of the tips from where they hang at the start.
fn mean_tip_displacement(groom: &Groom, length: f32) -> f64 {
    let starts = hanging_tips(groom, length);
    let tips = groom.strands().map(|s| s[s.len() - 1]);
    starts
        .iter()
        .zip(tips)
        .map(|(s, t)| distance(*s, t))
        .sum::<f64>()
        / starts.len() as f64
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
    let push = tip_push(&hanging_tips(&pressed, 0.04), &pressed, &released);
    let held = push.pushed;
    let kept = mean_tip_displacement(&released, 0.04);
    eprintln!(
        "bed_hair: tips {:.2} cm from the start under the pillow, {:.2} cm after release: {:.2}; \
         {:.2} cm along the push: {:.2}",
        held * 100.0,
        kept * 100.0,
        kept / held,
        push.kept * 100.0,
        push.kept / held
    );
    // The pillow pressed the hair visibly (4 cm strands).
    assert!(held > 0.015, "{held}");
    assert!(kept >= 0.25 * held, "kept {kept} of {held}");
    // The way the pillow pushed them, not mirrored.
    assert!(
        push.kept >= 0.2 * held,
        "kept {} along the push of {held}",
        push.kept
    );
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
/// their light frames far past their edges; src/sim/rod/direct/constants.rs
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

/// The full head (guides only, fewer of them: without hair-hair the guides
/// do not interact, and the generator grows the same first strands for any
/// count): the pillow flattens the left side while the hair dries, and
/// after release, under gravity, that side keeps a share of the push in the
/// direction the pillow pushed it.
#[test]
fn full_head_keeps_the_pillow_side_flattened_after_release_under_gravity() {
    let guides_only = |t: String| {
        let start = t.find("render = {").expect("render hair");
        let end = start + t[start..].find('\n').unwrap() + 1;
        format!("{}{}", &t[..start], &t[end..])
    };
    let released_timeline = variant("full_head.toml", 300, guides_only);
    // The start: the generated groom (the sag-free start holds it there).
    let dir = TestDir::new();
    let timeline =
        groombake::timeline::Timeline::parse(&dir.path("t.toml"), released_timeline.clone())
            .expect("the sample parses");
    let start = groombake::timeline::bake::load_groom(&timeline).expect("the generated groom");
    // The pillow holds from 0.9 s to the end of the dry stage and only then
    // leaves: the end of the dry stage is the most it pushes.
    let pressed = bake_final(&variant("full_head.toml", 300, |t| {
        without_stage(guides_only(t), "release")
    }));
    let released = bake_final(&released_timeline);

    // The strands rooted on the pillow's side of the head.
    let side = |g: &Groom| -> Groom {
        let kept: Vec<Vec<[f32; 3]>> = g
            .strands()
            .zip(start.strands())
            .filter(|(_, s)| s[0][0] < -0.06)
            .map(|(strand, _)| strand.to_vec())
            .collect();
        Groom::from_strands(&kept)
    };
    let starts: Vec<[f32; 3]> = side(&start).strands().map(|s| s[s.len() - 1]).collect();
    let push = tip_push(&starts, &side(&pressed), &side(&released));
    let count = push.strands;
    let (pushed, kept) = (push.pushed, push.kept);
    let (pushed_x, kept_x) = (push.pushed_mean[0], push.kept_mean[0]);
    eprintln!(
        "full_head: {count} strands on the pillow side; tips {:.2} cm from the start under the pillow \
         ({:.2} cm toward +X), after release {:.2} cm along the push ({:.2} cm toward +X): {:.2}",
        pushed * 100.0,
        pushed_x * 100.0,
        kept * 100.0,
        kept_x * 100.0,
        kept / pushed
    );
    assert!(count >= 20, "{count} strands on the pillow side");
    // The pillow pushed the left side visibly, toward the head (+X).
    assert!(pushed > 0.02, "{pushed}");
    assert!(
        pushed_x > 0.5 * pushed,
        "pushed {pushed_x} toward +X of {pushed}"
    );
    // After release the tips keep a quarter of the push, the same way.
    assert!(kept >= 0.25 * pushed, "kept {kept} of {pushed}");
    assert!(
        kept_x >= 0.2 * pushed_x,
        "kept {kept_x} toward +X of {pushed_x}"
    );
}
