//! glTF 2.0 reader (JSON with external or data-URI buffers, and GLB).
//!
//! The `gltf` crate parses and validates the JSON (every index into the document is checked
//! there). The GLB container, the buffers and the accessors are read here, with every offset
//! and length checked against the bytes really present, because the crate's own GLB header
//! and accessor readers trust the file (they panic or slice out of bounds on lying lengths),
//! and its validator indexes POSITION accessors unchecked, so those indices are checked first.
//! Reading accessors here also gives quantized positions (`KHR_mesh_quantization`): integer
//! POSITION accessors are decoded when the file declares that extension and refused otherwise
//! (the core spec allows only FLOAT VEC3, and bytes read as coordinates are garbage).
//!
//! Files the part refers to are untrusted input too: buffers are read only from data URIs,
//! the GLB BIN chunk, or relative paths that resolve (after percent-decoding and
//! canonicalising, so through `..` and symlinks) to a regular file inside the part file's
//! folder. Absolute paths, `file:` and other schemes, escapes from the folder, FIFOs, devices
//! and directories are refused before anything is opened, and errors name the URI, never the
//! bytes of what it points at. Images are never read (only geometry is loaded).
//!
//! What is loaded: every triangle primitive (`TRIANGLES`, `TRIANGLE_STRIP`, `TRIANGLE_FAN`)
//! of every node of the default scene (else the first scene, else every root node), placed
//! by its world transform (parent × local, in f64). Lines and points are skipped with a
//! warning; skins and morph targets are ignored. A node whose transform mirrors (negative
//! determinant) has its triangles' winding reversed so that they stay counter-clockwise.

use std::borrow::Cow;
use std::collections::BTreeSet;
use std::io::Read;
use std::path::{Path, PathBuf};

use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::mesh::Mode;
use ::gltf::{Accessor, Document};
use base64::Engine as _;
use nalgebra::{Matrix3, Matrix4, Point3, Quaternion, Translation3, UnitQuaternion, Vector3};

use super::{Format, MeshIoError, RawMesh, scaled_point};
use crate::mesh::Mesh;

/// Output vertices (and triangles) allowed per input byte, on top of [`OUTPUT_ALLOWANCE`]:
/// generous for real instancing, but a small file cannot ask for gigabytes.
const OUTPUT_PER_INPUT_BYTE: usize = 4;
const OUTPUT_ALLOWANCE: usize = 1 << 20;

const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

