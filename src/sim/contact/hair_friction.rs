//! Coulomb friction between hairs (issue 33, item 1; METHOD I), the
//! physical model's pairwise hair-hair contact.
//!
//! At the start of a step every edge of an active strand finds the edges
//! of other strands it may touch in the step, and keeps one contact per
//! pair: where on its own edge the two segments come closest (`s`), the
//! other fibre's closest point and velocity, and the normal between them,
//! all from the start of the step. A pair may touch when the gap between
//! them is under two hair radii plus twice their closing distance in the
//! step (and under two radii plus twice the fastest hair's, at most an
//! edge). The search lists each edge in the cells of a uniform grid (the
//! cells, their walk and sort are grid.rs's, shared with the pairwise
//! penalty) within its own margin of its segment: two radii plus twice
//! its own motion in the step relative to one velocity common to all
//! edges (the mean of the hair's, when that gives smaller margins than
//! zero: hair falling or swinging together), so hair at rest, or moving
//! with the rest, is listed in the few small cells along it, and only
//! hair moving against the rest reaches further.
//!
//! Inside the strand's constraint solve the other fibre is a kinematic
//! target (Jacobi between strands: it moves on with its velocity at the
//! start of the step), exactly as a moving collider is:
//! - after each Newton iteration, [`project`] pushes the contact point
//!   (`(1 - s) p_e + s p_{e+1}`) back to two radii from the target along
//!   the contact normal (an inequality: never pulled in), spreading the
//!   push over the edge's two vertices (near a pinned root only as far as
//!   a bounded lever gets it, see [`spread`]), and marks them as touching
//!   for the next solve (`contact_normals`, as a collider contact does);
//! - after the last iteration, [`friction`] applies Coulomb's law at each
//!   touching vertex (the vertices nearest each contact point) to its
//!   motion over the step relative to the other fibre's: its tangential
//!   part is cancelled while it is at most `mu` times the normal push the
//!   contacts gave (static: the fibres stick), else reduced by that much
//!   (kinetic). This is the colliders' position-level friction
//!   (`Work::friction` in contact/solve.rs), which holds a strand on a slope within
//!   1 % of Coulomb's rates; a contact then gets one more solve, after
//!   which [`restick`] puts the stuck vertices back where they stuck (by
//!   at most a quarter of a radius: further, the strand pulled them off).
//!
//! Each strand reads only the other strands' state at the start of the
//! step and its own contacts in a fixed order, so the result is the same
//! for any thread count and group. Buffers are kept from step to step.

use super::grid::{
    bucket_bits, bucket_of, cells_near_segment, sort_into_buckets, unpack, Bucketed, SortScratch,
};
use crate::sim::math::{add, cross, dot, is_finite3, length, scale, sub, V3};

/// One contact of an edge of a strand with an edge of another strand.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct HairContact {
    /// The strand's edge (vertices `edge` and `edge + 1` of the strand).
    pub edge: u32,
    /// Where on that edge, `0..=1` from vertex `edge`.
    pub s: f32,
    /// The other fibre's closest point at the start of the step, m.
    pub other: V3,
    /// Its velocity at the start of the step, m/s.
    pub other_velocity: V3,
    /// Unit normal from the other fibre toward this strand.
    pub normal: V3,
}

/// Strands whose contacts one task finds (fixed, so the buffers and their
/// order do not depend on the thread count).
const CHUNK_STRANDS: usize = 32;
/// Edges per task when the grid is filled.
const CHUNK_EDGES: usize = 4096;
/// Cells per longest rest edge. An edge is listed only in the cells near
/// its segment (within its margin), so cells of an edge are few per edge
/// and hold few edges; per step of hair at rest on a head (300 strands x
/// 32), half-edge cells cost 1.3x the instructions and quarter-edge ones
/// 2.1x (an edge's margin then reaches more of them).
const CELLS_PER_REST_EDGE: f32 = 1.0;
/// Cells an edge may be listed in; an edge near more (torn, or moving a
/// rest edge in a step) is searched against every edge instead.
const MAX_NEAR_CELLS: usize = 512;
/// Such edges above which the cells are doubled.
const MAX_LONG_EDGES: usize = 64;
/// The span of an edge near too many cells.
const NOT_PLACED: (u32, u32) = (u32::MAX, u32::MAX);

