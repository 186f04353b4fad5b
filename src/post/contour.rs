//! 2.5D contour programs: a tool-centre [`CenterPath`] at one cutting depth posted as a
//! [`PlanarProgram`] (G17 lines and G2/G3 arcs on the output grid) for a 3-axis machine, with
//! the machining-time model of seed 004.
//!
//! Each pass is entered by a rapid retract, a rapid traverse and a plunge at the plunge feed
//! (the first pass and every [`Link::Rapid`]); feed links ([`Link::Feed`]) stay at depth at the
//! feed; traverses at depth through air beside the stock ([`Link::Traverse`]) are G1 at the
//! rapid rate. Arcs over a half turn are posted as two halves, and the last block of a closed
//! pass ends exactly on its start.
//!
//! # Time model (seed 004 §1.2, §3.7, §4.1)
//!
//! Seed 004 attributes machining time to path length at the feed rate plus "dwell between
//! consecutive NC control commands" (Vickers and Bradley 1992, cited in §1.2; §4.1: fewer legs ⇒
//! "less dwell time in practical machining"). The post's one model ([`super::estimate`]: block
//! length / feed) with a dwell per motion line gives
//!
//! `time = (cut + feed-link length) / feed + plunge length / plunge_feed
//!        + (rapid + traverse-at-depth length) / rapid + lines × dwell_per_block`.
//!
//! Defaults: `feed` = 762 mm/min — the 30 ipm XY feed of seed 004 Table 3.1's caption (tool
//! radius 0.25 in, 3500 rpm, 4 Z steps); spindle 3500 rpm from the same caption. The seed gives
//! NO value for the dwell per block, the rapid rate or the plunge feed (its times come from the
//! ProCAM TekSoft-2D simulator; Table 3.1's contour-parallel 752.37 in at 30 ipm is 25.1 min of
//! pure feed against 65.03 min reported, so the overheads it models are large but not
//! separable). Chosen defaults, documented as such: dwell 0.05 s per block (a typical
//! block-processing delay of controllers of that era), rapid 5000 mm/min, plunge feed = XY feed.

use std::f64::consts::PI;

use super::planar::{PlanarError, PlanarProgram};
use super::{GcodeOptions, ProgramHeader};
use crate::contour::geometry::Segment;
use crate::contour::segops::{seg_end, split_arc};
use crate::contour::toolpath::{CenterPath, Link};
use crate::geom::{MoveKind, Point2};

/// Depths, feeds and spindle of a 2.5D program (see the module docs for the sources of the
/// defaults).
#[derive(Clone, Debug, PartialEq)]
pub struct PlanarParams {
    /// XY cutting feed, mm/min. Default 762 (30 ipm, seed 004 Table 3.1).
    pub feed: f64,
    /// Plunge feed, mm/min. Default 762 (seed gives none).
    pub plunge_feed: f64,
    /// Rapid traverse rate, mm/min, for the time estimate. Default 5000 (seed gives none).
    pub rapid: f64,
    /// Dwell per NC motion block, seconds. Default 0.05 (seed gives none).
    pub dwell_per_block: f64,
    /// Cutting depth (tool tip Z), mm. Default −1.
    pub cut_z: f64,
    /// Retract height for rapid moves, mm. Default 5.
    pub safe_z: f64,
    /// Spindle speed, rpm (M3 S…), or `None` to leave the spindle alone. Default 3500 (seed 004
    /// Table 3.1).
    pub spindle_rpm: Option<f64>,
}

impl Default for PlanarParams {
    fn default() -> Self {
        Self {
            feed: 762.0,
            plunge_feed: 762.0,
            rapid: 5000.0,
            dwell_per_block: 0.05,
            cut_z: -1.0,
            safe_z: 5.0,
            spindle_rpm: Some(3500.0),
        }
    }
}

/// Why a 2.5D program cannot be posted.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ContourPostError {
    /// A parameter is out of range.
    #[error("{name} = {value}: {reason}")]
    InvalidParameter {
        /// The parameter (field of [`PlanarParams`]).
        name: &'static str,
        /// The value given.
        value: f64,
        /// What it must be.
        reason: &'static str,
    },
    /// A coordinate cannot be posted.
    #[error(transparent)]
    Planar(#[from] PlanarError),
}

