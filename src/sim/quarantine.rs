//! Containment of non-finite state: a strand's new state is checked before
//! it is committed; a strand that fails keeps its state from before the step
//! and is frozen (see `step.rs`), so a NaN never reaches another strand.

use super::math::{Quat, V3};

/// True when every value is finite.
pub fn all_finite(positions: &[V3], velocities: &[V3], frames: &[Quat], angular: &[V3]) -> bool {
    // A float is NaN or infinite exactly when its exponent bits are all
    // ones; OR-ing the test over all values has no branch and no long
    // dependency chain, so it vectorises.
    const EXPONENT: u32 = 0x7f80_0000;
    let bad = |x: &f32| u32::from(x.to_bits() & EXPONENT == EXPONENT);
    let mut any = 0u32;
    for v in positions.iter().chain(velocities).chain(angular) {
        any |= v.iter().map(bad).fold(0, |a, b| a | b);
    }
    for q in frames {
        any |= q.iter().map(bad).fold(0, |a, b| a | b);
    }
    any == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_nan_and_infinity_anywhere() {
        let p = [[0.0, 1.0, -2.0e30]];
        let q = [[0.0, 0.0, 0.0, 1.0]];
        assert!(all_finite(&p, &p, &q, &p));
        assert!(!all_finite(&[[f32::NAN, 0.0, 0.0]], &p, &q, &p));
        assert!(!all_finite(&p, &[[0.0, f32::INFINITY, 0.0]], &q, &p));
        assert!(!all_finite(
            &p,
            &p,
            &[[0.0, 0.0, f32::NEG_INFINITY, 1.0]],
            &p
        ));
        assert!(!all_finite(&p, &p, &q, &[[0.0, 0.0, -f32::NAN]]));
    }
}
