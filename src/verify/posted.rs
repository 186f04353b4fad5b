//! Back-simulation of a posted program: the ball centre along every block as the control moves
//! it, measured against the part.
//!
//! The program is read from its text ([`super::program`]), so what is checked is what was
//! written, rounded as written, with every word the post left out. Between two blocks the
//! control interpolates X, Y, Z and both rotary axes linearly in the block's parameter
//! `t ∈ [0, 1]` (G1, and G0 on a control that coordinates its rapids, as LinuxCNC does); the
//! forward kinematics below turn those joints into the ball centre in the part frame.
//!
//! # How densely, and why that is enough
//! In the part frame the ball centre is `c(t) = Q(t)·u(t) − o`: `u` is the centre in machine
//! coordinates (tip + r along machine Z, linear in t), `Q(t)` the inverse rotation of the
//! table for the interpolated rotary angles, `o` the part origin in the table frame. With
//! `ω = |Δa| + |Δc|` (radians over the block), `|Q′v| ≤ ω|v|` and `|Q″v| ≤ ω²|v|`, so
//! `|c″| ≤ ω²·U + 2ω·L`, where `U` bounds `|u|` over the block (the larger end: `|u|` is convex
//! along a straight line) and `L = |Δu|`. A piece of parameter length `h` then leaves its
//! chord by at most `e = h²(ω²U + 2ωL)/8` (the error of linear interpolation). Each block is
//! cut into `n` equal pieces with `e ≤` the requested error bound, and each piece's chord is
//! measured exactly against the part ([`super::segment_distance`]); the clearance of the piece
//! is at least `distance(chord) − e − r`. The reported minimum is that lower bound, so it is
//! certified: no point of the interpolated path comes closer.
//!
//! # Measuring only what can change the answer
//! Only the least clearance (and the line it is first reached at) is reported, so a block
//! matters only where it goes below what other blocks reach. A first pass bounds the answer
//! from above with one point per block (a block's certified clearance is at most the ball's
//! distance at its end, less its last piece's error); the second measures each block as one
//! chord with the whole block's error, `curvature / 8`, and cuts it into pieces only when that
//! chord comes near enough to go below the bound. The minimum and its line are those of the
//! piece-by-piece measurement (a test compares the two); on the blower impeller's finishing
//! program this measures a fraction of the pieces.
//!
//! # The flutes
//! With [`PostedOptions::flutes_above_ball`] the cutting part of a ball-end mill is measured
//! whole: the cylinder of the ball's radius round the axis from the ball's centre up that
//! far. Its clearance is the distance from the part of the sheet `c(t) + s·k(t)` the axis
//! segment sweeps, less the radius; the sheet is cut into pieces measured as triangles with
//! an error bound of the same kind as the chords' ([`FluteSheets`]), so this minimum is a
//! certified lower bound too. Where the flutes are nowhere near the part the pieces are few
//! and far; the surface round the ball's contact lies below the ball's equator, where the
//! axis is nearest the part at the ball's centre, and is left to the ball's measure. The
//! flutes' figure is the least of theirs and the ball's, so after the ball's pass a sheet is
//! measured only where it could go below the ball's minimum.
//!
//! The path is one continuous curve from the program's first fully known position, which is
//! checked to lie outside the part's bounding sphere about the pivot. A path that never comes
//! within 0 of the surface therefore never enters the part, and the unsigned distance is the
//! clearance.

use rayon::prelude::*;
use serde::Serialize;

use super::program::{MotionBlock, ProgramError, read_conversational, read_program};
use super::segment_distance::{SegmentDistance, point_segment_distance};
use crate::geom::{Point3, Vector3};
use crate::mesh::Mesh;

/// The machine as the verifier models it: plain data, independent of the post's code.
#[derive(Clone, Debug, PartialEq)]
pub enum MachineModel {
    /// Tool along machine +Z; the cradle turns by A about machine X, the round table on it by
    /// C about its own axis. A part point `p` sits at machine `R_x(A)·R_z(C)·(p + o)`.
    TableTableAc {
        /// Where the part frame's origin sits in the table frame, mm.
        part_origin_in_table: Vector3,
    },
    /// Three linear axes, the tool along +Z, the work offset at the part's origin: machine X, Y,
    /// Z are the part's.
    ThreeAxis,
    /// Two rotary axes on the table or head side, as a machine file describes them.
    Chain(ChainModel),
}

/// One rotary axis of a [`ChainModel`]: the line it turns about at home (all rotaries at 0),
/// machine frame for a table axis, from the head's reference point for a head axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelAxis {
    /// Its address letter.
    pub letter: char,
    /// `true`: it turns the part; `false`: the spindle.
    pub on_table: bool,
    /// Unit direction (right-handed positive rotation).
    pub direction: Vector3,
    /// A point on it, mm.
    pub point: Vector3,
}

/// A 5-axis machine of two rotary axes as the verifier reads its programs.
///
/// The first axis is the one nearer the machine's base on its side (the cradle, the head of a
/// head-table machine, the ram-side head axis); a table axis carries the part at `o` from the
/// program origin, a head axis carries the tool tip `head_length` below the head's reference
/// point, which X, Y, Z command. In TCP programs X, Y, Z are the tip in the part frame.
#[derive(Clone, Debug, PartialEq)]
pub struct ChainModel {
    /// First and second rotary axis.
    pub axes: [ModelAxis; 2],
    /// Where the part frame's origin sits in the table frame, mm.
    pub part_origin_in_table: Vector3,
    /// Head reference point to tool tip per tool number (joint programs of machines with head
    /// axes), mm; empty otherwise.
    pub head_lengths: Vec<(u32, f64)>,
    /// X, Y, Z are the tool tip in the part frame (tool-centre-point control).
    pub tcp: bool,
    /// The program switches TCP control on and off itself (`G43.4`, `TRAORI`, `FUNCTION
    /// TCPM`); `false` where it is a mode of the machine's configuration (LinuxCNC), and the
    /// program cannot be checked for it.
    pub tcp_in_program: bool,
    /// The program is Heidenhain conversational.
    pub conversational: bool,
}

/// Rodrigues' rotation of `v` by `angle` (radians) about unit `k`.
fn rodrigues(k: &Vector3, angle: f64, v: &Vector3) -> Vector3 {
    let (s, c) = angle.sin_cos();
    v * c + k.cross(v) * s + k * (k.dot(v) * (1.0 - c))
}

impl ChainModel {
    fn has_head_axes(&self) -> bool {
        self.axes.iter().any(|a| !a.on_table)
    }

    fn head_length(&self, tool: Option<u32>) -> f64 {
        if self.tcp {
            return 0.0;
        }
        tool.and_then(|t| self.head_lengths.iter().find(|(n, _)| *n == t))
            .or(self.head_lengths.first())
            .map_or(0.0, |(_, l)| *l)
    }

    /// The tool axis and a machine point brought into the part frame at rotary angles
    /// `angles` (radians): the head's axes turn the tool (the one nearer the spindle first), the
    /// table's are undone (the one nearer the base first).
    fn to_part_frame(&self, angles: [f64; 2], machine_point: &Vector3) -> (Vector3, Vector3) {
        let mut axis = Vector3::z();
        for i in [1, 0] {
            let a = &self.axes[i];
            if !a.on_table {
                axis = rodrigues(&a.direction, angles[i], &axis);
            }
        }
        let mut point = *machine_point;
        for i in [0, 1] {
            let a = &self.axes[i];
            if a.on_table {
                point = a.point + rodrigues(&a.direction, -angles[i], &(point - a.point));
                axis = rodrigues(&a.direction, -angles[i], &axis);
            }
        }
        (point - self.part_origin_in_table, axis)
    }

