//! `StrandSet`: the whole simulation state, in flat per-vertex arrays.

use super::math::{self, Quat, IDENTITY, V3};
use super::{BondKind, Material, Pose, SimError, DEFAULT_RADIUS};
use groom::{Attribute, AttributeValues, Groom, Scope, UpAxis};

/// The frame of one edge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct EdgeState {
    pub rotation: Quat,
    pub angular_velocity: V3,
    pub rest_length: f32,
}

/// The bonds and stiffness of one joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct JointState {
    /// `k` of (13).
    pub stiffness: f32,
    /// `k'` of (12) for `StrandSet::prime_iterations`.
    pub stiffness_prime: f32,
    /// The share of the healthy modulus left by the cuticle gradient
    /// (13)-(14) at this joint (physical model).
    pub cuticle: f32,
    /// `b_j` per bond kind.
    pub rates: [f32; 4],
    /// `Omega_j` per bond kind.
    pub memories: [V3; 4],
}

/// How one vertex is driven.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct VertexControl {
    pub target: V3,
    pub targeted: bool,
}

/// A root in scalp space: where it sits and the frame of its first edge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct RootAnchor {
    pub position: V3,
    pub frame: Quat,
    /// The rest Darboux vector of the clamp between `frame` and the first
    /// edge's frame (physical model): zero, or what the sag-free start
    /// solved.
    pub rest: V3,
}

/// A rigid transform as the kernel uses it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Rigid {
    pub rotation: Quat,
    pub translation: V3,
}

impl Rigid {
    pub const IDENTITY: Rigid = Rigid {
        rotation: IDENTITY,
        translation: [0.0; 3],
    };

    pub fn from_pose(pose: &Pose) -> Rigid {
        let r = pose.rotation;
        let t = pose.translation;
        Rigid {
            rotation: math::qnormalize([r.x, r.y, r.z, r.w]),
            translation: [t.x, t.y, t.z],
        }
    }

    pub fn apply(&self, p: V3) -> V3 {
        math::add(math::rotate(self.rotation, p), self.translation)
    }
}

/// All strands of a groom being simulated. Created from a groom in metres,
/// Y up; the groomed shape is the rest shape (all bonds intact and
/// remembering it).
#[derive(Debug, Clone)]
pub struct StrandSet {
    pub(crate) material: Material,
    pub(crate) influences: [f32; 4],
    /// Vertex offset of each strand, plus the total at the end.
    pub(crate) offsets: Vec<usize>,
    /// Per strand: has at least one edge and no degenerate edge.
    pub(crate) simulated: Vec<bool>,
    /// Per strand: contained after turning non-finite.
    pub(crate) frozen: Vec<bool>,
    pub(crate) roots: Vec<RootAnchor>,
    pub(crate) root_transform: Rigid,
    pub(crate) positions: Vec<V3>,
    /// The vertices' real velocities, `(x_new - x_old) / dt` of the last
    /// step.
    pub(crate) velocities: Vec<V3>,
    /// What Follow-The-Leader's velocity correction (paper model) takes
    /// off the real velocity for the next step's prediction, m/s; zero in
    /// the physical model.
    pub(crate) velocity_corrections: Vec<V3>,
    pub(crate) edges: Vec<EdgeState>,
    pub(crate) joints: Vec<JointState>,
    pub(crate) controls: Vec<VertexControl>,
    pub(crate) wetness: Vec<f32>,
    /// Fibre radius per vertex, metres (physical model: masses and
    /// stiffness).
    pub(crate) radii: Vec<f32>,
    /// The iteration count `stiffness_prime` was computed for (0: none).
    pub(crate) prime_iterations: u32,
    /// The hold's targets (forces/hold.rs): each vertex where the strands were
    /// made, in scalp space (the root transform carries them), and its
    /// fraction of its strand's length from the root there.
    pub(crate) groomed: Vec<V3>,
    pub(crate) groomed_fraction: Vec<f32>,
    /// The edges' frames there (scalp space), per edge slot.
    pub(crate) groomed_frames: Vec<Quat>,
}

