//! Small meshes and an OBJ reader (v/f lines only) for the multires tests.

use nalgebra::Point3;

use super::Creases;
use crate::mesh::Mesh;

/// Parses `v x y z` and `f i j k` lines (1-based, `i/..` suffixes ignored); panics on
/// anything malformed (test data).
pub fn parse_obj(text: &str) -> Mesh {
    let mut mesh = Mesh::default();
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let c: Vec<f64> = it.map(|x| x.parse().unwrap()).collect();
                assert_eq!(c.len(), 3, "{line}");
                mesh.positions.push(Point3::new(c[0], c[1], c[2]));
            }
            Some("f") => {
                let i: Vec<u32> = it
                    .map(|x| x.split('/').next().unwrap().parse::<u32>().unwrap() - 1)
                    .collect();
                assert_eq!(i.len(), 3, "{line}");
                mesh.triangles.push([i[0], i[1], i[2]]);
            }
            _ => {}
        }
    }
    mesh
}

/// Reads `tests/data/loop_reference/<name>`.
pub fn reference_obj(name: &str) -> Mesh {
    let path = format!(
        "{}/tests/data/loop_reference/{name}",
        env!("CARGO_MANIFEST_DIR")
    );
    parse_obj(&std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}")))
}

/// Flips triangles of a mesh star-shaped around the origin so normals point outward.
fn orient_outward(mut m: Mesh) -> Mesh {
    for t in m.triangles.iter_mut() {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        let n = (b - a).cross(&(c - a));
        if n.dot(&(a.coords + b.coords + c.coords)) < 0.0 {
            t.swap(1, 2);
        }
    }
    m
}

/// Regular octahedron, vertices at ±1 on the axes (valence 4).
pub fn octahedron() -> Mesh {
    let positions = vec![
        Point3::new(1.0, 0.0, 0.0),
        Point3::new(-1.0, 0.0, 0.0),
        Point3::new(0.0, 1.0, 0.0),
        Point3::new(0.0, -1.0, 0.0),
        Point3::new(0.0, 0.0, 1.0),
        Point3::new(0.0, 0.0, -1.0),
    ];
    let mut triangles = Vec::new();
    for x in [0, 1] {
        for y in [2, 3] {
            for z in [4, 5] {
                triangles.push([x, y, z]);
            }
        }
    }
    orient_outward(Mesh {
        positions,
        triangles,
    })
}

/// Cube [-1, 1]³, vertex i = (bit0, bit1, bit2) mapped to ±1, 12 triangles.
pub fn cube() -> Mesh {
    let positions = (0..8)
        .map(|i| {
            let s = |b: u32| if i & (1 << b) != 0 { 1.0 } else { -1.0 };
            Point3::new(s(0), s(1), s(2))
        })
        .collect();
    let mut triangles = Vec::new();
    for d in 0..3u32 {
        for side in [0, 1] {
            let (u, v) = ((d + 1) % 3, (d + 2) % 3);
            let q =
                [(0, 0), (1, 0), (1, 1), (0, 1)].map(|(x, y)| (side << d) | (x << u) | (y << v));
            triangles.push([q[0], q[1], q[2]]);
            triangles.push([q[0], q[2], q[3]]);
        }
    }
    orient_outward(Mesh {
        positions,
        triangles,
    })
}

/// The 12 edges of [`cube`] (vertex pairs differing in one bit).
pub fn cube_edges() -> Creases {
    Creases::from_edges((0..8u32).flat_map(|i| (0..3).map(move |b| [i, i ^ (1 << b)])))
}

/// Flat `nx × ny` grid of unit squares in z = 0, vertex `x + (nx + 1) y`. `regular`: all
/// diagonals the same way (interior valence 6); else alternating (valences 4 and 8).
pub fn grid(nx: u32, ny: u32, regular: bool) -> Mesh {
    let mut positions = Vec::new();
    for y in 0..=ny {
        for x in 0..=nx {
            positions.push(Point3::new(f64::from(x), f64::from(y), 0.0));
        }
    }
    let id = |x: u32, y: u32| x + (nx + 1) * y;
    let mut triangles = Vec::new();
    for y in 0..ny {
        for x in 0..nx {
            let (a, b, c, d) = (id(x, y), id(x + 1, y), id(x + 1, y + 1), id(x, y + 1));
            if regular || (x + y) % 2 == 0 {
                triangles.extend([[a, b, c], [a, c, d]]);
            } else {
                triangles.extend([[a, b, d], [b, c, d]]);
            }
        }
    }
    Mesh {
        positions,
        triangles,
    }
}

/// Flat disc: centre 0 and `n` rim vertices on the unit circle (open, curved boundary).
pub fn fan(n: u32) -> Mesh {
    let mut positions = vec![Point3::origin()];
    for i in 0..n {
        let a = std::f64::consts::TAU * f64::from(i) / f64::from(n);
        positions.push(Point3::new(a.cos(), a.sin(), 0.0));
    }
    let triangles = (0..n).map(|i| [0, 1 + i, 1 + (i + 1) % n]).collect();
    Mesh {
        positions,
        triangles,
    }
}

/// Closed mesh with valences 3..8 (committed input of the trimesh reference).
pub fn irregular_closed() -> Mesh {
    reference_obj("irregular_input.obj")
}
