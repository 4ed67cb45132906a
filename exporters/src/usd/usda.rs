//! `.usda` text writer.
//!
//! An animated export cannot write the text in file order as frames arrive
//! (the stage header names the last time code), so everything after the
//! header goes to a spill file beside the output: the static properties when
//! the export starts, then the `points` samples frame by frame, then the
//! extents. `finish` writes the header and copies the spill file after it.
//! Memory stays at one frame plus one extent per frame.

use super::structure::{default_prim, layout, Step};
use super::{time_code, CurvesPrim, CurvesScene, Property, PropertyValue};
use crate::{ExportError, FrameWriter};
use groom::{AtomicFile, Frame};
use std::fmt::Write as _;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

pub(super) fn write_static(path: &Path, scene: &CurvesScene) -> Result<(), ExportError> {
    let io_error = |e| ExportError::io(path, e);
    let mut file = AtomicFile::create(path).map_err(io_error)?;
    let mut write = || -> io::Result<()> {
        let range = scene
            .codes
            .first()
            .copied()
            .zip(scene.codes.last().copied());
        file.write_all(header(scene, range).as_bytes())?;
        for step in layout(&scene.prims) {
            match step {
                Step::Curves { index, depth } => {
                    let Some(prim) = scene.prims.get(index) else {
                        continue;
                    };
                    file.write_all(prim_opening(prim, depth).as_bytes())?;
                    write_properties(&mut file, prim, &scene.codes)?;
                    file.write_all(closing(depth).as_bytes())?;
                }
                step => file.write_all(xform_step(&step).as_bytes())?,
            }
        }
        Ok(())
    };
    write().map_err(io_error)?;
    file.commit().map_err(io_error)
}

/// Closes a prim at `depth` (0: a root prim).
fn closing(depth: usize) -> String {
    format!("{}}}\n", indent(depth))
}

fn indent(depth: usize) -> String {
    "    ".repeat(depth)
}

/// Opens a curves prim at `depth`. Its properties are indented as at depth
/// 1 whatever its depth: text only, USD reads them the same.
fn prim_opening(prim: &CurvesPrim, depth: usize) -> String {
    let pad = indent(depth);
    format!("{pad}def BasisCurves \"{}\"\n{pad}{{\n", prim.name)
}

/// The text of opening or closing an `Xform` parent.
fn xform_step(step: &Step) -> String {
    match step {
        Step::Open { name, depth } => {
            let pad = indent(*depth);
            format!("{pad}def Xform \"{name}\"\n{pad}{{\n")
        }
        Step::Close { depth } => closing(*depth),
        Step::Curves { .. } => String::new(),
    }
}

/// Stage metadata; `range`
/// is the first and last time code of an animated export.
fn header(scene: &CurvesScene, range: Option<(f64, f64)>) -> String {
    let mut header = String::from("#usda 1.0\n(\n");
    let _ = writeln!(
        header,
        "    defaultPrim = \"{}\"",
        default_prim(&scene.prims)
    );
    header.push_str("    doc = \"Written by groombake\"\n");
    if let (Some(timing), Some((start, end))) = (scene.timing, range) {
        let _ = writeln!(header, "    endTimeCode = {}", Num(end));
        let _ = writeln!(header, "    framesPerSecond = {}", Num(timing.fps));
        let _ = writeln!(header, "    metersPerUnit = {}", Num(scene.meters_per_unit));
        let _ = writeln!(header, "    startTimeCode = {}", Num(start));
        let _ = writeln!(header, "    timeCodesPerSecond = {}", Num(timing.fps));
    } else {
        let _ = writeln!(header, "    metersPerUnit = {}", Num(scene.meters_per_unit));
    }
    let _ = writeln!(header, "    upAxis = \"{}\"", scene.up_axis);
    header.push_str(")\n\n");
    header
}

