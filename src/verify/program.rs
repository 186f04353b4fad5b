//! Reading a posted G-code program back as a control would: modal motion, absolute axis
//! words, tool length compensation. Written for the verifier alone: it shares nothing with the
//! writer in `post`, so what it reads is what the file says, not what the post meant.
//!
//! Only what the 5-axis post writes is accepted: G0/G1 in absolute millimetres with feed per
//! minute (`G94`) or inverse time (`G93`, where a `G1` without its own `F` is refused as a
//! control refuses it), length compensation `G43`/`G49` or Siemens `D`, tool-centre-point
//! control `G43.4` (Fanuc) or `TRAORI`/`TRAFOOF` (Siemens); and Heidenhain conversational `L`
//! blocks ([`read_conversational`]). Anything else a control would do differently (arcs,
//! inches, incremental moves, canned cycles) is refused with its line number rather than
//! guessed at.

/// One motion block: where the axes go and how.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionBlock {
    /// 1-based line number in the program text.
    pub line: usize,
    /// `true` for G0 (positioning), `false` for G1 (feed).
    pub rapid: bool,
    /// X, Y, Z (mm) and the two rotary axes (degrees) after the block; `None` for an axis the
    /// program has not commanded yet.
    pub axes: [Option<f64>; 5],
    /// Whether tool length compensation (G43) was on for this block.
    pub length_compensation: bool,
    /// The tool in the spindle: the `T` word of the last tool change (`M6`) before the block,
    /// `None` before the first.
    pub tool: Option<u32>,
    /// Whether tool-centre-point control was on (`G43.4`, `TRAORI`, `FUNCTION TCPM`).
    pub tcp: bool,
    /// The block's feed word in force: mm/min, or 1/min in inverse time; `None` for a rapid.
    pub feed: Option<f64>,
    /// Whether the feed is inverse time (`G93`).
    pub inverse_time: bool,
}

/// A line the reader cannot take.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("line {line}: {reason}")]
pub struct ProgramError {
    pub line: usize,
    pub reason: String,
}

/// Reads `text` with the axis letters `axes` (e.g. `['X', 'Y', 'Z', 'A', 'C']`) into its
/// motion blocks.
pub fn read_program(text: &str, axes: [char; 5]) -> Result<Vec<MotionBlock>, ProgramError> {
    let mut blocks = Vec::new();
    let mut position: [Option<f64>; 5] = [None; 5];
    let mut motion: Option<bool> = None;
    let mut compensation = false;
    let mut tcp = false;
    let mut inverse_time = false;
    let mut feed: Option<f64> = None;
    let mut selected: Option<u32> = None;
    let mut spindle: Option<u32> = None;
    for (index, raw) in text.lines().enumerate() {
        let line = index + 1;
        let fail = |reason: String| ProgramError { line, reason };
        let code = strip_comments(raw).map_err(|r| fail(r.into()))?;
        let code = code.trim();
        if code.is_empty() || code == "%" {
            continue;
        }
        // Siemens keywords stand in blocks of their own.
        match code {
            "TRAORI" => {
                tcp = true;
                continue;
            }
            "TRAFOOF" => {
                tcp = false;
                continue;
            }
            _ => {}
        }
        let mut feed_word = None;
        let mut moved = false;
        let mut target = position;
        let words = words(code).map_err(fail)?;
        // T selects a tool, M6 puts the selected one in the spindle (both may share a line).
        for &(letter, value) in &words {
            if letter == 'T' {
                if !(value >= 0.0 && value.fract() == 0.0 && value <= u32::MAX as f64) {
                    return Err(fail(format!("T{value} is not a tool number")));
                }
                selected = Some(value as u32);
            }
        }
        if words.iter().any(|&(l, v)| l == 'M' && v == 6.0) {
            spindle = Some(selected.ok_or_else(|| fail("M6 without a tool selected (T)".into()))?);
        }
        for (letter, value) in words {
            match letter {
                'G' if value == 43.4 => {
                    compensation = true;
                    tcp = true;
                }
                'G' if value.fract() != 0.0 => {
                    return Err(fail(format!("G{value} is not read by the verifier")));
                }
                'G' => match value as i64 {
                    0 => motion = Some(true),
                    1 => motion = Some(false),
                    43 => compensation = true,
                    49 => {
                        compensation = false;
                        tcp = false;
                    }
                    93 => inverse_time = true,
                    94 => inverse_time = false,
                    // Metric (G21, Siemens G71), absolute, XY plane, no cutter compensation, no
                    // canned cycle: the state the post assumes.
                    21 | 71 | 90 | 17 | 40 | 80 => {}
                    other => return Err(fail(format!("G{other} is not read by the verifier"))),
                },
                // Siemens: D selects the tool's offset (length compensation), D0 none.
                'D' => compensation = value != 0.0,
                'F' => {
                    if !(value.is_finite() && value > 0.0) {
                        return Err(fail(format!("F{value} is not a usable feed")));
                    }
                    feed_word = Some(value);
                }
                'X' | 'Y' | 'Z' | 'A' | 'B' | 'C' => {
                    let Some(slot) = axes.iter().position(|&a| a == letter) else {
                        return Err(fail(format!(
                            "axis {letter} is not an axis of this machine"
                        )));
                    };
                    if !value.is_finite() {
                        return Err(fail(format!("{letter} is not a finite number")));
                    }
                    target[slot] = Some(value);
                    moved = true;
                }
                // Tool, length-offset register, spindle, miscellaneous, block number.
                'T' | 'H' | 'S' | 'M' | 'N' => {}
                other => return Err(fail(format!("word {other} is not read by the verifier"))),
            }
        }
        if let Some(f) = feed_word {
            feed = Some(f);
        }
        if moved {
            let Some(rapid) = motion else {
                return Err(fail("axis words before any G0/G1".into()));
            };
            if !rapid && inverse_time && feed_word.is_none() {
                return Err(fail("G1 without F in inverse time (G93)".into()));
            }
            if !rapid && feed.is_none() {
                return Err(fail("G1 before any F".into()));
            }
            blocks.push(MotionBlock {
                line,
                rapid,
                axes: target,
                length_compensation: compensation,
                tool: spindle,
                tcp,
                feed: if rapid { None } else { feed },
                inverse_time,
            });
            position = target;
        }
    }
    Ok(blocks)
}

