//! From the object tree to a groom: every Curves object, placed by the
//! transforms above it, with its samples, widths, uvs and arbitrary
//! geometry parameters.

use super::archive::{Archive, Kind, Object, Pod, Property};
use super::ogawa::Fault;
use crate::transform::{multiply, scaling, transform_point, translation, Matrix, IDENTITY};
use groom::{Attribute, AttributeValues, CurveBasis, Frame, Groom, Scope, Units};

/// Imath's `setAxisAngle`, transposed for column vectors; `degrees` as
/// Alembic stores them.
fn axis_angle(axis: [f64; 3], degrees: f64) -> Matrix {
    let length = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    if length == 0.0 {
        return IDENTITY;
    }
    let [u0, u1, u2] = axis.map(|a| a / length);
    let (s, c) = degrees.to_radians().sin_cos();
    let t = 1.0 - c;
    [
        [
            u0 * u0 * t + c,
            u0 * u1 * t - u2 * s,
            u0 * u2 * t + u1 * s,
            0.0,
        ],
        [
            u0 * u1 * t + u2 * s,
            u1 * u1 * t + c,
            u1 * u2 * t - u0 * s,
            0.0,
        ],
        [
            u0 * u2 * t - u1 * s,
            u1 * u2 * t + u0 * s,
            u2 * u2 * t + c,
            0.0,
        ],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

/// A matrix as Imath stores it (16 values, row by row, for row vectors),
/// transposed for column vectors.
fn from_imath(v: &[f64]) -> Matrix {
    let mut m = IDENTITY;
    for (index, value) in v.iter().take(16).enumerate() {
        m[index % 4][index / 4] = *value;
    }
    m
}

/// Converts stored values of any numeric type to f64, component by component.
fn components(pod: Pod, bytes: &[u8], path: &str) -> Result<Vec<f64>, Fault> {
    let size = pod
        .size()
        .ok_or_else(|| Fault::path(path, "string values where numbers were expected"))?;
    if !bytes.len().is_multiple_of(size) {
        return Err(Fault::path(
            path,
            format!(
                "{} bytes is not a whole number of {size}-byte values",
                bytes.len()
            ),
        ));
    }
    let values = bytes.chunks_exact(size).map(|c| {
        let mut word = [0u8; 8];
        word[..size].copy_from_slice(c);
        let raw = u64::from_le_bytes(word);
        match pod {
            Pod::Bool | Pod::U8 => raw as u8 as f64,
            Pod::I8 => raw as u8 as i8 as f64,
            Pod::U16 => raw as u16 as f64,
            Pod::I16 => raw as u16 as i16 as f64,
            Pod::U32 => raw as u32 as f64,
            Pod::I32 => raw as u32 as i32 as f64,
            Pod::U64 => raw as f64,
            Pod::I64 => raw as i64 as f64,
            Pod::F16 => f64::from(half_to_f32(raw as u16)),
            Pod::F32 => f64::from(f32::from_bits(raw as u32)),
            Pod::F64 => f64::from_bits(raw),
            Pod::String | Pod::WString => 0.0,
        }
    });
    Ok(values.collect())
}

fn half_to_f32(bits: u16) -> f32 {
    let sign = if bits & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exponent = i32::from((bits >> 10) & 0x1f);
    let mantissa = f32::from(bits & 0x3ff);
    match exponent {
        0 => sign * mantissa * 2f32.powi(-24),
        31 if mantissa == 0.0 => sign * f32::INFINITY,
        31 => f32::NAN,
        _ => sign * (1.0 + mantissa / 1024.0) * 2f32.powi(exponent - 15),
    }
}

/// Limits the bytes decoded from samples: shared blocks could otherwise make
/// a small file expand without bound.
struct Budget {
    remaining: u64,
}

impl Budget {
    fn take(&mut self, bytes: usize, path: &str) -> Result<(), Fault> {
        let bytes = bytes as u64;
        if bytes > self.remaining {
            return Err(Fault::path(
                path,
                "the samples decode to far more data than the file holds (too many shared samples)",
            ));
        }
        self.remaining -= bytes;
        Ok(())
    }
}

/// One Curves object, read and placed.
struct Part {
    path: String,
    counts: Vec<u32>,
    /// Sample 0 first; more for an animated object.
    samples: Vec<Vec<[f32; 3]>>,
    times: Vec<f64>,
    basis: CurveBasis,
    attributes: Vec<Attribute>,
    /// `.arbGeomParams` whose samples change with `P`'s: each one's value
    /// at every sample (as a bake writes its bond rates and wetness).
    frame_attributes: Vec<Vec<Attribute>>,
}

struct SceneReader<'r, 'a> {
    archive: &'r Archive<'a>,
    budget: Budget,
    notes: Vec<String>,
    /// `Some(k)`: read only sample `k` of each object (its last one when
    /// it has fewer), for a frame-at-a-time reader; `None`: every sample.
    only_sample: Option<u32>,
    /// The times of the most-sampled object's samples (every one, even
    /// when only one sample is read).
    times: Vec<f64>,
}

/// Reads every Curves object of the archive into one groom.
pub fn read_groom(archive: &Archive) -> Result<Groom, Fault> {
    read_groom_samples(archive, None).map(|(groom, _)| groom)
}

/// Reads every Curves object of the archive into one groom, with every
/// sample (`only_sample` `None`) or only sample `k` of each object as the
/// groom's rest points and its single frame (when the file is animated);
/// also the times of all the file's frames.
pub fn read_groom_samples(
    archive: &Archive,
    only_sample: Option<u32>,
) -> Result<(Groom, Vec<f64>), Fault> {
    let mut reader = SceneReader {
        only_sample,
        times: Vec::new(),
        archive,
        budget: Budget {
            remaining: archive
                .ogawa
                .size()
                .saturating_mul(64)
                .saturating_add(64 << 20),
        },
        notes: Vec::new(),
    };
    let mut parts = Vec::new();
    reader.walk(&archive.top, &IDENTITY, &mut parts)?;
    let mut groom = merge(parts, &mut reader.budget)?;
    groom.provenance.format = "abc".into();
    let (units, units_source) = archive_units(&archive.metadata);
    groom.units = units;
    groom.provenance.units_source = units_source;
    let mut info = archive
        .metadata
        .get("_ai_Application")
        .unwrap_or_default()
        .to_string();
    for note in &reader.notes {
        if !info.is_empty() {
            info.push_str("; ");
        }
        info.push_str(note);
    }
    groom.provenance.info = info;
    Ok((groom, reader.times))
}

/// The units of an archive by the units rule: groombake's own mark, else the
/// writing application's working units (Alembic has no unit field), else
/// centimetres. Returns the units and the rule that gave them.
pub fn archive_units(metadata: &super::archive::Metadata) -> (Units, String) {
    if let Some(units) = metadata
        .get(groom::ALEMBIC_UNITS_KEY)
        .and_then(|u| u.parse().ok())
    {
        return (units, "file".into());
    }
    match metadata.get("_ai_Application") {
        // groombake marks any units but centimetres.
        Some(application) if application.starts_with("groombake") => {
            (Units::CENTIMETERS, "file".into())
        }
        Some(application) => {
            let units = application_units(application).unwrap_or(Units::CENTIMETERS);
            (units, format!("application {application}"))
        }
        None => (Units::CENTIMETERS, "format".into()),
    }
}

/// The units an application writes Alembic in: Blender and Houdini in
/// metres, Maya and Unreal in centimetres; `None` for others (taken as
/// centimetres, the groom tools' convention).
pub fn application_units(application: &str) -> Option<Units> {
    let name = application.to_ascii_lowercase();
    if name.contains("blender") || name.contains("houdini") {
        Some(Units::METERS)
    } else if name.contains("maya") || name.contains("unreal") {
        Some(Units::CENTIMETERS)
    } else {
        None
    }
}

fn schema(object: &Object) -> &str {
    object.metadata.get("schema").unwrap_or_default()
}

impl SceneReader<'_, '_> {
    fn walk(
        &mut self,
        object: &Object,
        parent: &Matrix,
        parts: &mut Vec<Part>,
    ) -> Result<(), Fault> {
        let mut world = *parent;
        let kind = schema(object);
        if kind.starts_with("AbcGeom_Xform") {
            let (local, inherits) = self.xform(object)?;
            world = if inherits {
                multiply(parent, &local)
            } else {
                local
            };
        } else if kind.starts_with("AbcGeom_Curve") {
            parts.push(self.curves(object, &world)?);
        }
        for child in &object.children {
            self.walk(child, &world, parts)?;
        }
        Ok(())
    }

    fn sample_values(&mut self, property: &Property, index: u32) -> Result<Vec<f64>, Fault> {
        if property.kind == Kind::Compound {
            return Err(Fault::path(
                &property.path,
                "expected values, found a compound",
            ));
        }
        let bytes = self.archive.sample(property, index)?;
        // Each sample costs at least a little, so empty ones cannot repeat
        // without bound either.
        self.budget.take(
            bytes.len().saturating_mul(2).saturating_add(64),
            &property.path,
        )?;
        let values = components(property.pod, bytes, &property.path)?;
        let extent = usize::from(property.extent).max(1);
        if !values.len().is_multiple_of(extent) {
            return Err(Fault::path(
                &property.path,
                format!(
                    "{} values is not a whole number of {extent}-component elements",
                    values.len()
                ),
            ));
        }
        Ok(values)
    }

    /// The points of sample `index` of `P`; 32-bit floats are read as they
    /// are, other types through [`components`].
    fn points(&mut self, property: &Property, index: u32) -> Result<Vec<[f32; 3]>, Fault> {
        let bytes = self.archive.sample(property, index)?;
        self.budget
            .take(bytes.len().saturating_add(64), &property.path)?;
        if property.pod == Pod::F32 {
            if !bytes.len().is_multiple_of(12) {
                return Err(Fault::path(
                    &property.path,
                    format!("{} bytes is not a whole number of points", bytes.len()),
                ));
            }
            let f = |c: &[u8]| f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
            return Ok(bytes
                .chunks_exact(12)
                .map(|c| [f(&c[0..4]), f(&c[4..8]), f(&c[8..12])])
                .collect());
        }
        let values = self.sample_values(property, index)?;
        if !values.len().is_multiple_of(3) {
            return Err(Fault::path(
                &property.path,
                format!("{} values is not a whole number of points", values.len()),
            ));
        }
        Ok(values
            .chunks_exact(3)
            .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32])
            .collect())
    }

    /// The local matrix of an Xform (its first sample) and whether it
    /// inherits its parent's.
    fn xform(&mut self, object: &Object) -> Result<(Matrix, bool), Fault> {
        let Some(xform) = object.property(".xform") else {
            return Ok((IDENTITY, true));
        };
        let inherits = match xform.child(".inherits") {
            Some(p) if p.sample_count > 0 => {
                self.sample_values(p, 0)?.first().is_none_or(|&v| v != 0.0)
            }
            _ => true,
        };
        let Some(ops) = xform.child(".ops").filter(|p| p.sample_count > 0) else {
            return Ok((IDENTITY, inherits));
        };
        let codes = self.sample_values(ops, 0)?;
        let values = match xform.child(".vals").filter(|p| p.sample_count > 0) {
            Some(vals) => self.sample_values(vals, 0)?,
            None => Vec::new(),
        };
        let path = format!("{}/.xform", object.path);
        let mut matrix = IDENTITY;
        let mut next = 0usize;
        for code in codes {
            let kind = (code as u8) >> 4;
            let channels = match kind {
                0..=1 => 3,
                2 => 4,
                3 => 16,
                4..=6 => 1,
                _ => {
                    return Err(Fault::path(
                        &path,
                        format!("unknown transform operation {kind}"),
                    ))
                }
            };
            let v = values.get(next..next + channels).ok_or_else(|| {
                Fault::path(
                    &path,
                    format!(
                        "the operations need more than the {} values stored",
                        values.len()
                    ),
                )
            })?;
            next += channels;
            if v.iter().any(|x| !x.is_finite()) {
                return Err(Fault::path(&path, "a transform value is not finite"));
            }
            let op = match kind {
                0 => scaling([v[0], v[1], v[2]]),
                1 => translation([v[0], v[1], v[2]]),
                2 => axis_angle([v[0], v[1], v[2]], v[3]),
                3 => from_imath(v),
                4 => axis_angle([1.0, 0.0, 0.0], v[0]),
                5 => axis_angle([0.0, 1.0, 0.0], v[0]),
                _ => axis_angle([0.0, 0.0, 1.0], v[0]),
            };
            // Each operation applies before the ones already accumulated.
            matrix = multiply(&matrix, &op);
        }
        Ok((matrix, inherits))
    }

    fn curves(&mut self, object: &Object, world: &Matrix) -> Result<Part, Fault> {
        let path = object.path.clone();
        let geom = object
            .property(".geom")
            .filter(|p| p.kind == Kind::Compound)
            .ok_or_else(|| Fault::path(&path, "Curves object without a .geom compound"))?;
        let positions = geom
            .child("P")
            .filter(|p| p.kind != Kind::Compound)
            .ok_or_else(|| Fault::path(&format!("{path}/.geom"), "Curves without P"))?;
        let n_vertices = geom
            .child("nVertices")
            .filter(|p| p.kind != Kind::Compound)
            .ok_or_else(|| Fault::path(&format!("{path}/.geom"), "Curves without nVertices"))?;
        if positions.extent != 3 || positions.pod.is_integer() {
            return Err(Fault::path(
                &positions.path,
                "P must hold 3 floating-point components per point",
            ));
        }
        if positions.sample_count == 0 {
            return Err(Fault::path(&positions.path, "P has no samples"));
        }
        let counts = self.counts(n_vertices)?;
        let total: u64 = counts.iter().map(|&c| u64::from(c)).sum();
        let basis = self.basis(geom)?;
        // Several samples make frames even when they are all equal: the file
        // says when they are.
        let animated = positions.sample_count > 1;
        let sample_count = if animated { positions.sample_count } else { 1 };
        if animated && sample_count as usize > self.times.len() {
            // The header's count is unchecked: the budget bounds the list.
            self.budget
                .take((sample_count as usize).saturating_mul(8), &positions.path)?;
            self.times = (0..sample_count)
                .map(|index| self.archive.sample_time(positions, index))
                .collect::<Result<_, _>>()?;
        }
        let wanted = match self.only_sample {
            Some(k) => k.min(sample_count - 1)..k.min(sample_count - 1) + 1,
            None => 0..sample_count,
        };
        let mut samples = Vec::new();
        let mut times = Vec::new();
        for index in wanted.clone() {
            let mut points = self.points(positions, index)?;
            if points.len() as u64 != total {
                return Err(Fault::path(
                    &positions.path,
                    format!(
                        "sample {index} has {} points but nVertices adds up to {total}",
                        points.len()
                    ),
                ));
            }
            if *world != IDENTITY {
                for p in &mut points {
                    *p = transform_point(world, p.map(f64::from)).map(|c| c as f32);
                }
            }
            samples.push(points);
            if animated {
                times.push(self.archive.sample_time(positions, index)?);
            }
        }
        let mut part = Part {
            path: path.clone(),
            counts,
            samples,
            times,
            basis,
            attributes: Vec::new(),
            frame_attributes: Vec::new(),
        };
        let vertex_count = total as usize;
        for property in &geom.children {
            let name = match property.name.as_str() {
                "width" => "width".to_string(),
                "uv" => "uv".to_string(),
                _ => continue,
            };
            if let Some(attribute) =
                self.geom_param(property, &name, vertex_count, part.counts.len(), 0)?
            {
                part.attributes.push(attribute);
            }
        }
        if let Some(arbitrary) = geom.child(".arbGeomParams") {
            for property in &arbitrary.children {
                let name = property.name.clone();
                if let Some(attribute) =
                    self.geom_param(property, &name, vertex_count, part.counts.len(), 0)?
                {
                    // Sampled with `P` and not the same throughout: a value
                    // per frame.
                    if animated
                        && property.kind != Kind::Compound
                        && property.sample_count == sample_count
                    {
                        if self.only_sample.is_some() {
                            // One frame: its value, whether or not it
                            // differs from the others (not read).
                            let at = self.geom_param(
                                property,
                                &name,
                                vertex_count,
                                part.counts.len(),
                                wanted.start,
                            )?;
                            if let Some(a) = at.filter(|a| a.scope == attribute.scope) {
                                part.frame_attributes.push(vec![a]);
                            }
                            part.attributes.push(attribute);
                            continue;
                        }
                        let mut values = vec![attribute.clone()];
                        for index in 1..sample_count {
                            let at = self.geom_param(
                                property,
                                &name,
                                vertex_count,
                                part.counts.len(),
                                index,
                            )?;
                            match at {
                                Some(a) if a.scope == attribute.scope => values.push(a),
                                _ => break,
                            }
                        }
                        let complete = values.len() == sample_count as usize;
                        if complete && values.iter().any(|v| v.values != attribute.values) {
                            part.frame_attributes.push(values);
                        }
                    }
                    part.attributes.push(attribute);
                }
            }
        }
        Ok(part)
    }

    fn counts(&mut self, n_vertices: &Property) -> Result<Vec<u32>, Fault> {
        if !n_vertices.pod.is_integer() || n_vertices.extent != 1 {
            return Err(Fault::path(&n_vertices.path, "nVertices must be integers"));
        }
        if n_vertices.sample_count == 0 {
            return Err(Fault::path(&n_vertices.path, "nVertices has no samples"));
        }
        let first = self.archive.sample(n_vertices, 0)?;
        // Curves whose topology changes over time cannot become one groom.
        // Comparing the stored samples covers every sample, and there are no
        // more of them than the file has room for.
        let per_sample = if n_vertices.kind == Kind::Array { 2 } else { 1 };
        let stored = n_vertices.samples.len() / per_sample;
        for index in 1..stored as u32 {
            if self.archive.stored_sample(n_vertices, index)? != first {
                return Err(Fault::path(
                    &n_vertices.path,
                    format!("the curve topology changes at stored sample {index} (not supported)"),
                ));
            }
        }
        let values = self.sample_values(n_vertices, 0)?;
        values
            .into_iter()
            .enumerate()
            .map(|(i, v)| {
                if v >= 0.0 && v <= f64::from(u32::MAX) {
                    Ok(v as u32)
                } else {
                    Err(Fault::path(
                        &n_vertices.path,
                        format!("curve {i} has {v} vertices"),
                    ))
                }
            })
            .collect()
    }

    fn basis(&mut self, geom: &Property) -> Result<CurveBasis, Fault> {
        let Some(property) = geom
            .child("curveBasisAndType")
            .filter(|p| p.sample_count > 0)
        else {
            // The reference's default: cubic Bézier.
            return Ok(CurveBasis::Bezier);
        };
        let values = self.sample_values(property, 0)?;
        let curve_type = values.first().copied().unwrap_or(0.0) as u32;
        let basis = values.get(2).copied().unwrap_or(0.0) as u32;
        if curve_type == 1 {
            return Ok(CurveBasis::Linear);
        }
        Ok(match basis {
            2 => CurveBasis::Bspline,
            3 => CurveBasis::CatmullRom,
            4 => CurveBasis::Hermite,
            5 => CurveBasis::Power,
            // Bézier, and "no basis" on cubic curves.
            _ => CurveBasis::Bezier,
        })
    }

    /// A geometry parameter as an attribute (first sample), or `None` with a
    /// note when its values cannot be matched to the curves.
    fn geom_param(
        &mut self,
        property: &Property,
        name: &str,
        vertex_count: usize,
        curve_count: usize,
        index: u32,
    ) -> Result<Option<Attribute>, Fault> {
        let (values_property, indices) = match property.kind {
            Kind::Compound => match property.child(".vals") {
                Some(vals) if vals.kind != Kind::Compound => {
                    let indices = match property.child(".indices") {
                        Some(indices)
                            if indices.kind != Kind::Compound && indices.sample_count > 0 =>
                        {
                            Some(self.sample_values(indices, 0)?)
                        }
                        _ => None,
                    };
                    (vals, indices)
                }
                _ => return Ok(None),
            },
            _ => (property, None),
        };
        if values_property.sample_count == 0 {
            return Ok(None);
        }
        if values_property.pod.size().is_none() {
            self.notes
                .push(format!("skipped {}: string values", property.path));
            return Ok(None);
        }
        let mut extent = usize::from(values_property.extent);
        // Arrays of several scalars per element (Unreal's
        // groom_closest_guides, int32[3]) say so in `arrayExtent`.
        let array_extent = property
            .metadata
            .get("arrayExtent")
            .and_then(|e| e.parse::<usize>().ok())
            .unwrap_or(1);
        if extent == 1 && (2..=3).contains(&array_extent) {
            extent = array_extent;
        }
        if extent > 3 {
            self.notes.push(format!(
                "skipped {}: {extent} components per value",
                property.path
            ));
            return Ok(None);
        }
        let mut values = self.sample_values(values_property, index)?;
        if let Some(indices) = indices {
            let groups = values.len() / extent;
            let mut expanded = Vec::with_capacity(indices.len().saturating_mul(extent));
            self.budget
                .take(indices.len().saturating_mul(extent * 8), &property.path)?;
            for index in indices {
                let i = index as usize;
                if index < 0.0 || i >= groups {
                    return Err(Fault::path(
                        &property.path,
                        format!("index {index} is out of range ({groups} values)"),
                    ));
                }
                expanded.extend_from_slice(&values[i * extent..(i + 1) * extent]);
            }
            values = expanded;
        }
        let count = values.len() / extent;
        let declared = property.metadata.get("geoScope").unwrap_or_default();
        // Groom-level values (such as Unreal's groom_version_major) have no
        // place in a groom's per-strand or per-vertex attributes, also when
        // the groom has one strand or one point.
        if declared == "con" && count == 1 && name != "width" {
            return Ok(None);
        }
        let scope = if count == vertex_count
            && (count != curve_count || declared == "vtx" || declared == "var")
        {
            Scope::Vertex
        } else if count == curve_count {
            Scope::Strand
        } else if count == 1 && name == "width" {
            // A constant width: the same for every curve.
            values = values.repeat(curve_count);
            Scope::Strand
        } else if count == 1 {
            // Groom-level values (such as Unreal's groom_version_major) have
            // no place in a groom's per-strand or per-vertex attributes.
            return Ok(None);
        } else {
            self.notes.push(format!(
                "skipped {}: {count} values for {curve_count} curves and {vertex_count} points",
                property.path
            ));
            return Ok(None);
        };
        let name = match (name, scope) {
            ("uv", Scope::Strand) => "root_uv",
            (other, _) => other,
        };
        let integer = values_property.pod.is_integer() && extent == 1;
        let attribute_values = match extent {
            1 if integer => AttributeValues::Int(
                values
                    .iter()
                    .map(|&v| v.clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32)
                    .collect(),
            ),
            1 => AttributeValues::Float(values.iter().map(|&v| v as f32).collect()),
            2 => AttributeValues::Vec2(
                values
                    .chunks_exact(2)
                    .map(|c| [c[0] as f32, c[1] as f32])
                    .collect(),
            ),
            _ => AttributeValues::Vec3(
                values
                    .chunks_exact(3)
                    .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32])
                    .collect(),
            ),
        };
        Ok(Some(Attribute {
            name: name.to_string(),
            scope,
            values: attribute_values,
        }))
    }
}

