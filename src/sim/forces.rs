//! External forces and interactions of 000 §6: the blower (19) and the
//! hair-hair penalty (20) through a uniform grid over edges. The grid is
//! built from the positions at the start of the step and only read while
//! strands are advanced in parallel (gathered, never scattered), so the
//! result does not depend on the thread count.

use super::math::{cross, dot, is_finite3, length, scale, sub, V3};
use super::Blower;

/// The blower's velocity change at a vertex, (19):
/// `alpha sin(theta) / (d + 1)^2 w_hat dt`, `theta` between the hair edge and
/// the wind, `d` the distance from the vertex to the wind axis.
#[inline]
pub fn blower_dv(blower: &Blower, position: V3, edge_direction: V3, dt: f32) -> V3 {
    let wind = sub(blower.to, blower.from);
    let wind_length = length(wind);
    let edge_length = length(edge_direction);
    if !(wind_length > 0.0 && edge_length > 0.0) {
        return [0.0; 3];
    }
    let w_hat = scale(wind, 1.0 / wind_length);
    let sin_theta = length(cross(edge_direction, w_hat)) / edge_length;
    let rel = sub(position, blower.from);
    let along = dot(rel, w_hat);
    let d = length(sub(rel, scale(w_hat, along)));
    scale(
        w_hat,
        blower.strength * sin_theta / ((d + 1.0) * (d + 1.0)) * dt,
    )
}

/// An edge in one cell.
#[derive(Debug, Clone, Copy, Default)]
struct Entry {
    /// The cell, packed by [`pack`].
    key: u64,
    /// Global index of the edge's first vertex.
    edge: u32,
    strand: u32,
}

/// Edges generated per chunk of this many vertices: fixed, so the grid's
/// order does not depend on the thread count.
const CHUNK_VERTICES: usize = 2048;
/// Cells per edge above which an edge is left out for the step (only a
/// strand torn far beyond its rest length gets there).
const MAX_CELLS_PER_EDGE: usize = 96;
/// Cells per edge length: smaller cells mean fewer far edges scanned per
/// vertex, more entries to sort (measured best at 10k and 100k strands).
const CELLS_PER_EDGE: f32 = 3.0;

/// Edges of all strands in a uniform grid of cells of about a third of the
/// longest edge (at least the interaction distance `2r`). An edge sits in
/// every cell its segment passes through (not its box, not grown by `2r`),
/// so a vertex scans the few cells its `2r` ball touches and only edges
/// that pass nearby. A vertex-edge pair found through several cells counts
/// once: in the cell holding the closest point of the edge.
///
/// Built once per step: entries are generated in parallel in fixed chunks,
/// then counting-sorted into buckets by cell (a spatial wrap-around
/// index, so a strand's consecutive cells land in nearby buckets); queries
/// only read. All buffers are kept from step to step (no allocation once
/// warm).
#[derive(Debug, Default)]
pub struct EdgeGrid {
    inv_cell: f32,
    /// Buckets per axis are `1 << axis_bits`.
    axis_bits: u32,
    starts: Vec<u32>,
    entries: Vec<Entry>,
    /// Per chunk of vertices, its edges' entries in order.
    chunks: Vec<Vec<Entry>>,
    /// Strand of each vertex whose edge is binned, `u32::MAX` otherwise.
    owner: Vec<u32>,
}

#[inline]
fn cell_of(p: V3, inv_cell: f32) -> [i32; 3] {
    // Saturating float-to-int casts keep far-away points in the end cells.
    [
        (p[0] * inv_cell).floor() as i32,
        (p[1] * inv_cell).floor() as i32,
        (p[2] * inv_cell).floor() as i32,
    ]
}

/// A cell as one key (21 bits per axis: cells alias only 2^21 cells apart,
/// which the exact distance test then rejects).
#[inline]
fn pack(cell: [i32; 3]) -> u64 {
    let m = (1u64 << 21) - 1;
    ((cell[0] as u64 & m) << 42) | ((cell[1] as u64 & m) << 21) | (cell[2] as u64 & m)
}

#[inline]
fn bucket_of(cell: [i32; 3], bits: u32) -> usize {
    let m = (1usize << bits) - 1;
    ((cell[0] as usize & m) << (2 * bits))
        | ((cell[1] as usize & m) << bits)
        | (cell[2] as usize & m)
}

