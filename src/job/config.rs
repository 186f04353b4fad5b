//! The job file (TOML): part, units, tool, machine, strategy, feeds, safety margins, and the
//! operations (`[[operation]]`, see [`super::operation`]).
//!
//! Every field has a documented default, embedded here, so `wavemill plan PART` works without a
//! job file; a job file only says what differs, and CLI flags override both. Unknown keys are
//! errors (a misspelt `scallop_heigth` must not silently fall back to the default).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

pub use crate::error::JobError;
use crate::tool::{Cutter, Section, ToolAssembly};

fn invalid(key: &str, reason: String) -> JobError {
    JobError::Invalid {
        key: key.to_string(),
        reason,
    }
}

/// A whole job.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Job {
    pub part: PartSection,
    pub tool: ToolSection,
    pub machine: MachineSection,
    pub surface: SurfaceSection,
    pub strategy: StrategySection,
    pub feeds: FeedSection,
    pub safety: SafetySection,
    pub limits: LimitsSection,
    pub stock: StockSection,
    pub roughing: RoughingSection,
    pub cutting: CuttingSection,
    pub impeller: ImpellerSection,
    /// `[corner_tool]`: a ball smaller than `[tool]`'s that finishes the corners after it
    /// (a `corner-finish` operation last, in a job without `[[operation]]` tables); left out:
    /// none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub corner_tool: Option<ToolSection>,
    /// The operations, in order (`[[operation]]` tables); empty: the ones today's
    /// `[strategy]` keys describe (see [`Job::operations`]).
    #[serde(rename = "operation", skip_serializing_if = "Vec::is_empty")]
    pub operations: Vec<OperationSection>,
}

/// `[impeller]`: recognising the part as an impeller (axis, blades, splitters, hub;
/// [`crate::impeller`]), reported in `report.json`. Given keys are checked on the part, not
/// taken on trust: a part that does not match them is an error.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ImpellerSection {
    /// Look for an impeller at all.
    pub recognise: bool,
    /// The rotation axis in the part frame (after `part.up`); left out: found.
    pub axis: Option<[f64; 3]>,
    /// The main blades' count (the order of the rotational symmetry); left out: found.
    pub blades: Option<usize>,
    /// Finish a recognised impeller with its own strategies (flow lines over the hub between
    /// the blades, loops around the blades, copied by the symmetry; the parallel planes for
    /// the rest); `false`: the parallel planes everywhere.
    pub finishing: bool,
    /// The tool axes on the hub: `"passage"`, one per passage (the mean of its walls' span
    /// directions: the rotary axes stand still along the passes); `"visibility"`, one per
    /// passage too, the direction with the most room among those every point of the passage
    /// sees (from the points' visibility maps, nearest the walls' mean among equals); or
    /// `"walls"`, the walls' span directions interpolated across the passage, leaning toward
    /// the feed.
    pub hub_axes: HubAxes,
    /// The tool axes around a blade: `"blade"`, the passages' axis turned to the blade (the
    /// rotary axes stand still round each loop); `"visibility"`, one axis per blade too, the
    /// direction with the most room among those every point round it sees (from the
    /// visibility maps of points on its loops, nearest the passages' axis among equals;
    /// splitters take it turned to them); or `"lean"`, the blade's rising direction leaned off
    /// its surface by `blade_lean_deg`.
    pub blade_axes: BladeAxes,
    /// How far the tool leans off a blade's surface with `blade_axes = "lean"`, degrees (0:
    /// along the blade, cutting with the ball's equator; 90: square to the surface).
    pub blade_lean_deg: f64,
    /// Swarf a blade where its flanks are ruled within the strategy's tolerance and no taller
    /// than the flutes: passes round its root with the tool along the rulings, the flutes
    /// cutting the flank; the loops finish the rest (`report.json` says where and why). On by
    /// default; the posted program is checked along the flutes as along the ball.
    pub swarf: bool,
    /// Passes along each blade's tip (its land, facing away from the hub), kept where the
    /// loops leave it; off when the tips are turned to the shroud's contour afterwards.
    pub tip: bool,
    /// Rest passes: the first passage as planned is measured against its balls, and a pass is
    /// added along each place left over the scallop target (where the part departs from the
    /// surface the strategies space their passes by), copied with the passage; then the same
    /// over what the parallel planes finish (a wall they cross at a slant, the ends of their
    /// pieces). Off: faster, and the report's scallop shows what they would have mended.
    pub rest: bool,
}

/// How the tool axes are set around a blade.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BladeAxes {
    Blade,
    Visibility,
    Lean,
}

/// How the tool axes are set on the hub between the blades.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum HubAxes {
    Passage,
    Visibility,
    Walls,
}

impl Default for ImpellerSection {
    fn default() -> Self {
        Self {
            recognise: true,
            axis: None,
            blades: None,
            finishing: true,
            hub_axes: HubAxes::Passage,
            blade_axes: BladeAxes::Blade,
            blade_lean_deg: 20.0,
            swarf: true,
            tip: true,
            rest: true,
        }
    }
}

impl ImpellerSection {
    /// Whether the job states anything about the impeller (then it must be one).
    pub fn is_given(&self) -> bool {
        self.axis.is_some() || self.blades.is_some()
    }
}

/// How much work a job may ask for before it is refused (with a message saying how to raise
/// the limit), so that a mistyped unit or scallop height fails at once instead of running for
/// hours or exhausting memory.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LimitsSection {
    /// Most drive points the finishing passes may have, estimated before planning as the
    /// part's area over (stepover × `strategy.max_step`), a lower estimate (the sample impeller
    /// at the defaults: 55 thousand estimated, 156 thousand planned in about 35 s). Each point
    /// costs a few collision queries.
    pub max_drive_points: u64,
}

impl Default for LimitsSection {
    fn default() -> Self {
        Self {
            max_drive_points: 2_000_000,
        }
    }
}

/// `[stock]`: the blank the job starts from. By default the part's bar stock (`cylinder`):
/// it is roughed first, and every operation's moves are run on the in-process stock (a
/// tri-dexel model, [`crate::stock`]) in order; a shank, neck or holder touching material, a
/// rapid through it or a gouge fails the plan. `blank = "none"` takes the part as already
/// roughed: nothing is roughed or simulated.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StockSection {
    /// `cylinder` (about the part's vertical axis, holding it with 2 mm to spare, the
    /// default), `box:X0,Y0,Z0,X1,Y1,Z1`, `cylinder:R,Z0,Z1` (about the vertical line through
    /// the part's box centre), `offset:M` (the part grown by M) or `mesh:FILE` (relative to the
    /// job file), mm, in the part's frame as planned; `none` (or no value) for no blank.
    pub blank: Option<String>,
    /// Distance between dexel lines, mm; leave out for the part's box diagonal / 400, within
    /// 0.05 to 1 mm.
    pub resolution: Option<f64>,
}

/// What `blank = "none"` says: the part is already roughed.
pub const NO_BLANK: &str = "none";

impl Default for StockSection {
    fn default() -> Self {
        Self {
            blank: Some("cylinder".into()),
            resolution: None,
        }
    }
}

impl StockSection {
    /// The blank, read; `None` for `none` (or no value): the part is taken as roughed.
    pub fn blank_spec(&self) -> Result<Option<super::blank::BlankSpec>, JobError> {
        self.blank
            .as_deref()
            .filter(|text| text.trim() != NO_BLANK)
            .map(|text| super::blank::BlankSpec::parse(text).map_err(|e| invalid("stock.blank", e)))
            .transpose()
    }
}

