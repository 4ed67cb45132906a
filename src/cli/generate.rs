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
    /// A combed head of hair: roots inside a hairline, a parting and a
    /// crown whorl, lying on the head and hanging, with varied lengths,
    /// widths, curls and clumps.
    Head,
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
    /// Hair width, metres [head: mean; default 8e-5].
    #[arg(long, help_heading = "Head")]
    width: Option<f32>,
    /// A closed head mesh (.obj, .glb, .gltf; metres, Y up, face +Z) to root the hair on
    /// instead of the ellipsoid [head].
    #[arg(long, help_heading = "Head", value_hint = clap::ValueHint::FilePath)]
    scalp_mesh: Option<PathBuf>,
    /// Hairline: polar angles from the top at the front, sides and back, degrees
    /// [head; 30 to 170; default 60,100,125].
    #[arg(long, help_heading = "Head", value_delimiter = ',')]
    hairline: Option<Vec<f32>>,
    /// Parting, degrees from the top toward +X (0: centre) [head; -60 to 60; default 15].
    #[arg(long, help_heading = "Head", allow_hyphen_values = true)]
    parting: Option<f32>,
    /// Crown whorl's polar angle toward the back, degrees [head; 0 to 80; default 35].
    #[arg(long, help_heading = "Head")]
    whorl_angle: Option<f32>,
    /// Turn of the hair around the whorl, degrees (+: clockwise from above)
    /// [head; -180 to 180; default 40].
    #[arg(long, help_heading = "Head", allow_hyphen_values = true)]
    whorl_swirl: Option<f32>,
    /// Angle at which hair leaves the scalp, degrees [head; 1 to 60; default 15].
    #[arg(long, help_heading = "Head")]
    lift: Option<f32>,
    /// Thickness of the hair layer on the head, metres [head; 2e-4 to 0.05; default 0.003].
    #[arg(long, help_heading = "Head")]
    volume: Option<f32>,
    /// Arc length that lies on the head however steep, metres [head; 0 to 0.3; default 0.04].
    #[arg(long, help_heading = "Head")]
    contact_length: Option<f32>,
    /// Relative standard deviation of the lengths [head; 0 to 0.3; default 0.15].
    #[arg(long, help_heading = "Head")]
    length_spread: Option<f32>,
    /// Relative standard deviation of the widths [head; 0 to 0.3; default 0.15].
    #[arg(long, help_heading = "Head")]
    width_spread: Option<f32>,
    /// Curl the hair [head].
    #[arg(long, help_heading = "Head")]
    curl: bool,
    /// Mean curl radius, metres [head; 0.001 to 0.05; default 0.01].
    #[arg(long, help_heading = "Head")]
    curl_radius: Option<f32>,
    /// Relative standard deviation of the curl radius [head; 0 to 0.3; default 0.15].
    #[arg(long, help_heading = "Head")]
    curl_radius_spread: Option<f32>,
    /// Length of one curl turn along the hair's line, metres [head; 0.002 to 0.5; default 0.03].
    #[arg(long, help_heading = "Head")]
    curl_pitch: Option<f32>,
    /// Curl phase at the root, degrees [head; -360 to 360; default 0].
    #[arg(long, help_heading = "Head", allow_hyphen_values = true)]
    curl_phase: Option<f32>,
    /// Random phase per strand, plus or minus degrees [head; 0 to 180; default 180].
    #[arg(long, help_heading = "Head")]
    curl_phase_spread: Option<f32>,
    /// Mean distance between clump centres, metres (0: no clumps)
    /// [head; 0 or 0.002 to 0.1; default 0.012].
    #[arg(long, help_heading = "Head")]
    clump_size: Option<f32>,
    /// How far tips gather to their clump's centre, 0 to 1 [head; default 0.5].
    #[arg(long, help_heading = "Head")]
    clump_strength: Option<f32>,
    /// Exponent of clumping along the strand (above 1: toward the tips)
    /// [head; 0.1 to 10; default 1.5].
    #[arg(long, help_heading = "Head")]
    clump_profile: Option<f32>,
}

pub fn run(args: GenerateArgs) -> anyhow::Result<()> {
    super::check_output_path(&args.output)?;
    let (layout, shape) = match args.kind {
        Kind::Straight => (RootLayout::Scalp, StrandShape::Straight),
        Kind::Wavy => (RootLayout::Scalp, StrandShape::Wavy),
        Kind::Swatch => (RootLayout::Swatch, StrandShape::Straight),
        Kind::WavySwatch => (RootLayout::Swatch, StrandShape::Wavy),
        Kind::Head => (RootLayout::Head, StrandShape::Straight),
    };
    let d = GeneratorParameters::default();
    if let Some(h) = &args.hairline {
        if h.len() != 3 {
            return Err(super::BadInput(format!(
                "--hairline takes three angles, front,side,back in degrees (got {})",
                h.len()
            ))
            .into());
        }
    }
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
        width: args.width.unwrap_or(d.width),
        scalp_mesh: args.scalp_mesh,
        hairline: args.hairline.map_or(d.hairline, |h| [h[0], h[1], h[2]]),
        parting: args.parting.unwrap_or(d.parting),
        whorl_angle: args.whorl_angle.unwrap_or(d.whorl_angle),
        whorl_swirl: args.whorl_swirl.unwrap_or(d.whorl_swirl),
        lift: args.lift.unwrap_or(d.lift),
        volume: args.volume.unwrap_or(d.volume),
        contact_length: args.contact_length.unwrap_or(d.contact_length),
        length_spread: args.length_spread.unwrap_or(d.length_spread),
        width_spread: args.width_spread.unwrap_or(d.width_spread),
        curl: args.curl,
        curl_radius: args.curl_radius.unwrap_or(d.curl_radius),
        curl_radius_spread: args.curl_radius_spread.unwrap_or(d.curl_radius_spread),
        curl_pitch: args.curl_pitch.unwrap_or(d.curl_pitch),
        curl_phase: args.curl_phase.unwrap_or(d.curl_phase),
        curl_phase_spread: args.curl_phase_spread.unwrap_or(d.curl_phase_spread),
        clump_size: args.clump_size.unwrap_or(d.clump_size),
        clump_strength: args.clump_strength.unwrap_or(d.clump_strength),
        clump_profile: args.clump_profile.unwrap_or(d.clump_profile),
        ..d.clone()
    };
    let groom = generate(&parameters)?;
    exporters::write(&args.output, &groom)?;
    Ok(())
}
