//! Volumetric hair-hair for dense grooms (Petrovic, Henne, Anderson 2005,
//! "Volumetric methods for simulation and rendering of hair"; McAdams et
//! al. 2009): the hair's volume and momentum are spread on a grid of
//! nodes (trilinear weights); each vertex's velocity then moves toward the
//! hair's mean velocity around it (volumetric friction) and the hair is
//! pushed from denser to less dense regions (down the gradient of the
//! volume fraction). The cost is linear in the vertex count whatever the
//! density, unlike the pairwise penalty (20) whose pairs grow with it.
//!
//! Order of a build: the hair's box and cells; the active strands ordered
//! by their roots along a Z-order curve (neighbouring strands then touch
//! the same nodes one after the other, in cache); each of a fixed number
//! of ranges of that order spread on its own grid; the grids summed node
//! by node in range order; every vertex's change gathered (strand by
//! strand in the same order, where the step reads it); the nodes written
//! cleared again. Each grid is zero between steps and only the span of
//! each row of nodes that the hair touched is summed and cleared: hair
//! fills a thin shell of its box.
//!
//! Deterministic for any thread count: the order, the ranges and the sums'
//! order are fixed; the changes are only read. Buffers are kept from step
//! to step (no allocation once warm, unless the hair's box grows).

use crate::sim::avx::eight_to_lanes;
use crate::sim::instructions::{in_widest, prefetch, Instructions};
#[cfg(target_arch = "x86_64")]
use crate::sim::math::{is_finite3, V3};
use serde::{Deserialize, Serialize};

/// The settings of the volumetric mode (units in the names' docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Volumetric {
    /// Edge of a grid cell, metres (0.001 - 0.05): the distance over
    /// which hair averages its motion.
    pub cell_size: f32,
    /// Rate at which a vertex's velocity goes to the hair's mean velocity
    /// around it, per second (0 - 1000): the share `1 - exp(-rate dt)` of
    /// the difference goes each step.
    pub smoothing: f32,
    /// Push from denser toward less dense hair, m^2/s^2 (0 - 1000): the
    /// acceleration is `-repulsion * grad(phi)`, `phi` the volume fraction
    /// of hair (hair volume per volume, from the fibre radii).
    pub repulsion: f32,
    /// Friction through the grid, 1/s per unit volume fraction (0 -
    /// 10,000; 0: off): a vertex's velocity also moves toward the hair's
    /// mean velocity around it at the rate `friction * phi`, so hair in
    /// dense regions moves with its neighbours (Petrovic, Henne, Anderson
    /// 2005: friction as a filter toward the grid's velocity; McAdams et
    /// al. 2009), while lone strands move freely. Combed hair is at `phi`
    /// about 0.05 - 0.3: `friction = 1000` then takes 13 - 57 % of the
    /// difference each step at dt 1/360 (the share is `friction phi dt`,
    /// at most 1).
    pub friction: f32,
}

impl Default for Volumetric {
    fn default() -> Self {
        Volumetric {
            cell_size: 0.005,
            smoothing: 20.0,
            repulsion: 10.0,
            friction: 0.0,
        }
    }
}

impl Volumetric {
    /// Why the settings are unusable, if they are.
    pub fn problem(&self) -> Option<&'static str> {
        if !(self.cell_size.is_finite() && (0.001..=0.05).contains(&self.cell_size)) {
            return Some("cell_size must be 0.001 to 0.05 metres");
        }
        if !(self.smoothing.is_finite() && (0.0..=1000.0).contains(&self.smoothing)) {
            return Some("smoothing must be 0 to 1000 per second");
        }
        if !(self.repulsion.is_finite() && (0.0..=1000.0).contains(&self.repulsion)) {
            return Some("repulsion must be 0 to 1000 m^2/s^2");
        }
        if !(self.friction.is_finite() && (0.0..=10_000.0).contains(&self.friction)) {
            return Some("grid_friction must be 0 to 10000 per second per unit volume fraction");
        }
        None
    }
}

/// Strand ranges spread apart, each on its own grid (fixed, so the sums'
/// order is too). Two: every further range costs a grid to sum and to
/// clear each step, which on this 2-core machine cost more than the
/// spreading it parallelised.
const RANGES: usize = 2;
/// The most grid nodes: past it the cells grow (a bound on memory for
/// hair spread far apart).
const MAX_NODES: usize = 1 << 20;
/// Rows of nodes (along z) summed per task.
const ROWS_PER_TASK: usize = 64;
/// Vertices per task of the gather.
const GATHER_CHUNK: usize = 4096;
/// How many vertices ahead the gather asks for its nodes (4 was slower,
/// 8 and 16 about 15 % faster at 10,000 strands; the spreading gained
/// nothing from it: its time goes to adding into the nodes).
const PREFETCH_AHEAD: usize = 16;

