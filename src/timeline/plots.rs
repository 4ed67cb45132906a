//! What a bake's HTML report plots, sampled as the bake runs: the mean
//! bond rate of each kind, the mean wetness and the largest edge strain
//! (against the groom at the start), at the start, every 1/24 s and at the
//! end of every stage; and after each stage how much of the largest shape
//! change so far the rest shape keeps (`set_kept`).

use crate::sim::{BondKind, StrandSet};
use serde::Serialize;

/// Samples per simulated second (a film frame each).
pub const SAMPLES_PER_SECOND: f64 = 24.0;

/// The plotted quantities at one time.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct PlotSample {
    /// Simulated seconds from the start.
    pub time: f64,
    /// Mean `b_j` of hydrogen, ionic, disulfide and peptide bonds.
    pub bonds: [f64; 4],
    pub wetness: f64,
    /// Largest `|length / length at the start - 1|` of any edge.
    pub strain: f64,
}

/// Samples a bake's strands as it runs.
pub struct Plotter {
    start_pose: Vec<[f32; 3]>,
    start_rest: Vec<[f32; 3]>,
    next_time: f64,
    /// The largest mean distance of the pose from the start's so far, m.
    largest_change: f64,
    pub samples: Vec<PlotSample>,
}

fn mean(values: impl ExactSizeIterator<Item = f32>) -> f64 {
    let n = values.len();
    if n == 0 {
        return 0.0;
    }
    values.map(f64::from).sum::<f64>() / n as f64
}

fn distance(a: [f32; 3], b: [f32; 3]) -> f64 {
    (0..3)
        .map(|k| f64::from(a[k] - b[k]).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// Mean distance between two point lists of the same length.
fn mean_distance(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    if a.is_empty() {
        return 0.0;
    }
    a.iter().zip(b).map(|(&p, &q)| distance(p, q)).sum::<f64>() / a.len() as f64
}

impl Plotter {
    /// Starts with the strands as the bake starts (sampled at time 0).
    pub fn new(strands: &StrandSet) -> Plotter {
        let mut plotter = Plotter {
            start_pose: strands.positions().to_vec(),
            start_rest: strands.rest_pose(),
            next_time: 0.0,
            largest_change: 0.0,
            samples: Vec::new(),
        };
        plotter.sample(0.0, strands);
        plotter
    }

    fn sample(&mut self, time: f64, strands: &StrandSet) {
        let bonds = BondKind::ALL.map(|kind| mean(strands.bond_rates(kind).into_iter()));
        let positions = strands.positions();
        if positions.len() == self.start_pose.len() {
            let change = mean_distance(positions, &self.start_pose);
            self.largest_change = self.largest_change.max(change);
        }
        let mut strain = 0.0f64;
        for strand in 0..strands.strand_count() {
            let Some(range) = strands.strand_range(strand) else {
                continue;
            };
            for v in range.start..range.end.saturating_sub(1) {
                let before = distance(self.start_pose[v], self.start_pose[v + 1]);
                if before > 0.0 {
                    let now = distance(positions[v], positions[v + 1]);
                    strain = strain.max((now / before - 1.0).abs());
                }
            }
        }
        self.samples.push(PlotSample {
            time,
            bonds,
            wetness: mean(strands.wetness().iter().copied()),
            strain,
        });
        self.next_time = (time * SAMPLES_PER_SECOND + 1e-6).floor() / SAMPLES_PER_SECOND
            + 1.0 / SAMPLES_PER_SECOND;
    }

    /// After a step that ended at `time`: a sample when a frame is due.
    pub fn after_step(&mut self, time: f64, strands: &StrandSet) {
        if time + 1e-9 >= self.next_time {
            self.sample(time, strands);
        }
    }

    /// At the end of a stage (at `time`): a sample, unless one was just
    /// taken, and the share of the largest shape change so far (the pose
    /// pressed, wound or blown furthest from the groom at the start, as a
    /// mean distance over the vertices, sampled every frame) that the rest
    /// shape keeps: mean `|rest - rest at the start|` over it. 0: released
    /// now the hair springs back to its groomed shape; 1: it keeps the whole
    /// change. `None` while the pose has not changed (under 0.01 mm on
    /// average) or when the strands were rebuilt with other vertices.
    pub fn stage_end(&mut self, time: f64, strands: &StrandSet) -> Option<f64> {
        if self
            .samples
            .last()
            .is_none_or(|s| (s.time - time).abs() > 1e-9)
        {
            self.sample(time, strands);
        }
        let rest = strands.rest_pose();
        if rest.len() != self.start_rest.len() || self.largest_change < 1e-5 {
            return None;
        }
        let kept = mean_distance(&rest, &self.start_rest) / self.largest_change;
        Some((kept * 1000.0).round() / 1000.0)
    }
}
