//! Every mesh in `../shared/testdata/meshes/` loads with its documented triangle count, and
//! the validation report says what is wrong with the dirty ones. Skips (with a message) when
//! the shared folder is absent, as on a newcomer's clone.

use crate::common;
use wavemill::mesh::io::{Units, read_mesh};
use wavemill::mesh::{MeshReport, PrepareOptions, prepare, prepare_without_stray_pieces};

/// (file, units, documented triangles) from testdata/README.md.
const MESHES: &[(&str, Units, usize)] = &[
    (
        "impeller_compressor_splitter__omorellAUS_Impellor-V3.stl",
        Units::Millimetres,
        25_278,
    ),
    (
        "impeller_blower_9blade__necro-nemesis_aero2205.stl",
        Units::Millimetres,
        65_304,
    ),
    (
        "impeller_blower_9blade_tall__necro-nemesis_aero2205_aggressive.stl",
        Units::Millimetres,
        66_810,
    ),
    (
        "turbine_blade_with_root__dengwirda_jigsaw-models.stl",
        Units::Metres,
        13_306,
    ),
    (
        "blade_airfoil__LostSunset_pyturbo-aero.stl",
        Units::Metres,
        4_720,
    ),
    (
        "blade_coarse196tri__pittance_compressorFan.stl",
        Units::Millimetres,
        196,
    ),
    (
        "propeller_edf_dirty__doingWork234_MATLAB-Propeller-Generator.stl",
        Units::Metres,
        29_710,
    ),
    ("ocl/wheel_in_box.stl", Units::Millimetres, 6_102),
    ("ocl/sphere_on_plate.stl", Units::Millimetres, 7_570),
    ("ocl/ktoolcav.stl", Units::Millimetres, 4_090),
    ("ocl/demo.stl", Units::Millimetres, 1_894),
    (
        "converted/impeller_compressor_splitter.glb",
        Units::Millimetres,
        25_278,
    ),
    (
        "converted/impeller_compressor_splitter.obj",
        Units::Millimetres,
        25_278,
    ),
    (
        "converted/turbine_blade_with_root.glb",
        Units::Metres,
        13_306,
    ),
];

fn report(rel: &str, units: Units) -> Option<MeshReport> {
    let dir = common::testdata()?;
    let raw =
        read_mesh(&dir.join("meshes").join(rel), units).unwrap_or_else(|e| panic!("{rel}: {e}"));
    Some(
        prepare(&raw.mesh, &PrepareOptions::default())
            .unwrap_or_else(|e| panic!("{rel}: {e}"))
            .1,
    )
}

#[test]
fn every_shared_mesh_loads_with_its_documented_triangle_count() {
    for &(rel, units, triangles) in MESHES {
        let Some(r) = report(rel, units) else { return };
        assert_eq!(r.input_triangles, triangles, "{rel}");
    }
}

/// The closed parts are closed, oriented 2-manifolds with the genus their shape has: the
/// impellers have a bore (1), the blades none (0).
#[test]
fn closed_parts_are_watertight_with_the_expected_genus() {
    for (rel, units, genus) in [
        (
            "impeller_compressor_splitter__omorellAUS_Impellor-V3.stl",
            Units::Millimetres,
            1,
        ),
        (
            "impeller_blower_9blade__necro-nemesis_aero2205.stl",
            Units::Millimetres,
            1,
        ),
        (
            "impeller_blower_9blade_tall__necro-nemesis_aero2205_aggressive.stl",
            Units::Millimetres,
            1,
        ),
        (
            "turbine_blade_with_root__dengwirda_jigsaw-models.stl",
            Units::Metres,
            0,
        ),
        (
            "blade_coarse196tri__pittance_compressorFan.stl",
            Units::Millimetres,
            0,
        ),
        (
            "converted/impeller_compressor_splitter.glb",
            Units::Millimetres,
            1,
        ),
        (
            "converted/impeller_compressor_splitter.obj",
            Units::Millimetres,
            1,
        ),
        ("ocl/sphere_on_plate.stl", Units::Millimetres, 0),
    ] {
        let Some(r) = report(rel, units) else { return };
        assert!(r.watertight, "{rel}: {:?}", r.problems());
        assert_eq!(r.genus, Some(genus), "{rel}");
        assert_eq!(r.components, 1, "{rel}");
        assert!(r.volume.unwrap() > 0.0, "{rel}: outward");
        assert_eq!(
            r.flipped_faces, 0,
            "{rel}: the README says all closed meshes face outward"
        );
    }
}

