//! The `groombake` Python module: grooms as numpy arrays, timelines from
//! files or dicts, and bakes that release the GIL. Built with maturin
//! (`python/pyproject.toml`); `groombake/__init__.py` re-exports it.

mod dict_toml;

use groom::{Attribute, AttributeValues, Frame, Scope, Units, UpAxis};
use groombake::timeline::bake::{
    bake as run_bake, prepare, BakeError as EngineBakeError, BakeMonitor, BakeOptions,
};
use groombake::timeline::Timeline as EngineTimeline;
use numpy::{PyArray1, PyArrayMethods, PyUntypedArrayMethods, ToPyArray};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::Duration;

create_exception!(
    groombake,
    BadInput,
    PyException,
    "Bad input: an unreadable or malformed file, timeline or value (the CLI's exit code 2)."
);
create_exception!(
    groombake,
    BakeError,
    PyException,
    "A failure during the work: a bake or write that failed (the CLI's exit code 1)."
);

fn bad_input(message: impl ToString) -> PyErr {
    BadInput::new_err(message.to_string())
}

fn export_error(error: exporters::ExportError) -> PyErr {
    match error {
        exporters::ExportError::Invalid { .. } | exporters::ExportError::UnknownFormat { .. } => {
            bad_input(error)
        }
        other => BakeError::new_err(other.to_string()),
    }
}

fn engine_bake_error(error: EngineBakeError) -> PyErr {
    if error.is_bad_input() {
        bad_input(error)
    } else {
        BakeError::new_err(error.to_string())
    }
}

fn parse_units(text: Option<&str>) -> PyResult<Option<Units>> {
    text.map(|t| {
        t.parse::<Units>()
            .map_err(|e| bad_input(format!("units: {e}")))
    })
    .transpose()
}

fn parse_up(text: Option<&str>) -> PyResult<Option<UpAxis>> {
    text.map(|t| {
        t.parse::<UpAxis>()
            .map_err(|e| bad_input(format!("up: {e}")))
    })
    .transpose()
}

/// An (N, 3) float32 array of points.
fn points_array<'py>(py: Python<'py>, points: &[[f32; 3]]) -> PyResult<Bound<'py, PyAny>> {
    let flat: &[f32] = points.as_flattened();
    Ok(flat.to_pyarray(py).reshape([points.len(), 3])?.into_any())
}

/// An attribute's values as a numpy array: (N,) float32 or int32, (N, 2) or
/// (N, 3) float32.
fn values_array<'py>(py: Python<'py>, values: &AttributeValues) -> PyResult<Bound<'py, PyAny>> {
    Ok(match values {
        AttributeValues::Float(v) => v.to_pyarray(py).into_any(),
        AttributeValues::Int(v) => v.to_pyarray(py).into_any(),
        AttributeValues::Vec2(v) => v
            .as_flattened()
            .to_pyarray(py)
            .reshape([v.len(), 2])?
            .into_any(),
        AttributeValues::Vec3(v) => v
            .as_flattened()
            .to_pyarray(py)
            .reshape([v.len(), 3])?
            .into_any(),
    })
}

/// Any array-like as a C-contiguous numpy array of `dtype`.
fn as_array<'py>(value: &Bound<'py, PyAny>, dtype: &str) -> PyResult<Bound<'py, PyAny>> {
    let numpy = value.py().import("numpy")?;
    numpy.call_method1("ascontiguousarray", (value, dtype))
}

