//! APT cutter-location data (`cl.apt`), the input other post-processors read: one `GOTO/x, y,
//! z, i, j, k` per move of the original toolpath (tip in the part frame, unit tool axis), with
//! `MULTAX/ON`, `LOADTL` and `CUTTER` at each tool, `FEDRAT/MMPM,f` when the feed changes and
//! `RAPID` before each rapid (it holds for the next motion only, as APT defines it). Positions
//! and axes have 9 decimals, as in the CSV ([`super::cl`]); never a negative zero; deterministic.

use super::cl::{CL_DECIMALS, CL_FEED_DECIMALS};
use super::format::fixed;
use crate::geom::{Move, MoveKind};

/// A tool as APT describes it: number, diameter and corner radius (mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AptTool {
    /// `LOADTL` number.
    pub number: u32,
    /// Cutter diameter, mm.
    pub diameter: f64,
    /// Corner radius, mm (the radius for a ball end, 0 for a flat end).
    pub corner_radius: f64,
}

/// Writes `moves` (each with the tool that runs it) as APT CL data for part `part_name`.
pub fn write_apt(part_name: &str, moves: &[(AptTool, Move)]) -> String {
    let name: String = part_name
        .chars()
        .map(|c| {
            if c.is_ascii_graphic() || c == ' ' {
                c
            } else {
                '_'
            }
        })
        .collect();
    let mut s = String::with_capacity(80 * (moves.len() + 8));
    s.push_str("$$ wavemill cutter-location data: tip and unit tool axis in the part frame, mm\n");
    s.push_str(&format!("PARTNO/{name}\n"));
    s.push_str("UNITS/MM\nMULTAX/ON\n");
    let mut tool: Option<u32> = None;
    let mut feed: Option<String> = None;
    let number = |v: f64| fixed(v, CL_DECIMALS);
    for (t, m) in moves {
        if tool != Some(t.number) {
            s.push_str(&format!(
                "LOADTL/{}\nCUTTER/{},{}\n",
                t.number,
                fixed(t.diameter, 6),
                fixed(t.corner_radius, 6)
            ));
            tool = Some(t.number);
            feed = None;
        }
        if m.kind == MoveKind::Rapid {
            s.push_str("RAPID\n");
        } else {
            let f = fixed(m.feed, CL_FEED_DECIMALS);
            if feed.as_deref() != Some(f.as_str()) {
                s.push_str(&format!("FEDRAT/MMPM,{f}\n"));
                feed = Some(f);
            }
        }
        let (p, k) = (m.pose.tip, m.pose.axis);
        s.push_str(&format!(
            "GOTO/{},{},{},{},{},{}\n",
            number(p.x),
            number(p.y),
            number(p.z),
            number(k.x),
            number(k.y),
            number(k.z)
        ));
    }
    s.push_str("FINI\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::post::tests::toolpath;

    /// Read back with a reader written here: one GOTO per move with its values, RAPID exactly
    /// before the rapids, the feed in force on every feed move, a tool change where the tool
    /// changes.
    #[test]
    fn apt_reads_back_as_the_moves() {
        let path = toolpath(&[
            (MoveKind::Rapid, 0.0, [1.0, -2.0, 50.0], [0.0, 0.0, 1.0]),
            (
                MoveKind::Approach,
                300.0,
                [1.0, -2.0, 10.0],
                [0.0, 0.6, 0.8],
            ),
            (MoveKind::Cut, 1200.0, [3.25, -2.0, 9.5], [0.0, 0.6, 0.8]),
            (MoveKind::Cut, 1200.0, [-0.0, -2.5, 9.0], [0.6, 0.0, 0.8]),
            (
                MoveKind::Retract,
                2000.0,
                [0.0, -2.5, 40.0],
                [0.6, 0.0, 0.8],
            ),
        ]);
        let ball = AptTool {
            number: 1,
            diameter: 4.0,
            corner_radius: 2.0,
        };
        let flat = AptTool {
            number: 7,
            corner_radius: 0.0,
            ..ball
        };
        let rows: Vec<(AptTool, Move)> = path
            .moves
            .iter()
            .enumerate()
            .map(|(i, m)| (if i < 3 { ball } else { flat }, *m))
            .collect();
        let text = write_apt("dome", &rows);
        assert!(!text.contains("-0.000000000"));
        let mut rapid = false;
        let mut feed = None;
        let mut tools = Vec::new();
        let mut read = Vec::new();
        for line in text.lines() {
            if let Some(v) = line.strip_prefix("GOTO/") {
                let v: Vec<f64> = v.split(',').map(|x| x.parse().unwrap()).collect();
                read.push((v, rapid, feed));
                rapid = false;
            } else if line == "RAPID" {
                rapid = true;
            } else if let Some(f) = line.strip_prefix("FEDRAT/MMPM,") {
                feed = Some(f.parse::<f64>().unwrap());
            } else if let Some(t) = line.strip_prefix("LOADTL/") {
                tools.push(t.parse::<u32>().unwrap());
            }
        }
        assert_eq!(tools, [1, 7]);
        assert_eq!(read.len(), path.moves.len());
        for ((v, was_rapid, f), m) in read.iter().zip(&path.moves) {
            let want = [
                m.pose.tip.x,
                m.pose.tip.y,
                m.pose.tip.z,
                m.pose.axis.x,
                m.pose.axis.y,
                m.pose.axis.z,
            ];
            for (a, b) in v.iter().zip(want) {
                assert!((a - b).abs() <= 5e-10, "{v:?} vs {want:?}");
            }
            assert_eq!(*was_rapid, m.kind == MoveKind::Rapid);
            if m.kind != MoveKind::Rapid {
                assert_eq!(*f, Some(m.feed));
            }
        }
        assert!(text.ends_with("FINI\n"));
    }
}
