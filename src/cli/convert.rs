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
    let mut groom = super::read_groom(&args.input)?;
    if let Some(units) = args.source_units {
        groom.units = units;
        groom.provenance.units_source = "stated".into();
    }
    if let Some(up) = args.source_up {
        groom.up_axis = up;
    }
    if let Some(frame) = args.frame {
        let frames = groom.frames.len();
        groom = groom.at_frame(frame).ok_or_else(|| {
            BadInput(format!(
                "{}: --frame {frame}: the file has {frames} frames",
                args.input.display()
            ))
        })?;
    }
    warn_of_dropped_frames(&args, &groom);
    let units = args
        .units
        .unwrap_or_else(|| exporters::default_units(&args.output, groom.units));
    let up = args.up.unwrap_or(groom.up_axis);
    groom.convert_to(units, up);
    let warnings = exporters::warnings(&args.output, &groom, units);
    super::warn_or_refuse(&warnings, args.strict)?;
    exporters::write(&args.output, &groom)?;
    Ok(())
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