/// Names of the state attributes (see `to_groom_attributes`).
pub mod attribute_names {
    pub const BOND_RATES: [&str; 4] = [
        "bond_hydrogen",
        "bond_ionic",
        "bond_disulfide",
        "bond_peptide",
    ];
    pub const BOND_MEMORIES: [&str; 4] = [
        "bond_memory_hydrogen",
        "bond_memory_ionic",
        "bond_memory_disulfide",
        "bond_memory_peptide",
    ];
    pub const WETNESS: &str = "wetness";
    pub const VELOCITY: &str = "sim_velocity";
    pub const VELOCITY_CORRECTION: &str = "sim_velocity_correction";
    pub const FRAME_XYZ: &str = "sim_frame_xyz";
    pub const FRAME_W: &str = "sim_frame_w";
    pub const ANGULAR_VELOCITY: &str = "sim_angular_velocity";
    pub const REST_LENGTH: &str = "sim_rest_length";
    pub const ROOT_ANCHOR: &str = "sim_root_anchor";
    pub const ROOT_FRAME_XYZ: &str = "sim_root_frame_xyz";
    pub const ROOT_FRAME_W: &str = "sim_root_frame_w";
    pub const ROOT_REST: &str = "sim_root_rest";
    pub const FROZEN: &str = "sim_frozen";
}

/// The fibre radius of every vertex: the material's, else half the groom's
/// `width` (per vertex or per strand) where it is positive and finite, else
/// `DEFAULT_RADIUS`.
fn fibre_radii(groom: &Groom, material: &Material) -> Vec<f32> {
    let n = groom.points.len();
    if let Some(r) = material.radius {
        return vec![r; n];
    }
    let mut radii = vec![DEFAULT_RADIUS; n];
    let widths = ["width", "widths", "groom_width"].iter().find_map(|name| {
        match groom.attribute(name).map(|a| &a.values) {
            Some(AttributeValues::Float(v)) => Some(v),
            _ => None,
        }
    });
    let usable = |w: f32| w.is_finite() && w > 0.0 && w < 0.02;
    if let Some(widths) = widths {
        if widths.len() == n {
            for (r, w) in radii.iter_mut().zip(widths) {
                if usable(*w) {
                    *r = 0.5 * w;
                }
            }
        } else if widths.len() == groom.strand_vertex_counts.len() {
            let mut start = 0usize;
            for (count, w) in groom.strand_vertex_counts.iter().zip(widths) {
                let end = (start + *count as usize).min(n);
                if usable(*w) {
                    radii[start..end].fill(0.5 * w);
                }
                start = end;
            }
        }
    }
    radii
}

