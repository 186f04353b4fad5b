//! `wavemill rough`: layer roughing of a part from its blank with a library tool, down to the
//! part's verified offset shape S₀ (the part plus an allowance), 3-axis ([`crate::rough`]).
//!
//! What is written is what is checked: the program is posted for a 3-axis machine, read back
//! from the G-code as the control would run it, checked against S₀ exactly
//! ([`crate::rough::check`]) and run on a tri-dexel model of the blank with the tool's whole
//! assembly ([`crate::stock::simulate`]): gouges into the part, rapids through material, and
//! the shank or holder touching it fail the run (exit 3, only `rough.json` written).

use std::time::Instant;

use serde::Serialize;

use super::blank::BlankSpec;
use super::offsets::stock_shapes;
use super::output::{OutputKind, write_output_set};
use super::rough_stages::{
    ToolRoughing, cl_csv_of, first_rougher, layer_blank, next_rougher, rough_with_tool,
    split_at_tool_changes,
};
use super::stock_model::{
    CollisionReport, blank_stock, default_resolution, stock_error, stock_model_glb,
};
use crate::error::{Error, Result};
use crate::mesh::io::RawMesh;
use crate::post::{
    GcodeOptions, GcodeWriter, LineariseOptions, ProgramHeader, ProgramSink, ThreeAxis,
};
use crate::rough::boxes::box_clearance;
use crate::rough::check::{OvercutReport, overcuts};
use crate::rough::{LayerReport, NotReached, RoughingFeeds, RoughingTool};
use crate::stock::cutter::CuttingBody;
use crate::stock::rest::{Rest, rest_over};
use crate::stock::simulate::{SimulationOptions, simulate};
use crate::stock::{DEFAULT_MAX_DEXELS, Stock};
use crate::tool::{ToolAssembly, ToolLibrary};
use crate::verify::{MachineModel, program_toolpath};

/// What `rough` is asked to do.
#[derive(Clone, Debug, PartialEq)]
pub struct RoughOptions {
    /// Material S₀ leaves on the part, mm.
    pub allowance: f64,
    /// The direction in the part file that points up the spindle (the part's axis for an
    /// impeller); the part is turned so that it becomes +Z, and the program is in that frame.
    /// `None`: +Z.
    pub up: Option<[f64; 3]>,
    /// The blank; `None`: a cylinder about the part's vertical axis, `margin` mm wider than the
    /// part and 1 mm above it, standing on the part's lowest point.
    pub blank: Option<BlankSpec>,
    pub margin: f64,
    /// The library tool to rough with; `None`: the largest flat or bull-nose end mill, the
    /// first that reaches the floor if any does.
    pub tool_id: Option<u32>,
    /// How many smaller end mills rest-rough after it, each only where material stands.
    pub rest_tools: usize,
    /// The holder stays this far above the blank, mm.
    pub holder_margin: f64,
    pub spindle_rpm: u32,
    pub feeds: RoughingFeeds,
    /// Distance between dexel lines of the stock model, mm; `None`: the part's default.
    pub resolution: Option<f64>,
    /// Chord and post tolerance, and the depth a touch must exceed to count, mm.
    pub tolerance: f64,
    /// Feeds from each move's engagement, to hold a cutting force ([`crate::feed`]); `None`:
    /// the programmed feeds throughout.
    pub feed_control: Option<crate::feed::CuttingModel>,
    /// Equal layers at the largest depth of cut, no extra plane at the flats: with one tool
    /// and no feed control, the conventional z-level roughing to compare against.
    pub uniform_layers: bool,
    /// The largest depth of cut of every tool, mm; `None`: each tool's radius.
    pub max_depth: Option<f64>,
    /// The smallest depth of cut, mm: thinner layers are merged upward; `None`: a fifth of
    /// each tool's radius.
    pub min_depth: Option<f64>,
    /// Widest radial engagement of a pass, as a share of the tool's diameter (1: every pass
    /// straight).
    pub max_engagement: f64,
    /// The planner of each layer's passes.
    pub layer_paths: crate::rough::LayerPaths,
    /// What the layers stop at.
    pub bound: LayerBound,
}

