//! Collider shapes and poses in the solver's terms, from the timeline's
//! `[[collider]]` specs: shared by the bake and the preview's surfaces.

use super::error::BakeError;
use super::motion::Pose as KeyPose;
use super::schema::ShapeSpec;
use super::Timeline;
use crate::sim;

pub(crate) fn shape_of(
    timeline: &Timeline,
    spec: &ShapeSpec,
) -> Result<sim::parry3d::shape::SharedShape, BakeError> {
    use sim::parry3d::math::Vector;
    use sim::parry3d::shape::SharedShape;
    Ok(match spec {
        ShapeSpec::HalfSpace { normal } => {
            SharedShape::halfspace(Vector::new(normal[0], normal[1], normal[2]).normalize())
        }
        ShapeSpec::Cuboid { half_extents: h } => SharedShape::cuboid(h[0], h[1], h[2]),
        ShapeSpec::Ball { radius } => SharedShape::ball(*radius),
        ShapeSpec::Capsule {
            half_height,
            radius,
        } => SharedShape::capsule_y(*half_height, *radius),
        ShapeSpec::Cylinder {
            half_height,
            radius,
        } => SharedShape::cylinder(*half_height, *radius),
        ShapeSpec::Mesh { path, scale } => {
            let file = timeline.resolve(path);
            let (vertices, triangles) = importers::mesh::read_triangles(&file)?;
            let vertices: Vec<Vector> = vertices
                .iter()
                .map(|v| Vector::new(v[0] * scale, v[1] * scale, v[2] * scale))
                .collect();
            check_mesh_coordinates(&vertices).map_err(|message| BakeError::Input {
                file: file.clone(),
                message,
            })?;
            SharedShape::trimesh(vertices, triangles).map_err(|e| BakeError::Input {
                file,
                message: format!("not a usable collider mesh: {e}"),
            })?
        }
    })
}

/// Refuses a collider vertex (after the mesh's scale) outside the scene's
/// range, [`crate::budget::MAX_COORDINATE`]: its grid would be one cell
/// holding the whole mesh, and f32 positions there cannot resolve a hair.
fn check_mesh_coordinates(vertices: &[sim::parry3d::math::Vector]) -> Result<(), String> {
    for (i, v) in vertices.iter().enumerate() {
        for (c, axis) in ["x", "y", "z"].into_iter().enumerate() {
            // Written so that NaN is outside too.
            let inside = f64::from(v[c]).abs() <= crate::budget::MAX_COORDINATE;
            if !inside {
                return Err(format!(
                    "vertex {i} has {axis} = {:e} m (after `scale`): outside \
                     -{max:e} to {max:e} m",
                    v[c],
                    max = crate::budget::MAX_COORDINATE
                ));
            }
        }
    }
    Ok(())
}

pub(crate) fn pose_of(pose: KeyPose) -> sim::Pose {
    let t = pose.translation.map(|c| c as f32);
    let r = pose.rotation.map(|c| c as f32);
    sim::Pose::from_parts(
        sim::parry3d::math::Vector::new(t[0], t[1], t[2]),
        sim::parry3d::math::Rot3::from_xyzw(r[0], r[1], r[2], r[3]),
    )
}