impl StrandSet {
    /// Builds the state of `groom` (metres, Y up): frames by parallel
    /// transport along each strand, all bonds intact remembering the groomed
    /// shape, roots pinned. A strand of fewer than 2 points or with a
    /// zero-length edge is kept but not simulated.
    pub fn from_groom(groom: &Groom, material: &Material) -> Result<StrandSet, SimError> {
        material.check()?;
        if (groom.units.meters_per_unit - 1.0).abs() > 1e-9 || groom.up_axis != UpAxis::Y {
            return Err(SimError::Groom(format!(
                "the solver needs metres and Y up, the groom is in {} with {} up (convert it first)",
                groom.units.name(),
                groom.up_axis.name()
            )));
        }
        let total: usize = groom.strand_vertex_counts.iter().map(|&c| c as usize).sum();
        if total != groom.points.len() {
            return Err(SimError::Groom(format!(
                "the strand vertex counts add up to {total} but there are {} points",
                groom.points.len()
            )));
        }
        let strand_count = groom.strand_vertex_counts.len();
        let mut offsets = Vec::with_capacity(strand_count + 1);
        let mut start = 0usize;
        offsets.push(0);
        for &count in &groom.strand_vertex_counts {
            start += count as usize;
            offsets.push(start);
        }
        let vertex_count = groom.points.len();
        let mut set = StrandSet {
            material: *material,
            influences: material.normalized_influences(),
            offsets,
            simulated: vec![false; strand_count],
            frozen: vec![false; strand_count],
            roots: Vec::with_capacity(strand_count),
            root_transform: Rigid::IDENTITY,
            positions: groom.points.clone(),
            velocities: vec![[0.0; 3]; vertex_count],
            velocity_corrections: vec![[0.0; 3]; vertex_count],
            edges: vec![
                EdgeState {
                    rotation: IDENTITY,
                    angular_velocity: [0.0; 3],
                    rest_length: 0.0,
                };
                vertex_count
            ],
            joints: vec![
                JointState {
                    stiffness: material.stiffness,
                    stiffness_prime: 0.0,
                    cuticle: 1.0,
                    rates: [1.0; 4],
                    memories: [[0.0; 3]; 4],
                };
                vertex_count
            ],
            controls: vec![
                VertexControl {
                    target: [0.0; 3],
                    targeted: false,
                };
                vertex_count
            ],
            wetness: vec![0.0; vertex_count],
            radii: fibre_radii(groom, material),
            prime_iterations: 0,
            groomed: groom.points.clone(),
            groomed_fraction: Vec::new(),
            groomed_frames: Vec::new(),
        };
        for strand in 0..strand_count {
            let range = set.offsets[strand]..set.offsets[strand + 1];
            if let Some((local, point)) = groom.points[range.clone()]
                .iter()
                .enumerate()
                .find(|(_, p)| !math::is_finite3(**p))
            {
                let _ = point;
                return Err(SimError::NonFinite {
                    strand,
                    vertex: local,
                });
            }
            set.init_strand(strand);
        }
        set.groomed_fraction = super::forces::hold::arc_fractions(&set.groomed, &set.offsets);
        set.groomed_frames = set.edges.iter().map(|e| e.rotation).collect();
        Ok(set)
    }

    /// Frames, rest lengths, memories and stiffness of one strand from its
    /// current positions.
    fn init_strand(&mut self, strand: usize) {
        let first = self.offsets[strand];
        let end = self.offsets[strand + 1];
        let n = end - first;
        let root_position = self.positions.get(first).copied().unwrap_or([0.0; 3]);
        let mut anchor = RootAnchor {
            position: root_position,
            frame: IDENTITY,
            rest: [0.0; 3],
        };
        let mut ok = n >= 2;
        let mut previous_tangent = [0.0f32, 0.0, 1.0];
        let mut previous_frame = IDENTITY;
        for e in 0..n.saturating_sub(1) {
            let a = self.positions[first + e];
            let b = self.positions[first + e + 1];
            let d = math::sub(b, a);
            let l = math::length(d);
            if !(l > 1e-9 && l.is_finite()) {
                ok = false;
                break;
            }
            let t = math::scale(d, 1.0 / l);
            // Parallel transport: rotate the previous frame by the smallest
            // rotation taking the previous tangent to this one (no twist).
            let frame = math::qnormalize(math::qmul(
                math::rotation_between(previous_tangent, t),
                previous_frame,
            ));
            self.edges[first + e] = EdgeState {
                rotation: frame,
                angular_velocity: [0.0; 3],
                rest_length: l,
            };
            if e == 0 {
                anchor.frame = frame;
            }
            previous_tangent = t;
            previous_frame = frame;
        }
        self.roots.push(anchor);
        self.simulated[strand] = ok;
        if !ok {
            return;
        }
        let mut arc = 0.0f32;
        for j in 1..n - 1 {
            arc += self.edges[first + j - 1].rest_length;
            let omega = math::darboux(
                self.edges[first + j - 1].rotation,
                self.edges[first + j].rotation,
            );
            let joint = &mut self.joints[first + j];
            joint.stiffness = self.material.stiffness_at(arc);
            joint.cuticle = self.material.cuticle_factor(arc);
            joint.memories = [omega; 4];
            joint.rates = [1.0; 4];
        }
    }

