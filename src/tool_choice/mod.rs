//! Tool choice: which tool of a library finishes which region of the part, largest first
//! (seed 004 ch. 5 step 6; seed 001 ch. 4; DESIGN.md §3.6).
//!
//! For every point (the part's vertices, evenly thinned to at most `max_points`):
//!
//! * the principal curvatures and the convex / concave / saddle / flat class (`curvature`);
//! * the largest ball that touches the point along its normal and dips into the part by at
//!   most the tolerance anywhere — exact in f64 and global, so it sees the gap between two
//!   blades as well as a fillet's concave radius (a ball inside a cavity of radius R fits up
//!   to R + τ/2; a slot of width w takes w/2 + τ/2). Smaller balls touching at the same point
//!   lie inside a fitting one, so the fit is monotone and bisection finds it;
//! * the first tool, largest first (`ToolLibrary::largest_first`), that can touch the point:
//!   its cutting end within the tolerance, its flutes, neck, shank and holder clear of the part
//!   by their margins and of the machine table (the part stands on it), for some axis within
//!   `max_tilt_deg` of the normal. Axes are tried from the normal outward in rings; each is
//!   screened by a ray along the axis (obvhs) and decided by the exact body tests (`collide`).
//!
//! Points not evaluated take the answer of the nearest evaluated point along the mesh. Regions
//! are the connected sets of vertices given the same tool. The proposal lists the tools that
//! finish anything, largest first, each with the area that no larger tool could finish (rest
//! machining), its regions, and why the next larger tool was refused there.

pub mod curvature;

use std::collections::{BTreeMap, VecDeque};

use rayon::prelude::*;
use serde::Serialize;

use crate::access::RayScene;
use crate::collide::{ColliderError, Collision, Margins, PartCollider, PreparedTool, Table};
use crate::geom::ToolPose;
use crate::geom::{Direction, Vector3, orthonormal_frame, triangle_area};
use crate::mesh::Mesh;
use crate::tool::{BodyRole, ToolLibrary};
pub use curvature::{Curvature, ShapeClass, vertex_curvatures, vertex_neighbours};

/// What `choose_tools` looks at and how strictly.
#[derive(Clone, Debug, PartialEq)]
pub struct ToolChoiceOptions {
    /// How far a cutting end may dip into the part, mm (the finishing tolerance). Default 0.01.
    pub tolerance: f64,
    /// At most this many points are evaluated (vertices thinned evenly). Default 20000.
    pub max_points: usize,
    /// Curvatures within ± this (1/mm) count as flat. Default 0.001 (radii beyond 1 m).
    pub flat_curvature: f64,
    /// Largest angle between the tool axis and the normal, degrees. Default 90: a ball or a
    /// flat end mill may stand along a wall it finishes with its side.
    pub max_tilt_deg: f64,
    /// Angular step of the axis rings, degrees. Default 10.
    pub tilt_step_deg: f64,
    /// At most this many axes per tool and point get the exact body test. Default 48.
    pub max_exact_tests: usize,
    /// The reach is measured on at most this many points, evenly spread (it costs about ten
    /// holder-sized collision tests where the part is in the way). Default 2000.
    pub reach_points: usize,
    /// Shank and holder margins, mm (the job's defaults 0.5 and 2).
    pub margins: Margins,
    /// The machine table at the part's lowest point, with this margin; `None` leaves it out.
    pub table_margin: Option<f64>,
}

impl Default for ToolChoiceOptions {
    fn default() -> Self {
        Self {
            tolerance: 0.01,
            max_points: 20_000,
            flat_curvature: 1e-3,
            max_tilt_deg: 90.0,
            tilt_step_deg: 10.0,
            max_exact_tests: 48,
            reach_points: 2000,
            margins: Margins {
                shank: 0.5,
                holder: 2.0,
            },
            table_margin: Some(2.0),
        }
    }
}

