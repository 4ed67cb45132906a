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
/// Cells an edge may cross in the grid; a longer edge (a strand torn far
/// beyond its rest length) goes on the long-edge list, which every vertex
/// checks.
const MAX_CELLS_PER_EDGE: usize = 96;
/// Long edges above which the cells are doubled (and the edges sorted
/// again), so the list stays short.
const MAX_LONG_EDGES: usize = 64;
/// Cell entries at most this many per edge on average: the smallest cell
/// is the edges' mean extent over this (less one), so the grid's memory
/// is a bounded multiple of the edge count however dense or torn the hair
/// is (and reserved once, so a step does not allocate as hair stretches).
const MAX_ENTRIES_PER_EDGE: f64 = 6.0;
/// Entries reserved per edge of a chunk: the mean bound, the cells an
/// edge's ends add, and room for a chunk above the mean.
const RESERVED_ENTRIES_PER_EDGE: usize = 12;
/// The largest cell is the longest rest edge over this: an edge stretched
/// in the step crosses more cells, it does not make cells bigger.
const CELLS_PER_REST_EDGE: f32 = 1.5;
/// Cell sizes the cost model tries, geometric between the bounds.
const CELL_CANDIDATES: usize = 24;
/// The cost of scanning one entry over that of listing one in its cell
/// (walked to, written and moved twice by the sort): 0.1 and 0.01 measured
/// alike at 10k strands, 0.3 and 1 slower (too many small cells).
const SCAN_COST: f64 = 0.1;

/// The hair-hair penalty (20) of every vertex, found once per step
/// through a uniform grid over the edges.
///
/// Each edge sits in every cell its segment passes through (not its box,
/// not grown by `2r`), each vertex in its own cell; a vertex scans the few
/// cells its `2r` ball touches, so only edges that pass nearby. Vertices
/// are visited in cell order, not strand order, so the cells a run of
/// vertices scans are the same few in memory.
///
/// The cell size only changes the cost, never a sum: a vertex gathers the
/// pushes of the edges it finds and adds them in edge order, each edge
/// once, which is exactly the brute-force sum over all edges of other
/// strands. So the size can follow the hair: between `2r` (and the
/// memory bound [`MAX_ENTRIES_PER_EDGE`]) and the longest rest edge, the
/// one a cost model fitted to the last step's scan finds cheapest (few
/// entries per edge for sparse guides, small cells for dense hair, where
/// a big cell holds hundreds of edges a vertex must test).
///
/// Entries are generated in parallel in fixed chunks, counting-sorted into
/// buckets by cell (a spatial wrap-around index); the sums are computed in
/// parallel in fixed chunks of the sorted vertices, so the result is the
/// same for any thread count. The step then only reads a vertex's sum.
/// All buffers are kept from step to step (no allocation once warm).
#[derive(Debug, Default)]
pub struct EdgeGrid {
    inv_cell: f32,
    /// Buckets per axis are `1 << axis_bits`.
    axis_bits: u32,
    starts: Vec<u32>,
    entries: Vec<Entry>,
    /// Per chunk of vertices, its edges' entries in order.
    chunks: Vec<Vec<Entry>>,
    /// Per chunk of vertices, its edges that cross too many cells.
    chunk_long_edges: Vec<Vec<u32>>,
    /// Those edges of all chunks, in order.
    long_edges: Vec<u32>,
    /// Strand of each vertex of an active strand, `u32::MAX` otherwise.
    owner: Vec<u32>,
    /// The vertices of active strands, sorted by bucket like `entries`.
    vertex_starts: Vec<u32>,
    vertices: Vec<Entry>,
    /// Per chunk of sorted vertices: the pushes a vertex found (edge,
    /// push), and how many entries the chunk scanned.
    found: Vec<Vec<(u32, V3)>>,
    scanned: Vec<u64>,
    /// Sums in the order of `vertices`, then by vertex index.
    sorted_sums: Vec<V3>,
    sums: Vec<V3>,
    scratch: SortScratch,
    /// The last build's cell and scan, for the next cell size.
    last: Option<Measured>,
}

/// What one build cost, to size the next build's cells.
#[derive(Debug, Clone, Copy)]
struct Measured {
    cell: f64,
    /// Entries scanned per vertex.
    scanned: f64,
}

