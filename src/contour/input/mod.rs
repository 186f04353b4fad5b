//! Outline input: reads planar part outlines from SVG and DXF files into a [`Shape`].
//!
//! This is the input stage of 2.5D contour machining (issue #6): the part profile, or the
//! pocket boundary with its islands (seed 004 §1.2), as closed contours of straight lines and
//! circular arcs only, since CNC interpolators take nothing else (seed 004, chapter 4
//! introduction); free-form curves become G¹ biarcs, the smoothing that chapter cites from
//! Chuang and Kao (1999). The region lies to the left of every contour.
//!
//! * `svg` interprets SVG geometry itself (roxmltree + svgtypes, no renderer) so that the
//!   coordinate semantics are under our control: root viewBox user units, the viewBox origin
//!   moved to (0, 0), y flipped, times [`OutlineOptions::scale`].
//! * `dxf` reads LINE/ARC/CIRCLE/ELLIPSE/LWPOLYLINE/POLYLINE/SPLINE and chains open pieces into
//!   loops by their endpoints.
//! * `curves` turns everything that is not a line or a circular arc (Béziers, elliptical arcs,
//!   NURBS) into biarcs within [`OutlineOptions::tolerance`].
//! * `mesh_section` cuts a closed triangle mesh by a plane z = Z into an outline (the region
//!   by nesting, straight runs merged within the tolerance).
//! * `fill` checks that contours neither cross nor overlap (exact line/arc intersections),
//!   builds the containment tree, applies the fill rule and orients the contours.
//!
//! Crossing or overlapping contours are reported as errors naming both contours and the point;
//! they are not resolved by polygon booleans.

pub(crate) mod curves;
mod dxf;
mod fill;
mod mesh_section;
mod segmath;
mod svg;

use std::fmt;
use std::io::Read;
use std::path::Path;

use crate::contour::geometry::{Point2, Shape, Vertex};

pub use fill::FillRule;
pub use mesh_section::mesh_section;

/// Largest input file accepted, bytes.
pub const MAX_FILE_BYTES: u64 = 50 * 1024 * 1024;

/// Options of the outline readers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OutlineOptions {
    /// Multiplies all coordinates after unit conversion (SVG: one user unit becomes `scale` mm;
    /// DXF: one drawing unit converted to mm becomes `scale` mm). Default 1.
    pub scale: f64,
    /// Largest distance, mm, between a curve (Bézier, ellipse, spline) and the lines and arcs
    /// that replace it. Default 0.001 mm. Circles and circular arcs are always exact.
    pub tolerance: f64,
}

impl Default for OutlineOptions {
    fn default() -> Self {
        Self {
            scale: 1.0,
            tolerance: 0.001,
        }
    }
}

