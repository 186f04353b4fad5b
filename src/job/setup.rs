//! The first stages of a plan, shared by every operation: the part prepared for planning
//! ([`prepare_part`]) and the cell it is machined in ([`PlanSetup`]) — its collision
//! structures, the tool, the machine with the part clamped on it, the safe plane, and how the
//! job's tolerance is split ([`ToleranceBudget`]).

use super::budget::ToleranceBudget;
use super::config::{Job, unit_direction};
use crate::access::RayScene;
use crate::collide::{Margins, PartCollider, PreparedTool, Table};
use crate::error::{Error, JobError, Result};
use crate::geom::{Point3, Vector3, positive_zero};
use crate::mesh::io::RawMesh;
use crate::mesh::{Mesh, MeshReport, Piece, PrepareOptions, prepare_without_stray_pieces};
use crate::orient::{AxisChooser, AxisOptions, AxisTurn, SmoothingOptions};
use crate::path::{self, FinishingContext, FinishingOptions, LinkOptions};
use crate::post::{
    GcodeOptions, KinematicsKind, Machine, MachineKinematics, TableTableAC, ThreeAxis,
};
use crate::tool::ToolAssembly;

/// The part as it will be planned, and what preparing it found.
pub struct PreparedPart {
    /// The part's name in errors, the report and the program header.
    pub name: String,
    /// Welded, oriented, turned upright, stray pieces set aside.
    pub part: Mesh,
    pub mesh_report: MeshReport,
    /// Debris set aside (a lone far triangle, a sliver shell), for the report.
    pub stray_pieces: Vec<Piece>,
    /// Height of the machine table's top in the part frame, mm.
    pub table_z: f64,
}

/// Prepares `raw` for planning: turned so `part.up` points along +Z, welded and repaired,
/// stray debris set aside (issue 17 item 8), and refused unless closed (inside and outside
/// must be told apart) or when it would stand inside the table or ask for more drive points
/// than `limits.max_drive_points`. `part_name` names the part in errors.
pub fn prepare_part(raw: &RawMesh, part_name: &str, job: &Job) -> Result<PreparedPart> {
    let mesh_error = |reason: String| Error::Mesh {
        file: part_name.to_string(),
        reason,
    };
    let upright = match job.part.up {
        Some(up) => turned_upright(
            &raw.mesh,
            &unit_direction(up).ok_or_else(|| {
                Error::JobFile(JobError::Invalid {
                    key: "part.up".into(),
                    reason: format!("must be a non-zero vector, got {up:?}"),
                })
            })?,
        ),
        None => raw.mesh.clone(),
    };
    let (part, mesh_report, stray_pieces) =
        prepare_without_stray_pieces(&upright, &PrepareOptions::default())
            .map_err(|e| mesh_error(e.to_string()))?;
    if !mesh_report.watertight {
        return Err(mesh_error(format!(
            "the part must be a closed, consistently oriented surface to tell inside from outside; found: {}",
            mesh_report.problems().join("; ")
        )));
    }
    check_drive_points(&mesh_report, job)?;
    let lowest = part.aabb().min.z;
    let table_z = job.machine.table_z.unwrap_or(lowest);
    if table_z > lowest + job.strategy.tolerance {
        return Err(Error::JobFile(JobError::Invalid {
            key: "machine.table_z".into(),
            reason: format!(
                "= {table_z} mm is above the part's lowest point (z = {lowest:.4} mm after \
                 turning the part up): the part would stand inside the table"
            ),
        }));
    }
    Ok(PreparedPart {
        name: part_name.to_string(),
        part,
        mesh_report,
        stray_pieces,
        table_z,
    })
}

/// Everything the operations of a plan share.
pub struct PlanSetup {
    /// The part with the table, for exact distances and tool-body collisions.
    pub collider: PartCollider,
    /// The part for visibility rays.
    pub rays: std::sync::Arc<RayScene>,
    pub tool: ToolAssembly,
    pub prepared_tool: PreparedTool,
    pub margins: Margins,
    pub table: Table,
    pub kinematics: Machine,
    /// Where the part's frame origin sits in the table frame, mm.
    pub part_origin_in_table: Vector3,
    /// The machine's pivot in the part frame.
    pub pivot: Point3,
    /// Distance of the safe plane from the pivot along the tool axis, mm.
    pub safe_distance: f64,
    pub budget: ToleranceBudget,
    pub gcode_options: GcodeOptions,
    pub chooser: AxisChooser,
    /// Finishing options at the job's scallop height; operations set their own.
    pub finishing: FinishingOptions,
    pub link: LinkOptions,
    /// How far collision queries look beyond the margins, mm.
    pub search: f64,
    /// How an impeller is finished (`[impeller]`).
    pub impeller: super::config::ImpellerSection,
}