    /// The tip in the machine frame for joints `[x, y, z, …]` (joint programs): X, Y, Z plus
    /// the head's turn of the vector to the tip.
    fn tip_in_machine(&self, joints: &[f64; 5], angles: [f64; 2], tool: Option<u32>) -> Vector3 {
        let mut tip = Vector3::new(0.0, 0.0, -self.head_length(tool));
        for i in [1, 0] {
            let a = &self.axes[i];
            if !a.on_table {
                tip = a.point + rodrigues(&a.direction, angles[i], &(tip - a.point));
            }
        }
        Vector3::new(joints[0], joints[1], joints[2]) + tip
    }

    /// Tip and axis in the part frame.
    fn pose(&self, joints: &[f64; 5], tool: Option<u32>) -> (Point3, Vector3) {
        let angles = [joints[3].to_radians(), joints[4].to_radians()];
        if self.tcp {
            let (_, axis) = self.to_part_frame(angles, &Vector3::zeros());
            return (Point3::new(joints[0], joints[1], joints[2]), axis);
        }
        let (tip, axis) = self.to_part_frame(angles, &self.tip_in_machine(joints, angles, tool));
        (Point3::from(tip), axis)
    }
}

impl MachineModel {
    /// The block's joints once all five are known (a 3-axis machine's rotaries stand at 0).
    fn joints(&self, b: &MotionBlock) -> Option<[f64; 5]> {
        let [x, y, z, a, c] = b.axes;
        match self {
            MachineModel::ThreeAxis => Some([x?, y?, z?, 0.0, 0.0]),
            _ => Some([x?, y?, z?, a?, c?]),
        }
    }

    fn axis_letters(&self) -> [char; 5] {
        match self {
            MachineModel::TableTableAc { .. } | MachineModel::ThreeAxis => {
                ['X', 'Y', 'Z', 'A', 'C']
            }
            MachineModel::Chain(m) => ['X', 'Y', 'Z', m.axes[0].letter, m.axes[1].letter],
        }
    }

    /// Reads `program` in the machine's language.
    fn read(&self, program: &str) -> Result<Vec<MotionBlock>, ProgramError> {
        match self {
            MachineModel::Chain(m) if m.conversational => {
                read_conversational(program, self.axis_letters())
            }
            _ => read_program(program, self.axis_letters()),
        }
    }

    /// Whether the program's motion blocks must run with length compensation on: off only for
    /// joint programs of machines with head axes, whose X, Y, Z carry the tool length.
    fn expects_compensation(&self) -> bool {
        match self {
            MachineModel::Chain(m) => m.tcp || !m.has_head_axes(),
            _ => true,
        }
    }

    /// Whether the program's motion blocks must have TCP control on (`Some(true)`), off, or
    /// cannot say (`None`: LinuxCNC, where it is the machine configuration's mode).
    fn expects_tcp(&self) -> Option<bool> {
        match self {
            MachineModel::Chain(m) if m.tcp && !m.tcp_in_program => None,
            MachineModel::Chain(m) => Some(m.tcp),
            _ => Some(false),
        }
    }

    /// The pivot (where the rotary axes meet) in the part frame.
    pub fn pivot(&self) -> Point3 {
        match self {
            MachineModel::TableTableAc {
                part_origin_in_table,
            } => Point3::from(-part_origin_in_table),
            MachineModel::ThreeAxis => Point3::origin(),
            MachineModel::Chain(m) => Point3::from(-m.part_origin_in_table),
        }
    }

    /// The ball centre (radius `r`) in the part frame at joints `[x, y, z, a°, c°]`.
    fn ball_centre(&self, joints: &[f64; 5], r: f64, tool: Option<u32>) -> Point3 {
        let pose = self.pose(joints, tool);
        pose.tip + pose.axis.into_inner() * r
    }

    /// A bound on the second derivative (in the block parameter) of the ball centre along the
    /// joint interpolation `j0 → j1` (see the module docs).
    fn curvature_bound(&self, j0: &[f64; 5], j1: &[f64; 5], r: f64, tool: Option<u32>) -> f64 {
        let u0 = Vector3::new(j0[0], j0[1], j0[2]);
        let u1 = Vector3::new(j1[0], j1[1], j1[2]);
        let omega = (j1[3] - j0[3]).to_radians().abs() + (j1[4] - j0[4]).to_radians().abs();
        match self {
            MachineModel::ThreeAxis => 0.0,
            MachineModel::TableTableAc { .. } => {
                let lift = Vector3::new(0.0, 0.0, r);
                omega * omega * (u0 + lift).norm().max((u1 + lift).norm())
                    + 2.0 * omega * (u1 - u0).norm()
            }
            // TCP: the tip moves on its line; only the ball centre's swing about it curves.
            MachineModel::Chain(m) if m.tcp => omega * omega * r,
            // The ball centre is c = T⁻¹(u + H·w): w the ball centre from the head's
            // reference point (|w| ≤ head length + r), H the head's turns, T the table's, each
            // a turn R about a line through a point b, x ↦ b + R(x − b). Two turns at rates
            // ω₁, ω₂ bend a point x by |(R₁R₂x)″| ≤ (ω₁ + ω₂)²(|x| + |b₁| + 2|b₂|) (expand the
            // product; |x − b| ≤ |x| + |b|). So the head's turns alone bend c by at most
            // ω²(|w| + 2Σ|b|): the linear axes only carry the head along. With table axes the
            // turned point is u + H·w, and the cross term of the table's turn with the linear
            // motion adds 2ω|Δu|.
            MachineModel::Chain(m) => {
                let points: f64 = m.axes.iter().map(|a| a.point.norm()).sum();
                let w = m.head_length(tool) + r;
                let table = m.axes.iter().any(|a| a.on_table);
                let u = if table { u0.norm().max(u1.norm()) } else { 0.0 };
                let cross = if table {
                    2.0 * omega * (u1 - u0).norm()
                } else {
                    0.0
                };
                omega * omega * (u + w + 2.0 * points) + cross
            }
        }
    }

    /// The tool's pose in the part frame at a program's joints `[x, y, z, first°, second°]`
    /// for the tool numbered `tool` (what the verifier reads the program as).
    pub fn program_pose(&self, joints: &[f64; 5], tool: Option<u32>) -> crate::geom::ToolPose {
        self.pose(joints, tool)
    }

    /// The tool's pose in the part frame at joints `[x, y, z, a°, c°]` (the tip at machine
    /// X, Y, Z with length compensation on, the tool along machine +Z).
    fn pose(&self, joints: &[f64; 5], tool: Option<u32>) -> crate::geom::ToolPose {
        let (tip, axis) = match self {
            MachineModel::ThreeAxis => (Point3::new(joints[0], joints[1], joints[2]), Vector3::z()),
            MachineModel::TableTableAc {
                part_origin_in_table,
            } => {
                // R_x(a)ᵀ, then R_z(c)ᵀ: undo the cradle, then the table.
                let (a, c) = (joints[3].to_radians(), joints[4].to_radians());
                let undo = |u: &Vector3| {
                    let (sa, ca) = a.sin_cos();
                    let w = Vector3::new(u.x, ca * u.y + sa * u.z, -sa * u.y + ca * u.z);
                    let (sc, cc) = c.sin_cos();
                    Vector3::new(cc * w.x + sc * w.y, -sc * w.x + cc * w.y, w.z)
                };
                let u = Vector3::new(joints[0], joints[1], joints[2]);
                (
                    Point3::from(undo(&u) - part_origin_in_table),
                    undo(&Vector3::z()),
                )
            }
            MachineModel::Chain(m) => m.pose(joints, tool),
        };
        crate::geom::ToolPose {
            tip,
            axis: nalgebra::Unit::new_normalize(axis),
        }
    }
}

