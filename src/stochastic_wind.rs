//! The stochastic wind model of Agui, Miwa, Nakajima (`001_*`, METHOD F):
//! each hair is a chain of segments whose angles take random angular
//! accelerations around a mean that pulls them toward the wind, computed
//! root to tip once per model frame. Wind direction and strength at each
//! root come from 2-D potential flow around a cylinder head; an ellipsoid
//! around the head keeps segment ends outside it (an end sent inside turns
//! about its segment's start onto the surface, and the head stops that
//! segment). The model adds no damping: over the paper's 10 frames the
//! hair keeps moving (the mean pull, 1-2 % of the angle's distance from the
//! wind per frame squared, takes 11-16 frames to swing a segment there).
//!
//! Angles: `theta` is the azimuth of a segment's XZ projection measured from
//! +Z toward +X, `phi` the angle from -Y (hanging straight down); a negative
//! `phi` leans toward `theta + pi`. Y is up.

use crate::generate::SplitMix64;
use std::f64::consts::{FRAC_PI_2, PI};

/// The head as the model sees it.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct WindHead {
    /// Centre of the head (and the axis of the flow cylinder, along Y), metres.
    pub center: [f64; 3],
    /// Semi-axes of the ellipsoid that encloses the head, metres.
    pub radii: [f64; 3],
}

/// One chain of segments.
#[derive(Debug, Clone)]
struct Chain {
    root: [f64; 3],
    lengths: Vec<f64>,
    theta: Vec<f64>,
    phi: Vec<f64>,
    theta_velocity: Vec<f64>,
    phi_velocity: Vec<f64>,
}

/// The model's state for a whole groom.
#[derive(Debug, Clone)]
pub struct StochasticWind {
    chains: Vec<Chain>,
    head: WindHead,
    random: SplitMix64,
}

/// Wraps an angle to (-pi, pi] (`in_range` of the paper).
pub fn wrap_angle(x: f64) -> f64 {
    let mut y = x % (2.0 * PI);
    if y <= -PI {
        y += 2.0 * PI;
    } else if y > PI {
        y -= 2.0 * PI;
    }
    y
}

/// Segment direction from its angles.
fn direction(theta: f64, phi: f64) -> [f64; 3] {
    [phi.sin() * theta.sin(), -phi.cos(), phi.sin() * theta.cos()]
}

/// Angles of a segment direction (need not be unit).
fn angles(d: [f64; 3]) -> (f64, f64) {
    let horizontal = (d[0] * d[0] + d[2] * d[2]).sqrt();
    let phi = horizontal.atan2(-d[1]);
    let theta = if horizontal > 0.0 {
        d[0].atan2(d[2])
    } else {
        0.0
    };
    (theta, phi)
}

/// Per-segment parameters (25)-(29), in radians; `i` from the root.
struct SegmentParameters {
    theta_spread: f64,
    phi_spread: f64,
    theta_limit: f64,
    phi_limit: f64,
    slope: f64,
}

fn segment_parameters(i: usize, segments: usize) -> SegmentParameters {
    let s = i as f64 / segments as f64;
    SegmentParameters {
        theta_spread: (1.0 + 3.0 * s).to_radians(),
        phi_spread: (3.0 + 3.0 * s).to_radians(),
        theta_limit: (2.0 + 5.0 * s).to_radians(),
        phi_limit: (10.0 + 5.0 * s).to_radians(),
        // (29) gives the slope "in degrees"; it multiplies an angle
        // difference, so it is a pure number.
        slope: -(1.0 + s) / 100.0,
    }
}

impl WindHead {
    /// `sum ((p - center) / radii)^2`: below 1 inside the ellipsoid.
    fn level(&self, p: [f64; 3]) -> f64 {
        (0..3)
            .map(|k| ((p[k] - self.center[k]) / self.radii[k]).powi(2))
            .sum()
    }

