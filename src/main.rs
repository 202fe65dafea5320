//! The `dcnet-exp` binary: parses the arguments, runs the command, and maps the outcome
//! to an exit code (0 done, 1 bad spec, data or arguments, 2 failure while running).

use std::process::ExitCode;

fn main() -> ExitCode {
    match dcnet_exp::cli::main() {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            // A spec can have several faults, one per line: each gets its own prefix.
            for line in format!("{:#}", error.cause()).lines() {
                eprintln!("error: {line}");
            }
            ExitCode::from(error.exit_code())
        }
    }
}