/// Per node: hair volume (m^3) and its momentum-like sum (volume x
/// velocity). In this order (`repr(C)`): the gather loads a node as one
/// four-float register.
#[derive(Debug, Clone, Copy, Default)]
#[repr(C)]
struct Node {
    volume: f32,
    flow: V3,
}

impl Node {
    /// Volume, then flow.
    #[inline]
    fn values(&self) -> [f32; 4] {
        [self.volume, self.flow[0], self.flow[1], self.flow[2]]
    }

    #[inline]
    fn add(&mut self, other: &Node) {
        self.volume += other.volume;
        for c in 0..3 {
            self.flow[c] += other.flow[c];
        }
    }
}

/// The nodes a row (fixed x and y) has written: `start..end` along z
/// (empty when `start >= end`).
#[derive(Debug, Clone, Copy)]
struct Span {
    start: u32,
    end: u32,
}

impl Span {
    const EMPTY: Span = Span {
        start: u32::MAX,
        end: 0,
    };

    #[inline]
    fn cover(&mut self, start: usize, end: usize) {
        self.start = self.start.min(start as u32);
        self.end = self.end.max(end as u32);
    }

    /// Widens this span over `other` (nothing when `other` is empty).
    fn join(&mut self, other: Span) {
        if other.start < other.end {
            self.start = self.start.min(other.start);
            self.end = self.end.max(other.end);
        }
    }

    fn range(&self) -> std::ops::Range<usize> {
        if self.start < self.end {
            self.start as usize..self.end as usize
        } else {
            0..0
        }
    }
}

/// Where a vertex sits on the grid: its base node's index and its
/// fractions along x, y, z (found once by the spreading, read by the
/// gather). In this order (`repr(C)`): the gather loads a place as one
/// four-float register.
#[derive(Debug, Clone, Copy, Default)]
#[repr(C)]
struct Place {
    /// `OFF` when the vertex is off the grid.
    first: u32,
    fraction: V3,
}

impl Place {
    const OFF: u32 = u32::MAX;
}

/// One range's grid and, per row, the nodes it wrote.
#[derive(Debug, Default)]
struct Partial {
    nodes: Vec<Node>,
    spans: Vec<Span>,
}

/// Where the grid lies: its first node, cells per metre and nodes per
/// axis (x, then y, then z fastest).
#[derive(Debug, Clone, Copy, Default)]
struct Placement {
    origin: V3,
    inv_cell: f32,
    dims: [usize; 3],
}

impl Placement {
    fn node_count(&self) -> usize {
        self.dims.iter().product()
    }

    fn row_count(&self) -> usize {
        self.dims[0] * self.dims[1]
    }

    /// A vertex's base node and trilinear fractions, or `None` off the grid.
    #[inline]
    fn locate(&self, p: V3) -> Option<([usize; 3], V3)> {
        let mut base = [0usize; 3];
        let mut frac = [0.0f32; 3];
        for c in 0..3 {
            let x = (p[c] - self.origin[c]) * self.inv_cell;
            if !(x >= 0.0 && x < (self.dims[c] - 1) as f32) {
                return None;
            }
            let i = x as usize;
            base[c] = i.min(self.dims[c] - 2);
            frac[c] = x - base[c] as f32;
        }
        Some((base, frac))
    }

    /// The row of a base node (its x and y).
    #[inline]
    fn row(&self, base: [usize; 3]) -> usize {
        base[0] * self.dims[1] + base[1]
    }

    /// The index of a base node.
    #[inline]
    fn index(&self, base: [usize; 3]) -> usize {
        self.row(base) * self.dims[2] + base[2]
    }

    /// Asks the cache for the eight nodes of base node `first` (four rows
    /// of two along z). Where the hair goes next is known here, not to
    /// the hardware, and the grid is megabytes.
    #[inline(always)]
    fn prefetch(&self, nodes: &[Node], first: usize) {
        let (rows, row) = (self.dims[1], self.dims[2]);
        for k in [0, row, rows * row, (rows + 1) * row] {
            if let Some(node) = nodes.get(first + k) {
                prefetch(node);
            }
        }
    }

    /// The nodes (x, y) steps from base node `first` (its index): the
    /// pair along z there.
    #[inline]
    fn pair(&self, nodes: &[Node], first: usize, dx: usize, dy: usize) -> [[f32; 4]; 2] {
        let k = first + (dx * self.dims[1] + dy) * self.dims[2];
        [nodes[k].values(), nodes[k + 1].values()]
    }
}