impl PlanSetup {
    /// The table-table A/C machine's C axis, along which the part is clamped: the tool axis,
    /// in the part frame, at which the rotary axes are singular.
    const POLE: Vector3 = Vector3::new(0.0, 0.0, 1.0);

    /// The kinematics the program's words are written in: the machine's, or seen through
    /// tool-centre-point control in TCP output (how the control moves between blocks).
    pub fn program_kinematics(&self) -> Box<dyn crate::post::MachineKinematics + '_> {
        if self.gcode_options.output == crate::post::OutputMode::Tcp {
            Box::new(crate::post::ToolCentrePoint(&self.kinematics))
        } else {
            Box::new(self.kinematics.clone())
        }
    }

    /// The machine as the back-simulation models it (plain data for the verifier's own
    /// kinematics), with the gauge length of every tool the program runs (`(number, mm)`).
    pub fn verifier_model(&self, gauges: &[(u32, f64)]) -> crate::verify::MachineModel {
        verifier_model_of(
            &self.kinematics,
            self.part_origin_in_table,
            &self.gcode_options,
            gauges,
        )
    }

    /// The cell for `part`: collision structures, the job's tool, the machine with the part
    /// clamped (by default centred on the C axis, standing on the table at the pivot height),
    /// the safe plane beyond the part's reach, and the tolerance budget.
    pub fn new(part: &PreparedPart, job: &Job) -> Result<PlanSetup> {
        let table = Table {
            top_z: part.table_z,
            margin: job.safety.table_margin,
        };
        let collider = PartCollider::new(&part.part)
            .map_err(|e| Error::Mesh {
                file: part.name.clone(),
                reason: e.to_string(),
            })?
            .with_table(table);
        let rays = std::sync::Arc::new(RayScene::new(&part.part));
        let tool = job.tool.assembly();
        let margins = Margins {
            shank: job.safety.shank_margin,
            holder: job.safety.holder_margin,
        };
        let prepared_tool = PreparedTool::new(&tool, &margins);
        let part_origin_in_table = part_origin_in_table(job, &part.part);
        let kinematics = machine(job, part_origin_in_table, tool.total_length())?;
        let pivot = Point3::from(-part_origin_in_table);
        let reach = part
            .part
            .positions
            .iter()
            .map(|p| (p - pivot).norm())
            .fold(0.0, f64::max);
        let safe_distance = job
            .machine
            .safe_distance
            .unwrap_or(reach + job.machine.safe_margin);
        if safe_distance <= reach {
            return Err(Error::JobFile(JobError::Invalid {
                key: "machine.safe_distance".into(),
                reason: format!(
                    "= {safe_distance} mm is inside the part's reach from the pivot \
                     ({reach:.3} mm)"
                ),
            }));
        }
        // Rounding is charged where the ball centre is farthest from the pivot: on the safe
        // plane.
        let gcode_options = gcode_options(job)?;
        let budget = ToleranceBudget::split(
            job.strategy.tolerance,
            &gcode_options,
            safe_distance + prepared_tool.ball_radius + kinematics.head_length(),
        )?;
        let turn = smoothing_turn(&kinematics);
        let chooser = AxisChooser::new(AxisOptions {
            lead_deg: job.strategy.lead_deg,
            tilt_deg: job.strategy.tilt_deg,
            max_deviation_deg: job.strategy.max_axis_deviation_deg,
            ..AxisOptions::default()
        });
        let finishing = FinishingOptions {
            drive_normal: Vector3::from(job.strategy.drive_normal),
            scallop_height: job.strategy.scallop_height,
            tolerance: budget.chord_mm,
            sag_tolerance: budget.chord_mm,
            max_step: job.strategy.max_step,
            max_axis_turn_deg: job.strategy.max_axis_turn_deg,
            axis_smoothing: (job.strategy.max_axis_change_deg_per_mm > 0.0).then_some(
                SmoothingOptions {
                    max_turn_deg_per_mm: job.strategy.max_axis_change_deg_per_mm,
                    window_mm: job.strategy.axis_smoothing_window_mm,
                    turn,
                },
            ),
        };
        let link = LinkOptions {
            pivot,
            safe_distance,
            clearance: job.feeds.clearance,
            cut_feed: job.feeds.cut,
            approach_feed: job.feeds.approach,
            retract_feed: job.feeds.retract,
            rapid_feed: job.machine.rapid_feed,
            rapid_margin: job.safety.shank_margin,
            max_short_link: job.feeds.max_short_link,
            chord_tolerance: budget.chord_mm,
        };
        let search = job.safety.holder_margin.max(job.safety.shank_margin) + 5.0;
        Ok(PlanSetup {
            collider,
            rays,
            tool,
            prepared_tool,
            margins,
            table,
            kinematics,
            part_origin_in_table,
            pivot,
            safe_distance,
            budget,
            impeller: job.impeller.clone(),
            gcode_options,
            chooser,
            finishing,
            link,
            search,
        })
    }

    /// The same cell with another ball in the spindle (a corner finish's): its bodies for the
    /// collision checks and its gauge length for the machine; the part's structures shared.
    pub fn with_ball(&self, tool: &super::config::ToolSection) -> PlanSetup {
        let assembly = tool.assembly();
        PlanSetup {
            collider: self.collider.clone(),
            rays: self.rays.clone(),
            prepared_tool: PreparedTool::new(&assembly, &self.margins),
            kinematics: self.kinematics.with_gauge_length(assembly.total_length()),
            tool: assembly,
            margins: self.margins,
            table: self.table,
            part_origin_in_table: self.part_origin_in_table,
            pivot: self.pivot,
            safe_distance: self.safe_distance,
            budget: self.budget,
            gcode_options: self.gcode_options.clone(),
            chooser: AxisChooser::new(self.chooser.options().clone()),
            finishing: self.finishing.clone(),
            link: self.link.clone(),
            search: self.search,
            impeller: self.impeller.clone(),
        }
    }

    /// Whether the machine can point the tool along `axis` (the inverse kinematics has a
    /// solution within the axis limits).
    pub fn reachable(&self, axis: &Vector3) -> bool {
        self.kinematics.reaches_axis(&self.pivot, axis)
    }

    /// The tool axis, in the part frame, at which the machine's rotary axes are singular: the
    /// built-in A/C machine's C axis (+Z), which the impeller strategies keep the tool off. A
    /// machine definition's own pole is not derived: +Z stands for it too.
    pub fn pole(&self) -> Vector3 {
        Self::POLE
    }

    /// The finishing context against `collider`/`rays` (the part, or a stock-to-leave
    /// shape), with this setup's tool, axis chooser and machine.
    pub fn finishing_context<'a>(
        &'a self,
        collider: &'a PartCollider,
        rays: &'a RayScene,
        reachable: &'a (dyn Fn(&Vector3) -> bool + Sync),
    ) -> FinishingContext<'a> {
        FinishingContext {
            part: collider,
            rays,
            tool: &self.prepared_tool,
            chooser: &self.chooser,
            reachable,
            allowance: 0.0,
            lift: 0.0,
            material_filter: None,
            axis_field: None,
            region: None,
        }
    }
}

