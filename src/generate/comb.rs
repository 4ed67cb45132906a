//! Combing: the direction field on the scalp, and a strand's line grown
//! along it, lying on the head and then hanging under its own line.
//!
//! The field, on the unit sphere of the head's normalised space (see
//! [`super::scalp`]), is what a comb leaves:
//!
//! - away from the parting: the parting is the arc of the vertical plane
//!   `x = sin(parting)` from the forehead back to the crown whorl; hair
//!   beside it leaves it at a right angle, to either side (the field is
//!   discontinuous across it, which is what a parting is);
//! - around the crown whorl: behind the parting's end the hair leaves the
//!   whorl radially, turned about it by `whorl_swirl` where it is close
//!   (a Gaussian of 20 degrees);
//! - down: the further from the parting, the more the hair follows the
//!   scalp's fall line (the tangent part of -Y);
//! - back: on the front half the hair is also combed back, off the face.
//!
//! A strand leaves its root at `lift` degrees to the scalp along the
//! field, rises to its own height in the hair layer (drawn up to
//! `volume`) and lies there, following the field while the scalp holds it
//! up (its normal more than 6 degrees above horizontal) and at least for
//! `contact_length`. Then it hangs: it turns toward -Y (at most 25 rad/m,
//! the bend of a hair's own line) and slides over the head at its layer
//! height where hanging straight would cross it. Every step is one edge of
//! the strand, so the lengths are exact.

use super::scalp::{Root, Scalp};
use super::GeneratorParameters;
use groom::math::double::{add, cross, dot, length, scale, sub, try_normalize, V3};

/// Lying hair turns to the field within about 7 mm (rad/m).
const LYING_TURN: f64 = 150.0;
/// Hanging hair turns toward -Y at most this fast (rad/m): a 4 cm bend.
const FALL_TURN: f64 = 25.0;
/// The scalp holds hair up while its normal's Y is above this (sin 6 deg).
const SUPPORT: f64 = 0.1;
/// How far from the parting, in unit-sphere chord, the fall line weighs as
/// much as the comb's direction away from it (about 30 degrees).
const PART_REACH: f64 = 0.5;
/// Width of the whorl's swirl (chord, about 20 degrees).
const WHORL_REACH: f64 = 0.35;
/// Weight of combing back on the front (times `u_z`).
const BACK: f64 = 0.8;

fn unit_or(a: V3, fallback: V3) -> V3 {
    try_normalize(a).unwrap_or(fallback)
}

/// The tangent part of `v` at the unit normal `n`.
fn tangent(v: V3, n: V3) -> V3 {
    sub(v, scale(n, dot(v, n)))
}

/// `from` turned toward `to` (both unit) by at most `angle` radians.
fn turn_toward(from: V3, to: V3, angle: f64) -> V3 {
    let between = dot(from, to).clamp(-1.0, 1.0).acos();
    if between <= angle || between < 1e-12 {
        return to;
    }
    let side = tangent(to, from);
    let Some(side) = try_normalize(side) else {
        return from;
    };
    unit_or(add(scale(from, angle.cos()), scale(side, angle.sin())), to)
}

pub(super) struct Comb {
    part_x: f64,
    part_radius: f64,
    /// The parting's ends: angles in its plane from +Y toward +Z.
    whorl_end: f64,
    front_end: f64,
    whorl: V3,
    swirl: f64,
    lift: f64,
    contact: f64,
    radii: V3,
}

impl Comb {
    pub fn new(p: &GeneratorParameters, scalp: &Scalp) -> Comb {
        let parting = (p.parting as f64).to_radians();
        let part_radius = parting.cos();
        let whorl_end = -(p.whorl_angle as f64).to_radians();
        // The parting reaches past the forehead hairline.
        let front_end = (p.hairline[0] as f64 + 10.0).to_radians();
        Comb {
            part_x: parting.sin(),
            part_radius,
            whorl_end,
            front_end,
            whorl: [
                parting.sin(),
                part_radius * whorl_end.cos(),
                part_radius * whorl_end.sin(),
            ],
            // Clockwise seen from above is a negative turn about +Y.
            swirl: -(p.whorl_swirl as f64).to_radians(),
            lift: (p.lift as f64).to_radians(),
            contact: p.contact_length as f64,
            radii: scalp.radii(),
        }
    }

