//! Containment of non-finite state: a strand's new state is checked before
//! it is committed; a strand that fails keeps its state from before the step
//! and is frozen (see `step.rs`), so a NaN never reaches another strand.

use super::math::{Quat, V3};

/// True when every value is finite.
pub fn all_finite(positions: &[V3], velocities: &[V3], frames: &[Quat], angular: &[V3]) -> bool {
    // Summing is cheaper than testing each value, and any NaN or infinity
    // makes the sum non-finite (inf - inf is NaN, too).
    let mut sum = 0.0f32;
    for p in positions.iter().chain(velocities).chain(angular) {
        sum += p[0] * 0.0 + p[1] * 0.0 + p[2] * 0.0;
    }
    for q in frames {
        sum += (q[0] + q[1] + q[2] + q[3]) * 0.0;
    }
    sum == 0.0
}
