//! Layer roughing with a fixed vertical tool axis: the blank cleared down to a shape that
//! encloses the part (a verified offset shape S₀, so roughing can never overcut the part), one
//! 2.5D pocket per layer (DESIGN.md §3.12; seed 002 §4; seed 004 ch. 5, "rough-cuts can be
//! made with the low-resolution models").
//!
//! The stages, each plain data in and out:
//!
//! * [`envelope`] — the shape's top envelope on a grid, exact per cell (seed 002's z-mapped
//!   boxes): a vertical tool outside every box taller than its tip is outside the shape;
//! * [`layers`] — seed 002's non-uniform layers: a slicing plane at each flat of the shape,
//!   layers deeper than the maximum depth of cut subdivided, thinner than the minimum merged;
//! * [`region`] — per layer, the boxes taller than it traced as an outline, and the blank's;
//! * the contour engine ([`crate::contour::contour_parallel`]) clears the blank's section
//!   minus that outline, far side first (a facing layer above the shape is cleared by the
//!   blank's inward offsets);
//! * [`moves`] — the passes as moves: arcs circumscribed (never inside), and every entry into
//!   material ramped along its pass at a bounded angle instead of plunged, as a 2D material map
//!   of the layer tells ([`crate::contour::material::MaterialMap`]); the tool moves between
//!   regions just above the layer when the straight way is clear, else over the blank;
//! * [`boxes`] — the same layers down to seed 002's own model instead of a shape: the
//!   convex-hull boxes of the part's Bézier patches ([`crate::cad::boxes`]), sliced at their
//!   tops, split by de Casteljau where a layer is too thick, and checked on the program;
//! * [`check`] — the program checked against the shape exactly, by code that shares nothing
//!   with the planning.

pub mod boxes;
pub mod check;
pub mod envelope;
pub mod indexed;
pub mod layers;
pub mod moves;
pub mod region;
pub mod rest;
pub mod setups;
pub mod trochoid;

use serde::Serialize;

use crate::contour::geometry::{Contour, Point2, Segment, Shape};
use crate::contour::material::{MaterialMap, Window};
use crate::contour::region::RegionIndex;
use crate::contour::toolpath::{CenterPath, Link, Pass};
use crate::contour::{
    ContourError, MultiresOptions, ParallelOptions, contour_parallel, multires_paths,
};
use crate::geom::{Direction, Move, MoveKind, Point3, ToolPose, Toolpath, Vector3};
use crate::mesh::Mesh;
use crate::stock::Stock;
use crate::stock::cutter::CuttingBody;
use crate::tool::ToolAssembly;
use envelope::TopEnvelope;
pub use layers::{Layer, LayerOptions};

/// What can stop a layer roughing plan.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum RoughError {
    #[error("roughing option `{name}` = {value} is invalid: {reason}")]
    InvalidOption {
        name: &'static str,
        value: f64,
        reason: String,
    },
    #[error("the blank: {0}")]
    Blank(String),
    #[error("layer at z = {z:.3} mm: {error}")]
    Layer {
        z: f64,
        #[source]
        error: ContourError,
    },
}

/// A blank the layers can clear: an upright prism, its outline extruded from `bottom` to
/// `top` (a cylinder or a box).
#[derive(Clone, Debug, PartialEq)]
pub struct Blank {
    pub outline: Shape,
    pub bottom: f64,
    pub top: f64,
}

impl Blank {
    /// A cylinder about the vertical line through `center`.
    pub fn cylinder(center: Point2, radius: f64, bottom: f64, top: f64) -> Blank {
        Blank {
            outline: Shape {
                contours: vec![region::circle(center, radius)],
            },
            bottom,
            top,
        }
    }

    /// An axis-aligned box.
    pub fn cuboid(min: Point3, max: Point3) -> Blank {
        Blank {
            outline: Shape {
                contours: vec![region::rectangle(
                    Point2::new(min.x, min.y),
                    Point2::new(max.x, max.y),
                )],
            },
            bottom: min.z,
            top: max.z,
        }
    }
}

/// What the planner needs of the tool: how wide it is below the holder and how deep it can go.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RoughingTool {
    /// The widest radius of the flutes, neck and shank, mm: the path keeps this far from the
    /// shape, so no part of the tool below the holder can touch it.
    pub radius: f64,
    /// Fluted length, mm: no layer is deeper.
    pub flute_length: f64,
    /// How far below the blank's top the tip may go with the holder still above it by the
    /// margin, mm.
    pub reach: f64,
}

impl RoughingTool {
    /// The roughing view of `tool`, keeping its holder `holder_margin` mm above the blank.
    pub fn of(tool: &ToolAssembly, holder_margin: f64) -> RoughingTool {
        let radius = tool
            .bodies()
            .iter()
            .filter(|b| b.role != crate::tool::BodyRole::Holder)
            .map(|b| b.radius_from.max(b.radius_to))
            .fold(tool.cutter.diameter() / 2.0, f64::max);
        RoughingTool {
            radius,
            flute_length: tool.cutter.flute_length(),
            reach: tool.stickout - holder_margin,
        }
    }
}

/// Feed rates of a roughing program, mm/min.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RoughingFeeds {
    pub cut: f64,
    /// Ramped entries and straight descents into air.
    pub entry: f64,
    /// Rapid rate, for the time estimate of rapids and traverses through air at depth.
    pub rapid: f64,
}

/// Which 2.5D planner clears a layer's region (the contour engine's two methods).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LayerPaths {
    /// Exact offsets of the shape's section at r, r + s, …, far side first
    /// ([`crate::contour::contour_parallel`]).
    #[default]
    Offsets,
    /// Seed 004's multiresolution paths: wavelet-simplified passes within a band of their
    /// level, inside the loose convex hull of the section ([`crate::contour::multires_paths`]).
    Wavelet,
}