pub(super) fn read_gltf(
    bytes: &[u8],
    name: &str,
    base_dir: Option<&Path>,
    scale: f64,
) -> Result<RawMesh, MeshIoError> {
    let is_glb = bytes.starts_with(GLB_MAGIC);
    let format = if is_glb { Format::Glb } else { Format::Gltf };
    let invalid = |message: String| MeshIoError::Invalid {
        name: name.to_owned(),
        format,
        message,
    };
    let (json, bin) = if is_glb {
        split_glb(bytes).map_err(invalid)?
    } else {
        (bytes, None)
    };
    let json = json.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(json); // UTF-8 BOM
    let mut root: ::gltf::json::Root =
        ::gltf::json::deserialize::from_slice(json).map_err(|e| invalid(e.to_string()))?;
    // gltf-json 1.4's validator indexes `accessors` with the POSITION index before checking
    // it (a panic on a bad file): check attribute indices first.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            if let Some(bad) = prim
                .attributes
                .values()
                .find(|i| i.value() >= root.accessors.len())
            {
                return Err(invalid(format!(
                    "mesh {m} primitive {p}: attribute accessor {} does not exist",
                    bad.value()
                )));
            }
        }
    }
    // Integer positions are only meaningful under KHR_mesh_quantization (a file that declares
    // it must at least list it as used).
    let quantized_positions = root
        .extensions_used
        .iter()
        .chain(&root.extensions_required)
        .any(|e| e.as_str() == "KHR_mesh_quantization");
    // Supported by the accessor reader below, unknown to the crate's validator.
    root.extensions_required
        .retain(|e| e.as_str() != "KHR_mesh_quantization");
    let doc = Document::from_json(root).map_err(|e| invalid(e.to_string()))?;

    let mut warnings = Vec::new();
    let instances = scene_instances(&doc, &mut warnings).map_err(invalid)?;
    let buffers = load_buffers(&doc, &instances, bin, base_dir, name)?;
    let input_len = json.len() + buffers.iter().flatten().map(|b| b.len()).sum::<usize>();
    let limit = input_len
        .saturating_mul(OUTPUT_PER_INPUT_BYTE)
        .saturating_add(OUTPUT_ALLOWANCE)
        .min(u32::MAX as usize);

    let mut out = Mesh::default();
    let mut warned = BTreeSet::new();
    for inst in &instances {
        let Some(mesh) = doc.meshes().nth(inst.mesh) else {
            continue; // invariant: validation checked node.mesh indices
        };
        for (p, prim) in mesh.primitives().enumerate() {
            let here = format!("node {} mesh {} primitive {p}", inst.node, inst.mesh);
            let mode = prim.mode();
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                if warned.insert((inst.mesh, p)) {
                    warnings.push(format!(
                        "mesh {} primitive {p}: mode {mode:?} skipped (not triangles)",
                        inst.mesh
                    ));
                }
                continue;
            }
            let ctx = Ctx {
                name,
                format,
                here: &here,
                buffers: &buffers,
                input_len,
                quantized_positions,
            };
            let Some(pos) = prim.get(&::gltf::Semantic::Positions) else {
                return Err(invalid(format!("{here}: no POSITION attribute")));
            };
            let local = ctx.read_positions(&pos)?;
            // Refuse what does not fit before allocating for it (also keeps indices in u32).
            let too_large = || MeshIoError::TooLarge {
                name: name.to_owned(),
                message: format!(
                    "the scene instantiates more than {limit} vertices or triangles \
                     from {input_len} bytes of input"
                ),
            };
            let base = out.positions.len();
            if base + local.len() > limit {
                return Err(too_large());
            }
            let indices = match prim.indices() {
                Some(acc) => ctx.read_indices(&acc)?,
                None => (0..local.len() as u32).collect(), // local.len() <= limit <= u32::MAX
            };
            let n = local.len();
            if let Some(k) = indices.iter().position(|&i| i as usize >= n) {
                return Err(MeshIoError::IndexOutOfRange {
                    name: name.to_owned(),
                    face: if mode == Mode::Triangles {
                        k / 3
                    } else {
                        k.saturating_sub(2)
                    },
                    location: here,
                    index: i64::from(indices[k]),
                    vertex_count: n,
                });
            }
            let mut tris = Vec::new();
            let notes = triangulate(mode, &indices, &mut tris);
            if warned.insert((inst.mesh, p)) {
                warnings.extend(notes.into_iter().map(|n| format!("{here}: {n}")));
            }
            if out.triangles.len() + tris.len() > limit {
                return Err(too_large());
            }
            let m = &inst.world;
            let linear: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
            let shift: Vector3<f64> = m.fixed_view::<3, 1>(0, 3).into_owned();
            for (k, q) in local.iter().enumerate() {
                let w = linear * q.coords + shift;
                let v = out.positions.len();
                out.positions
                    .push(scaled_point([w.x, w.y, w.z], scale, name, v, || {
                        format!("{here}, vertex {k}")
                    })?);
            }
            let mirrored = linear.determinant() < 0.0;
            let b = base as u32; // base + n <= limit <= u32::MAX, and every index < n
            out.triangles.extend(tris.iter().map(|t| {
                let [a, c, d] = t.map(|i| i + b);
                if mirrored { [a, d, c] } else { [a, c, d] }
            }));
        }
    }
    Ok(RawMesh {
        mesh: out,
        warnings,
    })
}

/// A mesh placed in the scene.
struct Instance {
    node: usize,
    mesh: usize,
    world: Matrix4<f64>,
}

