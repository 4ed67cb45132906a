//! `groombake completions SHELL` and `groombake man`: shell completion
//! scripts (clap_complete) and a roff man page (clap_mangen), both made from
//! the same clap definition as the parser, so they never fall behind it.

use clap::{Args, CommandFactory};
use clap_complete::Shell;
use std::io::Write;

#[derive(Debug, Args)]
pub struct CompletionsArgs {
    /// The shell to complete for: bash, zsh, fish, elvish or powershell.
    shell: Shell,
}

/// Prints the completion script of `shell` to stdout.
pub fn run_completions(args: CompletionsArgs) -> anyhow::Result<()> {
    let mut command = super::Args::command();
    let mut out = std::io::stdout().lock();
    clap_complete::generate(args.shell, &mut command, "groombake", &mut out);
    out.flush()?;
    Ok(())
}

/// Prints the man page (roff, section 1) to stdout.
pub fn run_man() -> anyhow::Result<()> {
    let man = clap_mangen::Man::new(super::Args::command());
    let mut out = std::io::stdout().lock();
    man.render(&mut out)?;
    out.flush()?;
    Ok(())
}
