//! A hairstyle that holds (issue 33): a swatch of long real hair combed
//! over a cylinder the size of a head, wetted, pressed flat by a slab,
//! dried under it and released under gravity keeps part of the slab's push
//! with hair-hair friction on, and less with it off.
//!
//! The scene (metres, Y up): a cylinder collider of radius 9 cm along Z
//! (the head); `STRANDS` hairs of 24 cm (1 cm edges, E 3.5 GPa, r 40 um,
//! real hair) rooted just off its surface over the crown, between 95 and
//! 125 degrees from +X and 3 cm either side of the middle along Z, each
//! leaving its root toward +X (combed over the top) at 10 to 30 degrees
//! above the surface, straight (its rest shape). The timeline is what a TD
//! writes (`timeline` below): a settle of 1 s under gravity (the hair
//! drapes over the cylinder; the roots' stiffness holds the hair near
//! them off the surface), wet, a slab (a box) coming down onto the crown
//! to 1.5 mm above the cylinder's top by t = 2 s, dried under it (hydrogen
//! bonds re-form remembering the pressed shape), lifted away by t = 3.8 s,
//! and 3 s more under gravity.
//!
//! **Share of the push kept**: the outer hair surface over the crown is the
//! 98th percentile of the height `y - R` (above the cylinder's top line) of
//! the hair's vertices over the pressed region, `|x| < 2 cm` and `|z| < 2 cm`
//! (the middle of the swatch, where the slab lay flat on it); measured at
//! the end of the wet stage (`before`, t = 1.3 s, the slab not yet down),
//! at the end of the dry stage under the slab (`under`, t = 3.5 s) and 3 s
//! after the slab left (`after`, t = 6.8 s), the share kept is
//! `(before - after) / (before - under)`: 1 if the hair stays as flat as the
//! slab left it, 0 if it springs back to where it stood.

use crate::util::TestDir;

/// Strands in the swatch (see the module doc and the test for the scale).
const STRANDS: usize = 200;
/// Cylinder radius, m.
const RADIUS: f32 = 0.09;
const LENGTH: f32 = 0.24;
const EDGES: usize = 24;

/// A small deterministic generator (SplitMix64), so the groom is the same
/// on every machine.
struct Random(u64);

impl Random {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 40) as f32 / (1u64 << 24) as f32
    }

    fn between(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.next()
    }
}

/// The swatch combed over the cylinder, as an `.obj` of polylines.
fn swatch_obj(strands: usize) -> String {
    let mut random = Random(1);
    let mut vertices = String::new();
    let mut lines = String::new();
    let mut index = 1;
    for _ in 0..strands {
        let phi = random.between(95.0, 125.0).to_radians();
        let z = random.between(-0.03, 0.03);
        let lift = random.between(10.0, 30.0).to_radians();
        let r0 = RADIUS + 2e-4;
        let root = [r0 * phi.cos(), r0 * phi.sin()];
        // Along the surface toward +X (decreasing phi), lifted off it.
        let (tangent, normal) = ([phi.sin(), -phi.cos()], [phi.cos(), phi.sin()]);
        let d = [0, 1].map(|k| tangent[k] * lift.cos() + normal[k] * lift.sin());
        let mut line = String::from("l");
        for i in 0..=EDGES {
            let s = LENGTH * i as f32 / EDGES as f32;
            vertices.push_str(&format!(
                "v {:.7} {:.7} {:.7}\n",
                root[0] + d[0] * s,
                root[1] + d[1] * s,
                z
            ));
            line.push_str(&format!(" {}", index + i));
        }
        lines.push_str(&line);
        lines.push('\n');
        index += EDGES + 1;
    }
    format!("# a swatch combed over a cylinder of radius {RADIUS} m\n{vertices}{lines}")
}

/// The timeline, with `hair_hair` as given.
fn timeline(hair_hair: &str) -> String {
    format!(
        r#"# A swatch combed over a head-sized cylinder, pressed flat by a slab
# while it dries, released under gravity.
seed = 1

[groom]
source = "swatch.obj"
units = "m"

[material]
radius = 4e-5
bonds = {{ hydrogen = 0.33, ionic = 0.30, disulfide = 0.20, peptide = 0.17 }}

[solver]
dt = "1/360"
hair_radius = 4e-5
# The groom is straight hair before it drapes (its natural shape), not a
# shape to hold against gravity.
sag_free = false
{hair_hair}

[[collider]]
name = "head"
shape = {{ cylinder = {{ half_height = 0.1, radius = {RADIUS} }} }}
friction = 0.3
motion = [{{ t = 0.0, rotation = [90.0, 0.0, 0.0] }}]

# The slab: its bottom face 2 cm below its centre, down to 1.5 mm above
# the cylinder's top, held while the hair dries, lifted away.
[[collider]]
name = "slab"
active = "listed"
shape = {{ cuboid = {{ half_extents = [0.06, 0.02, 0.06] }} }}
friction = 0.5
motion = [
  {{ t = 1.3, translation = [0.0, 0.16, 0.0] }},
  {{ t = 2.0, translation = [0.0, 0.1115, 0.0] }},
  {{ t = 3.5, translation = [0.0, 0.1115, 0.0] }},
  {{ t = 3.8, translation = [0.0, 0.20, 0.0] }},
]

[[stage]]
kind = "settle"
duration = 1.0

[[stage]]
kind = "wet"
duration = 0.3

[[stage]]
kind = "press"
duration = 0.7
colliders = ["slab"]

[[stage]]
kind = "dry"
duration = 1.5
colliders = ["slab"]
drying_time = 1.0

[[stage]]
kind = "release"
duration = 3.3
colliders = ["slab"]

[[export]]
path = "anim.abc"
what = "animated"
fps = 10
"#
    )
}

