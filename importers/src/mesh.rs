//! Triangle meshes for colliders (a head, a pillow): `.obj` faces and glTF
//! TRIANGLES / TRIANGLE_STRIP / TRIANGLE_FAN primitives, as vertices and
//! index triples.

use crate::obj_syntax::{statements, ForwardReferences};
use crate::{extension_of, read_bytes, ImportError, Place};
use std::path::Path;

pub use crate::mesh_types::{Mesh, Triangles};

/// Reads the triangles of an `.obj`, `.glb` or `.gltf` file (node
/// transforms applied for glTF).
pub fn read_triangles(path: &Path) -> Result<Triangles, ImportError> {
    let mesh = read_mesh(path)?;
    Ok((mesh.vertices, mesh.triangles))
}

/// Reads the triangles and corner UVs of an `.obj`, `.glb` or `.gltf`
/// file (node transforms applied for glTF).
pub fn read_mesh(path: &Path) -> Result<Mesh, ImportError> {
    let mesh = match extension_of(path).as_str() {
        "obj" => parse_obj_mesh(path, &read_bytes(path)?)?,
        "glb" | "gltf" => crate::gltf::read_mesh(path)?,
        _ => {
            return Err(ImportError::malformed(
                path,
                Place::File,
                "collider meshes are read from .obj, .glb or .gltf",
            ))
        }
    };
    if mesh.triangles.is_empty() {
        return Err(ImportError::malformed(
            path,
            Place::File,
            "the file has no triangles",
        ));
    }
    Ok(mesh)
}

/// The triangles of an `.obj` file (see [`parse_obj_mesh`]).
pub fn parse_obj(path: &Path, bytes: &[u8]) -> Result<Triangles, ImportError> {
    let mesh = parse_obj_mesh(path, bytes)?;
    Ok((mesh.vertices, mesh.triangles))
}