/// The mesh nodes of the scene to load, with world transforms, in depth-first order.
fn scene_instances(doc: &Document, warnings: &mut Vec<String>) -> Result<Vec<Instance>, String> {
    let nodes: Vec<_> = doc.nodes().collect();
    let scene_count = doc.scenes().len();
    let roots: Vec<usize> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => {
            if scene_count > 1 {
                warnings.push(format!(
                    "{scene_count} scenes; only scene {} is loaded",
                    scene.index()
                ));
            }
            scene.nodes().map(|n| n.index()).collect()
        }
        None => {
            let mut is_child = vec![false; nodes.len()];
            for n in &nodes {
                for c in n.children() {
                    is_child[c.index()] = true; // invariant: validated child index
                }
            }
            (0..nodes.len()).filter(|&i| !is_child[i]).collect()
        }
    };
    // Explicit stack: a deep hierarchy must not overflow the call stack. Each node may be
    // reached once (the spec requires disjoint trees); this also stops cycles and the
    // exponential blow-up of shared subtrees.
    let mut reached = vec![false; nodes.len()];
    let mut stack: Vec<(usize, Matrix4<f64>)> = roots
        .iter()
        .rev()
        .map(|&r| (r, Matrix4::identity()))
        .collect();
    let mut out = Vec::new();
    let mut singular = 0usize;
    while let Some((i, parent)) = stack.pop() {
        let Some(node) = nodes.get(i) else {
            continue; // invariant: validated node index
        };
        if std::mem::replace(&mut reached[i], true) {
            return Err(format!(
                "node {i} is reached twice: the node hierarchy is not a set of trees"
            ));
        }
        let world = parent * local_transform(node)?;
        if let Some(mesh) = node.mesh() {
            if world.fixed_view::<3, 3>(0, 0).determinant() == 0.0 {
                singular += 1;
            }
            out.push(Instance {
                node: i,
                mesh: mesh.index(),
                world,
            });
        }
        let children: Vec<usize> = node.children().map(|c| c.index()).collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world)));
    }
    if singular > 0 {
        warnings.push(format!(
            "{singular} mesh nodes have a singular transform (their triangles are flat)"
        ));
    }
    if out.is_empty() {
        warnings.push(format!(
            "the scene places no meshes ({} meshes in the file)",
            doc.meshes().len()
        ));
    }
    Ok(out)
}

/// A node's local transform in f64: the matrix as given, or T·R·S.
fn local_transform(node: &::gltf::Node) -> Result<Matrix4<f64>, String> {
    let m = match node.transform() {
        ::gltf::scene::Transform::Matrix { matrix } => {
            Matrix4::from_fn(|r, c| f64::from(matrix[c][r])) // glTF stores columns
        }
        ::gltf::scene::Transform::Decomposed {
            translation: t,
            rotation: r,
            scale: s,
        } => {
            let q = Quaternion::new(
                f64::from(r[3]),
                f64::from(r[0]),
                f64::from(r[1]),
                f64::from(r[2]),
            );
            let norm = q.norm();
            if !(norm.is_finite() && norm > 0.0) {
                return Err(format!("node {}: invalid rotation {r:?}", node.index()));
            }
            let rot = UnitQuaternion::from_quaternion(q);
            let t = Translation3::new(f64::from(t[0]), f64::from(t[1]), f64::from(t[2]));
            let s = Vector3::new(f64::from(s[0]), f64::from(s[1]), f64::from(s[2]));
            t.to_homogeneous() * rot.to_homogeneous() * Matrix4::new_nonuniform_scaling(&s)
        }
    };
    if m.iter().all(|x| x.is_finite()) {
        Ok(m)
    } else {
        Err(format!("node {}: non-finite transform", node.index()))
    }
}

