//! Composition: the layer a user opens, with its sublayers, references,
//! payloads, inherits and specializes followed, flattened into one prim list
//! as usd-core composes the stage (instanceable prims read as their instance
//! proxies do, since a flattened copy holds the same curves).
//!
//! Opinion strength follows USD's LIVRPS in the cases grooms use: a layer is
//! stronger than its sublayers, a prim's own opinions are stronger than what
//! its arcs bring, and the arcs of one prim are applied strongest first
//! (inherits, references, payloads, specializes). An attribute authored in a
//! stronger place replaces the weaker one; missing pieces (a default value,
//! an interpolation) are taken from the weaker. Variants are not selected.
//!
//! Written here because no Rust crate composes USD; every arc is resolved
//! relative to the layer that authors it, a layer is parsed once, and the
//! depth and the number of composed prims are bounded. Layer offsets of
//! sublayers, references and payloads move the time samples they bring
//! (`t * scale + offset`, composed through nested arcs); a crate file's
//! sublayer offsets and a
//! difference in `timeCodesPerSecond` between layers are not applied.

use super::{Arc, ArcTarget, LayerOffset, Prim, Specifier, Stage};
use crate::{ImportError, Place};
use std::collections::HashMap;
use std::path::{Component, Path, PathBuf};

/// Deepest chain of arcs followed (a cycle ends here with an error).
const MAX_ARC_DEPTH: usize = 64;
/// Largest layer an arc may bring, in bytes.
const MAX_LAYER_BYTES: u64 = 8 << 30;
/// Most prims a composed stage may hold.
const MAX_COMPOSED_PRIMS: usize = 4_000_000;

/// A prim with its children, and its arcs tagged with the layer that
/// authored them.
#[derive(Clone)]
struct Node {
    prim: Prim,
    arcs: Vec<(Arc, usize)>,
    children: Vec<Node>,
}

struct Layer {
    file: PathBuf,
    default_prim: Option<String>,
    roots: Vec<Node>,
}

struct Composer {
    layers: Vec<Layer>,
    by_file: HashMap<PathBuf, usize>,
    prims: usize,
    notes: Vec<String>,
}

/// Composes the stage whose root layer `stage` was read from `file`.
pub(super) fn compose(file: &Path, stage: Stage) -> Result<Stage, ImportError> {
    let mut composer = Composer {
        layers: Vec::new(),
        by_file: HashMap::new(),
        prims: 0,
        notes: Vec::new(),
    };
    let simple = stage.sublayers.is_empty() && stage.prims.iter().all(|p| p.arcs.is_empty());
    if simple {
        return Ok(stage);
    }
    let mut composed = Stage {
        meters_per_unit: stage.meters_per_unit,
        up_axis: stage.up_axis.clone(),
        time_codes_per_second: stage.time_codes_per_second,
        frames_per_second: stage.frames_per_second,
        default_prim: stage.default_prim.clone(),
        ..Stage::default()
    };
    let root = composer.add_layer(file, stage, 0)?;
    // The root layer's own tree stays for its internal arcs to fetch from.
    let mut roots = composer.layers[root].roots.clone();
    for node in &mut roots {
        composer.resolve(node, 0)?;
    }
    composed.notes = std::mem::take(&mut composer.notes);
    for node in roots {
        flatten(node, None, &mut composed.prims);
    }
    Ok(composed)
}

/// A layer's own prims as a tree.
fn tree(prims: Vec<Prim>, layer: usize) -> Vec<Node> {
    let mut nodes: Vec<Option<Node>> = Vec::with_capacity(prims.len());
    let mut parents = Vec::with_capacity(prims.len());
    for mut prim in prims {
        let arcs = std::mem::take(&mut prim.arcs)
            .into_iter()
            .map(|arc| (arc, layer))
            .collect();
        parents.push(prim.parent.filter(|&p| p < nodes.len()));
        nodes.push(Some(Node {
            prim,
            arcs,
            children: Vec::new(),
        }));
    }
    // Children come after their parents: attach from the last one back.
    let mut roots = Vec::new();
    for index in (0..nodes.len()).rev() {
        let Some(node) = nodes[index].take() else {
            continue;
        };
        match parents[index].and_then(|p| nodes[p].as_mut()) {
            Some(parent) => parent.children.insert(0, node),
            None => roots.insert(0, node),
        }
    }
    roots
}

fn flatten(node: Node, parent: Option<usize>, out: &mut Vec<Prim>) {
    let index = out.len();
    let mut prim = node.prim;
    prim.parent = parent;
    out.push(prim);
    for child in node.children {
        flatten(child, Some(index), out);
    }
}

