//! Checks of a groom's consistency, reporting every problem with its place.

use crate::{Frame, Groom, Scope};
use std::fmt;

/// What is wrong.
#[derive(Debug, Clone, PartialEq)]
pub enum ProblemKind {
    /// The strand counts do not add up to the number of points.
    CountMismatch { counted: u64, points: usize },
    /// A strand with no points at all.
    EmptyStrand,
    /// A strand of one point: USC-HairSalon's "no hair at this root" marker.
    /// Not fatal.
    SinglePointStrand,
    /// A coordinate is NaN or infinite.
    NonFinitePoint,
    /// An attribute has the wrong number of elements for its scope.
    AttributeLength {
        name: String,
        expected: usize,
        found: usize,
    },
    /// An attribute value is NaN or infinite.
    NonFiniteAttribute { name: String },
    /// A frame has a different number of points than the groom.
    FrameLength { expected: usize, found: usize },
    /// Frame times do not increase.
    FrameTimeOrder,
}

/// One problem found by [`Groom::validate`], with where it is.
#[derive(Debug, Clone, PartialEq)]
pub struct Problem {
    pub kind: ProblemKind,
    pub strand: Option<usize>,
    /// The vertex's index within `strand` (0 = root), as the message
    /// "strand S, vertex V" reads; the groom-wide index if no strand is known.
    pub vertex: Option<usize>,
    pub frame: Option<usize>,
}

impl Problem {
    /// True for problems that make the groom unusable; false for the ones
    /// that are only flagged (single-point strands).
    pub fn is_fatal(&self) -> bool {
        !matches!(self.kind, ProblemKind::SinglePointStrand)
    }

    fn new(kind: ProblemKind) -> Problem {
        Problem {
            kind,
            strand: None,
            vertex: None,
            frame: None,
        }
    }
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut place = Vec::new();
        if let Some(frame) = self.frame {
            place.push(format!("frame {frame}"));
        }
        if let Some(strand) = self.strand {
            place.push(format!("strand {strand}"));
        }
        if let Some(vertex) = self.vertex {
            place.push(format!("vertex {vertex}"));
        }
        if !place.is_empty() {
            write!(f, "{}: ", place.join(", "))?;
        }
        match &self.kind {
            ProblemKind::CountMismatch { counted, points } => write!(
                f,
                "strand vertex counts add up to {counted} but there are {points} points"
            ),
            ProblemKind::EmptyStrand => write!(f, "strand has no points"),
            ProblemKind::SinglePointStrand => {
                write!(f, "strand has a single point (no hair at this root)")
            }
            ProblemKind::NonFinitePoint => write!(f, "point is not finite"),
            ProblemKind::AttributeLength {
                name,
                expected,
                found,
            } => write!(
                f,
                "attribute '{name}' has {found} values, expected {expected}"
            ),
            ProblemKind::NonFiniteAttribute { name } => {
                write!(f, "attribute '{name}' has a value that is not finite")
            }
            ProblemKind::FrameLength { expected, found } => {
                write!(f, "frame has {found} points, expected {expected}")
            }
            ProblemKind::FrameTimeOrder => write!(f, "frame time does not increase"),
        }
    }
}

impl Groom {
    /// Every problem of the groom, each with its strand/vertex/frame index.
    /// Only fatal problems ([`Problem::is_fatal`]) make it unusable.
    pub fn validate(&self) -> Vec<Problem> {
        let mut problems = Vec::new();
        let counted: u64 = self.strand_vertex_counts.iter().map(|&c| c as u64).sum();
        if counted != self.points.len() as u64 {
            problems.push(Problem::new(ProblemKind::CountMismatch {
                counted,
                points: self.points.len(),
            }));
        }
        let mut start = 0usize;
        for (strand, &count) in self.strand_vertex_counts.iter().enumerate() {
            let kind = match count {
                0 => Some(ProblemKind::EmptyStrand),
                1 => Some(ProblemKind::SinglePointStrand),
                _ => None,
            };
            if let Some(kind) = kind {
                problems.push(Problem {
                    strand: Some(strand),
                    ..Problem::new(kind)
                });
            }
            let end = start.saturating_add(count as usize).min(self.points.len());
            if start < end {
                push_non_finite(&mut problems, &self.points[start..end], strand, None);
            }
            start = end;
        }
        for attribute in &self.attributes {
            let expected = match attribute.scope {
                Scope::Vertex => self.points.len(),
                Scope::Strand => self.strand_vertex_counts.len(),
            };
            let found = attribute.values.len();
            if found != expected {
                problems.push(Problem::new(ProblemKind::AttributeLength {
                    name: attribute.name.clone(),
                    expected,
                    found,
                }));
            }
            if let Some(index) = attribute.values.first_non_finite() {
                let (strand, vertex) = match attribute.scope {
                    Scope::Vertex => match self
                        .strand_ranges()
                        .enumerate()
                        .find(|(_, r)| r.contains(&index))
                    {
                        Some((strand, range)) => (Some(strand), Some(index - range.start)),
                        None => (None, Some(index)),
                    },
                    Scope::Strand => (Some(index), None),
                };
                problems.push(Problem {
                    strand,
                    vertex,
                    ..Problem::new(ProblemKind::NonFiniteAttribute {
                        name: attribute.name.clone(),
                    })
                });
            }
        }
        let mut previous_time = f64::NEG_INFINITY;
        for (index, frame) in self.frames.iter().enumerate() {
            problems.extend(self.validate_frame(index, frame, previous_time));
            previous_time = frame.time;
        }
        problems
    }