/// How the axes' change along a pass is measured for `machine`. On the built-in A/C machine,
/// its C turning without end, by how far the rotaries turn, not the tool. Where C is limited,
/// the great circle's passes by the pole let the post flip A's sign and bring C back (a dome on
/// a head-head fork limited to ±100° did not post once smoothed by the rotaries: C ran out
/// along a pass), and a machine definition's pole is its own. (Choosing the axes by the
/// rotaries' turn too measured slower on the blower's fixture, 29.0 against 27.1 min, its
/// links between segments taking longer; the sample impeller gained nothing.)
fn smoothing_turn(machine: &Machine) -> AxisTurn {
    match machine {
        Machine::TableTableAc(ac) if ac.c_limits_deg.is_none() => AxisTurn::Rotaries {
            pole: PlanSetup::POLE,
        },
        _ => AxisTurn::Angle,
    }
}

/// Refuses a job whose finishing passes are estimated to have more drive points than
/// `limits.max_drive_points`, before any of the work. The planes are a stepover apart and each
/// section is sampled at most `max_step` apart, so a surface of area A has at least about
/// A / (stepover · max_step) drive points; the points where sections cross the drive surface's
/// edges come on top (measured: 2.8× the estimate on the sample impeller, 4.4× on the real
/// blower), so the estimate is a lower one and the limit is set with that in mind.
fn check_drive_points(mesh: &MeshReport, job: &Job) -> Result<()> {
    let stepover = path::planned_stepover(job.tool.diameter / 2.0, job.strategy.scallop_height);
    let estimate = mesh.surface_area / (stepover * job.strategy.max_step);
    let limit = job.limits.max_drive_points;
    if estimate > limit as f64 {
        return Err(Error::TooLarge {
            what: format!(
                "finishing {:.0} mm² at a {stepover:.4} mm stepover and {} mm steps",
                mesh.surface_area, job.strategy.max_step
            ),
            estimate: format!("{:.3e} drive points", estimate),
            limit: format!("{limit}"),
            advice: "check the part's units and the scallop height".into(),
            limit_key: "limits.max_drive_points".into(),
        });
    }
    Ok(())
}

