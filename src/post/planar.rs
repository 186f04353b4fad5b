//! Planar programs for 3-axis machines: straight and circular (G17 XY-arc) blocks on the grid of
//! the numbers the writer prints.
//!
//! Every coordinate is snapped once, as an integer, to the grid `10^−linear_decimals` mm of
//! the [`GcodeOptions`] the program is written with, so each block starts exactly where the
//! previous one ended and the program the control reads is the program measured here. For each
//! arc the centre (and, where the next block does not depend on it, the end point) is chosen
//! among the nearest grid points so that the start and end radii agree to well below one grid
//! unit: controllers reject arcs whose radii differ (LinuxCNC by more than 0.002 mm in G21).
//! Arcs are posted as planned; an arc over a half turn should be given as two halves so that
//! no block's end can round onto its start (which a control reads as a full circle).
//!
//! The blocks go out through any [`ProgramSink`] with the [`ThreeAxis`] kinematics (machine
//! X, Y, Z = the tool tip in the part frame), and are timed by the one model of
//! [`super::estimate`].

use super::estimate::{TimeEstimate, TimeModel, block_length, block_seconds};
use super::kinematics::{Joints, ThreeAxis};
use super::{ArcXY, GcodeOptions, GcodeWriter, ProgramHeader, ProgramSink};
use crate::geom::{Move, MoveKind, Point2, Point3, ToolPose};

/// Largest |coordinate| a planar program accepts, mm: keeps the integer grid exact.
pub const MAX_COORDINATE_MM: f64 = 1e9;

/// Why a planar block cannot be posted.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PlanarError {
    /// A coordinate is not finite or beyond [`MAX_COORDINATE_MM`].
    #[error("{axis} coordinate {value} cannot be posted (not finite, or beyond ±1e9 mm)")]
    Unpostable {
        /// The axis (`X`, `Y` or `Z`).
        axis: char,
        /// The value given.
        value: f64,
    },
    /// A block that leaves an axis where it is, before any block said where the tool is.
    #[error("the first block of a planar program must give X, Y and Z")]
    NoStart,
    /// The writer's decimals give no usable grid.
    #[error("linear_decimals = {0}: a planar program needs 0 to 6 decimals")]
    Decimals(usize),
}

/// An arc of a planar block on the grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GridArc {
    /// Centre, grid units.
    pub center: [i64; 2],
    /// Counter-clockwise seen from +Z.
    pub ccw: bool,
}

/// One block of a planar program.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanarBlock {
    /// Rapid blocks are posted as G0, the others at `feed`.
    pub kind: MoveKind,
    /// mm/min (the rapid rate for rapids: time estimate only).
    pub feed: f64,
    /// Where the block ends, grid units.
    pub end: [i64; 3],
    /// `Some` for a circular block in XY (Z constant or helical).
    pub arc: Option<GridArc>,
}

/// A planar program under construction and, once built, posted and timed.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanarProgram {
    quantum: f64,
    blocks: Vec<PlanarBlock>,
}

/// Radius mismatch |‖e − c‖ − ‖s − c‖| in grid units.
fn radius_mismatch(s: [i64; 2], e: [i64; 2], c: [i64; 2]) -> f64 {
    let rs = ((s[0] - c[0]) as f64).hypot((s[1] - c[1]) as f64);
    let re = ((e[0] - c[0]) as f64).hypot((e[1] - c[1]) as f64);
    (re - rs).abs()
}

impl PlanarProgram {
    /// An empty program on the grid of `opts`. Where the tool is before the first block is
    /// unknown, so the first block must give X, Y and Z (a rapid to the safe height above the
    /// first cut); it has no length.
    pub fn new(opts: &GcodeOptions) -> Result<Self, PlanarError> {
        if opts.linear_decimals > 6 {
            return Err(PlanarError::Decimals(opts.linear_decimals));
        }
        Ok(PlanarProgram {
            quantum: 10f64.powi(-(opts.linear_decimals as i32)),
            blocks: Vec::new(),
        })
    }

    /// The grid step, mm.
    pub fn quantum(&self) -> f64 {
        self.quantum
    }

    /// `v` (mm) on the grid.
    pub fn snap(&self, v: f64, axis: char) -> Result<i64, PlanarError> {
        if !(v.is_finite() && v.abs() < MAX_COORDINATE_MM) {
            return Err(PlanarError::Unpostable { axis, value: v });
        }
        Ok((v / self.quantum).round() as i64)
    }