/// The trilinear weights along one axis at fraction `f`: of the node
/// below and the one above.
#[inline]
fn weights(f: f32) -> [f32; 2] {
    [1.0 - f, f]
}

/// `a + (b - a) t`, componentwise.
#[inline]
fn lerp4(a: [f32; 4], b: [f32; 4], t: f32) -> [f32; 4] {
    std::array::from_fn(|c| a[c] + (b[c] - a[c]) * t)
}

#[inline]
fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a + (b - a) * t
}

/// The grid and the per-vertex velocity changes of one step.
///
/// Every node of `partial` is zero between steps: a step clears only the
/// spans of rows it wrote (a step used to clear and sum every node of
/// five grids, tens of megabytes at 10,000 strands).
#[derive(Debug, Default)]
pub struct VolumeGrid {
    grid: Placement,
    /// Per vertex range, its own grid.
    partial: Vec<Partial>,
    /// The active strands in the order they are spread and read (see
    /// [`VolumeGrid::order_strands`]), with a scratch of sort keys.
    order: Vec<u32>,
    keys: Vec<(u64, u32)>,
    /// Where each strand of `order` starts in `ordered_dv`, and the end.
    ordered_starts: Vec<usize>,
    /// Per strand, its start in `ordered_dv` (`usize::MAX` when inactive):
    /// the step reads a strand's changes there.
    start_of: Vec<usize>,
    /// The velocity changes of the ordered strands, one after the other.
    ordered_dv: Vec<V3>,
    /// The places of the ordered strands' vertices, likewise.
    places: Vec<Place>,
}

/// `grid` at `count` nodes, all zero as it already is; a grid that must
/// grow takes twice the room, so hair that spreads as it falls does not
/// allocate every step.
fn sized(grid: &mut Vec<Node>, count: usize) {
    if grid.capacity() < count {
        let room = (2 * count).min(MAX_NODES.max(count));
        grid.reserve_exact(room - grid.len());
    }
    grid.resize(count, Node::default());
}

/// Zeroes each row's span of `nodes` (rows of `row_length` nodes).
fn clear_spans(nodes: &mut [Node], spans: &[Span], row_length: usize) {
    for (row, span) in nodes.chunks_mut(row_length).zip(spans) {
        row[span.range()].fill(Node::default());
    }
}

/// Spreads the vertices of `strands` (in that order) on `nodes`, widening
/// each row's span over the nodes written.
fn spread(instructions: Instructions, strands: &[u32], hair: &Hair, grid: &Placement, out: Spread) {
    in_widest!(
        instructions,
        fn(strands: &[u32], hair: &Hair, grid: &Placement, out: Spread) {
            spread_strands(strands, hair, grid, out)
        }
    )
}

/// What one range's spreading writes: its grid, each row's span, and the
/// place of each of its vertices (in order).
struct Spread<'a> {
    nodes: &'a mut [Node],
    spans: &'a mut [Span],
    places: &'a mut [Place],
}

#[inline(always)]
fn spread_strands(strands: &[u32], hair: &Hair, grid: &Placement, out: Spread) {
    let Spread {
        nodes,
        spans,
        places,
    } = out;
    let mut places = places.iter_mut();
    let Hair {
        positions,
        velocities,
        radii,
        offsets,
    } = *hair;
    for &strand in strands {
        let strand = strand as usize;
        let (a, b) = (offsets[strand], offsets[strand + 1]);
        // The vertex's share of its strand: half of each adjacent edge
        // (each edge's half found once, carried to the next vertex).
        let half = |j: usize| {
            let (x, y) = (positions[j], positions[j + 1]);
            let d = [y[0] - x[0], y[1] - x[1], y[2] - x[2]];
            0.5 * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
        };
        let mut before = 0.0;
        for i in a..b {
            let after = if i + 1 < b { half(i) } else { 0.0 };
            let length = before + after;
            before = after;
            let located = grid.locate(positions[i]);
            if let Some(place) = places.next() {
                *place = match located {
                    Some((base, fraction)) => Place {
                        first: grid.index(base) as u32,
                        fraction,
                    },
                    None => Place {
                        first: Place::OFF,
                        fraction: [0.0; 3],
                    },
                };
            }
            let Some((base, f)) = located else {
                continue;
            };
            let r = radii[i];
            let volume = std::f32::consts::PI * r * r * length;
            if !(volume.is_finite() && is_finite3(velocities[i])) {
                continue;
            }
            let v = velocities[i];
            let row = grid.row(base);
            for next in [row, row + 1, row + grid.dims[1], row + grid.dims[1] + 1] {
                spans[next].cover(base[2], base[2] + 2);
            }
            let first = grid.index(base);
            let [wx, wy, wz] = [weights(f[0]), weights(f[1]), weights(f[2])];
            for (dx, wx) in wx.into_iter().enumerate() {
                for (dy, wy) in wy.into_iter().enumerate() {
                    let k = first + (dx * grid.dims[1] + dy) * grid.dims[2];
                    let wxy = volume * wx * wy;
                    for (dz, wz) in wz.into_iter().enumerate() {
                        let w = wxy * wz;
                        let node = &mut nodes[k + dz];
                        node.volume += w;
                        for (flow, v) in node.flow.iter_mut().zip(v) {
                            *flow += w * v;
                        }
                    }
                }
            }
        }
    }
}

