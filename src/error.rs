//! The library's error type: every variant says which file or setting is at fault.

use crate::access::VisibilityError;
use crate::collide::ColliderError;
use crate::contour::{ContourError, OutlineError};
use crate::mesh::io::{GlbError, MeshIoError};
use crate::multires::{RemeshError, WaveletError};
use crate::offset::OffsetError;
use crate::post::{ContourPostError, KinematicsError, LineariseError};
use crate::tool::ToolError;
use crate::tool_choice::ToolChoiceError;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    MeshIo(#[from] MeshIoError),
    /// The part (a mesh or an outline) was read but cannot be used as it is.
    #[error("{file}: {reason}")]
    Mesh { file: String, reason: String },
    /// An IGES file is malformed; the error names the line.
    #[error("{file}: {error}")]
    Iges {
        file: String,
        #[source]
        error: crate::cad::iges::IgesError,
    },
    /// A CAD face could not be tessellated; the error names the face.
    #[error("{file}: tessellating {error}")]
    Tessellate {
        file: String,
        #[source]
        error: crate::cad::tessellate::TessellateError,
    },
    /// A job file or option is wrong, naming the key, operation or file.
    #[error(transparent)]
    JobFile(#[from] JobError),
    /// A data file other than a part or a job (query points, …) is malformed at `line`.
    #[error("{file}: line {line}: {reason}")]
    DataFile {
        file: String,
        line: usize,
        reason: String,
    },
    /// A tool spec or tool library is wrong.
    #[error(transparent)]
    Tool(#[from] ToolError),
    /// The part could not be remeshed into a subdivision hierarchy.
    #[error("remeshing: {0}")]
    Remesh(#[from] RemeshError),
    /// The wavelet analysis of the hierarchy failed.
    #[error("wavelets: {0}")]
    Wavelets(#[from] WaveletError),
    /// An offset shape could not be built; `what` says which.
    #[error("{what}: {error}")]
    Offset {
        what: String,
        #[source]
        error: OffsetError,
    },
    /// A surface could not be made into a collision model; `what` says which.
    #[error("{what}: {error}")]
    Collider {
        what: String,
        #[source]
        error: ColliderError,
    },
    /// Visibility maps could not be computed.
    #[error("visibility: {0}")]
    Visibility(#[from] VisibilityError),
    /// Tool choice refused its input.
    #[error("tool choice: {0}")]
    ToolChoice(#[from] ToolChoiceError),
    /// A GLB picture could not be built; `file` names it.
    #[error("{file}: {error}")]
    Glb {
        file: String,
        #[source]
        error: GlbError,
    },
    /// The worker threads could not be started.
    #[error("worker threads: {0}")]
    Threads(#[from] rayon::ThreadPoolBuildError),
    /// A broken internal invariant: a bug, not bad input.
    #[error("internal error (please report): {0}")]
    Internal(String),
    /// An outline (SVG, DXF) cannot be read; the error names the file.
    #[error(transparent)]
    Outline(#[from] OutlineError),
    /// The 2.5D planner refused an input or failed, naming the file it was working on.
    #[error("{file}: {error}")]
    Contour {
        file: String,
        #[source]
        error: ContourError,
    },
    /// A 2.5D program cannot be posted, naming the file it was planned from.
    #[error("{file}: cannot post the program: {error}")]
    ContourPost {
        file: String,
        #[source]
        error: ContourPostError,
    },
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
    /// The work the input asks for is estimated above a limit the user can raise: `limit_key`
    /// names the option or job-file key that sets it (the CLI names its flag instead).
    #[error(
        "{what} needs about {estimate}, above the limit of {limit}; {advice}, or raise {limit_key}"
    )]
    TooLarge {
        what: String,
        estimate: String,
        limit: String,
        advice: String,
        limit_key: String,
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
