//! `simulate`: a program's CL data run on a blank, checked against the part (issue 19): the
//! blank as a tri-dexel stock, each move's ball-end body removing material, the part as a
//! second model only a gouge may cut, shank and holder against the material
//! (`stock::simulate`). Writes `simulation.json` (with the rest material over the part and the
//! depths of cut), `stock.glb` (the stock left, coloured by its distance to the part) and
//! `stock.png` (the same from two sides, with its legend).
//!
//! The program is CL data or posted G-code read back through the machine's forward kinematics
//! (`verify::program_toolpath`); the cutter is a ball, flat, bull-nose or tapered-ball end
//! mill. The report names only what was checked.

use std::path::Path;
use std::time::Instant;

use serde::Serialize;

pub use super::blank::BlankSpec;
use super::observer::Observer;
use super::output::{OutputKind, write_output_set};
use super::render;
use super::stock_model::{
    CollisionReport, ColouredStock, DepthOfCutReport, EngagementReport, GougeReport, blank_stock,
    closed_part, coloured_stock, cutting_spreads, default_resolution, distance_colour,
    enclosure_warning, stock_error,
};
use crate::error::{Error, JobError, Result};
use crate::mesh::Mesh;
use crate::mesh::io::RawMesh;
use crate::post::read_cl_csv;
use crate::stock::cutter::CuttingBody;
use crate::stock::rest::{Rest, rest_over};
use crate::stock::simulate::{SimulationOptions, simulate_with_progress};
use crate::stock::{DEFAULT_MAX_DEXELS, Stock};

/// How the program text is read.
#[derive(Clone, Debug, PartialEq)]
pub enum ProgramFormat {
    /// CL data (`cl.csv`, as `plan` writes it): tip and axis in the part frame.
    ClData,
    /// A posted program (G-code, or Heidenhain conversational), read back through the
    /// machine's forward kinematics as the verifier models it (written apart from the post;
    /// [`super::setup::posted_program_model`] builds it for a job's machine).
    Posted {
        model: crate::verify::MachineModel,
        /// The machine and the part's place on it, for the report.
        machine: String,
    },
    /// A program posted for a job's machine ([`super::setup::posted_program_model`]): the
    /// part clamped where the job clamps it, the job's tool in the spindle.
    PostedFor(Box<super::config::Job>),
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
    /// How the program is read.
    pub format: ProgramFormat,
    /// The cutter, when not a ball of `tool_diameter` (and no `assembly` is given).
    pub cutter: Option<crate::tool::Cutter>,
}

/// `cutter` with its flutes `flute_length` long.
fn with_flute_length(cutter: crate::tool::Cutter, flute_length: f64) -> crate::tool::Cutter {
    use crate::tool::Cutter;
    match cutter {
        Cutter::Ball { diameter, .. } => Cutter::Ball {
            diameter,
            flute_length,
        },
        Cutter::Flat { diameter, .. } => Cutter::Flat {
            diameter,
            flute_length,
        },
        Cutter::BullNose {
            diameter,
            corner_radius,
            ..
        } => Cutter::BullNose {
            diameter,
            corner_radius,
            flute_length,
        },
        Cutter::TaperedBall {
            diameter,
            taper_deg,
            ..
        } => Cutter::TaperedBall {
            diameter,
            taper_deg,
            flute_length,
        },
    }
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
            format: ProgramFormat::ClData,
            cutter: None,
        }
    }
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
    /// How the program was read.
    pub program_format: String,
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
    pub depth_of_cut: DepthOfCutReport,
    /// Material left over the part's surface (area-weighted over its triangles, good to
    /// about half the resolution).
    pub rest: Rest,
    pub stock: StockReport,
    /// What the colours of `stock.glb` and `stock.png` mean.
    pub colours: Vec<String>,
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
    pub rest: f64,
    pub pictures: f64,
}

/// A finished simulation: the report, the stock left and the part it was checked against.
#[derive(Clone, Debug)]
pub struct SimulationRun {
    pub report: SimulationReport,
    pub stock: Stock,
    pub part: Mesh,
    /// `stock.glb` and `stock.png`.
    pub pictures: Files,
}

/// Output files by name, with their bytes.
type Files = Vec<(String, Vec<u8>)>;