/// A posted program read back as the part-frame toolpath the control drives: every motion
/// block from the first fully known position, its joints interpolated linearly as the control
/// does, cut into moves whose tips stay within `max_error` mm of their chords (the bound of
/// the module docs, with the tip for the ball centre). G0 blocks become rapids, G1 blocks cuts
/// (at feed 0: the feed is not read). Written apart from the post, like the rest of this
/// module, so a simulation of it checks the post too.
///
/// Also the program line each move comes from.
pub fn program_toolpath(
    program: &str,
    machine: &MachineModel,
    max_error: f64,
) -> Result<(crate::geom::Toolpath, Vec<usize>), ProgramError> {
    use crate::geom::{Move, MoveKind, Toolpath};
    let blocks = machine.read(program)?;
    let mut moves = Vec::new();
    let mut lines = Vec::new();
    let mut previous: Option<[f64; 5]> = None;
    for block in &blocks {
        let Some(j1) = machine.joints(block) else {
            continue;
        };
        let kind = if block.rapid {
            MoveKind::Rapid
        } else {
            MoveKind::Cut
        };
        let Some(j0) = previous else {
            moves.push(Move {
                pose: machine.pose(&j1, block.tool),
                kind: MoveKind::Rapid,
                feed: 0.0,
            });
            lines.push(block.line);
            previous = Some(j1);
            continue;
        };
        let curvature = machine.curvature_bound(&j0, &j1, 0.0, block.tool);
        let n =
            ((curvature / (8.0 * max_error.max(1e-9))).sqrt().ceil() as usize).clamp(1, MAX_PIECES);
        if moves.len() + n > MAX_MOVES {
            return Err(ProgramError {
                line: block.line,
                reason: format!(
                    "the program runs to more than {MAX_MOVES} moves at a {max_error} mm \
                     tolerance (rotary moves this long are not a part's program)"
                ),
            });
        }
        for k in 1..=n {
            let t = k as f64 / n as f64;
            let j: [f64; 5] = std::array::from_fn(|i| j0[i] + (j1[i] - j0[i]) * t);
            moves.push(Move {
                pose: machine.pose(&j, block.tool),
                kind,
                feed: 0.0,
            });
            lines.push(block.line);
        }
        previous = Some(j1);
    }
    if moves.is_empty() {
        return Err(ProgramError {
            line: program.lines().count(),
            reason: "no motion block with X, Y, Z and both rotary axes known: nothing to run"
                .into(),
        });
    }
    Ok((Toolpath { tool_id: 1, moves }, lines))
}

/// How the back-simulation measures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PostedOptions {
    pub ball_radius: f64,
    /// Largest distance between the interpolated path and the chords measured, along feed
    /// moves (G1), mm. Subtracted from every clearance reported.
    pub feed_error_mm: f64,
    /// The same along rapids (G0), where only a margin is at stake, mm.
    pub rapid_error_mm: f64,
    /// Clearances are searched up to this distance beyond the ball; farther reads as this.
    pub search_mm: f64,
    /// Measure only the blocks this tool runs (the ball's, in a program whose roughing tools
    /// are checked by [`crate::rough::check`]); `None`: every block.
    pub tool: Option<u32>,
    /// How far the printed words' rounding can move a block's end (mm, ball centre): an
    /// inverse-time block's distance is taken this much shorter at each end before it is
    /// timed by its F, so a short block's rounding does not read as speed.
    pub rounding_mm: f64,
    /// How far the flutes reach up the axis above the ball's centre, mm: with more than 0 the
    /// ball and its flutes are measured together too ([`FluteClearance`]).
    pub flutes_above_ball: f64,
}

/// What the back-simulation found.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PostedClearance {
    pub motion_blocks: usize,
    /// Chords measured: whole blocks, the runs of pieces they were halved into, and pieces
    /// (each within its error bound), where they could go below the least clearance.
    pub pieces: usize,
    /// Least ball clearance (distance of the ball centre − r) along G1 blocks, a certified lower
    /// bound; negative = the ball cuts into the part by that much.
    pub min_feed_clearance_mm: f64,
    /// Program line where it occurs.
    pub min_feed_line: usize,
    /// The same along G0 blocks.
    pub min_rapid_clearance_mm: f64,
    pub min_rapid_line: usize,
    pub feed_error_bound_mm: f64,
    pub rapid_error_bound_mm: f64,
    pub search_distance_mm: f64,
    /// In an inverse-time program: the fastest the ball centre moves relative to the part
    /// along a G1 block (the straight distance it makes good, less the rounding at both ends,
    /// times the block's F), mm/min, and the line. `None` for feed per minute.
    pub fastest_part_feed: Option<(f64, usize)>,
    /// The ball and its flutes together, where [`PostedOptions::flutes_above_ball`] asks.
    pub flutes: Option<FluteClearance>,
    /// What is wrong with the program's structure (motion before tool length compensation, a
    /// start that cannot be shown to be outside the part).
    pub problems: Vec<String>,
}

impl PostedClearance {
    /// The checks of one program's blocks for two tools (each measured with its own ball) as
    /// one: the least clearances with their lines, pieces added, the fastest feed, each
    /// problem once.
    pub fn merge(mut self, other: PostedClearance) -> PostedClearance {
        // The smaller clearance, with its line.
        fn keep_least(clearance: &mut f64, line: &mut usize, other: (f64, usize)) {
            if other.0 < *clearance {
                (*clearance, *line) = other;
            }
        }
        let (feed, rapid) = (
            (other.min_feed_clearance_mm, other.min_feed_line),
            (other.min_rapid_clearance_mm, other.min_rapid_line),
        );
        keep_least(
            &mut self.min_feed_clearance_mm,
            &mut self.min_feed_line,
            feed,
        );
        keep_least(
            &mut self.min_rapid_clearance_mm,
            &mut self.min_rapid_line,
            rapid,
        );
        self.pieces += other.pieces;
        self.fastest_part_feed = match (self.fastest_part_feed, other.fastest_part_feed) {
            (Some(a), Some(b)) => Some(if b.0 > a.0 { b } else { a }),
            (a, b) => a.or(b),
        };
        self.flutes = match (self.flutes.take(), other.flutes) {
            (Some(mut a), Some(b)) => {
                let (feed, rapid) = (
                    (b.min_feed_clearance_mm, b.min_feed_line),
                    (b.min_rapid_clearance_mm, b.min_rapid_line),
                );
                keep_least(&mut a.min_feed_clearance_mm, &mut a.min_feed_line, feed);
                keep_least(&mut a.min_rapid_clearance_mm, &mut a.min_rapid_line, rapid);
                a.cells += b.cells;
                Some(a)
            }
            (a, b) => a.or(b),
        };
        for problem in other.problems {
            if !self.problems.contains(&problem) {
                self.problems.push(problem);
            }
        }
        self
    }
}

/// The least clearance of the ball and its flutes together: of the cylinder of the ball's
/// radius round the axis from the ball's centre to the flutes' top (capped by half a ball
/// there), which holds the ball-end mill's cutting part. Measured as the distance from the
/// part of the sheet the axis segment sweeps, less the radius, and never above the ball's
/// own; certified like the ball's (module docs, "The flutes").
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FluteClearance {
    pub flutes_above_ball_mm: f64,
    /// Pieces of sheet measured.
    pub cells: usize,
    /// Least clearance along G1 blocks; negative = the tool cuts into the part by that much.
    pub min_feed_clearance_mm: f64,
    pub min_feed_line: usize,
    /// The same along G0 blocks.
    pub min_rapid_clearance_mm: f64,
    pub min_rapid_line: usize,
}

/// Most pieces one block may be cut into; a block that needs more is measured with the error
/// this leaves, which is reported.
const MAX_PIECES: usize = 100_000;

