//! Base mesh for semi-regular remeshing (DESIGN.md §3.2, step 1): topology-preserving
//! quadric-error edge collapse that keeps boundaries, creases and genus.
//!
//! The algorithm is Garland & Heckbert's, *Surface Simplification Using Quadric Error
//! Metrics*, SIGGRAPH 1997: every vertex carries the area-weighted sum of the squared-distance
//! quadrics of its triangles' planes; edges are collapsed cheapest first; the merged vertex
//! carries the sum of the two quadrics. Additions for a subdivision base mesh:
//!
//! * **Features.** Boundary edges and crease edges (dihedral angle above
//!   [`SimplifyOptions::crease_angle_deg`]) are *sharp*. Each adds heavily weighted planes
//!   through the edge, perpendicular to its faces (G&H §6.1), to both endpoints. Vertices are
//!   classified as in the multires conventions: smooth (no sharp edge), crease (two), corner
//!   (one, or three or more). A crease vertex collapses only along one of its sharp edges,
//!   a corner never moves, and a feature vertex always keeps its original position, so
//!   feature lines of the result run through input vertices.
//! * **Topology.** An edge collapses only if its endpoints' common neighbours are exactly its
//!   opposite vertices (the link condition), it does not merge two sharp edges into one, and a
//!   closed component keeps at least 4 triangles. Genus, components and boundary loops are
//!   therefore kept.
//! * **Geometry.** A collapse is rejected if a surviving triangle's normal turns by more than
//!   [`SimplifyOptions::max_normal_turn_deg`] or a triangle falls below
//!   [`SimplifyOptions::min_triangle_quality`] (unless it was already that bad); the next
//!   cheapest placement is tried then.
//! * **Placement** of a smooth edge's vertex: the quadric optimum, solved in the eigenbasis of
//!   the quadric with ill-conditioned directions dropped (they stay at the edge midpoint), if
//!   it lies within one edge length of the midpoint; otherwise, or if it is rejected, the best
//!   valid one of the endpoints and the midpoint.
//! * **Determinism.** A binary heap keyed by (error, lower index, higher index) with lazy
//!   deletion through per-vertex version counters; the output is bit-identical run to run.
//!
//! ```
//! use nalgebra::Point3;
//! use wavemill::mesh::Mesh;
//! use wavemill::multires::{SimplifyOptions, simplify};
//!
//! // A flat square fan of four triangles around a centre vertex.
//! let mesh = Mesh {
//!     positions: vec![
//!         Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 0.0, 0.0), Point3::new(1.0, 1.0, 0.0),
//!         Point3::new(0.0, 1.0, 0.0), Point3::new(0.5, 0.5, 0.0),
//!     ],
//!     triangles: vec![[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]],
//! };
//! let out = simplify(&mesh, &SimplifyOptions::with_target(2)).unwrap();
//! assert_eq!(out.mesh.triangles.len(), 2);
//! assert_eq!(out.mesh.positions.len(), 4);
//! ```

mod collapse;
mod features;
mod quadric;
mod topology;

#[cfg(test)]
pub(crate) mod test_support;
#[cfg(test)]
mod tests;

use nalgebra::{Point3, Vector3};
use thiserror::Error;

use crate::mesh::Mesh;
use crate::multires::Creases;

/// Options of [`simplify`]. Build with [`SimplifyOptions::with_target`] and the `with_*`
/// setters; every field has a documented default.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimplifyOptions {
    /// Stop when the mesh has at most this many triangles (default 1000). The result may have
    /// more if no further collapse is valid or `max_error` stops it first.
    pub target_triangles: usize,
    /// Interior edges whose dihedral angle (between the two face normals) exceeds this, in
    /// degrees, are creases and are kept (default 40).
    pub crease_angle_deg: f64,
    /// Stop when the cheapest remaining collapse's error exceeds this many millimetres
    /// (default `None`: no limit). The error is the square root of the merged quadric's value
    /// divided by its area, i.e. an area-weighted RMS distance to the original triangle planes;
    /// deviation from features is weighted much more heavily.
    pub max_error: Option<f64>,
    /// Reject collapses that create a triangle of quality below this, unless the triangle
    /// was already worse (default 0.1; roughly a 5° smallest angle). Quality is
    /// `4√3·area / Σ edge²`: 1 for equilateral, 0 for degenerate. Range `[0, 1]`.
    pub min_triangle_quality: f64,
    /// Reject collapses that turn a surviving triangle's normal by more than this many degrees
    /// (default 90: no face may flip). Range `(0, 180]`.
    pub max_normal_turn_deg: f64,
}

