//! Strands stepped in SIMD groups of four or eight (f32 lanes of the
//! paper model's sweep, f64 lanes of the physical model's direct solve, in
//! AVX2 or AVX-512) give each strand the bits it gets stepped alone.

use super::tests::{head_and_pillow, metres, paper};
use super::*;
use crate::generate::{generate, GeneratorParameters, StrandShape};
use groom::Groom;

#[test]
fn simd_groups_match_strands_stepped_alone_bit_for_bit() {
    // SIMD groups run the paper model's sweep in f32 lanes.
    assert_groups_match_strands_alone(&paper(), 80, 13, 3, 0.0);
}

#[test]
fn physical_simd_groups_match_strands_stepped_alone_bit_for_bit() {
    // And the physical model's direct solve in f64x4 lanes.
    assert_groups_match_strands_alone(&Material::default(), 40, 13, 3, 0.0);
}

#[test]
fn physical_wide_groups_match_strands_stepped_alone_bit_for_bit() {
    // 19 strands of one length: two groups of eight (f64x8 lanes where
    // the CPU has AVX-512, else four of four) and three alone. The step
    // has a bond drive and a blower: the groups of eight find their rest
    // shapes in lanes (`rest_eight`, driven), and the blower of each
    // strand's first 24 vertices goes eight at a time (`blow_eights`).
    assert_groups_match_strands_alone(&Material::default(), 40, 19, 1, 0.0);
}

#[test]
fn physical_wide_groups_in_a_still_step_match_strands_stepped_alone_bit_for_bit() {
    // With no drive and no blower the groups of eight find their rest
    // shapes joint by joint in lanes (`rest_eight`, still); some bonds are
    // broken, so the rest shapes mix memory and current shape.
    assert_groups_match_strands_alone_in(&Material::default(), 40, 19, 1, 0.0, true, WIDEST);
}

#[test]
fn physical_groups_in_avx2_match_strands_stepped_alone_bit_for_bit() {
    // What a CPU with AVX2 but not AVX-512 runs (checked on any CPU with
    // AVX2): groups of four in f64x4 lanes and the per-strand phases
    // compiled for AVX2, driven (with a blower) and still.
    if !Instructions::of_this_cpu().avx2() {
        eprintln!("no AVX2 on this CPU: no AVX2 path to test");
        return;
    }
    for still in [false, true] {
        let (material, avx2) = (&Material::default(), Instructions::Avx2);
        assert_groups_match_strands_alone_in(material, 40, 19, 1, 0.0, still, avx2);
    }
}

#[test]
fn strands_that_converge_first_keep_their_state_while_their_group_iterates() {
    // With a Newton tolerance strands stop after different counts: those
    // that converged keep their state bit for bit while the others of their
    // lane group iterate (and those hitting the head get their extra solve),
    // so each still gets what it gets alone.
    // (Tighter than the default, so these gently moving strands need
    // different counts.)
    let solves = assert_groups_match_strands_alone(&Material::default(), 40, 19, 1, 1e-6);
    eprintln!("{solves} solves of 19 strands in 40 steps");
    // Some strands stopped early and some did not (5 iterations at most,
    // plus one after a contact).
    assert!(
        solves > 19 * 40 && solves < 19 * 40 * 5,
        "{solves} solves of 19 strands in 40 steps"
    );
}

/// `count` strands, the `i`-th shortened by `i % lengths` vertices, with
/// the Newton `tolerance`. Returns the grouped run's solves.
fn assert_groups_match_strands_alone(
    material: &Material,
    steps: usize,
    count: usize,
    lengths: usize,
    tolerance: f32,
) -> u64 {
    assert_groups_match_strands_alone_in(material, steps, count, lengths, tolerance, false, WIDEST)
}

/// Any instructions this CPU has (the cap of `with_instructions_at_most`).
const WIDEST: Instructions = Instructions::Avx512;

