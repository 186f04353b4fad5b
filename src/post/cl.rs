//! Cutter-location (CL) data as CSV, for other post-processors.
//!
//! One row per move of the **original** toolpath (not the linearised one), header exactly
//! `x,y,z,i,j,k,kind,feed,tool`: tip position (mm, part frame), unit tool axis, the move kind
//! in lowercase (`rapid|approach|cut|retract`), feed (mm/min) and tool id. Positions and axis
//! components have 9 fixed decimals: with 6, the ball centre `tip + r·axis` read back from the
//! file would carry up to r·1e-6 mm of rounding, as large as the gouge tolerance itself.
//! Feeds have 3. Never a negative zero. Deterministic.

use super::format::fixed;
use crate::geom::{Move, MoveKind, ToolPose, Toolpath};

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

/// A CL file that cannot be read: the file, the line (from 1) and what is wrong there.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{file}: line {line}: {reason}")]
pub struct ClError {
    /// The file, as named by the caller.
    pub file: String,
    /// The line, counted from 1.
    pub line: usize,
    /// What is wrong.
    pub reason: String,
}

/// Reads CL data written by [`write_cl_csv`] (the header exactly, then one move per line;
/// blank lines skipped). Every field is checked: finite numbers, an axis of unit length
/// (within 1e-6, then normalised), a known kind, a positive feed, one tool id throughout.
pub fn read_cl_csv(text: &str, file: &str) -> Result<Toolpath, ClError> {
    let bad = |line: usize, reason: String| ClError {
        file: file.to_string(),
        line,
        reason,
    };
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l.trim()));
    match lines.next() {
        Some((_, header)) if header == CL_CSV_HEADER => {}
        Some((n, header)) => {
            return Err(bad(
                n,
                format!("expected the header `{CL_CSV_HEADER}`, found `{header}`"),
            ));
        }
        None => return Err(bad(1, "the file is empty".into())),
    }
    let mut moves = Vec::new();
    let mut tool_id = None;
    for (n, line) in lines.filter(|(_, l)| !l.is_empty()) {
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if fields.len() != 9 {
            return Err(bad(n, format!("expected 9 fields, found {}", fields.len())));
        }
        let mut numbers = [0.0; 6];
        for (k, value) in numbers.iter_mut().enumerate() {
            *value = fields[k]
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad(n, format!("`{}` is not a finite number", fields[k])))?;
        }
        let axis = nalgebra::Vector3::new(numbers[3], numbers[4], numbers[5]);
        if (axis.norm() - 1.0).abs() > 1e-6 {
            return Err(bad(
                n,
                format!(
                    "the axis ({}, {}, {}) is not a unit vector",
                    axis.x, axis.y, axis.z
                ),
            ));
        }
        let kind = match fields[6] {
            "rapid" => MoveKind::Rapid,
            "approach" => MoveKind::Approach,
            "cut" => MoveKind::Cut,
            "retract" => MoveKind::Retract,
            other => return Err(bad(n, format!("unknown move kind `{other}`"))),
        };
        let feed = fields[7]
            .parse::<f64>()
            .ok()
            .filter(|f| f.is_finite() && *f > 0.0)
            .ok_or_else(|| bad(n, format!("feed `{}` is not a positive number", fields[7])))?;
        let tool = fields[8]
            .parse::<u32>()
            .map_err(|_| bad(n, format!("tool `{}` is not a tool number", fields[8])))?;
        if *tool_id.get_or_insert(tool) != tool {
            return Err(bad(
                n,
                format!(
                    "tool {tool} after tool {}: one tool per file",
                    tool_id.unwrap_or(tool)
                ),
            ));
        }
        moves.push(Move {
            pose: ToolPose {
                tip: crate::geom::Point3::new(numbers[0], numbers[1], numbers[2]),
                axis: nalgebra::Unit::new_normalize(axis),
            },
            kind,
            feed,
        });
    }
    if moves.is_empty() {
        return Err(bad(1, "no moves after the header".into()));
    }
    Ok(Toolpath {
        tool_id: tool_id.unwrap_or(0),
        moves,
    })
}
