//! Surfaces drawn with the hair. A solid one (a head) is drawn opaque and
//! lit (`head.rs`). The others (a pillow, a plate): triangles rasterised
//! flat-shaded with a depth buffer into a layer that lies behind the hair
//! and, faintly, over it, so that hair behind such a surface still shows and
//! the surface still shows where hair covers it.
//!
//! Hand-written rather than a crate: a few thousand triangles at preview
//! size, drawn once per picture, with the camera the hair uses.

use super::camera::{cross, dot, normalize, sub, Camera, Vec3};

/// A triangle surface to draw, in the groom's coordinates (Y up, the groom's
/// units), with its colour (linear RGB).
#[derive(Debug, Clone, PartialEq)]
pub struct Surface {
    pub triangles: Vec<[[f32; 3]; 3]>,
    pub color: [f32; 3],
    /// Opaque and smooth-shaded, hiding the hair behind it (a head); else
    /// semi-transparent (a pillow that comes and goes).
    pub solid: bool,
}

impl Surface {
    /// A head: solid, skin-coloured.
    pub fn head(triangles: Vec<[[f32; 3]; 3]>) -> Surface {
        Surface {
            triangles,
            color: super::head::SKIN,
            solid: true,
        }
    }
}

/// The nearest surface at each pixel: its shaded colour and its depth.
pub(crate) type Layer = Vec<Option<([f32; 3], f32)>>;

/// How much of a surface's colour replaces the background behind the hair.
pub(crate) const BEHIND_HAIR: f32 = 0.6;
/// How much of a surface's colour is laid over the finished picture.
pub(crate) const OVER_HAIR: f32 = 0.22;

/// The shaded colour and depth of the nearest surface at every pixel
/// (row-major), `None` where no surface is.
pub(crate) fn rasterize(
    surfaces: &[&Surface],
    camera: &Camera,
    width: usize,
    height: usize,
) -> Layer {
    let mut color = vec![None; width * height];
    let mut depth = vec![f32::INFINITY; width * height];
    for surface in surfaces {
        for triangle in &surface.triangles {
            draw_triangle(
                triangle,
                surface.color,
                camera,
                width,
                height,
                &mut color,
                &mut depth,
            );
        }
    }
    color
        .into_iter()
        .zip(depth)
        .map(|(c, d)| c.map(|c| (c, d)))
        .collect()
}

fn draw_triangle(
    triangle: &[[f32; 3]; 3],
    base: [f32; 3],
    camera: &Camera,
    width: usize,
    height: usize,
    color: &mut [Option<[f32; 3]>],
    depth: &mut [f32],
) {
    let [a, b, c] = *triangle;
    let (Some(pa), Some(pb), Some(pc)) = (camera.project(a), camera.project(b), camera.project(c))
    else {
        return;
    };
    // Lit from the eye: faces toward the camera bright, edge-on ones dark,
    // whichever way the triangle winds.
    let normal: Vec3 = normalize(cross(sub(b, a), sub(c, a)));
    let facing = dot(normal, camera.forward).abs();
    let shade = 0.35 + 0.65 * facing;
    let shaded = base.map(|c| c * shade);
    let area = (pb.x - pa.x) * (pc.y - pa.y) - (pb.y - pa.y) * (pc.x - pa.x);
    if !area.is_finite() || area.abs() < 1e-12 {
        return;
    }
    let clamp_x = |v: f32| v.clamp(0.0, width as f32) as usize;
    let clamp_y = |v: f32| v.clamp(0.0, height as f32) as usize;
    let (x0, x1) = (
        clamp_x(pa.x.min(pb.x).min(pc.x).floor()),
        clamp_x(pa.x.max(pb.x).max(pc.x).ceil()),
    );
    let (y0, y1) = (
        clamp_y(pa.y.min(pb.y).min(pc.y).floor()),
        clamp_y(pa.y.max(pb.y).max(pc.y).ceil()),
    );
    for y in y0..y1 {
        for x in x0..x1 {
            let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
            // Barycentric weights from the signed areas of the sub-triangles.
            let wa = ((pb.x - px) * (pc.y - py) - (pb.y - py) * (pc.x - px)) / area;
            let wb = ((pc.x - px) * (pa.y - py) - (pc.y - py) * (pa.x - px)) / area;
            let wc = 1.0 - wa - wb;
            if wa < 0.0 || wb < 0.0 || wc < 0.0 {
                continue;
            }
            let z = wa * pa.depth + wb * pb.depth + wc * pc.depth;
            let at = y * width + x;
            if z < depth[at] {
                depth[at] = z;
                color[at] = Some(shaded);
            }
        }
    }
}

/// `a` mixed toward `b` by `t`.
pub(crate) fn mix(a: [f32; 3], b: [f32; 3], t: f32) -> [f32; 3] {
    [0, 1, 2].map(|k| a[k] + (b[k] - a[k]) * t)
}