/// An edge listed in one cell near it, with what a scan of the cell tests.
#[derive(Debug, Clone, Copy, Default)]
struct Placed {
    a: V3,
    b: V3,
    /// How near the edge may come to another this step (see `margin`), m.
    margin: f32,
    strand: u32,
    /// Global index of its first vertex.
    edge: u32,
    key: u32,
}

impl Bucketed for Placed {
    #[inline]
    fn cell_key(&self) -> u32 {
        self.key
    }
}

/// The contacts of every active strand's edges with other strands' edges,
/// found by [`HairContacts::build`] at the start of a step.
#[derive(Debug, Default)]
pub struct HairContacts {
    /// Centre distance a contact keeps: two hair radii, m.
    distance: f32,
    /// Coulomb's coefficient between hairs.
    mu: f32,
    /// The strand of each vertex of an active strand, `u32::MAX` otherwise.
    owner: Vec<u32>,
    /// Per chunk of edges, each edge in the cells near it; the edges near
    /// too many cells (searched against all); scratch for an edge's cells.
    placed_chunks: Vec<Vec<Placed>>,
    long_chunks: Vec<Vec<Placed>>,
    cell_chunks: Vec<Vec<u32>>,
    /// Per vertex, where the cells of the edge starting there are in its
    /// chunk of `placed_chunks` (the search reads them back); `(0, 0)`
    /// without an edge, `NOT_PLACED` for an edge near too many cells.
    spans: Vec<(u32, u32)>,
    /// All of them, sorted by bucket, and each bucket's start.
    placed: Vec<Placed>,
    starts: Vec<u32>,
    axis_bits: u32,
    /// The edges near too many cells, in edge order.
    long: Vec<Placed>,
    scratch: SortScratch<Placed>,
    /// Per chunk of strands: their contacts in strand then edge order, and
    /// each strand's range of them.
    chunks: Vec<Chunk>,
    /// Per strand, its contacts: (chunk, start, end) in `chunks`.
    ranges: Vec<(u32, u32, u32)>,
}

#[derive(Debug, Default)]
struct Chunk {
    contacts: Vec<HairContact>,
    ranges: Vec<(u32, u32)>,
    /// Scratch: the edges an edge found in its cells.
    found: Vec<u32>,
}

/// How near an edge (first vertex `v`) may come to another this step: the
/// contact distance `distance` plus twice the farthest its faster vertex
/// moves in `dt` relative to the step's common `reference` velocity (at
/// most `longest`). Two edges closer than the sum of their margins are all
/// the pairs the contact test below may keep: it asks for a gap under
/// `2 distance + 2 closing dt`, and the closing speed of two points of the
/// edges is at most the sum of the two edges' fastest vertices relative to
/// any one velocity both edges measure against (the triangle inequality;
/// a point's velocity is a blend of its vertices'), and under `reach`
/// (`2 distance + min(2 fastest dt, longest)`).
#[inline]
fn margin(velocities: &[V3], v: usize, reference: V3, distance: f32, longest: f32, dt: f32) -> f32 {
    let relative =
        length(sub(velocities[v], reference)).max(length(sub(velocities[v + 1], reference)));
    // (NaN or infinite speeds: the longest, like a fast edge. The pad
    // covers the round-off of the subtraction against the contact test's
    // own blend of the velocities.)
    distance + (2.0 * pad(relative, reference) * dt).min(longest)
}

/// A relative speed grown by the f32 round-off of measuring it against
/// `reference` rather than as a difference of two blended velocities.
#[inline]
fn pad(relative: f32, reference: V3) -> f32 {
    relative * (1.0 + 1e-4) + 1e-4 * length(reference)
}