/// Whether segment `a`-`b` meets the box `lo`-`hi` (slab test).
#[inline]
fn segment_meets_box(a: V3, b: V3, lo: V3, hi: V3) -> bool {
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    for c in 0..3 {
        let d = b[c] - a[c];
        if d == 0.0 {
            if a[c] < lo[c] || a[c] > hi[c] {
                return false;
            }
            continue;
        }
        let (mut u, mut v) = ((lo[c] - a[c]) / d, (hi[c] - a[c]) / d);
        if u > v {
            std::mem::swap(&mut u, &mut v);
        }
        t0 = t0.max(u);
        t1 = t1.min(v);
        if t0 > t1 {
            return false;
        }
    }
    true
}

/// The cells segment `a`-`b` passes through (each cell grown by a hair of
/// its size so round-off never loses the cell of a point on the segment),
/// in a fixed order, without repeats. `None` when there are more than
/// `MAX_CELLS_PER_EDGE`.
fn edge_cells(a: V3, b: V3, cell: f32, out: &mut [u64; MAX_CELLS_PER_EDGE]) -> Option<usize> {
    let inv = 1.0 / cell;
    let eps = cell * 1e-3;
    let lo = cell_of(
        [
            a[0].min(b[0]) - eps,
            a[1].min(b[1]) - eps,
            a[2].min(b[2]) - eps,
        ],
        inv,
    );
    let hi = cell_of(
        [
            a[0].max(b[0]) + eps,
            a[1].max(b[1]) + eps,
            a[2].max(b[2]) + eps,
        ],
        inv,
    );
    let span: i64 = (0..3)
        .map(|c| i64::from(hi[c]) - i64::from(lo[c]) + 1)
        .product();
    if !(1..=(MAX_CELLS_PER_EDGE as i64) * 8).contains(&span) {
        return None;
    }
    let mut n = 0;
    for x in lo[0]..=hi[0] {
        for y in lo[1]..=hi[1] {
            for z in lo[2]..=hi[2] {
                let min = [
                    x as f32 * cell - eps,
                    y as f32 * cell - eps,
                    z as f32 * cell - eps,
                ];
                let max = [
                    min[0] + cell + 2.0 * eps,
                    min[1] + cell + 2.0 * eps,
                    min[2] + cell + 2.0 * eps,
                ];
                if segment_meets_box(a, b, min, max) {
                    if n == MAX_CELLS_PER_EDGE {
                        return None;
                    }
                    out[n] = pack([x, y, z]);
                    n += 1;
                }
            }
        }
    }
    Some(n)
}