/// `mesh` turned so that the unit vector `up` points along +Z (the shortest rotation; 180°
/// about X when `up` points down).
pub(crate) fn turned_upright(mesh: &Mesh, up: &Vector3) -> Mesh {
    let rotation = upright_rotation(up);
    Mesh {
        positions: mesh.positions.iter().map(|p| rotation * p).collect(),
        triangles: mesh.triangles.clone(),
    }
}

/// The rotation that turns `up` into +Z (the shortest one; a half turn about X for −Z).
pub(crate) fn upright_rotation(up: &Vector3) -> nalgebra::Rotation3<f64> {
    nalgebra::Rotation3::rotation_between(up, &Vector3::z()).unwrap_or_else(|| {
        nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
    })
}

/// Where the job clamps `part` on the table: `[machine] part_origin_in_table`, by default
/// centred on the table's axis in X and Y and standing on the table.
pub fn part_origin_in_table(job: &Job, part: &Mesh) -> Vector3 {
    let part_box = part.aabb();
    job.machine
        .part_origin_in_table
        .map(Vector3::from)
        .unwrap_or_else(|| -Vector3::new(part_box.center().x, part_box.center().y, part_box.min.z))
        .map(positive_zero)
}

/// The program's dialect, output and feed modes: the machine definition's, else the built-in
/// machine's LinuxCNC with `[machine] feed` (per minute when left out), joint output (the
/// validation refuses TCP output without a definition) and its rotary speed.
pub fn gcode_options(job: &Job) -> Result<GcodeOptions> {
    Ok(match job.machine_definition()? {
        Some(d) => GcodeOptions {
            dialect: d.dialect,
            output: d.output,
            feed: d.feed,
            max_rotary_speed: d.max_rotary_speed,
            ..GcodeOptions::default()
        },
        None => {
            let default = GcodeOptions::default();
            GcodeOptions {
                output: job.machine.output.unwrap_or(default.output),
                feed: job.machine.feed.unwrap_or(default.feed),
                max_rotary_speed: job.machine.max_rotary_speed,
                ..default
            }
        }
    })
}

/// How the back-simulation reads a program posted for `kinematics` in `options`' dialect and
/// output mode: plain data for the verifier's own forward kinematics, with the gauge length of
/// every tool the program runs (`(number, mm)`).
pub fn verifier_model_of(
    kinematics: &Machine,
    part_origin_in_table: Vector3,
    options: &GcodeOptions,
    gauges: &[(u32, f64)],
) -> crate::verify::MachineModel {
    use crate::verify::{ChainModel, MachineModel, ModelAxis};
    match kinematics {
        Machine::Chain(chain) => {
            let axis = |j: &crate::post::RotaryJoint| ModelAxis {
                letter: j.letter.to_string().chars().next().unwrap_or('A'),
                on_table: j.side == crate::post::AxisSide::Table,
                direction: j.direction.into_inner(),
                point: j.point,
            };
            let head = chain.has_head_axes();
            MachineModel::Chain(ChainModel {
                axes: [axis(&chain.first), axis(&chain.second)],
                part_origin_in_table: chain.part_origin_in_table,
                head_lengths: if head {
                    gauges
                        .iter()
                        .map(|&(id, g)| (id, chain.pivot_length + g))
                        .collect()
                } else {
                    Vec::new()
                },
                tcp: options.output == crate::post::OutputMode::Tcp,
                tcp_in_program: options.dialect != crate::post::Dialect::Linuxcnc,
                conversational: options.dialect == crate::post::Dialect::Heidenhain,
            })
        }
        _ => MachineModel::TableTableAc {
            part_origin_in_table,
        },
    }
}