/// The velocity the step's margins are measured against: the mean
/// velocity of the active vertices when margins relative to it are
/// smaller in all (hair that swings or falls together: the pairs' closing
/// speeds are small although the hair is fast), else zero (a few fast
/// strands would drag the mean away from hair at rest). Either choice
/// finds the same contacts; only the search's cost differs. Sums in fixed
/// chunks, in order: the same for any thread count.
fn reference_velocity(velocities: &[V3], owner: &[u32], longest: f32, dt: f32) -> V3 {
    use rayon::prelude::*;
    let active = |(v, o): (&V3, &u32)| *o != u32::MAX && is_finite3(*v);
    let sums: Vec<([f64; 3], usize)> = velocities
        .par_chunks(CHUNK_EDGES)
        .zip(owner.par_chunks(CHUNK_EDGES))
        .map(|(vs, os)| {
            let mut sum = [0.0f64; 3];
            let mut n = 0;
            for (v, _) in vs.iter().zip(os).filter(|&p| active(p)) {
                for k in 0..3 {
                    sum[k] += f64::from(v[k]);
                }
                n += 1;
            }
            (sum, n)
        })
        .collect();
    let (sum, n) = sums.iter().fold(([0.0f64; 3], 0usize), |(s, n), (c, m)| {
        ([s[0] + c[0], s[1] + c[1], s[2] + c[2]], n + m)
    });
    if n == 0 {
        return [0.0; 3];
    }
    let mean = sum.map(|s| (s / n as f64) as f32);
    if !is_finite3(mean) {
        return [0.0; 3];
    }
    // The search's cost grows with the margins' area around each edge:
    // compare the sums of the squared motions either way.
    let motion = |speed: f32| {
        let m = f64::from((2.0 * speed * dt).min(longest));
        m * m
    };
    let costs: Vec<(f64, f64)> = velocities
        .par_chunks(CHUNK_EDGES)
        .zip(owner.par_chunks(CHUNK_EDGES))
        .map(|(vs, os)| {
            vs.iter()
                .zip(os)
                .filter(|&p| active(p))
                .fold((0.0, 0.0), |(a, r), (v, _)| {
                    (
                        a + motion(length(*v)),
                        r + motion(pad(length(sub(*v, mean)), mean)),
                    )
                })
        })
        .collect();
    let (still, relative) = costs
        .iter()
        .fold((0.0, 0.0), |(a, r), (c, d)| (a + c, r + d));
    if relative < still {
        mean
    } else {
        [0.0; 3]
    }
}

/// The contact of edge `v` (`a`-`b`) with edge `f` (`c`-`d`) of another
/// strand, when they may touch in the step: their closest points are the
/// contact of their features, the gap between them is under `reach` and
/// under two contact `distance`s plus twice their closing distance in
/// `dt`. (`edge` of the result is left 0: the caller's.)
#[allow(clippy::too_many_arguments)]
#[inline]
fn contact(
    edge_of: &impl Fn(usize) -> Option<(u32, V3, V3)>,
    velocities: &[V3],
    v: usize,
    f: usize,
    a: V3,
    b: V3,
    c: V3,
    d: V3,
    reach: f32,
    distance: f32,
    dt: f32,
) -> Option<HairContact> {
    let (s, t) = closest_parameters(a, b, c, d);
    if !closest_feature(edge_of, v, f, s, t, a, c) {
        return None;
    }
    let (on_own, on_other) = (lerp3(a, b, s), lerp3(c, d, t));
    let gap = sub(on_own, on_other);
    let gap_length = length(gap);
    if gap_length.is_nan() || gap_length >= reach {
        return None;
    }
    let normal = if gap_length > 1e-3 * distance {
        scale(gap, 1.0 / gap_length)
    } else {
        // Crossing at their axes: across both.
        let across = cross(sub(b, a), sub(d, c));
        let l = length(across);
        if l.is_nan() || l <= 0.0 {
            return None;
        }
        scale(across, 1.0 / l)
    };
    let other_velocity = lerp3(velocities[f], velocities[f + 1], t);
    let own_velocity = lerp3(velocities[v], velocities[v + 1], s);
    // Only fibres that may touch in this step: two radii plus twice their
    // closing distance (a margin of the fastest hair's motion made hair
    // that falls together touch everything within millimetres).
    let closing = length(sub(own_velocity, other_velocity));
    if !is_finite3(other_velocity)
        || closing.is_nan()
        || gap_length >= 2.0 * distance + 2.0 * closing * dt
    {
        return None;
    }
    Some(HairContact {
        edge: 0,
        s,
        other: on_other,
        other_velocity,
        normal,
    })
}

