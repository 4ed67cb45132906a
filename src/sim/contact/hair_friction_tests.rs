//! Coulomb friction between hairs (issue 33, item 1): stick and slip of a
//! strand lying across a bed of fixed parallel strands on a slope.

use crate::sim::*;

/// What a run of [`across_a_bed`] measured.
struct Slide {
    /// The largest distance any vertex moved from its start, m.
    largest: f64,
    /// The mean downhill displacement of the far quarter of the strand
    /// after each step, m.
    far: Vec<f64>,
}

/// A 40 cm strand of real hair (1 cm edges) lying level across 40 fixed
/// strands that run down a slope tilted `angle` (radians) about the
/// strand's line, one under the middle of each of its edges, touching it
/// (centres two hair radii apart); its root moved with the strand's mean
/// motion, no damping; hair-hair friction `mu`, `seconds` at dt 1/360.
fn across_a_bed(angle: f64, mu: f32, seconds: f32) -> Slide {
    let (length, edges, radius) = (0.4f32, 40usize, 4e-5f32);
    let a = angle as f32;
    // The slope's normal and its downhill direction (tilted about z).
    let normal = [-a.sin(), a.cos(), 0.0];
    let downhill = [-a.cos(), -a.sin(), 0.0];
    let strand: Vec<[f32; 3]> = (0..=edges)
        .map(|i| [0.0, 0.0, length * i as f32 / edges as f32])
        .collect();
    let mut strands = vec![strand.clone()];
    for k in 1..=edges {
        // Under the middle of each edge (the contacts are inside edges),
        // from 2 cm uphill to 20 cm downhill of the strand, 1 cm edges.
        let middle = math::scale(math::add(strand[k - 1], strand[k]), 0.5);
        let centre = math::sub(middle, math::scale(normal, 2.0 * radius));
        strands.push(
            (0..=22)
                .map(|j| math::add(centre, math::scale(downhill, 0.01 * j as f32 - 0.02)))
                .collect(),
        );
    }
    let mut groom = groom::Groom::from_strands(strands);
    groom.units = groom::Units::METERS;
    let mut set = StrandSet::from_groom(&groom, &Material::default()).unwrap();
    // The bed is fixed: every vertex held where it is.
    for s in 1..=edges {
        let range = set.strand_range(s).unwrap();
        for v in 0..range.len() {
            let p = set.positions()[range.start + v];
            set.set_kinematic_target(s, v, Some(p)).unwrap();
        }
    }
    let parameters = SolverParameters {
        dt: 1.0 / 360.0,
        iterations: 5,
        hair_radius: radius,
        linear_damping: 0.0,
        angular_damping: 0.0,
        hair_hair_strength: Some(5.0),
        hair_friction: Some(mu),
        ..SolverParameters::default()
    };
    let mut solver = Solver::new(parameters).unwrap();
    let start = set.positions()[..=edges].to_vec();
    let mut largest = 0.0f64;
    let mut far = Vec::new();
    for step in 0..(seconds / parameters.dt).round() as usize {
        // The root follows the strand's mean motion (a strand clamped at
        // a fixed root arcs as it slides, and its elasticity then drives
        // the far end), so the strand slides as a free one would.
        let mean = (1..=edges).fold([0.0f32; 3], |sum, v| {
            math::add(sum, math::sub(set.positions()[v], start[v]))
        });
        let mean = math::scale(mean, 1.0 / edges as f32);
        set.set_root_transform(&Pose::from_translation(parry3d::math::Vector::new(
            mean[0], mean[1], mean[2],
        )));
        let report = solver
            .step(&mut set, &ColliderSet::new(), &Environment::default())
            .unwrap();
        assert!(report.contained.is_empty(), "step {step}: {report:?}");
        for (p, s) in set.positions()[..=edges].iter().zip(&start) {
            largest = largest.max(math::length(math::sub(*p, *s)) as f64);
        }
        let far_vertices = 3 * edges / 4..=edges;
        let count = far_vertices.clone().count() as f64;
        far.push(
            far_vertices
                .map(|v| math::dot(math::sub(set.positions()[v], start[v]), downhill) as f64)
                .sum::<f64>()
                / count,
        );
    }
    Slide { largest, far }
}