    /// Fibre radius per vertex, metres.
    pub fn radii(&self) -> &[f32] {
        &self.radii
    }

    pub fn strand_count(&self) -> usize {
        self.offsets.len() - 1
    }

    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// The vertex range of a strand.
    pub fn strand_range(&self, strand: usize) -> Option<std::ops::Range<usize>> {
        Some(*self.offsets.get(strand)?..*self.offsets.get(strand + 1)?)
    }

    pub fn material(&self) -> &Material {
        &self.material
    }

    pub fn positions(&self) -> &[[f32; 3]] {
        &self.positions
    }

    /// Moving vertices by hand (the next step takes them as they are).
    pub fn positions_mut(&mut self) -> &mut [[f32; 3]] {
        &mut self.positions
    }

    pub fn velocities(&self) -> &[[f32; 3]] {
        &self.velocities
    }

    pub fn velocities_mut(&mut self) -> &mut [[f32; 3]] {
        &mut self.velocities
    }

    /// The frame of each edge, in the slot of its first vertex (`[x,y,z,w]`).
    pub fn edge_rotations(&self) -> Vec<[f32; 4]> {
        self.edges.iter().map(|e| e.rotation).collect()
    }

    pub fn rest_lengths(&self) -> Vec<f32> {
        self.edges.iter().map(|e| e.rest_length).collect()
    }

    /// Wetness per vertex: a state value the timeline drives (0 dry, 1 wet);
    /// the solver keeps and exports it.
    pub fn wetness(&self) -> &[f32] {
        &self.wetness
    }

    pub fn wetness_mut(&mut self) -> &mut [f32] {
        &mut self.wetness
    }

    /// `b_j` of one kind at every joint (per vertex; root and tip slots are
    /// unused and copy their neighbour joint).
    pub fn bond_rates(&self, kind: BondKind) -> Vec<f32> {
        self.per_vertex_joint(|j| j.rates[kind.index()])
    }

    /// Sets `b_j` of one kind at joint `vertex` (a global vertex index),
    /// clamped to [0, 1]. Setting it does not update the memory (17); use
    /// `Environment::bond_rate_drive` for re-forming bonds.
    pub fn set_bond_rate(&mut self, vertex: usize, kind: BondKind, rate: f32) {
        if let Some(joint) = self.joints.get_mut(vertex) {
            joint.rates[kind.index()] = if rate.is_nan() {
                joint.rates[kind.index()]
            } else {
                rate.clamp(0.0, 1.0)
            };
        }
    }

    /// Sets `b_j` of one kind at every joint.
    pub fn set_all_bond_rates(&mut self, kind: BondKind, rate: f32) {
        for vertex in 0..self.joints.len() {
            self.set_bond_rate(vertex, kind, rate);
        }
    }

    /// `Omega_j` of one kind at every joint (per vertex slots).
    pub fn bond_memories(&self, kind: BondKind) -> Vec<[f32; 3]> {
        self.per_vertex_joint(|j| j.memories[kind.index()])
    }

    pub fn set_bond_memory(&mut self, vertex: usize, kind: BondKind, memory: [f32; 3]) {
        if let Some(joint) = self.joints.get_mut(vertex) {
            if math::is_finite3(memory) {
                joint.memories[kind.index()] = memory;
            }
        }
    }

    /// The stiffness `k` of (13) per joint slot.
    pub fn stiffness(&self) -> Vec<f32> {
        self.per_vertex_joint(|j| j.stiffness)
    }