/// Everything that can go wrong while reading an outline. Every message starts with the file
/// name.
#[derive(Debug, thiserror::Error)]
pub enum OutlineError {
    #[error("{file}: cannot read the file: {source}")]
    Io {
        file: String,
        #[source]
        source: std::io::Error,
    },
    #[error("{file}: unknown outline format (expected a .svg or .dxf extension)")]
    UnknownFormat { file: String },
    #[error("{file}: the file is {size} bytes, more than the limit of {limit} bytes")]
    TooLarge { file: String, size: u64, limit: u64 },
    #[error("{file}: the file is empty")]
    Empty { file: String },
    #[error("{file}: invalid options: {message}")]
    Options { file: String, message: String },
    #[error("{file}: cannot parse: {message}")]
    Parse { file: String, message: String },
    #[error("{file}: {what}: unsupported: {message}")]
    Unsupported {
        file: String,
        what: String,
        message: String,
    },
    #[error("{file}: {what}: {message}")]
    Invalid {
        file: String,
        what: String,
        message: String,
    },
    #[error("{file}: {what} is open: it ends at ({x:.6}, {y:.6}) mm, {gap:.6} mm from its start")]
    Open {
        file: String,
        what: String,
        gap: f64,
        x: f64,
        y: f64,
    },
    #[error("{file}: {what} has zero area{detail}")]
    ZeroArea {
        file: String,
        what: String,
        detail: String,
    },
    #[error("{file}: the plane z = {z} mm misses the part (it spans z = {zmin} … {zmax} mm)")]
    PlaneMisses {
        file: String,
        z: f64,
        zmin: f64,
        zmax: f64,
    },
    #[error(
        "{file}: the section at z = {z} mm is open: it ends at ({x:.6}, {y:.6}) mm, {gap:.6} mm \
         from its start; the mesh is not closed there"
    )]
    OpenSection {
        file: String,
        z: f64,
        x: f64,
        y: f64,
        gap: f64,
    },
    #[error(
        "{file}: the plane z = {z} mm runs along a horizontal face of the part (triangle \
         {triangle}), where the section is not defined; try a slightly different Z, e.g. \
         z = {suggestion}"
    )]
    DegenerateSection {
        file: String,
        z: f64,
        triangle: usize,
        suggestion: f64,
    },
    #[error("{file}: no closed shape found{detail}")]
    NoClosedShape { file: String, detail: String },
    #[error(
        "{file}: {first} and {second} {kind} at ({x:.6}, {y:.6}) mm; \
         the outline must consist of non-crossing closed contours"
    )]
    Crossing {
        file: String,
        first: String,
        second: String,
        kind: CrossingKind,
        x: f64,
        y: f64,
    },
}

/// How two contours (or one contour with itself) meet where they must not.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CrossingKind {
    /// The boundaries cross transversally.
    Cross,
    /// The boundaries run along each other (shared edge or a spike folding back).
    Overlap,
}

impl fmt::Display for CrossingKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CrossingKind::Cross => write!(f, "cross"),
            CrossingKind::Overlap => write!(f, "overlap"),
        }
    }
}

/// A closed contour as read from a file, before region building.
#[derive(Clone, Debug)]
pub(crate) struct RawContour {
    /// Closed: the last vertex connects back to the first.
    pub vertices: Vec<Vertex>,
    /// Where it came from, for error messages ("path \"p1\" (line 7), subpath 2").
    pub label: String,
    pub rule: FillRule,
}

/// An open or closed chain of segments: `vertices[i]` starts segment i; `end` is where the last
/// segment ends (equal to `vertices[0]` for a closed chain).
#[derive(Clone, Debug)]
pub(crate) struct Chain {
    pub vertices: Vec<Vertex>,
    pub end: Point2,
}

impl Chain {
    pub fn new(start: Point2) -> Self {
        Self {
            vertices: Vec::new(),
            end: start,
        }
    }

    pub fn start(&self) -> Point2 {
        self.vertices.first().map_or(self.end, |v| v.point)
    }

    /// Appends a segment from the current end to `to` with `bulge`.
    pub fn push(&mut self, to: Point2, bulge: f64) {
        self.vertices.push(Vertex {
            point: self.end,
            bulge,
        });
        self.end = to;
    }

    /// Appends already built vertices (each starting a segment) followed by the end point.
    pub fn extend(&mut self, vertices: &[Vertex], to: Point2) {
        if let Some(first) = vertices.first() {
            // The first vertex of a curve starts where the chain ends; keep the chain's copy of
            // that point so the chain stays exactly connected.
            self.vertices.push(Vertex {
                point: self.end,
                bulge: first.bulge,
            });
            self.vertices.extend_from_slice(&vertices[1..]);
            self.end = to;
        }
    }

    pub fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }

    /// The same chain run backwards.
    pub fn reversed(&self) -> Chain {
        let n = self.vertices.len();
        let mut out = Vec::with_capacity(n);
        for i in (0..n).rev() {
            let to = if i + 1 < n {
                self.vertices[i + 1].point
            } else {
                self.end
            };
            out.push(Vertex {
                point: to,
                bulge: -self.vertices[i].bulge,
            });
        }
        Chain {
            vertices: out,
            end: self.start(),
        }
    }

    /// The chain as a closed contour's vertex list (the end must coincide with the start;
    /// the closing gap, if any, is absorbed by the last segment).
    pub fn into_closed_vertices(self) -> Vec<Vertex> {
        self.vertices
    }
}