/// What the layers of `rough` stop at.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum LayerBound {
    /// The part's verified offset shape at the allowance.
    #[default]
    OffsetShape,
    /// The part's own mesh (no allowance): a part read from IGES is its surfaces within the
    /// tessellation's tolerance, so this is slicing the surfaces themselves.
    Part,
    /// Seed 002's convex-hull boxes of the Bézier patches of these faces (the part's, as read
    /// from IGES, in the file's frame), each grown by the allowance.
    HullBoxes {
        surfaces: std::sync::Arc<super::cad_part::PartSurfaces>,
        /// Boxes wider than this are split before the layers, mm; `f64::INFINITY`: only the
        /// seed's splits for thick layers.
        max_box_width: f64,
        /// How the planes at the box tops become layers.
        merge: crate::rough::boxes::LayerMerge,
    },
}

impl LayerBound {
    /// The name in reports.
    pub fn name(&self) -> &'static str {
        match self {
            LayerBound::OffsetShape => "offset-shape",
            LayerBound::Part => "part",
            LayerBound::HullBoxes { .. } => "hull-boxes",
        }
    }
}

/// What the convex-hull boxes of a `hull-boxes` roughing were, and their own check.
#[derive(Clone, Debug, Serialize)]
pub struct HullBoxesReport {
    pub faces: usize,
    /// Bézier patches of the surfaces kept (before any split for the layers), and those left
    /// out as wholly outside their faces' trims.
    pub patches: usize,
    pub trimmed_away: usize,
    /// Points of the untrimmed faces' surfaces, evaluated on their own, each found in a box
    /// of its face.
    pub enclosure: crate::cad::boxes::Enclosure,
    /// Every vertex of the part's tessellation found within twice its tolerance of a box of
    /// its face.
    pub mesh_enclosure: crate::cad::boxes::Enclosure,
}

impl Default for RoughOptions {
    fn default() -> Self {
        RoughOptions {
            allowance: 0.5,
            up: None,
            blank: None,
            margin: 2.0,
            tool_id: None,
            rest_tools: 1,
            holder_margin: 2.0,
            spindle_rpm: 8000,
            feeds: RoughingFeeds {
                cut: 2000.0,
                entry: 800.0,
                rapid: 15000.0,
            },
            resolution: None,
            tolerance: 0.01,
            feed_control: Some(crate::feed::CuttingModel::default()),
            uniform_layers: false,
            max_depth: None,
            min_depth: None,
            max_engagement: 0.5,
            layer_paths: crate::rough::LayerPaths::default(),
            bound: LayerBound::default(),
        }
    }
}

/// A tool `rough` used and why.
#[derive(Clone, Debug, Serialize)]
pub struct RoughToolReport {
    pub id: u32,
    pub name: String,
    pub description: String,
    pub chosen: String,
    pub planning: RoughingTool,
}

/// What the tri-dexel run of one tool's posted moves found.
#[derive(Clone, Debug, Serialize)]
pub struct RoughStockReport {
    pub removed_volume_mm3: f64,
    pub volume_after_mm3: f64,
    pub air_cut_fraction: f64,
    pub gouges: usize,
    pub rapids_through_material: usize,
    pub collisions: usize,
    /// The first collisions (move numbers within this tool's read-back moves).
    pub first_collisions: Vec<CollisionReport>,
    /// Material left over the part after this tool.
    pub rest: Rest,
}

