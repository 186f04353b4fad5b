//! Tests for `mesh::io`: one file per reader, round trips, fuzzing, real files.
//!
//! Shapes are checked by invariants (counts, signed volume, normals, triangle soups), not by
//! vertex order, except where the format fixes the order.

use nalgebra::{Point3, Vector3};

use crate::mesh::Mesh;

mod api;
mod fuzz;
mod gltf_doc;
mod gltf_uris;
mod read_gltf;
mod read_obj;
mod read_stl;
mod real_data;
mod round_trip;

/// A tetrahedron with outward (CCW) triangles; volume 1/6.
pub fn tetra() -> Mesh {
    Mesh {
        positions: vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
            Point3::new(0.0, 0.0, 1.0),
        ],
        triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    }
}

/// The cube [0,2]×[0,3]×[0,4] (volume 24) as 12 outward triangles.
pub fn cube() -> Mesh {
    let positions = (0..8)
        .map(|i| {
            Point3::new(
                2.0 * f64::from(i & 1),
                3.0 * f64::from((i >> 1) & 1),
                4.0 * f64::from((i >> 2) & 1),
            )
        })
        .collect();
    let quads = cube_quads();
    let triangles = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    Mesh {
        positions,
        triangles,
    }
}

/// The cube's six faces as CCW quads (vertex i has coordinates from bits x=1, y=2, z=4).
pub fn cube_quads() -> [[u32; 4]; 6] {
    [
        [0, 2, 3, 1], // z = 0, normal -z
        [4, 5, 7, 6], // z = 4, +z
        [0, 1, 5, 4], // y = 0, -y
        [2, 6, 7, 3], // y = 3, +y
        [0, 4, 6, 2], // x = 0, -x
        [1, 3, 7, 5], // x = 2, +x
    ]
}

/// Signed volume (divergence theorem): positive when the triangles face outward.
pub fn signed_volume(m: &Mesh) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize].coords);
            a.dot(&b.cross(&c)) / 6.0
        })
        .sum()
}

/// The triangles as position triples, in order.
pub fn soup(m: &Mesh) -> Vec<[Point3<f64>; 3]> {
    m.triangles
        .iter()
        .map(|t| t.map(|i| m.positions[i as usize]))
        .collect()
}

/// Unit normal of triangle `f`.
pub fn normal(m: &Mesh, f: usize) -> Vector3<f64> {
    let [a, b, c] = m.triangles[f].map(|i| m.positions[i as usize]);
    (b - a).cross(&(c - a)).normalize()
}

pub fn close(a: &Point3<f64>, b: &Point3<f64>, rel: f64) -> bool {
    (a - b).norm() <= rel * (1.0 + a.coords.norm().max(b.coords.norm()))
}

/// ASCII STL of a mesh (one `solid` block), with junk normals.
pub fn ascii_stl(m: &Mesh, name: &str) -> Vec<u8> {
    let mut s = format!("solid {name}\n");
    for t in soup(m) {
        s.push_str("  facet normal 0 0 0\n    outer loop\n");
        for p in t {
            s.push_str(&format!("      vertex {} {} {}\n", p.x, p.y, p.z));
        }
        s.push_str("    endloop\n  endfacet\n");
    }
    s.push_str(&format!("endsolid {name}\n"));
    s.into_bytes()
}

/// Binary STL of a mesh with the given header text (padded to 80 bytes).
pub fn binary_stl(m: &Mesh, header: &str) -> Vec<u8> {
    let mut b = header.as_bytes().to_vec();
    b.resize(80, 0);
    b.extend_from_slice(&(m.triangles.len() as u32).to_le_bytes());
    for t in soup(m) {
        b.extend_from_slice(&[0u8; 12]);
        for p in t {
            for x in [p.x, p.y, p.z] {
                b.extend_from_slice(&(x as f32).to_le_bytes());
            }
        }
        b.extend_from_slice(&[0u8; 2]);
    }
    b
}

/// A fresh, empty scratch directory for one test.
pub fn scratch_dir(test: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("meshio-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The cube as OBJ with quads, texture coordinates and normals, in two groups.
pub fn cube_obj() -> String {
    let m = cube();
    let mut s = String::from("# cube\nmtllib missing.mtl\no cube\n");
    for p in &m.positions {
        s.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
    }
    s.push_str("vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\nusemtl steel\ng half1\ns off\n");
    for (k, q) in cube_quads().iter().enumerate() {
        if k == 3 {
            s.push_str("g half2\n");
        }
        let [a, b, c, d] = q.map(|i| i + 1);
        s.push_str(&format!("f {a}/1/1 {b}/2/1 {c}/3/1 {d}//1\n"));
    }
    s
}