/// The closest points of segments `p1`-`q1` and `p2`-`q2`: the parameters
/// `(s, t)` along each (Ericson, Real-Time Collision Detection, 5.1.9).
fn closest_parameters(p1: V3, q1: V3, p2: V3, q2: V3) -> (f32, f32) {
    let d1 = sub(q1, p1);
    let d2 = sub(q2, p2);
    let r = sub(p1, p2);
    let a = dot(d1, d1);
    let e = dot(d2, d2);
    let f = dot(d2, r);
    let tiny = 1e-20;
    if a <= tiny && e <= tiny {
        return (0.0, 0.0);
    }
    if a <= tiny {
        return (0.0, (f / e).clamp(0.0, 1.0));
    }
    let c = dot(d1, r);
    if e <= tiny {
        return ((-c / a).clamp(0.0, 1.0), 0.0);
    }
    let b = dot(d1, d2);
    let denom = a * e - b * b;
    let mut s = if denom > tiny * a * e {
        ((b * f - c * e) / denom).clamp(0.0, 1.0)
    } else {
        // Parallel: any point; the middle of the overlap is found below.
        0.5
    };
    let mut t = (b * s + f) / e;
    if t < 0.0 {
        t = 0.0;
        s = (-c / a).clamp(0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = ((b - c) / a).clamp(0.0, 1.0);
    }
    (s, t)
}

/// Whether the closest points `s` on edge `v` (from `a`) and `t` on edge
/// `f` (from `c`) are the contact of their features: a contact at a
/// vertex two edges share is kept once, by the edge that starts there,
/// and only when the other point does not lie across the previous edge
/// (which then has the contact inside it). Without this a fibre sliding
/// along another met a second, tilted contact at each of its vertices (a
/// bump every edge), and friction counted a shared vertex twice.
#[inline]
fn closest_feature(
    edge_of: &impl Fn(usize) -> Option<(u32, V3, V3)>,
    v: usize,
    f: usize,
    s: f32,
    t: f32,
    a: V3,
    c: V3,
) -> bool {
    // The next edge finds the vertex at its start.
    if (s == 1.0 && edge_of(v + 1).is_some()) || (t == 1.0 && edge_of(f + 1).is_some()) {
        return false;
    }
    // At an edge's start, the point across from it must not lie along the
    // previous edge (that edge has the contact inside it).
    let along_previous = |vertex: usize, start: V3, point: V3| {
        vertex > 0
            && edge_of(vertex - 1)
                .is_some_and(|(_, before, _)| dot(sub(point, start), sub(start, before)) < 0.0)
    };
    if s == 0.0 {
        if let Some((_, c0, d0)) = edge_of(f) {
            if along_previous(v, a, lerp3(c0, d0, t)) {
                return false;
            }
        }
    }
    if t == 0.0 {
        if let Some((_, a0, b0)) = edge_of(v) {
            if along_previous(f, c, lerp3(a0, b0, s)) {
                return false;
            }
        }
    }
    true
}

#[inline]
fn lerp3(a: V3, b: V3, t: f32) -> V3 {
    add(a, scale(sub(b, a), t))
}

impl HairContacts {
    /// Finds the contacts of the `active` strands (`offsets` as in
    /// StrandSet) at `positions` with `velocities`, for hair radius
    /// `radius` and Coulomb coefficient `mu`; `rest_longest` is the
    /// longest rest edge (sizes the cells), `dt` the step.
    ///
    /// Each edge is listed in the grid cells within its margin (see
    /// [`margin`]: its contact distance and how far it moves in the step
    /// relative to [`reference_velocity`])
    /// of its segment, cut where it crosses cell walls, and searches the
    /// cells it is listed in: two edges that may touch in the step share
    /// one. The edges it meets are tested in edge order, each once.
    #[allow(clippy::too_many_arguments)]
    pub fn build(
        &mut self,
        positions: &[V3],
        velocities: &[V3],
        offsets: &[usize],
        active: &[bool],
        radius: f32,
        mu: f32,
        rest_longest: f32,
        dt: f32,
    ) {
        use rayon::prelude::*;
        self.distance = 2.0 * radius;
        self.mu = mu;
        self.owner.clear();
        self.owner.resize(positions.len(), u32::MAX);
        for (strand, w) in offsets.windows(2).enumerate() {
            if active[strand] {
                self.owner[w[0]..w[1]].fill(strand as u32);
            }
        }
        let owner = &self.owner;
        let distance = self.distance;
        // The fastest vertex bounds how far two fibres close in a step: the
        // reach (capped at an edge, so a wild vertex cannot make the search
        // quadratic).
        let fastest = velocities
            .par_iter()
            .zip(owner.par_iter())
            .with_min_len(CHUNK_EDGES)
            .filter(|(v, o)| **o != u32::MAX && is_finite3(**v))
            .map(|(v, _)| length(*v))
            .reduce(|| 0.0, f32::max);
        let longest = if rest_longest.is_finite() && rest_longest > 0.0 {
            rest_longest
        } else {
            distance
        };
        let reach = 2.0 * distance + (2.0 * fastest * dt).min(longest);
        let reference = reference_velocity(velocities, owner, longest, dt);
        let edge_of = |v: usize| -> Option<(u32, V3, V3)> {
            let strand = owner[v];
            if strand == u32::MAX || owner.get(v + 1) != Some(&strand) {
                return None;
            }
            let (a, b) = (positions[v], positions[v + 1]);
            (is_finite3(a) && is_finite3(b)).then_some((strand, a, b))
        };

        // The grid: each edge in the cells near it; cells doubled while
        // too many edges are near too many of them.
        let edge_chunks = positions.len().div_ceil(CHUNK_EDGES);
        if self.placed_chunks.len() < edge_chunks {
            self.placed_chunks.resize_with(edge_chunks, Vec::new);
            self.long_chunks.resize_with(edge_chunks, Vec::new);
            self.cell_chunks.resize_with(edge_chunks, Vec::new);
        }
        let mut cell = (longest / CELLS_PER_REST_EDGE).max(2.0 * distance);
        self.spans.clear();
        self.spans.resize(positions.len(), (0, 0));
        loop {
            let inv_cell = 1.0 / cell;
            self.placed_chunks[..edge_chunks]
                .par_iter_mut()
                .zip(self.long_chunks[..edge_chunks].par_iter_mut())
                .zip(self.cell_chunks[..edge_chunks].par_iter_mut())
                .zip(self.spans.par_chunks_mut(CHUNK_EDGES))
                .enumerate()
                .for_each(|(k, (((out, long), cells), spans))| {
                    out.clear();
                    long.clear();
                    for v in k * CHUNK_EDGES..((k + 1) * CHUNK_EDGES).min(positions.len()) {
                        let Some((strand, a, b)) = edge_of(v) else {
                            spans[v - k * CHUNK_EDGES] = (0, 0);
                            continue;
                        };
                        let margin = margin(velocities, v, reference, distance, longest, dt);
                        let placed = |key| Placed {
                            a,
                            b,
                            margin,
                            strand,
                            edge: v as u32,
                            key,
                        };
                        spans[v - k * CHUNK_EDGES] =
                            if cells_near_segment(a, b, margin, inv_cell, MAX_NEAR_CELLS, cells) {
                                let start = out.len() as u32;
                                out.extend(cells.iter().map(|&key| placed(key)));
                                (start, out.len() as u32)
                            } else {
                                long.push(placed(0));
                                NOT_PLACED
                            };
                    }
                });
            let long: usize = self.long_chunks[..edge_chunks].iter().map(Vec::len).sum();
            if long <= MAX_LONG_EDGES || cell >= f32::MAX / 4.0 {
                break;
            }
            cell *= 2.0;
        }
        self.long.clear();
        for long in &self.long_chunks[..edge_chunks] {
            self.long.extend_from_slice(long);
        }
        let total: usize = self.placed_chunks[..edge_chunks].iter().map(Vec::len).sum();
        self.axis_bits = bucket_bits(total);
        sort_into_buckets(
            &self.placed_chunks[..edge_chunks],
            self.axis_bits,
            &mut self.scratch,
            &mut self.starts,
            &mut self.placed,
        );

        // Each strand's contacts, in fixed chunks of strands.
        let strands = offsets.len().saturating_sub(1);
        let strand_chunks = strands.div_ceil(CHUNK_STRANDS);
        if self.chunks.len() < strand_chunks {
            self.chunks.resize_with(strand_chunks, Default::default);
        }
        let (placed, starts, long, bits) = (&self.placed, &self.starts, &self.long, self.axis_bits);
        let (spans, placed_chunks) = (&self.spans, &self.placed_chunks);
        self.chunks[..strand_chunks]
            .par_iter_mut()
            .enumerate()
            .for_each(|(k, chunk)| {
                let Chunk {
                    contacts: out,
                    ranges,
                    found,
                } = chunk;
                out.clear();
                ranges.clear();
                for strand in k * CHUNK_STRANDS..((k + 1) * CHUNK_STRANDS).min(strands) {
                    let begin = out.len() as u32;
                    if !active[strand] {
                        ranges.push((begin, begin));
                        continue;
                    }
                    let first = offsets[strand];
                    for v in first..offsets[strand + 1] {
                        let Some((own, a, b)) = edge_of(v) else {
                            continue;
                        };
                        let margin = margin(velocities, v, reference, distance, longest, dt);
                        // Boxes apart by more than the two margins: no
                        // contact (most edges of a cell).
                        let near = |e: &Placed| {
                            let m = margin + e.margin;
                            e.strand != own
                                && (0..3).all(|k| {
                                    a[k].min(b[k]) <= e.a[k].max(e.b[k]) + m
                                        && a[k].max(b[k]) + m >= e.a[k].min(e.b[k])
                                })
                        };
                        found.clear();
                        let span = spans[v];
                        if span != NOT_PLACED {
                            let cells =
                                &placed_chunks[v / CHUNK_EDGES][span.0 as usize..span.1 as usize];
                            for &Placed { key, .. } in cells {
                                let bucket = bucket_of(unpack(key), bits);
                                let (from, to) =
                                    (starts[bucket] as usize, starts[bucket + 1] as usize);
                                found.extend(
                                    placed[from..to]
                                        .iter()
                                        .filter(|e| e.key == key && near(e))
                                        .map(|e| e.edge),
                                );
                            }
                        } else {
                            // Near too many cells: every edge.
                            found.extend(placed.iter().filter(|e| near(e)).map(|e| e.edge));
                        }
                        found.extend(long.iter().filter(|e| near(e)).map(|e| e.edge));
                        found.sort_unstable();
                        found.dedup();
                        for &other in found.iter() {
                            let f = other as usize;
                            let (c, d) = (positions[f], positions[f + 1]);
                            if let Some(contact) =
                                contact(&edge_of, velocities, v, f, a, b, c, d, reach, distance, dt)
                            {
                                out.push(HairContact {
                                    edge: (v - first) as u32,
                                    ..contact
                                });
                            }
                        }
                    }
                    ranges.push((begin, out.len() as u32));
                }
            });
        self.ranges.clear();
        for (k, chunk) in self.chunks[..strand_chunks].iter().enumerate() {
            self.ranges
                .extend(chunk.ranges.iter().map(|&(a, b)| (k as u32, a, b)));
        }
    }

    /// The contacts of strand `strand` found by the last build.
    #[inline]
    pub(crate) fn of(&self, strand: usize) -> &[HairContact] {
        match self.ranges.get(strand) {
            Some(&(chunk, start, end)) => self
                .chunks
                .get(chunk as usize)
                .and_then(|c| c.contacts.get(start as usize..end as usize))
                .unwrap_or(&[]),
            None => &[],
        }
    }

    /// How many contacts the last build found.
    pub fn count(&self) -> usize {
        self.ranges
            .iter()
            .map(|&(_, start, end)| (end - start) as usize)
            .sum()
    }

    /// Coulomb's coefficient of the last build.
    #[inline]
    pub(crate) fn mu(&self) -> f32 {
        self.mu
    }

    /// The centre distance contacts keep, m.
    #[inline]
    pub(crate) fn distance(&self) -> f32 {
        self.distance
    }
}

/// The weights of an edge's two vertices at `s` for a push of the contact
/// point (only free vertices move), and the push's divisor (the contact
/// point moves by `(w_a (1 - s) + w_b s)` times the vertices' move).
///
/// The divisor is at least [`MIN_DIVISOR`], its value for two free
/// vertices at the middle of the edge: a contact near a pinned vertex (a
/// root, in a dense groom where every root edge lies among others) moves
/// the free vertex at most 1.5 times the overlap (`2 s` times it for
/// `s <= 1/2`), instead of swinging that vertex by `gap / s` (a 10 um
/// overlap 2 % along the root edge threw vertex 1 half a millimetre, and
/// a dense tuft blew up: hair_friction_tests.rs). The rest of such an
/// overlap is where the roots are: the roots hold it, not the hair.
#[inline]
fn spread(s: f32, free_a: f32, free_b: f32) -> Option<(f32, f32, f32)> {
    let (wa, wb) = ((1.0 - s) * free_a.min(1.0), s * free_b.min(1.0));
    let divisor = wa * (1.0 - s) + wb * s;
    (divisor > 1e-6).then_some((wa, wb, divisor.max(MIN_DIVISOR)))
}

/// The smallest divisor of a contact's push ([`spread`]).
const MIN_DIVISOR: f32 = 0.5;

/// Pushes each contact point of the strand (`p`, free where `free > 0`)
/// out to `distance` from the other fibre's point where it is at the end of
/// the step, along the contact normal, and marks the pushed vertices in
/// `normals` for the solve. The pushes are averaged per vertex (Jacobi):
/// one after the other, the contacts in the middle of successive edges
/// of a strand lying across others pushed each shared vertex twice and
/// threw the strand up by half a radius. `push` is scratch (one per
/// vertex). Returns whether a vertex moved more than `tolerance`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn project(
    contacts: &[HairContact],
    push: &mut [VertexContact],
    p: &mut [V3],
    free: &[f32],
    normals: &mut [V3],
    distance: f32,
    dt: f32,
    tolerance: f32,
) -> bool {
    let mut any = false;
    for c in contacts {
        let (a, b) = (c.edge as usize, c.edge as usize + 1);
        let Some((wa, wb, divisor)) = spread(c.s, free[a], free[b]) else {
            continue;
        };
        let target = add(c.other, scale(c.other_velocity, dt));
        let point = lerp3(p[a], p[b], c.s);
        let gap = dot(sub(point, target), c.normal) - distance;
        if gap >= 0.0 {
            continue;
        }
        if !any {
            push.fill(VertexContact::default());
            any = true;
        }
        let out = scale(c.normal, -gap / divisor);
        for (i, w) in [(a, wa), (b, wb)] {
            if w > 0.0 {
                let v = &mut push[i];
                v.normal = add(v.normal, scale(out, w));
                v.weight += 1.0;
                normals[i] = c.normal;
            }
        }
    }
    let mut moved = false;
    if any {
        for (p, v) in p.iter_mut().zip(push.iter()) {
            if v.weight > 0.0 {
                let step = scale(v.normal, 1.0 / v.weight);
                *p = add(*p, step);
                moved |= length(step) > tolerance;
            }
        }
    }
    moved
}

