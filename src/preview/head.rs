//! The head (any solid surface the hair grows on or lies against) drawn
//! opaque under the hair: smooth-shaded triangles lit by the lights the hair
//! is lit by, anti-aliased (2 x 2 samples a pixel), with a depth buffer that
//! hides the hair behind the head. Without it a TD looks through the face
//! opening at the inside of the back hair.
//!
//! Hand-written (as the collider layer in `surfaces.rs`): a few thousand
//! triangles at preview size, drawn once per picture with the hair's camera.

use super::camera::{cross, dot, normalize, sub, Camera, Vec3};
use super::shading::Lights;
use super::Surface;
use rayon::prelude::*;
use std::collections::HashMap;

/// Skin (linear RGB), about sRGB (206, 160, 137): a light-medium tone that
/// no attribute ramp uses and that the mid-brown hair stands out against.
pub const SKIN: [f32; 3] = [0.62, 0.35, 0.25];

/// Samples along each side of a pixel.
const SAMPLES: usize = 2;

/// Rows of pixels a thread draws together.
const BAND_ROWS: usize = 32;

/// Hair this far inside the head's surface, as a share of the head's
/// bounding-box diagonal (about 2 mm on a 20 cm head), still shows: the head
/// is drawn from flat triangles whose faces lie inside the round surface the
/// collider is (0.7 mm on a 24-sided 8 cm ball), and hair lying on the scalp
/// sits a hair radius above it.
const DEPTH_TOLERANCE: f32 = 0.007;

/// The head as drawn, per pixel (row-major).
pub(crate) struct HeadLayer {
    /// Shaded colour times coverage, and coverage (0 to 1).
    pub color: Vec<[f32; 4]>,
    /// Hair fragments farther than this are behind the head (infinite where
    /// the head covers less than half the pixel).
    pub hides_beyond: Vec<f32>,
    /// Depth of the head's nearest sample (infinite where there is none).
    pub depth: Vec<f32>,
}

impl HeadLayer {
    /// `plain` with the head over it at `pixel`.
    pub fn over(&self, pixel: usize, plain: [f32; 3]) -> [f32; 3] {
        match self.color.get(pixel) {
            Some(&[r, g, b, coverage]) if coverage > 0.0 => [
                r + plain[0] * (1.0 - coverage),
                g + plain[1] * (1.0 - coverage),
                b + plain[2] * (1.0 - coverage),
            ],
            _ => plain,
        }
    }
}

/// A projected vertex with its (outward) normal.
#[derive(Clone, Copy)]
struct Corner {
    x: f32,
    y: f32,
    depth: f32,
    normal: Vec3,
    /// Unit direction toward the eye.
    view: Vec3,
}

struct Triangle {
    corners: [Corner; 3],
    color: [f32; 3],
    /// Rows of samples it may cover.
    rows: (usize, usize),
}

