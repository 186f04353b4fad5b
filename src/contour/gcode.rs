//! G-code output (Fanuc / LinuxCNC dialect) and the machining-time model of seed 004.
//!
//! A [`Program`] is the list of NC motion blocks of a [`CenterPath`] at one cutting depth:
//! millimetres (G21), absolute (G90), XY plane (G17), feed per minute (G94); G0 rapids, G1 lines,
//! G2 (clockwise) / G3 (counter-clockwise) arcs with the centre as I/J relative to the arc
//! start. Coordinates are quantised to 0.1 µm (4 decimals) once, as integers, so the text has no
//! "-0.0000" and every block starts exactly where the previous one ended. For each arc the
//! centre (and, where the next block does not depend on it, the end point) is chosen among the
//! nearest grid points so that the start and end radii agree to well below 1e-4 mm (controllers
//! reject arcs whose radii differ, LinuxCNC by more than 0.002 mm in G21).
//!
//! # Time model (seed 004 §1.2, §3.7, §4.1)
//!
//! Seed 004 attributes machining time to path length at the feed rate plus "dwell between
//! consecutive NC control commands" (Vickers and Bradley 1992, cited in §1.2; §4.1: fewer legs ⇒
//! "less dwell time in practical machining"). The model here is
//!
//! `time = (cut + feed-link length) / feed + plunge length / plunge_feed
//!        + (rapid + traverse-at-depth length) / rapid + blocks × dwell_per_block`,
//!
//! counting every motion block. Defaults: `feed` = 762 mm/min — the 30 ipm XY feed of seed 004
//! Table 3.1's caption (tool radius 0.25 in, 3500 rpm, 4 Z steps); spindle 3500 rpm from the
//! same caption. The seed gives NO value for the dwell per block, the rapid rate or the plunge
//! feed (its times come from the ProCAM TekSoft-2D simulator; Table 3.1's contour-parallel
//! 752.37 in at 30 ipm is 25.1 min of pure feed against 65.03 min reported, so the overheads it
//! models are large but not separable). Chosen defaults, documented as such: dwell 0.05 s per
//! block (a typical block-processing delay of controllers of that era), rapid 5000 mm/min,
//! plunge feed = XY feed.

use crate::contour::error::{ContourError, Result};
use crate::contour::geometry::{Point2, Segment};
use crate::contour::segops::{seg_end, split_arc};
use crate::contour::toolpath::{CenterPath, Link};
use std::f64::consts::{PI, TAU};
use std::fmt::Write as _;

/// Quantum of the output coordinates: 1e-4 mm.
const QUANTUM: f64 = 1e-4;
/// Largest |coordinate| accepted, mm (keeps the integer quantisation exact).
const MAX_COORD: f64 = 1e9;

/// Machine and posting parameters (see the module docs for the sources of the defaults).
#[derive(Clone, Debug, PartialEq)]
pub struct MachineParams {
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

impl Default for MachineParams {
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

impl MachineParams {
    fn validate(&self) -> Result<()> {
        let positive = [
            ("feed", self.feed),
            ("plunge_feed", self.plunge_feed),
            ("rapid", self.rapid),
        ];
        for (name, value) in positive {
            if !(value.is_finite() && value > 0.0) {
                return Err(ContourError::InvalidOption {
                    name,
                    value,
                    reason: "must be a positive finite rate in mm/min",
                });
            }
        }
        if !(self.dwell_per_block.is_finite() && self.dwell_per_block >= 0.0) {
            return Err(ContourError::InvalidOption {
                name: "dwell_per_block",
                value: self.dwell_per_block,
                reason: "must be a finite number of seconds ≥ 0",
            });
        }
        for (name, value) in [("cut_z", self.cut_z), ("safe_z", self.safe_z)] {
            if !(value.is_finite() && value.abs() < MAX_COORD) {
                return Err(ContourError::InvalidOption {
                    name,
                    value,
                    reason: "must be finite",
                });
            }
        }
        if self.safe_z <= self.cut_z {
            return Err(ContourError::InvalidOption {
                name: "safe_z",
                value: self.safe_z,
                reason: "must be above cut_z",
            });
        }
        if let Some(s) = self.spindle_rpm
            && !(s.is_finite() && s > 0.0)
        {
            return Err(ContourError::InvalidOption {
                name: "spindle_rpm",
                value: s,
                reason: "must be a positive finite speed",
            });
        }
        Ok(())
    }
}

/// What a block does, for the statistics.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MoveKind {
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

/// Motion of one NC block; coordinates in units of 1e-4 mm.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Motion {
    /// G0 to (x, y, z); `None` axes do not move.
    Rapid {
        x: Option<i64>,
        y: Option<i64>,
        z: Option<i64>,
    },
    /// G1 to (x, y, z).
    Line {
        x: Option<i64>,
        y: Option<i64>,
        z: Option<i64>,
    },
    /// G2 (`ccw == false`) or G3 to (x, y) around start + (i, j).
    Arc {
        x: i64,
        y: i64,
        i: i64,
        j: i64,
        ccw: bool,
    },
}

/// One motion block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Block {
    pub kind: MoveKind,
    pub motion: Motion,
    /// Feed word to emit with this block (mm/min), when the modal feed changes.
    pub feed: Option<f64>,
}

