//! The contact search against brute force, on tangles at rest, fast and
//! moving together, for any thread count.

use super::*;

/// `strands` random walks of `vertices` (edges about 2 mm) in a 1 cm
/// box, with random velocities up to 0.5 m/s, every 7th strand at
/// 20 m/s (near more cells than an edge may be listed in).
fn tangle(strands: usize, vertices: usize) -> (Vec<V3>, Vec<V3>, Vec<usize>) {
    tangle_moving(strands, vertices, [0.0; 3])
}

/// [`tangle`], all of it moving on at `drift` besides.
fn tangle_moving(strands: usize, vertices: usize, drift: V3) -> (Vec<V3>, Vec<V3>, Vec<usize>) {
    let mut random = crate::generate::SplitMix64::new(7);
    let mut next = |scale: f64| (random.next_f64() * 2.0 - 1.0) * scale;
    let (mut positions, mut velocities, mut offsets) = (Vec::new(), Vec::new(), vec![0]);
    for strand in 0..strands {
        let mut p = [0.0f32; 3].map(|_| next(0.005) as f32);
        let speed = if strand % 7 == 3 { 20.0 } else { 0.5 };
        for _ in 0..vertices {
            positions.push(p);
            let v = [0.0f32; 3].map(|_| next(speed) as f32);
            velocities.push(add(v, drift));
            p = std::array::from_fn(|k| p[k] + next(0.0012) as f32);
        }
        offsets.push(positions.len());
    }
    (positions, velocities, offsets)
}

/// Every edge against every edge of the other active strands, in edge
/// order.
fn brute_force(
    positions: &[V3],
    velocities: &[V3],
    offsets: &[usize],
    active: &[bool],
    radius: f32,
    rest_longest: f32,
    dt: f32,
) -> Vec<Vec<HairContact>> {
    let distance = 2.0 * radius;
    let mut owner = vec![u32::MAX; positions.len()];
    for (strand, w) in offsets.windows(2).enumerate() {
        if active[strand] {
            owner[w[0]..w[1]].fill(strand as u32);
        }
    }
    let fastest = velocities
        .iter()
        .zip(&owner)
        .filter(|(v, o)| **o != u32::MAX && is_finite3(**v))
        .map(|(v, _)| length(*v))
        .fold(0.0, f32::max);
    let reach = 2.0 * distance + (2.0 * fastest * dt).min(rest_longest);
    let edge_of = |v: usize| -> Option<(u32, V3, V3)> {
        let strand = owner[v];
        if strand == u32::MAX || owner.get(v + 1) != Some(&strand) {
            return None;
        }
        let (a, b) = (positions[v], positions[v + 1]);
        (is_finite3(a) && is_finite3(b)).then_some((strand, a, b))
    };
    (0..offsets.len() - 1)
        .map(|strand| {
            let mut out = Vec::new();
            for v in offsets[strand]..offsets[strand + 1] {
                let Some((own, a, b)) = edge_of(v) else {
                    continue;
                };
                for f in 0..positions.len() {
                    let Some((other, c, d)) = edge_of(f) else {
                        continue;
                    };
                    if other == own {
                        continue;
                    }
                    if let Some(c) =
                        contact(&edge_of, velocities, v, f, a, b, c, d, reach, distance, dt)
                    {
                        out.push(HairContact {
                            edge: (v - offsets[strand]) as u32,
                            ..c
                        });
                    }
                }
            }
            out
        })
        .collect()
}

#[test]
fn the_grid_finds_exactly_the_contacts_brute_force_finds_on_any_thread_count() {
    let (positions, velocities, offsets) = tangle(60, 12);
    grid_equals_brute_force(&positions, &velocities, &offsets);
}

/// Hair falling together at 3 m/s: the margins are measured against
/// the hair's mean velocity (each edge's own speed would list it in
/// every cell about it), and the search still finds every contact.
#[test]
fn the_grid_finds_exactly_the_contacts_of_hair_moving_together() {
    let (positions, velocities, offsets) = tangle_moving(60, 12, [1.0, -2.6, 1.0]);
    let owner: Vec<u32> = (0..offsets.len() - 1)
        .flat_map(|s| std::iter::repeat_n(s as u32, offsets[s + 1] - offsets[s]))
        .collect();
    let reference = reference_velocity(&velocities, &owner, 0.002, 1.0 / 360.0);
    assert!(
        length(sub(reference, [1.0, -2.6, 1.0])) < 1.0,
        "{reference:?}"
    );
    grid_equals_brute_force(&positions, &velocities, &offsets);
}

