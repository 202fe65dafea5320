//! The `dcnet-exp` binary: parses the arguments, runs the command, and maps the outcome
//! to an exit code (0 done, 1 bad spec, data or arguments, 2 failure while running).

use std::process::ExitCode;

fn main() -> ExitCode {
    match dcnet_exp::cli::main() {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {:#}", error.cause());
            ExitCode::from(error.exit_code())
        }
    }
}
