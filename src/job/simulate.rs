//! `simulate`: a program's CL data run on a blank, checked against the part (issue 19, first
//! part): the blank as a tri-dexel stock, each move's ball-end body removing material, the part
//! as a second model only a gouge may cut (`stock::simulate`). Writes `simulation.json`.
//!
//! Not yet: posted G-code read back through the machine's forward kinematics, shank and holder
//! against material (collisions), the rest material over the part surface, flat, bull-nose and
//! tapered cutters, the stock's surface mesh and picture. The report names only what was
//! checked.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use super::output::{OutputKind, write_output_set};
use crate::error::{Error, JobError, Result};
use crate::geom::{Aabb, MoveKind, Point3, Vector3};
use crate::mesh::io::RawMesh;
use crate::mesh::{Mesh, PrepareOptions, prepare};
use crate::post::read_cl_csv;
use crate::stock::cutter::BallEndBody;
use crate::stock::simulate::{SimulationOptions, simulate};
use crate::stock::{DEFAULT_MAX_DEXELS, Stock, StockError};

/// The blank a simulation starts from.
#[derive(Clone, Debug, PartialEq)]
pub enum BlankSpec {
    /// A box `[x0, y0, z0, x1, y1, z1]`, mm.
    Box([f64; 6]),
    /// A cylinder about the vertical line through the part's box centre: radius, `z0`, `z1`.
    Cylinder { radius: f64, z0: f64, z1: f64 },
    /// The part grown by this many mm (its verified enclosing offset shape).
    Offset(f64),
    /// A closed mesh file (in the part's units).
    Mesh(PathBuf),
}

impl BlankSpec {
    fn describe(&self) -> String {
        match self {
            BlankSpec::Box(b) => {
                format!("box:{},{},{},{},{},{}", b[0], b[1], b[2], b[3], b[4], b[5])
            }
            BlankSpec::Cylinder { radius, z0, z1 } => format!("cylinder:{radius},{z0},{z1}"),
            BlankSpec::Offset(m) => format!("offset:{m}"),
            BlankSpec::Mesh(p) => format!(
                "mesh:{}",
                p.file_name()
                    .map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into())
            ),
        }
    }
}

/// Options of [`simulate_program`].
#[derive(Clone, Debug, PartialEq)]
pub struct SimulateOptions {
    /// The blank.
    pub blank: BlankSpec,
    /// Ball-end mill diameter, mm.
    pub tool_diameter: f64,
    /// Fluted length from the tip, mm; `None` = 3 × diameter.
    pub flute_length: Option<f64>,
    /// The whole tool (a ball-end cutter, shank, holder), when known: its non-cutting bodies
    /// are checked against the material, and its cutter sets the diameter and flutes.
    pub assembly: Option<crate::tool::ToolAssembly>,
    /// Distance between dexel lines, mm; `None` = the part's box diagonal / 400, within
    /// 0.05 to 1 mm.
    pub resolution: Option<f64>,
    /// Depth into the part that counts as a gouge, mm.
    pub tolerance: f64,
    /// Largest number of dexel lines per model.
    pub max_dexels: usize,
    /// Units of the part and a mesh blank.
    pub units: String,
    /// Keep the run-dependent timings in the report.
    pub timings: bool,
}

impl SimulateOptions {
    /// A ball of `tool_diameter` and `blank`; the other options at their defaults.
    pub fn new(blank: BlankSpec, tool_diameter: f64) -> Self {
        SimulateOptions {
            blank,
            tool_diameter,
            flute_length: None,
            assembly: None,
            resolution: None,
            tolerance: 0.01,
            max_dexels: DEFAULT_MAX_DEXELS,
            units: "mm".into(),
            timings: true,
        }
    }
}

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
#[derive(Clone, Debug, Serialize)]
pub struct EngagementReport {
    pub max: f64,
    pub p99: f64,
    pub mean: f64,
}

/// The stock in `simulation.json`.
#[derive(Clone, Debug, Serialize)]
pub struct StockReport {
    pub blank: String,
    pub resolution_mm: f64,
    pub dexel_lines: usize,
    pub volume_before_mm3: f64,
    pub volume_after_mm3: f64,
}

