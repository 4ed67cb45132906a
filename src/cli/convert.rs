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
    /// Units of the output (m, cm, mm, in, or metres per unit); default: the input's.
    #[arg(long)]
    units: Option<Units>,
    /// Up axis of the output; default: the input's.
    #[arg(long)]
    up: Option<UpAxis>,
    /// Units the input is in, for formats that do not say (.hair, .abc, .obj, .data: cm by default).
    #[arg(long)]
    source_units: Option<Units>,
    /// Up axis the input uses, for formats that do not say (default y).
    #[arg(long)]
    source_up: Option<UpAxis>,
    /// Write only this frame (0-based) of an animated input, as a static groom.
    #[arg(long)]
    frame: Option<usize>,
}

pub fn run(args: ConvertArgs) -> anyhow::Result<()> {
    super::check_output_path(&args.output)?;
    let mut groom = super::read_groom(&args.input)?;
    if let Some(units) = args.source_units {
        groom.units = units;
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
    let units = args.units.unwrap_or(groom.units);
    let up = args.up.unwrap_or(groom.up_axis);
    groom.convert_to(units, up);
    exporters::write(&args.output, &groom)?;
    Ok(())
}
