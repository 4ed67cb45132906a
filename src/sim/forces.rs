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

#[derive(Debug, Clone, Copy)]
struct Entry {
    cell: [i32; 3],
    /// Global index of the edge's first vertex.
    edge: u32,
    strand: u32,
}

/// Edges of all strands binned in a hashed uniform grid; each edge sits in
/// every cell its box (grown by `2r`) touches.
#[derive(Debug, Default)]
pub struct EdgeGrid {
    inv_cell: f32,
    mask: usize,
    starts: Vec<u32>,
    entries: Vec<Entry>,
    scratch: Vec<Entry>,
    counts: Vec<u32>,
}

#[inline]
fn hash(cell: [i32; 3], mask: usize) -> usize {
    let h = (cell[0] as u32).wrapping_mul(0x8da6_b343)
        ^ (cell[1] as u32).wrapping_mul(0xd816_3841)
        ^ (cell[2] as u32).wrapping_mul(0xcb1a_b31f);
    (h as usize) & mask
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

impl EdgeGrid {
    /// Bins the edges of the `active` strands (`offsets` as in StrandSet).
    pub fn build(&mut self, positions: &[V3], offsets: &[usize], active: &[bool], radius: f32) {
        let reach = 2.0 * radius;
        // Cells as large as the longest edge (at least 2 * reach) so an edge
        // spans at most a few cells per axis.
        let mut cell = 2.0 * reach;
        for (strand, w) in offsets.windows(2).enumerate() {
            if !active[strand] {
                continue;
            }
            for v in w[0]..w[1].saturating_sub(1) {
                let d = sub(positions[v + 1], positions[v]);
                if is_finite3(d) {
                    cell = cell.max(d[0].abs()).max(d[1].abs()).max(d[2].abs());
                }
            }
        }
        self.inv_cell = 1.0 / cell;
        self.scratch.clear();
        for (strand, w) in offsets.windows(2).enumerate() {
            if !active[strand] {
                continue;
            }
            for v in w[0]..w[1].saturating_sub(1) {
                let (a, b) = (positions[v], positions[v + 1]);
                if !(is_finite3(a) && is_finite3(b)) {
                    continue;
                }
                let lo = cell_of(
                    [
                        a[0].min(b[0]) - reach,
                        a[1].min(b[1]) - reach,
                        a[2].min(b[2]) - reach,
                    ],
                    self.inv_cell,
                );
                let hi = cell_of(
                    [
                        a[0].max(b[0]) + reach,
                        a[1].max(b[1]) + reach,
                        a[2].max(b[2]) + reach,
                    ],
                    self.inv_cell,
                );
                // An edge spans at most 3 cells per axis (cells are at least
                // as long as any edge); far-off coordinates saturate to one
                // cell. Never loop over more than that.
                if (0..3).any(|c| i64::from(hi[c]) - i64::from(lo[c]) > 3) {
                    continue;
                }
                for x in lo[0]..=hi[0] {
                    for y in lo[1]..=hi[1] {
                        for z in lo[2]..=hi[2] {
                            self.scratch.push(Entry {
                                cell: [x, y, z],
                                edge: v as u32,
                                strand: strand as u32,
                            });
                        }
                    }
                }
            }
        }
        let buckets = (self.scratch.len() * 2).next_power_of_two().max(16);
        self.mask = buckets - 1;
        self.counts.clear();
        self.counts.resize(buckets + 1, 0);
        for e in &self.scratch {
            self.counts[hash(e.cell, self.mask) + 1] += 1;
        }
        for i in 1..self.counts.len() {
            self.counts[i] += self.counts[i - 1];
        }
        self.starts.clear();
        self.starts.extend_from_slice(&self.counts);
        // Counting sort keeps edge order within a bucket: deterministic.
        self.entries.clear();
        self.entries.resize(
            self.scratch.len(),
            Entry {
                cell: [0; 3],
                edge: 0,
                strand: 0,
            },
        );
        for e in &self.scratch {
            let slot = &mut self.counts[hash(e.cell, self.mask)];
            self.entries[*slot as usize] = *e;
            *slot += 1;
        }
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
        let cell = cell_of(p, self.inv_cell);
        let bucket = hash(cell, self.mask);
        let (start, end) = (
            self.starts[bucket] as usize,
            self.starts[bucket + 1] as usize,
        );
        for e in &self.entries[start..end] {
            if e.cell != cell || e.strand as usize == strand {
                continue;
            }
            let a = positions[e.edge as usize];
            let b = positions[e.edge as usize + 1];
            // Most edges of a cell are farther than 2r on some axis: a box
            // test is cheaper than the foot point.
            if (0..3).any(|c| p[c] < a[c].min(b[c]) - reach || p[c] > a[c].max(b[c]) + reach) {
                continue;
            }
            let ab = sub(b, a);
            let ab2 = dot(ab, ab);
            let t = if ab2 > 0.0 {
                (dot(sub(p, a), ab) / ab2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let foot = [a[0] + ab[0] * t, a[1] + ab[1] * t, a[2] + ab[2] * t];
            let d = sub(p, foot);
            let dist = length(d);
            if dist < reach && dist > 0.0 {
                let k = alpha * (reach - dist) / reach / dist * dt;
                dv = [dv[0] + d[0] * k, dv[1] + d[1] * k, dv[2] + d[2] * k];
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
        let dv = grid.penalty_dv(&positions, positions[0], 0, 4e-5, 1.0, 1.0);
        // Distance 1e-5 of 8e-5: (8 - 1) / 8 away from the other edge (-x).
        assert!((dv[0] + 7.0 / 8.0).abs() < 1e-5, "{dv:?}");
        let own = grid.penalty_dv(&positions, [1e-5, 0.0, 0.0], 1, 4e-5, 1.0, 1.0);
        assert!((own[0] - 7.0 / 8.0).abs() < 1e-5, "{own:?}");
        let far = grid.penalty_dv(&positions, [0.0, 0.0, 1.0], 0, 4e-5, 1.0, 1.0);
        assert_eq!(far, [0.0; 3]);
    }
}
