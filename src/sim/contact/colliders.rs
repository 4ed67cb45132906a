//! Colliders: parry3d shapes with kinematic poses and Coulomb friction.
//! A vertex is projected to outside the shape plus the hair radius.
//! A triangle mesh answers through its distance grid ([`sdf`]), built
//! once when the collider is made; its motion moves the queries.

mod sdf;

use crate::sim::math::{add, cross, dot, length, scale, sub, V3};
use crate::sim::Pose;
use parry3d::math::Vector;
use parry3d::query::PointProjection;
use parry3d::shape::SharedShape;
use sdf::{MeshSdf, Query};
use std::sync::Arc;

/// One kinematic collider.
#[derive(Clone)]
pub struct Collider {
    pub name: String,
    pub shape: SharedShape,
    /// Where the shape is at the end of the coming step.
    pub pose: Pose,
    /// Coulomb friction coefficient (0 slides freely).
    pub friction: f32,
    /// Velocity of the pose's origin during the coming step, m/s (for
    /// friction: a surface drags hair along with its own motion).
    pub linear_velocity: [f32; 3],
    /// Angular velocity about the pose's origin, rad/s.
    pub angular_velocity: [f32; 3],
    /// A mesh shape's distance grid, and the shape it was built for (a
    /// replaced `shape` is queried directly).
    grid: Option<(Arc<MeshSdf>, SharedShape)>,
}

impl std::fmt::Debug for Collider {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Collider")
            .field("name", &self.name)
            .field("shape", &self.shape.shape_type())
            .field("pose", &self.pose)
            .field("friction", &self.friction)
            .finish()
    }
}

impl Collider {
    /// A mesh shape gets its distance grid here, once (none, and parry's
    /// queries instead, for a grid over the budget: see [`Collider::checked`]).
    pub fn new(name: impl Into<String>, shape: SharedShape, pose: Pose, friction: f32) -> Collider {
        let grid = shape
            .as_trimesh()
            .and_then(|mesh| MeshSdf::new(mesh).ok().flatten())
            .map(|sdf| (Arc::new(sdf), shape.clone()));
        Collider::with_grid(name.into(), shape, pose, friction, grid)
    }

    /// As [`Collider::new`], refusing a mesh whose distance grid would be
    /// larger than the [`crate::budget`] allows (the message says why).
    pub fn checked(
        name: impl Into<String>,
        shape: SharedShape,
        pose: Pose,
        friction: f32,
    ) -> Result<Collider, String> {
        let grid = match shape.as_trimesh() {
            Some(mesh) => MeshSdf::new(mesh)?.map(|sdf| (Arc::new(sdf), shape.clone())),
            None => None,
        };
        Ok(Collider::with_grid(
            name.into(),
            shape,
            pose,
            friction,
            grid,
        ))
    }

    fn with_grid(
        name: String,
        shape: SharedShape,
        pose: Pose,
        friction: f32,
        grid: Option<(Arc<MeshSdf>, SharedShape)>,
    ) -> Collider {
        Collider {
            name,
            shape,
            pose,
            friction,
            linear_velocity: [0.0; 3],
            angular_velocity: [0.0; 3],
            grid,
        }
    }

    /// The grid, if it was built for the current shape.
    fn mesh_grid(&self) -> Option<&MeshSdf> {
        match &self.grid {
            Some((sdf, built_for)) if Arc::ptr_eq(&built_for.0, &self.shape.0) => Some(sdf),
            _ => None,
        }
    }

    /// Places the collider without motion (no drag on the hair).
    pub fn set_pose(&mut self, pose: Pose) {
        self.pose = pose;
        self.linear_velocity = [0.0; 3];
        self.angular_velocity = [0.0; 3];
    }

    /// Moves the collider from its current pose to `pose` over `dt`
    /// seconds: sets the pose and the velocities friction uses.
    pub fn move_to(&mut self, pose: Pose, dt: f32) {
        if dt > 0.0 {
            let t = (pose.translation - self.pose.translation) / dt;
            let delta = pose.rotation * self.pose.rotation.inverse();
            let (axis, angle) = delta.to_axis_angle();
            let w = axis * (angle / dt);
            self.linear_velocity = [t.x, t.y, t.z];
            self.angular_velocity = if w.is_finite() {
                [w.x, w.y, w.z]
            } else {
                [0.0; 3]
            };
        }
        self.pose = pose;
    }
}