/// How the layers are planned.
#[derive(Clone, Debug, PartialEq)]
pub struct RoughingOptions {
    pub layers: LayerOptions,
    /// The planner of each layer's passes.
    pub paths: LayerPaths,
    /// Stepover between passes, mm (0 < s ≤ tool radius, so nothing reachable is left between
    /// passes and the column above every pass is clear: that is what lets the tool drop to
    /// just above a layer).
    pub stepover: f64,
    /// Side of the envelope's cells, mm.
    pub cell: f64,
    /// Steepest descent of a ramped entry, degrees from the horizontal.
    pub ramp_angle_deg: f64,
    /// Longest leg of a ramp along its pass, mm.
    pub max_ramp_leg: f64,
    /// A descent meeting more uncut material than this share of the tool's disc is ramped.
    pub max_plunge_share: f64,
    /// Where a layer lies deeper below the blank's top than the flutes are long, the shank
    /// runs beside material: the path then keeps this much more off the shape, mm (flutes and
    /// shank of one radius would otherwise ride the wall the flutes cut).
    pub shank_clearance: f64,
    /// Height above the layer above, and above the blank for the safe moves, mm.
    pub clearance: f64,
    /// Arcs are replaced by straight moves at most this far outside them, mm.
    pub tolerance: f64,
    /// Radial engagement a pass may take, averaged over a tool radius of travel, mm: heavier
    /// stretches (slots, concave corners) are cut as trochoidal loops where there is room
    /// ([`trochoid`]); `None` cuts every pass straight.
    pub max_engagement: Option<f64>,
    /// Lowest layer (the floor the part stands on, or above it), mm; `None`: the blank's bottom
    /// or the shape's lowest point, whichever is higher.
    pub floor: Option<f64>,
    /// Layers clear rest material only inside this convex counter-clockwise polygon (an
    /// indexed setup's zone, [`indexed`]); `None`: wherever it stands.
    pub zone: Option<Vec<Point2>>,
    /// With a zone: material within this distance of the shape above the layer, mm, is the
    /// skin the surfaces keep (the allowance the layers before left), not rest; it is left.
    pub skin: f64,
    /// The height the holder must stay above, by the tool's reach, mm; `None`: the blank's
    /// top. An indexed setup gives the top of the material its holder can pass over.
    pub holder_top: Option<f64>,
    pub feeds: RoughingFeeds,
}

impl RoughingOptions {
    /// Options for a tool of radius `r`: layers of at most r deep (at least r/5), stepover
    /// 0.8 r, engagement at most r (half the diameter), cells of r/8, 3° ramps.
    pub fn for_radius(r: f64) -> RoughingOptions {
        RoughingOptions {
            paths: LayerPaths::default(),
            layers: LayerOptions {
                max_depth: r,
                min_depth: 0.2 * r,
                flat_band: 0.02 * r,
                flat_area: std::f64::consts::PI * r * r,
            },
            stepover: 0.8 * r,
            cell: r / 8.0,
            ramp_angle_deg: 3.0,
            max_ramp_leg: 8.0 * r,
            max_plunge_share: 0.05,
            shank_clearance: 0.5,
            clearance: 1.0,
            tolerance: 0.01,
            max_engagement: Some(r),
            floor: None,
            zone: None,
            skin: 0.0,
            holder_top: None,
            feeds: RoughingFeeds {
                cut: 2000.0,
                entry: 800.0,
                rapid: 15000.0,
            },
        }
    }

    fn validate(&self, tool: &RoughingTool) -> Result<(), RoughError> {
        let bad = |name, value, reason: &str| {
            Err(RoughError::InvalidOption {
                name,
                value,
                reason: reason.to_string(),
            })
        };
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !(positive(tool.radius) && positive(tool.flute_length)) {
            return bad(
                "tool radius",
                tool.radius,
                "the tool needs a positive radius and flute length",
            );
        }
        if !(positive(self.stepover) && self.stepover <= tool.radius) {
            return bad(
                "stepover",
                self.stepover,
                &format!("must lie in (0, {}] (the tool radius)", tool.radius),
            );
        }
        let l = &self.layers;
        if !(positive(l.max_depth) && l.min_depth >= 0.0 && l.min_depth <= l.max_depth) {
            return bad(
                "max_depth",
                l.max_depth,
                "needs 0 ≤ min_depth ≤ max_depth, max_depth > 0",
            );
        }
        if l.max_depth > tool.flute_length {
            return bad(
                "max_depth",
                l.max_depth,
                &format!("is deeper than the flutes ({} mm)", tool.flute_length),
            );
        }
        if !positive(l.flat_band) || l.flat_area.is_nan() || l.flat_area < 0.0 {
            return bad(
                "flat_band",
                l.flat_band,
                "flats need a positive band and an area ≥ 0",
            );
        }
        if !positive(self.cell) {
            return bad("cell", self.cell, "must be a positive number of mm");
        }
        if !(self.ramp_angle_deg > 0.0 && self.ramp_angle_deg <= 45.0) {
            return bad("ramp_angle_deg", self.ramp_angle_deg, "must lie in (0, 45]");
        }
        if !positive(self.max_ramp_leg) || !(0.0..=1.0).contains(&self.max_plunge_share) {
            return bad(
                "max_ramp_leg",
                self.max_ramp_leg,
                "needs a positive leg and a plunge share in [0, 1]",
            );
        }
        if !(self.shank_clearance >= 0.0 && self.shank_clearance.is_finite()) {
            return bad(
                "shank_clearance",
                self.shank_clearance,
                "must be a finite number of mm ≥ 0",
            );
        }
        if !positive(self.clearance) || !positive(self.tolerance) {
            return bad(
                "clearance",
                self.clearance,
                "clearance and tolerance must be positive",
            );
        }
        if let Some(e) = self.max_engagement
            && !(positive(e) && e <= 2.0 * tool.radius)
        {
            return bad(
                "max_engagement",
                e,
                &format!(
                    "must lie in (0, {}] (the tool's diameter)",
                    2.0 * tool.radius
                ),
            );
        }
        let f = &self.feeds;
        if !(positive(f.cut) && positive(f.entry) && positive(f.rapid)) {
            return bad("feeds", f.cut, "feeds must be positive");
        }
        Ok(())
    }
}

