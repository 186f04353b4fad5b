//! Binary glTF (GLB) writer for previews: triangle meshes with a colour (and optional
//! per-vertex colours) and line sets (toolpaths, normals, …), viewable in any glTF viewer.
//!
//! Layout: one glTF mesh, node and primitive per part, in the order added; one material per
//! distinct colour; one buffer (the BIN chunk) holding, per part, f32 positions, u32 indices
//! and optional f32 RGBA colours, every view 4-byte aligned. Positions are written in mm as
//! given. The output depends only on the parts added (same input ⇒ same bytes).

use nalgebra::Point3;
use serde_json::{Map, Value, json};

use crate::mesh::Mesh;

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;
const MODE_LINES: u32 = 1;
const MODE_TRIANGLES: u32 = 4;

/// Why a part could not be added to a [`GlbBuilder`].
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GlbError {
    #[error("part '{part}': vertex {vertex} is not finite as f32 ({value:?})")]
    NonFinite {
        part: String,
        vertex: usize,
        value: [f64; 3],
    },
    #[error("part '{part}': triangle {face} refers to vertex {index} of {vertex_count}")]
    IndexOutOfRange {
        part: String,
        face: usize,
        index: u32,
        vertex_count: usize,
    },
    #[error("part '{part}': {colors} vertex colours for {vertices} vertices")]
    ColourCount {
        part: String,
        colors: usize,
        vertices: usize,
    },
    #[error("part '{part}': colour {value:?} is not finite")]
    BadColour { part: String, value: [f32; 4] },
    #[error("part '{part}': the GLB would exceed 4 GiB")]
    TooLarge { part: String },
}

/// Collects triangle meshes and line sets and writes them as one GLB file.
///
/// ```
/// use wavemill::mesh::{Mesh, io::GlbBuilder};
/// use nalgebra::Point3;
/// let tri = Mesh {
///     positions: vec![Point3::origin(), Point3::new(1.0, 0.0, 0.0), Point3::new(0.0, 1.0, 0.0)],
///     triangles: vec![[0, 1, 2]],
/// };
/// let mut glb = GlbBuilder::new();
/// glb.add_triangles("part", &tri, [0.7, 0.7, 0.7, 1.0], None)?;
/// glb.add_polylines("path", &[vec![Point3::new(0.0, 0.0, 1.0), Point3::new(1.0, 1.0, 1.0)]],
///     [1.0, 0.0, 0.0, 1.0])?;
/// let bytes = glb.build();
/// assert_eq!(&bytes[..4], b"glTF");
/// # Ok::<(), wavemill::mesh::io::GlbError>(())
/// ```
#[derive(Clone, Debug, Default)]
pub struct GlbBuilder {
    parts: Vec<Part>,
    /// Upper bound on the GLB size so far.
    size_bound: usize,
}

#[derive(Clone, Debug)]
struct Part {
    name: String,
    rgba: [f32; 4],
    mode: u32,
    positions: Vec<[f32; 3]>,
    indices: Vec<u32>,
    colors: Option<Vec<[f32; 4]>>,
}

impl GlbBuilder {
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a triangle mesh with a base colour (linear RGBA, 0..1) and optional per-vertex
    /// colours (one per position, written as `COLOR_0`). A mesh without triangles adds nothing.
    pub fn add_triangles(
        &mut self,
        name: &str,
        mesh: &Mesh,
        rgba: [f32; 4],
        vertex_colors: Option<&[[f32; 4]]>,
    ) -> Result<&mut Self, GlbError> {
        let n = mesh.positions.len();
        if let Some(c) = vertex_colors {
            if c.len() != n {
                return Err(GlbError::ColourCount {
                    part: name.to_owned(),
                    colors: c.len(),
                    vertices: n,
                });
            }
            if let Some(bad) = c.iter().find(|c| !c.iter().all(|x| x.is_finite())) {
                return Err(GlbError::BadColour {
                    part: name.to_owned(),
                    value: *bad,
                });
            }
        }
        for (face, t) in mesh.triangles.iter().enumerate() {
            if let Some(&index) = t.iter().find(|&&i| i as usize >= n) {
                return Err(GlbError::IndexOutOfRange {
                    part: name.to_owned(),
                    face,
                    index,
                    vertex_count: n,
                });
            }
        }
        if mesh.triangles.is_empty() {
            return Ok(self);
        }
        let positions = to_f32(name, &mesh.positions)?;
        let indices = mesh.triangles.iter().flatten().copied().collect();
        self.push(Part {
            name: name.to_owned(),
            rgba,
            mode: MODE_TRIANGLES,
            positions,
            indices,
            colors: vertex_colors.map(<[_]>::to_vec),
        })
    }