/// Most pieces of sheet one block's flutes are measured in; past it the pieces left are taken
/// with the error they have (still a lower bound, a looser one).
const MAX_SHEET_CELLS: usize = 20_000;

/// Most moves a read-back program may expand to: bounds the memory a small file with huge
/// rotary words could ask for.
const MAX_MOVES: usize = 20_000_000;

/// Reads `program` and measures the ball centre along every motion block against `part`.
pub fn check_posted(
    program: &str,
    machine: &MachineModel,
    part: &Mesh,
    options: &PostedOptions,
) -> Result<PostedClearance, ProgramError> {
    check_posted_pruned(program, machine, part, options, true)
}

/// [`check_posted`], with `prune` false measuring every piece of every block (the reference
/// the pruned measurement is tested against).
fn check_posted_pruned(
    program: &str,
    machine: &MachineModel,
    part: &Mesh,
    options: &PostedOptions,
    prune: bool,
) -> Result<PostedClearance, ProgramError> {
    let blocks = machine.read(program)?;
    let tree = SegmentDistance::new(part);
    let r = options.ball_radius;
    let mut problems = Vec::new();
    let expected = machine.expects_compensation();
    if let Some(b) = blocks.iter().find(|b| b.length_compensation != expected) {
        problems.push(if expected {
            format!(
                "line {}: moves before tool length compensation is on",
                b.line
            )
        } else {
            format!(
                "line {}: moves with tool length compensation on, but X Y Z already carry the \
                 tool's length",
                b.line
            )
        });
    }
    if let Some(tcp) = machine.expects_tcp()
        && let Some(b) = blocks.iter().find(|b| b.tcp != tcp)
    {
        problems.push(format!(
            "line {}: moves with tool-centre-point control {} in a {} program",
            b.line,
            if b.tcp { "on" } else { "off" },
            if tcp { "TCP" } else { "joint" }
        ));
    }
    let joints = |b: &MotionBlock| machine.joints(b);
    let first = blocks.iter().position(|b| joints(b).is_some());
    let pivot = machine.pivot();
    let reach = part
        .positions
        .iter()
        .map(|p| (p - pivot).norm())
        .fold(0.0, f64::max);
    if let Some(i) = first {
        let j = joints(&blocks[i]).unwrap_or_default();
        let start = machine.ball_centre(&j, r, blocks[i].tool);
        let flutes_top =
            start + machine.pose(&j, blocks[i].tool).axis.into_inner() * options.flutes_above_ball;
        let flutes_in_reach = options.flutes_above_ball > 0.0
            && point_segment_distance(&pivot, &start, &flutes_top) <= reach + r;
        if (start - pivot).norm() <= reach + r || flutes_in_reach {
            problems.push(format!(
                "line {}: the first position is within the part's reach from the pivot; it \
                 cannot be shown to be outside the part",
                blocks[i].line
            ));
        }
    }
    let pairs: Vec<BlockJoints> = match first {
        None => Vec::new(),
        Some(f) => (f + 1..blocks.len())
            .filter(|&i| options.tool.is_none_or(|t| blocks[i].tool == Some(t)))
            .filter_map(|i| Some((i, joints(&blocks[i - 1])?, joints(&blocks[i])?)))
            .collect(),
    };
    let limit = r + options.search_mm;
    let steps: Vec<BlockSteps> = pairs
        .iter()
        .map(|&(i, j0, j1)| {
            let error = if blocks[i].rapid {
                options.rapid_error_mm
            } else {
                options.feed_error_mm
            };
            BlockSteps::new(machine, &j0, &j1, r, error, blocks[i].tool)
        })
        .collect();
    // What a block must go below to change the answer, per kind (feed, rapid): the ceilings
    // of the first pass, raised by a nanometre so that f64 rounding in either pass cannot
    // leave out the block the minimum is reached at. Without a ceiling within the search
    // distance there is nothing to prune against.
    let floors = if prune {
        let (feed, rapid) = clearance_ceilings(machine, &tree, &blocks, &pairs, &steps, r, limit);
        let raise = |c: f64| (c + r + 1e-9 < limit).then_some(c + 1e-9);
        (raise(feed), raise(rapid))
    } else {
        (None, None)
    };
    // Fixed chunks, each a sequential minimum: the same answer for any number of threads.
    let per_chunk: Vec<Minima> = pairs
        .par_chunks(256)
        .zip(steps.par_chunks(256))
        .map(|(chunk, chunk_steps)| {
            let mut m = Minima::new(options.search_mm);
            let mut floors = floors;
            for ((i, j0, j1), block_steps) in chunk.iter().zip(chunk_steps) {
                let block = &blocks[*i];
                let floor = if block.rapid {
                    &mut floors.1
                } else {
                    &mut floors.0
                };
                let (clearance, pieces, length) = block_clearance(
                    machine,
                    &tree,
                    j0,
                    j1,
                    r,
                    block_steps,
                    limit,
                    *floor,
                    block.tool,
                );
                m.pieces += pieces;
                if let Some(c) = clearance {
                    m.note(block.rapid, c, block.line);
                    if floor.is_some() {
                        *floor = Some(m.least(block.rapid));
                    }
                }
                if let (false, true, Some(f)) = (block.rapid, block.inverse_time, block.feed) {
                    m.note_feed(
                        (length - 2.0 * options.rounding_mm).max(0.0) * f,
                        block.line,
                    );
                }
            }
            m
        })
        .collect();
    let mut total = Minima::new(options.search_mm);
    for m in per_chunk {
        total.pieces += m.pieces;
        total.note(false, m.feed.0, m.feed.1);
        total.note(true, m.rapid.0, m.rapid.1);
        if let Some((f, line)) = m.fastest {
            total.note_feed(f, line);
        }
    }
    // The flutes' figure is the least of theirs and the ball's, so a sheet matters only where
    // it goes below the ball's: its minimum is their floor, raised like the ball's.
    let flutes = (options.flutes_above_ball > 0.0).then(|| {
        let sheets = FluteSheets {
            machine,
            tree: &tree,
            r,
            length: options.flutes_above_ball,
            limit,
        };
        let raise = |c: f64| (c + r + 1e-9 < limit).then_some(c + 1e-9);
        let floors = if prune {
            (raise(total.feed.0), raise(total.rapid.0))
        } else {
            (None, None)
        };
        sheets.measure(&blocks, &pairs, options, floors)
    });
    // The sheets leave the surface below the ball's equator to the ball's measure.
    let flutes = flutes.map(|mut f| {
        if total.feed.0 < f.min_feed_clearance_mm {
            (f.min_feed_clearance_mm, f.min_feed_line) = total.feed;
        }
        if total.rapid.0 < f.min_rapid_clearance_mm {
            (f.min_rapid_clearance_mm, f.min_rapid_line) = total.rapid;
        }
        f
    });
    Ok(PostedClearance {
        motion_blocks: blocks.len(),
        pieces: total.pieces,
        min_feed_clearance_mm: total.feed.0,
        min_feed_line: total.feed.1,
        min_rapid_clearance_mm: total.rapid.0,
        min_rapid_line: total.rapid.1,
        feed_error_bound_mm: options.feed_error_mm,
        rapid_error_bound_mm: options.rapid_error_mm,
        search_distance_mm: options.search_mm,
        fastest_part_feed: total.fastest,
        flutes,
        problems,
    })
}

/// Running minima (clearance, line) for feed and rapid blocks.
struct Minima {
    feed: (f64, usize),
    rapid: (f64, usize),
    pieces: usize,
    /// Fastest inverse-time part feed (mm/min) and its line.
    fastest: Option<(f64, usize)>,
}

impl Minima {
    fn new(search: f64) -> Self {
        Minima {
            feed: (search, 0),
            rapid: (search, 0),
            pieces: 0,
            fastest: None,
        }
    }

