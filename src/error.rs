//! The library's error type: every variant says which file or setting is at fault.

use crate::mesh::io::MeshIoError;
use crate::post::{KinematicsError, LineariseError};

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    MeshIo(#[from] MeshIoError),
    /// The mesh was read but cannot be used as it is.
    #[error("{file}: {reason}")]
    Mesh { file: String, reason: String },
    /// A job file or option is wrong, naming the key, operation or file.
    #[error(transparent)]
    JobFile(#[from] JobError),
    /// A job's input or options are wrong in a way no more specific variant covers.
    #[error("{0}")]
    Job(String),
    #[error("machine: {0}")]
    Kinematics(#[from] KinematicsError),
    #[error("post-processor: {0}")]
    Linearise(#[from] LineariseError),
    /// The planned path failed its own verification; only the report was written.
    #[error("verification failed: {0}")]
    Verification(String),
    #[error("{path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error("sample part: {0}")]
    Sample(#[from] crate::sample::SampleError),
    /// A value given on the command line (or to the library in its place) is out of range or
    /// malformed; nothing was read or written.
    #[error("{0}")]
    Usage(String),
    /// The input is valid but leaves nothing to machine (every point unreachable, a part too
    /// small for the tool, an outline with nothing between stock and part): no program is
    /// written, and the message says why.
    #[error("nothing to cut: {0}")]
    NothingToCut(String),
    /// The work the input asks for is estimated above a limit the user can raise.
    #[error("{what} needs about {estimate}, above the limit of {limit}; {how_to_raise}")]
    TooLarge {
        what: String,
        estimate: String,
        limit: String,
        how_to_raise: String,
    },
}

impl Error {
    /// Exit code for the command-line tool: 1 bad input, I/O or a limit, 2 a bad command-line
    /// value (as clap's usage errors), 3 the planned path failed verification, 4 nothing to
    /// cut.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Usage(_) => 2,
            Error::Verification(_) => 3,
            Error::NothingToCut(_) => 4,
            _ => 1,
        }
    }
}

pub type Result<T> = std::result::Result<T, Error>;

/// What is wrong with a job, naming the key, the operation or the file.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum JobError {
    /// A key's value is out of its range or malformed.
    #[error("{key} {reason}")]
    Invalid { key: String, reason: String },
    /// The `[tool]` is not a valid assembly.
    #[error("{0}")]
    Tool(String),
    /// One operation of the list breaks a rule; `index` counts from 1, as listed.
    #[error("operation {index} ({name}): {reason}")]
    Operation {
        index: usize,
        name: String,
        reason: String,
    },
    /// The list of operations as a whole breaks a rule.
    #[error("{0}")]
    Operations(String),
    /// The job file cannot be read or is not a job file (TOML syntax, unknown keys, types).
    #[error("{file}: {reason}")]
    File { file: String, reason: String },
    /// A job file whose content breaks a rule.
    #[error("{file}: {error}")]
    InFile {
        file: String,
        #[source]
        error: Box<JobError>,
    },
}

impl JobError {
    /// The job-file key the error is about, if it is about one (`tool` for the tool).
    pub fn key(&self) -> Option<&str> {
        match self {
            JobError::Invalid { key, .. } => Some(key),
            JobError::Tool(_) => Some("tool"),
            JobError::InFile { error, .. } => error.key(),
            _ => None,
        }
    }
}
