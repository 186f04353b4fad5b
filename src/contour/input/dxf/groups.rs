//! DXF group-code pairs from ASCII or binary files.
//!
//! A DXF file is a flat sequence of (group code, value) pairs; the code says what the value
//! means and, by its range, which type it has (the DXF reference's "group code value types":
//! 10–59 reals, 60–79 16-bit integers, 90–99 32-bit integers, …). ASCII DXF writes each code and
//! value on a line of its own; binary DXF starts with the sentinel `AutoCAD Binary DXF\r\n\x1a\0`
//! and writes codes as 2 little-endian bytes (R13 and later) or 1 byte with 255 escaping a
//! 2-byte code (R12), strings NUL-terminated, numbers little-endian.
//!
//! Every pair remembers where it stands in the file (line or byte), so the reader above can name
//! the place of a bad entity; a malformed value is an error naming its place, never a panic.

use std::fmt;

/// Where a pair stands in its file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Place {
    /// 1-based line of the group code in an ASCII file.
    Line(usize),
    /// Byte offset of the group code in a binary file.
    Byte(usize),
}

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Place::Line(n) => write!(f, "line {n}"),
            Place::Byte(n) => write!(f, "byte {n}"),
        }
    }
}

/// A group value, typed by its code's range.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Value {
    Text(String),
    Real(f64),
    Integer(i64),
    /// Binary chunks (codes 310–319, 1004); nothing an outline needs.
    Bytes,
}

/// One (group code, value) pair.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Group {
    pub code: i32,
    pub value: Value,
    pub place: Place,
}

impl Group {
    pub fn text(&self) -> &str {
        match &self.value {
            Value::Text(s) => s,
            _ => "",
        }
    }

    pub fn is(&self, code: i32, text: &str) -> bool {
        self.code == code && self.text() == text
    }

    pub fn real(&self) -> Option<f64> {
        match self.value {
            Value::Real(v) => Some(v),
            // Integers stand in for reals nowhere in valid files; accepting them costs nothing.
            Value::Integer(i) => Some(i as f64),
            _ => None,
        }
    }

    pub fn integer(&self) -> Option<i64> {
        match self.value {
            Value::Integer(i) => Some(i),
            _ => None,
        }
    }

    /// The real, or an error naming the pair.
    pub fn number(&self) -> Result<f64, String> {
        self.real()
            .ok_or_else(|| format!("{}: group {} is not a number", self.place, self.code))
    }

    /// The integer, or an error naming the pair.
    pub fn whole_number(&self) -> Result<i64, String> {
        self.integer()
            .ok_or_else(|| format!("{}: group {} is not an integer", self.place, self.code))
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Text,
    Real,
    Short,
    Int32,
    Int64,
    Bool,
    Bytes,
}

/// The value type of a group code (DXF reference, "Group code value types"); `None` for codes
/// the reference does not define.
fn kind_of(code: i32) -> Option<Kind> {
    Some(match code {
        0..=9
        | 100..=102
        | 105
        | 300..=309
        | 320..=369
        | 390..=399
        | 410..=419
        | 430..=439
        | 470..=481
        | 999
        | 1000..=1003
        | 1005..=1009 => Kind::Text,
        10..=59 | 110..=149 | 210..=239 | 460..=469 | 1010..=1059 => Kind::Real,
        60..=79 | 170..=179 | 270..=289 | 370..=389 | 400..=409 | 1060..=1070 => Kind::Short,
        90..=99 | 420..=429 | 440..=459 | 1071 => Kind::Int32,
        160..=169 => Kind::Int64,
        290..=299 => Kind::Bool,
        310..=319 | 1004 => Kind::Bytes,
        _ => return None,
    })
}

const BINARY_SENTINEL: &[u8] = b"AutoCAD Binary DXF\r\n\x1a\0";

/// All pairs of a DXF file, ASCII or binary. `Err` says what is wrong and where.
pub(super) fn read_groups(bytes: &[u8]) -> Result<Vec<Group>, String> {
    match bytes.strip_prefix(BINARY_SENTINEL) {
        Some(rest) => Binary::new(rest, BINARY_SENTINEL.len()).read_all(),
        None => read_ascii(bytes),
    }
}

fn read_ascii(bytes: &[u8]) -> Result<Vec<Group>, String> {
    // Text values only name entities and layers here; older files write them in the drawing's
    // code page, which a lossy decode keeps readable enough for a message.
    let text = String::from_utf8_lossy(bytes);
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    let mut lines: Vec<&str> = text
        .split('\n')
        .map(|l| l.strip_suffix('\r').unwrap_or(l))
        .collect();
    // The newline that ends the last line starts no line of its own.
    if lines.last() == Some(&"") {
        lines.pop();
    }
    let mut groups = Vec::new();
    let mut at = 0;
    while at < lines.len() {
        let code_text = lines[at].trim();
        let line = at + 1;
        if code_text.is_empty() {
            // Blank lines after the last pair (an editor's trailing newlines) end the file.
            if lines[at..].iter().all(|l| l.trim().is_empty()) {
                break;
            }
            return Err(format!(
                "line {line}: a blank line where a group code belongs"
            ));
        }
        let code: i32 = code_text
            .parse()
            .map_err(|_| format!("line {line}: \"{code_text}\" is not a group code"))?;
        let Some(value_line) = lines.get(at + 1) else {
            return Err(format!("line {line}: group code {code} has no value"));
        };
        let value = ascii_value(code, value_line).map_err(|expected| {
            format!(
                "line {}: group code {code} expects {expected}, found \"{}\"",
                line + 1,
                value_line.trim()
            )
        })?;
        at += 2;
        let end = matches!(&value, Value::Text(s) if code == 0 && s == "EOF");
        groups.push(Group {
            code,
            value,
            place: Place::Line(line),
        });
        if end {
            break;
        }
    }
    Ok(groups)
}

fn ascii_value(code: i32, raw: &str) -> Result<Value, &'static str> {
    let trimmed = raw.trim();
    Ok(match kind_of(code) {
        // Unknown codes (application extensions) are kept as text; nothing here reads them.
        Some(Kind::Text) | None => Value::Text(trimmed.to_string()),
        Some(Kind::Real) => Value::Real(trimmed.parse().map_err(|_| "a number")?),
        Some(Kind::Short | Kind::Int32 | Kind::Int64 | Kind::Bool) => {
            Value::Integer(parse_integer(trimmed).ok_or("an integer")?)
        }
        Some(Kind::Bytes) => Value::Bytes,
    })
}

