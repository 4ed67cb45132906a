//! Triangle meshes for colliders (a head, a pillow): `.obj` faces and glTF
//! TRIANGLES / TRIANGLE_STRIP / TRIANGLE_FAN primitives, as vertices and
//! index triples.

use crate::obj_syntax::{statements, ForwardReferences};
use crate::{extension_of, read_bytes, ImportError, Place};
use std::path::Path;

/// Vertices and triangles (indices into the vertices) of a mesh file.
pub type Triangles = (Vec<[f32; 3]>, Vec<[u32; 3]>);

/// Reads the triangles of an `.obj`, `.glb` or `.gltf` file (node
/// transforms applied for glTF).
pub fn read_triangles(path: &Path) -> Result<Triangles, ImportError> {
    let mesh = match extension_of(path).as_str() {
        "obj" => read_obj(path)?,
        "glb" | "gltf" => crate::gltf::read_triangles(path)?,
        _ => {
            return Err(ImportError::malformed(
                path,
                Place::File,
                "collider meshes are read from .obj, .glb or .gltf",
            ))
        }
    };
    if mesh.1.is_empty() {
        return Err(ImportError::malformed(
            path,
            Place::File,
            "the file has no triangles",
        ));
    }
    Ok(mesh)
}

fn read_obj(path: &Path) -> Result<Triangles, ImportError> {
    parse_obj(path, &read_bytes(path)?)
}

/// `v x y z [w]` vertices and `f i j k ...` faces (1-based indices, negative
/// ones relative to the vertices read so far, `i/t/n` references keep the
/// vertex index). Polygons become triangle fans; other statements (lines,
/// normals, groups, materials) are skipped.
pub fn parse_obj(path: &Path, bytes: &[u8]) -> Result<Triangles, ImportError> {
    let mut vertices: Vec<[f32; 3]> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut forward = ForwardReferences::default();
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
            "f" => {
                let corners: Vec<u32> = statement
                    .vertex_indices(vertices.len(), i64::from(u32::MAX), &mut forward)?
                    .into_iter()
                    .map(|index| index as u32)
                    .collect();
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
            }
            _ => {}
        }
    }
    forward.check(path, vertices.len())?;
    Ok((vertices, triangles))
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
            parse_str("f 1 2 3\nv 0 0 0\nv 1 0 0 # x\nv 1 1 0\r\nv 0 1 0\nf 1/1 2/2/2 3//3 -1\n")
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
