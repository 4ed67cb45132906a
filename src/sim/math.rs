//! The solver's f32 quaternion helpers, on the engine's one vector set
//! (`groom::math::single`, re-exported here). Quaternions are `[x, y, z, w]`
//! (Hamilton product), the layout glam and glTF use.

pub use groom::math::single::{add, cross, dot, is_finite3, length, scale, sub, V3};

pub type Quat = [f32; 4];

pub const IDENTITY: Quat = [0.0, 0.0, 0.0, 1.0];

/// Hamilton product `a * b`.
#[inline(always)]
pub fn qmul(a: Quat, b: Quat) -> Quat {
    [
        a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1],
        a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0],
        a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3],
        a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2],
    ]
}
#[inline(always)]
pub fn conj(q: Quat) -> Quat {
    [-q[0], -q[1], -q[2], q[3]]
}
#[inline(always)]
pub fn pure(v: V3) -> Quat {
    [v[0], v[1], v[2], 0.0]
}
#[inline(always)]
pub fn imag(q: Quat) -> V3 {
    [q[0], q[1], q[2]]
}
#[inline(always)]
pub fn qdot(a: Quat, b: Quat) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]
}

/// The angular velocity turning frame `q_old` into `q` in `1 / inv_dt`
/// seconds, taking the nearer of `q` and `-q`. Im(q conj(q_old)) =
/// Im((q - q_old) conj(q_old)) since q_old conj(q_old) is real; the
/// difference form avoids the round-off of a product of two nearly equal
/// frames (noise in a soft system).
#[inline(always)]
pub fn turn_rate(q: Quat, q_old: Quat, inv_dt: f32) -> V3 {
    let sign = if qdot(q, q_old) < 0.0 { -1.0 } else { 1.0 };
    let change = [
        q[0] - sign * q_old[0],
        q[1] - sign * q_old[1],
        q[2] - sign * q_old[2],
        q[3] - sign * q_old[3],
    ];
    let delta = qmul(change, conj(q_old));
    scale(imag(delta), 2.0 * sign * inv_dt)
}

/// Unit quaternion; a degenerate one (zero or not finite) stays as it is so
/// the quarantine sees it rather than a made-up frame.
#[inline(always)]
pub fn qnormalize(q: Quat) -> Quat {
    let n2 = qdot(q, q);
    if n2 > 0.0 {
        let inv = 1.0 / n2.sqrt();
        [q[0] * inv, q[1] * inv, q[2] * inv, q[3] * inv]
    } else {
        q
    }
}

/// The Darboux vector of two adjacent frames, eq. (8): `Im(conj(q1) q2)`.
#[inline(always)]
pub fn darboux(q1: Quat, q2: Quat) -> V3 {
    // Im(conj(q1) * q2) written out.
    [
        q1[3] * q2[0] - q1[0] * q2[3] - q1[1] * q2[2] + q1[2] * q2[1],
        q1[3] * q2[1] + q1[0] * q2[2] - q1[1] * q2[3] - q1[2] * q2[0],
        q1[3] * q2[2] - q1[0] * q2[1] + q1[1] * q2[0] - q1[2] * q2[3],
    ]
}

/// The real part of the Darboux quaternion `conj(q1) q2` (its imaginary
/// part is [`darboux`]): `q1 . q2` in 4D.
#[inline(always)]
pub fn darboux_real(q1: Quat, q2: Quat) -> f32 {
    qdot(q1, q2)
}

/// The real part of the unit quaternion whose imaginary part is the rest
/// Darboux vector `omega` (taken non-negative: a rest bend below half a turn).
#[inline(always)]
pub fn rest_real(omega: V3) -> f32 {
    (1.0 - dot(omega, omega)).max(0.0).sqrt()
}

/// `s` of (9)-(18), the quaternion double cover (METHOD A): +1 when the
/// full Darboux quaternion `(omega, w)` is nearer `(rest, rest_real(rest))`
/// than its negative, i.e. when their 4D dot product is not negative. On
/// the imaginary parts alone the test would flip whenever a joint is bent
/// past straight, mirroring the rest bend.
#[inline(always)]
pub fn double_cover_sign(omega: V3, w: f32, rest: V3) -> f32 {
    if dot(omega, rest) + w * rest_real(rest) < 0.0 {
        -1.0
    } else {
        1.0
    }
}

/// The representative of the Darboux quaternion `(omega, w)` with a
/// non-negative real part: frames may flip sign (`q` and `-q` are one
/// rotation), but remembered and rest Darboux vectors are stored with an
/// implied non-negative real part, so what is mixed into them must be too.
#[inline(always)]
pub fn canonical_darboux(omega: V3, w: f32) -> (V3, f32) {
    if w < 0.0 {
        (scale(omega, -1.0), -w)
    } else {
        (omega, w)
    }
}

/// `R(q) e3`: the frame's tangent.
#[inline(always)]
pub fn tangent(q: Quat) -> V3 {
    let [x, y, z, w] = q;
    [
        2.0 * (x * z + w * y),
        2.0 * (y * z - w * x),
        1.0 - 2.0 * (x * x + y * y),
    ]
}

/// Rotates `v` by unit `q`.
#[inline(always)]
pub fn rotate(q: Quat, v: V3) -> V3 {
    let u = imag(q);
    let t = scale(cross(u, v), 2.0);
    add(add(v, scale(t, q[3])), cross(u, t))
}

/// The shortest-arc rotation taking unit `from` to unit `to`.
pub fn rotation_between(from: V3, to: V3) -> Quat {
    let d = dot(from, to);
    if d < -0.999_999 {
        // Opposite: half a turn about any axis normal to `from`.
        let helper = if from[0].abs() < 0.9 {
            [1.0, 0.0, 0.0]
        } else {
            [0.0, 1.0, 0.0]
        };
        let axis = cross(from, helper);
        let n = length(axis);
        return [axis[0] / n, axis[1] / n, axis[2] / n, 0.0];
    }
    let c = cross(from, to);
    qnormalize([c[0], c[1], c[2], 1.0 + d])
}

/// The unit quaternion with imaginary part `v` and a non-negative real part.
pub fn from_imaginary(v: V3) -> Quat {
    let w2 = 1.0 - dot(v, v);
    qnormalize([v[0], v[1], v[2], w2.max(0.0).sqrt()])
}
