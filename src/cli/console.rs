//! Lines for the user on stdout and stderr, where either may be a pipe that
//! closes early (`triwild batch DIR -o OUT | head`).
//!
//! `println!` panics on a closed stdout ("failed printing to stdout: Broken
//! pipe"). Here a closed stdout ends the process quietly with exit code 141,
//! what a shell reports for `cat` killed by SIGPIPE (128 + 13): everything
//! written before (meshes, reports) is complete, since output files are
//! renamed into place before anything is printed about them. A closed stderr
//! loses the message and nothing else: there is nobody left to tell.

use std::fmt::Arguments;
use std::io::Write;

/// Exit code when stdout closed under us (128 + SIGPIPE, as a shell reports `cat`).
pub(crate) const BROKEN_PIPE: i32 = 141;

/// One line on stdout; a closed pipe ends the process with [`BROKEN_PIPE`].
pub(crate) fn out(args: Arguments<'_>) {
    let mut stdout = std::io::stdout().lock();
    let written = stdout
        .write_fmt(args)
        .and_then(|()| stdout.write_all(b"\n"))
        .and_then(|()| stdout.flush());
    match written {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => std::process::exit(BROKEN_PIPE),
        Err(e) => {
            err(format_args!("error: cannot write to standard output: {e}"));
            std::process::exit(1);
        }
    }
}

/// One line on stderr; lost if stderr is closed.
pub(crate) fn err(args: Arguments<'_>) {
    let mut stderr = std::io::stderr().lock();
    let _ = stderr
        .write_fmt(args)
        .and_then(|()| stderr.write_all(b"\n"));
}

/// `println!` for the binary: see [`out`].
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::cli::console::out(format_args!($($arg)*))
    };
}

/// `eprintln!` for the binary: see [`err`].
macro_rules! errln {
    ($($arg:tt)*) => {
        $crate::cli::console::err(format_args!($($arg)*))
    };
}

pub(crate) use {errln, outln};
