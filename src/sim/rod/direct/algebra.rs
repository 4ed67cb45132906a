//! The fixed-size algebra of the direct solve, generic over [`Real`]: the
//! LDL^T factorisation of a 6x6 block and its substitutions (rows written
//! out, as the blocks are fixed-size and sparse in a known pattern), and
//! the 3x3 and quaternion products it needs.

use super::{DirectInput, Unit, D3, D6, M3};
use crate::sim::rod::real::Real;

// The triangular loops here are written out row by row (by macros with
// literal bounds) so the compiler unrolls them fully: as nested loops with
// bounds depending on the outer index they stayed loops with index
// arithmetic and bounds checks on the solve's critical path. The operations
// and their order are those of the loops.

/// Row `i` of the `L D L^T` factor: `L D` and `L` below the diagonal (over
/// columns `j`), then the pivot.
macro_rules! ldlt_row {
    ($a:ident, $l:ident, $inv:ident, $ld:ident, $i:literal; $($j:literal)*) => {
        $(
            let mut s = $a[$i][$j];
            for k in 0..$j {
                s = s - $ld[k] * $l[($j, k)];
            }
            $ld[$j] = s;
            $l[($i, $j)] = s * $inv[$j];
        )*
        let mut s = $a[$i][$i];
        for k in 0..$i {
            s = s - $ld[k] * $l[($i, k)];
        }
        let (zero, one) = (T::splat(0.0), T::splat(1.0));
        $inv[$i] = one / T::gt_select(s, zero, s, one);
    };
}

/// `L D L^T` factor of a symmetric positive definite 6x6 block given by
/// its lower triangle: `L` unit lower (below the diagonal) and `D^-1`. A
/// non-positive pivot (only from non-finite input) becomes 1 so the
/// quarantine sees the NaN rather than a panic.
#[inline(always)]
// Row 0 (and column 0) have no terms: empty ranges from the macro.
#[allow(clippy::reversed_empty_ranges)]
pub(super) fn ldlt<T: Real>(a: &[D6<T>; 6], l: &mut Unit<T>, inv: &mut D6<T>) {
    // Row i of L D, below the diagonal.
    let mut ld = [T::splat(0.0); 6];
    ldlt_row!(a, l, inv, ld, 0;);
    ldlt_row!(a, l, inv, ld, 1; 0);
    ldlt_row!(a, l, inv, ld, 2; 0 1);
    ldlt_row!(a, l, inv, ld, 3; 0 1 2);
    ldlt_row!(a, l, inv, ld, 4; 0 1 2 3);
    ldlt_row!(a, l, inv, ld, 5; 0 1 2 3 4);
}

/// `y_i = b_i - sum_{k < i} L_ik y_k`.
macro_rules! forward_row {
    ($l:ident, $y:ident, $i:literal) => {
        for k in 0..$i {
            $y[$i] = $y[$i] - $l[($i, k)] * $y[k];
        }
    };
}

/// `D^-1 L^-1 b`.
#[inline(always)]
pub(super) fn forward_substitute<T: Real>(l: &Unit<T>, inv: &D6<T>, b: D6<T>) -> D6<T> {
    let mut y = b;
    forward_row!(l, y, 1);
    forward_row!(l, y, 2);
    forward_row!(l, y, 3);
    forward_row!(l, y, 4);
    forward_row!(l, y, 5);
    build(|i| y[i] * inv[i])
}

/// `x_i = y_i - sum_{j > i} L_ji x_j`.
macro_rules! backward_row {
    ($l:expr, $y:ident, $x:ident, $i:literal) => {
        let mut s = $y[$i];
        for j in $i + 1..6 {
            s = s - $l[(j, $i)] * $x[j];
        }
        $x[$i] = s;
    };
}

/// `L^-T y`.
#[inline(always)]
pub(super) fn backward_substitute<T: Real>(l: &Unit<T>, y: D6<T>) -> D6<T> {
    let mut x = y;
    backward_row!(l, y, x, 4);
    backward_row!(l, y, x, 3);
    backward_row!(l, y, x, 2);
    backward_row!(l, y, x, 1);
    backward_row!(l, y, x, 0);
    x
}

#[inline(always)]
pub(super) fn tangent<T: Real>(q: [T; 4]) -> D3<T> {
    let [x, y, z, w] = q;
    let two = T::splat(2.0);
    [
        two * (x * z + w * y),
        two * (y * z - w * x),
        T::splat(1.0) - two * (x * x + y * y),
    ]
}

#[inline(always)]
pub(super) fn rotation_matrix<T: Real>(q: [T; 4]) -> M3<T> {
    let [x, y, z, w] = q;
    let one = T::splat(1.0);
    let two = T::splat(2.0);
    [
        [
            one - two * (y * y + z * z),
            two * (x * y - w * z),
            two * (x * z + w * y),
        ],
        [
            two * (x * y + w * z),
            one - two * (x * x + z * z),
            two * (y * z - w * x),
        ],
        [
            two * (x * z - w * y),
            two * (y * z + w * x),
            one - two * (x * x + y * y),
        ],
    ]
}

#[inline(always)]
pub(super) fn qmul<T: Real>(a: [T; 4], b: [T; 4]) -> [T; 4] {
    [
        a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1],
        a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0],
        a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3],
        a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2],
    ]
}

#[inline(always)]
pub(super) fn conj<T: Real>(q: [T; 4]) -> [T; 4] {
    [-q[0], -q[1], -q[2], q[3]]
}

/// `a v`.
#[inline(always)]
pub(super) fn mul_av<T: Real>(a: &M3<T>, v: D3<T>) -> D3<T> {
    build(|r| a[r][0] * v[0] + a[r][1] * v[1] + a[r][2] * v[2])
}

/// `a^T v`.
#[inline(always)]
pub(super) fn mul_at_v<T: Real>(a: &M3<T>, v: D3<T>) -> D3<T> {
    build(|c| a[0][c] * v[0] + a[1][c] * v[1] + a[2][c] * v[2])
}

/// Lane `i` of a number from strand `i`.
#[inline(always)]
pub(super) fn gather<T: Real>(
    strands: &[DirectInput<'_>],
    get: impl Fn(&DirectInput<'_>) -> f64,
) -> T {
    T::gather(|i| get(&strands[i]))
}

/// `[f(0), .., f(N - 1)]`, always inlined (`array::map` and `from_fn`
/// were not, in the hot loop).
#[inline(always)]
pub(super) fn build<U: Copy + Default, const N: usize>(mut f: impl FnMut(usize) -> U) -> [U; N] {
    let mut out = [U::default(); N];
    for (i, o) in out.iter_mut().enumerate() {
        *o = f(i);
    }
    out
}

#[inline(always)]
pub(super) fn cross<T: Real>(a: D3<T>, b: D3<T>) -> D3<T> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
