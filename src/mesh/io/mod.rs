//! Mesh file input (STL, OBJ, glTF/GLB) and mesh/preview output (OBJ, GLB).
//!
//! Reading gives a [`RawMesh`]: the triangles exactly as indexed in the file (STL: three new
//! vertices per facet; OBJ and glTF: the file's own indexing), scaled to millimetres, plus
//! warnings about what was skipped. Nothing is welded, oriented or cleaned here: that is the
//! next stage's job. Every loader checks what it must so that later stages can index safely:
//! all coordinates are finite, every index is in range and there is at least one triangle.
//!
//! Any byte string gives `Ok` or `Err`, never a panic, and no allocation is sized from a
//! header before that header has been checked against the input length.
//!
//! Writing is deterministic (same input ⇒ same bytes): [`write_obj`] for meshes that other
//! tools should read back exactly, [`write_stl`] for those that only take STL, [`GlbBuilder`] for previews (triangles with colours, and
//! line sets such as toolpaths) that any glTF viewer can open.

use std::fmt;
use std::path::Path;
use std::str::FromStr;

use crate::mesh::Mesh;

mod glb_writer;
mod gltf;
mod obj;
mod obj_writer;
mod stl;
mod stl_writer;

#[cfg(test)]
mod tests;

pub use glb_writer::{GlbBuilder, GlbError};
pub use obj_writer::write_obj;
pub use stl_writer::write_stl;

/// A mesh file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Format {
    /// STL, binary or ASCII.
    Stl,
    /// Wavefront OBJ (geometry only; materials are ignored).
    Obj,
    /// glTF 2.0 JSON, with buffers embedded as data URIs or in external files.
    Gltf,
    /// glTF 2.0 binary container.
    Glb,
}

impl Format {
    /// The format named by a path's extension (case-insensitive): `.stl`, `.obj`, `.gltf`, `.glb`.
    pub fn from_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "stl" => Some(Format::Stl),
            "obj" => Some(Format::Obj),
            "gltf" => Some(Format::Gltf),
            "glb" => Some(Format::Glb),
            _ => None,
        }
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Format::Stl => "STL",
            Format::Obj => "OBJ",
            Format::Gltf => "glTF",
            Format::Glb => "GLB",
        })
    }
}

/// The length unit of a mesh file. No format used here records its unit reliably (glTF says
/// metres, but exporters ignore that), so the caller says what the file uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Units {
    #[default]
    Millimetres,
    Metres,
    Inches,
}

impl Units {
    /// Millimetres per file unit: 1, 1000 or 25.4.
    pub fn scale_to_mm(self) -> f64 {
        match self {
            Units::Millimetres => 1.0,
            Units::Metres => 1000.0,
            Units::Inches => 25.4,
        }
    }
}

/// A unit name that [`Units::from_str`] did not recognise.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown length unit {0:?} (expected mm, m or in)")]
pub struct UnitsParseError(pub String);

impl FromStr for Units {
    type Err = UnitsParseError;

    /// `mm`, `m`, `in` (case-insensitive); the long names (`millimetres`, `meters`, `inch`, …)
    /// are accepted too.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "mm" | "millimetre" | "millimetres" | "millimeter" | "millimeters" => {
                Ok(Units::Millimetres)
            }
            "m" | "metre" | "metres" | "meter" | "meters" => Ok(Units::Metres),
            "in" | "inch" | "inches" | "\"" => Ok(Units::Inches),
            _ => Err(UnitsParseError(s.to_owned())),
        }
    }
}

impl fmt::Display for Units {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Units::Millimetres => "mm",
            Units::Metres => "m",
            Units::Inches => "in",
        })
    }
}

/// A mesh as read, before welding: the triangles as indexed in the file (STL: three vertices
/// per facet), positions in mm, plus warnings about what was skipped or repaired.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RawMesh {
    pub mesh: Mesh,
    pub warnings: Vec<String>,
}

