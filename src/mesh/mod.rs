//! Triangle meshes: the part as the planner sees it.
//!
//! * [`io`] reads STL, OBJ and glTF/GLB into a raw triangle soup and writes OBJ and GLB;
//! * [`weld`] merges duplicate vertices (every STL stores three copies of each vertex);
//! * [`topology`] finds edges, boundaries, non-manifold places, components, genus, and makes the
//!   winding consistent and outward where the surface allows it;
//! * [`pieces`] lists the connected pieces and tells stray debris (tiny against the largest
//!   piece) from the part;
//! * [`distance`]: exact f64 closest points and signed distance to the mesh (the gouge
//!   guarantee every stage measures with);
//! * [`section`]: the mesh cut by a plane, as ordered polylines;
//! * [`prepare`] runs those in order and returns the clean [`Mesh`] with a [`MeshReport`];
//!   [`prepare_without_stray_pieces`] also sets the stray pieces aside, for planning.
//!
//! Connectivity code never looks at positions except where a decision needs geometry (zero-area
//! faces, the outward sign of a closed component): the same split spade and geometry-central make.

pub mod distance;
pub mod io;
pub mod pieces;
mod prepare;
pub mod region;
pub mod section;
pub mod topology;
pub mod weld;

pub use distance::{Closest, SegmentSearch, SurfaceDistance};
pub use section::{DrivePoint, SectionCurve, level_section, plane_section};

pub use pieces::{Piece, PieceSplit, StrayPieceRule, set_aside_warning, split_stray_pieces};

/// The largest coordinate magnitude a part may have, in millimetres (1000 km): beyond it a
/// file is in the wrong units or broken, and counts derived from the part's extent (grid
/// cells, layers) would overflow.
pub const MAX_COORDINATE_MM: f64 = 1e9;
pub use prepare::{
    MAX_LISTED_PIECES, MeshReport, PrepareError, PrepareOptions, UnitsGuess, prepare,
    prepare_without_stray_pieces,
};

use crate::geom::{Aabb, Point3, Vector3, triangle_area, triangle_normal};

