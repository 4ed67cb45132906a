//! Side-chain bonds (000 §5): the rest shape from the bonds (15)-(16) and
//! the memory update when bonds re-form (17)-(18).

use crate::sim::math::{canonical_darboux, double_cover_sign, V3};

/// `Omega_o` of (15): intact bonds pull toward their memory, broken ones
/// toward the current shape `omega` (`w` the real part of its Darboux
/// quaternion, for the sign `s_j`). `influences` are normalised (sum 1).
#[inline(always)]
pub fn rest_darboux(
    omega: V3,
    w: f32,
    rates: &[f32; 4],
    memories: &[V3; 4],
    influences: &[f32; 4],
) -> V3 {
    #[cfg(target_arch = "x86_64")]
    {
        rest_darboux_x86(omega, w, rates, memories, influences)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        rest_darboux_scalar(omega, w, rates, memories, influences)
    }
}

/// [`rest_darboux`] with the four kinds in the four lanes of one SSE
/// register (x86-64's baseline): the same IEEE operations per kind in the
/// same order, so the same bits as one kind after the other, in about half
/// the instructions (the rest shape was a fifth of a step). Hand-written:
/// the compiler's own vectorisation of the scalar loop shuffled more than
/// it saved.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn rest_darboux_x86(
    omega: V3,
    w: f32,
    rates: &[f32; 4],
    memories: &[V3; 4],
    influences: &[f32; 4],
) -> V3 {
    use std::arch::x86_64::*;
    let (omega, w) = canonical_darboux(omega, w);
    let flat: &[f32; 12] = memories.as_flattened().try_into().unwrap_or(&[0.0; 12]);
    // SAFETY: SSE is part of x86-64; the loads read the 12 floats of
    // `flat`, the 4 of `rates` and of `influences`, and the store writes
    // the 4 of `out`.
    unsafe {
        // The memories, one register per coordinate (kinds in the lanes).
        let a = _mm_loadu_ps(flat.as_ptr());
        let b = _mm_loadu_ps(flat.as_ptr().add(4));
        let c = _mm_loadu_ps(flat.as_ptr().add(8));
        // x: a0 a3 b2 c1; y: a1 b0 b3 c2; z: a2 b1 c0 c3.
        let bc = _mm_shuffle_ps::<0b01_01_10_10>(b, c);
        let mx = _mm_shuffle_ps::<0b10_00_11_00>(a, bc);
        let ab = _mm_shuffle_ps::<0b00_00_01_01>(a, b);
        let bc = _mm_shuffle_ps::<0b10_10_11_11>(b, c);
        let my = _mm_shuffle_ps::<0b10_00_10_00>(ab, bc);
        let ab = _mm_shuffle_ps::<0b01_01_10_10>(a, b);
        let cc = _mm_shuffle_ps::<0b11_11_00_00>(c, c);
        let mz = _mm_shuffle_ps::<0b10_00_10_00>(ab, cc);
        let (zero, one) = (_mm_setzero_ps(), _mm_set1_ps(1.0));
        let (ox, oy, oz) = (
            _mm_set1_ps(omega[0]),
            _mm_set1_ps(omega[1]),
            _mm_set1_ps(omega[2]),
        );
        // double_cover_sign: dot(omega, m) + w * rest_real(m) < 0.
        let along = _mm_add_ps(
            _mm_add_ps(_mm_mul_ps(ox, mx), _mm_mul_ps(oy, my)),
            _mm_mul_ps(oz, mz),
        );
        let norm2 = _mm_add_ps(
            _mm_add_ps(_mm_mul_ps(mx, mx), _mm_mul_ps(my, my)),
            _mm_mul_ps(mz, mz),
        );
        // `max(x, 0)` gives 0 for a NaN `x`, as `f32::max` does.
        let real = _mm_sqrt_ps(_mm_max_ps(_mm_sub_ps(one, norm2), zero));
        let test = _mm_add_ps(along, _mm_mul_ps(_mm_set1_ps(w), real));
        let flip = _mm_cmplt_ps(test, zero);
        let sign = _mm_or_ps(
            _mm_and_ps(flip, _mm_set1_ps(-1.0)),
            _mm_andnot_ps(flip, one),
        );
        // (15) per coordinate: f * (s m + broken * (omega - s m)).
        let broken = _mm_sub_ps(one, _mm_loadu_ps(rates.as_ptr()));
        let f = _mm_loadu_ps(influences.as_ptr());
        let term = |o: __m128, m: __m128| {
            let remembered = _mm_mul_ps(sign, m);
            _mm_mul_ps(
                f,
                _mm_add_ps(remembered, _mm_mul_ps(broken, _mm_sub_ps(o, remembered))),
            )
        };
        let (tx, ty, tz) = (term(ox, mx), term(oy, my), term(oz, mz));
        // Back to one register per kind ([x, y, z, 0]), summed in kind
        // order from 0 as the scalar sum is.
        let xy_lo = _mm_unpacklo_ps(tx, ty);
        let xy_hi = _mm_unpackhi_ps(tx, ty);
        let z_lo = _mm_unpacklo_ps(tz, zero);
        let z_hi = _mm_unpackhi_ps(tz, zero);
        let mut sum = _mm_add_ps(zero, _mm_movelh_ps(xy_lo, z_lo));
        sum = _mm_add_ps(sum, _mm_movehl_ps(z_lo, xy_lo));
        sum = _mm_add_ps(sum, _mm_movelh_ps(xy_hi, z_hi));
        sum = _mm_add_ps(sum, _mm_movehl_ps(z_hi, xy_hi));
        let mut out = [0.0f32; 4];
        _mm_storeu_ps(out.as_mut_ptr(), sum);
        [out[0], out[1], out[2]]
    }
}