/// The hair a step spreads: per vertex its position, velocity and radius;
/// strands as in StrandSet.
#[derive(Clone, Copy)]
struct Hair<'a> {
    positions: &'a [V3],
    velocities: &'a [V3],
    radii: &'a [f32],
    offsets: &'a [usize],
}

/// What the gather reads: the summed grid, the ordered strands (`order`
/// and `starts` as in [`VolumeGrid`], `offsets` as in StrandSet) and the
/// step's settings.
struct Gather<'a> {
    /// The widest the gather may use (AVX2 or wider: in lanes).
    instructions: Instructions,
    grid: Placement,
    nodes: &'a [Node],
    places: &'a [Place],
    velocities: &'a [V3],
    order: &'a [u32],
    starts: &'a [usize],
    offsets: &'a [usize],
    /// The share of the velocity difference taken this step.
    keep: f32,
    /// Repulsion times dt.
    push: f32,
    /// Grid friction times dt per node volume (share of the difference
    /// per unit of interpolated node volume; 0: off).
    friction: f32,
    /// From node volumes to the volume fraction's gradient.
    scale: f32,
}

impl Gather<'_> {
    /// The changes of ordered slots `first..` into `out` (zero off the
    /// grid).
    /// In AVX2 or wider, eight slots at a time in the lanes.
    fn chunk(&self, first: usize, out: &mut [V3]) {
        let gather = self;
        in_widest!(
            self.instructions,
            fn<const WIDE;>(gather: &Gather<'_>, first: usize, out: &mut [V3]) {
                gather.chunk_slots::<WIDE>(first, out)
            }
        )
    }

    /// `LANES`: eight slots at a time through [`Gather::eight`] (only in
    /// a function compiled for AVX2 or wider).
    #[inline(always)]
    fn chunk_slots<const LANES: bool>(&self, first: usize, out: &mut [V3]) {
        let (order, starts, offsets) = (self.order, self.starts, self.offsets);
        // The ordered strand holding slot `first`, then on.
        let mut at = starts.partition_point(|&s| s <= first) - 1;
        let mut vertex = |slot: usize| {
            while starts[at + 1] <= slot {
                at += 1;
            }
            offsets[order[at] as usize] + (slot - starts[at])
        };
        let mut done = 0;
        #[cfg(target_arch = "x86_64")]
        if LANES {
            for block in out.chunks_exact_mut(8) {
                let slot = first + done;
                let vertices: [usize; 8] = std::array::from_fn(|l| vertex(slot + l));
                for l in 0..8 {
                    self.prefetch(slot + l + PREFETCH_AHEAD);
                }
                // SAFETY: `LANES` is only set in code compiled for
                // AVX2 or AVX-512F, which the CPU has.
                if !unsafe { self.eight(slot, &vertices, block) } {
                    for (l, dv) in block.iter_mut().enumerate() {
                        *dv = self.change_at(slot + l, vertices[l]).unwrap_or([0.0; 3]);
                    }
                }
                done += 8;
            }
        }
        for (j, dv) in out.iter_mut().enumerate().skip(done) {
            let slot = first + j;
            let i = vertex(slot);
            self.prefetch(slot + PREFETCH_AHEAD);
            *dv = self.change_at(slot, i).unwrap_or([0.0; 3]);
        }
    }

    /// [`Gather::change_at`] of the eight slots from `slot` (their vertices
    /// `vertices`) into `out`, one slot per lane of AVX registers: per
    /// lane the same operations in the same order, so the same bits. The
    /// places and nodes are loaded as four-float registers and transposed
    /// (a register per value, a lane per slot). One slot at a time, the
    /// gather was a chain of dependent operations ending in a division,
    /// with few slots in flight. Returns false, writing nothing, when a
    /// lane's nodes or vertex would be out of bounds (the caller then
    /// takes `change_at`'s checked reads). Hand-written: the compiler
    /// does not turn the per-vertex layout into lanes.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn eight(&self, slot: usize, vertices: &[usize; 8], out: &mut [V3]) -> bool {
        use std::arch::x86_64::*;
        let (grid, nodes) = (&self.grid, self.nodes);
        let Some(places) = self.places.get(slot..slot + 8) else {
            return false;
        };
        let (rows, row) = (grid.dims[1], grid.dims[2]);
        // The farthest node a place reads, from its base node.
        let reach = (rows + 1) * row + 1;
        let mut bases = [0usize; 8];
        let mut on = [0u32; 8];
        for l in 0..8 {
            if places[l].first != Place::OFF {
                bases[l] = places[l].first as usize;
                on[l] = u32::MAX;
            }
            if bases[l] + reach >= nodes.len() || vertices[l] >= self.velocities.len() {
                return false;
            }
        }
        // SAFETY (the loads): a `Place` and a `Node` are four `f32`s
        // (`repr(C)`), and every index was checked against its slice above.
        let [_, f0, f1, f2] = eight_to_lanes(std::array::from_fn(|l| unsafe {
            _mm_loadu_ps(std::ptr::from_ref(&places[l]).cast())
        }));
        let corner = |dx: usize, dy: usize, dz: usize| -> [__m256; 4] {
            let k = (dx * rows + dy) * row + dz;
            eight_to_lanes(std::array::from_fn(|l| unsafe {
                _mm_loadu_ps(nodes.as_ptr().add(bases[l] + k).cast())
            }))
        };
        let lerp = |a: __m256, b: __m256, t: __m256| {
            _mm256_add_ps(a, _mm256_mul_ps(_mm256_sub_ps(b, a), t))
        };
        let lerp4 = |a: [__m256; 4], b: [__m256; 4], t: __m256| -> [__m256; 4] {
            std::array::from_fn(|c| lerp(a[c], b[c], t))
        };
        // As `change_at`: along z, y, then x, and the volume's differences.
        let mut along_y = [[_mm256_setzero_ps(); 4]; 2];
        let mut dy_volume = [_mm256_setzero_ps(); 2];
        let mut dz_volume = [_mm256_setzero_ps(); 2];
        for dx in 0..2 {
            let low = [corner(dx, 0, 0), corner(dx, 0, 1)];
            let high = [corner(dx, 1, 0), corner(dx, 1, 1)];
            let (z_low, z_high) = (lerp4(low[0], low[1], f2), lerp4(high[0], high[1], f2));
            along_y[dx] = lerp4(z_low, z_high, f1);
            dy_volume[dx] = _mm256_sub_ps(z_high[0], z_low[0]);
            dz_volume[dx] = lerp(
                _mm256_sub_ps(low[1][0], low[0][0]),
                _mm256_sub_ps(high[1][0], high[0][0]),
                f1,
            );
        }
        let [volume, fx, fy, fz] = lerp4(along_y[0], along_y[1], f0);
        let gradient = [
            _mm256_sub_ps(along_y[1][0], along_y[0][0]),
            lerp(dy_volume[0], dy_volume[1], f0),
            lerp(dz_volume[0], dz_volume[1], f0),
        ];
        let v: [__m256; 3] = std::array::from_fn(|c| {
            let at = |l: usize| self.velocities[vertices[l]][c];
            _mm256_setr_ps(at(0), at(1), at(2), at(3), at(4), at(5), at(6), at(7))
        });
        let (mut keep, push, scale) = (
            _mm256_set1_ps(self.keep),
            _mm256_set1_ps(self.push),
            _mm256_set1_ps(self.scale),
        );
        if self.friction > 0.0 {
            // As `change_at`: `keep + (1 - keep) min(friction volume, 1)`.
            let one = _mm256_set1_ps(1.0);
            let share = _mm256_min_ps(_mm256_mul_ps(_mm256_set1_ps(self.friction), volume), one);
            keep = _mm256_add_ps(keep, _mm256_mul_ps(_mm256_sub_ps(one, keep), share));
        }
        // Where there is no hair volume the change is `0 - push`, as in
        // `change_at` (the lanes divide anyway and drop the quotient).
        let positive = _mm256_cmp_ps::<_CMP_GT_OQ>(volume, _mm256_setzero_ps());
        let per_volume = _mm256_div_ps(_mm256_set1_ps(1.0), volume);
        let mut kept = _mm256_castsi256_ps(_mm256_loadu_si256(on.as_ptr().cast()));
        let (largest, sign) = (_mm256_set1_ps(f32::MAX), _mm256_set1_ps(-0.0));
        let mut change = [_mm256_setzero_ps(); 3];
        for (c, flow) in [fx, fy, fz].into_iter().enumerate() {
            let toward = _mm256_sub_ps(_mm256_mul_ps(flow, per_volume), v[c]);
            change[c] = _mm256_sub_ps(
                _mm256_and_ps(positive, _mm256_mul_ps(keep, toward)),
                _mm256_mul_ps(_mm256_mul_ps(push, gradient[c]), scale),
            );
            // `is_finite`: |x| <= MAX, false for infinities and NaN.
            let magnitude = _mm256_andnot_ps(sign, change[c]);
            kept = _mm256_and_ps(kept, _mm256_cmp_ps::<_CMP_LE_OQ>(magnitude, largest));
        }
        let mut lanes = [[0.0f32; 8]; 3];
        for (lane, change) in lanes.iter_mut().zip(change) {
            _mm256_storeu_ps(lane.as_mut_ptr(), _mm256_and_ps(kept, change));
        }
        for (l, dv) in out.iter_mut().enumerate() {
            *dv = [lanes[0][l], lanes[1][l], lanes[2][l]];
        }
        true
    }

    /// Asks the cache for the nodes the gather at `slot` will read.
    #[inline(always)]
    fn prefetch(&self, slot: usize) {
        if let Some(place) = self.places.get(slot) {
            if place.first != Place::OFF {
                self.grid.prefetch(self.nodes, place.first as usize);
            }
        }
    }

    #[inline(always)]
    fn change_at(&self, slot: usize, i: usize) -> Option<V3> {
        let (grid, nodes) = (&self.grid, self.nodes);
        let (keep, push, scale) = (self.keep, self.push, self.scale);
        let place = self.places[slot];
        if place.first == Place::OFF {
            return None;
        }
        let (first, f) = (place.first as usize, place.fraction);
        // Trilinear, one axis at a time (z, y, x); the volume's gradient
        // (per cell) from the differences across each axis.
        let mut along_y = [[0.0f32; 4]; 2];
        let mut dy_volume = [0.0f32; 2];
        let mut dz_volume = [0.0f32; 2];
        for (dx, (y_lerp, (dy_v, dz_v))) in along_y
            .iter_mut()
            .zip(dy_volume.iter_mut().zip(dz_volume.iter_mut()))
            .enumerate()
        {
            let [low, high] = [0, 1].map(|dy| grid.pair(nodes, first, dx, dy));
            let (z_low, z_high) = (lerp4(low[0], low[1], f[2]), lerp4(high[0], high[1], f[2]));
            *y_lerp = lerp4(z_low, z_high, f[1]);
            *dy_v = z_high[0] - z_low[0];
            *dz_v = lerp(low[1][0] - low[0][0], high[1][0] - high[0][0], f[1]);
        }
        let [volume, fx, fy, fz] = lerp4(along_y[0], along_y[1], f[0]);
        let flow = [fx, fy, fz];
        let gradient = [
            along_y[1][0] - along_y[0][0],
            lerp(dy_volume[0], dy_volume[1], f[0]),
            lerp(dz_volume[0], dz_volume[1], f[0]),
        ];
        let v = self.velocities[i];
        let mut change = [0.0f32; 3];
        if volume > 0.0 {
            // Grid friction: a larger share where the hair is dense.
            let keep = if self.friction > 0.0 {
                keep + (1.0 - keep) * (self.friction * volume).min(1.0)
            } else {
                keep
            };
            // One division, not three (a tenth of the gather's time).
            let per_volume = 1.0 / volume;
            for c in 0..3 {
                change[c] = keep * (flow[c] * per_volume - v[c]);
            }
        }
        for c in 0..3 {
            change[c] -= push * gradient[c] * scale;
        }
        is_finite3(change).then_some(change)
    }
}

