//! Rough-to-fine intermediate shapes: nested offsets of the wavelet levels that never overcut
//! the part (DESIGN.md §3.4; seed 004 ch. 5 step 3, "the surface of a higher resolution model
//! must be covered with that of a lower resolution model in order to prevent overcut"; the 3D
//! analogue of seed 004 eq. 3.1, d₁ = r + e, and of seed 001 ch. 3's global offset error bound).
//!
//! For shape j with allowance aⱼ, tool radius r (0 for the stock shapes; cⱼ = aⱼ + r) and
//! deviation bound eⱼ (every part point within eⱼ of the level surface Lⱼ: the exact L∞
//! deviation of Lⱼ from the finest level plus the finest level's Hausdorff distance to the
//! part), the shape is the boundary of
//!
//! ```text
//! Rⱼ = inside(part) ∪ tube(Lⱼ, tⱼ) ∪ ⋃_{k>j} tube(Lₖ, tₖ + cⱼ − cₖ),   tⱼ = cⱼ + eⱼ
//! ```
//!
//! with tube(L, t) = {x : dist(x, L) ≤ t} (unsigned: it does not trust the sign of a level
//! surface that may fold or touch itself; the part's inside, from its exact sign, fills the
//! rest). A point x of Sⱼ on the tube of Lₖ has dist(x, part) ≥ tₖ + cⱼ − cₖ − eₖ = cⱼ, and
//! Sⱼ ⊇ Sⱼ₊₁ whatever the allowance schedule, since Rⱼ holds every finer region grown by the
//! difference of clearances (a schedule with tⱼ ≥ tⱼ₊₁ + eⱼ + eⱼ₊₁ would nest anyway; the
//! union costs nothing where it does). Excess over cⱼ is at most 2eⱼ where Lⱼ's tube is the
//! outer one.
//!
//! How the shapes are made (`extract`, `normal_offset`): shapes are iso-surfaces of that
//! region's distance field on a sparse narrow-band grid (surface nets), so the folds an offset
//! makes in concave regions never appear: the result is the boundary of the offset region. Each
//! vertex is then moved exactly onto the level set (plus a chord margin). The grid spacing is
//! tⱼ/4, but no finer than the part's diagonal / 300; a shell thinner than two cells (or a thin
//! part feature) would slip between the grid's corners, so such a shape is extracted from the
//! region with every tube raised to two cells, and its vertices are then projected down onto
//! the tubes' own radii (moves that would turn a triangle over are shortened); the
//! verification pushes out whatever the coarse triangles cut off. The innermost shape is first
//! tried as the closed level surface pushed out along conservative vertex directions, which
//! keeps its small offset exact; it is refused (and made on the grid) where a triangle would
//! flip, which happens on the fitted finest levels of the CAD impellers.
//!
//! Local bounds (DESIGN.md §3.4 "locally per region"; [`local_fit`] measures the finest
//! level's part of them): with per-vertex bounds eᵥ, a triangle
//! needs only the largest of its corners' (the deviation is linear over it), so tube(Lⱼ, tⱼ) is
//! the union of tubes around the triangles of each bound class — eⱼ, eⱼ/2, eⱼ/4, eⱼ/8 and below,
//! each rounded up to its class — and the shape stays as thin as the level is close to the part
//! where it is close.
//!
//! Nothing above is trusted: `verify` checks every shape with exact f64 distance queries on
//! dense samples of the shape (clearance), of the part (inside by ray parity, at depth), and of
//! the next shape (nesting), pushes out the triangles that fail and checks again.

mod extract;
mod field;
mod fit;
mod normal_offset;
mod verify;

#[cfg(test)]
mod tests;

use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use crate::geom::{Point3, Vector3};
use crate::mesh::Mesh;
use crate::mesh::SurfaceDistance;
use crate::mesh::topology::Topology;

pub use fit::local_fit;
pub use verify::{CLEARANCE_SLACK_MM, Samples, sample_surface};