/// Stick and slip on hair (issue 33): across the bed the strand stays
/// within 0.1 mm for 1 s where `tan theta < 0.95 mu`, and beyond `1.05
/// mu` slides with Coulomb's acceleration `g (sin theta - mu cos theta)`
/// (within 5 %), for mu 0.1, 0.3 and 0.5. The acceleration is the second
/// difference of the far quarter's downhill displacement at 0.1, 0.2 and
/// 0.3 s (so a start-up transient of the first steps does not count).
#[test]
fn a_strand_across_hair_sticks_inside_the_cone_and_slides_at_the_coulomb_rate() {
    let g = SolverParameters::default().gravity[1].abs() as f64;
    let dt = SolverParameters::default().dt as f64;
    for mu in [0.1f64, 0.3, 0.5] {
        let held = across_a_bed((0.95 * mu).atan(), mu as f32, 1.0);
        eprintln!(
            "mu {mu}: tan 0.95 mu held within {:.4} mm in 1 s",
            held.largest * 1e3
        );
        assert!(
            held.largest < 1e-4,
            "mu {mu}: moved {} m under static friction",
            held.largest
        );
        for ratio in [1.05, 1.5] {
            let angle = (ratio * mu).atan();
            let slid = across_a_bed(angle, mu as f32, 0.3);
            let coulomb = g * (angle.sin() - mu * angle.cos());
            let at = |seconds: f64| slid.far[(seconds / dt).round() as usize - 1];
            let acceleration = (at(0.3) - 2.0 * at(0.2) + at(0.1)) / (0.1f64 * 0.1);
            eprintln!(
                "mu {mu}: tan {ratio} mu slid {:.2} mm in 0.3 s at {acceleration:.4} m/s^2 (Coulomb {coulomb:.4}: {:+.1} %)",
                at(0.3) * 1e3,
                (acceleration / coulomb - 1.0) * 100.0,
            );
            assert!(
                (acceleration / coulomb - 1.0).abs() <= 0.05,
                "mu {mu}, tan {ratio} mu: slid at {acceleration} m/s^2, Coulomb {coulomb}"
            );
        }
    }
}

/// A strand hung over a fixed horizontal rod (a collider of friction `mu`,
/// radius 1.5 cm, along z): two 10 cm legs and the half turn between
/// them, 2.5 mm edges, a soft string (E 10 MPa: its bending stiffness is
/// about 1 % of the tension over the rod). End masses are emulated by the
/// legs' weight: leg 1 weighs `k1` times its own, leg 2 `ratio * k1`
/// times (an extra acceleration on their vertices), the wrapped part
/// nothing (so the tensions at the rod are the legs' weights, and the
/// capstan law holds as for a weightless rope). The root, at the bottom of
/// leg 1, moves with vertex 1 (so that end is free). Returns how far the end
/// of leg 2 moved down in `seconds`.
fn capstan(mu: f32, ratio: f32, seconds: f32) -> f64 {
    use parry3d::math::{Rot3, Vector};
    use parry3d::shape::SharedShape;
    let (rod, radius, leg, edge) = (0.015f32, 4e-5f32, 0.1f32, 0.0025f32);
    let around = rod + radius;
    let mut points: Vec<[f32; 3]> = Vec::new();
    let legs = (leg / edge).round() as usize;
    // Leg 1 up the left side (x = -around), from its end to the rod's
    // height.
    for i in 0..legs {
        points.push([-around, -leg + edge * i as f32, 0.0]);
    }
    let turn = (std::f32::consts::PI * around / edge).round() as usize;
    let first_wrapped = points.len();
    for i in 0..=turn {
        let a = std::f32::consts::PI * (1.0 - i as f32 / turn as f32);
        points.push([around * a.cos(), around * a.sin(), 0.0]);
    }
    let last_wrapped = points.len() - 1;
    for i in 1..=legs {
        points.push([around, -edge * i as f32, 0.0]);
    }
    let mut groom = groom::Groom::from_strands([points.clone()]);
    groom.units = groom::Units::METERS;
    let material = Material {
        youngs_modulus: 1.0e7,
        ..Material::default()
    };
    let mut set = StrandSet::from_groom(&groom, &material).unwrap();
    let parameters = SolverParameters {
        dt: 1.0 / 360.0,
        iterations: 5,
        hair_radius: radius,
        linear_damping: 0.0,
        angular_damping: 0.0,
        ..SolverParameters::default()
    };
    let g = parameters.gravity;
    let k1 = 3.0f32;
    let extra: Vec<[f32; 3]> = (0..points.len())
        .map(|i| {
            let weight = if i < first_wrapped {
                k1
            } else if i <= last_wrapped {
                0.0
            } else {
                ratio * k1
            };
            math::scale(g, weight - 1.0)
        })
        .collect();
    let mut solver = Solver::new(parameters).unwrap();
    let mut colliders = ColliderSet::new();
    colliders.insert(Collider::new(
        "rod",
        SharedShape::cylinder(0.05, rod),
        Pose::from_parts(
            Vector::new(0.0, 0.0, 0.0),
            Rot3::from_axis_angle(Vector::new(1.0, 0.0, 0.0), std::f32::consts::FRAC_PI_2),
        ),
        mu,
    ));
    let environment = Environment {
        extra_acceleration: Some(&extra),
        ..Environment::default()
    };
    let start = set.positions().to_vec();
    for step in 0..(seconds / parameters.dt).round() as usize {
        // The root moves as vertex 1 is about to (where it is, on at its
        // velocity): that end is free.
        let moved = math::add(
            math::sub(set.positions()[1], start[1]),
            math::scale(set.velocities()[1], parameters.dt),
        );
        set.set_root_transform(&Pose::from_translation(Vector::new(
            moved[0], moved[1], moved[2],
        )));
        let report = solver.step(&mut set, &colliders, &environment).unwrap();
        assert!(report.contained.is_empty(), "step {step}: {report:?}");
    }
    let end = points.len() - 1;
    f64::from(start[end][1] - set.positions()[end][1])
}

