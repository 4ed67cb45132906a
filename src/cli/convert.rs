//! `groombake convert IN OUT [--units U] [--up y|z] [--frame F]`.

use super::BadInput;
use clap::Args;
use groom::{Units, UpAxis};
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// The groom to read.
    input: PathBuf,
    /// The file to write; its extension picks the format.
    output: PathBuf,
    /// Units of the output (m, cm, mm, in, or metres per unit); default: the
    /// format's (glTF m; USD the input's; .abc, .hair, .data, .obj cm).
    #[arg(long)]
    units: Option<Units>,
    /// Up axis of the output; default: the input's.
    #[arg(long)]
    up: Option<UpAxis>,
    /// Units the input is in, for formats that do not record them (.hair,
    /// .data, .obj: cm by default; .abc: by the writing application).
    #[arg(long)]
    source_units: Option<Units>,
    /// Up axis the input uses, for formats that do not say (default y).
    #[arg(long)]
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
    warn_of_dropped_frames(&args, &groom);
    let units = args
        .units
        .unwrap_or_else(|| exporters::default_units(&args.output, groom.units));
    let up = args.up.unwrap_or(groom.up_axis);
    groom.convert_to(units, up);
    let mut warnings = exporters::warnings(&args.output, &groom, units);
    warnings.extend(exporters::order_and_pose_warnings(&args.output, &groom));
    super::warn_or_refuse(&warnings, args.strict)?;
    exporters::write(&args.output, &groom)?;
    Ok(())
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
    let first_units = grooms.first().map_or(Units::METERS, |g| g.units);
    let units = args
        .units
        .unwrap_or_else(|| exporters::default_units(&args.output, first_units));
    let mut warnings: Vec<String> = Vec::new();
    for groom in &mut grooms {
        let up = args.up.unwrap_or(groom.up_axis);
        groom.convert_to(units, up);
        for warning in exporters::warnings(&args.output, groom, units) {
            if !warnings.contains(&warning) {
                warnings.push(warning);
            }
        }
    }
    super::warn_or_refuse(&warnings, args.strict)?;
    exporters::write_sequence(&args.output, &grooms)?;
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
        "{}: .{} cannot hold curve counts that change over time: only the first topology ({} strands, {} frames) is written, up to the change at {change} s of {} (.usda/.usdc keep every topology; --frame F writes frame F)",
        args.output.display(),
        importers::extension_of(&args.output),
        first.strand_count(),
        first.frames.len(),
        args.input.display()
    )
}

/// A static format keeps one pose: say so when the input's frames are lost.
fn warn_of_dropped_frames(args: &ConvertArgs, groom: &groom::Groom) {
    let frames = groom.frames.len();
    let static_output =
        !exporters::ANIMATED_EXTENSIONS.contains(&importers::extension_of(&args.output).as_str());
    if frames > 0 && static_output {
        eprintln!(
            "groombake: warning: {}: holds one pose; the {frames} frames of {} are dropped and its base pose is written (--frame F writes frame F instead)",
            args.output.display(),
            args.input.display()
        );
    }
}