    /// An XY point on the grid.
    pub fn snap_xy(&self, p: Point2) -> Result<[i64; 2], PlanarError> {
        Ok([self.snap(p.x, 'X')?, self.snap(p.y, 'Y')?])
    }

    /// A grid value in mm.
    pub fn mm(&self, v: i64) -> f64 {
        v as f64 * self.quantum
    }

    /// Where the tool is after the last block (grid units); `None` before the first.
    pub fn position(&self) -> Option<[i64; 3]> {
        self.blocks.last().map(|b| b.end)
    }

    /// The blocks so far.
    pub fn blocks(&self) -> &[PlanarBlock] {
        &self.blocks
    }

    /// The joints of a grid point on the 3-axis machine.
    pub fn joints(&self, p: [i64; 3]) -> Joints {
        Joints {
            x: self.mm(p[0]),
            y: self.mm(p[1]),
            z: self.mm(p[2]),
            a: 0.0,
            c: 0.0,
        }
    }

    fn push(&mut self, kind: MoveKind, feed: f64, end: [i64; 3], arc: Option<GridArc>) {
        self.blocks.push(PlanarBlock {
            kind,
            feed,
            end,
            arc,
        });
    }

    /// A straight block to `to` (`None` axes stay where they are). Adds nothing when the move
    /// is shorter than the grid; returns whether a block was added.
    pub fn straight(
        &mut self,
        kind: MoveKind,
        feed: f64,
        to: [Option<f64>; 3],
    ) -> Result<bool, PlanarError> {
        let position = self.position();
        let mut end = [0; 3];
        for (i, axis) in ['X', 'Y', 'Z'].into_iter().enumerate() {
            end[i] = match (to[i], position) {
                (Some(v), _) => self.snap(v, axis)?,
                (None, Some(p)) => p[i],
                (None, None) => return Err(PlanarError::NoStart),
            };
        }
        self.straight_to_grid(kind, feed, end)
    }

    /// [`Self::straight`] to a point already on the grid.
    pub fn straight_to_grid(
        &mut self,
        kind: MoveKind,
        feed: f64,
        end: [i64; 3],
    ) -> Result<bool, PlanarError> {
        if self.position() == Some(end) {
            return Ok(false);
        }
        self.push(kind, feed, end, None);
        Ok(true)
    }

    /// An arc in XY at the current Z from the current position about `center`, sweeping
    /// `sweep` radians (positive counter-clockwise) with `radius`, ending at `end`, or exactly at
    /// `pinned_end` (grid) when the next block depends on it (a closed pass returning to its
    /// start). An arc that is straight to within the grid (sagitta below one unit), or shorter
    /// than it, is posted as a straight block. Returns whether a block was added.
    #[allow(clippy::too_many_arguments)]
    pub fn arc(
        &mut self,
        kind: MoveKind,
        feed: f64,
        center: Point2,
        radius: f64,
        sweep: f64,
        end: Point2,
        pinned_end: Option<[i64; 2]>,
    ) -> Result<bool, PlanarError> {
        let e0 = match pinned_end {
            Some(e) => e,
            None => self.snap_xy(end)?,
        };
        let [sx, sy, z] = self.position().ok_or(PlanarError::NoStart)?;
        let s = [sx, sy];
        let sagitta = radius * (1.0 - (0.5 * sweep).cos());
        if e0 == s || sagitta < self.quantum {
            return self.straight_to_grid(kind, feed, [e0[0], e0[1], z]);
        }
        let c0 = self.snap_xy(center)?;
        let ends: Vec<[i64; 2]> = match pinned_end {
            Some(e) => vec![e],
            None => (-1..=1)
                .flat_map(|dx| (-1..=1).map(move |dy| [e0[0] + dx, e0[1] + dy]))
                .collect(),
        };
        // (radius mismatch, squared displacement from the exact grid points, end, centre)
        type Choice = (f64, i64, [i64; 2], [i64; 2]);
        let mut best: Option<Choice> = None;
        for &e in &ends {
            if e == s {
                continue;
            }
            for dx in -2..=2i64 {
                for dy in -2..=2i64 {
                    let c = [c0[0] + dx, c0[1] + dy];
                    let m = radius_mismatch(s, e, c);
                    let moved = (e[0] - e0[0]).pow(2) + (e[1] - e0[1]).pow(2) + dx * dx + dy * dy;
                    if best
                        .is_none_or(|b| m < b.0 - 1e-9 || ((m - b.0).abs() <= 1e-9 && moved < b.1))
                    {
                        best = Some((m, moved, e, c));
                    }
                }
            }
        }
        let Some((_, _, e, c)) = best else {
            return self.straight_to_grid(kind, feed, [e0[0], e0[1], z]);
        };
        self.push(
            kind,
            feed,
            [e[0], e[1], z],
            Some(GridArc {
                center: c,
                ccw: sweep > 0.0,
            }),
        );
        Ok(true)
    }

