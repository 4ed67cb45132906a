//! Side-chain bonds (000 §5): the rest shape from the bonds (15)-(16) and
//! the memory update when bonds re-form (17)-(18).

use super::math::{dot, sub, V3};

/// `s` of (16)/(18): +1 when `omega` is nearer `memory` than `-memory`
/// (quaternion double cover).
#[inline(always)]
pub fn sign_against(omega: V3, memory: V3) -> f32 {
    let d = sub(omega, memory);
    let s = [
        omega[0] + memory[0],
        omega[1] + memory[1],
        omega[2] + memory[2],
    ];
    if dot(d, d) <= dot(s, s) {
        1.0
    } else {
        -1.0
    }
}

/// `Omega_o` of (15): intact bonds pull toward their memory, broken ones
/// toward the current shape `omega`. `influences` are normalised (sum 1).
#[inline(always)]
pub fn rest_darboux(omega: V3, rates: &[f32; 4], memories: &[V3; 4], influences: &[f32; 4]) -> V3 {
    let mut out = [0.0f32; 3];
    for j in 0..4 {
        let s = sign_against(omega, memories[j]);
        let broken = 1.0 - rates[j];
        let f = influences[j];
        for c in 0..3 {
            let remembered = s * memories[j][c];
            out[c] += f * (remembered + broken * (omega[c] - remembered));
        }
    }
    out
}

/// (17): a bond kind whose rate grows by `db > 0` from `rate` remembers
/// the current shape `omega` in proportion to the growth.
#[inline(always)]
pub fn reform(memory: V3, rate: f32, db: f32, omega: V3) -> V3 {
    let s = sign_against(omega, memory);
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
        let wet = rest_darboux(omega, &[0.0, 1.0, 1.0, 1.0], &memories, &influences);
        assert!((wet[0] - 0.033).abs() < 1e-7);
        let dry = rest_darboux(omega, &[1.0; 4], &memories, &influences);
        assert_eq!(dry, [0.0; 3]);
    }

    #[test]
    fn reforming_from_zero_remembers_the_current_shape() {
        let m = reform([0.5, 0.0, 0.0], 0.0, 0.1, [0.0, 0.2, 0.0]);
        assert_eq!(m, [0.0, 0.2, 0.0]);
        // 80% kept + 20% re-formed: a weighted mean.
        let m = reform([0.0; 3], 0.8, 0.2, [0.1, 0.0, 0.0]);
        assert!((m[0] - 0.02).abs() < 1e-7);
        // The double cover: a memory of -omega counts as omega.
        let m = reform([-0.1, 0.0, 0.0], 0.5, 0.5, [0.1, 0.0, 0.0]);
        assert!((m[0] - 0.1).abs() < 1e-7);
    }
}
