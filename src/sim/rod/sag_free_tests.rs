//! The sag-free start on long combed grooms (issue 33, item 2): it must
//! never make a shape worse than starting without it.

use crate::sim::math;
use crate::sim::*;
use groom::Groom;
use parry3d::math::{Pose, Vector};
use parry3d::shape::SharedShape;

/// A scalp of `length` hair combed down over a head (the groom of
/// `samples/wind.toml` before its combed head: drape 12 rad/m, 1.2 cm
/// edges), 200 strands.
fn combed_scalp(length: f32) -> Groom {
    crate::generate::generate(&crate::generate::GeneratorParameters {
        strands: 200,
        length,
        segment_length: 0.012,
        head_radii: [0.08, 0.1, 0.09],
        scalp_angle: 95.0,
        drape: 12.0,
        ..Default::default()
    })
    .unwrap()
}

/// The head the scalp grows on: the convex hull of its ellipsoid (radii
/// of `samples/wind.toml`), a hair's breadth inside the roots.
fn head() -> ColliderSet {
    let radii = [0.08f32, 0.1, 0.09];
    let (rings, around) = (24u32, 48u32);
    let mut points = vec![Vector::new(0.0, 0.998 * radii[1], 0.0)];
    for i in 1..rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..around {
            let phi = 2.0 * std::f32::consts::PI * j as f32 / around as f32;
            let u = [
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            ];
            points.push(Vector::new(
                0.998 * radii[0] * u[0],
                0.998 * radii[1] * u[1],
                0.998 * radii[2] * u[2],
            ));
        }
    }
    points.push(Vector::new(0.0, -0.998 * radii[1], 0.0));
    let bottom = points.len() as u32 - 1;
    let at = |i: u32, j: u32| 1 + (i - 1) * around + j % around;
    let mut triangles = Vec::new();
    for j in 0..around {
        triangles.push([0, at(1, j + 1), at(1, j)]);
        triangles.push([bottom, at(rings - 1, j), at(rings - 1, j + 1)]);
        for i in 1..rings - 1 {
            triangles.push([at(i, j), at(i, j + 1), at(i + 1, j)]);
            triangles.push([at(i, j + 1), at(i + 1, j + 1), at(i + 1, j)]);
        }
    }
    let mut colliders = ColliderSet::new();
    colliders.insert(Collider::new(
        "head",
        SharedShape::trimesh(points, triangles).unwrap(),
        Pose::from_parts(Vector::new(0.0, 0.0, 0.0), Default::default()),
        0.3,
    ));
    colliders
}

/// What a settle did to a groom, per strand.
struct Settled {
    /// The largest amount any joint turns beyond its groomed turn, degrees.
    beyond: Vec<f64>,
    /// The largest edge strain at any step.
    strain: f64,
}

fn turn(p: &[math::V3], k: usize) -> f64 {
    let a = math::sub(p[k], p[k - 1]);
    let b = math::sub(p[k + 1], p[k]);
    let c = (math::dot(a, b) / (math::length(a) * math::length(b))).clamp(-1.0, 1.0);
    (c as f64).acos().to_degrees()
}

fn settle(groom: &Groom, sag_free: bool, seconds: f32) -> (Settled, SagFreeReport) {
    let mut set = StrandSet::from_groom(groom, &Material::default()).unwrap();
    let parameters = SolverParameters {
        hair_radius: 4e-5,
        ..SolverParameters::default()
    };
    let colliders = head();
    let report = if sag_free {
        set.make_sag_free_with(&parameters, &colliders).unwrap()
    } else {
        SagFreeReport::default()
    };
    let groomed = set.positions().to_vec();
    let rest = set.rest_lengths();
    let mut solver = Solver::new(parameters).unwrap();
    let mut strain = 0.0f64;
    for _ in 0..(seconds / parameters.dt).round() as usize {
        solver
            .step(&mut set, &colliders, &Environment::default())
            .unwrap();
        for s in 0..set.strand_count() {
            let r = set.strand_range(s).unwrap();
            let p = &set.positions()[r.clone()];
            for (pair, rest) in p.windows(2).zip(&rest[r]) {
                let l = math::length(math::sub(pair[1], pair[0]));
                strain = strain.max((l as f64 / *rest as f64 - 1.0).abs());
            }
        }
    }
    let beyond = (0..set.strand_count())
        .map(|s| {
            let r = set.strand_range(s).unwrap();
            let (now, then) = (&set.positions()[r.clone()], &groomed[r.clone()]);
            (1..r.len() - 1)
                .map(|k| turn(now, k) - turn(then, k))
                .fold(0.0, f64::max)
        })
        .collect();
    (Settled { beyond, strain }, report)
}

fn median(v: &[f64]) -> f64 {
    let mut sorted = v.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted[sorted.len() / 2]
}

fn max(v: &[f64]) -> f64 {
    v.iter().cloned().fold(0.0, f64::max)
}

#[test]
fn sag_free_never_leaves_a_long_combed_scalp_worse() {
    for length in [0.24f32, 0.60] {
        let groom = combed_scalp(length);
        let (with, report) = settle(&groom, true, 3.0);
        let (without, _) = settle(&groom, false, 3.0);
        eprintln!(
            "combed scalp {length} m: beyond groomed turn median/worst {:.1}/{:.1} deg, strain {:.2} % with sag-free ({} unstable, {} limited, clamped {}); {:.1}/{:.1} deg, {:.2} % without",
            median(&with.beyond),
            max(&with.beyond),
            100.0 * with.strain,
            report.unstable.len(),
            report.limited.len(),
            report.clamped_joints,
            median(&without.beyond),
            max(&without.beyond),
            100.0 * without.strain,
        );
        // Never worse than starting without it: strand by strand, no joint
        // turns further beyond its groomed angle, and no edge stretches.
        for (strand, (w, o)) in with.beyond.iter().zip(&without.beyond).enumerate() {
            assert!(
                w <= &(o + 1.0),
                "{length} m, strand {strand}: {w} deg against {o}"
            );
        }
        assert!(with.strain < 0.01, "{length}: strain {}", with.strain);
    }
}
