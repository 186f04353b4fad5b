//! Heidenhain TNC conversational (Klartext) output through the [`ProgramSink`] trait.
//!
//! ```text
//! 0 BEGIN PGM WAVEMILL MM
//! 1 ; PROGRAM: …                               — one comment per block
//! 7 TOOL CALL 1 Z S12000                       — tool change, tool axis Z
//! 8 FUNCTION TCPM F TCP AXIS POS PATHCTRL AXIS — TCP output only
//! 9 L Z+120.0000 R0 FMAX M3 M8                 — Z first, spindle and coolant on
//! 10 L X+… Y+… B+… C+… R0 FMAX                 — then X, Y and the rotaries
//! 11 L X+… Y+… Z+… B+… C+… R0 F1500            — motion; unchanged coordinates left out
//! …
//! 812 L Z+… R0 FMAX M5 M9
//! 813 FUNCTION RESET TCPM
//! 814 END PGM WAVEMILL MM
//! ```
//!
//! Coordinates carry their sign and fixed decimals; `FMAX` holds for its block only, so the
//! first feed block after a rapid restates `F`. With `FUNCTION TCPM F TCP` the control keeps `F`
//! at the tool tip relative to the part, what the planner meant; in joint output `F` is the
//! contouring feed of the axes, as with `G94`. The conversational language has no inverse-time
//! feed (machine files refuse the combination). `TOOL CALL` applies the tool table's length:
//! joint output on a machine with head axes already carries the gauge length in X, Y, Z, so
//! its header asks for a zero length in the tool table.

use super::dialect::OutputMode;
use super::format::{comment_text, fixed};
use super::gcode::GcodeOptions;
use super::kinematics::{Joints, MachineKinematics, RotaryAxis};
use super::{ArcXY, ProgramHeader, ProgramSink};
use crate::geom::{Move, MoveKind};

/// Writes a conversational program into a `String`.
#[derive(Clone, Debug)]
pub struct HeidenhainWriter {
    opts: GcodeOptions,
    machine: String,
    work_offset: String,
    rotary: Vec<RotaryAxis>,
    head: bool,
    out: String,
    block: usize,
    last: [Option<String>; 5],
    last_f: Option<String>,
    last_joints: Option<Joints>,
    /// The next motion is the first after a tool call: Z alone, spindle and coolant on.
    first_motion: bool,
    spindle: bool,
    coolant: bool,
}

/// Program name in `BEGIN PGM` / `END PGM`.
const PROGRAM: &str = "WAVEMILL";

impl HeidenhainWriter {
    /// A writer for the given machine.
    pub fn new<K: MachineKinematics + ?Sized>(kin: &K, opts: GcodeOptions) -> Self {
        let tcp = opts.output == OutputMode::Tcp;
        HeidenhainWriter {
            machine: kin.description(),
            work_offset: if tcp {
                "origin at the part origin (FUNCTION TCPM places the rotary axes)".into()
            } else {
                kin.work_offset().to_string()
            },
            rotary: kin.rotary_axes(),
            head: kin.has_head_axes(),
            opts,
            out: String::new(),
            block: 0,
            last: Default::default(),
            last_f: None,
            last_joints: None,
            first_motion: true,
            spindle: false,
            coolant: false,
        }
    }

    fn line(&mut self, s: &str) {
        self.out.push_str(&format!("{} {s}\n", self.block));
        self.block += 1;
    }

    fn comment(&mut self, label: &str, text: &str) {
        let body = comment_text(text);
        if label.is_empty() {
            self.line(&format!("; {body}"));
        } else {
            self.line(&format!("; {label}: {body}"));
        }
    }

    /// A signed fixed-decimal coordinate (`+0.0000`, `-12.5000`).
    fn signed(v: f64, decimals: usize) -> String {
        let s = fixed(v, decimals);
        if s.starts_with('-') {
            s
        } else {
            format!("+{s}")
        }
    }

    fn slot(&self, i: usize, j: &Joints) -> (String, String) {
        let (ld, ad) = (self.opts.linear_decimals, self.opts.angular_decimals);
        match i {
            0 => ("X".into(), Self::signed(j.x, ld)),
            1 => ("Y".into(), Self::signed(j.y, ld)),
            2 => ("Z".into(), Self::signed(j.z, ld)),
            3 => (self.rotary[0].to_string(), Self::signed(j.a, ad)),
            _ => (self.rotary[1].to_string(), Self::signed(j.c, ad)),
        }
    }

