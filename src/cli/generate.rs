//! `groombake generate KIND [options] -o OUT`.

use clap::{Args, ValueEnum};
use groombake::generate::{generate, GeneratorParameters, RootLayout, StrandShape};
use std::path::PathBuf;

#[derive(Debug, Clone, Copy, ValueEnum)]
enum Kind {
    /// Straight strands on a scalp cap.
    Straight,
    /// Waved strands (elliptic-cone spiral) on a scalp cap.
    Wavy,
    /// Straight strands hanging from a bar.
    Swatch,
    /// Waved strands hanging from a bar.
    WavySwatch,
}

#[derive(Debug, Args)]
pub struct GenerateArgs {
    kind: Kind,
    /// Output file; its extension picks the format.
    #[arg(short, long)]
    output: PathBuf,
    /// Number of strands.
    #[arg(long, default_value_t = 200)]
    strands: usize,
    /// Strand length, metres.
    #[arg(long, default_value_t = 0.24)]
    length: f32,
    /// Segment length, metres.
    #[arg(long, default_value_t = 0.01)]
    segment_length: f32,
    /// Seed of the random root placement (the same seed, the same groom).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Head semi-axes x,y,z in metres (equal for a sphere).
    #[arg(long, value_delimiter = ',', num_args = 3, default_values_t = [0.08, 0.1, 0.09])]
    head_radii: Vec<f32>,
    /// Largest polar angle of a root from the top of the head, degrees.
    #[arg(long, default_value_t = 80.0)]
    scalp_angle: f32,
    /// Wave slopes A,B of the spiral radius.
    #[arg(long, value_delimiter = ',', num_args = 2, default_values_t = [0.15, 0.1])]
    wave_amplitude: Vec<f32>,
    /// Wave frequency C, radians per metre.
    #[arg(long, default_value_t = 60.0)]
    wave_frequency: f32,
    /// Combs scalp strands down: bend toward -Y in radians per metre (0: straight out).
    #[arg(long, default_value_t = 0.0)]
    drape: f32,
}

pub fn run(args: GenerateArgs) -> anyhow::Result<()> {
    super::check_output_path(&args.output)?;
    let (layout, shape) = match args.kind {
        Kind::Straight => (RootLayout::Scalp, StrandShape::Straight),
        Kind::Wavy => (RootLayout::Scalp, StrandShape::Wavy),
        Kind::Swatch => (RootLayout::Swatch, StrandShape::Straight),
        Kind::WavySwatch => (RootLayout::Swatch, StrandShape::Wavy),
    };
    let parameters = GeneratorParameters {
        layout,
        shape,
        strands: args.strands,
        length: args.length,
        segment_length: args.segment_length,
        seed: args.seed,
        head_radii: [args.head_radii[0], args.head_radii[1], args.head_radii[2]],
        scalp_angle: args.scalp_angle,
        wave_amplitude: [args.wave_amplitude[0], args.wave_amplitude[1]],
        wave_frequency: args.wave_frequency,
        drape: args.drape,
        ..GeneratorParameters::default()
    };
    let groom = generate(&parameters)?;
    exporters::write(&args.output, &groom)?;
    Ok(())
}
