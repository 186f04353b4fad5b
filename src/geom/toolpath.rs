use crate::geom::{Direction, Point3};

/// A tool pose in the part frame: `tip` is the tool tip (lowest point of the cutter on its
/// axis), `axis` the unit tool axis pointing from the tip toward the spindle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToolPose {
    pub tip: Point3,
    pub axis: Direction,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum MoveKind {
    Rapid,
    Approach,
    Cut,
    Retract,
}

impl MoveKind {
    pub fn name(self) -> &'static str {
        match self {
            MoveKind::Rapid => "rapid",
            MoveKind::Approach => "approach",
            MoveKind::Cut => "cut",
            MoveKind::Retract => "retract",
        }
    }
}

/// One move: go from the previous move's pose to `pose`. `feed` in mm/min; for rapids it is
/// the machine's rapid rate (used only for time estimates; posted as G0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Move {
    pub pose: ToolPose,
    pub kind: MoveKind,
    pub feed: f64,
}

/// The moves of one tool, in order. The first move is always a Rapid.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Toolpath {
    pub tool_id: u32,
    pub moves: Vec<Move>,
}

impl Toolpath {
    /// Length of the cutting moves, mm.
    pub fn cutting_length(&self) -> f64 {
        self.moves
            .windows(2)
            .filter(|w| w[1].kind == MoveKind::Cut)
            .map(|w| (w[1].pose.tip - w[0].pose.tip).norm())
            .sum()
    }
}
