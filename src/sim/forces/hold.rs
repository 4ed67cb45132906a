//! The hold: a TD's spring of every free vertex toward its groomed
//! position, as Maya nHair's start-curve attract and Houdini Vellum's
//! pin-to-target stiffness give (shared DECISIONS.md, the Bangs). Off
//! unless the caller asks for it ([`Environment::hold`](crate::sim::Environment)).
//!
//! Each edge's frame is held the same way toward its groomed frame (see
//! [`fold_frame`]), with the strength at the edge's middle.
//!
//! The target is the vertex's position when the strands were made
//! (`StrandSet::from_groom` or `from_state`: the groom, or the shape a
//! continued bake starts from), carried rigidly with the scalp (the root
//! transform), so a moving head takes its hold targets along.
//!
//! The strength `k` is an acceleration per metre of displacement, 1/s^2:
//! the hold's force on a vertex of mass `m` is `-m k (x - x_target)`, so it
//! does not depend on the hair's thickness or density. A lone vertex under
//! gravity `g` settles `g / k` from its target; the hold's own frequency is
//! `sqrt(k) / (2 pi)` Hz.
//!
//! How it is solved: implicitly, inside the step. The hold's energy
//! `m k |p - x*|^2 / 2` and the step's inertia `m |p - x~|^2 / (2 dt^2)`
//! are both quadratic in the vertex's position alone, so their sum is one
//! inertia `m (1 + k dt^2) |p - p^|^2 / (2 dt^2)` about `p^ = (x~ + k dt^2
//! x*) / (1 + k dt^2)`: the prediction moves to `p^` and the vertex's
//! inverse mass in the constraint solve is divided by `1 + k dt^2`. That is
//! the exact backward-Euler step of the rod with the spring, the spring
//! acting as a compliant constraint of compliance `1 / (m k)` solved with
//! the others, so it is stable at any `k` and `dt` (an explicit force in
//! the prediction diverges beyond `k dt^2 = 4`, `k = 518,000 1/s^2` at
//! dt 1/360), and the static balance against the rod's elastic forces
//! and gravity is `k (x - x*) = g + f / m` whatever `dt`.

use crate::sim::math::{self, Quat, V3};
use serde::{Deserialize, Serialize};

/// The hold of one step (see the module's doc).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Hold {
    /// `k`, 1/s^2: the acceleration toward the target per metre of
    /// displacement where the ramp is 1. Range 0 - [`Hold::MAX_STRENGTH`].
    pub strength: f32,
    /// The share of `strength` at the root and at the tip, each in [0, 1],
    /// linear in the arc length of the groomed strand in between (`[1, 1]`:
    /// the same everywhere; `[0, 1]`: free at the root, fully held at the
    /// tip).
    pub ramp: [f32; 2],
}

impl Hold {
    /// The largest strength accepted, 1/s^2: a vertex then follows its
    /// target within `g / k` = 0.1 um, pinned in effect.
    pub const MAX_STRENGTH: f32 = 1.0e8;

    /// A hold of `strength` the same from root to tip.
    pub fn uniform(strength: f32) -> Hold {
        Hold {
            strength,
            ramp: [1.0, 1.0],
        }
    }

    /// What is wrong with it, if anything.
    pub fn problem(&self) -> Option<&'static str> {
        if !(self.strength.is_finite() && (0.0..=Hold::MAX_STRENGTH).contains(&self.strength)) {
            return Some("strength must be an acceleration per metre in [0, 1e8] 1/s^2");
        }
        if self
            .ramp
            .iter()
            .any(|r| !(r.is_finite() && (0.0..=1.0).contains(r)))
        {
            return Some("ramp must be two shares in [0, 1] (root, tip)");
        }
        None
    }

    /// `k` at the fraction `u` of the groomed strand's length from the
    /// root, 1/s^2.
    #[inline(always)]
    pub fn at(&self, u: f32) -> f32 {
        self.strength * (self.ramp[0] + (self.ramp[1] - self.ramp[0]) * u)
    }
}