/// The NC program of a path at one depth.
#[derive(Clone, Debug, PartialEq)]
pub struct Program {
    params: MachineParams,
    tool_radius: f64,
    blocks: Vec<Block>,
}

/// Statistics of a [`Program`] under the time model of the module docs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ProgramStats {
    /// Motion blocks (each pays `dwell_per_block`).
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
    /// Minutes at rapid.
    pub rapid_minutes: f64,
    /// Minutes of block dwell.
    pub dwell_minutes: f64,
    /// Total estimated machining time, minutes.
    pub total_minutes: f64,
}

fn quantise(v: f64, what: &str) -> Result<i64> {
    if !(v.is_finite() && v.abs() < MAX_COORD) {
        return Err(ContourError::BadPath(format!(
            "{what} coordinate {v} cannot be posted"
        )));
    }
    Ok((v / QUANTUM).round() as i64)
}

fn qpoint(p: Point2) -> Result<(i64, i64)> {
    Ok((quantise(p.x, "x")?, quantise(p.y, "y")?))
}

fn unq(v: i64) -> f64 {
    v as f64 * QUANTUM
}

/// Radius mismatch |‖e − c‖ − ‖s − c‖| in quantum units.
fn mismatch(s: (i64, i64), e: (i64, i64), c: (i64, i64)) -> f64 {
    let rs = ((s.0 - c.0) as f64).hypot((s.1 - c.1) as f64);
    let re = ((e.0 - c.0) as f64).hypot((e.1 - c.1) as f64);
    (re - rs).abs()
}

struct Emitter {
    params: MachineParams,
    blocks: Vec<Block>,
    pos: (i64, i64),
    modal_feed: Option<f64>,
}

impl Emitter {
    fn push(&mut self, kind: MoveKind, motion: Motion, feed: Option<f64>) {
        let feed = match feed {
            Some(f) if self.modal_feed != Some(f) => {
                self.modal_feed = Some(f);
                Some(f)
            }
            _ => None,
        };
        self.blocks.push(Block { kind, motion, feed });
        match motion {
            Motion::Rapid { x, y, .. } | Motion::Line { x, y, .. } => {
                self.pos = (x.unwrap_or(self.pos.0), y.unwrap_or(self.pos.1));
            }
            Motion::Arc { x, y, .. } => self.pos = (x, y),
        }
    }

    fn retract_traverse_plunge(&mut self, to: (i64, i64)) -> Result<()> {
        let (safe, cut) = (
            quantise(self.params.safe_z, "z")?,
            quantise(self.params.cut_z, "z")?,
        );
        self.push(
            MoveKind::Retract,
            Motion::Rapid {
                x: None,
                y: None,
                z: Some(safe),
            },
            None,
        );
        self.push(
            MoveKind::Traverse,
            Motion::Rapid {
                x: Some(to.0),
                y: Some(to.1),
                z: None,
            },
            None,
        );
        let pf = self.params.plunge_feed;
        self.push(
            MoveKind::Plunge,
            Motion::Line {
                x: None,
                y: None,
                z: Some(cut),
            },
            Some(pf),
        );
        Ok(())
    }

