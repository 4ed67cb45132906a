//! Line primitives into strands: `LINE_STRIP` primitives are one strand
//! each, `LINES` primitives join consecutive segments that share an end
//! vertex; their `_NAME` attributes and `TEXCOORD_0` become attributes.
//! Their morph targets are read, or for a stream only checked and read
//! later, target by target, as frames need them.

use super::accessors::Accessor;
use super::document::Document;
use crate::ImportError;
use gltf::json;
use groom::AttributeValues;
use json::mesh::{Mode, Semantic};
use json::validation::Checked;
use std::collections::{BTreeMap, BTreeSet};

/// The groom attribute `TEXCOORD_0` holds, with V flipped back: glTF puts
/// the texture's origin at the top left, groombake (like USD and Alembic)
/// at the bottom left.
pub(super) const ROOT_UV: &str = "root_uv";

/// One line primitive, decoded once however many nodes instance it.
pub(super) struct Lines {
    /// Vertex indices of each strand, into the primitive's accessors.
    pub strands: Vec<Vec<usize>>,
    pub positions: Vec<[f32; 3]>,
    pub attributes: BTreeMap<String, AttributeValues>,
    /// Attributes marked per strand whose values agree along every strand.
    pub per_strand: BTreeSet<String>,
    /// The morph targets, in order.
    pub targets: Vec<Target>,
    pub default_weights: Vec<f32>,
}

/// A morph target of a line primitive.
pub(super) enum Target {
    /// A target without POSITION: it moves nothing.
    Still,
    /// Its position deltas, one per vertex.
    Deltas(Vec<[f32; 3]>),
    /// Checked (type, count, range) but not read yet: its POSITION
    /// accessor, and that reference's JSON pointer for errors.
    Deferred(json::Index<json::Accessor>, String),
}

/// Whether [`Document::lines`] reads the morph targets' deltas or only
/// checks them ([`Target::Deferred`]) for a stream to read the ones a
/// frame needs ([`Document::read_target`]).
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Targets {
    Read,
    Check,
}

impl Lines {
    /// The points one instance adds to the groom.
    pub fn point_count(&self) -> usize {
        self.strands.iter().map(Vec::len).sum()
    }
}

