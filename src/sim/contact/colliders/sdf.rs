//! A triangle-mesh collider's distance grid, built once per mesh in the
//! mesh's own frame (a moving collider transforms the queries, never the
//! grid). Each cell near the surface lists every triangle that can be the
//! closest to a point of the cell, and a bound on their distance; a query
//! reads one cell and tests only those triangles, with the triangle
//! projection and pseudo-normal rule parry uses, so it is exact at a small
//! fixed cost instead of a walk down the mesh's tree. Cells farther out
//! are clear (outside, flood-filled from the grid's border) or inside
//! (closed meshes only; those rare deep points get parry's full query).

use parry3d::math::Vector;
use parry3d::query::{PointProjection, PointQuery, PointQueryWithLocation};
use parry3d::shape::{TriMesh, TriMeshFlags, TrianglePointLocation};

/// Cells along the mesh's longest side.
const CELLS_ALONG: f32 = 80.0;
/// At most this many cells in all (memory bound for flat, wide meshes).
const MAX_CELLS: usize = 4_000_000;

#[derive(Debug, Clone, Copy)]
struct Cell {
    start: u32,
    count: u32,
    /// A lower bound of the distance from any point of the cell to the
    /// surface (`f32::INFINITY` for a cell of no triangle).
    lower: f32,
    /// The whole cell is inside (meaningful when `lower > 0`).
    inside: bool,
}

/// What the grid says about a point (mesh frame).
pub(crate) enum Query {
    /// Outside and farther than the hair radius from the surface.
    Clear,
    /// The closest surface point and whether the query point is inside.
    Surface(PointProjection),
    /// Deep inside: ask parry.
    Exact,
}

pub(crate) struct MeshSdf {
    /// The mesh, with pseudo-normals when it is closed (inside is
    /// decided as parry decides it).
    mesh: TriMesh,
    origin: [f32; 3],
    cell: f32,
    inv_cell: f32,
    dims: [usize; 3],
    /// The largest hair radius the grid answers exactly for.
    pub(crate) max_radius: f32,
    cells: Vec<Cell>,
    /// One bit per cell: outside and farther than `max_radius` from the
    /// surface, so clear for any hair the grid answers for. Most of a
    /// groom's queries land in such cells; at a bit a cell this fits the
    /// second-level cache, where the 16-byte cells do not (reading them
    /// was half of a query's time).
    clear: Vec<u64>,
    triangles: Vec<u32>,
}

/// Whether every edge is shared by exactly two triangles that run it in
/// opposite directions (a closed, consistently wound surface).
fn is_closed(indices: &[[u32; 3]]) -> bool {
    let mut directed: Vec<(u32, u32)> = indices
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .collect();
    directed.sort_unstable();
    if directed.windows(2).any(|w| w[0] == w[1]) {
        return false;
    }
    directed
        .iter()
        .all(|&(a, b)| directed.binary_search(&(b, a)).is_ok())
}