/// [`rest_darboux`] one kind after the other (other CPUs; and the
/// reference its four-wide form is tested against).
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
#[inline(always)]
fn rest_darboux_scalar(
    omega: V3,
    w: f32,
    rates: &[f32; 4],
    memories: &[V3; 4],
    influences: &[f32; 4],
) -> V3 {
    let (omega, w) = canonical_darboux(omega, w);
    // The four kinds' terms first (independent, so computed side by side),
    // then summed in kind order.
    let mut terms = [[0.0f32; 3]; 4];
    for j in 0..4 {
        let s = double_cover_sign(omega, w, memories[j]);
        let broken = 1.0 - rates[j];
        let f = influences[j];
        for c in 0..3 {
            let remembered = s * memories[j][c];
            terms[j][c] = f * (remembered + broken * (omega[c] - remembered));
        }
    }
    let mut out = [0.0f32; 3];
    for term in terms {
        for c in 0..3 {
            out[c] += term[c];
        }
    }
    out
}

/// A joint's bond rates this step ([`still_rates`], [`driven_rates`]):
/// what the step changes and the rates in effect.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointRates {
    /// The change of each rate, `target - b` (the target held to 0..1).
    pub db: [f32; 4],
    /// The rates the rest shape uses, `min(b, target)`: breaking acts at
    /// once, re-forming at the bond update (17).
    pub effective: [f32; 4],
    /// Every change is +0 and no rate is -0 or NaN: the bond update (17)
    /// has nothing to do (`b + 0` is `b` except for -0 and NaN).
    pub unchanged: bool,
}

/// The [`JointRates`] of `rates` in a step with no drive and no drying:
/// each rate held to 0..1 (the target is `clamp(b, 0, 1)`).
#[inline(always)]
pub fn still_rates(rates: &[f32; 4]) -> JointRates {
    #[cfg(target_arch = "x86_64")]
    {
        still_rates_x86(rates)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        still_rates_scalar(rates)
    }
}

