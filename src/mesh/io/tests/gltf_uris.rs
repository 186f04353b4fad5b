//! Issue 17 item 10: glTF buffer URIs are read only from data URIs or from regular files inside
//! the part file's folder. Each hostile case below was read (or hung the reader) before.
//!
//! Layout of each scratch folder: `outer/secret.bin` (a file the part must not reach, long
//! enough for the buffer, with a marker that must never show up in a message) and
//! `outer/part/t.gltf` (the part).

use std::path::{Path, PathBuf};

use serde_json::json;

use super::gltf_doc::Doc;
use super::{scratch_dir, tetra};
use crate::mesh::io::{MeshIoError, RawMesh, Units, read_mesh};

const MARKER: &[u8] = b"TOPSECRET-CONTENT";

/// The tetrahedron, mesh 0 on node 0, buffer in an external file.
fn tetra_doc() -> Doc {
    let mut d = Doc::default();
    let (pts, idx) = super::gltf_doc::tetra_arrays();
    let p = d.positions(&pts);
    let i = d.indices_u16(&idx);
    d.mesh(vec![Doc::prim(p, Some(i), 4)]);
    d.node(json!({ "mesh": 0 }));
    d.scenes = Some(vec![vec![0]]);
    d
}

/// Makes `outer/secret.bin` (the tetra's real buffer followed by the marker, so a reader that
/// follows the URI would even load a valid mesh) and `outer/part/`; returns (outer, part dir).
fn folders(test: &str) -> (PathBuf, PathBuf) {
    let outer = scratch_dir(test);
    let part = outer.join("part");
    std::fs::create_dir_all(&part).unwrap();
    let (_, mut bin) = tetra_doc().gltf_external("x");
    bin.extend_from_slice(MARKER);
    std::fs::write(outer.join("secret.bin"), bin).unwrap();
    (outer, part)
}

/// Writes `part/t.gltf` referring to `uri` and reads it.
fn read_with_uri(part: &Path, uri: &str) -> Result<RawMesh, MeshIoError> {
    let (json, _) = tetra_doc().gltf_external(uri);
    let gltf = part.join("t.gltf");
    std::fs::write(&gltf, json).unwrap();
    read_mesh(&gltf, Units::Millimetres)
}

/// The read must fail with a buffer error naming the glTF file and the URI as written, saying
/// `why`, and showing nothing of the file the URI points at.
fn assert_refused(result: Result<RawMesh, MeshIoError>, uri: &str, why: &str) {
    let e = match result {
        Ok(_) => panic!("{uri}: read, but must be refused"),
        Err(e) => e,
    };
    let msg = e.to_string();
    assert!(matches!(e, MeshIoError::Buffer { .. }), "{uri}: {msg}");
    assert!(msg.contains("t.gltf") && msg.contains(uri), "{uri}: {msg}");
    assert!(msg.contains(why), "{uri}: expected `{why}` in: {msg}");
    let marker = std::str::from_utf8(MARKER).unwrap();
    assert!(!msg.contains(marker), "{uri}: file content in: {msg}");
    assert!(
        !msg.contains("root:"),
        "{uri}: /etc/passwd content in: {msg}"
    );
}

#[test]
fn relative_escape_from_the_folder_is_refused() {
    let (outer, part) = folders("uri_escape");
    assert_refused(
        read_with_uri(&part, "../secret.bin"),
        "../secret.bin",
        "outside the glTF file's folder",
    );
    // Down and back up out of the folder, through a real subfolder.
    std::fs::create_dir_all(part.join("sub")).unwrap();
    assert_refused(
        read_with_uri(&part, "sub/../../secret.bin"),
        "sub/../../secret.bin",
        "outside",
    );
    std::fs::remove_dir_all(outer).unwrap();
}

#[test]
fn absolute_paths_are_refused() {
    let (outer, part) = folders("uri_absolute");
    let secret = outer.join("secret.bin").canonicalize().unwrap();
    let uri = secret.to_str().unwrap().to_owned();
    assert_refused(
        read_with_uri(&part, &uri),
        &uri,
        "absolute paths are not read",
    );
    if Path::new("/etc/passwd").is_file() {
        assert_refused(
            read_with_uri(&part, "/etc/passwd"),
            "/etc/passwd",
            "absolute paths are not read",
        );
    }
    std::fs::remove_dir_all(outer).unwrap();
}