fn grid_equals_brute_force(positions: &[V3], velocities: &[V3], offsets: &[usize]) {
    let (positions, velocities, offsets) =
        (positions.to_vec(), velocities.to_vec(), offsets.to_vec());
    let strands = offsets.len() - 1;
    let active: Vec<bool> = (0..strands).map(|s| s % 11 != 5).collect();
    let (radius, rest_longest, dt) = (3e-4, 0.002, 1.0 / 360.0);
    let expected = brute_force(
        &positions,
        &velocities,
        &offsets,
        &active,
        radius,
        rest_longest,
        dt,
    );
    let total: usize = expected.iter().map(Vec::len).sum();
    let fast: usize = (0..strands)
        .filter(|s| s % 7 == 3)
        .map(|s| expected[s].len())
        .sum();
    assert!(
        total > 500 && fast > 50,
        "{total} contacts, {fast} of fast strands"
    );
    for threads in [1, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut contacts = HairContacts::default();
        // Twice: the second build reuses the first one's buffers.
        for _ in 0..2 {
            pool.install(|| {
                contacts.build(
                    &positions,
                    &velocities,
                    &offsets,
                    &active,
                    radius,
                    0.3,
                    rest_longest,
                    dt,
                )
            });
            for (strand, expected) in expected.iter().enumerate() {
                assert_eq!(contacts.of(strand), &expected[..], "strand {strand}");
            }
        }
        assert_eq!(contacts.count(), total);
    }
}

#[test]
fn crossing_segments_meet_at_their_crossing() {
    let (s, t) = closest_parameters(
        [-1.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.5, 1.0, -1.0],
        [0.5, 1.0, 3.0],
    );
    assert!(
        (s - 0.75).abs() < 1e-6 && (t - 0.25).abs() < 1e-6,
        "{s} {t}"
    );
}

#[test]
fn a_contact_point_is_pushed_out_and_held_inside_the_cone() {
    let contact = HairContact {
        edge: 0,
        s: 0.25,
        other: [0.0, 0.0, 0.0],
        other_velocity: [0.0; 3],
        normal: [0.0, 1.0, 0.0],
    };
    let start = [[-0.25, 0.1, 0.0], [0.75, 0.1, 0.0]];
    // Fell 0.2 and slid 0.01 sideways: pushed back up to 0.1 and held.
    let predicted = [[-0.24, -0.1, 0.0], [0.76, -0.1, 0.0]];
    let mut p = predicted;
    let mut normals = [[0.0; 3]; 2];
    let mut touch = [VertexContact::default(); 2];
    assert!(project(
        &[contact],
        &mut touch,
        &mut p,
        &[1.0, 1.0],
        &mut normals,
        0.1,
        0.01,
        0.0
    ));
    let point = lerp3(p[0], p[1], 0.25);
    assert!((point[1] - 0.1).abs() < 1e-6, "{p:?}");
    assert_eq!(normals, [[0.0, 1.0, 0.0]; 2]);
    friction(
        &[contact],
        &mut touch,
        &mut [false; 2],
        &mut p,
        &start,
        &predicted,
        &[1.0, 1.0],
        0.3,
        0.01,
        0.0,
    );
    let point = lerp3(p[0], p[1], 0.25);
    assert!(point[0].abs() < 1e-6, "{p:?}");
    // Slid 0.1: shortened by mu times the push (0.3 x 0.2).
    let predicted = [[-0.15, -0.1, 0.0], [0.85, -0.1, 0.0]];
    let mut p = predicted;
    project(
        &[contact],
        &mut touch,
        &mut p,
        &[1.0, 1.0],
        &mut normals,
        0.1,
        0.01,
        0.0,
    );
    friction(
        &[contact],
        &mut touch,
        &mut [false; 2],
        &mut p,
        &start,
        &predicted,
        &[1.0, 1.0],
        0.3,
        0.01,
        0.0,
    );
    let point = lerp3(p[0], p[1], 0.25);
    assert!((point[0] - 0.04).abs() < 1e-6, "{p:?}");
}