    fn coordinates(&mut self, j: &Joints, slots: &[usize]) -> Vec<String> {
        let mut words = Vec::new();
        for &i in slots {
            let (letter, printed) = self.slot(i, j);
            if self.last[i].as_deref() != Some(printed.as_str()) {
                words.push(format!("{letter}{printed}"));
                self.last[i] = Some(printed);
            }
        }
        words
    }

    fn tool_call(&mut self, h: &ProgramHeader) {
        for d in &h.tool_description {
            self.comment(&format!("TOOL T{}", h.tool_number), d);
        }
        if h.spindle_rpm > 0 {
            self.line(&format!("TOOL CALL {} Z S{}", h.tool_number, h.spindle_rpm));
        } else {
            self.line(&format!("TOOL CALL {} Z", h.tool_number));
        }
        self.spindle = h.spindle_rpm > 0;
        if self.opts.output == OutputMode::Tcp {
            self.line("FUNCTION TCPM F TCP AXIS POS PATHCTRL AXIS");
        }
        self.first_motion = true;
        self.last = Default::default();
        self.last_f = None;
        self.last_joints = None;
    }

    fn reset_tcpm(&mut self) {
        if self.opts.output == OutputMode::Tcp {
            self.line("FUNCTION RESET TCPM");
        }
    }

    /// The program text.
    pub fn into_string(self) -> String {
        self.out
    }
}

impl ProgramSink for HeidenhainWriter {
    fn begin(&mut self, h: &ProgramHeader) {
        self.coolant = h.coolant;
        self.line(&format!("BEGIN PGM {PROGRAM} MM"));
        self.comment("PROGRAM", &h.program_name);
        self.comment("PART", &h.part_name);
        self.comment("UNITS", "MM");
        let machine = self.machine.clone();
        self.comment("MACHINE", &machine);
        let work_offset = self.work_offset.clone();
        self.comment("WORK OFFSET", &work_offset);
        let mode = match self.opts.output {
            OutputMode::Tcp => "tcp output: X Y Z are the tool tip in the part frame, F at the tip",
            OutputMode::Joint if self.head => {
                "joint output: X Y Z are the head pivot with the tool's gauge length included; \
                 the tool table's length must be 0"
            }
            OutputMode::Joint => "joint output: F is the axes' contouring feed",
        };
        self.comment("MODE", mode);
        self.comment("GENERATED BY", "wavemill post");
        for c in &h.comments {
            self.comment("", c);
        }
        self.tool_call(h);
    }

    fn motion(&mut self, m: &Move, j: &Joints) {
        if self.first_motion {
            // Z first, alone, with the spindle and coolant switched on (see the module docs).
            let mut words = vec!["L".to_string()];
            words.extend(self.coordinates(j, &[2]));
            words.push("R0 FMAX".into());
            if self.spindle {
                words.push("M3".into());
            }
            if self.coolant {
                words.push("M8".into());
            }
            self.line(&words.join(" "));
            self.first_motion = false;
        }
        let slots: Vec<usize> = (0..3 + self.rotary.len()).collect();
        let coordinates = self.coordinates(j, &slots);
        self.last_joints = Some(*j);
        if coordinates.is_empty() {
            return;
        }
        let mut words = vec!["L".to_string()];
        words.extend(coordinates);
        words.push("R0".into());
        if m.kind == MoveKind::Rapid {
            words.push("FMAX".into());
            // FMAX holds for its block only.
            self.last_f = None;
        } else {
            let f = fixed(m.feed, self.opts.feed_decimals);
            if self.last_f.as_deref() != Some(f.as_str()) {
                words.push(format!("F{f}"));
                self.last_f = Some(f);
            }
        }
        self.line(&words.join(" "));
    }

    /// Planar programs are not written in this dialect: an arc is posted as a straight move
    /// to its end (the 5-axis post never calls this).
    fn arc(&mut self, m: &Move, end: &Joints, _arc: &ArcXY) {
        self.motion(m, end);
    }

    fn tool_change(&mut self, h: &ProgramHeader) {
        self.reset_tcpm();
        self.tool_call(h);
    }

    fn end(&mut self) {
        let z = self
            .last_joints
            .map_or_else(|| "+0.0000".to_string(), |j| self.slot(2, &j).1);
        let mut words = vec![format!("L Z{z} R0 FMAX")];
        if self.spindle {
            words.push("M5".into());
        }
        if self.coolant {
            words.push("M9".into());
        }
        self.line(&words.join(" "));
        self.reset_tcpm();
        self.line(&format!("END PGM {PROGRAM} MM"));
    }

    fn finish(self: Box<Self>) -> String {
        self.out
    }
}
