//! The mesh types every mesh reader returns (`.obj` in [`crate::mesh`], glTF
//! in its own module), in a file of their own so the readers and the
//! dispatcher that picks one by extension do not import each other.

/// Vertices and triangles (indices into the vertices) of a mesh file.
pub type Triangles = (Vec<[f32; 3]>, Vec<[u32; 3]>);

/// A mesh file's triangles and, when every face has them, the texture
/// coordinates (U, V with V up, as `.obj` and the groom's `root_uv` have
/// them) of each triangle's three corners.
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    pub vertices: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
    /// Per triangle: the UVs of its corners, in the triangle's order.
    pub corner_uvs: Option<Vec<[[f32; 2]; 3]>>,
}