/// Rows of `width` float32 values from an array-like of shape (N, width).
fn float_rows<const W: usize>(value: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<[f32; W]>> {
    let array = as_array(value, "float32")?;
    let array = array
        .cast::<numpy::PyArray2<f32>>()
        .map_err(|_| bad_input(format!("{what}: expected an array of shape (N, {W})")))?;
    if array.shape()[1] != W {
        return Err(bad_input(format!(
            "{what}: expected shape (N, {W}), got {:?}",
            array.shape()
        )));
    }
    let flat: Vec<f32> = array.to_vec()?;
    Ok(flat
        .chunks_exact(W)
        .map(|c| std::array::from_fn(|k| c[k]))
        .collect())
}

/// An attribute from an array-like: int arrays become `int`, (N,) floats
/// `float`, (N, 2) and (N, 3) floats `vec2` and `vec3`.
fn attribute_values(value: &Bound<'_, PyAny>, name: &str) -> PyResult<AttributeValues> {
    let numpy = value.py().import("numpy")?;
    let array = numpy.call_method1("asarray", (value,))?;
    let kind: String = array.getattr("dtype")?.getattr("kind")?.extract()?;
    let ndim: usize = array.getattr("ndim")?.extract()?;
    let what = format!("attribute {name}");
    match (kind.as_str(), ndim) {
        ("i" | "b", 1) => {
            // Through int64 and a checked narrowing: numpy's own cast to
            // int32 wraps (2**40 would become 0).
            let ints = as_array(&array, "int64")?;
            let ints = ints
                .cast::<PyArray1<i64>>()
                .map_err(|e| bad_input(format!("{what}: {e}")))?;
            Ok(AttributeValues::Int(int32_values(ints.to_vec()?, &what)?))
        }
        ("u", 1) => {
            let ints = as_array(&array, "uint64")?;
            let ints = ints
                .cast::<PyArray1<u64>>()
                .map_err(|e| bad_input(format!("{what}: {e}")))?;
            Ok(AttributeValues::Int(int32_values(ints.to_vec()?, &what)?))
        }
        (_, 1) => {
            let floats = as_array(&array, "float32")?;
            let floats = floats
                .cast::<PyArray1<f32>>()
                .map_err(|e| bad_input(format!("{what}: {e}")))?;
            Ok(AttributeValues::Float(floats.to_vec()?))
        }
        (_, 2) => {
            let width = array.getattr("shape")?.get_item(1)?.extract::<usize>()?;
            match width {
                2 => Ok(AttributeValues::Vec2(float_rows::<2>(&array, &what)?)),
                3 => Ok(AttributeValues::Vec3(float_rows::<3>(&array, &what)?)),
                _ => Err(bad_input(format!(
                    "{what}: 1, 2 or 3 components, got {width}"
                ))),
            }
        }
        _ => Err(bad_input(format!(
            "{what}: expected a 1- or 2-dimensional array"
        ))),
    }
}

/// Integer attribute values as the groom stores them (int32), refusing
/// one out of range instead of wrapping it.
fn int32_values<T>(values: Vec<T>, what: &str) -> PyResult<Vec<i32>>
where
    T: Copy + std::fmt::Display,
    i32: TryFrom<T>,
{
    values
        .into_iter()
        .enumerate()
        .map(|(i, v)| {
            i32::try_from(v).map_err(|_| {
                bad_input(format!(
                    "{what}[{i}]: {v} is outside the int32 range of integer attributes \
                     ({} to {})",
                    i32::MIN,
                    i32::MAX
                ))
            })
        })
        .collect()
}

/// Refuses frame times an export would refuse: not finite, negative, or
/// not increasing by at least [`groombake::budget::MIN_DT`] (closer times
/// share one USD time code or one f32 glTF key).
fn check_times(times: &[f64]) -> PyResult<()> {
    for (k, &time) in times.iter().enumerate() {
        if !(time.is_finite() && time >= 0.0) {
            return Err(bad_input(format!(
                "times[{k}]: {time} is not a non-negative number of seconds"
            )));
        }
        if k > 0 {
            let last = times[k - 1];
            if !(time - last >= groombake::budget::MIN_DT && (time as f32) > (last as f32)) {
                return Err(bad_input(format!(
                    "times[{k}]: {time} s does not follow {last} s by at least {} s",
                    groombake::budget::MIN_DT
                )));
            }
        }
    }
    Ok(())
}

/// Refuses points no format can store: finite as f32 in centimetres (the
/// largest scale a writer applies, Alembic's).
fn check_storable(points: &[[f32; 3]], meters_per_unit: f64, what: &str) -> PyResult<()> {
    let scale = meters_per_unit / groom::Units::CENTIMETERS.meters_per_unit;
    match points.iter().position(|p| {
        !p.iter()
            .all(|&c| ((f64::from(c) * scale) as f32).is_finite())
    }) {
        Some(i) => Err(bad_input(format!(
            "{what}[{i}]: {:?} is not finite in centimetres, as Alembic stores it",
            points[i]
        ))),
        None => Ok(()),
    }
}

fn scope_name(scope: Scope) -> &'static str {
    match scope {
        Scope::Vertex => "vertex",
        Scope::Strand => "strand",
    }
}

