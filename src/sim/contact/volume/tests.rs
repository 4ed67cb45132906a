use super::*;
use crate::sim::{ColliderSet, Environment, Gravity, Material, Solver, SolverParameters};
use groom::Groom;

/// A dense bundle: `side` x `side` straight strands 0.4 mm apart,
/// hanging from roots in the XZ plane, 10 vertices over 3 cm.
fn bundle(side: usize) -> crate::sim::StrandSet {
    let strands: Vec<Vec<V3>> = (0..side * side)
        .map(|k| {
            let (x, z) = ((k % side) as f32 * 4e-4, (k / side) as f32 * 4e-4);
            (0..10).map(|i| [x, -0.003 * i as f32, z]).collect()
        })
        .collect();
    let mut groom = Groom::from_strands(strands);
    groom.units = groom::Units::METERS;
    crate::sim::StrandSet::from_groom(&groom, &Material::default()).unwrap()
}

/// Mean |v_x| over the free vertices after one step of the bundle
/// whose strands move +x and -x in turn at 0.5 m/s.
fn mean_crossing_speed(volumetric: Option<Volumetric>) -> f32 {
    mean_crossing_speed_of(volumetric, 1.0)
}

/// [`mean_crossing_speed`] with fibres `thicker` times the default.
fn mean_crossing_speed_of(volumetric: Option<Volumetric>, thicker: f32) -> f32 {
    let mut set = bundle(8);
    for r in &mut set.radii {
        *r *= thicker;
    }
    for (strand, w) in set.offsets.clone().windows(2).enumerate() {
        let sign = if strand % 2 == 0 { 1.0 } else { -1.0 };
        for v in &mut set.velocities[w[0] + 1..w[1]] {
            *v = [0.5 * sign, 0.0, 0.0];
        }
    }
    let mut solver = Solver::new(SolverParameters {
        volumetric,
        ..SolverParameters::default()
    })
    .unwrap();
    let quiet = Environment {
        gravity: Gravity::Off,
        ..Environment::default()
    };
    solver.step(&mut set, &ColliderSet::new(), &quiet).unwrap();
    let mut sum = 0.0;
    let mut count = 0;
    for w in set.offsets.windows(2) {
        for v in &set.velocities[w[0] + 1..w[1]] {
            sum += v[0].abs();
            count += 1;
        }
    }
    sum / count as f32
}

#[test]
fn a_dense_bundle_moves_together_only_in_the_volumetric_mode() {
    let volumetric = Volumetric {
        smoothing: 200.0,
        repulsion: 0.0,
        ..Volumetric::default()
    };
    let with = mean_crossing_speed(Some(volumetric));
    let without = mean_crossing_speed(None);
    // Strands moving through each other keep most of their speed
    // without it (their roots and stiffness hold back some); the
    // grid's mean motion of the bundle is near zero, and each step takes
    // 1 - exp(-200 / 360) = 43 % of the difference away.
    assert!(without > 0.25, "{without}");
    assert!(with < 0.65 * without, "{with} vs {without}");
}

/// Grid friction (issue 33) filters a vertex's velocity toward the
/// grid's in proportion to the hair's volume fraction: off, the
/// strands cross at full speed; on, they slow, and four times as much
/// hair volume (fibres twice as thick) slows them about four times as
/// much (at `grid_friction` 1000: by 1.1 % and 4.5 % in a step).
#[test]
fn grid_friction_slows_crossing_hair_in_proportion_to_its_density() {
    let settings = |friction| {
        Some(Volumetric {
            smoothing: 0.0,
            repulsion: 0.0,
            friction,
            ..Volumetric::default()
        })
    };
    let free = mean_crossing_speed_of(settings(0.0), 1.0);
    let thin = mean_crossing_speed_of(settings(5000.0), 1.0);
    let thick = mean_crossing_speed_of(settings(5000.0), 2.0);
    let free_thick = mean_crossing_speed_of(settings(0.0), 2.0);
    eprintln!(
        "crossing speed: free {free} / {free_thick}, grid friction: thin {thin}, thick {thick}"
    );
    assert!(thin < 0.97 * free, "{thin} vs {free}");
    let (slowed_thin, slowed_thick) = (1.0 - thin / free, 1.0 - thick / free_thick);
    assert!(
        slowed_thick > 2.5 * slowed_thin,
        "slowed {slowed_thin} (thin), {slowed_thick} (thick)"
    );
}

/// RMS distance of the tips from the bundle's axis after `seconds`.
fn tip_spread(volumetric: Option<Volumetric>, seconds: f32) -> f32 {
    let mut set = bundle(8);
    let mut solver = Solver::new(SolverParameters {
        volumetric,
        ..SolverParameters::default()
    })
    .unwrap();
    let steps = (seconds / solver.parameters().dt) as usize;
    for _ in 0..steps {
        solver
            .step(&mut set, &ColliderSet::new(), &Environment::default())
            .unwrap();
    }
    let centre = 3.5 * 4e-4;
    let mut sum = 0.0;
    for w in set.offsets.windows(2) {
        let tip = set.positions[w[1] - 1];
        sum += (tip[0] - centre).powi(2) + (tip[2] - centre).powi(2);
    }
    (sum / (set.offsets.len() - 1) as f32).sqrt()
}

#[test]
fn a_dense_bundle_spreads_out_of_its_own_density_only_in_the_volumetric_mode() {
    let volumetric = Volumetric {
        cell_size: 0.002,
        smoothing: 0.0,
        repulsion: 200.0,
        friction: 0.0,
    };
    let with = tip_spread(Some(volumetric), 0.1);
    let without = tip_spread(None, 0.1);
    assert!(with > 1.2 * without, "{with} vs {without}");
}