/// `[roughing]`: where the roughing tools come from and how they cut. Roughing operations
/// (`kind = "rough"`, `"rest-rough"`) clear the `[stock]` blank in layers down to the part's
/// offset shape at their `stock_to_leave` with the library's flat and bull-nose end mills,
/// 3-axis ([`crate::rough`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RoughingSection {
    /// Tool library file (relative to the job file); leave out for the bundled one
    /// (`data/tools.toml`).
    pub library: Option<PathBuf>,
    /// Material the roughing leaves on the part when the operations are not listed, mm.
    pub allowance: f64,
    /// Smaller end mills that rest-rough after the first when the operations are not listed,
    /// each only where material stands.
    pub rest_tools: usize,
    pub spindle_rpm: u32,
    /// Feed along the layers, mm/min.
    pub cut_feed: f64,
    /// Feed down the ramps into material, mm/min.
    pub entry_feed: f64,
    /// Widest radial engagement a layer's pass may take, as a share of the tool's diameter:
    /// slots and concave corners heavier than this are cut as trochoidal loops where there
    /// is room (1 cuts every pass straight).
    pub max_engagement: f64,
    /// The planner of each layer's passes: `offsets` (exact offsets of the section, far side
    /// first) or `wavelet` (seed 004's wavelet passes inside the loose convex hull).
    pub layer_paths: crate::rough::LayerPaths,
    /// When the operations are not listed: after the vertical end mills, at most this many
    /// indexed (3+2) setups rough the rest they leave under overhangs, with the last end
    /// mill along tilted axes proposed from the visibility maps (`indexed-rough`); 0: none.
    pub indexed_setups: usize,
    /// Indexed setups: the steepest tilt of the tool axis from the vertical, degrees.
    pub indexed_max_tilt_deg: f64,
    /// When the operations are not listed: after the end mills, rough the rest they leave
    /// under overhangs and between blades with the job's ball, 5-axis, in offset layers
    /// (`channel-rough`).
    pub channel: bool,
    /// Channel roughing: mm between its offset layers; leave out for the ball's radius.
    pub channel_step: Option<f64>,
    /// Channel roughing: offset layers at most (the deepest rest beyond them stays).
    pub channel_max_layers: usize,
    /// Channel roughing: scallop height of its passes on each layer, mm.
    pub channel_scallop_height: f64,
    /// Channel roughing: `shroud-to-hub` or `offset` layers.
    pub channel_layering: Layering,
}

impl Default for RoughingSection {
    fn default() -> Self {
        Self {
            library: None,
            allowance: 0.5,
            rest_tools: 1,
            spindle_rpm: 8000,
            cut_feed: 2000.0,
            entry_feed: 800.0,
            max_engagement: 0.5,
            layer_paths: crate::rough::LayerPaths::default(),
            indexed_setups: 0,
            indexed_max_tilt_deg: 60.0,
            channel: false,
            channel_step: None,
            channel_max_layers: 40,
            channel_scallop_height: 0.25,
            channel_layering: Layering::default(),
        }
    }
}

impl RoughingSection {
    /// The library the roughing tools come from.
    pub fn tool_library(&self) -> Result<crate::tool::ToolLibrary, JobError> {
        let read = match &self.library {
            Some(path) => crate::tool::ToolLibrary::read(path),
            None => crate::tool::ToolLibrary::parse(BUNDLED_LIBRARY, "the bundled data/tools.toml"),
        };
        read.map_err(|e| invalid("roughing.library", e.to_string()))
    }
}

/// `[cutting]`: the material's cutting-force model and the machine's feed limits. The
/// roughing operations' feeds are set from each move's engagement so the mean tangential
/// force stays at the target ([`crate::feed`], seed 004 ch. 5 step 8).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CuttingSection {
    /// What is cut, for the report.
    pub material: String,
    /// K_t, N/mm²: 800 for aluminium 7075, about 2000 for Ti-6Al-4V, 3000 for Inconel 718.
    pub specific_force: f64,
    /// The force to hold, N; leave out for each tool's nominal cut (D/2 wide, D/2 deep, at the
    /// programmed cut feed).
    pub target_force: Option<f64>,
    /// The machine's feed limits, mm/min.
    pub min_feed: f64,
    pub max_feed: f64,
    /// Off: the programmed feeds throughout.
    pub feed_control: bool,
}

impl Default for CuttingSection {
    fn default() -> Self {
        let model = crate::feed::CuttingModel::default();
        Self {
            material: "aluminium 7075".into(),
            specific_force: model.specific_force,
            target_force: model.target_force,
            min_feed: model.min_feed,
            max_feed: model.max_feed,
            feed_control: true,
        }
    }
}

impl CuttingSection {
    /// The cutting model, or `None` with feed control off.
    pub fn model(&self) -> Option<crate::feed::CuttingModel> {
        self.feed_control.then_some(crate::feed::CuttingModel {
            specific_force: self.specific_force,
            target_force: self.target_force,
            min_feed: self.min_feed,
            max_feed: self.max_feed,
        })
    }
}

