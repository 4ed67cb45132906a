//! `groombake`: parse the command line, run one command, map the outcome to
//! an exit code (0 ok, 1 failure during work, 2 bad input or usage).

mod cli;

use std::process::ExitCode;

fn main() -> ExitCode {
    // A file past the size limit (`ulimit -f`) fails its write with EFBIG,
    // as a full disk fails with ENOSPC, instead of killing the process by
    // SIGXFSZ: the error path then removes the temporaries, as a bake's,
    // a convert's or a batch's.
    // SAFETY: setting a signal's disposition to "ignore" before any thread
    // starts; no handler runs.
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
    }
    let args = match cli::parse() {
        Ok(args) => args,
        Err(code) => return code,
    };
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            if cli::is_broken_pipe(&error) {
                return ExitCode::SUCCESS;
            }
            eprintln!("groombake: {}", cli::message_of(&error));
            ExitCode::from(cli::exit_code_for(&error))
        }
    }
}