    /// Drives vertex `vertex` of `strand` to a position (pinned with a
    /// prescribed position), or releases it with `None`. A released root
    /// follows the scalp again.
    pub fn set_kinematic_target(
        &mut self,
        strand: usize,
        vertex: usize,
        target: Option<[f32; 3]>,
    ) -> Result<(), SimError> {
        let range = self.strand_range(strand).ok_or(SimError::Index {
            strand,
            vertex,
            message: "no such strand",
        })?;
        if vertex >= range.len() {
            return Err(SimError::Index {
                strand,
                vertex,
                message: "no such vertex in the strand",
            });
        }
        let control = &mut self.controls[range.start + vertex];
        match target {
            Some(p) if math::is_finite3(p) => {
                control.target = p;
                control.targeted = true;
            }
            Some(_) => {
                return Err(SimError::Index {
                    strand,
                    vertex,
                    message: "kinematic target is not finite",
                })
            }
            None => control.targeted = false,
        }
        Ok(())
    }

    /// Releases every kinematic target (roots follow the scalp again).
    pub fn clear_kinematic_targets(&mut self) {
        for control in &mut self.controls {
            control.targeted = false;
        }
    }

    /// Roots (and root frames) follow this transform of their initial
    /// placement from the next step on.
    pub fn set_root_transform(&mut self, pose: &Pose) {
        let rigid = Rigid::from_pose(pose);
        if math::is_finite3(rigid.translation)
            && rigid.rotation.iter().all(|c| c.is_finite())
            && math::qdot(rigid.rotation, rigid.rotation) > 0.5
        {
            self.root_transform = rigid;
        }
    }

    /// The hold's targets (see [`super::Hold`]): every vertex where the
    /// strands were made, in scalp space.
    pub fn groomed_positions(&self) -> &[[f32; 3]] {
        &self.groomed
    }

    /// Takes the hold's targets of `other` (the same strands: same vertex
    /// counts), e.g. after rebuilding the state from positions that a
    /// stage moved directly. Returns false, changing nothing, when the
    /// strands differ.
    pub fn keep_groomed_of(&mut self, other: &StrandSet) -> bool {
        if other.offsets != self.offsets {
            return false;
        }
        self.groomed.clone_from(&other.groomed);
        self.groomed_fraction.clone_from(&other.groomed_fraction);
        self.groomed_frames.clone_from(&other.groomed_frames);
        true
    }

    /// Strands that are simulated (at least one edge, none degenerate).
    pub fn is_simulated(&self, strand: usize) -> bool {
        self.simulated.get(strand).copied().unwrap_or(false)
    }

    /// Strands contained after turning non-finite.
    pub fn frozen_strands(&self) -> Vec<usize> {
        (0..self.strand_count())
            .filter(|&s| self.frozen[s])
            .collect()
    }

    fn per_vertex_joint<T: Copy>(&self, get: impl Fn(&JointState) -> T) -> Vec<T> {
        let mut out: Vec<T> = self.joints.iter().map(&get).collect();
        for strand in 0..self.strand_count() {
            let (first, end) = (self.offsets[strand], self.offsets[strand + 1]);
            let n = end - first;
            if n >= 3 {
                out[first] = get(&self.joints[first + 1]);
                out[end - 1] = get(&self.joints[end - 2]);
            }
        }
        out
    }