/// The tool library shipped with wavemill, for jobs that name none.
pub const BUNDLED_LIBRARY: &str = include_str!("../../data/tools.toml");

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PartSection {
    /// Mesh file; relative paths are relative to the job file. The CLI's PART overrides it.
    pub path: Option<PathBuf>,
    /// Units the mesh file is written in: "mm" (default), "m" or "in".
    pub units: Option<String>,
    /// The direction in the file that points up the machine's C axis (the part's axis of
    /// rotation for an impeller); the part is turned so that it becomes +Z. Default +Z.
    pub up: Option<[f64; 3]>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ToolSection {
    /// Tool number (T word, H offset).
    pub id: u32,
    /// Ball diameter, mm.
    pub diameter: f64,
    /// Fluted length from the tip, mm.
    pub flute_length: f64,
    /// A relieved neck above the flutes, `{ diameter, length }` (mm; its length from the
    /// flutes' top): how a small ball reaches down a wall; left out: none.
    pub neck: Option<crate::tool::Neck>,
    pub shank_diameter: f64,
    /// Length out of the holder, from the tip, mm.
    pub stickout: f64,
    /// Holder sections from the nose up.
    pub holder: Vec<Section>,
    pub spindle_rpm: u32,
}

impl Default for ToolSection {
    /// A 4 mm ball mill, 36 mm out of a slim shrink-fit holder: a common impeller finisher.
    fn default() -> Self {
        Self {
            id: 1,
            diameter: 4.0,
            flute_length: 10.0,
            neck: None,
            shank_diameter: 4.0,
            stickout: 36.0,
            holder: vec![
                Section {
                    diameter: 12.0,
                    top_diameter: Some(22.0),
                    length: 30.0,
                },
                Section::cylinder(40.0, 40.0),
            ],
            spindle_rpm: 16000,
        }
    }
}

impl ToolSection {
    pub fn assembly(&self) -> ToolAssembly {
        ToolAssembly {
            id: self.id,
            name: String::new(),
            cutter: Cutter::Ball {
                diameter: self.diameter,
                flute_length: self.flute_length,
            },
            neck: self.neck,
            shank_diameter: self.shank_diameter,
            stickout: self.stickout,
            holder: self.holder.clone(),
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MachineSection {
    /// A machine definition (`data/machines/*.toml`): a shipped machine's name
    /// (`trunnion-ac`, `trunnion-bc`, `head-table-bc`, `head-table-ac`, `head-head`) or a file
    /// (relative to the job file). It sets the kinematics, the control's dialect, output mode
    /// and feed mode, the rapid feed and the rotary speed; `kinematics`, `a_limits`,
    /// `c_limits`, `rapid_feed` and `max_rotary_speed` here are then not used.
    pub definition: Option<String>,
    /// Overrides the definition's output mode: `"joint"` or `"tcp"`.
    pub output: Option<crate::post::OutputMode>,
    /// Overrides the definition's feed mode: `"per-minute"` or `"inverse-time"`.
    pub feed: Option<crate::post::FeedMode>,
    /// The machine's kinematics without a definition: `"table-table-ac"` (the other kinds
    /// need a definition; a name the post does not know is refused when the file is read).
    pub kinematics: crate::post::KinematicsKind,
    /// Where the part frame's origin sits relative to the pivot (A and C axes' intersection), mm.
    pub part_origin_in_table: Option<[f64; 3]>,
    /// A axis travel, degrees.
    pub a_limits: [f64; 2],
    /// C axis travel, degrees; absent = continuous.
    pub c_limits: Option<[f64; 2]>,
    /// Distance of the safe retract plane from the pivot, mm; absent = the part's reach from
    /// the pivot plus `safe_margin`.
    pub safe_distance: Option<f64>,
    /// mm added to the part's reach for the automatic safe distance.
    pub safe_margin: f64,
    /// Height of the table top (or fixture top) in the part frame, mm; absent = the part's
    /// lowest point (the part stands on the table). The tool stays `safety.table_margin` above it.
    pub table_z: Option<f64>,
    /// mm/min.
    pub rapid_feed: f64,
    /// Fastest rotary motion, degrees/min, for time estimates.
    pub max_rotary_speed: f64,
}

impl Default for MachineSection {
    fn default() -> Self {
        Self {
            definition: None,
            output: None,
            feed: None,
            kinematics: crate::post::KinematicsKind::TableTableAc,
            part_origin_in_table: None,
            a_limits: [-120.0, 120.0],
            c_limits: None,
            safe_distance: None,
            safe_margin: 20.0,
            table_z: None,
            rapid_feed: 15000.0,
            max_rotary_speed: 7200.0,
        }
    }
}

/// The surface the passes are driven on: the part itself when it already has subdivision
/// connectivity, else the finest level of its multiresolution hierarchy (DESIGN.md §3.2). The
/// tool is always kept off the part as read, whichever surface drives it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SurfaceSection {
    /// Remesh a part that is not semi-regular (default true); false drives on the part as read.
    pub remesh: bool,
    /// Two-sided Hausdorff distance the finest level must reach, mm.
    pub tolerance: f64,
    /// Triangles of the hierarchy's base mesh (a target: see `base_max_error`).
    pub base_triangles: usize,
    /// The base stops simplifying when a collapse would move the surface more than this, mm;
    /// absent = 3 × `tolerance`.
    pub base_max_error: Option<f64>,
    /// At most this many levels above the base.
    pub max_levels: u32,
    /// No level larger than this many triangles.
    pub max_triangles: usize,
    /// Edges whose faces meet at more than this angle are feature lines, degrees.
    pub crease_angle_deg: f64,
}

impl Default for SurfaceSection {
    fn default() -> Self {
        let r = crate::multires::RemeshOptions::default();
        Self {
            remesh: true,
            tolerance: r.tolerance,
            base_triangles: r.base_triangles,
            base_max_error: None,
            max_levels: r.max_levels,
            max_triangles: 1_000_000,
            crease_angle_deg: r.crease_angle_deg,
        }
    }
}

impl SurfaceSection {
    /// The remeshing options these settings stand for.
    pub fn remesh_options(&self) -> crate::multires::RemeshOptions {
        crate::multires::RemeshOptions {
            tolerance: self.tolerance,
            base_triangles: self.base_triangles,
            base_max_error: Some(self.base_max_error.unwrap_or(3.0 * self.tolerance)),
            crease_angle_deg: self.crease_angle_deg,
            max_levels: self.max_levels,
            max_triangles: self.max_triangles,
            ..crate::multires::RemeshOptions::default()
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StrategySection {
    /// Cusp height left between passes on a flat surface, mm.
    pub scallop_height: f64,
    /// Chord and post-processor tolerance, mm.
    pub tolerance: f64,
    /// Normal of the parallel drive planes.
    pub drive_normal: [f64; 3],
    /// Longest step between drive points before refinement, mm.
    pub max_step: f64,
    pub lead_deg: f64,
    pub tilt_deg: f64,
    /// How far the axis may turn from the preferred lead/tilt axis to avoid collisions, degrees.
    pub max_axis_deviation_deg: f64,
    /// Largest axis change between consecutive poses, degrees.
    pub max_axis_turn_deg: f64,
    /// Axis smoothing along each pass: largest axis change per mm of travel, degrees (on the
    /// built-in A/C machine with a continuous C, of each rotary axis); 0 keeps the point-by-point choice. Smoothed axes
    /// are checked like chosen ones.
    pub max_axis_change_deg_per_mm: f64,
    /// Width (σ) of the Gaussian average of the axes along a pass, mm; 0 leaves only the rate
    /// limit.
    pub axis_smoothing_window_mm: f64,
    /// Stock to leave by semi-finishing before the finishing passes, mm, strictly decreasing
    /// (issue 4): one intermediate shape of the part's hierarchy per allowance (shape j offsets
    /// level j, as `wavemill offsets` builds them), each machined with the ball centre driven
    /// on the shape, coarsest first. Empty: finishing only.
    pub semi_finish_allowances: Vec<f64>,
    /// Scallop height of the semi-finishing passes, mm.
    pub semi_finish_scallop_height: f64,
}

impl Default for StrategySection {
    fn default() -> Self {
        Self {
            scallop_height: 0.01,
            tolerance: 0.01,
            drive_normal: [1.0, 0.0, 0.0],
            max_step: 1.0,
            lead_deg: 10.0,
            tilt_deg: 0.0,
            max_axis_deviation_deg: 70.0,
            max_axis_turn_deg: 5.0,
            max_axis_change_deg_per_mm: 2.0,
            axis_smoothing_window_mm: 2.0,
            semi_finish_allowances: Vec::new(),
            semi_finish_scallop_height: 0.05,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FeedSection {
    /// mm/min.
    pub cut: f64,
    pub approach: f64,
    pub retract: f64,
    /// Distance above the entry point where the rapid plunge turns into the approach feed, mm.
    pub clearance: f64,
    /// Longest short link between two ball passes, mm: the next pass starting this near is
    /// reached by a small lift, a checked move across at the retract feed and a plunge, not
    /// by way of the safe plane. 0: always the safe plane.
    pub max_short_link: f64,
}

impl Default for FeedSection {
    fn default() -> Self {
        Self {
            cut: 2000.0,
            approach: 600.0,
            retract: 3000.0,
            clearance: 3.0,
            max_short_link: 20.0,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SafetySection {
    /// The shank must stay this far from the part, mm.
    pub shank_margin: f64,
    /// The holder must stay this far from the part, mm.
    pub holder_margin: f64,
    /// Every part of the tool must stay this far above the table, mm.
    pub table_margin: f64,
}

impl Default for SafetySection {
    fn default() -> Self {
        Self {
            shank_margin: 0.5,
            holder_margin: 2.0,
            table_margin: 2.0,
        }
    }
}

impl Job {
    /// Parses a job file's text; `name` is used in error messages.
    pub fn from_toml(text: &str, name: &str) -> Result<Job, JobError> {
        let job: Job = toml::from_str(text).map_err(|e| JobError::File {
            file: name.to_string(),
            reason: e.to_string(),
        })?;
        job.validate().map_err(|error| JobError::InFile {
            file: name.to_string(),
            error: Box::new(error),
        })?;
        Ok(job)
    }

    /// Reads a job file; a relative part path becomes relative to the file's folder.
    pub fn load(path: &Path) -> Result<Job, JobError> {
        let text = std::fs::read_to_string(path).map_err(|e| JobError::File {
            file: path.display().to_string(),
            reason: e.to_string(),
        })?;
        let mut job = Job::from_toml(&text, &path.display().to_string())?;
        if let Some(p) = &job.part.path
            && p.is_relative()
        {
            job.part.path = Some(path.parent().unwrap_or(Path::new(".")).join(p));
        }
        if let Some(super::blank::BlankSpec::Mesh(p)) = job.stock.blank_spec()?
            && p.is_relative()
        {
            let resolved = path.parent().unwrap_or(Path::new(".")).join(p);
            job.stock.blank = Some(format!("mesh:{}", resolved.display()));
        }
        if let Some(p) = &job.roughing.library
            && p.is_relative()
        {
            job.roughing.library = Some(path.parent().unwrap_or(Path::new(".")).join(p));
        }
        if let Some(d) = &job.machine.definition
            && !crate::post::machine_file::is_shipped(d)
            && Path::new(d).is_relative()
        {
            let resolved = path.parent().unwrap_or(Path::new(".")).join(d);
            job.machine.definition = Some(resolved.display().to_string());
        }
        Ok(job)
    }

    /// The machine definition the job names, read (`None` without one).
    pub fn machine_definition(&self) -> Result<Option<crate::post::MachineDefinition>, JobError> {
        let Some(d) = &self.machine.definition else {
            return Ok(None);
        };
        let mut definition = crate::post::MachineDefinition::load(d)
            .map_err(|e| invalid("machine.definition", e.to_string()))?;
        if let Some(o) = self.machine.output {
            definition.output = o;
        }
        if let Some(f) = self.machine.feed {
            definition.feed = f;
        }
        definition.check_modes().map_err(|reason| {
            invalid(
                if self.machine.feed.is_some() {
                    "machine.feed"
                } else {
                    "machine.output"
                },
                reason,
            )
        })?;
        Ok(Some(definition))
    }

    /// Names a machine definition for the job (`--machine`): its kind, rapid feed and rotary
    /// speed replace `[machine]`'s.
    pub fn use_machine(&mut self, name_or_file: &str) -> Result<(), JobError> {
        self.machine.definition = Some(name_or_file.to_string());
        if let Some(d) = self.machine_definition()? {
            self.machine.kinematics = d.chain.kind;
            self.machine.rapid_feed = d.rapid_feed;
            self.machine.max_rotary_speed = d.max_rotary_speed;
        }
        Ok(())
    }

    /// Checks every number is usable, naming the key that is not.
    pub fn validate(&self) -> Result<(), JobError> {
        let positive = |key: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(invalid(key, format!("must be a positive number, got {v}")))
            }
        };
        let non_negative = |key: &str, v: f64| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(invalid(key, format!("must be zero or positive, got {v}")))
            }
        };
        self.tool
            .assembly()
            .validate()
            .map_err(|e| JobError::Tool(e.to_string()))?;
        positive("surface.tolerance", self.surface.tolerance)?;
        self.stock.blank_spec()?;
        if let Some(r) = self.stock.resolution {
            positive("stock.resolution", r)?;
        }
        positive("roughing.allowance", self.roughing.allowance)?;
        positive("roughing.cut_feed", self.roughing.cut_feed)?;
        positive("roughing.entry_feed", self.roughing.entry_feed)?;
        let e = self.roughing.max_engagement;
        if !(e > 0.0 && e <= 1.0) {
            return Err(invalid(
                "roughing.max_engagement",
                format!("{e} is not a share of the diameter in (0, 1]"),
            ));
        }
        if let Some(axis) = self.impeller.axis
            && unit_direction(axis).is_none()
        {
            return Err(invalid(
                "impeller.axis",
                format!("must be a non-zero vector, got {axis:?}"),
            ));
        }
        if let Some(blades) = self.impeller.blades
            && blades < 3
        {
            return Err(invalid(
                "impeller.blades",
                format!("{blades}: an impeller has at least three blades"),
            ));
        }
        let tilt = self.roughing.indexed_max_tilt_deg;
        if !(tilt > 10.0 && tilt <= 90.0) {
            return Err(invalid(
                "roughing.indexed_max_tilt_deg",
                format!("{tilt} must lie in (10, 90] degrees (setups lean at least 10°)"),
            ));
        }
        if let Some(step) = self.roughing.channel_step {
            positive("roughing.channel_step", step)?;
        }
        positive(
            "roughing.channel_scallop_height",
            self.roughing.channel_scallop_height,
        )?;
        if self.roughing.channel_max_layers == 0 {
            return Err(invalid(
                "roughing.channel_max_layers",
                "must be at least 1".to_string(),
            ));
        }
        if let Some(model) = self.cutting.model() {
            model.validate().map_err(|e| invalid("cutting", e))?;
        }
        if let Some(e) = self.surface.base_max_error {
            non_negative("surface.base_max_error", e)?;
        }
        if !(0.0..=180.0).contains(&self.surface.crease_angle_deg) {
            return Err(invalid(
                "surface.crease_angle_deg",
                format!(
                    "must be between 0 and 180, got {}",
                    self.surface.crease_angle_deg
                ),
            ));
        }
        if self.surface.base_triangles < 4
            || self.surface.max_triangles < self.surface.base_triangles
        {
            return Err(invalid(
                "surface.base_triangles",
                format!(
                    "must be at least 4 and at most surface.max_triangles, got {} and {}",
                    self.surface.base_triangles, self.surface.max_triangles
                ),
            ));
        }
        positive("strategy.scallop_height", self.strategy.scallop_height)?;
        positive("strategy.tolerance", self.strategy.tolerance)?;
        positive("strategy.max_step", self.strategy.max_step)?;
        positive(
            "strategy.semi_finish_scallop_height",
            self.strategy.semi_finish_scallop_height,
        )?;
        let allowances = &self.strategy.semi_finish_allowances;
        for (i, &a) in allowances.iter().enumerate() {
            if !(a.is_finite() && a > 0.0 && (i == 0 || a < allowances[i - 1])) {
                return Err(invalid(
                    "strategy.semi_finish_allowances",
                    format!("must be finite, > 0 mm and strictly decreasing; entry {i} is {a}"),
                ));
            }
        }
        positive(
            "strategy.max_axis_turn_deg",
            self.strategy.max_axis_turn_deg,
        )?;
        non_negative(
            "strategy.max_axis_deviation_deg",
            self.strategy.max_axis_deviation_deg,
        )?;
        non_negative(
            "strategy.max_axis_change_deg_per_mm",
            self.strategy.max_axis_change_deg_per_mm,
        )?;
        non_negative(
            "strategy.axis_smoothing_window_mm",
            self.strategy.axis_smoothing_window_mm,
        )?;
        if self.strategy.scallop_height >= self.tool.diameter / 2.0 {
            return Err(invalid(
                "strategy.scallop_height",
                format!(
                    "{} must be smaller than the ball radius {}",
                    self.strategy.scallop_height,
                    self.tool.diameter / 2.0
                ),
            ));
        }
        if let Some(up) = self.part.up
            && unit_direction(up).is_none()
        {
            return Err(invalid(
                "part.up",
                format!("must be a non-zero vector, got {up:?}"),
            ));
        }
        let n = self.strategy.drive_normal;
        if unit_direction(n).is_none() {
            return Err(invalid(
                "strategy.drive_normal",
                format!("must be a non-zero vector, got {n:?}"),
            ));
        }
        if let Some(units) = &self.part.units
            && units.parse::<crate::mesh::io::Units>().is_err()
        {
            return Err(invalid(
                "part.units",
                format!("must be \"mm\", \"m\" or \"in\", got \"{units}\""),
            ));
        }
        // A lead or tilt of 90° or more turns the axis into or behind the surface.
        for (key, v) in [
            ("strategy.lead_deg", self.strategy.lead_deg),
            ("strategy.tilt_deg", self.strategy.tilt_deg),
        ] {
            if !(v.is_finite() && v.abs() < 90.0) {
                return Err(invalid(
                    key,
                    format!("must be a number of degrees between -90 and 90 (exclusive), got {v}"),
                ));
            }
        }
        if self.strategy.max_axis_deviation_deg > 180.0 {
            return Err(invalid(
                "strategy.max_axis_deviation_deg",
                format!(
                    "must be at most 180, got {}",
                    self.strategy.max_axis_deviation_deg
                ),
            ));
        }
        if self.limits.max_drive_points == 0 {
            return Err(invalid(
                "limits.max_drive_points",
                "must be at least 1".into(),
            ));
        }
        for (key, v) in [
            ("feeds.cut", self.feeds.cut),
            ("feeds.approach", self.feeds.approach),
            ("feeds.retract", self.feeds.retract),
            ("machine.rapid_feed", self.machine.rapid_feed),
            ("machine.max_rotary_speed", self.machine.max_rotary_speed),
        ] {
            positive(key, v)?;
        }
        non_negative("feeds.clearance", self.feeds.clearance)?;
        non_negative("feeds.max_short_link", self.feeds.max_short_link)?;
        if !(0.0..=90.0).contains(&self.impeller.blade_lean_deg) {
            return Err(invalid(
                "impeller.blade_lean_deg",
                format!(
                    "must be 0 to 90 degrees, not {}",
                    self.impeller.blade_lean_deg
                ),
            ));
        }
        non_negative("safety.shank_margin", self.safety.shank_margin)?;
        non_negative("safety.holder_margin", self.safety.holder_margin)?;
        non_negative("safety.table_margin", self.safety.table_margin)?;
        if let Some(z) = self.machine.table_z
            && !z.is_finite()
        {
            return Err(invalid(
                "machine.table_z",
                format!("must be a number, got {z}"),
            ));
        }
        non_negative("machine.safe_margin", self.machine.safe_margin)?;
        if let Some(d) = self.machine.safe_distance {
            positive("machine.safe_distance", d)?;
        }
        if !self.machine.kinematics.is_five_axis() {
            return Err(invalid(
                "machine.kinematics",
                "names a machine that cannot tilt the tool; a job drives 5-axis poses and needs \
                 one that can (table-table-ac, or a machine definition); 2.5D programs for \
                 three axes come from `wavemill contour`"
                    .into(),
            ));
        }
        match self.machine_definition()? {
            Some(d)
                if d.chain.kind != self.machine.kinematics
                    && self.machine.kinematics != crate::post::KinematicsKind::TableTableAc =>
            {
                return Err(invalid(
                    "machine.kinematics",
                    format!(
                        "= {} but the definition describes a {} machine",
                        self.machine.kinematics.name(),
                        d.chain.kind.name()
                    ),
                ));
            }
            None if self.machine.kinematics != crate::post::KinematicsKind::TableTableAc => {
                return Err(invalid(
                    "machine.kinematics",
                    format!(
                        "= {} needs a machine definition (machine.definition) giving its axes",
                        self.machine.kinematics.name()
                    ),
                ));
            }
            // The back-simulation reads tool-centre-point programs through a definition's
            // chain; the built-in machine's programs are in joints.
            None if self.machine.output == Some(crate::post::OutputMode::Tcp) => {
                return Err(invalid(
                    "machine.output",
                    "= \"tcp\" needs a machine definition (machine.definition, e.g.                      \"trunnion-ac\" for this table-table A/C machine); the built-in machine                      posts joint output"
                        .into(),
                ));
            }
            _ => {}
        }
        let [lo, hi] = self.machine.a_limits;
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return Err(invalid(
                "machine.a_limits",
                format!(
                    "must be [min, max] with min < max, got {:?}",
                    self.machine.a_limits
                ),
            ));
        }
        if let Some([lo, hi]) = self.machine.c_limits
            && !(lo.is_finite() && hi.is_finite() && lo < hi)
        {
            return Err(invalid(
                "machine.c_limits",
                format!("must be [min, max] with min < max, got [{lo}, {hi}]"),
            ));
        }
        // The operation list: each operation's own numbers and the order rules.
        self.operations().map(|_| ())
    }
}

// ---- Operations ---------------------------------------------------------------------------
//
// A job takes the part through a list of operations — today semi-finishing to stock-to-leave
// shapes (DESIGN.md §3.4, seed 004 ch. 5 step 3) and ball-end finishing; roughing and
// rest-roughing (issue 20) plug in as further kinds. Each has its own tool, stock to leave and
// strategy options. In the job file they are `[[operation]]` tables; a job file without them
// keeps meaning what it meant before: one semi-finishing operation per entry of
// `strategy.semi_finish_allowances`, then finishing ([`Job::operations`]).

/// What an operation does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OperationKind {
    /// Layers from the blank down to the offset shape that holds the part at
    /// `stock_to_leave` mm, with a library end mill (seed 002 §4), 3-axis.
    Rough,
    /// Layers again with a smaller end mill, only where the stock the operations before it
    /// leave still holds material outside its offset shape.
    RestRough,
    /// Layers along fixed tilted axes (3+2), one setup per axis proposed from the visibility
    /// maps of the rest the roughing before it left under overhangs, with its end mill.
    IndexedRough,
    /// Offset layers of the job's ball, 5-axis, from the deepest rest the operations before
    /// left down to `stock_to_leave` mm off the part, each cutting only where material stands:
    /// the rest under overhangs and between blades that vertical end mills cannot reach.
    ChannelRough,
    /// Ball-end passes over the stock-to-leave shape that holds the part at
    /// `stock_to_leave` mm (seed 004 ch. 5 step 3).
    SemiFinish,
    /// Ball-end passes over the part itself (stock to leave 0).
    Finish,
    /// After finishing, a smaller ball (its own `[operation.tool]`) along the concave corners
    /// the finishing ball leaves material in: an impeller's blade and splitter roots, from
    /// the corner out to where the finishing ball's passes touch.
    CornerFinish,
}

impl OperationKind {
    /// The name used in the job file and in messages.
    pub fn name(self) -> &'static str {
        match self {
            OperationKind::Rough => "rough",
            OperationKind::RestRough => "rest-rough",
            OperationKind::IndexedRough => "indexed-rough",
            OperationKind::ChannelRough => "channel-rough",
            OperationKind::SemiFinish => "semi-finish",
            OperationKind::Finish => "finish",
            OperationKind::CornerFinish => "corner-finish",
        }
    }

    /// Roughing kinds cut with a library end mill along an axis fixed per setup (vertical,
    /// or tilted for `indexed-rough`); the others with the job's ball along the 5-axis passes.
    pub fn is_roughing(self) -> bool {
        matches!(
            self,
            OperationKind::Rough | OperationKind::RestRough | OperationKind::IndexedRough
        )
    }
}

/// One `[[operation]]` table of a job file; what it leaves out comes from the job's
/// `[tool]` and `[strategy]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OperationSection {
    pub kind: OperationKind,
    /// A name for messages and the report; default: the kind and its stock to leave.
    pub name: Option<String>,
    /// Material left on the part, mm: > 0 for semi-finishing, 0 (or left out) for finishing.
    pub stock_to_leave: Option<f64>,
    /// Scallop height target, mm; default `strategy.semi_finish_scallop_height` when
    /// semi-finishing, `strategy.scallop_height` when finishing.
    pub scallop_height: Option<f64>,
    /// The operation's own tool; default the job's `[tool]`. Not for roughing.
    pub tool: Option<ToolSection>,
    /// Roughing: the library tool (its id); default the largest flat or bull-nose end mill
    /// that reaches the floor (`rough`), the next at most 3/4 of the one before (`rest-rough`).
    pub tool_id: Option<u32>,
    /// Channel roughing: mm between offset layers; default `roughing.channel_step`.
    pub step: Option<f64>,
    /// Channel roughing: offset layers at most; default `roughing.channel_max_layers`.
    pub max_layers: Option<usize>,
    /// Channel roughing: `shroud-to-hub` or `offset`; default `roughing.channel_layering`.
    pub layering: Option<Layering>,
    /// `rough` and `rest-rough`: what the layers stop at, `offset-shape` (default) or
    /// `hull-boxes` (seed 002's convex-hull boxes of an IGES part's surfaces, grown by the
    /// stock to leave).
    pub bound: Option<RoughingBound>,
    /// With `hull-boxes`: boxes wider than this are split before the layers, mm (default:
    /// only the seed's splits for layers thicker than the maximum depth).
    pub box_width: Option<f64>,
    /// With `hull-boxes`: `upward` (the seed's merge of thin layers, default) or `deepest`
    /// (the deepest box top within the maximum depth, layer by layer).
    pub box_layers: Option<crate::rough::boxes::LayerMerge>,
}

/// What the layers of a roughing operation stop at.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RoughingBound {
    /// The part's verified offset shape at the stock to leave.
    #[default]
    OffsetShape,
    /// Seed 002's convex-hull boxes of the part's Bézier patches, grown by the stock to
    /// leave: needs a part read from IGES.
    HullBoxes,
}

/// How a `hull-boxes` roughing makes its boxes and layers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoxBound {
    /// Boxes wider than this are split first, mm (`f64::INFINITY`: the seed's model).
    pub max_box_width: f64,
    pub merge: crate::rough::boxes::LayerMerge,
}

/// One operation, every option resolved.
#[derive(Clone, Debug, PartialEq)]
pub struct Operation {
    pub name: String,
    pub kind: OperationKind,
    /// The ball of the semi-finishing and finishing passes (the job's `[tool]` for roughing,
    /// which cuts with a library tool instead).
    pub tool: ToolSection,
    /// Roughing: the library tool asked for, if one is.
    pub library_tool: Option<u32>,
    /// Material left on the part, mm (0 when finishing).
    pub stock_to_leave: f64,
    /// Scallop height target, mm.
    pub scallop_height: f64,
    /// Channel roughing's offset layers; `None` for every other kind.
    pub layers: Option<ChannelLayers>,
    /// `rough` and `rest-rough` to the convex-hull boxes instead of the offset shape.
    pub boxes: Option<BoxBound>,
}

/// The layers of a `channel-rough` operation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChannelLayers {
    /// mm between layers (the most a layer cuts into material on a face).
    pub step: f64,
    /// Layers at most.
    pub max_layers: usize,
    pub layering: Layering,
}

/// How channel roughing lays its layers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Layering {
    /// Surfaces interpolated from the shroud (the stock's top) down to the hub (the part's
    /// lowest upward face under each point), the ball's bottom on each: every layer cuts at
    /// most a step from above, whatever the channel's width.
    #[default]
    ShroudToHub,
    /// Offsets of the whole part, the ball held a + k·step off it, outermost first, each cut
    /// as waterlines from the top down.
    Offset,
}