/// A groom: strands as flat arrays of points and per-strand vertex counts,
/// named attributes per vertex or per strand, and optional frames.
#[pyclass(name = "Groom", module = "groombake")]
#[derive(Clone)]
pub struct PyGroom {
    inner: groom::Groom,
}

#[pymethods]
impl PyGroom {
    /// Every point, strand after strand: float32 array of shape (N, 3)
    /// in the groom's `units` and `up` axis (a copy).
    #[getter]
    fn points<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        points_array(py, &self.inner.points)
    }

    /// Vertices of each strand: int32 array of shape (S,).
    #[getter]
    fn counts<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i32>> {
        let counts: Vec<i32> = self
            .inner
            .strand_vertex_counts
            .iter()
            .map(|&c| i32::try_from(c).unwrap_or(i32::MAX))
            .collect();
        PyArray1::from_vec(py, counts)
    }

    /// Attributes: a dict of name -> (values, scope), values a numpy array
    /// with one row per vertex or strand, scope "vertex" or "strand".
    #[getter]
    fn attributes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        for a in &self.inner.attributes {
            let pair = PyTuple::new(
                py,
                [
                    values_array(py, &a.values)?,
                    scope_name(a.scope).into_pyobject(py)?.into_any(),
                ],
            )?;
            dict.set_item(&a.name, pair)?;
        }
        Ok(dict)
    }

    /// Time samples: a list of (seconds, points (N, 3) float32); empty for a
    /// static groom.
    #[getter]
    fn frames<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let items = self
            .inner
            .frames
            .iter()
            .map(|f| {
                PyTuple::new(
                    py,
                    [
                        f.time.into_pyobject(py)?.into_any(),
                        points_array(py, &f.points)?,
                    ],
                )
            })
            .collect::<PyResult<Vec<_>>>()?;
        PyList::new(py, items)
    }

    /// Length unit of the coordinates ("m", "cm", ...).
    #[getter]
    fn units(&self) -> String {
        self.inner.units.name()
    }

    /// Up axis ("y" or "z").
    #[getter]
    fn up(&self) -> &'static str {
        self.inner.up_axis.name()
    }

    #[getter]
    fn strand_count(&self) -> usize {
        self.inner.strand_count()
    }

    #[getter]
    fn vertex_count(&self) -> usize {
        self.inner.vertex_count()
    }

    /// Builds a groom from arrays.
    ///
    /// points: (N, 3) array-like; counts: (S,) vertices per strand, summing
    /// to N; frames: optional (F, N, 3) time samples at `times` seconds
    /// (default k / 24); units and up: what the coordinates use. Every
    /// other keyword is an attribute: an array (scope from its length: N
    /// per vertex, S per strand) or a (array, "vertex"|"strand") pair.
    #[staticmethod]
    #[pyo3(signature = (points, counts, *, frames=None, times=None, units="m", up="y", **attributes))]
    fn from_arrays(
        points: &Bound<'_, PyAny>,
        counts: &Bound<'_, PyAny>,
        frames: Option<&Bound<'_, PyAny>>,
        times: Option<Vec<f64>>,
        units: &str,
        up: &str,
        attributes: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<PyGroom> {
        let mut groom = groom::Groom {
            points: float_rows::<3>(points, "points")?,
            ..groom::Groom::default()
        };
        let counts = as_array(counts, "int64")?;
        let counts: Vec<i64> = counts
            .cast::<PyArray1<i64>>()
            .map_err(|_| bad_input("counts: expected a 1-dimensional array of integers"))?
            .to_vec()?;
        groom.strand_vertex_counts = counts
            .iter()
            .enumerate()
            .map(|(i, &c)| {
                u32::try_from(c)
                    .map_err(|_| bad_input(format!("counts[{i}]: {c} is not a vertex count")))
            })
            .collect::<PyResult<_>>()?;
        let total: u64 = groom.strand_vertex_counts.iter().map(|&c| c as u64).sum();
        if total != groom.points.len() as u64 {
            return Err(bad_input(format!(
                "counts sum to {total}, but there are {} points",
                groom.points.len()
            )));
        }
        groom.units = parse_units(Some(units))?.unwrap_or_default();
        groom.up_axis = parse_up(Some(up))?.unwrap_or_default();
        groom.provenance.format = "python".into();
        if let Some(times) = &times {
            check_times(times)?;
        }
        check_storable(&groom.points, groom.units.meters_per_unit, "points")?;
        if let Some(frames) = frames {
            let frames = as_array(frames, "float32")?;
            let shape: Vec<usize> = frames.getattr("shape")?.extract()?;
            if shape.len() != 3 || shape[1] != groom.points.len() || shape[2] != 3 {
                return Err(bad_input(format!(
                    "frames: expected shape (F, {}, 3), got {shape:?}",
                    groom.points.len()
                )));
            }
            for k in 0..shape[0] {
                let time = match &times {
                    Some(t) => *t.get(k).ok_or_else(|| {
                        bad_input(format!("times: {} values for {} frames", t.len(), shape[0]))
                    })?,
                    None => k as f64 / 24.0,
                };
                let what = format!("frames[{k}]");
                let points = float_rows::<3>(&frames.get_item(k)?, &what)?;
                check_storable(&points, groom.units.meters_per_unit, &what)?;
                groom.frames.push(Frame {
                    time,
                    points,
                    attributes: Vec::new(),
                });
            }
        }
        let (vertices, strands) = (groom.vertex_count(), groom.strand_count());
        for (name, value) in attributes.into_iter().flatten() {
            let name: String = name.extract()?;
            let (values, scope) = match value.cast::<PyTuple>() {
                Ok(pair) if pair.len() == 2 => (
                    pair.get_item(0)?,
                    Some(pair.get_item(1)?.extract::<String>()?),
                ),
                _ => (value, None),
            };
            let values = attribute_values(&values, &name)?;
            let n = values.len();
            let scope = match scope.as_deref() {
                Some("vertex") => Scope::Vertex,
                Some("strand") => Scope::Strand,
                Some(other) => {
                    return Err(bad_input(format!(
                        "attribute {name}: scope '{other}': use 'vertex' or 'strand'"
                    )))
                }
                None if n == vertices => Scope::Vertex,
                None if n == strands => Scope::Strand,
                None => {
                    return Err(bad_input(format!(
                    "attribute {name}: {n} values for {vertices} vertices and {strands} strands"
                )))
                }
            };
            let expected = if scope == Scope::Vertex {
                vertices
            } else {
                strands
            };
            if n != expected {
                return Err(bad_input(format!(
                    "attribute {name}: {n} values, per {} needs {expected}",
                    scope_name(scope)
                )));
            }
            groom.set_attribute(Attribute {
                name,
                scope,
                values,
            });
        }
        if let Some(problem) = groom.first_fatal_problem() {
            return Err(bad_input(problem));
        }
        Ok(PyGroom { inner: groom })
    }

    /// Writes the groom; the extension picks the format (.abc, .usda,
    /// .usdc, .glb, .gltf, .hair, .data, .obj). `units` and `up` convert
    /// the coordinates first (default: as they are).
    #[pyo3(signature = (path, units=None, up=None))]
    fn save(
        &self,
        py: Python<'_>,
        path: PathBuf,
        units: Option<&str>,
        up: Option<&str>,
    ) -> PyResult<()> {
        let mut groom = self.inner.clone();
        let units = parse_units(units)?.unwrap_or(groom.units);
        let up = parse_up(up)?.unwrap_or(groom.up_axis);
        py.detach(|| {
            groom.convert_to(units, up);
            exporters::write(&path, &groom)
        })
        .map_err(export_error)
    }

    fn __repr__(&self) -> String {
        format!(
            "<groombake.Groom: {} strands, {} vertices, {} frames, {} attributes, {} {}-up>",
            self.inner.strand_count(),
            self.inner.vertex_count(),
            self.inner.frames.len(),
            self.inner.attributes.len(),
            self.inner.units.name(),
            self.inner.up_axis.name()
        )
    }
}

