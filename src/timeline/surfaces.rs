//! The colliders of a timeline as triangle surfaces for the preview: for
//! each snapshot of a bake (before the first stage, after each stage), the
//! colliders active then, where their motion has them, and for a snapshot
//! during a perm the rods the hair is wound on.
//!
//! The head is drawn solid (opaque, skin-coloured, hiding the hair behind
//! it): each collider active in every stage (`active = "always"`, the
//! schema's head) and the head ellipsoid of a `wind` stage; with neither,
//! the head a `[groom] generate` of layout `scalp` or `head` rooted the
//! hair on (its `scalp_mesh`, or the ellipsoid of `head_center` and
//! `head_radii`). Colliders that come and go (a pillow) stay
//! semi-transparent.

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

/// Subdivisions of a round head: its outline stays round in a large picture.
const HEAD_SUBDIVISIONS: u32 = 64;

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
        .map(|c| {
            let subdivisions = if c.active == ColliderActivity::Always {
                HEAD_SUBDIVISIONS
            } else {
                ROUND_SUBDIVISIONS
            };
            Ok(triangles_of(
                &shape_of(timeline, c.shape.get_ref())?,
                subdivisions,
            ))
        })
        .collect::<Result<Vec<_>, BakeError>>()?;
    let heads = heads_without_collider(timeline)?;
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
                let triangles = corners(&placed, triangles);
                Some(if c.active == ColliderActivity::Always {
                    Surface::head(triangles)
                } else {
                    Surface {
                        triangles,
                        color: COLLIDER_COLOR,
                        solid: false,
                    }
                })
            })
            .chain(heads.iter().cloned())
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
        solid: false,
    }
}

/// Whether the snapshots of `timeline` draw a head (a collider always
/// active, a wind stage's head, or the head a generated groom grows on).
pub fn draws_a_head(timeline: &Timeline) -> bool {
    use crate::generate::RootLayout;
    let file = &timeline.file;
    file.colliders
        .iter()
        .any(|c| c.active == ColliderActivity::Always)
        || file.stages.get_ref().iter().any(|s| s.wind.is_some())
        || file
            .groom
            .generate
            .as_ref()
            .is_some_and(|g| matches!(g.get_ref().layout, RootLayout::Head | RootLayout::Scalp))
}

/// The heads that are no collider: the ellipsoid of each `wind` stage; with
/// no head at all (neither that nor an always-active collider), the one a
/// generated groom is rooted on.
fn heads_without_collider(timeline: &Timeline) -> Result<Vec<Surface>, BakeError> {
    use crate::generate::RootLayout;
    let mut heads: Vec<Surface> = Vec::new();
    for stage in timeline.file.stages.get_ref() {
        if let Some(wind) = &stage.wind {
            let head = &wind.get_ref().head;
            heads.push(ellipsoid(
                head.center.map(|c| c as f32),
                head.radii.map(|r| r as f32),
            ));
        }
    }
    let has_head = timeline
        .file
        .colliders
        .iter()
        .any(|c| c.active == ColliderActivity::Always);
    let generated = timeline.file.groom.generate.as_ref().map(|g| g.get_ref());
    if let (false, true, Some(p)) = (has_head, heads.is_empty(), generated) {
        match (&p.layout, &p.scalp_mesh) {
            (RootLayout::Head, Some(mesh)) => {
                let path = timeline.resolve(&mesh.to_string_lossy());
                let mesh = importers::mesh::read_mesh(&path).map_err(|e| BakeError::Input {
                    file: path.clone(),
                    message: format!("the scalp mesh: {e}"),
                })?;
                heads.push(Surface::head(corners(&mesh.vertices, &mesh.triangles)));
            }
            (RootLayout::Head | RootLayout::Scalp, _) => {
                heads.push(ellipsoid(p.head_center, p.head_radii));
            }
            _ => {}
        }
    }
    Ok(heads)
}

/// A head ellipsoid of `center` and semi-axes `radii`.
fn ellipsoid(center: [f32; 3], radii: [f32; 3]) -> Surface {
    let (vertices, triangles) = crate::sim::parry3d::shape::Ball::new(1.0)
        .to_trimesh(HEAD_SUBDIVISIONS, HEAD_SUBDIVISIONS / 2);
    let placed: Vec<[f32; 3]> = vertices
        .iter()
        .map(|v| {
            let unit = [v.x, v.y, v.z];
            [0, 1, 2].map(|k| center[k] + radii[k] * unit[k])
        })
        .collect();
    Surface::head(corners(&placed, &triangles))
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
fn triangles_of(shape: &SharedShape, subdivisions: u32) -> Option<(Vec<Vector>, Vec<[u32; 3]>)> {
    if let Some(cuboid) = shape.as_cuboid() {
        Some(cuboid.to_trimesh())
    } else if let Some(ball) = shape.as_ball() {
        Some(ball.to_trimesh(subdivisions, subdivisions / 2))
    } else if let Some(capsule) = shape.as_capsule() {
        Some(capsule.to_trimesh(subdivisions, subdivisions / 2))
    } else if let Some(cylinder) = shape.as_cylinder() {
        Some(cylinder.to_trimesh(subdivisions))
    } else {
        shape
            .as_trimesh()
            .map(|mesh| (mesh.vertices().to_vec(), mesh.indices().to_vec()))
    }
}
