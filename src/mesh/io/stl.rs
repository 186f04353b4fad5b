//! STL reader, binary and ASCII.
//!
//! Binary is recognised by its size first (84 + 50·n bytes, n read from bytes 80..84),
//! because real binary files often have headers that start with `solid` just like ASCII
//! ones. A text file cannot match by accident below 7 GB (text bytes at 80..84 make
//! n ≥ 0x09090909). Only then is a file that starts with `solid` parsed as ASCII. Stored
//! normals are ignored in both (real files carry zero, non-unit or NaN normals); the winding
//! is the truth. Each facet gets three new vertices: welding is done later.

use super::{Format, MeshIoError, RawMesh, excerpt, scaled_point};
use crate::mesh::Mesh;

const HEADER_LEN: usize = 80;
/// Header plus the u32 facet count.
const PREFIX_LEN: usize = HEADER_LEN + 4;
/// Normal (12) + three vertices (36) + attribute byte count (2).
const FACET_LEN: usize = 50;
/// The most facets whose vertices can still be indexed by `u32`.
const MAX_FACETS: u64 = u32::MAX as u64 / 3;

pub(super) fn read_stl(bytes: &[u8], name: &str, scale: f64) -> Result<RawMesh, MeshIoError> {
    let count = binary_facet_count(bytes);
    let binary_len = count.map(|n| PREFIX_LEN as u64 + FACET_LEN as u64 * n);
    if binary_len == Some(bytes.len() as u64) {
        return read_binary(bytes, count.unwrap_or(0), name, scale, Vec::new());
    }
    let size_note = || match (count, binary_len) {
        (Some(n), Some(len)) => format!(
            "its size ({} bytes) does not match a binary STL with the {n} facets its header \
             announces ({len} bytes)",
            bytes.len()
        ),
        _ => format!("it is too short ({} bytes) for a binary STL", bytes.len()),
    };
    if starts_with_solid(bytes) {
        let not_ascii = |line: usize, message: String| MeshIoError::Invalid {
            name: name.to_owned(),
            format: Format::Stl,
            message: format!(
                "starts with 'solid' but is not ASCII STL (line {line}: {message}), and {}",
                size_note()
            ),
        };
        return match read_ascii(bytes, name, scale) {
            // A binary file with a "solid" header whose size is off: say so.
            Ok(r) if r.mesh.triangles.is_empty() && looks_binary(bytes) => {
                Err(not_ascii(1, "no facets".to_owned()))
            }
            Err(MeshIoError::Syntax { line, message, .. }) if looks_binary(bytes) => {
                Err(not_ascii(line, message))
            }
            r => r,
        };
    }
    // Tolerate junk after a binary body (some exporters pad files), never a short body.
    if let (Some(n), Some(len)) = (count, binary_len)
        && n > 0
        && (bytes.len() as u64) > len
    {
        let extra = bytes.len() as u64 - len;
        let warning = format!("{extra} bytes after the last binary STL facet were ignored");
        return read_binary(bytes, n, name, scale, vec![warning]);
    }
    Err(MeshIoError::Invalid {
        name: name.to_owned(),
        format: Format::Stl,
        message: format!(
            "not ASCII STL (it does not start with 'solid') and not binary STL: {}",
            size_note()
        ),
    })
}

/// The facet count of a binary header, if the file is long enough to have one.
fn binary_facet_count(bytes: &[u8]) -> Option<u64> {
    let c = bytes.get(HEADER_LEN..PREFIX_LEN)?;
    Some(u64::from(u32::from_le_bytes([c[0], c[1], c[2], c[3]])))
}

/// `solid` (any case) after optional whitespace, followed by whitespace or the end.
fn starts_with_solid(bytes: &[u8]) -> bool {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes); // UTF-8 BOM
    let start = bytes
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(bytes.len());
    let rest = &bytes[start..];
    rest.len() >= 5
        && rest[..5].eq_ignore_ascii_case(b"solid")
        && rest.get(5).is_none_or(|b| b.is_ascii_whitespace())
}

/// Text files do not contain NUL bytes; binary STL headers and floats nearly always do.
fn looks_binary(bytes: &[u8]) -> bool {
    bytes.iter().take(4096).any(|&b| b == 0)
}

fn read_binary(
    bytes: &[u8],
    count: u64,
    name: &str,
    scale: f64,
    warnings: Vec<String>,
) -> Result<RawMesh, MeshIoError> {
    if count > MAX_FACETS {
        return Err(MeshIoError::TooLarge {
            name: name.to_owned(),
            message: format!("{count} facets (at most {MAX_FACETS} are supported)"),
        });
    }
    // The caller checked the length against `count`, so this capacity is bounded by the input.
    let body = bytes.get(PREFIX_LEN..).unwrap_or_default();
    let n = (body.len() / FACET_LEN).min(count as usize);
    let mut positions = Vec::with_capacity(3 * n);
    let mut triangles = Vec::with_capacity(n);
    for (facet, chunk) in body.chunks_exact(FACET_LEN).take(n).enumerate() {
        for corner in 0..3 {
            let o = 12 + 12 * corner;
            // invariant: chunks_exact yields 50-byte chunks and o + 12 <= 48.
            let f = |k: usize| {
                let s = o + 4 * k;
                f64::from(f32::from_le_bytes([
                    chunk[s],
                    chunk[s + 1],
                    chunk[s + 2],
                    chunk[s + 3],
                ]))
            };
            let v = positions.len();
            positions.push(scaled_point([f(0), f(1), f(2)], scale, name, v, || {
                format!("binary facet {facet}, corner {corner}")
            })?);
        }
        let b = 3 * facet as u32; // count <= MAX_FACETS, so no overflow
        triangles.push([b, b + 1, b + 2]);
    }
    Ok(RawMesh {
        mesh: Mesh {
            positions,
            triangles,
        },
        warnings,
    })
}