    fn line_to(&mut self, kind: MoveKind, e: (i64, i64)) {
        if e != self.pos {
            let f = if kind == MoveKind::StayDown {
                self.params.rapid
            } else {
                self.params.feed
            };
            self.push(
                kind,
                Motion::Line {
                    x: Some(e.0),
                    y: Some(e.1),
                    z: None,
                },
                Some(f),
            );
        }
    }

    /// Emits one pass segment; `fixed_end` pins the quantised end point.
    fn segment(&mut self, seg: &Segment, fixed_end: Option<(i64, i64)>) -> Result<()> {
        let e0 = match fixed_end {
            Some(e) => e,
            None => qpoint(seg_end(seg))?,
        };
        let Segment::Arc {
            center,
            radius,
            sweep,
            ..
        } = *seg
        else {
            self.line_to(MoveKind::Cut, e0);
            return Ok(());
        };
        let sagitta = radius * (1.0 - (0.5 * sweep).cos());
        if e0 == self.pos || sagitta < QUANTUM {
            // Shorter than the output resolution, or straight to within it.
            self.line_to(MoveKind::Cut, e0);
            return Ok(());
        }
        let c0 = qpoint(center)?;
        let s = self.pos;
        let ends: Vec<(i64, i64)> = match fixed_end {
            Some(e) => vec![e],
            None => (-1..=1)
                .flat_map(|dx| (-1..=1).map(move |dy| (e0.0 + dx, e0.1 + dy)))
                .collect(),
        };
        // (radius mismatch, squared displacement, end, centre)
        type Choice = (f64, i64, (i64, i64), (i64, i64));
        let mut best: Option<Choice> = None;
        for &e in &ends {
            if e == s {
                continue;
            }
            for dx in -2..=2i64 {
                for dy in -2..=2i64 {
                    let c = (c0.0 + dx, c0.1 + dy);
                    let m = mismatch(s, e, c);
                    let moved = (e.0 - e0.0).pow(2) + (e.1 - e0.1).pow(2) + dx * dx + dy * dy;
                    if best
                        .is_none_or(|b| m < b.0 - 1e-9 || ((m - b.0).abs() <= 1e-9 && moved < b.1))
                    {
                        best = Some((m, moved, e, c));
                    }
                }
            }
        }
        let Some((_, _, e, c)) = best else {
            self.line_to(MoveKind::Cut, e0);
            return Ok(());
        };
        let f = self.params.feed;
        self.push(
            MoveKind::Cut,
            Motion::Arc {
                x: e.0,
                y: e.1,
                i: c.0 - s.0,
                j: c.1 - s.1,
                ccw: sweep > 0.0,
            },
            Some(f),
        );
        Ok(())
    }
}

impl Program {
    /// Posts `path` at the depth and feeds of `params`.
    pub fn new(path: &CenterPath, params: &MachineParams) -> Result<Self> {
        params.validate()?;
        let mut em = Emitter {
            params: params.clone(),
            blocks: Vec::new(),
            pos: (0, 0),
            modal_feed: None,
        };
        for (k, pass) in path.passes().iter().enumerate() {
            let start = qpoint(pass.start())?;
            if k == 0 {
                em.pos = start;
                em.retract_traverse_plunge(start)?;
            } else {
                match path.links()[k - 1] {
                    Link::Feed { .. } => em.line_to(MoveKind::Link, start),
                    Link::Traverse { .. } => em.line_to(MoveKind::StayDown, start),
                    Link::Rapid { .. } => em.retract_traverse_plunge(start)?,
                }
            }
            let segs: Vec<Segment> = pass.segments().collect();
            let last = segs.len().saturating_sub(1);
            for (i, seg) in segs.iter().enumerate() {
                // Arcs over a half turn are posted as two halves so no block's end can round
                // onto its start (which a controller would read as a full circle).
                let pieces = if matches!(seg, Segment::Arc { sweep, .. } if sweep.abs() > PI) {
                    split_arc(seg, PI)
                } else {
                    vec![*seg]
                };
                let np = pieces.len();
                for (j, piece) in pieces.iter().enumerate() {
                    let fixed = (pass.is_closed() && i == last && j + 1 == np).then_some(start);
                    em.segment(piece, fixed)?;
                }
            }
        }
        if !path.passes().is_empty() {
            let safe = quantise(params.safe_z, "z")?;
            em.push(
                MoveKind::Retract,
                Motion::Rapid {
                    x: None,
                    y: None,
                    z: Some(safe),
                },
                None,
            );
        }
        Ok(Self {
            params: params.clone(),
            tool_radius: path.tool_radius(),
            blocks: em.blocks,
        })
    }