/// The outer hair surface over the pressed region: the 98th percentile of
/// `y - R` over the vertices (roots excluded) with `|x|, |z| < 2 cm`, m.
fn outer_surface(points: &[[f32; 3]], counts: &[u32]) -> f64 {
    let mut heights = Vec::new();
    let mut start = 0usize;
    for &n in counts {
        for p in &points[start + 1..start + n as usize] {
            if p[0].abs() < 0.02 && p[2].abs() < 0.02 {
                heights.push(f64::from(p[1] - RADIUS));
            }
        }
        start += n as usize;
    }
    assert!(
        heights.len() > 100,
        "{} vertices over the crown",
        heights.len()
    );
    heights.sort_by(f64::total_cmp);
    heights[(0.98 * (heights.len() - 1) as f64).round() as usize]
}

/// The heights before the press, under the slab and 3 s after release, m.
struct Push {
    before: f64,
    under: f64,
    after: f64,
}

impl Push {
    fn kept(&self) -> f64 {
        (self.before - self.after) / (self.before - self.under)
    }
}

/// Bakes the scene with `hair_hair`; returns the heights and the bake's
/// warnings (a strained or frozen strand is named there).
fn bake(hair_hair: &str) -> (Push, Vec<serde_json::Value>) {
    let dir = TestDir::new();
    std::fs::write(dir.path("swatch.obj"), swatch_obj(STRANDS)).unwrap();
    std::fs::write(dir.path("t.toml"), timeline(hair_hair)).unwrap();
    dir.run_ok(&["bake", "t.toml", "-q", "--report", "r.json"]);
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path("r.json")).unwrap()).unwrap();
    let warnings = report["warnings"].as_array().cloned().unwrap_or_default();
    let groom = importers::read(&dir.path("anim.abc")).unwrap();
    let at = |t: f64| {
        let frame = groom
            .frames
            .iter()
            .min_by(|a, b| (a.time - t).abs().total_cmp(&(b.time - t).abs()))
            .unwrap();
        assert!((frame.time - t).abs() < 1e-3, "no frame at {t} s");
        outer_surface(&frame.points, &groom.strand_vertex_counts)
    };
    let push = Push {
        before: at(1.3),
        under: at(3.5),
        after: at(6.8),
    };
    (push, warnings)
}

/// See the module doc: with friction 0.3 the swatch keeps at least a
/// quarter of the push, without friction (the frictionless penalty alone)
/// less, and no strand is strained or frozen on the way.
///
/// Not met (issue 33), measured by this test at 200 strands (a tenth of
/// the issue's 2,000, the scale a test can afford: with friction on, the
/// contact search makes a 500-strand bake cost about 100 s of CPU per
/// simulated second, and 2,000 strands did not finish their first 0.1 s in
/// 5 minutes; this test takes about 2 minutes of CPU): friction on keeps
/// 0.129 of the push (outer surface 3.71 mm before, 1.46 mm under the
/// slab, 3.42 mm after), frictionless 0.165 (2.93, 1.46, 2.69); with
/// friction on, 3 strands strain an edge beyond 5 % (8.9 % at a tip) while
/// the hair drapes in the first second. Friction holds the draped hair up
/// before the press (3.71 mm against 2.93) as it holds it after; the
/// frictionless bake of all 2,000 strands keeps 0.247 (2.96, 1.46, 2.59).
#[test]
#[ignore = "friction on keeps less of the push than frictionless (see the doc)"]
fn a_pressed_swatch_keeps_its_flattened_crown_with_hair_friction() {
    let (on, on_warnings) = bake("hair_hair = { strength = 5.0, friction = 0.3 }");
    let (off, off_warnings) = bake("hair_hair = { strength = 5.0 }");
    for (name, p, w) in [
        ("friction 0.3", &on, &on_warnings),
        ("frictionless", &off, &off_warnings),
    ] {
        eprintln!(
            "{STRANDS} strands, {name}: outer surface {:.2} mm before, {:.2} mm under the slab, \
             {:.2} mm 3 s after release: {:.3} of the push kept; warnings {w:?}",
            p.before * 1e3,
            p.under * 1e3,
            p.after * 1e3,
            p.kept()
        );
    }
    // The slab pressed the crown visibly.
    assert!(
        on.before - on.under > 1e-3,
        "pushed {} m",
        on.before - on.under
    );
    assert!(on.kept() >= 0.25, "kept {} with friction", on.kept());
    assert!(
        off.kept() < on.kept() - 0.05,
        "kept {} without friction, {} with",
        off.kept(),
        on.kept()
    );
    // The numbers are of hair, not of a strained solve.
    assert_eq!(on_warnings, Vec::<serde_json::Value>::new());
    assert_eq!(off_warnings, Vec::<serde_json::Value>::new());
}
