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
//! The path is one continuous curve from the program's first fully known position, which is
//! checked to lie outside the part's bounding sphere about the pivot. A path that never comes
//! within 0 of the surface therefore never enters the part, and the unsigned distance is the
//! clearance.

use rayon::prelude::*;
use serde::Serialize;

use super::program::{MotionBlock, ProgramError, read_program};
use super::segment_distance::SegmentDistance;
use crate::geom::{Point3, Vector3};
use crate::mesh::Mesh;

/// The machine as the verifier models it: plain data, independent of the post's code.
#[derive(Clone, Copy, Debug, PartialEq)]
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
}

impl MachineModel {
    fn axis_letters(&self) -> [char; 5] {
        match self {
            MachineModel::TableTableAc { .. } | MachineModel::ThreeAxis => {
                ['X', 'Y', 'Z', 'A', 'C']
            }
        }
    }

    /// The pivot (where the rotary axes meet) in the part frame.
    pub fn pivot(&self) -> Point3 {
        match self {
            MachineModel::TableTableAc {
                part_origin_in_table,
            } => Point3::from(-part_origin_in_table),
            MachineModel::ThreeAxis => Point3::origin(),
        }
    }

    /// The ball centre in the part frame for machine-frame centre `u` (relative to the pivot)
    /// and rotary angles `a`, `c` in radians.
    fn centre_in_part(&self, u: &Vector3, a: f64, c: f64) -> Point3 {
        match self {
            MachineModel::TableTableAc {
                part_origin_in_table,
            } => Point3::from(self.rotate_into_part(u, a, c) - part_origin_in_table),
            MachineModel::ThreeAxis => Point3::from(*u),
        }
    }

    /// A machine-frame direction in the part frame at rotary angles `a`, `c` (radians).
    fn rotate_into_part(&self, u: &Vector3, a: f64, c: f64) -> Vector3 {
        match self {
            MachineModel::TableTableAc { .. } => {
                // R_x(a)ᵀ, then R_z(c)ᵀ: undo the cradle, then the table.
                let (sa, ca) = a.sin_cos();
                let w = Vector3::new(u.x, ca * u.y + sa * u.z, -sa * u.y + ca * u.z);
                let (sc, cc) = c.sin_cos();
                Vector3::new(cc * w.x + sc * w.y, -sc * w.x + cc * w.y, w.z)
            }
            MachineModel::ThreeAxis => *u,
        }
    }