/// STL, GLB and OBJ versions of the same impeller agree (the GLB is f32, so to 1e-4 mm³/mm).
#[test]
fn the_converted_impeller_matches_its_stl() {
    let Some(stl) = report(
        "impeller_compressor_splitter__omorellAUS_Impellor-V3.stl",
        Units::Millimetres,
    ) else {
        return;
    };
    for rel in [
        "converted/impeller_compressor_splitter.glb",
        "converted/impeller_compressor_splitter.obj",
    ] {
        let Some(other) = report(rel, Units::Millimetres) else {
            return;
        };
        assert_eq!(other.vertices, stl.vertices, "{rel}");
        let (a, b) = (stl.volume.unwrap(), other.volume.unwrap());
        assert!((a - b).abs() / a < 1e-6, "{rel}: {a} vs {b}");
    }
}

#[test]
fn the_dirty_airfoil_is_repaired_by_dropping_its_zero_area_faces() {
    // README: 3 pieces, 2 non-manifold edges, 4 zero-area and 2 duplicate faces. The two
    // non-manifold edges and the split into pieces are made by the 4 degenerate faces lying
    // along edges; once they are dropped the surface is one closed, oriented blade.
    let Some(r) = report("blade_airfoil__LostSunset_pyturbo-aero.stl", Units::Metres) else {
        return;
    };
    assert_eq!(r.dropped_zero_area_faces, 4);
    assert!(r.watertight, "{:?}", r.problems());
    assert_eq!(r.genus, Some(0));
    assert!(r.problems().iter().any(|p| p.contains("zero-area")));
}

#[test]
fn the_dirty_propeller_gets_a_clear_validation_report() {
    let Some(r) = report(
        "propeller_edf_dirty__doingWork234_MATLAB-Propeller-Generator.stl",
        Units::Metres,
    ) else {
        return;
    };
    // README: 395 pieces, 432 non-manifold edges, 622 zero-area faces, inconsistent winding.
    // Zero-area faces are counted the same way; pieces and non-manifold edges are counted here
    // after those faces are dropped and with pieces joined across non-manifold edges, so they
    // are fewer, but every kind of fault must be reported.
    assert_eq!(r.dropped_zero_area_faces, 622);
    assert!(!r.watertight);
    assert!(r.components > 1);
    assert!(r.non_manifold_edges > 0 && r.boundary_edges > 0 && r.inconsistent_edges > 0);
    assert_eq!(r.genus, None);
    let problems = r.problems().join("\n");
    for needle in [
        "non-manifold edges",
        "boundary edges",
        "inconsistent winding",
        "zero-area",
        "separate pieces",
    ] {
        assert!(
            problems.contains(needle),
            "missing `{needle}` in:\n{problems}"
        );
    }
}