impl Default for SimplifyOptions {
    fn default() -> Self {
        Self {
            target_triangles: 1000,
            crease_angle_deg: 40.0,
            max_error: None,
            min_triangle_quality: 0.1,
            max_normal_turn_deg: 90.0,
        }
    }
}

impl SimplifyOptions {
    /// Default options with the given triangle target.
    pub fn with_target(target_triangles: usize) -> Self {
        Self {
            target_triangles,
            ..Self::default()
        }
    }

    /// Sets [`Self::crease_angle_deg`].
    pub fn with_crease_angle_deg(self, crease_angle_deg: f64) -> Self {
        Self {
            crease_angle_deg,
            ..self
        }
    }

    /// Sets [`Self::max_error`].
    pub fn with_max_error(self, max_error: Option<f64>) -> Self {
        Self { max_error, ..self }
    }

    /// Sets [`Self::min_triangle_quality`].
    pub fn with_min_triangle_quality(self, min_triangle_quality: f64) -> Self {
        Self {
            min_triangle_quality,
            ..self
        }
    }

    /// Sets [`Self::max_normal_turn_deg`].
    pub fn with_max_normal_turn_deg(self, max_normal_turn_deg: f64) -> Self {
        Self {
            max_normal_turn_deg,
            ..self
        }
    }
}

/// The simplified mesh and what happened.
#[derive(Clone, Debug, PartialEq)]
pub struct Simplified {
    /// The base mesh: compacted (only referenced vertices, numbered in increasing input index
    /// order), triangles in input order with their orientation kept.
    pub mesh: Mesh,
    /// Interior sharp edges of `mesh` (creases), by its indices. Boundary edges are sharp too
    /// but, per the conventions, not listed.
    pub creases: Creases,
    /// For each base vertex, the input vertex it kept the index of. Feature (crease, boundary,
    /// corner) vertices also kept that input vertex's position exactly.
    pub origin: Vec<u32>,
    /// The input's sharp edges (creases by the angle, and boundary edges), `[min, max]` by
    /// input indices: the feature lines the base's sharp edges run along.
    pub input_sharp_edges: Vec<[u32; 2]>,
    /// Number of edge collapses performed.
    pub collapses: usize,
    /// Largest collapse error (same measure as [`SimplifyOptions::max_error`]), in mm; an
    /// estimate, not a Hausdorff distance.
    pub max_error: f64,
}

/// Why [`simplify`] refused its input.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum SimplifyError {
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {triangle} refers to vertex {vertex}, which does not exist")]
    IndexOutOfRange {
        /// Triangle index.
        triangle: usize,
        /// The offending vertex index.
        vertex: u32,
    },
    /// A triangle repeats a vertex.
    #[error("triangle {triangle} repeats a vertex")]
    DegenerateTriangle {
        /// Triangle index.
        triangle: usize,
    },
    /// A referenced vertex has a NaN or infinite coordinate.
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFinitePosition {
        /// Vertex index.
        vertex: u32,
    },
    /// An edge is shared by more than two triangles.
    #[error("edge {edge:?} is shared by {triangles} triangles (non-manifold)")]
    NonManifoldEdge {
        /// `[min, max]` vertex indices.
        edge: [u32; 2],
        /// How many triangles use it.
        triangles: usize,
    },
    /// Two triangles traverse an edge in the same direction (inconsistent orientation, or a
    /// non-orientable surface).
    #[error("edge {edge:?} is traversed in the same direction by both its triangles")]
    InconsistentOrientation {
        /// `[min, max]` vertex indices.
        edge: [u32; 2],
    },
    /// A vertex's triangles form more than one fan (e.g. two cones touching at their tips).
    #[error("vertex {vertex} is non-manifold (its triangles form more than one fan)")]
    NonManifoldVertex {
        /// Vertex index.
        vertex: u32,
    },
    /// An option is out of range.
    #[error("option {name} = {value} is out of range ({expected})")]
    InvalidOption {
        /// Field name in [`SimplifyOptions`].
        name: &'static str,
        /// The value given.
        value: f64,
        /// The accepted range.
        expected: &'static str,
    },
}

