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

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use super::output::{OutputKind, write_output_set};
use super::pipeline::Observer;
use super::render;
use crate::error::{Error, JobError, Result};
use crate::geom::{Aabb, MoveKind, Point3, Toolpath, Vector3};
use crate::mesh::io::RawMesh;
use crate::mesh::{Mesh, PrepareOptions, prepare};
use crate::post::read_cl_csv;
use crate::stock::cutter::CuttingBody;
use crate::stock::rest::{Rest, rest_over};
use crate::stock::simulate::{Simulation, SimulationOptions, simulate_with_progress};
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
    /// Reads `box:X0,Y0,Z0,X1,Y1,Z1`, `cylinder:R,Z0,Z1`, `offset:M` or `mesh:FILE` (mm); the
    /// error says what was expected.
    pub fn parse(text: &str) -> std::result::Result<BlankSpec, String> {
        let bad = || {
            format!(
                "`{text}`: expected box:X0,Y0,Z0,X1,Y1,Z1 (X0 < X1, …), cylinder:R,Z0,Z1 (R > 0, \
                 Z0 < Z1), offset:M (M > 0) or mesh:FILE"
            )
        };
        let (kind, value) = text.split_once(':').ok_or_else(bad)?;
        let numbers = || -> std::result::Result<Vec<f64>, String> {
            value
                .split(',')
                .map(|v| v.trim().parse::<f64>().ok().filter(|x| x.is_finite()))
                .collect::<Option<Vec<f64>>>()
                .ok_or_else(bad)
        };
        match kind.trim() {
            "box" => match numbers()?.as_slice() {
                &[x0, y0, z0, x1, y1, z1] if x0 < x1 && y0 < y1 && z0 < z1 => {
                    Ok(BlankSpec::Box([x0, y0, z0, x1, y1, z1]))
                }
                _ => Err(bad()),
            },
            "cylinder" => match numbers()?.as_slice() {
                &[radius, z0, z1] if radius > 0.0 && z0 < z1 => {
                    Ok(BlankSpec::Cylinder { radius, z0, z1 })
                }
                _ => Err(bad()),
            },
            "offset" => match numbers()?.as_slice() {
                &[m] if m > 0.0 => Ok(BlankSpec::Offset(m)),
                _ => Err(bad()),
            },
            "mesh" if !value.trim().is_empty() => Ok(BlankSpec::Mesh(PathBuf::from(value))),
            _ => Err(bad()),
        }
    }

    /// The spec as a user writes it (a mesh by its file name).
    pub fn describe(&self) -> String {
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

/// How the program text is read.
#[derive(Clone, Debug, PartialEq)]
pub enum ProgramFormat {
    /// CL data (`cl.csv`, as `plan` writes it): tip and axis in the part frame.
    ClData,
    /// Posted G-code for a table-table A/C machine, read back through its forward kinematics
    /// (`verify`'s model, written apart from the post) with the part clamped at
    /// `part_origin_in_table` (`None`: where `plan` puts it by default, the part's box centre
    /// in X and Y and its bottom on the table).
    TableTableAc {
        part_origin_in_table: Option<[f64; 3]>,
    },
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

/// The colours of the stock's surface by its signed distance `d` to the part (mm, negative
/// inside): red deeper than `band` into the part (a gouge), green within `band`, blue above,
/// light at `band` to dark at `deep` and beyond.
fn distance_colour(d: f64, band: f64, deep: f64) -> [f32; 4] {
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

/// Output files by name, with their bytes.
type Files = Vec<(String, Vec<u8>)>;

/// The stock's surface coloured by its signed distance to the part.
struct ColouredStock {
    /// `stock.glb`.
    glb: Vec<u8>,
    surface: Mesh,
    colours: Vec<[f32; 4]>,
    /// What the colours mean, a line each.
    legend: Vec<String>,
    /// Green within this distance of the part, mm.
    band: f64,
    /// The darkest blue from this much material, mm.
    deep: f64,
}

fn coloured_stock(stock: &Stock, part: &Mesh, tolerance: f64) -> Result<ColouredStock> {
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
    let panel = 600;
    let mut canvas = render::Canvas::new(2 * panel, panel + 40);
    for (k, (eye, up)) in render::VIEWS.iter().enumerate() {
        let view = render::View {
            towards_eye: Vector3::from(*eye),
            up: Vector3::from(*up),
        };
        render::draw_mesh(
            &mut canvas,
            (k * panel, 0, panel),
            &surface,
            &colours,
            &view,
        );
    }
    render::legend(
        &mut canvas,
        10,
        panel + 12,
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

pub(crate) fn stock_error(e: StockError) -> Error {
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
    match spec {
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
    let (toolpath, lines, format) = match &options.format {
        ProgramFormat::ClData => (
            read_cl_csv(cl_text, cl_name).map_err(|e| Error::DataFile {
                file: e.file,
                line: e.line,
                reason: e.reason,
            })?,
            None,
            "cl data; moves are numbered by their row from 0 (the header not counted)".to_string(),
        ),
        ProgramFormat::TableTableAc {
            part_origin_in_table,
        } => {
            let b = part.aabb();
            let origin = part_origin_in_table
                .map(Vector3::from)
                .unwrap_or_else(|| -Vector3::new(b.center().x, b.center().y, b.min.z))
                .map(|v| v + 0.0);
            let machine = crate::verify::MachineModel::TableTableAc {
                part_origin_in_table: origin,
            };
            // Moves within a quarter of the tolerance of the control's interpolation.
            let (toolpath, lines) = crate::verify::program_toolpath(
                cl_text,
                &machine,
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
                    "posted g-code, table-table A/C, part origin in table [{}, {}, {}] mm, read back through the machine's forward kinematics; moves are named by their program line",
                    origin.x, origin.y, origin.z
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