/// The cell size of a step: edges of mean extent `mean_extent` (sum of
/// the absolute coordinate differences, m), interaction reach `reach`,
/// longest rest edge `rest_longest`. Without a last build, the largest
/// cell (a few entries per edge). Otherwise the candidate minimising
/// entries per edge `1 + mean / c` plus entries scanned per vertex, which
/// grows as `(c + mean) (c + 2 reach)^3 / c` (the edges per cell times
/// the cells a `2 reach` box touches), scaled to what the last build
/// scanned at its cell size.
fn cell_size(reach: f32, rest_longest: f32, mean_extent: f64, last: Option<Measured>) -> f32 {
    let reach = f64::from(reach);
    let lo = reach.max(mean_extent / (MAX_ENTRIES_PER_EDGE - 1.0));
    let hi = lo.max(f64::from(rest_longest / CELLS_PER_REST_EDGE));
    let scan_shape = |c: f64| (c + mean_extent) * (c + 2.0 * reach).powi(3) / c;
    let chosen = match last {
        Some(last) if last.scanned > 0.0 && hi > lo => {
            let scale = last.scanned / scan_shape(last.cell);
            let cost = |c: f64| 1.0 + mean_extent / c + SCAN_COST * scale * scan_shape(c);
            let ratio = (hi / lo).powf(1.0 / (CELL_CANDIDATES - 1) as f64);
            let mut best = (lo, cost(lo));
            let mut c = lo;
            for _ in 1..CELL_CANDIDATES {
                c *= ratio;
                let here = cost(c);
                if here < best.1 {
                    best = (c, here);
                }
            }
            best.0
        }
        _ => hi,
    };
    if chosen.is_finite() && chosen > 0.0 {
        chosen as f32
    } else {
        // Degenerate input (no finite edge): any cell will do.
        reach.max(1e-6) as f32
    }
}

/// `floor` as an integer, saturating far away (truncation, then one down
/// for negatives: `floor` is a libm call on baseline x86-64).
#[inline]
fn floor_i32(x: f32) -> i32 {
    let t = x as i32;
    if (t as f32) > x {
        t - 1
    } else {
        t
    }
}

