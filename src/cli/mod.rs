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
mod values;

use clap::{CommandFactory, Parser, Subcommand};
use std::process::ExitCode;

#[derive(Debug, Parser)]
#[command(
    name = "groombake",
    version,
    about = "Bakes styled hair grooms from the chemistry of hair",
    // A bare `groombake` shows the commands, not one line.
    arg_required_else_help = true
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
    /// Prints the man page (roff): `groombake man > groombake.1`; `groombake man DIR` writes one per command.
    Man(install::ManArgs),
    /// Bakes the jobs of a manifest (in parallel, a shard, resumed) or emits a farm script.
    Batch(batch::BatchArgs),
    /// Compares two grooms within a tolerance (exit 0 equal, 1 different).
    Diff(diff::DiffArgs),
}

/// Bad input or usage: exit code 2.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct BadInput(pub String);

/// Stopped by a signal (its number): exit code 128 + the number.
#[derive(Debug, thiserror::Error)]
#[error("stopped by signal {0}; temporaries removed, no output replaced")]
pub struct Interrupted(pub usize);

/// Parses the command line; on `--help`/`--version` prints clap's text and
/// returns 0; with no arguments prints the help (the command list) and
/// returns 2; on a usage error prints one line, `groombake: <where>:
/// <what>` (the subcommand and argument, clap's message with the names of
/// missing arguments and its "a similar ... exists" tip), and returns 2.
pub fn parse() -> Result<Args, ExitCode> {
    Args::try_parse().map_err(|error| {
        if !error.use_stderr() {
            let _ = error.print();
            return ExitCode::SUCCESS;
        }
        if error.kind() == clap::error::ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
            let _ = error.print();
            return ExitCode::from(2);
        }
        eprintln!(
            "groombake: {}",
            shortened(&printable(&usage_error_line(&error)))
        );
        ExitCode::from(2)
    })
}

/// `<where>: <what>` of a clap usage error.
fn usage_error_line(error: &clap::Error) -> String {
    use clap::error::{ContextKind, ContextValue};
    let rendered = error.render().to_string();
    // clap's message up to its usage lines: the error, then the missing
    // arguments' names and a tip, each on lines of their own.
    let mut what = String::new();
    for line in rendered.lines().map(str::trim) {
        if line.starts_with("Usage:") || line.starts_with("For more information") {
            break;
        }
        let line = line.trim_start_matches("error:").trim();
        if line.is_empty() {
            continue;
        }
        if !what.is_empty() {
            what.push_str(if line.starts_with("tip:") { "; " } else { " " });
        }
        what.push_str(line);
    }
    if what.is_empty() {
        what.push_str("bad usage");
    }
    let subcommand = std::env::args()
        .nth(1)
        .filter(|a| Args::command().find_subcommand(a).is_some());
    let argument = match error.get(ContextKind::InvalidArg) {
        Some(ContextValue::String(a)) => Some(a.clone()),
        _ => None,
    };
    let place: Vec<String> = subcommand.into_iter().chain(argument).collect();
    let place = if place.is_empty() {
        "usage".to_string()
    } else {
        place.join(" ")
    };
    format!("{place}: {what} (see --help)")
}

/// Text safe to print: control characters (NUL, escapes, newlines) from a
/// file or argument are shown escaped, never sent to the terminal raw.
pub fn printable(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

/// The longest error or warning message, in characters: with its
/// `groombake: warning: ` in front (20 characters), a line stays within 300.
pub const MAX_LINE: usize = 280;
/// A word (a run without spaces: a token, a path) longer than this many
/// characters is shown by its two ends and its length.
const MAX_WORD: usize = 120;
/// Characters kept from each end of a shortened word.
const WORD_ENDS: usize = 40;

/// A line of at most [`MAX_LINE`] characters: each word over [`MAX_WORD`]
/// (a 1 MB token from a file) becomes its two ends and its length in
/// bytes, and a line still too long keeps its start and end.
pub fn shortened(text: &str) -> String {
    let mut out = String::with_capacity(text.len().min(4 * MAX_LINE));
    for (i, word) in text.split(' ').enumerate() {
        if i > 0 {
            out.push(' ');
        }
        let count = word.chars().count();
        if count > MAX_WORD {
            let head: String = word.chars().take(WORD_ENDS).collect();
            let tail: String = word.chars().skip(count - WORD_ENDS).collect();
            // The length of the token itself, without the quotes around it.
            let token = word.trim_matches(|c| matches!(c, '\'' | '"' | '`'));
            out.push_str(&format!("{head}...{tail} ({} bytes)", token.len()));
        } else {
            out.push_str(word);
        }
    }
    let count = out.chars().count();
    if count <= MAX_LINE {
        return out;
    }
    let marker = format!(" ...({} characters)... ", count);
    let keep = MAX_LINE - marker.len();
    let head: String = out.chars().take(keep * 2 / 3).collect();
    let tail: String = out.chars().skip(count - (keep - keep * 2 / 3)).collect();
    format!("{head}{marker}{tail}")
}

/// An error and its causes on one line, each cause once: errors that show
/// their source in their own text are not followed by it again.
pub fn message_of(error: &anyhow::Error) -> String {
    let mut message = String::new();
    for cause in error.chain() {
        let text = cause.to_string();
        if message.contains(&text) {
            continue;
        }
        if !message.is_empty() {
            message.push_str(": ");
        }
        message.push_str(&text);
    }
    shortened(&printable(&message))
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
        Command::Man(a) => install::run_man(a),
        Command::Diff(a) => diff::run(a),
        Command::Batch(a) => batch::run(a),
    }
}

