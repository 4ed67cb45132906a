//! `groombake convert IN OUT [--target T | --units U --up y|z] [--frame F]`.

use super::{values, BadInput};
use clap::Args;
use groom::{Units, UpAxis};
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// The groom to read.
    #[arg(value_hint = clap::ValueHint::FilePath)]
    input: PathBuf,
    /// The file to write; its extension picks the format.
    #[arg(value_hint = clap::ValueHint::FilePath)]
    output: PathBuf,
    /// The program the output is for (unreal, maya, houdini, blender, usd):
    /// a preset of units, up axis and attribute names (docs/formats.md);
    /// --units and --up override its units and axis.
    #[arg(long)]
    target: Option<exporters::Target>,
    /// Units of the output (m, cm, mm or in); default: the
    /// target's, else the format's (glTF, .abc, .obj m; USD the input's;
    /// .hair, .data cm).
    #[arg(long, value_parser = values::suggest::<Units>(values::UNITS))]
    units: Option<Units>,
    /// Up axis of the output; default: the target's, else Y (USD: the
    /// input's).
    #[arg(long, value_parser = values::suggest::<UpAxis>(values::UP))]
    up: Option<UpAxis>,
    /// Units the input is in, for formats that do not record them (.hair,
    /// .data, .obj: cm by default; .abc: by the writing application).
    #[arg(long, value_parser = values::suggest::<Units>(values::UNITS))]
    source_units: Option<Units>,
    /// Up axis the input uses, for formats that do not say (default y).
    #[arg(long, value_parser = values::suggest::<UpAxis>(values::UP))]
    source_up: Option<UpAxis>,
    /// Write only this frame (0-based) of an animated input, as a static groom.
    #[arg(long)]
    frame: Option<usize>,
    /// Fail (exit 2) instead of warning when the output must change anything
    /// about the data.
    #[arg(long)]
    strict: bool,
}

pub fn run(args: ConvertArgs) -> anyhow::Result<()> {
    super::check_output_path(&args.output)?;
    // Temporaries of killed converts to the same file (a kill or a signal
    // leaves `.NAME.PID.tmp`): removed as a bake removes its own.
    groombake::timeline::outputs::remove_stale_temporaries(std::slice::from_ref(&args.output));
    let mut grooms = super::read_sequence(&args.input)?;
    // A prim that lacked an attribute is no loss when the USD writer writes
    // the prims back as they were (it leaves the attribute out again).
    if grooms.len() == 1 || args.frame.is_some() {
        for groom in &mut grooms {
            if exporters::keeps_source_prims(&args.output, groom) {
                let kept: Vec<String> = groom::source_prims::zero_filled(groom)
                    .into_iter()
                    .map(str::to_string)
                    .collect();
                groom.provenance.losses.retain(|loss| !kept.contains(loss));
            }
        }
    }
    // What the reader left out, before anything is written.
    super::warn_or_refuse(&super::losses(&args.input, &grooms), args.strict)?;
    for groom in &mut grooms {
        if let Some(units) = args.source_units {
            groom.units = units;
            groom.provenance.units_source = "stated".into();
        }
        if let Some(up) = args.source_up {
            groom.up_axis = up;
        }
    }
    if let Some(frame) = args.frame {
        grooms = vec![frame_of(&args, &grooms, frame)?];
    }
    if grooms.len() > 1 {
        if exporters::holds_topology_changes(&args.output) {
            return write_topology_changes(&args, grooms);
        }
        super::warn_or_refuse(&[topology_warning(&args, &grooms)], args.strict)?;
        grooms.truncate(1);
    }
    let Some(mut groom) = grooms.pop() else {
        return Err(BadInput(format!("{}: no groom", args.input.display())).into());
    };
    let dropped = dropped_frames(&args, &groom);
    let destination = destination_of(&args, &groom);
    groom.convert_to(destination.units, destination.up);
    check_in_range(&args, &groom, destination.units)?;
    let mut warnings: Vec<String> = dropped.into_iter().collect();
    warnings.extend(exporters::warnings(&args.output, &groom, destination.units));
    warnings.extend(exporters::order_and_pose_warnings(&args.output, &groom));
    super::warn_or_refuse(&warnings, args.strict)?;
    exporters::write_as(&args.output, &groom, destination.attributes)?;
    print_written(&args.output, &groom);
    Ok(())
}

