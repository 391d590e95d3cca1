//! Atomic file creation: write into a temporary file next to the target, then rename.
//!
//! Guarantees: the target path either keeps its old content (or stays absent) or
//! holds the complete new content; a failure at any point (the writer returns an
//! error, the disk fills up, the rename is refused) removes the temporary file.
//! A target that exists and is neither a regular file nor a directory (a device
//! such as `/dev/null`, a FIFO, `/dev/stdout`) is written in place: a rename
//! would replace the device node by a regular file (as root, `/dev/null`
//! itself), and no rename is atomic for a stream anyway.
//!
//! Every live temporary file is also listed in a process-global registry, so
//! a signal handler (the binary's, on SIGINT / SIGTERM) can remove them with
//! [`remove_temporaries`] before the process exits: after that call no
//! temporary file is created and none is renamed into place.

use crate::{Error, Result};
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard, PoisonError};

/// Temporary files of this process not yet renamed or removed; `None` once
/// [`remove_temporaries`] has run (the process is ending).
static LIVE: Mutex<Option<Vec<PathBuf>>> = Mutex::new(Some(Vec::new()));

fn live() -> MutexGuard<'static, Option<Vec<PathBuf>>> {
    LIVE.lock().unwrap_or_else(PoisonError::into_inner)
}

fn ending() -> io::Error {
    io::Error::new(
        io::ErrorKind::Interrupted,
        "the process is ending (interrupted)",
    )
}

/// A temporary file listed in [`LIVE`] while this lives.
struct Registered(PathBuf);

impl Registered {
    fn new(path: &Path) -> io::Result<Registered> {
        match live().as_mut() {
            Some(list) => {
                list.push(path.to_path_buf());
                Ok(Registered(path.to_path_buf()))
            }
            None => Err(ending()),
        }
    }
}

impl Drop for Registered {
    fn drop(&mut self) {
        if let Some(list) = live().as_mut() {
            list.retain(|p| p != &self.0);
        }
    }
}

/// Remove every temporary file this process is writing, and refuse to create
/// or rename any from now on: for a signal handler, just before the process
/// exits. Returns how many files were removed.
pub fn remove_temporaries() -> usize {
    let mut live = live();
    let list = live.take().unwrap_or_default();
    list.iter()
        .filter(|p| std::fs::remove_file(p).is_ok())
        .count()
}

/// Buffer size of the writers: large enough that a million-triangle mesh is a
/// few thousand system calls.
const BUFFER_BYTES: usize = 1 << 20;

/// The directory a file at `path` is created in (`.` for a bare file name).
fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// A temporary file in `dir`, named after `path` so a leftover (after a crash) is recognisable.
fn temp_in(dir: &Path, path: &Path) -> io::Result<tempfile::NamedTempFile> {
    let stem = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    // ".out.msh.tmpXXXXXX": hidden, and matched by the repository's `*.msh.tmp*` ignore rule.
    let prefix = format!(".{stem}.tmp");
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix);
    #[cfg(unix)]
    {
        // NamedTempFile defaults to 0o600; a finished output file should get the
        // usual permissions (0o666 restricted by the umask), like `File::create`.
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    builder.tempfile_in(dir)
}

/// Fail early, with a message a user can act on, when no file can be created at `path`.
fn check_target(path: &Path) -> io::Result<PathBuf> {
    let dir = parent_dir(path);
    match std::fs::metadata(&dir) {
        Err(e) if e.kind() == io::ErrorKind::NotFound => {
            return Err(io::Error::new(
                io::ErrorKind::NotFound,
                format!("directory {} does not exist", dir.display()),
            ));
        }
        Err(e) => {
            return Err(io::Error::new(
                e.kind(),
                format!("cannot access directory {}: {e}", dir.display()),
            ));
        }
        Ok(m) if !m.is_dir() => {
            return Err(io::Error::new(
                io::ErrorKind::NotADirectory,
                format!("{} is not a directory", dir.display()),
            ));
        }
        Ok(_) => {}
    }
    if path.is_dir() {
        return Err(io::Error::new(
            io::ErrorKind::IsADirectory,
            format!("{} is a directory", path.display()),
        ));
    }
    Ok(dir)
}

