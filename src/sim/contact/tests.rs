//! Contact that keeps edge length (issue 10, point 4): while a collider
//! presses the hair, the physical model's edges stay within 1 % of rest at
//! dt 1/360. (The perm rod's wrap and roll are in timeline/stages.rs.)
//! And the pairwise hair-hair penalty: it pushes close strands apart, and
//! a strand with an infinite vertex is contained without harm to others.

use crate::generate::{generate, GeneratorParameters, RootLayout};
use crate::sim::math::{self, V3};
use crate::sim::tests::{arc_points, head_and_pillow, metres, quiet, run};
use crate::sim::*;
use groom::Groom;
use parry3d::math::{Rot3, Vector};
use parry3d::shape::SharedShape;

/// The largest `|edge / rest - 1|` over every edge of `set`.
pub(crate) fn max_edge_strain(set: &StrandSet) -> f64 {
    let p = set.positions();
    let rest = set.rest_lengths();
    let mut worst = 0.0f64;
    for s in 0..set.strand_count() {
        let Some(range) = set.strand_range(s) else {
            continue;
        };
        for v in range.start..range.end - 1 {
            let d: f64 = (0..3)
                .map(|k| (p[v + 1][k] - p[v][k]) as f64)
                .map(|x| x * x)
                .sum::<f64>()
                .sqrt();
            worst = worst.max((d / rest[v] as f64 - 1.0).abs());
        }
    }
    worst
}

/// Whether any free vertex is within `reach` of the collider's surface.
fn touching(set: &StrandSet, collider: &Collider, reach: f32) -> bool {
    (0..set.strand_count()).any(|s| {
        let range = set.strand_range(s).unwrap_or(0..0);
        set.positions()[range.start + 1..range.end].iter().any(|p| {
            collider
                .shape
                .distance_to_point(&collider.pose, Vector::new(p[0], p[1], p[2]), false)
                <= reach
        })
    })
}

/// bed_hair's press: a swatch of 24 cm real hair (3 cm edges) hanging from
/// a bar; a pillow tilted 25 degrees rises 20 cm into it in a second, and
/// holds. Today's contact projected vertices after the last solve and
/// squeezed edges by 16 %.
#[test]
fn edges_keep_their_length_while_a_slab_presses_the_hair() {
    let groom = generate(&GeneratorParameters {
        layout: RootLayout::Swatch,
        strands: 8,
        length: 0.24,
        segment_length: 0.03,
        swatch_width: 0.08,
        head_center: [0.0, 0.30, 0.0],
        ..Default::default()
    })
    .unwrap();
    let mut set = StrandSet::from_groom(&groom, &Material::default()).unwrap();
    let parameters = SolverParameters {
        dt: 1.0 / 360.0,
        iterations: 5,
        hair_radius: 4e-5,
        ..SolverParameters::default()
    };
    let mut solver = Solver::new(parameters).unwrap();
    let tilt = Rot3::from_axis_angle(Vector::new(0.0, 0.0, 1.0), 25f32.to_radians());
    let pose_at = |y: f32| Pose::from_parts(Vector::new(0.0, y, 0.0), tilt);
    let mut colliders = ColliderSet::new();
    colliders.insert(Collider::new(
        "pillow",
        SharedShape::cuboid(0.15, 0.05, 0.15),
        pose_at(-0.10),
        0.5,
    ));
    let lowest = |set: &StrandSet| {
        set.positions()
            .iter()
            .map(|p| p[1])
            .fold(f32::MAX, f32::min)
    };
    let low_start = lowest(&set);
    let (mut worst, mut touched_steps) = (0.0f64, 0);
    for step in 0..540 {
        let t = (step + 1) as f32 * parameters.dt;
        let y = -0.10 + 0.20 * t.min(1.0);
        colliders.colliders[0].move_to(pose_at(y), parameters.dt);
        let report = solver
            .step(&mut set, &colliders, &Environment::default())
            .unwrap();
        assert!(report.contained.is_empty(), "step {step}: {report:?}");
        if touching(&set, &colliders.colliders[0], 2.0 * parameters.hair_radius) {
            touched_steps += 1;
            worst = worst.max(max_edge_strain(&set));
        }
    }
    let low_end = lowest(&set);
    eprintln!(
        "slab press: max |edge/rest - 1| {:.3} % over {touched_steps} steps in contact; the lowest point rose {:.1} cm",
        worst * 100.0,
        (low_end - low_start) * 100.0
    );
    // The test means something only if the pillow pressed the hair.
    assert!(touched_steps > 200, "{touched_steps}");
    assert!(low_end - low_start > 0.02, "{low_start} -> {low_end}");
    assert!(worst <= 0.01, "edges strained {:.2} %", worst * 100.0);
}

