//! Procedural test grooms: strands rooted on the scalp cap of a sphere or
//! ellipsoid head, or a swatch of strands hanging from a bar; straight or
//! waved with the elliptic-cone spiral of `001_*` eq. (30)-(31).
//!
//! Coordinates are metres, Y up. The same parameters and seed give the same
//! groom bit for bit (a fixed SplitMix64 stream, no platform randomness).

use groom::{Attribute, AttributeValues, Groom, Provenance, Units, UpAxis};
use serde::{Deserialize, Serialize};

/// Where the roots are.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum RootLayout {
    /// On the scalp cap of an ellipsoid head centred at `head_center`,
    /// growing along the surface normal.
    #[default]
    Scalp,
    /// Along a bar of width `swatch_width` at `head_center`, along X,
    /// hanging straight down (-Y). The paper's single-strand scenes.
    Swatch,
}

/// The shape of the strand around its axis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum StrandShape {
    #[default]
    Straight,
    /// `x = A z cos(C z + D)`, `y = B z sin(C z + D)` around the straight
    /// axis, `z` the arc length from `wave_start`, `D` random per strand.
    Wavy,
}

/// Everything a generated groom depends on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GeneratorParameters {
    pub layout: RootLayout,
    pub shape: StrandShape,
    pub strands: usize,
    /// Strand length, metres.
    pub length: f32,
    /// Target segment length, metres; each strand gets `round(length / segment_length)` edges.
    pub segment_length: f32,
    pub seed: u64,
    pub head_center: [f32; 3],
    /// Ellipsoid semi-axes (x, y, z), metres; equal for a sphere.
    pub head_radii: [f32; 3],
    /// Largest polar angle of a root from +Y, degrees (the cap's size).
    pub scalp_angle: f32,
    /// Width of the swatch bar, metres.
    pub swatch_width: f32,
    /// Wave amplitude slopes A and B (dimensionless: radius grows A z).
    pub wave_amplitude: [f32; 2],
    /// Wave frequency C, radians per metre.
    pub wave_frequency: f32,
    /// Arc length from the root where the wave starts, metres.
    pub wave_start: f32,
    /// Hair width written as the `width` attribute, metres.
    pub width: f32,
    /// Scalp strands bend from the root normal toward -Y at this rate,
    /// radians per metre, and are kept off the head: combed-down hair.
    /// 0 keeps them straight along the normal.
    pub drape: f32,
}

impl Default for GeneratorParameters {
    fn default() -> Self {
        GeneratorParameters {
            layout: RootLayout::Scalp,
            shape: StrandShape::Straight,
            strands: 200,
            length: 0.24,
            segment_length: 0.01,
            seed: 1,
            head_center: [0.0, 0.0, 0.0],
            head_radii: [0.08, 0.1, 0.09],
            scalp_angle: 80.0,
            swatch_width: 0.05,
            wave_amplitude: [0.15, 0.1],
            wave_frequency: 60.0,
            wave_start: 0.03,
            width: 8.0e-5,
            drape: 0.0,
        }
    }
}

/// Why parameters cannot make a groom.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("generator parameter '{name}': {message}")]
pub struct GeneratorError {
    pub name: &'static str,
    pub message: String,
}

impl GeneratorParameters {
    /// Every edge count the parameters give (the same for all strands).
    pub fn edges_per_strand(&self) -> usize {
        ((self.length / self.segment_length).round() as usize).max(1)
    }

