//! Deterministic generators for the sample parts `wavemill` ships with.
//!
//! * [`impeller()`]: a centrifugal-compressor impeller, axis +Z, base on z = 0. A hub of
//!   revolution with a through bore (flat bottom, bore cylinder, short outer rim, and a concave
//!   top that falls from a tall nose at the bore to the rim like a trumpet bell) carries N thin,
//!   wrapped, leaning blades whose height falls from the inlet to the rim. The channels between
//!   the blades are a few millimetres wide at the inlet, which is what makes the part hard to
//!   machine. One closed 2-manifold of genus 1.
//! * [`lens`]: a freeform lens for `wavemill lens`, a rational bicubic B-spline patch closed by
//!   five planes, as IGES text (not a mesh).
//! * [`blade()`]: a turbine-blade stand-in. A box root block carries a twisted, tapered, cambered
//!   airfoil blade (NACA-4-like) with a flat tip. One closed 2-manifold of genus 0.
//!
//! # How the parts are built
//!
//! Both parts are assembled from vertex *loops* (closed polygons of mesh vertex indices) and
//! two operations that only ever reuse the loops' vertices, so every seam is shared exactly and
//! the result is welded by construction:
//!
//! * **Loft** (`loft.rs`): two loops with the same number of vertices are joined by quads, each
//!   split along its shorter diagonal. Walls, bore, rim, root-block sides and blades are lofts.
//! * **Region triangulation** (`cdt.rs`): a constrained Delaunay triangulation (`spade`) in the
//!   (x, y) plane of the region bounded by loops (outer boundary plus holes), with Steiner points
//!   that *we* place (a polar or staggered grid, thinned away from holes). spade's `refine` is not
//!   used because it splits constraint edges, which would break the shared seams. The region is
//!   picked by a parity flood fill across constraint edges. The triangles keep the 3D positions
//!   of their vertices, so the impeller's hub top is the triangulated annulus lifted onto the
//!   hub profile z_hub(r), and blade footprints are holes whose loops are the blades' first loft
//!   loops.
//!
//! All loops are oriented so that walls face outward; planar faces seen from below are flipped.
//! Output order depends only on the parameters: no hashing, no threads, no randomness, so the
//! same parameters give bit-identical vertex and triangle arrays.
//!
//! # Quality
//!
//! Edges are about `resolution` long (shorter near blade edges). The smallest triangle angle
//! is about 19° for the default impeller and 13° for the default blade (at the tip's leading
//! edge). It drops when a blade is much thinner than `resolution` (the tip cap is then a thin
//! strip): the test-suite's parameter sweeps stay above 2°.

mod blade;
mod builder;
mod cdt;
#[cfg(test)]
mod check;
mod impeller;
pub mod lens;
mod loft;
mod poly;

use crate::mesh::Mesh;

/// Parameters of the sample [`impeller()`]. Lengths in millimetres, angles in degrees.
///
/// Quantities derived from these (fixed ratios, documented here so the part is fully described):
/// the rim (back plate) is `hub_height / 4` tall; the blade height falls from `blade_height` at
/// the leading edge to `0.35 × blade_height` at the trailing edge; the trailing edge stops
/// `0.03 × hub_radius` short of the rim; the blade is `0.75 × blade_thickness` thick at its tip.
#[derive(Clone, Debug, PartialEq)]
pub struct ImpellerParams {
    /// Number of blades, evenly spaced in angle (default 7).
    pub blade_count: u32,
    /// Radius of the through bore, mm (default 8).
    pub bore_radius: f64,
    /// Outer radius of the hub (the rim), mm (default 45).
    pub hub_radius: f64,
    /// Height of the hub's nose at the bore, i.e. the hub's highest point, mm (default 12).
    pub hub_height: f64,
    /// Blade height above the hub surface at the leading edge, mm (default 22). It falls
    /// smoothly to `0.35 × blade_height` at the trailing edge.
    pub blade_height: f64,
    /// Radius of the blades' leading edge (the camber line's start), mm (default 14).
    pub blade_inner_radius: f64,
    /// Angle the camber line turns through from the leading to the trailing edge, degrees
    /// (default 60). The turn is steepest at the inlet and the blade leaves the rim radially.
    pub wrap_angle_deg: f64,
    /// Tangential lean of the blade with height, degrees from vertical (default 10).
    pub lean_angle_deg: f64,
    /// Blade thickness at the hub, mm (default 2.0); it tapers to 75 % at the blade tip.
    pub blade_thickness: f64,
    /// Target edge length of the mesh, mm (default 1.2).
    pub resolution: f64,
}