#[inline]
fn cell_of(p: V3, inv_cell: f32) -> [i32; 3] {
    // Saturating float-to-int casts keep far-away points in the end cells.
    [
        floor_i32(p[0] * inv_cell),
        floor_i32(p[1] * inv_cell),
        floor_i32(p[2] * inv_cell),
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
    // Both powers of two: a shift, not a division per entry.
    let part_shift = per_part.trailing_zeros();
    let part_of = |e: &Entry| bucket_of(unpack(e.key), bits) >> part_shift;
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
            // As much room as the chunk has: no allocation as it fills.
            grouped.reserve(chunk.capacity());
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
    out.reserve(chunks.iter().map(Vec::capacity).sum());
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

/// Bits per axis for about one bucket per item or two: at least 2 (64
/// buckets, one per part of the sort), at most 7 (2 million buckets, 8 MB
/// of starts: more would cost more to clear than aliasing cells do).
fn bucket_bits(items: usize) -> u32 {
    let mut bits = 2;
    while (1usize << (3 * bits)) < items && bits < 7 {
        bits += 1;
    }
    bits
}

impl EdgeGrid {
    /// Finds the penalty sums of every vertex of the `active` strands
    /// (`offsets` as in StrandSet) at `positions`, for hair radius `radius`;
    /// `rest_longest` is the longest rest edge (bounds the cell size).
    pub fn build(
        &mut self,
        positions: &[V3],
        offsets: &[usize],
        active: &[bool],
        radius: f32,
        rest_longest: f32,
    ) {
        let reach = 2.0 * radius;
        self.find_owners(positions.len(), offsets, active);
        let mean_extent = self.mean_edge_extent(positions);
        let mut cell = cell_size(reach, rest_longest, mean_extent, self.last);
        let chunk_count = positions.len().div_ceil(CHUNK_VERTICES);
        // Torn strands: bigger cells until few edges are left over.
        while self.generate_entries(positions, chunk_count, 1.0 / cell) > MAX_LONG_EDGES
            && cell < f32::MAX / 4.0
        {
            cell *= 2.0;
        }
        self.inv_cell = 1.0 / cell;
        self.sort_entries(positions, chunk_count);
        let scanned = self.sum_pushes(positions, reach);
        self.last = Some(Measured {
            cell: f64::from(cell),
            scanned: scanned as f64 / self.vertices.len().max(1) as f64,
        });
    }

    /// The strand of each vertex of an active strand.
    fn find_owners(&mut self, vertex_count: usize, offsets: &[usize], active: &[bool]) {
        self.owner.clear();
        self.owner.resize(vertex_count, u32::MAX);
        for (strand, w) in offsets.windows(2).enumerate() {
            if active[strand] {
                self.owner[w[0]..w[1]].fill(strand as u32);
            }
        }
    }

    /// The strand of the edge starting at `v`, when `v + 1` is of the same
    /// active strand.
    #[inline]
    fn edge_strand(owner: &[u32], v: usize) -> Option<u32> {
        let strand = owner[v];
        (strand != u32::MAX && owner.get(v + 1) == Some(&strand)).then_some(strand)
    }

    /// The mean `|dx| + |dy| + |dz|` of the finite edges
    /// (about the cells an edge crosses times the cell size), summed in
    /// whole micrometres: exact in any order, so the cell size does not
    /// depend on the thread count.
    fn mean_edge_extent(&self, positions: &[V3]) -> f64 {
        use rayon::prelude::*;
        let owner = &self.owner;
        let (count, micrometres) = (0..positions.len().saturating_sub(1))
            .into_par_iter()
            .with_min_len(CHUNK_VERTICES)
            .filter(|&v| Self::edge_strand(owner, v).is_some())
            .map(|v| {
                let d = sub(positions[v + 1], positions[v]);
                let extent = f64::from(d[0].abs() + d[1].abs() + d[2].abs());
                if extent.is_finite() {
                    (1u64, (extent * 1e6).min(1e12) as u64)
                } else {
                    (0, 0)
                }
            })
            .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1.saturating_add(b.1)));
        if count > 0 {
            micrometres as f64 * 1e-6 / count as f64
        } else {
            0.0
        }
    }

    /// Each chunk's edges into the cells they cross; returns how many
    /// edges cross too many (kept on the long-edge list).
    fn generate_entries(&mut self, positions: &[V3], chunk_count: usize, inv_cell: f32) -> usize {
        use rayon::prelude::*;
        if self.chunks.len() < chunk_count {
            self.chunks.resize_with(chunk_count, Vec::new);
        }
        if self.chunk_long_edges.len() < chunk_count {
            self.chunk_long_edges.resize_with(chunk_count, Vec::new);
        }
        let owner = &self.owner;
        self.chunks[..chunk_count]
            .par_iter_mut()
            .zip(self.chunk_long_edges[..chunk_count].par_iter_mut())
            .enumerate()
            .for_each(|(k, (out, long))| {
                out.clear();
                if out.capacity() == 0 {
                    out.reserve(CHUNK_VERTICES * RESERVED_ENTRIES_PER_EDGE);
                    long.reserve(MAX_LONG_EDGES);
                }
                long.clear();
                let mut cells = [0u32; MAX_CELLS_PER_EDGE];
                let first = k * CHUNK_VERTICES;
                for v in first..(first + CHUNK_VERTICES).min(positions.len()) {
                    let Some(strand) = Self::edge_strand(owner, v) else {
                        continue;
                    };
                    let (a, b) = (positions[v], positions[v + 1]);
                    if !(is_finite3(a) && is_finite3(b)) {
                        continue;
                    }
                    match edge_cells(a, b, inv_cell, &mut cells) {
                        Some(n) => out.extend(cells[..n].iter().map(|&key| Entry {
                            key,
                            edge: v as u32,
                            strand,
                        })),
                        None => long.push(v as u32),
                    }
                }
            });
        self.long_edges.clear();
        self.long_edges.reserve(2 * MAX_LONG_EDGES);
        for long in &self.chunk_long_edges[..chunk_count] {
            self.long_edges.extend_from_slice(long);
        }
        self.long_edges.len()
    }

    /// The entries, then the vertices, counting-sorted by bucket.
    fn sort_entries(&mut self, positions: &[V3], chunk_count: usize) {
        use rayon::prelude::*;
        let total: usize = self.chunks[..chunk_count].iter().map(Vec::len).sum();
        self.axis_bits = bucket_bits(total);
        sort_into_buckets(
            &self.chunks[..chunk_count],
            self.axis_bits,
            &mut self.scratch,
            &mut self.starts,
            &mut self.entries,
        );
        let (owner, inv_cell) = (&self.owner, self.inv_cell);
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
        // The vertices' order only needs to be local: their own (fewer)
        // buckets.
        sort_into_buckets(
            &self.chunks[..chunk_count],
            bucket_bits(self.owner.len()),
            &mut self.scratch,
            &mut self.vertex_starts,
            &mut self.vertices,
        );
    }

    /// Every vertex's penalty sum, in parallel over fixed chunks of the
    /// sorted vertices; returns the entries scanned.
    fn sum_pushes(&mut self, positions: &[V3], reach: f32) -> u64 {
        use rayon::prelude::*;
        let count = self.vertices.len();
        let chunk_count = count.div_ceil(CHUNK_VERTICES);
        if self.found.len() < chunk_count {
            // Room for a dense tangle's pushes, so a warm step does not grow them.
            self.found
                .resize_with(chunk_count, || Vec::with_capacity(256));
        }
        self.scanned.clear();
        self.scanned.resize(chunk_count, 0);
        self.sorted_sums.clear();
        self.sorted_sums.resize(count, [0.0; 3]);
        let lookup = Lookup {
            entries: &self.entries,
            starts: &self.starts,
            long_edges: &self.long_edges,
            owner: &self.owner,
            positions,
            inv_cell: self.inv_cell,
            bits: self.axis_bits,
            reach,
        };
        self.sorted_sums
            .par_chunks_mut(CHUNK_VERTICES)
            .zip(self.vertices.par_chunks(CHUNK_VERTICES))
            .zip(self.found[..chunk_count].par_iter_mut())
            .zip(self.scanned.par_iter_mut())
            .for_each(|(((sums, vertices), found), scanned)| {
                for (sum, v) in sums.iter_mut().zip(vertices) {
                    *sum = lookup.penalty_sum(positions[v.edge as usize], v.strand, found, scanned);
                }
            });
        self.sums.clear();
        self.sums.resize(positions.len(), [0.0; 3]);
        for (v, sum) in self.vertices.iter().zip(&self.sorted_sums) {
            self.sums[v.edge as usize] = *sum;
        }
        self.scanned.iter().sum()
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

/// The push of (20) on a vertex at `p` from edge `a`-`b`:
/// `(p - foot) (2r - d) / (2r d)` when the distance `d` to the foot point
/// is below `reach` = `2r` (and not zero).
#[inline]
fn edge_push(p: V3, a: V3, b: V3, reach: f32) -> Option<V3> {
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
        return None;
    }
    let dist = dist2.sqrt();
    let k = (reach - dist) / reach / dist;
    Some([d[0] * k, d[1] * k, d[2] * k])
}

/// The sorted grid, read by every vertex's sum.
struct Lookup<'a> {
    entries: &'a [Entry],
    starts: &'a [u32],
    long_edges: &'a [u32],
    owner: &'a [u32],
    positions: &'a [V3],
    inv_cell: f32,
    bits: u32,
    reach: f32,
}