fn same_kind(a: &AttributeValues, b: &AttributeValues) -> bool {
    std::mem::discriminant(a) == std::mem::discriminant(b)
}

fn append(into: &mut AttributeValues, from: &AttributeValues) {
    match (into, from) {
        (AttributeValues::Float(a), AttributeValues::Float(b)) => a.extend_from_slice(b),
        (AttributeValues::Vec2(a), AttributeValues::Vec2(b)) => a.extend_from_slice(b),
        (AttributeValues::Vec3(a), AttributeValues::Vec3(b)) => a.extend_from_slice(b),
        (AttributeValues::Int(a), AttributeValues::Int(b)) => a.extend_from_slice(b),
        _ => {}
    }
}

/// One groom from all Curves objects: strands one object after another;
/// attributes every object has; frames when any object is animated.
fn merge(parts: Vec<Part>, budget: &mut Budget) -> Result<Groom, Fault> {
    let mut groom = Groom::default();
    let Some(first) = parts.first() else {
        return Err(Fault::path("/", "the file has no Curves object"));
    };
    groom.basis = first.basis;
    for part in &parts {
        if part.basis != groom.basis {
            return Err(Fault::path(
                &part.path,
                format!(
                    "curves of basis {} cannot be merged with curves of basis {}",
                    part.basis.name(),
                    groom.basis.name()
                ),
            ));
        }
    }
    let animated = parts
        .iter()
        .max_by_key(|p| p.times.len())
        .filter(|p| !p.times.is_empty());
    let frame_times: Vec<f64> = animated.map(|p| p.times.clone()).unwrap_or_default();
    for part in &parts {
        groom.strand_vertex_counts.extend_from_slice(&part.counts);
        if let Some(points) = part.samples.first() {
            groom.points.extend_from_slice(points);
        }
    }
    // Static objects are repeated in every frame of the animated ones.
    let frame_bytes = groom.points.len().saturating_mul(12);
    budget.take(frame_bytes.saturating_mul(frame_times.len()), "/")?;
    for (index, &time) in frame_times.iter().enumerate() {
        let mut points = Vec::with_capacity(groom.points.len());
        for part in &parts {
            let sample = part
                .samples
                .get(index)
                .or_else(|| part.samples.last())
                .map(Vec::as_slice)
                .unwrap_or_default();
            points.extend_from_slice(sample);
        }
        groom.frames.push(Frame {
            time,
            points,
            attributes: Vec::new(),
        });
    }
    for attribute in &first.attributes {
        let mut merged = attribute.clone();
        let everywhere = parts.iter().skip(1).all(|part| {
            part.attributes.iter().any(|a| {
                a.name == attribute.name
                    && a.scope == attribute.scope
                    && same_kind(&a.values, &attribute.values)
            })
        });
        if !everywhere {
            continue;
        }
        for part in parts.iter().skip(1) {
            if let Some(a) = part.attributes.iter().find(|a| a.name == attribute.name) {
                append(&mut merged.values, &a.values);
            }
        }
        groom.set_attribute(merged);
    }
    frame_attributes(&parts, &mut groom);
    one_attribute_per_meaning(&mut groom);
    Ok(groom)
}