/// A 40 cm strand of real hair (1 cm edges) lying level across a slab
/// tilted `angle` degrees (friction `mu`), its root held, no damping (it
/// would slow the slide too): each vertex's downhill displacement after
/// each step for `seconds`, dt 1/360.
fn slide_on_slope(angle: f32, mu: f32, seconds: f32) -> Vec<Vec<f64>> {
    let (length, edges, radius) = (0.4f32, 40, 4e-5f32);
    let points: Vec<[f32; 3]> = (0..=edges)
        .map(|i| [0.0, 0.0, length * i as f32 / edges as f32])
        .collect();
    let mut groom = groom::Groom::from_strands([points]);
    groom.units = groom::Units::METERS;
    let mut set = StrandSet::from_groom(&groom, &Material::default()).unwrap();
    let parameters = SolverParameters {
        dt: 1.0 / 360.0,
        iterations: 5,
        hair_radius: radius,
        linear_damping: 0.0,
        angular_damping: 0.0,
        ..SolverParameters::default()
    };
    let mut solver = Solver::new(parameters).unwrap();
    let a = angle.to_radians();
    let tilt = Rot3::from_axis_angle(Vector::new(0.0, 0.0, 1.0), a);
    // The slab's top face (normal (-sin a, cos a, 0)) one hair radius
    // below the strand.
    let half = 0.05;
    let normal = [-a.sin(), a.cos(), 0.0];
    let center = normal.map(|c| -c * (half + radius));
    let mut colliders = ColliderSet::new();
    colliders.insert(Collider::new(
        "slope",
        SharedShape::cuboid(0.5, half, 0.5),
        Pose::from_parts(Vector::new(center[0], center[1], 0.2), tilt),
        mu,
    ));
    let downhill = [-(a.cos() as f64), -(a.sin() as f64), 0.0];
    let start = set.positions().to_vec();
    let mut history = Vec::new();
    for step in 0..(seconds / parameters.dt).round() as usize {
        let report = solver
            .step(&mut set, &colliders, &Environment::default())
            .unwrap();
        assert!(report.contained.is_empty(), "step {step}: {report:?}");
        history.push(
            set.positions()
                .iter()
                .zip(&start)
                .map(|(p, s)| (0..3).map(|k| (p[k] - s[k]) as f64 * downhill[k]).sum())
                .collect(),
        );
    }
    history
}

/// Friction that holds in the physical model: hair on a slope steeper than
/// its friction angle slides with Coulomb's kinetic acceleration, on a
/// gentler one it stays put. (Friction applied only before each solve let
/// the solve slide a resting strand on.)
#[test]
fn hair_on_a_slope_stays_put_under_static_friction_and_slides_at_the_kinetic_rate() {
    let angle = 30f32;
    // mu 0.8 > tan 30 (0.577): held.
    let held = slide_on_slope(angle, 0.8, 1.0);
    let moved = held.iter().flatten().fold(0.0f64, |m, d| m.max(d.abs()));
    // mu 0.3: g (sin a - mu cos a) downhill, measured on the far quarter
    // of the strand (the root holds the near part) over the first 0.2 s.
    let (mu, seconds) = (0.3f64, 0.2f64);
    let slid = slide_on_slope(angle, mu as f32, seconds as f32);
    let a = (angle as f64).to_radians();
    let g = SolverParameters::default().gravity[1].abs() as f64;
    let expected = 0.5 * g * (a.sin() - mu * a.cos()) * seconds * seconds;
    let last = slid.last().unwrap();
    let far = &last[3 * last.len() / 4..];
    let measured = far.iter().sum::<f64>() / far.len() as f64;
    let frictionless = 0.5 * g * a.sin() * seconds * seconds;
    eprintln!(
        "slope {angle} deg: mu 0.8 held within {:.3} mm in 1 s; mu 0.3 slid {:.2} cm in {seconds} s (Coulomb {:.2} cm, frictionless {:.2} cm)",
        moved * 1000.0,
        measured * 100.0,
        expected * 100.0,
        frictionless * 100.0
    );
    assert!(moved < 1e-3, "slid {moved} m under static friction");
    assert!(
        (measured / expected - 1.0).abs() <= 0.1,
        "slid {measured} m, Coulomb {expected} m"
    );
}