/// What one layer did.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LayerReport {
    #[serde(flatten)]
    pub layer: Layer,
    pub passes: usize,
    /// Entries into material ramped along their pass, and descents made straight (into air, or
    /// onto less than the allowed share of the tool's disc).
    pub ramped_entries: usize,
    pub straight_entries: usize,
    /// Entries that had to go straight down into material (a pass too short to ramp along).
    pub plunges_into_material: usize,
    /// Material area the layer cleared (its 2D map), mm².
    pub cleared_area_mm2: f64,
    /// Widest radial engagement along the passes (averaged over one tool radius of travel),
    /// mm, and at the feed links.
    pub max_engagement_mm: f64,
    /// Where the widest engagement's window ended.
    pub max_engagement_at: [f64; 2],
    pub max_link_engagement_mm: f64,
    pub cut_length_mm: f64,
    /// Stretches of the passes that would have engaged more than the bound, cut as loops,
    /// and their length along the passes (each from a radius before its heavy part), mm.
    #[serde(skip_serializing_if = "is_zero_count")]
    pub looped_stretches: usize,
    #[serde(skip_serializing_if = "is_zero")]
    pub looped_length_mm: f64,
    /// Length of such stretches cut straight for want of room for a loop beside them, mm.
    #[serde(skip_serializing_if = "is_zero")]
    pub heavy_unlooped_mm: f64,
    /// Length of the passes left out because the tool would meet material still standing
    /// above the layer above (rest the layers above could not take), mm.
    #[serde(skip_serializing_if = "is_zero")]
    pub kept_from_material_above_mm: f64,
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

fn is_zero_count(x: &usize) -> bool {
    *x == 0
}

/// Layers the tool cannot reach.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NotReached {
    /// The deepest layer cut and the floor that was asked for, mm.
    pub deepest_cut_z: f64,
    pub floor_z: f64,
    pub reason: String,
}

/// A layer roughing program and what planning it measured.
#[derive(Clone, Debug, PartialEq)]
pub struct Roughing {
    /// The moves, axis +Z, starting and ending on the safe height.
    pub toolpath: Toolpath,
    pub layers: Vec<LayerReport>,
    pub safe_z: f64,
    pub not_reached: Option<NotReached>,
    /// What each move took off the stock as it stood when planned (0 for the first move);
    /// empty for [`Material::Blank`].
    pub removed_mm3: Vec<f64>,
    /// With [`Guard::HullBoxes`]: the boxes the layers kept out of and how they were made.
    pub hull_boxes: Option<BoxRoughing>,
}

/// The boxes a [`Guard::HullBoxes`] roughing kept the tool out of.
#[derive(Clone, Debug, PartialEq)]
pub struct BoxRoughing {
    /// Every patch's box after the splits for the layers, grown by the stock to leave.
    pub boxes: Vec<crate::geom::Aabb>,
    pub summary: boxes::BoxSummary,
}

/// What the layers keep the tool out of.
#[derive(Clone, Copy, Debug)]
pub enum Guard<'a> {
    /// A closed shape that holds the part (its verified offset shape, or the part).
    Shape(&'a Mesh),
    /// Seed 002's convex-hull boxes of the part's surfaces, each grown by `allowance` mm;
    /// the layers are then planned at the boxes' tops ([`boxes::box_layers`]).
    HullBoxes {
        boxes: &'a crate::cad::boxes::HullBoxes,
        allowance: f64,
        /// Patches whose boxes are wider than this, mm, are split first (a tighter model
        /// than the seed's, which splits only for the layers); `f64::INFINITY`: the seed's.
        max_box_width: f64,
        merge: boxes::LayerMerge,
    },
}

/// Plans layer roughing of `blank` down to `shape` with `tool` (its T number `tool_id`).
pub fn rough_layers(
    shape: &Mesh,
    blank: &Blank,
    tool: &RoughingTool,
    tool_id: u32,
    material: Material,
    options: &RoughingOptions,
) -> Result<Roughing, RoughError> {
    rough_within(Guard::Shape(shape), blank, tool, tool_id, material, options)
}

