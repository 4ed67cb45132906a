//! Colliders: parry3d shapes with kinematic poses and Coulomb friction.
//! A vertex is projected to outside the shape plus the hair radius.

use super::math::{add, cross, dot, length, scale, sub, V3};
use super::Pose;
use parry3d::math::Vector;
use parry3d::shape::SharedShape;

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
    pub fn new(name: impl Into<String>, shape: SharedShape, pose: Pose, friction: f32) -> Collider {
        Collider {
            name: name.into(),
            shape,
            pose,
            friction,
            linear_velocity: [0.0; 3],
            angular_velocity: [0.0; 3],
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

    /// Per-step data: world boxes grown by the hair radius.
    pub(crate) fn prepare(&self, radius: f32) -> Vec<PreparedCollider<'_>> {
        self.colliders
            .iter()
            .map(|c| {
                let aabb = c.shape.compute_aabb(&c.pose);
                let grow = radius * 1.01;
                PreparedCollider {
                    collider: c,
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

pub(crate) struct PreparedCollider<'a> {
    collider: &'a Collider,
    min: V3,
    max: V3,
    center: V3,
}

/// Pushes `p` out of every collider to at least `radius` from its surface.
/// With `start` (the vertex at the start of the step), Coulomb friction
/// removes the tangential motion relative to the surface, up to
/// `mu * depth`. Returns the new position.
pub(crate) fn project(
    colliders: &[PreparedCollider<'_>],
    mut p: V3,
    start: Option<V3>,
    radius: f32,
    dt: f32,
) -> V3 {
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
        let projection =
            c.collider
                .shape
                .project_point(&c.collider.pose, Vector::new(p[0], p[1], p[2]), false);
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
        if let Some(start) = start {
            let mu = c.collider.friction;
            if mu > 0.0 {
                let arm = sub(p, c.center);
                let surface_velocity = add(
                    c.collider.linear_velocity,
                    cross(c.collider.angular_velocity, arm),
                );
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
    p
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
}