/// The full-head bench's pillow (issue 10, point 4): a slab (8 x 40 x 40 cm,
/// tilted 10 degrees) comes in from the left at the sample's speed (18 cm/s,
/// half a millimetre a step) and presses the bench groom's 24 cm hair on the
/// left of the head into the 1.5 cm gap against the head. Returns the worst
/// `|edge/rest - 1|` while the slab touches the hair, the steps it touched,
/// and how far (m) the leftmost vertex was pushed towards the head.
///
/// The tearing reported from `groombake bench --preset full-head` (edges
/// 19 times their rest length after one step) is not this: the bench puts
/// its pillow in place at the first step, across 1,795 of the 5,000
/// strands (19,390 vertices start inside the slab), and each vertex leaves
/// by the slab's nearest face, many by the far one.
fn pillow_pinch_strain(head: SharedShape) -> (f64, usize, f32) {
    let scalp = bench_groom(600, 32).unwrap();
    // Six strands rooted on the left side, where the pillow presses.
    let left: Vec<Vec<[f32; 3]>> = scalp
        .strands()
        .filter(|s| s[0][0] < -0.06 && s[0][1].abs() < 0.05)
        .take(6)
        .map(|s| s.to_vec())
        .collect();
    assert_eq!(left.len(), 6);
    let (mut set, mut solver, parameters) = real_hair_at_dt_1_360(left);
    let tilt = Rot3::from_axis_angle(Vector::Z, (-10f32).to_radians());
    let pose_at = |x: f32| Pose::from_parts(Vector::new(x, 0.0, 0.0), tilt);
    let mut colliders = ColliderSet::new();
    colliders.insert(Collider::new("head", head, Pose::IDENTITY, 0.3));
    let (start, end, speed) = (-0.40f32, -0.135f32, 0.18f32);
    colliders.insert(Collider::new(
        "pillow",
        SharedShape::cuboid(0.04, 0.2, 0.2),
        pose_at(start),
        0.6,
    ));
    let leftmost = |set: &StrandSet| {
        set.positions()
            .iter()
            .map(|p| p[0])
            .fold(f32::MAX, f32::min)
    };
    let left_start = leftmost(&set);
    let (mut worst, mut touched_steps) = (0.0f64, 0);
    let steps = ((end - start) / speed / parameters.dt) as usize + 180;
    for step in 0..steps {
        let t = (step + 1) as f32 * parameters.dt;
        let x = (start + speed * t).min(end);
        colliders.colliders[1].move_to(pose_at(x), parameters.dt);
        let report = solver
            .step(&mut set, &colliders, &Environment::default())
            .unwrap();
        assert!(report.contained.is_empty(), "step {step}: {report:?}");
        if touching(&set, &colliders.colliders[1], 2.0 * parameters.hair_radius) {
            touched_steps += 1;
            worst = worst.max(max_edge_strain(&set));
        }
    }
    (worst, touched_steps, leftmost(&set) - left_start)
}