/// The properties of a prim; those it holds as time samples only (see
/// [`CurvesPrim::sampled`]) are declared with their metadata and given
/// their samples at `codes`.
fn write_properties(out: &mut dyn Write, prim: &CurvesPrim, codes: &[f64]) -> io::Result<()> {
    let mut text = String::new();
    for property in &prim.properties {
        text.clear();
        match prim.samples_of(&property.name) {
            Some(samples) => write_sampled_property(&mut text, property, codes, samples),
            None => write_property(&mut text, property),
        }
        out.write_all(text.as_bytes())?;
    }
    Ok(())
}

fn write_sampled_property(
    text: &mut String,
    property: &Property,
    codes: &[f64],
    samples: &[PropertyValue],
) {
    if let Some(interpolation) = property.interpolation {
        let _ = writeln!(
            text,
            "        {} {} (\n            interpolation = \"{interpolation}\"\n        )",
            property.type_name, property.name
        );
    }
    let _ = writeln!(
        text,
        "        {} {}.timeSamples = {{",
        property.type_name, property.name
    );
    for (code, value) in codes.iter().zip(samples) {
        let _ = write!(text, "            {}: ", Num(*code));
        write_value(text, value);
        text.push_str(",\n");
    }
    text.push_str("        }\n");
}

fn write_property(text: &mut String, property: &Property) {
    text.push_str("        ");
    if property.uniform {
        text.push_str("uniform ");
    }
    let _ = write!(text, "{} {} = ", property.type_name, property.name);
    write_value(text, &property.value);
    if let Some(interpolation) = property.interpolation {
        let _ = write!(
            text,
            " (\n            interpolation = \"{interpolation}\"\n        )"
        );
    }
    text.push('\n');
}

fn write_value(text: &mut String, value: &PropertyValue) {
    match value {
        PropertyValue::Token(token) => {
            let _ = write!(text, "\"{token}\"");
        }
        PropertyValue::Ints(values) => write_list(text, values, |t, v| {
            let _ = write!(t, "{v}");
        }),
        PropertyValue::Floats(values) => write_list(text, values, |t, v| {
            let _ = write!(t, "{}", Num(*v));
        }),
        PropertyValue::Float2s(values) => write_list(text, values, |t, v| {
            let _ = write!(t, "({}, {})", Num(v[0]), Num(v[1]));
        }),
        PropertyValue::Float3s(values) => write_float3s(text, values),
        PropertyValue::Int3s(values) => write_list(text, values, |t, v| {
            let _ = write!(t, "({}, {}, {})", v[0], v[1], v[2]);
        }),
    }
}

fn write_float3s(text: &mut String, values: &[[f32; 3]]) {
    write_list(text, values, |t, v| {
        let _ = write!(t, "({}, {}, {})", Num(v[0]), Num(v[1]), Num(v[2]));
    });
}

/// A number as USD text: the shortest digits that read back to the same
/// value, in exponent form where the plain form is long (Rust writes 1e30
/// as a 31-digit integer, which usd-core warns about) or tiny.
struct Num<T>(T);

impl<T: Copy + Into<f64> + std::fmt::Display + std::fmt::LowerExp> std::fmt::Display for Num<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let magnitude = self.0.into().abs();
        if magnitude != 0.0 && !(1e-5..1e16).contains(&magnitude) {
            write!(f, "{:e}", self.0)
        } else {
            write!(f, "{}", self.0)
        }
    }
}

fn write_list<T>(text: &mut String, values: &[T], mut item: impl FnMut(&mut String, &T)) {
    text.push('[');
    for (index, value) in values.iter().enumerate() {
        if index > 0 {
            text.push_str(", ");
        }
        item(text, value);
    }
    text.push(']');
}

/// A temporary file beside the output, removed when dropped.
struct SpillFile {
    path: PathBuf,
    writer: Option<BufWriter<File>>,
}

