//! The blower on strands: it dries the hydrogen bonds where it blows, and
//! its push falls off with its length in metres, not behind its nozzle nor
//! outside its cone.

use crate::sim::math::V3;
use crate::sim::tests::{arc_points, groom_of};
use crate::sim::*;

#[test]
fn a_blower_dries_hydrogen_bonds_where_it_blows() {
    // (21): db_hyd = 0.003 |dv_w| per step while b_hyd < 1.
    let mut set =
        StrandSet::from_groom(&groom_of(arc_points(24, 0.0)), &Material::default()).unwrap();
    set.set_all_bond_rates(BondKind::Hydrogen, 0.0);
    let mut solver = Solver::new(SolverParameters::default()).unwrap();
    let blower = Blower {
        falloff_length: 1.0,
        cone_half_angle: None,
        from: [0.1, 0.0, -0.5],
        to: [0.1, 0.0, 0.0],
        strength: 40.0,
        hydrogen_rate: 0.003,
    };
    let env = Environment {
        gravity: Gravity::Off,
        blower: Some(blower),
        ..Environment::default()
    };
    let colliders = ColliderSet::new();
    let before = set.positions().to_vec();
    solver.step(&mut set, &colliders, &env).unwrap();
    let rates = set.bond_rates(BondKind::Hydrogen);
    // The wind is along +z, across the strand (along +x): sin(theta) = 1,
    // d = |x - 0.1| off the axis.
    for (j, rate) in rates.iter().enumerate().take(24).skip(1) {
        let d = (before[j][0] - 0.1f32).abs();
        let dv = 40.0 / ((d + 1.0) * (d + 1.0)) / 360.0;
        assert!(
            (rate - 0.003 * dv).abs() < 1e-7,
            "joint {j}: {rate} vs {}",
            0.003 * dv
        );
    }
    // And it pushes the hair downwind.
    assert!(set.positions()[24][2] > 0.0);
}

#[test]
fn blower_falls_off_with_a_length_in_metres_and_not_behind_or_outside_its_cone() {
    let blower = |falloff_length: f32, cone_half_angle: Option<f32>| Blower {
        from: [0.0; 3],
        to: [1.0, 0.0, 0.0],
        strength: 10.0,
        hydrogen_rate: 0.0,
        falloff_length,
        cone_half_angle,
    };
    let across = [0.0, 1.0, 0.0];
    let dv = |b: &Blower, p: V3| super::blower::blower_dv(b, p, across, 1.0)[0];
    let on_axis = dv(&blower(0.1, None), [0.3, 0.0, 0.0]);
    let off_axis = dv(&blower(0.1, None), [0.3, 0.3, 0.0]);
    // d = 30 cm with a 10 cm length scale: (3 + 1)^2 = 16 times weaker.
    assert!(
        (on_axis / off_axis - 16.0).abs() < 1e-3,
        "{on_axis} {off_axis}"
    );
    // The paper's formula read in metres barely falls over 30 cm.
    let paper = dv(&blower(1.0, None), [0.3, 0.3, 0.0]) / on_axis;
    assert!((paper - 1.0 / 1.69).abs() < 1e-4, "{paper}");
    assert_eq!(dv(&blower(0.1, None), [-0.3, 0.0, 0.0]), 0.0);
    assert_eq!(dv(&blower(0.1, Some(30.0)), [0.3, 0.3, 0.0]), 0.0);
    assert!(dv(&blower(0.1, Some(60.0)), [0.3, 0.3, 0.0]) > 0.0);
}