impl PlanarParams {
    /// Checks the parameters (positive rates, finite depths with `safe_z > cut_z`, …).
    pub fn validate(&self) -> Result<(), ContourPostError> {
        let invalid = |name, value, reason| {
            Err(ContourPostError::InvalidParameter {
                name,
                value,
                reason,
            })
        };
        for (name, value) in [
            ("feed", self.feed),
            ("plunge_feed", self.plunge_feed),
            ("rapid", self.rapid),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return invalid(name, value, "must be a positive finite rate in mm/min");
            }
        }
        if !(self.dwell_per_block.is_finite() && self.dwell_per_block >= 0.0) {
            return invalid(
                "dwell_per_block",
                self.dwell_per_block,
                "must be a finite number of seconds ≥ 0",
            );
        }
        for (name, value) in [("cut_z", self.cut_z), ("safe_z", self.safe_z)] {
            if !value.is_finite() {
                return invalid(name, value, "must be finite");
            }
        }
        if self.safe_z <= self.cut_z {
            return invalid("safe_z", self.safe_z, "must be above cut_z");
        }
        if let Some(s) = self.spindle_rpm
            && !(s.is_finite() && s > 0.0 && s < u32::MAX as f64)
        {
            return invalid("spindle_rpm", s, "must be a positive finite speed");
        }
        Ok(())
    }
}

/// What a block of a 2.5D program does, for the statistics.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlockRole {
    /// Part of a pass, at cutting depth.
    Cut,
    /// A feed link at cutting depth.
    Link,
    /// A traverse at cutting depth through air beside the stock, at the rapid rate (G1).
    StayDown,
    /// Down to cutting depth at the plunge feed.
    Plunge,
    /// Up to the safe height (rapid).
    Retract,
    /// XY traverse at the safe height (rapid).
    Traverse,
}

impl BlockRole {
    /// The move kind the post gives the block (G0 for rapids, else a feed move).
    fn kind(self) -> MoveKind {
        match self {
            BlockRole::Cut | BlockRole::Link | BlockRole::StayDown => MoveKind::Cut,
            BlockRole::Plunge => MoveKind::Approach,
            BlockRole::Retract | BlockRole::Traverse => MoveKind::Rapid,
        }
    }
}

/// The posted program of a path at one depth, with the role of each block.
#[derive(Clone, Debug, PartialEq)]
pub struct ContourProgram {
    params: PlanarParams,
    gcode: GcodeOptions,
    tool_radius: f64,
    program: PlanarProgram,
    roles: Vec<BlockRole>,
}

/// Statistics of a [`ContourProgram`] under the time model of the module docs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ProgramStats {
    /// Motion lines (each pays `dwell_per_block`).
    pub blocks: usize,
    /// XY length of pass moves, mm.
    pub cut_length: f64,
    /// XY length of feed links, mm.
    pub feed_link_length: f64,
    /// XY length of traverses at cutting depth (at the rapid rate), mm.
    pub stay_down_length: f64,
    /// Z length of plunges, mm.
    pub plunge_length: f64,
    /// Length of rapid moves (retracts and traverses), mm.
    pub rapid_length: f64,
    /// Minutes at feed (cut + feed links + plunges).
    pub feed_minutes: f64,
    /// Minutes at rapid (rapids and traverses at depth).
    pub rapid_minutes: f64,
    /// Minutes of block dwell.
    pub dwell_minutes: f64,
    /// Total estimated machining time, minutes.
    pub total_minutes: f64,
}

/// Builds the blocks of a path, tagging each with its role.
struct Builder<'p> {
    params: &'p PlanarParams,
    program: PlanarProgram,
    roles: Vec<BlockRole>,
}