/// Measured: 0.006 % (ball), 0.003 % (mesh) over about 210 steps in
/// contact, the hair pushed 19-20 cm towards the head.
#[test]
fn edges_keep_their_length_while_a_pillow_pins_hair_against_the_head() {
    let (vertices, triangles) = crate::sim::contact::colliders::sample_head();
    let mesh = SharedShape::trimesh(vertices, triangles).unwrap();
    for (name, head) in [("ball", SharedShape::ball(0.08)), ("mesh", mesh)] {
        let (worst, touched_steps, pushed) = pillow_pinch_strain(head);
        eprintln!(
            "pillow against the {name} head: max |edge/rest - 1| {:.3} % over {touched_steps} steps in contact, the hair pushed {:.1} cm",
            worst * 100.0,
            pushed * 100.0
        );
        // The test means something only if the pillow pressed the hair
        // into the gap (the tips start 24 cm out, the gap is 1.5 cm).
        assert!(touched_steps > 100, "{name}: {touched_steps}");
        assert!(pushed > 0.15, "{name}: pushed {pushed} m");
        assert!(
            worst <= 0.01,
            "{name}: edges strained {:.2} %",
            worst * 100.0
        );
    }
}

/// The signed distance (m) from a head's surface, negative inside.
type HeadDistance<'a> = &'a dyn Fn(V3) -> f32;

/// What a whip onto the head did: the worst `|edge/rest - 1|` and its
/// step, the vertices found inside the head (deeper than a tenth of the
/// hair radius) after any step, and the fastest vertex within 1 mm of the
/// head (m/s).
struct Whip {
    worst: f64,
    worst_step: usize,
    inside: usize,
    impact_speed: f32,
}

/// `strands` (metres) as real 40 um hair, and a solver of the physical model
/// at dt 1/360 with its default iterations, and its parameters.
fn real_hair_at_dt_1_360(strands: Vec<Vec<[f32; 3]>>) -> (StrandSet, Solver, SolverParameters) {
    let mut groom = groom::Groom::from_strands(strands);
    groom.units = groom::Units::METERS;
    let set = StrandSet::from_groom(&groom, &Material::default()).unwrap();
    let parameters = SolverParameters {
        dt: 1.0 / 360.0,
        iterations: Model::Physical.default_iterations(),
        tolerance: Model::Physical.default_tolerance(),
        hair_radius: 4e-5,
        ..SolverParameters::default()
    };
    (set, Solver::new(parameters).unwrap(), parameters)
}

/// Hair whipping onto the head (issue 10, point 4), as `groombake bench`
/// shows it: a dozen strands of the bench groom (24 cm real hair, 32
/// vertices) start straight out of the scalp, fall under gravity and hit
/// the head, at dt 1/360 and the physical model's default iterations, for
/// a second.
fn whip(head: SharedShape, distance: HeadDistance<'_>) -> Whip {
    let scalp = bench_groom(600, 32).unwrap();
    let picked: Vec<Vec<[f32; 3]>> = scalp.strands().step_by(50).map(|s| s.to_vec()).collect();
    let (mut set, mut solver, parameters) = real_hair_at_dt_1_360(picked);
    let mut colliders = ColliderSet::new();
    colliders.insert(Collider::new("head", head, Pose::IDENTITY, 0.3));
    let mut result = Whip {
        worst: 0.0,
        worst_step: 0,
        inside: 0,
        impact_speed: 0.0,
    };
    for step in 0..360 {
        let before = set.positions().to_vec();
        let report = solver
            .step(&mut set, &colliders, &Environment::default())
            .unwrap();
        assert!(report.contained.is_empty(), "step {step}: {report:?}");
        let strain = max_edge_strain(&set);
        if strain > result.worst {
            (result.worst, result.worst_step) = (strain, step);
        }
        for (p, old) in set.positions().iter().zip(&before) {
            let d = distance(*p);
            result.inside += usize::from(d < -0.1 * parameters.hair_radius);
            if d < 1e-3 {
                let speed = math::length(math::sub(*p, *old)) / parameters.dt;
                result.impact_speed = result.impact_speed.max(speed);
            }
        }
    }
    result
}