/// Splits a GLB container into its JSON chunk and optional BIN chunk.
fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), String> {
    let u32_at = |o: usize| -> Option<u32> {
        let b = bytes.get(o..o.checked_add(4)?)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let (Some(version), Some(length)) = (u32_at(4), u32_at(8)) else {
        return Err("GLB header truncated".to_owned());
    };
    if version != 2 {
        return Err(format!("GLB version {version} (only 2 is supported)"));
    }
    let length = length as usize;
    if length > bytes.len() || length < 12 {
        return Err(format!(
            "GLB header says {length} bytes, the data has {}",
            bytes.len()
        ));
    }
    let mut pos = 12;
    let mut json = None;
    let mut bin = None;
    while pos < length {
        let (Some(chunk_len), Some(chunk_type)) = (u32_at(pos), u32_at(pos + 4)) else {
            return Err(format!("GLB chunk header at byte {pos} truncated"));
        };
        let start = pos + 8;
        let end = start
            .checked_add(chunk_len as usize)
            .filter(|&e| e <= length)
            .ok_or_else(|| format!("GLB chunk at byte {pos} ({chunk_len} bytes) truncated"))?;
        let data = &bytes[start..end];
        match chunk_type {
            CHUNK_JSON if json.is_none() && pos == 12 => json = Some(data),
            CHUNK_BIN if bin.is_none() && json.is_some() => bin = Some(data),
            _ if pos == 12 => return Err("GLB does not start with a JSON chunk".to_owned()),
            _ => {} // unknown chunks are skipped, as the spec asks
        }
        pos = end;
    }
    let json = json.ok_or_else(|| "GLB has no JSON chunk".to_owned())?;
    // Padding is spaces by the spec; some writers use NULs.
    let trimmed = json.len()
        - json
            .iter()
            .rev()
            .take_while(|&&b| b == 0 || b.is_ascii_whitespace())
            .count();
    Ok((&json[..trimmed], bin))
}

/// Loads the buffers that the instanced triangle primitives read (others may be missing).
fn load_buffers<'a>(
    doc: &Document,
    instances: &[Instance],
    bin: Option<&'a [u8]>,
    base_dir: Option<&Path>,
    name: &str,
) -> Result<Vec<Option<Cow<'a, [u8]>>>, MeshIoError> {
    let mut needed = BTreeSet::new();
    let meshes: BTreeSet<usize> = instances.iter().map(|i| i.mesh).collect();
    for mesh in doc.meshes().filter(|m| meshes.contains(&m.index())) {
        for prim in mesh.primitives() {
            let accessors = prim
                .get(&::gltf::Semantic::Positions)
                .into_iter()
                .chain(prim.indices());
            for acc in accessors {
                needed.extend(acc.view().map(|v| v.buffer().index()));
                if let Some(sparse) = acc.sparse() {
                    needed.insert(sparse.indices().view().buffer().index());
                    needed.insert(sparse.values().view().buffer().index());
                }
            }
        }
    }
    let mut out: Vec<Option<Cow<'a, [u8]>>> = vec![None; doc.buffers().len()];
    for buffer in doc.buffers().filter(|b| needed.contains(&b.index())) {
        let index = buffer.index();
        let want = buffer.length();
        let (uri, data) = match buffer.source() {
            ::gltf::buffer::Source::Bin => ("GLB BIN chunk".to_owned(), bin.map(Cow::Borrowed)),
            ::gltf::buffer::Source::Uri(uri) => (
                excerpt_uri(uri),
                Some(
                    read_uri(uri, want, base_dir).map_err(|message| MeshIoError::Buffer {
                        name: name.to_owned(),
                        buffer: index,
                        uri: excerpt_uri(uri),
                        message,
                    })?,
                ),
            ),
        };
        let fail = |message: String| MeshIoError::Buffer {
            name: name.to_owned(),
            buffer: index,
            uri: uri.clone(),
            message,
        };
        let data = data.ok_or_else(|| fail("the file has no BIN chunk".to_owned()))?;
        if data.len() < want {
            return Err(fail(format!(
                "{} bytes, but byteLength is {want}",
                data.len()
            )));
        }
        out[index] = Some(match data {
            Cow::Borrowed(b) => Cow::Borrowed(&b[..want]),
            Cow::Owned(mut v) => {
                v.truncate(want);
                Cow::Owned(v)
            }
        });
    }
    Ok(out)
}

/// A URI shortened for messages (data URIs can be megabytes long).
fn excerpt_uri(uri: &str) -> String {
    if uri.starts_with("data:") {
        let head: String = uri.chars().take_while(|&c| c != ',').take(60).collect();
        format!("{head},…")
    } else {
        uri.chars().take(200).collect()
    }
}