    /// The least clearance so far of feed (`false`) or rapid blocks.
    fn least(&self, rapid: bool) -> f64 {
        if rapid { self.rapid.0 } else { self.feed.0 }
    }

    /// Keeps the faster feed, the earlier line on a tie.
    fn note_feed(&mut self, feed: f64, line: usize) {
        match self.fastest {
            Some((f, l)) if f > feed || (f == feed && l <= line) => {}
            _ => self.fastest = Some((feed, line)),
        }
    }

    /// Keeps the smaller clearance, the earlier line on a tie.
    fn note(&mut self, rapid: bool, clearance: f64, line: usize) {
        let slot = if rapid {
            &mut self.rapid
        } else {
            &mut self.feed
        };
        if clearance < slot.0
            || (clearance == slot.0 && line != 0 && (slot.1 == 0 || line < slot.1))
        {
            *slot = (clearance, line);
        }
    }
}

/// A motion block's index, with the joints at its start and at its end.
type BlockJoints = (usize, [f64; 5], [f64; 5]);

/// How a block is cut into pieces: from the bound `curvature` of `|c″|` along it (see the
/// module docs), the number of pieces `n` that keeps each within its error, and the error
/// `e = curvature / (8 n²)` each piece's chord leaves.
#[derive(Clone, Copy)]
struct BlockSteps {
    n: usize,
    piece_error: f64,
}

impl BlockSteps {
    fn new(
        machine: &MachineModel,
        j0: &[f64; 5],
        j1: &[f64; 5],
        r: f64,
        error: f64,
        tool: Option<u32>,
    ) -> Self {
        let curvature = machine.curvature_bound(j0, j1, r, tool);
        let n = ((curvature / (8.0 * error)).sqrt().ceil() as usize).clamp(1, MAX_PIECES);
        BlockSteps {
            n,
            piece_error: curvature / (8.0 * (n * n) as f64),
        }
    }
}

/// Upper bounds (feed, rapid) of the least certified clearance [`block_clearance`] finds: a
/// block's last piece ends at the ball centre of its end point, so its chord is no farther from
/// the part than that point, and the block's clearance is at most the point's distance less
/// the piece's error and the radius. One point query per block, searched only as far as the
/// chunk's bound so far.
fn clearance_ceilings(
    machine: &MachineModel,
    tree: &SegmentDistance,
    blocks: &[MotionBlock],
    pairs: &[BlockJoints],
    steps: &[BlockSteps],
    r: f64,
    limit: f64,
) -> (f64, f64) {
    let per_chunk: Vec<(f64, f64)> = pairs
        .par_chunks(256)
        .zip(steps.par_chunks(256))
        .map(|(chunk, chunk_steps)| {
            let mut ceilings = (limit - r, limit - r);
            for (pair, block_steps) in chunk.iter().zip(chunk_steps) {
                let block = &blocks[pair.0];
                let piece_error = block_steps.piece_error;
                let ceiling = if block.rapid {
                    &mut ceilings.1
                } else {
                    &mut ceilings.0
                };
                let end = machine.ball_centre(&pair.2, r, block.tool);
                let reach = *ceiling + r + piece_error;
                let d = tree.distance(&end, &end, reach);
                if d < reach {
                    *ceiling = ceiling.min(d - piece_error - r);
                }
            }
            ceilings
        })
        .collect();
    per_chunk
        .iter()
        .fold((limit - r, limit - r), |(f, q), c| (f.min(c.0), q.min(c.1)))
}

/// The certified least clearance of the ball along the joint interpolation `j0 → j1`, how
/// many chords were measured, and the straight distance the ball centre makes good over the
/// block (the planned motion the block interpolates; its path may bulge from it within the
/// tolerance, and be that much longer).
///
/// With a `floor`, the block's clearance is wanted only where it is below the floor (`None`
/// otherwise): the whole block is measured first as one chord, and halved only where a chord
/// comes near enough to go below it. A run of `m` pieces spans `m/n` of the block's
/// parameter, so the path over it lies within `m² · e` of the run's chord, and so does every
/// piece's chord in it (the points within a distance of a segment form a convex set, and a
/// piece's chord joins two of them): each piece's certified clearance `d(piece) − e − r` is at
/// least `d(run) − (m² + 1) · e − r`. The searches, too, reach only as far as the floor.
#[allow(clippy::too_many_arguments)]
fn block_clearance(
    machine: &MachineModel,
    tree: &SegmentDistance,
    j0: &[f64; 5],
    j1: &[f64; 5],
    r: f64,
    steps: &BlockSteps,
    limit: f64,
    floor: Option<f64>,
    tool: Option<u32>,
) -> (Option<f64>, usize, f64) {
    let BlockSteps { n, piece_error } = *steps;
    let at = |k: usize| {
        let t = k as f64 / n as f64;
        let j: [f64; 5] = std::array::from_fn(|i| j0[i] + (j1[i] - j0[i]) * t);
        machine.ball_centre(&j, r, tool)
    };
    let (start, end) = (at(0), at(n));
    let mut least = floor.map_or(limit, |f| f + r);
    let mut lowered = false;
    // A piece's certified distance, kept where it is below the least so far.
    let mut measure_piece = |a: &Point3, b: &Point3, least: &mut f64| {
        let d = tree.distance(a, b, *least + piece_error) - piece_error;
        if d < *least {
            *least = d;
            lowered = true;
        }
    };
    let mut measured = 0;
    if floor.is_none() {
        let mut previous = start;
        for k in 1..=n {
            let next = at(k);
            measure_piece(&previous, &next, &mut least);
            previous = next;
        }
        measured = n;
    } else {
        // Runs of pieces, left to right: a run of `m` pieces is measured as one chord, whose
        // pieces' chords lie within m² · e of it, and split in two only when that chord could
        // come below the least so far.
        let mut runs = vec![(0, n)];
        while let Some((first, m)) = runs.pop() {
            let (a, b) = (at(first), at(first + m));
            measured += 1;
            if m == 1 {
                measure_piece(&a, &b, &mut least);
                continue;
            }
            let reach = least + ((m * m) as f64 + 1.0) * piece_error;
            if tree.distance(&a, &b, reach) < reach {
                let half = m / 2;
                runs.push((first + half, m - half));
                runs.push((first, half));
            }
        }
    }
    let clearance = (least - r).min(limit - r);
    let below = floor.is_none() || (lowered && floor.is_some_and(|f| clearance < f));
    (below.then_some(clearance), measured, (end - start).norm())
}

/// The sheets the flutes' axis sweeps over the blocks, measured against the part.
struct FluteSheets<'a> {
    machine: &'a MachineModel,
    tree: &'a SegmentDistance,
    r: f64,
    /// How far the flutes reach above the ball's centre.
    length: f64,
    limit: f64,
}

