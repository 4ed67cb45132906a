//! Containment of non-finite state: a strand's new state is checked before
//! it is committed; a strand that fails keeps its state from before the step
//! and is frozen (see `step.rs`, `velocities` and `commit`), so a NaN never reaches another strand.
//! Beside it the physical sanity watchdog (`contain_blowups`) freezes a
//! strand with an edge strained beyond [`MAX_STRAIN`] and notes, for one
//! warning per stage, those beyond [`WARN_STRAIN`] ([`StrainWatch`]).

use super::math::{Quat, V3};
use super::state::StrandSet;

/// True when every value is finite.
pub fn all_finite(positions: &[V3], velocities: &[V3], frames: &[Quat], angular: &[V3]) -> bool {
    // A float is NaN or infinite exactly when its exponent bits are all
    // ones; OR-ing the test over all values has no branch and no long
    // dependency chain, so it vectorises.
    // The slices flat, each a plain loop: a chain of iterators over the
    // vectors did not vectorise.
    const EXPONENT: u32 = 0x7f80_0000;
    let bad = |values: &[f32]| {
        values.iter().fold(0u32, |any, x| {
            any | u32::from(x.to_bits() & EXPONENT == EXPONENT)
        })
    };
    let any = bad(positions.as_flattened())
        | bad(velocities.as_flattened())
        | bad(angular.as_flattened())
        | bad(frames.as_flattened());
    any == 0
}

/// Largest strain of an edge (length against rest length) the watchdog
/// lets pass: hair stretches a few per cent before it breaks.
pub const MAX_STRAIN: f32 = 0.5;

/// The strain from which the watchdog warns (length against rest length,
/// stretched or compressed). Hair is elastic to about 2 % and yields
/// beyond (Robbins, *Chemical and Physical Behavior of Human Hair*: the
/// Hookean region of the stress-strain curve), and the loads of a styling
/// scene strain it far less (a 24 cm hair's own weight: 1e-6), so an edge
/// 5 % off its rest length is the solver's doing (hair pushed into a
/// collider, a step too coarse for an impact), not the hair's.
pub const WARN_STRAIN: f32 = 0.05;

/// The strands the watchdog saw strained beyond [`WARN_STRAIN`] (but not
/// frozen) over a span of steps, e.g. a stage: which, and the worst edge.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StrainWatch {
    /// The strands, in order of strand index.
    pub strands: Vec<usize>,
    /// The largest `|length / rest - 1|` seen, with its strand and edge.
    pub worst: Option<(f32, usize, usize)>,
}

impl StrainWatch {
    fn note(&mut self, strand: usize, strain: f32, edge: usize) {
        if let Err(at) = self.strands.binary_search(&strand) {
            self.strands.insert(at, strand);
        }
        if self.worst.is_none_or(|(worst, _, _)| strain > worst) {
            self.worst = Some((strain, strand, edge));
        }
    }

    /// The TD's one line about the strands strained beyond
    /// [`WARN_STRAIN`] in stage `stage` (its name), or `None` when none was.
    pub fn warning(&self, stage: &str) -> Option<String> {
        let (worst, strand, edge) = self.worst?;
        let first: Vec<String> = self.strands.iter().take(8).map(usize::to_string).collect();
        Some(format!(
            "stage '{stage}': {} strand(s) had an edge strained beyond {:.0} % (strands {}{}; worst {:.1} % at strand {strand} edge {edge}); no styling load strains hair that far: look for a collider inside the hair or its roots, or a step too long for the motion ([solver] dt)",
            self.strands.len(),
            WARN_STRAIN * 100.0,
            first.join(", "),
            if self.strands.len() > first.len() { ", ..." } else { "" },
            worst * 100.0,
        ))
    }
}

/// A strand the physical sanity watchdog contained, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Blowup {
    pub strand: usize,
    pub reason: String,
}

/// The physical sanity watchdog, beside the NaN quarantine: after a step,
/// a simulated strand with a non-finite position or velocity, an edge
/// strained beyond [`MAX_STRAIN`] (stretched or compressed) or a collapsed
/// edge is put back where it was before the step (`before`, the positions
/// then), stopped and frozen, as a strand that turned NaN is. Returns the
/// strands contained, in order.
pub fn contain_blowups(strands: &mut StrandSet, before: &[V3]) -> Vec<Blowup> {
    contain_blowups_watching(strands, before, &mut StrainWatch::default())
}

/// [`contain_blowups`], also noting in `watch` the strands (not frozen)
/// with an edge strained beyond [`WARN_STRAIN`].
pub fn contain_blowups_watching(
    strands: &mut StrandSet,
    before: &[V3],
    watch: &mut StrainWatch,
) -> Vec<Blowup> {
    let mut blowups = Vec::new();
    for strand in 0..strands.strand_count() {
        if !strands.simulated[strand] || strands.frozen[strand] {
            continue;
        }
        let (first, end) = (strands.offsets[strand], strands.offsets[strand + 1]);
        let reason = match strand_problem(strands, first, end) {
            Ok(None) => continue,
            Ok(Some((strain, edge))) => {
                watch.note(strand, strain, edge);
                continue;
            }
            Err(reason) => reason,
        };
        if before.len() == strands.positions.len() {
            strands.positions[first..end].copy_from_slice(&before[first..end]);
        }
        strands.velocities[first..end].fill([0.0; 3]);
        strands.velocity_corrections[first..end].fill([0.0; 3]);
        strands.frozen[strand] = true;
        blowups.push(Blowup { strand, reason });
    }
    blowups
}

/// What is physically wrong with the strand of vertices `first..end`: a
/// reason to freeze it (`Err`), or its worst strain and edge where that is
/// beyond [`WARN_STRAIN`].
fn strand_problem(
    strands: &StrandSet,
    first: usize,
    end: usize,
) -> Result<Option<(f32, usize)>, String> {
    let positions = &strands.positions[first..end];
    let velocities = &strands.velocities[first..end];
    if !all_finite(positions, velocities, &[], &[]) {
        return Err("a position or velocity is not finite".into());
    }
    let mut worst: Option<(f32, usize)> = None;
    for (e, w) in positions.windows(2).enumerate() {
        let length = (0..3)
            .map(|k| (w[1][k] - w[0][k]).powi(2))
            .sum::<f32>()
            .sqrt();
        if length <= 1e-9 {
            return Err(format!("edge {e} collapsed (two identical points)"));
        }
        let rest = strands.edges[first + e].rest_length;
        let strain = length / rest - 1.0;
        if strain.abs() > MAX_STRAIN {
            return Err(format!(
                "edge {e} strained {:+.0} % ({length:.3e} m, rest {rest:.3e} m)",
                strain * 100.0
            ));
        }
        if strain.abs() > WARN_STRAIN && worst.is_none_or(|(w, _)| strain.abs() > w) {
            worst = Some((strain.abs(), e));
        }
    }
    Ok(worst)
}

/// The strands that are not simulated, with why: fewer than two points, or
/// two identical consecutive points (a zero-length edge).
pub fn unsimulated_strands(strands: &StrandSet) -> Vec<Blowup> {
    (0..strands.strand_count())
        .filter(|&s| !strands.simulated[s])
        .map(|strand| {
            let (first, end) = (strands.offsets[strand], strands.offsets[strand + 1]);
            let positions = &strands.positions[first..end];
            let reason = match positions.windows(2).position(|w| w[0] == w[1]) {
                _ if positions.len() < 2 => "fewer than two points".to_string(),
                Some(e) => format!("points {e} and {} are identical", e + 1),
                None => "an edge of zero length".to_string(),
            };
            Blowup { strand, reason }
        })
        .collect()
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