impl Document<'_> {
    /// The strands of a LINES or LINE_STRIP primitive; `None` for other
    /// modes.
    pub fn lines(
        &self,
        mesh_index: usize,
        mesh: &json::Mesh,
        primitive_index: usize,
        primitive: &json::mesh::Primitive,
        targets_wanted: Targets,
    ) -> Result<Option<Lines>, ImportError> {
        let place = format!("/meshes/{mesh_index}/primitives/{primitive_index}");
        let mode = self.valid(&primitive.mode, "primitive mode", || {
            format!("{place}/mode")
        })?;
        if !matches!(mode, Mode::Lines | Mode::LineStrip) {
            return Ok(None);
        }
        let Some(&position) = primitive
            .attributes
            .get(&Checked::Valid(Semantic::Positions))
        else {
            return Err(self.error(place, "line primitive without POSITION"));
        };
        let position = self.accessor(position, || format!("{place}/attributes/POSITION"))?;
        let positions = self.vec3(&position)?;
        let vertex_count = positions.len();
        let indices = self.primitive_indices(&place, primitive, vertex_count)?;
        let strands = match mode {
            Mode::LineStrip if indices.len() >= 2 => vec![indices],
            Mode::LineStrip => Vec::new(),
            _ => chain_segments(&indices),
        };
        let mut attributes = BTreeMap::new();
        let mut per_strand = BTreeSet::new();
        // Vectors and wide integers the exporter split into one scalar
        // accessor per component: name -> (marker, components so far).
        let mut split: BTreeMap<String, (Marker, Vec<Option<AttributeValues>>)> = BTreeMap::new();
        for (semantic, &index) in &primitive.attributes {
            let default_name = match semantic {
                Checked::Valid(Semantic::Extras(name)) => name.to_lowercase(),
                Checked::Valid(Semantic::TexCoords(0)) => ROOT_UV.to_string(),
                _ => continue,
            };
            let accessor = self.accessor(index, || {
                format!("{place}/attributes/{}", semantic_name(semantic))
            })?;
            if accessor.count() != vertex_count as u64 {
                return Err(self.error(
                    accessor.place(),
                    format!(
                        "attribute {} has {} values for {vertex_count} vertices",
                        semantic_name(semantic),
                        accessor.count()
                    ),
                ));
            }
            let marker = Marker::of(&accessor);
            let values = if matches!(semantic, Checked::Valid(Semantic::TexCoords(_))) {
                self.texcoords(&accessor)?
            } else {
                self.custom_attribute(&accessor, &marker)?
            };
            let Some(values) = values else {
                continue;
            };
            match (&marker.name, marker.component, marker.components) {
                (Some(name), Some(k), Some(n)) if k < n && (2..=3).contains(&n) => {
                    let entry = split
                        .entry(name.clone())
                        .or_insert_with(|| (marker.clone(), vec![None; n]));
                    if let Some(slot) = entry.1.get_mut(k) {
                        *slot = Some(values);
                    }
                }
                _ => {
                    let name = marker.name.clone().unwrap_or(default_name);
                    if marker.strand && constant_along(&values, &strands) {
                        per_strand.insert(name.clone());
                    }
                    attributes.insert(name, values);
                }
            }
        }
        for (name, (marker, parts)) in split {
            // An incomplete or mixed set of parts is left out.
            let Some(values) = join_components(&marker, parts) else {
                continue;
            };
            if marker.strand && constant_along(&values, &strands) {
                per_strand.insert(name.clone());
            }
            attributes.insert(name, values);
        }
        let mut targets = Vec::new();
        for (k, target) in primitive.targets.iter().flatten().enumerate() {
            let Some(index) = target.positions else {
                targets.push(Target::Still);
                continue;
            };
            let from = format!("{place}/targets/{k}/POSITION");
            targets.push(match targets_wanted {
                Targets::Read => Target::Deltas(self.target_deltas(index, &from, vertex_count)?),
                Targets::Check => {
                    let accessor = self.accessor(index, || from.clone())?;
                    self.check_floats(&accessor, json::accessor::Type::Vec3)?;
                    self.check_target_count(accessor.count(), vertex_count, &from)?;
                    Target::Deferred(index, from)
                }
            });
        }
        Ok(Some(Lines {
            strands,
            positions,
            attributes,
            per_strand,
            targets,
            default_weights: mesh.weights.clone().unwrap_or_default(),
        }))
    }

    /// Reads target `k` of `lines` if it is [`Target::Deferred`].
    pub fn read_target(&self, lines: &mut Lines, k: usize) -> Result<(), ImportError> {
        let vertex_count = lines.positions.len();
        if let Some(target) = lines.targets.get_mut(k) {
            if let Target::Deferred(index, from) = target {
                *target = Target::Deltas(self.target_deltas(*index, from, vertex_count)?);
            }
        }
        Ok(())
    }

    /// The deltas of the morph target POSITION accessor `index`, referenced
    /// from `from`, which must have one per vertex.
    fn target_deltas(
        &self,
        index: json::Index<json::Accessor>,
        from: &str,
        vertex_count: usize,
    ) -> Result<Vec<[f32; 3]>, ImportError> {
        let accessor = self.accessor(index, || from.to_string())?;
        let deltas = self.vec3(&accessor)?;
        self.check_target_count(deltas.len() as u64, vertex_count, from)?;
        Ok(deltas)
    }

    fn check_target_count(
        &self,
        count: u64,
        vertex_count: usize,
        from: &str,
    ) -> Result<(), ImportError> {
        if count != vertex_count as u64 {
            let place = from.strip_suffix("/POSITION").unwrap_or(from);
            return Err(self.error(place, "morph target POSITION count differs from the base"));
        }
        Ok(())
    }

    /// The vertex indices of a primitive, each checked against the vertex
    /// count; `0..vertex_count` for a primitive without indices.
    pub fn primitive_indices(
        &self,
        place: &str,
        primitive: &json::mesh::Primitive,
        vertex_count: usize,
    ) -> Result<Vec<usize>, ImportError> {
        let Some(index) = primitive.indices else {
            return Ok((0..vertex_count).collect());
        };
        let accessor = self.accessor(index, || format!("{place}/indices"))?;
        let values = self.indices(&accessor)?;
        if let Some(bad) = values.iter().find(|&&i| i >= vertex_count) {
            return Err(self.error(
                accessor.place(),
                format!("index {bad} is out of range ({vertex_count} vertices)"),
            ));
        }
        Ok(values)
    }

    /// TEXCOORD_0 as root UVs (float VEC2 only; V flipped back).
    pub(super) fn texcoords(
        &self,
        accessor: &Accessor,
    ) -> Result<Option<AttributeValues>, ImportError> {
        if accessor.kind != json::accessor::Type::Vec2
            || accessor.component != json::accessor::ComponentType::F32
        {
            return Ok(None);
        }
        let uv = self.vec2(accessor)?;
        Ok(Some(AttributeValues::Vec2(
            uv.into_iter().map(|[u, v]| [u, 1.0 - v]).collect(),
        )))
    }

    /// A `_NAME` attribute, decoded as its extras marker says where the
    /// marker fits the accessor (a marker that does not is ignored).
    fn custom_attribute(
        &self,
        accessor: &Accessor,
        marker: &Marker,
    ) -> Result<Option<AttributeValues>, ImportError> {
        let split = match marker.split_int {
            true => self.split_integers(accessor)?,
            false => None,
        };
        let values = match split {
            Some(values) => Some(values),
            None => self.attribute(accessor)?,
        };
        Ok(values.map(|values| match values {
            values if marker.int => integers_if_exact(values),
            values => values,
        }))
    }
}

