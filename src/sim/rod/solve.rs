//! The step's "constraints" phase: the paper model's Gauss-Seidel sweeps of
//! stretch/shear and bend/twist with collisions after each, the physical
//! model's Newton iterations of the direct solve (with the contacts of
//! contact/solve.rs between them), and the end of the phase: the
//! inextensibility pass and the final collision pass.

use super::constraints::{bend_twist, follow_the_leader, stretch_shear};
use super::direct::{
    Direct, DirectInput, RodMaterial, FRAME_INERTIA_SPEED, MIDPOINT_FRAME_INERTIA_SPEED,
};
use super::real::{Real, WIDE};
use crate::sim::contact::colliders::project;
use crate::sim::contact::hair_friction;
use crate::sim::math::{Quat, V3};
use crate::sim::work::{Context, StrandMut, Work};

/// Per-strand sweep state carried in registers: the current edge's first
/// vertex and the previous edge's frame.
struct Sweep {
    p_a: V3,
    q_prev: Quat,
}

impl Work {
    /// Stretch/shear of edge 0 (no joint before it).
    #[inline(always)]
    fn sweep_begin(&mut self) -> Sweep {
        let mut p_a = self.p[0];
        let mut p_b = self.p[1];
        let mut q_prev = self.q[0];
        stretch_shear(&mut p_a, &mut p_b, &mut q_prev, &self.stretch[0]);
        self.p[0] = p_a;
        Sweep { p_a: p_b, q_prev }
    }

    /// Edge `e`'s stretch/shear, then the bend of the joint between edges
    /// `e - 1` and `e` (Gauss-Seidel, root to tip).
    #[inline(always)]
    fn sweep_edge(&mut self, e: usize, state: &mut Sweep) {
        let mut p_b = self.p[e + 1];
        let mut q_e = self.q[e];
        stretch_shear(&mut state.p_a, &mut p_b, &mut q_e, &self.stretch[e]);
        bend_twist(&mut state.q_prev, &mut q_e, self.rest[e], self.bend[e]);
        self.p[e] = state.p_a;
        self.q[e - 1] = state.q_prev;
        state.p_a = p_b;
        state.q_prev = q_e;
    }

    #[inline(always)]
    fn sweep_end(&mut self, m: usize, state: Sweep) {
        self.p[m] = state.p_a;
        self.q[m - 1] = state.q_prev;
    }

    pub(in crate::sim) fn sweep(&mut self, m: usize) {
        let mut state = self.sweep_begin();
        for e in 1..m {
            self.sweep_edge(e, &mut state);
        }
        self.sweep_end(m, state);
    }

    /// Collision projection with friction after an iteration.
    pub(in crate::sim) fn collide(&mut self, ctx: &Context<'_>, n: usize) {
        if ctx.colliders.is_empty() {
            return;
        }
        for i in 1..n {
            if self.w[i] > 0.0 {
                self.p[i] = project(
                    ctx.colliders,
                    self.p[i],
                    Some(self.x[i]),
                    ctx.radius,
                    ctx.dt,
                );
            }
        }
    }
}

impl Work {
    /// (iv) of the physical model: `iterations` Newton-XPBD iterations,
    /// each an exact solve of the strand's linearised compliant system.
    /// Collisions come before each solve and the solve keeps them: a
    /// touching vertex moves along the surface, and hardly across it
    /// (`contact_normals` in rod/direct.rs). Pinning vertices that static
    /// friction holds was tried: a strand pressed between its root and a
    /// held tip buckled into a zig-zag the Newton iterations could not
    /// follow (edges 50 % long). Coulomb friction acts once, after the
    /// last solve (`friction`). A contact or friction that moved a vertex
    /// after the last solve gets one more solve, so the step never ends on
    /// a projection that squeezes or stretches edges.
    pub(in crate::sim) fn solve_direct(
        &mut self,
        ctx: &Context<'_>,
        material: RodMaterial,
        s: &StrandMut<'_>,
    ) {
        let n = s.positions.len();
        let m = n - 1;
        self.clear_contacts(n);
        if self.touches(ctx) {
            self.begin_contacts(ctx, n);
        }
        // Taken out so the solve can borrow the rest of the working copy.
        let mut direct = std::mem::take(&mut self.direct);
        direct.begin(&[direct_input(ctx, material, s, self)]);
        newton_iterations(ctx, std::slice::from_mut(self), &mut direct, n);
        direct.end(&mut [(&mut self.p[..n], &mut self.q[..m])]);
        self.direct = direct;
    }
}

