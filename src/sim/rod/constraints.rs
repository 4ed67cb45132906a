//! The rod constraints of 000 §4.1 (PBD Cosserat rods): stretch/shear
//! (1)-(5), bend/twist (6)-(11), and the root-to-tip inextensibility pass.

use crate::sim::math::{darboux, darboux_real, double_cover_sign, qnormalize, tangent, Quat, V3};

/// Squared size of a stretch/shear violation too small to correct.
pub(crate) const STRETCH_DEADBAND2: f32 = 4.0e-12;
/// Squared size of a bend/twist violation too small to correct.
pub(crate) const BEND_DEADBAND2: f32 = 1.0e-14;
/// How far from 1 a squared quaternion length may be for the Newton
/// renormalisation.
pub(crate) const NEWTON_RANGE: f32 = 1.0e-3;
/// Relative length error the inextensibility pass leaves alone.
pub(crate) const LENGTH_DEADBAND: f32 = 2.0e-6;

/// The per-step constants of one edge's stretch/shear constraint (the
/// inverse masses do not change during a step).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StretchCoefficients {
    pub inv_l: f32,
    /// `w1 l / D`, `w2 l / D`, `w_q l^2 / D` with `D = w1 + w2 + 4 w_q l^2`.
    pub a: f32,
    pub b: f32,
    pub k: f32,
}

impl StretchCoefficients {
    /// `w_q` is the frame's inverse mass.
    pub fn new(w1: f32, w2: f32, w_q: f32, l: f32) -> StretchCoefficients {
        let wq_l2 = w_q * l * l;
        let denominator = w1 + w2 + 4.0 * wq_l2;
        if !(denominator > 0.0 && l > 0.0) {
            return StretchCoefficients {
                inv_l: if l > 0.0 { 1.0 / l } else { 0.0 },
                ..StretchCoefficients::default()
            };
        }
        let inv = 1.0 / denominator;
        StretchCoefficients {
            inv_l: 1.0 / l,
            a: w1 * l * inv,
            b: w2 * l * inv,
            k: wq_l2 * inv,
        }
    }
}

/// Stretch/shear of one edge, (2)-(5): moves both ends and the frame so the
/// edge points along the frame's tangent with its rest length.
#[inline(always)]
pub fn stretch_shear(p1: &mut V3, p2: &mut V3, q: &mut Quat, c: &StretchCoefficients) {
    let inv_l = c.inv_l;
    let d3 = tangent(*q);
    let gamma = [
        (p2[0] - p1[0]) * inv_l - d3[0],
        (p2[1] - p1[1]) * inv_l - d3[1],
        (p2[2] - p1[2]) * inv_l - d3[2],
    ];
    // Below f32 round-off of positions about 0.1 m apart by 1 cm edges
    // (~1e-6), a correction would only feed rounding noise into the
    // velocities of a very soft system; skip it.
    if gamma[0] * gamma[0] + gamma[1] * gamma[1] + gamma[2] * gamma[2] < STRETCH_DEADBAND2 {
        return;
    }
    let (a, b) = (c.a, c.b);
    p1[0] += a * gamma[0];
    p1[1] += a * gamma[1];
    p1[2] += a * gamma[2];
    p2[0] -= b * gamma[0];
    p2[1] -= b * gamma[1];
    p2[2] -= b * gamma[2];
    let k = c.k;
    if k > 0.0 {
        // (4): dq = w_q l^2 / (...) * gamma q conj(e3), with gamma and e3 pure
        // quaternions. Written out: (gamma q) then times (0, 0, -1, 0).
        let [x, y, z, w] = *q;
        let [g0, g1, g2] = gamma;
        // t = (g, 0) * q
        let t0 = g0 * w + g1 * z - g2 * y;
        let t1 = -g0 * z + g1 * w + g2 * x;
        let t2 = g0 * y - g1 * x + g2 * w;
        let t3 = -g0 * x - g1 * y - g2 * z;
        // t * (0, 0, -1, 0) = (-t1, t0, -t3, t2)
        *q = renormalize([x - k * t1, y + k * t0, z - k * t3, w + k * t2]);
    }
}

/// The per-step constants of one joint's bend/twist constraint:
/// `k' w1 / (w1 + w2)` and `k' w2 / (w1 + w2)`.
pub fn bend_coefficients(w1: f32, w2: f32, k_prime: f32) -> [f32; 2] {
    let total = w1 + w2;
    if total > 0.0 {
        [k_prime * w1 / total, k_prime * w2 / total]
    } else {
        [0.0; 2]
    }
}

/// Bend/twist of the joint between frames `q1` and `q2`, (9)-(11), toward
/// the rest Darboux vector `rest`; `ab` from `bend_coefficients`.
#[inline(always)]
pub fn bend_twist(q1: &mut Quat, q2: &mut Quat, rest: V3, ab: [f32; 2]) {
    let omega = darboux(*q1, *q2);
    // s of (9)-(11) on the full Darboux quaternion (METHOD A).
    let s = double_cover_sign(omega, darboux_real(*q1, *q2), rest);
    let delta = [
        omega[0] - s * rest[0],
        omega[1] - s * rest[1],
        omega[2] - s * rest[2],
    ];
    let delta2 = delta[0] * delta[0] + delta[1] * delta[1] + delta[2] * delta[2];
    if delta2 < BEND_DEADBAND2 {
        return;
    }
    let [a, b] = ab;
    let d = [delta[0], delta[1], delta[2], 0.0];
    // dq1 = +a q2 (0, delta); dq2 = -b q1 (0, delta)
    let r1 = qmul_pure(*q2, d);
    let r2 = qmul_pure(*q1, d);
    if a > 0.0 {
        *q1 = renormalize([
            q1[0] + a * r1[0],
            q1[1] + a * r1[1],
            q1[2] + a * r1[2],
            q1[3] + a * r1[3],
        ]);
    }
    if b > 0.0 {
        *q2 = renormalize([
            q2[0] - b * r2[0],
            q2[1] - b * r2[1],
            q2[2] - b * r2[2],
            q2[3] - b * r2[3],
        ]);
    }
}