impl FluteSheets<'_> {
    /// Every block's sheet, in the ball pass's fixed chunks, each wanted only below its
    /// `floors` (feed, rapid; `None`: measured whole) and below the least clearance its chunk
    /// has found.
    fn measure(
        &self,
        blocks: &[MotionBlock],
        pairs: &[BlockJoints],
        options: &PostedOptions,
        floors: (Option<f64>, Option<f64>),
    ) -> FluteClearance {
        let per_chunk: Vec<Minima> = pairs
            .par_chunks(256)
            .map(|chunk| {
                let mut m = Minima::new(options.search_mm);
                let mut floors = floors;
                for (i, j0, j1) in chunk {
                    let block = &blocks[*i];
                    let (floor, error) = if block.rapid {
                        (&mut floors.1, options.rapid_error_mm)
                    } else {
                        (&mut floors.0, options.feed_error_mm)
                    };
                    let (clearance, cells) = self.block(j0, j1, error, *floor, block.tool);
                    m.pieces += cells;
                    if let Some(c) = clearance {
                        m.note(block.rapid, c, block.line);
                        if floor.is_some() {
                            *floor = Some(m.least(block.rapid));
                        }
                    }
                }
                m
            })
            .collect();
        let mut total = Minima::new(options.search_mm);
        for m in per_chunk {
            total.pieces += m.pieces;
            total.note(false, m.feed.0, m.feed.1);
            total.note(true, m.rapid.0, m.rapid.1);
        }
        FluteClearance {
            flutes_above_ball_mm: self.length,
            cells: total.pieces,
            min_feed_clearance_mm: total.feed.0,
            min_feed_line: total.feed.1,
            min_rapid_clearance_mm: total.rapid.0,
            min_rapid_line: total.rapid.1,
        }
    }

    /// The ball's centre and the unit axis at `joints`.
    fn axis_at(&self, joints: &[f64; 5], tool: Option<u32>) -> (Point3, Vector3) {
        let pose = self.machine.pose(joints, tool);
        let axis = pose.axis.into_inner();
        (pose.tip + axis * self.r, axis)
    }

    /// The certified least clearance of the ball and flutes along the joint interpolation
    /// `j0 → j1` (with a `floor`, only where below it), and how many pieces were measured.
    ///
    /// The sheet `p(t, s) = c(t) + s·k(t)` is cut into pieces `[ta, tb] × [sa, sb]`, each
    /// measured as the two triangles of its corners. A piece's points lie within
    /// `K·(tb − ta)²/8` of the bilinear patch through its corners (linear interpolation in
    /// `t`; `K` bounds `|∂²p/∂t²|`, which is affine in `s` and so at most the larger of the
    /// centre's and the top's curvature bounds), and the patch within `|D|/4` of the two
    /// triangles, `D = (sb − sa)·(k(tb) − k(ta))` its twist. A piece whose triangles are far
    /// enough is dropped; one whose error is above `error` is halved in `t` where its bend
    /// dominates, in `s` where its twist does.
    ///
    /// Mesh triangles below the ball's equator at every pose of a piece are left out: for a
    /// point `p` with `(p − c)·k ≤ 0` the nearest point of the axis segment is the centre, so
    /// its distance to the sheet is its distance to the centre's path, which the ball's
    /// measure bounds (the caller takes the least of both). Below for every `t` is shown with
    /// the chords: `(p − c(t))·k(t)` is at most its larger value at the piece's ends against
    /// the mean axis, plus the centre's bend `e` and `(|p − c| + e)` times how far the axis
    /// strays from that mean (half the chord of its ends, plus `ω²h²/8`).
    fn block(
        &self,
        j0: &[f64; 5],
        j1: &[f64; 5],
        error: f64,
        floor: Option<f64>,
        tool: Option<u32>,
    ) -> (Option<f64>, usize) {
        let curvature =
            self.machine
                .curvature_bound(j0, j1, self.r, tool)
                .max(
                    self.machine
                        .curvature_bound(j0, j1, self.r + self.length, tool),
                );
        let at = |t: f64| {
            let j: [f64; 5] = std::array::from_fn(|i| j0[i] + (j1[i] - j0[i]) * t);
            self.axis_at(&j, tool)
        };
        // The axis turns at most this fast in the block parameter, so it leaves its chord
        // between two parameters h apart by at most ω²h²/8.
        let omega = (j1[3] - j0[3]).to_radians().abs() + (j1[4] - j0[4]).to_radians().abs();
        let mut least = floor.map_or(self.limit, |f| f + self.r);
        let mut lowered = false;
        let mut measured = 0;
        // Strips no taller than the radius to start: a tall tilted sheet's box holds much of
        // the surface round the ball, and most strips are far from it.
        let strips = (self.length / self.r).ceil().max(1.0) as usize;
        let height = self.length / strips as f64;
        let mut pieces: Vec<(f64, f64, f64, f64)> = (0..strips)
            .rev()
            .map(|k| (0.0, 1.0, k as f64 * height, (k + 1) as f64 * height))
            .collect();
        while let Some((ta, tb, sa, sb)) = pieces.pop() {
            let ((ca, ka), (cb, kb)) = (at(ta), at(tb));
            let bend = curvature * (tb - ta) * (tb - ta) / 8.0;
            let twist = (sb - sa) * (kb - ka).norm() / 4.0;
            let piece_error = bend + twist;
            let corners = [ca + ka * sa, cb + kb * sa, cb + kb * sb, ca + ka * sb];
            let reach = least + piece_error;
            // A mesh triangle below the ball's equator at every pose of the piece is nearest
            // the axis at the ball's centre: the ball's own measure has it.
            let (bend_centre, mid) = (bend, 0.5 * (ka + kb));
            let wobble = 0.5 * (kb - ka).norm() + omega * omega * (tb - ta) * (tb - ta) / 8.0;
            let above = |triangle: &[Point3; 3]| {
                triangle.iter().any(|v| {
                    let height = (v - ca).dot(&mid).max((v - cb).dot(&mid));
                    let reach = (v - ca).norm().max((v - cb).norm());
                    height + bend_centre + (reach + bend_centre) * wobble >= 0.0
                })
            };
            let d = self.tree.quad_distance(&corners, reach, above);
            measured += 1;
            if d >= reach {
                continue;
            }
            if piece_error <= error || measured >= MAX_SHEET_CELLS {
                if d - piece_error < least {
                    least = d - piece_error;
                    lowered = true;
                }
            } else if bend >= twist {
                let tm = 0.5 * (ta + tb);
                pieces.push((tm, tb, sa, sb));
                pieces.push((ta, tm, sa, sb));
            } else {
                let sm = 0.5 * (sa + sb);
                pieces.push((ta, tb, sm, sb));
                pieces.push((ta, tb, sa, sm));
            }
        }
        let clearance = (least - self.r).min(self.limit - self.r);
        let below = floor.is_none() || (lowered && floor.is_some_and(|f| clearance < f));
        (below.then_some(clearance), measured)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::cuboid;

    fn machine() -> MachineModel {
        MachineModel::TableTableAc {
            part_origin_in_table: Vector3::new(-15.0, -15.0, 0.0),
        }
    }

    fn options() -> PostedOptions {
        PostedOptions {
            ball_radius: 2.0,
            feed_error_mm: 1e-4,
            rapid_error_mm: 1e-2,
            search_mm: 5.0,
            rounding_mm: 0.0,
            tool: None,
            flutes_above_ball: 0.0,
        }
    }

    const START: &str = "G0 G43 H1 Z100\nX0 Y0 A0 C0\n";

    /// The forward map, spelled out the other way round: `R_x(a)·R_z(c)·(p + o)` of the
    /// centre it returns is the machine point it was given.
    #[test]
    fn forward_kinematics_inverts_the_table_rotation() {
        let m = machine();
        let o = Vector3::new(-15.0, -15.0, 0.0);
        for (a, c) in [(0.0f64, 0.0f64), (30.0, 0.0), (90.0, 90.0), (-45.0, 200.0)] {
            let u = Vector3::new(3.0, -4.0, 25.0);
            let p = m.pose(&[u.x, u.y, u.z, a, c], None).tip;
            let rz = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), c.to_radians());
            let rx = nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), a.to_radians());
            let back = rx * rz * (p.coords + o);
            assert!((back - u).norm() < 1e-12, "{a} {c}: {back}");
        }
        // A = 90°: the tool along machine Z is the part's −Y... turned by C = 90° to +X.
        let axis = m.pose(&[0.0, 0.0, 0.0, 90.0, 90.0], None).axis;
        assert!(
            (axis.into_inner() - Vector3::x()).norm() < 1e-12,
            "{axis:?}"
        );
    }

    /// The block's top face is z = 10 (a 30 × 30 × 10 cuboid from the origin, pivot at its
    /// footprint's centre). A straight G1 across it 2.0 mm above touches; one 1.99 mm above
    /// gouges by 0.01; the minimum is found at its line.
    #[test]
    fn a_straight_feed_move_over_a_face_is_measured_exactly() {
        let part = cuboid(30.0, 30.0, 10.0);
        for (z, expected) in [(10.0, 0.0), (9.99, -0.01)] {
            let program = format!(
                "{START}G0 X-5 Y0 Z{}\nG1 Z{z} F100\nG1 X5\nZ{}\nG0 Z100\n",
                z + 10.0,
                z + 10.0
            );
            let c = check_posted(&program, &machine(), &part, &options()).unwrap();
            assert!(c.problems.is_empty(), "{:?}", c.problems);
            assert!((c.min_feed_clearance_mm - expected).abs() < 1e-9, "{c:?}");
            assert!(c.min_rapid_clearance_mm >= 5.0 - 1e-9);
            // Flutes standing up from the ball, the face below it: the ball's contact is the
            // least of both, the surface below the equator left to the ball's measure.
            let with_flutes = PostedOptions {
                flutes_above_ball: 8.0,
                ..options()
            };
            let f = check_posted(&program, &machine(), &part, &with_flutes).unwrap();
            let flutes = f.flutes.unwrap();
            assert_eq!(
                (flutes.min_feed_clearance_mm, flutes.min_feed_line),
                (c.min_feed_clearance_mm, c.min_feed_line)
            );
        }
    }

    /// In a program with tool changes, `tool` measures only that tool's blocks: a roughing
    /// tool's plunge through the top face is not the ball's (the roughing check has it), and
    /// the ball's own 0.01 mm gouge after the change still is.
    #[test]
    fn only_the_named_tools_blocks_are_measured() {
        let part = cuboid(30.0, 30.0, 10.0);
        let program = format!(
            "T3 M6\n{START}G0 X-5 Y0 Z20\nG1 Z7 F100\nG1 X5\nG0 Z100\n\
             T1 M6\nG0 G43 H1 Z100\nG0 X-5 Y0 Z20\nG1 Z9.99 F100\nG1 X5\nG0 Z100\n"
        );
        // The roughing plunge crosses the top face: the ball centre's path meets the surface.
        let all = check_posted(&program, &machine(), &part, &options()).unwrap();
        assert_eq!(
            (all.min_feed_clearance_mm, all.min_feed_line),
            (-2.0, 5),
            "{all:?}"
        );
        let ball = PostedOptions {
            tool: Some(1),
            ..options()
        };
        let c = check_posted(&program, &machine(), &part, &ball).unwrap();
        assert!((c.min_feed_clearance_mm + 0.01).abs() < 1e-9, "{c:?}");
        assert!(c.min_feed_line > 8, "{c:?}");
    }

    /// Turning the table by C sweeps the ball on a circle about the C axis, and the check
    /// follows the circle, not the chord between its ends. The cuboid's side faces are 15 mm
    /// from the axis, its vertical edges 15√2 ≈ 21.21 mm. A ball (r = 2) centred 12 mm from the
    /// axis 1 mm above the top face gouges by 1 mm all the way round; one centred 24 mm from
    /// the axis at mid-height clears the edge by 24 − 15√2 − 2 ≈ 0.787 mm at 45°, where the
    /// chord of the quarter turn would pass through the part.
    #[test]
    fn rotary_moves_are_followed_along_the_arc_not_the_chord() {
        let part = cuboid(30.0, 30.0, 10.0);
        let program = format!("{START}G0 X12 Y0 Z9\nG1 C90 F100\n");
        let c = check_posted(&program, &machine(), &part, &options()).unwrap();
        assert!((c.min_feed_clearance_mm + 1.0).abs() < 2e-4, "{c:?}");
        let program = format!("{START}G0 X24 Y0 Z3\nG1 C90 F100\n");
        let c = check_posted(&program, &machine(), &part, &options()).unwrap();
        let expected = 24.0 - 15.0 * 2f64.sqrt() - 2.0;
        assert!(
            c.min_feed_clearance_mm <= expected && c.min_feed_clearance_mm > expected - 2e-4,
            "{} vs {expected}",
            c.min_feed_clearance_mm
        );
    }

    #[test]
    fn motion_before_length_compensation_and_a_start_inside_are_problems() {
        let part = cuboid(30.0, 30.0, 10.0);
        let c = check_posted(
            "G0 X0 Y0 A0 C0\nG43 H1 Z100\n",
            &machine(),
            &part,
            &options(),
        )
        .unwrap();
        assert_eq!(c.problems.len(), 1, "{:?}", c.problems);
        assert!(c.problems[0].contains("line 1"));
        let c = check_posted("G0 G43 H1 X0 Y0 Z20 A0 C0\n", &machine(), &part, &options()).unwrap();
        assert!(c.problems[0].contains("outside"), "{:?}", c.problems);
    }

    /// Measuring a block as one chord first, and in pieces only where that chord comes near
    /// enough to go below the least clearance found, gives the very minimum and line the
    /// piece-by-piece measurement does: a ball winding over a torus (concave inside, convex
    /// outside) with the table turning, dipping in and out of the surface, feed and rapid.
    #[test]
    fn pruned_blocks_give_the_piece_by_piece_minimum() {
        use nalgebra::Rotation3;
        let part = crate::mesh::fixtures::torus(12.0, 4.0, 64, 32);
        let o = Vector3::new(-15.0, -15.0, 0.0);
        let mut program = String::from(START);
        for k in 0..360 {
            let t = k as f64 * 2.5f64.to_radians();
            // Across the tube's top and down its inner and outer sides, 0.05 mm in and out.
            let phi = (90.0 + 70.0 * (3.0 * t).sin()).to_radians();
            let lift = 4.0 + 2.0 + 0.05 * (11.0 * t).sin() - 0.01;
            let radial = Vector3::new(t.cos(), t.sin(), 0.0);
            let centre = Point3::from(
                12.0 * radial + lift * (phi.cos() * radial + phi.sin() * Vector3::z()),
            );
            let (a, c) = (3f64.to_radians() * (2.0 * t).sin(), t * 0.5);
            let machine_centre = Rotation3::from_axis_angle(&Vector3::x_axis(), a)
                * Rotation3::from_axis_angle(&Vector3::z_axis(), c)
                * (centre.coords + o);
            let word = if k % 37 == 20 { "G0" } else { "G1" };
            program += &format!(
                "{word} X{:.4} Y{:.4} Z{:.4} A{:.4} C{:.4} F500\n",
                machine_centre.x,
                machine_centre.y,
                machine_centre.z - 2.0,
                a.to_degrees(),
                c.to_degrees(),
            );
        }
        let options = PostedOptions {
            search_mm: 3.0,
            ..options()
        };
        let pruned = check_posted_pruned(&program, &machine(), &part, &options, true).unwrap();
        let every = check_posted_pruned(&program, &machine(), &part, &options, false).unwrap();
        assert!(
            every.min_feed_clearance_mm < 0.0 && every.min_rapid_clearance_mm < 3.0,
            "{every:?}"
        );
        assert_eq!(
            PostedClearance {
                pieces: every.pieces,
                ..pruned.clone()
            },
            every
        );
        assert!(2 * pruned.pieces < every.pieces, "{pruned:?} {every:?}");
    }

    /// Flutes along the side of a block that floats 5 mm up (a cuboid from z = 5 to 15), the
    /// ball's centre 2 mm below its bottom: the flutes' clearance is the axis's distance from
    /// the face less the radius (and a 0.01 mm gouge when it is 1.99 mm), while the ball,
    /// diagonally off the bottom edge, is 1.05 mm clear.
    #[test]
    fn flutes_beside_a_wall_are_measured_in_closed_form() {
        let mut part = cuboid(30.0, 30.0, 10.0);
        for p in &mut part.positions {
            p.z += 5.0;
        }
        let options = PostedOptions {
            flutes_above_ball: 8.0,
            ..options()
        };
        for (gap, expected) in [(2.3, 0.3), (1.99, -0.01)] {
            // Machine X = part x − 15 at A = C = 0; the tip 2 mm below the ball's centre.
            let x = -gap - 15.0;
            let program = format!(
                "{START}G0 X{x} Y-20 Z{}
G1 Z1 F100
G1 Y0
G1 X{}
G0 Z100
",
                11.0,
                x - 10.0
            );
            let c = check_posted(&program, &machine(), &part, &options).unwrap();
            assert!(c.problems.is_empty(), "{:?}", c.problems);
            let flutes = c.flutes.clone().unwrap();
            assert!(
                (flutes.min_feed_clearance_mm - expected).abs() < 1e-9,
                "{flutes:?}"
            );
            assert_eq!(flutes.min_feed_line, 5, "{flutes:?}");
            let ball = (gap * gap + 4.0f64).sqrt() - 2.0;
            assert!((c.min_feed_clearance_mm - ball).abs() < 1e-9, "{c:?}");
        }
    }

    /// The table turns the flutes about a ball centre held 2.5 mm off a block's side face,
    /// toward the face and over its top edge: the certified flute clearance of every block is
    /// never above the least clearance of 201 × 201 points of its sheet (it is a lower bound),
    /// and within the sampling's resolution and twice the error bound of it. Measuring against
    /// the first pass's ceilings finds the same minimum at the same line.
    #[test]
    fn the_flute_sheet_bound_holds_against_dense_sampling() {
        use nalgebra::Rotation3;
        let part = cuboid(30.0, 30.0, 10.0);
        let tree = SegmentDistance::new(&part);
        let o = Vector3::new(-15.0, -15.0, 0.0);
        let (r, length) = (2.0, 8.0);
        let centre = Point3::new(-2.5, 15.0, 4.0);
        let mut program = String::from(START);
        let mut joints = Vec::new();
        for k in 0..=40 {
            let t = k as f64 / 40.0;
            let (a, c) = (35.0 * t, -25.0 + 50.0 * t + 8.0 * (9.0 * t).sin());
            let m = Rotation3::from_axis_angle(&Vector3::x_axis(), a.to_radians())
                * Rotation3::from_axis_angle(&Vector3::z_axis(), c.to_radians())
                * (centre.coords + o);
            let j = [m.x, m.y, m.z - r, a, c];
            let word = if k == 0 { "G0" } else { "G1" };
            program += &format!(
                "{word} X{} Y{} Z{} A{} C{} F500\n",
                j[0], j[1], j[2], j[3], j[4]
            );
            joints.push(j);
        }
        let options = PostedOptions {
            flutes_above_ball: length,
            ..options()
        };
        let pruned = check_posted_pruned(&program, &machine(), &part, &options, true).unwrap();
        let every = check_posted_pruned(&program, &machine(), &part, &options, false).unwrap();
        let (pruned, every) = (pruned.flutes.unwrap(), every.flutes.unwrap());
        assert_eq!(
            (pruned.min_feed_clearance_mm, pruned.min_feed_line),
            (every.min_feed_clearance_mm, every.min_feed_line)
        );
        let m = machine();
        let (samples_t, samples_s) = (200, 200);
        let mut sampled = f64::INFINITY;
        let mut resolution: f64 = 0.0;
        for pair in joints.windows(2) {
            let at = |t: f64, s: f64| {
                let j: [f64; 5] =
                    std::array::from_fn(|i| pair[0][i] + (pair[1][i] - pair[0][i]) * t);
                let pose = m.pose(&j, None);
                pose.tip + pose.axis.into_inner() * (r + s)
            };
            for i in 0..=samples_t {
                let t = i as f64 / samples_t as f64;
                let step_t = (at(t + 1.0 / samples_t as f64, length) - at(t, length)).norm();
                resolution = resolution.max(step_t.hypot(length / samples_s as f64) / 2.0);
                for k in 0..=samples_s {
                    let p = at(t, length * k as f64 / samples_s as f64);
                    sampled = sampled.min(tree.distance(&p, &p, f64::INFINITY) - r);
                }
            }
        }
        let certified = every.min_feed_clearance_mm;
        assert!(
            certified < 0.0,
            "the flutes were to cut into the face: {certified}"
        );
        assert!(
            certified <= sampled + 1e-12,
            "{certified} above the sampled {sampled}"
        );
        assert!(
            sampled - certified <= resolution + 2.0 * options.feed_error_mm,
            "{certified} vs sampled {sampled} (resolution {resolution})"
        );
    }

    /// The curvature bound of every chain kind holds against the second differences of the
    /// ball centre along random blocks: offset axis lines, long heads, big turns.
    #[test]
    fn the_chain_curvature_bound_holds_on_random_blocks() {
        let axis = |letter, on_table, d: [f64; 3], p: [f64; 3]| ModelAxis {
            letter,
            on_table,
            direction: Vector3::from(d).normalize(),
            point: Vector3::from(p),
        };
        let kinds = [
            // table-table B/C with offsets, head-table B/C, head-head C/A with a fork offset.
            [
                axis('B', true, [0.0, 1.0, 0.0], [0.8, 0.0, -60.0]),
                axis('C', true, [0.0, 0.0, 1.0], [0.0, 0.0, 0.0]),
            ],
            [
                axis('B', false, [0.0, 1.0, 0.0], [0.0, 0.0, 0.0]),
                axis('C', true, [0.0, 0.0, 1.0], [5.0, -3.0, 0.0]),
            ],
            [
                axis('C', false, [0.0, 0.0, 1.0], [0.0, 0.0, 0.0]),
                axis('A', false, [1.0, 0.0, 0.0], [0.0, 12.0, -40.0]),
            ],
        ];
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut random = |lo: f64, hi: f64| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            lo + (hi - lo) * (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let r = 3.0;
        for axes in kinds {
            let head = axes.iter().any(|a| !a.on_table);
            let m = MachineModel::Chain(ChainModel {
                axes,
                part_origin_in_table: Vector3::new(-10.0, 20.0, 5.0),
                head_lengths: if head { vec![(1, 280.0)] } else { Vec::new() },
                tcp: false,
                tcp_in_program: false,
                conversational: false,
            });
            for _ in 0..200 {
                let mut joints = || {
                    [
                        random(-300.0, 300.0),
                        random(-300.0, 300.0),
                        random(-200.0, 400.0),
                        random(-120.0, 120.0),
                        random(-360.0, 360.0),
                    ]
                };
                let (j0, j1) = (joints(), joints());
                let bound = m.curvature_bound(&j0, &j1, r, Some(1));
                let at = |t: f64| {
                    let mut j = [0.0; 5];
                    for k in 0..5 {
                        j[k] = j0[k] + (j1[k] - j0[k]) * t;
                    }
                    m.ball_centre(&j, r, Some(1))
                };
                let h = 1e-3;
                for k in 1..1000 {
                    let t = k as f64 * h;
                    let second =
                        (at(t + h) - 2.0 * at(t).coords + at(t - h).coords).coords / (h * h);
                    assert!(
                        second.norm() <= bound * (1.0 + 1e-3) + 1e-3,
                        "{:?}: |c''| = {} above the bound {bound}",
                        axes.map(|a| a.letter),
                        second.norm()
                    );
                }
            }
        }
    }
}
