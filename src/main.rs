//! The `dcnet-exp` binary: parses the arguments, runs the command, and maps the outcome
//! to an exit code (0 done, 1 bad spec, data or arguments, 2 failure while running).

use std::process::ExitCode;

#[global_allocator]
static ALLOCATOR: dcnet_exp::memory::CountingAllocator = dcnet_exp::memory::CountingAllocator;

/// Run before anything allocates (a constructor, before `main`): under `ulimit -v`,
/// the allocator's first allocation must not reserve a gigabyte of address space ahead.
#[cfg(target_os = "linux")]
#[used]
#[unsafe(link_section = ".init_array")]
static BEFORE_THE_FIRST_ALLOCATION: extern "C" fn() =
    dcnet_exp::memory::reserve_no_arena_under_an_address_limit;

fn main() -> ExitCode {
    // Output piped into a reader that stops early (`plan … | head`) ends the process
    // quietly, as it ends any Unix tool, rather than panicking at the next line.
    // A file-size limit (`ulimit -f`) makes the write that passes it fail, named with
    // its file and exit 2, rather than killing the process with SIGXFSZ.
    // SAFETY: restoring the default action of a signal, and ignoring another, before
    // any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
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
