//! Volumetric hair-hair for dense grooms (Petrovic, Henne, Anderson 2005,
//! "Volumetric methods for simulation and rendering of hair"; McAdams et
//! al. 2009): the hair's volume and momentum are spread on a grid of
//! nodes (trilinear weights); each vertex's velocity then moves toward the
//! hair's mean velocity around it (volumetric friction) and the hair is
//! pushed from denser to less dense regions (down the gradient of the
//! volume fraction). The cost is linear in the vertex count whatever the
//! density, unlike the pairwise penalty (20) whose pairs grow with it.
//!
//! Deterministic for any thread count: vertices are scattered in a fixed
//! number of fixed ranges, each into its own grid in vertex order, and the
//! grids are summed node by node in range order; the per-vertex changes
//! are then only read (gathered). Buffers are kept from step to step (no
//! allocation once warm, unless the hair's box grows).

use super::math::{is_finite3, V3};
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
}

impl Default for Volumetric {
    fn default() -> Self {
        Volumetric {
            cell_size: 0.005,
            smoothing: 20.0,
            repulsion: 10.0,
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
        None
    }
}

/// Vertex ranges scattered apart (fixed, so the sums' order is too).
const RANGES: usize = 4;
/// The most grid nodes: past it the cells grow (a bound on memory for
/// hair spread far apart).
const MAX_NODES: usize = 1 << 20;

/// Per node: hair volume (m^3) and its momentum-like sum (volume x
/// velocity).
#[derive(Debug, Clone, Copy, Default)]
struct Node {
    volume: f32,
    flow: V3,
}

impl Node {
    #[inline]
    fn add(&mut self, other: &Node) {
        self.volume += other.volume;
        for c in 0..3 {
            self.flow[c] += other.flow[c];
        }
    }
}

/// The grid and the per-vertex velocity changes of one step.
#[derive(Debug, Default)]
pub struct VolumeGrid {
    origin: V3,
    inv_cell: f32,
    dims: [usize; 3],
    /// Per vertex range, its own grid.
    partial: Vec<Vec<Node>>,
    nodes: Vec<Node>,
    /// Per vertex: the velocity change of this step (zero off active strands).
    dv: Vec<V3>,
}

/// `count` zero nodes in `grid`; a grid that must grow takes twice the
/// room, so hair that spreads as it falls does not allocate every step.
fn zeroed(grid: &mut Vec<Node>, count: usize) {
    grid.clear();
    if grid.capacity() < count {
        grid.reserve_exact((2 * count).min(MAX_NODES.max(count)));
    }
    grid.resize(count, Node::default());
}

/// A vertex's base node and trilinear fractions, or `None` off the grid.
#[inline]
fn locate(p: V3, origin: V3, inv_cell: f32, dims: [usize; 3]) -> Option<([usize; 3], V3)> {
    let mut base = [0usize; 3];
    let mut frac = [0.0f32; 3];
    for c in 0..3 {
        let x = (p[c] - origin[c]) * inv_cell;
        if !(x >= 0.0 && x < (dims[c] - 1) as f32) {
            return None;
        }
        let i = x as usize;
        base[c] = i.min(dims[c] - 2);
        frac[c] = x - base[c] as f32;
    }
    Some((base, frac))
}

impl VolumeGrid {
    /// Spreads the active strands' hair (`offsets` as in StrandSet) on the
    /// grid and finds every vertex's velocity change for a step of `dt`.
    #[allow(clippy::too_many_arguments)]
    pub fn build(
        &mut self,
        positions: &[V3],
        velocities: &[V3],
        radii: &[f32],
        offsets: &[usize],
        active: &[bool],
        settings: &Volumetric,
        dt: f32,
    ) {
        use rayon::prelude::*;
        self.dv.clear();
        self.dv.resize(positions.len(), [0.0; 3]);
        // The box of the active hair.
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        for (strand, w) in offsets.windows(2).enumerate() {
            if !active[strand] {
                continue;
            }
            for p in &positions[w[0]..w[1]] {
                if is_finite3(*p) {
                    for c in 0..3 {
                        lo[c] = lo[c].min(p[c]);
                        hi[c] = hi[c].max(p[c]);
                    }
                }
            }
        }
        if lo[0] > hi[0] {
            return;
        }
        let mut cell = settings.cell_size;
        let dims = loop {
            let dims: [usize; 3] = std::array::from_fn(|c| ((hi[c] - lo[c]) / cell) as usize + 3);
            if dims.iter().product::<usize>() <= MAX_NODES {
                break dims;
            }
            cell *= 1.25;
        };
        self.origin = std::array::from_fn(|c| lo[c] - cell);
        self.inv_cell = 1.0 / cell;
        self.dims = dims;
        let count = dims.iter().product::<usize>();
        let (origin, inv_cell) = (self.origin, self.inv_cell);
        let index = |b: [usize; 3]| (b[0] * dims[1] + b[1]) * dims[2] + b[2];

        // Scatter: each fixed range of strands into its own grid.
        if self.partial.len() < RANGES {
            self.partial.resize_with(RANGES, Vec::new);
        }
        let strands = offsets.len().saturating_sub(1);
        let per_range = strands.div_ceil(RANGES).max(1);
        self.partial
            .par_iter_mut()
            .enumerate()
            .for_each(|(r, grid)| {
                zeroed(grid, count);
                let first = (r * per_range).min(strands);
                let last = ((r + 1) * per_range).min(strands);
                for strand in first..last {
                    if !active[strand] {
                        continue;
                    }
                    let (a, b) = (offsets[strand], offsets[strand + 1]);
                    for i in a..b {
                        let p = positions[i];
                        let Some((base, f)) = locate(p, origin, inv_cell, dims) else {
                            continue;
                        };
                        // The vertex's share of its strand: half of each
                        // adjacent edge.
                        let half = |j: usize| {
                            let (x, y) = (positions[j], positions[j + 1]);
                            let d = [y[0] - x[0], y[1] - x[1], y[2] - x[2]];
                            0.5 * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
                        };
                        let mut length = 0.0;
                        if i > a {
                            length += half(i - 1);
                        }
                        if i + 1 < b {
                            length += half(i);
                        }
                        let r = radii[i];
                        let volume = std::f32::consts::PI * r * r * length;
                        if !(volume.is_finite() && is_finite3(velocities[i])) {
                            continue;
                        }
                        let v = velocities[i];
                        for corner in 0..8 {
                            let mut w = volume;
                            let mut at = base;
                            for c in 0..3 {
                                if corner >> c & 1 == 1 {
                                    at[c] += 1;
                                    w *= f[c];
                                } else {
                                    w *= 1.0 - f[c];
                                }
                            }
                            let node = &mut grid[index(at)];
                            node.volume += w;
                            for (flow, v) in node.flow.iter_mut().zip(v) {
                                *flow += w * v;
                            }
                        }
                    }
                }
            });
        // Sum the ranges' grids node by node, in range order.
        zeroed(&mut self.nodes, count);
        let partial = &self.partial[..RANGES];
        self.nodes
            .par_chunks_mut(4096)
            .enumerate()
            .for_each(|(k, nodes)| {
                let first = k * 4096;
                for (j, node) in nodes.iter_mut().enumerate() {
                    for grid in partial {
                        node.add(&grid[first + j]);
                    }
                }
            });

        // Gather: per vertex, the grid's velocity and the volume
        // fraction's gradient at its place.
        let keep = 1.0 - (-settings.smoothing * dt).exp();
        let push = settings.repulsion * dt;
        let cell_volume = cell * cell * cell;
        let nodes = &self.nodes;
        let owner_active = |v: usize| {
            // Strand of vertex v by binary search over the offsets.
            let s = offsets.partition_point(|&o| o <= v).saturating_sub(1);
            active.get(s).copied().unwrap_or(false)
        };
        self.dv
            .par_chunks_mut(4096)
            .enumerate()
            .for_each(|(k, out)| {
                let first = k * 4096;
                let mut active_here = owner_active(first);
                let mut next_start = offsets.partition_point(|&o| o <= first);
                for (j, dv) in out.iter_mut().enumerate() {
                    let i = first + j;
                    while next_start < offsets.len() && offsets[next_start] <= i {
                        active_here = active.get(next_start).copied().unwrap_or(false);
                        next_start += 1;
                    }
                    if !active_here {
                        continue;
                    }
                    let p = positions[i];
                    let Some((base, f)) = locate(p, origin, inv_cell, dims) else {
                        continue;
                    };
                    let mut volume = 0.0f32;
                    let mut flow = [0.0f32; 3];
                    let mut gradient = [0.0f32; 3];
                    for corner in 0..8 {
                        let mut w = 1.0f32;
                        let mut dw = [1.0f32; 3];
                        let mut at = base;
                        for c in 0..3 {
                            let (wc, dc) = if corner >> c & 1 == 1 {
                                at[c] += 1;
                                (f[c], 1.0)
                            } else {
                                (1.0 - f[c], -1.0)
                            };
                            w *= wc;
                            for (d, dwd) in dw.iter_mut().enumerate() {
                                *dwd *= if d == c { dc } else { wc };
                            }
                        }
                        let node = &nodes[index(at)];
                        volume += w * node.volume;
                        for c in 0..3 {
                            flow[c] += w * node.flow[c];
                            gradient[c] += dw[c] * node.volume;
                        }
                    }
                    let v = velocities[i];
                    let scale = inv_cell / cell_volume;
                    let mut change = [0.0f32; 3];
                    if volume > 0.0 {
                        for c in 0..3 {
                            change[c] = keep * (flow[c] / volume - v[c]);
                        }
                    }
                    for c in 0..3 {
                        change[c] -= push * gradient[c] * scale;
                    }
                    if is_finite3(change) {
                        *dv = change;
                    }
                }
            });
    }