impl SpillFile {
    /// A spill file named by `tag` (the prim's index, then the index of a
    /// time-varying attribute).
    fn create(destination: &Path, tag: &str) -> io::Result<SpillFile> {
        let mut name = std::ffi::OsString::from(".");
        name.push(destination.file_name().unwrap_or_default());
        name.push(format!(".{}.{tag}.frames.tmp", std::process::id()));
        let path = destination.with_file_name(name);
        let file = File::create(&path)?;
        Ok(SpillFile {
            path,
            writer: Some(BufWriter::new(file)),
        })
    }

    fn writer(&mut self) -> io::Result<&mut BufWriter<File>> {
        self.writer
            .as_mut()
            .ok_or_else(|| io::Error::other("spill file already closed"))
    }

    /// Flushes and reopens the file for reading from its start.
    fn into_reader(mut self) -> io::Result<(File, SpillFile)> {
        if let Some(writer) = self.writer.take() {
            writer.into_inner().map_err(|e| e.into_error())?;
        }
        let file = File::open(&self.path)?;
        Ok((file, self))
    }
}

impl Drop for SpillFile {
    fn drop(&mut self) {
        self.writer = None;
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Streams the frames of an animated `.usda` export: one spill file per
/// curves prim, since each prim's samples must precede the next prim.
pub(super) struct AnimatedUsda {
    path: PathBuf,
    scene: CurvesScene,
    spills: Vec<SpillFile>,
    codes: Vec<f64>,
    /// Per prim, the extent of each frame.
    extents: Vec<Vec<[[f32; 3]; 2]>>,
    /// Per prim, the samples of each time-varying attribute: its property,
    /// USD type and spill file (made at the first frame).
    attribute_spills: Vec<Vec<(String, &'static str, SpillFile)>>,
    /// The time-varying attributes every frame carries (the first sets them).
    animated: Option<Vec<String>>,
    line: String,
}

impl AnimatedUsda {
    pub fn create(path: &Path, mut scene: CurvesScene) -> Result<AnimatedUsda, ExportError> {
        let io_error = |e| ExportError::io(path, e);
        let mut spills = Vec::with_capacity(scene.prims.len());
        for (index, prim) in scene.prims.iter().enumerate() {
            let mut spill = SpillFile::create(path, &index.to_string()).map_err(io_error)?;
            let writer = spill.writer().map_err(io_error)?;
            write_properties(writer, prim, &[])
                .and_then(|()| writer.write_all(b"        point3f[] points.timeSamples = {\n"))
                .map_err(io_error)?;
            spills.push(spill);
        }
        // The static values are in the spill files now; only the metadata
        // is needed until the end.
        scene.forget_values();
        let extents = vec![Vec::new(); scene.prims.len()];
        let attribute_spills = (0..scene.prims.len()).map(|_| Vec::new()).collect();
        Ok(AnimatedUsda {
            path: path.to_path_buf(),
            scene,
            spills,
            codes: Vec::new(),
            extents,
            attribute_spills,
            animated: None,
            line: String::new(),
        })
    }
}

impl FrameWriter for AnimatedUsda {
    fn write_frame(&mut self, frame: &Frame) -> Result<(), ExportError> {
        self.scene.check_frame(&self.path, frame)?;
        let fps = self.scene.timing.map_or(1.0, |t| t.fps);
        let code = time_code(frame.time, fps);
        if self.codes.last().is_some_and(|last| code <= *last) {
            return Err(ExportError::Invalid {
                file: self.path.clone(),
                message: format!("frame time codes must increase (time code {code})"),
            });
        }
        super::frame_values::check_names(&self.path, &mut self.animated, frame)?;
        let first = self.codes.is_empty();
        self.codes.push(code);
        for (index, (prim, attribute_spills)) in self
            .scene
            .prims
            .iter()
            .zip(&mut self.attribute_spills)
            .enumerate()
        {
            let values = super::frame_values::prim_values(&self.path, prim, frame)?;
            for (k, (property, value)) in values.into_iter().enumerate() {
                if first {
                    let type_name = prim
                        .properties
                        .iter()
                        .find(|p| p.name == property)
                        .map_or("float[]", |p| p.type_name);
                    let spill = SpillFile::create(&self.path, &format!("{index}.{k}"))
                        .map_err(|e| ExportError::io(&self.path, e))?;
                    attribute_spills.push((property, type_name, spill));
                }
                let Some((_, _, spill)) = attribute_spills.get_mut(k) else {
                    continue;
                };
                self.line.clear();
                let _ = write!(self.line, "            {}: ", Num(code));
                write_value(&mut self.line, &value);
                self.line.push_str(",\n");
                spill
                    .writer()
                    .and_then(|w| w.write_all(self.line.as_bytes()))
                    .map_err(|e| ExportError::io(&self.path, e))?;
            }
        }
        for ((prim, spill), extents) in self
            .scene
            .prims
            .iter()
            .zip(&mut self.spills)
            .zip(&mut self.extents)
        {
            let points = prim.points_of(&frame.points);
            extents.push(prim.extent(&points));
            self.line.clear();
            let _ = write!(self.line, "            {}: ", Num(code));
            write_float3s(&mut self.line, &points);
            self.line.push_str(",\n");
            spill
                .writer()
                .and_then(|w| w.write_all(self.line.as_bytes()))
                .map_err(|e| ExportError::io(&self.path, e))?;
        }
        Ok(())
    }

    fn finish(self: Box<Self>) -> Result<(), ExportError> {
        let this = *self;
        let io_error = |e| ExportError::io(&this.path, e);
        let (Some(&start), Some(&end)) = (this.codes.first(), this.codes.last()) else {
            return Err(ExportError::Invalid {
                file: this.path.clone(),
                message: "an animated export needs at least one frame".into(),
            });
        };
        let mut file = AtomicFile::create(&this.path).map_err(io_error)?;
        file.write_all(header(&this.scene, Some((start, end))).as_bytes())
            .map_err(io_error)?;
        let mut bodies: Vec<_> = this
            .spills
            .into_iter()
            .zip(&this.extents)
            .zip(this.attribute_spills)
            .map(Some)
            .collect();
        for step in layout(&this.scene.prims) {
            let (index, depth) = match step {
                Step::Curves { index, depth } => (index, depth),
                step => {
                    file.write_all(xform_step(&step).as_bytes())
                        .map_err(io_error)?;
                    continue;
                }
            };
            let (Some(prim), Some(Some(((mut spill, extents), attributes)))) = (
                this.scene.prims.get(index),
                bodies.get_mut(index).map(Option::take),
            ) else {
                continue;
            };
            file.write_all(prim_opening(prim, depth).as_bytes())
                .map_err(io_error)?;
            let mut tail = String::from("        }\n        float3[] extent.timeSamples = {\n");
            for (code, extent) in this.codes.iter().zip(extents) {
                let _ = write!(tail, "            {}: ", Num(*code));
                write_float3s(&mut tail, extent);
                tail.push_str(",\n");
            }
            tail.push_str("        }\n");
            let spill_writer = spill.writer().map_err(io_error)?;
            spill_writer.write_all(tail.as_bytes()).map_err(io_error)?;
            let (mut body, _spill) = spill.into_reader().map_err(io_error)?;
            io::copy(&mut body, &mut file).map_err(io_error)?;
            // The time-varying primvars' samples, beside their defaults.
            for (property, type_name, samples) in attributes {
                let opening = format!("        {type_name} {property}.timeSamples = {{\n");
                file.write_all(opening.as_bytes()).map_err(io_error)?;
                let (mut body, _samples) = samples.into_reader().map_err(io_error)?;
                io::copy(&mut body, &mut file).map_err(io_error)?;
                file.write_all(b"        }\n").map_err(io_error)?;
            }
            file.write_all(closing(depth).as_bytes())
                .map_err(io_error)?;
        }
        file.commit().map_err(io_error)
    }
}