/// One tool's share of the program: its layers, its moves as read back, their checks and
/// what they did to the stock.
#[derive(Clone, Debug, Serialize)]
pub struct RoughToolRun {
    pub tool: RoughToolReport,
    /// `blank` for the first tool, `rest` for the ones after it (only where material stands).
    pub material: &'static str,
    /// What feed control made of the programmed feeds ([`crate::feed`]); `None` when off.
    pub feed_control: Option<crate::feed::FeedReport>,
    pub layers: Vec<LayerReport>,
    pub not_reached: Option<NotReached>,
    pub moves: usize,
    pub cutting_length_mm: f64,
    /// Every move's length, rapids included, mm.
    pub path_length_mm: f64,
    /// At the programmed feeds and the rapid rate, s.
    pub estimated_time_s: f64,
    /// This tool's moves as read back from the G-code, checked against S₀ (or the boxes) and
    /// the part.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub overcut_vs_shape: Option<OvercutReport>,
    /// With `hull-boxes`: how the layers were made, and the moves as read back against every
    /// box (the seed's guarantee: no cutter position inside any box).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub box_layers: Option<crate::rough::boxes::BoxSummary>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub overcut_vs_boxes: Option<crate::rough::boxes::BoxClearance>,
    pub overcut_vs_part: OvercutReport,
    pub stock: RoughStockReport,
}

/// `rough.json`.
#[derive(Clone, Debug, Serialize)]
pub struct RoughReport {
    pub wavemill_version: &'static str,
    pub part: String,
    pub blank: String,
    pub allowance_mm: f64,
    /// Equal layers, no planes at the flats (the conventional baseline).
    pub uniform_layers: bool,
    /// The largest depth of cut asked for, mm (`None`: each tool's radius).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_depth_mm: Option<f64>,
    /// The widest radial engagement of a pass, as a share of the diameter.
    pub max_engagement: f64,
    /// The planner of each layer's passes.
    pub layer_paths: crate::rough::LayerPaths,
    /// What the layers stop at: `offset-shape`, `part` or `hull-boxes`.
    pub bound: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hull_boxes: Option<HullBoxesReport>,
    /// Triangles of the offset shape or part the layers stop at (0 for boxes).
    pub shape_triangles: usize,
    pub resolution_mm: f64,
    pub blank_volume_mm3: f64,
    /// One per tool, in machining order.
    pub tools: Vec<RoughToolRun>,
    pub estimated_time_s: f64,
    pub volume_after_mm3: f64,
    /// `rough-boxes --compare`: the convex-hull-box route and the uniform one, side by side.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub comparison: Option<Vec<SlicingRow>>,
    pub timings_ms: Option<std::collections::BTreeMap<&'static str, f64>>,
}

/// One route of the comparison.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SlicingRow {
    /// `hull-boxes` (seed 002) or `uniform` (equal layers to the part's sections).
    pub route: &'static str,
    pub layers: usize,
    /// Layers at a box top or a flat of the part.
    pub layers_at_tops: usize,
    pub moves: usize,
    pub cutting_length_mm: f64,
    /// Every move, rapids included, mm.
    pub path_length_mm: f64,
    pub estimated_time_s: f64,
    /// Material left on the part after the program, on the tri-dexel model, mm³.
    pub material_left_mm3: f64,
    /// How thick it stands on the part: mean and largest, mm.
    pub rest_mean_mm: f64,
    pub rest_max_mm: f64,
    /// Least distance between the tool and the part's mesh, mm.
    pub min_clearance_to_part_mm: f64,
}

/// What `rough` produced.
pub struct RoughOutput {
    pub report: RoughReport,
    pub gcode: String,
    pub cl_csv: String,
    pub stock_glb: Vec<u8>,
    /// Why the program must not be run, if it must not.
    pub failure: Option<String>,
}

