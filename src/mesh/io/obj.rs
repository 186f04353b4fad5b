//! Wavefront OBJ reader (geometry only), built on `tobj`.
//!
//! A first pass over the text keeps only what a machining mesh needs (`v` and `f` lines) and
//! checks them with line numbers, so errors point at the line (tobj's do not). It also keeps
//! tobj away from the texture-coordinate and normal code paths, where a huge negative index
//! overflows. tobj then triangulates (fan) and indexes the faces. Everything ends up in one
//! model, so vertices shared between groups stay shared; unused vertices are dropped and the
//! rest renumbered in order of first use.

use super::{Format, MeshIoError, RawMesh, excerpt, scaled_point};
use crate::mesh::Mesh;

pub(super) fn read_obj(bytes: &[u8], name: &str, scale: f64) -> Result<RawMesh, MeshIoError> {
    let filtered = prepass(bytes, name)?;
    // `..Default::default()` stays: the `merging`/`reordering` fields exist only with those
    // tobj features, and another crate in the build may turn them on.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        single_index: false,
        ..Default::default()
    };
    // Materials are never needed: answer every `mtllib` with "not found" (which tobj
    // tolerates) instead of touching the file system.
    let (models, _materials) = tobj::load_obj_buf(&mut filtered.text.as_bytes(), &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| MeshIoError::Invalid {
        name: name.to_owned(),
        format: Format::Obj,
        message: e.to_string(),
    })?;

    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut face = 0usize;
    for (m, model) in models.iter().enumerate() {
        let base = positions.len();
        for (k, p) in model.mesh.positions.chunks_exact(3).enumerate() {
            let xyz = [p[0], p[1], p[2]]; // tobj's `use_f64` feature: no precision lost
            let v = positions.len();
            positions.push(scaled_point(xyz, scale, name, v, || {
                format!("model {m}, vertex {k} after tobj's renumbering")
            })?);
        }
        let count = positions.len() - base;
        let base = u32::try_from(base).ok();
        for t in model.mesh.indices.chunks_exact(3) {
            let mut tri = [0u32; 3];
            for (slot, &i) in tri.iter_mut().zip(t) {
                let index = base.and_then(|b| b.checked_add(i));
                *slot = match index {
                    Some(index) if (i as usize) < count => index,
                    _ => {
                        return Err(MeshIoError::IndexOutOfRange {
                            name: name.to_owned(),
                            face,
                            location: format!("model {m} after triangulation"),
                            index: i64::from(i),
                            vertex_count: count,
                        });
                    }
                };
            }
            triangles.push(tri);
            face += 1;
        }
    }
    Ok(RawMesh {
        mesh: Mesh {
            positions,
            triangles,
        },
        warnings: filtered.warnings,
    })
}

struct Filtered {
    /// Only the `v` and `f` lines, as UTF-8.
    text: String,
    warnings: Vec<String>,
}

/// Keeps the `v` and `f` lines and checks them: three finite numbers per `v`, at least one
/// vertex per `f`, every face index in range. Counts what is ignored for the warnings.
fn prepass(bytes: &[u8], name: &str) -> Result<Filtered, MeshIoError> {
    let syntax = |line: usize, message: String| MeshIoError::Syntax {
        name: name.to_owned(),
        line,
        message,
    };
    let mut text = String::new();
    let mut vertices = 0usize;
    let (mut faces, mut small_faces, mut lines, mut points) = (0usize, 0usize, 0usize, 0usize);
    let mut face_lines = Vec::new();
    for (line_no, line) in bytes.split(|&b| b == b'\n').enumerate() {
        let line_no = line_no + 1;
        let mut words = line
            .split(|b| b.is_ascii_whitespace())
            .filter(|w| !w.is_empty());
        match words.next() {
            Some(b"v") => {
                for axis in ["x", "y", "z"] {
                    let word = words.next().unwrap_or_default();
                    let value = parse::<f64>(word).ok_or_else(|| {
                        syntax(
                            line_no,
                            format!("vertex {vertices}: malformed {axis} '{}'", excerpt(word)),
                        )
                    })?;
                    if !value.is_finite() {
                        return Err(MeshIoError::NonFinite {
                            name: name.to_owned(),
                            vertex: vertices,
                            location: format!("line {line_no}"),
                            value: [value; 3],
                        });
                    }
                }
                vertices += 1;
            }
            Some(b"f") => {
                face_lines.push((line_no, faces, vertices, line));
                faces += 1;
            }
            Some(b"l") => {
                lines += 1;
                continue;
            }
            Some(b"p") => {
                points += 1;
                continue;
            }
            _ => continue,
        }
        text.push_str(&String::from_utf8_lossy(line));
        text.push('\n');
    }
    // Second look at the faces, now that the total vertex count is known (tobj resolves
    // positive indices at the end of the model, negative ones at the face).
    for &(line_no, face, before, line) in &face_lines {
        let words = line
            .split(|b| b.is_ascii_whitespace())
            .filter(|w| !w.is_empty())
            .skip(1);
        let mut corners = 0;
        for word in words {
            corners += 1;
            let first = word.split(|&b| b == b'/').next().unwrap_or_default();
            let index = parse::<i64>(first).ok_or_else(|| {
                syntax(
                    line_no,
                    format!("face {face}: malformed vertex index '{}'", excerpt(word)),
                )
            })?;
            let resolved = if index < 0 {
                (before as i64).checked_add(index)
            } else {
                index.checked_sub(1)
            };
            if !resolved.is_some_and(|r| r >= 0 && (r as u64) < vertices as u64) {
                return Err(MeshIoError::IndexOutOfRange {
                    name: name.to_owned(),
                    face,
                    location: format!("line {line_no}"),
                    index,
                    vertex_count: vertices,
                });
            }
        }
        if corners == 0 {
            return Err(syntax(line_no, format!("face {face} has no vertices")));
        }
        if corners < 3 {
            small_faces += 1;
        }
    }
    let mut warnings = Vec::new();
    if small_faces > 0 {
        warnings.push(format!(
            "{small_faces} faces with fewer than 3 vertices ignored"
        ));
    }
    if lines > 0 {
        warnings.push(format!("{lines} line elements ('l') ignored"));
    }
    if points > 0 {
        warnings.push(format!("{points} point elements ('p') ignored"));
    }
    if vertices > u32::MAX as usize {
        return Err(MeshIoError::TooLarge {
            name: name.to_owned(),
            message: format!("{vertices} vertices (u32 indices)"),
        });
    }
    Ok(Filtered { text, warnings })
}

fn parse<T: std::str::FromStr>(word: &[u8]) -> Option<T> {
    std::str::from_utf8(word).ok()?.parse().ok()
}