impl MeshSdf {
    /// `Ok(None)` for a mesh the grid cannot describe (empty, not
    /// finite); an error when the grid would be larger than the
    /// [`crate::budget`] allows (checked before anything is allocated).
    pub(crate) fn new(source: &TriMesh) -> Result<Option<MeshSdf>, String> {
        let indices = source.indices().to_vec();
        let flags = if is_closed(&indices) {
            TriMeshFlags::ORIENTED
        } else {
            TriMeshFlags::empty()
        };
        let Ok(mesh) = TriMesh::with_flags(source.vertices().to_vec(), indices, flags) else {
            return Ok(None);
        };
        let aabb = mesh.local_aabb();
        let (mins, maxs) = (aabb.mins, aabb.maxs);
        let extent = (maxs - mins).max_element();
        if !(extent.is_finite() && extent > 0.0) {
            return Ok(None);
        }
        let mut cell = extent / CELLS_ALONG;
        if !cell.is_normal() {
            return Ok(None);
        }
        // Triangles are listed in the cells within `band` of them: a cell
        // whose bound is at most `max_radius` holds only points within
        // `max_radius + 2 half_diagonal = band` of the surface, so its list
        // holds their closest triangle.
        let band_of = |cell: f32| cell * (3f32.sqrt() + 0.5);
        // In f64: a finite f32 extent near f32::MAX plus the margins is
        // not finite in f32, and a saturated cast would size the grid from
        // garbage.
        let dims_for = |cell: f32| -> [f64; 3] {
            let margin = f64::from(band_of(cell)) + f64::from(cell);
            [0, 1, 2].map(|c| {
                ((f64::from(maxs[c]) - f64::from(mins[c]) + 2.0 * margin) / f64::from(cell)).ceil()
                    + 1.0
            })
        };
        let mut dims_f = dims_for(cell);
        while dims_f.iter().product::<f64>() > MAX_CELLS as f64 && cell.is_finite() {
            cell *= 1.25;
            dims_f = dims_for(cell);
        }
        let band = band_of(cell);
        let margin = band + cell;
        let origin = [0, 1, 2].map(|c| (f64::from(mins[c]) - f64::from(margin)) as f32);
        let sized = dims_f.iter().product::<f64>() <= MAX_CELLS as f64;
        if !(sized && cell.is_finite() && band.is_finite() && origin.iter().all(|o| o.is_finite()))
        {
            return Ok(None);
        }
        // At most MAX_CELLS each, so exact in usize.
        let dims = dims_f.map(|d| d as usize);
        let inv_cell = 1.0 / cell;
        let half_diagonal = cell * 3f32.sqrt() * 0.5;
        let index = |x: usize, y: usize, z: usize| (x * dims[1] + y) * dims[2] + z;

        // Every (cell, triangle) pair whose triangle box, grown by the
        // band, overlaps the cell; then only those within reach of the
        // cell's points. Counted first: a few large triangles over a fine
        // grid can ask for more pairs than memory holds.
        let span = |triangle: &parry3d::shape::Triangle| {
            let at = |m: f32, c: usize| {
                (((m - origin[c]) * inv_cell).floor().max(0.0) as usize).min(dims[c] - 1)
            };
            let lo = [0, 1, 2].map(|c| {
                at(
                    triangle.a[c].min(triangle.b[c]).min(triangle.c[c]) - band,
                    c,
                )
            });
            let hi = [0, 1, 2].map(|c| {
                at(
                    triangle.a[c].max(triangle.b[c]).max(triangle.c[c]) + band,
                    c,
                )
            });
            (lo, hi)
        };
        let entries = mesh.triangles().fold(0u64, |sum, triangle| {
            let (lo, hi) = span(&triangle);
            let count = (0..3).fold(1u64, |n, c| n.saturating_mul((hi[c] - lo[c] + 1) as u64));
            sum.saturating_add(count)
        });
        crate::budget::check_grid_entries(entries, mesh.indices().len() as u64)?;
        let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(entries as usize);
        for (t, triangle) in mesh.triangles().enumerate() {
            let (lo, hi) = span(&triangle);
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        pairs.push((index(x, y, z) as u32, t as u32));
                    }
                }
            }
        }
        pairs.sort_unstable();
        let total = dims.iter().product::<usize>();
        let mut cells = vec![
            Cell {
                start: 0,
                count: 0,
                lower: f32::INFINITY,
                inside: false,
            };
            total
        ];
        let mut triangles = Vec::new();
        let mut distances = Vec::new();
        for group in pairs.chunk_by(|a, b| a.0 == b.0) {
            let c = group[0].0 as usize;
            let (x, y, z) = (
                c / (dims[1] * dims[2]),
                (c / dims[2]) % dims[1],
                c % dims[2],
            );
            let center = Vector::new(
                origin[0] + (x as f32 + 0.5) * cell,
                origin[1] + (y as f32 + 0.5) * cell,
                origin[2] + (z as f32 + 0.5) * cell,
            );
            distances.clear();
            distances.extend(
                group
                    .iter()
                    .map(|&(_, t)| mesh.triangle(t).distance_to_local_point(center, false)),
            );
            let nearest = distances.iter().copied().fold(f32::INFINITY, f32::min);
            // A point of the cell is at most `nearest + half_diagonal` from
            // the surface, so its closest triangle is at most
            // `nearest + 2 half_diagonal` from the centre (with a hair to
            // spare for round-off): the rest can never be a point's
            // closest. A triangle farther than band + half a diagonal from
            // the centre is farther than band from every point of the cell.
            let keep = (band + half_diagonal).min(nearest + 2.0 * half_diagonal + 0.01 * cell);
            let start = triangles.len();
            triangles.extend(
                group
                    .iter()
                    .zip(&distances)
                    .filter(|&(_, &d)| d <= keep)
                    .map(|(&(_, t), _)| t),
            );
            if triangles.len() > start {
                cells[c] = Cell {
                    start: start as u32,
                    count: (triangles.len() - start) as u32,
                    lower: nearest - half_diagonal,
                    inside: false,
                };
            }
        }
        let max_radius = cell * 0.5;
        let mut sdf = MeshSdf {
            mesh,
            origin,
            cell,
            inv_cell,
            dims,
            max_radius,
            cells,
            clear: Vec::new(),
            triangles,
        };
        if sdf.mesh.pseudo_normals_if_oriented().is_some() {
            sdf.mark_inside();
        }
        sdf.clear = vec![0; sdf.cells.len().div_ceil(64)];
        for (i, c) in sdf.cells.iter().enumerate() {
            if c.lower > max_radius && !c.inside {
                sdf.clear[i / 64] |= 1 << (i % 64);
            }
        }
        Ok(Some(sdf))
    }

    /// Cells of no triangle that the border cannot reach through other
    /// such cells are inside (the band is a closed shell around a closed
    /// mesh).
    fn mark_inside(&mut self) {
        let [nx, ny, nz] = self.dims;
        let index = |x: usize, y: usize, z: usize| (x * ny + y) * nz + z;
        let mut outside = vec![false; self.cells.len()];
        let mut stack = Vec::new();
        for x in 0..nx {
            for y in 0..ny {
                for z in 0..nz {
                    let border =
                        x == 0 || y == 0 || z == 0 || x == nx - 1 || y == ny - 1 || z == nz - 1;
                    if border && self.cells[index(x, y, z)].count == 0 {
                        outside[index(x, y, z)] = true;
                        stack.push((x, y, z));
                    }
                }
            }
        }
        while let Some((x, y, z)) = stack.pop() {
            let neighbours = [
                (x.wrapping_sub(1), y, z),
                (x + 1, y, z),
                (x, y.wrapping_sub(1), z),
                (x, y + 1, z),
                (x, y, z.wrapping_sub(1)),
                (x, y, z + 1),
            ];
            for (a, b, c) in neighbours {
                if a < nx && b < ny && c < nz {
                    let i = index(a, b, c);
                    if !outside[i] && self.cells[i].count == 0 {
                        outside[i] = true;
                        stack.push((a, b, c));
                    }
                }
            }
        }
        for (cell, out) in self.cells.iter_mut().zip(outside) {
            if cell.count == 0 && !out {
                cell.inside = true;
            }
        }
        // A listed cell clear of the surface takes the side of its centre
        // (its list holds the centre's closest triangle).
        for i in 0..self.cells.len() {
            if self.cells[i].count > 0 && self.cells[i].lower > 0.0 {
                let (x, y, z) = (i / (ny * nz), (i / nz) % ny, i % nz);
                let center = Vector::new(
                    self.origin[0] + (x as f32 + 0.5) * self.cell,
                    self.origin[1] + (y as f32 + 0.5) * self.cell,
                    self.origin[2] + (z as f32 + 0.5) * self.cell,
                );
                if let Some(projection) = self.closest_in(&self.cells[i], center) {
                    self.cells[i].inside = projection.is_inside;
                }
            }
        }
    }

    /// The surface near `p` (mesh frame) for a hair of radius `radius`
    /// (at most `max_radius`): exact whenever `p` is within `radius` of
    /// the surface or inside.
    #[inline]
    pub(crate) fn query(&self, p: Vector, radius: f32) -> Query {
        let mut at = [0usize; 3];
        for c in 0..3 {
            let f = (p[c] - self.origin[c]) * self.inv_cell;
            // Outside the grid (or not finite): farther than the margin.
            if !(f >= 0.0 && f < self.dims[c] as f32) {
                return Query::Clear;
            }
            at[c] = f as usize;
        }
        let index = (at[0] * self.dims[1] + at[1]) * self.dims[2] + at[2];
        // What the cell would say (`lower > radius`, outside), from a bit.
        if radius <= self.max_radius && self.clear[index / 64] >> (index % 64) & 1 == 1 {
            return Query::Clear;
        }
        let cell = &self.cells[index];
        if cell.lower > radius {
            return if cell.inside {
                Query::Exact
            } else {
                Query::Clear
            };
        }
        match self.closest_in(cell, p) {
            Some(projection) => Query::Surface(projection),
            None => Query::Exact,
        }
    }

    /// The closest point to `p` among a cell's triangles, inside or not
    /// as parry decides it: behind the pseudo-normal of the closest
    /// feature (never inside for an open mesh).
    #[inline]
    fn closest_in(&self, cell: &Cell, p: Vector) -> Option<PointProjection> {
        let list = &self.triangles[cell.start as usize..(cell.start + cell.count) as usize];
        let mut best: Option<(f32, u32, PointProjection, TrianglePointLocation)> = None;
        for &t in list {
            let (projection, location) = self
                .mesh
                .triangle(t)
                .project_local_point_and_get_location(p, false);
            let d2 = (p - projection.point).length_squared();
            if best.as_ref().is_none_or(|b| d2 < b.0) {
                best = Some((d2, t, projection, location));
            }
        }
        let (_, t, mut projection, location) = best?;
        projection.is_inside = false;
        if let Some(normals) = self.mesh.pseudo_normals_if_oriented() {
            let normal = match location {
                TrianglePointLocation::OnFace(..) | TrianglePointLocation::OnSolid => {
                    Some(self.mesh.triangle(t).scaled_normal())
                }
                TrianglePointLocation::OnEdge(i, _) => normals
                    .edges_pseudo_normal
                    .get(t as usize)
                    .map(|n| n[i as usize]),
                TrianglePointLocation::OnVertex(i) => self
                    .mesh
                    .indices()
                    .get(t as usize)
                    .and_then(|idx| normals.vertices_pseudo_normal.get(idx[i as usize] as usize))
                    .copied(),
            };
            if let Some(normal) = normal {
                projection.is_inside = (p - projection.point).dot(normal) <= 0.0;
            }
        }
        Some(projection)
    }

    /// parry's full query on the same mesh.
    pub(crate) fn exact(&self, p: Vector) -> PointProjection {
        self.mesh.project_local_point(p, false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn head() -> TriMesh {
        let (vertices, triangles) = crate::sim::contact::colliders::sample_head();
        TriMesh::with_flags(vertices, triangles, TriMeshFlags::ORIENTED).expect("head mesh")
    }

    #[test]
    fn the_grid_agrees_with_parrys_exact_distance() {
        let mesh = head();
        let sdf = MeshSdf::new(&mesh).expect("within budget").expect("grid");
        let radius = 4e-5;
        assert!(radius <= sdf.max_radius);
        let mut seed = 7u32;
        let mut next = || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1u32 << 24) as f32 - 0.5
        };
        let (mut near, mut inside, mut clear) = (0, 0, 0);
        for i in 0..20_000 {
            // Points on rays through the head at distances from 0.9 to 1.1
            // of the surface (and a few far inside and outside).
            let dir = Vector::new(next(), next(), next()).normalize();
            let exact_on_ray = mesh.project_local_point(dir * 0.2, false);
            let scale = if i % 10 == 0 {
                0.5 + 2.0 * (next() + 0.5)
            } else {
                1.0 + 0.01 * next()
            };
            let p = exact_on_ray.point * scale + Vector::new(next(), next(), next()) * 1e-4;
            let exact = mesh.project_local_point(p, false);
            let distance = (p - exact.point).length();
            match sdf.query(p, radius) {
                Query::Clear => {
                    assert!(!exact.is_inside && distance > radius, "{p:?}: {distance}");
                    clear += 1;
                }
                Query::Surface(got) => {
                    assert_eq!(got.is_inside, exact.is_inside, "{p:?}");
                    let got_distance = (p - got.point).length();
                    assert!(
                        (got_distance - distance).abs() <= 1e-7,
                        "{p:?}: {got_distance} vs {distance}"
                    );
                    near += 1;
                    inside += usize::from(got.is_inside);
                }
                Query::Exact => assert!(exact.is_inside, "{p:?}"),
            }
        }
        eprintln!("{near} near ({inside} inside), {clear} clear");
        assert!(
            near > 1000 && inside > 300 && clear > 1000,
            "{near} {inside} {clear}"
        );
    }

    /// A vertex at a huge but finite coordinate (3.2e38) once sized the
    /// grid from an overflowed product and listed cells without bound;
    /// the grid stays within its cell budget (a coarse, valid grid).
    #[test]
    fn a_vertex_near_f32_max_gives_a_bounded_grid() {
        let (mut vertices, triangles) = crate::sim::contact::colliders::sample_head();
        vertices[0].y = 3.2e38;
        let mesh = TriMesh::new(vertices, triangles).expect("mesh");
        let sdf = MeshSdf::new(&mesh).expect("within budget").expect("grid");
        assert!(
            sdf.dims.iter().product::<usize>() <= MAX_CELLS,
            "{:?}",
            sdf.dims
        );
        assert!(sdf.cell.is_finite() && sdf.origin.iter().all(|o| o.is_finite()));
    }
}