    /// Adds separate line segments (`LINES` mode). No segments adds nothing.
    pub fn add_lines(
        &mut self,
        name: &str,
        segments: &[[Point3<f64>; 2]],
        rgba: [f32; 4],
    ) -> Result<&mut Self, GlbError> {
        // A segment is a two-point polyline; one code path writes both.
        self.add_polylines(name, segments, rgba)
    }

    /// Adds polylines (each drawn through its points in order) as one `LINES` part.
    /// Polylines with fewer than two points are skipped.
    pub fn add_polylines<P: AsRef<[Point3<f64>]>>(
        &mut self,
        name: &str,
        polylines: &[P],
        rgba: [f32; 4],
    ) -> Result<&mut Self, GlbError> {
        let mut points = Vec::new();
        let mut indices = Vec::new();
        for line in polylines.iter().map(AsRef::as_ref).filter(|l| l.len() >= 2) {
            let first = points.len() as u32; // bounded by push's size check below
            for k in 1..line.len() as u32 {
                indices.extend([first + k - 1, first + k]);
            }
            points.extend_from_slice(line);
            if points.len() > u32::MAX as usize / 16 {
                return Err(GlbError::TooLarge {
                    part: name.to_owned(),
                });
            }
        }
        if indices.is_empty() {
            return Ok(self);
        }
        let positions = to_f32(name, &points)?;
        self.push(Part {
            name: name.to_owned(),
            rgba,
            mode: MODE_LINES,
            positions,
            indices,
            colors: None,
        })
    }

    fn push(&mut self, part: Part) -> Result<&mut Self, GlbError> {
        if !part.rgba.iter().all(|x| x.is_finite()) {
            return Err(GlbError::BadColour {
                part: part.name,
                value: part.rgba,
            });
        }
        // The file length is a u32: count the binary data plus a generous bound on this
        // part's JSON (about 700 bytes, plus the name, escaped, twice).
        let len = 12 * part.positions.len()
            + 4 * part.indices.len()
            + part.colors.as_ref().map_or(0, |c| 16 * c.len())
            + 1024
            + 12 * part.name.len();
        if self.size_bound + len > u32::MAX as usize - 4096 {
            return Err(GlbError::TooLarge { part: part.name });
        }
        self.size_bound += len;
        self.parts.push(part);
        Ok(self)
    }