/// Plans, posts, reads back and checks layer roughing of `raw` (in mm) from its blank with
/// tools of `library`: the first from the blank, each further (smaller) one only where the
/// stock the ones before it leave still holds material.
pub fn rough(
    raw: &RawMesh,
    part_name: &str,
    units: &str,
    library: &ToolLibrary,
    options: &RoughOptions,
) -> Result<RoughOutput> {
    let mut timings = std::collections::BTreeMap::new();
    let t = Instant::now();
    let upright = match options.up {
        Some(up) => {
            let axis = super::config::unit_direction(up)
                .ok_or_else(|| Error::Usage(format!("up must be a non-zero vector, got {up:?}")))?;
            super::setup::turned_upright(&raw.mesh, &axis)
        }
        None => raw.mesh.clone(),
    };
    let (part, _) =
        crate::mesh::prepare(&upright, &Default::default()).map_err(|e| Error::Mesh {
            file: part_name.to_string(),
            reason: e.to_string(),
        })?;
    let floor = part.aabb().min.z;
    let spec = match &options.blank {
        Some(spec) => spec.clone(),
        None => BlankSpec::EnclosingCylinder {
            margin: options.margin,
        },
    }
    .resolved(&part);
    let blank = layer_blank(&spec, &part)?;
    let sequence = choose_tools(
        library,
        options.tool_id,
        options.rest_tools,
        blank.top - floor,
        options.holder_margin,
    )?;
    let spacing = options
        .resolution
        .unwrap_or_else(|| default_resolution(&part));
    timings.insert("prepare", ms(t));

    let t = Instant::now();
    let frame = match options.up {
        Some(up) => super::config::unit_direction(up)
            .map(|axis| super::setup::upright_rotation(&axis))
            .unwrap_or_else(nalgebra::Rotation3::identity),
        None => nalgebra::Rotation3::identity(),
    };
    let (shape, hull_boxes) = match &options.bound {
        LayerBound::OffsetShape => {
            let shapes = stock_shapes(&part, &Default::default(), &[options.allowance])?;
            let shape = shapes
                .into_iter()
                .next()
                .ok_or_else(|| Error::Internal("no offset shape was built".into()))?
                .1
                .mesh;
            (Some(shape), None)
        }
        LayerBound::Part => (Some(part.clone()), None),
        LayerBound::HullBoxes { surfaces, .. } => {
            let faces = &surfaces.faces;
            let boxes = crate::cad::boxes::HullBoxes::of_faces(faces, frame)
                .map_err(|e| Error::Usage(format!("{part_name}: convex-hull boxes: {e}")))?;
            if surfaces.face_of_triangle.len() != raw.mesh.triangles.len() {
                return Err(Error::Internal(format!(
                    "{part_name}: {} triangles named by face for a mesh of {}",
                    surfaces.face_of_triangle.len(),
                    raw.mesh.triangles.len()
                )));
            }
            let enclosure = boxes.enclosure(faces, 4);
            let mesh_enclosure = boxes.mesh_enclosure(
                &raw.mesh,
                &surfaces.face_of_triangle,
                2.0 * surfaces.tolerance,
            );
            for (what, e) in [("surface", &enclosure), ("mesh", &mesh_enclosure)] {
                if e.outside > 0 {
                    return Err(Error::Internal(format!(
                        "{part_name}: {} of {} {what} points lie outside their face's \
                         convex-hull boxes, the farthest by {:.3e} mm",
                        e.outside, e.samples, e.worst_mm
                    )));
                }
            }
            let report = HullBoxesReport {
                faces: faces.len(),
                patches: boxes.patches.len(),
                trimmed_away: boxes.trimmed_away,
                enclosure,
                mesh_enclosure,
            };
            (None, Some((boxes, report)))
        }
    };
    let guard = match (&shape, &hull_boxes) {
        (Some(shape), _) => crate::rough::Guard::Shape(shape),
        (None, Some((boxes, _))) => crate::rough::Guard::HullBoxes {
            boxes,
            allowance: options.allowance,
            max_box_width: match &options.bound {
                LayerBound::HullBoxes { max_box_width, .. } => *max_box_width,
                _ => f64::INFINITY,
            },
            merge: match &options.bound {
                LayerBound::HullBoxes { merge, .. } => *merge,
                _ => Default::default(),
            },
        },
        (None, None) => return Err(Error::Internal("roughing has nothing to stop at".into())),
    };
    timings.insert(
        if hull_boxes.is_some() {
            "hull_boxes"
        } else {
            "offset_shape"
        },
        ms(t),
    );

    // Plan tool by tool on a stock model: each later tool from what the earlier ones leave.
    let t = Instant::now();
    let mut planning_stock = blank_stock(&part, &spec, units, spacing, DEFAULT_MAX_DEXELS)?;
    let mut planned = Vec::with_capacity(sequence.len());
    for (k, (assembly, _)) in sequence.iter().enumerate() {
        let from_blank = k == 0;
        let planned_tool = rough_with_tool(
            guard,
            &blank,
            assembly,
            &ToolRoughing {
                holder_margin: options.holder_margin,
                floor,
                feeds: &options.feeds,
                tolerance: options.tolerance,
                feed_control: options
                    .feed_control
                    .map(|model| (model, f64::from(options.spindle_rpm))),
                uniform_layers: options.uniform_layers,
                max_depth: options.max_depth,
                max_engagement: options.max_engagement,
                paths: options.layer_paths,
                min_depth: options.min_depth,
            },
            &mut planning_stock,
            from_blank,
        )
        .map_err(|e| Error::Usage(format!("{part_name}: roughing with T{}: {e}", assembly.id)))?;
        if from_blank && !planned_tool.cuts() {
            return Err(Error::NothingToCut(format!(
                "{part_name}: the blank `{}` holds no material outside the part's offset \
                 shape that the tool can reach",
                spec.describe()
            )));
        }
        let cutting_length = planned_tool.cutting_length();
        let super::rough_stages::ToolLayers {
            tool,
            layers,
            feed_control,
        } = planned_tool;
        planned.push((tool, layers, feed_control, cutting_length));
    }
    timings.insert("layers", ms(t));

    // One program, a tool change before each tool after the first.
    let t = Instant::now();
    let header = |assembly: &ToolAssembly| ProgramHeader {
        program_name: "wavemill layer roughing".into(),
        part_name: part_name.to_string(),
        tool_description: vec![assembly.describe()],
        tool_number: assembly.id,
        spindle_rpm: options.spindle_rpm,
        coolant: true,
        control_point_mm: None,
        comments: vec![format!(
            "roughing to the part + {} mm from {}, 3-axis, work offset at the part's origin",
            options.allowance,
            spec.describe()
        )],
    };
    let linearise = LineariseOptions {
        tolerance_mm: options.tolerance,
        ..Default::default()
    };
    let mut writer = GcodeWriter::new(&ThreeAxis, GcodeOptions::default());
    let mut all_moves = Vec::new();
    for (k, ((assembly, _), (_, layers, _, _))) in sequence.iter().zip(&planned).enumerate() {
        let blocks = crate::post::linearise_opt(&ThreeAxis, &layers.toolpath, &linearise)
            .map_err(|e| Error::Internal(format!("posting the roughing program: {e}")))?;
        if k == 0 {
            writer.begin(&header(assembly));
        } else {
            writer.tool_change(&header(assembly));
        }
        for (m, j) in &blocks {
            writer.motion(m, j);
        }
        all_moves.extend(layers.toolpath.moves.iter().map(|m| (assembly.id, *m)));
    }
    writer.end();
    let gcode = writer.into_string();
    let cl_csv = cl_csv_of(&all_moves);
    let (posted, lines) = program_toolpath(&gcode, &MachineModel::ThreeAxis, options.tolerance)
        .map_err(|e| {
            Error::Internal(format!(
                "the posted roughing program does not read back: {e}"
            ))
        })?;
    let sections = split_at_tool_changes(&gcode, &posted, &lines, sequence.len())?;
    timings.insert("post", ms(t));

    // Check each tool's moves as read back, and run them on a fresh blank in order.
    let t = Instant::now();
    let mut stock = blank_stock(&part, &spec, units, spacing, DEFAULT_MAX_DEXELS)?;
    let blank_volume = stock.volume();
    let part_model = Stock::from_mesh(&part, spacing, DEFAULT_MAX_DEXELS).map_err(stock_error)?;
    // Rounding to the posted decimals may bring a move 5e-5 mm nearer; the check allows that.
    let rounding = 1e-4;
    let mut runs = Vec::with_capacity(sequence.len());
    let mut problems = Vec::new();
    for (((assembly, chosen), (tool, layers, feed_control, cutting_length)), section) in
        sequence.iter().zip(planned).zip(sections)
    {
        let overcut_vs_shape = shape
            .as_ref()
            .map(|shape| overcuts(shape, &section, tool.radius, rounding));
        let overcut_vs_boxes = layers.hull_boxes.as_ref().map(|planned| {
            box_clearance(
                &section,
                &planned.boxes,
                tool.radius,
                rounding,
                BOX_CHECK_REACH,
            )
        });
        let overcut_vs_part = overcuts(&part, &section, tool.radius, rounding);
        let sim = simulate(
            &mut stock,
            &part,
            &section,
            &CuttingBody::of(&assembly.cutter),
            &SimulationOptions::for_tool(assembly, options.tolerance),
        )
        .map_err(stock_error)?;
        let rest = rest_over(&stock, &part, &part_model, stock.bounds().diagonal());
        let label = format!("T{}", assembly.id);
        if let Some(o) = overcut_vs_shape.as_ref().and_then(|o| o.overcuts.first()) {
            problems.push(format!(
                "{label}: move(s) into the {}, the first by {:.4} mm",
                options.bound.name(),
                o.depth_mm
            ));
        }
        if let Some(c) = overcut_vs_boxes.as_ref().filter(|c| c.violation_count > 0) {
            problems.push(format!(
                "{label}: {} move(s) into a convex-hull box, by up to {:.4} mm",
                c.violation_count, -c.min_clearance_mm
            ));
        }
        if let Some(o) = overcut_vs_part.overcuts.first() {
            problems.push(format!(
                "{label}: move(s) into the part, the first by {:.4} mm",
                o.depth_mm
            ));
        }
        if sim.gouge.count > 0 {
            problems.push(format!("{label}: {} gouging move(s)", sim.gouge.count));
        }
        if !sim.rapids_through_material.is_empty() {
            problems.push(format!(
                "{label}: {} rapid(s) through material",
                sim.rapids_through_material.len()
            ));
        }
        if let Some(c) = sim.collisions.first() {
            problems.push(format!(
                "{label}: {} move(s) with the shank or holder in material (the first a {:?})",
                sim.collisions.len(),
                c.role
            ));
        }
        let moves = &layers.toolpath.moves;
        runs.push(RoughToolRun {
            tool: RoughToolReport {
                id: assembly.id,
                name: assembly.name.clone(),
                description: assembly.describe(),
                chosen: chosen.clone(),
                planning: tool,
            },
            material: if runs.is_empty() { "blank" } else { "rest" },
            feed_control,
            layers: layers.layers,
            not_reached: layers.not_reached,
            moves: moves.len(),
            cutting_length_mm: cutting_length,
            path_length_mm: moves
                .windows(2)
                .map(|w| (w[1].pose.tip - w[0].pose.tip).norm())
                .sum(),
            estimated_time_s: moves
                .windows(2)
                .map(|w| 60.0 * (w[1].pose.tip - w[0].pose.tip).norm() / w[1].feed)
                .sum(),
            overcut_vs_shape,
            box_layers: layers.hull_boxes.as_ref().map(|b| b.summary.clone()),
            overcut_vs_boxes,
            overcut_vs_part,
            stock: RoughStockReport {
                removed_volume_mm3: sim.removed_volume_mm3,
                volume_after_mm3: stock.volume(),
                air_cut_fraction: sim.air_cut_fraction,
                gouges: sim.gouge.count,
                rapids_through_material: sim.rapids_through_material.len(),
                collisions: sim.collisions.len(),
                first_collisions: sim
                    .collisions
                    .iter()
                    .take(10)
                    .map(|c| CollisionReport {
                        move_index: c.move_index,
                        body: c.role,
                        depth_mm: c.depth_mm,
                        at: [c.at.x, c.at.y, c.at.z],
                    })
                    .collect(),
                rest,
            },
        });
    }
    let stock_glb = stock_model_glb(&stock, &part, options.tolerance)?;
    timings.insert("stock", ms(t));
    let failure = (!problems.is_empty()).then(|| format!("{part_name}: {}", problems.join("; ")));
    let report = RoughReport {
        wavemill_version: env!("CARGO_PKG_VERSION"),
        part: part_name.to_string(),
        blank: spec.describe(),
        allowance_mm: options.allowance,
        uniform_layers: options.uniform_layers,
        max_depth_mm: options.max_depth,
        max_engagement: options.max_engagement,
        layer_paths: options.layer_paths,
        bound: options.bound.name(),
        hull_boxes: hull_boxes.map(|(_, report)| report),
        shape_triangles: shape.as_ref().map_or(0, |s| s.triangles.len()),
        resolution_mm: spacing,
        blank_volume_mm3: blank_volume,
        estimated_time_s: runs.iter().map(|r| r.estimated_time_s).sum(),
        volume_after_mm3: stock.volume(),
        tools: runs,
        comparison: None,
        timings_ms: Some(timings),
    };
    Ok(RoughOutput {
        report,
        gcode,
        cl_csv,
        stock_glb,
        failure,
    })
}