/// Reads a Heidenhain conversational program (`BEGIN PGM` … `END PGM`, numbered blocks) with
/// the axis letters `axes` into its motion blocks: `L` blocks (`FMAX` a rapid for its block
/// only, `F` modal), `TOOL CALL n Z …` (the tool in the spindle, its length applied),
/// `FUNCTION TCPM …` / `FUNCTION RESET TCPM`, `;` comments. Block numbers must count up from 0.
pub fn read_conversational(text: &str, axes: [char; 5]) -> Result<Vec<MotionBlock>, ProgramError> {
    let mut blocks = Vec::new();
    let mut position: [Option<f64>; 5] = [None; 5];
    let mut tool = None;
    let mut tcp = false;
    let mut feed: Option<f64> = None;
    let mut expected_number = 0usize;
    let mut ended = false;
    for (index, raw) in text.lines().enumerate() {
        let line = index + 1;
        let fail = |reason: String| ProgramError { line, reason };
        let raw = raw.trim();
        if raw.is_empty() {
            continue;
        }
        if ended {
            return Err(fail("text after END PGM".into()));
        }
        let (number, rest) = raw.split_once(' ').unwrap_or((raw, ""));
        if number.parse::<usize>().ok() != Some(expected_number) {
            return Err(fail(format!(
                "block number {number}, expected {expected_number}"
            )));
        }
        expected_number += 1;
        let rest = rest.trim();
        let tokens: Vec<&str> = rest.split_whitespace().collect();
        match tokens.as_slice() {
            [] => return Err(fail("empty block".into())),
            [first, ..] if first.starts_with(';') => continue,
            ["BEGIN", "PGM", _, "MM"] => {
                if line_index_is_not_first(&blocks, expected_number) {
                    return Err(fail("BEGIN PGM not first".into()));
                }
                continue;
            }
            ["BEGIN", "PGM", ..] => return Err(fail("only MM programs are read".into())),
            ["END", "PGM", ..] => {
                ended = true;
                continue;
            }
            ["TOOL", "CALL", n, "Z", extra @ ..] => {
                let t: u32 = n
                    .parse()
                    .map_err(|_| fail(format!("TOOL CALL {n}: not a tool number")))?;
                if extra.iter().any(|w| !w.starts_with('S')) {
                    return Err(fail(format!("TOOL CALL words {extra:?} are not read")));
                }
                tool = Some(t);
                continue;
            }
            ["TOOL", "CALL", ..] => {
                return Err(fail("TOOL CALL along an axis other than Z".into()));
            }
            [
                "FUNCTION",
                "TCPM",
                "F",
                "TCP",
                "AXIS",
                "POS",
                "PATHCTRL",
                "AXIS",
            ] => {
                tcp = true;
                continue;
            }
            ["FUNCTION", "TCPM", ..] => {
                return Err(fail(
                    "FUNCTION TCPM other than F TCP AXIS POS PATHCTRL AXIS".into(),
                ));
            }
            ["FUNCTION", "RESET", "TCPM"] => {
                tcp = false;
                continue;
            }
            ["L", words @ ..] => {
                let mut target = position;
                let mut rapid = false;
                let mut moved = false;
                for w in words {
                    // By characters: a word may begin with any letter a file holds.
                    let mut chars = w.chars();
                    let letter = chars.next().unwrap_or(' ');
                    let value = chars.as_str();
                    match (letter, value) {
                        ('R', "0") => {}
                        ('F', "MAX") => rapid = true,
                        ('M', m) if m.parse::<u32>().is_ok() => {}
                        ('F', f) => {
                            let f: f64 = f
                                .parse()
                                .map_err(|_| fail(format!("F{f} is not a number")))?;
                            if !(f.is_finite() && f > 0.0) {
                                return Err(fail(format!("F{f} is not a usable feed")));
                            }
                            feed = Some(f);
                        }
                        (l, v) if axes.contains(&l) => {
                            if !(v.starts_with('+') || v.starts_with('-')) {
                                return Err(fail(format!("{w}: coordinates carry their sign")));
                            }
                            let v: f64 = v
                                .parse()
                                .map_err(|_| fail(format!("{w} is not a coordinate")))?;
                            if !v.is_finite() {
                                return Err(fail(format!("{w} is not finite")));
                            }
                            let slot = axes.iter().position(|&a| a == l).unwrap_or(0);
                            target[slot] = Some(v);
                            moved = true;
                        }
                        _ => return Err(fail(format!("word {w} is not read by the verifier"))),
                    }
                }
                if !rapid && feed.is_none() && moved {
                    return Err(fail("L block before any F".into()));
                }
                if moved {
                    blocks.push(MotionBlock {
                        line,
                        rapid,
                        axes: target,
                        // TOOL CALL applies the tool table's length.
                        length_compensation: tool.is_some(),
                        tool,
                        tcp,
                        feed: if rapid { None } else { feed },
                        inverse_time: false,
                    });
                    position = target;
                }
            }
            _ => return Err(fail(format!("block '{rest}' is not read by the verifier"))),
        }
    }
    if !ended {
        return Err(ProgramError {
            line: text.lines().count(),
            reason: "no END PGM".into(),
        });
    }
    Ok(blocks)
}

