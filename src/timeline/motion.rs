//! Keyframed kinematic motion of colliders: linear translation, spherical
//! rotation, held before the first and after the last key.

use super::schema::KeySpec;

/// A rigid pose: translation and unit quaternion `[x, y, z, w]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    pub translation: [f64; 3],
    pub rotation: [f64; 4],
}

impl Pose {
    pub const IDENTITY: Pose = Pose {
        translation: [0.0; 3],
        rotation: [0.0, 0.0, 0.0, 1.0],
    };
}

fn quaternion_multiply(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    [
        a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1],
        a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0],
        a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3],
        a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2],
    ]
}

/// X, Y, Z Euler angles in degrees, X applied first (as USD's rotateXYZ).
pub fn quaternion_from_euler_degrees(angles: [f32; 3]) -> [f64; 4] {
    let axis_rotation = |axis: usize, degrees: f32| {
        let half = (degrees as f64).to_radians() * 0.5;
        let mut q = [0.0, 0.0, 0.0, half.cos()];
        q[axis] = half.sin();
        q
    };
    let x = axis_rotation(0, angles[0]);
    let y = axis_rotation(1, angles[1]);
    let z = axis_rotation(2, angles[2]);
    quaternion_multiply(z, quaternion_multiply(y, x))
}

fn slerp(a: [f64; 4], b: [f64; 4], t: f64) -> [f64; 4] {
    let mut dot: f64 = (0..4).map(|k| a[k] * b[k]).sum();
    let mut b = b;
    if dot < 0.0 {
        dot = -dot;
        b = b.map(|c| -c);
    }
    let (wa, wb) = if dot > 0.9995 {
        (1.0 - t, t)
    } else {
        let angle = dot.clamp(-1.0, 1.0).acos();
        let s = angle.sin();
        (((1.0 - t) * angle).sin() / s, (t * angle).sin() / s)
    };
    let q = [0, 1, 2, 3].map(|k| wa * a[k] + wb * b[k]);
    let n = (0..4).map(|k| q[k] * q[k]).sum::<f64>().sqrt();
    q.map(|c| c / n)
}

fn key_pose(key: &KeySpec) -> Pose {
    Pose {
        translation: key.translation.map(f64::from),
        rotation: quaternion_from_euler_degrees(key.rotation),
    }
}

/// The pose at time `t` (global seconds) of a keyframed motion.
pub fn pose_at(keys: &[KeySpec], t: f64) -> Pose {
    let (Some(first), Some(last)) = (keys.first(), keys.last()) else {
        return Pose::IDENTITY;
    };
    if t <= first.t {
        return key_pose(first);
    }
    if t >= last.t {
        return key_pose(last);
    }
    let next = keys
        .iter()
        .position(|k| k.t > t)
        .unwrap_or(keys.len() - 1)
        .max(1);
    let (a, b) = (&keys[next - 1], &keys[next]);
    let s = (t - a.t) / (b.t - a.t);
    let (pa, pb) = (key_pose(a), key_pose(b));
    Pose {
        translation: [0, 1, 2]
            .map(|k| pa.translation[k] + s * (pb.translation[k] - pa.translation[k])),
        rotation: slerp(pa.rotation, pb.rotation, s),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(t: f64, translation: [f32; 3], rotation: [f32; 3]) -> KeySpec {
        KeySpec {
            t,
            translation,
            rotation,
        }
    }

    #[test]
    fn interpolates_and_holds() {
        let keys = [
            key(1.0, [0.0, 1.0, 0.0], [0.0; 3]),
            key(3.0, [0.0, 0.0, 0.0], [0.0, 90.0, 0.0]),
        ];
        assert_eq!(pose_at(&keys, 0.0).translation, [0.0, 1.0, 0.0]);
        assert_eq!(pose_at(&keys, 5.0).translation, [0.0, 0.0, 0.0]);
        let mid = pose_at(&keys, 2.0);
        assert!((mid.translation[1] - 0.5).abs() < 1e-12);
        // Halfway to 90 degrees about Y is 45 degrees.
        let expected = quaternion_from_euler_degrees([0.0, 45.0, 0.0]);
        for (got, want) in mid.rotation.iter().zip(expected) {
            assert!((got - want).abs() < 1e-9);
        }
        assert_eq!(pose_at(&[], 1.0), Pose::IDENTITY);
    }
}