/// Why a tool cannot finish a point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Refusal {
    /// The cutting end dips into the part beyond the tolerance (too large for the concave
    /// radius or the gap) at every axis tried.
    Gouge,
    /// Every axis ray hits the part.
    Occluded,
    Flutes,
    Shank,
    Holder,
    Table,
}

impl Refusal {
    fn of(collision: Collision) -> Self {
        match collision {
            Collision::Gouge { .. } => Refusal::Gouge,
            Collision::Table => Refusal::Table,
            Collision::Body { role } | Collision::Material { role } => match role {
                BodyRole::Flutes => Refusal::Flutes,
                BodyRole::Shank => Refusal::Shank,
                BodyRole::Holder => Refusal::Holder,
            },
        }
    }
}

/// The answer at one evaluated point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointChoice {
    pub vertex: u32,
    /// Index into the library of the largest tool that finishes the point.
    pub tool: Option<usize>,
    /// Its axis there (zero when none).
    pub axis: Vector3,
    /// Why the next larger tool (or, without a tool, the smallest) was refused.
    pub refusal: Option<Refusal>,
    /// Radius of the largest ball that fits here (lower bound of the bisection), mm.
    pub safe_ball: f64,
    /// Reach needed with the chosen tool and axis, mm: how far from the tip a cylinder as wide
    /// as the tool's holder (plus its margin) must start to clear the part. Measured on an
    /// even subset of the points (`reach_points`); `None` elsewhere and without a tool.
    pub reach: Option<f64>,
}

/// Everything `choose_tools` finds, as plain data.
#[derive(Clone, Debug)]
pub struct ToolChoice {
    pub curvatures: Vec<Option<Curvature>>,
    pub points: Vec<PointChoice>,
    /// Per vertex: the library index of its tool (from its nearest evaluated point).
    pub vertex_tool: Vec<Option<usize>>,
    pub report: ToolChoiceReport,
}

/// The figures, as `tools.json` shows them.
#[derive(Clone, Debug, Serialize)]
pub struct ToolChoiceReport {
    pub vertices: usize,
    pub points_evaluated: usize,
    pub tolerance_mm: f64,
    pub area_mm2: f64,
    pub shape: ShapeSummary,
    /// Tools that finish something, largest first.
    pub proposal: Vec<ProposedTool>,
    /// Library tools the proposal leaves out, with why.
    pub not_used: Vec<UnusedTool>,
    pub unreachable: Unreachable,
}

#[derive(Clone, Debug, Serialize)]
pub struct ShapeSummary {
    /// Area share (%) of each class.
    pub percent: BTreeMap<ShapeClass, f64>,
    /// The smallest concave radius of curvature over the part, mm, and where.
    pub min_concave_radius_mm: Option<f64>,
    pub min_concave_radius_at: Option<[f64; 3]>,
    /// The smallest "largest safe ball" over the evaluated points, mm, and where.
    pub min_safe_ball_mm: f64,
    pub min_safe_ball_at: Option<[f64; 3]>,
}

#[derive(Clone, Debug, Serialize)]
pub struct ProposedTool {
    pub id: u32,
    pub name: String,
    pub tool: String,
    /// Area it finishes that no larger tool could, mm², and its share of the part.
    pub area_mm2: f64,
    pub percent: f64,
    pub vertices: usize,
    pub regions: usize,
    /// Why the next larger tool was refused on this tool's points (point counts).
    pub larger_refused_for: BTreeMap<Refusal, usize>,
    /// The longest reach needed on its points, mm, against the tool's stickout.
    pub reach_needed_mm: f64,
    pub stickout_mm: f64,
    /// The largest regions (at most 10).
    pub largest_regions: Vec<Region>,
}

