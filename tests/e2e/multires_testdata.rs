//! The multiresolution core on every manifold mesh of the shared test data and on the sample
//! parts: the hierarchy has exact subdivision connectivity, the wavelet transform inverts to
//! round-off, and non-manifold input is refused with a message that says where. Prints, per
//! mesh, the base size, level count, fit to the input, reconstruction error and time.

use crate::common;
use std::time::Instant;

use wavemill::job;
use wavemill::mesh::{PrepareOptions, prepare};
use wavemill::multires::{Hierarchy, RemeshOptions, WaveletHierarchy, check_split};

fn hierarchy_checks(label: &str, path: &std::path::Path, units: &str) {
    let raw = job::load_part(path, units).unwrap();
    let (mesh, _) = prepare(&raw.mesh, &PrepareOptions::default()).unwrap();
    let diagonal = mesh.aabb().diagonal();
    let reach = mesh
        .positions
        .iter()
        .map(|p| p.coords.norm())
        .fold(0.0, f64::max);
    let options = RemeshOptions {
        tolerance: 0.0,
        base_triangles: 1500,
        max_levels: 1,
        ..Default::default()
    };
    let started = Instant::now();
    let h = Hierarchy::build(&mesh, &options).unwrap_or_else(|e| panic!("{label}: {e}"));
    let remesh_s = started.elapsed().as_secs_f64();
    for w in h.levels.windows(2) {
        check_split(
            &w[0].mesh.triangles,
            w[0].mesh.positions.len(),
            &w[1].mesh.triangles,
        )
        .unwrap_or_else(|e| panic!("{label}: {e}"));
    }
    let base = &h.levels[0];
    // Each level interpolates the one below and fits the input no worse — up to 1 %: where a
    // coarse base has squashed a thin blade (its two sides millimetres apart), the finer level
    // may follow either side (tall blower, base 1,500: 2.899 → 2.902 mm); or up to 1 µm, far
    // below any machining tolerance, where the base is already the input to microns (OpenCAMLib's
    // wheel_in_box: 5.55 → 5.86 µm as odd vertices land on slightly different input points).
    for w in h.levels.windows(2) {
        let n = w[0].mesh.positions.len();
        assert_eq!(
            &w[1].mesh.positions[..n],
            &w[0].mesh.positions[..],
            "{label}"
        );
        assert!(
            w[1].hausdorff <= (1.01 * w[0].hausdorff).max(w[0].hausdorff + 1e-3),
            "{label}: fit {} after {}",
            w[1].hausdorff,
            w[0].hausdorff
        );
    }
    let wavelets = WaveletHierarchy::new(
        &base.mesh.triangles,
        base.mesh.positions.len(),
        &base.creases,
        h.levels.len() - 1,
    )
    .unwrap();
    let finest = &h.finest().mesh;
    let analysed = wavelets.analyse_all(&finest.positions).unwrap();
    let rebuilt = wavelets.synthesise_all(&analysed).unwrap();
    let error = rebuilt
        .iter()
        .zip(&finest.positions)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    // Round-off scales with the coordinates (parts far from the origin), not just the size.
    assert!(
        error <= 1e-12 * diagonal.max(reach),
        "{label}: reconstruction error {error}"
    );
    println!(
        "{label}: {} triangles -> base {} + {} level(s) -> {} triangles; Hausdorff {:.4} mm (base {:.4}); reconstruction {error:.2e} mm; remesh {remesh_s:.2} s",
        mesh.triangles.len(),
        base.mesh.triangles.len(),
        h.levels.len() - 1,
        finest.triangles.len(),
        h.finest().hausdorff,
        base.hausdorff,
    );
}

#[test]
fn hierarchies_of_the_sample_parts() {
    for part in ["impeller", "blade"] {
        hierarchy_checks(part, &common::repo_file(&format!("data/{part}.glb")), "mm");
    }
}

#[test]
fn hierarchies_of_the_shared_manifold_meshes() {
    let Some(dir) = common::testdata() else {
        return;
    };
    for (file, units) in common::MANIFOLD_MESHES {
        hierarchy_checks(file, &dir.join("meshes").join(file), units);
    }
}

#[test]
fn non_manifold_input_is_refused_saying_where() {
    let Some(dir) = common::testdata() else {
        return;
    };
    let raw = job::load_part(
        &dir.join("meshes/propeller_edf_dirty__doingWork234_MATLAB-Propeller-Generator.stl"),
        "m",
    )
    .unwrap();
    let (mesh, _) = prepare(&raw.mesh, &PrepareOptions::default()).unwrap();
    let err = Hierarchy::build(&mesh, &RemeshOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("non-manifold") || err.contains("manifold"),
        "{err}"
    );
    assert!(
        err.chars().any(|c| c.is_ascii_digit()),
        "the message must say where: {err}"
    );
}