    /// The velocity change of vertex `vertex` (global index) this step.
    #[inline]
    pub fn dv(&self, vertex: usize) -> V3 {
        self.dv.get(vertex).copied().unwrap_or([0.0; 3])
    }
}

#[cfg(test)]
mod tests {
    use super::super::{ColliderSet, Environment, Gravity, Material, Solver, SolverParameters};
    use super::*;
    use groom::Groom;

    /// A dense bundle: `side` x `side` straight strands 0.4 mm apart,
    /// hanging from roots in the XZ plane, 10 vertices over 3 cm.
    fn bundle(side: usize) -> super::super::StrandSet {
        let strands: Vec<Vec<V3>> = (0..side * side)
            .map(|k| {
                let (x, z) = ((k % side) as f32 * 4e-4, (k / side) as f32 * 4e-4);
                (0..10).map(|i| [x, -0.003 * i as f32, z]).collect()
            })
            .collect();
        let mut groom = Groom::from_strands(strands);
        groom.units = groom::Units::METERS;
        super::super::StrandSet::from_groom(&groom, &Material::default()).unwrap()
    }

    /// Mean |v_x| over the free vertices after one step of the bundle
    /// whose strands move +x and -x in turn at 0.5 m/s.
    fn mean_crossing_speed(volumetric: Option<Volumetric>) -> f32 {
        let mut set = bundle(8);
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
        };
        let with = tip_spread(Some(volumetric), 0.1);
        let without = tip_spread(None, 0.1);
        assert!(with > 1.2 * without, "{with} vs {without}");
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
                    &set.positions,
                    &velocities,
                    &set.radii,
                    &set.offsets,
                    &active,
                    &Volumetric::default(),
                    1.0 / 360.0,
                );
                (0..set.positions.len())
                    .flat_map(|v| grid.dv(v).map(f32::to_bits))
                    .collect::<Vec<u32>>()
            })
        };
        let one = run(1);
        assert!(one.iter().any(|b| *b != 0));
        assert_eq!(one, run(2));
        assert_eq!(one, run(3));
    }
}
