//! The `triwild` command line: the whole of it lives in the library's hidden
//! `cli` module (so the Python package can run it in-process); this binary only
//! hands it the process's arguments, and owns the process's signals.

use std::process::ExitCode;

/// SIGINT and SIGTERM: remove the temporary output files and exit 128 + the
/// signal (130, 143); in `triwild batch`, stop the children, write their rows
/// as interrupted and let the batch finish (a second signal exits at once).
fn install_signal_handlers(batch: bool) {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]) else {
        return;
    };
    std::thread::spawn(move || {
        let mut first: Option<std::time::Instant> = None;
        for sig in signals.forever() {
            if batch {
                // The same signal often comes twice at once (to the process
                // and to its group, as `timeout` and a terminal send it):
                // only a repeat after a grace period ends the batch at once.
                match first {
                    None => {
                        first = Some(std::time::Instant::now());
                        triwild::batch::interrupt(sig);
                        continue;
                    }
                    Some(t) if t.elapsed() < SIGNAL_GRACE => continue,
                    Some(_) => {}
                }
            }
            triwild::remove_temporaries();
            std::process::exit(128 + sig);
        }
    });
}

/// A second SIGINT / SIGTERM this long after the first ends a batch at once.
const SIGNAL_GRACE: std::time::Duration = std::time::Duration::from_secs(2);

fn main() -> ExitCode {
    // The batch is the only command with a subcommand word, always first.
    let batch = std::env::args_os().nth(1).is_some_and(|a| a == "batch");
    install_signal_handlers(batch);
    ExitCode::from(triwild::cli::main_with(std::env::args_os(), None))
}