impl EdgeGrid {
    /// Bins the edges of the `active` strands (`offsets` as in StrandSet).
    pub fn build(&mut self, positions: &[V3], offsets: &[usize], active: &[bool], radius: f32) {
        use rayon::prelude::*;
        let reach = 2.0 * radius;
        self.owner.clear();
        self.owner.resize(positions.len(), u32::MAX);
        for (strand, w) in offsets.windows(2).enumerate() {
            if active[strand] && w[1] > w[0] + 1 {
                self.owner[w[0]..w[1] - 1].fill(strand as u32);
            }
        }
        // Cells from the longest edge (max is exact in any order).
        let owner = &self.owner;
        let longest = positions
            .par_iter()
            .enumerate()
            .with_min_len(CHUNK_VERTICES)
            .filter(|(v, _)| owner[*v] != u32::MAX)
            .map(|(v, a)| {
                let d = sub(positions[v + 1], *a);
                if is_finite3(d) {
                    d[0].abs().max(d[1].abs()).max(d[2].abs())
                } else {
                    0.0
                }
            })
            .reduce(|| 0.0, f32::max);
        let cell = (longest / CELLS_PER_EDGE).max(reach);
        self.inv_cell = 1.0 / cell;
        let chunk_count = positions.len().div_ceil(CHUNK_VERTICES);
        if self.chunks.len() < chunk_count {
            self.chunks.resize_with(chunk_count, Vec::new);
        }
        self.chunks[..chunk_count]
            .par_iter_mut()
            .enumerate()
            .for_each(|(k, out)| {
                out.clear();
                let mut cells = [0u64; MAX_CELLS_PER_EDGE];
                let first = k * CHUNK_VERTICES;
                for v in first..(first + CHUNK_VERTICES).min(positions.len()) {
                    let strand = owner[v];
                    if strand == u32::MAX {
                        continue;
                    }
                    let (a, b) = (positions[v], positions[v + 1]);
                    if !(is_finite3(a) && is_finite3(b)) {
                        continue;
                    }
                    if let Some(n) = edge_cells(a, b, cell, &mut cells) {
                        out.extend(cells[..n].iter().map(|&key| Entry {
                            key,
                            edge: v as u32,
                            strand,
                        }));
                    }
                }
            });
        let total: usize = self.chunks[..chunk_count].iter().map(Vec::len).sum();
        // About two buckets per entry, a power of two per axis.
        let mut bits = 1;
        while (1usize << (3 * bits)) < 2 * total && bits < 10 {
            bits += 1;
        }
        self.axis_bits = bits;
        let buckets = 1usize << (3 * bits);
        self.starts.clear();
        self.starts.resize(buckets + 1, 0);
        let unpack = |key: u64| -> [i32; 3] {
            let m = (1u64 << 21) - 1;
            [
                ((key >> 42) & m) as i32,
                ((key >> 21) & m) as i32,
                (key & m) as i32,
            ]
        };
        for e in self.chunks[..chunk_count].iter().flatten() {
            self.starts[bucket_of(unpack(e.key), bits) + 1] += 1;
        }
        for i in 1..self.starts.len() {
            self.starts[i] += self.starts[i - 1];
        }
        // Counting sort keeps the generation order within a bucket.
        self.entries.clear();
        self.entries.resize(total, Entry::default());
        for e in self.chunks[..chunk_count].iter().flatten() {
            let slot = &mut self.starts[bucket_of(unpack(e.key), bits)];
            self.entries[*slot as usize] = *e;
            *slot += 1;
        }
        // The cursors now hold each bucket's end: shift back to starts.
        for i in (1..self.starts.len()).rev() {
            self.starts[i] = self.starts[i - 1];
        }
        self.starts[0] = 0;
    }