/// The bytes of a buffer URI: a base64 data URI, or a regular file inside `base_dir` (see
/// [`resolve_inside`]). Reads at most `want` bytes and refuses files shorter than that before
/// reading them. Messages name paths, never what a file contains.
fn read_uri(uri: &str, want: usize, base_dir: Option<&Path>) -> Result<Cow<'static, [u8]>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((_, payload)) = rest.split_once(";base64,") else {
            return Err("only base64 data URIs are supported".to_owned());
        };
        let engine = base64::engine::GeneralPurpose::new(
            &base64::alphabet::STANDARD,
            base64::engine::GeneralPurposeConfig::new()
                .with_decode_padding_mode(base64::engine::DecodePaddingMode::Indifferent),
        );
        return engine
            .decode(payload.trim_end())
            .map(Cow::Owned)
            .map_err(|e| format!("bad base64: {e}"));
    }
    let dir = base_dir.ok_or_else(|| {
        "external buffer, but no directory to look in (reading from memory)".to_owned()
    })?;
    let path = resolve_inside(uri, dir)?;
    let shown = path.display();
    let file = std::fs::File::open(&path).map_err(|e| format!("cannot open {shown}: {e}"))?;
    let meta = file
        .metadata()
        .map_err(|e| format!("cannot read {shown}: {e}"))?;
    // Checked again on the open file: it may have been replaced since `resolve_inside`.
    if !meta.is_file() {
        return Err(format!("{shown} is not a regular file"));
    }
    let have = meta.len();
    if have < want as u64 {
        return Err(format!(
            "{shown} has {have} bytes, but byteLength is {want}"
        ));
    }
    let mut data = Vec::with_capacity(want); // bounded by the file's real size, checked above
    file.take(want as u64)
        .read_to_end(&mut data)
        .map_err(|e| format!("cannot read {shown}: {e}"))?;
    Ok(Cow::Owned(data))
}

/// The file a relative URI reference names inside `dir`, canonical, checked to be a regular
/// file there without opening it.
///
/// A part file is often handed over by someone else, and `wavemill` may run where it can read
/// more than that person should see: a URI must not reach `/etc/passwd`, a sibling project or
/// a FIFO that blocks the reader forever. So URIs with a scheme (`file:`, `http:`, and `C:`,
/// which parses as one) and absolute paths are refused; the rest is percent-decoded, joined to
/// `dir` and canonicalised, which resolves `..` and symlinks, and must still lie inside the
/// canonical `dir`; and it must be a regular file (metadata is read before opening, since
/// opening a FIFO already blocks). A file swapped for a FIFO between that check and the open
/// is not guarded against.
fn resolve_inside(uri: &str, dir: &Path) -> Result<PathBuf, String> {
    // RFC 3986 §4.2: a relative reference's first segment has no ':', so a ':' before any '/'
    // means a scheme.
    if let Some(colon) = uri.find(':')
        && !uri[..colon].contains('/')
    {
        return Err(format!(
            "'{}:' URIs are not read: only data URIs and paths relative to the glTF file's folder",
            &uri[..colon]
        ));
    }
    let decoded = percent_decode(uri);
    if decoded.contains('\0') {
        return Err("the path contains a NUL byte".to_owned());
    }
    let rel = Path::new(&decoded);
    if decoded.starts_with('/') || decoded.starts_with('\\') || rel.has_root() {
        return Err(
            "absolute paths are not read: only paths relative to the glTF file's folder".to_owned(),
        );
    }
    // `Path::parent` of a bare file name is "", which canonicalize does not accept.
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    let folder = dir.canonicalize().map_err(|e| {
        format!(
            "cannot resolve the glTF file's folder {}: {e}",
            dir.display()
        )
    })?;
    let joined = folder.join(rel);
    let path = joined
        .canonicalize()
        .map_err(|e| format!("cannot open {}: {e}", joined.display()))?;
    if !path.starts_with(&folder) {
        return Err(format!(
            "resolves to {}, outside the glTF file's folder {}",
            path.display(),
            folder.display()
        ));
    }
    let meta =
        std::fs::metadata(&path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    if !meta.is_file() {
        return Err(format!(
            "{} is {}, not a regular file",
            path.display(),
            file_kind(&meta.file_type())
        ));
    }
    Ok(path)
}

/// What a non-regular file is, for messages.
fn file_kind(ty: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt as _;
        if ty.is_fifo() {
            return "a FIFO";
        }
        if ty.is_char_device() || ty.is_block_device() {
            return "a device";
        }
        if ty.is_socket() {
            return "a socket";
        }
    }
    if ty.is_dir() {
        "a directory"
    } else {
        "a special file"
    }
}

