use super::*;

#[test]
fn penalty_pushes_apart_only_other_strands_within_two_radii() {
    let positions = vec![
        [0.0, 0.0, 0.0],
        [0.0, -0.01, 0.0],
        [1e-5, 0.0, -0.005],
        [1e-5, 0.0, 0.005],
    ];
    let offsets = [0, 2, 4];
    let mut grid = EdgeGrid::default();
    grid.build(&positions, &offsets, &[true, true], 4e-5, 0.01);
    let dv = grid.penalty_dv(0, 1.0, 1.0);
    // Distance 1e-5 of 8e-5: (8 - 1) / 8 away from the other edge (-x).
    assert!((dv[0] + 7.0 / 8.0).abs() < 1e-5, "{dv:?}");
    // The other strand's vertices lie 5 mm off: untouched.
    assert_eq!(grid.penalty_dv(2, 1.0, 1.0), [0.0; 3]);
    // The far end of the first strand: untouched.
    assert_eq!(grid.penalty_dv(1, 1.0, 1.0), [0.0; 3]);
}

/// Scattered strands of long edges, many within `2r` of each other.
fn tangle(strands: usize, vertices: usize) -> (Vec<V3>, Vec<usize>) {
    let mut positions = Vec::new();
    let mut offsets = vec![0];
    let mut seed = 12345u32;
    let mut next = || {
        seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (seed >> 8) as f32 / (1u32 << 24) as f32
    };
    for _ in 0..strands {
        let mut p = [next() * 0.004, next() * 0.004, next() * 0.004];
        let dir = [next() - 0.5, next() - 0.5, next() - 0.5];
        for _ in 0..vertices {
            positions.push(p);
            p = [
                p[0] + 0.003 * dir[0] + 0.001 * (next() - 0.5),
                p[1] + 0.003 * dir[1] + 0.001 * (next() - 0.5),
                p[2] + 0.003 * dir[2] + 0.001 * (next() - 0.5),
            ];
        }
        offsets.push(positions.len());
    }
    (positions, offsets)
}

/// (20) summed over every edge of every other active strand, in edge
/// order.
fn brute_force(
    positions: &[V3],
    offsets: &[usize],
    active: &[bool],
    vertex: usize,
    radius: f32,
) -> V3 {
    let strand = offsets.partition_point(|&o| o <= vertex) - 1;
    let mut dv = [0.0f32; 3];
    if !active[strand] {
        return dv;
    }
    for (s, w) in offsets.windows(2).enumerate() {
        if s == strand || !active[s] {
            continue;
        }
        for v in w[0]..w[1] - 1 {
            let (a, b) = (positions[v], positions[v + 1]);
            if let Some(push) = edge_push(positions[vertex], a, b, 2.0 * radius) {
                dv = [dv[0] + push[0], dv[1] + push[1], dv[2] + push[2]];
            }
        }
    }
    dv
}

/// Builds the grid three times (its cell size adapts to the last
/// build) and checks every vertex's sum against brute force, bit for
/// bit; returns how many vertices touched another strand.
fn check_against_brute_force(
    positions: &[V3],
    offsets: &[usize],
    active: &[bool],
    rest_longest: f32,
) -> (usize, EdgeGrid) {
    let radius = 1e-4;
    let mut grid = EdgeGrid::default();
    let mut touching = 0;
    let mut cells = Vec::new();
    for _ in 0..3 {
        grid.build(positions, offsets, active, radius, rest_longest);
        cells.push(1.0 / grid.inv_cell);
        touching = 0;
        for v in 0..positions.len() {
            let expected = brute_force(positions, offsets, active, v, radius);
            let got = grid.penalty_dv(v, 1.0, 1.0);
            if expected != [0.0; 3] {
                touching += 1;
            }
            assert_eq!(
                got.map(f32::to_bits),
                expected.map(f32::to_bits),
                "vertex {v} with cells {cells:?}: {got:?} vs {expected:?}"
            );
        }
    }
    (touching, grid)
}