impl Builder<'_> {
    fn straight(
        &mut self,
        role: BlockRole,
        feed: f64,
        to: [Option<f64>; 3],
    ) -> Result<(), PlanarError> {
        if self.program.straight(role.kind(), feed, to)? {
            self.roles.push(role);
        }
        Ok(())
    }

    fn retract_traverse_plunge(&mut self, to: Point2) -> Result<(), PlanarError> {
        let p = self.params;
        self.straight(BlockRole::Retract, p.rapid, [None, None, Some(p.safe_z)])?;
        self.straight(BlockRole::Traverse, p.rapid, [Some(to.x), Some(to.y), None])?;
        self.straight(
            BlockRole::Plunge,
            p.plunge_feed,
            [None, None, Some(p.cut_z)],
        )
    }

    fn line_to(&mut self, role: BlockRole, to: Point2) -> Result<(), PlanarError> {
        let feed = if role == BlockRole::StayDown {
            self.params.rapid
        } else {
            self.params.feed
        };
        self.straight(role, feed, [Some(to.x), Some(to.y), None])
    }

    /// One pass segment; `pinned_end` fixes the grid end point.
    fn segment(&mut self, seg: &Segment, pinned_end: Option<[i64; 2]>) -> Result<(), PlanarError> {
        let feed = self.params.feed;
        let added = match *seg {
            Segment::Arc {
                center,
                radius,
                sweep,
                ..
            } => self.program.arc(
                MoveKind::Cut,
                feed,
                center,
                radius,
                sweep,
                seg_end(seg),
                pinned_end,
            )?,
            Segment::Line { .. } => {
                let z = self.program.position().ok_or(PlanarError::NoStart)?[2];
                let end = match pinned_end {
                    Some(e) => e,
                    None => self.program.snap_xy(seg_end(seg))?,
                };
                self.program
                    .straight_to_grid(MoveKind::Cut, feed, [end[0], end[1], z])?
            }
        };
        if added {
            self.roles.push(BlockRole::Cut);
        }
        Ok(())
    }
}

impl ContourProgram {
    /// Posts `path` at the depth and feeds of `params` on the grid of `gcode`.
    pub fn new(
        path: &CenterPath,
        params: &PlanarParams,
        gcode: &GcodeOptions,
    ) -> Result<Self, ContourPostError> {
        params.validate()?;
        let mut b = Builder {
            params,
            program: PlanarProgram::new(gcode)?,
            roles: Vec::new(),
        };
        for (k, pass) in path.passes().iter().enumerate() {
            let start = pass.start();
            if k == 0 {
                // From wherever the tool is, to the safe height above the first pass, then down.
                let above = [Some(start.x), Some(start.y), Some(params.safe_z)];
                b.straight(BlockRole::Traverse, params.rapid, above)?;
                b.straight(
                    BlockRole::Plunge,
                    params.plunge_feed,
                    [None, None, Some(params.cut_z)],
                )?;
            } else {
                match path.links()[k - 1] {
                    Link::Feed { .. } => b.line_to(BlockRole::Link, start)?,
                    Link::Traverse { .. } => b.line_to(BlockRole::StayDown, start)?,
                    Link::Rapid { .. } => b.retract_traverse_plunge(start)?,
                }
            }
            let start_on_grid = b.program.snap_xy(start)?;
            let segs: Vec<Segment> = pass.segments().collect();
            let last = segs.len().saturating_sub(1);
            for (i, seg) in segs.iter().enumerate() {
                // Arcs over a half turn go as two halves, so no block's end can round onto
                // its start (which a control would read as a full circle).
                let pieces = if matches!(seg, Segment::Arc { sweep, .. } if sweep.abs() > PI) {
                    split_arc(seg, PI)
                } else {
                    vec![*seg]
                };
                let np = pieces.len();
                for (j, piece) in pieces.iter().enumerate() {
                    let pinned =
                        (pass.is_closed() && i == last && j + 1 == np).then_some(start_on_grid);
                    b.segment(piece, pinned)?;
                }
            }
        }
        if !path.passes().is_empty() {
            let (rapid, safe) = (params.rapid, params.safe_z);
            b.straight(BlockRole::Retract, rapid, [None, None, Some(safe)])?;
        }
        Ok(Self {
            params: params.clone(),
            gcode: gcode.clone(),
            tool_radius: path.tool_radius(),
            program: b.program,
            roles: b.roles,
        })
    }

    /// The planar program.
    pub fn program(&self) -> &PlanarProgram {
        &self.program
    }

    /// The role of each block of [`Self::program`].
    pub fn roles(&self) -> &[BlockRole] {
        &self.roles
    }