#[derive(Clone, Debug, Serialize)]
pub struct Region {
    pub vertices: usize,
    pub area_mm2: f64,
    /// Area-weighted centre, mm.
    pub centre: [f64; 3],
    /// Smallest concave radius of curvature in the region (none where nothing is concave).
    pub min_concave_radius_mm: Option<f64>,
    /// The largest ball that fits at every evaluated point of the region, mm.
    pub largest_safe_ball_mm: f64,
    /// The longest reach its tool needs there (`PointChoice::reach`, on the measured points), mm.
    pub reach_needed_mm: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct UnusedTool {
    pub id: u32,
    pub name: String,
    pub why: String,
}

#[derive(Clone, Debug, Serialize)]
pub struct Unreachable {
    pub vertices: usize,
    pub area_mm2: f64,
    pub percent: f64,
    pub regions: usize,
    /// Why the smallest tool was refused there (point counts).
    pub smallest_refused_for: BTreeMap<Refusal, usize>,
}

/// Why tools cannot be chosen.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ToolChoiceError {
    /// An option is out of its range.
    #[error("{name} = {value}: {reason}")]
    InvalidOption {
        /// The option (field of [`ToolChoiceOptions`]).
        name: &'static str,
        /// The value given.
        value: f64,
        /// What it must be.
        reason: &'static str,
    },
    /// The part cannot be made into a collision model.
    #[error(transparent)]
    Collider(#[from] ColliderError),
}

/// Chooses tools from `library` for `part` (a closed, outward-oriented mesh in mm).
pub fn choose_tools(
    part: &Mesh,
    library: &ToolLibrary,
    options: &ToolChoiceOptions,
) -> Result<ToolChoice, ToolChoiceError> {
    if !(options.tolerance.is_finite() && options.tolerance >= 0.0) {
        return Err(ToolChoiceError::InvalidOption {
            name: "tolerance",
            value: options.tolerance,
            reason: "must be a non-negative number of mm",
        });
    }
    let normals = part.vertex_normals();
    let ring = vertex_neighbours(part);
    let curvatures = vertex_curvatures(part, &normals, &ring);
    let areas = vertex_areas(part);

    let mut collider = PartCollider::new(part)?;
    if let Some(margin) = options.table_margin {
        collider = collider.with_table(Table {
            top_z: part.aabb().min.z,
            margin,
        });
    }
    let scene = RayScene::new(part);
    let order = library.largest_first();
    let prepared: Vec<PreparedTool> = order
        .iter()
        .map(|&i| PreparedTool::new(&library.tools[i], &options.margins))
        .collect();
    // The safe-ball search goes as far as the largest cutter: beyond that no tool cares.
    let largest_ball = library
        .tools
        .iter()
        .map(|t| t.cutter.diameter() / 2.0)
        .fold(0.0, f64::max);
    let axes = AxisRings::new(options.max_tilt_deg, options.tilt_step_deg);

    let candidates: Vec<u32> = (0..part.positions.len() as u32)
        .filter(|&v| normals[v as usize].norm() > 0.5)
        .collect();
    let stride = candidates.len().div_ceil(options.max_points.max(1)).max(1);
    let evaluated: Vec<u32> = candidates.iter().copied().step_by(stride).collect();

    let reach_stride = evaluated.len().div_ceil(options.reach_points.max(1)).max(1);
    let points: Vec<PointChoice> = evaluated
        .par_iter()
        .enumerate()
        .map(|(k, &v)| {
            let p = part.positions[v as usize];
            let n = normals[v as usize];
            let (safe_ball, too_big) =
                safe_ball(&collider, &p, &n, largest_ball, options.tolerance);
            let mut refusal = None;
            for (rank, tool) in prepared.iter().enumerate() {
                let r = tool.ball_radius;
                // A ball at least as large as one known not to fit does not fit either (module
                // docs); one in between is checked once, exactly, whatever the axis.
                let ball_gouges = r > 0.0
                    && (r >= too_big
                        || r > safe_ball
                            && collider
                                .check_ball(&(p + n * r), r, options.tolerance)
                                .is_err());
                let outcome = if ball_gouges {
                    Err(Refusal::Gouge)
                } else {
                    touch(&collider, &scene, tool, &p, &n, &axes, options)
                };
                match outcome {
                    Ok(axis) => {
                        let assembly = &library.tools[order[rank]];
                        return PointChoice {
                            vertex: v,
                            tool: Some(order[rank]),
                            axis,
                            refusal,
                            safe_ball,
                            reach: (k % reach_stride == 0).then(|| {
                                reach_needed(&collider, tool, assembly, &p, &n, &axis, options)
                            }),
                        };
                    }
                    Err(why) => refusal = Some(why),
                }
            }
            PointChoice {
                vertex: v,
                tool: None,
                axis: Vector3::zeros(),
                refusal,
                safe_ball,
                reach: None,
            }
        })
        .collect();

    let vertex_tool = spread(&ring, &points, part.positions.len());
    let report = summarise(
        part,
        library,
        &order,
        &curvatures,
        &areas,
        &ring,
        &points,
        &vertex_tool,
        options,
    );
    Ok(ToolChoice {
        curvatures,
        points,
        vertex_tool,
        report,
    })
}

/// The reach `tool` needs at `p` along `axis` (see [`PointChoice::reach`]): the lowest start,
/// by bisection to 0.1 mm between the flute top and twice the stickout, of a cylinder of the
/// holder's largest radius plus its margin, as long as the holder, that clears the part. The
/// tool's own stickout is enough when its holder clears; a reach above it says how much
/// longer a tool with a straight holder that wide would have to stick out.
fn reach_needed(
    collider: &PartCollider,
    tool: &PreparedTool,
    assembly: &crate::tool::ToolAssembly,
    p: &crate::geom::Point3,
    n: &Vector3,
    axis: &Vector3,
    options: &ToolChoiceOptions,
) -> f64 {
    let Some(tip) = tool.cutter().tip_touching(p, n, axis) else {
        return 0.0;
    };
    let pose = ToolPose {
        tip,
        axis: Direction::new_normalize(*axis),
    };
    let radius = assembly
        .holder
        .iter()
        .map(|s| s.diameter.max(s.top()) / 2.0)
        .fold(assembly.shank_diameter / 2.0, f64::max)
        + options.margins.holder;
    let length: f64 = assembly
        .holder
        .iter()
        .map(|s| s.length)
        .sum::<f64>()
        .max(1.0);
    let clear = |s: f64| collider.cylinder_clear(&pose, s, s + length, radius);
    let (mut lo, mut hi) = (assembly.flute_length(), 2.0 * assembly.stickout);
    if clear(lo) {
        return lo;
    }
    if !clear(hi) {
        return hi;
    }
    while hi - lo > 0.1 {
        let mid = 0.5 * (lo + hi);
        if clear(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

/// The largest ball radius (≤ `cap`) touching `p` along `n` within `tolerance`, by bisection:
/// `(fits, does_not_fit)`, with `does_not_fit = ∞` when even `cap` fits.
pub fn safe_ball(
    collider: &PartCollider,
    p: &crate::geom::Point3,
    n: &Vector3,
    cap: f64,
    tolerance: f64,
) -> (f64, f64) {
    let fits = |r: f64| collider.check_ball(&(p + n * r), r, tolerance).is_ok();
    if cap <= 0.0 || fits(cap) {
        return (cap, f64::INFINITY);
    }
    let (mut lo, mut hi) = (0.0, cap);
    while hi - lo > 1e-3 * cap {
        let mid = 0.5 * (lo + hi);
        if fits(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (lo, hi)
}

/// Candidate axes as unit vectors in the frame (t1, t2, n): the normal, then rings of growing
/// tilt.
struct AxisRings {
    local: Vec<Vector3>,
}

impl AxisRings {
    fn new(max_tilt_deg: f64, step_deg: f64) -> Self {
        let mut local = vec![Vector3::z()];
        let step = step_deg.max(1.0);
        let mut tilt = step;
        while tilt <= max_tilt_deg.min(90.0) + 1e-9 {
            let t = tilt.to_radians();
            let count = ((std::f64::consts::TAU * t.sin()) / step.to_radians())
                .round()
                .max(6.0) as usize;
            for k in 0..count {
                let a = std::f64::consts::TAU * k as f64 / count as f64;
                local.push(Vector3::new(t.sin() * a.cos(), t.sin() * a.sin(), t.cos()));
            }
            tilt += step;
        }
        Self { local }
    }
}

/// The first axis along which `tool` can touch `p`, or why none can.
fn touch(
    collider: &PartCollider,
    scene: &RayScene,
    tool: &PreparedTool,
    p: &crate::geom::Point3,
    n: &Vector3,
    axes: &AxisRings,
    options: &ToolChoiceOptions,
) -> Result<Vector3, Refusal> {
    let (t1, t2) = orthonormal_frame(n);
    let cutter = tool.cutter();
    // The ray starts inside the cutter's end, so it does not see the face it touches.
    let lift = 0.5 * cutter.end_height() + 1e-3;
    let mut exact = 0;
    // Why, when nothing fits: the last exact test's answer, else the table, else the rays.
    let mut last_exact = None;
    let mut table = false;
    for l in &axes.local {
        let axis = t1 * l.x + t2 * l.y + n * l.z;
        let Some(tip) = cutter.tip_touching(p, n, &axis) else {
            continue;
        };
        let pose = ToolPose {
            tip,
            axis: Direction::new_normalize(axis),
        };
        // The table first: it is plain arithmetic, and it rules out every axis at the underside.
        if collider
            .table()
            .is_some_and(|t| collider.table_clearance(tool, &pose, 0.0) < t.margin)
        {
            table = true;
            continue;
        }
        // Screened by rays along the axis: from the axis and from four points of the flank at
        // 0.9 of the cutter's radius (a flank that grazes a wall it finishes still escapes; one
        // that would run into the opposite wall does not), which spares most exact tests.
        let start = tip + axis * lift;
        let (s1, s2) = orthonormal_frame(&axis);
        let flank = 0.9 * cutter.diameter() / 2.0;
        let blocked = [Vector3::zeros(), s1, -s1, s2, -s2]
            .iter()
            .any(|w| !scene.escapes(&(start + w * flank), &axis, tool.reach));
        if blocked {
            continue;
        }
        exact += 1;
        let checked = if tool.ball_radius > 0.0 {
            // The ball was checked once for the point: only the bodies above depend on the axis.
            collider.check_bodies(tool, &pose)
        } else {
            collider
                .check_touching(tool, p, n, &axis, options.tolerance)
                .map(|_| ())
        };
        match checked {
            Ok(()) => return Ok(axis),
            Err(c) => last_exact = Some(Refusal::of(c)),
        }
        if exact >= options.max_exact_tests {
            break;
        }
    }
    Err(last_exact.unwrap_or(if table {
        Refusal::Table
    } else {
        Refusal::Occluded
    }))
}

/// A third of the area of the triangles around each vertex.
fn vertex_areas(mesh: &Mesh) -> Vec<f64> {
    let mut area = vec![0.0; mesh.positions.len()];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let [a, b, c] = mesh.corners(t);
        let third = triangle_area(&a, &b, &c) / 3.0;
        for &v in tri {
            area[v as usize] += third;
        }
    }
    area
}

/// Every vertex takes the tool of the nearest evaluated point along the mesh (breadth-first from
/// all evaluated points at once, in their order: deterministic).
fn spread(ring: &[Vec<u32>], points: &[PointChoice], vertices: usize) -> Vec<Option<usize>> {
    let mut tool: Vec<Option<Option<usize>>> = vec![None; vertices];
    let mut queue = VecDeque::new();
    for p in points {
        tool[p.vertex as usize] = Some(p.tool);
        queue.push_back(p.vertex);
    }
    while let Some(v) = queue.pop_front() {
        let t = tool[v as usize];
        for &w in &ring[v as usize] {
            if tool[w as usize].is_none() {
                tool[w as usize] = t;
                queue.push_back(w);
            }
        }
    }
    tool.into_iter().map(Option::flatten).collect()
}

/// Connected sets of vertices with the same tool: a label per vertex and the label count.
fn regions(ring: &[Vec<u32>], vertex_tool: &[Option<usize>]) -> (Vec<u32>, usize) {
    let mut label = vec![u32::MAX; vertex_tool.len()];
    let mut count = 0;
    for start in 0..vertex_tool.len() {
        if label[start] != u32::MAX || ring[start].is_empty() {
            continue;
        }
        label[start] = count;
        let mut stack = vec![start as u32];
        while let Some(v) = stack.pop() {
            for &w in &ring[v as usize] {
                if label[w as usize] == u32::MAX && vertex_tool[w as usize] == vertex_tool[start] {
                    label[w as usize] = count;
                    stack.push(w);
                }
            }
        }
        count += 1;
    }
    (label, count as usize)
}

#[allow(clippy::too_many_arguments)]
fn summarise(
    part: &Mesh,
    library: &ToolLibrary,
    order: &[usize],
    curvatures: &[Option<Curvature>],
    areas: &[f64],
    ring: &[Vec<u32>],
    points: &[PointChoice],
    vertex_tool: &[Option<usize>],
    options: &ToolChoiceOptions,
) -> ToolChoiceReport {
    let total_area: f64 = areas.iter().sum();
    let pct = |a: f64| {
        if total_area > 0.0 {
            100.0 * a / total_area
        } else {
            0.0
        }
    };
    let flat = options.flat_curvature;
    let at = |v: usize| {
        let p = part.positions[v];
        [p.x, p.y, p.z]
    };

    let mut class_area: BTreeMap<ShapeClass, f64> = BTreeMap::new();
    let mut min_concave: Option<(f64, usize)> = None;
    for (v, k) in curvatures.iter().enumerate() {
        let Some(k) = k else { continue };
        *class_area.entry(k.class(flat)).or_default() += areas[v];
        if let Some(r) = k.concave_radius(flat)
            && min_concave.is_none_or(|(m, _)| r < m)
        {
            min_concave = Some((r, v));
        }
    }
    let min_ball = points
        .iter()
        .min_by(|a, b| a.safe_ball.total_cmp(&b.safe_ball));

    let (label, region_count) = regions(ring, vertex_tool);
    // Per region: vertices, area, weighted centre, min concave radius, min safe ball.
    let mut per_region = vec![
        Region {
            vertices: 0,
            area_mm2: 0.0,
            centre: [0.0; 3],
            min_concave_radius_mm: None,
            largest_safe_ball_mm: f64::INFINITY,
            reach_needed_mm: 0.0,
        };
        region_count
    ];
    let mut moments = vec![Vector3::zeros(); region_count];
    for v in 0..part.positions.len() {
        if label[v] == u32::MAX {
            continue;
        }
        let r = &mut per_region[label[v] as usize];
        r.vertices += 1;
        r.area_mm2 += areas[v];
        moments[label[v] as usize] += part.positions[v].coords * areas[v];
        if let Some(c) = curvatures[v].and_then(|k| k.concave_radius(flat)) {
            r.min_concave_radius_mm = Some(r.min_concave_radius_mm.map_or(c, |m| m.min(c)));
        }
    }
    for p in points {
        let r = &mut per_region[label[p.vertex as usize] as usize];
        r.largest_safe_ball_mm = r.largest_safe_ball_mm.min(p.safe_ball);
        r.reach_needed_mm = r.reach_needed_mm.max(p.reach.unwrap_or(0.0));
    }
    for (r, m) in per_region.iter_mut().zip(&moments) {
        let c = if r.area_mm2 > 0.0 { m / r.area_mm2 } else { *m };
        r.centre = [c.x, c.y, c.z];
    }
    let region_of = |index: usize| per_region[index].clone();
    let mut regions_of_tool: BTreeMap<Option<usize>, Vec<usize>> = BTreeMap::new();
    let mut seen = vec![false; region_count];
    for v in 0..part.positions.len() {
        if label[v] != u32::MAX && !seen[label[v] as usize] {
            seen[label[v] as usize] = true;
            regions_of_tool
                .entry(vertex_tool[v])
                .or_default()
                .push(label[v] as usize);
        }
    }
    let refusals = |tool: Option<usize>| {
        let mut counts = BTreeMap::new();
        for p in points.iter().filter(|p| p.tool == tool) {
            if let Some(r) = p.refusal {
                *counts.entry(r).or_insert(0) += 1;
            }
        }
        counts
    };

    let mut proposal = Vec::new();
    let mut not_used = Vec::new();
    for &i in order {
        let tool = &library.tools[i];
        let list = regions_of_tool.get(&Some(i)).cloned().unwrap_or_default();
        if list.is_empty() {
            not_used.push(UnusedTool {
                id: tool.id,
                name: tool.name.clone(),
                why: {
                    let rank = order_rank(order, i);
                    let tried = points
                        .iter()
                        .filter(|p| p.tool.is_none_or(|t| order_rank(order, t) > rank))
                        .count();
                    format!(
                        "larger tools finish every point it can; it was refused on the {tried} \
                         point(s) left for it"
                    )
                },
            });
            continue;
        }
        let mut regions: Vec<Region> = list.iter().map(|&r| region_of(r)).collect();
        let area: f64 = regions.iter().map(|r| r.area_mm2).sum();
        let vertices = regions.iter().map(|r| r.vertices).sum();
        regions.sort_by(|a, b| b.area_mm2.total_cmp(&a.area_mm2));
        regions.truncate(10);
        proposal.push(ProposedTool {
            id: tool.id,
            name: tool.name.clone(),
            tool: tool.describe(),
            area_mm2: area,
            percent: pct(area),
            vertices,
            regions: list.len(),
            larger_refused_for: refusals(Some(i)),
            reach_needed_mm: points
                .iter()
                .filter(|p| p.tool == Some(i))
                .filter_map(|p| p.reach)
                .fold(0.0, f64::max),
            stickout_mm: tool.stickout,
            largest_regions: regions,
        });
    }
    let unreachable_regions = regions_of_tool.get(&None).cloned().unwrap_or_default();
    let unreachable_area: f64 = unreachable_regions
        .iter()
        .map(|&r| per_region[r].area_mm2)
        .sum();
    ToolChoiceReport {
        vertices: part.positions.len(),
        points_evaluated: points.len(),
        tolerance_mm: options.tolerance,
        area_mm2: total_area,
        shape: ShapeSummary {
            percent: class_area.into_iter().map(|(c, a)| (c, pct(a))).collect(),
            min_concave_radius_mm: min_concave.map(|(r, _)| r),
            min_concave_radius_at: min_concave.map(|(_, v)| at(v)),
            min_safe_ball_mm: min_ball.map_or(0.0, |p| p.safe_ball),
            min_safe_ball_at: min_ball.map(|p| at(p.vertex as usize)),
        },
        proposal,
        not_used,
        unreachable: Unreachable {
            vertices: unreachable_regions
                .iter()
                .map(|&r| per_region[r].vertices)
                .sum(),
            area_mm2: unreachable_area,
            percent: pct(unreachable_area),
            regions: unreachable_regions.len(),
            smallest_refused_for: refusals(None),
        },
    }
}

fn order_rank(order: &[usize], index: usize) -> usize {
    order.iter().position(|&i| i == index).unwrap_or(usize::MAX)
}

#[cfg(test)]
mod tests;