    /// The comb's unit direction at `u` on the unit sphere.
    pub fn field(&self, u: V3) -> V3 {
        let angle = u[2].atan2(u[1]).clamp(self.whorl_end, self.front_end);
        let on_part = [
            self.part_x,
            self.part_radius * angle.cos(),
            self.part_radius * angle.sin(),
        ];
        let away = sub(u, on_part);
        let distance = length(away);
        let side = if u[0] >= self.part_x { 1.0 } else { -1.0 };
        let sideways = tangent([side, 0.0, 0.0], u);
        let mut comb = unit_or(tangent(away, u), unit_or(sideways, [0.0, -1.0, 0.0]));
        let to_whorl = length(sub(u, self.whorl));
        let twist = self.swirl * (-(to_whorl / WHORL_REACH).powi(2)).exp();
        comb = add(scale(comb, twist.cos()), scale(cross(u, comb), twist.sin()));
        let down = tangent([0.0, -1.0, 0.0], u);
        let back = scale(tangent([0.0, 0.0, -1.0], u), BACK * u[2].max(0.0));
        let weight = (distance / PART_REACH).powi(2);
        unit_or(
            add(add(comb, scale(down, weight)), back),
            unit_or(down, [0.0, 0.0, -1.0]),
        )
    }

    /// The field at the scalp point of direction `u` and normal `n`, in
    /// world space: the unit sphere's direction mapped by the head's radii
    /// and laid in the scalp's tangent plane.
    pub fn world_field(&self, u: V3, n: V3) -> V3 {
        let f = self.field(u);
        let mapped = [0, 1, 2].map(|k| f[k] * self.radii[k]);
        let fall = unit_or(tangent([0.0, -1.0, 0.0], n), [0.0, 0.0, -1.0]);
        unit_or(tangent(mapped, n), fall)
    }

    /// The strand's line from `root` (on the scalp):
    /// `edges` edges of `step`, lying at `layer` above the scalp. Also the
    /// arc length at which it stops lying on the head.
    pub fn grow(
        &self,
        scalp: &Scalp,
        root: &Root,
        edges: usize,
        step: f64,
        layer: f64,
    ) -> (Vec<V3>, f64) {
        let (normal, u) = (root.normal, root.u);
        let root = root.point;
        let mut points = Vec::with_capacity(edges + 1);
        points.push(root);
        let along = self.world_field(u, normal);
        let mut direction = unit_or(
            add(
                scale(along, self.lift.cos()),
                scale(normal, self.lift.sin()),
            ),
            normal,
        );
        let rise = self.lift.tan();
        let mut x = root;
        let mut lying = true;
        let mut lying_until = edges as f64 * step;
        for k in 1..=edges {
            let arc = k as f64 * step;
            let (_, _, n) = scalp.height(x);
            if lying && arc - step >= self.contact && n[1] < SUPPORT {
                lying = false;
                lying_until = arc - step;
            }
            let (desired, rate) = if lying {
                (self.world_field(scalp.direction(x), n), LYING_TURN)
            } else {
                ([0.0, -1.0, 0.0], FALL_TURN)
            };
            direction = turn_toward(direction, desired, rate * step);
            let mut next = add(x, scale(direction, step));
            let (h, _, _) = scalp.height(next);
            // Lying: rise at the lift angle to the layer and stay there.
            // Hanging: never below the layer (slide over the head).
            let target = if lying {
                Some((arc * rise).min(layer))
            } else if h < layer {
                Some(layer)
            } else {
                None
            };
            if let Some(target) = target {
                let placed = scalp.at_height(next, target);
                if let Some(d) = try_normalize(sub(placed, x)) {
                    direction = d;
                    next = add(x, scale(d, step));
                }
            }
            points.push(next);
            x = next;
        }
        (points, lying_until)
    }
}

/// Puts every vertex but the root that is closer to the scalp than
/// `clearance` (or inside it) at `clearance` above it.
pub(super) fn keep_off(scalp: &Scalp, points: &mut [V3], clearance: f64) {
    for point in points.iter_mut().skip(1) {
        let (h, foot, n) = scalp.height(*point);
        if h < clearance {
            *point = add(foot, scale(n, clearance));
        }
    }
}