    /// The motion blocks.
    pub fn blocks(&self) -> &[Block] {
        &self.blocks
    }

    /// Lengths, block count and estimated time (module docs). The tool is taken to start at
    /// the safe height above the first pass.
    pub fn stats(&self) -> ProgramStats {
        let p = &self.params;
        let mut st = ProgramStats {
            blocks: self.blocks.len(),
            ..Default::default()
        };
        let (mut x, mut y, mut z) = (0i64, 0i64, quantise(p.safe_z, "z").unwrap_or(0));
        let mut first_xy = true;
        for b in &self.blocks {
            let (nx, ny, nz, len) = match b.motion {
                Motion::Rapid {
                    x: bx,
                    y: by,
                    z: bz,
                }
                | Motion::Line {
                    x: bx,
                    y: by,
                    z: bz,
                } => {
                    let (nx, ny, nz) = (bx.unwrap_or(x), by.unwrap_or(y), bz.unwrap_or(z));
                    if first_xy && (bx.is_some() || by.is_some()) {
                        // Initial positioning: the start point is unknown, count no length.
                        first_xy = false;
                        (nx, ny, nz, 0.0)
                    } else {
                        let d = (unq(nx - x).powi(2) + unq(ny - y).powi(2) + unq(nz - z).powi(2))
                            .sqrt();
                        (nx, ny, nz, d)
                    }
                }
                Motion::Arc {
                    x: ex,
                    y: ey,
                    i,
                    j,
                    ccw,
                } => {
                    let (cx, cy) = (x + i, y + j);
                    let a0 = ((y - cy) as f64).atan2((x - cx) as f64);
                    let a1 = ((ey - cy) as f64).atan2((ex - cx) as f64);
                    let mut sweep = if ccw {
                        (a1 - a0).rem_euclid(TAU)
                    } else {
                        (a0 - a1).rem_euclid(TAU)
                    };
                    if sweep == 0.0 {
                        sweep = TAU;
                    }
                    let rad = unq(i).hypot(unq(j));
                    (ex, ey, z, rad * sweep)
                }
            };
            match b.kind {
                MoveKind::Cut => st.cut_length += len,
                MoveKind::Link => st.feed_link_length += len,
                MoveKind::StayDown => st.stay_down_length += len,
                MoveKind::Plunge => st.plunge_length += len,
                MoveKind::Retract | MoveKind::Traverse => st.rapid_length += len,
            }
            (x, y, z) = (nx, ny, nz);
        }
        st.feed_minutes =
            (st.cut_length + st.feed_link_length) / p.feed + st.plunge_length / p.plunge_feed;
        st.rapid_minutes = (st.rapid_length + st.stay_down_length) / p.rapid;
        st.dwell_minutes = st.blocks as f64 * p.dwell_per_block / 60.0;
        st.total_minutes = st.feed_minutes + st.rapid_minutes + st.dwell_minutes;
        st
    }

