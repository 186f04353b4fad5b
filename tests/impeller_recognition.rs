//! Impeller recognition on real parts: the bundled sample impeller and the shared test data's
//! blower (9 blades) and compressor (main blades and splitters) are recognised with the blade
//! count their sources give, about an axis through their hub; a blade and non-impeller meshes
//! are refused. Each symmetry is checked on the surface by the recognition itself; on the
//! sample it is checked again here by the tests' own distance oracle.

mod common;

use wavemill::impeller::{NotAnImpeller, RecogniseOptions, recognise};
use wavemill::mesh::io::{Units, read_mesh};
use wavemill::mesh::{Mesh, PrepareOptions, prepare};

fn load(path: &std::path::Path) -> Mesh {
    let raw = read_mesh(path, Units::Millimetres).expect("mesh");
    prepare(&raw.mesh, &PrepareOptions::default())
        .expect("prepared")
        .0
}

/// The largest distance from a sampled vertex turned by 2π/order about the axis to the
/// surface (the tests' own bucketed point–triangle oracle), up to 1 mm.
fn turned_miss(mesh: &Mesh, axis: [f64; 3], centre: [f64; 3], order: usize) -> f64 {
    let k = nalgebra::Unit::new_normalize(nalgebra::Vector3::from(axis));
    let c = nalgebra::Point3::from(centre);
    let turn = nalgebra::Rotation3::from_axis_angle(&k, std::f64::consts::TAU / order as f64);
    let oracle = common::Oracle::new(&mesh.positions, &mesh.triangles, 2.0);
    mesh.positions
        .iter()
        .step_by(7)
        .map(|p| oracle.distance_below(&(c + turn * (p - c)), 1.0))
        .fold(0.0, f64::max)
}

#[test]
fn the_sample_impeller_is_recognised_and_the_sample_blade_is_not() {
    let mesh = load(&common::repo_file("data/impeller.glb"));
    let found = recognise(&mesh, &RecogniseOptions::default()).expect("an impeller");
    assert_eq!(
        (found.order, found.blades, found.splitters),
        (7, 7, 0),
        "{found:?}"
    );
    assert!(found.axis[2] > 0.999, "{:?}", found.axis);
    let miss = turned_miss(&mesh, found.axis, found.centre, found.order);
    assert!(miss < 0.02, "{miss}");
    let blade = load(&common::repo_file("data/blade.glb"));
    assert!(recognise(&blade, &RecogniseOptions::default()).is_err());
}

#[test]
fn the_real_impellers_are_recognised_with_their_blade_counts() {
    let Some(dir) = common::testdata() else {
        return;
    };
    let blower = load(&dir.join("meshes/impeller_blower_9blade__necro-nemesis_aero2205.stl"));
    let found = recognise(&blower, &RecogniseOptions::default()).expect("the blower");
    assert_eq!((found.order, found.blades), (9, 9), "{found:?}");
    let compressor =
        load(&dir.join("meshes/impeller_compressor_splitter__omorellAUS_Impellor-V3.stl"));
    let found = recognise(&compressor, &RecogniseOptions::default()).expect("the compressor");
    assert_eq!(
        (found.order, found.blades, found.splitters),
        (6, 6, 6),
        "{found:?}"
    );
    let turbine = load(&dir.join("meshes/turbine_blade_with_root__dengwirda_jigsaw-models.stl"));
    assert!(matches!(
        recognise(&turbine, &RecogniseOptions::default()),
        Err(NotAnImpeller::NoSymmetry { .. })
    ));
}