/// `%20` → space etc.; malformed escapes are kept as they are.
fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        match (
            b[i],
            b.get(i + 1).and_then(|&c| hex(c)),
            b.get(i + 2).and_then(|&c| hex(c)),
        ) {
            (b'%', Some(h), Some(l)) => {
                out.push((h * 16 + l) as u8);
                i += 3;
            }
            (c, _, _) => {
                out.push(c);
                i += 1;
            }
        }
    }
    String::from_utf8(out).unwrap_or_else(|_| s.to_owned())
}

/// Triangulates one primitive's index list. Strips alternate winding (glTF 2.0 §3.7.2.1:
/// triangle i is (vᵢ, vᵢ₊₁₊ᵢ﹪₂, vᵢ₊₂₋ᵢ﹪₂)); fans turn around v₀. Degenerate strip and fan
/// triangles (a repeated index: stitches between strips) are skipped. Returns notes.
fn triangulate(mode: Mode, idx: &[u32], out: &mut Vec<[u32; 3]>) -> Vec<String> {
    let mut notes = Vec::new();
    match mode {
        Mode::Triangles => {
            out.extend(idx.chunks_exact(3).map(|t| [t[0], t[1], t[2]]));
            let rest = idx.len() % 3;
            if rest != 0 {
                notes.push(format!(
                    "{} indices is not a multiple of 3; the last {rest} ignored",
                    idx.len()
                ));
            }
        }
        Mode::TriangleStrip | Mode::TriangleFan => {
            let mut degenerate = 0usize;
            for i in 0..idx.len().saturating_sub(2) {
                let t = if mode == Mode::TriangleFan {
                    [idx[0], idx[i + 1], idx[i + 2]]
                } else if i % 2 == 0 {
                    [idx[i], idx[i + 1], idx[i + 2]]
                } else {
                    [idx[i], idx[i + 2], idx[i + 1]]
                };
                if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                    degenerate += 1;
                } else {
                    out.push(t);
                }
            }
            if idx.len() < 3 {
                notes.push(format!("{mode:?} with {} vertices ignored", idx.len()));
            }
            if degenerate > 0 {
                notes.push(format!(
                    "{degenerate} degenerate {mode:?} triangles skipped"
                ));
            }
        }
        _ => {}
    }
    notes
}

/// What an accessor reader needs to know and to say in errors.
struct Ctx<'a, 'b> {
    name: &'a str,
    format: Format,
    here: &'a str,
    buffers: &'a [Option<Cow<'b, [u8]>>],
    input_len: usize,
    /// The file declares `KHR_mesh_quantization`: integer POSITION accessors are allowed.
    quantized_positions: bool,
}

impl Ctx<'_, '_> {
    fn err(&self, acc: usize, message: String) -> MeshIoError {
        MeshIoError::Invalid {
            name: self.name.to_owned(),
            format: self.format,
            message: format!("{}: accessor {acc}: {message}", self.here),
        }
    }

