//! Comparison of two grooms within a tolerance (`groombake diff`): for
//! studio CI where byte equality is too strict (another platform, another
//! exporter). Both grooms are compared in metres, Y up, so files of
//! different formats and units compare by what they hold.
//!
//! What is compared: the strand count and each strand's vertex count (a
//! topology mismatch stops the comparison of values), the points, every
//! frame's time and points, and every attribute (its scope, type and
//! values; the state a `state` export carries is attributes too).

use groom::{Attribute, Groom, Units, UpAxis};
use serde::Serialize;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// How to compare.
#[derive(Debug, Clone)]
pub struct DiffOptions {
    /// Largest accepted deviation: metres for points (Euclidean distance),
    /// the attribute's own unit for attributes (largest component
    /// difference). Frame times must agree within 1 microsecond.
    pub tolerance: f64,
    /// How many of the largest deviations to list.
    pub listed: usize,
    /// Attributes left out of the comparison (an exporter's own, such as
    /// Alembic's `groom_guide`).
    pub ignore: Vec<String>,
}

impl Default for DiffOptions {
    fn default() -> Self {
        DiffOptions {
            tolerance: 1e-6,
            listed: 10,
            ignore: Vec::new(),
        }
    }
}

/// One value that differs: where, and by how much.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Deviation {
    /// `points` or `attribute <name>`.
    pub what: String,
    /// The frame (0-based) for animated points; `None` for the groom's own
    /// points and for attributes.
    pub frame: Option<usize>,
    pub strand: usize,
    /// The vertex within its strand (0 = root); `None` for per-strand values.
    pub vertex: Option<usize>,
    /// The vertex's index in the whole groom; `None` for per-strand values.
    pub global_vertex: Option<usize>,
    pub a: Vec<f32>,
    pub b: Vec<f32>,
    /// Distance (points) or largest component difference (attributes).
    pub amount: f64,
}

/// The outcome of a comparison.
#[derive(Debug, Clone, Serialize)]
pub struct DiffReport {
    /// Equal within the tolerance: no structural difference and no
    /// deviation above the tolerance.
    pub equal: bool,
    pub tolerance: f64,
    /// Differences of shape: counts, frames, attributes present in one only,
    /// scopes and types.
    pub structural: Vec<String>,
    /// Values compared (points of every frame plus attribute elements).
    pub compared: u64,
    /// Values that deviate by more than the tolerance.
    pub above_tolerance: u64,
    /// The largest deviation found (0 when none).
    pub max_deviation: f64,
    /// The largest deviations above the tolerance, largest first.
    pub largest: Vec<Deviation>,
}

/// A deviation ordered by amount (then by discovery, earlier first), for
/// a bounded min-heap of the largest.
struct Ranked(Deviation, u64);

