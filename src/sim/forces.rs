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
    // Nothing blows behind the nozzle, nor outside its cone.
    let outside_cone = blower
        .cone_half_angle
        .is_some_and(|a| d > along * a.to_radians().tan());
    if along <= 0.0 || outside_cone {
        return [0.0; 3];
    }
    let falloff = d / blower.falloff_length + 1.0;
    scale(
        w_hat,
        blower.strength * sin_theta / (falloff * falloff) * dt,
    )
}

/// An edge in one cell.
#[derive(Debug, Clone, Copy, Default)]
struct Entry {
    /// The cell, packed by [`pack`].
    key: u32,
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
const CELLS_PER_EDGE: f32 = 1.5;

/// The hair-hair penalty (20) of every vertex, found once per step
/// through a uniform grid of cells of two thirds of the longest edge
/// (at least the interaction distance `2r`).
///
/// Each edge sits in every cell its segment passes through (not its box,
/// not grown by `2r`), each vertex in its own cell; a vertex scans the few
/// cells its `2r` ball touches, so only edges that pass nearby. Vertices
/// are visited in cell order, not strand order, so the cells a run of
/// vertices scans are the same few in memory (visited in strand order,
/// almost every vertex missed the cache). A vertex-edge pair met in
/// several cells counts once.
///
/// Entries are generated in parallel in fixed chunks, counting-sorted into
/// buckets by cell (a spatial wrap-around index); the sums are computed in
/// parallel in fixed chunks of the sorted vertices, each vertex's in a
/// fixed order, so the result is the same for any thread count. The step
/// then only reads a vertex's sum. All buffers are kept from step to step
/// (no allocation once warm).
#[derive(Debug, Default)]
pub struct EdgeGrid {
    inv_cell: f32,
    /// Buckets per axis are `1 << axis_bits`.
    axis_bits: u32,
    starts: Vec<u32>,
    entries: Vec<Entry>,
    /// Per chunk of vertices, its edges' entries in order.
    chunks: Vec<Vec<Entry>>,
    /// Strand of each vertex of an active strand, `u32::MAX` otherwise.
    owner: Vec<u32>,
    /// The vertices of active strands, sorted by bucket like `entries`.
    vertex_starts: Vec<u32>,
    vertices: Vec<Entry>,
    /// Sums in the order of `vertices`, then by vertex index.
    sorted_sums: Vec<V3>,
    sums: Vec<V3>,
    scratch: SortScratch,
}

#[inline]
fn cell_of(p: V3, inv_cell: f32) -> [i32; 3] {
    // Saturating float-to-int casts keep far-away points in the end cells
    // (truncation, then one down for negatives: `floor` is a libm call on
    // baseline x86-64).
    let floor = |x: f32| {
        let t = x as i32;
        if (t as f32) > x {
            t - 1
        } else {
            t
        }
    };
    [
        floor(p[0] * inv_cell),
        floor(p[1] * inv_cell),
        floor(p[2] * inv_cell),
    ]
}

/// A cell as one key (10 bits per axis, so an entry is 12 bytes: cells
/// alias only 1,024 cells apart, metres at the usual cell sizes, and an
/// aliased edge is then rejected by the exact distance test).
#[inline]
fn pack(cell: [i32; 3]) -> u32 {
    let m = (1u32 << 10) - 1;
    ((cell[0] as u32 & m) << 20) | ((cell[1] as u32 & m) << 10) | (cell[2] as u32 & m)
}

#[inline]
fn bucket_of(cell: [i32; 3], bits: u32) -> usize {
    let m = (1usize << bits) - 1;
    ((cell[0] as usize & m) << (2 * bits))
        | ((cell[1] as usize & m) << bits)
        | (cell[2] as usize & m)
}

/// The cells segment `a`-`b` passes through, walked from `a` to `b`
/// (Amanatides and Woo 1987), without repeats (hand-written: the walk is
/// a dozen lines and the hot loop of the grid's build). `None` when there are more
/// than `MAX_CELLS_PER_EDGE`.
fn edge_cells(a: V3, b: V3, inv_cell: f32, out: &mut [u32; MAX_CELLS_PER_EDGE]) -> Option<usize> {
    let mut at = cell_of(a, inv_cell);
    let end = cell_of(b, inv_cell);
    let crossings: i64 = (0..3)
        .map(|c| (i64::from(end[c]) - i64::from(at[c])).abs())
        .sum();
    if crossings >= MAX_CELLS_PER_EDGE as i64 {
        return None;
    }
    let mut step = [0i32; 3];
    // Segment parameter of the next cell wall per axis, and between walls.
    let mut next = [f32::INFINITY; 3];
    let mut delta = [f32::INFINITY; 3];
    for c in 0..3 {
        let d = (b[c] - a[c]) * inv_cell;
        let x = a[c] * inv_cell;
        if end[c] > at[c] {
            step[c] = 1;
            delta[c] = 1.0 / d;
            next[c] = ((at[c] as f32 + 1.0) - x) / d;
        } else if end[c] < at[c] {
            step[c] = -1;
            delta[c] = -1.0 / d;
            next[c] = (at[c] as f32 - x) / d;
        }
    }
    out[0] = pack(at);
    let mut n = 1;
    // One wall per step, on an axis not yet at the end cell, so the walk
    // ends in `b`'s cell whatever round-off does at corners.
    while at != end {
        let mut c = 3;
        for axis in 0..3 {
            if at[axis] != end[axis] && (c == 3 || next[axis] < next[c]) {
                c = axis;
            }
        }
        at[c] += step[c];
        next[c] += delta[c];
        out[n] = pack(at);
        n += 1;
    }
    Some(n)
}

/// Bucket ranges sorted independently (in parallel).
const PARTS: usize = 64;

/// Reusable buffers of [`sort_into_buckets`].
#[derive(Debug, Default)]
struct SortScratch {
    /// Per chunk, its entries grouped by part (in order within a part).
    grouped: Vec<Vec<Entry>>,
    /// Per chunk, where each part starts in `grouped` (and the end).
    part_starts: Vec<[u32; PARTS + 1]>,
}

/// A stable counting sort of the entries of `chunks` (in chunk order)
/// into `out` by bucket (`1 << 3 bits` of them); `starts` ends as each
/// bucket's first index and the total. Chunks first group their entries
/// by part (a range of buckets), then each part sorts its entries from
/// every chunk: both in parallel, each over data that fits in cache, and
/// the result does not depend on the thread count.
fn sort_into_buckets(
    chunks: &[Vec<Entry>],
    bits: u32,
    scratch: &mut SortScratch,
    starts: &mut Vec<u32>,
    out: &mut Vec<Entry>,
) {
    use rayon::prelude::*;
    let buckets = 1usize << (3 * bits);
    let per_part = buckets / PARTS;
    let part_of = |e: &Entry| bucket_of(unpack(e.key), bits) / per_part;
    if scratch.grouped.len() < chunks.len() {
        scratch.grouped.resize_with(chunks.len(), Vec::new);
    }
    scratch.part_starts.resize(chunks.len(), [0; PARTS + 1]);
    chunks
        .par_iter()
        .zip(scratch.grouped.par_iter_mut())
        .zip(scratch.part_starts.par_iter_mut())
        .for_each(|((chunk, grouped), part_starts)| {
            *part_starts = [0; PARTS + 1];
            for e in chunk {
                part_starts[part_of(e) + 1] += 1;
            }
            for p in 1..=PARTS {
                part_starts[p] += part_starts[p - 1];
            }
            let mut cursor = *part_starts;
            grouped.clear();
            grouped.resize(chunk.len(), Entry::default());
            for e in chunk {
                let slot = &mut cursor[part_of(e)];
                grouped[*slot as usize] = *e;
                *slot += 1;
            }
        });
    let grouped = &scratch.grouped[..chunks.len()];
    let part_starts = &scratch.part_starts;
    let total: usize = chunks.iter().map(Vec::len).sum();
    out.clear();
    out.resize(total, Entry::default());
    starts.clear();
    starts.resize(buckets + 1, 0);
    starts[buckets] = total as u32;
    // Each part's slice of `out`, cut in order without allocating.
    let mut rest = out.as_mut_slice();
    let mut base = 0u32;
    let parts: [(u32, &mut [Entry]); PARTS] = std::array::from_fn(|p| {
        let size: u32 = part_starts.iter().map(|s| s[p + 1] - s[p]).sum();
        let (mine, tail) = std::mem::take(&mut rest).split_at_mut(size as usize);
        rest = tail;
        base += size;
        (base - size, mine)
    });
    parts
        .into_par_iter()
        .zip(starts[..buckets].par_chunks_mut(per_part))
        .enumerate()
        .for_each(|(p, ((base, out), starts))| {
            let first_bucket = p * per_part;
            let entries = grouped
                .iter()
                .zip(part_starts)
                .flat_map(|(g, s)| &g[s[p] as usize..s[p + 1] as usize]);
            starts.fill(0);
            for e in entries.clone() {
                starts[bucket_of(unpack(e.key), bits) - first_bucket] += 1;
            }
            let mut sum = 0;
            for s in starts.iter_mut() {
                let count = *s;
                *s = sum;
                sum += count;
            }
            for e in entries {
                let slot = &mut starts[bucket_of(unpack(e.key), bits) - first_bucket];
                out[*slot as usize] = *e;
                *slot += 1;
            }
            // The cursors hold each bucket's end: back to starts, global.
            let mut previous = 0;
            for s in starts.iter_mut() {
                let end = *s;
                *s = previous + base;
                previous = end;
            }
        });
}

#[inline]
fn unpack(key: u32) -> [i32; 3] {
    let m = (1u32 << 10) - 1;
    [
        ((key >> 20) & m) as i32,
        ((key >> 10) & m) as i32,
        (key & m) as i32,
    ]
}

impl EdgeGrid {
    /// Finds the penalty sums of every vertex of the `active` strands
    /// (`offsets` as in StrandSet) at `positions`, for hair radius `radius`.
    pub fn build(&mut self, positions: &[V3], offsets: &[usize], active: &[bool], radius: f32) {
        use rayon::prelude::*;
        let reach = 2.0 * radius;
        self.owner.clear();
        self.owner.resize(positions.len(), u32::MAX);
        for (strand, w) in offsets.windows(2).enumerate() {
            if active[strand] {
                self.owner[w[0]..w[1]].fill(strand as u32);
            }
        }
        let owner = &self.owner;
        // An edge starts at `v` when `v + 1` is of the same active strand.
        let edge_of = |v: usize| -> Option<u32> {
            let strand = owner[v];
            (strand != u32::MAX && owner.get(v + 1) == Some(&strand)).then_some(strand)
        };
        // Cells from the longest edge (max is exact in any order).
        let longest = positions
            .par_iter()
            .enumerate()
            .with_min_len(CHUNK_VERTICES)
            .filter(|(v, _)| edge_of(*v).is_some())
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
        let inv_cell = 1.0 / cell;
        self.inv_cell = inv_cell;
        let chunk_count = positions.len().div_ceil(CHUNK_VERTICES);
        if self.chunks.len() < chunk_count {
            self.chunks.resize_with(chunk_count, Vec::new);
        }
        self.chunks[..chunk_count]
            .par_iter_mut()
            .enumerate()
            .for_each(|(k, out)| {
                out.clear();
                let mut cells = [0u32; MAX_CELLS_PER_EDGE];
                let first = k * CHUNK_VERTICES;
                for v in first..(first + CHUNK_VERTICES).min(positions.len()) {
                    let Some(strand) = edge_of(v) else {
                        continue;
                    };
                    let (a, b) = (positions[v], positions[v + 1]);
                    if !(is_finite3(a) && is_finite3(b)) {
                        continue;
                    }
                    if let Some(n) = edge_cells(a, b, inv_cell, &mut cells) {
                        out.extend(cells[..n].iter().map(|&key| Entry {
                            key,
                            edge: v as u32,
                            strand,
                        }));
                    }
                }
            });
        let total: usize = self.chunks[..chunk_count].iter().map(Vec::len).sum();
        // About one bucket per entry or two, a power of two per axis.
        // At least 2 bits: 64 buckets, one per part.
        let mut bits = 2;
        while (1usize << (3 * bits)) < total && bits < 9 {
            bits += 1;
        }
        self.axis_bits = bits;
        sort_into_buckets(
            &self.chunks[..chunk_count],
            bits,
            &mut self.scratch,
            &mut self.starts,
            &mut self.entries,
        );

        // The vertices, in cell order.
        self.chunks[..chunk_count]
            .par_iter_mut()
            .enumerate()
            .for_each(|(k, out)| {
                out.clear();
                let first = k * CHUNK_VERTICES;
                for v in first..(first + CHUNK_VERTICES).min(positions.len()) {
                    let p = positions[v];
                    if owner[v] != u32::MAX && is_finite3(p) {
                        out.push(Entry {
                            key: pack(cell_of(p, inv_cell)),
                            edge: v as u32,
                            strand: owner[v],
                        });
                    }
                }
            });
        sort_into_buckets(
            &self.chunks[..chunk_count],
            bits,
            &mut self.scratch,
            &mut self.vertex_starts,
            &mut self.vertices,
        );
        let count = self.vertices.len();
        self.sorted_sums.clear();
        self.sorted_sums.resize(count, [0.0; 3]);
        let (entries, starts) = (&self.entries, &self.starts);
        self.sorted_sums
            .par_chunks_mut(CHUNK_VERTICES)
            .zip(self.vertices.par_chunks(CHUNK_VERTICES))
            .for_each(|(sums, vertices)| {
                for (sum, v) in sums.iter_mut().zip(vertices) {
                    *sum = penalty_sum(
                        entries,
                        starts,
                        positions,
                        (inv_cell, bits),
                        positions[v.edge as usize],
                        v.strand,
                        reach,
                    );
                }
            });
        self.sums.clear();
        self.sums.resize(positions.len(), [0.0; 3]);
        for (v, sum) in self.vertices.iter().zip(&self.sorted_sums) {
            self.sums[v.edge as usize] = *sum;
        }
    }