/// Plans layer roughing of `blank` down to what `guard` protects with `tool` (its T number
/// `tool_id`).
pub fn rough_within(
    guard: Guard,
    blank: &Blank,
    tool: &RoughingTool,
    tool_id: u32,
    material: Material,
    options: &RoughingOptions,
) -> Result<Roughing, RoughError> {
    let mut material = material;
    options.validate(tool)?;
    if blank.bottom.partial_cmp(&blank.top) != Some(std::cmp::Ordering::Less)
        || blank.outline.contours.is_empty()
    {
        return Err(RoughError::Blank(format!(
            "needs an outline and bottom < top (got {} and {})",
            blank.bottom, blank.top
        )));
    }
    let guard_bounds = match guard {
        Guard::Shape(shape) => shape.aabb(),
        Guard::HullBoxes {
            boxes, allowance, ..
        } => boxes.bounds().inflated(allowance),
    };
    if guard_bounds.is_empty() {
        return Err(RoughError::Blank(
            "there is nothing to rough down to".into(),
        ));
    }
    let shape_bottom = guard_bounds.min.z;
    let floor = options
        .floor
        .unwrap_or_else(|| blank.bottom.max(shape_bottom));
    let holder_top = options.holder_top.unwrap_or(blank.top);
    let reach_floor = holder_top - tool.reach;
    let bottom = floor.max(reach_floor);
    let (envelope, planned, hull_boxes) = match guard {
        Guard::Shape(shape) => {
            let envelope = TopEnvelope::of_mesh(shape, options.cell);
            let planned = layers::layer_heights(
                &envelope.top,
                options.cell * options.cell,
                blank.top,
                bottom,
                &options.layers,
            );
            (envelope, planned, None)
        }
        Guard::HullBoxes {
            boxes,
            allowance,
            max_box_width,
            merge,
        } => {
            let planned = boxes::box_layers(
                boxes,
                allowance,
                blank.top,
                bottom,
                &options.layers,
                max_box_width,
                merge,
            );
            let envelope = TopEnvelope::of_boxes(&planned.boxes, options.cell);
            let layers = planned.layers;
            let kept = BoxRoughing {
                boxes: planned.boxes,
                summary: planned.summary,
            };
            (envelope, layers, Some(kept))
        }
    };
    let not_reached = (reach_floor > floor).then(|| NotReached {
        deepest_cut_z: reach_floor,
        floor_z: floor,
        reason: format!(
            "the tool reaches {:.1} mm below the top of what its holder passes over with the \
             holder {:.1} mm above it; the material below z = {reach_floor:.3} is left for a \
             longer tool",
            tool.reach,
            holder_top - reach_floor - tool.reach
        ),
    });

    let axis = Direction::new_normalize(Vector3::z());
    // A coarse shape may stand above a blank that is close to the part's top: the moves over
    // the blank clear it too.
    let safe_z = blank.top.max(guard_bounds.max.z) + options.clearance;
    let mut writer = Writer {
        moves: Vec::new(),
        axis,
    };
    let start = blank_anchor(&blank.outline);
    writer.push(
        Point3::new(start.x, start.y, safe_z),
        MoveKind::Rapid,
        options.feeds.rapid,
    );

    // What each move of `writer` took off the tracked stock, as far as it is taken off.
    let mut removed = vec![0.0];
    let slope = options.ramp_angle_deg.to_radians().tan();
    let mut reports = Vec::with_capacity(planned.len());
    // Above the first layer, only what of the shape stands out of the blank's top.
    let mut above: Option<RegionIndex> =
        region::cells_above(&envelope, blank.top, 0.0).map(|s| RegionIndex::new(&s));
    let mut z_above = blank.top;
    for layer in planned {
        let z = layer.z;
        let r = if blank.top - z > tool.flute_length {
            tool.radius + options.shank_clearance
        } else {
            tool.radius
        };
        let err = |error| RoughError::Layer { z, error };
        let forbidden = region::cells_above(&envelope, z, 0.0);
        let section = match &mut material {
            Material::Blank | Material::BlankOnStock { .. } => blank.outline.clone(),
            Material::Stock { stock, .. } => {
                match rest::material_in_slab_within(
                    stock,
                    &envelope,
                    z,
                    z_above,
                    REST_MIN_THICKNESS,
                    options.zone.as_deref().map(|hull| (hull, options.skin)),
                ) {
                    Some(region) => region,
                    None => {
                        // Nothing stands in this slab: the layers below start from here.
                        above = forbidden.as_ref().map(RegionIndex::new);
                        z_above = z;
                        continue;
                    }
                }
            }
        };
        let path = match (&forbidden, options.paths) {
            (Some(part), LayerPaths::Offsets) => {
                contour_parallel(part, &section, &ParallelOptions::new(r, options.stepover))
                    .map_err(err)?
            }
            (Some(part), LayerPaths::Wavelet) => {
                multires_paths(part, &section, &MultiresOptions::new(r, options.stepover))
                    .map_err(err)?
                    .path
            }
            (None, _) => facing(&section, r, options.stepover).map_err(err)?,
        };
        let mut map =
            MaterialMap::of_stock(&section, forbidden.as_ref(), tool.radius, tool.radius / 8.0)
                .map_err(err)?;
        let mut report = LayerReport {
            layer,
            passes: path.passes().len(),
            ramped_entries: 0,
            straight_entries: 0,
            plunges_into_material: 0,
            cleared_area_mm2: map.material_area(),
            max_engagement_mm: 0.0,
            max_engagement_at: [0.0, 0.0],
            max_link_engagement_mm: 0.0,
            cut_length_mm: 0.0,
            looped_stretches: 0,
            looped_length_mm: 0.0,
            heavy_unlooped_mm: 0.0,
            kept_from_material_above_mm: 0.0,
        };
        let part_index = forbidden.as_ref().map(RegionIndex::new);
        // What still stands above the height the tool moves at between passes (just above
        // the layer above): rest the layers above could not take (a wall thinner than they
        // take, a corner between passes). Rapids at that height go round it, and descend
        // beside it at the entry feed.
        let low = z_above + options.clearance;
        // Where the layer lies deeper than the flutes are long, the shank passes beside what
        // stands above them: the passes stop short of it.
        let (standing, above_flutes) = match &material {
            Material::Stock { stock, .. } | Material::BlankOnStock { stock, .. } => (
                rest::material_on_lines(stock, &envelope, low, f64::INFINITY)
                    .map(|region| RegionIndex::new(&region)),
                rest::material_in_slab(stock, &envelope, z + tool.flute_length, f64::INFINITY, 0.0)
                    .map(|region| RegionIndex::new(&region)),
            ),
            Material::Blank => (None, None),
        };
        let step = 0.25 * options.cell;
        // Whether the tool ended the previous pass where that pass ends (a feed link from
        // there is then a straight move at the layer).
        let mut at_pass_end = false;
        for (i, pass) in path.passes().iter().enumerate() {
            let whole = moves::pass_points(pass, options.tolerance);
            let runs = match &above_flutes {
                Some(keep_out) => moves::clear_runs(&whole, keep_out, r, step),
                None => vec![whole.clone()],
            };
            let kept: f64 = runs.iter().map(|run| moves::polyline_length(run)).sum();
            report.kept_from_material_above_mm += moves::polyline_length(&whole) - kept;
            let whole_start = whole[0];
            let whole_end = whole[whole.len() - 1];
            let linked = i > 0 && !matches!(path.links()[i - 1], Link::Rapid { .. });
            let run_count = runs.len();
            for (k, points) in runs.into_iter().enumerate() {
                let entering = !(k == 0 && linked && at_pass_end && points[0] == whole_start);
                at_pass_end = k + 1 == run_count && points[points.len() - 1] == whole_end;
                if entering {
                    let to = points[0];
                    writer.transit(
                        to,
                        low,
                        safe_z,
                        [above.as_ref(), standing.as_ref()],
                        r,
                        (options.feeds.rapid, options.feeds.entry),
                    );
                    let plunge_limit =
                        options.max_plunge_share * std::f64::consts::PI * tool.radius * tool.radius;
                    let ramp = if map.material_within(to) > plunge_limit {
                        moves::ramp_along(
                            &points,
                            z_above + 0.1 * options.clearance,
                            z,
                            slope,
                            options.max_ramp_leg,
                        )
                    } else {
                        Vec::new()
                    };
                    if ramp.is_empty() {
                        if map.material_within(to) > plunge_limit {
                            report.plunges_into_material += 1;
                        } else {
                            report.straight_entries += 1;
                        }
                        writer.push(
                            Point3::new(to.x, to.y, z),
                            MoveKind::Approach,
                            options.feeds.entry,
                        );
                        map.plunge(to);
                    } else {
                        report.ramped_entries += 1;
                        writer.push(
                            Point3::new(to.x, to.y, z_above + 0.1 * options.clearance),
                            MoveKind::Approach,
                            options.feeds.entry,
                        );
                        map.plunge(to);
                        let mut window = Window::without_values(r);
                        let mut from = to;
                        for p in ramp {
                            let q = Point2::new(p.x, p.y);
                            map.cut(
                                &Segment::Line {
                                    start: from,
                                    end: q,
                                },
                                &mut window,
                            );
                            writer.push(p, MoveKind::Cut, options.feeds.entry);
                            from = q;
                        }
                    }
                } else {
                    let link = path.links()[i - 1];
                    let mut window = Window::new(r);
                    map.cut(
                        &Segment::Line {
                            start: link.from(),
                            end: link.to(),
                        },
                        &mut window,
                    );
                    window.finish();
                    report.max_link_engagement_mm = report.max_link_engagement_mm.max(window.max);
                    let (kind, feed) = match link {
                        Link::Traverse { .. } => (MoveKind::Approach, options.feeds.rapid),
                        _ => (MoveKind::Cut, options.feeds.cut),
                    };
                    writer.push(Point3::new(points[0].x, points[0].y, z), kind, feed);
                }
                let points = match options.max_engagement {
                    Some(bound) => {
                        let keep_off: Vec<&RegionIndex> =
                            [part_index.as_ref(), above_flutes.as_ref()]
                                .into_iter()
                                .flatten()
                                .collect();
                        let looped = trochoid::loop_heavy_stretches(
                            &points,
                            &map,
                            &keep_off,
                            r,
                            &trochoid::LoopOptions::for_radius(tool.radius, bound),
                        );
                        report.looped_stretches += looped.stretches;
                        report.looped_length_mm += looped.looped_mm;
                        report.heavy_unlooped_mm += looped.unlooped_mm;
                        looped.points
                    }
                    None => points,
                };
                let mut window = Window::new(r);
                for w in points.windows(2) {
                    map.cut(
                        &Segment::Line {
                            start: w[0],
                            end: w[1],
                        },
                        &mut window,
                    );
                    writer.push(
                        Point3::new(w[1].x, w[1].y, z),
                        MoveKind::Cut,
                        options.feeds.cut,
                    );
                }
                window.finish();
                if window.max > report.max_engagement_mm {
                    report.max_engagement_mm = window.max;
                    report.max_engagement_at = [window.max_at.x, window.max_at.y];
                }
                report.cut_length_mm += moves::polyline_length(&points);
            }
            if run_count == 0 {
                at_pass_end = false;
            }
        }
        report.cleared_area_mm2 -= map.material_area();
        let rest = matches!(material, Material::Stock { .. });
        // The next layer is planned from what this one leaves.
        material.take_off(&writer.moves, &mut removed, tool_id, options.tolerance);
        if report.passes > 0 || rest {
            above = part_index;
            z_above = z;
        }
        if report.passes > 0 {
            reports.push(report);
        }
    }
    let last = writer.last();
    writer.push(
        Point3::new(last.x, last.y, safe_z),
        MoveKind::Retract,
        options.feeds.rapid,
    );
    material.take_off(&writer.moves, &mut removed, tool_id, options.tolerance);
    if matches!(material, Material::Blank) {
        removed.clear();
    }
    Ok(Roughing {
        toolpath: Toolpath {
            tool_id,
            moves: writer.moves,
        },
        layers: reports,
        safe_z,
        not_reached,
        removed_mm3: removed,
        hull_boxes,
    })
}

