//! Cutter-location (CL) data as CSV, for other post-processors.
//!
//! One row per move of the **original** toolpath (not the linearised one), header exactly
//! `x,y,z,i,j,k,kind,feed,tool`: tip position (mm, part frame), unit tool axis, the move kind
//! in lowercase (`rapid|approach|cut|retract`), feed (mm/min) and tool id. Positions and axis
//! components have 9 fixed decimals: with 6, the ball centre `tip + r·axis` read back from the
//! file would carry up to r·1e-6 mm of rounding, as large as the gouge tolerance itself.
//! Feeds have 3. Never a negative zero. Deterministic.

use super::format::fixed;
use crate::geom::{MoveKind, Toolpath};

/// The exact CSV header line.
pub const CL_CSV_HEADER: &str = "x,y,z,i,j,k,kind,feed,tool";

/// Decimals of positions and axis components in the CL CSV.
pub const CL_DECIMALS: usize = 9;
/// Decimals of feeds in the CL CSV.
pub const CL_FEED_DECIMALS: usize = 3;

/// Lowercase name of a move kind, as written in CL data.
pub fn kind_name(kind: MoveKind) -> &'static str {
    match kind {
        MoveKind::Rapid => "rapid",
        MoveKind::Approach => "approach",
        MoveKind::Cut => "cut",
        MoveKind::Retract => "retract",
    }
}

/// Writes the toolpath's CL data as CSV (header line, then one line per move, `\n` endings).
pub fn write_cl_csv(toolpath: &Toolpath) -> String {
    let mut s = String::with_capacity(64 * (toolpath.moves.len() + 1));
    s.push_str(CL_CSV_HEADER);
    s.push('\n');
    for m in &toolpath.moves {
        let p = m.pose.tip;
        let k = m.pose.axis;
        for v in [p.x, p.y, p.z, k.x, k.y, k.z] {
            s.push_str(&fixed(v, CL_DECIMALS));
            s.push(',');
        }
        s.push_str(kind_name(m.kind));
        s.push(',');
        s.push_str(&fixed(m.feed, CL_FEED_DECIMALS));
        s.push(',');
        s.push_str(&toolpath.tool_id.to_string());
        s.push('\n');
    }
    s
}