/// What the direct solve reads of one strand: its working copy, fibre
/// radii and joints.
pub(in crate::sim) fn direct_input<'a>(
    ctx: &Context<'_>,
    material: RodMaterial,
    s: &'a StrandMut<'_>,
    work: &'a Work,
) -> DirectInput<'a> {
    let n = s.positions.len();
    let m = n - 1;
    DirectInput {
        p: &work.p[..n],
        q: &work.q[..m],
        free: &work.w[..n],
        frame_free: &work.frame_keep[..m],
        // Empty without contacts: the solve then skips reading zeros.
        contact_normals: if work.touches(ctx) {
            &work.contact_normals[..n]
        } else {
            &[]
        },
        l: &work.l[..m],
        radii: s.radii,
        joints: s.joints,
        material,
        rest: &work.rest[..m],
        root_frame: work.root_frame,
        dt: ctx.dt,
        frame_inertia_speed: if work.midpoint {
            MIDPOINT_FRAME_INERTIA_SPEED
        } else {
            FRAME_INERTIA_SPEED
        },
    }
}

/// Where a strand's Newton iterations stand (`newton_iterations`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::sim) enum Progress {
    Iterating,
    /// Its last contact projection or friction moved a vertex: one more
    /// solve, so the step does not end on a projection that squeezes or
    /// stretches edges.
    OneMore,
    Done,
}

/// The physical model's Newton iterations of the strands in `direct`'s
/// lanes (`works[lane]`) with their contacts. A strand iterates until its
/// stretch/shear residual is within `ctx.tolerance` of its edges (checked
/// after each iteration but the last; 0: never) or it has had
/// `ctx.iterations`; collisions are projected after every iteration and
/// Coulomb friction after its last. A strand that is done keeps its
/// state, bit for bit, while the other lanes iterate, so its result is the
/// one it gets alone (`solve_direct`). Adds each strand's solves to its
/// `Work::solves`.
pub(in crate::sim) fn newton_iterations<T: Real>(
    ctx: &Context<'_>,
    works: &mut [Work],
    direct: &mut Direct<T>,
    n: usize,
) {
    let lanes = T::WIDTH;
    let mut progress = [Progress::Iterating; WIDE];
    let mut iteration = 0;
    while progress[..lanes].iter().any(|p| *p != Progress::Done) {
        direct.iterate_lanes(ctx.instructions);
        iteration += 1;
        let unconverged = (ctx.tolerance > 0.0 && iteration < ctx.iterations)
            .then(|| direct.unconverged_lanes(ctx.instructions, ctx.tolerance));
        for (lane, work) in works.iter_mut().take(lanes).enumerate() {
            match progress[lane] {
                Progress::Done => {}
                Progress::OneMore => {
                    work.solves += 1;
                    progress[lane] = Progress::Done;
                    direct.set_active(lane, false);
                }
                Progress::Iterating => {
                    work.solves += 1;
                    let last = iteration >= ctx.iterations
                        || unconverged.is_some_and(|u| u.lane(lane) == 0.0);
                    let moved = work.touches(ctx)
                        && work.contacts_after_iteration(direct, lane, ctx, n, last);
                    if last {
                        progress[lane] = if moved {
                            Progress::OneMore
                        } else {
                            Progress::Done
                        };
                        direct.set_active(lane, moved);
                    }
                }
            }
        }
    }
}

/// The end of the "constraints" phase: the inextensibility pass (paper
/// model, unless it already ran in lanes: `ftl_done`) and the final
/// collision pass, so no vertex ends inside a collider.
pub(in crate::sim) fn end_constraints(
    ctx: &Context<'_>,
    work: &mut Work,
    n: usize,
    ftl_done: bool,
) {
    let m = n - 1;
    if ctx.ftl.is_some() && !ftl_done {
        follow_the_leader(
            &mut work.p[..n],
            &work.w[..n],
            &work.l[..m],
            &mut work.corrections[..n],
        );
    }
    if let Some(hairs) = ctx.hair_contacts {
        // Stuck vertices stay stuck through the last solve.
        if work.stuck.len() == n && !hairs.of(work.strand).is_empty() {
            hair_friction::restick(
                &work.touch[..n],
                &work.stuck,
                &mut work.p[..n],
                &work.x[..n],
                ctx.dt,
                hair_friction::RESTICK_CAP * ctx.radius,
            );
        }
    }
    if !ctx.colliders.is_empty() {
        for i in 1..n {
            if work.w[i] > 0.0 {
                work.p[i] = project(ctx.colliders, work.p[i], None, ctx.radius, ctx.dt);
            }
        }
    }
}