impl Lookup<'_> {
    /// The sum of [`edge_push`] over the edges of other strands within
    /// `reach` of `p`, each once, in edge order (so the sum does not
    /// depend on the cells); `found` is scratch, `scanned` counts the
    /// entries looked at.
    fn penalty_sum(&self, p: V3, strand: u32, found: &mut Vec<(u32, V3)>, scanned: &mut u64) -> V3 {
        let reach = self.reach;
        found.clear();
        let lo = cell_of([p[0] - reach, p[1] - reach, p[2] - reach], self.inv_cell);
        let hi = cell_of([p[0] + reach, p[1] + reach, p[2] + reach], self.inv_cell);
        // More than 3 cells per axis only at far-off (saturated) coordinates.
        if (0..3).all(|c| i64::from(hi[c]) - i64::from(lo[c]) <= 2) {
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        let here = [x, y, z];
                        let key = pack(here);
                        let bucket = bucket_of(here, self.bits);
                        let (start, end) = (
                            self.starts[bucket] as usize,
                            self.starts[bucket + 1] as usize,
                        );
                        *scanned += (end - start) as u64;
                        for e in &self.entries[start..end] {
                            if e.key != key || e.strand == strand {
                                continue;
                            }
                            self.push_from(p, e.edge, found);
                        }
                    }
                }
            }
        }
        for &edge in self.long_edges {
            if self.owner[edge as usize] != strand {
                self.push_from(p, edge, found);
            }
        }
        // An edge met in several cells pushes the same each time: once.
        found.sort_unstable_by_key(|&(edge, _)| edge);
        let mut dv = [0.0f32; 3];
        let mut previous = None;
        for &(edge, push) in found.iter() {
            if previous != Some(edge) {
                dv = [dv[0] + push[0], dv[1] + push[1], dv[2] + push[2]];
                previous = Some(edge);
            }
        }
        dv
    }

    #[inline]
    fn push_from(&self, p: V3, edge: u32, found: &mut Vec<(u32, V3)>) {
        let (a, b) = (
            self.positions[edge as usize],
            self.positions[edge as usize + 1],
        );
        if let Some(push) = edge_push(p, a, b, self.reach) {
            found.push((edge, push));
        }
    }
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
        // (too many cells: the long-edge list).
        positions[offsets[3] + 5][1] += 0.02;
        positions[offsets[7] + 4] = [0.5, 0.002, 0.002];
        let active: Vec<bool> = (0..60).map(|s| s % 11 != 5).collect();
        let (touching, grid) = check_against_brute_force(&positions, &offsets, &active, 0.003);
        // The test means something only if vertices touched other strands
        // and the torn edges were on the long list.
        assert!(touching > 30, "{touching}");
        assert!(!grid.long_edges.is_empty());
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
        assert!(grid.long_edges.len() <= MAX_LONG_EDGES);
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
}
