//! The scalp of the `head` layout, and where its roots go.
//!
//! The head is star-shaped about its centre `c`: in the head's normalised
//! space `q = (x - c) / r` (`r` the ellipsoid's radii, or the half extents
//! of a mesh's bounding box), the surface is `|q| = rho(u)` along each unit
//! direction `u`. For the ellipsoid `rho = 1`; for a mesh, `rho` and the
//! hit triangle's normal are sampled by casting rays from the centre on a
//! polar grid of `u` (parry3d's BVH) and interpolated bilinearly. So one
//! description serves the ellipsoid and any head mesh its centre sees
//! whole (a head is), and every query the comb makes (the surface point
//! and normal under a point, a point's height above the scalp) costs the
//! same small constant on both.
//!
//! The hairline bounds the scalp on the unit sphere of `u`: a root's polar
//! angle from the top is at most `a0 + a1 cos(phi) + a2 cos(2 phi)`, the
//! smooth curve through the three given angles at the front (`phi = 0`,
//! toward +Z, the forehead), the sides (`phi = 90` degrees, above the
//! ears) and the back (the nape).
//!
//! Roots: a spherical Fibonacci lattice (Gonzalez 2010, "Measurement of
//! areas on a sphere using Fibonacci and latitude-longitude lattices"),
//! turned by a seeded angle and each point jittered by a quarter of the
//! lattice spacing, kept inside the hairline and thinned by systematic
//! sampling in proportion to the scalp's area per solid angle. The roots
//! are evenly spread (no holes, no two much closer than the spacing: the
//! look of blue noise without its cost) and there are exactly as many as
//! asked.

use super::{GeneratorError, GeneratorParameters, SplitMix64};
use groom::math::double::{add, dot, length, scale, sub, try_normalize, V3};
use parry3d::math::Vector;
use parry3d::query::{Ray, RayCast};
use parry3d::shape::TriMesh;
use rayon::prelude::*;
use std::f64::consts::{PI, TAU};
use std::path::Path;

/// Polar rows (pole to pole) and azimuth columns of a mesh scalp's grid:
/// 0.7 degree cells, far finer than a head mesh's facets.
const GRID_ROWS: usize = 257;
const GRID_COLS: usize = 512;

/// Random stream of the lattice jitter (see [`SplitMix64::for_item`]).
const STREAM_JITTER: u64 = 11;

/// A root: its point on the scalp, the outward normal there and its
/// direction `u` in the head's normalised space.
#[derive(Debug, Clone, Copy)]
pub(super) struct Root {
    pub point: V3,
    pub normal: V3,
    pub u: V3,
}

/// `rho` and the normals of a mesh scalp on the polar grid.
struct RadialGrid {
    rho: Vec<f64>,
    normal: Vec<V3>,
    mesh: TriMesh,
}

pub(super) struct Scalp {
    center: V3,
    radii: V3,
    grid: Option<RadialGrid>,
    /// Hairline coefficients a0, a1, a2, radians.
    hairline: [f64; 3],
}

fn unit(a: V3) -> V3 {
    try_normalize(a).unwrap_or([0.0, 1.0, 0.0])
}

/// The polar angle from +Y and the azimuth from +Z toward +X of `u`.
pub(super) fn angles(u: V3) -> (f64, f64) {
    (u[1].clamp(-1.0, 1.0).acos(), u[0].atan2(u[2]))
}

fn from_angles(polar: f64, azimuth: f64) -> V3 {
    [
        polar.sin() * azimuth.sin(),
        polar.cos(),
        polar.sin() * azimuth.cos(),
    ]
}

impl Scalp {
    fn new(center: V3, radii: V3, p: &GeneratorParameters) -> Scalp {
        let [front, side, back] = p.hairline.map(|a| (a as f64).to_radians());
        let a1 = (front - back) / 2.0;
        let a0 = ((front + back) / 2.0 + side) / 2.0;
        let a2 = ((front + back) / 2.0 - side) / 2.0;
        Scalp {
            center,
            radii,
            grid: None,
            hairline: [a0, a1, a2],
        }
    }