fn destination_of(args: &ConvertArgs, groom: &groom::Groom) -> exporters::Destination {
    exporters::destination(
        &args.output,
        args.target,
        args.units,
        args.up,
        groom.units,
        groom.up_axis,
    )
}

/// Alembic and `.obj` record neither units nor axis in a way other
/// programs read: say what the numbers are.
fn print_written(output: &std::path::Path, groom: &groom::Groom) {
    if let Some(written) = exporters::written_in(output, groom.units, groom.up_axis) {
        eprintln!("groombake: wrote {}: {written}", output.display());
    }
}

/// Frame `frame` (0-based, counted over the whole sequence) as a static groom.
fn frame_of(
    args: &ConvertArgs,
    grooms: &[groom::Groom],
    frame: usize,
) -> anyhow::Result<groom::Groom> {
    let mut index = frame;
    for groom in grooms {
        if let Some(at) = groom.at_frame(index) {
            return Ok(at);
        }
        index -= groom.frames.len().min(index);
    }
    let frames: usize = grooms.iter().map(|g| g.frames.len()).sum();
    Err(BadInput(format!(
        "{}: --frame {frame}: the file has {frames} frames",
        args.input.display()
    ))
    .into())
}

/// Writes a groom whose topology changes over time, every topology kept.
fn write_topology_changes(args: &ConvertArgs, mut grooms: Vec<groom::Groom>) -> anyhow::Result<()> {
    let Some(first) = grooms.first() else {
        return Err(BadInput(format!("{}: no groom", args.input.display())).into());
    };
    let units = destination_of(args, first).units;
    let attributes = destination_of(args, first).attributes;
    let mut warnings: Vec<String> = Vec::new();
    for groom in &mut grooms {
        let up = destination_of(args, groom).up;
        groom.convert_to(units, up);
        check_in_range(args, groom, units)?;
        for warning in exporters::warnings(&args.output, groom, units) {
            if !warnings.contains(&warning) {
                warnings.push(warning);
            }
        }
    }
    super::warn_or_refuse(&warnings, args.strict)?;
    exporters::write_sequence_as(&args.output, &grooms, attributes)?;
    if let Some(first) = grooms.first() {
        print_written(&args.output, first);
    }
    Ok(())
}

/// The warning for a format that holds one topology: only the first
/// stretch of time is written.
fn topology_warning(args: &ConvertArgs, grooms: &[groom::Groom]) -> String {
    let first = &grooms[0];
    let change = grooms
        .get(1)
        .and_then(|g| g.frames.first())
        .map_or(0.0, |f| f.time);
    format!(
        "{}: .{} cannot hold curve counts that change over time: only the first topology ({} strands, {} frames) is written, up to the change at {change} s of {} (.usda/.usdc/.abc keep every topology; --frame F writes frame F)",
        args.output.display(),
        importers::extension_of(&args.output),
        first.strand_count(),
        first.frames.len(),
        args.input.display()
    )
}

/// A static format keeps one pose: say so when the input's frames are
/// lost (a warning, or the refusal under `--strict`).
fn dropped_frames(args: &ConvertArgs, groom: &groom::Groom) -> Option<String> {
    let frames = groom.frames.len();
    let static_output =
        !exporters::ANIMATED_EXTENSIONS.contains(&importers::extension_of(&args.output).as_str());
    (frames > 0 && static_output).then(|| {
        format!(
            "{}: holds one pose; the {frames} frames of {} are dropped and its base pose is written (--frame F writes frame F instead)",
            args.output.display(),
            args.input.display()
        )
    })
}

/// A point finite in the input's units can overflow 32-bit floats in the
/// output's (3e38 cm is 3e39 mm): bad input, found before writing, rather
/// than an exporter's failure.
fn check_in_range(
    args: &ConvertArgs,
    groom: &groom::Groom,
    units: groom::Units,
) -> anyhow::Result<()> {
    match groom.first_fatal_problem() {
        Some(problem) => Err(BadInput(format!(
            "{}: {problem} in the output's units ({units}): a coordinate beyond the range of 32-bit floats",
            args.input.display()
        ))
        .into()),
        None => Ok(()),
    }
}