/// The Z-order (Morton) code of a cell: the bits of x, y, z interleaved
/// (a dozen lines of bit spreading; no dependency for it).
fn morton(cell: [u32; 3]) -> u64 {
    let spread = |v: u32| {
        let mut x = u64::from(v) & 0x1f_ffff;
        x = (x | x << 32) & 0x1f_0000_0000_ffff;
        x = (x | x << 16) & 0x1f_0000_ff00_00ff;
        x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
        x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
        (x | x << 2) & 0x1249_2492_4924_9249
    };
    spread(cell[0]) << 2 | spread(cell[1]) << 1 | spread(cell[2])
}

/// The box of the active strands' finite vertices, if any (min and max
/// are exact in any order, so the box does not depend on the threads).
fn active_box(positions: &[V3], offsets: &[usize], active: &[bool]) -> Option<(V3, V3)> {
    use rayon::prelude::*;
    let empty = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    let (lo, hi) = offsets
        .par_windows(2)
        .zip(active.par_iter())
        .filter(|(_, &on)| on)
        .map(|(w, _)| {
            let mut bounds = empty;
            for p in positions[w[0]..w[1]].iter().filter(|p| is_finite3(**p)) {
                bounds.0 = std::array::from_fn(|c| bounds.0[c].min(p[c]));
                bounds.1 = std::array::from_fn(|c| bounds.1[c].max(p[c]));
            }
            bounds
        })
        .reduce(
            || empty,
            |a, b| {
                (
                    std::array::from_fn(|c| a.0[c].min(b.0[c])),
                    std::array::from_fn(|c| a.1[c].max(b.1[c])),
                )
            },
        );
    (lo[0] <= hi[0]).then_some((lo, hi))
}