/// Layers thinner than this in a slab of the stock are not rest material, mm (the skin a
/// layer's floor may keep in the model's round-off).
const REST_MIN_THICKNESS: f64 = 0.05;

/// What a layer clears.
pub enum Material<'a> {
    /// The blank's section, whole: the first roughing of a blank.
    Blank,
    /// The blank's section, whole, with the stock that models the blank: each layer's moves
    /// are removed from it with `body` as they are planned, so that the layers below keep the
    /// shank off what the layers above left, as in rest roughing.
    BlankOnStock {
        stock: &'a mut Stock,
        body: &'a CuttingBody,
    },
    /// What the stock still holds in the layer's slab (rest roughing). Each layer's moves are
    /// removed from the stock with `body` before the next layer is planned.
    Stock {
        stock: &'a mut Stock,
        body: &'a CuttingBody,
    },
}

impl Material<'_> {
    /// Takes the moves not yet taken off the tracked stock off it (those after the last one
    /// `removed` holds), recording what each removes; nothing without a stock.
    fn take_off(&mut self, moves: &[Move], removed: &mut Vec<f64>, tool_id: u32, tolerance: f64) {
        let (Material::BlankOnStock { stock, body } | Material::Stock { stock, body }) = self
        else {
            return;
        };
        let from = removed.len() - 1;
        if moves.len() > from + 1 {
            let rest = Toolpath {
                tool_id,
                moves: moves[from..].to_vec(),
            };
            removed.extend(
                stock
                    .remove_cutting(&rest, body, tolerance)
                    .into_iter()
                    .skip(1),
            );
        }
    }
}

/// A point on the blank's outline, where the program starts above.
fn blank_anchor(outline: &Shape) -> Point2 {
    outline
        .contours
        .first()
        .and_then(|c| c.vertices.first())
        .map_or(Point2::origin(), |v| v.point)
}