#[test]
fn file_and_other_scheme_uris_are_refused() {
    let (outer, part) = folders("uri_scheme");
    let secret = outer.join("secret.bin").canonicalize().unwrap();
    let uri = format!("file://{}", secret.display());
    assert_refused(
        read_with_uri(&part, &uri),
        &uri,
        "'file:' URIs are not read",
    );
    // Even a file: URI naming a file in the folder: a scheme means "not relative".
    std::fs::copy(&secret, part.join("inside.bin")).unwrap();
    assert_refused(
        read_with_uri(&part, "file:inside.bin"),
        "file:inside.bin",
        "'file:' URIs",
    );
    assert_refused(
        read_with_uri(&part, "https://example.com/t.bin"),
        "https://example.com/t.bin",
        "'https:' URIs",
    );
    std::fs::remove_dir_all(outer).unwrap();
}

#[test]
fn percent_encoded_escapes_are_refused() {
    let (outer, part) = folders("uri_percent");
    for uri in [
        "..%2Fsecret.bin",
        "%2E%2E%2Fsecret.bin",
        "%2e%2e/secret.bin",
    ] {
        assert_refused(read_with_uri(&part, uri), uri, "outside");
    }
    let secret = outer.join("secret.bin").canonicalize().unwrap();
    let encoded = secret.to_str().unwrap().replace('/', "%2F");
    assert_refused(
        read_with_uri(&part, &encoded),
        &encoded,
        "absolute paths are not read",
    );
    std::fs::remove_dir_all(outer).unwrap();
}

#[cfg(unix)]
#[test]
fn symlink_inside_the_folder_pointing_outside_is_refused() {
    let (outer, part) = folders("uri_symlink");
    std::os::unix::fs::symlink(outer.join("secret.bin"), part.join("link.bin")).unwrap();
    assert_refused(read_with_uri(&part, "link.bin"), "link.bin", "outside");
    // A symlinked folder leading out is the same.
    std::os::unix::fs::symlink(&outer, part.join("up")).unwrap();
    assert_refused(
        read_with_uri(&part, "up/secret.bin"),
        "up/secret.bin",
        "outside",
    );
    std::fs::remove_dir_all(outer).unwrap();
}

/// A FIFO blocks `open` until a writer appears: before the fix `wavemill info` hung. The read
/// runs on a thread so that a regression fails the test instead of hanging it.
#[cfg(unix)]
#[test]
fn fifo_and_directory_are_refused_without_opening_them() {
    let (outer, part) = folders("uri_fifo");
    std::fs::create_dir_all(part.join("dir.bin")).unwrap();
    assert_refused(read_with_uri(&part, "dir.bin"), "dir.bin", "a directory");
    let made = std::process::Command::new("mkfifo")
        .arg(part.join("pipe.bin"))
        .status();
    if !made.is_ok_and(|s| s.success()) {
        eprintln!("skipped: the FIFO case (mkfifo is not available)");
        std::fs::remove_dir_all(outer).unwrap();
        return;
    }
    let (json, _) = tetra_doc().gltf_external("pipe.bin");
    let gltf = part.join("t.gltf");
    std::fs::write(&gltf, json).unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(read_mesh(&gltf, Units::Millimetres));
    });
    let result = rx
        .recv_timeout(std::time::Duration::from_secs(20))
        .expect("reading a glTF whose buffer is a FIFO hangs");
    assert_refused(result, "pipe.bin", "a FIFO, not a regular file");
    std::fs::remove_dir_all(outer).unwrap();
}

#[test]
fn legitimate_relative_buffers_still_load() {
    let (outer, part) = folders("uri_ok");
    let (_, bin) = tetra_doc().gltf_external("x");
    std::fs::write(part.join("t.bin"), &bin).unwrap();
    std::fs::create_dir_all(part.join("buffers/deeper")).unwrap();
    std::fs::write(part.join("buffers/deeper/t 2.bin"), &bin).unwrap();
    for uri in [
        "t.bin",
        "./t.bin",
        "buffers/deeper/t%202.bin",
        "buffers/../t.bin",
    ] {
        let got = read_with_uri(&part, uri).unwrap_or_else(|e| panic!("{uri}: {e}"));
        assert_eq!(got.mesh, tetra(), "{uri}");
    }
    // A symlink that stays inside the folder is fine.
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(part.join("t.bin"), part.join("alias.bin")).unwrap();
        assert_eq!(read_with_uri(&part, "alias.bin").unwrap().mesh, tetra());
    }
    std::fs::remove_dir_all(outer).unwrap();
}
