//! The `dcnet-exp` binary: parses the arguments, runs the command, and maps the outcome
//! to an exit code (0 done, 1 bad spec, data or arguments, 2 failure while running).

use std::process::ExitCode;

#[global_allocator]
static ALLOCATOR: dcnet_exp::memory::CountingAllocator = dcnet_exp::memory::CountingAllocator;

fn main() -> ExitCode {
    // Output piped into a reader that stops early (`plan … | head`) ends the process
    // quietly, as it ends any Unix tool, rather than panicking at the next line.
    // SAFETY: restoring the default action of a signal, before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    dcnet_exp::memory::keep_freed_memory();
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
