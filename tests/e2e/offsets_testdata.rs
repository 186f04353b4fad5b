//! Issue 4 on real parts: the nested shapes of the sample impeller and of every manifold shared
//! test mesh keep their guarantees (clearance, containment, nesting), checked again here with
//! the independent oracle of `common` (uniform grid + brute force, ray parity) that shares no
//! code with the library; and a rigid motion of the part leaves the figures where they were.
//! Prints the per-shape table (allowance, min clearance − allowance, mean/max excess, bound,
//! triangles, build and verify time).

use crate::common;
use nalgebra::{Rotation3, Vector3};
use wavemill::job::{self, OffsetsOutput};
use wavemill::mesh::{Mesh, PrepareOptions, prepare};
use wavemill::multires::RemeshOptions;
use wavemill::offset::OffsetOptions;

const ALLOWANCES: [f64; 2] = [1.0, 0.2];

/// Small hierarchies and a coarse grid: the guarantees do not depend on the resolution, and
/// CI runs these in the dev profile on 2 cores.
fn small() -> (RemeshOptions, OffsetOptions) {
    (
        RemeshOptions {
            tolerance: 0.0,
            base_triangles: 600,
            base_max_error: None,
            max_levels: 1,
            ..Default::default()
        },
        OffsetOptions {
            max_cells_across: 80.0,
            ..OffsetOptions::default()
        },
    )
}

fn load(path: &std::path::Path, units: &str) -> Mesh {
    let raw = job::load_part(path, units).unwrap();
    prepare(&raw.mesh, &PrepareOptions::default()).unwrap().0
}

fn build(label: &str, part: &Mesh) -> OffsetsOutput {
    let (remesh, options) = small();
    let out = job::offsets(part, &remesh, &ALLOWANCES, &options, true)
        .unwrap_or_else(|e| panic!("{label}: {e}"));
    for s in &out.report.shapes {
        let f = &s.figures;
        println!(
            "{label} | shape {} level {} | a {} | clearance-a {:.2e} | excess mean {:.4} max {:.4} | bound {:.4} | {} tris | {} | build {:.2} s verify {:.2} s | failures {} rounds {}",
            s.shape,
            s.level,
            f.allowance_mm,
            f.min_clearance_minus_allowance_mm,
            f.mean_excess_mm,
            f.max_excess_mm,
            f.bound_mm,
            f.triangles,
            f.method.kind(),
            f.build_s,
            f.verify_s,
            f.failures_found,
            f.repair_rounds
        );
    }
    out
}

/// The guarantees from the report, then again with the independent oracle on a subset.
fn check(label: &str, part: &Mesh, out: &OffsetsOutput) {
    assert!(out.report.verified, "{label}");
    assert_eq!(out.files.len(), ALLOWANCES.len());
    let part_closed =
        wavemill::mesh::topology::Topology::analyse(&part.triangles, part.positions.len())
            .boundary_edges
            == 0;
    let part_oracle = common::Oracle::new(&part.positions, &part.triangles, 2.0);
    for (j, shape) in out.shapes.iter().enumerate() {
        let r = &shape.report;
        assert!(r.verified, "{label} shape {j}");
        assert!(
            r.min_clearance_minus_allowance_mm >= -1e-6,
            "{label} shape {j}"
        );
        assert!(
            r.min_part_depth_minus_allowance_mm >= -1e-6,
            "{label} shape {j}"
        );
        if j + 1 < out.shapes.len() {
            assert!(
                r.min_inner_depth_mm.is_some_and(|d| d > 0.0),
                "{label} shape {j}"
            );
        }
        let topology = wavemill::mesh::topology::Topology::analyse(
            &shape.mesh.triangles,
            shape.mesh.positions.len(),
        );
        assert!(
            topology.is_closed_manifold() && topology.inconsistent_edges == 0,
            "{label} shape {j}: {topology:?}"
        );
        let a = r.allowance_mm;
        for v in shape.mesh.positions.iter().step_by(13) {
            let d = part_oracle.distance_below(v, a + 1.0);
            assert!(
                d >= a - 1e-6,
                "{label} shape {j}: {d} mm from the part at {v:?}"
            );
            if part_closed {
                assert!(!part_oracle.inside(v), "{label} shape {j}: inside at {v:?}");
            }
        }
        let shape_oracle = common::Oracle::new(&shape.mesh.positions, &shape.mesh.triangles, 2.0);
        for p in part.positions.iter().step_by(17) {
            assert!(
                shape_oracle.inside(p),
                "{label} shape {j}: part point {p:?} outside"
            );
        }
        if let Some(inner) = out.shapes.get(j + 1) {
            for p in inner.mesh.positions.iter().step_by(17) {
                assert!(
                    shape_oracle.inside(p),
                    "{label} shape {j}: shape {} at {p:?}",
                    j + 1
                );
            }
        }
    }
}

#[test]
fn offsets_of_the_sample_impeller() {
    let part = load(&common::repo_file("data/impeller.glb"), "mm");
    let out = build("sample impeller", &part);
    check("sample impeller", &part, &out);
}

#[test]
fn offsets_of_the_shared_manifold_meshes() {
    let Some(dir) = common::testdata() else {
        return;
    };
    for (file, units) in common::MANIFOLD_MESHES {
        let part = load(&dir.join("meshes").join(file), units);
        let out = build(file, &part);
        check(file, &part, &out);
    }
}

/// Rotate and translate the part: the hierarchy and the grid meet it differently, so the
/// shapes differ in their triangles, but their figures stay within 10 % and half a grid cell
/// (the grid is anchored to the origin). The max excess of a shell extracted at two cells and
/// projected down is an exception: the few vertices whose move would turn a triangle over stay
/// up to two cells out, and which ones do is set by where the lattice falls; it is held to
/// 10 % and two cells.
#[test]
fn a_rigid_motion_leaves_the_figures() {
    let part = load(&common::repo_file("data/blade.glb"), "mm");
    let motion = Rotation3::from_axis_angle(&Vector3::y_axis(), 0.7)
        * Rotation3::from_axis_angle(&Vector3::x_axis(), -0.4);
    let shift = Vector3::new(31.7, -12.25, 8.5);
    let moved = Mesh {
        positions: part.positions.iter().map(|p| motion * p + shift).collect(),
        triangles: part.triangles.clone(),
    };
    let a = build("blade", &part);
    let b = build("blade moved", &moved);
    check("blade moved", &moved, &b);
    for (x, y) in a.report.shapes.iter().zip(&b.report.shapes) {
        let (x, y) = (&x.figures, &y.figures);
        let spacing = match x.method {
            wavemill::offset::Method::DistanceGrid { spacing_mm } => spacing_mm,
            wavemill::offset::Method::NormalOffset => 0.0,
        };
        let within = |p: f64, q: f64, cells: f64, what: &str| {
            assert!(
                (p - q).abs() <= 0.1 * p.abs().max(q.abs()) + cells * spacing + 1e-6,
                "{what}: {p} vs {q}"
            );
        };
        let close = |p: f64, q: f64, what: &str| within(p, q, 0.5, what);
        close(x.bound_mm, y.bound_mm, "bound");
        close(x.mean_excess_mm, y.mean_excess_mm, "mean excess");
        within(x.max_excess_mm, y.max_excess_mm, 2.0, "max excess");
        close(
            x.min_clearance_minus_allowance_mm,
            y.min_clearance_minus_allowance_mm,
            "min clearance",
        );
    }
}