impl Default for ImpellerParams {
    fn default() -> Self {
        Self {
            blade_count: 7,
            bore_radius: 8.0,
            hub_radius: 45.0,
            hub_height: 12.0,
            blade_height: 22.0,
            blade_inner_radius: 14.0,
            wrap_angle_deg: 60.0,
            lean_angle_deg: 10.0,
            blade_thickness: 2.0,
            resolution: 1.2,
        }
    }
}

/// Parameters of the sample [`blade()`]. Lengths in millimetres, angles in degrees.
#[derive(Clone, Debug, PartialEq)]
pub struct BladeParams {
    /// Height of the blade above the root block's top face, mm (default 80).
    pub span: f64,
    /// Chord at the root, mm (default 30).
    pub root_chord: f64,
    /// Chord at the tip, mm (default 20); the chord varies linearly along the span.
    pub tip_chord: f64,
    /// Maximum thickness as a fraction of the chord (NACA `t`, default 0.12).
    pub thickness_ratio: f64,
    /// Maximum camber as a fraction of the chord (NACA `m`, at 40 % chord, default 0.04).
    pub camber_ratio: f64,
    /// Twist of the tip section relative to the root about +Z, degrees (default 35); the twist
    /// varies linearly along the span. The root chord lies along +X.
    pub twist_deg: f64,
    /// Root block size `[x, y, z]`, mm (default `[40, 24, 16]`). The block is centred on the Z
    /// axis with its bottom on z = 0; the blade stands on its top face, mid-chord on the axis.
    pub root_block: [f64; 3],
    /// Target edge length of the mesh, mm (default 1.0).
    pub resolution: f64,
}

impl Default for BladeParams {
    fn default() -> Self {
        Self {
            span: 80.0,
            root_chord: 30.0,
            tip_chord: 20.0,
            thickness_ratio: 0.12,
            camber_ratio: 0.04,
            twist_deg: 35.0,
            root_block: [40.0, 24.0, 16.0],
            resolution: 1.0,
        }
    }
}

/// Why a sample part could not be generated.
#[derive(Debug, thiserror::Error)]
pub enum SampleError {
    /// A parameter is out of range, or a combination of parameters gives an invalid part
    /// (blades that overlap or leave the hub, a bore as large as the hub, …). `name` is the
    /// field of the parameter struct to change.
    #[error("invalid sample parameter `{name}`: {reason}")]
    InvalidParameter {
        /// The parameter's field name.
        name: &'static str,
        /// What is wrong and what the valid range is.
        reason: String,
    },
    /// The constrained Delaunay triangulation of a face rejected the generated boundary. This
    /// is a bug in the generator for parameters that passed validation.
    #[error("triangulating the {surface} failed: {reason}")]
    Triangulation {
        /// Which face was being triangulated.
        surface: &'static str,
        /// The failure.
        reason: String,
    },
}

/// Generates the sample impeller: one closed, outward-oriented, welded 2-manifold of genus 1.
///
/// At the default parameters the mesh has about 38 500 triangles (minimum angle ≈ 19°). Returns
/// [`SampleError::InvalidParameter`] for out-of-range parameters; never panics.
pub fn impeller(p: &ImpellerParams) -> Result<Mesh, SampleError> {
    impeller::Impeller::new(p)?.build()
}

/// Generates the sample turbine blade on its root block: one closed, outward-oriented, welded
/// 2-manifold of genus 0.
///
/// At the default parameters the mesh has about 18 700 triangles (minimum angle ≈ 13°). Returns
/// [`SampleError::InvalidParameter`] for out-of-range parameters; never panics.
pub fn blade(p: &BladeParams) -> Result<Mesh, SampleError> {
    blade::Blade::new(p)?.build()
}

/// An [`SampleError::InvalidParameter`] for `name`.
fn invalid(name: &'static str, reason: impl Into<String>) -> SampleError {
    SampleError::InvalidParameter {
        name,
        reason: reason.into(),
    }
}

/// `v` if it is finite and strictly positive.
fn positive(name: &'static str, v: f64) -> Result<f64, SampleError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(invalid(name, format!("must be finite and > 0, got {v}")))
    }
}

/// `v` if it is finite and `|v| <= limit`.
fn bounded(name: &'static str, v: f64, limit: f64) -> Result<f64, SampleError> {
    if v.is_finite() && v.abs() <= limit {
        Ok(v)
    } else {
        Err(invalid(
            name,
            format!("must be finite and within ±{limit}, got {v}"),
        ))
    }
}

/// Upper bound on the triangle count a parameter set may ask for (guards against a tiny
/// `resolution` exhausting memory).
const MAX_TRIANGLES: f64 = 4.0e6;