/// Back to unit length after a small correction: one Newton step for
/// `1/sqrt(n2)` around 1 when the length is within 1e-3 of it (error below
/// f32 resolution), an exact division otherwise.
#[inline(always)]
fn renormalize(q: Quat) -> Quat {
    let n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
    let e = n2 - 1.0;
    if e.abs() < NEWTON_RANGE {
        let s = 1.0 - 0.5 * e + 0.375 * e * e;
        [q[0] * s, q[1] * s, q[2] * s, q[3] * s]
    } else {
        qnormalize(q)
    }
}

/// `q * (v, 0)`.
#[inline(always)]
fn qmul_pure(q: Quat, v: Quat) -> Quat {
    [
        q[3] * v[0] + q[1] * v[2] - q[2] * v[1],
        q[3] * v[1] - q[0] * v[2] + q[2] * v[0],
        q[3] * v[2] + q[0] * v[1] - q[1] * v[0],
        -q[0] * v[0] - q[1] * v[1] - q[2] * v[2],
    ]
}

/// Follow-The-Leader: from root to tip, each free vertex is put at its rest
/// length from its predecessor along their current direction. Records the
/// correction of each vertex in `corrections` (for the velocity fix).
pub fn follow_the_leader(p: &mut [V3], w: &[f32], l: &[f32], corrections: &mut [V3]) {
    if let Some(c) = corrections.first_mut() {
        *c = [0.0; 3];
    }
    for i in 1..p.len() {
        corrections[i] = [0.0; 3];
        if w[i] <= 0.0 {
            continue;
        }
        let a = p[i - 1];
        let b = p[i];
        let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        if len2 <= 0.0 {
            continue;
        }
        let s = l[i - 1] / len2.sqrt();
        if (s - 1.0).abs() < LENGTH_DEADBAND {
            continue;
        }
        let n = [a[0] + d[0] * s, a[1] + d[1] * s, a[2] + d[2] * s];
        corrections[i] = [n[0] - b[0], n[1] - b[1], n[2] - b[2]];
        p[i] = n;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::math::{self, qmul, rotation_between};

    #[test]
    fn stretch_shear_aligns_a_frame_with_pinned_ends() {
        let mut p1 = [0.0, 0.0, 0.0];
        let mut p2 = [0.01, 0.0, 0.0];
        let mut q = math::IDENTITY;
        for _ in 0..40 {
            stretch_shear(
                &mut p1,
                &mut p2,
                &mut q,
                &StretchCoefficients::new(0.0, 0.0, 1.0e4, 0.01),
            );
        }
        let t = tangent(q);
        assert!((t[0] - 1.0).abs() < 1e-4, "{t:?}");
        assert_eq!(p2, [0.01, 0.0, 0.0]);
    }

    #[test]
    fn stretch_shear_moves_a_free_end_onto_the_frame() {
        let mut p1 = [0.0, 0.0, 0.0];
        let mut p2 = [0.0, 0.0, 0.02];
        let mut q = math::IDENTITY;
        stretch_shear(
            &mut p1,
            &mut p2,
            &mut q,
            &StretchCoefficients::new(0.0, 1.0, 0.0, 0.01),
        );
        assert!((p2[2] - 0.01).abs() < 1e-7);
    }

    #[test]
    fn bend_twist_moves_toward_the_rest_darboux_vector() {
        let mut q1 = math::IDENTITY;
        let mut q2 = rotation_between([0.0, 0.0, 1.0], [0.0, 0.5f32.sin(), 0.5f32.cos()]);
        let before = math::length(darboux(q1, q2));
        bend_twist(&mut q1, &mut q2, [0.0; 3], bend_coefficients(1.0, 1.0, 0.5));
        let after = math::length(darboux(q1, q2));
        assert!(after < before * 0.6, "{before} -> {after}");
        // k' = 1 with both free reaches the rest shape in one projection
        // for small bends.
        let mut q1 = math::IDENTITY;
        let mut q2 = qmul(math::from_imaginary([0.01, 0.0, 0.0]), math::IDENTITY);
        bend_twist(&mut q1, &mut q2, [0.0; 3], bend_coefficients(1.0, 1.0, 1.0));
        assert!(math::length(darboux(q1, q2)) < 1e-4);
    }

    #[test]
    fn follow_the_leader_restores_lengths() {
        let mut p = vec![[0.0, 0.0, 0.0], [0.0, -0.02, 0.0], [0.0, -0.02, 0.03]];
        let w = [0.0, 1.0, 1.0];
        let l = [0.01, 0.01];
        let mut c = vec![[0.0; 3]; 3];
        follow_the_leader(&mut p, &w, &l, &mut c);
        assert!((math::length(math::sub(p[1], p[0])) - 0.01).abs() < 1e-7);
        assert!((math::length(math::sub(p[2], p[1])) - 0.01).abs() < 1e-7);
        assert!((c[1][1] - 0.01).abs() < 1e-7);
    }
}