/// Reads a groom file of any supported format.
///
/// units and up: convert the coordinates to these ("m", "cm", "mm", "in"
/// or metres per unit; "y" or "z"); default: as the file has them.
/// Raises BadInput for a missing, unreadable or malformed file.
#[pyfunction]
#[pyo3(signature = (path, units=None, up=None))]
fn load(py: Python<'_>, path: PathBuf, units: Option<&str>, up: Option<&str>) -> PyResult<PyGroom> {
    let units = parse_units(units)?;
    let up = parse_up(up)?;
    let mut groom = py.detach(|| importers::read(&path)).map_err(bad_input)?;
    if let Some(problem) = groom.first_fatal_problem() {
        return Err(bad_input(format!("{}: {problem}", path.display())));
    }
    let (u, a) = (units.unwrap_or(groom.units), up.unwrap_or(groom.up_axis));
    groom.convert_to(u, a);
    Ok(PyGroom { inner: groom })
}

/// A parsed and checked timeline (the TOML schema of `groombake bake`).
#[pyclass(name = "Timeline", module = "groombake")]
pub struct PyTimeline {
    inner: EngineTimeline,
}

#[pymethods]
impl PyTimeline {
    /// Reads and checks a timeline file. Raises BadInput naming the line
    /// and column of a problem.
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<PyTimeline> {
        let inner = EngineTimeline::load(&path).map_err(bad_input)?;
        Ok(PyTimeline { inner })
    }

