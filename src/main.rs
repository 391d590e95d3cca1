//! The `triwild` command line: the whole of it lives in the library's hidden
//! `cli` module (so the Python package can run it in-process); this binary only
//! hands it the process's arguments.

use std::process::ExitCode;

fn main() -> ExitCode {
    ExitCode::from(triwild::cli::main_with(std::env::args_os(), None))
}