/// [`still_rates`] with the four kinds in the lanes of one SSE register,
/// the same IEEE operations as the scalar form. Hand-written: the
/// compiler kept the kinds apart, with `f32::min`'s NaN handling and the
/// bit tests one kind at a time, about half of the rest shape's
/// instructions.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn still_rates_x86(rates: &[f32; 4]) -> JointRates {
    use std::arch::x86_64::*;
    // SAFETY: SSE2 is part of x86-64; the load reads the 4 floats of
    // `rates` and the stores write the 4 of `db` and of `effective`.
    unsafe {
        let b = _mm_loadu_ps(rates.as_ptr());
        let (zero, one) = (_mm_setzero_ps(), _mm_set1_ps(1.0));
        // `clamp(b, 0, 1)`: `max` keeps `b` when it is NaN or a zero
        // (`0 > b` false), `min` likewise, as the clamp's comparisons do.
        let target = _mm_min_ps(one, _mm_max_ps(zero, b));
        let db = _mm_sub_ps(target, b);
        // `b.min(target)`: `target` where `b` is NaN (then so is
        // `target`), else the smaller; they differ only outside 0..1.
        let effective = _mm_min_ps(b, target);
        let still = _mm_cmpeq_epi32(_mm_castps_si128(db), _mm_setzero_si128());
        let negative_zero = _mm_cmpeq_epi32(_mm_castps_si128(b), _mm_set1_epi32(i32::MIN));
        let number = _mm_castps_si128(_mm_cmpord_ps(b, b));
        let unchanged = _mm_andnot_si128(negative_zero, _mm_and_si128(still, number));
        let mut out = JointRates {
            db: [0.0; 4],
            effective: [0.0; 4],
            unchanged: _mm_movemask_epi8(unchanged) == 0xffff,
        };
        _mm_storeu_ps(out.db.as_mut_ptr(), db);
        _mm_storeu_ps(out.effective.as_mut_ptr(), effective);
        out
    }
}

/// [`still_rates`] one kind after the other (other CPUs; and the
/// reference its four-wide form is tested against).
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
#[inline(always)]
fn still_rates_scalar(rates: &[f32; 4]) -> JointRates {
    let mut db = [0.0; 4];
    let mut effective = *rates;
    for ((&b, db), effective) in rates.iter().zip(&mut db).zip(&mut effective) {
        let target = b.clamp(0.0, 1.0);
        *db = target - b;
        *effective = b.min(target);
    }
    JointRates {
        db,
        effective,
        unchanged: rates_unchanged(&db, rates),
    }
}

/// Whether the bond update (17) leaves `rates` as they are after changes
/// `db`: every change is +0 (no re-forming) and no rate is -0 or NaN
/// (`b + 0` is `b` except for those).
#[inline(always)]
pub fn rates_unchanged(db: &[f32; 4], rates: &[f32; 4]) -> bool {
    const NEGATIVE_ZERO: u32 = 0x8000_0000;
    db.iter()
        .zip(rates)
        .all(|(d, b)| d.to_bits() == 0 && b.to_bits() != NEGATIVE_ZERO && !b.is_nan())
}

/// A step's bond drive: per kind the rate change (the stage's rate times
/// `dt`) and the rate it drives toward, if any (`Environment`'s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Drive {
    pub change: [f32; 4],
    pub targets: [Option<f32>; 4],
}

/// A joint's bond rates in a step with a drive or drying: each rate moves
/// by the drive's change toward its target (if any), plus `extra` for
/// hydrogen (the blower's drying, (21)), held to 0..1. Breaking acts at
/// once (`effective`); re-forming takes effect at the bond update (17).
#[inline(always)]
pub fn driven_rates(rates: &[f32; 4], extra: f32, drive: &Drive) -> JointRates {
    let mut effective = *rates;
    let mut db = [0.0f32; 4];
    for k in 0..4 {
        let extra = if k == 0 { extra } else { 0.0 };
        let b = rates[k];
        let driven = match drive.targets[k] {
            Some(goal) if b < goal => min_of(b + drive.change[k].abs(), goal),
            Some(goal) => max_of(b - drive.change[k].abs(), goal),
            None => b + drive.change[k],
        };
        let target = (driven + extra).clamp(0.0, 1.0);
        db[k] = target - b;
        effective[k] = min_of(b, target);
    }
    JointRates {
        db,
        effective,
        unchanged: rates_unchanged(&db, rates),
    }
}