/// Why a mesh file could not be read. Every message starts with the file name.
#[derive(Debug, thiserror::Error)]
pub enum MeshIoError {
    /// The file (or a file it refers to) could not be read.
    #[error("{name}: cannot read {path}: {source}")]
    Io {
        name: String,
        path: String,
        #[source]
        source: std::io::Error,
    },
    /// The extension is not one of `.stl`, `.obj`, `.gltf`, `.glb`.
    #[error("{name}: unknown mesh format (expected a .stl, .obj, .gltf or .glb file)")]
    UnknownFormat { name: String },
    /// A syntax error at a known line of a text file.
    #[error("{name}: line {line}: {message}")]
    Syntax {
        name: String,
        line: usize,
        message: String,
    },
    /// The file is not a valid file of its format.
    #[error("{name}: invalid {format} file: {message}")]
    Invalid {
        name: String,
        format: Format,
        message: String,
    },
    /// A vertex coordinate is NaN, infinite or beyond [`MAX_COORDINATE_MM`](crate::mesh::MAX_COORDINATE_MM)
    /// (after transforms and unit scaling).
    #[error(
        "{name}: vertex {vertex} ({location}) has a coordinate that is not a finite length within \
         ±{} mm: {value:?}",
        crate::mesh::MAX_COORDINATE_MM
    )]
    NonFinite {
        name: String,
        /// Index into [`RawMesh::mesh`]`.positions` that the vertex would have had.
        vertex: usize,
        location: String,
        value: [f64; 3],
    },
    /// A face refers to a vertex that does not exist.
    #[error(
        "{name}: face {face} ({location}) refers to vertex index {index}, \
         but there are only {vertex_count} vertices"
    )]
    IndexOutOfRange {
        name: String,
        face: usize,
        location: String,
        index: i64,
        vertex_count: usize,
    },
    /// A buffer that the glTF file refers to is missing or unreadable.
    #[error("{name}: buffer {buffer} ({uri}): {message}")]
    Buffer {
        name: String,
        buffer: usize,
        uri: String,
        message: String,
    },
    /// The file describes more geometry than the loader is willing to build from it.
    #[error("{name}: too large: {message}")]
    TooLarge { name: String, message: String },
    /// The file is valid but contains no triangles.
    #[error("{name}: no triangles{detail}")]
    Empty { name: String, detail: String },
}

/// Reads a mesh file; the format comes from the extension, external glTF buffers are looked
/// up next to the file, and positions are multiplied by `units.scale_to_mm()`.
pub fn read_mesh(path: &Path, units: Units) -> Result<RawMesh, MeshIoError> {
    let name = path.display().to_string();
    let format =
        Format::from_path(path).ok_or_else(|| MeshIoError::UnknownFormat { name: name.clone() })?;
    let bytes = std::fs::read(path).map_err(|source| MeshIoError::Io {
        name: name.clone(),
        path: name.clone(),
        source,
    })?;
    read_mesh_bytes(&bytes, format, &name, path.parent(), units)
}

/// Reads a mesh from memory. `name` is only used in messages; `base_dir` is where external
/// glTF buffers are looked up (`None`: external buffers are an error).
pub fn read_mesh_bytes(
    bytes: &[u8],
    format: Format,
    name: &str,
    base_dir: Option<&Path>,
    units: Units,
) -> Result<RawMesh, MeshIoError> {
    let scale = units.scale_to_mm();
    let raw = match format {
        Format::Stl => stl::read_stl(bytes, name, scale)?,
        Format::Obj => obj::read_obj(bytes, name, scale)?,
        // One reader for both: it tells JSON from binary by the magic bytes, so a misnamed
        // file still loads.
        Format::Gltf | Format::Glb => self::gltf::read_gltf(bytes, name, base_dir, scale)?,
    };
    if raw.mesh.triangles.is_empty() {
        let detail = if raw.warnings.is_empty() {
            String::new()
        } else {
            format!(" ({})", raw.warnings.join("; "))
        };
        return Err(MeshIoError::Empty {
            name: name.to_owned(),
            detail,
        });
    }
    debug_assert!(raw.mesh.check_indices_and_coordinates().is_ok());
    Ok(raw)
}

/// Converts a point to millimetres and checks it is a usable coordinate (finite, within
/// [`MAX_COORDINATE_MM`](crate::mesh::MAX_COORDINATE_MM)). `vertex` and `location` only feed
/// the error.
fn scaled_point(
    p: [f64; 3],
    scale: f64,
    name: &str,
    vertex: usize,
    location: impl FnOnce() -> String,
) -> Result<nalgebra::Point3<f64>, MeshIoError> {
    let q = [p[0] * scale, p[1] * scale, p[2] * scale];
    if q.iter().all(|c| c.abs() <= crate::mesh::MAX_COORDINATE_MM) {
        Ok(nalgebra::Point3::new(q[0], q[1], q[2]))
    } else {
        Err(MeshIoError::NonFinite {
            name: name.to_owned(),
            vertex,
            location: location(),
            value: q,
        })
    }
}

/// Shortens text taken from a file for an error message.
fn excerpt(bytes: &[u8]) -> String {
    const MAX: usize = 40;
    let s = String::from_utf8_lossy(&bytes[..bytes.len().min(MAX)]).into_owned();
    if bytes.len() > MAX {
        format!("{s}…")
    } else {
        s
    }
}