    /// The penalty velocity change (20) at vertex `vertex` (global index)
    /// from the edges of other strands, as found by the last `build`.
    #[inline]
    pub fn penalty_dv(&self, vertex: usize, alpha: f32, dt: f32) -> V3 {
        match self.sums.get(vertex) {
            Some(sum) => scale(*sum, alpha * dt),
            None => [0.0; 3],
        }
    }
}

/// `sum (p - foot) (2r - d) / (2r d)` over the edges of other strands
/// within `2r` of `p` (d the distance to the foot point), each once.
fn penalty_sum(
    entries: &[Entry],
    starts: &[u32],
    positions: &[V3],
    (inv_cell, bits): (f32, u32),
    p: V3,
    strand: u32,
    reach: f32,
) -> V3 {
    let mut dv = [0.0f32; 3];
    let lo = cell_of([p[0] - reach, p[1] - reach, p[2] - reach], inv_cell);
    let hi = cell_of([p[0] + reach, p[1] + reach, p[2] + reach], inv_cell);
    if (0..3).any(|c| i64::from(hi[c]) - i64::from(lo[c]) > 2) {
        // Far-off (saturated) coordinates.
        return dv;
    }
    let mut seen = [0u32; 64];
    let mut found = 0;
    for x in lo[0]..=hi[0] {
        for y in lo[1]..=hi[1] {
            for z in lo[2]..=hi[2] {
                let here = [x, y, z];
                let key = pack(here);
                let bucket = bucket_of(here, bits);
                let (start, end) = (starts[bucket] as usize, starts[bucket + 1] as usize);
                for e in &entries[start..end] {
                    if e.key != key || e.strand == strand {
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
                    // An edge met in several of the scanned cells counts
                    // once (the first time).
                    if seen[..found].contains(&e.edge) {
                        continue;
                    }
                    if found < seen.len() {
                        seen[found] = e.edge;
                        found += 1;
                    }
                    let dist = dist2.sqrt();
                    let k = (reach - dist) / reach / dist;
                    dv = [dv[0] + d[0] * k, dv[1] + d[1] * k, dv[2] + d[2] * k];
                }
            }
        }
    }
    dv
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blower_pushes_along_the_wind_and_ignores_parallel_hair() {
        let blower = Blower {
            falloff_length: 1.0,
            cone_half_angle: None,
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
            for v in w[0]..w[1] {
                let expected = brute_force(&positions, &offsets, positions[v], s, radius);
                let got = grid.penalty_dv(v, 1.0, 1.0);
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
}