    /// The program text.
    pub fn to_gcode(&self) -> String {
        let mut out = String::new();
        out.push_str("%\n");
        let _ = writeln!(
            out,
            "(wavemill 2.5D contour path, tool radius {} mm)",
            fmt_mm(self.tool_radius)
        );
        out.push_str("G21 G90 G17 G94\n");
        if let Some(s) = self.params.spindle_rpm {
            let _ = writeln!(out, "S{} M3", s.round() as i64);
        }
        for b in &self.blocks {
            let mut line = String::new();
            let axes = |line: &mut String, x: Option<i64>, y: Option<i64>, z: Option<i64>| {
                for (name, v) in [("X", x), ("Y", y), ("Z", z)] {
                    if let Some(v) = v {
                        let _ = write!(line, " {name}{}", fmt_q(v));
                    }
                }
            };
            match b.motion {
                Motion::Rapid { x, y, z } => {
                    line.push_str("G0");
                    axes(&mut line, x, y, z);
                }
                Motion::Line { x, y, z } => {
                    line.push_str("G1");
                    axes(&mut line, x, y, z);
                }
                Motion::Arc { x, y, i, j, ccw } => {
                    let _ = write!(
                        line,
                        "{} X{} Y{} I{} J{}",
                        if ccw { "G3" } else { "G2" },
                        fmt_q(x),
                        fmt_q(y),
                        fmt_q(i),
                        fmt_q(j)
                    );
                }
            }
            if let Some(f) = b.feed {
                let _ = write!(line, " F{}", fmt_mm(f));
            }
            out.push_str(&line);
            out.push('\n');
        }
        if self.params.spindle_rpm.is_some() {
            out.push_str("M5\n");
        }
        out.push_str("M2\n%\n");
        out
    }
}

/// A quantised coordinate as text with 4 decimals (never "-0.0000").
pub fn fmt_q(v: i64) -> String {
    let sign = if v < 0 { "-" } else { "" };
    let a = v.unsigned_abs();
    format!("{sign}{}.{:04}", a / 10_000, a % 10_000)
}

/// A length in mm with 4 decimals (never "-0.0000").
pub fn fmt_mm(v: f64) -> String {
    quantise(v, "value").map_or_else(|_| format!("{v}"), fmt_q)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contour::geometry::Vertex;
    use crate::contour::toolpath::Pass;

    #[test]
    fn numbers_have_four_decimals_and_no_negative_zero() {
        assert_eq!(fmt_q(0), "0.0000");
        assert_eq!(fmt_q(-1), "-0.0001");
        assert_eq!(fmt_q(123_456), "12.3456");
        assert_eq!(fmt_q(-123_456), "-12.3456");
        assert_eq!(fmt_mm(-0.00004), "0.0000");
        assert_eq!(fmt_mm(-0.0), "0.0000");
        assert_eq!(fmt_mm(762.0), "762.0000");
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
        let params = MachineParams {
            feed: 100.0,
            plunge_feed: 50.0,
            rapid: 1000.0,
            dwell_per_block: 0.6,
            cut_z: -2.0,
            safe_z: 3.0,
            spindle_rpm: None,
        };
        let prog = Program::new(&path, &params).expect("post");
        let st = prog.stats();
        // G0 Z3, G0 X0 Y0 (initial, no length), G1 Z−2 (5 mm plunge), 4 × G1, G0 Z3 (5 mm).
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
        let text = prog.to_gcode();
        assert!(
            text.contains("G1 Z-2.0000 F50.0000\nG1 X10.0000 Y0.0000 F100.0000\n"),
            "{text}"
        );
    }

    #[test]
    fn defaults_follow_the_seed_where_it_has_values() {
        let d = MachineParams::default();
        assert_eq!(d.feed, 30.0 * 25.4, "30 ipm, seed 004 Table 3.1");
        assert_eq!(d.spindle_rpm, Some(3500.0));
        let bad = MachineParams {
            safe_z: -5.0,
            ..MachineParams::default()
        };
        let path = CenterPath::with_rapid_links(1.0, vec![]).expect("empty path");
        assert!(Program::new(&path, &bad).is_err());
    }

    /// A tiny G-code reader for the dialect above: motion moves with their start points.
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
                            mode = g;
                        }
                    }
                    'X' | 'Y' | 'Z' | 'I' | 'J' | 'F' => {
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
                    'M' | 'S' => {}
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
        let params = MachineParams::default();
        let prog = Program::new(&path, &params).expect("post");
        let text = prog.to_gcode();
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
                text.contains(&format!("F{:.4}", params.rapid)),
                "no rapid-rate G1"
            );
        }
        // One block per pass segment, feed link and traverse; a G0 up, a G0 across and a G1
        // down per rapid link and at the start; a final retract.
        assert_eq!(
            ps.blocks,
            st.segments + st.feed_links + st.traverse_links + 3 * st.rapid_links + 3 + 1
        );
        assert!(text.starts_with("%\n(wavemill") && text.ends_with("M5\nM2\n%\n"));
        assert!(!text.contains("-0.0000"));
    }
}
