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
    /// A job file or option is wrong.
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
