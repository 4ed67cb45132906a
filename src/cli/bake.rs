//! `groombake bake TIMELINE [--out DIR] [--threads N] [--seed S] [--report R.json] [-q]`
//! and `groombake validate TIMELINE`.

use super::BadInput;
use clap::Args;
use groombake::timeline::bake::{bake, plan_outputs, prepare, BakeError, BakeMonitor, BakeOptions};
use groombake::timeline::report::BakeReport;
use groombake::timeline::Timeline;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::atomic::AtomicUsize;
use std::sync::Arc;

#[derive(Debug, Args)]
pub struct BakeArgs {
    /// The timeline (TOML).
    #[arg(value_hint = clap::ValueHint::FilePath)]
    timeline: PathBuf,
    /// Folder that relative export paths are written under.
    #[arg(long, default_value = ".", value_hint = clap::ValueHint::DirPath)]
    out: PathBuf,
    /// Worker threads (default: one per core; at most 1024). Outputs are identical for any count.
    #[arg(short = 'j', long, value_parser = parse_threads)]
    threads: Option<usize>,
    /// Seed of the random processes (overrides the timeline's `seed`).
    #[arg(long)]
    seed: Option<u64>,
    /// Write a report (status, inputs' and outputs' SHA-256, stages, timings, warnings),
    /// on failure too: JSON, an HTML page for R.html, or JSON on stdout for `-`.
    #[arg(long, value_name = "R.json|R.html|-", value_hint = clap::ValueHint::FilePath)]
    report: Option<PathBuf>,
    /// No progress bars.
    #[arg(short, long)]
    quiet: bool,
    /// Fail (exit 2, before simulating) instead of warning when an export
    /// must change anything about the data.
    #[arg(long)]
    strict: bool,
}

/// `--threads`: 1 to the budget's cap.
pub fn parse_threads(text: &str) -> Result<usize, String> {
    let threads: usize = text.parse().map_err(|_| {
        format!(
            "{:?} is not a whole number",
            text.escape_debug().to_string()
        )
    })?;
    groombake::budget::check_threads(threads).map_err(|m| m.replace("--threads ", ""))
}

#[derive(Debug, Args)]
pub struct ValidateArgs {
    /// The timeline (TOML).
    timeline: PathBuf,
}

/// Maps bake errors on bad input to exit code 2.
pub fn classify(error: BakeError) -> anyhow::Error {
    match error {
        BakeError::Interrupted { signal } => super::Interrupted(signal).into(),
        e @ BakeError::Report { .. } => ReportUnusable(e.to_string()).into(),
        e if e.is_bad_input() => BadInput(e.to_string()).into(),
        e => e.into(),
    }
}

/// SIGINT, SIGTERM and SIGHUP store their number in `stop` (the bake's
/// [`BakeMonitor::stop`]) so the bake stops at its next step and removes
/// its temporaries; a second such signal ends the process at once.
pub(super) fn stop_on_signals(stop: &Arc<AtomicUsize>) -> anyhow::Result<()> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    for number in [SIGINT, SIGTERM, SIGHUP] {
        let stop_now = Arc::new(std::sync::atomic::AtomicBool::new(false));
        // The conditional shutdown is registered first, so it sees the flag
        // from the signal before this one.
        signal_hook::flag::register_conditional_shutdown(number, 128 + number, stop_now.clone())?;
        signal_hook::flag::register(number, stop_now)?;
        signal_hook::flag::register_usize(number, stop.clone(), number as usize)?;
    }
    Ok(())
}

/// The report path itself is unusable: bad input, and no report is written.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct ReportUnusable(String);

pub fn run_bake(args: BakeArgs) -> anyhow::Result<()> {
    let mut report = BakeReport::start(&args.timeline);
    let (mut sheet, mut samples) = (None, Vec::new());
    let result = bake_and_report(&args, &mut report, &mut sheet, &mut samples);
    let Some(path) = &args.report else {
        return result;
    };
    if let Err(e) = &result {
        if e.chain().any(|c| c.is::<ReportUnusable>()) {
            return result;
        }
    }
    let (status, error) = match &result {
        Ok(()) => ("ok", None),
        Err(e) => {
            let code = super::exit_code_for(e);
            let status = match code {
                2 => "invalid",
                1 => "failed",
                _ => "interrupted",
            };
            (status, Some(super::message_of(e)))
        }
    };
    let code = result.as_ref().map_or_else(super::exit_code_for, |_| 0);
    report.finish(status, code, error);
    let written = if is_stdout(path) {
        print_report(&report)
    } else if wants_html(Some(path)) {
        let folder = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(std::path::Path::new("."));
        let page = groombake::report_html::bake_page(&report, &samples, sheet.as_deref(), folder);
        groom::AtomicFile::create(path).and_then(|mut file| {
            std::io::Write::write_all(&mut file, page.as_bytes())?;
            file.commit()
        })
    } else {
        report.write(path)
    }
    .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()));
    result.and(written)
}

