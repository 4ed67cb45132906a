//! The pairwise hair-hair penalty of 000 §6 (20): vertices within two
//! hair radii of an edge of another strand are pushed apart, found through
//! a uniform grid over the vertices that every edge walks. The sums are
//! found from the positions at the start of the step, in parallel and then
//! added in edge order, and only read while strands are advanced in
//! parallel, so the result does not depend on the thread count. (The
//! physical model's contacts between strands with Coulomb friction, which
//! the penalty leaves little to do once on, are in hair_friction.rs; the
//! grid's cells, walk and sort, shared by both, in grid.rs.)

use super::grid::{
    bucket_bits, bucket_of, cell_of, crossings, pack, sort_into_buckets, unpack, walk_cells,
    Bucketed, SortScratch, MAX_CELLS_PER_EDGE,
};
use crate::sim::instructions::prefetch;
use crate::sim::math::{cross, dot, is_finite3, scale, sub, V3};

/// A vertex in one cell its `2r` box touches, with its position (so an
/// edge scanning the cell reads entries in order, not positions at
/// random).
#[derive(Debug, Clone, Copy, Default)]
struct Entry {
    position: V3,
    /// The next vertex's position (the end of the vertex's edge, when
    /// `key` has [`EDGE`]).
    next: V3,
    /// Global index of the vertex.
    vertex: u32,
    /// The cell, packed by [`pack`], with the flags [`HOME`] and [`EDGE`].
    key: u32,
}

impl Bucketed for Entry {
    #[inline]
    fn cell_key(&self) -> u32 {
        self.key
    }
}

/// An entry as an edge's scan reads it: the vertex's position and the
/// key and its strand (fewer bytes than an [`Entry`]: the scan is bound
/// by memory).
#[derive(Debug, Clone, Copy, Default)]
struct Probe {
    position: V3,
    key: u32,
    /// The vertex's strand: an edge skips its own strand's vertices, which
    /// share its cells and lie on its line, before any distance test.
    strand: u32,
}

/// A push an edge found: the vertex, the edge (its first vertex) and the
/// push of (20), before `alpha dt`.
type Pair = (u32, u32, V3);

/// The key bit of a vertex's first entry (its box's lowest cell), where
/// the edge starting at the vertex is searched: edges then go in cell
/// order, so the cells a run of them walks are the same few in memory.
const HOME: u32 = 1 << 31;
/// The key bit of a vertex that starts a finite edge of its strand.
const EDGE: u32 = 1 << 30;
/// The cell bits of a key.
const CELL: u32 = EDGE - 1;

/// Entries placed per chunk of this many vertices: fixed, so the order
/// does not depend on the thread count.
const CHUNK_VERTICES: usize = 2048;
/// Sorted entries whose edges are searched together.
const CHUNK_ENTRIES: usize = 4096;
/// Long edges above which the cells are doubled, so few edges test every
/// vertex.
const MAX_LONG_EDGES: usize = 64;
/// Entries reserved per vertex: a box of `2r` in cells of at least `2r`
/// touches at most two cells per axis.
const MAX_ENTRIES_PER_VERTEX: usize = 8;
/// Pushes a chunk of entries keeps for the sum; when a chunk finds more
/// (a dense tangle), the sums are found edge by edge in order instead,
/// so the memory is bounded whatever the hair does.
const PAIRS_PER_CHUNK: usize = 4 * CHUNK_ENTRIES;
/// The largest cell is the longest rest edge over this: an edge stretched
/// in the step crosses more cells, it does not make cells bigger.
const CELLS_PER_REST_EDGE: f32 = 1.5;
/// Cell sizes the cost model tries, geometric between the bounds.
const CELL_CANDIDATES: usize = 24;
/// The cost of an edge walking into one cell (a bucket looked up) over
/// that of placing one vertex entry (written and moved twice by the
/// sort).
const WALK_COST: f64 = 1.0;
/// The cost of scanning one entry over that of placing one.
const SCAN_COST: f64 = 0.05;