/// One attribute from the scalar accessors the exporter split it into:
/// float components into a 2- or 3-vector, the u16 halves of wide integers
/// into i32.
fn join_components(
    marker: &Marker,
    parts: Vec<Option<AttributeValues>>,
) -> Option<AttributeValues> {
    let parts: Vec<AttributeValues> = parts.into_iter().collect::<Option<_>>()?;
    match parts.as_slice() {
        [AttributeValues::Int(lo), AttributeValues::Int(hi)]
            if marker.pair_int && lo.len() == hi.len() =>
        {
            Some(AttributeValues::Int(
                lo.iter()
                    .zip(hi)
                    .map(|(&lo, &hi)| ((hi as u32) << 16 | (lo as u32 & 0xFFFF)) as i32)
                    .collect(),
            ))
        }
        [AttributeValues::Float(x), AttributeValues::Float(y)] if x.len() == y.len() => Some(
            AttributeValues::Vec2(x.iter().zip(y).map(|(&x, &y)| [x, y]).collect()),
        ),
        [AttributeValues::Float(x), AttributeValues::Float(y), AttributeValues::Float(z)]
            if x.len() == y.len() && y.len() == z.len() =>
        {
            Some(AttributeValues::Vec3(
                x.iter()
                    .zip(y)
                    .zip(z)
                    .map(|((&x, &y), &z)| [x, y, z])
                    .collect(),
            ))
        }
        _ => None,
    }
}

/// How a semantic is spelled in the file, for messages.
fn semantic_name(semantic: &Checked<Semantic>) -> String {
    match semantic {
        Checked::Valid(Semantic::Extras(name)) => format!("_{name}"),
        Checked::Valid(Semantic::TexCoords(n)) => format!("TEXCOORD_{n}"),
        Checked::Valid(Semantic::Positions) => "POSITION".into(),
        Checked::Valid(other) => format!("{other:?}"),
        Checked::Invalid => "(unknown)".into(),
    }
}

/// Joins `LINES` segments into strands: a segment that starts where the
/// previous one ended continues its strand; a degenerate segment `(i, i)` is
/// a strand of one point.
pub(super) fn chain_segments(indices: &[usize]) -> Vec<Vec<usize>> {
    let mut strands: Vec<Vec<usize>> = Vec::new();
    for segment in indices.chunks_exact(2) {
        // A segment from a vertex to itself is a one-point strand (how the
        // exporter keeps USC-HairSalon's empty roots).
        if segment[0] == segment[1] {
            strands.push(vec![segment[0]]);
            continue;
        }
        match strands.last_mut() {
            Some(strand) if strand.len() == 1 => strands.push(vec![segment[0], segment[1]]),
            Some(strand) if strand.last() == Some(&segment[0]) => strand.push(segment[1]),
            _ => strands.push(vec![segment[0], segment[1]]),
        }
    }
    strands
}

/// What groombake's exporter keeps in an attribute accessor's
/// `extras.groombake`; all unset for other files.
#[derive(Default, Clone)]
struct Marker {
    name: Option<String>,
    strand: bool,
    int: bool,
    /// i32 as a VEC2 of u16 (files of earlier versions).
    split_int: bool,
    /// i32 as two u16 scalar accessors (components 0 and 1).
    pair_int: bool,
    /// Which component of a split attribute the accessor holds, of how many.
    component: Option<usize>,
    components: Option<usize>,
}

impl Marker {
    fn of(accessor: &Accessor) -> Marker {
        let Some(raw) = &accessor.json.extras else {
            return Marker::default();
        };
        let Ok(extras) = serde_json::from_str::<serde_json::Value>(raw.get()) else {
            return Marker::default();
        };
        let marker = &extras["groombake"];
        let index = |key: &str| marker[key].as_u64().and_then(|v| usize::try_from(v).ok());
        Marker {
            name: marker["name"]
                .as_str()
                .filter(|name| !name.is_empty())
                .map(String::from),
            strand: marker["scope"] == "strand",
            int: marker["type"] == "int",
            split_int: marker["encoding"] == "i32_as_u16x2",
            pair_int: marker["encoding"] == "i32_as_u16_pair",
            component: index("component"),
            components: index("components"),
        }
    }
}

/// Float values that are all whole numbers in i32's range become integers.
fn integers_if_exact(values: AttributeValues) -> AttributeValues {
    match values {
        AttributeValues::Float(floats)
            if floats
                .iter()
                .all(|&v| v.fract() == 0.0 && v >= i32::MIN as f32 && v < i32::MAX as f32) =>
        {
            AttributeValues::Int(floats.into_iter().map(|v| v as i32).collect())
        }
        other => other,
    }
}

/// Whether every strand's vertices (indices into `values`) hold one value.
fn constant_along(values: &AttributeValues, strands: &[Vec<usize>]) -> bool {
    fn constant<T: PartialEq>(values: &[T], strands: &[Vec<usize>]) -> bool {
        strands.iter().all(|strand| {
            let mut picked = strand.iter().map(|&i| values.get(i));
            let first = picked.next().flatten();
            first.is_some() && picked.all(|v| v == first)
        })
    }
    match values {
        AttributeValues::Float(v) => constant(v, strands),
        AttributeValues::Vec2(v) => constant(v, strands),
        AttributeValues::Vec3(v) => constant(v, strands),
        AttributeValues::Int(v) => constant(v, strands),
    }
}