    /// The ellipsoid head of `head_center` and `head_radii`.
    pub fn ellipsoid(p: &GeneratorParameters) -> Scalp {
        Scalp::new(p.head_center.map(f64::from), p.head_radii.map(f64::from), p)
    }

    /// A head mesh: read, its bounds taken and its radial grid cast.
    pub fn mesh(path: &Path, p: &GeneratorParameters) -> Result<Scalp, GeneratorError> {
        let fail = |message: String| GeneratorError {
            name: "scalp_mesh",
            message,
        };
        let mesh = importers::mesh::read_mesh(path).map_err(|e| fail(e.to_string()))?;
        let shown = path.display();
        let (mut low, mut high) = ([f64::MAX; 3], [f64::MIN; 3]);
        for v in &mesh.vertices {
            for k in 0..3 {
                let c = v[k] as f64;
                if !(c.is_finite() && c.abs() <= crate::budget::MAX_COORDINATE) {
                    return Err(fail(format!(
                        "{shown}: a vertex is not a finite coordinate within 10 km"
                    )));
                }
                low[k] = low[k].min(c);
                high[k] = high[k].max(c);
            }
        }
        let center = [0, 1, 2].map(|k| (low[k] + high[k]) / 2.0);
        let radii = [0, 1, 2].map(|k| (high[k] - low[k]) / 2.0);
        if radii.iter().any(|r| r.is_nan() || *r <= 1e-3) {
            return Err(fail(format!(
                "{shown}: the mesh is flat (its bounds are under 2 mm along an axis), not a head"
            )));
        }
        let vertices: Vec<Vector> = mesh
            .vertices
            .iter()
            .map(|v| Vector::new(v[0], v[1], v[2]))
            .collect();
        let trimesh = TriMesh::new(vertices, mesh.triangles)
            .map_err(|e| fail(format!("{shown}: not a usable head mesh: {e}")))?;
        let mut scalp = Scalp::new(center, radii, p);
        let cells: Vec<Option<(f64, V3)>> = (0..GRID_ROWS * GRID_COLS)
            .into_par_iter()
            .map(|i| {
                let (row, col) = (i / GRID_COLS, i % GRID_COLS);
                let polar = PI * row as f64 / (GRID_ROWS - 1) as f64;
                let azimuth = TAU * col as f64 / GRID_COLS as f64;
                scalp.cast(&trimesh, from_angles(polar, azimuth))
            })
            .collect();
        let mut rho = Vec::with_capacity(cells.len());
        let mut normal = Vec::with_capacity(cells.len());
        for cell in cells {
            let Some((r, n)) = cell else {
                return Err(fail(format!(
                    "{shown}: a ray from the centre of its bounds misses the mesh: a scalp \
                     mesh must be a closed head around that centre"
                )));
            };
            rho.push(r);
            normal.push(n);
        }
        scalp.grid = Some(RadialGrid {
            rho,
            normal,
            mesh: trimesh,
        });
        Ok(scalp)
    }

    /// The ray from the centre along `u`: `rho` there and the outward
    /// normal of the triangle it leaves through.
    fn cast(&self, mesh: &TriMesh, u: V3) -> Option<(f64, V3)> {
        let dir = unit([0, 1, 2].map(|k| u[k] * self.radii[k]));
        let reach = 4.0 * self.radii.iter().fold(0.0f64, |a, b| a.max(*b));
        let ray = Ray::new(
            Vector::new(
                self.center[0] as f32,
                self.center[1] as f32,
                self.center[2] as f32,
            ),
            Vector::new(dir[0] as f32, dir[1] as f32, dir[2] as f32),
        );
        let hit = mesh.cast_local_ray_and_get_normal(&ray, reach as f32, false)?;
        let t = hit.time_of_impact as f64;
        let mut n = unit([
            hit.normal.x as f64,
            hit.normal.y as f64,
            hit.normal.z as f64,
        ]);
        if dot(n, dir) < 0.0 {
            n = scale(n, -1.0);
        }
        let scaled = length([0, 1, 2].map(|k| dir[k] / self.radii[k]));
        Some((t * scaled, n))
    }