/// All colliders of a scene, in a fixed order.
#[derive(Debug, Clone, Default)]
pub struct ColliderSet {
    pub colliders: Vec<Collider>,
}

impl ColliderSet {
    pub fn new() -> ColliderSet {
        ColliderSet::default()
    }

    pub fn insert(&mut self, collider: Collider) -> usize {
        self.colliders.push(collider);
        self.colliders.len() - 1
    }

    pub fn get_mut(&mut self, name: &str) -> Option<&mut Collider> {
        self.colliders.iter_mut().find(|c| c.name == name)
    }

    pub fn is_empty(&self) -> bool {
        self.colliders.is_empty()
    }

    /// Per-step data: world boxes grown by the hair radius (inline, no
    /// allocation for up to eight colliders).
    pub(crate) fn prepare(&self, radius: f32) -> Prepared<'_> {
        self.colliders
            .iter()
            .map(|c| {
                let aabb = c.shape.compute_aabb(&c.pose);
                let grow = radius * 1.01;
                let surface = match c.mesh_grid() {
                    Some(sdf) if radius <= sdf.max_radius => Surface::Grid(sdf),
                    Some(sdf) => Surface::Mesh(sdf),
                    None => Surface::Shape,
                };
                PreparedCollider {
                    collider: c,
                    surface,
                    min: [aabb.mins.x - grow, aabb.mins.y - grow, aabb.mins.z - grow],
                    max: [aabb.maxs.x + grow, aabb.maxs.y + grow, aabb.maxs.z + grow],
                    center: [
                        c.pose.translation.x,
                        c.pose.translation.y,
                        c.pose.translation.z,
                    ],
                }
            })
            .collect()
    }
}

/// The colliders of one step (derefs to a slice).
pub(crate) type Prepared<'a> = smallvec::SmallVec<[PreparedCollider<'a>; 8]>;

/// How a collider's surface is found.
#[derive(Clone, Copy)]
enum Surface<'a> {
    /// parry's query on the shape.
    Shape,
    /// A mesh's distance grid.
    Grid(&'a MeshSdf),
    /// A mesh too fine for the hair radius: parry's query on the grid's
    /// (oriented) mesh.
    Mesh(&'a MeshSdf),
}

pub(crate) struct PreparedCollider<'a> {
    collider: &'a Collider,
    surface: Surface<'a>,
    min: V3,
    max: V3,
    center: V3,
}

impl PreparedCollider<'_> {
    /// The closest surface point (world), or `None` when `p` is outside
    /// and farther than `radius`.
    #[inline]
    fn closest(&self, p: V3, radius: f32) -> Option<PointProjection> {
        let pose = &self.collider.pose;
        let world = Vector::new(p[0], p[1], p[2]);
        let in_mesh_frame = |sdf: &MeshSdf, local: Vector| {
            let mut projection = sdf.exact(local);
            projection.point = pose.transform_point(projection.point);
            projection
        };
        match self.surface {
            Surface::Shape => Some(self.collider.shape.project_point(pose, world, false)),
            Surface::Mesh(sdf) => Some(in_mesh_frame(sdf, pose.inverse_transform_point(world))),
            Surface::Grid(sdf) => {
                let local = pose.inverse_transform_point(world);
                match sdf.query(local, radius) {
                    Query::Clear => None,
                    Query::Surface(mut projection) => {
                        projection.point = pose.transform_point(projection.point);
                        Some(projection)
                    }
                    Query::Exact => Some(in_mesh_frame(sdf, local)),
                }
            }
        }
    }
}