    /// POSITION is FLOAT VEC3 (glTF 2.0 §3.7.2.1); with `KHR_mesh_quantization` also BYTE,
    /// UNSIGNED_BYTE, SHORT or UNSIGNED_SHORT, normalized or not, which [`component`] decodes
    /// as that extension says (the node transform then dequantizes).
    fn read_positions(&self, acc: &Accessor) -> Result<Vec<Point3<f64>>, MeshIoError> {
        let ty = acc.data_type();
        let allowed = match ty {
            DataType::F32 => !acc.normalized(),
            DataType::I8 | DataType::U8 | DataType::I16 | DataType::U16 => self.quantized_positions,
            DataType::U32 => false,
        };
        if acc.dimensions() != Dimensions::Vec3 || !allowed {
            let hint = if self.quantized_positions {
                "FLOAT, or BYTE/UNSIGNED_BYTE/SHORT/UNSIGNED_SHORT under KHR_mesh_quantization"
            } else {
                "FLOAT (integer types need the KHR_mesh_quantization extension, \
                 which the file does not declare)"
            };
            return Err(self.err(
                acc.index(),
                format!(
                    "POSITION is declared {}{} {}, but must be VEC3 of {hint}",
                    if acc.normalized() { "normalized " } else { "" },
                    component_type_name(ty),
                    dimensions_name(acc.dimensions()),
                ),
            ));
        }
        let flat = self.read(acc)?;
        Ok(flat
            .chunks_exact(3)
            .map(|c| Point3::new(c[0], c[1], c[2]))
            .collect())
    }

    fn read_indices(&self, acc: &Accessor) -> Result<Vec<u32>, MeshIoError> {
        if acc.dimensions() != Dimensions::Scalar
            || !matches!(
                acc.data_type(),
                DataType::U8 | DataType::U16 | DataType::U32
            )
        {
            return Err(self.err(
                acc.index(),
                format!(
                    "indices are declared {} {}, but must be SCALAR of UNSIGNED_BYTE, \
                     UNSIGNED_SHORT or UNSIGNED_INT",
                    component_type_name(acc.data_type()),
                    dimensions_name(acc.dimensions())
                ),
            ));
        }
        if acc.normalized() {
            return Err(self.err(acc.index(), "indices must not be normalized".to_owned()));
        }
        // Unsigned integers up to u32::MAX are exact in f64.
        Ok(self.read(acc)?.into_iter().map(|x| x as u32).collect())
    }

    /// The bytes of a buffer view, checked against its buffer.
    fn view_bytes(&self, acc: usize, view: &::gltf::buffer::View) -> Result<&[u8], MeshIoError> {
        let buffer = view.buffer().index();
        let data = self
            .buffers
            .get(buffer)
            .and_then(|b| b.as_deref())
            .ok_or_else(|| self.err(acc, format!("buffer {buffer} was not loaded")))?;
        view.offset()
            .checked_add(view.length())
            .and_then(|end| data.get(view.offset()..end))
            .ok_or_else(|| {
                self.err(
                    acc,
                    format!(
                        "buffer view {} (offset {}, length {}) exceeds buffer {buffer} ({} bytes)",
                        view.index(),
                        view.offset(),
                        view.length(),
                        data.len()
                    ),
                )
            })
    }

