//! Side-chain bonds (000 §5): the rest shape from the bonds (15)-(16) and
//! the memory update when bonds re-form (17)-(18).

use super::math::{canonical_darboux, double_cover_sign, V3};

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
