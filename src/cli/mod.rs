//! The command line: argument parsing (clap) and one module per subcommand.
//! Each subcommand only composes library functions.

mod bake;
mod batch;
mod bench;
mod convert;
mod diff;
mod generate;
mod inspect;
mod install;
mod preview;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Debug, Parser)]
#[command(
    name = "groombake",
    version,
    about = "Bakes styled hair grooms from the chemistry of hair"
)]
pub struct Args {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Strands, vertices, bounds, attributes and time samples of a groom file.
    Inspect(inspect::InspectArgs),
    /// Converts a groom between formats (chosen by extension).
    Convert(convert::ConvertArgs),
    /// Writes a procedural test groom.
    Generate(generate::GenerateArgs),
    /// Runs a timeline of treatments and writes its exports.
    Bake(bake::BakeArgs),
    /// Checks a timeline (schema, files, values) without simulating.
    Validate(bake::ValidateArgs),
    /// Times the solver on a generated groom.
    Bench(bench::BenchArgs),
    /// Draws a groom (or a sheet of its frames) to a PNG picture.
    Preview(preview::PreviewArgs),
    /// Prints a shell completion script: `groombake completions bash > ...`.
    Completions(install::CompletionsArgs),
    /// Prints the man page (roff): `groombake man > groombake.1`.
    Man,
    /// Bakes the jobs of a manifest (in parallel, a shard, resumed) or emits a farm script.
    Batch(batch::BatchArgs),
    /// Compares two grooms within a tolerance (exit 0 equal, 1 different).
    Diff(diff::DiffArgs),
}

/// Bad input or usage: exit code 2.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct BadInput(pub String);

/// Parses the command line; on `--help`/`--version` or a usage error, prints
/// clap's text and returns the exit code to end with (0 or 2).
pub fn parse() -> Result<Args, ExitCode> {
    Args::try_parse().map_err(|error| {
        let _ = error.print();
        if error.use_stderr() {
            ExitCode::from(2)
        } else {
            ExitCode::SUCCESS
        }
    })
}

pub fn run(args: Args) -> anyhow::Result<()> {
    match args.command {
        Command::Inspect(a) => inspect::run(a),
        Command::Convert(a) => convert::run(a),
        Command::Generate(a) => generate::run(a),
        Command::Bake(a) => bake::run_bake(a),
        Command::Validate(a) => bake::run_validate(a),
        Command::Bench(a) => bench::run(a),
        Command::Preview(a) => preview::run(a),
        Command::Completions(a) => install::run_completions(a),
        Command::Man => install::run_man(),
        Command::Diff(a) => diff::run(a),
        Command::Batch(a) => batch::run(a),
    }
}

/// 2 for bad input (unreadable or malformed files, bad parameters), 1 for a
/// failure during the work.
pub fn exit_code_for(error: &anyhow::Error) -> u8 {
    let bad_input = error.chain().any(|cause| {
        cause.is::<BadInput>()
            || cause.is::<importers::ImportError>()
            || cause.is::<groombake::generate::GeneratorError>()
    });
    if bad_input {
        2
    } else {
        1
    }
}

/// A write to a closed pipe (`groombake inspect x | head`) is not a failure.
pub fn is_broken_pipe(error: &anyhow::Error) -> bool {
    error.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// Prints each warning on stderr, one line each; with `strict`, refuses
/// (exit 2) instead, before anything is written.
pub fn warn_or_refuse(warnings: &[String], strict: bool) -> anyhow::Result<()> {
    if strict {
        if let Some(first) = warnings.first() {
            return Err(BadInput(format!("--strict: {first}")).into());
        }
    }
    for warning in warnings {
        eprintln!("groombake: warning: {warning}");
    }
    Ok(())
}

/// Reads a groom file and refuses one with fatal problems, naming the first.
pub fn read_groom(path: &std::path::Path) -> anyhow::Result<groom::Groom> {
    let groom = importers::read(path)?;
    if let Some(problem) = groom.first_fatal_problem() {
        return Err(BadInput(format!("{}: {problem}", path.display())).into());
    }
    Ok(groom)
}
