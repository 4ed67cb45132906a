//! The prims of a groom read from USD, written again where they were: one
//! `BasisCurves` prim per source prim ([`groom::source_prims`]), at its
//! path, under plain `Xform` parents, with its own basis, wrap and
//! attributes (those it did not have are left out, and a `group_id` the
//! reader made up from the prims is not written: reading the file back
//! makes the same). Points are already in world space, so the parents carry
//! no transform. A groom whose table no longer describes its strands, or
//! whose paths cannot be written as one tree, is written flat
//! ([`super::CurvesScene::new`]).
//!
//! [`layout`] gives both writers the order to open and close prims in.

use super::{curves_prim, wrap_of, CurvesPrim, BASES, WRAPS};
use crate::ExportError;
use groom::source_prims::{group_id_is_synthesised, source_prims, SourcePrim};
use groom::{AttributeValues, Groom, Scope};
use std::path::Path;

/// The source prims and their paths' names, when they can be written.
fn table(groom: &Groom) -> Option<(Vec<SourcePrim>, Vec<Vec<String>>)> {
    let table = source_prims(groom)?;
    // `curve_basis` and `curve_wrap` are left out of the prims (each prim
    // says its kind): only where they are the reader's per-prim kind
    // codes. Any other attribute of those names is the groom's own data,
    // which the flat writer keeps.
    for name in ["curve_basis", "curve_wrap"] {
        if groom.attribute(name).is_none() {
            continue;
        }
        let kinds = if name == "curve_wrap" {
            WRAPS.len()
        } else {
            BASES.len()
        };
        let codes = per_strand(groom, name)?;
        let mut first = 0usize;
        for prim in &table {
            let own = codes.get(first..first + prim.strands)?;
            let kind = *own.first()?;
            if usize::try_from(kind).map_or(true, |k| k >= kinds) || own.iter().any(|&c| c != kind)
            {
                return None;
            }
            first += prim.strands;
        }
    }
    let components = table
        .iter()
        .map(|prim| prim_path(&prim.path))
        .collect::<Option<Vec<_>>>()?;
    one_tree(&components).then_some((table, components))
}

/// Whether the groom is written prim by prim at its source's paths.
pub(super) fn writable(groom: &Groom) -> bool {
    table(groom).is_some()
}

/// The curves prims of a groom that keeps its source prims, or `None` when
/// it is to be written flat.
pub(super) fn source_prims_of(
    path: &Path,
    groom: &Groom,
) -> Result<Option<Vec<CurvesPrim>>, ExportError> {
    let Some((table, components)) = table(groom) else {
        return Ok(None);
    };
    let offsets = groom.strand_offsets();
    let basis_codes = per_strand(groom, "curve_basis");
    let wrap_codes = per_strand(groom, "curve_wrap");
    let mut prims = Vec::with_capacity(table.len());
    let mut first = 0usize;
    for (prim, mut parts) in table.iter().zip(components) {
        let strands: Vec<usize> = (first..first + prim.strands).collect();
        let mut part = groom.select_strands(&strands);
        if let Some(basis) = basis_codes
            .and_then(|c| c.get(first))
            .and_then(|&c| usize::try_from(c).ok())
            .and_then(|c| BASES.get(c))
        {
            part.basis = *basis;
        }
        let wrap = wrap_codes
            .and_then(|c| c.get(first))
            .and_then(|&c| usize::try_from(c).ok())
            .and_then(|c| WRAPS.get(c).copied())
            .unwrap_or_else(|| wrap_of(groom));
        part.provenance
            .metadata
            .insert("usd.wrap".into(), wrap.into());
        let mut omitted = vec!["curve_basis".to_string(), "curve_wrap".to_string()];
        if group_id_is_synthesised(groom) {
            omitted.push("group_id".into());
        }
        omitted.extend(prim.missing.iter().cloned());
        for name in &omitted {
            part.remove_attribute(name);
        }
        let name = parts.pop().unwrap_or_default();
        let vertices = offsets[first]..offsets[first + prim.strands];
        let strand_range = first..first + prim.strands;
        let mut curves = curves_prim(
            path,
            &part,
            name,
            std::iter::once(vertices).collect(),
            std::iter::once(strand_range).collect(),
        )?;
        curves.parents = parts;
        curves.omitted = omitted;
        prims.push(curves);
        first += prim.strands;
    }
    Ok(Some(prims))
}

/// A per-strand integer attribute of the groom's strand count.
fn per_strand<'g>(groom: &'g Groom, name: &str) -> Option<&'g [i32]> {
    match groom.attribute(name).map(|a| (&a.values, a.scope)) {
        Some((AttributeValues::Int(codes), Scope::Strand))
            if codes.len() == groom.strand_count() =>
        {
            Some(codes)
        }
        _ => None,
    }
}