/// `x.min(y)` with the sign of an equal zero defined (`y`), so that the
/// lanes of [`rest_eight`] give the same bits: `f32::min` leaves it open.
/// A NaN argument gives the other, as `f32::min`.
#[inline(always)]
fn min_of(x: f32, y: f32) -> f32 {
    if x < y || y.is_nan() {
        x
    } else {
        y
    }
}

/// `x.max(y)` as [`min_of`].
#[inline(always)]
fn max_of(x: f32, y: f32) -> f32 {
    if x > y || y.is_nan() {
        x
    } else {
        y
    }
}

/// How [`rest_eight`] changes the bond rates: held to 0..1 ([`still_rates`])
/// or driven ([`driven_rates`], with each lane's hydrogen `extra`).
#[derive(Debug, Clone, Copy)]
pub enum RatesIn<'a> {
    Still,
    Driven { drive: &'a Drive, extra: [f32; 8] },
}

/// One joint of eight strands, one strand per lane of AVX registers: per
/// lane the operations of `darboux`, `darboux_real`, [`still_rates`] or
/// [`driven_rates`] and [`rest_darboux`] in the same order, so the same
/// bits as strand by strand. `frames` are the old frames of the joint's
/// two edges, `rates` and `memories` its bonds. Returns the rest shapes,
/// the rate changes and, per lane (bit `l`), whether the rates stay
/// unchanged. Strand by strand the rest shape was a sixth of a step, a
/// chain of dependent operations per joint with few joints in flight.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub fn rest_eight(
    frames: [(&[f32; 4], &[f32; 4]); 8],
    rates: [&[f32; 4]; 8],
    memories: [&[V3; 4]; 8],
    influences: &[f32; 4],
    rule: RatesIn<'_>,
) -> ([V3; 8], [[f32; 4]; 8], u32) {
    use crate::sim::avx::{eight_to_lanes, lanes_to_eight};
    use std::arch::x86_64::*;
    // SAFETY (the loads): each reads four floats of a `[f32; 4]`, or of
    // the twelve of a `[V3; 4]` (an array of arrays: contiguous).
    let load = |x: &[f32; 4]| unsafe { _mm_loadu_ps(x.as_ptr()) };
    let [ax, ay, az, aw] = eight_to_lanes(std::array::from_fn(|l| load(frames[l].0)));
    let [bx, by, bz, bw] = eight_to_lanes(std::array::from_fn(|l| load(frames[l].1)));
    let memory = |part: usize| {
        eight_to_lanes(std::array::from_fn(|l| unsafe {
            _mm_loadu_ps(memories[l].as_flattened().as_ptr().add(4 * part))
        }))
    };
    // Twelve floats per strand, kind after kind: x y z of kind 0, ...
    let [m0, m1, m2] = [memory(0), memory(1), memory(2)];
    let m: [[__m256; 3]; 4] = [
        [m0[0], m0[1], m0[2]],
        [m0[3], m1[0], m1[1]],
        [m1[2], m1[3], m2[0]],
        [m2[1], m2[2], m2[3]],
    ];
    let (add, sub, mul) = (_mm256_add_ps, _mm256_sub_ps, _mm256_mul_ps);
    // `darboux`: Im(conj(a) b), each coordinate's terms in its order.
    let omega = [
        add(sub(sub(mul(aw, bx), mul(ax, bw)), mul(ay, bz)), mul(az, by)),
        sub(sub(add(mul(aw, by), mul(ax, bz)), mul(ay, bw)), mul(az, bx)),
        sub(add(sub(mul(aw, bz), mul(ax, by)), mul(ay, bx)), mul(az, bw)),
    ];
    // `darboux_real`: the 4D dot product, summed x, y, z, w.
    let w = add(add(add(mul(ax, bx), mul(ay, by)), mul(az, bz)), mul(aw, bw));
    // `canonical_darboux`: negated where the real part is negative.
    let (zero, one) = (_mm256_setzero_ps(), _mm256_set1_ps(1.0));
    let flip = _mm256_cmp_ps::<_CMP_LT_OQ>(w, zero);
    let minus_one = _mm256_set1_ps(-1.0);
    let omega = omega.map(|o| _mm256_blendv_ps(o, mul(o, minus_one), flip));
    let w = _mm256_blendv_ps(w, _mm256_xor_ps(w, _mm256_set1_ps(-0.0)), flip);
    // `still_rates` or `driven_rates`, kind by kind.
    let b = eight_to_lanes(std::array::from_fn(|l| load(rates[l])));
    let mut unchanged = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
    let mut db = [zero; 4];
    let mut effective = [zero; 4];
    // `min_of(x, y)` and `max_of(x, y)` for a `y` the same in every lane
    // (a NaN `y` keeps `x`).
    let min_of = |x: __m256, y: f32| {
        if y.is_nan() {
            return x;
        }
        let y = _mm256_set1_ps(y);
        _mm256_blendv_ps(y, x, _mm256_cmp_ps::<_CMP_LT_OQ>(x, y))
    };
    let max_of = |x: __m256, y: f32| {
        if y.is_nan() {
            return x;
        }
        let y = _mm256_set1_ps(y);
        _mm256_blendv_ps(y, x, _mm256_cmp_ps::<_CMP_GT_OQ>(x, y))
    };
    for k in 0..4 {
        // The target held to 0..1 and the rates in effect.
        let (target, in_effect) = match rule {
            // `clamp(b, 0, 1)`: `max` keeps `b` when it is NaN or a zero
            // (`0 > b` false), `min` likewise, as the clamp's comparisons do;
            // `b.min(target)` likewise.
            RatesIn::Still => {
                let target = _mm256_min_ps(one, _mm256_max_ps(zero, b[k]));
                (target, _mm256_min_ps(b[k], target))
            }
            RatesIn::Driven { drive, extra } => {
                let driven = match drive.targets[k] {
                    Some(goal) => {
                        let d = _mm256_set1_ps(drive.change[k].abs());
                        let up = min_of(add(b[k], d), goal);
                        let down = max_of(sub(b[k], d), goal);
                        let below = _mm256_cmp_ps::<_CMP_LT_OQ>(b[k], _mm256_set1_ps(goal));
                        _mm256_blendv_ps(down, up, below)
                    }
                    None => add(b[k], _mm256_set1_ps(drive.change[k])),
                };
                let extra = if k == 0 {
                    // SAFETY: reads the eight floats of `extra`.
                    unsafe { _mm256_loadu_ps(extra.as_ptr()) }
                } else {
                    zero
                };
                // `clamp(x, 0, 1)`: 0 where `x < 0`, then 1 where `x > 1`.
                let x = add(driven, extra);
                let x = _mm256_blendv_ps(x, zero, _mm256_cmp_ps::<_CMP_LT_OQ>(x, zero));
                let target = _mm256_blendv_ps(x, one, _mm256_cmp_ps::<_CMP_GT_OQ>(x, one));
                // `min_of(b, target)`: `b` where `b < target` or `target` is
                // NaN.
                let keep = _mm256_or_ps(
                    _mm256_cmp_ps::<_CMP_LT_OQ>(b[k], target),
                    _mm256_cmp_ps::<_CMP_UNORD_Q>(target, target),
                );
                (target, _mm256_blendv_ps(target, b[k], keep))
            }
        };
        db[k] = sub(target, b[k]);
        effective[k] = in_effect;
        let still = _mm256_cmpeq_epi32(_mm256_castps_si256(db[k]), _mm256_setzero_si256());
        let negative_zero =
            _mm256_cmpeq_epi32(_mm256_castps_si256(b[k]), _mm256_set1_epi32(i32::MIN));
        let number = _mm256_cmp_ps::<_CMP_ORD_Q>(b[k], b[k]);
        let kept = _mm256_andnot_si256(negative_zero, still);
        unchanged = _mm256_and_ps(unchanged, _mm256_and_ps(_mm256_castsi256_ps(kept), number));
    }
    // `rest_darboux`: each kind's term, summed in kind order from 0.
    let mut out = [zero; 3];
    for k in 0..4 {
        let [mx, my, mz] = m[k];
        let along = add(add(mul(omega[0], mx), mul(omega[1], my)), mul(omega[2], mz));
        let norm2 = add(add(mul(mx, mx), mul(my, my)), mul(mz, mz));
        let real = _mm256_sqrt_ps(_mm256_max_ps(sub(one, norm2), zero));
        let test = add(along, mul(w, real));
        let sign = _mm256_blendv_ps(one, minus_one, _mm256_cmp_ps::<_CMP_LT_OQ>(test, zero));
        let broken = sub(one, effective[k]);
        let f = _mm256_set1_ps(influences[k]);
        for (c, m) in [mx, my, mz].into_iter().enumerate() {
            let remembered = mul(sign, m);
            let term = mul(f, add(remembered, mul(broken, sub(omega[c], remembered))));
            out[c] = add(out[c], term);
        }
    }
    let mut rest = [[0.0f32; 3]; 8];
    for (l, v) in lanes_to_eight([out[0], out[1], out[2], zero])
        .into_iter()
        .enumerate()
    {
        let mut four = [0.0f32; 4];
        // SAFETY: stores the four floats of `four`.
        unsafe { _mm_storeu_ps(four.as_mut_ptr(), v) };
        rest[l] = [four[0], four[1], four[2]];
    }
    let mut changes = [[0.0f32; 4]; 8];
    for (l, v) in lanes_to_eight(db).into_iter().enumerate() {
        // SAFETY: stores the four floats of `changes[l]`.
        unsafe { _mm_storeu_ps(changes[l].as_mut_ptr(), v) };
    }
    let mask = _mm256_movemask_ps(unchanged) as u32;
    (rest, changes, mask)
}

