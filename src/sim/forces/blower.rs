//! The blower of 000 §6 (19): air from a nozzle that pushes hair across
//! its stream, falling off with the distance from the wind's axis; one
//! vertex at a time, or eight at a time in AVX lanes with the same bits.

use crate::sim::math::{cross, dot, length, scale, sub, V3};
use crate::sim::Blower;

/// The blower's velocity change at a vertex, (19):
/// `alpha sin(theta) / (d + 1)^2 w_hat dt`, `theta` between the hair edge and
/// the wind, `d` the distance from the vertex to the wind axis.
#[inline]
pub fn blower_dv(blower: &Blower, position: V3, edge_direction: V3, dt: f32) -> V3 {
    let edge_length = length(edge_direction);
    if edge_length.is_nan() || edge_length <= 0.0 {
        return [0.0; 3];
    }
    let Some((w_hat, falloff)) = wind_at(blower, position) else {
        return [0.0; 3];
    };
    let sin_theta = length(cross(edge_direction, w_hat)) / edge_length;
    scale(
        w_hat,
        blower.strength * sin_theta / (falloff * falloff) * dt,
    )
}

/// How far the blower's air reaches a point, 0..1: the falloff of (19)
/// (`1 / (d / L + 1)^2`, `d` the distance from the wind's axis), nothing
/// behind the nozzle or outside its cone, as `blower_dv` pushes (without
/// the angle to the hair: air dries a fibre whatever its direction). The
/// drying of a `dry` stage reads it (`timeline::drying`).
pub fn blower_reach(blower: &Blower, position: V3) -> f32 {
    match wind_at(blower, position) {
        Some((_, falloff)) => 1.0 / (falloff * falloff),
        None => 0.0,
    }
}

/// The wind's direction and the falloff `d / L + 1` of (19) at `position`
/// (`d` its distance from the wind's axis), or `None` where nothing blows:
/// behind the nozzle, outside its cone, or for a blower of no length.
#[inline]
fn wind_at(blower: &Blower, position: V3) -> Option<(V3, f32)> {
    let wind = sub(blower.to, blower.from);
    let wind_length = length(wind);
    if wind_length.is_nan() || wind_length <= 0.0 {
        return None;
    }
    let w_hat = scale(wind, 1.0 / wind_length);
    let rel = sub(position, blower.from);
    let along = dot(rel, w_hat);
    let d = length(sub(rel, scale(w_hat, along)));
    let outside_cone = blower
        .cone_half_angle
        .is_some_and(|a| d > along * a.to_radians().tan());
    if along <= 0.0 || outside_cone {
        return None;
    }
    Some((w_hat, d / blower.falloff_length + 1.0))
}