    /// The problems of frame `index` of this groom's topology, `frame`,
    /// given the time of the frame before it (`NEG_INFINITY` for the
    /// first): what [`Groom::validate`] finds in it, for a reader that
    /// holds one frame at a time.
    pub fn validate_frame(&self, index: usize, frame: &Frame, previous_time: f64) -> Vec<Problem> {
        let mut problems = Vec::new();
        if frame.points.len() != self.points.len() {
            problems.push(Problem {
                frame: Some(index),
                ..Problem::new(ProblemKind::FrameLength {
                    expected: self.points.len(),
                    found: frame.points.len(),
                })
            });
        } else {
            for (strand, range) in self.strand_ranges().enumerate() {
                push_non_finite(&mut problems, &frame.points[range], strand, Some(index));
            }
        }
        if frame.time.is_nan() || frame.time <= previous_time {
            problems.push(Problem {
                frame: Some(index),
                ..Problem::new(ProblemKind::FrameTimeOrder)
            });
        }
        problems
    }

    /// The first problem that makes the groom unusable, if any.
    pub fn first_fatal_problem(&self) -> Option<Problem> {
        self.validate().into_iter().find(Problem::is_fatal)
    }

    /// The range of point indices of each strand, clipped to the points.
    pub fn strand_ranges(&self) -> impl Iterator<Item = std::ops::Range<usize>> + '_ {
        let total = self.points.len();
        let mut start = 0usize;
        self.strand_vertex_counts.iter().map(move |&count| {
            let end = start.saturating_add(count as usize).min(total);
            let range = start..end;
            start = end;
            range
        })
    }

    /// The strand a vertex index belongs to.
    pub fn strand_of_vertex(&self, vertex: usize) -> Option<usize> {
        self.strand_ranges().position(|r| r.contains(&vertex))
    }
}

fn push_non_finite(
    problems: &mut Vec<Problem>,
    points: &[[f32; 3]],
    strand: usize,
    frame: Option<usize>,
) {
    for (offset, p) in points.iter().enumerate() {
        if !p.iter().all(|c| c.is_finite()) {
            problems.push(Problem {
                strand: Some(strand),
                vertex: Some(offset),
                frame,
                ..Problem::new(ProblemKind::NonFinitePoint)
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::{Attribute, AttributeValues, Frame, Groom};

    #[test]
    fn reports_every_problem_with_its_place() {
        let mut groom = Groom::from_strands([
            vec![[0.0, 0.0, 0.0]],
            vec![[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0]],
        ]);
        groom
            .attributes
            .push(Attribute::new("width", AttributeValues::Float(vec![1.0])));
        groom.frames.push(Frame {
            time: 0.0,
            points: vec![[0.0; 3]; 2],
            attributes: Vec::new(),
        });
        let problems = groom.validate();
        let text: Vec<String> = problems.iter().map(|p| p.to_string()).collect();
        assert_eq!(
            text,
            vec![
                "strand 0: strand has a single point (no hair at this root)",
                // Vertex 1 of strand 1 (the groom's third point).
                "strand 1, vertex 1: point is not finite",
                "attribute 'width' has 1 values, expected 3",
                "frame 0: frame has 2 points, expected 3",
            ]
        );
        assert!(!problems[0].is_fatal());
        assert!(problems[1].is_fatal());
    }

    #[test]
    fn problems_name_the_vertex_by_its_index_within_the_strand() {
        let mut groom = Groom::from_strands([
            vec![[0.0; 3], [0.0, 1.0, 0.0], [0.0, 2.0, 0.0]],
            vec![[1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [1.0, 2.0, 0.0]],
        ]);
        groom.attributes.push(Attribute::new(
            "width",
            AttributeValues::Float(vec![1.0, 1.0, 1.0, 1.0, f32::INFINITY, 1.0]),
        ));
        groom.frames.push(Frame {
            time: 0.0,
            points: {
                let mut points = groom.points.clone();
                points[5][1] = f32::NAN;
                points
            },
            attributes: Vec::new(),
        });
        let text: Vec<String> = groom.validate().iter().map(|p| p.to_string()).collect();
        assert_eq!(
            text,
            vec![
                "strand 1, vertex 1: attribute 'width' has a value that is not finite",
                "frame 0, strand 1, vertex 2: point is not finite",
            ]
        );
    }

    #[test]
    fn clean_groom_has_no_problems() {
        let groom = Groom::from_strands([vec![[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]]]);
        assert!(groom.validate().is_empty());
    }

    #[test]
    fn count_mismatch_is_reported() {
        let mut groom = Groom::from_strands([vec![[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]]]);
        groom.strand_vertex_counts[0] = 5;
        assert!(groom.validate().iter().any(|p| p.is_fatal()));
    }
}
