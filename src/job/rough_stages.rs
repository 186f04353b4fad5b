//! The roughing stages `wavemill rough` and a plan's roughing operations share: the blank as
//! layers see it, the choice of end mills from a library, one tool's layers on the planning
//! stock, and the program cut back into tools after posting.

use super::blank::BlankSpec;
use crate::contour::geometry::Point2;
use crate::error::{Error, Result};
use crate::feed::{Cutter as FeedCutter, CuttingModel, FeedReport, control_feeds};
use crate::geom::Point3;
use crate::rough::{Blank, Material, RoughingFeeds, RoughingOptions, RoughingTool, rough_within};
use crate::stock::Stock;
use crate::stock::cutter::CuttingBody;
use crate::tool::{Cutter, ToolAssembly, ToolLibrary};

/// The layer-roughing blank of a box or cylinder spec (others are refused: layers clear a
/// prism).
pub(super) fn layer_blank(spec: &BlankSpec, part: &crate::mesh::Mesh) -> Result<Blank> {
    match spec.resolved(part) {
        BlankSpec::Cylinder { radius, z0, z1 } => {
            let centre = part.aabb().center();
            Ok(Blank::cylinder(
                Point2::new(centre.x, centre.y),
                radius,
                z0,
                z1,
            ))
        }
        BlankSpec::Box(b) => Ok(Blank::cuboid(
            Point3::new(b[0], b[1], b[2]),
            Point3::new(b[3], b[4], b[5]),
        )),
        other => Err(Error::Usage(format!(
            "blank `{}`: layer roughing clears a box or a cylinder blank",
            other.describe()
        ))),
    }
}

/// How one tool roughs, beyond its shape and blank.
pub(super) struct ToolRoughing<'a> {
    /// The holder stays this far above the blank, mm.
    pub holder_margin: f64,
    /// The lowest the tool tip goes, mm.
    pub floor: f64,
    pub feeds: &'a RoughingFeeds,
    pub tolerance: f64,
    /// Feeds from each move's engagement ([`crate::feed`]) at this spindle speed; `None`: the
    /// programmed feeds.
    pub feed_control: Option<(CuttingModel, f64)>,
    /// Equal layers at the largest depth of cut, without the extra planes at flats (the
    /// conventional z-level roughing the baseline is).
    pub uniform_layers: bool,
    /// The largest depth of cut, mm; `None`: the tool's radius.
    pub max_depth: Option<f64>,
    /// Widest radial engagement of a pass, as a share of the tool's diameter (1: every pass
    /// straight, slots and all).
    pub max_engagement: f64,
    /// The planner of each layer's passes.
    pub paths: crate::rough::LayerPaths,
    /// The smallest depth of cut, mm (thinner layers merge upward); `None`: a fifth of the
    /// tool's radius.
    pub min_depth: Option<f64>,
}

/// One tool's layers, and what feed control made of their feeds.
pub(super) struct ToolLayers {
    pub tool: RoughingTool,
    pub layers: crate::rough::Roughing,
    pub feed_control: Option<FeedReport>,
}

impl ToolLayers {
    /// Whether any move cuts (a blank with nothing outside the shape gives none).
    pub fn cuts(&self) -> bool {
        self.layers
            .toolpath
            .moves
            .iter()
            .any(|m| m.kind == crate::geom::MoveKind::Cut)
    }

    /// Length of the cutting moves, mm.
    pub fn cutting_length(&self) -> f64 {
        self.layers.toolpath.cutting_length()
    }
}

/// The layer planner's options for `assembly` (its roughing view `tool`) roughing as `how`
/// says.
pub(super) fn roughing_options(
    tool: &RoughingTool,
    assembly: &ToolAssembly,
    how: &ToolRoughing,
) -> RoughingOptions {
    let mut options = RoughingOptions::for_radius(tool.radius);
    options.floor = Some(how.floor);
    options.feeds = how.feeds.clone();
    options.tolerance = how.tolerance;
    if how.uniform_layers {
        options.layers.flat_area = f64::INFINITY;
    }
    options.paths = how.paths;
    options.max_engagement =
        (how.max_engagement < 1.0).then(|| how.max_engagement * assembly.cutter.diameter());
    if let Some(depth) = how.max_depth {
        options.layers.max_depth = depth;
        options.layers.min_depth = options.layers.min_depth.min(depth);
    }
    if let Some(depth) = how.min_depth {
        options.layers.min_depth = depth.min(options.layers.max_depth);
    }
    options
}

