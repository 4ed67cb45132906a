//! The lights hair and head are shaded by: a key, a fill and a rim light
//! fixed relative to the camera, and Kajiya-Kay shading of hair fibres.

use super::camera::{dot, normalize, Camera, Vec3};

/// A key, a fill and a rim light, fixed relative to the camera so every view
/// is lit alike.
pub(crate) struct Lights {
    pub key: Vec3,
    pub fill: Vec3,
    pub rim: Vec3,
}

impl Lights {
    pub fn new(camera: &Camera) -> Lights {
        let toward = |r: f32, u: f32, b: f32| {
            normalize([
                camera.right[0] * r + camera.up[0] * u - camera.forward[0] * b,
                camera.right[1] * r + camera.up[1] * u - camera.forward[1] * b,
                camera.right[2] * r + camera.up[2] * u - camera.forward[2] * b,
            ])
        };
        Lights {
            key: toward(-0.45, 0.65, 0.6),
            fill: toward(0.8, 0.1, 0.45),
            rim: toward(0.3, 0.5, -0.8),
        }
    }

    /// Kajiya-Kay: diffuse `sin(T, L)`, specular
    /// `(sin(T,L) sin(T,V) - cos(T,L) cos(T,V))^p` around the reflection cone.
    pub fn shade(
        &self,
        tangent: Vec3,
        view: Vec3,
        base: [f32; 3],
        occlusion: f32,
        key_light: f32,
        mapped: bool,
    ) -> [f32; 3] {
        let kk = |light: Vec3, exponent: f32| {
            let tl = dot(tangent, light).clamp(-1.0, 1.0);
            let tv = dot(tangent, view).clamp(-1.0, 1.0);
            let sin_tl = (1.0 - tl * tl).max(0.0).sqrt();
            let sin_tv = (1.0 - tv * tv).max(0.0).sqrt();
            let diffuse = sin_tl;
            let specular = (sin_tl * sin_tv - tl * tv).max(0.0).powf(exponent);
            (diffuse, specular)
        };
        let (key_diffuse, key_specular) = kk(self.key, 80.0);
        let (_, key_broad) = kk(self.key, 12.0);
        let (fill_diffuse, _) = kk(self.fill, 1.0);
        let (_, rim_specular) = kk(self.rim, 20.0);
        // Mapped colours keep more ambient light so the ramp stays legible.
        let ambient = if mapped { 0.35 } else { 0.12 };
        let diffuse = ambient + 0.85 * key_light * key_diffuse + 0.3 * fill_diffuse;
        let specular_strength = if mapped { 0.12 } else { 0.2 };
        // The sharp highlight is a warm white (light reflected at the cuticle);
        // the broad one and the rim carry the hair's own colour (light that
        // went through the fibre).
        const HIGHLIGHT: [f32; 3] = [1.0, 0.9, 0.8];
        let mut color = [0.0; 3];
        for ((c, b), h) in color.iter_mut().zip(base).zip(HIGHLIGHT) {
            *c = (b * (diffuse + 0.5 * key_light * key_broad + 0.8 * rim_specular)
                + specular_strength * h * key_light * key_specular)
                * occlusion;
        }
        color
    }
}