/// Merges `weaker` opinions into `stronger` (same prim path).
fn merge(stronger: &mut Node, weaker: Node) {
    let prim = &mut stronger.prim;
    if prim.specifier == Specifier::Over {
        prim.specifier = weaker.prim.specifier;
    }
    if prim.type_name.is_empty() {
        prim.type_name = weaker.prim.type_name;
    }
    for attribute in weaker.prim.attributes {
        match prim
            .attributes
            .iter_mut()
            .find(|a| a.name == attribute.name)
        {
            Some(existing) => {
                if existing.default.is_none() && existing.samples.is_empty() {
                    existing.default = attribute.default;
                    existing.samples = attribute.samples;
                }
                if existing.interpolation.is_none() {
                    existing.interpolation = attribute.interpolation;
                }
                if existing.element_size.is_none() {
                    existing.element_size = attribute.element_size;
                }
                if existing.type_name.is_empty() {
                    existing.type_name = attribute.type_name;
                }
            }
            None => prim.attributes.push(attribute),
        }
    }
    stronger.arcs.extend(weaker.arcs);
    for child in weaker.children {
        let name = child.prim.path.rsplit('/').next().unwrap_or("").to_string();
        match stronger
            .children
            .iter_mut()
            .find(|c| c.prim.path.rsplit('/').next() == Some(name.as_str()))
        {
            Some(existing) => merge(existing, child),
            None => stronger.children.push(child),
        }
    }
}

/// Gives a subtree brought by an arc the path of the prim it lands on.
fn reroot(node: &mut Node, from: &str, to: &str) {
    if let Some(rest) = node.prim.path.strip_prefix(from) {
        node.prim.path = format!("{to}{rest}");
    }
    for child in &mut node.children {
        reroot(child, from, to);
    }
}

fn find<'n>(nodes: &'n [Node], path: &str) -> Option<&'n Node> {
    let mut names = path.trim_start_matches('/').split('/');
    let first = names.next()?;
    let mut node = nodes.iter().find(|n| n.prim.path == format!("/{first}"))?;
    let mut so_far = format!("/{first}");
    for name in names {
        so_far = format!("{so_far}/{name}");
        node = node.children.iter().find(|n| n.prim.path == so_far)?;
    }
    Some(node)
}

fn count(node: &Node) -> usize {
    1 + node.children.iter().map(count).sum::<usize>()
}

impl Composer {
    /// Adds a parsed layer with its sublayers merged in; returns its index.
    fn add_layer(&mut self, file: &Path, stage: Stage, depth: usize) -> Result<usize, ImportError> {
        let index = self.layers.len();
        self.by_file.insert(file.to_path_buf(), index);
        self.notes.extend(stage.notes);
        self.layers.push(Layer {
            file: file.to_path_buf(),
            default_prim: stage.default_prim,
            roots: Vec::new(),
        });
        let mut roots = tree(stage.prims, index);
        self.prims += roots.iter().map(count).sum::<usize>();
        for (asset, place, offset) in stage.sublayers {
            let arc = format!("subLayers @{asset}@");
            let sub = self.load(file, &asset, &arc, &place, depth + 1)?;
            for mut node in self.layers[sub].roots.clone() {
                retime(&mut node, offset);
                let name = node.prim.path.clone();
                match roots.iter_mut().find(|r| r.prim.path == name) {
                    Some(existing) => merge(existing, node),
                    None => roots.push(node),
                }
            }
        }
        self.layers[index].roots = roots;
        self.check_budget(file)?;
        Ok(index)
    }

    /// The layer `asset` names, relative to the layer `from` that authors
    /// the arc `arc` at `place`; parsed once.
    fn load(
        &mut self,
        from: &Path,
        asset: &str,
        arc: &str,
        place: &Place,
        depth: usize,
    ) -> Result<usize, ImportError> {
        let here = |message: String| ImportError::malformed(from, place.clone(), message);
        if depth > MAX_ARC_DEPTH {
            return Err(here(format!(
                "{arc}: arcs nest deeper than {MAX_ARC_DEPTH} layers (a cycle?)"
            )));
        }
        // Without `.` components, so that a layer reached as `./a.usda`
        // from `./b.usda` is the layer already loaded, and errors name it plainly.
        let file: PathBuf = from
            .parent()
            .unwrap_or(Path::new(""))
            .join(asset)
            .components()
            .filter(|c| !matches!(c, Component::CurDir))
            .collect();
        if let Some(&index) = self.by_file.get(&file) {
            return Ok(index);
        }
        let cannot_open =
            |e: std::io::Error| here(format!("{arc}: cannot open {}: {e}", file.display()));
        // A layer is a regular file of bounded size: an arc (which the file
        // chooses) to a device (`/dev/zero`), a pipe or `/proc/kcore` would
        // never end or allocate without bound.
        let metadata = std::fs::metadata(&file).map_err(cannot_open)?;
        if !metadata.is_file() {
            return Err(here(format!(
                "{arc}: {} is not a regular file",
                file.display()
            )));
        }
        if metadata.len() > MAX_LAYER_BYTES {
            return Err(here(format!(
                "{arc}: {} is larger than {} GiB",
                file.display(),
                MAX_LAYER_BYTES >> 30
            )));
        }
        let bytes = std::fs::read(&file).map_err(cannot_open)?;
        let stage = super::parse_layer(&file, &bytes)?;
        self.add_layer(&file, stage, depth)
    }