/// Clears a whole section with no part in it: loops of the section's inward offsets, the first
/// one stepover in from where the tool's edge meets the outline, outermost first, each
/// entered afresh. The loops run clockwise: the material still standing is inside them, on
/// the cutter's right, which with a clockwise (M3) spindle is climb milling.
fn facing(outline: &Shape, r: f64, s: f64) -> Result<CenterPath, ContourError> {
    let mut passes = Vec::new();
    let mut depth = s - r;
    loop {
        let loops = crate::contour::cavc::offset_region(outline, -depth, "blank")?;
        if loops.is_empty() {
            break;
        }
        for c in loops
            .into_iter()
            .filter(|c: &Contour| c.signed_area() > 0.0)
        {
            passes.push(Pass::closed(c.vertices, depth)?.reversed());
        }
        depth += s;
    }
    CenterPath::with_rapid_links(r, passes)
}

/// The moves being written.
struct Writer {
    moves: Vec<Move>,
    axis: Direction,
}

impl Writer {
    fn push(&mut self, tip: Point3, kind: MoveKind, feed: f64) {
        self.moves.push(Move {
            pose: ToolPose {
                tip,
                axis: self.axis,
            },
            kind,
            feed,
        });
    }

    fn last(&self) -> Point3 {
        self.moves.last().map_or(Point3::origin(), |m| m.pose.tip)
    }