/// The fewest grid cells across the offset a shape is extracted with (see `OffsetOptions`).
const MIN_CELLS_PER_OFFSET: f64 = 2.0;

/// One shape to build: the level surface, its allowance and its deviation bound.
#[derive(Clone, Debug)]
pub struct ShapeSpec {
    /// Lⱼ: the level's surface (any connectivity), part coordinates, mm.
    pub surface: Mesh,
    /// aⱼ, mm: material left on the part by roughing to this shape.
    pub allowance: f64,
    /// eⱼ, mm: every point of the part is within this distance of `surface`.
    pub bound: f64,
    /// Local bounds (≤ `bound`), one per surface vertex: every point of the part is within
    /// max(e of t's corners) of some point of a triangle t (DESIGN.md §3.4 "locally per
    /// region"; for a level at the finest connectivity, eᵥ = |deviation at v| + the finest
    /// level's Hausdorff distance, since the deviation is linear over each triangle). `None`:
    /// `bound` everywhere.
    pub vertex_bounds: Option<Vec<f64>>,
}

/// Triangles whose local bounds round up to the same value share one tube: the bound classes
/// are `bound`·2⁻ᵏ for k < this (the last class takes everything smaller).
const BOUND_CLASSES: usize = 4;

impl ShapeSpec {
    /// The surface split into classes of local bound, each with the bound its triangles round
    /// up to (module docs): one class, the whole surface at `bound`, without local bounds.
    fn bound_classes(&self) -> Vec<(Mesh, f64)> {
        let Some(local) = &self.vertex_bounds else {
            return vec![(self.surface.clone(), self.bound)];
        };
        let levels: Vec<f64> = (0..BOUND_CLASSES)
            .map(|k| self.bound * 0.5f64.powi(k as i32))
            .collect();
        let mut classes: Vec<Vec<[u32; 3]>> = vec![Vec::new(); BOUND_CLASSES];
        for t in &self.surface.triangles {
            let e = t.iter().map(|&v| local[v as usize]).fold(0.0, f64::max);
            let class = (0..BOUND_CLASSES)
                .rev()
                .find(|&k| levels[k] >= e)
                .unwrap_or(0);
            classes[class].push(*t);
        }
        classes
            .into_iter()
            .zip(levels)
            .filter(|(triangles, _)| !triangles.is_empty())
            .map(|(triangles, level)| (Mesh::compacted(&self.surface.positions, triangles), level))
            .collect()
    }

    /// The local bound each vertex is pushed out by in a normal offset: the largest class bound
    /// of its triangles.
    fn vertex_offsets(&self, clearance: f64) -> Vec<f64> {
        let classes = self.bound_classes();
        let mut bound = vec![0.0f64; self.surface.positions.len()];
        match &self.vertex_bounds {
            None => bound.fill(self.bound),
            Some(local) => {
                let levels: Vec<f64> = classes.iter().map(|(_, e)| *e).collect();
                for t in &self.surface.triangles {
                    let e = t.iter().map(|&v| local[v as usize]).fold(0.0, f64::max);
                    let class = levels
                        .iter()
                        .copied()
                        .filter(|&l| l >= e)
                        .fold(self.bound, f64::min);
                    for &v in t {
                        bound[v as usize] = bound[v as usize].max(class);
                    }
                }
            }
        }
        bound.iter().map(|e| clearance + e).collect()
    }
}

/// How to build and verify the shapes.
#[derive(Clone, Debug, PartialEq)]
pub struct OffsetOptions {
    /// Ball radius r, mm: with r > 0 the shapes are tool-centre surfaces. Default 0.
    pub tool_radius: f64,
    /// Grid cells across the offset distance tⱼ (spacing tⱼ / this). Default 4: chords of a
    /// cell over a convex offset of radius ≥ tⱼ dip by ≈ h²/(8tⱼ) = tⱼ/128, covered by the margin.
    pub cells_per_offset: f64,
    /// The grid spacing is at least the part's box diagonal divided by this (bounds the cost
    /// of shapes with a small offset on a big part). Default 300.
    pub max_cells_across: f64,
    /// Rounds of push-out and re-verification before giving up. Default 12.
    pub max_repair_rounds: usize,
}

