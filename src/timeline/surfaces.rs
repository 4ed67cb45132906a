//! The colliders of a timeline as triangle surfaces for the preview: for
//! each snapshot of a bake (before the first stage, after each stage), the
//! colliders active then, where their motion has them, and for a snapshot
//! during a perm the rods the hair is wound on.

use super::error::BakeError;
use super::motion::pose_at;
use super::schema::ColliderActivity;
use super::shapes::{pose_of, shape_of};
use super::stages::RodCylinder;
use super::Timeline;
use crate::preview::Surface;
use crate::sim::parry3d::math::Vector;
use crate::sim::parry3d::shape::{Cylinder, SharedShape};

/// A collider's colour in previews (linear RGB): a pale, neutral grey-blue
/// that no attribute ramp uses.
const COLLIDER_COLOR: [f32; 3] = [0.42, 0.45, 0.52];

/// A perm rod's colour in previews (linear RGB): a warm pink, as the
/// plastic rods are, lighter than the hair and unlike the colliders.
pub const ROD_COLOR: [f32; 3] = [0.85, 0.40, 0.55];

/// A snapshot taken during a perm (the hair wound on its rods): where it is
/// among the snapshots, the stage and the time (s from the bake's start)
/// it was taken at, and the rods.
#[derive(Debug, Clone)]
pub struct RodSnapshot {
    pub snapshot: usize,
    pub stage: usize,
    pub time: f64,
    pub rods: Vec<RodCylinder>,
}

/// Subdivisions of round shapes: smooth enough at preview sizes.
const ROUND_SUBDIVISIONS: u32 = 24;

/// The surfaces to draw with each snapshot of a bake of `timeline`: first the
/// colliders of the first stage at time 0, then, for each stage, the
/// colliders of that stage at its end; and, at the places `rods` name
/// (in snapshot order, as the bake took them), the colliders then with the
/// perm's rods. Half-spaces (infinite) are not drawn.
pub fn snapshot_surfaces(
    timeline: &Timeline,
    rods: &[RodSnapshot],
) -> Result<Vec<Vec<Surface>>, BakeError> {
    let colliders = &timeline.file.colliders;
    let meshes = colliders
        .iter()
        .map(|c| Ok(triangles_of(&shape_of(timeline, c.shape.get_ref())?)))
        .collect::<Result<Vec<_>, BakeError>>()?;
    let stages = timeline.file.stages.get_ref();
    let surfaces_at = |stage: usize, time: f64| -> Vec<Surface> {
        let Some(spec) = stages.get(stage) else {
            return Vec::new();
        };
        colliders
            .iter()
            .zip(&meshes)
            .filter(|(c, _)| {
                c.active == ColliderActivity::Always
                    || spec
                        .colliders
                        .iter()
                        .any(|n| n.get_ref() == c.name.get_ref())
            })
            .filter_map(|(c, mesh)| {
                let (vertices, triangles) = mesh.as_ref()?;
                let pose = pose_of(pose_at(c.motion.get_ref(), time));
                let placed: Vec<[f32; 3]> = vertices
                    .iter()
                    .map(|v| {
                        let p = pose.transform_point(*v);
                        [p.x, p.y, p.z]
                    })
                    .collect();
                Some(Surface {
                    triangles: corners(&placed, triangles),
                    color: COLLIDER_COLOR,
                })
            })
            .collect()
    };
    let mut out = vec![surfaces_at(0, 0.0)];
    let mut time = 0.0;
    for (index, stage) in stages.iter().enumerate() {
        time += *stage.duration.get_ref();
        out.push(surfaces_at(index, time));
    }
    for during in rods {
        let mut surfaces = surfaces_at(during.stage, during.time);
        surfaces.extend(during.rods.iter().map(rod_surface));
        out.insert(during.snapshot.min(out.len()), surfaces);
    }
    Ok(out)
}

/// A perm rod as a closed cylinder surface.
fn rod_surface(rod: &RodCylinder) -> Surface {
    let (vertices, triangles) =
        Cylinder::new(rod.half_length, rod.radius).to_trimesh(ROUND_SUBDIVISIONS);
    let [a, u] = [rod.axis, rod.across];
    let w = [
        a[1] * u[2] - a[2] * u[1],
        a[2] * u[0] - a[0] * u[2],
        a[0] * u[1] - a[1] * u[0],
    ];
    // parry's cylinder lies along its Y axis: Y goes to the rod's axis.
    let placed: Vec<[f32; 3]> = vertices
        .iter()
        .map(|v| [0, 1, 2].map(|k| rod.center[k] + v.x * u[k] + v.y * a[k] + v.z * w[k]))
        .collect();
    Surface {
        triangles: corners(&placed, &triangles),
        color: ROD_COLOR,
    }
}

/// Each indexed triangle as its three placed corners.
fn corners(placed: &[[f32; 3]], triangles: &[[u32; 3]]) -> Vec<[[f32; 3]; 3]> {
    triangles
        .iter()
        .filter_map(|t| {
            Some([
                *placed.get(t[0] as usize)?,
                *placed.get(t[1] as usize)?,
                *placed.get(t[2] as usize)?,
            ])
        })
        .collect()
}

/// The triangles of a collider shape in its own frame; `None` for a
/// half-space, which has no finite surface to draw.
fn triangles_of(shape: &SharedShape) -> Option<(Vec<Vector>, Vec<[u32; 3]>)> {
    if let Some(cuboid) = shape.as_cuboid() {
        Some(cuboid.to_trimesh())
    } else if let Some(ball) = shape.as_ball() {
        Some(ball.to_trimesh(ROUND_SUBDIVISIONS, ROUND_SUBDIVISIONS / 2))
    } else if let Some(capsule) = shape.as_capsule() {
        Some(capsule.to_trimesh(ROUND_SUBDIVISIONS, ROUND_SUBDIVISIONS / 2))
    } else if let Some(cylinder) = shape.as_cylinder() {
        Some(cylinder.to_trimesh(ROUND_SUBDIVISIONS))
    } else {
        shape
            .as_trimesh()
            .map(|mesh| (mesh.vertices().to_vec(), mesh.indices().to_vec()))
    }
}