    /// The penalty velocity change (20) at `p` of strand `strand` from the
    /// edges of other strands.
    pub fn penalty_dv(
        &self,
        positions: &[V3],
        p: V3,
        strand: usize,
        radius: f32,
        alpha: f32,
        dt: f32,
    ) -> V3 {
        let mut dv = [0.0f32; 3];
        if self.entries.is_empty() {
            return dv;
        }
        let reach = 2.0 * radius;
        let lo = cell_of([p[0] - reach, p[1] - reach, p[2] - reach], self.inv_cell);
        let hi = cell_of([p[0] + reach, p[1] + reach, p[2] + reach], self.inv_cell);
        if (0..3).any(|c| i64::from(hi[c]) - i64::from(lo[c]) > 2) {
            // Far-off (saturated) or non-finite coordinates.
            return dv;
        }
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    let here = [x, y, z];
                    let key = pack(here);
                    let bucket = bucket_of(here, self.axis_bits);
                    let (start, end) = (
                        self.starts[bucket] as usize,
                        self.starts[bucket + 1] as usize,
                    );
                    for e in &self.entries[start..end] {
                        if e.key != key || e.strand as usize == strand {
                            continue;
                        }
                        let a = positions[e.edge as usize];
                        let b = positions[e.edge as usize + 1];
                        let ab = sub(b, a);
                        let ab2 = dot(ab, ab);
                        let t = if ab2 > 0.0 {
                            (dot(sub(p, a), ab) / ab2).clamp(0.0, 1.0)
                        } else {
                            0.0
                        };
                        let foot = [a[0] + ab[0] * t, a[1] + ab[1] * t, a[2] + ab[2] * t];
                        let d = sub(p, foot);
                        let dist2 = dot(d, d);
                        if !(dist2 < reach * reach && dist2 > 0.0) {
                            continue;
                        }
                        // Counted once: in the (scanned) cell of the foot.
                        let f = cell_of(foot, self.inv_cell);
                        let owner = [
                            f[0].clamp(lo[0], hi[0]),
                            f[1].clamp(lo[1], hi[1]),
                            f[2].clamp(lo[2], hi[2]),
                        ];
                        if owner != here {
                            continue;
                        }
                        let dist = dist2.sqrt();
                        let k = alpha * (reach - dist) / reach / dist * dt;
                        dv = [dv[0] + d[0] * k, dv[1] + d[1] * k, dv[2] + d[2] * k];
                    }
                }
            }
        }
        dv
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blower_pushes_along_the_wind_and_ignores_parallel_hair() {
        let blower = Blower {
            from: [0.0, 0.0, -1.0],
            to: [0.0, 0.0, 0.0],
            strength: 2.0,
            hydrogen_rate: 0.003,
        };
        let dv = blower_dv(&blower, [0.0, 0.0, 0.0], [0.0, -1.0, 0.0], 0.5);
        assert!((dv[2] - 1.0).abs() < 1e-6, "{dv:?}");
        let parallel = blower_dv(&blower, [0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 0.5);
        assert!(length(parallel) < 1e-6);
        // (d + 1)^2 falloff: 1 m off the axis gives a quarter.
        let off = blower_dv(&blower, [1.0, 0.0, 0.0], [0.0, -1.0, 0.0], 0.5);
        assert!((off[2] - 0.25).abs() < 1e-6);
    }

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
        grid.build(&positions, &offsets, &[true, true], 4e-5);
        let dv = grid.penalty_dv(&positions, positions[0], 0, 4e-5, 1.0, 1.0);
        // Distance 1e-5 of 8e-5: (8 - 1) / 8 away from the other edge (-x).
        assert!((dv[0] + 7.0 / 8.0).abs() < 1e-5, "{dv:?}");
        let own = grid.penalty_dv(&positions, [1e-5, 0.0, 0.0], 1, 4e-5, 1.0, 1.0);
        assert!((own[0] - 7.0 / 8.0).abs() < 1e-5, "{own:?}");
        let far = grid.penalty_dv(&positions, [0.0, 0.0, 1.0], 0, 4e-5, 1.0, 1.0);
        assert_eq!(far, [0.0; 3]);
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

    /// (20) summed over every edge of every other strand.
    fn brute_force(positions: &[V3], offsets: &[usize], p: V3, strand: usize, radius: f32) -> V3 {
        let reach = 2.0 * radius;
        let mut dv = [0.0f32; 3];
        for (s, w) in offsets.windows(2).enumerate() {
            if s == strand {
                continue;
            }
            for v in w[0]..w[1] - 1 {
                let (a, b) = (positions[v], positions[v + 1]);
                let ab = sub(b, a);
                let t = (dot(sub(p, a), ab) / dot(ab, ab)).clamp(0.0, 1.0);
                let d = sub(p, [a[0] + ab[0] * t, a[1] + ab[1] * t, a[2] + ab[2] * t]);
                let dist = length(d);
                if dist < reach && dist > 0.0 {
                    dv = super::super::math::add(dv, scale(d, (reach - dist) / reach / dist));
                }
            }
        }
        dv
    }

    #[test]
    fn the_grid_finds_every_pair_within_two_radii_once() {
        let (positions, offsets) = tangle(60, 12);
        let radius = 1e-4;
        let mut grid = EdgeGrid::default();
        grid.build(&positions, &offsets, &[true; 60], radius);
        let mut touching = 0;
        for (s, w) in offsets.windows(2).enumerate() {
            for &p in &positions[w[0]..w[1]] {
                let expected = brute_force(&positions, &offsets, p, s, radius);
                let got = grid.penalty_dv(&positions, p, s, radius, 1.0, 1.0);
                if expected != [0.0; 3] {
                    touching += 1;
                }
                for c in 0..3 {
                    assert!(
                        (got[c] - expected[c]).abs() <= 1e-5 * (1.0 + expected[c].abs()),
                        "strand {s}: {got:?} vs {expected:?}"
                    );
                }
            }
        }
        // The test means something only if vertices touched other strands.
        assert!(touching > 30, "{touching}");
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
                grid.build(&positions, &offsets, &active, 1e-4);
                let mut out = Vec::new();
                for (s, w) in offsets.windows(2).enumerate() {
                    for &p in &positions[w[0]..w[1]] {
                        let dv = grid.penalty_dv(&positions, p, s, 1e-4, 5.0, 1.0 / 360.0);
                        out.extend(dv.map(f32::to_bits));
                    }
                }
                out
            })
        };
        let one = run(1);
        assert!(one.iter().any(|b| *b != 0));
        assert_eq!(one, run(2));
        assert_eq!(one, run(3));
    }
}