/// Layers of one tool down to `shape`: from the whole blank (`from_blank`), else only where
/// `stock` still holds material; each layer is taken off `stock` as it is planned. `stock` is the planning model the next tool starts from. With feed
/// control, each move's feed is set from the volume it takes off the stock as it stood.
pub(super) fn rough_with_tool(
    guard: crate::rough::Guard,
    blank: &Blank,
    assembly: &ToolAssembly,
    how: &ToolRoughing,
    stock: &mut Stock,
    from_blank: bool,
) -> std::result::Result<ToolLayers, crate::rough::RoughError> {
    let tool = RoughingTool::of(assembly, how.holder_margin);
    let options = roughing_options(&tool, assembly, how);
    let body = CuttingBody::of(&assembly.cutter);
    // Either way each layer comes off the stock as it is planned, which measures what each
    // move removes from the stock as it stood.
    let material = if from_blank {
        Material::BlankOnStock {
            stock: &mut *stock,
            body: &body,
        }
    } else {
        Material::Stock {
            stock: &mut *stock,
            body: &body,
        }
    };
    let mut layers = rough_within(guard, blank, &tool, assembly.id, material, &options)?;
    let removed = std::mem::take(&mut layers.removed_mm3);
    let feed_control = how.feed_control.map(|(model, spindle_rpm)| {
        let cutter = FeedCutter {
            diameter: assembly.cutter.diameter(),
            spindle_rpm,
            pass_feed: how.feeds.cut,
            rapid_feed: how.feeds.rapid,
            speed_up: true,
        };
        let skin = how.tolerance * stock.spacing() * stock.spacing();
        let (feeds, report) = control_feeds(&layers.toolpath, &removed, &cutter, &model, skin);
        for (m, feed) in layers.toolpath.moves.iter_mut().zip(feeds) {
            m.feed = feed;
        }
        report
    });
    Ok(ToolLayers {
        tool,
        layers,
        feed_control,
    })
}

/// CL data of several tools' moves, each row with its tool.
pub(super) fn cl_csv_of(moves: &[(u32, crate::geom::Move)]) -> String {
    let mut out = String::new();
    let mut start = 0;
    while start < moves.len() {
        let id = moves[start].0;
        let end = moves[start..]
            .iter()
            .position(|(t, _)| *t != id)
            .map_or(moves.len(), |n| start + n);
        let text = crate::post::write_cl_csv(&crate::geom::Toolpath {
            tool_id: id,
            moves: moves[start..end].iter().map(|(_, m)| *m).collect(),
        });
        if start == 0 {
            out.push_str(&text);
        } else {
            // The header line once.
            out.extend(text.lines().skip(1).flat_map(|l| [l, "\n"]));
        }
        start = end;
    }
    out
}

/// The read-back program cut at its tool changes (`T… M6` lines) into one toolpath per tool,
/// each starting from where the one before it ended.
pub(super) fn split_at_tool_changes(
    gcode: &str,
    posted: &crate::geom::Toolpath,
    lines: &[usize],
    tools: usize,
) -> Result<Vec<crate::geom::Toolpath>> {
    let changes: Vec<usize> = gcode
        .lines()
        .enumerate()
        // ISO `Tn M6`; Heidenhain conversational `<block> TOOL CALL n Z …`.
        .filter(|(_, l)| {
            (l.starts_with('T') && l.ends_with(" M6"))
                || l.split_once(' ')
                    .is_some_and(|(_, rest)| rest.starts_with("TOOL CALL "))
        })
        .map(|(k, _)| k + 1)
        .collect();
    if changes.len() != tools {
        return Err(Error::Internal(format!(
            "the roughing program has {} tool changes for {tools} tools",
            changes.len()
        )));
    }
    let mut sections = Vec::with_capacity(tools);
    for k in 0..tools {
        let (from, to) = (
            changes[k],
            changes.get(k + 1).copied().unwrap_or(usize::MAX),
        );
        let first = lines.iter().position(|&l| l > from).unwrap_or(lines.len());
        let last = lines.iter().position(|&l| l > to).unwrap_or(lines.len());
        let begin = first.saturating_sub(1);
        sections.push(crate::geom::Toolpath {
            tool_id: posted.tool_id,
            moves: posted.moves[begin..last.max(begin)].to_vec(),
        });
    }
    Ok(sections)
}