/// `v x y z [w]` vertices, `vt u [v [w]]` texture coordinates and
/// `f i j k ...` faces (1-based indices, negative ones relative to those
/// read so far; `i/t/n` references give the vertex and texture coordinate
/// indices). Polygons become triangle fans; other statements (lines,
/// normals, groups, materials) are skipped. The mesh has corner UVs when
/// every face corner names a texture coordinate.
pub fn parse_obj_mesh(path: &Path, bytes: &[u8]) -> Result<Mesh, ImportError> {
    let mut vertices: Vec<[f32; 3]> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut uvs: Vec<[f32; 2]> = Vec::new();
    // Per triangle: its corners' texture coordinate indices, while every
    // corner so far had one.
    let mut corner_uv_indices: Option<Vec<[usize; 3]>> = Some(Vec::new());
    let mut forward = ForwardReferences::default();
    let mut texture_forward = ForwardReferences::default();
    for statement in statements(path, bytes) {
        let mut statement = statement?;
        match statement.keyword {
            "v" => {
                let point = statement
                    .coordinates(|token, _| format!("'{token}' is not a finite number"))?;
                // Triangles index vertices with u32.
                if vertices.len() > u32::MAX as usize - 1 {
                    return Err(statement.error(1, "more than 2^32 vertices".into()));
                }
                vertices.push(point);
            }
            "vt" => {
                let uv = statement.texture_coordinates()?;
                // Bounded like the vertices: indices are at most u32::MAX.
                if uvs.len() > u32::MAX as usize - 1 {
                    return Err(statement.error(1, "more than 2^32 texture coordinates".into()));
                }
                uvs.push(uv);
            }
            "f" => {
                let indices = statement.corner_indices(
                    vertices.len(),
                    i64::from(u32::MAX),
                    &mut forward,
                    Some((uvs.len(), &mut texture_forward)),
                )?;
                let corners: Vec<u32> = indices.iter().map(|&(v, _)| v as u32).collect();
                let textures: Option<Vec<usize>> = indices.iter().map(|&(_, t)| t).collect();
                if corners.len() < 3 {
                    return Err(statement.error(
                        1,
                        format!("face has {} corners, needs at least 3", corners.len()),
                    ));
                }
                // Polygons as triangle fans around their first corner.
                for pair in corners[1..].windows(2) {
                    triangles.push([corners[0], pair[0], pair[1]]);
                }
                corner_uv_indices = match (corner_uv_indices, textures) {
                    (Some(mut fans), Some(t)) => {
                        fans.extend(t[1..].windows(2).map(|pair| [t[0], pair[0], pair[1]]));
                        Some(fans)
                    }
                    _ => None,
                };
            }
            _ => {}
        }
    }
    forward.check(path, vertices.len())?;
    texture_forward.check_textures(path, uvs.len())?;
    // Every index was checked against the texture coordinates read.
    let corner_uvs = corner_uv_indices
        .filter(|fans| !fans.is_empty())
        .map(|fans| {
            fans.iter()
                .map(|t| t.map(|i| uvs.get(i).copied().unwrap_or([0.0; 2])))
                .collect()
        });
    Ok(Mesh {
        vertices,
        triangles,
        corner_uvs,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_str(text: &str) -> Result<Triangles, ImportError> {
        parse_obj(Path::new("t.obj"), text.as_bytes())
    }

    #[test]
    fn obj_polygons_become_fans_with_relative_and_forward_indices() {
        let (v, t) =
            parse_str("f 1 2 3\nv 0 0 0\nv 1 0 0 # x\nv 1 1 0\r\nv 0 1 0\nf 1/1 2/2/2 3//3 -1\nvt 0 0\nvt 1 0\n")
                .unwrap();
        assert_eq!(v.len(), 4);
        assert_eq!(v[3], [0.0, 1.0, 0.0]);
        assert_eq!(t, vec![[0, 1, 2], [0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn obj_errors_name_line_and_column() {
        let cases = [
            (
                "v 0 0 0\nf 1 2 3\n",
                "t.obj:2:5: vertex index 2 is out of range",
            ),
            (
                "v 0 0 0\nf 1 -2 1\n",
                "t.obj:2:5: vertex index -2 is out of range",
            ),
            (
                "v 0 0 0\nf 0 1 1\n",
                "t.obj:2:3: vertex index 0 is out of range",
            ),
            ("v 0 0 0\nf 1 x 1\n", "t.obj:2:5: 'x' is not a vertex index"),
            ("v 0 0 0\nf 1 1\n", "t.obj:2:1: face has 2 corners"),
            ("v 0 inf 0\n", "t.obj:1:5: 'inf' is not a finite number"),
            ("v 0 0\n", "t.obj:1:6: vertex has 2 coordinates"),
        ];
        for (text, expected) in cases {
            let e = parse_str(text).unwrap_err().to_string();
            assert!(e.starts_with(expected), "{text:?}: {e}");
        }
        let e = parse_obj(Path::new("t.obj"), b"v 0 0 0\n\xff\n")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("t.obj:2:1: not UTF-8"), "{e}");
    }

    #[test]
    fn obj_texture_coordinates_become_corner_uvs() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0.25 0.5\nvt 0.75 0.5 0\n\
                    vt 0.75 1\nvt 0.25\nf 1/1 2/2/1 3/3 4/-1\n";
        let mesh = parse_obj_mesh(Path::new("t.obj"), text.as_bytes()).unwrap();
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(
            mesh.corner_uvs,
            Some(vec![
                [[0.25, 0.5], [0.75, 0.5], [0.75, 1.0]],
                [[0.25, 0.5], [0.75, 1.0], [0.25, 0.0]],
            ])
        );
        // A face without texture coordinates leaves the mesh without UVs.
        let partial = "v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nf 1/1 2/1 3/1\nf 1 2 3\n";
        let mesh = parse_obj_mesh(Path::new("t.obj"), partial.as_bytes()).unwrap();
        assert_eq!((mesh.triangles.len(), mesh.corner_uvs), (2, None));
        let cases = [
            (
                "v 0 0 0\nvt 0 0\nf 1/1 1/2 1/1\n",
                "t.obj:3:7: texture coordinate index 2 is out of range (the file has 1",
            ),
            (
                "v 0 0 0\nvt 0 0\nf 1/1 1/-2 1/1\n",
                "t.obj:3:7: texture coordinate index -2 is out of range (1 texture",
            ),
            (
                "v 0 0 0\nvt 0 0\nf 1/0 1/1 1/1\n",
                "t.obj:3:3: texture coordinate index 0 is out of range",
            ),
            (
                "v 0 0 0\nf 1/x 1 1\n",
                "t.obj:2:3: '1/x' has no valid texture coordinate index",
            ),
            ("vt nan 0\n", "t.obj:1:4: 'nan' is not a finite number"),
            ("vt\n", "t.obj:1:3: texture coordinate has no u"),
        ];
        for (text, expected) in cases {
            let e = parse_str(text).unwrap_err().to_string();
            assert!(e.starts_with(expected), "{text:?}: {e}");
        }
    }

    #[test]
    fn obj_truncations_never_panic() {
        let text = b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\nf -4 -2 -1\n";
        for cut in 0..text.len() {
            let _ = parse_obj(Path::new("t.obj"), &text[..cut]);
        }
    }

    #[test]
    fn files_without_triangles_or_of_other_formats_are_refused() {
        let dir = tempdir();
        let lines = dir.join("lines.obj");
        std::fs::write(&lines, "v 0 0 0\nv 1 0 0\nl 1 2\n").unwrap();
        let e = read_triangles(&lines).unwrap_err().to_string();
        assert!(e.ends_with("lines.obj: the file has no triangles"), "{e}");
        let e = read_triangles(&dir.join("head.hair"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("collider meshes are read from"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn samples_load() {
        let samples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../samples");
        let (vertices, triangles) = read_triangles(&samples.join("head.obj")).unwrap();
        assert!(
            (600..=1500).contains(&triangles.len()),
            "{}",
            triangles.len()
        );
        // The head is a closed ellipsoid of semi-axes 0.08, 0.10, 0.09 m.
        for (axis, radius) in [0.08f32, 0.10, 0.09].into_iter().enumerate() {
            let max = vertices.iter().map(|p| p[axis].abs()).fold(0.0, f32::max);
            assert!((max - radius).abs() < 1e-4, "axis {axis}: {max}");
        }
        assert_closed(&triangles);
        let (_, pillow) = read_triangles(&samples.join("pillow.glb")).unwrap();
        assert_eq!(pillow.len(), 12);
        assert_closed(&pillow);
    }

    /// Every edge is used once in each direction: closed and consistently
    /// oriented.
    pub(crate) fn assert_closed(triangles: &[[u32; 3]]) {
        let mut edges = std::collections::BTreeMap::new();
        for t in triangles {
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        for (&(a, b), &count) in &edges {
            assert_eq!(count, 1, "edge {a}-{b} used {count} times");
            assert_eq!(edges.get(&(b, a)), Some(&1), "edge {a}-{b} has no twin");
        }
    }

    fn tempdir() -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("groombake-mesh-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }
}