/// The names of an absolute prim path, when each is a USD identifier.
fn prim_path(path: &str) -> Option<Vec<String>> {
    let rest = path.strip_prefix('/')?;
    let parts: Vec<String> = rest.split('/').map(str::to_string).collect();
    let identifier = |name: &str| {
        name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
            && name.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_')
    };
    parts.iter().all(|p| identifier(p)).then_some(parts)
}

/// Whether the paths, in order, form one tree written in one pass: no path
/// twice, none inside another curves prim, and each parent's prims
/// together (a parent, once closed, is not opened again).
fn one_tree(paths: &[Vec<String>]) -> bool {
    let mut seen: std::collections::HashSet<&[String]> = std::collections::HashSet::new();
    let mut closed: std::collections::HashSet<Vec<String>> = std::collections::HashSet::new();
    let mut open: Vec<String> = Vec::new();
    for path in paths {
        if !seen.insert(path.as_slice()) {
            return false;
        }
        let parents = &path[..path.len() - 1];
        // Ancestors are Xforms: none may be a curves prim of the table.
        if (1..path.len()).any(|n| seen.contains(&path[..n])) {
            return false;
        }
        let shared = open.iter().zip(parents).take_while(|(a, b)| a == b).count();
        while open.len() > shared {
            closed.insert(open.clone());
            open.pop();
        }
        for name in &parents[shared..] {
            open.push(name.clone());
            if closed.contains(&open) || seen.contains(open.as_slice()) {
                return false;
            }
        }
        // A curves prim is closed at once.
        closed.insert(path.clone());
    }
    true
}

/// One step of writing the prims of a scene, depth-first.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Step {
    /// Open an `Xform` parent at this depth (0: a root prim).
    Open { name: String, depth: usize },
    /// Write curves prim `index` of the scene, at this depth.
    Curves { index: usize, depth: usize },
    /// Close the `Xform` opened at this depth.
    Close { depth: usize },
}

/// The order to write the scene's prims in: parents opened before their
/// first curves prim and closed after their last.
pub(crate) fn layout(prims: &[CurvesPrim]) -> Vec<Step> {
    let mut steps = Vec::new();
    let mut open: Vec<&str> = Vec::new();
    for (index, prim) in prims.iter().enumerate() {
        let shared = open
            .iter()
            .zip(&prim.parents)
            .take_while(|(a, b)| **a == b.as_str())
            .count();
        while open.len() > shared {
            open.pop();
            steps.push(Step::Close { depth: open.len() });
        }
        for name in &prim.parents[shared..] {
            steps.push(Step::Open {
                name: name.clone(),
                depth: open.len(),
            });
            open.push(name);
        }
        steps.push(Step::Curves {
            index,
            depth: open.len(),
        });
    }
    while !open.is_empty() {
        open.pop();
        steps.push(Step::Close { depth: open.len() });
    }
    steps
}

/// The stage's `defaultPrim`: the first root prim.
pub(crate) fn default_prim(prims: &[CurvesPrim]) -> &str {
    prims
        .first()
        .map(|p| p.parents.first().unwrap_or(&p.name).as_str())
        .unwrap_or(super::ROOT_PRIM)
}

/// The root prims' names, in order.
pub(crate) fn roots(prims: &[CurvesPrim]) -> Vec<&str> {
    let mut out: Vec<&str> = Vec::new();
    for prim in prims {
        let root = prim.parents.first().unwrap_or(&prim.name).as_str();
        if !out.contains(&root) {
            out.push(root);
        }
    }
    out
}

/// The names of the prims directly under the `Xform` at `prefix` (its
/// names, root first), in order.
pub(crate) fn children_of<'p>(prims: &'p [CurvesPrim], prefix: &[String]) -> Vec<&'p str> {
    let mut out: Vec<&str> = Vec::new();
    for prim in prims {
        if prim.parents.len() < prefix.len() || prim.parents[..prefix.len()] != *prefix {
            continue;
        }
        let child = prim
            .parents
            .get(prefix.len())
            .unwrap_or(&prim.name)
            .as_str();
        if !out.contains(&child) {
            out.push(child);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn paths(list: &[&str]) -> Vec<Vec<String>> {
        list.iter().map(|p| prim_path(p).unwrap()).collect()
    }

    #[test]
    fn paths_that_make_one_tree() {
        assert!(one_tree(&paths(&["/A/b", "/A/C/d", "/A/e", "/F"])));
        // /A reopened after /G.
        assert!(!one_tree(&paths(&["/A/b", "/G/c", "/A/d"])));
        // A curves prim inside another.
        assert!(!one_tree(&paths(&["/A/b", "/A/b/c"])));
        assert!(!one_tree(&paths(&["/A/b", "/A/b"])));
        assert_eq!(prim_path("/A/1b"), None);
        assert_eq!(prim_path("A/b"), None);
    }
}