/// The hair-hair penalty (20) of every vertex, found once per step
/// through a uniform grid over the vertices.
///
/// Each vertex sits in every cell its `2r` box touches (one, sometimes
/// two to eight: cells are at least `2r`), with a copy of its position;
/// each edge walks the cells its segment passes through and tests the
/// vertices there, so only vertices that lie nearby. The entries are few
/// (about one per vertex) and an edge's scan reads them in order.
///
/// The cell size only changes the cost, never a sum: an edge's pushes
/// are kept per vertex once (a vertex met in several cells pushes the
/// same each time), and every vertex's pushes are added in edge order,
/// which is exactly the brute-force sum over all edges of other strands.
/// So the size can follow the hair: between `2r` and the longest rest
/// edge, the one a cost model fitted to the last step's scan finds
/// cheapest (large cells for sparse guides, small cells for dense hair,
/// where a big cell holds hundreds of vertices an edge must test).
///
/// Entries are generated in parallel in fixed chunks and counting-sorted
/// into buckets by cell (a spatial wrap-around index); the pushes are
/// found in parallel in fixed chunks of edges, then added in chunk order,
/// so the result is the same for any thread count. The step then only
/// reads a vertex's sum. All buffers are kept from step to step (no
/// allocation once warm).
#[derive(Debug, Default)]
pub struct EdgeGrid {
    inv_cell: f32,
    /// Buckets per axis are `1 << axis_bits`.
    axis_bits: u32,
    starts: Vec<u32>,
    entries: Vec<Entry>,
    /// `entries` as the scan reads them.
    probes: Vec<Probe>,
    /// Per chunk of vertices, their entries in order.
    chunks: Vec<Vec<Entry>>,
    /// Strand of each vertex of an active strand, `u32::MAX` otherwise.
    owner: Vec<u32>,
    /// Per chunk of sorted entries: the pushes its edges found, whether it
    /// found too many, the entries scanned.
    pairs: Vec<Vec<Pair>>,
    overflow: Vec<bool>,
    scanned: Vec<u64>,
    /// Every push found, sorted by vertex then edge for the sums.
    all_pairs: Vec<Pair>,
    /// Pushes a chunk may find before the sums go edge by edge (0: half
    /// of [`PAIRS_PER_CHUNK`]; tests lower it).
    max_pairs: usize,
    /// Edges that crossed too many cells in the last build.
    long_edges: usize,
    sums: Vec<V3>,
    scratch: SortScratch<Entry>,
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
/// cell. Otherwise the candidate minimising, per vertex, the entries
/// placed `(1 + 2 reach / c)^3`, the cells an edge walks `1 + mean / c`
/// and the entries scanned, which grows as `(c + mean) (c + 2 reach)^3 / c`
/// (the edges through a cell times the entries of the vertices a cell
/// holds), scaled to what the last build scanned at its cell size.
fn cell_size(reach: f32, rest_longest: f32, mean_extent: f64, last: Option<Measured>) -> f32 {
    let reach = f64::from(reach);
    let lo = 2.0 * reach;
    let hi = lo.max(f64::from(rest_longest / CELLS_PER_REST_EDGE));
    let scan_shape = |c: f64| (c + mean_extent) * (c + 2.0 * reach).powi(3) / c;
    let chosen = match last {
        Some(last) if last.scanned > 0.0 && hi > lo => {
            let scale = last.scanned / scan_shape(last.cell);
            let cost = |c: f64| {
                (1.0 + 2.0 * reach / c).powi(3)
                    + WALK_COST * (1.0 + mean_extent / c)
                    + SCAN_COST * scale * scan_shape(c)
            };
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
        let placed = self.find_owners(positions.len(), offsets, active);
        let (mean_extent, largest_extent) = self.edge_extents(positions);
        let mut cell = cell_size(reach, rest_longest, mean_extent, self.last);
        // Torn strands: bigger cells until few edges are left over.
        loop {
            // An edge crosses at most `extent / cell + 3` cell walls (one
            // more per axis for where it starts; one more for round-off):
            // when the largest cannot reach the limit, none is counted.
            let bound = largest_extent / f64::from(cell) + 4.0;
            self.long_edges = if bound < MAX_CELLS_PER_EDGE as f64 {
                0
            } else {
                self.count_long_edges(positions, 1.0 / cell)
            };
            if self.long_edges <= MAX_LONG_EDGES || cell >= f32::MAX / 4.0 {
                break;
            }
            cell *= 2.0;
        }
        self.inv_cell = 1.0 / cell;
        let chunk_count = positions.len().div_ceil(CHUNK_VERTICES);
        self.place_vertices(positions, chunk_count, reach);
        let scanned = self.find_pushes(positions, reach);
        self.sum_pushes(positions, reach);
        self.last = Some(Measured {
            cell: f64::from(cell),
            scanned: scanned as f64 / placed.max(1) as f64,
        });
    }

    /// The strand of each vertex of an active strand; returns how many
    /// vertices have one.
    fn find_owners(&mut self, vertex_count: usize, offsets: &[usize], active: &[bool]) -> usize {
        self.owner.clear();
        self.owner.resize(vertex_count, u32::MAX);
        let mut owned = 0;
        for (strand, w) in offsets.windows(2).enumerate() {
            if active[strand] {
                self.owner[w[0]..w[1]].fill(strand as u32);
                owned += w[1] - w[0];
            }
        }
        owned
    }

    /// The strand of the edge starting at `v`, when `v + 1` is of the same
    /// active strand.
    #[inline]
    fn edge_strand(owner: &[u32], v: usize) -> Option<u32> {
        let strand = owner[v];
        (strand != u32::MAX && owner.get(v + 1) == Some(&strand)).then_some(strand)
    }

    /// The mean `|dx| + |dy| + |dz|` of the finite edges (about the
    /// cells an edge crosses times the cell size), summed in whole
    /// micrometres: exact in any order, so the cell size does not depend
    /// on the thread count; and the largest of an edge between finite
    /// points (infinite when the difference overflows).
    fn edge_extents(&self, positions: &[V3]) -> (f64, f64) {
        use rayon::prelude::*;
        let owner = &self.owner;
        let edges = positions.len().saturating_sub(1);
        // A plain loop per fixed chunk (a filter-map-reduce per vertex
        // cost 18 ns a vertex); integer sums and a maximum, so the order
        // of the chunks does not matter.
        let (count, micrometres, largest) = (0..edges.div_ceil(CHUNK_VERTICES))
            .into_par_iter()
            .map(|k| {
                let (mut count, mut micrometres, mut largest) = (0u64, 0u64, 0.0f64);
                for v in k * CHUNK_VERTICES..((k + 1) * CHUNK_VERTICES).min(edges) {
                    if Self::edge_strand(owner, v).is_none() {
                        continue;
                    }
                    let (a, b) = (positions[v], positions[v + 1]);
                    let d = sub(b, a);
                    let extent = f64::from(d[0].abs() + d[1].abs() + d[2].abs());
                    if extent.is_finite() {
                        count += 1;
                        // In 0..=1e12: through i64, a single conversion.
                        micrometres += (extent * 1e6).min(1e12) as i64 as u64;
                        largest = largest.max(extent);
                    } else if is_finite3(a) && is_finite3(b) {
                        largest = f64::INFINITY;
                    }
                }
                (count, micrometres, largest)
            })
            .reduce(
                || (0, 0, 0.0),
                |a, b| (a.0 + b.0, a.1.saturating_add(b.1), a.2.max(b.2)),
            );
        let mean = if count > 0 {
            micrometres as f64 * 1e-6 / count as f64
        } else {
            0.0
        };
        (mean, largest)
    }

    /// The finite edges that cross too many cells of size `1 / inv_cell`.
    fn count_long_edges(&self, positions: &[V3], inv_cell: f32) -> usize {
        use rayon::prelude::*;
        let owner = &self.owner;
        (0..positions.len().saturating_sub(1))
            .into_par_iter()
            .with_min_len(CHUNK_VERTICES)
            .filter(|&v| {
                let (a, b) = (positions[v], positions[v + 1]);
                Self::edge_strand(owner, v).is_some()
                    && is_finite3(a)
                    && is_finite3(b)
                    && crossings(cell_of(a, inv_cell), cell_of(b, inv_cell))
                        >= MAX_CELLS_PER_EDGE as i64
            })
            .count()
    }

    /// Each vertex of an active strand into the cells its `reach` box
    /// touches, counting-sorted by bucket.
    fn place_vertices(&mut self, positions: &[V3], chunk_count: usize, reach: f32) {
        use rayon::prelude::*;
        if self.chunks.len() < chunk_count {
            self.chunks.resize_with(chunk_count, Vec::new);
        }
        let (owner, inv_cell) = (&self.owner, self.inv_cell);
        self.chunks[..chunk_count]
            .par_iter_mut()
            .enumerate()
            .for_each(|(k, out)| {
                out.clear();
                if out.capacity() == 0 {
                    out.reserve(CHUNK_VERTICES * MAX_ENTRIES_PER_VERTEX);
                }
                let first = k * CHUNK_VERTICES;
                for v in first..(first + CHUNK_VERTICES).min(positions.len()) {
                    let p = positions[v];
                    if owner[v] == u32::MAX || !is_finite3(p) {
                        continue;
                    }
                    let next = positions.get(v + 1).copied().unwrap_or_default();
                    let edge = if Self::edge_strand(owner, v).is_some() && is_finite3(next) {
                        EDGE
                    } else {
                        0
                    };
                    let lo = cell_of([p[0] - reach, p[1] - reach, p[2] - reach], inv_cell);
                    let hi = cell_of([p[0] + reach, p[1] + reach, p[2] + reach], inv_cell);
                    let entry = |key| Entry {
                        position: p,
                        next,
                        vertex: v as u32,
                        key,
                    };
                    if hi == lo {
                        // Most vertices: one cell.
                        out.push(entry(pack(lo) | HOME | edge));
                        continue;
                    }
                    // More than 2 cells per axis only at far-off
                    // (saturated) coordinates: then the home cell only.
                    let hi = if (0..3).all(|c| i64::from(hi[c]) - i64::from(lo[c]) <= 1) {
                        hi
                    } else {
                        lo
                    };
                    for x in lo[0]..=hi[0] {
                        for y in lo[1]..=hi[1] {
                            for z in lo[2]..=hi[2] {
                                let home = if [x, y, z] == lo { HOME | edge } else { 0 };
                                out.push(entry(pack([x, y, z]) | home));
                            }
                        }
                    }
                }
            });
        let total: usize = self.chunks[..chunk_count].iter().map(Vec::len).sum();
        self.axis_bits = bucket_bits(total);
        sort_into_buckets(
            &self.chunks[..chunk_count],
            self.axis_bits,
            &mut self.scratch,
            &mut self.starts,
            &mut self.entries,
        );
        // Written whole below: resized, not cleared.
        self.probes
            .reserve(self.entries.capacity().saturating_sub(self.probes.len()));
        self.probes.resize(self.entries.len(), Probe::default());
        let owner = &self.owner;
        self.probes
            .par_chunks_mut(CHUNK_ENTRIES)
            .zip(self.entries.par_chunks(CHUNK_ENTRIES))
            .for_each(|(probes, entries)| {
                for (probe, e) in probes.iter_mut().zip(entries) {
                    *probe = Probe {
                        position: e.position,
                        key: e.key & CELL,
                        strand: owner[e.vertex as usize],
                    };
                }
            });
    }

    /// The sorted grid, read by every edge's search.
    fn lookup<'a>(&'a self, positions: &'a [V3], reach: f32) -> Lookup<'a> {
        Lookup {
            entries: &self.entries,
            probes: &self.probes,
            starts: &self.starts,
            owner: &self.owner,
            positions,
            inv_cell: self.inv_cell,
            bits: self.axis_bits,
            reach,
        }
    }

    /// Every edge's pushes, in parallel over fixed chunks of the sorted
    /// entries (each edge at its first vertex's home entry); returns the
    /// entries scanned.
    fn find_pushes(&mut self, positions: &[V3], reach: f32) -> u64 {
        use rayon::prelude::*;
        let chunk_count = self.entries.len().div_ceil(CHUNK_ENTRIES);
        let mut pairs = std::mem::take(&mut self.pairs);
        let mut overflow = std::mem::take(&mut self.overflow);
        let mut scanned = std::mem::take(&mut self.scanned);
        if pairs.len() < chunk_count {
            pairs.resize_with(chunk_count, || Vec::with_capacity(PAIRS_PER_CHUNK));
        }
        overflow.clear();
        overflow.resize(chunk_count, false);
        scanned.clear();
        scanned.resize(chunk_count, 0);
        let max_pairs = match self.max_pairs {
            0 => PAIRS_PER_CHUNK / 2,
            n => n,
        };
        let lookup = self.lookup(positions, reach);
        self.entries
            .par_chunks(CHUNK_ENTRIES)
            .zip(self.probes.par_chunks(CHUNK_ENTRIES))
            .zip(pairs[..chunk_count].par_iter_mut())
            .zip(overflow.par_iter_mut())
            .zip(scanned.par_iter_mut())
            .for_each(|((((entries, probes), pairs), overflow), scanned)| {
                pairs.clear();
                let mut batch = Batch::new();
                // The strand from the entry's probe, read in order (the
                // owner table, indexed by vertex, is read at random).
                for (e, probe) in entries
                    .iter()
                    .zip(probes)
                    .filter(|(e, _)| e.key & (HOME | EDGE) == HOME | EDGE)
                {
                    if batch.is_full() && !lookup.search(&mut batch, max_pairs, pairs, scanned) {
                        *overflow = true;
                        return;
                    }
                    lookup.walk(&mut batch, e.vertex, probe.strand, e.position, e.next);
                }
                if !lookup.search(&mut batch, max_pairs, pairs, scanned) {
                    *overflow = true;
                }
            });
        let total = scanned.iter().sum();
        (self.pairs, self.overflow, self.scanned) = (pairs, overflow, scanned);
        total
    }

    /// Every vertex's sum of its pushes in edge order: sorted, or (when a
    /// chunk found too many) edge by edge.
    fn sum_pushes(&mut self, positions: &[V3], reach: f32) {
        let chunk_count = self.entries.len().div_ceil(CHUNK_ENTRIES);
        let mut sums = std::mem::take(&mut self.sums);
        let mut all = std::mem::take(&mut self.all_pairs);
        sums.clear();
        sums.resize(positions.len(), [0.0; 3]);
        all.clear();
        if all.capacity() == 0 {
            // Room for a dense tangle's pushes, so a warm step does not grow them.
            all.reserve(positions.len() / 4 + 1024);
        }
        if self.overflow.iter().any(|&o| o) {
            let lookup = self.lookup(positions, reach);
            let mut scanned = 0;
            let mut batch = Batch::new();
            for edge in 0..positions.len() {
                all.clear();
                lookup.edge_pushes(edge, &mut batch, &mut all, &mut scanned);
                add_pushes(&mut sums, &all);
            }
        } else {
            for pairs in &self.pairs[..chunk_count] {
                all.extend_from_slice(pairs);
            }
            // Unique keys (an edge keeps a vertex once): any sort gives
            // the same order.
            all.sort_unstable_by_key(|&(v, edge, _)| (v, edge));
            add_pushes(&mut sums, &all);
        }
        all.clear();
        self.sums = sums;
        self.all_pairs = all;
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

/// Adds each push to its vertex's sum, in the order given.
fn add_pushes(sums: &mut [V3], pairs: &[Pair]) {
    for &(v, _, push) in pairs {
        let s = &mut sums[v as usize];
        *s = [s[0] + push[0], s[1] + push[1], s[2] + push[2]];
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

/// A cheap first test of [`edge_push`]: the distance to the edge's line
/// (never more than to the segment), without a division.
struct NearLine {
    a: V3,
    ab: V3,
    /// `reach^2 |ab|^2` with 1 % to spare for round-off (the squared
    /// distance is off by about 1e-5 of itself at `reach`).
    limit: f32,
}

impl NearLine {
    #[inline]
    fn new(a: V3, b: V3, reach: f32) -> Self {
        let ab = sub(b, a);
        NearLine {
            a,
            ab,
            limit: reach * reach * dot(ab, ab) * 1.01,
        }
    }

    /// False only when `p` is beyond the reach of the segment.
    #[inline]
    fn may_reach(&self, p: V3) -> bool {
        let c = cross(sub(p, self.a), self.ab);
        dot(c, c) <= self.limit
    }
}

/// The sorted grid, read by every edge's search.
struct Lookup<'a> {
    entries: &'a [Entry],
    probes: &'a [Probe],
    starts: &'a [u32],
    owner: &'a [u32],
    positions: &'a [V3],
    inv_cell: f32,
    bits: u32,
    reach: f32,
}

impl Lookup<'_> {
    /// Appends to `out` the [`edge_push`] of the edge starting at vertex
    /// `edge` on every vertex of another strand within `reach`, each once
    /// (`batch` empty, and left empty); `scanned` counts the entries
    /// looked at.
    fn edge_pushes(&self, edge: usize, batch: &mut Batch, out: &mut Vec<Pair>, scanned: &mut u64) {
        if EdgeGrid::edge_strand(self.owner, edge).is_none() {
            return;
        }
        let (a, b) = (self.positions[edge], self.positions[edge + 1]);
        if is_finite3(a) && is_finite3(b) {
            // A batch of one edge: no limit on its pushes, so it completes.
            self.walk(batch, edge as u32, self.owner[edge], a, b);
            self.search(batch, usize::MAX, out, scanned);
        }
    }

    /// The pushes of edge `edge` (of `strand`, `near` its line, ending at
    /// `b`) on the vertices of the entries `cell` (a bucket's range) in
    /// cell `key`, in entry order.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn scan_cell(
        &self,
        key: u32,
        cell: (u32, u32),
        edge: u32,
        strand: u32,
        near: &NearLine,
        b: V3,
        out: &mut Vec<Pair>,
        scanned: &mut u64,
    ) {
        let (start, end) = (cell.0 as usize, cell.1 as usize);
        *scanned += (end - start) as u64;
        for (i, e) in self.probes[start..end].iter().enumerate() {
            if e.key != key || e.strand == strand || !near.may_reach(e.position) {
                continue;
            }
            if let Some(push) = edge_push(e.position, near.a, b, self.reach) {
                out.push((self.entries[start + i].vertex, edge, push));
            }
        }
    }

    /// An edge too long to walk: its pushes on every vertex of another
    /// active strand.
    fn every_vertex(
        &self,
        edge: u32,
        strand: u32,
        a: V3,
        b: V3,
        out: &mut Vec<Pair>,
        scanned: &mut u64,
    ) {
        *scanned += self.positions.len() as u64;
        for (v, (&p, &owner)) in self.positions.iter().zip(self.owner).enumerate() {
            if owner == u32::MAX || owner == strand {
                continue;
            }
            if let Some(push) = edge_push(p, a, b, self.reach) {
                out.push((v as u32, edge, push));
            }
        }
    }

    /// Adds an edge (its first vertex `edge`, of `strand`, from `a` to
    /// `b`) to `batch` with the cells it walks, and asks the cache for
    /// their buckets' starts.
    #[inline]
    fn walk(&self, batch: &mut Batch, edge: u32, strand: u32, a: V3, b: V3) {
        let first = batch.visit_count;
        let walked = walk_cells(a, b, self.inv_cell, |key| {
            let bucket = bucket_of(unpack(key), self.bits);
            if let Some(start) = self.starts.get(bucket) {
                prefetch(start);
            }
            batch.visits[batch.visit_count] = Visit {
                key,
                bucket: bucket as u32,
                cell: (0, 0),
            };
            batch.visit_count += 1;
        });
        batch.edges[batch.edge_count] = BatchEdge {
            edge,
            strand,
            a,
            b,
            visits: (first as u16, batch.visit_count as u16),
            walked,
        };
        batch.edge_count += 1;
    }

    /// The pushes of the edges of `batch` appended to `out` in order,
    /// each edge's as [`Self::edge_pushes`] describes; the batch is left
    /// empty. In passes, each reading what the pass before asked of the
    /// cache: the buckets' starts (asked for by [`Self::walk`]), which ask
    /// for each bucket's first entries, then the scans. False when the
    /// pushes reached `max_pairs` (the rest not searched).
    fn search(
        &self,
        batch: &mut Batch,
        max_pairs: usize,
        out: &mut Vec<Pair>,
        scanned: &mut u64,
    ) -> bool {
        for visit in &mut batch.visits[..batch.visit_count] {
            let bucket = visit.bucket as usize;
            visit.cell = (self.starts[bucket], self.starts[bucket + 1]);
            if let Some(probe) = self.probes.get(visit.cell.0 as usize) {
                prefetch(probe);
            }
        }
        let mut complete = true;
        for edge in &batch.edges[..batch.edge_count] {
            if out.len() >= max_pairs {
                complete = false;
                break;
            }
            let first = out.len();
            if edge.walked {
                let near = NearLine::new(edge.a, edge.b, self.reach);
                let (from, to) = (usize::from(edge.visits.0), usize::from(edge.visits.1));
                for visit in &batch.visits[from..to] {
                    let cell = visit.cell;
                    self.scan_cell(
                        visit.key,
                        cell,
                        edge.edge,
                        edge.strand,
                        &near,
                        edge.b,
                        out,
                        scanned,
                    );
                }
                keep_once(out, first);
            } else {
                self.every_vertex(edge.edge, edge.strand, edge.a, edge.b, out, scanned);
            }
        }
        batch.edge_count = 0;
        batch.visit_count = 0;
        complete
    }
}

/// Drops the repeats of `out[first..]` (one edge's pushes): a vertex met
/// in several cells pushes the same each time, and counts once.
fn keep_once(out: &mut Vec<Pair>, first: usize) {
    if out.len() - first > 1 {
        out[first..].sort_unstable_by_key(|&(v, _, _)| v);
        let mut kept = first + 1;
        for i in first + 1..out.len() {
            if out[i].0 != out[kept - 1].0 {
                out[kept] = out[i];
                kept += 1;
            }
        }
        out.truncate(kept);
    }
}

/// Cells a batch of edges walks before its search (once past this, the
/// batch is searched: each edge walks at most [`MAX_CELLS_PER_EDGE`]).
const BATCH_CELLS: usize = 64;
/// Edges a batch holds at most (an edge walks one cell at least).
const BATCH_EDGES: usize = BATCH_CELLS;

/// A cell an edge of a batch walks, and its bucket's entries.
#[derive(Clone, Copy, Default)]
struct Visit {
    key: u32,
    bucket: u32,
    /// The bucket's range of entries, once read.
    cell: (u32, u32),
}

/// An edge of a batch: its first vertex, strand and ends, and its visits.
#[derive(Clone, Copy, Default)]
struct BatchEdge {
    edge: u32,
    strand: u32,
    a: V3,
    b: V3,
    visits: (u16, u16),
    /// False when it crossed too many cells (it tests every vertex).
    walked: bool,
}

/// Edges searched together, so that their memory reads overlap (each
/// edge alone waits on one cell's read after another). On the stack:
/// no allocation.
struct Batch {
    visits: [Visit; BATCH_CELLS + MAX_CELLS_PER_EDGE],
    visit_count: usize,
    edges: [BatchEdge; BATCH_EDGES],
    edge_count: usize,
}

impl Batch {
    fn new() -> Self {
        Batch {
            visits: [Visit::default(); BATCH_CELLS + MAX_CELLS_PER_EDGE],
            visit_count: 0,
            edges: [BatchEdge::default(); BATCH_EDGES],
            edge_count: 0,
        }
    }

    /// True when the next edge might not fit.
    fn is_full(&self) -> bool {
        self.visit_count >= BATCH_CELLS || self.edge_count >= BATCH_EDGES
    }
}

#[cfg(test)]
mod tests;