    /// The unit direction, if `d` is not one, in which a segment of
    /// `length` from `start` ends on or outside the ellipsoid: `d` turned
    /// toward the ellipsoid's outward normal at `start` by the smallest
    /// angle that brings the end out (the end then lies on the surface).
    /// The paper moves an end inside to the nearest surface point (line 261
    /// of 001_*); that point is nearer the start than the segment's length,
    /// and stretching the segment back to its length along the same line
    /// sends the end through the surface again. Turning toward the normal
    /// always gets out when `start` lies on or outside the ellipsoid (it is
    /// convex); from a start inside it, the segment points straight out.
    fn keep_outside(&self, start: [f64; 3], d: [f64; 3], length: f64) -> Option<[f64; 3]> {
        let end = |dir: [f64; 3]| [0, 1, 2].map(|k| start[k] + dir[k] * length);
        if self.level(end(d)) >= 1.0 {
            return None;
        }
        let normal = unit([0, 1, 2].map(|k| (start[k] - self.center[k]) / self.radii[k].powi(2)))
            .unwrap_or([0.0, 1.0, 0.0]);
        let along = dot(d, normal);
        // The unit vector in the plane of `d` and the normal, at right
        // angles to `d`, toward the normal (any one when they are parallel).
        let across = unit([0, 1, 2].map(|k| normal[k] - along * d[k]))
            .or_else(|| unit([d[1], -d[0], 0.0]))
            .or_else(|| unit([0.0, d[2], -d[1]]))
            .unwrap_or([1.0, 0.0, 0.0]);
        let turned = |angle: f64| [0, 1, 2].map(|k| angle.cos() * d[k] + angle.sin() * across[k]);
        let full = along.clamp(-1.0, 1.0).acos();
        if self.level(end(turned(full))) < 1.0 {
            return Some(turned(full));
        }
        // The end is inside at angle 0 and outside at `full`: bisect,
        // keeping the outside end.
        let (mut inside, mut outside) = (0.0, full);
        for _ in 0..60 {
            let mid = 0.5 * (inside + outside);
            if self.level(end(turned(mid))) < 1.0 {
                inside = mid;
            } else {
                outside = mid;
            }
        }
        Some(turned(outside))
    }
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `v` scaled to unit length, or `None` if it is (nearly) zero.
fn unit(v: [f64; 3]) -> Option<[f64; 3]> {
    let n = dot(v, v).sqrt();
    (n > 1e-12).then(|| v.map(|x| x / n))
}

impl StochasticWind {
    /// Starts the model from strands' current shapes (positions in metres,
    /// Y up), all angular velocities zero.
    pub fn new(strands: &[Vec<[f64; 3]>], head: WindHead, seed: u64) -> StochasticWind {
        let chains = strands
            .iter()
            .map(|points| {
                let mut chain = Chain {
                    root: points.first().copied().unwrap_or([0.0; 3]),
                    lengths: Vec::new(),
                    theta: Vec::new(),
                    phi: Vec::new(),
                    theta_velocity: Vec::new(),
                    phi_velocity: Vec::new(),
                };
                for w in points.windows(2) {
                    let d = [w[1][0] - w[0][0], w[1][1] - w[0][1], w[1][2] - w[0][2]];
                    let (theta, phi) = angles(d);
                    chain
                        .lengths
                        .push((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt());
                    chain.theta.push(theta);
                    chain.phi.push(phi);
                    chain.theta_velocity.push(0.0);
                    chain.phi_velocity.push(0.0);
                }
                chain
            })
            .collect();
        StochasticWind {
            chains,
            head,
            random: SplitMix64::new(seed),
        }
    }

    /// `theta_1, phi_1` at a root for flow direction `theta_u` and strength
    /// `v` in [0, 1]: (23)-(24). `theta_1` is the surface tangent (the
    /// direction of increasing root azimuth); the sign of `phi_1` says which
    /// way along it the flow goes.
    pub fn wind_targets(&self, root: [f64; 3], theta_u: f64, v: f64) -> (f64, f64) {
        let x = root[0] - self.head.center[0];
        let z = root[2] - self.head.center[2];
        let root_azimuth = x.atan2(z);
        let theta_1 = wrap_angle(root_azimuth + FRAC_PI_2);
        let phi_1 = -v * FRAC_PI_2 * (PI - theta_u + root_azimuth).sin();
        (theta_1, phi_1)
    }

    /// Advances every hair by one model frame (1)-(12) under a flow from
    /// azimuth `theta_u` (radians) of strength `v` in [0, 1].
    pub fn advance(&mut self, theta_u: f64, v: f64) {
        let head = self.head;
        for index in 0..self.chains.len() {
            let root = self.chains[index].root;
            let (theta_1, phi_1) = self.wind_targets(root, theta_u, v);
            let random = &mut self.random;
            let chain = &mut self.chains[index];
            let segments = chain.theta.len();
            let mut start = root;
            for i in 0..segments {
                let p = segment_parameters(i, segments);
                let (theta, phi) = (chain.theta[i], chain.phi[i]);
                let th_acc = p.slope * wrap_angle(theta - theta_1)
                    + random.next_normal() * p.theta_spread / 6.0;
                let th_turn = if phi.abs() < 0.3 {
                    // Near vertical the azimuth is free: a normal random in
                    // about [-6, 6] degrees (3 sigma).
                    random.next_normal() * 2f64.to_radians()
                } else {
                    th_acc / phi.sin().abs()
                };
                let mut th_v = chain.theta_velocity[i] + th_turn;
                let mut new_theta = wrap_angle(theta + th_v);
                let ph_acc =
                    p.slope * wrap_angle(phi - phi_1) + random.next_normal() * p.phi_spread / 6.0;
                let mut ph_v = chain.phi_velocity[i] + ph_acc;
                let mut new_phi = wrap_angle(phi + ph_v);
                if i > 0 {
                    let (prev_theta, prev_phi) = (chain.theta[i - 1], chain.phi[i - 1]);
                    let dt = wrap_angle(new_theta - prev_theta);
                    if dt.abs() > p.theta_limit {
                        if chain.theta_velocity[i] == 0.0 {
                            new_theta = theta;
                        } else {
                            new_theta = wrap_angle(prev_theta + p.theta_limit.copysign(dt));
                        }
                        th_v = 0.0;
                    }
                    let dp = wrap_angle(new_phi - prev_phi);
                    if dp.abs() > p.phi_limit {
                        if chain.phi_velocity[i] == 0.0 {
                            new_phi = phi;
                        } else {
                            new_phi = wrap_angle(prev_phi + p.phi_limit.copysign(dp));
                        }
                        ph_v = 0.0;
                    }
                }
                let length = chain.lengths[i];
                let mut d = direction(new_theta, new_phi);
                // Head collision: an end inside the ellipsoid moves onto its
                // surface, the segment keeping its length; the head stops
                // the segment (its angular velocities are zeroed, as at the
                // model's own angle limits), so it does not keep pushing in.
                if let Some(turned) = head.keep_outside(start, d, length) {
                    d = turned;
                    (new_theta, new_phi) = angles(d);
                    th_v = 0.0;
                    ph_v = 0.0;
                }
                let end = [
                    start[0] + d[0] * length,
                    start[1] + d[1] * length,
                    start[2] + d[2] * length,
                ];
                chain.theta[i] = new_theta;
                chain.phi[i] = new_phi;
                chain.theta_velocity[i] = th_v;
                chain.phi_velocity[i] = ph_v;
                start = end;
            }
        }
    }

    /// Current points of every hair, root first.
    pub fn points(&self) -> Vec<Vec<[f64; 3]>> {
        self.chains
            .iter()
            .map(|chain| {
                let mut points = Vec::with_capacity(chain.lengths.len() + 1);
                let mut p = chain.root;
                points.push(p);
                for i in 0..chain.lengths.len() {
                    let d = direction(chain.theta[i], chain.phi[i]);
                    p = [
                        p[0] + d[0] * chain.lengths[i],
                        p[1] + d[1] * chain.lengths[i],
                        p[2] + d[2] * chain.lengths[i],
                    ];
                    points.push(p);
                }
                points
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hanging(root: [f64; 3], segments: usize, length: f64) -> Vec<[f64; 3]> {
        (0..=segments)
            .map(|i| [root[0], root[1] - i as f64 * length, root[2]])
            .collect()
    }

    fn head() -> WindHead {
        WindHead {
            center: [0.0, 0.0, 0.0],
            radii: [0.08, 0.1, 0.09],
        }
    }

    #[test]
    fn angles_round_trip() {
        for &(t, p) in &[(0.3, 0.5), (-2.0, 1.2), (3.0, 2.5)] {
            let (t2, p2) = angles(direction(t, p));
            assert!((wrap_angle(t2 - t)).abs() < 1e-12 && (p2 - p).abs() < 1e-12);
        }
        assert_eq!(wrap_angle(3.0 * PI), PI);
        assert!((wrap_angle(-PI) - PI).abs() < 1e-15);
    }

    #[test]
    fn flow_tangent_and_strength_follow_potential_flow() {
        let wind = StochasticWind::new(&[], head(), 1);
        // A root facing the flow head-on (azimuth = theta_u - pi) sits at a
        // stagnation point: no strength.
        let theta_u = 178f64.to_radians();
        let azimuth = theta_u - PI;
        let root = [0.09 * azimuth.sin(), 0.0, 0.09 * azimuth.cos()];
        let (_, phi_1) = wind.wind_targets(root, theta_u, 0.8);
        assert!(phi_1.abs() < 1e-12);
        // At 90 degrees from it the tangential flow is strongest: |phi_1| = V pi/2.
        let side = azimuth + FRAC_PI_2;
        let root = [0.09 * side.sin(), 0.0, 0.09 * side.cos()];
        let (theta_1, phi_1) = wind.wind_targets(root, theta_u, 0.8);
        assert!((phi_1.abs() - 0.8 * FRAC_PI_2).abs() < 1e-12);
        assert!((wrap_angle(theta_1 - side - FRAC_PI_2)).abs() < 1e-12);
    }

    #[test]
    fn wind_lifts_hair_and_keeps_segment_lengths_and_head_clear() {
        let roots: Vec<[f64; 3]> = (0..16)
            .map(|k| {
                let a = k as f64 / 16.0 * 2.0 * PI;
                [0.085 * a.sin(), 0.0, 0.095 * a.cos()]
            })
            .collect();
        let strands: Vec<_> = roots.iter().map(|&r| hanging(r, 20, 0.012)).collect();
        let mut wind = StochasticWind::new(&strands, head(), 7);
        for _ in 0..10 {
            wind.advance(178f64.to_radians(), 0.8);
        }
        let points = wind.points();
        let mut lifted = 0;
        for strand in &points {
            for w in strand.windows(2) {
                let l = ((w[1][0] - w[0][0]).powi(2)
                    + (w[1][1] - w[0][1]).powi(2)
                    + (w[1][2] - w[0][2]).powi(2))
                .sqrt();
                assert!((l - 0.012).abs() < 1e-9);
            }
            for p in &strand[1..] {
                let inside: f64 = (0..3).map(|k| (p[k] / head().radii[k]).powi(2)).sum();
                assert!(
                    inside >= 1.0 - 1e-9,
                    "segment end inside the head: {inside}"
                );
            }
            if strand[20][1] > strand[0][1] - 20.0 * 0.012 + 1e-3 {
                lifted += 1;
            }
        }
        assert!(lifted >= 12, "wind lifted only {lifted} of 16 hairs");
    }

    /// Hair combed over the head: from roots on the ellipsoid down its
    /// meridians, each end 0.5 mm off the surface, as the head generator
    /// lays it.
    fn combed(head: WindHead, strands: usize, segments: usize, length: f64) -> Vec<Vec<[f64; 3]>> {
        (0..strands)
            .map(|k| {
                let azimuth = k as f64 / strands as f64 * 2.0 * PI;
                let on = |polar: f64, lift: f64| {
                    let u = [
                        polar.sin() * azimuth.sin(),
                        polar.cos(),
                        polar.sin() * azimuth.cos(),
                    ];
                    [0, 1, 2].map(|i| u[i] * (head.radii[i] + lift) + head.center[i])
                };
                let mut points = vec![on(0.3, 0.0)];
                let mut polar = 0.3;
                while points.len() <= segments {
                    // March down the meridian until one segment length away.
                    let last = *points.last().unwrap();
                    let mut next = on(polar, 5e-4);
                    while polar < PI
                        && (0..3)
                            .map(|i| (next[i] - last[i]).powi(2))
                            .sum::<f64>()
                            .sqrt()
                            < length
                    {
                        polar += 1e-4;
                        next = on(polar, 5e-4);
                    }
                    points.push(next);
                }
                points
            })
            .collect()
    }

    #[test]
    fn hair_combed_on_the_head_never_enters_it_and_keeps_its_lengths() {
        let head = head();
        let strands = combed(head, 64, 20, 0.012);
        let lengths: Vec<Vec<f64>> = strands
            .iter()
            .map(|s| {
                s.windows(2)
                    .map(|w| {
                        (0..3)
                            .map(|i| (w[1][i] - w[0][i]).powi(2))
                            .sum::<f64>()
                            .sqrt()
                    })
                    .collect()
            })
            .collect();
        let mut wind = StochasticWind::new(&strands, head, 5);
        for frame in 1..=10 {
            wind.advance(178f64.to_radians(), if frame < 6 { 0.5 } else { 0.8 });
            for (strand, lengths) in wind.points().iter().zip(&lengths) {
                for (w, l) in strand.windows(2).zip(lengths) {
                    let got = (0..3)
                        .map(|i| (w[1][i] - w[0][i]).powi(2))
                        .sum::<f64>()
                        .sqrt();
                    assert!(
                        (got - l).abs() < 1e-9,
                        "frame {frame}: length {got} for {l}"
                    );
                    assert!(
                        head.level(w[1]) >= 1.0 - 1e-12,
                        "frame {frame}: a segment end inside the head (level {})",
                        head.level(w[1])
                    );
                }
            }
        }
    }

    #[test]
    fn a_segment_into_the_head_turns_out_onto_its_surface() {
        let head = head();
        // From the top of the head, pointing straight down into it.
        let start = [0.0, 0.1, 0.0];
        let turned = head.keep_outside(start, [0.0, -1.0, 0.0], 0.012).unwrap();
        let end = [0, 1, 2].map(|k| start[k] + turned[k] * 0.012);
        assert!(
            head.level(end) >= 1.0 && head.level(end) < 1.0 + 1e-9,
            "{end:?}"
        );
        // Pointing out: unchanged.
        assert_eq!(head.keep_outside(start, [0.0, 1.0, 0.0], 0.012), None);
    }

    #[test]
    fn same_seed_same_motion() {
        let strands = vec![hanging([0.0, 0.0, 0.095], 20, 0.012)];
        let mut a = StochasticWind::new(&strands, head(), 3);
        let mut b = StochasticWind::new(&strands, head(), 3);
        for _ in 0..5 {
            a.advance(1.0, 0.6);
            b.advance(1.0, 0.6);
        }
        assert_eq!(a.points(), b.points());
    }
}
