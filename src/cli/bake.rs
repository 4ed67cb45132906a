//! `groombake bake TIMELINE [--out DIR] [--threads N] [--seed S] [--report R.json] [-q]`
//! and `groombake validate TIMELINE`.

use super::BadInput;
use clap::Args;
use groombake::timeline::bake::{bake, prepare, BakeError, BakeOptions};
use groombake::timeline::Timeline;
use std::io::IsTerminal;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct BakeArgs {
    /// The timeline (TOML).
    timeline: PathBuf,
    /// Folder that relative export paths are written under (default: the current folder).
    #[arg(long, default_value = ".")]
    out: PathBuf,
    /// Worker threads (default: one per core). Outputs are identical for any count.
    #[arg(long)]
    threads: Option<usize>,
    /// Seed of the random processes (overrides the timeline's `seed`).
    #[arg(long)]
    seed: Option<u64>,
    /// Write a JSON report (stages, timings, counts, warnings, outputs with SHA-256).
    #[arg(long)]
    report: Option<PathBuf>,
    /// No progress bars.
    #[arg(short, long)]
    quiet: bool,
}

#[derive(Debug, Args)]
pub struct ValidateArgs {
    /// The timeline (TOML).
    timeline: PathBuf,
}

/// Maps bake errors on bad input to exit code 2.
pub fn classify(error: BakeError) -> anyhow::Error {
    if error.is_bad_input() {
        BadInput(error.to_string()).into()
    } else {
        error.into()
    }
}

pub fn run_bake(args: BakeArgs) -> anyhow::Result<()> {
    if args.threads == Some(0) {
        return Err(BadInput("--threads must be at least 1".into()).into());
    }
    let timeline = Timeline::load(&args.timeline).map_err(|e| BadInput(e.to_string()))?;
    let options = BakeOptions {
        out_dir: args.out,
        threads: args.threads,
        seed: args.seed,
        progress: !args.quiet && std::io::stderr().is_terminal(),
        dry: false,
        monitor: None,
    };
    let outcome = bake(&timeline, &options).map_err(classify)?;
    let report = &outcome.report;
    if let Some(path) = &args.report {
        let mut file = groom::AtomicFile::create(path)
            .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
        if path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("html"))
        {
            let html = html_report(&timeline, &outcome)?;
            std::io::Write::write_all(&mut file, html.as_bytes())?;
        } else {
            serde_json::to_writer_pretty(&mut file, report)?;
            std::io::Write::write_all(&mut file, b"\n")?;
        }
        file.commit()
            .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    }
    if !args.quiet {
        for stage in &report.stages {
            eprintln!(
                "stage {} {:<8} {:>7.3} s simulated in {:.2} s",
                stage.index, stage.name, stage.simulated_seconds, stage.wall_seconds
            );
        }
        for output in &report.outputs {
            eprintln!("wrote {} ({} bytes)", output.path, output.bytes);
        }
        for warning in &report.warnings {
            eprintln!("warning: {warning}");
        }
    }
    Ok(())
}

/// The HTML page of a bake, with its contact sheet drawn from the snapshots.
fn html_report(
    timeline: &Timeline,
    outcome: &groombake::timeline::bake::BakeOutcome,
) -> anyhow::Result<String> {
    use groombake::preview;
    let entries: Vec<preview::SheetEntry> = outcome
        .snapshots
        .iter()
        .map(|(label, groom)| preview::SheetEntry {
            label,
            groom,
            frame: None,
        })
        .collect();
    let options = groombake::timeline::bake::sheet_options(timeline);
    let sheet = preview::render_sheet(&entries, &options)?;
    let png = preview::png_bytes(&sheet)?;
    Ok(groombake::report_html::bake_page(
        &outcome.report,
        &outcome.snapshots,
        Some(&png),
    ))
}

pub fn run_validate(args: ValidateArgs) -> anyhow::Result<()> {
    let timeline = Timeline::load(&args.timeline).map_err(|e| BadInput(e.to_string()))?;
    let prepared = prepare(&timeline, None).map_err(classify)?;
    println!(
        "{}: ok: {} strands, {} vertices, {} colliders, {} stages ({:.3} s at dt {:.6} s), {} exports",
        args.timeline.display(),
        prepared.strands.strand_count(),
        prepared.strands.vertex_count(),
        timeline.file.colliders.len(),
        timeline.file.stages.get_ref().len(),
        timeline.duration(),
        timeline.dt,
        timeline.file.exports.len()
    );
    Ok(())
}