/// An integer, also when an exporter wrote it with a zero fraction ("1.0").
fn parse_integer(s: &str) -> Option<i64> {
    if let Ok(i) = s.parse::<i64>() {
        return Some(i);
    }
    let v: f64 = s.parse().ok()?;
    (v.fract() == 0.0 && v.abs() < 9.0e15).then_some(v as i64)
}

/// A cursor over a binary DXF body.
struct Binary<'a> {
    bytes: &'a [u8],
    at: usize,
    /// Offset of `bytes[0]` in the file, for messages.
    base: usize,
}

impl<'a> Binary<'a> {
    fn new(bytes: &'a [u8], base: usize) -> Self {
        Self { bytes, at: 0, base }
    }

    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let Some(end) = end else {
            return Err(format!(
                "byte {}: the file ends inside a value",
                self.base + self.at
            ));
        };
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], String> {
        let mut out = [0u8; N];
        out.copy_from_slice(self.take(N)?);
        Ok(out)
    }

    fn string(&mut self) -> Result<String, String> {
        let rest = &self.bytes[self.at..];
        let Some(len) = rest.iter().position(|&b| b == 0) else {
            return Err(format!(
                "byte {}: a string without its terminating NUL",
                self.base + self.at
            ));
        };
        let s = String::from_utf8_lossy(&rest[..len]).into_owned();
        self.at += len + 1;
        Ok(s)
    }

    fn read_all(mut self) -> Result<Vec<Group>, String> {
        // The first pair is (0, "SECTION"): its code is one byte 0x00 followed by 'S' in R12
        // files, two bytes 0x00 0x00 in later ones.
        let two_byte_codes = self.bytes.get(1) == Some(&0);
        let mut groups = Vec::new();
        while self.at < self.bytes.len() {
            let place = Place::Byte(self.base + self.at);
            let code = if two_byte_codes {
                i32::from(i16::from_le_bytes(self.array()?))
            } else {
                match self.array::<1>()?[0] {
                    255 => i32::from(i16::from_le_bytes(self.array()?)),
                    c => i32::from(c),
                }
            };
            let Some(kind) = kind_of(code) else {
                return Err(format!(
                    "{place}: group code {code} is not a DXF group code (the binary value's size is unknown)"
                ));
            };
            let value = match kind {
                Kind::Text => Value::Text(self.string()?),
                Kind::Real => Value::Real(f64::from_le_bytes(self.array()?)),
                Kind::Short => Value::Integer(i64::from(i16::from_le_bytes(self.array()?))),
                Kind::Int32 => Value::Integer(i64::from(i32::from_le_bytes(self.array()?))),
                Kind::Int64 => Value::Integer(i64::from_le_bytes(self.array()?)),
                // One byte from R13 on, a 16-bit integer before.
                Kind::Bool if two_byte_codes => Value::Integer(i64::from(self.array::<1>()?[0])),
                Kind::Bool => Value::Integer(i64::from(i16::from_le_bytes(self.array()?))),
                Kind::Bytes => {
                    let n = usize::from(self.array::<1>()?[0]);
                    self.take(n)?;
                    Value::Bytes
                }
            };
            let end = matches!(&value, Value::Text(s) if code == 0 && s == "EOF");
            groups.push(Group { code, value, place });
            if end {
                break;
            }
        }
        Ok(groups)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ascii_pairs_are_typed_by_their_code() {
        let text = "  0\r\nSECTION\r\n  2\r\nENTITIES\r\n 10\r\n 1.5e1\r\n 70\r\n     1\r\n 62\r\n1.0\r\n  8\r\n Layer 1 \r\n\r\n";
        let g = read_groups(text.as_bytes()).unwrap();
        assert_eq!(g.len(), 6);
        assert!(g[0].is(0, "SECTION") && g[1].is(2, "ENTITIES"));
        assert_eq!((g[2].real(), g[2].place), (Some(15.0), Place::Line(5)));
        assert_eq!(g[3].integer(), Some(1));
        // A 16-bit integer written with a zero fraction.
        assert_eq!((g[4].code, g[4].integer()), (62, Some(1)));
        assert_eq!(g[5].text(), "Layer 1");
    }

    #[test]
    fn ascii_errors_name_the_line() {
        let e = read_groups(b"0\nLINE\n10\nabc\n").unwrap_err();
        assert!(
            e.contains("line 4") && e.contains("number") && e.contains("abc"),
            "{e}"
        );
        let e = read_groups(b"0\nLINE\nten\n1\n").unwrap_err();
        assert!(e.contains("line 3") && e.contains("group code"), "{e}");
        let e = read_groups(b"0\nLINE\n10\n").unwrap_err();
        assert!(e.contains("has no value"), "{e}");
        let e = read_groups(b"0\nLINE\n\n10\n1\n").unwrap_err();
        assert!(e.contains("line 3") && e.contains("blank"), "{e}");
        // Nothing after EOF is read.
        assert_eq!(read_groups(b"0\nEOF\ngarbage").unwrap().len(), 1);
    }

    /// A binary body written by hand, byte by byte from the DXF reference's layout, in both
    /// code widths.
    #[test]
    fn binary_pairs_in_both_code_widths() {
        let mut r13 = BINARY_SENTINEL.to_vec();
        r13.extend([0, 0]);
        r13.extend(b"SECTION\0");
        r13.extend([10, 0]);
        r13.extend(2.5f64.to_le_bytes());
        r13.extend([70, 0]);
        r13.extend((-3i16).to_le_bytes());
        r13.extend([90, 0]);
        r13.extend(70000i32.to_le_bytes());
        r13.extend([0x22, 0x01]); // 290, a one-byte boolean
        r13.push(1);
        r13.extend([0x36, 0x01, 3, 0xaa, 0xbb, 0xcc]); // 310, three bytes of binary chunk
        r13.extend([0xa0, 0x00]); // 160, 64-bit
        r13.extend((1i64 << 40).to_le_bytes());
        r13.extend([0, 0]);
        r13.extend(b"EOF\0");
        r13.extend(b"trailing bytes are ignored");
        let g = read_groups(&r13).unwrap();
        let values: Vec<(i32, Value)> = g.iter().map(|g| (g.code, g.value.clone())).collect();
        assert_eq!(
            values,
            vec![
                (0, Value::Text("SECTION".into())),
                (10, Value::Real(2.5)),
                (70, Value::Integer(-3)),
                (90, Value::Integer(70000)),
                (290, Value::Integer(1)),
                (310, Value::Bytes),
                (160, Value::Integer(1 << 40)),
                (0, Value::Text("EOF".into())),
            ]
        );
        assert_eq!(g[1].place, Place::Byte(BINARY_SENTINEL.len() + 10));

        let mut r12 = BINARY_SENTINEL.to_vec();
        r12.push(0);
        r12.extend(b"SECTION\0");
        r12.push(40);
        r12.extend((-1.25f64).to_le_bytes());
        r12.extend([255, 0xe8, 0x03]); // 1000 through the escape
        r12.extend(b"x\0");
        r12.extend([255, 0x22, 0x01]); // 290: a 16-bit boolean before R13
        r12.extend(1i16.to_le_bytes());
        let g = read_groups(&r12).unwrap();
        let values: Vec<(i32, Value)> = g.iter().map(|g| (g.code, g.value.clone())).collect();
        assert_eq!(
            values,
            vec![
                (0, Value::Text("SECTION".into())),
                (40, Value::Real(-1.25)),
                (1000, Value::Text("x".into())),
                (290, Value::Integer(1)),
            ]
        );
    }

    #[test]
    fn truncated_binary_is_an_error_not_a_panic() {
        let mut b = BINARY_SENTINEL.to_vec();
        b.extend([0, 0]);
        b.extend(b"SECTION\0");
        b.extend([10, 0, 1, 2, 3]);
        let e = read_groups(&b).unwrap_err();
        assert!(e.contains("ends inside a value"), "{e}");
        let mut b = BINARY_SENTINEL.to_vec();
        b.extend([0, 0]);
        b.extend(b"SECTION");
        assert!(read_groups(&b).unwrap_err().contains("NUL"));
        let mut b = BINARY_SENTINEL.to_vec();
        b.extend([0, 0]);
        b.extend(b"SECTION\0");
        b.extend([0xd0, 0x07, 0]); // 2000: no such code
        assert!(
            read_groups(&b)
                .unwrap_err()
                .contains("not a DXF group code")
        );
    }
}
