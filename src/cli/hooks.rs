//! Test-only hooks (cargo feature `test-hooks`), so the batch tests can make a
//! child misbehave: each environment variable holds a substring of the input
//! path that triggers it. The shipped binary is built without them.

use std::path::Path;
use std::time::Duration;

/// The paragraph `triwild batch --help` adds when the hooks are built in.
pub(crate) const HELP: &str = "\
Test-only hooks (environment variables read by the single-file command; never
set them in production): TRIWILD_TEST_PANIC_ON=S panics, TRIWILD_TEST_SLEEP_ON=S
sleeps for an hour, TRIWILD_TEST_ALLOC_ON=S allocates until killed (up to
16 GiB), each when the input path contains S.";

/// Misbehave as the environment asks for `input`: panic
/// (`TRIWILD_TEST_PANIC_ON`), sleep for an hour (`TRIWILD_TEST_SLEEP_ON`) or
/// allocate up to 16 GiB (`TRIWILD_TEST_ALLOC_ON`).
pub(crate) fn trigger(input: &Path) {
    let name = input.to_string_lossy();
    let hit = |var: &str| {
        std::env::var(var)
            .ok()
            .is_some_and(|s| !s.is_empty() && name.contains(&s))
    };
    if hit("TRIWILD_TEST_PANIC_ON") {
        panic!("test hook TRIWILD_TEST_PANIC_ON matched {name}");
    }
    if hit("TRIWILD_TEST_SLEEP_ON") {
        std::thread::sleep(Duration::from_secs(3600));
    }
    if hit("TRIWILD_TEST_ALLOC_ON") {
        let mut hog: Vec<Vec<u8>> = Vec::new();
        for _ in 0..1024 {
            hog.push(vec![1u8; 16 << 20]);
            std::thread::sleep(Duration::from_millis(10));
        }
        std::thread::sleep(Duration::from_secs(3600));
        drop(hog);
    }
}
