//! The stock model as the commands show it: blanks built from their specs, the summaries of a
//! simulated program's moves, and the stock's surface coloured by its distance to the part.
//! Shared by `simulate` (one program) and `plan` (its operations in order,
//! [`super::stock_run`]).

use serde::Serialize;

use super::blank::BlankSpec;
use crate::error::{Error, JobError, Result};
use crate::geom::{Aabb, MoveKind, Point3, Toolpath, Vector3};
use crate::mesh::io::RawMesh;
use crate::mesh::{Mesh, PrepareOptions, prepare};
use crate::stock::simulate::Simulation;
use crate::stock::{Stock, StockError};

/// Gouges in `simulation.json`.
#[derive(Clone, Debug, Serialize)]
pub struct GougeReport {
    pub count: usize,
    pub max_depth_mm: f64,
    pub volume_mm3: f64,
    pub first_move: Option<usize>,
}

/// A non-cutting body in material, in `simulation.json`.
#[derive(Clone, Debug, Serialize)]
pub struct CollisionReport {
    #[serde(rename = "move")]
    pub move_index: usize,
    pub body: crate::tool::BodyRole,
    pub depth_mm: f64,
    pub at: [f64; 3],
}

/// Removed volume per mm of cut, over the feed moves that removed material, mm³/mm.
pub type EngagementReport = Spread;

/// The engagement and the depths of cut of a simulated program's feed moves that removed
/// material.
pub fn cutting_spreads(sim: &Simulation, toolpath: &Toolpath) -> (Spread, DepthOfCutReport) {
    let cutting = || {
        sim.moves
            .iter()
            .zip(&toolpath.moves)
            .filter(|(r, m)| m.kind != MoveKind::Rapid && r.removed_mm3 > 0.0)
            .map(|(r, _)| r)
    };
    (
        Spread::of(
            cutting()
                .filter(|r| r.removed_per_mm > 0.0)
                .map(|r| r.removed_per_mm)
                .collect(),
        ),
        DepthOfCutReport {
            axial_mm: Spread::of(cutting().map(|r| r.axial_depth_mm).collect()),
            radial_mm: Spread::of(cutting().map(|r| r.radial_width_mm).collect()),
        },
    )
}

/// A distribution over the cutting moves that removed material.
#[derive(Clone, Debug, Serialize)]
pub struct Spread {
    pub max: f64,
    pub p99: f64,
    pub mean: f64,
}

impl Spread {
    fn of(mut values: Vec<f64>) -> Spread {
        values.sort_by(f64::total_cmp);
        let n = values.len();
        Spread {
            max: values.last().copied().unwrap_or(0.0),
            p99: values
                .get(((n as f64 * 0.99) as usize).min(n.saturating_sub(1)))
                .copied()
                .unwrap_or(0.0),
            mean: if n == 0 {
                0.0
            } else {
                values.iter().sum::<f64>() / n as f64
            },
        }
    }
}

/// Depths of cut in `simulation.json`: the extent of the stock each move removed along the
/// tool axis (axial) and across the feed and the axis (radial), mm.
#[derive(Clone, Debug, Serialize)]
pub struct DepthOfCutReport {
    pub axial_mm: Spread,
    pub radial_mm: Spread,
}

/// The colours of the stock's surface by its signed distance `d` to the part (mm, negative
/// inside): red deeper than `band` into the part (a gouge), green within `band`, blue above,
/// light at `band` to dark at `deep` and beyond.
pub(super) fn distance_colour(d: f64, band: f64, deep: f64) -> [f32; 4] {
    if d < -band {
        [0.85, 0.1, 0.1, 1.0]
    } else if d <= band {
        [0.15, 0.75, 0.2, 1.0]
    } else {
        let f = ((d - band) / (deep - band).max(1e-9)).clamp(0.0, 1.0) as f32;
        [0.55 - 0.45 * f, 0.75 - 0.55 * f, 1.0 - 0.3 * f, 1.0]
    }
}

/// The voxel budget of the pictures' stock mesh: about 4 M lattice points (a few hundred
/// thousand triangles on an impeller).
const PICTURE_VOXELS: usize = 4_000_000;

/// The stock's surface coloured by its signed distance to the part.
pub(super) struct ColouredStock {
    /// `stock.glb`.
    pub glb: Vec<u8>,
    pub surface: Mesh,
    pub colours: Vec<[f32; 4]>,
    /// What the colours mean, a line each.
    pub legend: Vec<String>,
    /// Green within this distance of the part, mm.
    pub band: f64,
    /// The darkest blue from this much material, mm.
    pub deep: f64,
}