    /// A timeline from a dict with the TOML file's structure, e.g.
    /// {"groom": {"generate": {...}}, "stage": [{"kind": "wet", "duration": 0.3}]}.
    /// The same checks as a file; BadInput names the key path of a
    /// problem ("stage[1].duration: ..."). Relative paths in it are taken
    /// from `base` (default: the current folder).
    #[staticmethod]
    #[pyo3(signature = (d, base=None))]
    fn from_dict(d: &Bound<'_, PyDict>, base: Option<PathBuf>) -> PyResult<PyTimeline> {
        let document = dict_toml::Document::from_dict(d)?;
        let base = match base {
            Some(b) => b,
            None => std::env::current_dir().map_err(bad_input)?,
        };
        let path = base.join("<dict>");
        EngineTimeline::parse(&path, document.text.clone())
            .map(|inner| PyTimeline { inner })
            .map_err(|e| {
                let place = document.key_path_at_line(e.line);
                bad_input(format!("<dict>: {place}: {}", e.message))
            })
    }

    /// Checks that the timeline can run: reads the groom and colliders and
    /// builds the simulation, without stepping. Returns a summary dict;
    /// raises BadInput.
    fn validate<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let prepared = py
            .detach(|| prepare(&self.inner, None))
            .map_err(engine_bake_error)?;
        let dict = PyDict::new(py);
        dict.set_item("strands", prepared.strands.strand_count())?;
        dict.set_item("vertices", prepared.strands.vertex_count())?;
        dict.set_item("colliders", self.inner.file.colliders.len())?;
        dict.set_item("stages", self.inner.file.stages.get_ref().len())?;
        dict.set_item("duration", self.inner.duration())?;
        dict.set_item("dt", self.inner.dt)?;
        dict.set_item("exports", self.inner.file.exports.len())?;
        Ok(dict)
    }

    /// Total simulated seconds of all stages.
    #[getter]
    fn duration(&self) -> f64 {
        self.inner.duration()
    }

    #[getter]
    fn path(&self) -> PathBuf {
        self.inner.path.clone()
    }
}

/// JSON-like data as Python objects (dicts, lists, numbers, strings).
fn to_python<'py>(py: Python<'py>, value: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    use serde_json::Value;
    Ok(match value {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => b.into_pyobject(py)?.to_owned().into_any(),
        Value::Number(n) => match (n.as_i64(), n.as_u64()) {
            (Some(i), _) => i.into_pyobject(py)?.into_any(),
            (_, Some(u)) => u.into_pyobject(py)?.into_any(),
            _ => n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any(),
        },
        Value::String(s) => s.into_pyobject(py)?.into_any(),
        Value::Array(items) => PyList::new(
            py,
            items
                .iter()
                .map(|v| to_python(py, v))
                .collect::<PyResult<Vec<_>>>()?,
        )?
        .into_any(),
        Value::Object(map) => {
            let dict = PyDict::new(py);
            for (k, v) in map {
                dict.set_item(k, to_python(py, v)?)?;
            }
            dict.into_any()
        }
    })
}

/// What a bake did (the content of `groombake bake --report`): its keys
/// are attributes (`report.status`, `report.finished`, `report.stages`,
/// `report.outputs`, `report.warnings`, ...), listed by `dir()`;
/// `to_dict()` gives all of it.
#[pyclass(name = "Report", module = "groombake")]
pub struct PyReport {
    data: Py<PyDict>,
}