/// [`assert_groups_match_strands_alone`], in a `still` step (no bond
/// drive, no blower: the rest shape's still path) with some bonds broken,
/// or with a drive, a blower and a hold; the groups in at most `widest`
/// instructions.
fn assert_groups_match_strands_alone_in(
    material: &Material,
    steps: usize,
    count: usize,
    lengths: usize,
    tolerance: f32,
    still: bool,
    widest: Instructions,
) -> u64 {
    // Mixed lengths (13 strands of 25, 24 and 23 vertices: sorted into three
    // uniform groups and one single) plus every force.
    let mut strands = Vec::new();
    for (i, strand) in generate(&GeneratorParameters {
        strands: count,
        shape: StrandShape::Wavy,
        ..Default::default()
    })
    .unwrap()
    .strands()
    .enumerate()
    {
        strands.push(strand[..strand.len() - i % lengths].to_vec());
    }
    let groom = metres(Groom::from_strands(&strands));
    let mut grouped_set = StrandSet::from_groom(&groom, material).unwrap();
    if still {
        grouped_set.set_all_bond_rates(BondKind::Hydrogen, 0.4);
        grouped_set.set_all_bond_rates(BondKind::Ionic, 0.7);
    }
    let mut alone_set = grouped_set.clone();
    let parameters = SolverParameters {
        hair_radius: 1e-3,
        hair_hair_strength: Some(3.0),
        tolerance,
        ..SolverParameters::default()
    };
    let mut grouped = Solver::new(parameters)
        .unwrap()
        .with_instructions_at_most(widest);
    // The grouped run also times its phases: the clock changes no result.
    grouped.set_phase_clock(true);
    let mut alone = Solver::new(parameters).unwrap().without_simd();
    let colliders = head_and_pillow();
    let env = if still {
        Environment::default()
    } else {
        Environment {
            blower: Some(Blower {
                falloff_length: 1.0,
                cone_half_angle: None,
                from: [0.3, 0.2, 0.0],
                to: [0.0, 0.0, 0.0],
                strength: 6.0,
                hydrogen_rate: 0.003,
            }),
            bond_rate_drive: [-0.5, 0.0, 0.0, 0.0],
            // The hold too (ramped: a different strength per vertex).
            hold: Some(Hold {
                strength: 3000.0,
                ramp: [0.2, 1.0],
            }),
            ..Environment::default()
        }
    };
    let mut solves = 0;
    let mut phases = PhaseTimes::default();
    for _ in 0..steps {
        let report = grouped.step(&mut grouped_set, &colliders, &env).unwrap();
        solves += report.solves;
        phases += report.phases.expect("the grouped run times its phases");
        let alone_report = alone.step(&mut alone_set, &colliders, &env).unwrap();
        assert_eq!(report.solves, alone_report.solves);
        assert_eq!(alone_report.phases, None, "off by default");
    }
    // Every phase took time (nanoseconds summed over the steps).
    assert!(
        phases.forces > 0 && phases.constraints > 0 && phases.bonds > 0,
        "{phases:?}"
    );
    // The whole state, bit for bit: a last-bit change in a velocity or an
    // angular velocity need not show in the positions of the next step,
    // and `==` would take -0.0 for 0.0.
    assert!(state_bits(&grouped_set) == state_bits(&alone_set));
    // They did move.
    assert!(grouped_set.positions() != groom.points.as_slice());
    solves
}

/// Every number of `set`'s state as bits, in a fixed order: positions,
/// velocities and their corrections, the edges' frames, angular velocities
/// and rest lengths, the joints' constants, bond rates and memories, the
/// wetness.
fn state_bits(set: &StrandSet) -> Vec<u32> {
    let mut bits = Vec::new();
    let mut add = |values: &[f32]| bits.extend(values.iter().map(|v| v.to_bits()));
    for v in set
        .positions
        .iter()
        .chain(&set.velocities)
        .chain(&set.velocity_corrections)
    {
        add(v);
    }
    for e in &set.edges {
        add(&e.rotation);
        add(&e.angular_velocity);
        add(&[e.rest_length]);
    }
    for j in &set.joints {
        add(&[j.stiffness, j.stiffness_prime, j.cuticle]);
        add(&j.rates);
        for m in &j.memories {
            add(m);
        }
    }
    add(&set.wetness);
    bits
}
