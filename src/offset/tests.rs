//! Closed-form offsets (sphere, capped cylinder) and the verification catching a broken bound.

use super::*;
use crate::mesh::fixtures::uv_sphere;

#[test]
fn sphere_offsets_are_spheres() {
    let radius = 10.0;
    let part = uv_sphere(radius, 24, 48);
    let specs = [2.0, 0.5].map(|a| ShapeSpec {
        surface: part.clone(),
        allowance: a,
        bound: 0.0,
    });
    let shapes = nested_offsets(&part, &specs).unwrap();
    for s in &shapes {
        println!("{:?}", s.report);
    }
}