/// 2 for bad input (unreadable or malformed files, bad parameters), 1 for a
/// failure during the work.
pub fn exit_code_for(error: &anyhow::Error) -> u8 {
    if let Some(Interrupted(signal)) = error.chain().find_map(|c| c.downcast_ref()) {
        return u8::try_from(128 + signal).unwrap_or(u8::MAX);
    }
    let bad_input = error.chain().any(|cause| {
        cause.is::<BadInput>()
            || cause.is::<importers::ImportError>()
            || cause.is::<groombake::generate::GeneratorError>()
            || cause.is::<bake::ReportUnusable>()
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
        eprintln!("groombake: warning: {}", shortened(&printable(warning)));
    }
    Ok(())
}

/// Refuses an output path whose extension names no format or that cannot
/// be written, before any input is read.
pub fn check_output_path(path: &std::path::Path) -> anyhow::Result<()> {
    groombake::timeline::check_output_extension(path)
        .and_then(|()| groombake::timeline::outputs::check_writable(path))
        .map_err(|message| BadInput(format!("{}: {message}", path.display())).into())
}

/// Reads a groom file as a sequence of grooms of one topology each
/// (`importers::read_sequence`), refusing one with fatal problems and one
/// with no strand at all: nothing in it reads as hair, so there is nothing
/// to inspect, convert or compare (the message adds what the reader
/// skipped, such as a glTF's triangle primitives).
pub fn read_sequence(path: &std::path::Path) -> anyhow::Result<Vec<groom::Groom>> {
    let grooms = importers::read_sequence(path)?;
    for groom in &grooms {
        if let Some(problem) = groom.first_fatal_problem() {
            return Err(BadInput(format!("{}: {problem}", path.display())).into());
        }
    }
    no_strands_is_an_error(path, &grooms)?;
    Ok(grooms)
}

/// The checks of [`read_sequence`] on a groom read a frame at a time:
/// its topology and rest pose (each frame is checked as it is read).
pub fn check_groom(path: &std::path::Path, groom: &groom::Groom) -> anyhow::Result<()> {
    if let Some(problem) = groom.first_fatal_problem() {
        return Err(BadInput(format!("{}: {problem}", path.display())).into());
    }
    no_strands_is_an_error(path, std::slice::from_ref(groom))
}

/// A file of no strands at all is refused, naming the first thing skipped.
fn no_strands_is_an_error(path: &std::path::Path, grooms: &[groom::Groom]) -> anyhow::Result<()> {
    if grooms.iter().all(|g| g.strand_count() == 0) {
        let skipped: Vec<&String> = grooms.iter().flat_map(|g| &g.provenance.losses).collect();
        let mut message = format!(
            "{}: no strands: nothing in the file reads as hair",
            path.display()
        );
        if let Some(first) = skipped.first() {
            message.push_str(&format!(" ({first})"));
        }
        return Err(BadInput(message).into());
    }
    Ok(())
}

/// What the readers could not keep of the grooms' file (`Provenance::losses`),
/// each line once (a changing topology is read once per stretch).
pub fn losses(file: &std::path::Path, grooms: &[groom::Groom]) -> Vec<String> {
    let mut all: Vec<String> = Vec::new();
    for loss in grooms.iter().flat_map(|g| &g.provenance.losses) {
        let line = format!("{}: {loss}", file.display());
        if !all.contains(&line) {
            all.push(line);
        }
    }
    all
}
