//! The stock's surface as a triangle mesh, for pictures and viewers.
//!
//! The tri-dexel model knows its surface exactly along its lines and nowhere else, so the mesh
//! is an isosurface: a signed distance is sampled on a voxel lattice over the stock's box
//! (padded by one voxel of air so the surface closes) and meshed by naive surface nets
//! (`fast-surface-nets`). At each lattice point each grid's nearest line gives the distance
//! along it to the nearest end of material (negative inside a span); the three vote on inside
//! or outside as [`Stock::is_material`] does, and the value is the smallest distance among the
//! grids that agree, capped at two voxels. Along a line that is the exact distance to the
//! surface it crosses, and the others only bound it from above, so the mesh sits within about
//! a voxel of the model. The lattice points lie on the lines (every line, or every n-th when
//! that would exceed a voxel budget), so along the lattice's edges the distances are exact;
//! the mesh is for looking at, the model is for measuring.

use fast_surface_nets::ndshape::{RuntimeShape, Shape};
use fast_surface_nets::{SurfaceNetsBuffer, surface_nets};

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
        // Air beyond the lines: one lattice point before them and two after (surface nets
        // makes no faces on the lattice's last layer).
        let counts = lines.map(|(_, n)| (n.div_ceil(stride) + 3) as u32);
        let origin = Point3::new(lines[0].0 - voxel, lines[1].0 - voxel, lines[2].0 - voxel);
        let shape = RuntimeShape::<u32, 3>::new(counts);
        let cap = 2.0 * voxel;
        let total = shape.usize();
        use rayon::prelude::*;
        let sdf: Vec<f32> = (0..total)
            .into_par_iter()
            .map(|i| {
                let [x, y, z] = shape.delinearize(i as u32);
                let p = origin + voxel * nalgebra::Vector3::new(x as f64, y as f64, z as f64);
                (self.surface_distance(&p, cap) / voxel) as f32
            })
            .collect();
        let mut buffer = SurfaceNetsBuffer::default();
        surface_nets(&sdf, &shape, [0; 3], counts.map(|c| c - 1), &mut buffer);
        let positions = buffer
            .positions
            .iter()
            .map(|q| origin + voxel * nalgebra::Vector3::new(q[0] as f64, q[1] as f64, q[2] as f64))
            .collect();
        // surface_nets winds its quads for a right-handed frame with the field negative
        // inside; the orientation is checked in the tests (outward normals, positive volume).
        let triangles = buffer
            .indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
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
        // A coarser budget still closes the surface.
        let (coarse, _) = stock.surface_mesh(20_000);
        let v = coarse.signed_volume();
        assert!((v - stock.volume()).abs() < 0.15 * stock.volume(), "{v}");
    }
}
