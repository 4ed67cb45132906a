//! The layout of eight strands or vertices in AVX registers, shared by the
//! phases that run eight at a time (the bond update, the rest shape, the
//! blower's push, the volumetric grid).

/// Eight four-float values (one per strand or vertex) as four registers
/// of eight lanes, value `c` of item `l` in lane `l` of register `c`:
/// items 0-3 in the low halves, 4-7 in the high, then a 4x4 transpose in
/// each half. (The per-item layout of the state into lanes, for code that
/// runs eight items at once in AVX registers.)
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(in crate::sim) fn eight_to_lanes(
    x: [std::arch::x86_64::__m128; 8],
) -> [std::arch::x86_64::__m256; 4] {
    use std::arch::x86_64::*;
    let r0 = _mm256_insertf128_ps::<1>(_mm256_castps128_ps256(x[0]), x[4]);
    let r1 = _mm256_insertf128_ps::<1>(_mm256_castps128_ps256(x[1]), x[5]);
    let r2 = _mm256_insertf128_ps::<1>(_mm256_castps128_ps256(x[2]), x[6]);
    let r3 = _mm256_insertf128_ps::<1>(_mm256_castps128_ps256(x[3]), x[7]);
    transpose_halves([r0, r1, r2, r3])
}

/// The inverse of [`eight_to_lanes`]: four registers of eight lanes back
/// to eight four-float values.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(in crate::sim) fn lanes_to_eight(
    c: [std::arch::x86_64::__m256; 4],
) -> [std::arch::x86_64::__m128; 8] {
    use std::arch::x86_64::*;
    let r = transpose_halves(c);
    std::array::from_fn(|l| {
        let half = r[l % 4];
        if l < 4 {
            _mm256_castps256_ps128(half)
        } else {
            _mm256_extractf128_ps::<1>(half)
        }
    })
}

/// A 4x4 transpose of floats in each 128-bit half of four registers (its
/// own inverse).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn transpose_halves(r: [std::arch::x86_64::__m256; 4]) -> [std::arch::x86_64::__m256; 4] {
    use std::arch::x86_64::*;
    let t0 = _mm256_unpacklo_ps(r[0], r[1]);
    let t1 = _mm256_unpackhi_ps(r[0], r[1]);
    let t2 = _mm256_unpacklo_ps(r[2], r[3]);
    let t3 = _mm256_unpackhi_ps(r[2], r[3]);
    [
        _mm256_shuffle_ps::<0x44>(t0, t2),
        _mm256_shuffle_ps::<0xee>(t0, t2),
        _mm256_shuffle_ps::<0x44>(t1, t3),
        _mm256_shuffle_ps::<0xee>(t1, t3),
    ]
}