/// `BEGIN PGM` must be block 0 (`expected_number` already counts it).
fn line_index_is_not_first(blocks: &[MotionBlock], expected_number: usize) -> bool {
    !blocks.is_empty() || expected_number != 1
}

/// The line without `( … )` and `; …` comments.
fn strip_comments(line: &str) -> Result<String, &'static str> {
    let mut out = String::with_capacity(line.len());
    let mut depth = false;
    for ch in line.chars() {
        match ch {
            '(' if depth => return Err("nested comment"),
            '(' => depth = true,
            ')' if depth => depth = false,
            ')' => return Err("')' without '('"),
            ';' if !depth => break,
            c if !depth => out.push(c),
            _ => {}
        }
    }
    if depth {
        return Err("comment not closed");
    }
    Ok(out)
}

/// The words of a block: a letter and a number each, spaces allowed between words.
fn words(code: &str) -> Result<Vec<(char, f64)>, String> {
    let mut out = Vec::new();
    let mut chars = code.chars().peekable();
    while let Some(ch) = chars.next() {
        if ch.is_whitespace() {
            continue;
        }
        if !ch.is_ascii_alphabetic() {
            return Err(format!("unexpected '{ch}'"));
        }
        let mut number = String::new();
        while let Some(&c) = chars.peek() {
            if c.is_ascii_digit() || c == '.' || c == '-' || c == '+' {
                number.push(c);
                chars.next();
            } else if c == ' ' && number.is_empty() {
                chars.next();
            } else {
                break;
            }
        }
        let value: f64 = number
            .parse()
            .map_err(|_| format!("word {ch} has no number ('{number}')"))?;
        out.push((ch.to_ascii_uppercase(), value));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const AC: [char; 5] = ['X', 'Y', 'Z', 'A', 'C'];

    #[test]
    fn modal_motion_and_axis_words_carry_over() {
        let text = "%\n(comment (with text)\nG21 G90 G94\nG0 G43 H1 Z50.0\nX1 Y2 A3 C4\nG1 X1.5 F100 ; feed\nY-2.25\n%\n";
        let text = text.replace("(comment (with text)", "(comment [with text])");
        let blocks = read_program(&text, AC).unwrap();
        assert_eq!(blocks.len(), 4);
        assert_eq!(blocks[0].axes, [None, None, Some(50.0), None, None]);
        assert!(blocks[0].rapid && blocks[0].length_compensation);
        assert_eq!(
            blocks[1].axes,
            [Some(1.0), Some(2.0), Some(50.0), Some(3.0), Some(4.0)]
        );
        assert!(!blocks[2].rapid);
        assert_eq!(blocks[3].axes[1], Some(-2.25));
        assert_eq!(blocks[3].line, 7);
    }

    #[test]
    fn what_a_control_would_do_differently_is_refused_with_its_line() {
        for (text, line) in [
            ("G0 X1\nG2 X1 Y1 I1\n", 2),
            ("G20\n", 1),
            ("G0 X1 B2\n", 1),
            ("X1\n", 1),
            ("G0 X1 (open\n", 1),
            ("G0 Xabc\n", 1),
            ("G0 X1\nM6\n", 2),
            ("T1.5 M6\n", 1),
        ] {
            let e = read_program(text, AC).unwrap_err();
            assert_eq!(e.line, line, "{text}: {e}");
        }
    }

    /// A motion belongs to the tool of the last `M6`, whatever `T` was selected since (a
    /// control may preselect the next tool).
    #[test]
    fn each_block_knows_the_tool_in_the_spindle() {
        let text = "G0 X0 Y0 Z9\nT3 M6\nG0 X1\nT7\nG1 X2 F100\nM6\nG0 X3\n";
        let tools: Vec<Option<u32>> = read_program(text, AC)
            .unwrap()
            .iter()
            .map(|b| b.tool)
            .collect();
        assert_eq!(tools, [None, Some(3), Some(3), Some(7)]);
    }

    /// Inverse time: a G1 without its own F is refused as a control refuses it; TCP and length
    /// compensation states follow G43.4 / G49 and Siemens' D, TRAORI and TRAFOOF.
    #[test]
    fn inverse_time_tcp_and_siemens_states_are_read() {
        let text = "G21 G90 G93\nG0 G43.4 H1 Z50\nX1 Y2 A3 C4\nG1 X2 F12.5\nX3\n";
        let e = read_program(text, AC).unwrap_err();
        assert_eq!(e.line, 5, "{e}");
        let blocks = read_program(&text.replace("X3", "X3 F7"), AC).unwrap();
        assert!(
            blocks
                .iter()
                .all(|b| b.tcp && b.length_compensation && b.inverse_time)
        );
        assert_eq!(blocks[3].feed, Some(7.0));
        let siemens =
            "G71 G90 G94\nT1 M6\nD1\nTRAORI\nG0 Z50\nG1 X1 Y1 A1 C1 F900\nTRAFOOF\nD0\nG0 Z60\n";
        let blocks = read_program(siemens, AC).unwrap();
        assert!(blocks[0].tcp && blocks[0].length_compensation);
        assert!(!blocks[2].tcp && !blocks[2].length_compensation);
        assert_eq!(blocks[1].feed, Some(900.0));
    }

    /// Conversational: numbered blocks, signed coordinates, FMAX for one block, F modal, and
    /// anything else refused with its line.
    #[test]
    fn conversational_programs_are_read_and_refused_by_line() {
        let text = "0 BEGIN PGM W MM\n1 ; c\n2 TOOL CALL 3 Z S9000\n3 FUNCTION TCPM F TCP AXIS POS PATHCTRL AXIS\n4 L Z+50.0000 R0 FMAX M3\n5 L X+1.0000 Y-2.0000 A+3.0000 C+4.0000 R0 FMAX\n6 L Z+10.0000 R0 F500\n7 L X+2.0000 R0\n8 FUNCTION RESET TCPM\n9 END PGM W MM\n";
        let blocks = read_conversational(text, AC).unwrap();
        assert_eq!(blocks.len(), 4);
        assert!(blocks[0].rapid && blocks[1].rapid && !blocks[2].rapid && !blocks[3].rapid);
        assert_eq!(blocks[3].feed, Some(500.0));
        assert!(blocks.iter().all(|b| b.tcp && b.tool == Some(3)));
        assert_eq!(
            blocks[3].axes,
            [Some(2.0), Some(-2.0), Some(10.0), Some(3.0), Some(4.0)]
        );
        for (edit, line) in [
            (text.replace("7 L X+2.0000", "8 L X+2.0000"), 8),
            (text.replace("X+2.0000 R0", "X2.0000 R0"), 8),
            (text.replace("6 L Z+10.0000 R0 F500", "6 L Z+10.0000 R0"), 7),
            (text.replace("9 END PGM W MM\n", ""), 9),
            (text.replace("R0 F500", "R0 F500 G1"), 7),
            (text.replace("R0 F500", "R0 F500 Ä1"), 7),
        ] {
            let e = read_conversational(&edit, AC).unwrap_err();
            assert_eq!(e.line, line, "{e}");
        }
    }
}