impl VolumeGrid {
    /// Spreads the active strands' hair (`offsets` as in StrandSet) on the
    /// grid and finds every vertex's velocity change for a step of `dt`.
    ///
    /// Order: the hair's box and cell; the strands ordered by root; each
    /// range of them spread on its own grid; the grids summed node by
    /// node in range order; every vertex's change gathered; the written
    /// nodes cleared for the next step.
    #[allow(clippy::too_many_arguments)]
    pub fn build(
        &mut self,
        instructions: Instructions,
        positions: &[V3],
        velocities: &[V3],
        radii: &[f32],
        offsets: &[usize],
        active: &[bool],
        settings: &Volumetric,
        dt: f32,
    ) {
        let Some((lo, hi)) = active_box(positions, offsets, active) else {
            // No hair on the grid: no change anywhere.
            self.start_of.clear();
            return;
        };
        let mut cell = settings.cell_size;
        let dims = loop {
            let dims: [usize; 3] = std::array::from_fn(|c| ((hi[c] - lo[c]) / cell) as usize + 3);
            if dims.iter().product::<usize>() <= MAX_NODES {
                break dims;
            }
            cell *= 1.25;
        };
        self.grid = Placement {
            origin: std::array::from_fn(|c| lo[c] - cell),
            inv_cell: 1.0 / cell,
            dims,
        };
        let hair = Hair {
            positions,
            velocities,
            radii,
            offsets,
        };
        self.order_strands(positions, offsets, active);
        self.scatter(instructions, &hair);
        self.sum_ranges();
        self.gather(instructions, velocities, offsets, settings, cell, dt);
        self.clear();
    }

