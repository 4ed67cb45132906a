//! `groombake completions SHELL` and `groombake man [DIR]`: shell completion
//! scripts (clap_complete) and roff man pages (clap_mangen), one for the
//! tool and one per command, all made from the same clap definition as the
//! parser, so they never fall behind it.

use super::BadInput;
use clap::{Args, CommandFactory};
use clap_complete::Shell;
use std::io::Write;
use std::path::PathBuf;

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

#[derive(Debug, Args)]
pub struct ManArgs {
    /// A folder to write every page to (created if missing): groombake.1
    /// and groombake-COMMAND.1 for each command. Without it the tool's page
    /// is printed to stdout.
    dir: Option<PathBuf>,
}

/// Prints the tool's man page (roff, section 1) to stdout, or writes every
/// page to `args.dir`.
pub fn run_man(args: ManArgs) -> anyhow::Result<()> {
    let Some(dir) = args.dir else {
        let man = clap_mangen::Man::new(super::Args::command());
        let mut out = std::io::stdout().lock();
        man.render(&mut out)?;
        out.flush()?;
        return Ok(());
    };
    let refuse =
        |what: &str, e: std::io::Error| BadInput(format!("{}: {what}: {e}", dir.display()));
    if dir.exists() && !dir.is_dir() {
        return Err(BadInput(format!("{}: not a folder", dir.display())).into());
    }
    std::fs::create_dir_all(&dir).map_err(|e| refuse("cannot create the folder", e))?;
    // Pages are written into a fresh folder beside them and moved in only
    // when all are written: a failure leaves no half set.
    let staging = dir.join(format!(".groombake-man-{}", std::process::id()));
    let written = std::fs::create_dir(&staging)
        .and_then(|()| clap_mangen::generate_to(super::Args::command(), &staging))
        .and_then(|()| {
            let mut pages: Vec<PathBuf> = std::fs::read_dir(&staging)?
                .map(|entry| entry.map(|e| e.path()))
                .collect::<Result<_, _>>()?;
            pages.sort();
            for page in &pages {
                if let Some(name) = page.file_name() {
                    std::fs::rename(page, dir.join(name))?;
                }
            }
            Ok(pages.len())
        });
    let _ = std::fs::remove_dir_all(&staging);
    let count = written.map_err(|e| refuse("cannot write the man pages", e))?;
    eprintln!("wrote {count} man pages to {}", dir.display());
    Ok(())
}