/// Whether the report goes to stdout (`--report -`).
fn is_stdout(path: &std::path::Path) -> bool {
    path.as_os_str() == "-"
}

/// The JSON report on stdout, for a pipe (`--report - | jq`).
fn print_report(report: &BakeReport) -> std::io::Result<()> {
    let mut out = std::io::stdout().lock();
    serde_json::to_writer_pretty(&mut out, report)?;
    std::io::Write::write_all(&mut out, b"\n")?;
    std::io::Write::flush(&mut out)
}

/// Whether the report path asks for the HTML page (`--report R.html`).
fn wants_html(path: Option<&std::path::Path>) -> bool {
    path.and_then(|p| p.extension())
        .is_some_and(|e| e.eq_ignore_ascii_case("html"))
}

fn bake_and_report(
    args: &BakeArgs,
    report: &mut BakeReport,
    html: &mut Option<Vec<u8>>,
    samples: &mut Vec<groombake::timeline::plots::PlotSample>,
) -> anyhow::Result<()> {
    let monitor = Arc::new(BakeMonitor::default());
    stop_on_signals(&monitor.stop)?;
    let timeline = Timeline::load(&args.timeline).map_err(|e| BadInput(e.to_string()))?;
    report.record_sources(&timeline);
    let options = BakeOptions {
        out_dir: args.out.clone(),
        threads: args.threads,
        seed: args.seed,
        progress: !args.quiet && std::io::stderr().is_terminal(),
        dry: false,
        monitor: Some(monitor),
        // stdout is no file to check or replace.
        report: args.report.clone().filter(|p| !is_stdout(p)),
        strict: args.strict,
    };
    let outcome = bake(&timeline, &options).map_err(classify)?;
    if wants_html(args.report.as_deref()) {
        *html = Some(sheet_png(&timeline, &outcome.snapshots, &outcome.rods)?);
        *samples = outcome.plot_samples;
    }
    let started = std::mem::take(&mut report.started);
    *report = outcome.report;
    report.started = started;
    report.warnings.splice(0..0, timeline.warnings());
    if !args.quiet {
        if let Some(radius) = &report.fibre_radius {
            eprintln!("fibre radius {}", radius.describe());
        }
        for stage in &report.stages {
            eprintln!(
                "stage {} {:<8} {:>7.3} s simulated in {:.2} s",
                stage.index, stage.name, stage.simulated_seconds, stage.wall_seconds
            );
        }
        for output in &report.outputs {
            match &output.written_in {
                Some(units) => eprintln!("wrote {} ({} bytes, {units})", output.path, output.bytes),
                None => eprintln!("wrote {} ({} bytes)", output.path, output.bytes),
            }
        }
    }
    for warning in &report.warnings {
        eprintln!("warning: {}", super::shortened(&super::printable(warning)));
    }
    Ok(())
}

/// The contact sheet of a bake's snapshots, as PNG bytes for the HTML page.
fn sheet_png(
    timeline: &Timeline,
    snapshots: &[(String, groom::Groom)],
    rods: &[groombake::timeline::surfaces::RodSnapshot],
) -> anyhow::Result<Vec<u8>> {
    let sheet =
        groombake::timeline::bake::sheet_image(timeline, snapshots, rods).map_err(classify)?;
    Ok(groombake::preview::png_bytes(&sheet)?)
}

pub fn run_validate(args: ValidateArgs) -> anyhow::Result<()> {
    let timeline = Timeline::load(&args.timeline).map_err(|e| BadInput(e.to_string()))?;
    plan_outputs(&timeline, &BakeOptions::default()).map_err(classify)?;
    let prepared = prepare(&timeline, None).map_err(classify)?;
    eprintln!("fibre radius {}", prepared.fibre_radius.describe());
    for warning in timeline
        .warnings()
        .into_iter()
        .chain(prepared.fibre_radius.warning())
    {
        eprintln!("warning: {}", super::shortened(&super::printable(&warning)));
    }
    let unsimulated = groombake::sim::unsimulated_strands(&prepared.strands);
    if let Some(first) = unsimulated.first() {
        eprintln!(
            "warning: {} strand(s) would not be simulated (first: strand {}: {})",
            unsimulated.len(),
            first.strand,
            first.reason
        );
    }
    println!(
        "{}: ok: {}, {}, {}, {} ({:.3} s at dt {:.6} s), {}",
        args.timeline.display(),
        counted(prepared.strands.strand_count(), "strand"),
        counted(prepared.strands.vertex_count(), "vertex"),
        counted(timeline.file.colliders.len(), "collider"),
        counted(timeline.file.stages.get_ref().len(), "stage"),
        timeline.duration(),
        timeline.dt,
        counted(timeline.file.exports.len(), "export")
    );
    Ok(())
}

/// `1 stage`, `2 stages`, `1 vertex`, `0 vertices`.
fn counted(n: usize, noun: &str) -> String {
    match (n, noun) {
        (1, _) => format!("1 {noun}"),
        (_, "vertex") => format!("{n} vertices"),
        _ => format!("{n} {noun}s"),
    }
}