    pub fn radii(&self) -> V3 {
        self.radii
    }

    /// `u` of a point (straight up at the centre itself).
    pub fn direction(&self, x: V3) -> V3 {
        unit([0, 1, 2].map(|k| (x[k] - self.center[k]) / self.radii[k]))
    }

    /// `rho` and the outward normal along `u`.
    fn radial(&self, u: V3) -> (f64, V3) {
        let Some(grid) = &self.grid else {
            return (1.0, unit([0, 1, 2].map(|k| u[k] / self.radii[k])));
        };
        let (polar, azimuth) = angles(u);
        let y = polar / PI * (GRID_ROWS - 1) as f64;
        let x = azimuth.rem_euclid(TAU) / TAU * GRID_COLS as f64;
        let (r0, c0) = ((y.floor() as usize).min(GRID_ROWS - 2), x.floor() as usize);
        let (fy, fx) = (
            (y - r0 as f64).clamp(0.0, 1.0),
            (x - c0 as f64).clamp(0.0, 1.0),
        );
        let mut rho = 0.0;
        let mut n = [0.0; 3];
        for (dr, wy) in [(0, 1.0 - fy), (1, fy)] {
            for (dc, wx) in [(0, 1.0 - fx), (1, fx)] {
                let i = (r0 + dr) * GRID_COLS + (c0 + dc) % GRID_COLS;
                rho += wy * wx * grid.rho[i];
                n = add(n, scale(grid.normal[i], wy * wx));
            }
        }
        (rho, unit(n))
    }

    /// The scalp point along `u` and the outward normal there.
    pub fn surface(&self, u: V3) -> (V3, V3) {
        let (rho, n) = self.radial(u);
        let point = [0, 1, 2].map(|k| self.center[k] + self.radii[k] * rho * u[k]);
        (point, n)
    }

    /// A point's height above the scalp (negative inside), the scalp point
    /// below it (along the ray from the centre) and the normal there. The
    /// height is the radial gap times the normal's cosine to the ray: the
    /// distance to the tangent plane, exact at the scalp and to second
    /// order near it.
    pub fn height(&self, x: V3) -> (f64, V3, V3) {
        let u = self.direction(x);
        let (foot, n) = self.surface(u);
        let out = sub(x, self.center);
        let ray = unit(out);
        let gap = length(out) - length(sub(foot, self.center));
        (gap * dot(n, ray).max(0.05), foot, n)
    }

    /// The point at height `h` above the scalp point under `x`.
    pub fn at_height(&self, x: V3, h: f64) -> V3 {
        let (_, foot, n) = self.height(x);
        add(foot, scale(n, h))
    }

    /// Is `u` inside the hairline?
    pub fn in_scalp(&self, u: V3) -> bool {
        let (polar, azimuth) = angles(u);
        let [a0, a1, a2] = self.hairline;
        polar <= a0 + a1 * azimuth.cos() + a2 * (2.0 * azimuth).cos()
    }

    /// Scalp area per unit solid angle of `u`, over `r_x r_y r_z`: for the
    /// surface `q = rho(u) u` of normal `n_q`, `dA_q = rho^2 / (n_q . u)`
    /// per steradian and `dA = det(R) |R^-1 n_q| dA_q`.
    fn area_weight(&self, u: V3) -> f64 {
        let (rho, n) = self.radial(u);
        let n_q = unit([0, 1, 2].map(|k| n[k] * self.radii[k]));
        let inverse = length([0, 1, 2].map(|k| n_q[k] / self.radii[k]));
        rho * rho * inverse / dot(n_q, u).max(0.05)
    }