impl Default for OffsetOptions {
    fn default() -> Self {
        Self {
            tool_radius: 0.0,
            cells_per_offset: 4.0,
            max_cells_across: 300.0,
            max_repair_rounds: 12,
        }
    }
}

impl OffsetOptions {
    /// Sets the ball radius (tool-centre surfaces).
    pub fn with_tool_radius(mut self, r: f64) -> Self {
        self.tool_radius = r;
        self
    }
}

/// Why the shapes could not be built.
#[derive(Debug, thiserror::Error)]
pub enum OffsetError {
    #[error("option {name} = {value} is out of range ({expected})")]
    InvalidOption {
        name: &'static str,
        value: f64,
        expected: &'static str,
    },
    #[error(
        "allowance {index} = {value} mm: allowances must be finite, >= 0 and strictly decreasing"
    )]
    Allowance { index: usize, value: f64 },
    #[error("shape {index}: bound {value} mm must be finite and >= 0")]
    Bound { index: usize, value: f64 },
    #[error("shape {index}: the level surface has no triangles")]
    EmptySurface { index: usize },
    #[error(
        "shape {index}: local bounds must be one per surface vertex, finite, within 0 and the bound"
    )]
    LocalBounds { index: usize },
    #[error("the part has no triangles")]
    EmptyPart,
    #[error("shape {index}: {reason}")]
    Grid { index: usize, reason: String },
}

/// How a shape was made.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum Method {
    /// Iso-surface of the distance field on a sparse grid of this spacing (mm).
    DistanceGrid { spacing_mm: f64 },
    /// The level surface pushed out along conservative vertex directions.
    NormalOffset,
}

impl Method {
    /// The name used in reports.
    pub fn kind(&self) -> &'static str {
        match self {
            Method::DistanceGrid { .. } => "distance_grid",
            Method::NormalOffset => "normal_offset",
        }
    }
}

/// The figures of one shape (issue 4 points 2–3), all in mm.
#[derive(Clone, Debug, Serialize)]
pub struct ShapeReport {
    pub allowance_mm: f64,
    pub tool_radius_mm: f64,
    /// eⱼ.
    pub bound_mm: f64,
    /// The offset of the level surface: tⱼ = aⱼ + r + eⱼ (a thinner shell is extracted at two
    /// grid cells and projected down to it).
    pub offset_mm: f64,
    pub method: Method,
    pub vertices: usize,
    pub triangles: usize,
    /// Edges with more than two triangles and vertices whose triangles form more than one fan:
    /// 0 for the grid shapes, whose ambiguous cells are resolved towards the inside (see
    /// `extract`); counted so that any other method is held to the same.
    pub non_manifold_edges: usize,
    pub non_manifold_vertices: usize,
    /// Shape samples checked against the part; part samples and inner-shape samples checked
    /// against the shape.
    pub shape_samples: usize,
    pub part_samples: usize,
    pub inner_samples: usize,
    /// min over shape samples of dist(x, part) − (aⱼ + r): must be ≥ −1e-6.
    pub min_clearance_minus_allowance_mm: f64,
    /// Excess = dist(x, part) − (aⱼ + r) over shape samples.
    pub mean_excess_mm: f64,
    pub max_excess_mm: f64,
    /// Issue 4 point 3 targets: mean ≤ eⱼ, max ≤ 2eⱼ.
    pub meets_mean_target: bool,
    pub meets_max_target: bool,
    /// min over part samples of the depth inside the shape minus (aⱼ + r) (≥ −1e-6 when the
    /// part is inside at the allowance).
    pub min_part_depth_minus_allowance_mm: f64,
    /// min over inner-shape samples of their depth inside this shape (> 0: nested).
    pub min_inner_depth_mm: Option<f64>,
    /// Failing samples found by the first verification, and push-out rounds it took.
    pub failures_found: usize,
    pub repair_rounds: usize,
    /// Every check passed after the repairs.
    pub verified: bool,
    /// Seconds: making the shape, and verifying plus repairing it.
    #[serde(skip)]
    pub build_s: f64,
    #[serde(skip)]
    pub verify_s: f64,
}

