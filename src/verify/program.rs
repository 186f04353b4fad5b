//! Reading a posted G-code program back as a control would: modal motion, absolute axis
//! words, tool length compensation. Written for the verifier alone: it shares nothing with the
//! writer in `post`, so what it reads is what the file says, not what the post meant.
//!
//! Only the dialect the 5-axis post writes is accepted (G0/G1 in absolute millimetres with feed
//! per minute); anything else a control would do differently (arcs, inverse-time feed, inches,
//! incremental moves, canned cycles) is refused with its line number rather than guessed at.

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
                'G' if value.fract() != 0.0 => {
                    return Err(fail(format!("G{value} is not read by the verifier")));
                }
                'G' => match value as i64 {
                    0 => motion = Some(true),
                    1 => motion = Some(false),
                    43 => compensation = true,
                    49 => compensation = false,
                    // Metric, absolute, feed per minute, XY plane, no cutter compensation, no
                    // canned cycle: the state the post assumes.
                    21 | 90 | 94 | 17 | 40 | 80 => {}
                    other => return Err(fail(format!("G{other} is not read by the verifier"))),
                },
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
                // Feed, tool, length-offset register, spindle, miscellaneous, block number.
                'F' | 'T' | 'H' | 'S' | 'M' | 'N' => {}
                other => return Err(fail(format!("word {other} is not read by the verifier"))),
            }
        }
        if moved {
            let Some(rapid) = motion else {
                return Err(fail("axis words before any G0/G1".into()));
            };
            blocks.push(MotionBlock {
                line,
                rapid,
                axes: target,
                length_compensation: compensation,
                tool: spindle,
            });
            position = target;
        }
    }
    Ok(blocks)
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
}