/// Each frame's values of the attributes some object samples per frame
/// (objects that hold one still give it to every frame), for the
/// attributes the groom kept (those every object has).
fn frame_attributes(parts: &[Part], groom: &mut Groom) {
    let mut names: Vec<&str> = Vec::new();
    for part in parts {
        for values in &part.frame_attributes {
            if let Some(first) = values.first() {
                if !names.contains(&first.name.as_str()) {
                    names.push(&first.name);
                }
            }
        }
    }
    names.retain(|name| groom.attribute(name).is_some());
    for (index, frame) in groom.frames.iter_mut().enumerate() {
        for &name in &names {
            let Some(kept) = groom.attributes.iter().find(|a| a.name == name) else {
                continue;
            };
            let mut merged = Attribute {
                name: name.to_string(),
                scope: kept.scope,
                values: match kept.values {
                    AttributeValues::Float(_) => AttributeValues::Float(Vec::new()),
                    AttributeValues::Vec2(_) => AttributeValues::Vec2(Vec::new()),
                    AttributeValues::Vec3(_) => AttributeValues::Vec3(Vec::new()),
                    AttributeValues::Int(_) => AttributeValues::Int(Vec::new()),
                },
            };
            for part in parts {
                let sampled = part
                    .frame_attributes
                    .iter()
                    .find(|v| v.first().is_some_and(|a| a.name == name))
                    .and_then(|v| v.get(index).or_else(|| v.last()));
                let value = sampled.or_else(|| part.attributes.iter().find(|a| a.name == name));
                if let Some(value) = value {
                    append(&mut merged.values, &value.values);
                }
            }
            frame.attributes.push(merged);
        }
    }
}