    pub fn check(&self) -> Result<(), GeneratorError> {
        let fail = |name, message: &str| {
            Err(GeneratorError {
                name,
                message: message.to_string(),
            })
        };
        if self.strands == 0 || self.strands > 10_000_000 {
            return fail("strands", "must be between 1 and 10,000,000");
        }
        if !(self.length.is_finite() && self.length > 0.0) {
            return fail("length", "must be a positive length");
        }
        if !(self.segment_length.is_finite() && self.segment_length > 0.0) {
            return fail("segment_length", "must be a positive length");
        }
        if self.length / self.segment_length > 10_000.0 {
            return fail(
                "segment_length",
                "gives more than 10,000 segments per strand",
            );
        }
        if self.head_radii.iter().any(|r| !(r.is_finite() && *r > 0.0)) {
            return fail("head_radii", "must be three positive lengths");
        }
        if !(self.scalp_angle.is_finite() && self.scalp_angle > 0.0 && self.scalp_angle <= 180.0) {
            return fail("scalp_angle", "must be in (0, 180] degrees");
        }
        let finite = self.head_center.iter().all(|c| c.is_finite())
            && self.wave_amplitude.iter().all(|c| c.is_finite())
            && self.wave_frequency.is_finite()
            && self.wave_start.is_finite()
            && self.swatch_width.is_finite()
            && self.width.is_finite()
            && self.drape.is_finite();
        if !finite {
            return fail("parameters", "every number must be finite");
        }
        // The product, not only each factor: 10 M strands of 10 k segments
        // would ask for a terabyte.
        let per_strand = self.edges_per_strand() as u64 + 1;
        if let Err(message) = crate::budget::check_vertices(self.strands as u64, per_strand) {
            return Err(GeneratorError {
                name: "strands",
                message,
            });
        }
        Ok(())
    }
}