    /// The tool's pose in the part frame at joints `[x, y, z, a°, c°]` (the tip at machine
    /// X, Y, Z with length compensation on, the tool along machine +Z).
    fn pose(&self, joints: &[f64; 5]) -> crate::geom::ToolPose {
        let (a, c) = (joints[3].to_radians(), joints[4].to_radians());
        let tip = self.centre_in_part(&Vector3::new(joints[0], joints[1], joints[2]), a, c);
        let axis = self.rotate_into_part(&Vector3::z(), a, c);
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
    let blocks = read_program(program, machine.axis_letters())?;
    let joints = |b: &MotionBlock| -> Option<[f64; 5]> {
        let [x, y, z, a, c] = b.axes;
        match machine {
            // No rotary words on a 3-axis machine: its rotaries stand at zero.
            MachineModel::ThreeAxis => Some([x?, y?, z?, 0.0, 0.0]),
            MachineModel::TableTableAc { .. } => Some([x?, y?, z?, a?, c?]),
        }
    };
    let mut moves = Vec::new();
    let mut lines = Vec::new();
    let mut previous: Option<[f64; 5]> = None;
    for block in &blocks {
        let Some(j1) = joints(block) else {
            continue;
        };
        let kind = if block.rapid {
            MoveKind::Rapid
        } else {
            MoveKind::Cut
        };
        let Some(j0) = previous else {
            moves.push(Move {
                pose: machine.pose(&j1),
                kind: MoveKind::Rapid,
                feed: 0.0,
            });
            lines.push(block.line);
            previous = Some(j1);
            continue;
        };
        let u0 = Vector3::new(j0[0], j0[1], j0[2]);
        let u1 = Vector3::new(j1[0], j1[1], j1[2]);
        let omega = (j1[3] - j0[3]).to_radians().abs() + (j1[4] - j0[4]).to_radians().abs();
        let curvature = omega * omega * u0.norm().max(u1.norm()) + 2.0 * omega * (u1 - u0).norm();
        let n =
            ((curvature / (8.0 * max_error.max(1e-9))).sqrt().ceil() as usize).clamp(1, MAX_PIECES);
        for k in 1..=n {
            let t = k as f64 / n as f64;
            let j: [f64; 5] = std::array::from_fn(|i| j0[i] + (j1[i] - j0[i]) * t);
            moves.push(Move {
                pose: machine.pose(&j),
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
}

/// What the back-simulation found.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PostedClearance {
    pub motion_blocks: usize,
    /// Straight pieces measured (blocks are cut so each stays within its error bound).
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
    /// What is wrong with the program's structure (motion before tool length compensation, a
    /// start that cannot be shown to be outside the part).
    pub problems: Vec<String>,
}

/// Most pieces one block may be cut into; a block that needs more is measured with the error
/// this leaves, which is reported.
const MAX_PIECES: usize = 100_000;

/// Reads `program` and measures the ball centre along every motion block against `part`.
pub fn check_posted(
    program: &str,
    machine: &MachineModel,
    part: &Mesh,
    options: &PostedOptions,
) -> Result<PostedClearance, ProgramError> {
    let blocks = read_program(program, machine.axis_letters())?;
    let tree = SegmentDistance::new(part);
    let r = options.ball_radius;
    let mut problems = Vec::new();
    if let Some(b) = blocks.iter().find(|b| !b.length_compensation) {
        problems.push(format!(
            "line {}: moves before tool length compensation (G43) is on",
            b.line
        ));
    }
    let joints = |b: &MotionBlock| -> Option<[f64; 5]> {
        let [x, y, z, a, c] = b.axes;
        Some([x?, y?, z?, a?, c?])
    };
    let first = blocks.iter().position(|b| joints(b).is_some());
    let pivot = machine.pivot();
    let reach = part
        .positions
        .iter()
        .map(|p| (p - pivot).norm())
        .fold(0.0, f64::max);
    if let Some(i) = first {
        let [x, y, z, a, c] = joints(&blocks[i]).unwrap_or_default();
        let start =
            machine.centre_in_part(&Vector3::new(x, y, z + r), a.to_radians(), c.to_radians());
        if (start - pivot).norm() <= reach + r {
            problems.push(format!(
                "line {}: the first position is within the part's reach from the pivot; it \
                 cannot be shown to be outside the part",
                blocks[i].line
            ));
        }
    }
    let pairs: Vec<(usize, [f64; 5], [f64; 5])> = match first {
        None => Vec::new(),
        Some(f) => (f + 1..blocks.len())
            .filter(|&i| options.tool.is_none_or(|t| blocks[i].tool == Some(t)))
            .filter_map(|i| Some((i, joints(&blocks[i - 1])?, joints(&blocks[i])?)))
            .collect(),
    };
    let limit = r + options.search_mm;
    // Fixed chunks, each a sequential minimum: the same answer for any number of threads.
    let per_chunk: Vec<Minima> = pairs
        .par_chunks(256)
        .map(|chunk| {
            let mut m = Minima::new(options.search_mm);
            for &(i, j0, j1) in chunk {
                let block = &blocks[i];
                let error = if block.rapid {
                    options.rapid_error_mm
                } else {
                    options.feed_error_mm
                };
                let (clearance, pieces) =
                    block_clearance(machine, &tree, &j0, &j1, r, error, limit);
                m.pieces += pieces;
                m.note(block.rapid, clearance, block.line);
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
        problems,
    })
}

/// Running minima (clearance, line) for feed and rapid blocks.
struct Minima {
    feed: (f64, usize),
    rapid: (f64, usize),
    pieces: usize,
}

impl Minima {
    fn new(search: f64) -> Self {
        Minima {
            feed: (search, 0),
            rapid: (search, 0),
            pieces: 0,
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

/// The certified least clearance of the ball along the joint interpolation `j0 → j1`, and how
/// many pieces were measured (see the module docs).
fn block_clearance(
    machine: &MachineModel,
    tree: &SegmentDistance,
    j0: &[f64; 5],
    j1: &[f64; 5],
    r: f64,
    error: f64,
    limit: f64,
) -> (f64, usize) {
    let u0 = Vector3::new(j0[0], j0[1], j0[2] + r);
    let u1 = Vector3::new(j1[0], j1[1], j1[2] + r);
    let (a0, c0) = (j0[3].to_radians(), j0[4].to_radians());
    let (a1, c1) = (j1[3].to_radians(), j1[4].to_radians());
    let omega = (a1 - a0).abs() + (c1 - c0).abs();
    let curvature = omega * omega * u0.norm().max(u1.norm()) + 2.0 * omega * (u1 - u0).norm();
    let n = ((curvature / (8.0 * error)).sqrt().ceil() as usize).clamp(1, MAX_PIECES);
    let piece_error = curvature / (8.0 * (n * n) as f64);
    let at = |k: usize| {
        let t = k as f64 / n as f64;
        machine.centre_in_part(&u0.lerp(&u1, t), a0 + (a1 - a0) * t, c0 + (c1 - c0) * t)
    };
    let mut least = limit;
    let mut previous = at(0);
    for k in 1..=n {
        let next = at(k);
        least = least.min(tree.distance(&previous, &next, least + piece_error) - piece_error);
        previous = next;
    }
    ((least - r).min(limit - r), n)
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
            tool: None,
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
            let p = m.centre_in_part(&u, a.to_radians(), c.to_radians());
            let rz = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), c.to_radians());
            let rx = nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), a.to_radians());
            let back = rx * rz * (p.coords + o);
            assert!((back - u).norm() < 1e-12, "{a} {c}: {back}");
        }
        // A = 90°: the tool along machine Z is the part's −Y... turned by C = 90° to +X.
        let axis = m.centre_in_part(&Vector3::z(), 90f64.to_radians(), 90f64.to_radians())
            - m.centre_in_part(&Vector3::zeros(), 90f64.to_radians(), 90f64.to_radians());
        assert!((axis - Vector3::x()).norm() < 1e-12, "{axis}");
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
}
