//! Hair shadowing itself from the key light: a coarse grid aligned with the
//! light holds the hair cross-section (width x length) in each cell; a vertex
//! is lit through the hair in the cells between it and the light (the idea
//! of deep opacity maps, on a voxel grid). Without it a groom reads as a
//! flat shape.

use super::camera::{cross, dot, normalize, Vec3};
use rayon::prelude::*;

/// Cells along each axis of the grid.
const CELLS: usize = 64;

/// Light a hair fibre lets through is not zero (it scatters inside); this
/// scales the optical depth of the hair in front.
const ABSORPTION: f32 = 0.35;

/// However deep in the hair, some light arrives (multiple scattering).
const LEAST_LIGHT: f32 = 0.12;

/// Fraction of the key light reaching each point (1 = unshadowed).
///
/// `points` are Y-up positions, `cross_sections[i]` the hair area a vertex
/// stands for (width times the length it represents), in the same units
/// squared. Non-finite points get 1.
pub(crate) fn key_light(points: &[Vec3], cross_sections: &[f32], toward_light: Vec3) -> Vec<f32> {
    let w = normalize(toward_light);
    let helper = if w[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let u = normalize(cross(w, helper));
    let v = cross(w, u);
    let to_light_space = |p: &Vec3| [dot(*p, u), dot(*p, v), dot(*p, w)];
    let mut min = [f32::INFINITY; 3];
    let mut max = [f32::NEG_INFINITY; 3];
    for p in points.iter().filter(|p| p.iter().all(|c| c.is_finite())) {
        let q = to_light_space(p);
        for k in 0..3 {
            min[k] = min[k].min(q[k]);
            max[k] = max[k].max(q[k]);
        }
    }
    if !(min[0].is_finite() && max[0].is_finite()) {
        return vec![1.0; points.len()];
    }
    let size: [f32; 3] = [0, 1, 2].map(|k| ((max[k] - min[k]) / CELLS as f32).max(1e-12));
    // Cell coordinates, continuous (cell centres at whole numbers + 0.5).
    let cell_of = |q: [f32; 3]| [0, 1, 2].map(|k| (q[k] - min[k]) / size[k]);
    let index = |i: usize, j: usize, k: usize| (i * CELLS + j) * CELLS + k;
    let clamp_cell = |x: f32| (x.max(0.0) as usize).min(CELLS - 1);

    // Sequential sums: the same order, hence the same bits, every run.
    let mut grid = vec![0f64; CELLS * CELLS * CELLS];
    for (p, &area) in points.iter().zip(cross_sections) {
        if !p.iter().all(|c| c.is_finite()) || !area.is_finite() || area <= 0.0 {
            continue;
        }
        let c = cell_of(to_light_space(p));
        grid[index(clamp_cell(c[0]), clamp_cell(c[1]), clamp_cell(c[2]))] += f64::from(area);
    }
    // Optical depth in front of each cell's centre: everything nearer the
    // light (higher w) plus half of the cell itself.
    let cell_area = f64::from(size[0]) * f64::from(size[1]);
    let mut depth = vec![0f32; grid.len()];
    for i in 0..CELLS {
        for j in 0..CELLS {
            let mut before = 0f64;
            for k in (0..CELLS).rev() {
                let own = grid[index(i, j, k)];
                depth[index(i, j, k)] = ((before + 0.5 * own) / cell_area) as f32;
                before += own;
            }
        }
    }
    // Trilinear lookup between cell centres, so the shadow has no steps.
    let lookup = |c: [f32; 3]| {
        let mut total = 0.0;
        let base = c.map(|x| (x - 0.5).max(0.0));
        let whole = base.map(|x| (x as usize).min(CELLS - 1));
        let fraction = [0, 1, 2].map(|k| (base[k] - whole[k] as f32).clamp(0.0, 1.0));
        for corner in 0..8usize {
            let mut weight = 1.0;
            let mut at = [0usize; 3];
            for k in 0..3 {
                let high = corner >> k & 1 == 1;
                at[k] = (whole[k] + usize::from(high)).min(CELLS - 1);
                weight *= if high { fraction[k] } else { 1.0 - fraction[k] };
            }
            total += weight * depth[index(at[0], at[1], at[2])];
        }
        total
    };
    points
        .par_iter()
        .zip(cross_sections)
        .map(|(p, &area)| {
            if !p.iter().all(|c| c.is_finite()) {
                return 1.0;
            }
            // A hair does not shade itself: take out its own half share.
            let own = if area.is_finite() && area > 0.0 {
                (0.5 * f64::from(area) / cell_area) as f32
            } else {
                0.0
            };
            let optical_depth = (lookup(cell_of(to_light_space(p))) - own).max(0.0);
            LEAST_LIGHT + (1.0 - LEAST_LIGHT) * (-ABSORPTION * optical_depth).exp()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hair_between_a_point_and_the_light_shades_it() {
        // A sheet of hair at y = 1 above a lone point at y = 0; light from +Y.
        let mut points = Vec::new();
        let mut areas = Vec::new();
        for i in 0..100 {
            for j in 0..100 {
                points.push([i as f32 / 99.0, 1.0, j as f32 / 99.0]);
                areas.push(1e-4);
            }
        }
        points.push([0.5, 0.0, 0.5]);
        areas.push(1e-4);
        points.push([0.5, 2.0, 0.5]);
        areas.push(1e-4);
        let light = key_light(&points, &areas, [0.0, 1.0, 0.0]);
        let under = light[points.len() - 2];
        let above = light[points.len() - 1];
        assert!(above > 0.99, "{above}");
        assert!(under < 0.8, "{under}");
        assert!(under >= LEAST_LIGHT);
        // Not finite: fully lit, no panic.
        assert_eq!(
            key_light(&[[f32::NAN; 3]], &[1.0], [0.0, 1.0, 0.0]),
            vec![1.0]
        );
    }
}