    /// Everything needed to continue the simulation later, plus the
    /// per-vertex bond rates and wetness for export, as groom attributes:
    /// - `bond_hydrogen|ionic|disulfide|peptide` (float per vertex): `b_j`
    ///   of the joint at that vertex (root and tip copy their neighbour);
    /// - `bond_memory_*` (vec3 per vertex): `Omega_j` likewise;
    /// - `wetness` (float per vertex);
    /// - `sim_velocity` (vec3 per vertex): the real velocity, m/s;
    /// - `sim_velocity_correction` (vec3 per vertex): Follow-The-Leader's
    ///   correction the next step takes off it (paper model);
    /// - `sim_frame_xyz` + `sim_frame_w`, `sim_angular_velocity`,
    ///   `sim_rest_length`: the edge starting at that vertex (the tip
    ///   copies the last edge);
    /// - per strand: `sim_root_anchor`, `sim_root_frame_xyz|w` (the root in
    ///   scalp space), `sim_root_rest` (the clamp's rest Darboux vector),
    ///   `sim_frozen` (int).
    ///
    /// The groom's points are the current positions (`positions()`).
    pub fn to_groom_attributes(&self) -> Vec<Attribute> {
        use attribute_names as names;
        let mut attributes = Vec::new();
        for kind in BondKind::ALL {
            attributes.push(Attribute::new(
                names::BOND_RATES[kind.index()],
                AttributeValues::Float(self.bond_rates(kind)),
            ));
        }
        for kind in BondKind::ALL {
            attributes.push(Attribute::new(
                names::BOND_MEMORIES[kind.index()],
                AttributeValues::Vec3(self.bond_memories(kind)),
            ));
        }
        attributes.push(Attribute::new(
            names::WETNESS,
            AttributeValues::Float(self.wetness.clone()),
        ));
        attributes.push(Attribute::new(
            names::VELOCITY,
            AttributeValues::Vec3(self.velocities.clone()),
        ));
        attributes.push(Attribute::new(
            names::VELOCITY_CORRECTION,
            AttributeValues::Vec3(self.velocity_corrections.clone()),
        ));
        let edges = self.per_vertex_edge();
        attributes.push(Attribute::new(
            names::FRAME_XYZ,
            AttributeValues::Vec3(edges.iter().map(|e| math::imag(e.rotation)).collect()),
        ));
        attributes.push(Attribute::new(
            names::FRAME_W,
            AttributeValues::Float(edges.iter().map(|e| e.rotation[3]).collect()),
        ));
        attributes.push(Attribute::new(
            names::ANGULAR_VELOCITY,
            AttributeValues::Vec3(edges.iter().map(|e| e.angular_velocity).collect()),
        ));
        attributes.push(Attribute::new(
            names::REST_LENGTH,
            AttributeValues::Float(edges.iter().map(|e| e.rest_length).collect()),
        ));
        attributes.push(Attribute::per_strand(
            names::ROOT_ANCHOR,
            AttributeValues::Vec3(
                self.roots
                    .iter()
                    .map(|r| self.root_transform.apply(r.position))
                    .collect(),
            ),
        ));
        let root_frames: Vec<Quat> = self
            .roots
            .iter()
            .map(|r| math::qmul(self.root_transform.rotation, r.frame))
            .collect();
        attributes.push(Attribute::per_strand(
            names::ROOT_FRAME_XYZ,
            AttributeValues::Vec3(root_frames.iter().map(|q| math::imag(*q)).collect()),
        ));
        attributes.push(Attribute::per_strand(
            names::ROOT_FRAME_W,
            AttributeValues::Float(root_frames.iter().map(|q| q[3]).collect()),
        ));
        attributes.push(Attribute::per_strand(
            names::ROOT_REST,
            AttributeValues::Vec3(self.roots.iter().map(|r| r.rest).collect()),
        ));
        attributes.push(Attribute::per_strand(
            names::FROZEN,
            AttributeValues::Int(self.frozen.iter().map(|&f| f as i32).collect()),
        ));
        attributes
    }

    fn per_vertex_edge(&self) -> Vec<EdgeState> {
        let mut out = self.edges.clone();
        for strand in 0..self.strand_count() {
            let (first, end) = (self.offsets[strand], self.offsets[strand + 1]);
            if end - first >= 2 {
                out[end - 1] = self.edges[end - 2];
            }
        }
        out
    }

    /// A copy of `base` with the current positions and the state attributes
    /// (`to_groom_attributes`), ready to export or to continue from.
    pub fn to_groom(&self, base: &Groom) -> Groom {
        let mut groom = base.clone();
        groom.points = self.positions.clone();
        groom.frames.clear();
        for attribute in self.to_groom_attributes() {
            groom.set_attribute(attribute);
        }
        groom
    }