/// The tools to rough with, in order, and why each: the first is `id` if given, else the
/// largest flat or bull-nose end mill of the library, the first of them that reaches `depth`
/// below the blank's top if any does; then up to `rest` smaller ones, each at most 3/4 of the
/// one before it across, preferring those that reach.
fn choose_tools(
    library: &ToolLibrary,
    id: Option<u32>,
    rest: usize,
    depth: f64,
    holder_margin: f64,
) -> Result<Vec<(ToolAssembly, String)>> {
    let mut sequence = vec![first_rougher(library, id, depth, holder_margin)?];
    while sequence.len() <= rest {
        let previous = sequence[sequence.len() - 1].0.cutter.diameter();
        match next_rougher(library, None, previous, depth, holder_margin)? {
            Some(next) => sequence.push(next),
            None => break,
        }
    }
    Ok(sequence)
}

/// How far from a box the check measures the clearance, mm.
const BOX_CHECK_REACH: f64 = 5.0;

fn ms(since: Instant) -> f64 {
    (since.elapsed().as_secs_f64() * 1e4).round() / 10.0
}

/// Writes `rough.nc`, `cl.csv`, `rough.json` and `stock.glb` into `dir`, all or nothing; when
/// the program failed its checks, only `rough.json`, and returns the failure (exit 3); without timings when `timings` is
/// false (byte-identical reports).
pub fn write_rough_outputs(
    dir: &std::path::Path,
    output: &RoughOutput,
    timings: bool,
) -> Result<()> {
    let mut report = output.report.clone();
    if !timings {
        report.timings_ms = None;
    }
    let json = serde_json::to_vec_pretty(&report)
        .map_err(|e| Error::Internal(format!("rough.json: {e}")))?;
    let mut files = vec![("rough.json".to_string(), json)];
    if let Some(problem) = &output.failure {
        write_output_set(dir, &OutputKind::ROUGH, &files)?;
        return Err(Error::Verification(format!(
            "{problem} (see {})",
            dir.join("rough.json").display()
        )));
    }
    files.push(("rough.nc".into(), output.gcode.clone().into_bytes()));
    files.push(("cl.csv".into(), output.cl_csv.clone().into_bytes()));
    files.push(("stock.glb".into(), output.stock_glb.clone()));
    write_output_set(dir, &OutputKind::ROUGH, &files)
}