/// Whether `path` exists and is neither a regular file nor a directory (a
/// device, a FIFO, a socket; symbolic links followed): written in place.
fn is_special(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

/// Check that a file can be created at `path`: creates and removes a temporary
/// file in its directory (a device or FIFO is not checked: it is written in
/// place, and opening a FIFO would wait for a reader).
pub(crate) fn check_writable(path: &Path) -> Result<()> {
    if is_special(path) {
        return Ok(());
    }
    let dir = check_target(path).map_err(Error::Write)?;
    let tmp = temp_in(&dir, path).map_err(|e| {
        Error::Write(io::Error::new(
            e.kind(),
            format!("directory {} is not writable: {e}", dir.display()),
        ))
    })?;
    let _listed = Registered::new(tmp.path()).map_err(Error::Write)?;
    tmp.close().map_err(Error::Write)
}

/// Create `path` with the bytes `write` produces, atomically.
///
/// `write` gets a buffered writer on a temporary file in the target directory; the
/// file is flushed, synced and renamed onto `path` only if `write` succeeds.
pub(crate) fn write_atomic<F>(path: &Path, write: F) -> Result<()>
where
    F: FnOnce(&mut BufWriter<&mut File>) -> io::Result<()>,
{
    if is_special(path) {
        let mut file = std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .map_err(Error::Write)?;
        let mut w = BufWriter::with_capacity(BUFFER_BYTES, &mut file);
        write(&mut w).map_err(Error::Write)?;
        return w.flush().map_err(Error::Write);
    }
    let dir = check_target(path).map_err(Error::Write)?;
    let mut tmp = temp_in(&dir, path).map_err(|e| {
        Error::Write(io::Error::new(
            e.kind(),
            format!("cannot create a file in {}: {e}", dir.display()),
        ))
    })?;
    let _listed = Registered::new(tmp.path()).map_err(Error::Write)?;
    {
        let mut w = BufWriter::with_capacity(BUFFER_BYTES, tmp.as_file_mut());
        write(&mut w).map_err(Error::Write)?;
        w.flush().map_err(Error::Write)?;
    }
    #[cfg(feature = "test-hooks")]
    slow_write_hook(path);
    tmp.as_file().sync_all().map_err(Error::Write)?;
    // Renamed under the registry's lock: a signal handler's cleanup runs
    // wholly before (the complete file is in place) or after (no rename).
    let live = live();
    if live.is_none() {
        return Err(Error::Write(ending()));
    }
    tmp.persist(path).map_err(|e| Error::Write(e.error))?;
    drop(live);
    Ok(())
}

/// Test-only (`test-hooks`): with `TRIWILD_TEST_SLOW_WRITE_ON=S`, a write
/// whose target path contains S sleeps for a minute with its temporary file
/// complete but not yet renamed, so a test can signal the process then.
#[cfg(feature = "test-hooks")]
fn slow_write_hook(path: &Path) {
    let hit = std::env::var("TRIWILD_TEST_SLOW_WRITE_ON")
        .ok()
        .is_some_and(|s| !s.is_empty() && path.to_string_lossy().contains(&s));
    if hit {
        std::thread::sleep(std::time::Duration::from_secs(60));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("target/tmp/unit-atomic")
            .join(name);
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).expect("create scratch dir");
        d
    }

    fn entries(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .expect("read dir")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    /// A FIFO (like `/dev/null` or `/dev/stdout`: not a regular file) is
    /// written in place and stays a FIFO; renaming a temporary file onto it
    /// would replace it (as root, `-o /dev/null` replaced the device node).
    #[cfg(unix)]
    #[test]
    fn a_fifo_is_written_in_place_and_never_replaced() {
        use std::io::Read;
        use std::os::unix::fs::FileTypeExt;
        let d = scratch("fifo");
        let p = d.join("out.msh");
        let made = std::process::Command::new("mkfifo").arg(&p).status();
        if !made.is_ok_and(|s| s.success()) {
            return; // no mkfifo here: nothing to test
        }
        let reader = {
            let p = p.clone();
            std::thread::spawn(move || {
                let mut got = Vec::new();
                File::open(&p)
                    .expect("open the fifo")
                    .read_to_end(&mut got)
                    .expect("read");
                got
            })
        };
        write_atomic(&p, |w| w.write_all(b"mesh bytes")).expect("write into the fifo");
        // (checked before joining: a replaced fifo would leave the reader waiting)
        let kind = std::fs::symlink_metadata(&p)
            .expect("still there")
            .file_type();
        assert!(kind.is_fifo(), "the fifo was replaced: {kind:?}");
        assert_eq!(reader.join().expect("reader"), b"mesh bytes");
        assert_eq!(entries(&d), vec!["out.msh".to_owned()]);
        check_writable(&p).expect("a fifo counts as writable");
    }

    #[test]
    fn failure_midway_keeps_old_file_and_leaves_no_temp() {
        let d = scratch("midway");
        let p = d.join("out.msh");
        std::fs::write(&p, b"old content").expect("seed file");
        let err = write_atomic(&p, |w| {
            w.write_all(&vec![b'x'; 3 * BUFFER_BYTES])?;
            Err(io::Error::other("disk on fire"))
        })
        .expect_err("the writer failed");
        assert!(matches!(err, Error::Write(_)));
        assert_eq!(std::fs::read(&p).expect("read"), b"old content");
        assert_eq!(entries(&d), vec!["out.msh".to_owned()]);
    }

    #[test]
    fn success_replaces_file() {
        let d = scratch("success");
        let p = d.join("out.msh");
        std::fs::write(&p, b"old").expect("seed file");
        write_atomic(&p, |w| w.write_all(b"new")).expect("write");
        assert_eq!(std::fs::read(&p).expect("read"), b"new");
        assert_eq!(entries(&d), vec!["out.msh".to_owned()]);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&p).expect("meta").permissions().mode();
            assert_eq!(mode & 0o600, 0o600);
        }
    }

    #[test]
    fn check_writable_messages() {
        let d = scratch("check");
        let missing = d.join("nope/out.msh");
        let e = check_writable(&missing).expect_err("missing dir");
        assert!(e.to_string().contains("does not exist"), "{e}");
        assert!(!d.join("nope").exists());
        let e = check_writable(&d).expect_err("a directory");
        assert!(e.to_string().contains("is a directory"), "{e}");
        std::fs::write(d.join("file"), b"").expect("seed");
        let e = check_writable(&d.join("file/out.msh")).expect_err("parent is a file");
        assert!(e.to_string().contains("not a directory"), "{e}");
        check_writable(&d.join("ok.msh")).expect("writable");
        assert_eq!(entries(&d), vec!["file".to_owned()]);
    }
}