#[pymethods]
impl PyReport {
    fn __getattr__<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
        self.data
            .bind(py)
            .get_item(name)?
            .ok_or_else(|| pyo3::exceptions::PyAttributeError::new_err(name.to_string()))
    }

    /// The report's keys beside the class's attributes, so that `dir()`
    /// and completion in an interactive shell show them.
    fn __dir__(slf: &Bound<'_, Self>) -> PyResult<Vec<String>> {
        let py = slf.py();
        let object = py.import("builtins")?.getattr("object")?;
        let mut names: Vec<String> = object.call_method1("__dir__", (slf,))?.extract()?;
        for key in slf.borrow().data.bind(py).keys() {
            names.push(key.extract()?);
        }
        names.sort();
        names.dedup();
        Ok(names)
    }

    /// The whole report as a dict.
    fn to_dict<'py>(&self, py: Python<'py>) -> Bound<'py, PyDict> {
        self.data.bind(py).clone()
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let d = self.data.bind(py);
        let get = |k: &str| {
            d.get_item(k)
                .ok()
                .flatten()
                .map(|v| v.to_string())
                .unwrap_or_default()
        };
        format!(
            "<groombake.Report: {} strands, {} s simulated in {} s, {} outputs>",
            get("strands"),
            get("simulated_seconds"),
            get("wall_seconds"),
            d.get_item("outputs")
                .ok()
                .flatten()
                .and_then(|o| o.len().ok())
                .unwrap_or(0)
        )
    }
}