/// A small, fixed pseudo-random stream (SplitMix64) so generated grooms are
/// the same on every platform and crate version.
#[derive(Debug, Clone)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    pub fn new(seed: u64) -> SplitMix64 {
        SplitMix64(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Standard normal (Box-Muller).
    pub fn next_normal(&mut self) -> f64 {
        let u1 = self.next_f64().max(f64::MIN_POSITIVE);
        let u2 = self.next_f64();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

use groom::math::double::{add, cross, scale, try_normalize, V3};

/// Unit `a`; straight up for a vector without direction (the generator's
/// directions are bounded, so this only guards a degenerate input).
fn normalize(a: V3) -> V3 {
    try_normalize(a).unwrap_or([0.0, 1.0, 0.0])
}

/// Builds the groom. Also writes the per-strand `root_uv` (spherical
/// coordinates of the root on the scalp, or position along the swatch) and
/// per-vertex `width` attributes.
pub fn generate(parameters: &GeneratorParameters) -> Result<Groom, GeneratorError> {
    parameters.check()?;
    let p = parameters;
    let mut random = SplitMix64::new(p.seed);
    let edges = p.edges_per_strand();
    let step = p.length as f64 / edges as f64;
    let center = p.head_center.map(f64::from);
    let radii = p.head_radii.map(f64::from);
    let mut groom = Groom {
        units: Units::METERS,
        up_axis: UpAxis::Y,
        provenance: Provenance {
            format: "generated".into(),
            ..Default::default()
        },
        ..Groom::default()
    };
    groom.points.reserve(p.strands * (edges + 1));
    let mut root_uv = Vec::with_capacity(p.strands);
    let cap = (p.scalp_angle as f64).to_radians();
    for strand in 0..p.strands {
        let (root, axis, uv) = match p.layout {
            RootLayout::Scalp => {
                // Uniform on the sphere cap: cos(polar) uniform in [cos(cap), 1].
                let cos_polar = 1.0 - random.next_f64() * (1.0 - cap.cos());
                let polar = cos_polar.clamp(-1.0, 1.0).acos();
                let azimuth = random.next_f64() * std::f64::consts::TAU;
                let d = [
                    polar.sin() * azimuth.cos(),
                    cos_polar,
                    polar.sin() * azimuth.sin(),
                ];
                let root = add(center, [d[0] * radii[0], d[1] * radii[1], d[2] * radii[2]]);
                // The ellipsoid normal is the gradient of sum (x_i / r_i)^2.
                let normal = normalize([d[0] / radii[0], d[1] / radii[1], d[2] / radii[2]]);
                let uv = [
                    (azimuth / std::f64::consts::TAU) as f32,
                    (polar / cap) as f32,
                ];
                (root, normal, uv)
            }
            RootLayout::Swatch => {
                let u = if p.strands == 1 {
                    0.5
                } else {
                    strand as f64 / (p.strands - 1) as f64
                };
                let x = (u - 0.5) * p.swatch_width as f64;
                (
                    add(center, [x, 0.0, 0.0]),
                    [0.0, -1.0, 0.0],
                    [u as f32, 0.0],
                )
            }
        };
        root_uv.push(uv);
        // Two normals of the axis for the wave.
        let helper = if axis[0].abs() < 0.9 {
            [1.0, 0.0, 0.0]
        } else {
            [0.0, 0.0, 1.0]
        };
        // Normals of the axis, parallel-transported along the spine below.
        let mut normal_x = normalize(cross(axis, helper));
        let phase = random.next_f64() * std::f64::consts::TAU;
        let first = groom.points.len();
        let spine = spine(p, root, axis, edges, step, center, radii);
        for (vertex, &on_spine) in spine.iter().enumerate() {
            let arc = vertex as f64 * step;
            let mut point = on_spine;
            let next = spine
                .get(vertex + 1)
                .or(spine.get(vertex.wrapping_sub(1)))
                .copied()
                .unwrap_or(on_spine);
            let mut tangent = normalize([
                next[0] - on_spine[0],
                next[1] - on_spine[1],
                next[2] - on_spine[2],
            ]);
            if vertex + 1 == spine.len() {
                tangent = scale(tangent, -1.0);
            }
            let along =
                normal_x[0] * tangent[0] + normal_x[1] * tangent[1] + normal_x[2] * tangent[2];
            normal_x = normalize(add(normal_x, scale(tangent, -along)));
            let normal_y = cross(tangent, normal_x);
            if p.shape == StrandShape::Wavy && arc > p.wave_start as f64 {
                let z = arc - p.wave_start as f64;
                let angle = p.wave_frequency as f64 * z + phase;
                let x = p.wave_amplitude[0] as f64 * z * angle.cos();
                let y = p.wave_amplitude[1] as f64 * z * angle.sin();
                point = add(point, add(scale(normal_x, x), scale(normal_y, y)));
            }
            groom.points.push(point.map(|c| c as f32));
        }
        if p.shape == StrandShape::Wavy {
            rescale_to_length(&mut groom.points[first..], step);
        }
        groom.strand_vertex_counts.push((edges + 1) as u32);
    }
    groom.attributes.push(Attribute::new(
        "width",
        AttributeValues::Float(vec![p.width; groom.points.len()]),
    ));
    groom.attributes.push(Attribute::per_strand(
        "root_uv",
        AttributeValues::Vec2(root_uv),
    ));
    Ok(groom)
}

/// The strand's axis: straight along `axis`, or bending toward -Y at the
/// drape rate and kept a little off the head ellipsoid.
fn spine(
    p: &GeneratorParameters,
    root: V3,
    axis: V3,
    edges: usize,
    step: f64,
    center: V3,
    radii: V3,
) -> Vec<V3> {
    let mut points = Vec::with_capacity(edges + 1);
    points.push(root);
    let mut direction = axis;
    let mut current = root;
    let bend = p.drape as f64 * step;
    for _ in 0..edges {
        if bend > 0.0 && p.layout == RootLayout::Scalp {
            // Turn the direction toward -Y by at most `bend` radians, in
            // the plane of the direction and -Y (or, straight up, the plane
            // through the root's own horizontal direction).
            let along = -direction[1];
            let angle = along.clamp(-1.0, 1.0).acos();
            if angle > 1e-9 {
                let mut toward = [
                    -direction[0] * along,
                    -1.0 - direction[1] * along,
                    -direction[2] * along,
                ];
                if (toward[0] * toward[0] + toward[1] * toward[1] + toward[2] * toward[2]) < 1e-12 {
                    toward = [root[0] - center[0], 0.0, root[2] - center[2]];
                    if toward[0] == 0.0 && toward[2] == 0.0 {
                        toward = [0.0, 0.0, 1.0];
                    }
                }
                let toward = normalize(toward);
                let turn = bend.min(angle);
                direction = normalize(add(scale(direction, turn.cos()), scale(toward, turn.sin())));
            }
        }
        let mut next = add(current, scale(direction, step));
        if bend > 0.0 && p.layout == RootLayout::Scalp {
            // Keep off the head: push out along the ellipsoid's radial
            // direction to 1.02 of its surface, keeping the edge length.
            let local = [0, 1, 2].map(|k| (next[k] - center[k]) / radii[k]);
            let r = (local[0] * local[0] + local[1] * local[1] + local[2] * local[2]).sqrt();
            if r < 1.02 && r > 0.0 {
                let pushed = [0, 1, 2].map(|k| center[k] + local[k] / r * 1.02 * radii[k]);
                let d = normalize([
                    pushed[0] - current[0],
                    pushed[1] - current[1],
                    pushed[2] - current[2],
                ]);
                direction = d;
                next = add(current, scale(d, step));
            }
        }
        points.push(next);
        current = next;
    }
    points
}

/// Keeps every edge of a waved strand at the segment length, so the wave
/// shortens the strand's reach instead of stretching the hair.
fn rescale_to_length(points: &mut [[f32; 3]], step: f64) {
    let shape: Vec<V3> = points.iter().map(|p| p.map(f64::from)).collect();
    let mut current = shape[0];
    for i in 1..shape.len() {
        let d = [
            shape[i][0] - shape[i - 1][0],
            shape[i][1] - shape[i - 1][1],
            shape[i][2] - shape[i - 1][2],
        ];
        current = add(current, scale(normalize(d), step));
        points[i] = current.map(|c| c as f32);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_seed_same_groom() {
        let parameters = GeneratorParameters {
            strands: 50,
            ..Default::default()
        };
        let a = generate(&parameters).unwrap();
        let b = generate(&parameters).unwrap();
        assert_eq!(a, b);
        let c = generate(&GeneratorParameters {
            seed: 2,
            ..parameters
        })
        .unwrap();
        assert_ne!(a.points, c.points);
    }

    #[test]
    fn roots_on_head_and_lengths_kept() {
        let parameters = GeneratorParameters {
            strands: 20,
            shape: StrandShape::Wavy,
            ..Default::default()
        };
        let groom = generate(&parameters).unwrap();
        assert!(groom.validate().is_empty());
        assert_eq!(groom.strand_count(), 20);
        for strand in groom.strands() {
            let r = strand[0];
            let radii = parameters.head_radii;
            let on =
                (r[0] / radii[0]).powi(2) + (r[1] / radii[1]).powi(2) + (r[2] / radii[2]).powi(2);
            assert!((on - 1.0).abs() < 1e-4, "root off the head: {on}");
            assert!(r[1] >= radii[1] * (80f32.to_radians().cos()) - 1e-5);
            let length: f32 = strand
                .windows(2)
                .map(|w| {
                    ((w[1][0] - w[0][0]).powi(2)
                        + (w[1][1] - w[0][1]).powi(2)
                        + (w[1][2] - w[0][2]).powi(2))
                    .sqrt()
                })
                .sum();
            assert!((length - 0.24).abs() < 1e-4, "length {length}");
        }
    }

    #[test]
    fn wave_follows_elliptic_cone() {
        let parameters = GeneratorParameters {
            strands: 1,
            layout: RootLayout::Swatch,
            shape: StrandShape::Wavy,
            wave_start: 0.0,
            ..Default::default()
        };
        let groom = generate(&parameters).unwrap();
        let tip = groom.points[groom.points.len() - 1];
        // The spiral leaves the axis by at most A z (A the larger slope).
        let off_axis = (tip[0].powi(2) + tip[2].powi(2)).sqrt();
        assert!(
            off_axis > 0.0 && off_axis <= 0.15 * 0.24 + 1e-4,
            "{off_axis}"
        );
    }

    #[test]
    fn draped_hair_hangs_and_stays_off_the_head() {
        let parameters = GeneratorParameters {
            strands: 30,
            drape: 20.0,
            ..Default::default()
        };
        let groom = generate(&parameters).unwrap();
        let radii = parameters.head_radii;
        for strand in groom.strands() {
            let tip = strand[strand.len() - 1];
            assert!(tip[1] < strand[0][1], "tip not below root");
            for p in &strand[1..] {
                let r = (p[0] / radii[0]).powi(2)
                    + (p[1] / radii[1]).powi(2)
                    + (p[2] / radii[2]).powi(2);
                assert!(r >= 1.0, "inside the head: {r}");
            }
        }
    }

    #[test]
    fn bad_parameters_are_named() {
        let error = generate(&GeneratorParameters {
            strands: 0,
            ..Default::default()
        })
        .unwrap_err();
        assert_eq!(error.name, "strands");
        let error = generate(&GeneratorParameters {
            segment_length: -1.0,
            ..Default::default()
        })
        .unwrap_err();
        assert_eq!(error.name, "segment_length");
    }
}