    /// The blocks as the post sees them: move (part frame, tool along +Z), joints, arc.
    fn posted(&self) -> Vec<(Move, Joints, Option<ArcXY>)> {
        let axis = nalgebra::Unit::new_unchecked(nalgebra::Vector3::z());
        self.blocks
            .iter()
            .map(|b| {
                let j = self.joints(b.end);
                let m = Move {
                    pose: ToolPose {
                        tip: Point3::new(j.x, j.y, j.z),
                        axis,
                    },
                    kind: b.kind,
                    feed: b.feed,
                };
                let arc = b.arc.map(|a| ArcXY {
                    center: [self.mm(a.center[0]), self.mm(a.center[1])],
                    ccw: a.ccw,
                });
                (m, j, arc)
            })
            .collect()
    }

    /// Feeds the program through `sink`.
    pub fn emit<S: ProgramSink + ?Sized>(&self, header: &ProgramHeader, sink: &mut S) {
        sink.begin(header);
        for (m, j, arc) in self.posted() {
            match arc {
                Some(arc) => sink.arc(&m, &j, &arc),
                None => sink.motion(&m, &j),
            }
        }
        sink.end();
    }

    /// The program as G-code for a 3-axis machine. `opts` must be the options the program was
    /// built with (its grid is their linear decimals).
    pub fn to_gcode(&self, header: &ProgramHeader, opts: &GcodeOptions) -> String {
        let mut writer = GcodeWriter::new(&ThreeAxis, opts.clone());
        self.emit(header, &mut writer);
        writer.into_string()
    }

    /// Length of block `i` (mm) from the previous block's end; 0 for the first, whose start
    /// is unknown.
    pub fn block_length(&self, i: usize) -> f64 {
        let Some(from) = i.checked_sub(1).map(|k| self.blocks[k].end) else {
            return 0.0;
        };
        let b = &self.blocks[i];
        let arc = b.arc.map(|a| ArcXY {
            center: [self.mm(a.center[0]), self.mm(a.center[1])],
            ccw: a.ccw,
        });
        block_length(&self.joints(from), &self.joints(b.end), arc.as_ref())
    }

    /// Lines of motion the control processes: one per block, and one more for the first,
    /// which the writer posts as Z alone (with length compensation) and then X and Y.
    pub fn motion_lines(&self) -> usize {
        self.blocks.len() + usize::from(!self.blocks.is_empty())
    }

    /// Seconds of motion of each block under the one model of [`super::estimate`] (no dwell),
    /// from the previous block's end (0 for the first, whose start is unknown); `None` where a
    /// feed is not finite and positive.
    pub fn block_seconds(&self, max_rotary_deg_per_min: f64) -> Vec<Option<f64>> {
        let mut from: Option<Joints> = None;
        self.posted()
            .iter()
            .map(|(m, j, arc)| {
                let s = match from {
                    None => Some(0.0),
                    Some(f) => block_seconds(&f, m, j, arc.as_ref(), max_rotary_deg_per_min),
                };
                from = Some(*j);
                s
            })
            .collect()
    }

    /// Machining time under the one model of [`super::estimate`]; every motion line ([`Self::motion_lines`]) pays the model's dwell.
    pub fn estimate(&self, model: &TimeModel) -> TimeEstimate {
        let mut est = TimeEstimate {
            dwell_s: self.motion_lines() as f64 * model.dwell_per_block_s,
            ..TimeEstimate::default()
        };
        let seconds = self.block_seconds(model.max_rotary_deg_per_min);
        for (b, s) in self.blocks.iter().zip(seconds) {
            match s {
                Some(s) => est.add(b.kind, s),
                None => est.invalid_feed_blocks += 1,
            }
        }
        est
    }
}
