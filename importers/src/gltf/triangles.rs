//! Triangle primitives for mesh colliders.

use super::document::Document;
use crate::ImportError;
use gltf::json;
use groom::AttributeValues;
use json::mesh::{Mode, Semantic};
use json::validation::Checked;

/// The most vertices, and the most triangles, a collider mesh may have once
/// instanced meshes are expanded (a few shared nodes can multiply a small
/// file into an enormous mesh).
pub(super) const MAX_MESH_VERTICES: usize = 1 << 24;
pub(super) const MAX_MESH_TRIANGLES: usize = 1 << 25;

/// A triangle primitive: positions, triangles (indices into them) and
/// the TEXCOORD_0 of each position (V flipped back), if it has them.
pub(super) struct TrianglePrimitive {
    pub positions: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
    pub uvs: Option<Vec<[f32; 2]>>,
}

impl Document<'_> {
    /// The positions and triangles (indices into those positions) of a
    /// TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN primitive; `None` for other
    /// modes. Triangles that repeat a vertex (how strips are joined) are left
    /// out: they have no area.
    pub fn triangles(
        &self,
        mesh_index: usize,
        primitive_index: usize,
        primitive: &json::mesh::Primitive,
    ) -> Result<Option<TrianglePrimitive>, ImportError> {
        let place = format!("/meshes/{mesh_index}/primitives/{primitive_index}");
        let mode = self.valid(&primitive.mode, "primitive mode", || {
            format!("{place}/mode")
        })?;
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            return Ok(None);
        }
        let Some(&position) = primitive
            .attributes
            .get(&Checked::Valid(Semantic::Positions))
        else {
            return Err(self.error(place, "triangle primitive without POSITION"));
        };
        let position = self.accessor(position, || format!("{place}/attributes/POSITION"))?;
        let positions = self.vec3(&position)?;
        if positions.len() > MAX_MESH_VERTICES {
            return Err(self.error(
                position.place(),
                format!(
                    "{} vertices are more than the {MAX_MESH_VERTICES} a collider mesh may have",
                    positions.len()
                ),
            ));
        }
        let indices = self.primitive_indices(&place, primitive, positions.len())?;
        // Indices are below the vertex count, itself below u32::MAX.
        let corner = |k: usize| indices.get(k).map_or(0, |&i| i as u32);
        let mut triangles = Vec::new();
        match mode {
            Mode::Triangles => {
                if indices.len() % 3 != 0 {
                    return Err(self.error(
                        place,
                        format!(
                            "TRIANGLES primitive with {} vertices (indices), not a multiple of 3",
                            indices.len()
                        ),
                    ));
                }
                for k in (0..indices.len()).step_by(3) {
                    triangles.push([corner(k), corner(k + 1), corner(k + 2)]);
                }
            }
            // glTF 2.0 section 3.7.2.1: strip triangle i is (i, i+1, i+2)
            // for even i and (i, i+2, i+1) for odd i, so all face one way;
            // fan triangle i is (i+1, i+2, 0).
            Mode::TriangleStrip => {
                for k in 0..indices.len().saturating_sub(2) {
                    triangles.push(if k % 2 == 0 {
                        [corner(k), corner(k + 1), corner(k + 2)]
                    } else {
                        [corner(k), corner(k + 2), corner(k + 1)]
                    });
                }
            }
            _ => {
                for k in 0..indices.len().saturating_sub(2) {
                    triangles.push([corner(k + 1), corner(k + 2), corner(0)]);
                }
            }
        }
        triangles.retain(|[a, b, c]| a != b && b != c && a != c);
        let uvs = match primitive
            .attributes
            .get(&Checked::Valid(Semantic::TexCoords(0)))
        {
            Some(&uv) => {
                let accessor = self.accessor(uv, || format!("{place}/attributes/TEXCOORD_0"))?;
                match self.texcoords(&accessor)? {
                    Some(AttributeValues::Vec2(uvs)) if uvs.len() == positions.len() => Some(uvs),
                    _ => None,
                }
            }
            None => None,
        };
        Ok(Some(TrianglePrimitive {
            positions,
            triangles,
            uvs,
        }))
    }
}