/// Bounding-box diagonal of a set of points (0 for none), used as the drawing size that scales
/// the matching tolerances.
pub(crate) fn points_size<'a>(points: impl IntoIterator<Item = &'a Point2>) -> f64 {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in points {
        lo[0] = lo[0].min(p.x);
        lo[1] = lo[1].min(p.y);
        hi[0] = hi[0].max(p.x);
        hi[1] = hi[1].max(p.y);
    }
    if lo[0] > hi[0] {
        return 0.0;
    }
    ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2)).sqrt()
}

fn check_options(file: &str, options: &OutlineOptions) -> Result<(), OutlineError> {
    let bad = |message: String| {
        Err(OutlineError::Options {
            file: file.to_string(),
            message,
        })
    };
    if !(options.scale.is_finite() && options.scale > 0.0) {
        return bad(format!(
            "scale must be positive and finite, got {}",
            options.scale
        ));
    }
    if !(options.tolerance.is_finite() && options.tolerance > 0.0) {
        return bad(format!(
            "tolerance must be positive and finite, got {}",
            options.tolerance
        ));
    }
    Ok(())
}

/// Reads an outline file; the format is chosen by the extension (`.svg` or `.dxf`, any case).
pub fn read_outline(path: &Path, options: &OutlineOptions) -> Result<Shape, OutlineError> {
    let file = path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let is_svg = match ext.as_deref() {
        Some("svg") => true,
        Some("dxf") => false,
        _ => return Err(OutlineError::UnknownFormat { file }),
    };
    let io = |source| OutlineError::Io {
        file: file.clone(),
        source,
    };
    let handle = std::fs::File::open(path).map_err(io)?;
    let size = handle.metadata().map_err(io)?.len();
    if size > MAX_FILE_BYTES {
        return Err(OutlineError::TooLarge {
            file,
            size,
            limit: MAX_FILE_BYTES,
        });
    }
    let mut bytes = Vec::new();
    // `take` guards against a file that grows between the size check and the read.
    handle
        .take(MAX_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if is_svg {
        let text = String::from_utf8(bytes).map_err(|e| OutlineError::Parse {
            file: file.clone(),
            message: format!("not UTF-8 text: {e}"),
        })?;
        read_svg_str(&text, &file, options)
    } else {
        read_dxf_bytes(&bytes, &file, options)
    }
}

/// Reads SVG text; `name` is used in error messages.
pub fn read_svg_str(
    text: &str,
    name: &str,
    options: &OutlineOptions,
) -> Result<Shape, OutlineError> {
    check_input(name, text.len(), text.trim().is_empty())?;
    check_options(name, options)?;
    svg::read(text, name, options)
}

/// Reads a DXF file (ASCII or binary) from memory; `name` is used in error messages.
pub fn read_dxf_bytes(
    bytes: &[u8],
    name: &str,
    options: &OutlineOptions,
) -> Result<Shape, OutlineError> {
    let blank = bytes.iter().all(|b| b.is_ascii_whitespace());
    check_input(name, bytes.len(), blank)?;
    check_options(name, options)?;
    dxf::read(bytes, name, options)
}

fn check_input(name: &str, len: usize, blank: bool) -> Result<(), OutlineError> {
    let size = len as u64;
    if size > MAX_FILE_BYTES {
        return Err(OutlineError::TooLarge {
            file: name.to_string(),
            size,
            limit: MAX_FILE_BYTES,
        });
    }
    if blank {
        return Err(OutlineError::Empty {
            file: name.to_string(),
        });
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod test_util;

#[cfg(test)]
mod tests;