    /// All components of an accessor as f64, flat (count × components), with sparse
    /// substitution and normalisation applied. Sizes are checked before allocating.
    fn read(&self, acc: &Accessor) -> Result<Vec<f64>, MeshIoError> {
        let ai = acc.index();
        let dims = acc.dimensions().multiplicity();
        let ty = acc.data_type();
        let comp = ty.size();
        let elem = comp * dims;
        let count = acc.count();
        let norm = acc.normalized();
        if count > self.input_len {
            return Err(self.err(ai, format!("count {count} is larger than the input")));
        }
        let base = match acc.view() {
            Some(view) => {
                let data = self.view_bytes(ai, &view)?;
                let stride = view.stride().unwrap_or(elem);
                if stride < elem {
                    return Err(self.err(ai, format!("byteStride {stride} < element size {elem}")));
                }
                let need = match count {
                    0 => Some(0),
                    n => (n - 1)
                        .checked_mul(stride)
                        .and_then(|x| x.checked_add(elem))
                        .and_then(|x| x.checked_add(acc.offset())),
                };
                if need.is_none_or(|need| need > data.len()) {
                    return Err(self.err(
                        ai,
                        format!(
                            "{count} elements of {elem} bytes (stride {stride}, offset {}) \
                             exceed buffer view {} ({} bytes)",
                            acc.offset(),
                            view.index(),
                            data.len()
                        ),
                    ));
                }
                Some((data, stride))
            }
            None => None,
        };
        let mut out = vec![0.0; count * dims]; // count <= input length, dims <= 16
        if let Some((data, stride)) = base {
            for (k, e) in out.chunks_exact_mut(dims).enumerate() {
                let at = acc.offset() + k * stride; // checked above
                for (c, x) in e.iter_mut().enumerate() {
                    *x = component(data, at + c * comp, ty, norm)
                        .ok_or_else(|| self.err(ai, "read past the view".to_owned()))?;
                }
            }
        }
        if let Some(sparse) = acc.sparse() {
            let n = sparse.count();
            if n > count {
                return Err(self.err(ai, format!("{n} sparse values for {count} elements")));
            }
            let ind = sparse.indices();
            let (ity, isz) = match ind.index_type() {
                ::gltf::accessor::sparse::IndexType::U8 => (DataType::U8, 1),
                ::gltf::accessor::sparse::IndexType::U16 => (DataType::U16, 2),
                ::gltf::accessor::sparse::IndexType::U32 => (DataType::U32, 4),
            };
            let idata = self.view_bytes(ai, &ind.view())?;
            let vals = sparse.values();
            let vdata = self.view_bytes(ai, &vals.view())?;
            let fits = |off: usize, size: usize, len: usize| {
                n.checked_mul(size)
                    .and_then(|x| x.checked_add(off))
                    .is_some_and(|end| end <= len)
            };
            if !fits(ind.offset(), isz, idata.len()) || !fits(vals.offset(), elem, vdata.len()) {
                return Err(self.err(ai, "sparse indices or values exceed their views".to_owned()));
            }
            for j in 0..n {
                let target = component(idata, ind.offset() + j * isz, ity, false)
                    .map(|x| x as usize)
                    .filter(|&t| t < count)
                    .ok_or_else(|| self.err(ai, format!("sparse index {j} out of range")))?;
                for c in 0..dims {
                    out[target * dims + c] =
                        component(vdata, vals.offset() + j * elem + c * comp, ty, norm)
                            .ok_or_else(|| self.err(ai, "read past the view".to_owned()))?;
                }
            }
        }
        Ok(out)
    }
}

/// One little-endian component at byte `at`, normalised as glTF 2.0 §3.11 says.
fn component(data: &[u8], at: usize, ty: DataType, normalized: bool) -> Option<f64> {
    let b = data.get(at..at.checked_add(ty.size())?)?;
    Some(match ty {
        DataType::I8 => {
            let v = f64::from(b[0] as i8);
            if normalized { (v / 127.0).max(-1.0) } else { v }
        }
        DataType::U8 => {
            let v = f64::from(b[0]);
            if normalized { v / 255.0 } else { v }
        }
        DataType::I16 => {
            let v = f64::from(i16::from_le_bytes([b[0], b[1]]));
            if normalized {
                (v / 32767.0).max(-1.0)
            } else {
                v
            }
        }
        DataType::U16 => {
            let v = f64::from(u16::from_le_bytes([b[0], b[1]]));
            if normalized { v / 65535.0 } else { v }
        }
        DataType::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        DataType::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
    })
}

/// The glTF name of a component type, as a file's author would look it up.
fn component_type_name(ty: DataType) -> &'static str {
    match ty {
        DataType::I8 => "BYTE (5120)",
        DataType::U8 => "UNSIGNED_BYTE (5121)",
        DataType::I16 => "SHORT (5122)",
        DataType::U16 => "UNSIGNED_SHORT (5123)",
        DataType::U32 => "UNSIGNED_INT (5125)",
        DataType::F32 => "FLOAT (5126)",
    }
}

/// The glTF name of an accessor type.
fn dimensions_name(d: Dimensions) -> &'static str {
    match d {
        Dimensions::Scalar => "SCALAR",
        Dimensions::Vec2 => "VEC2",
        Dimensions::Vec3 => "VEC3",
        Dimensions::Vec4 => "VEC4",
        Dimensions::Mat2 => "MAT2",
        Dimensions::Mat3 => "MAT3",
        Dimensions::Mat4 => "MAT4",
    }
}
