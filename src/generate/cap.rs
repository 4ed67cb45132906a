//! The first two layouts: strands rooted on the scalp cap of an ellipsoid
//! head along the surface normal (optionally draped toward -Y), or hanging
//! from a bar (a swatch); straight or waved with the elliptic-cone spiral of
//! Agui et al. eq. (30)-(31). Kept as they were: the samples and goldens
//! depend on every number of their random stream.

use super::{GeneratorParameters, RootLayout, SplitMix64, StrandShape};
use groom::math::double::{add, cross, scale, try_normalize, V3};
use groom::{Attribute, AttributeValues, Groom};

/// Unit `a`; straight up for a vector without direction (the generator's
/// directions are bounded, so this only guards a degenerate input).
fn normalize(a: V3) -> V3 {
    try_normalize(a).unwrap_or([0.0, 1.0, 0.0])
}

/// Builds a `scalp` or `swatch` groom from checked parameters. Also writes
/// the per-strand `root_uv` (spherical coordinates of the root on the
/// scalp, or position along the swatch) and per-vertex `width` attributes.
pub(super) fn generate_cap(parameters: &GeneratorParameters) -> Groom {
    let p = parameters;
    let mut random = SplitMix64::new(p.seed);
    let edges = p.edges_per_strand();
    let step = p.length as f64 / edges as f64;
    let center = p.head_center.map(f64::from);
    let radii = p.head_radii.map(f64::from);
    let mut groom = super::empty_groom();
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
            // `Head` never comes here (`generate` sends it to `head`).
            RootLayout::Swatch | RootLayout::Head => {
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
    groom
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
