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
}

impl Error {
    /// Exit code for the command-line tool: 1 for bad input or I/O, 3 when the planned path
    /// failed verification (2 is clap's usage error).
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Verification(_) => 3,
            _ => 1,
        }
    }
}

pub type Result<T> = std::result::Result<T, Error>;