    /// Continues from a groom written by `to_groom`: positions from its
    /// points, all other state from its attributes. The root transform
    /// starts as the identity, with the anchors written as they were placed
    /// at the end. A groom without the `sim_*` attributes starts as
    /// `from_groom` does, with bond rates, memories and wetness taken from
    /// their attributes where present.
    pub fn from_state(groom: &Groom, material: &Material) -> Result<StrandSet, SimError> {
        use attribute_names as names;
        let mut set = StrandSet::from_groom(groom, material)?;
        let fresh = set.clone();
        let n = set.vertex_count();
        let s = set.strand_count();
        for kind in BondKind::ALL {
            if let Some(rates) = floats(groom, names::BOND_RATES[kind.index()], n, Scope::Vertex)? {
                for (joint, rate) in set.joints.iter_mut().zip(rates) {
                    joint.rates[kind.index()] = rate.clamp(0.0, 1.0);
                }
            }
            if let Some(memories) =
                vec3s(groom, names::BOND_MEMORIES[kind.index()], n, Scope::Vertex)?
            {
                for (joint, memory) in set.joints.iter_mut().zip(memories) {
                    joint.memories[kind.index()] = *memory;
                }
            }
        }
        if let Some(wetness) = floats(groom, names::WETNESS, n, Scope::Vertex)? {
            set.wetness = wetness.to_vec();
        }
        if let Some(velocities) = vec3s(groom, names::VELOCITY, n, Scope::Vertex)? {
            set.velocities = velocities.to_vec();
        }
        if let Some(corrections) = vec3s(groom, names::VELOCITY_CORRECTION, n, Scope::Vertex)? {
            set.velocity_corrections = corrections.to_vec();
        }
        let frame_xyz = vec3s(groom, names::FRAME_XYZ, n, Scope::Vertex)?;
        let frame_w = floats(groom, names::FRAME_W, n, Scope::Vertex)?;
        if let (Some(xyz), Some(w)) = (frame_xyz, frame_w) {
            for (edge, (v, w)) in set.edges.iter_mut().zip(xyz.iter().zip(w)) {
                edge.rotation = [v[0], v[1], v[2], *w];
            }
        }
        if let Some(angular) = vec3s(groom, names::ANGULAR_VELOCITY, n, Scope::Vertex)? {
            for (edge, w) in set.edges.iter_mut().zip(angular) {
                edge.angular_velocity = *w;
            }
        }
        if let Some(lengths) = floats(groom, names::REST_LENGTH, n, Scope::Vertex)? {
            for (edge, l) in set.edges.iter_mut().zip(lengths) {
                edge.rest_length = *l;
            }
            // Stiffness follows the arc length at rest, not the deformed one.
            for strand in 0..s {
                let (first, end) = (set.offsets[strand], set.offsets[strand + 1]);
                let mut arc = 0.0f32;
                for j in first + 1..end.saturating_sub(1) {
                    arc += set.edges[j - 1].rest_length;
                    set.joints[j].stiffness = set.material.stiffness_at(arc);
                    set.joints[j].cuticle = set.material.cuticle_factor(arc);
                }
            }
        }
        let anchors = vec3s(groom, names::ROOT_ANCHOR, s, Scope::Strand)?;
        let root_xyz = vec3s(groom, names::ROOT_FRAME_XYZ, s, Scope::Strand)?;
        let root_w = floats(groom, names::ROOT_FRAME_W, s, Scope::Strand)?;
        if let (Some(anchors), Some(xyz), Some(w)) = (anchors, root_xyz, root_w) {
            for (i, root) in set.roots.iter_mut().enumerate() {
                root.position = anchors[i];
                root.frame = [xyz[i][0], xyz[i][1], xyz[i][2], w[i]];
            }
        }
        if let Some(rests) = vec3s(groom, names::ROOT_REST, s, Scope::Strand)? {
            for (root, rest) in set.roots.iter_mut().zip(rests) {
                if math::is_finite3(*rest) && math::dot(*rest, *rest) < 1.0 {
                    root.rest = *rest;
                }
            }
        }
        if let Some(attribute) = groom.attribute(names::FROZEN) {
            match &attribute.values {
                AttributeValues::Int(values) if values.len() == s => {
                    for (frozen, v) in set.frozen.iter_mut().zip(values) {
                        *frozen = *v != 0;
                    }
                }
                _ => {
                    return Err(SimError::Attribute {
                        name: names::FROZEN.into(),
                        message: format!("must be one int per strand ({s})"),
                    })
                }
            }
        }
        // The unused slots (tip edge, root and tip joints) hold copies in
        // the attributes; keep them as a fresh state has them.
        for strand in 0..s {
            let (first, end) = (set.offsets[strand], set.offsets[strand + 1]);
            if end > first {
                set.edges[end - 1] = fresh.edges[end - 1];
                set.joints[first] = fresh.joints[first];
                set.joints[end - 1] = fresh.joints[end - 1];
            }
        }
        // The hold's frames: the ones the bake continues from.
        set.groomed_frames = set.edges.iter().map(|e| e.rotation).collect();
        // Restored state must be usable: no non-finite value, no degenerate edge.
        for strand in 0..s {
            let range = set.offsets[strand]..set.offsets[strand + 1];
            for v in range.clone() {
                let edge = &set.edges[v];
                let joint = &set.joints[v];
                let finite = math::is_finite3(set.velocities[v])
                    && math::is_finite3(set.velocity_corrections[v])
                    && edge.rotation.iter().all(|c| c.is_finite())
                    && math::is_finite3(edge.angular_velocity)
                    && edge.rest_length.is_finite()
                    && joint.memories.iter().all(|m| math::is_finite3(*m))
                    && joint.rates.iter().all(|r| r.is_finite())
                    && set.wetness[v].is_finite();
                if !finite {
                    return Err(SimError::Attribute {
                        name: "sim state".into(),
                        message: format!(
                            "strand {strand} vertex {}: a value is not finite",
                            v - range.start
                        ),
                    });
                }
                if set.simulated[strand] && v + 1 < range.end && edge.rest_length <= 1e-9 {
                    return Err(SimError::Attribute {
                        name: names::REST_LENGTH.into(),
                        message: format!(
                            "strand {strand} vertex {}: rest length must be positive",
                            v - range.start
                        ),
                    });
                }
            }
        }
        Ok(set)
    }
}