    fn check_budget(&self, file: &Path) -> Result<(), ImportError> {
        if self.prims > MAX_COMPOSED_PRIMS {
            return Err(ImportError::malformed(
                file,
                Place::File,
                format!("composition brings more than {MAX_COMPOSED_PRIMS} prims"),
            ));
        }
        Ok(())
    }

    /// Follows the arcs of `node` and of everything under it.
    fn resolve(&mut self, node: &mut Node, depth: usize) -> Result<(), ImportError> {
        let arcs = std::mem::take(&mut node.arcs);
        for (arc, layer) in arcs {
            for target in &arc.targets {
                let mut source = self.fetch(&arc, target, layer, depth)?;
                retime(&mut source, target.offset);
                merge(node, land(source, &node.prim.path));
            }
        }
        // Arcs merged in from weaker opinions (sublayers' overs).
        if !node.arcs.is_empty() {
            if depth > MAX_ARC_DEPTH {
                let file = self.layers[node.arcs[0].1].file.clone();
                return Err(ImportError::malformed(
                    &file,
                    node.arcs[0].0.place.clone(),
                    format!("arcs nest deeper than {MAX_ARC_DEPTH} (a cycle?)"),
                ));
            }
            return self.resolve(node, depth + 1);
        }
        for child in &mut node.children {
            self.resolve(child, depth)?;
        }
        Ok(())
    }

    /// The composed subtree an arc target brings, with its own paths.
    fn fetch(
        &mut self,
        arc: &Arc,
        target: &ArcTarget,
        layer: usize,
        depth: usize,
    ) -> Result<Node, ImportError> {
        let from = self.layers[layer].file.clone();
        let described = format!(
            "{} {}{}",
            arc.kind.key(),
            target
                .asset
                .as_ref()
                .map_or(String::new(), |a| format!("@{a}@")),
            target
                .prim_path
                .as_ref()
                .map_or(String::new(), |p| format!("<{p}>"))
        );
        let here = |message: String| ImportError::malformed(&from, arc.place.clone(), message);
        if depth > MAX_ARC_DEPTH {
            return Err(here(format!(
                "{described}: arcs nest deeper than {MAX_ARC_DEPTH} (a cycle?)"
            )));
        }
        let source_layer = match &target.asset {
            Some(asset) => self.load(&from, asset, &described, &arc.place, depth + 1)?,
            None => layer,
        };
        let source_file = self.layers[source_layer].file.clone();
        let path = match (&target.prim_path, &self.layers[source_layer].default_prim) {
            (Some(path), _) => path.clone(),
            (None, Some(default)) => format!("/{default}"),
            (None, None) => {
                return Err(here(format!(
                    "{described}: names no prim and {} has no defaultPrim",
                    source_file.display()
                )))
            }
        };
        let mut source = find(&self.layers[source_layer].roots, &path)
            .cloned()
            .ok_or_else(|| {
                here(format!(
                    "{described}: {} has no prim <{path}>",
                    source_file.display()
                ))
            })?;
        self.prims += count(&source);
        self.check_budget(&from)?;
        self.resolve(&mut source, depth + 1)?;
        Ok(source)
    }
}

/// Moves the time samples of a subtree a sublayer or an arc brings into
/// the time of the layer that authors it (its layer offset).
fn retime(node: &mut Node, offset: LayerOffset) {
    if offset.is_identity() {
        return;
    }
    for attribute in &mut node.prim.attributes {
        for (code, _) in &mut attribute.samples {
            *code = offset.apply(*code);
        }
        // A negative scale reverses them.
        attribute.samples.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    // Arcs not yet followed bring their times through this offset too.
    for (arc, _) in &mut node.arcs {
        for target in &mut arc.targets {
            target.offset = LayerOffset {
                offset: offset.apply(target.offset.offset),
                scale: target.offset.scale * offset.scale,
            };
        }
    }
    for child in &mut node.children {
        retime(child, offset);
    }
}

/// Gives a fetched subtree the path of the prim it composes into.
fn land(mut source: Node, landing: &str) -> Node {
    let from = source.prim.path.clone();
    reroot(&mut source, &from, landing);
    source
}