    /// The active strands ordered by their roots' place on a Z-order curve
    /// over the grid's cells (then by index), so that strands spread and
    /// read one after the other touch the same nodes while they are in
    /// cache. A groom's strands come in any order (a generated scalp's at
    /// random): in that order each vertex's eight nodes were cache misses
    /// in a grid of megabytes. The order depends only on the positions.
    fn order_strands(&mut self, positions: &[V3], offsets: &[usize], active: &[bool]) {
        use rayon::prelude::*;
        let grid = self.grid;
        let strands = offsets.len().saturating_sub(1);
        self.keys.clear();
        self.keys
            .extend((0..strands).filter(|&s| active[s]).map(|s| {
                let root = positions[offsets[s]..offsets[s + 1]]
                    .iter()
                    .find(|p| is_finite3(**p));
                let key = root.map_or(u64::MAX, |p| {
                    // Saturating casts: 21 bits per axis.
                    morton(std::array::from_fn(|c| {
                        (((p[c] - grid.origin[c]) * grid.inv_cell) as u32).min((1 << 21) - 1)
                    }))
                });
                (key, s as u32)
            }));
        // Unique keys (the strand breaks ties): the order is the same for
        // any sort.
        self.keys.par_sort_unstable();
        self.order.clear();
        self.order.extend(self.keys.iter().map(|&(_, s)| s));
        self.start_of.clear();
        self.start_of.resize(strands, usize::MAX);
        self.ordered_starts.clear();
        let mut slot = 0;
        for &s in &self.order {
            let s = s as usize;
            self.ordered_starts.push(slot);
            self.start_of[s] = slot;
            slot += offsets[s + 1] - offsets[s];
        }
        self.ordered_starts.push(slot);
    }