/// `plan` refuses the dirty propeller with an error that names the file and the problems, and
/// writes nothing; `info` describes it and succeeds.
#[test]
fn cli_on_the_dirty_propeller() {
    let Some(dir) = common::testdata() else {
        return;
    };
    let part = dir.join("meshes/propeller_edf_dirty__doingWork234_MATLAB-Propeller-Generator.stl");
    let out_dir = std::env::temp_dir().join(format!("wavemill-dirty-{}", std::process::id()));
    let bin = env!("CARGO_BIN_EXE_wavemill");
    let plan = std::process::Command::new(bin)
        .args([
            "plan",
            part.to_str().unwrap(),
            "--units",
            "m",
            "--out",
            out_dir.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert_eq!(plan.status.code(), Some(1));
    let err = String::from_utf8_lossy(&plan.stderr);
    assert!(
        err.contains("propeller_edf_dirty") && err.contains("non-manifold"),
        "{err}"
    );
    assert!(!out_dir.join("job.nc").exists());
    let info = std::process::Command::new(bin)
        .args(["info", part.to_str().unwrap(), "--units", "m"])
        .output()
        .unwrap();
    assert_eq!(info.status.code(), Some(0));
    let text = String::from_utf8_lossy(&info.stdout);
    assert!(
        text.contains("watertight       no") && text.contains("622 zero-area faces dropped"),
        "{text}"
    );
}

/// Issue 17 item 8: one triangle at (1e6, 1e6, 1e6) mm used to stretch the box-relative
/// tolerances (weld 0.17 mm, minimum area 3 mm²) so far that 19,363 of the compressor's 25,278
/// faces were dropped as "zero-area" and `access` went on with the wreck. The impeller must come through whole, with the triangle reported
/// as one stray piece and set aside for planning.
#[test]
fn a_far_stray_triangle_leaves_the_compressor_whole() {
    let Some(dir) = common::testdata() else {
        return;
    };
    let src = dir.join("meshes/impeller_compressor_splitter__omorellAUS_Impellor-V3.stl");
    let mut stl = std::fs::read(&src).unwrap();
    // Binary STL: bump the facet count and append one facet (normal, 3 corners, attribute).
    let count = u32::from_le_bytes(stl[80..84].try_into().unwrap());
    stl[80..84].copy_from_slice(&(count + 1).to_le_bytes());
    stl.extend_from_slice(&[0u8; 12]);
    for p in [
        [1e6f32, 1e6, 1e6],
        [1e6 + 1.0, 1e6, 1e6],
        [1e6, 1e6 + 1.0, 1e6],
    ] {
        for x in p {
            stl.extend_from_slice(&x.to_le_bytes());
        }
    }
    stl.extend_from_slice(&[0u8; 2]);
    let tmp = std::env::temp_dir().join(format!("wavemill-stray-{}.stl", std::process::id()));
    std::fs::write(&tmp, &stl).unwrap();

    let options = PrepareOptions::default();
    let alone = prepare(&read_mesh(&src, Units::Millimetres).unwrap().mesh, &options)
        .unwrap()
        .1;
    let raw = read_mesh(&tmp, Units::Millimetres).unwrap();
    let (_, r) = prepare(&raw.mesh, &options).unwrap();
    assert_eq!(r.input_triangles, 25_279);
    assert_eq!(r.dropped_zero_area_faces, 0, "{:?}", r.problems());
    assert_eq!(r.triangles, alone.triangles + 1);
    assert_eq!(r.stray_piece_count, 1);
    assert_eq!(r.pieces[0].triangles, alone.triangles);
    assert!(r.pieces[1].stray && r.pieces[1].triangles == 1);

    let (part, kept, stray) = prepare_without_stray_pieces(&raw.mesh, &options).unwrap();
    assert_eq!(part.triangles.len(), 25_278);
    assert_eq!(kept.triangles, alone.triangles);
    assert!(
        kept.watertight && kept.genus == Some(1),
        "{:?}",
        kept.problems()
    );
    assert_eq!(kept.volume, alone.volume);
    assert_eq!(stray.len(), 1);
    assert_eq!(stray[0].bounding_box_min, [1e6, 1e6, 1e6]);

    // `info` shows the piece; it exits 0 because describing a file is not refusing it.
    let info = std::process::Command::new(env!("CARGO_BIN_EXE_wavemill"))
        .args(["info", tmp.to_str().unwrap()])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&info.stdout);
    assert_eq!(info.status.code(), Some(0), "{text}");
    assert!(text.contains("triangles        25279"), "{text}");
    assert!(
        text.contains("1 stray piece,") && text.contains("[1000000.0000, 1000000.0000"),
        "{text}"
    );
    let _ = std::fs::remove_file(&tmp);
}