/// A vertex's share of its contacts with other strands: the contact
/// normals and the other fibres' velocities, weighted by how near the
/// vertex each contact point is.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct VertexContact {
    normal: V3,
    velocity: V3,
    weight: f32,
}

/// The smallest share of a contact that makes a vertex touch (the nearer
/// vertex of a contact point always does).
const TOUCH_SHARE: f32 = 0.25;

/// The farthest [`restick`] puts a stuck vertex back, in hair radii: a
/// resting strand creeps by micrometres a step, a strand pulled off its
/// contact moves much further (gravity alone moves hair 76 um in a step of
/// 1/360 s).
pub(crate) const RESTICK_CAP: f32 = 0.25;

/// Coulomb friction at each touching vertex after the solve, as the
/// colliders' (`Work::friction` in contact/solve.rs): the vertex's motion over the
/// step relative to the fibres it touches (at `start` when the step began,
/// `predicted` before any contact), along their contact plane, is
/// cancelled while it is at most `mu` times the normal push from the
/// prediction (static), else shortened by that much (kinetic). Per vertex,
/// so a contact found through two edges that share a vertex (or a fibre
/// touching two edges of the other at their shared vertex) counts once.
/// `touch` is scratch (one per vertex); `stuck` (one per vertex) is set
/// for the vertices that stuck, for [`restick`]. Returns whether a vertex
/// moved more than `tolerance`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn friction(
    contacts: &[HairContact],
    touch: &mut [VertexContact],
    stuck: &mut [bool],
    p: &mut [V3],
    start: &[V3],
    predicted: &[V3],
    free: &[f32],
    mu: f32,
    dt: f32,
    tolerance: f32,
) -> bool {
    let mut moved = false;
    stuck.fill(false);
    if mu <= 0.0 {
        return false;
    }
    gather_touch(contacts, touch, free);
    for i in 0..p.len() {
        let t = touch[i];
        if t.weight <= 0.0 {
            continue;
        }
        let l = length(t.normal);
        if l.is_nan() || l <= 0.0 {
            continue;
        }
        let normal = scale(t.normal, 1.0 / l);
        let pushed = dot(sub(p[i], predicted[i]), normal).max(0.0);
        if pushed <= 0.0 {
            continue;
        }
        let other = scale(t.velocity, dt / t.weight);
        let relative = sub(sub(p[i], start[i]), other);
        let tangential = sub(relative, scale(normal, dot(relative, normal)));
        let slide = length(tangential);
        if slide == 0.0 {
            stuck[i] = true;
            continue;
        }
        stuck[i] = slide <= mu * pushed;
        let held = if stuck[i] { 1.0 } else { mu * pushed / slide };
        p[i] = sub(p[i], scale(tangential, held));
        moved |= held * slide > tolerance;
    }
    moved
}