/// The hold folded into one free vertex's prediction `p` (see the module's
/// doc): the new prediction, and the factor of its inverse mass.
#[inline(always)]
pub(in crate::sim) fn fold(p: V3, target: V3, k: f32, dt: f32) -> (V3, f32) {
    let c = k * dt * dt;
    let keep = 1.0 / (1.0 + c);
    // `p + (target - p) c / (1 + c)`: the same as the weighted mean, with
    // the round-off of a small move.
    let moved = math::add(p, math::scale(math::sub(target, p), c * keep));
    (moved, keep)
}

/// The hold folded into one free edge frame's prediction `q` toward its
/// groomed frame `target` (the same spring per unit of inertia, on the
/// frame's rotation: without it a strand held by its positions alone could
/// still roll its curl over about its own axis, as the Bangs' unstable
/// strands do, and then the hold had to carry the rod's whole bending
/// force): the new prediction (the quaternions' normalised weighted mean,
/// the shorter way round) and the factor of its inverse inertia.
#[inline(always)]
pub(in crate::sim) fn fold_frame(q: Quat, target: Quat, k: f32, dt: f32) -> (Quat, f32) {
    let c = k * dt * dt;
    let keep = 1.0 / (1.0 + c);
    let t = c * keep;
    let sign = if math::qdot(q, target) < 0.0 {
        -1.0
    } else {
        1.0
    };
    let mixed: Quat = std::array::from_fn(|i| q[i] + (sign * target[i] - q[i]) * t);
    (math::qnormalize(mixed), keep)
}

/// The fraction of its groomed length from the root of every vertex of
/// each strand (`offsets` as `StrandSet`'s), from the positions.
pub(in crate::sim) fn arc_fractions(positions: &[V3], offsets: &[usize]) -> Vec<f32> {
    let mut fractions = vec![0.0f32; positions.len()];
    for w in offsets.windows(2) {
        let strand = &positions[w[0]..w[1]];
        let out = &mut fractions[w[0]..w[1]];
        let mut arc = 0.0f64;
        for (i, e) in strand.windows(2).enumerate() {
            arc += f64::from(math::length(math::sub(e[1], e[0])));
            out[i + 1] = arc as f32;
        }
        if arc > 0.0 && arc.is_finite() {
            for f in out.iter_mut() {
                *f = (f64::from(*f) / arc) as f32;
            }
        }
    }
    fractions
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ramp_runs_from_root_to_tip() {
        let hold = Hold {
            strength: 1000.0,
            ramp: [0.2, 1.0],
        };
        assert_eq!(hold.at(0.0), 200.0);
        assert_eq!(hold.at(1.0), 1000.0);
        assert!((hold.at(0.5) - 600.0).abs() < 1e-3);
        assert_eq!(Hold::uniform(5.0).at(0.7), 5.0);
    }

    #[test]
    fn bad_holds_are_named() {
        for strength in [-1.0, f32::NAN, f32::INFINITY, 2e8] {
            assert!(Hold::uniform(strength).problem().is_some(), "{strength}");
        }
        for ramp in [[-0.1, 1.0], [0.0, 1.5], [f32::NAN, 0.0]] {
            let hold = Hold {
                strength: 1.0,
                ramp,
            };
            assert!(hold.problem().is_some(), "{ramp:?}");
        }
        assert!(Hold::uniform(0.0).problem().is_none());
        assert!(Hold::uniform(1e4).problem().is_none());
    }

    #[test]
    fn folding_is_the_weighted_mean_of_prediction_and_target() {
        let (p, keep) = fold([1.0, 0.0, 0.0], [0.0, 0.0, 0.0], 100.0, 0.1);
        // c = 1: halfway, half the inverse mass.
        assert!((p[0] - 0.5).abs() < 1e-7 && keep == 0.5, "{p:?} {keep}");
        let (p, keep) = fold([1.0, 2.0, 3.0], [0.0; 3], 0.0, 0.1);
        assert_eq!((p, keep), ([1.0, 2.0, 3.0], 1.0));
    }

    #[test]
    fn arc_fractions_run_from_zero_to_one_per_strand() {
        let positions = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [3.0, 0.0, 0.0],
            [5.0, 5.0, 5.0],
            [5.0, 6.0, 5.0],
        ];
        let f = arc_fractions(&positions, &[0, 3, 5]);
        let expected = [0.0, 1.0 / 3.0, 1.0, 0.0, 1.0];
        for (a, b) in f.iter().zip(expected) {
            assert!((a - b).abs() < 1e-6, "{f:?}");
        }
    }
}