impl PartialEq for Ranked {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Ranked {}
impl PartialOrd for Ranked {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Ranked {
    // Reversed so that BinaryHeap's top is the smallest kept deviation.
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .0
            .amount
            .total_cmp(&self.0.amount)
            .then(self.1.cmp(&other.1))
    }
}

/// Collects deviations, keeping the `listed` largest.
struct Collector {
    options: DiffOptions,
    heap: BinaryHeap<Ranked>,
    found: u64,
    compared: u64,
    max: f64,
}

impl Collector {
    fn offer(&mut self, amount: f64, make: impl FnOnce(f64) -> Deviation) {
        self.compared += 1;
        if amount > self.max || amount.is_nan() {
            self.max = if amount.is_nan() {
                f64::INFINITY
            } else {
                amount
            };
        }
        if amount <= self.options.tolerance {
            return;
        }
        self.found += 1;
        if self.options.listed == 0 {
            return;
        }
        let full = self.heap.len() >= self.options.listed;
        if full && self.heap.peek().is_some_and(|s| s.0.amount >= amount) {
            return;
        }
        self.heap.push(Ranked(make(amount), self.found));
        if self.heap.len() > self.options.listed {
            self.heap.pop();
        }
    }
}

/// Where element `index` of a vertex- or strand-scoped array lies.
fn locate(offsets: &[usize], index: usize, per_vertex: bool) -> (usize, Option<usize>) {
    if !per_vertex {
        return (index, None);
    }
    // `offsets` holds each strand's first vertex and the total at the end.
    let strand = offsets.partition_point(|&o| o <= index).saturating_sub(1);
    (strand, Some(index - offsets[strand]))
}

/// Difference of two values that may not be finite: equal non-finite
/// values (both NaN, or the same infinity) do not differ.
fn difference(a: f32, b: f32) -> f64 {
    if a == b || (a.is_nan() && b.is_nan()) {
        0.0
    } else {
        let d = (a as f64 - b as f64).abs();
        if d.is_finite() {
            d
        } else {
            f64::INFINITY
        }
    }
}

fn compare_points(
    collector: &mut Collector,
    offsets: &[usize],
    frame: Option<usize>,
    a: &[[f32; 3]],
    b: &[[f32; 3]],
) {
    for (index, (p, q)) in a.iter().zip(b).enumerate() {
        let squared: f64 = (0..3).map(|k| difference(p[k], q[k]).powi(2)).sum();
        collector.offer(squared.sqrt(), |amount| {
            let (strand, vertex) = locate(offsets, index, true);
            Deviation {
                what: "points".into(),
                frame,
                strand,
                vertex,
                global_vertex: Some(index),
                a: p.to_vec(),
                b: q.to_vec(),
                amount,
            }
        });
    }
}

fn compare_attribute(collector: &mut Collector, offsets: &[usize], a: &Attribute, b: &Attribute) {
    let width = a.values.components();
    let per_vertex = a.scope == groom::Scope::Vertex;
    let (fa, fb) = (a.values.to_f32_flat(), b.values.to_f32_flat());
    for (index, (ea, eb)) in fa.chunks(width).zip(fb.chunks(width)).enumerate() {
        let amount = ea
            .iter()
            .zip(eb)
            .map(|(&x, &y)| difference(x, y))
            .fold(0.0f64, f64::max);
        collector.offer(amount, |amount| {
            let (strand, vertex) = locate(offsets, index, per_vertex);
            Deviation {
                what: format!("attribute {}", a.name),
                frame: None,
                strand,
                vertex,
                global_vertex: per_vertex.then_some(index),
                a: ea.to_vec(),
                b: eb.to_vec(),
                amount,
            }
        });
    }
}

/// An attribute per vertex: a per-strand one's value repeated over each of
/// its strand's vertices.
fn per_vertex(attribute: &Attribute, groom: &Groom) -> Attribute {
    if attribute.scope == groom::Scope::Vertex {
        return attribute.clone();
    }
    let each_vertex: Vec<std::ops::Range<usize>> = groom
        .strand_vertex_counts
        .iter()
        .enumerate()
        .flat_map(|(strand, &n)| std::iter::repeat_n(strand..strand + 1, n as usize))
        .collect();
    Attribute {
        name: attribute.name.clone(),
        scope: groom::Scope::Vertex,
        values: attribute.values.select(&each_vertex),
    }
}

/// The first difference of topology, if any.
fn topology_difference(a: &Groom, b: &Groom) -> Option<String> {
    if a.strand_count() != b.strand_count() {
        return Some(format!(
            "strand count: {} in A, {} in B",
            a.strand_count(),
            b.strand_count()
        ));
    }
    let first = a
        .strand_vertex_counts
        .iter()
        .zip(&b.strand_vertex_counts)
        .position(|(x, y)| x != y)?;
    Some(format!(
        "vertex count of strand {first}: {} in A, {} in B",
        a.strand_vertex_counts[first], b.strand_vertex_counts[first]
    ))
}

fn compare_frames(
    collector: &mut Collector,
    structural: &mut Vec<String>,
    offsets: &[usize],
    a: &Groom,
    b: &Groom,
) {
    if a.frames.len() != b.frames.len() {
        structural.push(format!(
            "frame count: {} in A, {} in B",
            a.frames.len(),
            b.frames.len()
        ));
        return;
    }
    for (index, (fa, fb)) in a.frames.iter().zip(&b.frames).enumerate() {
        if (fa.time - fb.time).abs() > 1e-6 {
            structural.push(format!(
                "time of frame {index}: {} s in A, {} s in B",
                fa.time, fb.time
            ));
        }
        compare_points(collector, offsets, Some(index), &fa.points, &fb.points);
    }
}

fn compare_attributes(
    collector: &mut Collector,
    structural: &mut Vec<String>,
    offsets: &[usize],
    a: &Groom,
    b: &Groom,
) {
    let ignore = &collector.options.ignore;
    let kept = |attribute: &&Attribute| !ignore.contains(&attribute.name);
    let (a_kept, b_kept): (Vec<_>, Vec<_>) = (
        a.attributes.iter().filter(kept).collect(),
        b.attributes.iter().filter(kept).collect(),
    );
    for attribute in a_kept {
        let Some(other) = b.attribute(&attribute.name) else {
            structural.push(format!("attribute {} only in A", attribute.name));
            continue;
        };
        if attribute.scope != other.scope {
            // Per strand in one file and per vertex in the other (`.hair`
            // holds widths per vertex): the same data when every vertex of
            // a strand holds the strand's value, so compared per vertex.
            let (x, y) = (per_vertex(attribute, a), per_vertex(other, b));
            if x.values.components() == y.values.components() && x.values.len() == y.values.len() {
                compare_attribute(collector, offsets, &x, &y);
            } else {
                structural.push(format!(
                    "attribute {}: per {:?} in A, per {:?} in B",
                    attribute.name, attribute.scope, other.scope
                ));
            }
        } else if attribute.values.components() != other.values.components()
            || attribute.values.len() != other.values.len()
        {
            structural.push(format!(
                "attribute {}: {} x {} in A, {} x {} in B",
                attribute.name,
                attribute.values.len(),
                attribute.values.type_name(),
                other.values.len(),
                other.values.type_name()
            ));
        } else {
            compare_attribute(collector, offsets, attribute, other);
        }
    }
    for attribute in b_kept {
        if a.attribute(&attribute.name).is_none() {
            structural.push(format!("attribute {} only in B", attribute.name));
        }
    }
}

/// Compares two files read as sequences of topologies (a USD file whose
/// curve counts change over time is one groom per stretch of time): stretch
/// by stretch, when both have as many; a different number of stretches is
/// a structural difference. One groom each is [`diff`].
pub fn diff_sequences(a: &[Groom], b: &[Groom], options: &DiffOptions) -> DiffReport {
    if let ([a], [b]) = (a, b) {
        return diff(a, b, options);
    }
    let mut total = DiffReport {
        equal: a.len() == b.len(),
        tolerance: options.tolerance,
        structural: Vec::new(),
        compared: 0,
        above_tolerance: 0,
        max_deviation: 0.0,
        largest: Vec::new(),
    };
    if a.len() != b.len() {
        total.structural.push(format!(
            "topologies: A has {} stretches of time with their own curve counts, B {}",
            a.len(),
            b.len()
        ));
        return total;
    }
    for (index, (a, b)) in a.iter().zip(b).enumerate() {
        let report = diff(a, b, options);
        total.equal &= report.equal;
        total.structural.extend(
            report
                .structural
                .into_iter()
                .map(|s| format!("topology {index}: {s}")),
        );
        total.compared += report.compared;
        total.above_tolerance += report.above_tolerance;
        total.max_deviation = total.max_deviation.max(report.max_deviation);
        total
            .largest
            .extend(report.largest.into_iter().map(|mut d| {
                d.what = format!("topology {index}: {}", d.what);
                d
            }));
    }
    total.largest.sort_by(|x, y| y.amount.total_cmp(&x.amount));
    total.largest.truncate(options.listed);
    total
}

/// Compares two grooms in metres, Y up (each converted from its own units
/// and up axis).
pub fn diff(a: &Groom, b: &Groom, options: &DiffOptions) -> DiffReport {
    let mut a = a.clone();
    let mut b = b.clone();
    a.convert_to(Units::METERS, UpAxis::Y);
    b.convert_to(Units::METERS, UpAxis::Y);
    let mut structural = Vec::new();
    let mut collector = Collector {
        options: options.clone(),
        heap: BinaryHeap::new(),
        found: 0,
        compared: 0,
        max: 0.0,
    };
    match topology_difference(&a, &b) {
        Some(difference) => structural.push(difference),
        None => {
            let offsets = a.strand_offsets();
            compare_points(&mut collector, &offsets, None, &a.points, &b.points);
            compare_frames(&mut collector, &mut structural, &offsets, &a, &b);
            compare_attributes(&mut collector, &mut structural, &offsets, &a, &b);
        }
    }
    let mut largest: Vec<Ranked> = collector.heap.into_vec();
    // Ranked's order is reversed: ascending sort puts the largest first.
    largest.sort();
    DiffReport {
        equal: structural.is_empty() && collector.found == 0,
        tolerance: options.tolerance,
        structural,
        compared: collector.compared,
        above_tolerance: collector.found,
        max_deviation: collector.max,
        largest: largest.into_iter().map(|r| r.0).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use groom::{AttributeValues, Frame};

    fn groom() -> Groom {
        let mut g = Groom::from_strands([
            vec![[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![[1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [1.0, 2.0, 0.0]],
        ]);
        g.units = Units::METERS;
        g.set_attribute(Attribute::per_strand(
            "id",
            AttributeValues::Int(vec![7, 8]),
        ));
        g.frames = (0..3)
            .map(|k| Frame {
                time: k as f64 / 24.0,
                points: g.points.clone(),
                attributes: Vec::new(),
            })
            .collect();
        g
    }

    #[test]
    fn equal_grooms_are_equal() {
        let report = diff(&groom(), &groom(), &DiffOptions::default());
        assert!(report.equal, "{report:?}");
        assert_eq!(report.compared, 5 + 3 * 5 + 2);
        assert_eq!(report.max_deviation, 0.0);
    }

    #[test]
    fn a_moved_vertex_is_named_with_its_frame() {
        let mut b = groom();
        b.frames[2].points[3][2] += 3e-6;
        b.frames[1].points[0][0] += 0.5e-6; // within the tolerance
        let report = diff(&groom(), &b, &DiffOptions::default());
        assert!(!report.equal);
        assert_eq!(report.above_tolerance, 1);
        let d = &report.largest[0];
        assert_eq!((d.frame, d.strand, d.vertex), (Some(2), 1, Some(1)));
        assert!((d.amount - 3e-6).abs() < 1e-9, "{}", d.amount);
    }

    #[test]
    fn largest_come_first_and_are_bounded() {
        let mut b = groom();
        for (i, p) in b.points.iter_mut().enumerate() {
            p[0] += (i + 1) as f32 * 0.01;
        }
        let options = DiffOptions {
            listed: 2,
            ..DiffOptions::default()
        };
        let report = diff(&groom(), &b, &options);
        assert_eq!(report.above_tolerance, 5);
        let vertices: Vec<_> = report.largest.iter().map(|d| d.global_vertex).collect();
        assert_eq!(vertices, vec![Some(4), Some(3)]);
    }

    #[test]
    fn units_are_compared_in_metres() {
        let mut b = groom();
        b.convert_to(Units::CENTIMETERS, UpAxis::Z);
        assert!(diff(&groom(), &b, &DiffOptions::default()).equal);
    }

    #[test]
    fn a_per_strand_value_held_per_vertex_is_the_same_data() {
        let mut b = groom();
        b.set_attribute(Attribute {
            name: "id".into(),
            scope: groom::Scope::Vertex,
            values: AttributeValues::Int(vec![7, 7, 8, 8, 8]),
        });
        let report = diff(&groom(), &b, &DiffOptions::default());
        assert!(report.equal, "{report:?}");
        b.set_attribute(Attribute {
            name: "id".into(),
            scope: groom::Scope::Vertex,
            values: AttributeValues::Int(vec![7, 7, 8, 9, 8]),
        });
        let report = diff(&groom(), &b, &DiffOptions::default());
        assert!(!report.equal);
        let d = &report.largest[0];
        assert_eq!((d.strand, d.vertex), (1, Some(1)), "{d:?}");
    }

    #[test]
    fn structural_differences_are_listed() {
        let mut b = groom();
        b.remove_attribute("id");
        b.frames.pop();
        let report = diff(&groom(), &b, &DiffOptions::default());
        assert!(!report.equal);
        assert_eq!(
            report.structural,
            vec!["frame count: 3 in A, 2 in B", "attribute id only in A"]
        );
        let mut c = groom();
        c.strand_vertex_counts = vec![3, 2];
        let report = diff(&groom(), &c, &DiffOptions::default());
        assert_eq!(
            report.structural,
            vec!["vertex count of strand 0: 2 in A, 3 in B"]
        );
    }
}
