//! `groombake`: parse the command line, run one command, map the outcome to
//! an exit code (0 ok, 1 failure during work, 2 bad input or usage).

mod cli;

use std::process::ExitCode;

fn main() -> ExitCode {
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