/// The library's flat and bull-nose end mills, largest first.
fn roughers(library: &ToolLibrary) -> Vec<&ToolAssembly> {
    library
        .largest_first()
        .into_iter()
        .map(|i| &library.tools[i])
        .filter(|t| matches!(t.cutter, Cutter::Flat { .. } | Cutter::BullNose { .. }))
        .collect()
}

/// The library tool `id`, or an error naming it.
pub(super) fn library_tool(library: &ToolLibrary, id: u32) -> Result<(ToolAssembly, String)> {
    let tool = library
        .tools
        .iter()
        .find(|t| t.id == id)
        .ok_or_else(|| Error::Usage(format!("the library has no tool with id {id}")))?;
    if !matches!(tool.cutter, Cutter::Flat { .. } | Cutter::BullNose { .. }) {
        return Err(Error::Usage(format!(
            "T{id} ({}) is not a flat or bull-nose end mill: layers are roughed with one",
            tool.describe()
        )));
    }
    Ok((tool.clone(), format!("asked for (T{id})")))
}

/// The tool that roughs the blank, and why: `id` if given, else the largest flat or
/// bull-nose end mill of the library, the first of them that reaches `depth` below the
/// blank's top (its stickout less `holder_margin`) if any does.
pub(super) fn first_rougher(
    library: &ToolLibrary,
    id: Option<u32>,
    depth: f64,
    holder_margin: f64,
) -> Result<(ToolAssembly, String)> {
    if let Some(id) = id {
        return library_tool(library, id);
    }
    let roughers = roughers(library);
    let reaches = |t: &ToolAssembly| t.stickout - holder_margin >= depth;
    let Some(largest) = roughers.first() else {
        return Err(Error::Usage(
            "the library has no flat or bull-nose end mill to rough with".into(),
        ));
    };
    Ok(match roughers.iter().find(|t| reaches(t)) {
        Some(t) => (
            (*t).clone(),
            format!("the largest flat or bull-nose end mill reaching {depth:.1} mm deep"),
        ),
        None => (
            (*largest).clone(),
            format!("the largest flat or bull-nose end mill; none reaches {depth:.1} mm deep"),
        ),
    })
}

/// The tool that rest-roughs after one of `previous` mm, and why: `id` if given, else the
/// largest end mill at most 3/4 of it across, preferring one that reaches `depth`; `None`
/// when the library has no smaller one.
pub(super) fn next_rougher(
    library: &ToolLibrary,
    id: Option<u32>,
    previous: f64,
    depth: f64,
    holder_margin: f64,
) -> Result<Option<(ToolAssembly, String)>> {
    if let Some(id) = id {
        return library_tool(library, id).map(Some);
    }
    let reaches = |t: &ToolAssembly| t.stickout - holder_margin >= depth;
    let smaller: Vec<&ToolAssembly> = roughers(library)
        .into_iter()
        .filter(|t| t.cutter.diameter() <= 0.75 * previous)
        .collect();
    let Some(next) = smaller.iter().find(|t| reaches(t)).or(smaller.first()) else {
        return Ok(None);
    };
    let why = format!(
        "rest roughing: the largest end mill at most 3/4 of the D{previous} before it{}",
        if reaches(next) {
            ""
        } else {
            " (it does not reach the floor)"
        }
    );
    Ok(Some(((*next).clone(), why)))
}