    /// Each fixed range of ordered strands onto its own grid, in order.
    fn scatter(&mut self, instructions: Instructions, hair: &Hair) {
        use rayon::prelude::*;
        let grid = self.grid;
        if self.partial.len() < RANGES {
            self.partial.resize_with(RANGES, Partial::default);
        }
        let (order, starts) = (&self.order, &self.ordered_starts);
        let per_range = order.len().div_ceil(RANGES).max(1);
        // Written whole by the spreading: resized, not cleared.
        let total = starts.last().copied().unwrap_or(0);
        self.places.resize(total, Place::default());
        // Each range's slice of the places, cut in order.
        let mut rest = self.places.as_mut_slice();
        let places: [&mut [Place]; RANGES] = std::array::from_fn(|r| {
            let slots = |r: usize| starts[(r * per_range).min(order.len())];
            let (mine, tail) = std::mem::take(&mut rest).split_at_mut(slots(r + 1) - slots(r));
            rest = tail;
            mine
        });
        self.partial[..RANGES]
            .par_iter_mut()
            .zip(places.into_par_iter())
            .enumerate()
            .for_each(|(r, (partial, places))| {
                sized(&mut partial.nodes, grid.node_count());
                partial.spans.clear();
                partial.spans.resize(grid.row_count(), Span::EMPTY);
                let first = (r * per_range).min(order.len());
                let last = ((r + 1) * per_range).min(order.len());
                spread(
                    instructions,
                    &order[first..last],
                    hair,
                    &grid,
                    Spread {
                        nodes: &mut partial.nodes,
                        spans: &mut partial.spans,
                        places,
                    },
                );
            });
    }

    /// The ranges' grids summed node by node in range order into the
    /// first range's, over the nodes any of them wrote (the others stay
    /// zero).
    fn sum_ranges(&mut self) {
        use rayon::prelude::*;
        let grid = self.grid;
        let (first, rest) = self.partial[..RANGES].split_at_mut(1);
        let sum = &mut first[0];
        for range in rest.iter() {
            for (all, mine) in sum.spans.iter_mut().zip(&range.spans) {
                all.join(*mine);
            }
        }
        let (spans, row_length) = (&sum.spans, grid.dims[2]);
        sum.nodes
            .par_chunks_mut(ROWS_PER_TASK * row_length)
            .enumerate()
            .for_each(|(k, nodes)| {
                for (j, row) in nodes.chunks_mut(row_length).enumerate() {
                    let index = k * ROWS_PER_TASK + j;
                    let first = index * row_length;
                    for z in spans[index].range() {
                        for range in rest.iter() {
                            row[z].add(&range.nodes[first + z]);
                        }
                    }
                }
            });
    }

    /// Per vertex, the grid's velocity and the volume fraction's gradient
    /// at its place, as this step's velocity change: found strand by
    /// strand in the spreading order (the nodes are then in cache).
    fn gather(
        &mut self,
        instructions: Instructions,
        velocities: &[V3],
        offsets: &[usize],
        settings: &Volumetric,
        cell: f32,
        dt: f32,
    ) {
        use rayon::prelude::*;
        let grid = self.grid;
        let keep = 1.0 - (-settings.smoothing * dt).exp();
        let push = settings.repulsion * dt;
        let scale = grid.inv_cell / (cell * cell * cell);
        // phi = node volume / cell^3 (the gradient's `scale` without the
        // per-cell difference).
        let friction = settings.friction * dt / (cell * cell * cell);
        let gather = Gather {
            instructions,
            grid,
            nodes: &self.partial[0].nodes,
            places: &self.places,
            velocities,
            order: &self.order,
            starts: &self.ordered_starts,
            offsets,
            keep,
            push,
            friction,
            scale,
        };
        let slots = self.ordered_starts.last().copied().unwrap_or(0);
        // Every slot is written below: resized, not cleared.
        self.ordered_dv.resize(slots, [0.0; 3]);
        self.ordered_dv
            .par_chunks_mut(GATHER_CHUNK)
            .enumerate()
            .for_each(|(k, out)| gather.chunk(k * GATHER_CHUNK, out));
    }

    /// Back to all zero: the spans this step wrote.
    fn clear(&mut self) {
        use rayon::prelude::*;
        let row_length = self.grid.dims[2];
        self.partial
            .par_iter_mut()
            .for_each(|p| clear_spans(&mut p.nodes, &p.spans, row_length));
    }

    /// The velocity change this step of vertex `k` of strand `strand`.
    #[inline]
    pub fn dv(&self, strand: usize, k: usize) -> V3 {
        match self.start_of.get(strand) {
            Some(&start) if start != usize::MAX => {
                self.ordered_dv.get(start + k).copied().unwrap_or([0.0; 3])
            }
            _ => [0.0; 3],
        }
    }
}

#[cfg(test)]
mod tests;