/// A built shape with its figures.
#[derive(Clone, Debug)]
pub struct OffsetShape {
    pub mesh: Mesh,
    /// dist(v, part) − (aⱼ + r) at each vertex (for colouring).
    pub vertex_excess: Vec<f64>,
    pub report: ShapeReport,
}

/// The part, prepared for the exact queries every check makes.
pub(crate) struct PartQuery {
    surface: SurfaceDistance,
    /// Closed: signed distance (inside negative); open: unsigned.
    closed: bool,
}

impl PartQuery {
    fn new(part: &Mesh) -> Self {
        PartQuery {
            surface: SurfaceDistance::new(part),
            closed: is_closed(part),
        }
    }

    /// Distance from the part, negative inside when it is closed.
    fn signed_distance(&self, p: &Point3) -> f64 {
        self.signed_distance_and_away(p).0
    }

    /// The signed distance and the unit direction that leads away from the part at `p`
    /// (from its closest point, or along the pseudo-normal when `p` is on it or inside).
    fn signed_distance_and_away(&self, p: &Point3) -> (f64, Vector3) {
        let Some(c) = self.surface.closest(p, f64::INFINITY) else {
            return (f64::INFINITY, Vector3::zeros());
        };
        let normal = self.surface.pseudo_normal(&c);
        let offset = p - c.point;
        let inside = self.closed && offset.dot(&normal) < 0.0;
        let away = if c.distance > 1e-12 && !inside {
            offset / c.distance
        } else {
            normal / normal.norm().max(f64::MIN_POSITIVE)
        };
        (if inside { -c.distance } else { c.distance }, away)
    }
}

fn is_closed(mesh: &Mesh) -> bool {
    Topology::analyse(&mesh.triangles, mesh.positions.len()).boundary_edges == 0
}

fn check_inputs(
    part: &Mesh,
    specs: &[ShapeSpec],
    options: &OffsetOptions,
) -> Result<(), OffsetError> {
    let positive = |name, value: f64| {
        if value.is_finite() && value > 0.0 {
            Ok(())
        } else {
            Err(OffsetError::InvalidOption {
                name,
                value,
                expected: "finite, > 0",
            })
        }
    };
    positive("cells_per_offset", options.cells_per_offset)?;
    positive("max_cells_across", options.max_cells_across)?;
    if !(options.tool_radius.is_finite() && options.tool_radius >= 0.0) {
        return Err(OffsetError::InvalidOption {
            name: "tool_radius",
            value: options.tool_radius,
            expected: "finite, >= 0 mm",
        });
    }
    if part.triangles.is_empty() {
        return Err(OffsetError::EmptyPart);
    }
    for (index, s) in specs.iter().enumerate() {
        let decreasing = index == 0 || s.allowance < specs[index - 1].allowance;
        if !(s.allowance.is_finite() && s.allowance >= 0.0 && decreasing) {
            return Err(OffsetError::Allowance {
                index,
                value: s.allowance,
            });
        }
        if !(s.bound.is_finite() && s.bound >= 0.0) {
            return Err(OffsetError::Bound {
                index,
                value: s.bound,
            });
        }
        if s.surface.triangles.is_empty() {
            return Err(OffsetError::EmptySurface { index });
        }
        if let Some(local) = &s.vertex_bounds {
            let bad = local.len() != s.surface.positions.len()
                || local
                    .iter()
                    .any(|e| !(e.is_finite() && *e >= 0.0 && *e <= s.bound));
            if bad {
                return Err(OffsetError::LocalBounds { index });
            }
        }
    }
    Ok(())
}

/// Builds and verifies the nested shapes S₀ ⊇ S₁ ⊇ … ⊇ part, one per spec (coarsest first), with
/// the default options.
pub fn nested_offsets(part: &Mesh, specs: &[ShapeSpec]) -> Result<Vec<OffsetShape>, OffsetError> {
    nested_offsets_opt(part, specs, &OffsetOptions::default())
}