/// [`blower_dv`] of eight vertices, one per lane of AVX registers
/// (`position` and `edge_direction` by coordinate): per lane the same
/// operations in the same order, so the same bits; the wind's direction
/// and the cone's slope, the same for every vertex, are found once for the
/// eight (not once per vertex). In a
/// blow-dry step the blower vertex by vertex (four square roots and three
/// divisions in a chain) cost more than the rest of the prediction.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub fn blower_dv_eight(
    blower: &Blower,
    position: [std::arch::x86_64::__m256; 3],
    edge_direction: [std::arch::x86_64::__m256; 3],
    dt: f32,
) -> [std::arch::x86_64::__m256; 3] {
    use std::arch::x86_64::*;
    let zero = _mm256_setzero_ps();
    let wind = sub(blower.to, blower.from);
    let wind_length = length(wind);
    if wind_length.is_nan() || wind_length <= 0.0 {
        return [zero; 3];
    }
    let (add, sub, mul, div) = (_mm256_add_ps, _mm256_sub_ps, _mm256_mul_ps, _mm256_div_ps);
    let splat = |x: f32| _mm256_set1_ps(x);
    let dot = |a: [__m256; 3], b: [__m256; 3]| {
        add(add(mul(a[0], b[0]), mul(a[1], b[1])), mul(a[2], b[2]))
    };
    let w_hat = scale(wind, 1.0 / wind_length).map(splat);
    let e = edge_direction;
    let edge_length = _mm256_sqrt_ps(dot(e, e));
    let cross = [
        sub(mul(e[1], w_hat[2]), mul(e[2], w_hat[1])),
        sub(mul(e[2], w_hat[0]), mul(e[0], w_hat[2])),
        sub(mul(e[0], w_hat[1]), mul(e[1], w_hat[0])),
    ];
    let sin_theta = div(_mm256_sqrt_ps(dot(cross, cross)), edge_length);
    let from = blower.from.map(splat);
    let rel: [__m256; 3] = std::array::from_fn(|c| sub(position[c], from[c]));
    let along = dot(rel, w_hat);
    let across: [__m256; 3] = std::array::from_fn(|c| sub(rel[c], mul(w_hat[c], along)));
    let d = _mm256_sqrt_ps(dot(across, across));
    // No wind: an edge of no (or NaN) length, behind the nozzle, outside
    // its cone.
    let mut none = _mm256_or_ps(
        _mm256_cmp_ps::<_CMP_NGT_UQ>(edge_length, zero),
        _mm256_cmp_ps::<_CMP_LE_OQ>(along, zero),
    );
    if let Some(angle) = blower.cone_half_angle {
        let slope = splat(angle.to_radians().tan());
        none = _mm256_or_ps(none, _mm256_cmp_ps::<_CMP_GT_OQ>(d, mul(along, slope)));
    }
    let falloff = add(div(d, splat(blower.falloff_length)), splat(1.0));
    let s = mul(
        div(
            mul(splat(blower.strength), sin_theta),
            mul(falloff, falloff),
        ),
        splat(dt),
    );
    w_hat.map(|w| _mm256_blendv_ps(mul(w, s), zero, none))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The blower in lanes gives the bits of the blower vertex by vertex:
    /// random blowers (with and without a cone) and vertices in front of,
    /// beside and behind the nozzle, edges of zero, tiny, huge, infinite
    /// and NaN length among them.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn the_blower_in_lanes_is_the_blower_one_vertex_at_a_time() {
        use std::arch::x86_64::*;
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        let mut unit = crate::sim::test_sequence(0x2545_f491_4f6c_dd1d);
        let mut next = move || unit() * 2.0 - 1.0;
        let special = [0.0, -0.0, 1e-30, 1e30, f32::INFINITY, f32::NAN];
        let bits = |v: V3| v.map(|x| if x.is_nan() { u32::MAX } else { x.to_bits() });
        let (mut blowing, mut still) = (0usize, 0usize);
        for case in 0..3_000 {
            let blower = Blower {
                from: [next() * 0.3, next() * 0.3, next() * 0.3],
                to: if case % 97 == 0 {
                    [0.0; 3]
                } else {
                    [next() * 0.1, next() * 0.1, next() * 0.1]
                },
                strength: 40.0 * next().abs(),
                hydrogen_rate: 0.003,
                falloff_length: [1.0, 0.05, 0.3][case % 3],
                cone_half_angle: [None, Some(30.0), Some(80.0)][case % 3],
            };
            let mut p = [[0.0f32; 3]; 8];
            let mut e = [[0.0f32; 3]; 8];
            for l in 0..8 {
                p[l] = [next() * 0.3, next() * 0.3, next() * 0.3];
                e[l] = [next() * 0.01, next() * 0.01, next() * 0.01];
                if (case + l) % 13 == 0 {
                    let k = (case + l) / 13 % special.len();
                    e[l] = [special[k], 0.0, special[(k + 1) % special.len()]];
                    p[l][l % 3] = special[(k + 2) % special.len()];
                }
            }
            let dt = [1.0 / 360.0, 1.0 / 24.0][case % 2];
            let lanes = |v: &[V3; 8]| -> [__m256; 3] {
                std::array::from_fn(|c| {
                    let x: [f32; 8] = std::array::from_fn(|l| v[l][c]);
                    // SAFETY: reads the eight floats of `x`.
                    unsafe { _mm256_loadu_ps(x.as_ptr()) }
                })
            };
            // SAFETY: the CPU has AVX2 (checked above).
            let out = unsafe { blower_dv_eight(&blower, lanes(&p), lanes(&e), dt) };
            let mut got = [[0.0f32; 8]; 3];
            for c in 0..3 {
                // SAFETY: writes the eight floats of `got[c]`.
                unsafe { _mm256_storeu_ps(got[c].as_mut_ptr(), out[c]) };
            }
            for l in 0..8 {
                let expected = blower_dv(&blower, p[l], e[l], dt);
                let lane = [got[0][l], got[1][l], got[2][l]];
                assert_eq!(
                    bits(lane),
                    bits(expected),
                    "case {case} lane {l}: {blower:?} {:?} {:?}",
                    p[l],
                    e[l]
                );
                if expected == [0.0; 3] {
                    still += 1;
                } else {
                    blowing += 1;
                }
            }
        }
        assert!(blowing > 1_000 && still > 1_000, "{blowing} {still}");
    }

    #[test]
    fn blower_pushes_along_the_wind_and_ignores_parallel_hair() {
        let blower = Blower {
            falloff_length: 1.0,
            cone_half_angle: None,
            from: [0.0, 0.0, -1.0],
            to: [0.0, 0.0, 0.0],
            strength: 2.0,
            hydrogen_rate: 0.003,
        };
        let dv = blower_dv(&blower, [0.0, 0.0, 0.0], [0.0, -1.0, 0.0], 0.5);
        assert!((dv[2] - 1.0).abs() < 1e-6, "{dv:?}");
        let parallel = blower_dv(&blower, [0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 0.5);
        assert!(length(parallel) < 1e-6);
        // (d + 1)^2 falloff: 1 m off the axis gives a quarter.
        let off = blower_dv(&blower, [1.0, 0.0, 0.0], [0.0, -1.0, 0.0], 0.5);
        assert!((off[2] - 0.25).abs() < 1e-6);
    }
}