impl Job {
    /// The job's operations in machining order: its `[[operation]]` tables, or, without them,
    /// roughing when the job's `[stock]` blank is a box or a cylinder (one `rough` to
    /// `roughing.allowance` and `roughing.rest_tools` `rest-rough`s), one semi-finishing operation per
    /// `strategy.semi_finish_allowances` entry, then finishing. Checks what a list must
    /// satisfy: roughing first, stocks to leave positive and decreasing (strictly from one
    /// ball operation to the next), exactly one finishing operation and it comes last, the
    /// job's `[tool]` for every ball operation.
    pub fn operations(&self) -> Result<Vec<Operation>, JobError> {
        let default_name = |kind: OperationKind, stock: f64| match kind {
            OperationKind::Finish => "finish".to_string(),
            OperationKind::CornerFinish => "corner-finish".to_string(),
            kind => format!("{} to {stock} mm", kind.name()),
        };
        let layers = |kind: OperationKind,
                      step: Option<f64>,
                      max_layers: Option<usize>,
                      layering: Option<Layering>| {
            (kind == OperationKind::ChannelRough).then(|| ChannelLayers {
                step: step
                    .or(self.roughing.channel_step)
                    .unwrap_or(0.5 * self.tool.diameter),
                max_layers: max_layers.unwrap_or(self.roughing.channel_max_layers),
                layering: layering.unwrap_or(self.roughing.channel_layering),
            })
        };
        let operation = |kind: OperationKind, stock: f64, scallop: f64| Operation {
            name: default_name(kind, stock),
            kind,
            tool: self.tool.clone(),
            library_tool: None,
            stock_to_leave: stock,
            scallop_height: scallop,
            layers: layers(kind, None, None, None),
            boxes: None,
        };
        let operations: Vec<Operation> = if self.operations.is_empty() {
            // A near-net blank (the part grown, a casting's mesh) is taken as roughed.
            let layered = matches!(
                self.stock.blank_spec()?,
                Some(
                    super::blank::BlankSpec::Box(_)
                        | super::blank::BlankSpec::Cylinder { .. }
                        | super::blank::BlankSpec::EnclosingCylinder { .. }
                )
            );
            let roughing = if layered {
                1 + self.roughing.rest_tools
            } else {
                0
            };
            let rough = (0..roughing).map(|k| {
                let kind = if k == 0 {
                    OperationKind::Rough
                } else {
                    OperationKind::RestRough
                };
                operation(kind, self.roughing.allowance, self.strategy.scallop_height)
            });
            let indexed = (layered && self.roughing.indexed_setups > 0).then(|| {
                operation(
                    OperationKind::IndexedRough,
                    self.roughing.allowance,
                    self.strategy.scallop_height,
                )
            });
            let channel = (layered && self.roughing.channel).then(|| {
                operation(
                    OperationKind::ChannelRough,
                    self.roughing.allowance,
                    self.roughing.channel_scallop_height,
                )
            });
            let semi = self.strategy.semi_finish_allowances.iter().map(|&a| {
                operation(
                    OperationKind::SemiFinish,
                    a,
                    self.strategy.semi_finish_scallop_height,
                )
            });
            let corner = self.corner_tool.as_ref().map(|tool| Operation {
                tool: tool.clone(),
                ..operation(
                    OperationKind::CornerFinish,
                    0.0,
                    self.strategy.scallop_height,
                )
            });
            rough
                .chain(indexed)
                .chain(channel)
                .chain(semi)
                .chain(std::iter::once(operation(
                    OperationKind::Finish,
                    0.0,
                    self.strategy.scallop_height,
                )))
                .chain(corner)
                .collect()
        } else {
            if !self.strategy.semi_finish_allowances.is_empty() {
                return Err(JobError::Operations(
                    "strategy.semi_finish_allowances and [[operation]] tables both list \
                     operations; write the semi-finishing as [[operation]] tables"
                        .into(),
                ));
            }
            if self.corner_tool.is_some() {
                return Err(JobError::Operations(
                    "[corner_tool] and [[operation]] tables both list operations; give the \
                     corner-finish operation its [operation.tool]"
                        .into(),
                ));
            }
            let mut listed = Vec::with_capacity(self.operations.len());
            for (i, s) in self.operations.iter().enumerate() {
                let stock = s.stock_to_leave.unwrap_or(match s.kind {
                    OperationKind::Rough
                    | OperationKind::RestRough
                    | OperationKind::IndexedRough
                    | OperationKind::ChannelRough => self.roughing.allowance,
                    _ => 0.0,
                });
                let name = s
                    .name
                    .clone()
                    .unwrap_or_else(|| default_name(s.kind, stock));
                let fail = |reason: &str| JobError::Operation {
                    index: i + 1,
                    name: name.clone(),
                    reason: reason.to_string(),
                };
                if s.kind.is_roughing() && s.tool.is_some() {
                    return Err(fail(
                        "roughing takes its end mill from the tool library: name it by \
                         tool_id, not by an [operation.tool] table",
                    ));
                }
                if s.kind == OperationKind::CornerFinish && s.tool.is_none() {
                    return Err(fail(
                        "corner-finish needs its own ball, smaller than [tool]'s: an \
                         [operation.tool] table",
                    ));
                }
                if let Some(tool) = &s.tool {
                    tool.assembly()
                        .validate()
                        .map_err(|e| fail(&format!("its [operation.tool]: {e}")))?;
                }
                if !s.kind.is_roughing() && s.tool_id.is_some() {
                    return Err(fail(
                        "tool_id names a library end mill for roughing; a ball operation \
                         takes its tool from [tool]",
                    ));
                }
                if s.kind != OperationKind::ChannelRough
                    && (s.step.is_some() || s.max_layers.is_some() || s.layering.is_some())
                {
                    return Err(fail(
                        "step, max_layers and layering set the layers of channel-rough alone",
                    ));
                }
                if s.step.is_some_and(|step| !(step.is_finite() && step > 0.0)) {
                    return Err(fail("step must be a positive number of mm"));
                }
                if s.max_layers == Some(0) {
                    return Err(fail("max_layers must be at least 1"));
                }
                let boxed = s.bound == Some(RoughingBound::HullBoxes);
                if boxed && !matches!(s.kind, OperationKind::Rough | OperationKind::RestRough) {
                    return Err(fail(
                        "bound = \"hull-boxes\" is for rough and rest-rough operations",
                    ));
                }
                if !boxed && (s.box_width.is_some() || s.box_layers.is_some()) {
                    return Err(fail(
                        "box_width and box_layers set the boxes of bound = \"hull-boxes\" alone",
                    ));
                }
                if s.box_width.is_some_and(|w| !(w.is_finite() && w > 0.0)) {
                    return Err(fail("box_width must be a positive number of mm"));
                }
                listed.push(Operation {
                    name,
                    kind: s.kind,
                    tool: s.tool.clone().unwrap_or_else(|| self.tool.clone()),
                    library_tool: s.tool_id,
                    stock_to_leave: stock,
                    scallop_height: s.scallop_height.unwrap_or(match s.kind {
                        OperationKind::SemiFinish => self.strategy.semi_finish_scallop_height,
                        OperationKind::ChannelRough => self.roughing.channel_scallop_height,
                        _ => self.strategy.scallop_height,
                    }),
                    layers: layers(s.kind, s.step, s.max_layers, s.layering),
                    boxes: boxed.then(|| BoxBound {
                        max_box_width: s.box_width.unwrap_or(f64::INFINITY),
                        merge: s.box_layers.unwrap_or_default(),
                    }),
                });
            }
            listed
        };
        check_operations(&operations, &self.tool)?;
        Ok(operations)
    }
}