    /// Goes from where the tool is to above `to` at `low` (just above the layer above): up to
    /// `low`, then straight across when that way keeps the tool `r` clear of every region of
    /// `keep_off` (what of the shape stands above the layer above, nothing when that layer
    /// was the blank's top or a facing layer; the material still standing above `low`), else
    /// over the blank at `safe_z`, coming down to `low` at the `entry` feed when `to` lies
    /// within `r` of a region (the shape's coarse cells, or rest).
    fn transit(
        &mut self,
        to: Point2,
        low: f64,
        safe_z: f64,
        keep_off: [Option<&RegionIndex>; 2],
        r: f64,
        (rapid, entry): (f64, f64),
    ) {
        let at = self.last();
        let from = Point2::new(at.x, at.y);
        if at.z < low {
            self.push(Point3::new(at.x, at.y, low), MoveKind::Retract, rapid);
        }
        let seg = Segment::Line {
            start: from,
            end: to,
        };
        let clear = keep_off.into_iter().flatten().all(|index| {
            !index.contains(from)
                && !index.contains(to)
                && index
                    .boundary()
                    .nearest(&seg)
                    .is_none_or(|n| n.distance >= r + 1e-6)
        });
        let height = self.last().z;
        if clear && height <= low + 1e-9 {
            self.push(Point3::new(to.x, to.y, low), MoveKind::Rapid, rapid);
        } else {
            if height < safe_z {
                self.push(Point3::new(at.x, at.y, safe_z), MoveKind::Retract, rapid);
            }
            self.push(Point3::new(to.x, to.y, safe_z), MoveKind::Rapid, rapid);
            let beside =
                |index: &RegionIndex| index.contains(to) || index.boundary_distance(to) < r + 1e-6;
            if keep_off.into_iter().flatten().any(beside) {
                self.push(Point3::new(to.x, to.y, low), MoveKind::Approach, entry);
            } else {
                self.push(Point3::new(to.x, to.y, low), MoveKind::Rapid, rapid);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::cuboid;

    /// A 20 × 20 × 10 block on the floor in a 40 × 40 × 12 box blank, roughed with r = 3.
    fn block_job() -> (Mesh, Blank, RoughingTool, RoughingOptions) {
        let mut block = cuboid(20.0, 20.0, 10.0);
        for p in &mut block.positions {
            p.x -= 10.0;
            p.y -= 10.0;
        }
        let blank = Blank::cuboid(
            Point3::new(-20.0, -20.0, 0.0),
            Point3::new(20.0, 20.0, 12.0),
        );
        let tool = RoughingTool {
            radius: 3.0,
            flute_length: 20.0,
            reach: 50.0,
        };
        let mut options = RoughingOptions::for_radius(3.0);
        options.floor = Some(0.0);
        (block, blank, tool, options)
    }

    /// How near the block's sides the cutting moves at height `z` come, in the plane.
    fn nearest_to_block(rough: &Roughing, z: f64) -> f64 {
        rough
            .toolpath
            .moves
            .iter()
            .filter(|m| m.kind == MoveKind::Cut && (m.pose.tip.z - z).abs() < 1e-9)
            .map(|m| {
                let dx = (m.pose.tip.x.abs() - 10.0).max(0.0);
                let dy = (m.pose.tip.y.abs() - 10.0).max(0.0);
                dx.hypot(dy)
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// The block's top is a flat: a layer at its height (a facing layer, the tool resting on
    /// it), then the 10 mm below split evenly within the 3 mm depth of cut; no move comes
    /// nearer the block than the radius, and the layers below its top run within a cell's
    /// diagonal of that, leaving no more than the grid's rounding.
    #[test]
    fn a_block_is_roughed_in_layers_to_its_walls() {
        let (block, blank, tool, options) = block_job();
        let rough =
            rough_layers(&block, &blank, &tool, 7, Material::Blank, &options).expect("roughing");
        let zs: Vec<f64> = rough.layers.iter().map(|l| l.layer.z).collect();
        assert_eq!(zs, vec![10.0, 7.5, 5.0, 2.5, 0.0]);
        assert!(rough.layers[0].layer.at_flat);
        let check = check::overcuts(&block, &rough.toolpath, tool.radius, 1e-9);
        assert!(check.overcuts.is_empty(), "{:?}", &check.overcuts[..1]);
        assert!(
            check.min_clearance_mm >= -1e-9,
            "{}",
            check.min_clearance_mm
        );
        let nearest = |z: f64| nearest_to_block(&rough, z);
        for z in [7.5, 5.0, 2.5, 0.0] {
            let d = nearest(z);
            assert!(
                d >= 3.0 - 1e-9 && d <= 3.0 + options.cell * 2f64.sqrt() + 1e-9,
                "z {z}: {d}"
            );
        }
        // The facing layer clears the whole section, the others the section minus the block
        // and its grid margin.
        let faced = rough.layers[0].cleared_area_mm2;
        assert!((faced - 1600.0).abs() < 16.0, "{faced}");
        let walled = rough.layers[1].cleared_area_mm2;
        assert!(walled > 1600.0 - 21.0 * 21.0 && walled < 1200.0, "{walled}");
    }

    /// Climb milling with a clockwise (M3) spindle keeps the material a move cuts on the
    /// cutter's right: the facing loops run clockwise about the blank's centre, and the passes
    /// along the block's walls keep the block on their right.
    #[test]
    fn the_layers_are_cut_climb() {
        let (block, blank, tool, options) = block_job();
        let rough =
            rough_layers(&block, &blank, &tool, 7, Material::Blank, &options).expect("roughing");
        let cuts_at = |z: f64| {
            let moves = &rough.toolpath.moves;
            moves
                .windows(2)
                .filter(move |w| {
                    // Not the ramps: their foot runs back along the pass to its start.
                    w[1].kind == MoveKind::Cut
                        && w[1].feed == options.feeds.cut
                        && (w[0].pose.tip.z - z).abs() < 1e-9
                        && (w[1].pose.tip.z - z).abs() < 1e-9
                })
                .map(|w| (w[0].pose.tip.xy(), w[1].pose.tip.xy()))
                .filter(|(a, b)| (b - a).norm() > 1e-6)
                .collect::<Vec<_>>()
        };
        let right_of = |(a, b): (nalgebra::Point2<f64>, nalgebra::Point2<f64>),
                        q: nalgebra::Point2<f64>| {
            let d = b - a;
            let to = q - nalgebra::center(&a, &b);
            d.x * to.y - d.y * to.x < 0.0
        };
        let facing = cuts_at(10.0);
        assert!(facing.len() > 8);
        for cut in &facing {
            assert!(right_of(*cut, nalgebra::Point2::origin()), "{cut:?}");
        }
        let mut along_walls = 0;
        for (a, b) in cuts_at(5.0) {
            let mid = nalgebra::center(&a, &b);
            let nearest = nalgebra::Point2::new(mid.x.clamp(-10.0, 10.0), mid.y.clamp(-10.0, 10.0));
            if (mid - nearest).norm() < tool.radius + options.cell * 2.0 {
                assert!(right_of((a, b), nearest), "{a} → {b}");
                along_walls += 1;
            }
        }
        assert!(along_walls >= 4, "{along_walls}");
    }

    /// A shape standing out of the blank's top (a coarse offset over a blank close to the
    /// part) splits the blank in two: the tool goes from one side to the other over the shape,
    /// never through what of it stands above the blank.
    #[test]
    fn moves_between_regions_clear_a_shape_above_the_blank() {
        let (block, _, tool, options) = block_job();
        let blank = Blank::cuboid(Point3::new(-25.0, -10.0, 0.0), Point3::new(25.0, 10.0, 8.5));
        let rough =
            rough_layers(&block, &blank, &tool, 7, Material::Blank, &options).expect("roughing");
        assert!(
            rough.safe_z >= 10.0 + options.clearance - 1e-9,
            "{}",
            rough.safe_z
        );
        let sides = |sign: f64| {
            rough.toolpath.moves.iter().any(|m| {
                m.kind == MoveKind::Cut && m.pose.tip.x * sign > 10.0 && m.pose.tip.z < 8.5
            })
        };
        assert!(sides(1.0) && sides(-1.0), "both sides are roughed");
        let check = check::overcuts(&block, &rough.toolpath, tool.radius, 1e-9);
        assert!(check.overcuts.is_empty(), "{:?}", &check.overcuts[..1]);
    }

    /// Rest roughing beside material that stands above the flutes' reach of every layer (a
    /// 2 × 2 pillar rising above the blank's top, out of every slab): the passes stop short
    /// of it by the shank's radius, and the rest of each layer is still roughed.
    #[test]
    fn passes_keep_the_shank_off_material_above_the_flutes() {
        let (block, blank, mut tool, options) = block_job();
        tool.flute_length = 4.0;
        let boxed = |size: [f64; 3], at: [f64; 3]| {
            let mut m = cuboid(size[0], size[1], size[2]);
            for p in &mut m.positions {
                *p += Vector3::from(at);
            }
            m
        };
        let mut material = boxed([40.0, 40.0, 12.0], [-20.0, -20.0, 0.0]);
        let pillar = boxed([2.0, 2.0, 8.0], [14.0, -1.0, 12.0]);
        let offset = material.positions.len() as u32;
        material.positions.extend(pillar.positions);
        material
            .triangles
            .extend(pillar.triangles.iter().map(|t| t.map(|i| i + offset)));
        let mut stock = Stock::from_mesh(&material, 0.25, 1 << 22).expect("stock");
        let body = CuttingBody::of(&crate::tool::Cutter::Flat {
            diameter: 6.0,
            flute_length: 4.0,
        });
        let rough = rough_layers(
            &block,
            &blank,
            &tool,
            7,
            Material::Stock {
                stock: &mut stock,
                body: &body,
            },
            &options,
        )
        .expect("roughing");
        let from_pillar = |p: &Point3| {
            let dx = (p.x - 15.0).abs() - 1.0;
            let dy = p.y.abs() - 1.0;
            dx.max(0.0).hypot(dy.max(0.0))
        };
        // Along every cutting move, sampled every 0.02 mm.
        let moves = &rough.toolpath.moves;
        let nearest = moves
            .windows(2)
            .filter(|w| w[1].kind == MoveKind::Cut)
            .flat_map(|w| {
                let (a, b) = (w[0].pose.tip, w[1].pose.tip);
                let n = ((b - a).norm() / 0.02).ceil().max(1.0) as usize;
                (0..=n).map(move |k| from_pillar(&(a + (b - a) * (k as f64 / n as f64))))
            })
            .fold(f64::INFINITY, f64::min);
        let cuts: Vec<&Move> = moves.iter().filter(|m| m.kind == MoveKind::Cut).collect();
        assert!(
            nearest >= tool.radius,
            "a pass comes {nearest} mm from the pillar"
        );
        assert!(
            rough
                .layers
                .iter()
                .all(|l| l.kept_from_material_above_mm > 0.0)
        );
        for layer in &rough.layers {
            let beyond = cuts
                .iter()
                .any(|m| (m.pose.tip.z - layer.layer.z).abs() < 1e-9 && m.pose.tip.x > 17.0);
            assert!(beyond, "layer {} roughs past the pillar", layer.layer.z);
        }
    }

    /// Roughing the blank on its stock: what each move is recorded to remove is what it
    /// removes when the whole program is run on the blank's stock afterwards, move by move;
    /// the stock left is the same; the program is the blank roughing's where nothing is left
    /// standing above the flutes.
    #[test]
    fn layers_taken_off_as_planned_record_what_each_move_removes() {
        let (block, blank, tool, options) = block_job();
        let bounds = crate::geom::Aabb::from_points(&[
            Point3::new(-20.0, -20.0, 0.0),
            Point3::new(20.0, 20.0, 12.0),
        ]);
        let fresh = Stock::block(&bounds, 0.5, 1 << 22).expect("stock");
        let mut tracked = fresh.clone();
        let body = CuttingBody::of(&crate::tool::Cutter::Flat {
            diameter: 6.0,
            flute_length: 20.0,
        });
        let rough = rough_layers(
            &block,
            &blank,
            &tool,
            7,
            Material::BlankOnStock {
                stock: &mut tracked,
                body: &body,
            },
            &options,
        )
        .expect("roughing");
        let plain =
            rough_layers(&block, &blank, &tool, 7, Material::Blank, &options).expect("roughing");
        assert_eq!(plain.toolpath, rough.toolpath);
        assert!(plain.removed_mm3.is_empty());
        let mut replayed = fresh.clone();
        let removed = replayed.remove_cutting(&rough.toolpath, &body, options.tolerance);
        assert_eq!(rough.removed_mm3.len(), rough.toolpath.moves.len());
        for (k, (a, b)) in rough.removed_mm3.iter().zip(&removed).enumerate() {
            assert!(
                (a - b).abs() <= 1e-9 * (1.0 + b.abs()),
                "move {k}: {a} vs {b}"
            );
        }
        assert!(removed.iter().sum::<f64>() > 0.5 * (1600.0 * 12.0 - 4000.0));
        assert_eq!(tracked.to_bytes(), replayed.to_bytes());
    }

    /// Every descent into material is a ramp no steeper than the ramp angle; straight descents
    /// happen only into air; the tool starts and ends at the safe height; planning twice gives
    /// the same program.
    #[test]
    fn entries_are_ramped_and_the_program_is_deterministic() {
        let (block, blank, tool, options) = block_job();
        let rough =
            rough_layers(&block, &blank, &tool, 7, Material::Blank, &options).expect("roughing");
        let slope = options.ramp_angle_deg.to_radians().tan();
        for w in rough.toolpath.moves.windows(2) {
            let d = w[1].pose.tip - w[0].pose.tip;
            if w[1].kind == MoveKind::Cut && d.z < -1e-12 {
                assert!(
                    -d.z <= slope * d.xy().norm() + 1e-9,
                    "too steep: {:?}",
                    w[1]
                );
            }
        }
        assert!(rough.layers.iter().all(|l| l.plunges_into_material == 0));
        assert!(rough.layers.iter().any(|l| l.ramped_entries > 0));
        let moves = &rough.toolpath.moves;
        assert_eq!(moves[0].pose.tip.z, rough.safe_z);
        assert_eq!(moves[moves.len() - 1].pose.tip.z, rough.safe_z);
        let again =
            rough_layers(&block, &blank, &tool, 7, Material::Blank, &options).expect("roughing");
        assert_eq!(again.toolpath, rough.toolpath);
    }

    #[test]
    fn bad_options_and_blanks_are_refused_by_name() {
        let (block, blank, tool, options) = block_job();
        let mut o = options.clone();
        o.stepover = 4.0;
        let err =
            rough_layers(&block, &blank, &tool, 7, Material::Blank, &o).expect_err("stepover");
        assert!(err.to_string().contains("stepover"), "{err}");
        let mut o = options.clone();
        o.layers.max_depth = 25.0;
        let err = rough_layers(&block, &blank, &tool, 7, Material::Blank, &o).expect_err("depth");
        assert!(err.to_string().contains("deeper than the flutes"), "{err}");
        let flat = Blank { top: 0.0, ..blank };
        assert!(matches!(
            rough_layers(&block, &flat, &tool, 7, Material::Blank, &options),
            Err(RoughError::Blank(_))
        ));
    }

    /// Layers deeper below the blank's top than the flutes are long keep the shank's
    /// clearance more off the walls; those within the flutes ride them at the radius.
    #[test]
    fn the_shank_keeps_its_clearance_below_the_flutes() {
        let (block, blank, mut tool, options) = block_job();
        tool.flute_length = 3.0;
        let rough =
            rough_layers(&block, &blank, &tool, 7, Material::Blank, &options).expect("roughing");
        let nearest = |z: f64| nearest_to_block(&rough, z);
        let slack = options.cell * 2f64.sqrt() + 1e-9;
        // z = 10 faces the block's top (no wall); 2 mm under the top is within the flutes.
        for (z, keep) in [(7.5, 3.5), (5.0, 3.5), (2.5, 3.5), (0.0, 3.5)] {
            let d = nearest(z);
            assert!(d >= keep - 1e-9 && d <= keep + slack, "z {z}: {d}");
        }
        let mut within = options.clone();
        within.shank_clearance = 0.0;
        let plain =
            rough_layers(&block, &blank, &tool, 7, Material::Blank, &within).expect("roughing");
        assert!(plain.toolpath != rough.toolpath);
    }

    /// A tool too short for the blank cuts the layers it reaches and says what is left.
    #[test]
    fn layers_beyond_the_reach_are_reported() {
        let (block, blank, mut tool, options) = block_job();
        tool.reach = 6.0;
        let rough =
            rough_layers(&block, &blank, &tool, 7, Material::Blank, &options).expect("roughing");
        let lowest = rough.layers.last().expect("layers").layer.z;
        assert!((lowest - 6.0).abs() < 1e-12, "{lowest}");
        let left = rough.not_reached.expect("reported");
        assert_eq!((left.deepest_cut_z, left.floor_z), (6.0, 0.0));
    }
}