fn find<'a>(
    groom: &'a Groom,
    name: &str,
    len: usize,
    scope: Scope,
) -> Result<Option<&'a AttributeValues>, SimError> {
    let Some(attribute) = groom.attribute(name) else {
        return Ok(None);
    };
    if attribute.scope != scope || attribute.values.len() != len {
        return Err(SimError::Attribute {
            name: name.into(),
            message: format!(
                "must have {len} values per {}",
                if scope == Scope::Vertex {
                    "vertex"
                } else {
                    "strand"
                }
            ),
        });
    }
    Ok(Some(&attribute.values))
}

fn floats<'a>(
    groom: &'a Groom,
    name: &str,
    len: usize,
    scope: Scope,
) -> Result<Option<&'a [f32]>, SimError> {
    match find(groom, name, len, scope)? {
        None => Ok(None),
        Some(AttributeValues::Float(v)) => Ok(Some(v)),
        Some(other) => Err(SimError::Attribute {
            name: name.into(),
            message: format!("must be float, is {}", other.type_name()),
        }),
    }
}

fn vec3s<'a>(
    groom: &'a Groom,
    name: &str,
    len: usize,
    scope: Scope,
) -> Result<Option<&'a [[f32; 3]]>, SimError> {
    match find(groom, name, len, scope)? {
        None => Ok(None),
        Some(AttributeValues::Vec3(v)) => Ok(Some(v)),
        Some(other) => Err(SimError::Attribute {
            name: name.into(),
            message: format!("must be vec3, is {}", other.type_name()),
        }),
    }
}
