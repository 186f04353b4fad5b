//! The stock's surface as a triangle mesh, for pictures and viewers.
//!
//! The tri-dexel model knows its surface exactly along its lines and nowhere else, so the mesh
//! is an isosurface: a signed distance is sampled on a voxel lattice over the stock's box
//! (padded with air so the surface closes) and meshed by naive surface nets: one vertex per
//! cell the surface crosses, at the mean of its edges' crossings, and one quad per lattice edge
//! with a sign change, joining the four cells around it, facing from inside to outside.
//! (Written here: `fast-surface-nets` does the same but brings a second glam into the build,
//! which CRATES.md §1 rules out.) At each lattice point each grid's nearest line gives the distance
//! along it to the nearest end of material (negative inside a span); the three vote on inside
//! or outside as [`Stock::is_material`] does, and the value is the smallest distance among the
//! grids that agree, capped at two voxels. Along a line that is the exact distance to the
//! surface it crosses, and the others only bound it from above, so the mesh sits within about
//! a voxel of the model. The lattice points lie on the lines (every line, or every n-th when
//! that would exceed a voxel budget), so along the lattice's edges the distances are exact;
//! the mesh is for looking at, the model is for measuring.

use rayon::prelude::*;

use super::{DexelGrid, Stock};
use crate::geom::Point3;
use crate::mesh::Mesh;

/// Default voxel budget of [`Stock::surface_mesh`]: 16 M samples (64 MB of f32).
pub const DEFAULT_MAX_VOXELS: usize = 16_000_000;

impl DexelGrid {
    /// Distance from `p` along its nearest line to the nearest end of material, negative
    /// inside material; `None` when `p` is off the grid or the line is empty.
    fn signed_distance_along(&self, p: &Point3) -> Option<f64> {
        let line = &self.lines[self.nearest(p)?];
        let t = p[self.axis];
        line.iter()
            .map(|s| {
                if t >= s.start && t <= s.end {
                    -(t - s.start).min(s.end - t)
                } else {
                    (s.start - t).max(t - s.end)
                }
            })
            .min_by(f64::total_cmp)
    }
}

impl Stock {
    /// The signed distance estimate of the module docs at `p`, capped at `cap`.
    fn surface_distance(&self, p: &Point3, cap: f64) -> f64 {
        let along: Vec<f64> = self
            .grids
            .iter()
            .map(|g| g.signed_distance_along(p).unwrap_or(cap).clamp(-cap, cap))
            .collect();
        let inside = along.iter().filter(|d| **d < 0.0).count() >= 2;
        along
            .iter()
            .filter(|d| (**d < 0.0) == inside)
            .map(|d| d.abs())
            .fold(cap, f64::min)
            * if inside { -1.0 } else { 1.0 }
    }

