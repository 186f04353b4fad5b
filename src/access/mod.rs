//! Accessibility: from which directions can a point of the part be seen.
//!
//! DESIGN.md §3.5 and seed 004 ch. 5 step 4 (Chen & Woo visibility maps):
//!
//! * [`RayScene`]: the ray test everything stands on — a ray from a point along a direction
//!   escapes the part. Rays run on an obvhs compressed wide BVH in f32, relative to the part
//!   centre. This is one of the two modules where glam types exist; nothing glam leaves it.
//! * [`directions`]: near-uniform nested direction sets (subdivided icosahedron, 12 … 10242)
//!   and visibility maps as bitsets, intersected into region maps.
//! * [`visibility`]: per-point maps, by brute force or coarse-to-fine over the direction
//!   hierarchy (the hierarchy's speed-up; measured in `benches/access.rs`).
//! * [`region`]: one axis for a region of points from their maps (the impeller passages').
//!
//! The tool-axis choice (`orient`) still screens its candidates with single rays; accessibility
//! for a whole tool assembly is the exact body test in `collide`.

pub mod directions;
pub mod region;
pub mod visibility;

pub use directions::{
    BadDirectionCount, DirectionSet, LEVEL_COUNTS, MAX_LEVEL, VisibilityMap, level_for_count,
};
pub use region::{RegionAxis, region_axis};
pub use visibility::{
    PointMaps, Refine, SurfacePoint, VisibilityError, VisibilityOptions, vertex_points,
    visibility_brute_force, visibility_hierarchical,
};

use glam::Vec3A;
use obvhs::BvhBuildParams;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::ray::Ray;
use obvhs::triangle::Triangle;

use crate::geom::{Point3, Vector3};
use crate::mesh::Mesh;

/// The part's triangles in a ray-tracing BVH.
pub struct RayScene {
    bvh: CwBvh,
    /// Triangles in the BVH's leaf order.
    leaf_triangles: Vec<Triangle>,
    origin: Point3,
    /// Bounding-box diagonal of the part, mm: the scale default tolerances follow.
    diagonal: f64,
}

impl RayScene {
    pub fn new(mesh: &Mesh) -> Self {
        let aabb = mesh.aabb();
        let origin = aabb.center();
        let tris: Vec<Triangle> = (0..mesh.triangles.len())
            .map(|t| {
                let [a, b, c] = mesh.corners(t).map(|p| to_f32a(&(p - origin)));
                Triangle {
                    v0: a,
                    v1: b,
                    v2: c,
                }
            })
            .collect();
        let bvh = build_cwbvh_from_tris(
            &tris,
            BvhBuildParams::medium_build(),
            &mut std::time::Duration::default(),
        );
        let leaf_triangles = bvh
            .primitive_indices
            .iter()
            .map(|&i| tris[i as usize])
            .collect();
        Self {
            bvh,
            leaf_triangles,
            origin,
            diagonal: aabb.diagonal(),
        }
    }

    /// The part's bounding-box diagonal, mm.
    pub fn diagonal(&self) -> f64 {
        self.diagonal
    }

    /// True when the ray from `from` along unit `direction` meets no triangle within
    /// `max_distance`.
    pub fn escapes(&self, from: &Point3, direction: &Vector3, max_distance: f64) -> bool {
        // `+ Vec3A::ZERO` turns -0.0 into +0.0: obvhs misses everything otherwise (CRATES.md §8.1).
        let d = to_f32a(direction) + Vec3A::ZERO;
        let ray = Ray::new(to_f32a(&(from - self.origin)), d, 0.0, max_distance as f32);
        self.bvh
            .ray_traverse_miss(ray, |r, id| self.leaf_triangles[id].intersect(r))
    }
}

fn to_f32a(v: &Vector3) -> Vec3A {
    Vec3A::new(v.x as f32, v.y as f32, v.z as f32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::cuboid;

    #[test]
    fn rays_escape_or_hit_a_box_as_expected() {
        let scene = RayScene::new(&cuboid(10.0, 10.0, 10.0));
        let above = Point3::new(5.0, 5.0, 11.0);
        assert!(scene.escapes(&above, &Vector3::z(), 100.0));
        assert!(
            !scene.escapes(&above, &-Vector3::z(), 100.0),
            "straight down (-0.0 components) must hit"
        );
        assert!(
            scene.escapes(&above, &-Vector3::z(), 0.5),
            "the box is 1 mm away"
        );
        let side = Point3::new(-1.0, 5.0, 5.0);
        assert!(!scene.escapes(&side, &Vector3::x(), 100.0));
        assert!(scene.escapes(&side, &Vector3::new(-1.0, 0.0, 0.0), 100.0));
    }
}