/// Whitespace-separated tokens of an ASCII file, with 1-based line numbers.
struct Tokens<'a> {
    bytes: &'a [u8],
    pos: usize,
    line: usize,
}

impl<'a> Tokens<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
        Tokens {
            bytes,
            pos: 0,
            line: 1,
        }
    }

    fn next_token(&mut self) -> Option<(&'a [u8], usize)> {
        while let Some(&b) = self.bytes.get(self.pos) {
            if !b.is_ascii_whitespace() {
                break;
            }
            if b == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
        let start = self.pos;
        while self
            .bytes
            .get(self.pos)
            .is_some_and(|b| !b.is_ascii_whitespace())
        {
            self.pos += 1;
        }
        (self.pos > start).then(|| (&self.bytes[start..self.pos], self.line))
    }

    /// Skips a `solid`/`endsolid` name: the rest of the current line.
    fn skip_rest_of_line(&mut self) {
        match self.bytes[self.pos..].iter().position(|&b| b == b'\n') {
            Some(k) => {
                self.pos += k + 1;
                self.line += 1;
            }
            None => self.pos = self.bytes.len(),
        }
    }
}

fn is(tok: &[u8], keyword: &str) -> bool {
    tok.eq_ignore_ascii_case(keyword.as_bytes())
}

fn read_ascii(bytes: &[u8], name: &str, scale: f64) -> Result<RawMesh, MeshIoError> {
    let syntax = |line: usize, message: String| MeshIoError::Syntax {
        name: name.to_owned(),
        line,
        message,
    };
    let mut t = Tokens::new(bytes);
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut warnings = Vec::new();

    let mut solids = 0usize;
    'solids: while let Some((tok, line)) = t.next_token() {
        if !is(tok, "solid") && solids > 0 {
            // Junk after the last `endsolid` (NUL padding, a ^Z): the facets are complete.
            warnings.push(format!("text after 'endsolid' ignored from line {line}"));
            break;
        }
        solids += 1;
        if !is(tok, "solid") {
            return Err(syntax(
                line,
                format!("expected 'solid', found '{}'", excerpt(tok)),
            ));
        }
        t.skip_rest_of_line();
        loop {
            let Some((tok, line)) = t.next_token() else {
                warnings.push("ASCII STL ends without 'endsolid'".to_owned());
                break 'solids;
            };
            if is(tok, "endsolid") {
                t.skip_rest_of_line();
                break;
            }
            if is(tok, "solid") {
                warnings.push(format!("line {line}: 'solid' without 'endsolid' before it"));
                t.skip_rest_of_line();
                continue;
            }
            if !is(tok, "facet") {
                return Err(syntax(
                    line,
                    format!("expected 'facet' or 'endsolid', found '{}'", excerpt(tok)),
                ));
            }
            let facet_line = line;
            let eof = || {
                syntax(
                    last_line(bytes),
                    format!("file ends inside the facet of line {facet_line}"),
                )
            };
            // `normal nx ny nz` (possibly junk, possibly absent), then `outer loop`.
            let mut skipped = 0;
            loop {
                let (tok, line) = t.next_token().ok_or_else(eof)?;
                if is(tok, "outer") {
                    break;
                }
                skipped += 1;
                if skipped > 4 {
                    return Err(syntax(
                        line,
                        format!("expected 'outer loop', found '{}'", excerpt(tok)),
                    ));
                }
            }
            let (tok, line) = t.next_token().ok_or_else(eof)?;
            if !is(tok, "loop") {
                return Err(syntax(
                    line,
                    format!("expected 'loop' after 'outer', found '{}'", excerpt(tok)),
                ));
            }
            let mut corners = 0usize;
            loop {
                let (tok, line) = t.next_token().ok_or_else(eof)?;
                if is(tok, "endloop") {
                    break;
                }
                if !is(tok, "vertex") {
                    return Err(syntax(
                        line,
                        format!("expected 'vertex' or 'endloop', found '{}'", excerpt(tok)),
                    ));
                }
                let mut xyz = [0.0; 3];
                for c in &mut xyz {
                    let (tok, line) = t.next_token().ok_or_else(eof)?;
                    *c = std::str::from_utf8(tok)
                        .ok()
                        .and_then(|s| s.parse::<f64>().ok())
                        .ok_or_else(|| {
                            syntax(line, format!("malformed number '{}'", excerpt(tok)))
                        })?;
                }
                corners += 1;
                if corners <= 3 {
                    let v = positions.len();
                    positions.push(scaled_point(xyz, scale, name, v, || {
                        format!("line {line}")
                    })?);
                }
            }
            if corners != 3 {
                return Err(syntax(
                    facet_line,
                    format!("facet has {corners} vertices, expected 3"),
                ));
            }
            let (tok, line) = t.next_token().ok_or_else(eof)?;
            if !is(tok, "endfacet") {
                return Err(syntax(
                    line,
                    format!("expected 'endfacet', found '{}'", excerpt(tok)),
                ));
            }
            // `len` fits in u32, so do all three indices below it.
            let Ok(len) = u32::try_from(positions.len()) else {
                return Err(MeshIoError::TooLarge {
                    name: name.to_owned(),
                    message: "more vertices than u32 indices can address".to_owned(),
                });
            };
            let b = len - 3;
            triangles.push([b, b + 1, b + 2]);
        }
    }
    Ok(RawMesh {
        mesh: Mesh {
            positions,
            triangles,
        },
        warnings,
    })
}

/// The number of the last line of a text (for "unexpected end of file").
fn last_line(bytes: &[u8]) -> usize {
    1 + bytes.iter().filter(|&&b| b == b'\n').count()
}