#[test]
fn morton_codes_interleave_the_bits_of_x_y_and_z() {
    let naive = |cell: [u32; 3]| {
        (0..21).fold(0u64, |code, bit| {
            (0..3).fold(code, |code, axis| {
                code | (u64::from(cell[axis] >> bit & 1) << (3 * bit + 2 - axis))
            })
        })
    };
    for cell in [
        [0, 0, 0],
        [1, 0, 0],
        [0, 1, 0],
        [0, 0, 1],
        [0x1f_ffff; 3],
        [12345, 678, 1_048_577],
    ] {
        assert_eq!(morton(cell), naive(cell), "{cell:?}");
    }
}

#[test]
fn the_volume_grid_is_bit_identical_for_any_thread_count() {
    let set = bundle(12);
    let mut velocities = set.velocities.clone();
    for (i, v) in velocities.iter_mut().enumerate() {
        *v = [(i % 7) as f32 * 0.1 - 0.3, (i % 3) as f32 * 0.05, 0.2];
    }
    let active: Vec<bool> = (0..144).map(|s| s % 5 != 2).collect();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut grid = VolumeGrid::default();
            grid.build(
                Instructions::of_this_cpu(),
                &set.positions,
                &velocities,
                &set.radii,
                &set.offsets,
                &active,
                &Volumetric::default(),
                1.0 / 360.0,
            );
            set.offsets
                .windows(2)
                .enumerate()
                .flat_map(|(s, w)| (0..w[1] - w[0]).map(move |k| (s, k)))
                .flat_map(|(s, k)| grid.dv(s, k).map(f32::to_bits))
                .collect::<Vec<u32>>()
        })
    };
    let one = run(1);
    assert!(one.iter().any(|b| *b != 0));
    assert_eq!(one, run(2));
    assert_eq!(one, run(3));
}

/// The gather eight slots at a time in the lanes, in AVX2 and (where
/// the CPU has it) AVX-512, gives the bits of the gather one slot at a
/// time: random nodes (some empty, some with a negative or non-finite
/// volume), places on and off the grid, and velocities with infinities
/// and NaNs, over strands of uneven length.
#[cfg(target_arch = "x86_64")]
#[test]
fn the_gather_in_lanes_is_the_gather_one_slot_at_a_time() {
    let widest = Instructions::of_this_cpu();
    if !widest.avx2() {
        eprintln!("no AVX2 on this CPU: no lanes to test");
        return;
    }
    let mut next = crate::sim::test_sequence(0x2545_f491_4f6c_dd1d);
    let grid = Placement {
        origin: [0.0; 3],
        inv_cell: 200.0,
        dims: [5, 6, 7],
    };
    let special = [0.0, -0.0, -1e-9, f32::INFINITY, f32::NAN, 1e30];
    let nodes: Vec<Node> = (0..grid.node_count())
        .map(|k| Node {
            volume: if k % 5 == 0 {
                special[k / 5 % special.len()]
            } else {
                next() * 1e-9
            },
            flow: [next() - 0.5, next() - 0.5, next() * 1e-9],
        })
        .collect();
    let offsets: Vec<usize> = [0, 13, 40, 41, 90, 203, 230].to_vec();
    let vertices = *offsets.last().unwrap();
    let mut slots = 0;
    let starts: Vec<usize> = std::iter::once(0)
        .chain(offsets.windows(2).map(|w| {
            slots += w[1] - w[0];
            slots
        }))
        .collect();
    let order: Vec<u32> = (0..offsets.len() as u32 - 1).collect();
    let places: Vec<Place> = (0..vertices)
        .map(|i| {
            if i % 11 == 3 {
                return Place {
                    first: Place::OFF,
                    fraction: [0.0; 3],
                };
            }
            let base = [0, 1, 2].map(|c| (next() * (grid.dims[c] - 1) as f32) as usize);
            Place {
                first: grid.index(base.map(|b| b.min(3))) as u32,
                fraction: [next(), next(), next()],
            }
        })
        .collect();
    let velocities: Vec<V3> = (0..vertices)
        .map(|i| match i % 17 {
            5 => [f32::NAN, 0.0, 0.0],
            9 => [0.0, f32::INFINITY, 0.0],
            _ => [next() - 0.5, next() - 0.5, next() - 0.5],
        })
        .collect();
    let gather = |instructions, friction| Gather {
        instructions,
        grid,
        nodes: &nodes,
        places: &places,
        velocities: &velocities,
        order: &order,
        starts: &starts,
        offsets: &offsets,
        keep: 0.05,
        push: 0.03,
        friction,
        scale: 1e6,
    };
    let bits = |out: &[V3]| {
        out.iter()
            .flat_map(|v| v.map(f32::to_bits))
            .collect::<Vec<_>>()
    };
    let wider = [Instructions::Avx2, Instructions::Avx512];
    for instructions in wider.into_iter().filter(|i| *i <= widest) {
        // (Grid friction off and on: a share of 0.3 per unit node volume.)
        for (first, friction) in [(0, 0.0), (3, 0.0), (8, 0.3), (100, 0.3), (5, 0.3)] {
            let mut one = vec![[1.0; 3]; vertices - first];
            gather(Instructions::Baseline, friction).chunk(first, &mut one);
            let mut lanes = vec![[2.0; 3]; vertices - first];
            gather(instructions, friction).chunk(first, &mut lanes);
            assert_eq!(
                bits(&one),
                bits(&lanes),
                "{instructions:?} from slot {first}, friction {friction}"
            );
            assert!(one.iter().any(|v| v[0] != 0.0));
        }
    }
}