/// Unreal's `groom_width` and `groom_root_uv` say what the schema's `width`
/// and `uv` say: a groom keeps one attribute per meaning (the schema's when
/// both are present), so a re-read and re-written file does not gain a copy.
///
/// `groom_guide` and `groom_group_id` of all zeros are Unreal's defaults (no
/// guides, one group), what a groom without them means: not kept either.
fn one_attribute_per_meaning(groom: &mut Groom) {
    for name in ["groom_guide", "groom_group_id"] {
        let zeros = groom.attribute(name).is_some_and(|a| match &a.values {
            AttributeValues::Int(v) => v.iter().all(|&x| x == 0),
            AttributeValues::Float(v) => v.iter().all(|&x| x == 0.0),
            _ => false,
        });
        if zeros {
            groom.remove_attribute(name);
        }
    }
    for (unreal, own) in [("groom_width", "width"), ("groom_root_uv", "root_uv")] {
        if let Some(mut attribute) = groom.remove_attribute(unreal) {
            if groom.attribute(own).is_none() {
                attribute.name = own.to_string();
                groom.set_attribute(attribute);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_follows_imath() {
        // 90 degrees about Z takes +X to +Y.
        let m = axis_angle([0.0, 0.0, 1.0], 90.0);
        let p = transform_point(&m, [1.0, 0.0, 0.0]);
        assert!((p[0]).abs() < 1e-6 && (p[1] - 1.0).abs() < 1e-6 && p[2].abs() < 1e-6);
    }

    #[test]
    fn imath_translation_is_the_last_row() {
        let mut v = [0.0; 16];
        for k in 0..4 {
            v[5 * k] = 1.0;
        }
        v[12..16].copy_from_slice(&[1.0, 2.0, 3.0, 1.0]);
        assert_eq!(
            transform_point(&from_imath(&v), [1.0, 1.0, 1.0]),
            [2.0, 3.0, 4.0]
        );
    }

    #[test]
    fn halves() {
        assert_eq!(half_to_f32(0x3c00), 1.0);
        assert_eq!(half_to_f32(0xc000), -2.0);
        assert_eq!(half_to_f32(0x0000), 0.0);
    }
}
