//! Cameras framed automatically on a set of points (Y up).

use super::View;

pub(crate) use groom::math::single::{cross, dot, sub, V3 as Vec3};

/// Unit `a`, or zero for a vector without direction (a degenerate view).
pub(crate) fn normalize(a: Vec3) -> Vec3 {
    groom::math::single::try_normalize(a).unwrap_or([0.0; 3])
}

/// Where a point lands in the picture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Projected {
    pub x: f32,
    pub y: f32,
    /// Distance in front of the camera along its axis (larger is farther).
    pub depth: f32,
    /// Pixels per scene unit at this point (for widths).
    pub pixels_per_unit: f32,
}

/// A camera and the mapping of its image plane onto pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    pub(crate) eye: Vec3,
    pub(crate) right: Vec3,
    pub(crate) up: Vec3,
    /// Unit vector the camera looks along.
    pub(crate) forward: Vec3,
    pub(crate) perspective: bool,
    /// Image-plane units to pixels.
    scale: f32,
    /// Image-plane point at the centre of the framed area.
    center: [f32; 2],
    /// Pixel position of that centre.
    pixel_center: [f32; 2],
}

/// Half the vertical field of view of the perspective view, radians.
const PERSPECTIVE_HALF_ANGLE: f32 = 0.25;

impl Camera {
    /// A camera for `view` that shows every point of `points` (Y-up scene
    /// coordinates) inside the `width` x `height` area whose top-left is at
    /// pixel `origin`, leaving a margin. `None` without finite points.
    pub fn framing<'a>(
        view: View,
        points: impl Iterator<Item = &'a Vec3> + Clone,
        origin: [f32; 2],
        width: f32,
        height: f32,
    ) -> Option<Camera> {
        let (min, max) =
            groom::bounds_of(points.clone().filter(|p| p.iter().all(|c| c.is_finite())))?;
        let middle = [
            0.5 * (min[0] + max[0]),
            0.5 * (min[1] + max[1]),
            0.5 * (min[2] + max[2]),
        ];
        let radius = (0.5 * dot(sub(max, min), sub(max, min)).sqrt()).max(1e-6);
        let (forward, up_hint): (Vec3, Vec3) = match view {
            View::Front => ([0.0, 0.0, -1.0], [0.0, 1.0, 0.0]),
            View::Side => ([-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
            View::Top => ([0.0, -1.0, 0.0], [0.0, 0.0, -1.0]),
            // From the front right, a little above.
            View::Persp => (normalize([-0.55, -0.35, -0.76]), [0.0, 1.0, 0.0]),
        };
        let right = normalize(cross(forward, up_hint));
        let up = cross(right, forward);
        let perspective = view == View::Persp;
        let distance = if perspective {
            radius / PERSPECTIVE_HALF_ANGLE.sin() * 1.05
        } else {
            2.0 * radius
        };
        let eye = sub(middle, forward.map(|c| c * distance));
        let mut camera = Camera {
            eye,
            right,
            up,
            forward,
            perspective,
            scale: 1.0,
            center: [0.0, 0.0],
            pixel_center: [origin[0] + 0.5 * width, origin[1] + 0.5 * height],
        };
        // Fit the projected extent, not the 3D box, so the groom fills the frame.
        let mut plane_min = [f32::INFINITY; 2];
        let mut plane_max = [f32::NEG_INFINITY; 2];
        for p in points {
            if let Some(q) = camera.plane(*p) {
                for k in 0..2 {
                    plane_min[k] = plane_min[k].min(q[k]);
                    plane_max[k] = plane_max[k].max(q[k]);
                }
            }
        }
        if !(plane_min[0].is_finite() && plane_max[0].is_finite()) {
            return None;
        }
        camera.center = [
            0.5 * (plane_min[0] + plane_max[0]),
            0.5 * (plane_min[1] + plane_max[1]),
        ];
        let margin = 0.06;
        let extent_x = (plane_max[0] - plane_min[0]).max(1e-9);
        let extent_y = (plane_max[1] - plane_min[1]).max(1e-9);
        let fit_x = width * (1.0 - 2.0 * margin) / extent_x;
        let fit_y = height * (1.0 - 2.0 * margin) / extent_y;
        camera.scale = fit_x.min(fit_y);
        if !camera.scale.is_finite() || camera.scale <= 0.0 {
            return None;
        }
        Some(camera)
    }

    /// Image-plane coordinates of a point, `None` behind the camera.
    fn plane(&self, p: Vec3) -> Option<[f32; 2]> {
        let q = sub(p, self.eye);
        let x = dot(q, self.right);
        let y = dot(q, self.up);
        if self.perspective {
            let z = dot(q, self.forward);
            (z > 1e-9).then(|| [x / z, y / z])
        } else {
            Some([x, y])
        }
    }

    pub(crate) fn project(&self, p: Vec3) -> Option<Projected> {
        let q = sub(p, self.eye);
        let depth = dot(q, self.forward);
        let plane = self.plane(p)?;
        let pixels_per_unit = if self.perspective {
            self.scale / depth
        } else {
            self.scale
        };
        let projected = Projected {
            x: self.pixel_center[0] + (plane[0] - self.center[0]) * self.scale,
            y: self.pixel_center[1] - (plane[1] - self.center[1]) * self.scale,
            depth,
            pixels_per_unit,
        };
        let finite = projected.x.is_finite()
            && projected.y.is_finite()
            && projected.depth.is_finite()
            && projected.pixels_per_unit.is_finite();
        finite.then_some(projected)
    }

    /// Unit direction from `p` towards the camera.
    pub(crate) fn toward_eye(&self, p: Vec3) -> Vec3 {
        if self.perspective {
            normalize(sub(self.eye, p))
        } else {
            self.forward.map(|c| -c)
        }
    }
}