/// (17): a bond kind whose rate grows by `db > 0` from `rate` remembers
/// the current shape `omega` (real part `w`) in proportion to the growth.
#[inline(always)]
pub fn reform(memory: V3, rate: f32, db: f32, omega: V3, w: f32) -> V3 {
    let (omega, w) = canonical_darboux(omega, w);
    let s = double_cover_sign(omega, w, memory);
    let total = rate + db;
    let a = rate * s / total;
    let b = db / total;
    [
        a * memory[0] + b * omega[0],
        a * memory[1] + b * omega[1],
        a * memory[2] + b * omega[2],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intact_bonds_give_their_memory_and_broken_ones_the_current_shape() {
        let influences = [0.33, 0.67, 0.0, 0.0];
        let memories = [[0.0; 3]; 4];
        let omega = [0.1, 0.0, 0.0];
        let w = crate::sim::math::rest_real(omega);
        let wet = rest_darboux(omega, w, &[0.0, 1.0, 1.0, 1.0], &memories, &influences);
        assert!((wet[0] - 0.033).abs() < 1e-7);
        let dry = rest_darboux(omega, w, &[1.0; 4], &memories, &influences);
        assert_eq!(dry, [0.0; 3]);
    }

    /// The four-wide rest shape gives the bits of the scalar one, for
    /// random shapes, memories (a quarter of them the current shape
    /// negated, some past unit length) and rates, and with zeros, ones,
    /// infinities and NaNs among them.
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn the_four_wide_rest_shape_is_the_scalar_one_bit_for_bit() {
        let mut unit = crate::sim::test_sequence(0x9e37_79b9_7f4a_7c15);
        let mut next = move || unit() * 2.0 - 1.0;
        let special = [0.0, -0.0, 1.0, -1.0, f32::NAN, f32::INFINITY, 1e-30];
        for case in 0..20_000 {
            let mut v3 = |scale: f32| [next() * scale, next() * scale, next() * scale];
            let omega = v3(0.7);
            let mut memories = [v3(0.7), v3(0.7), v3(1.2), v3(0.3)];
            if case % 4 == 0 {
                memories[case % 3] = crate::sim::math::scale(omega, -1.0);
            }
            let mut w = next();
            let mut rates = [next().abs(), next().abs(), 1.0, 0.0];
            let influences = [0.33, 0.30, 0.20, 0.17];
            if case % 50 == 0 {
                let k = case / 50 % special.len();
                w = special[k];
                rates[case % 4] = special[(k + 1) % special.len()];
                memories[(case + 1) % 4][case % 3] = special[(k + 2) % special.len()];
            }
            // Any NaN is one value: which NaN an operation gives depends on
            // its operand order, which the compiler may swap (Rust makes no
            // promise of NaN bits), and a NaN strand is contained anyway.
            let bits = |v: V3| v.map(|x| if x.is_nan() { u32::MAX } else { x.to_bits() });
            let wide = rest_darboux_x86(omega, w, &rates, &memories, &influences);
            let scalar = rest_darboux_scalar(omega, w, &rates, &memories, &influences);
            assert_eq!(
                bits(wide),
                bits(scalar),
                "case {case}: {omega:?} {w} {rates:?} {memories:?}"
            );
        }
    }

    /// The four-wide still rates are the scalar ones bit for bit, for
    /// rates in and out of 0..1 and zeros, ones, infinities and NaNs.
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn the_four_wide_still_rates_are_the_scalar_ones_bit_for_bit() {
        let values = [
            0.0,
            -0.0,
            1.0,
            0.5,
            0.999_999_9,
            1.000_000_1,
            -1e-30,
            1e-30,
            -0.25,
            2.0,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ];
        let bits = |v: [f32; 4]| v.map(|x| if x.is_nan() { u32::MAX } else { x.to_bits() });
        for (i, a) in values.iter().enumerate() {
            for (j, b) in values.iter().enumerate() {
                let rates = [*a, *b, values[(i + j) % values.len()], 1.0];
                let wide = still_rates_x86(&rates);
                let scalar = still_rates_scalar(&rates);
                assert_eq!(bits(wide.db), bits(scalar.db), "{rates:?}");
                assert_eq!(bits(wide.effective), bits(scalar.effective), "{rates:?}");
                assert_eq!(wide.unchanged, scalar.unchanged, "{rates:?}");
            }
        }
        let intact = still_rates_x86(&[1.0; 4]);
        assert!(intact.unchanged && intact.db == [0.0; 4]);
    }

    /// A joint of eight strands in the lanes gives the bits of the same
    /// joint strand by strand, for random frames (some of them of opposite
    /// sign, so the Darboux quaternion's real part is negative), memories
    /// and rates, with zeros, ones, infinities and NaNs among them; in
    /// still steps and in driven ones (rates toward targets or not, the
    /// blower's drying, special goals, changes and drying among them).
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn the_rest_shape_of_eight_strands_is_theirs_one_by_one() {
        use crate::sim::math::{darboux, darboux_real};
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        let mut unit = crate::sim::test_sequence(0x9e37_79b9_7f4a_7c15);
        let mut next = move || unit() * 2.0 - 1.0;
        let special = [0.0, -0.0, 1.0, -1.0, f32::NAN, f32::INFINITY, 1e-30, 2.0];
        let influences = [0.33, 0.30, 0.20, 0.17];
        let bits3 = |v: V3| v.map(|x| if x.is_nan() { u32::MAX } else { x.to_bits() });
        let bits4 = |v: [f32; 4]| v.map(|x| if x.is_nan() { u32::MAX } else { x.to_bits() });
        let mut unchanged_lanes = [0usize; 2];
        for case in 0..8_000 {
            let mut frames = [([0.0f32; 4], [0.0f32; 4]); 8];
            let mut rates = [[0.0f32; 4]; 8];
            let mut memories = [[[0.0f32; 3]; 4]; 8];
            let mut extra = [0.0f32; 8];
            for l in 0..8 {
                let a = [next(), next(), next(), next()];
                let mut b = a.map(|x| x + 0.2 * next());
                if (case + l) % 3 == 0 {
                    b = b.map(|x| -x);
                }
                frames[l] = (a, b);
                rates[l] = [next().abs(), 1.0, next() * 1.5, 0.0];
                if (case + l) % 4 == 0 {
                    rates[l] = [1.0; 4];
                }
                for kind in memories[l].iter_mut() {
                    *kind = [next() * 0.7, next() * 0.7, next() * 0.7];
                }
                if l % 2 == 0 {
                    extra[l] = next().abs() * 0.01;
                }
                if (case + l) % 29 == 0 {
                    let k = (case + l) / 29 % special.len();
                    rates[l][l % 4] = special[k];
                    memories[l][(l + 1) % 4][l % 3] = special[(k + 1) % special.len()];
                    frames[l].1[l % 4] = special[(k + 2) % special.len()];
                    extra[l] = special[(k + 3) % special.len()];
                }
            }
            // Every other case still; the others driven, each kind toward
            // a goal or not, now and then a special goal or change.
            let drive = Drive {
                change: std::array::from_fn(|k| match (case / 2 + k) % 4 {
                    0 => 0.0,
                    1 => 0.03,
                    2 => -0.03,
                    _ => special[(case / 2 + k) % special.len()],
                }),
                targets: std::array::from_fn(|k| match (case / 2 + 3 * k) % 5 {
                    0 => None,
                    1 => Some(0.0),
                    2 => Some(1.0),
                    3 => Some(0.5),
                    _ => Some(special[(case / 2 + k) % special.len()]),
                }),
            };
            let still = case % 2 == 0;
            let rule = if still {
                RatesIn::Still
            } else {
                RatesIn::Driven {
                    drive: &drive,
                    extra,
                }
            };
            // SAFETY: the CPU has AVX2 (checked above).
            let (rest, db, unchanged) = unsafe {
                rest_eight(
                    std::array::from_fn(|l| (&frames[l].0, &frames[l].1)),
                    std::array::from_fn(|l| &rates[l]),
                    std::array::from_fn(|l| &memories[l]),
                    &influences,
                    rule,
                )
            };
            for l in 0..8 {
                let (a, b) = frames[l];
                let one = if still {
                    still_rates(&rates[l])
                } else {
                    driven_rates(&rates[l], extra[l], &drive)
                };
                let expected = rest_darboux(
                    darboux(a, b),
                    darboux_real(a, b),
                    &one.effective,
                    &memories[l],
                    &influences,
                );
                let at = format!(
                    "case {case} lane {l}: {:?} {:?} {rule:?}",
                    frames[l], rates[l]
                );
                assert_eq!(bits3(rest[l]), bits3(expected), "{at}");
                assert_eq!(bits4(db[l]), bits4(one.db), "{at}");
                assert_eq!(unchanged >> l & 1 == 1, one.unchanged, "{at}");
                unchanged_lanes[usize::from(still)] += usize::from(one.unchanged);
            }
        }
        // Both answers of the unchanged test were met, still and driven.
        for count in unchanged_lanes {
            assert!(count > 100 && count < 4_000 * 8, "{unchanged_lanes:?}");
        }
    }

    #[test]
    fn reforming_from_zero_remembers_the_current_shape() {
        let real = crate::sim::math::rest_real;
        let m = reform(
            [0.5, 0.0, 0.0],
            0.0,
            0.1,
            [0.0, 0.2, 0.0],
            real([0.0, 0.2, 0.0]),
        );
        assert_eq!(m, [0.0, 0.2, 0.0]);
        // 80% kept + 20% re-formed: a weighted mean.
        let m = reform([0.0; 3], 0.8, 0.2, [0.1, 0.0, 0.0], real([0.1, 0.0, 0.0]));
        assert!((m[0] - 0.02).abs() < 1e-7);
        // The double cover: the negated quaternion (omega, -w) is the
        // rotation (-omega, w), so it counts as the memory -omega.
        let m = reform(
            [-0.1, 0.0, 0.0],
            0.5,
            0.5,
            [0.1, 0.0, 0.0],
            -real([0.1, 0.0, 0.0]),
        );
        assert!((m[0] + 0.1).abs() < 1e-7, "{m:?}");
        // A bend past straight (small opposite omega, w near 1) is the
        // opposite bend, not the memory: the set must not mirror.
        let m = reform(
            [0.1, 0.0, 0.0],
            0.5,
            0.5,
            [-0.01, 0.0, 0.0],
            real([0.01, 0.0, 0.0]),
        );
        assert!((m[0] - 0.045).abs() < 1e-7, "{m:?}");
    }
}