    /// Point `i` of the jittered, turned Fibonacci lattice of `m` points.
    fn lattice(&self, i: usize, m: usize, turn: f64, seed: u64) -> V3 {
        let golden = PI * (3.0 - 5f64.sqrt());
        let y = 1.0 - (2.0 * i as f64 + 1.0) / m as f64;
        let azimuth = i as f64 * golden + turn;
        let polar = y.clamp(-1.0, 1.0).acos();
        let u = from_angles(polar, azimuth);
        let mut random = SplitMix64::for_item(seed, STREAM_JITTER, i as u64);
        let spacing = (4.0 * PI / m as f64).sqrt();
        let (a, b) = (random.next_f64() - 0.5, random.next_f64() - 0.5);
        let east = unit([azimuth.cos(), 0.0, -azimuth.sin()]);
        let north = unit(sub([0.0, 1.0, 0.0], scale(u, u[1])));
        let moved = add(
            u,
            add(
                scale(east, 0.5 * spacing * a),
                scale(north, 0.5 * spacing * b),
            ),
        );
        unit(moved)
    }

    /// Exactly `count` roots inside the hairline (see the module
    /// documentation), and the scalp's area in square metres.
    pub fn roots(&self, count: usize, random: &mut SplitMix64) -> (Vec<Root>, f64) {
        let turn = random.next_f64() * TAU;
        let offset = random.next_f64().clamp(1e-6, 1.0 - 1e-6);
        let seed = random.next_u64();
        // Weights of the points inside the hairline (0 outside).
        let weights = |m: usize| -> Vec<f64> {
            (0..m)
                .into_par_iter()
                .map(|i| {
                    let u = self.lattice(i, m, turn, seed);
                    if self.in_scalp(u) {
                        self.area_weight(u)
                    } else {
                        0.0
                    }
                })
                .collect()
        };
        // Enough lattice points that none is taken twice: a point is kept
        // with probability weight * count / total <= 1.
        let mut m = 4096usize;
        let mut w = weights(m);
        loop {
            let total: f64 = w.iter().sum();
            let largest = w.iter().fold(0.0f64, |a, b| a.max(*b));
            if total > 0.0 && largest * count as f64 <= total {
                break;
            }
            let mean = (total / m as f64).max(1e-12);
            let wanted = (1.15 * count as f64 * largest.max(1e-12) / mean) as usize;
            m = wanted.max(m * 2).min(m.saturating_mul(64)).max(m + 1);
            w = weights(m);
        }
        let total: f64 = w.iter().sum();
        let det = self.radii[0] * self.radii[1] * self.radii[2];
        let area = total * 4.0 * PI / m as f64 * det;
        let mut chosen = Vec::with_capacity(count);
        let mut acc = offset;
        for (i, wi) in w.iter().enumerate() {
            if *wi == 0.0 {
                continue;
            }
            let next = acc + wi * count as f64 / total;
            if next.floor() > acc.floor() && chosen.len() < count {
                chosen.push(i);
            }
            acc = next;
        }
        // Rounding can leave the last one out: take the last points not taken.
        let mut i = m;
        while chosen.len() < count && i > 0 {
            i -= 1;
            if w[i] > 0.0 && !chosen.contains(&i) {
                chosen.push(i);
            }
        }
        chosen.sort_unstable();
        let roots = chosen
            .par_iter()
            .map(|&i| {
                let u = self.lattice(i, m, turn, seed);
                let (point, normal) = match &self.grid {
                    // A root exactly on the mesh, not on its interpolation.
                    Some(grid) => match self.cast(&grid.mesh, u) {
                        Some((rho, n)) => (
                            [0, 1, 2].map(|k| self.center[k] + self.radii[k] * rho * u[k]),
                            n,
                        ),
                        None => self.surface(u),
                    },
                    None => self.surface(u),
                };
                Root { point, normal, u }
            })
            .collect();
        (roots, area)
    }
}
