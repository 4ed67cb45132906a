//! Contacts inside a strand's constraint solve (physical model): collider
//! contacts recorded for the solve, the strand's contacts with other
//! strands pushed out to two radii, and Coulomb friction at both after the
//! last solve.

use super::colliders::project_contact;
use super::hair_friction::{self, HairContact};
use crate::sim::math;
use crate::sim::rod::direct::Direct;
use crate::sim::rod::real::Real;
use crate::sim::work::{Context, Work};

impl Work {
    /// No contact yet this step. The colliders' friction data too: a
    /// vertex that only touches hair has a contact normal but no collider,
    /// and must not read the friction of another strand this working copy
    /// stepped before (that made a bake depend on the thread count).
    pub(in crate::sim) fn clear_contacts(&mut self, n: usize) {
        self.contact_normals[..n].fill([0.0; 3]);
        self.contact_velocities[..n].fill([0.0; 3]);
        self.contact_friction[..n].fill(0.0);
    }

    /// The strand's contacts with other strands this step.
    #[inline]
    pub(in crate::sim) fn hair_contacts<'c>(&self, ctx: &Context<'c>) -> &'c [HairContact] {
        ctx.hair_contacts.map_or(&[], |h| h.of(self.strand))
    }

    /// Whether the strand may touch anything this step (a collider or
    /// another strand): the solve then keeps contacts.
    #[inline]
    pub(in crate::sim) fn touches(&self, ctx: &Context<'_>) -> bool {
        !ctx.colliders.is_empty() || !self.hair_contacts(ctx).is_empty()
    }

    /// Before the solve: the prediction kept (friction measures from it),
    /// the predicted positions projected.
    pub(in crate::sim) fn begin_contacts(&mut self, ctx: &Context<'_>, n: usize) {
        self.predicted[..n].copy_from_slice(&self.p[..n]);
        self.collide_contacts(ctx, n);
        self.collide_hairs(ctx, n);
    }

    /// Pushes the strand's contact points with other strands out to two
    /// radii (hair_friction.rs). Returns whether a vertex moved.
    pub(in crate::sim) fn collide_hairs(&mut self, ctx: &Context<'_>, n: usize) -> bool {
        let Some(hairs) = ctx.hair_contacts else {
            return false;
        };
        self.touch
            .resize(n, hair_friction::VertexContact::default());
        hair_friction::project(
            hairs.of(self.strand),
            &mut self.touch[..n],
            &mut self.p[..n],
            &self.w[..n],
            &mut self.contact_normals[..n],
            hairs.distance(),
            ctx.dt,
            0.01 * ctx.radius,
        )
    }

    /// Coulomb friction at the strand's contacts with other strands, after
    /// the last solve. Returns whether a vertex moved.
    pub(in crate::sim) fn hair_friction(&mut self, ctx: &Context<'_>, n: usize) -> bool {
        let Some(hairs) = ctx.hair_contacts else {
            return false;
        };
        self.stuck.clear();
        self.stuck.resize(n, false);
        self.touch
            .resize(n, hair_friction::VertexContact::default());
        hair_friction::friction(
            hairs.of(self.strand),
            &mut self.touch[..n],
            &mut self.stuck,
            &mut self.p[..n],
            &self.x[..n],
            &self.predicted[..n],
            &self.w[..n],
            hairs.mu(),
            ctx.dt,
            0.01 * ctx.radius,
        )
    }

    /// After a solve: lane `lane`'s positions projected out of the
    /// colliders, its contacts recorded, after the `last` solve Coulomb
    /// friction applied, all handed back to the solve. Returns whether a
    /// vertex moved.
    pub(in crate::sim) fn contacts_after_iteration<T: Real>(
        &mut self,
        direct: &mut Direct<T>,
        lane: usize,
        ctx: &Context<'_>,
        n: usize,
        last: bool,
    ) -> bool {
        direct.positions_f32(lane, &mut self.p[..n]);
        let mut moved = self.collide_contacts(ctx, n);
        moved |= self.collide_hairs(ctx, n);
        if last {
            moved |= self.friction(ctx, n);
            moved |= self.hair_friction(ctx, n);
        }
        direct.set_positions(lane, &self.p[..n]);
        direct.set_contact_normals(lane, &self.contact_normals[..n]);
        moved
    }

    /// Projects the free vertices out of the colliders (with friction) and
    /// records the contacts for the solve: a contact lasts the rest of the
    /// step. Returns whether a vertex moved (more than a hundredth of the
    /// hair radius).
    pub(in crate::sim) fn collide_contacts(&mut self, ctx: &Context<'_>, n: usize) -> bool {
        let mut moved = false;
        if ctx.colliders.is_empty() {
            return false;
        }
        for i in 1..n {
            if self.w[i] <= 0.0 {
                continue;
            }
            // No friction here: it acts once, after the solve (`friction`).
            let contact = project_contact(ctx.colliders, self.p[i], None, ctx.radius, ctx.dt);
            moved |= math::length(math::sub(contact.position, self.p[i])) > 0.01 * ctx.radius;
            self.p[i] = contact.position;
            if let Some(normal) = contact.normal {
                self.contact_normals[i] = normal;
                self.contact_velocities[i] = contact.surface_velocity;
                self.contact_friction[i] = contact.friction;
            }
        }
        moved
    }

    /// Coulomb friction of the step at each touching vertex (position-level,
    /// as XPBD does it): the step's motion along the surface, relative to
    /// the surface, is held back by `mu` times the distance the contact
    /// pushed the vertex out along the normal (from its prediction, which
    /// gravity and inertia carried into the surface): all of it while it is
    /// smaller (static), else by that much (kinetic). A strand on a slope
    /// of angle `a` so stays put for `mu > tan a` and otherwise slides at
    /// `g (sin a - mu cos a)`. Applied once the solve has moved the strand,
    /// so the solve cannot undo it (applied before it, a resting strand
    /// slid on); per vertex, so in no order. Returns whether a vertex moved.
    pub(in crate::sim) fn friction(&mut self, ctx: &Context<'_>, n: usize) -> bool {
        let mut moved = false;
        for i in 1..n {
            let normal = self.contact_normals[i];
            let mu = self.contact_friction[i];
            if self.w[i] <= 0.0 || normal == [0.0; 3] || mu <= 0.0 {
                continue;
            }
            let pushed = math::dot(math::sub(self.p[i], self.predicted[i]), normal).max(0.0);
            let surface_motion = math::scale(self.contact_velocities[i], ctx.dt);
            let relative = math::sub(math::sub(self.p[i], self.x[i]), surface_motion);
            let tangential = math::sub(relative, math::scale(normal, math::dot(relative, normal)));
            let slide = math::length(tangential);
            if slide == 0.0 {
                continue;
            }
            let held = if slide <= mu * pushed {
                1.0
            } else {
                mu * pushed / slide
            };
            self.p[i] = math::sub(self.p[i], math::scale(tangential, held));
            moved |= held * slide > 0.01 * ctx.radius;
        }
        moved
    }
}