/// Each free vertex's share of the contacts (`touch`, one per vertex).
fn gather_touch(contacts: &[HairContact], touch: &mut [VertexContact], free: &[f32]) {
    touch.fill(VertexContact::default());
    for c in contacts {
        for (i, share) in [(c.edge as usize, 1.0 - c.s), (c.edge as usize + 1, c.s)] {
            if share >= TOUCH_SHARE && free[i] > 0.0 {
                let t = &mut touch[i];
                t.normal = add(t.normal, scale(c.normal, share));
                t.velocity = add(t.velocity, scale(c.other_velocity, share));
                t.weight += share;
            }
        }
    }
}

/// After the solve that follows [`friction`]: the vertices that stuck are
/// put back where they stuck (relative to the fibres they touch),
/// cancelling the little that solve slid them along the contact plane:
/// at most `cap` (m). A vertex the solve slid further was pulled off by its
/// own strand harder than the contact held it: it stays where the solve put
/// it, since putting it back after the last solve, with nothing to solve
/// after, strained its edges (tips of a swatch draped over a cylinder by
/// 12 %).
pub(crate) fn restick(
    touch: &[VertexContact],
    stuck: &[bool],
    p: &mut [V3],
    start: &[V3],
    dt: f32,
    cap: f32,
) {
    for i in 0..p.len() {
        let t = touch[i];
        let l = length(t.normal);
        if !stuck[i] || t.weight <= 0.0 || l.is_nan() || l <= 0.0 {
            continue;
        }
        let normal = scale(t.normal, 1.0 / l);
        let other = scale(t.velocity, dt / t.weight);
        let relative = sub(sub(p[i], start[i]), other);
        let slide = sub(relative, scale(normal, dot(relative, normal)));
        if length(slide) <= cap {
            p[i] = sub(p[i], slide);
        }
    }
}

#[cfg(test)]
mod search_tests;