/// `stock.glb` and `stock.png`, and the legend of their colours.
fn pictures(stock: &Stock, part: &Mesh, tolerance: f64) -> Result<(Files, Vec<String>)> {
    let ColouredStock {
        glb,
        surface,
        colours,
        legend,
        band,
        deep,
    } = coloured_stock(stock, part, tolerance)?;
    let mut canvas = render::two_views(&surface, &colours);
    render::legend(
        &mut canvas,
        10,
        render::PANEL + 12,
        &[
            (
                distance_colour(-2.0 * band, band, deep),
                format!("<-{band:.2}mm"),
            ),
            (distance_colour(0.0, band, deep), format!("+-{band:.2}mm")),
            (
                distance_colour(band * 1.0001, band, deep),
                format!(">{band:.2}mm"),
            ),
            (distance_colour(deep, band, deep), format!(">{deep:.2}mm")),
        ],
    );
    let png = canvas
        .png()
        .map_err(|e| Error::Internal(format!("stock.png: {e}")))?;
    Ok((
        vec![("stock.glb".into(), glb), ("stock.png".into(), png)],
        legend,
    ))
}

/// Runs the program `cl_text` (named `cl_name`; CL data or posted G-code, as
/// `options.format` says) on the blank, against the part.
pub fn simulate_program(
    raw: &RawMesh,
    part_name: &str,
    cl_text: &str,
    cl_name: &str,
    options: &SimulateOptions,
    observer: &dyn Observer,
) -> Result<SimulationRun> {
    // The cutter: the job's, or the one given, or a ball of the given diameter; the flute
    // length given replaces its own.
    let mut cutter = match (&options.assembly, &options.cutter) {
        (Some(tool), _) => tool.cutter,
        (None, Some(cutter)) => *cutter,
        (None, None) => crate::tool::Cutter::Ball {
            diameter: options.tool_diameter,
            flute_length: 3.0 * options.tool_diameter,
        },
    };
    if let (None, Some(f)) = (&options.assembly, options.flute_length) {
        cutter = with_flute_length(cutter, f);
    }
    cutter.validate().map_err(|e| {
        Error::JobFile(JobError::Invalid {
            key: "tool".into(),
            reason: e.to_string(),
        })
    })?;
    let (d, flutes) = (cutter.diameter(), cutter.flute_length());
    let non_cutting: Vec<crate::tool::Body> = options
        .assembly
        .as_ref()
        .map(|tool| SimulationOptions::for_tool(tool, options.tolerance).non_cutting)
        .unwrap_or_default();
    if !(d.is_finite() && d > 0.0 && flutes.is_finite() && flutes >= 0.5 * d) {
        return Err(Error::JobFile(JobError::Invalid {
            key: "tool".into(),
            reason: format!(
                "a cutter of {d} mm with {flutes} mm flutes: the diameter must be > 0 and the flutes at least the radius"
            ),
        }));
    }
    if !(options.tolerance.is_finite() && options.tolerance >= 0.0 && options.tolerance < 0.5 * d) {
        return Err(Error::JobFile(JobError::Invalid {
            key: "tolerance".into(),
            reason: format!(
                "= {}: must be ≥ 0 mm and below the cutter's radius",
                options.tolerance
            ),
        }));
    }
    let part = closed_part(raw, part_name)?;
    let posted = match &options.format {
        ProgramFormat::ClData => None,
        ProgramFormat::Posted { model, machine } => Some((model.clone(), machine.clone())),
        ProgramFormat::PostedFor(job) => Some(super::setup::posted_program_model(
            job,
            &part,
            job.tool.assembly().id,
        )?),
    };
    let (toolpath, lines, format) = match posted {
        None => (
            read_cl_csv(cl_text, cl_name).map_err(|e| Error::DataFile {
                file: e.file,
                line: e.line,
                reason: e.reason,
            })?,
            None,
            "cl data; moves are numbered by their row from 0 (the header not counted)".to_string(),
        ),
        Some((model, machine)) => {
            // Moves within a quarter of the tolerance of the control's interpolation.
            let (toolpath, lines) = crate::verify::program_toolpath(
                cl_text,
                &model,
                0.25 * options.tolerance.max(1e-4),
            )
            .map_err(|e| Error::DataFile {
                file: cl_name.to_string(),
                line: e.line,
                reason: e.reason,
            })?;
            (
                toolpath,
                Some(lines),
                format!(
                    "posted program, {machine}, read back through the machine's forward \
                     kinematics; moves are named by their program line"
                ),
            )
        }
    };
    let spacing = match options.resolution {
        Some(r) if r.is_finite() && r > 0.0 => r,
        Some(r) => {
            return Err(Error::JobFile(JobError::Invalid {
                key: "resolution".into(),
                reason: format!("= {r}: must be a positive number of mm"),
            }));
        }
        None => default_resolution(&part),
    };
    let t = Instant::now();
    let mut stock = blank_stock(
        &part,
        &options.blank,
        &options.units,
        spacing,
        options.max_dexels,
    )?;
    let blank_ms = elapsed_ms(t);
    let mut warnings = raw.warnings.clone();
    warnings.extend(enclosure_warning(&stock, &part));
    let volume_before = stock.volume();
    let body = CuttingBody::of(&cutter);
    let t = Instant::now();
    observer.stage("simulate", toolpath.moves.len() as u64);
    let reported = std::sync::atomic::AtomicUsize::new(0);
    let sim = simulate_with_progress(
        &mut stock,
        &part,
        &toolpath,
        &body,
        &SimulationOptions {
            tolerance: options.tolerance,
            max_dexels: options.max_dexels,
            non_cutting: non_cutting.clone(),
        },
        &|done| {
            let before = reported.swap(done, std::sync::atomic::Ordering::Relaxed);
            for _ in before..done {
                observer.advance();
            }
        },
    )
    .map_err(stock_error)?;
    let simulate_ms = elapsed_ms(t);
    observer.stage("rest material", 0);
    let t = Instant::now();
    // Walk out as far as the stock can reach: its box's diagonal.
    let part_model =
        Stock::from_mesh(&part, stock.spacing(), options.max_dexels).map_err(stock_error)?;
    let rest = rest_over(&stock, &part, &part_model, stock.bounds().diagonal());
    let rest_ms = elapsed_ms(t);
    observer.stage("stock pictures", 0);
    let t = Instant::now();
    let (pictures, colours) = pictures(&stock, &part, options.tolerance)?;
    let pictures_ms = elapsed_ms(t);
    observer.finish();
    let (engagement, depth_of_cut) = cutting_spreads(&sim, &toolpath);
    // Posted programs name a move by its line (a block may be several moves).
    let label = |k: usize| lines.as_ref().map_or(k, |l| l[k]);
    let mut rapids: Vec<usize> = sim
        .rapids_through_material
        .iter()
        .map(|&k| label(k))
        .collect();
    rapids.dedup();
    let report = SimulationReport {
        wavemill_version: env!("CARGO_PKG_VERSION"),
        part: file_name(Path::new(part_name)),
        program: file_name(Path::new(cl_name)),
        program_format: format,
        tool: options.assembly.as_ref().map_or_else(
            || format!("{} (flutes {flutes} mm)", cutter.describe()),
            |t| t.describe(),
        ),
        tolerance_mm: options.tolerance,
        moves: toolpath.moves.len(),
        removed_volume_mm3: sim.removed_volume_mm3,
        gouge: GougeReport {
            count: sim.gouge.count,
            max_depth_mm: sim.gouge.max_depth_mm,
            volume_mm3: sim.gouge.volume_mm3,
            first_move: sim.gouge.first_move.map(label),
        },
        rapids_through_material: rapids,
        collision_count: (!non_cutting.is_empty()).then_some(sim.collisions.len()),
        collisions: (!non_cutting.is_empty()).then(|| {
            sim.collisions
                .iter()
                .take(1000)
                .map(|c| CollisionReport {
                    move_index: label(c.move_index),
                    body: c.role,
                    depth_mm: c.depth_mm,
                    at: [c.at.x, c.at.y, c.at.z],
                })
                .collect()
        }),
        air_cut_fraction: sim.air_cut_fraction,
        engagement,
        depth_of_cut,
        rest,
        colours,
        stock: StockReport {
            blank: options.blank.describe(),
            resolution_mm: spacing,
            dexel_lines: stock.line_count(),
            volume_before_mm3: volume_before,
            volume_after_mm3: stock.volume(),
        },
        checked: {
            let mut checked = vec![
                "material removed by the cutter's cutting body (flutes included)",
                "gouges: the body deeper into the part than the tolerance",
                "rapids through material",
            ];
            if !non_cutting.is_empty() {
                checked.push("shank, neck and holder against the material (collisions)");
            }
            checked.push("rest material over the part's surface");
            checked.push("depths of cut (axial and radial) of every cutting move");
            checked
        },
        warnings,
        timings_ms: options.timings.then_some(Timings {
            blank: blank_ms,
            simulate: simulate_ms,
            rest: rest_ms,
            pictures: pictures_ms,
        }),
    };
    Ok(SimulationRun {
        report,
        stock,
        part,
        pictures,
    })
}

/// Writes `simulation.json`, `stock.glb` and `stock.png` into `dir` (replacing an earlier
/// run's, all or none); then, if the program gouges, rapids through material or touches it
/// with a non-cutting body, fails verification (exit 3) saying so.
pub fn write_simulation(dir: &Path, run: &SimulationRun) -> Result<()> {
    let report = &run.report;
    let json = (serde_json::to_string_pretty(report)
        .map_err(|e| Error::Internal(format!("simulation.json: {e}")))?
        + "\n")
        .into_bytes();
    let mut files = vec![("simulation.json".to_string(), json)];
    files.extend(run.pictures.iter().cloned());
    write_output_set(dir, &OutputKind::SIMULATE, &files)?;
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