/// Measured: 14.9 % (ball) and 10.6 % (mesh) with the frames' trust
/// region at 0.1 rad per iteration; 0.035 % and 0.049 % at 0.5.
#[test]
fn edges_keep_their_length_while_hair_whips_onto_the_head() {
    use parry3d::query::PointQuery;
    use parry3d::shape::{TriMesh, TriMeshFlags};
    let (vertices, triangles) = crate::sim::contact::colliders::sample_head();
    let exact =
        TriMesh::with_flags(vertices.clone(), triangles.clone(), TriMeshFlags::ORIENTED).unwrap();
    let mesh = SharedShape::trimesh(vertices, triangles).unwrap();
    let ball_distance = |p: V3| math::length(p) - 0.08;
    let mesh_distance = |p: V3| {
        let point = Vector::new(p[0], p[1], p[2]);
        let q = exact.project_local_point(point, false);
        let d = (q.point - point).length();
        if q.is_inside {
            -d
        } else {
            d
        }
    };
    let mut failures = Vec::new();
    let cases: [(&str, SharedShape, HeadDistance<'_>); 2] = [
        ("ball", SharedShape::ball(0.08), &ball_distance),
        ("mesh", mesh, &mesh_distance),
    ];
    for (name, head, distance) in cases {
        let w = whip(head, distance);
        eprintln!(
            "hair whipping onto the {name} head at up to {:.1} m/s: max |edge/rest - 1| {:.3} % (step {}), {} vertices inside",
            w.impact_speed,
            w.worst * 100.0,
            w.worst_step,
            w.inside
        );
        // The test means something only if the hair hit the head fast.
        assert!(w.impact_speed > 2.0, "{name}: {} m/s", w.impact_speed);
        if w.worst > 0.01 || w.inside > 0 {
            failures.push(format!(
                "{name}: edges strained {:.2} %, {} vertices inside",
                w.worst * 100.0,
                w.inside
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}

#[test]
fn hair_hair_penalty_pushes_close_strands_apart() {
    // Two parallel strands 1 mm apart with a 1 mm hair radius (contact
    // below 2 mm): they separate; without the penalty they do not.
    let a = arc_points(10, 0.0);
    let b: Vec<V3> = a.iter().map(|p| [p[0], p[1], p[2] + 0.001]).collect();
    let groom = metres(Groom::from_strands([a, b]));
    let gap = |strength: Option<f32>| {
        let mut set = StrandSet::from_groom(&groom, &Material::default()).unwrap();
        let mut solver = Solver::new(SolverParameters {
            hair_radius: 1e-3,
            hair_hair_strength: strength,
            ..SolverParameters::default()
        })
        .unwrap();
        run(&mut solver, &mut set, &quiet(), 0.2);
        set.positions()[21][2] - set.positions()[10][2]
    };
    let apart = gap(Some(5.0));
    let untouched = gap(None);
    eprintln!("tip gap with penalty {apart}, without {untouched}");
    assert!((untouched - 0.001).abs() < 1e-6);
    assert!(apart > 0.0015, "{apart}");
}

#[test]
fn an_infinite_vertex_with_hair_hair_on_is_contained_without_harm() {
    let groom = generate(&GeneratorParameters {
        strands: 12,
        ..Default::default()
    })
    .unwrap();
    let mut set = StrandSet::from_groom(&groom, &Material::default()).unwrap();
    let bad = set.strand_range(5).unwrap();
    set.positions_mut()[bad.start + 7] = [f32::INFINITY, 0.0, f32::NEG_INFINITY];
    let mut solver = Solver::new(SolverParameters {
        hair_radius: 1e-3,
        hair_hair_strength: Some(5.0),
        ..SolverParameters::default()
    })
    .unwrap();
    let report = solver
        .step(&mut set, &head_and_pillow(), &Environment::default())
        .unwrap();
    assert_eq!(report.contained, vec![5]);
    for _ in 0..10 {
        let report = solver
            .step(&mut set, &head_and_pillow(), &Environment::default())
            .unwrap();
        assert!(report.contained.is_empty());
    }
    for s in (0..12).filter(|s| *s != 5) {
        let r = set.strand_range(s).unwrap();
        assert!(set.positions()[r].iter().all(|p| math::is_finite3(*p)));
    }
}
