//! A hand-rolled glTF document builder for tests: writes JSON directly, so tests can make
//! anything the reader must handle (strips, fans, lines, nested transforms, sparse and
//! quantized accessors, external and data-URI buffers) independently of `GlbBuilder`.

use base64::Engine as _;
use serde_json::{Value, json};

#[derive(Default)]
pub struct Doc {
    pub bin: Vec<u8>,
    pub views: Vec<Value>,
    pub accessors: Vec<Value>,
    pub meshes: Vec<Value>,
    pub nodes: Vec<Value>,
    /// Root node lists; `None` ⇒ no `scenes` at all.
    pub scenes: Option<Vec<Vec<usize>>>,
    pub extensions_required: Vec<&'static str>,
}

impl Doc {
    fn view(&mut self, bytes: &[u8]) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.views.push(json!({
            "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()
        }));
        self.bin.extend_from_slice(bytes);
        self.views.len() - 1
    }

    pub fn positions(&mut self, pts: &[[f32; 3]]) -> usize {
        let bytes: Vec<u8> = pts.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes);
        let mut min = [f32::MAX; 3];
        let mut max = [f32::MIN; 3];
        for p in pts {
            for k in 0..3 {
                min[k] = min[k].min(p[k]);
                max[k] = max[k].max(p[k]);
            }
        }
        self.accessors.push(json!({
            "bufferView": view, "componentType": 5126, "count": pts.len(), "type": "VEC3",
            "min": min, "max": max
        }));
        self.accessors.len() - 1
    }

    /// Normalised i16 positions (KHR_mesh_quantization): value / 32767.
    pub fn positions_i16(&mut self, pts: &[[i16; 3]]) -> usize {
        let mut bytes = Vec::new();
        for p in pts {
            for x in p {
                bytes.extend_from_slice(&x.to_le_bytes());
            }
            bytes.extend_from_slice(&[0, 0]); // pad elements to 4 bytes
        }
        let view = self.view(&bytes);
        self.views[view]["byteStride"] = json!(8);
        self.accessors.push(json!({
            "bufferView": view, "componentType": 5122, "normalized": true, "count": pts.len(),
            "type": "VEC3", "min": [-1.0, -1.0, -1.0], "max": [1.0, 1.0, 1.0]
        }));
        if !self.extensions_required.contains(&"KHR_mesh_quantization") {
            self.extensions_required.push("KHR_mesh_quantization");
        }
        self.accessors.len() - 1
    }

    /// An accessor over `bytes` as given, declared with `componentType` and `type` and no
    /// extension: for files that declare one thing and store another.
    pub fn raw_accessor(
        &mut self,
        bytes: &[u8],
        component_type: u32,
        ty: &str,
        count: usize,
        stride: Option<usize>,
    ) -> usize {
        let view = self.view(bytes);
        if let Some(stride) = stride {
            self.views[view]["byteStride"] = json!(stride);
        }
        self.accessors.push(json!({
            "bufferView": view, "componentType": component_type, "count": count, "type": ty
        }));
        self.accessors.len() - 1
    }

    /// Replaces vertex `index` of a positions accessor through a sparse substitution.
    pub fn sparse_replace(&mut self, accessor: usize, index: u16, value: [f32; 3]) {
        let iview = self.view(&index.to_le_bytes());
        let vbytes: Vec<u8> = value.iter().flat_map(|x| x.to_le_bytes()).collect();
        let vview = self.view(&vbytes);
        self.accessors[accessor]["sparse"] = json!({
            "count": 1,
            "indices": { "bufferView": iview, "componentType": 5123 },
            "values": { "bufferView": vview }
        });
    }

    pub fn indices_u16(&mut self, idx: &[u16]) -> usize {
        let bytes: Vec<u8> = idx.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes);
        self.accessors.push(json!({
            "bufferView": view, "componentType": 5123, "count": idx.len(), "type": "SCALAR"
        }));
        self.accessors.len() - 1
    }

    pub fn indices_u32(&mut self, idx: &[u32]) -> usize {
        let bytes: Vec<u8> = idx.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes);
        self.accessors.push(json!({
            "bufferView": view, "componentType": 5125, "count": idx.len(), "type": "SCALAR"
        }));
        self.accessors.len() - 1
    }

    /// A primitive: mode (4 triangles, 5 strip, 6 fan, 1 lines, 0 points).
    pub fn prim(position: usize, indices: Option<usize>, mode: u32) -> Value {
        let mut p = json!({ "attributes": { "POSITION": position }, "mode": mode });
        if let Some(i) = indices {
            p["indices"] = json!(i);
        }
        p
    }

    pub fn mesh(&mut self, prims: Vec<Value>) -> usize {
        self.meshes.push(json!({ "primitives": prims }));
        self.meshes.len() - 1
    }

    /// A node; `extra` is merged in (e.g. `{"mesh": 0, "translation": [..]}`).
    pub fn node(&mut self, extra: Value) -> usize {
        self.nodes.push(extra);
        self.nodes.len() - 1
    }

    pub fn json(&self, buffer: Value) -> Value {
        let mut root = json!({ "asset": { "version": "2.0" } });
        let set = |root: &mut Value, key: &str, v: &[Value]| {
            if !v.is_empty() {
                root[key] = json!(v);
            }
        };
        set(&mut root, "bufferViews", &self.views);
        set(&mut root, "accessors", &self.accessors);
        set(&mut root, "meshes", &self.meshes);
        set(&mut root, "nodes", &self.nodes);
        if !self.bin.is_empty() {
            root["buffers"] = json!([buffer]);
        }
        if let Some(scenes) = &self.scenes {
            let list: Vec<Value> = scenes.iter().map(|n| json!({ "nodes": n })).collect();
            root["scenes"] = json!(list);
            root["scene"] = json!(0);
        }
        if !self.extensions_required.is_empty() {
            root["extensionsRequired"] = json!(self.extensions_required);
            root["extensionsUsed"] = json!(self.extensions_required);
        }
        root
    }

    /// glTF JSON with the buffer embedded as a base64 data URI.
    pub fn gltf_data_uri(&self) -> Vec<u8> {
        let b64 = base64::engine::general_purpose::STANDARD.encode(&self.bin);
        let uri = format!("data:application/octet-stream;base64,{b64}");
        serde_json::to_vec_pretty(&self.json(json!({ "byteLength": self.bin.len(), "uri": uri })))
            .unwrap()
    }

    /// glTF JSON referring to an external buffer file `uri`; returns (json, bin).
    pub fn gltf_external(&self, uri: &str) -> (Vec<u8>, Vec<u8>) {
        let json = self.json(json!({ "byteLength": self.bin.len(), "uri": uri }));
        (serde_json::to_vec(&json).unwrap(), self.bin.clone())
    }

    /// The JSON for a GLB (buffer 0 is the BIN chunk).
    pub fn glb_json(&self) -> Vec<u8> {
        serde_json::to_vec(&self.json(json!({ "byteLength": self.bin.len() }))).unwrap()
    }

    /// GLB container with the buffer in the BIN chunk.
    pub fn glb(&self) -> Vec<u8> {
        glb_container(&self.glb_json(), &self.bin)
    }
}

/// Wraps JSON and BIN bytes in a GLB container with correct lengths and padding.
pub fn glb_container(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let mut json = json.to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
    let mut out = b"glTF".to_vec();
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    if !bin.is_empty() {
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
    }
    out
}

/// The tetrahedron's positions and indices as glTF arrays.
pub fn tetra_arrays() -> (Vec<[f32; 3]>, Vec<u16>) {
    let m = super::tetra();
    let pts = m
        .positions
        .iter()
        .map(|p| [p.x as f32, p.y as f32, p.z as f32])
        .collect();
    let idx = m.triangles.iter().flatten().map(|&i| i as u16).collect();
    (pts, idx)
}
