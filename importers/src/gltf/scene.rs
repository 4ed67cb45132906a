//! The scene graph: which nodes the default scene holds, and their world
//! matrices (column-major, `m[column][row]`).

use super::document::Document;
use crate::ImportError;
use gltf::json;
use std::collections::btree_map::Entry;
use std::collections::BTreeMap;

pub(super) type Matrix = [[f32; 4]; 4];

const IDENTITY: Matrix = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
];

/// The most node instances a walk visits: nodes shared by several parents
/// could make it exponential.
const MAX_NODE_INSTANCES: usize = 1 << 20;
/// The deepest hierarchy a walk follows (deeper is a cycle, in practice).
const MAX_DEPTH: usize = 1024;

/// Visits every node instance of the default (or first) scene depth-first,
/// parents before children, with its index, JSON and world matrix.
pub(super) fn walk(
    document: &Document,
    mut visit: impl FnMut(usize, &json::Node, Matrix) -> Result<(), ImportError>,
) -> Result<(), ImportError> {
    let root = &document.root;
    let scene = match root.scene {
        Some(index) => {
            Some(document.get(&root.scenes, index.value(), "scene", || "/scene".into())?)
        }
        None => root.scenes.first(),
    };
    let roots: Vec<(usize, String)> = match scene {
        Some(scene) => {
            let scene_index = root.scene.map_or(0, |s| s.value());
            scene
                .nodes
                .iter()
                .enumerate()
                .map(|(k, n)| (n.value(), format!("/scenes/{scene_index}/nodes/{k}")))
                .collect()
        }
        None => Vec::new(),
    };
    let mut stack: Vec<(usize, String, Matrix, usize)> = roots
        .into_iter()
        .rev()
        .map(|(n, from)| (n, from, IDENTITY, 0))
        .collect();
    let mut visits = 0usize;
    while let Some((index, from, parent, depth)) = stack.pop() {
        visits += 1;
        if visits > MAX_NODE_INSTANCES {
            return Err(document.error(
                "/nodes",
                "scene graph has over a million node instances (nodes shared by many parents?)",
            ));
        }
        let node = document.get(&root.nodes, index, "node", || from)?;
        if depth > MAX_DEPTH {
            return Err(document.error(
                format!("/nodes/{index}"),
                format!("node hierarchy deeper than {MAX_DEPTH} (a cycle?)"),
            ));
        }
        let local = local_matrix(node);
        if local.iter().flatten().any(|v| !v.is_finite()) {
            return Err(document.error(
                format!("/nodes/{index}"),
                "transform has a value that is not finite",
            ));
        }
        let world = multiply(&parent, &local);
        visit(index, node, world)?;
        let children = node.children.as_deref().unwrap_or_default();
        for (k, child) in children.iter().enumerate().rev() {
            stack.push((
                child.value(),
                format!("/nodes/{index}/children/{k}"),
                world,
                depth + 1,
            ));
        }
    }
    Ok(())
}

/// A node's matrix, or its translation, rotation and scale composed as
/// glTF says (T * R * S), by the `gltf` crate's own arithmetic.
fn local_matrix(node: &json::Node) -> Matrix {
    match node.matrix {
        Some(m) => [
            [m[0], m[1], m[2], m[3]],
            [m[4], m[5], m[6], m[7]],
            [m[8], m[9], m[10], m[11]],
            [m[12], m[13], m[14], m[15]],
        ],
        None => gltf::scene::Transform::Decomposed {
            translation: node.translation.unwrap_or([0.0; 3]),
            rotation: node.rotation.unwrap_or_default().0,
            scale: node.scale.unwrap_or([1.0; 3]),
        }
        .matrix(),
    }
}

pub(super) fn multiply(a: &Matrix, b: &Matrix) -> Matrix {
    let mut m = [[0.0f32; 4]; 4];
    for (column, out) in m.iter_mut().enumerate() {
        for (row, value) in out.iter_mut().enumerate() {
            *value = (0..4).map(|k| a[k][row] * b[column][k]).sum();
        }
    }
    m
}

/// Determinant of the linear (upper-left 3x3) part of a transform.
pub(super) fn determinant(m: &Matrix) -> f32 {
    m[0][0] * (m[1][1] * m[2][2] - m[2][1] * m[1][2])
        - m[1][0] * (m[0][1] * m[2][2] - m[2][1] * m[0][2])
        + m[2][0] * (m[0][1] * m[1][2] - m[1][1] * m[0][2])
}

pub(super) fn transform(m: &Matrix, p: [f32; 3]) -> [f32; 3] {
    let mut out = [0.0f32; 3];
    for (row, value) in out.iter_mut().enumerate() {
        *value = m[0][row] * p[0] + m[1][row] * p[1] + m[2][row] * p[2] + m[3][row];
    }
    out
}

/// Every instance of every mesh primitive of the default scene, in [`walk`]
/// order: each (mesh, primitive) is decoded once by `decode` (`None`: not
/// of the wanted kind, skipped), then `visit` gets the node's index, its
/// world matrix, the decoded primitive's slot and the primitive, for each
/// node that instances it. Returns the decoded primitives by slot.
pub(super) fn walk_primitives<T>(
    document: &Document,
    mut decode: impl FnMut(
        usize,
        &json::Mesh,
        usize,
        &json::mesh::Primitive,
    ) -> Result<Option<T>, ImportError>,
    mut visit: impl FnMut(usize, Matrix, usize, &T) -> Result<(), ImportError>,
) -> Result<Vec<T>, ImportError> {
    let mut decoded: Vec<T> = Vec::new();
    let mut slot_of: BTreeMap<(usize, usize), Option<usize>> = BTreeMap::new();
    walk(document, |node_index, node, world| {
        let Some(mesh_index) = node.mesh.map(|m| m.value()) else {
            return Ok(());
        };
        let mesh = document.get(&document.root.meshes, mesh_index, "mesh", || {
            format!("/nodes/{node_index}/mesh")
        })?;
        for (primitive_index, primitive) in mesh.primitives.iter().enumerate() {
            let slot = match slot_of.entry((mesh_index, primitive_index)) {
                Entry::Occupied(entry) => *entry.get(),
                Entry::Vacant(entry) => {
                    let primitive = decode(mesh_index, mesh, primitive_index, primitive)?;
                    *entry.insert(primitive.map(|p| {
                        decoded.push(p);
                        decoded.len() - 1
                    }))
                }
            };
            if let Some(slot) = slot {
                visit(node_index, world, slot, &decoded[slot])?;
            }
        }
        Ok(())
    })?;
    Ok(decoded)
}
