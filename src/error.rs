//! The library's one error type.
//!
//! Errors carry what went wrong, not which file: the caller (the CLI or the
//! batch runner) knows the paths and prefixes them (`error: <file>: <cause>`).

use std::io;

/// What kind of failure an [`Error`] is; the CLI maps each to an exit code.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ErrorKind {
    /// The input is unusable (exit code 2).
    BadInput,
    /// The input was fine but no valid mesh could be made (exit code 3).
    Meshing,
    /// Reading or writing a file failed (exit code 4).
    Io,
}

/// Everything that can go wrong in triwild.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The input file could not be read.
    #[error("cannot read input: {0}")]
    Read(#[source] io::Error),
    /// The input path is a directory.
    #[error("is a directory, not an SVG file")]
    IsDirectory,
    /// The input file is empty.
    #[error("empty file")]
    EmptyFile,
    /// The input is not an SVG document (binary data, HTML, broken XML, ...).
    #[error("not a valid SVG document: {0}")]
    NotSvg(String),
    /// The SVG parsed but holds nothing to mesh; the string says what was there
    /// instead (images, text without a font, ...), or is empty.
    #[error("no geometry: the drawing has no paths, shapes or points to mesh{0}")]
    NoGeometry(String),
    /// A coordinate is NaN, infinite, or outside the range the mesher represents.
    #[error("bad coordinate: {0}")]
    BadCoordinate(String),
    /// The input is not a gmsh mesh this library reads (`triwild check`).
    #[error("not a readable gmsh mesh: {0}")]
    BadMesh(String),
    /// A parameter is out of range.
    #[error("invalid parameter: {0}")]
    InvalidParams(String),
    /// The input exceeds a resource budget (`--max-segments`, `--max-shapes`,
    /// `--max-memory`); the string names the count, the limit and the flag.
    #[error("too large: {0}")]
    TooLarge(String),
    /// The wall-clock budget (`--time-limit`) ran out; nothing was written.
    #[error("time limit of {seconds} s reached in {stage}")]
    TimeLimit {
        /// The limit, seconds.
        seconds: f64,
        /// The stage that noticed.
        stage: crate::stage::Stage,
    },
    /// The process's memory reached a limit (`--max-memory`, or one set from
    /// outside: `ulimit -v`, a cgroup); nothing was written.
    #[error("memory limit of {limit_mb} MB reached in {stage} ({limit})")]
    MemoryLimit {
        /// The limit, MiB.
        limit_mb: u64,
        /// Which limit: `--max-memory`, the address-space limit or the
        /// cgroup's.
        limit: &'static str,
        /// The stage that noticed.
        stage: crate::stage::Stage,
    },
    /// An allocation failed: the system (or a limit set from outside the
    /// process) had no more memory to give; nothing was written.
    #[error("out of memory in {stage}: {} MB could not be allocated", bytes.div_ceil(1 << 20))]
    OutOfMemory {
        /// The size asked for, bytes.
        bytes: u64,
        /// The stage that asked.
        stage: crate::stage::Stage,
    },
    /// A meshing stage failed.
    #[error("meshing failed in stage {stage}: {message}")]
    Meshing {
        /// The pipeline stage.
        stage: crate::stage::Stage,
        /// What went wrong.
        message: String,
    },
    /// Writing an output file failed.
    #[error("cannot write output: {0}")]
    Write(#[source] io::Error),
}

impl Error {
    /// The class of this error, for exit codes and batch reports.
    pub fn kind(&self) -> ErrorKind {
        match self {
            // A path that names no file is a bad argument, not a failing disk.
            Error::Read(e) if e.kind() == io::ErrorKind::NotFound => ErrorKind::BadInput,
            Error::Read(_) | Error::Write(_) => ErrorKind::Io,
            Error::IsDirectory
            | Error::EmptyFile
            | Error::NotSvg(_)
            | Error::NoGeometry(_)
            | Error::BadCoordinate(_)
            | Error::BadMesh(_)
            | Error::InvalidParams(_)
            | Error::TooLarge(_) => ErrorKind::BadInput,
            Error::Meshing { .. }
            | Error::TimeLimit { .. }
            | Error::MemoryLimit { .. }
            | Error::OutOfMemory { .. } => ErrorKind::Meshing,
        }
    }

    /// The error of a run that overran its budget in `stage`.
    pub(crate) fn overrun(over: crate::budget::Overrun, stage: crate::stage::Stage) -> Self {
        use crate::budget::Overrun;
        match over {
            Overrun::Time { seconds } => Error::TimeLimit { seconds, stage },
            Overrun::Memory { limit_mb, source } => Error::MemoryLimit {
                limit_mb,
                limit: source.flag(),
                stage,
            },
            Overrun::Allocation { bytes } => Error::OutOfMemory { bytes, stage },
        }
    }

    /// A meshing error in `stage`.
    pub fn meshing(stage: crate::stage::Stage, message: impl Into<String>) -> Self {
        Error::Meshing {
            stage,
            message: message.into(),
        }
    }
}

/// A time-limit or memory-limit error in `stage` once `deadline` has passed
/// (see [`crate::budget::Deadline`]).
///
/// # Errors
/// [`Error::MemoryLimit`] past the memory limit, [`Error::TimeLimit`] past the
/// time limit.
pub(crate) fn check_deadline(
    deadline: &crate::budget::Deadline,
    stage: crate::stage::Stage,
) -> Result<()> {
    deadline.check().map_err(|o| Error::overrun(o, stage))
}

/// `Result` with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