/// Simplifies a welded, oriented, manifold mesh (open or closed, any number of components) by
/// quadric-error edge collapse to about `options.target_triangles` triangles, keeping
/// boundaries, creases, corners, genus and components. See the [module docs](self).
///
/// Errors on non-manifold or inconsistently oriented input (naming the edge or vertex), on
/// out-of-range indices or non-finite positions, and on out-of-range options. Unreferenced
/// vertices are dropped.
pub fn simplify(mesh: &Mesh, options: &SimplifyOptions) -> Result<Simplified, SimplifyError> {
    validate_options(options)?;
    let topology = topology::analyse(&mesh.triangles, mesh.positions.len())?;

    // Bounding box of referenced vertices: origin for the quadrics, scale for tolerances.
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    for &v in mesh.triangles.iter().flatten() {
        let p: &Point3<f64> = &mesh.positions[v as usize];
        if !p.coords.iter().all(|c| c.is_finite()) {
            return Err(SimplifyError::NonFinitePosition { vertex: v });
        }
        lo = lo.inf(&p.coords);
        hi = hi.sup(&p.coords);
    }
    if mesh.triangles.is_empty() {
        return Ok(Simplified {
            mesh: Mesh::default(),
            creases: Creases::default(),
            origin: Vec::new(),
            input_sharp_edges: Vec::new(),
            collapses: 0,
            max_error: 0.0,
        });
    }
    let origin = (lo + hi) * 0.5;
    let diagonal = (hi - lo).norm();

    let sharp = features::sharp_edges(
        &mesh.positions,
        &mesh.triangles,
        &topology,
        options.crease_angle_deg,
    );
    let initial =
        features::initial_quadrics(&mesh.positions, &origin, &mesh.triangles, &topology, &sharp);
    let params = collapse::Params {
        target_triangles: options.target_triangles,
        max_error: options.max_error,
        min_quality: options.min_triangle_quality,
        cos_max_turn: options.max_normal_turn_deg.to_radians().cos(),
        origin,
        // Normalising area floor: far below any real triangle of the model.
        area_floor: (1e-12 * diagonal * diagonal).max(f64::MIN_POSITIVE),
    };
    let outcome = collapse::run(mesh, &topology, &sharp, initial, params);
    Ok(Simplified {
        mesh: outcome.mesh,
        creases: outcome.creases,
        origin: outcome.origin,
        input_sharp_edges: sharp,
        collapses: outcome.collapses,
        max_error: outcome.max_error,
    })
}

fn validate_options(o: &SimplifyOptions) -> Result<(), SimplifyError> {
    let check = |name, value: f64, ok: bool, expected| {
        if ok {
            Ok(())
        } else {
            Err(SimplifyError::InvalidOption {
                name,
                value,
                expected,
            })
        }
    };
    let c = o.crease_angle_deg;
    check(
        "crease_angle_deg",
        c,
        (0.0..=180.0).contains(&c),
        "[0, 180]",
    )?;
    let q = o.min_triangle_quality;
    check(
        "min_triangle_quality",
        q,
        (0.0..=1.0).contains(&q),
        "[0, 1]",
    )?;
    let t = o.max_normal_turn_deg;
    check("max_normal_turn_deg", t, t > 0.0 && t <= 180.0, "(0, 180]")?;
    if let Some(e) = o.max_error {
        check("max_error", e, e >= 0.0, ">= 0")?;
    }
    Ok(())
}