pub(super) fn coloured_stock(stock: &Stock, part: &Mesh, tolerance: f64) -> Result<ColouredStock> {
    use rayon::prelude::*;
    let (surface, voxel) = stock.surface_mesh(PICTURE_VOXELS);
    let distance = crate::mesh::distance::SurfaceDistance::new(part);
    // Surface nets places a vertex within about half a lattice step of the model's surface.
    let band = tolerance.max(0.5 * voxel);
    let deep = 2.0_f64.max(4.0 * band);
    let colours: Vec<[f32; 4]> = surface
        .positions
        .par_iter()
        .map(|p| {
            let d = distance
                .signed_distance(p)
                .map_or(f64::INFINITY, |(d, _)| d);
            distance_colour(d, band, deep)
        })
        .collect();
    let legend = vec![
        format!("red: more than {band:.3} mm inside the part (a gouge, as far as the mesh shows)"),
        format!(
            "green: within {band:.3} mm of the part (the tolerance or half the mesh's {voxel:.3} mm lattice, the larger)"
        ),
        format!("light to dark blue: material left, {band:.3} mm to {deep:.3} mm and more"),
    ];
    let mut glb = crate::mesh::io::GlbBuilder::new();
    glb.add_triangles("stock", &surface, [1.0, 1.0, 1.0, 1.0], Some(&colours))
        .map_err(|error| Error::Glb {
            file: "stock.glb".into(),
            error,
        })?;
    Ok(ColouredStock {
        glb: glb.build(),
        surface,
        colours,
        legend,
        band,
        deep,
    })
}

/// The stock after an operation of a plan as a GLB, coloured as `simulate`'s `stock.glb`.
pub fn stock_model_glb(stock: &Stock, part: &Mesh, tolerance: f64) -> Result<Vec<u8>> {
    Ok(coloured_stock(stock, part, tolerance)?.glb)
}

pub(super) fn stock_error(e: StockError) -> Error {
    match e {
        StockError::TooLarge {
            size,
            spacing,
            dexels,
            limit,
        } => Error::TooLarge {
            what: format!("a {size} mm stock at a {spacing} mm resolution"),
            estimate: format!("{dexels} dexel lines"),
            limit: format!("{limit} lines"),
            advice: "use a coarser resolution".into(),
            limit_key: "max_dexels".into(),
        },
        other => Error::JobFile(JobError::Invalid {
            key: "stock".into(),
            reason: other.to_string(),
        }),
    }
}

/// A warning when the stock does not enclose the part (it is simulated all the same), saying
/// where.
pub fn enclosure_warning(stock: &Stock, part: &Mesh) -> Option<String> {
    let outside: Vec<&Point3> = part
        .positions
        .iter()
        .filter(|p| stock.bounds().inflated(1e-9).distance_squared(p) > 0.0)
        .collect();
    outside.first().map(|first| {
        format!(
            "the stock does not enclose the part: {} of its {} vertices lie outside the stock's \
             box, the first at ({:.3}, {:.3}, {:.3})",
            outside.len(),
            part.positions.len(),
            first.x,
            first.y,
            first.z
        )
    })
}

/// The default distance between dexel lines for `part`: its box diagonal / 400, within 0.05
/// to 1 mm.
pub fn default_resolution(part: &Mesh) -> f64 {
    (part.aabb().diagonal() / 400.0).clamp(0.05, 1.0)
}

/// The blank `spec` as a stock model of `part` (a mesh blank is read in `units`).
pub fn blank_stock(
    part: &Mesh,
    spec: &BlankSpec,
    units: &str,
    spacing: f64,
    max: usize,
) -> Result<Stock> {
    let b = part.aabb();
    match &spec.resolved(part) {
        BlankSpec::EnclosingCylinder { .. } => Err(Error::Internal(
            "the enclosing cylinder was not sized for the part".into(),
        )),
        BlankSpec::Box(c) => {
            let bounds =
                Aabb::from_points(&[Point3::new(c[0], c[1], c[2]), Point3::new(c[3], c[4], c[5])]);
            Stock::block(&bounds, spacing, max).map_err(stock_error)
        }
        BlankSpec::Cylinder { radius, z0, z1 } => {
            let centre = b.center();
            Stock::cylinder(
                &Point3::new(centre.x, centre.y, *z0),
                &Vector3::z(),
                *radius,
                z1 - z0,
                spacing,
                max,
            )
            .map_err(stock_error)
        }
        BlankSpec::Offset(margin) => {
            let shapes = super::offsets::stock_shapes(
                part,
                &crate::multires::RemeshOptions::default(),
                &[*margin],
            )?;
            let shape = shapes
                .last()
                .ok_or_else(|| Error::Internal("no offset shape for the offset blank".into()))?;
            Stock::from_mesh(&shape.1.mesh, spacing, max).map_err(stock_error)
        }
        BlankSpec::Mesh(path) => {
            let raw = super::load_part(path, units)?;
            let mesh = closed_part(&raw, &path.display().to_string())?;
            Stock::from_mesh(&mesh, spacing, max).map_err(stock_error)
        }
    }
}

/// The part's mesh, welded and checked closed (the part model needs an inside).
pub(super) fn closed_part(raw: &RawMesh, name: &str) -> Result<Mesh> {
    let (mesh, report) =
        prepare(&raw.mesh, &PrepareOptions::default()).map_err(|e| Error::Mesh {
            file: name.to_string(),
            reason: e.to_string(),
        })?;
    if !report.watertight {
        return Err(Error::Mesh {
            file: name.to_string(),
            reason: format!(
                "the part must be closed to tell inside from outside; found: {}",
                report.problems().join("; ")
            ),
        });
    }
    Ok(mesh)
}