/// Draws `solids`; `None` when there are none.
pub(crate) fn rasterize(
    solids: &[&Surface],
    camera: &Camera,
    width: usize,
    height: usize,
) -> Option<HeadLayer> {
    if solids.is_empty() || width == 0 || height == 0 {
        return None;
    }
    let lights = Lights::new(camera);
    let scale = SAMPLES as f32;
    let mut triangles = Vec::new();
    let mut low = [f32::INFINITY; 3];
    let mut high = [f32::NEG_INFINITY; 3];
    for surface in solids {
        let (positions, normals, indices) = smooth_mesh(surface);
        let corners: Vec<Option<Corner>> = positions
            .iter()
            .zip(&normals)
            .map(|(&p, &normal)| {
                let projected = camera.project(p)?;
                for k in 0..3 {
                    low[k] = low[k].min(p[k]);
                    high[k] = high[k].max(p[k]);
                }
                Some(Corner {
                    x: projected.x * scale,
                    y: projected.y * scale,
                    depth: projected.depth,
                    normal,
                    view: camera.toward_eye(p),
                })
            })
            .collect();
        for [a, b, c] in indices {
            let (Some(Some(a)), Some(Some(b)), Some(Some(c))) =
                (corners.get(a), corners.get(b), corners.get(c))
            else {
                continue;
            };
            let top = a.y.min(b.y).min(c.y).floor().max(0.0) as usize;
            let bottom = a.y.max(b.y).max(c.y).ceil().max(0.0) as usize;
            triangles.push(Triangle {
                corners: [*a, *b, *c],
                color: surface.color,
                rows: (top, bottom),
            });
        }
    }
    let diagonal = dot(sub(high, low), sub(high, low)).sqrt();
    let tolerance = if diagonal.is_finite() {
        DEPTH_TOLERANCE * diagonal
    } else {
        0.0
    };
    let pixels = width * height;
    let mut color = vec![[0.0f32; 4]; pixels];
    let mut hides_beyond = vec![f32::INFINITY; pixels];
    let mut depth = vec![f32::INFINITY; pixels];
    color
        .par_chunks_mut(width * BAND_ROWS)
        .zip(hides_beyond.par_chunks_mut(width * BAND_ROWS))
        .zip(depth.par_chunks_mut(width * BAND_ROWS))
        .enumerate()
        .for_each(|(band, ((color, hides_beyond), depth))| {
            let rows = color.len() / width;
            let row0 = band * BAND_ROWS;
            let samples_wide = width * SAMPLES;
            let sample_rows = (row0 * SAMPLES, (row0 + rows) * SAMPLES);
            let mut nearest = vec![f32::INFINITY; samples_wide * rows * SAMPLES];
            let mut shaded = vec![[0.0f32; 3]; samples_wide * rows * SAMPLES];
            for triangle in triangles
                .iter()
                .filter(|t| t.rows.1 >= sample_rows.0 && t.rows.0 < sample_rows.1)
            {
                draw(
                    triangle,
                    &lights,
                    sample_rows,
                    samples_wide,
                    &mut nearest,
                    &mut shaded,
                );
            }
            for r in 0..rows {
                for x in 0..width {
                    let mut sum = [0.0f32; 3];
                    let mut covered = 0usize;
                    let mut least = f32::INFINITY;
                    for sy in 0..SAMPLES {
                        for sx in 0..SAMPLES {
                            let at = (r * SAMPLES + sy) * samples_wide + x * SAMPLES + sx;
                            if nearest[at].is_finite() {
                                covered += 1;
                                least = least.min(nearest[at]);
                                for (s, c) in sum.iter_mut().zip(shaded[at]) {
                                    *s += c;
                                }
                            }
                        }
                    }
                    let at = r * width + x;
                    let per_sample = 1.0 / (SAMPLES * SAMPLES) as f32;
                    color[at] = [
                        sum[0] * per_sample,
                        sum[1] * per_sample,
                        sum[2] * per_sample,
                        covered as f32 * per_sample,
                    ];
                    depth[at] = least;
                    if 2 * covered >= SAMPLES * SAMPLES {
                        hides_beyond[at] = least + tolerance;
                    }
                }
            }
        });
    Some(HeadLayer {
        color,
        hides_beyond,
        depth,
    })
}