    /// The surface of the material as a closed triangle mesh (see the module docs), on a
    /// lattice of about `max_voxels` points at most; triangles face outwards. Also the
    /// lattice's spacing, mm (the mesh's accuracy).
    pub fn surface_mesh(&self, max_voxels: usize) -> (Mesh, f64) {
        // Lattice points on the lines (every `stride`-th line position along each axis), so
        // the distance along each edge of the lattice is read off a line exactly.
        let lines = [0, 1, 2].map(|a| {
            let grid = &self.grids[(a + 2) % 3];
            (grid.origin[0], grid.counts[0])
        });
        let count: f64 = lines.iter().map(|l| l.1 as f64).product();
        let stride = ((count / max_voxels.max(1) as f64).cbrt().ceil() as usize).max(1);
        let voxel = stride as f64 * self.spacing;
        // Air beyond the lines: a lattice point before them and one after.
        let counts = lines.map(|(_, n)| (n.div_ceil(stride) + 2) as u32);
        let origin = Point3::new(lines[0].0 - voxel, lines[1].0 - voxel, lines[2].0 - voxel);
        let [nx, ny, nz] = counts.map(|c| c as usize);
        let index = |x: usize, y: usize, z: usize| x + nx * (y + ny * z);
        let cap = 2.0 * voxel;
        let sdf: Vec<f64> = (0..nx * ny * nz)
            .into_par_iter()
            .map(|i| {
                let (x, y, z) = (i % nx, (i / nx) % ny, i / (nx * ny));
                let p = origin + voxel * nalgebra::Vector3::new(x as f64, y as f64, z as f64);
                self.surface_distance(&p, cap)
            })
            .collect();
        let inside = |i: usize| sdf[i] < 0.0;
        // One vertex per crossed cell (cells indexed by their lowest corner).
        const CORNERS: [[usize; 3]; 8] = [
            [0, 0, 0],
            [1, 0, 0],
            [0, 1, 0],
            [1, 1, 0],
            [0, 0, 1],
            [1, 0, 1],
            [0, 1, 1],
            [1, 1, 1],
        ];
        const EDGES: [(usize, usize); 12] = [
            (0, 1),
            (2, 3),
            (4, 5),
            (6, 7),
            (0, 2),
            (1, 3),
            (4, 6),
            (5, 7),
            (0, 4),
            (1, 5),
            (2, 6),
            (3, 7),
        ];
        let cells = (nx - 1) * (ny - 1) * (nz - 1);
        let cell_vertex: Vec<Option<Point3>> = (0..cells)
            .into_par_iter()
            .map(|c| {
                let (x, y, z) = (
                    c % (nx - 1),
                    (c / (nx - 1)) % (ny - 1),
                    c / ((nx - 1) * (ny - 1)),
                );
                let corner = |k: usize| {
                    let [dx, dy, dz] = CORNERS[k];
                    index(x + dx, y + dy, z + dz)
                };
                let mut sum = nalgebra::Vector3::zeros();
                let mut crossings = 0;
                for (a, b) in EDGES {
                    let (ia, ib) = (corner(a), corner(b));
                    if inside(ia) != inside(ib) {
                        let t = sdf[ia] / (sdf[ia] - sdf[ib]);
                        let [ax, ay, az] = CORNERS[a];
                        let [bx, by, bz] = CORNERS[b];
                        let at = |u: usize, v: usize| u as f64 + t * (v as f64 - u as f64);
                        sum += nalgebra::Vector3::new(at(ax, bx), at(ay, by), at(az, bz));
                        crossings += 1;
                    }
                }
                (crossings > 0).then(|| {
                    let local = sum / crossings as f64;
                    origin
                        + voxel
                            * nalgebra::Vector3::new(
                                x as f64 + local.x,
                                y as f64 + local.y,
                                z as f64 + local.z,
                            )
                })
            })
            .collect();
        let mut positions = Vec::new();
        let mut vertex_of = vec![u32::MAX; cells];
        for (c, v) in cell_vertex.iter().enumerate() {
            if let Some(p) = v {
                vertex_of[c] = positions.len() as u32;
                positions.push(*p);
            }
        }
        let cell = |x: usize, y: usize, z: usize| vertex_of[x + (nx - 1) * (y + (ny - 1) * z)];
        // One quad per edge with a sign change, around it counter-clockwise seen from the
        // outside end. The lattice's outer layers are air, so every such edge has its four
        // cells.
        let mut triangles = Vec::new();
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let here = inside(index(x, y, z));
                    for axis in 0..3 {
                        let (ex, ey, ez) = match axis {
                            0 => (x + 1, y, z),
                            1 => (x, y + 1, z),
                            _ => (x, y, z + 1),
                        };
                        // The edge and the four cells around it inside the lattice.
                        let across_ok = match axis {
                            0 => y >= 1 && z >= 1,
                            1 => x >= 1 && z >= 1,
                            _ => x >= 1 && y >= 1,
                        };
                        if !across_ok
                            || ex >= nx
                            || ey >= ny
                            || ez >= nz
                            || inside(index(ex, ey, ez)) == here
                        {
                            continue;
                        }
                        // The four cells around the edge, in the plane across it, counter-
                        // clockwise about +axis.
                        let quad = match axis {
                            0 => [
                                cell(x, y - 1, z - 1),
                                cell(x, y, z - 1),
                                cell(x, y, z),
                                cell(x, y - 1, z),
                            ],
                            1 => [
                                cell(x - 1, y, z - 1),
                                cell(x - 1, y, z),
                                cell(x, y, z),
                                cell(x, y, z - 1),
                            ],
                            _ => [
                                cell(x - 1, y - 1, z),
                                cell(x, y - 1, z),
                                cell(x, y, z),
                                cell(x - 1, y, z),
                            ],
                        };
                        if quad.contains(&u32::MAX) {
                            continue;
                        }
                        let [a, b, c, d] = if here {
                            quad
                        } else {
                            [quad[0], quad[3], quad[2], quad[1]]
                        };
                        triangles.push([a, b, c]);
                        triangles.push([a, c, d]);
                    }
                }
            }
        }
        (
            Mesh {
                positions,
                triangles,
            },
            voxel,
        )
    }
}

#[cfg(test)]
mod tests {
    use crate::geom::{Aabb, Point3};
    use crate::stock::sweep::SphereSweptHull;
    use crate::stock::{DEFAULT_MAX_DEXELS, Stock};

    /// The surface of a block with a spherical dent encloses the model's volume, faces out,
    /// and has its vertices on the model's surface within a voxel.
    #[test]
    fn the_surface_mesh_encloses_the_model() {
        let bounds =
            Aabb::from_points(&[Point3::new(-5.0, -4.0, -3.0), Point3::new(5.0, 4.0, 3.0)]);
        let spacing = 0.2;
        let mut stock = Stock::block(&bounds, spacing, DEFAULT_MAX_DEXELS).unwrap();
        stock.remove(&SphereSweptHull::new(&[Point3::new(1.0, 0.5, 3.0)], 2.5));
        let (mesh, voxel) = stock.surface_mesh(super::DEFAULT_MAX_VOXELS);
        assert_eq!(voxel, spacing);
        assert!(!mesh.triangles.is_empty());
        let volume = mesh.signed_volume();
        assert!(
            (volume - stock.volume()).abs() < 0.03 * stock.volume(),
            "mesh {volume} vs model {}",
            stock.volume()
        );
        // Every vertex within a voxel of the box's or the dent's surface.
        for p in &mesh.positions {
            let to_box = [0, 1, 2]
                .map(|a| {
                    (p[a] - bounds.min[a])
                        .abs()
                        .min((p[a] - bounds.max[a]).abs())
                })
                .into_iter()
                .fold(f64::INFINITY, f64::min);
            let to_dent = ((p - Point3::new(1.0, 0.5, 3.0)).norm() - 2.5).abs();
            assert!(to_box.min(to_dent) < 1.5 * spacing, "{p:?}");
        }
        // Closed and consistently oriented: every directed edge once, and its reverse once.
        let mut edges = std::collections::HashMap::new();
        for t in &mesh.triangles {
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        for (&(a, b), &n) in &edges {
            assert_eq!(n, 1, "edge {a}-{b} used {n} times one way");
            assert_eq!(edges.get(&(b, a)), Some(&1), "edge {a}-{b} has no twin");
        }
        // A coarser budget still closes the surface.
        let (coarse, _) = stock.surface_mesh(20_000);
        let v = coarse.signed_volume();
        assert!((v - stock.volume()).abs() < 0.15 * stock.volume(), "{v}");
    }
}
