//! `groombake diff A B [--tolerance T] [--json]`: compares two grooms of any
//! formats; exit 0 when equal within the tolerance, 1 when different, 2 on
//! bad input.

use super::BadInput;
use clap::Args;
use groombake::diff::{diff_sequences, DiffOptions, DiffReport};
use std::io::Write;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct DiffArgs {
    /// The first groom (any format).
    a: PathBuf,
    /// The second groom (any format).
    b: PathBuf,
    /// Largest accepted deviation: metres for points (distance), the
    /// attribute's own unit for attribute values. Default 1e-6.
    #[arg(long, default_value_t = 1e-6)]
    tolerance: f64,
    /// How many of the largest deviations to print.
    #[arg(long, default_value_t = 10)]
    show: usize,
    /// Leave this attribute out (repeatable), e.g. an exporter's own
    /// `groom_guide` when comparing Alembic with USD.
    #[arg(long, value_name = "ATTRIBUTE")]
    ignore: Vec<String>,
    /// Print the comparison as JSON.
    #[arg(long)]
    json: bool,
}

/// The grooms differ: exit code 1 after the listing.
#[derive(Debug, thiserror::Error)]
#[error("{a} and {b} differ (tolerance {tolerance})")]
pub struct Different {
    a: String,
    b: String,
    tolerance: f64,
}

fn print_text(out: &mut impl Write, report: &DiffReport) -> std::io::Result<()> {
    if report.equal {
        writeln!(
            out,
            "equal within {}: {} values compared, largest deviation {:.3e}",
            report.tolerance, report.compared, report.max_deviation
        )?;
        return Ok(());
    }
    for line in &report.structural {
        writeln!(out, "differs: {line}")?;
    }
    if report.above_tolerance > 0 {
        writeln!(
            out,
            "{} of {} values deviate by more than {}; the largest:",
            report.above_tolerance, report.compared, report.tolerance
        )?;
    }
    for d in &report.largest {
        let frame = d.frame.map(|f| format!(" frame {f}")).unwrap_or_default();
        let vertex = match (d.vertex, d.global_vertex) {
            (Some(v), Some(g)) => format!(" vertex {v} (global {g})"),
            _ => String::new(),
        };
        writeln!(
            out,
            "  {:.6e}  {}{frame} strand {}{vertex}: A {:?} B {:?}",
            d.amount, d.what, d.strand, d.a, d.b
        )?;
    }
    Ok(())
}

pub fn run(args: DiffArgs) -> anyhow::Result<()> {
    if !(args.tolerance >= 0.0 && args.tolerance.is_finite()) {
        return Err(BadInput(format!(
            "--tolerance {}: must be a finite number >= 0",
            args.tolerance
        ))
        .into());
    }
    // Files whose curve counts change over time compare stretch by stretch.
    let a = super::read_sequence(&args.a)?;
    let b = super::read_sequence(&args.b)?;
    let options = DiffOptions {
        tolerance: args.tolerance,
        listed: args.show,
        ignore: args.ignore,
    };
    let report = diff_sequences(&a, &b, &options);
    let mut out = std::io::stdout().lock();
    if args.json {
        serde_json::to_writer_pretty(&mut out, &report)?;
        writeln!(out)?;
    } else {
        print_text(&mut out, &report)?;
    }
    out.flush()?;
    if report.equal {
        Ok(())
    } else {
        Err(Different {
            a: args.a.display().to_string(),
            b: args.b.display().to_string(),
            tolerance: args.tolerance,
        }
        .into())
    }
}