/// `simulation.json`.
#[derive(Clone, Debug, Serialize)]
pub struct SimulationReport {
    pub wavemill_version: &'static str,
    pub part: String,
    pub program: String,
    pub tool: String,
    pub tolerance_mm: f64,
    pub moves: usize,
    pub removed_volume_mm3: f64,
    pub gouge: GougeReport,
    /// Rapid moves that removed material (indices into the program, from 0).
    pub rapids_through_material: Vec<usize>,
    /// Shank, neck or holder touching material (the first 1000; `collision_count` has all).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub collisions: Option<Vec<CollisionReport>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub collision_count: Option<usize>,
    pub air_cut_fraction: f64,
    pub engagement: EngagementReport,
    pub stock: StockReport,
    /// What this simulation checks, so a missing check is not read as a pass.
    pub checked: Vec<&'static str>,
    pub warnings: Vec<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timings_ms: Option<Timings>,
}

/// Milliseconds per stage.
#[derive(Clone, Debug, Serialize)]
pub struct Timings {
    pub blank: f64,
    pub simulate: f64,
}

fn stock_error(e: StockError) -> Error {
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

/// The part's mesh, welded and checked closed (the part model needs an inside).
fn closed_part(raw: &RawMesh, name: &str) -> Result<Mesh> {
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

fn blank(part: &Mesh, options: &SimulateOptions, spacing: f64) -> Result<Stock> {
    let max = options.max_dexels;
    let b = part.aabb();
    match &options.blank {
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
            let raw = super::load_part(path, &options.units)?;
            let mesh = closed_part(&raw, &path.display().to_string())?;
            Stock::from_mesh(&mesh, spacing, max).map_err(stock_error)
        }
    }
}

/// Runs the CL data in `cl_text` (named `cl_name`) on the blank, against the part.
pub fn simulate_program(
    raw: &RawMesh,
    part_name: &str,
    cl_text: &str,
    cl_name: &str,
    options: &SimulateOptions,
) -> Result<SimulationReport> {
    let (d, flutes) = match &options.assembly {
        Some(tool) => match tool.cutter {
            crate::tool::Cutter::Ball {
                diameter,
                flute_length,
            } => (diameter, flute_length),
            other => {
                return Err(Error::JobFile(JobError::Invalid {
                    key: "tool".into(),
                    reason: format!(
                        "is a {} cutter: simulate drives ball-end mills so far",
                        other.kind()
                    ),
                }));
            }
        },
        None => (
            options.tool_diameter,
            options.flute_length.unwrap_or(3.0 * options.tool_diameter),
        ),
    };
    let non_cutting: Vec<crate::tool::Body> = options
        .assembly
        .as_ref()
        .map(|tool| {
            tool.bodies()
                .into_iter()
                .filter(|b| b.role != crate::tool::BodyRole::Flutes)
                .collect()
        })
        .unwrap_or_default();
    if !(d.is_finite() && d > 0.0 && flutes.is_finite() && flutes >= 0.5 * d) {
        return Err(Error::JobFile(JobError::Invalid {
            key: "tool".into(),
            reason: format!(
                "a ball of {d} mm with {flutes} mm flutes: the diameter must be > 0 and the flutes at least the radius"
            ),
        }));
    }
    if !(options.tolerance.is_finite() && options.tolerance >= 0.0 && options.tolerance < 0.5 * d) {
        return Err(Error::JobFile(JobError::Invalid {
            key: "tolerance".into(),
            reason: format!(
                "= {}: must be ≥ 0 mm and below the ball radius",
                options.tolerance
            ),
        }));
    }
    let toolpath = read_cl_csv(cl_text, cl_name).map_err(|e| Error::DataFile {
        file: e.file,
        line: e.line,
        reason: e.reason,
    })?;
    let part = closed_part(raw, part_name)?;
    let spacing = match options.resolution {
        Some(r) if r.is_finite() && r > 0.0 => r,
        Some(r) => {
            return Err(Error::JobFile(JobError::Invalid {
                key: "resolution".into(),
                reason: format!("= {r}: must be a positive number of mm"),
            }));
        }
        None => (part.aabb().diagonal() / 400.0).clamp(0.05, 1.0),
    };
    let t = Instant::now();
    let mut stock = blank(&part, options, spacing)?;
    let blank_ms = elapsed_ms(t);
    let mut warnings = raw.warnings.clone();
    let outside: Vec<&Point3> = part
        .positions
        .iter()
        .filter(|p| stock.bounds().inflated(1e-9).distance_squared(p) > 0.0)
        .collect();
    if let Some(first) = outside.first() {
        warnings.push(format!(
            "the stock does not enclose the part: {} of its {} vertices lie outside the stock's \
             box, the first at ({:.3}, {:.3}, {:.3})",
            outside.len(),
            part.positions.len(),
            first.x,
            first.y,
            first.z
        ));
    }
    let volume_before = stock.volume();
    let body = BallEndBody::new(d, flutes);
    let t = Instant::now();
    let sim = simulate(
        &mut stock,
        &part,
        &toolpath,
        &body,
        &SimulationOptions {
            tolerance: options.tolerance,
            max_dexels: options.max_dexels,
            non_cutting: non_cutting.clone(),
        },
    )
    .map_err(stock_error)?;
    let simulate_ms = elapsed_ms(t);
    let mut engaged: Vec<f64> = sim
        .moves
        .iter()
        .zip(&toolpath.moves)
        .filter(|(r, m)| m.kind != MoveKind::Rapid && r.removed_per_mm > 0.0)
        .map(|(r, _)| r.removed_per_mm)
        .collect();
    engaged.sort_by(f64::total_cmp);
    let engagement = EngagementReport {
        max: engaged.last().copied().unwrap_or(0.0),
        p99: engaged
            .get(((engaged.len() as f64 * 0.99) as usize).min(engaged.len().saturating_sub(1)))
            .copied()
            .unwrap_or(0.0),
        mean: if engaged.is_empty() {
            0.0
        } else {
            engaged.iter().sum::<f64>() / engaged.len() as f64
        },
    };
    Ok(SimulationReport {
        wavemill_version: env!("CARGO_PKG_VERSION"),
        part: file_name(Path::new(part_name)),
        program: file_name(Path::new(cl_name)),
        tool: options.assembly.as_ref().map_or_else(
            || format!("ball:{d} (flutes {flutes} mm)"),
            |t| t.describe(),
        ),
        tolerance_mm: options.tolerance,
        moves: toolpath.moves.len(),
        removed_volume_mm3: sim.removed_volume_mm3,
        gouge: GougeReport {
            count: sim.gouge.count,
            max_depth_mm: sim.gouge.max_depth_mm,
            volume_mm3: sim.gouge.volume_mm3,
            first_move: sim.gouge.first_move,
        },
        rapids_through_material: sim.rapids_through_material,
        collision_count: (!non_cutting.is_empty()).then_some(sim.collisions.len()),
        collisions: (!non_cutting.is_empty()).then(|| {
            sim.collisions
                .iter()
                .take(1000)
                .map(|c| CollisionReport {
                    move_index: c.move_index,
                    body: c.role,
                    depth_mm: c.depth_mm,
                    at: [c.at.x, c.at.y, c.at.z],
                })
                .collect()
        }),
        air_cut_fraction: sim.air_cut_fraction,
        engagement,
        stock: StockReport {
            blank: options.blank.describe(),
            resolution_mm: spacing,
            dexel_lines: stock.line_count(),
            volume_before_mm3: volume_before,
            volume_after_mm3: stock.volume(),
        },
        checked: {
            let mut checked = vec![
                "material removed by the ball-end cutting body (flutes included)",
                "gouges: the body deeper into the part than the tolerance",
                "rapids through material",
            ];
            if !non_cutting.is_empty() {
                checked.push("shank, neck and holder against the material (collisions)");
            }
            checked
        },
        warnings,
        timings_ms: options.timings.then_some(Timings {
            blank: blank_ms,
            simulate: simulate_ms,
        }),
    })
}

/// Writes `simulation.json` into `dir` (replacing an earlier run's); then, if the program
/// gouges or rapids through material, fails verification (exit 3) saying so.
pub fn write_simulation(dir: &Path, report: &SimulationReport) -> Result<()> {
    let json = (serde_json::to_string_pretty(report)
        .map_err(|e| Error::Internal(format!("simulation.json: {e}")))?
        + "\n")
        .into_bytes();
    write_output_set(
        dir,
        &OutputKind::SIMULATE,
        &[("simulation.json".to_string(), json)],
    )?;
    let collisions = report.collision_count.unwrap_or(0);
    if report.gouge.count > 0 || !report.rapids_through_material.is_empty() || collisions > 0 {
        let first_collision = report
            .collisions
            .as_ref()
            .and_then(|c| c.first())
            .map_or(String::new(), |c| {
                format!(", the first at move {} ({:?})", c.move_index, c.body)
            });
        return Err(Error::Verification(format!(
            "{}: {} gouging move(s), the first move {:?}, up to {:.4} mm deep; {} rapid(s) through material{}; {collisions} collision(s){first_collision}",
            report.program,
            report.gouge.count,
            report.gouge.first_move,
            report.gouge.max_depth_mm,
            report.rapids_through_material.len(),
            report
                .rapids_through_material
                .first()
                .map_or(String::new(), |m| format!(", the first move {m}"))
        )));
    }
    Ok(())
}

fn elapsed_ms(t: Instant) -> f64 {
    (t.elapsed().as_secs_f64() * 1e4).round() / 10.0
}

fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}