/// The capstan law (issue 33) with the colliders' Coulomb friction: the
/// strand stays put while `T2 / T1 < 0.95 e^(mu pi)` and slides beyond
/// `1.05 e^(mu pi)`, for friction 0.2 and 0.5.
///
/// Fails today (mu 0.2: the heavy end moves 48 mm in 1 s at 0.95 of the
/// ratio, 60 mm at 1.05): the colliders' friction measures the normal
/// force as the push from the predicted position, which is the weight
/// pressing a vertex on a surface but not the tension pulling a wrapped
/// string onto it (the solve pulls the vertex in and the projection puts
/// it back: no push from the prediction, so no friction). Hair-to-collider
/// friction is unchanged by issue 33's item 1; this test is kept for the
/// fix (the normal force from the contact's share of the solve).
#[test]
#[ignore = "collider friction does not see a wrapped string's tension (see the doc)"]
fn a_strand_over_a_rod_holds_below_the_capstan_ratio_and_slides_above_it() {
    for mu in [0.2f32, 0.5] {
        let law = (mu * std::f32::consts::PI).exp();
        let held = capstan(mu, 0.95 * law, 1.0);
        let slid = capstan(mu, 1.05 * law, 1.0);
        eprintln!(
            "mu {mu}: e^(mu pi) = {law:.3}; at 0.95 of it the heavy end moved {:.3} mm in 1 s, at 1.05 {:.2} mm",
            held * 1e3,
            slid * 1e3
        );
        assert!(held.abs() < 1e-3, "mu {mu}: held end moved {held} m");
        assert!(slid > 1e-2, "mu {mu}: heavy end moved only {slid} m");
    }
}