/// One bound class of a level surface as a tube: the radius the grid extracted it at (raised
/// to two cells where thinner) and its own radius, which the vertices are projected down to.
struct Tube {
    surface: SurfaceDistance,
    extracted: f64,
    radius: f64,
}

/// The terms of Rⱼ (module docs): the part's inside (exact sign: the part is a prepared,
/// closed, manifold mesh), the tube around level j, and the tubes around every finer level
/// grown by the difference of clearances, which holds the finer shapes (nesting, whatever the
/// schedule). The tubes are unsigned: a pseudo-normal sign is only as good as its surface, and
/// level surfaces and extracted shapes can fold or touch themselves, where a wrong sign far
/// from the surface would put sign changes outside the band.
fn region_terms<'a>(
    part: &'a PartQuery,
    tubes: &'a [Tube],
    finer: &'a [(Vec<Tube>, f64)],
    clearance: f64,
    extracted: bool,
) -> Vec<field::Term<'a>> {
    let level = |t: &Tube| if extracted { t.extracted } else { t.radius };
    let mut terms: Vec<field::Term<'a>> = tubes
        .iter()
        .map(|t| field::Term {
            surface: &t.surface,
            closed: false,
            level: level(t),
        })
        .collect();
    if part.closed {
        terms.push(field::Term {
            surface: &part.surface,
            closed: true,
            level: 0.0,
        });
    }
    for (classes, inner_clearance) in finer {
        terms.extend(classes.iter().map(|t| field::Term {
            surface: &t.surface,
            closed: false,
            level: level(t) + (clearance - inner_clearance),
        }));
    }
    terms
}