/// The rules of [`Job::operations`], naming the operation (1-based, as listed) that breaks one.
fn check_operations(operations: &[Operation], job_tool: &ToolSection) -> Result<(), JobError> {
    let mut previous_stock = f64::INFINITY;
    for (i, op) in operations.iter().enumerate() {
        let fail = |reason: String| JobError::Operation {
            index: i + 1,
            name: op.name.clone(),
            reason,
        };
        if !(op.scallop_height.is_finite() && op.scallop_height > 0.0) {
            return Err(fail(format!(
                "scallop_height must be a positive number of mm, got {}",
                op.scallop_height
            )));
        }
        let previous_kind = i.checked_sub(1).map(|j| operations[j].kind);
        match op.kind {
            OperationKind::Rough
            | OperationKind::RestRough
            | OperationKind::IndexedRough
            | OperationKind::ChannelRough
            | OperationKind::SemiFinish => {
                if !(op.stock_to_leave.is_finite() && op.stock_to_leave > 0.0) {
                    return Err(fail(format!(
                        "{} needs stock_to_leave > 0 mm, got {}",
                        op.kind.name(),
                        op.stock_to_leave
                    )));
                }
                // A rest-roughing tool may rough to the same shape as the one before it, and
                // channel roughing to the same allowance (it takes what they could not reach);
                // every other operation must leave less than what is already there.
                let same_allowed = matches!(
                    op.kind,
                    OperationKind::RestRough
                        | OperationKind::IndexedRough
                        | OperationKind::ChannelRough
                );
                if op.stock_to_leave > previous_stock
                    || (op.stock_to_leave == previous_stock && !same_allowed)
                {
                    return Err(fail(format!(
                        "stock_to_leave {} mm is not below the {previous_stock} mm the \
                         operation before leaves",
                        op.stock_to_leave
                    )));
                }
                previous_stock = op.stock_to_leave;
            }
            OperationKind::Finish | OperationKind::CornerFinish => {
                if op.stock_to_leave != 0.0 {
                    return Err(fail(format!(
                        "finishing leaves no stock; stock_to_leave must be 0, got {}",
                        op.stock_to_leave
                    )));
                }
                let after = operations.len() - i - 1;
                if op.kind == OperationKind::Finish
                    && operations[i + 1..]
                        .iter()
                        .any(|o| o.kind != OperationKind::CornerFinish)
                {
                    return Err(fail(format!(
                        "finishing must be the last operation but for a corner-finish ({after} \
                         follow it)"
                    )));
                }
            }
        }
        match op.kind {
            OperationKind::Rough if i != 0 => {
                return Err(fail(
                    "roughing from the blank must be the first operation (rest-rough clears \
                     what the ones before leave)"
                        .into(),
                ));
            }
            OperationKind::RestRough | OperationKind::IndexedRough
                if !previous_kind.is_some_and(OperationKind::is_roughing) =>
            {
                return Err(fail(format!(
                    "{} follows a roughing or rest-roughing operation",
                    op.kind.name()
                )));
            }
            // Its layers are cut only where material stands, which needs the stock model the
            // roughing from a blank keeps.
            OperationKind::ChannelRough
                if !previous_kind.is_some_and(|kind| {
                    kind.is_roughing() || kind == OperationKind::ChannelRough
                }) =>
            {
                return Err(fail(
                    "channel roughing follows the roughing of a blank (a rough or rest-rough \
                     operation)"
                        .into(),
                ));
            }
            _ => {}
        }
        if op.kind == OperationKind::CornerFinish {
            op.tool
                .assembly()
                .validate()
                .map_err(|e| fail(format!("its tool: {e}")))?;
            if previous_kind != Some(OperationKind::Finish) {
                return Err(fail(
                    "corner-finish follows the finishing operation (and comes once)".into(),
                ));
            }
            if op.tool.diameter >= job_tool.diameter {
                return Err(fail(format!(
                    "its ball ({} mm) must be smaller than the finishing ball ({} mm): it \
                     reaches into the corners that one cannot",
                    op.tool.diameter, job_tool.diameter
                )));
            }
            if op.tool.id == job_tool.id {
                return Err(fail(format!(
                    "its tool has the finishing tool's number T{}: give it its own id",
                    op.tool.id
                )));
            }
            if op.scallop_height >= op.tool.diameter / 2.0 {
                return Err(fail(format!(
                    "scallop_height {} must be smaller than its ball's radius {}",
                    op.scallop_height,
                    op.tool.diameter / 2.0
                )));
            }
        } else if !op.kind.is_roughing() && op.tool != *job_tool {
            return Err(fail(
                "uses another ball than [tool]; the semi-finishing and finishing passes run \
                 the job's tool (roughing operations take theirs from the library)"
                    .into(),
            ));
        }
    }
    if operations
        .iter()
        .rfind(|op| op.kind != OperationKind::CornerFinish)
        .is_none_or(|op| op.kind != OperationKind::Finish)
    {
        return Err(JobError::Operations(
            "the operations must end with one finishing operation (kind = \"finish\")".into(),
        ));
    }
    Ok(())
}