    /// The GLB bytes.
    pub fn build(&self) -> Vec<u8> {
        let mut bin: Vec<u8> = Vec::new();
        let mut views = Vec::new();
        let mut accessors = Vec::new();
        let mut meshes = Vec::new();
        let mut nodes = Vec::new();
        let mut materials: Vec<[f32; 4]> = Vec::new();

        for part in &self.parts {
            let mut view = |bin: &mut Vec<u8>, bytes: &[u8], target: u32| {
                views.push(json!({
                    "buffer": 0,
                    "byteOffset": bin.len(),
                    "byteLength": bytes.len(),
                    "target": target,
                }));
                bin.extend_from_slice(bytes);
                views.len() - 1
            };
            let pos_bytes: Vec<u8> = part
                .positions
                .iter()
                .flatten()
                .flat_map(|x| x.to_le_bytes())
                .collect();
            let pos_view = view(&mut bin, &pos_bytes, ARRAY_BUFFER);
            let idx_bytes: Vec<u8> = part.indices.iter().flat_map(|x| x.to_le_bytes()).collect();
            let idx_view = view(&mut bin, &idx_bytes, ELEMENT_ARRAY_BUFFER);
            let col_view = part.colors.as_ref().map(|c| {
                let bytes: Vec<u8> = c.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
                view(&mut bin, &bytes, ARRAY_BUFFER)
            });

            let (min, max) = bounds(&part.positions);
            accessors.push(json!({
                "bufferView": pos_view,
                "componentType": FLOAT,
                "count": part.positions.len(),
                "type": "VEC3",
                "min": min.map(json_f32),
                "max": max.map(json_f32),
            }));
            let mut attributes = Map::new();
            attributes.insert("POSITION".into(), json!(accessors.len() - 1));
            accessors.push(json!({
                "bufferView": idx_view,
                "componentType": UNSIGNED_INT,
                "count": part.indices.len(),
                "type": "SCALAR",
            }));
            let idx_accessor = accessors.len() - 1;
            if let (Some(v), Some(c)) = (col_view, &part.colors) {
                accessors.push(json!({
                    "bufferView": v,
                    "componentType": FLOAT,
                    "count": c.len(),
                    "type": "VEC4",
                }));
                attributes.insert("COLOR_0".into(), json!(accessors.len() - 1));
            }
            let key = part.rgba.map(f32::to_bits);
            let material = match materials.iter().position(|m| m.map(f32::to_bits) == key) {
                Some(m) => m,
                None => {
                    materials.push(part.rgba);
                    materials.len() - 1
                }
            };
            meshes.push(json!({
                "name": part.name,
                "primitives": [{
                    "attributes": attributes,
                    "indices": idx_accessor,
                    "material": material,
                    "mode": part.mode,
                }],
            }));
            nodes.push(json!({ "name": part.name, "mesh": meshes.len() - 1 }));
        }

        let materials: Vec<Value> = materials
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let mut m = json!({
                    "name": format!("colour_{i}"),
                    "pbrMetallicRoughness": {
                        "baseColorFactor": c.map(json_f32),
                        "metallicFactor": 0.0,
                        "roughnessFactor": 0.8,
                    },
                    "doubleSided": true,
                });
                if c[3] < 1.0 {
                    m["alphaMode"] = json!("BLEND");
                }
                m
            })
            .collect();

        let mut root = Map::new();
        root.insert(
            "asset".into(),
            json!({ "version": "2.0", "generator": "wavemill" }),
        );
        // glTF forbids empty arrays (and gltf-json wants `nodes` in a scene): an empty
        // builder writes no scene at all.
        if !nodes.is_empty() {
            let scene_nodes: Vec<usize> = (0..nodes.len()).collect();
            root.insert("scene".into(), json!(0));
            root.insert("scenes".into(), json!([{ "nodes": scene_nodes }]));
        }
        for (key, list) in [
            ("nodes", nodes),
            ("meshes", meshes),
            ("materials", materials),
            ("accessors", accessors),
            ("bufferViews", views),
        ] {
            if !list.is_empty() {
                root.insert(key.into(), Value::Array(list));
            }
        }
        if !bin.is_empty() {
            root.insert("buffers".into(), json!([{ "byteLength": bin.len() }]));
        }

        // serde_json's Map is a BTreeMap here (no preserve_order): key order is fixed.
        let mut json_bytes = Value::Object(root).to_string().into_bytes();
        pad(&mut json_bytes, b' ');
        pad(&mut bin, 0);
        let total = 12 + 8 + json_bytes.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
        let mut out = Vec::with_capacity(total);
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes()); // < 4 GiB: checked in push
        out.extend_from_slice(&(json_bytes.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&json_bytes);
        if !bin.is_empty() {
            out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
            out.extend_from_slice(b"BIN\0");
            out.extend_from_slice(&bin);
        }
        out
    }
}

fn to_f32(part: &str, points: &[Point3<f64>]) -> Result<Vec<[f32; 3]>, GlbError> {
    points
        .iter()
        .enumerate()
        .map(|(vertex, p)| {
            let q = [p.x as f32, p.y as f32, p.z as f32];
            if q.iter().all(|x| x.is_finite()) {
                Ok(q)
            } else {
                Err(GlbError::NonFinite {
                    part: part.to_owned(),
                    vertex,
                    value: [p.x, p.y, p.z],
                })
            }
        })
        .collect()
}

fn bounds(points: &[[f32; 3]]) -> ([f32; 3], [f32; 3]) {
    let mut min = [f32::INFINITY; 3];
    let mut max = [f32::NEG_INFINITY; 3];
    for p in points {
        for k in 0..3 {
            min[k] = min[k].min(p[k]);
            max[k] = max[k].max(p[k]);
        }
    }
    (min, max)
}

/// An f32 as the JSON number with the fewest digits that reads back to the same f32
/// (`0.8`, not `0.800000011920929`).
fn json_f32(x: f32) -> Value {
    let shortest: f64 = x.to_string().parse().unwrap_or(f64::from(x));
    json!(shortest)
}

fn pad(bytes: &mut Vec<u8>, with: u8) {
    while !bytes.len().is_multiple_of(4) {
        bytes.push(with);
    }
}
