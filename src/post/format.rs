//! Number formatting shared by the writers: fixed decimals, never a negative zero.

/// Decimals of an inverse-time `F` (1/min).
pub const INVERSE_TIME_DECIMALS: usize = 4;

/// Formats `v` with `decimals` fixed decimals; a value that rounds to zero is written without
/// a sign (`"-0.0000"` never appears). Non-finite values are written as `0` followed by the
/// decimals (callers validate beforehand; this keeps the output parseable).
pub fn fixed(v: f64, decimals: usize) -> String {
    let v = if v.is_finite() { v } else { 0.0 };
    let s = format!("{v:.decimals$}");
    match s.strip_prefix('-') {
        Some(rest) if rest.bytes().all(|b| b == b'0' || b == b'.') => rest.to_string(),
        _ => s,
    }
}

/// Makes `text` safe inside a G-code comment: parentheses become brackets, control characters
/// become spaces.
pub fn comment_text(text: &str) -> String {
    text.chars()
        .map(|ch| match ch {
            '(' => '[',
            ')' => ']',
            c if c.is_control() => ' ',
            c => c,
        })
        .collect()
}