/// Pushes `p` out of every collider to at least `radius` from its surface.
/// With `start` (the vertex at the start of the step), Coulomb friction
/// removes the tangential motion relative to the surface, up to
/// `mu * depth`. Returns the new position.
pub(crate) fn project(
    colliders: &[PreparedCollider<'_>],
    p: V3,
    start: Option<V3>,
    radius: f32,
    dt: f32,
) -> V3 {
    project_contact(colliders, p, start, radius, dt).position
}

/// Whether the box `[min, max]` overlaps any collider's box (this step's,
/// grown by the hair radius and by the collider's motion over `dt`): a
/// strand far from every collider takes the midpoint step
/// (rod/midpoint.rs).
pub(crate) fn boxes_overlap(colliders: &[PreparedCollider<'_>], min: V3, max: V3, dt: f32) -> bool {
    colliders.iter().any(|c| {
        let size = length(sub(c.max, c.min));
        let speed = length(c.collider.linear_velocity) + length(c.collider.angular_velocity) * size;
        let reach = speed * dt;
        (0..3).all(|i| min[i] <= c.max[i] + reach && max[i] >= c.min[i] - reach)
    })
}

/// What a projection found at one vertex.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Contact {
    /// The vertex outside every collider.
    pub position: V3,
    /// The outward normal of the (last) surface it was pushed out of.
    pub normal: Option<V3>,
    /// That surface's velocity at the vertex (m/s) and its Coulomb
    /// friction coefficient.
    pub surface_velocity: V3,
    pub friction: f32,
}

/// [`project`], also saying which surface the vertex touches (for a solve
/// that keeps contacts as constraints).
pub(crate) fn project_contact(
    colliders: &[PreparedCollider<'_>],
    mut p: V3,
    start: Option<V3>,
    radius: f32,
    dt: f32,
) -> Contact {
    let mut normal = None;
    let mut surface_velocity = [0.0; 3];
    let mut friction = 0.0;
    for c in colliders {
        if p[0] < c.min[0]
            || p[1] < c.min[1]
            || p[2] < c.min[2]
            || p[0] > c.max[0]
            || p[1] > c.max[1]
            || p[2] > c.max[2]
        {
            continue;
        }
        let Some(projection) = c.closest(p, radius) else {
            continue;
        };
        let surface = [projection.point.x, projection.point.y, projection.point.z];
        let offset = sub(p, surface);
        let distance = length(offset);
        let outward = if distance > radius * 1e-3 {
            if projection.is_inside {
                scale(offset, -1.0 / distance)
            } else {
                scale(offset, 1.0 / distance)
            }
        } else {
            // On the surface: away from the collider's origin.
            let away = sub(p, c.center);
            let n = length(away);
            if n > 0.0 {
                scale(away, 1.0 / n)
            } else {
                [0.0, 1.0, 0.0]
            }
        };
        let depth = if projection.is_inside {
            distance + radius
        } else if distance < radius {
            radius - distance
        } else {
            continue;
        };
        let mut target = add(surface, scale(outward, radius));
        normal = Some(outward);
        let arm = sub(p, c.center);
        surface_velocity = add(
            c.collider.linear_velocity,
            cross(c.collider.angular_velocity, arm),
        );
        friction = c.collider.friction;
        if let Some(start) = start {
            let mu = c.collider.friction;
            if mu > 0.0 {
                let relative = sub(sub(target, start), scale(surface_velocity, dt));
                let tangential = sub(relative, scale(outward, dot(relative, outward)));
                let t = length(tangential);
                if t > 0.0 {
                    let removed = if t <= mu * depth { 1.0 } else { mu * depth / t };
                    target = sub(target, scale(tangential, removed));
                }
            }
        }
        p = target;
    }
    Contact {
        position: p,
        normal,
        surface_velocity,
        friction,
    }
}

/// The shipped head mesh (`samples/head.obj`, metres, Y up) as a vertex and
/// triangle list, for tests of mesh colliders.
#[cfg(test)]
pub(crate) fn sample_head() -> (Vec<Vector>, Vec<[u32; 3]>) {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/samples/head.obj");
    let (vertices, triangles) =
        importers::mesh::read_triangles(std::path::Path::new(path)).expect("samples/head.obj");
    let vertices = vertices
        .iter()
        .map(|v| Vector::new(v[0], v[1], v[2]))
        .collect();
    (vertices, triangles)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_inside_or_near_a_ball_end_one_radius_outside() {
        let mut set = ColliderSet::new();
        set.insert(Collider::new(
            "head",
            SharedShape::ball(0.1),
            Pose::from_translation(Vector::new(0.0, 1.0, 0.0)),
            0.0,
        ));
        let prepared = set.prepare(0.001);
        let p = project(&prepared, [0.0, 1.05, 0.0], None, 0.001, 0.01);
        assert!((p[1] - 1.101).abs() < 1e-5, "{p:?}");
        let q = project(&prepared, [0.0, 1.1005, 0.0], None, 0.001, 0.01);
        assert!((q[1] - 1.101).abs() < 1e-5, "{q:?}");
        let far = project(&prepared, [0.0, 1.2, 0.0], None, 0.001, 0.01);
        assert_eq!(far, [0.0, 1.2, 0.0]);
    }

    #[test]
    fn friction_holds_a_slow_sliding_vertex() {
        let mut set = ColliderSet::new();
        set.insert(Collider::new(
            "floor",
            SharedShape::cuboid(1.0, 0.1, 1.0),
            Pose::from_translation(Vector::new(0.0, -0.1, 0.0)),
            1.0,
        ));
        let prepared = set.prepare(0.001);
        // Moved 1 mm sideways while pushed 2 mm into the floor: held.
        let p = project(
            &prepared,
            [0.001, -0.001, 0.0],
            Some([0.0, 0.001, 0.0]),
            0.001,
            0.01,
        );
        assert!(p[0].abs() < 1e-7 && (p[1] - 0.001).abs() < 1e-6, "{p:?}");
        // Moved 1 cm sideways: slides, less the friction.
        let p = project(
            &prepared,
            [0.01, -0.001, 0.0],
            Some([0.0, 0.001, 0.0]),
            0.001,
            0.01,
        );
        assert!((p[0] - 0.008).abs() < 1e-6, "{p:?}");
    }

    #[test]
    fn a_moving_mesh_head_leaves_every_vertex_a_radius_outside() {
        use parry3d::query::PointQuery;
        use parry3d::shape::{TriMesh, TriMeshFlags};
        let (vertices, triangles) = sample_head();
        let exact =
            TriMesh::with_flags(vertices.clone(), triangles.clone(), TriMeshFlags::ORIENTED)
                .expect("mesh");
        let mut set = ColliderSet::new();
        set.insert(Collider::new(
            "head",
            SharedShape::trimesh(vertices, triangles).expect("mesh"),
            Pose::from_translation(Vector::new(0.0, 1.5, 0.0)),
            0.0,
        ));
        // Turned and moved, as a keyframed head is.
        let pose = Pose::from_parts(
            Vector::new(0.1, 1.6, -0.05),
            parry3d::math::Rot3::from_axis_angle(Vector::new(0.3, 1.0, 0.2).normalize(), 0.7),
        );
        set.colliders[0].move_to(pose, 0.01);
        let radius = 4e-5;
        let prepared = set.prepare(radius);
        assert!(matches!(prepared[0].surface, Surface::Grid(_)));
        let mut seed = 3u32;
        let mut next = || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1u32 << 24) as f32 - 0.5
        };
        let mut pushed = 0;
        for _ in 0..5_000 {
            let dir = Vector::new(next(), next(), next()).normalize();
            let on = exact.project_local_point(dir * 0.2, false).point;
            let local = on * (1.0 + 0.02 * next());
            let world = pose.transform_point(local);
            let p = [world.x, world.y, world.z];
            let q = project(&prepared, p, None, radius, 0.01);
            let back = pose.inverse_transform_point(Vector::new(q[0], q[1], q[2]));
            let after = exact.project_local_point(back, false);
            let distance = (back - after.point).length();
            assert!(
                !after.is_inside && distance >= 0.99 * radius,
                "{p:?} -> {q:?}: {distance}"
            );
            pushed += usize::from(q != p);
        }
        assert!(pushed > 1000, "{pushed}");
    }
}
