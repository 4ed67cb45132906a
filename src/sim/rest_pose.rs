//! The plastic rest shape: what the hair would look like with no gravity
//! and nothing touching it, rebuilt from the rest Darboux vectors (15) and
//! rest lengths, integrating the frames from the fixed root to the tip.

use super::math::{self, V3};
use super::rod::bonds::rest_darboux;
use super::StrandSet;

impl StrandSet {
    /// `Omega_o` of (15) at every joint slot, from the current bonds and the
    /// current shape (zero at the root and tip slots).
    pub fn rest_darboux(&self) -> Vec<[f32; 3]> {
        let mut out = vec![[0.0f32; 3]; self.vertex_count()];
        for strand in 0..self.strand_count() {
            if !self.simulated[strand] {
                continue;
            }
            let (first, end) = (self.offsets[strand], self.offsets[strand + 1]);
            for (j, slot) in out
                .iter_mut()
                .enumerate()
                .take(end.saturating_sub(1))
                .skip(first + 1)
            {
                let (q1, q2) = (self.edges[j - 1].rotation, self.edges[j].rotation);
                let omega = math::darboux(q1, q2);
                let w = math::darboux_real(q1, q2);
                let joint = &self.joints[j];
                *slot = rest_darboux(omega, w, &joint.rates, &joint.memories, &self.influences);
            }
        }
        out
    }

    /// The rest shape of every strand (per vertex, in the strands' order):
    /// each root where it is now, its first edge in the root's *rest* frame
    /// (the scalp clamp's frame, moved with the roots' transform, turned by
    /// the clamp's rest Darboux vector: the groomed root edge, or what the
    /// sag-free start solved), each next frame the previous one turned by
    /// the rest Darboux vector, each vertex one rest length along its edge's
    /// tangent. Strands that are not simulated keep their current points.
    ///
    /// Not the first edge's current frame: under a load (gravity, a press)
    /// the physical model's clamp is a stiff joint, not a weld, so that
    /// frame is turned by the load, and the whole rest shape with it
    /// (3.6 degrees for a 20 cm helix hung under gravity).
    pub fn rest_pose(&self) -> Vec<[f32; 3]> {
        let rest = self.rest_darboux();
        let mut out = self.positions.clone();
        for strand in 0..self.strand_count() {
            if !self.simulated[strand] {
                continue;
            }
            let (first, end) = (self.offsets[strand], self.offsets[strand + 1]);
            let root = &self.roots[strand];
            let clamp = math::qmul(self.root_transform.rotation, root.frame);
            let mut frame = math::qnormalize(math::qmul(clamp, math::from_imaginary(root.rest)));
            let mut p: V3 = self.positions[first];
            for e in first..end - 1 {
                if e > first {
                    frame = math::qnormalize(math::qmul(frame, math::from_imaginary(rest[e])));
                }
                p = math::add(
                    p,
                    math::scale(math::tangent(frame), self.edges[e].rest_length),
                );
                out[e + 1] = p;
            }
        }
        out
    }
}