/// An indexed triangle mesh in millimetres, f64. Triangles are counter-clockwise seen from
/// outside (outward normals by the right-hand rule).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<Point3>,
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// `triangles` (indices into `positions`) as a mesh with only the vertices they use, in
    /// the order they are first used.
    pub fn compacted(positions: &[Point3], triangles: impl IntoIterator<Item = [u32; 3]>) -> Mesh {
        let mut index = vec![u32::MAX; positions.len()];
        let mut kept = Vec::new();
        let triangles = triangles
            .into_iter()
            .map(|t| {
                t.map(|v| {
                    if index[v as usize] == u32::MAX {
                        index[v as usize] = kept.len() as u32;
                        kept.push(positions[v as usize]);
                    }
                    index[v as usize]
                })
            })
            .collect();
        Mesh {
            positions: kept,
            triangles,
        }
    }

    /// The three corners of triangle `t`.
    pub fn corners(&self, t: usize) -> [Point3; 3] {
        let [a, b, c] = self.triangles[t];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// Unit normal of triangle `t` (zero for a degenerate triangle).
    pub fn face_normal(&self, t: usize) -> Vector3 {
        let [a, b, c] = self.corners(t);
        let n = triangle_normal(&a, &b, &c);
        let len = n.norm();
        if len > 0.0 { n / len } else { Vector3::zeros() }
    }

    /// Area-weighted unit vertex normals (zero for isolated vertices and where the faces
    /// around a vertex cancel).
    pub fn vertex_normals(&self) -> Vec<Vector3> {
        let mut normal = vec![Vector3::zeros(); self.positions.len()];
        for tri in &self.triangles {
            let [a, b, c] = tri.map(|v| self.positions[v as usize]);
            let face = triangle_normal(&a, &b, &c);
            for &v in tri {
                normal[v as usize] += face;
            }
        }
        normal
            .iter()
            .map(|n| n.try_normalize(1e-300).unwrap_or_else(Vector3::zeros))
            .collect()
    }

    pub fn aabb(&self) -> Aabb {
        Aabb::from_points(&self.positions)
    }

    pub fn surface_area(&self) -> f64 {
        (0..self.triangles.len())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                triangle_area(&a, &b, &c)
            })
            .sum()
    }

    /// Signed volume by the divergence theorem; positive for a closed, outward-oriented surface.
    /// Summed relative to the box centre so that parts far from the origin lose no digits.
    pub fn signed_volume(&self) -> f64 {
        let o = self.aabb().center();
        (0..self.triangles.len())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                (a - o).dot(&(b - o).cross(&(c - o))) / 6.0
            })
            .sum()
    }

    /// Every index in range and every coordinate a finite length within
    /// [`MAX_COORDINATE_MM`]: what the rest of the planner assumes (grids sized by the part's
    /// extent must not overflow).
    pub fn check_indices_and_coordinates(&self) -> Result<(), String> {
        if let Some((i, p)) = self
            .positions
            .iter()
            .enumerate()
            .find(|(_, p)| !p.iter().all(|c| c.abs() <= MAX_COORDINATE_MM))
        {
            return Err(format!(
                "vertex {i} has a coordinate that is not a finite length within \
                 ±{MAX_COORDINATE_MM} mm: ({}, {}, {})",
                p.x, p.y, p.z
            ));
        }
        let n = self.positions.len();
        for (t, tri) in self.triangles.iter().enumerate() {
            if let Some(&i) = tri.iter().find(|&&i| i as usize >= n) {
                return Err(format!(
                    "triangle {t} refers to vertex {i}, but there are only {n} vertices"
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
pub(crate) mod fixtures {
    //! Small closed meshes with known answers, for the unit tests of several stages.
    use super::Mesh;
    use crate::geom::Point3;

    /// Axis-aligned box `[0,sx]×[0,sy]×[0,sz]`, outward, 12 triangles, 8 vertices.
    pub fn cuboid(sx: f64, sy: f64, sz: f64) -> Mesh {
        let positions = (0..8)
            .map(|i| {
                Point3::new(
                    if i & 1 != 0 { sx } else { 0.0 },
                    if i & 2 != 0 { sy } else { 0.0 },
                    if i & 4 != 0 { sz } else { 0.0 },
                )
            })
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let triangles = quads
            .iter()
            .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
            .collect();
        Mesh {
            positions,
            triangles,
        }
    }

    /// Axis-aligned box from `min` to `max`, outward.
    pub fn box_between(min: Point3, max: Point3) -> Mesh {
        let e = max - min;
        let mut m = cuboid(e.x, e.y, e.z);
        for p in &mut m.positions {
            *p += min.coords;
        }
        m
    }

    /// The meshes as one (separate closed pieces stay separate).
    pub fn joined(meshes: impl IntoIterator<Item = Mesh>) -> Mesh {
        let mut out = Mesh {
            positions: Vec::new(),
            triangles: Vec::new(),
        };
        for m in meshes {
            let base = out.positions.len() as u32;
            out.positions.extend(m.positions);
            out.triangles
                .extend(m.triangles.into_iter().map(|t| t.map(|i| i + base)));
        }
        out
    }

    /// A 100 × 100 plate `plate_height` thick with a 10 × 100 × 60 block (a wall) standing at
    /// x = `wall_x`: two closed pieces, for tests of tools near walls.
    pub fn plate_and_wall(plate_height: f64, wall_x: f64) -> Mesh {
        let mut m = cuboid(100.0, 100.0, plate_height);
        let wall = cuboid(10.0, 100.0, 60.0);
        let base = m.positions.len() as u32;
        m.positions.extend(
            wall.positions
                .iter()
                .map(|p| Point3::new(p.x + wall_x, p.y, p.z)),
        );
        m.triangles
            .extend(wall.triangles.iter().map(|t| t.map(|i| i + base)));
        m
    }

    /// A UV sphere of radius `r` around the origin, outward.
    pub fn uv_sphere(r: f64, stacks: u32, slices: u32) -> Mesh {
        let mut positions = vec![Point3::new(0.0, 0.0, r)];
        for i in 1..stacks {
            let phi = std::f64::consts::PI * i as f64 / stacks as f64;
            for j in 0..slices {
                let th = 2.0 * std::f64::consts::PI * j as f64 / slices as f64;
                positions.push(Point3::new(
                    r * phi.sin() * th.cos(),
                    r * phi.sin() * th.sin(),
                    r * phi.cos(),
                ));
            }
        }
        positions.push(Point3::new(0.0, 0.0, -r));
        let south = positions.len() as u32 - 1;
        let ring = |i: u32, j: u32| 1 + (i - 1) * slices + (j % slices);
        let mut triangles = Vec::new();
        for j in 0..slices {
            triangles.push([0, ring(1, j), ring(1, j + 1)]);
            triangles.push([south, ring(stacks - 1, j + 1), ring(stacks - 1, j)]);
        }
        for i in 1..stacks - 1 {
            for j in 0..slices {
                let (a, b, c, d) = (
                    ring(i, j),
                    ring(i, j + 1),
                    ring(i + 1, j),
                    ring(i + 1, j + 1),
                );
                triangles.push([a, c, d]);
                triangles.push([a, d, b]);
            }
        }
        Mesh {
            positions,
            triangles,
        }
    }

    /// A torus (genus 1) around the Z axis, outward.
    pub fn torus(major: f64, minor: f64, n_major: u32, n_minor: u32) -> Mesh {
        let mut positions = Vec::new();
        for i in 0..n_major {
            let u = 2.0 * std::f64::consts::PI * i as f64 / n_major as f64;
            for j in 0..n_minor {
                let v = 2.0 * std::f64::consts::PI * j as f64 / n_minor as f64;
                let rr = major + minor * v.cos();
                positions.push(Point3::new(rr * u.cos(), rr * u.sin(), minor * v.sin()));
            }
        }
        let id = |i: u32, j: u32| (i % n_major) * n_minor + (j % n_minor);
        let mut triangles = Vec::new();
        for i in 0..n_major {
            for j in 0..n_minor {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                triangles.push([a, b, c]);
                triangles.push([a, c, d]);
            }
        }
        Mesh {
            positions,
            triangles,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::fixtures::*;

    #[test]
    fn cuboid_volume_and_area_are_exact() {
        let m = cuboid(2.0, 3.0, 4.0);
        assert!((m.signed_volume() - 24.0).abs() < 1e-12);
        assert!((m.surface_area() - 2.0 * (6.0 + 8.0 + 12.0)).abs() < 1e-12);
    }

    #[test]
    fn sphere_volume_converges() {
        let m = uv_sphere(10.0, 64, 128);
        let exact = 4.0 / 3.0 * std::f64::consts::PI * 1000.0;
        assert!(m.signed_volume() > 0.0);
        assert!((m.signed_volume() - exact).abs() / exact < 0.005);
    }

    #[test]
    fn bad_index_is_reported() {
        let mut m = cuboid(1.0, 1.0, 1.0);
        m.triangles.push([0, 1, 99]);
        assert!(
            m.check_indices_and_coordinates()
                .unwrap_err()
                .contains("vertex 99")
        );
        let mut m = cuboid(1.0, 1.0, 1.0);
        m.positions[3].y = 2e9;
        assert!(
            m.check_indices_and_coordinates()
                .unwrap_err()
                .contains("vertex 3 has a coordinate")
        );
    }
}