#[test]
fn the_grid_finds_exactly_the_pairs_brute_force_finds() {
    let (mut positions, offsets) = tangle(60, 12);
    // Over-stretched edges: a vertex pulled 2 cm off (an edge crossing
    // many cells), and one pulled half a metre off through the tangle
    // (too many cells: it tests every vertex).
    positions[offsets[3] + 5][1] += 0.02;
    positions[offsets[7] + 4] = [0.5, 0.002, 0.002];
    let active: Vec<bool> = (0..60).map(|s| s % 11 != 5).collect();
    let (touching, grid) = check_against_brute_force(&positions, &offsets, &active, 0.003);
    // The test means something only if vertices touched other strands
    // and a torn edge was too long to walk.
    assert!(touching > 30, "{touching}");
    assert!(grid.long_edges > 0);
    assert!(1.0 / grid.inv_cell < 0.003);
}

#[test]
fn many_torn_strands_make_bigger_cells_not_a_long_list_to_scan() {
    let (mut positions, offsets) = tangle(200, 8);
    for s in 0..100 {
        positions[offsets[s] + 3] = [1.0 + s as f32 * 0.01, 0.5, 0.001];
    }
    let (touching, grid) = check_against_brute_force(&positions, &offsets, &[true; 200], 0.003);
    assert!(touching > 30, "{touching}");
    assert!(grid.long_edges <= MAX_LONG_EDGES);
}

#[test]
fn the_grid_is_bit_identical_for_any_thread_count() {
    let (positions, offsets) = tangle(400, 16);
    let active: Vec<bool> = (0..400).map(|s| s % 7 != 3).collect();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut grid = EdgeGrid::default();
            grid.build(&positions, &offsets, &active, 1e-4, 0.003);
            let mut out = Vec::new();
            for v in 0..positions.len() {
                let dv = grid.penalty_dv(v, 5.0, 1.0 / 360.0);
                out.extend(dv.map(f32::to_bits));
            }
            out
        })
    };
    let one = run(1);
    assert!(one.iter().any(|b| *b != 0));
    assert_eq!(one, run(2));
    assert_eq!(one, run(3));
}

#[test]
fn a_moving_tangle_matches_brute_force_every_step_on_any_thread_count() {
    let (mut positions, offsets) = tangle(150, 12);
    let active = vec![true; 150];
    let radius = 1e-4;
    let mut grids: Vec<EdgeGrid> = (0..2).map(|_| EdgeGrid::default()).collect();
    let mut pushed = 0;
    for step in 0..6 {
        // Each strand drifts its own way: cells, home entries and
        // the cost model's cell size change from step to step.
        for (s, w) in offsets.windows(2).enumerate() {
            for p in &mut positions[w[0]..w[1]] {
                let phase = (s * 7 + step) as f32;
                p[0] += 3e-4 * phase.sin();
                p[1] += 2e-4 * phase.cos();
            }
        }
        for (threads, grid) in [1, 2].into_iter().zip(&mut grids) {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| grid.build(&positions, &offsets, &active, radius, 0.003));
            for v in 0..positions.len() {
                let expected = brute_force(&positions, &offsets, &active, v, radius);
                let got = grid.penalty_dv(v, 1.0, 1.0);
                assert_eq!(
                    got.map(f32::to_bits),
                    expected.map(f32::to_bits),
                    "step {step}, {threads} thread(s), vertex {v}"
                );
                pushed += usize::from(expected != [0.0; 3]);
            }
        }
    }
    assert!(pushed > 100, "{pushed}");
}

#[test]
fn a_tangle_with_too_many_pushes_sums_edge_by_edge_to_the_same_bits() {
    let (positions, offsets) = tangle(60, 12);
    let active = vec![true; 60];
    let mut grid = EdgeGrid {
        max_pairs: 1,
        ..EdgeGrid::default()
    };
    let (touching, _) = check_against_brute_force(&positions, &offsets, &active, 0.003);
    grid.build(&positions, &offsets, &active, 1e-4, 0.003);
    // The bounded path was taken, and it sums what brute force does.
    assert!(grid.overflow.iter().any(|&o| o));
    assert!(touching > 30, "{touching}");
    for v in 0..positions.len() {
        let expected = brute_force(&positions, &offsets, &active, v, 1e-4);
        assert_eq!(
            grid.penalty_dv(v, 1.0, 1.0).map(f32::to_bits),
            expected.map(f32::to_bits),
            "vertex {v}"
        );
    }
}