/// A contact a fiftieth of the way along a root edge (its first vertex
/// pinned) pushes the free vertex at most as far as the overlap: the
/// contact point cannot be levered out by swinging that vertex by
/// `overlap / s` (half a millimetre here, a twentieth of the edge).
#[test]
fn a_contact_next_to_a_root_does_not_swing_the_root_edge() {
    use super::hair_friction::{project, HairContact, VertexContact};
    let (distance, overlap, s) = (8e-5f32, 1e-5f32, 0.02f32);
    let contact = HairContact {
        edge: 0,
        s,
        other: [s * 0.01, -distance + overlap, 0.0],
        other_velocity: [0.0; 3],
        normal: [0.0, 1.0, 0.0],
    };
    let start = [[0.0, 0.0, 0.0], [0.01, 0.0, 0.0]];
    let mut p = start;
    let mut normals = [[0.0; 3]; 2];
    let mut touch = [VertexContact::default(); 2];
    project(
        &[contact],
        &mut touch,
        &mut p,
        &[0.0, 1.0],
        &mut normals,
        distance,
        1.0 / 360.0,
        0.0,
    );
    let moved = math::length(math::sub(p[1], start[1]));
    eprintln!(
        "overlap {:.1} um at s = {s}: vertex 1 moved {:.1} um",
        overlap * 1e6,
        moved * 1e6
    );
    assert_eq!(p[0], start[0]);
    assert!(moved > 0.0 && moved <= overlap, "vertex 1 moved {moved} m");
}

/// Largest relative change of an edge's length from `rest` in `p`.
fn worst_strain(p: &[[f32; 3]], rest: &[[f32; 3]], offsets: &[usize]) -> f32 {
    let mut worst = 0.0f32;
    for w in offsets.windows(2) {
        for i in w[0]..w[1] - 1 {
            let l = math::length(math::sub(p[i + 1], p[i]));
            let l0 = math::length(math::sub(rest[i + 1], rest[i]));
            worst = worst.max((l / l0 - 1.0).abs());
        }
    }
    worst
}

/// A dense tuft: 120 strands of 10 cm real hair (1 cm edges) rooted in a
/// 4 x 4 mm patch of a level scalp, leaving it at random angles (so their
/// root edges cross within a hair's width of one another), fall under
/// gravity for 0.3 s with hair-hair friction 0.3. No edge strains beyond
/// 1 % (measured 0.1 %). The old contact push levered root edges out by
/// `overlap / s` and the tuft blew up (edges 5e5 times their length; in a
/// swatch of 200 strands combed over a cylinder, root edges strained 23 %
/// in 0.2 s); with that fixed, putting stuck vertices back after the last
/// solve however far it had moved them still strained edges 1.9 % (tips of
/// the swatch 12 %).
#[test]
fn a_dense_tuft_with_hair_friction_keeps_its_edges() {
    let mut random = crate::generate::SplitMix64::new(3);
    let mut next = || random.next_f64() as f32;
    let (strands, edges, length) = (120usize, 10usize, 0.1f32);
    let mut grown = Vec::new();
    for _ in 0..strands {
        let root = [0.004 * next() - 0.002, 0.0, 0.004 * next() - 0.002];
        let (tilt, azimuth) = (0.2 + 1.0 * next(), std::f32::consts::TAU * next());
        let d = [
            tilt.sin() * azimuth.cos(),
            tilt.cos(),
            tilt.sin() * azimuth.sin(),
        ];
        grown.push(
            (0..=edges)
                .map(|i| math::add(root, math::scale(d, length * i as f32 / edges as f32)))
                .collect::<Vec<_>>(),
        );
    }
    let mut groom = groom::Groom::from_strands(grown);
    groom.units = groom::Units::METERS;
    let mut set = StrandSet::from_groom(&groom, &Material::default()).unwrap();
    let parameters = SolverParameters {
        dt: 1.0 / 360.0,
        hair_radius: 4e-5,
        hair_hair_strength: Some(5.0),
        hair_friction: Some(0.3),
        ..SolverParameters::default()
    };
    let offsets: Vec<usize> = (0..=strands).map(|s| s * (edges + 1)).collect();
    let rest = set.positions().to_vec();
    let mut solver = Solver::new(parameters).unwrap();
    let mut worst = 0.0f32;
    for _ in 0..108 {
        let report = solver
            .step(&mut set, &ColliderSet::new(), &Environment::default())
            .unwrap();
        assert!(report.contained.is_empty(), "{report:?}");
        worst = worst.max(worst_strain(set.positions(), &rest, &offsets));
    }
    eprintln!("dense tuft: worst edge strain {:.3} %", worst * 100.0);
    assert!(worst < 0.01, "an edge strained {} %", worst * 100.0);
}