/// [`nested_offsets`] with options. Shapes are built innermost first, since each encloses the
/// next. A shape that still fails a check after the repairs is returned with
/// `report.verified == false` (the caller decides; the CLI exits with the verification code).
pub fn nested_offsets_opt(
    part: &Mesh,
    specs: &[ShapeSpec],
    options: &OffsetOptions,
) -> Result<Vec<OffsetShape>, OffsetError> {
    check_inputs(part, specs, options)?;
    let query = PartQuery::new(part);
    let part_samples = sample_surface(part, None);
    let diagonal = part.aabb().diagonal();
    let mut built: Vec<(OffsetShape, Samples)> = Vec::with_capacity(specs.len());
    // The level surfaces of the shapes built so far (innermost first), by bound class with the
    // offset each was extracted at, and their clearance a + r.
    let mut tubes: Vec<(Vec<Tube>, f64)> = Vec::with_capacity(specs.len());
    for (index, spec) in specs.iter().enumerate().rev() {
        let inner = built.last().map(|(shape, samples)| (shape, samples));
        let clearance = spec.allowance + options.tool_radius;
        let mut offset = clearance + spec.bound;
        let classes = spec.bound_classes();
        let started = Instant::now();
        let normal = if inner.is_none() && is_closed(&spec.surface) {
            normal_offset::normal_offset(&spec.surface, &spec.vertex_offsets(clearance))
        } else {
            None
        };
        let (mut mesh, method, class_tubes) = match normal {
            Some(mesh) => {
                let class_tubes = classes
                    .iter()
                    .map(|(m, e)| Tube {
                        surface: SurfaceDistance::new(m),
                        extracted: clearance + e,
                        radius: clearance + e,
                    })
                    .collect();
                (mesh, Method::NormalOffset, class_tubes)
            }
            None => {
                let spacing =
                    (offset / options.cells_per_offset).max(diagonal / options.max_cells_across);
                // A shell thinner than two cells is not resolved by the grid (its sign changes
                // are missed between corners): it is extracted at two cells, then projected.
                let thinnest = MIN_CELLS_PER_OFFSET * spacing;
                offset = offset.max(thinnest);
                let class_tubes: Vec<Tube> = classes
                    .iter()
                    .map(|(m, e)| Tube {
                        surface: SurfaceDistance::new(m),
                        extracted: (clearance + e).max(thinnest),
                        radius: clearance + e,
                    })
                    .collect();
                let mut seeds = spec.surface.positions.clone();
                seeds.extend_from_slice(&part.positions);
                for (shape, _) in &built {
                    seeds.extend_from_slice(&shape.mesh.positions);
                }
                let field = field::Field {
                    terms: region_terms(&query, &class_tubes, &tubes, clearance, true),
                };
                let mesh = extract::extract(&field, &seeds, spacing)
                    .map_err(|reason| OffsetError::Grid { index, reason })?;
                // The chord margin follows the thinnest tube (the sharpest offset curvature).
                let thinnest_tube = class_tubes
                    .iter()
                    .map(|t| t.extracted)
                    .fold(offset, f64::min);
                let raised = class_tubes.iter().any(|t| t.radius < t.extracted)
                    || tubes
                        .iter()
                        .flat_map(|(t, _)| t)
                        .any(|t| t.radius < t.extracted);
                let mesh = if raised {
                    // The grid resolved the shape at two cells; its vertices now go down onto
                    // the tubes' own radii. Where the coarse triangles cut a sharp convex
                    // offset the verification pushes them back out.
                    let thin = field::Field {
                        terms: region_terms(&query, &class_tubes, &tubes, clearance, false),
                    };
                    offset = clearance + spec.bound;
                    thin.project_vertices(mesh, thinnest_tube)
                } else {
                    field.project_vertices(mesh, thinnest_tube)
                };
                drop(field);
                (
                    mesh,
                    Method::DistanceGrid {
                        spacing_mm: spacing,
                    },
                    class_tubes,
                )
            }
        };
        tubes.push((class_tubes, clearance));
        let build_s = started.elapsed().as_secs_f64();
        let started = Instant::now();
        let outcome = verify::verify_and_repair(
            &mut mesh,
            &query,
            &part_samples,
            inner.map(|(_, samples)| samples),
            clearance,
            options.max_repair_rounds,
        );
        let verify_s = started.elapsed().as_secs_f64();
        let topology = Topology::analyse(&mesh.triangles, mesh.positions.len());
        let report = ShapeReport {
            allowance_mm: spec.allowance,
            tool_radius_mm: options.tool_radius,
            bound_mm: spec.bound,
            offset_mm: offset,
            method,
            vertices: mesh.positions.len(),
            triangles: mesh.triangles.len(),
            non_manifold_edges: topology.non_manifold_edges,
            non_manifold_vertices: topology.non_manifold_vertices,
            shape_samples: outcome.shape_samples.points.len(),
            part_samples: part_samples.points.len(),
            inner_samples: inner.map_or(0, |(_, s)| s.points.len()),
            min_clearance_minus_allowance_mm: outcome.stats.min_margin,
            mean_excess_mm: outcome.stats.mean_excess,
            max_excess_mm: outcome.stats.max_excess,
            // The clearance's slack: a normal offset sits exactly at 2eⱼ where the level is eⱼ
            // from the part, and must not miss the target by rounding.
            meets_mean_target: outcome.stats.mean_excess <= spec.bound + CLEARANCE_SLACK_MM,
            meets_max_target: outcome.stats.max_excess <= 2.0 * spec.bound + CLEARANCE_SLACK_MM,
            min_part_depth_minus_allowance_mm: outcome.stats.min_part_depth,
            min_inner_depth_mm: outcome.stats.min_inner_depth,
            failures_found: outcome.failures_found,
            repair_rounds: outcome.rounds,
            verified: outcome.verified,
            build_s,
            verify_s,
        };
        let vertex_excess: Vec<f64> = mesh
            .positions
            .par_iter()
            .map(|p| query.signed_distance(p) - clearance)
            .collect();
        built.push((
            OffsetShape {
                mesh,
                vertex_excess,
                report,
            },
            outcome.shape_samples,
        ));
    }
    Ok(built.into_iter().rev().map(|(shape, _)| shape).collect())
}