/// Fills the samples of rows `sample_rows` a triangle covers where it is the
/// nearest so far, shaded.
fn draw(
    triangle: &Triangle,
    lights: &Lights,
    sample_rows: (usize, usize),
    samples_wide: usize,
    nearest: &mut [f32],
    shaded: &mut [[f32; 3]],
) {
    let [a, b, c] = triangle.corners;
    let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    if !area.is_finite() || area.abs() < 1e-12 {
        return;
    }
    let clamp_x = |v: f32| v.clamp(0.0, samples_wide as f32) as usize;
    let x0 = clamp_x(a.x.min(b.x).min(c.x).floor());
    let x1 = clamp_x(a.x.max(b.x).max(c.x).ceil());
    let y0 = triangle.rows.0.max(sample_rows.0);
    let y1 = triangle.rows.1.min(sample_rows.1);
    for y in y0..y1 {
        let py = y as f32 + 0.5;
        for x in x0..x1 {
            let px = x as f32 + 0.5;
            let wa = ((b.x - px) * (c.y - py) - (b.y - py) * (c.x - px)) / area;
            let wb = ((c.x - px) * (a.y - py) - (c.y - py) * (a.x - px)) / area;
            let wc = 1.0 - wa - wb;
            if wa < 0.0 || wb < 0.0 || wc < 0.0 {
                continue;
            }
            let z = wa * a.depth + wb * b.depth + wc * c.depth;
            let at = (y - sample_rows.0) * samples_wide + x;
            if z >= nearest[at] {
                continue;
            }
            nearest[at] = z;
            let blend = |f: fn(&Corner) -> Vec3| {
                let (p, q, r) = (f(&a), f(&b), f(&c));
                [0, 1, 2].map(|k| wa * p[k] + wb * q[k] + wc * r[k])
            };
            let view = normalize(blend(|c| c.view));
            let mut normal = normalize(blend(|c| c.normal));
            // The inside of a surface seen through an opening faces the eye too.
            if dot(normal, view) < 0.0 {
                normal = normal.map(|v| -v);
            }
            shaded[at] = skin_shade(normal, view, triangle.color, lights);
        }
    }
}

/// Diffuse light wrapped a little past the terminator (skin scatters light
/// under its surface), a faint rim, and ambient light.
fn skin_shade(normal: Vec3, view: Vec3, base: [f32; 3], lights: &Lights) -> [f32; 3] {
    let wrapped = |light: Vec3| ((dot(normal, light) + 0.3) / 1.3).max(0.0);
    let rim = (1.0 - dot(normal, view).clamp(0.0, 1.0)).powi(3);
    let light = 0.16 + 0.72 * wrapped(lights.key) + 0.22 * wrapped(lights.fill) + 0.2 * rim;
    base.map(|c| c * light)
}

/// A surface's corners welded into shared vertices (by exact position) with
/// area-weighted vertex normals pointing outward, and its triangles as
/// indices into them.
type SmoothMesh = (Vec<Vec3>, Vec<Vec3>, Vec<[usize; 3]>);

fn smooth_mesh(surface: &Surface) -> SmoothMesh {
    let mut index_of: HashMap<[u32; 3], usize> = HashMap::new();
    let mut positions: Vec<Vec3> = Vec::new();
    let mut indices = Vec::with_capacity(surface.triangles.len());
    for triangle in &surface.triangles {
        indices.push(triangle.map(|p| {
            *index_of.entry(p.map(f32::to_bits)).or_insert_with(|| {
                positions.push(p);
                positions.len() - 1
            })
        }));
    }
    let count = positions.len().max(1) as f32;
    let center = positions
        .iter()
        .fold([0.0f32; 3], |s, p| [s[0] + p[0], s[1] + p[1], s[2] + p[2]])
        .map(|s| s / count);
    // Face normals as wound (length: twice the area); flipped all together
    // when most point inward, so a mesh wound either way lights alike.
    let faces: Vec<Vec3> = indices
        .iter()
        .map(|&[a, b, c]| {
            cross(
                sub(positions[b], positions[a]),
                sub(positions[c], positions[a]),
            )
        })
        .collect();
    let outward: f32 = indices
        .iter()
        .zip(&faces)
        .map(|(&[a, _, _], n)| dot(*n, sub(positions[a], center)).signum())
        .sum();
    let sign = if outward < 0.0 { -1.0 } else { 1.0 };
    let mut normals = vec![[0.0f32; 3]; positions.len()];
    for (triangle, face) in indices.iter().zip(&faces) {
        for &i in triangle {
            for k in 0..3 {
                normals[i][k] += sign * face[k];
            }
        }
    }
    let normals = normals.into_iter().map(normalize).collect();
    (positions, normals, indices)
}