/// How a program posted for `job`'s machine is read back, with `part` clamped where the job
/// clamps it and the job's tool in the spindle (tool number `tool_number`), and a one-line
/// description of it.
pub fn posted_program_model(
    job: &Job,
    part: &Mesh,
    tool_number: u32,
) -> Result<(crate::verify::MachineModel, String)> {
    let origin = part_origin_in_table(job, part);
    let gauge = job.tool.assembly().total_length();
    let kinematics = machine(job, origin, gauge)?;
    let options = gcode_options(job)?;
    let model = verifier_model_of(&kinematics, origin, &options, &[(tool_number, gauge)]);
    let description = format!(
        "{}, {} output in the {} dialect, part origin in table [{}, {}, {}] mm",
        kinematics.description(),
        options.output.name(),
        options.dialect.name(),
        origin.x,
        origin.y,
        origin.z
    );
    Ok((model, description))
}

/// The machine the job describes, with the part clamped at `part_origin_in_table` and a tool of
/// gauge length `gauge_mm` in the spindle (used by machines with head axes, whose linear axes
/// carry the tool's length in joint output).
pub fn machine(job: &Job, part_origin_in_table: Vector3, gauge_mm: f64) -> Result<Machine> {
    let m = &job.machine;
    let kin = match job.machine_definition()? {
        Some(definition) => Machine::Chain(Box::new(
            definition.chain_for(part_origin_in_table, gauge_mm),
        )),
        None => match m.kinematics {
            KinematicsKind::ThreeAxis => Machine::ThreeAxis(ThreeAxis),
            // Validation lets no other kind through without a definition.
            _ => Machine::TableTableAc(
                TableTableAC::new(part_origin_in_table)
                    .with_a_limits(m.a_limits[0], m.a_limits[1])
                    .with_c_limits(m.c_limits.map(|[lo, hi]| (lo, hi))),
            ),
        },
    };
    kin.validate()?;
    Ok(kin)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::post::{FeedMode, OutputMode};

    /// Without a machine definition the built-in machine's program takes `[machine] feed`
    /// (`--feed`): it was once read and silently not used. (`output = "tcp"` needs a
    /// definition: the job file's validation refuses it.)
    #[test]
    fn axes_are_smoothed_by_the_rotaries_only_where_c_turns_without_end() {
        let ac = TableTableAC::new(Vector3::zeros());
        assert_eq!(
            smoothing_turn(&Machine::TableTableAc(ac.clone())),
            AxisTurn::Rotaries { pole: Vector3::z() }
        );
        let limited = ac.with_c_limits(Some((-100.0, 100.0)));
        assert_eq!(
            smoothing_turn(&Machine::TableTableAc(limited)),
            AxisTurn::Angle
        );
        assert_eq!(
            smoothing_turn(&Machine::ThreeAxis(ThreeAxis)),
            AxisTurn::Angle
        );
    }

    #[test]
    fn the_built_in_machine_takes_the_jobs_feed_mode() {
        let mut job = Job::default();
        let plain = gcode_options(&job).expect("options");
        assert_eq!(
            (plain.feed, plain.output),
            (FeedMode::PerMinute, OutputMode::Joint)
        );
        job.machine.feed = Some(FeedMode::InverseTime);
        job.machine.max_rotary_speed = 5400.0;
        let set = gcode_options(&job).expect("options");
        assert_eq!(
            (set.feed, set.output, set.max_rotary_speed),
            (FeedMode::InverseTime, OutputMode::Joint, 5400.0)
        );
    }
}