/// `v` scaled to unit length, or `None` when it is zero or not finite. Scaled by its largest
/// component first, so that `[1e200, 1e200, 0]` is a direction too (its squared length would
/// overflow).
pub fn unit_direction(v: [f64; 3]) -> Option<nalgebra::Vector3<f64>> {
    if !v.iter().all(|c| c.is_finite()) {
        return None;
    }
    let largest = v.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    if largest == 0.0 {
        return None;
    }
    let scaled = nalgebra::Vector3::from(v) / largest;
    Some(scaled / scaled.norm())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_file_gives_the_defaults() {
        assert_eq!(Job::from_toml("", "empty.toml").unwrap(), Job::default());
    }

    /// A `[stock]` blank is read with the simulate command's syntax; a bad one names the key
    /// and what was expected, and a relative mesh is found beside the job file.
    #[test]
    fn the_stock_blank_is_checked_and_a_mesh_found_beside_the_job() {
        let job = Job::from_toml(
            "[stock]\nblank = \"offset:0.5\"\nresolution = 0.2\n",
            "j.toml",
        )
        .unwrap();
        assert_eq!(
            job.stock.blank_spec().unwrap(),
            Some(super::super::blank::BlankSpec::Offset(0.5))
        );
        let e = Job::from_toml("[stock]\nblank = \"offset:-1\"\n", "j.toml").unwrap_err();
        let text = e.to_string();
        assert!(
            text.contains("stock.blank") && text.contains("offset:M"),
            "{text}"
        );
        let e = Job::from_toml("[stock]\nresolution = 0\n", "j.toml").unwrap_err();
        assert!(e.to_string().contains("stock.resolution"), "{e}");
        let dir = std::env::temp_dir().join(format!("wavemill-job-stock-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("job.toml");
        std::fs::write(&file, "[stock]\nblank = \"mesh:blank.stl\"\n").unwrap();
        let job = Job::load(&file).unwrap();
        assert_eq!(
            job.stock.blank_spec().unwrap(),
            Some(super::super::blank::BlankSpec::Mesh(dir.join("blank.stl")))
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Without `[stock]` the blank is the part's bar stock; `none` takes the part as roughed,
    /// and then no roughing is listed.
    #[test]
    fn the_default_blank_is_the_bar_stock_and_none_takes_the_part_as_roughed() {
        let job = Job::default();
        assert_eq!(
            job.stock.blank_spec().unwrap(),
            Some(super::super::blank::BlankSpec::EnclosingCylinder {
                margin: super::super::blank::ENCLOSING_MARGIN
            })
        );
        assert!(job.operations().unwrap()[0].kind.is_roughing());
        let roughed = Job::from_toml("[stock]\nblank = \"none\"\n", "j.toml").unwrap();
        assert_eq!(roughed.stock.blank_spec().unwrap(), None);
        assert!(
            roughed
                .operations()
                .unwrap()
                .iter()
                .all(|op| !op.kind.is_roughing())
        );
    }

    #[test]
    fn partial_file_overrides_only_what_it_says() {
        let job = Job::from_toml(
            "[tool]\ndiameter = 3.0\nshank_diameter = 3.0\n[strategy]\nscallop_height = 0.02\n",
            "j.toml",
        )
        .unwrap();
        assert_eq!(job.tool.diameter, 3.0);
        assert_eq!(job.strategy.scallop_height, 0.02);
        assert_eq!(job.tool.stickout, ToolSection::default().stickout);
    }

    #[test]
    fn mistakes_are_named() {
        let e = Job::from_toml("[strategy]\nscallop_heigth = 0.02\n", "j.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("j.toml") && e.contains("scallop_heigth"), "{e}");
        let e = Job::from_toml("[feeds]\ncut = -5\n", "j.toml").unwrap_err();
        assert_eq!(e.key(), Some("feeds.cut"));
        let e = e.to_string();
        assert!(
            e.contains("j.toml: feeds.cut must be a positive number"),
            "{e}"
        );
        let e = Job::from_toml("[machine]\na_limits = [30, -30]\n", "j.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("a_limits"), "{e}");
        let e = Job::from_toml("[strategy]\nscallop_height = 5\n", "j.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("ball radius"), "{e}");
    }

    /// `[impeller]` keys: an axis must be a direction and a count at least three; unknown keys
    /// are refused; by default the plan looks for an impeller and states nothing.
    #[test]
    fn impeller_keys_are_checked() {
        let check = |text: &str| Job::from_toml(text, "j.toml").and_then(|j| j.validate());
        let e = check("[impeller]\nblades = 2\n").unwrap_err().to_string();
        assert!(e.contains("impeller.blades"), "{e}");
        let e = check("[impeller]\naxis = [0.0, 0.0, 0.0]\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("impeller.axis"), "{e}");
        assert!(Job::from_toml("[impeller]\nblade = 7\n", "j.toml").is_err());
        let job =
            Job::from_toml("[impeller]\naxis = [0.0, 0.0, 1.0]\nblades = 7\n", "j.toml").unwrap();
        assert!(job.validate().is_ok() && job.impeller.is_given());
        assert!(Job::default().impeller.recognise && !Job::default().impeller.is_given());
    }

    /// The machine's kinematics is a typed kind: a name the post does not know is refused
    /// when the file is read (listing the known ones), a kind other than the built-in A/C needs
    /// a definition giving its axes, and a definition's kind must be the one named.
    #[test]
    fn machine_kinematics_is_a_known_kind() {
        let e = Job::from_toml("[machine]\nkinematics = \"five-axis\"\n", "j.toml")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("five-axis") && e.contains("table-table-ac") && e.contains("head-head"),
            "{e}"
        );
        let e = Job::from_toml("[machine]\noutput = \"tcp\"\n", "j.toml")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("machine.output") && e.contains("definition"),
            "{e}"
        );
        let e = Job::from_toml("[machine]\nkinematics = \"head-head\"\n", "j.toml")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("machine.kinematics") && e.contains("definition"),
            "{e}"
        );
        let e = Job::from_toml(
            "[machine]\nkinematics = \"head-head\"\ndefinition = \"trunnion-bc\"\n",
            "j.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("table-table-bc"), "{e}");
        let e = Job::from_toml("[machine]\ndefinition = \"nowhere.toml\"\n", "j.toml")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("machine.definition") && e.contains("nowhere.toml"),
            "{e}"
        );
        let job = Job::from_toml(
            "[machine]\ndefinition = \"head-head\"\noutput = \"tcp\"\n",
            "j.toml",
        )
        .unwrap();
        let d = job.machine_definition().unwrap().unwrap();
        assert_eq!(d.output, crate::post::OutputMode::Tcp);
        let e = Job::from_toml(
            "[machine]\ndefinition = \"trunnion-bc\"\nfeed = \"inverse-time\"\n",
            "j.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("machine.feed") && e.contains("Heidenhain"),
            "{e}"
        );
        let job = Job::from_toml("[machine]\nkinematics = \"table-table-ac\"\n", "j.toml").unwrap();
        assert_eq!(
            job.machine.kinematics,
            crate::post::KinematicsKind::TableTableAc
        );
    }

    /// Issue 17 item 9: `lead_deg = nan` (or inf, or 720) gave an empty program with exit 0.
    #[test]
    fn lead_and_tilt_must_be_usable_angles() {
        for text in [
            "lead_deg = nan",
            "tilt_deg = nan",
            "lead_deg = inf",
            "lead_deg = 720",
            "tilt_deg = -90",
        ] {
            let e = Job::from_toml(&format!("[strategy]\n{text}\n"), "j.toml")
                .unwrap_err()
                .to_string();
            let key = text.split(' ').next().unwrap();
            assert!(e.contains(&format!("strategy.{key}")), "{text}: {e}");
        }
        assert!(Job::from_toml("[strategy]\nlead_deg = 45\ntilt_deg = -30\n", "j").is_ok());
    }

    /// Issue 17 item 13: a bad unit in the job file is named by its key, not as `--units`.
    #[test]
    fn bad_units_in_the_job_file_name_the_key() {
        let e = Job::from_toml("[part]\nunits = \"furlong\"\n", "j.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("part.units") && e.contains("furlong"), "{e}");
        assert!(!e.contains("--units"), "{e}");
    }

    /// Issue 17 item 13: `--up 1e200,1e200,0` was silently ignored (its squared length
    /// overflowed, normalising gave NaN). It is a direction like any other.
    #[test]
    fn huge_and_tiny_directions_are_directions() {
        let u = unit_direction([1e200, 1e200, 0.0]).unwrap();
        assert!((u - nalgebra::Vector3::new(1.0, 1.0, 0.0).normalize()).norm() < 1e-15);
        let u = unit_direction([0.0, 1e-300, 0.0]).unwrap();
        assert_eq!(u, nalgebra::Vector3::y());
        for bad in [[0.0; 3], [f64::NAN, 0.0, 1.0], [f64::INFINITY, 0.0, 0.0]] {
            assert!(unit_direction(bad).is_none(), "{bad:?}");
        }
        let e = Job::from_toml("[part]\nup = [0, 0, 0]\n", "j.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("part.up"), "{e}");
    }

    #[test]
    fn defaults_round_trip_through_toml() {
        let text = toml::to_string(&Job::default()).unwrap();
        assert_eq!(Job::from_toml(&text, "x").unwrap(), Job::default());
    }
}