    /// A header for the program: `part_name` and a flat end mill of the path's radius as tool 1.
    pub fn header(&self, part_name: &str) -> ProgramHeader {
        ProgramHeader {
            program_name: "wavemill 2.5D contour path".into(),
            part_name: part_name.into(),
            tool_description: vec![format!(
                "flat end mill, diameter {} mm",
                super::format::fixed(2.0 * self.tool_radius, self.gcode.linear_decimals)
            )],
            tool_number: 1,
            spindle_rpm: self.params.spindle_rpm.map_or(0, |s| s.round() as u32),
            coolant: false,
            control_point_mm: None,
            comments: vec![format!(
                "cutting depth Z{}, safe height Z{}",
                super::format::fixed(self.params.cut_z, self.gcode.linear_decimals),
                super::format::fixed(self.params.safe_z, self.gcode.linear_decimals)
            )],
        }
    }

    /// The program text.
    pub fn to_gcode(&self, header: &ProgramHeader) -> String {
        self.program.to_gcode(header, &self.gcode)
    }

    /// Lengths, motion lines and estimated time (module docs). The tool is taken to start at
    /// the safe height above the first pass.
    pub fn stats(&self) -> ProgramStats {
        let program = &self.program;
        let mut st = ProgramStats {
            blocks: program.motion_lines(),
            ..Default::default()
        };
        // Feeds were validated positive, so every block has a time (no rotary axes: ω unused).
        let seconds = program.block_seconds(0.0);
        let (mut feed_s, mut rapid_s) = (0.0, 0.0);
        for (i, (role, s)) in self.roles.iter().zip(seconds).enumerate() {
            let (len, s) = (program.block_length(i), s.unwrap_or(0.0));
            match role {
                BlockRole::Cut => st.cut_length += len,
                BlockRole::Link => st.feed_link_length += len,
                BlockRole::StayDown => st.stay_down_length += len,
                BlockRole::Plunge => st.plunge_length += len,
                BlockRole::Retract | BlockRole::Traverse => st.rapid_length += len,
            }
            match role {
                BlockRole::Cut | BlockRole::Link | BlockRole::Plunge => feed_s += s,
                BlockRole::StayDown | BlockRole::Retract | BlockRole::Traverse => rapid_s += s,
            }
        }
        st.feed_minutes = feed_s / 60.0;
        st.rapid_minutes = rapid_s / 60.0;
        st.dwell_minutes = st.blocks as f64 * self.params.dwell_per_block / 60.0;
        st.total_minutes = st.feed_minutes + st.rapid_minutes + st.dwell_minutes;
        st
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::TAU;

    use super::*;
    use crate::contour::geometry::{Point2, Vertex};
    use crate::contour::toolpath::Pass;

    fn post(path: &CenterPath, params: &PlanarParams) -> ContourProgram {
        ContourProgram::new(path, params, &GcodeOptions::default()).expect("post")
    }

    #[test]
    fn time_model_on_a_hand_checked_square() {
        // One closed 10 mm square pass: 4 G1 blocks of 10 mm.
        let pass = Pass::closed(
            vec![
                Vertex::line(0.0, 0.0),
                Vertex::line(10.0, 0.0),
                Vertex::line(10.0, 10.0),
                Vertex::line(0.0, 10.0),
            ],
            1.0,
        )
        .expect("pass");
        let path = CenterPath::with_rapid_links(1.0, vec![pass]).expect("path");
        let params = PlanarParams {
            feed: 100.0,
            plunge_feed: 50.0,
            rapid: 1000.0,
            dwell_per_block: 0.6,
            cut_z: -2.0,
            safe_z: 3.0,
            spindle_rpm: None,
        };
        let prog = post(&path, &params);
        let st = prog.stats();
        // G0 G43 Z3 and G0 X0 Y0 (initial, no length), G1 Z−2 (5 mm plunge), 4 × G1, G0 Z3
        // (5 mm).
        assert_eq!(st.blocks, 8);
        assert!((st.cut_length - 40.0).abs() < 1e-12);
        assert!((st.plunge_length - 5.0).abs() < 1e-12);
        assert!((st.rapid_length - 5.0).abs() < 1e-12);
        let want = 40.0 / 100.0 + 5.0 / 50.0 + 5.0 / 1000.0 + 8.0 * 0.6 / 60.0;
        assert!(
            (st.total_minutes - want).abs() < 1e-12,
            "{} vs {want}",
            st.total_minutes
        );
        let text = prog.to_gcode(&prog.header("square"));
        assert!(
            text.contains(
                "G0 G43 H1 Z3.0000\nX0.0000 Y0.0000\nG1 Z-2.0000 F50.0\nX10.0000 F100.0\n"
            ),
            "{text}"
        );
    }

    #[test]
    fn defaults_follow_the_seed_where_it_has_values() {
        let d = PlanarParams::default();
        assert_eq!(d.feed, 30.0 * 25.4, "30 ipm, seed 004 Table 3.1");
        assert_eq!(d.spindle_rpm, Some(3500.0));
        let bad = PlanarParams {
            safe_z: -5.0,
            ..PlanarParams::default()
        };
        let path = CenterPath::with_rapid_links(1.0, vec![]).expect("empty path");
        assert!(ContourProgram::new(&path, &bad, &GcodeOptions::default()).is_err());
    }

    /// A tiny G-code reader for the dialect the post writes (modal motion words): motion moves
    /// with their start points.
    #[derive(Debug)]
    enum Parsed {
        Straight {
            rapid: bool,
            from: [f64; 3],
            to: [f64; 3],
        },
        Arc {
            from: [f64; 3],
            to: [f64; 3],
            center: [f64; 2],
            ccw: bool,
        },
    }

    fn parse(text: &str) -> Vec<Parsed> {
        let mut pos = [f64::NAN; 3];
        let mut mode = -1;
        let mut out = Vec::new();
        for line in text.lines() {
            let line = line.trim();
            if line.is_empty() || line == "%" || line.starts_with('(') {
                continue;
            }
            let mut words: Vec<(char, &str)> = Vec::new();
            for w in line.split_whitespace() {
                let (letter, num) = w.split_at(1);
                words.push((letter.chars().next().expect("word"), num));
            }
            let mut target = pos;
            let (mut i, mut j) = (None, None);
            let mut moved = false;
            for &(letter, num) in &words {
                match letter {
                    'G' => {
                        let g: i32 = num.parse().expect("G number");
                        if (0..=3).contains(&g) {
                            assert_ne!(mode, g, "a repeated motion word: {line}");
                            mode = g;
                        }
                    }
                    'F' => assert!(num.parse::<f64>().expect("feed") > 0.0, "{line}"),
                    'X' | 'Y' | 'Z' | 'I' | 'J' => {
                        // Exactly 4 decimals, never a negative zero.
                        let (int, frac) = num.split_once('.').expect("decimal point");
                        assert_eq!(frac.len(), 4, "{line}");
                        assert!(frac.chars().all(|c| c.is_ascii_digit()), "{line}");
                        assert!(
                            int.trim_start_matches('-')
                                .chars()
                                .all(|c| c.is_ascii_digit()),
                            "{line}"
                        );
                        assert_ne!(num, "-0.0000", "{line}");
                        let v: f64 = num.parse().expect("number");
                        match letter {
                            'X' => (target[0], moved) = (v, true),
                            'Y' => (target[1], moved) = (v, true),
                            'Z' => (target[2], moved) = (v, true),
                            'I' => i = Some(v),
                            'J' => j = Some(v),
                            _ => {}
                        }
                    }
                    'M' | 'S' | 'T' | 'H' => {}
                    other => panic!("unexpected word {other} in {line}"),
                }
            }
            if !moved {
                continue;
            }
            match mode {
                0 | 1 => out.push(Parsed::Straight {
                    rapid: mode == 0,
                    from: pos,
                    to: target,
                }),
                2 | 3 => out.push(Parsed::Arc {
                    from: pos,
                    to: target,
                    center: [pos[0] + i.expect("I"), pos[1] + j.expect("J")],
                    ccw: mode == 3,
                }),
                _ => panic!("motion without a motion mode: {line}"),
            }
            pos = target;
        }
        out
    }

    #[test]
    fn emitted_program_reads_back_onto_the_path() {
        use crate::contour::bvh::SegmentBvh;
        use crate::contour::geometry::{Contour, Shape};
        use crate::contour::parallel::tests::{circle, rect};
        use crate::contour::parallel::{ParallelOptions, contour_parallel};
        // An L-shaped part with a round pocket and a rounded (arc) notch, in a 40 mm stock.
        let l = Contour {
            vertices: vec![
                Vertex::line(0.0, 0.0),
                Vertex::line(20.0, 0.0),
                Vertex::line(20.0, 8.0),
                Vertex {
                    point: Point2::new(14.0, 8.0),
                    bulge: -0.6,
                },
                Vertex::line(8.0, 8.0),
                Vertex::line(8.0, 20.0),
                Vertex::line(0.0, 20.0),
            ],
        };
        let part = Shape {
            contours: vec![l, circle(4.0, 4.0, 2.5, false)],
        };
        let stock = Shape {
            contours: vec![rect(-10.0, -10.0, 30.0, 30.0, true)],
        };
        let path = contour_parallel(&part, &stock, &ParallelOptions::new(0.8, 1.2)).expect("plan");
        let params = PlanarParams::default();
        let prog = post(&path, &params);
        let text = prog.to_gcode(&prog.header("L with a pocket"));
        let moves = parse(&text);
        assert_eq!(moves.len(), prog.stats().blocks);
        let bvh = SegmentBvh::new(path.depth_segments());
        let near = |x: f64, y: f64| bvh.nearest_point(Point2::new(x, y)).expect("path").distance;
        let (mut arcs, mut cut_len) = (0, 0.0);
        for m in &moves {
            match *m {
                Parsed::Straight { rapid, from, to } => {
                    if !rapid && to[2] == params.cut_z && from[2] == params.cut_z {
                        assert!(near(to[0], to[1]) < 2e-4, "{m:?}");
                        assert!(
                            near(0.5 * (from[0] + to[0]), 0.5 * (from[1] + to[1])) < 2e-4,
                            "{m:?}"
                        );
                        cut_len += (to[0] - from[0]).hypot(to[1] - from[1]);
                    }
                }
                Parsed::Arc {
                    from,
                    to,
                    center,
                    ccw,
                } => {
                    arcs += 1;
                    assert_eq!(from[2], params.cut_z);
                    let rs = (from[0] - center[0]).hypot(from[1] - center[1]);
                    let re = (to[0] - center[0]).hypot(to[1] - center[1]);
                    assert!((rs - re).abs() <= 1e-4, "radius {rs} vs {re}: {m:?}");
                    // The arc runs the right way round: its midpoint is on the path.
                    let a0 = (from[1] - center[1]).atan2(from[0] - center[0]);
                    let a1 = (to[1] - center[1]).atan2(to[0] - center[0]);
                    let sweep = if ccw {
                        (a1 - a0).rem_euclid(TAU)
                    } else {
                        -(a0 - a1).rem_euclid(TAU)
                    };
                    let am = a0 + 0.5 * sweep;
                    assert!(
                        near(center[0] + rs * am.cos(), center[1] + rs * am.sin()) < 5e-4,
                        "{m:?}"
                    );
                    assert!(near(to[0], to[1]) < 2e-4, "{m:?}");
                    cut_len += rs * sweep.abs();
                }
            }
        }
        assert!(arcs > 20, "the test path should exercise arcs: {arcs}");
        let st = crate::contour::verify::path_stats(&path);
        let want = st.cut_length + st.feed_link_length + st.traverse_length;
        // Each block's ends move by ≤ 0.7e-4 mm in rounding.
        let tol = 1e-4 * moves.len() as f64;
        assert!((cut_len - want).abs() < tol, "{cut_len} vs {want}");
        let ps = prog.stats();
        assert!(
            (ps.cut_length + ps.feed_link_length + ps.stay_down_length - cut_len).abs()
                < 1e-9 * want
        );
        // Traverses at depth are posted at the rapid rate.
        if st.traverse_links > 0 {
            assert!(
                text.contains(&format!("F{:.1}", params.rapid)),
                "no rapid-rate G1"
            );
        }
        // One block per pass segment, feed link and traverse; a G0 up, a G0 across and a G1
        // down per rapid link and at the start; a final retract.
        assert_eq!(
            ps.blocks,
            st.segments + st.feed_links + st.traverse_links + 3 * st.rapid_links + 3 + 1
        );
        assert!(
            text.starts_with("%\n(PROGRAM: wavemill 2.5D contour path)")
                && text.ends_with("M5\nM30\n%\n")
        );
        assert!(!text.contains("-0.0000"));
    }
}