/// Runs a timeline and writes its exports, as `groombake bake` does.
///
/// timeline: a Timeline (or a path to a timeline file).
/// out: the folder relative export paths are written under (default ".").
/// threads: worker threads (default: one per core); outputs are
/// byte-identical for any count. seed: overrides the timeline's seed.
/// progress: called with the fraction done (0.0 to 1.0, never
/// decreasing) and the name of the stage running (`progress(fraction,
/// stage)`; a callable of one argument gets the fraction only), about 20
/// times a second, when a stage starts and at the end.
///
/// The GIL is released while baking: other Python threads run. Ctrl-C
/// (KeyboardInterrupt) stops the bake after its current step and leaves
/// no half-written file. Returns a finished Report (`status` "ok",
/// `finished`, `outputs`, `sources`, as `groombake bake --report` writes
/// it); raises BadInput for bad input and BakeError for a failure during
/// the bake.
#[pyfunction]
#[pyo3(signature = (timeline, out=None, threads=None, seed=None, progress=None))]
fn bake(
    py: Python<'_>,
    timeline: &Bound<'_, PyAny>,
    out: Option<PathBuf>,
    threads: Option<Bound<'_, PyAny>>,
    seed: Option<u64>,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<PyReport> {
    // The CLI's cap: a million threads would run for minutes.
    let threads = threads
        .map(|t| {
            t.extract::<i64>()
                .ok()
                .and_then(|t| usize::try_from(t).ok())
                .ok_or(())
                .and_then(|t| groombake::budget::check_threads(t).map_err(|_| ()))
                .map_err(|()| {
                    bad_input(format!(
                        "threads must be 1 to {}",
                        groombake::budget::MAX_THREADS
                    ))
                })
        })
        .transpose()?;
    let loaded;
    let timeline_ref = match timeline.cast::<PyTimeline>() {
        Ok(t) => t.borrow(),
        Err(_) => {
            let path: PathBuf = timeline
                .extract()
                .map_err(|_| bad_input("timeline: a Timeline or a path"))?;
            loaded = Bound::new(py, PyTimeline::load(path)?)?;
            loaded.borrow()
        }
    };
    let engine_timeline: &EngineTimeline = &timeline_ref.inner;
    let monitor = Arc::new(BakeMonitor::default());
    let options = BakeOptions {
        out_dir: out.unwrap_or_else(|| PathBuf::from(".")),
        threads,
        seed,
        monitor: Some(monitor.clone()),
        ..BakeOptions::default()
    };
    let stage_names: Vec<String> = engine_timeline
        .file
        .stages
        .get_ref()
        .iter()
        .map(|s| {
            s.name
                .clone()
                .unwrap_or_else(|| s.kind.get_ref().name().into())
        })
        .collect();
    let mut reporter = Progress {
        with_stage: progress.as_ref().is_some_and(takes_stage),
        names: stage_names,
        next_stage: 0,
        last: -1.0,
    };
    let fraction = |m: &BakeMonitor| {
        let total = m.steps_total.load(Ordering::Relaxed);
        if total == 0 {
            0.0
        } else {
            m.steps_done.load(Ordering::Relaxed) as f64 / total as f64
        }
    };
    // The start, before any poll: a bake shorter than one poll still
    // reports its start and its end (0.0, then 1.0).
    if let Some(callback) = &progress {
        reporter.update(callback, 0.0, 0)?;
    }
    let outcome = std::thread::scope(|scope| -> PyResult<_> {
        let worker = scope.spawn(|| run_bake(engine_timeline, &options));
        let mut interrupted: Option<PyErr> = None;
        while !worker.is_finished() {
            // Wait without the GIL; then, holding it, report and check Ctrl-C.
            py.detach(|| std::thread::sleep(Duration::from_millis(50)));
            if interrupted.is_some() {
                continue;
            }
            if let Err(e) = py.check_signals() {
                monitor.cancel();
                interrupted = Some(e);
                continue;
            }
            if let Some(callback) = &progress {
                let stage = monitor.stage.load(Ordering::Relaxed);
                if let Err(e) = reporter.update(callback, fraction(&monitor), stage) {
                    monitor.cancel();
                    interrupted = Some(e);
                }
            }
        }
        let result = worker
            .join()
            .map_err(|_| BakeError::new_err("the bake panicked"))?;
        if let Some(e) = interrupted {
            return Err(e);
        }
        Ok(result)
    })?;
    let mut report = outcome.map_err(engine_bake_error)?.report;
    report.finish_ok(engine_timeline);
    if let Some(callback) = &progress {
        let last = reporter.names.len().saturating_sub(1);
        reporter.update(callback, 1.0, last)?;
    }
    let value = serde_json::to_value(&report).map_err(|e| BakeError::new_err(e.to_string()))?;
    let data = to_python(py, &value)?.cast_into::<PyDict>()?.unbind();
    Ok(PyReport { data })
}

/// Calls a progress callback: at the start (0.0), once for every stage as
/// it starts (also a stage shorter than the 50 ms between polls, with the
/// fraction of the moment), and whenever the fraction grew.
struct Progress {
    /// `callback(fraction, stage)`, else `callback(fraction)`.
    with_stage: bool,
    names: Vec<String>,
    /// The first stage not yet reported.
    next_stage: usize,
    last: f64,
}

impl Progress {
    fn update(&mut self, callback: &Bound<'_, PyAny>, fraction: f64, stage: usize) -> PyResult<()> {
        let stage = stage.min(self.names.len().saturating_sub(1));
        if self.with_stage {
            while self.next_stage <= stage && self.next_stage < self.names.len() {
                let name = self.names[self.next_stage].clone();
                callback.call1((fraction, name))?;
                self.next_stage += 1;
                self.last = fraction;
            }
        }
        if fraction > self.last {
            self.last = fraction;
            if self.with_stage {
                let name = self.names.get(stage).cloned().unwrap_or_default();
                callback.call1((fraction, name))?;
            } else {
                callback.call1((fraction,))?;
            }
        }
        Ok(())
    }
}

/// Whether a progress callback takes the stage too: its signature binds
/// two arguments. One without a signature Python can read gets the
/// fraction only, as before the stage was passed.
fn takes_stage(callback: &Bound<'_, PyAny>) -> bool {
    let py = callback.py();
    py.import("inspect")
        .and_then(|inspect| inspect.call_method1("signature", (callback,)))
        .and_then(|signature| signature.call_method1("bind", (0.0f64, "")))
        .is_ok()
}

/// groombake: bakes styled hair grooms from the chemistry of hair.
///
/// load(path) -> Groom; Groom.points / counts / attributes / frames as
/// numpy arrays; Groom.from_arrays(...); Groom.save(path);
/// Timeline.load(path) / Timeline.from_dict(d); bake(timeline, out=...) -> Report.
#[pymodule]
fn _groombake(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyGroom>()?;
    m.add_class::<PyTimeline>()?;
    m.add_class::<PyReport>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(bake, m)?)?;
    m.add("BadInput", m.py().get_type::<BadInput>())?;
    m.add("BakeError", m.py().get_type::<BakeError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
