//! The real meshes in the shared test data (see its README): all load, with the documented
//! triangle counts. Skipped, with a note, where the folder does not exist.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::mesh::io::{Format, Units, read_mesh};

/// The test data folder relative to `CARGO_MANIFEST_DIR` (the one line to change when the
/// module moves to another crate).
const TESTDATA_FROM_MANIFEST: &str = "/../shared/testdata";

fn testdata() -> PathBuf {
    match std::env::var_os("WAVEMILL_TESTDATA") {
        Some(p) => PathBuf::from(p),
        None => PathBuf::from(format!(
            "{}{TESTDATA_FROM_MANIFEST}",
            env!("CARGO_MANIFEST_DIR")
        )),
    }
}

/// Triangle counts from testdata/README.md (the converted files: same parts).
const EXPECTED: &[(&str, usize)] = &[
    (
        "impeller_compressor_splitter__omorellAUS_Impellor-V3.stl",
        25_278,
    ),
    ("impeller_blower_9blade__necro-nemesis_aero2205.stl", 65_304),
    (
        "impeller_blower_9blade_tall__necro-nemesis_aero2205_aggressive.stl",
        66_810,
    ),
    (
        "turbine_blade_with_root__dengwirda_jigsaw-models.stl",
        13_306,
    ),
    ("blade_airfoil__LostSunset_pyturbo-aero.stl", 4_720),
    ("blade_coarse196tri__pittance_compressorFan.stl", 196),
    (
        "propeller_edf_dirty__doingWork234_MATLAB-Propeller-Generator.stl",
        29_710,
    ),
    ("wheel_in_box.stl", 6_102),
    ("sphere_on_plate.stl", 7_570),
    ("ktoolcav.stl", 4_090),
    ("demo.stl", 1_894),
];

fn mesh_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut paths: Vec<PathBuf> = entries.flatten().map(|e| e.path()).collect();
    paths.sort();
    for p in paths {
        if p.is_dir() {
            mesh_files(&p, out);
        } else if Format::from_path(&p).is_some() {
            out.push(p);
        }
    }
}

#[test]
fn real_meshes_load_with_documented_counts() {
    debug_assert!(TESTDATA_FROM_MANIFEST.starts_with("/.."));
    let root = testdata().join("meshes");
    if !root.is_dir() {
        println!(
            "real_meshes_load_with_documented_counts: skipped, {} does not exist \
             (set WAVEMILL_TESTDATA to the shared testdata folder)",
            root.display()
        );
        return;
    }
    let mut files = Vec::new();
    mesh_files(&root, &mut files);
    assert!(files.len() >= 11, "found only {files:?}");
    let mut checked = 0;
    for path in &files {
        let t = Instant::now();
        let r = read_mesh(path, Units::Millimetres).unwrap_or_else(|e| panic!("{e}"));
        let file = path.file_name().unwrap().to_string_lossy();
        let n = r.mesh.triangles.len();
        let (lo, hi) =
            r.mesh
                .positions
                .iter()
                .fold(([f64::MAX; 3], [f64::MIN; 3]), |(lo, hi), p| {
                    (
                        [lo[0].min(p.x), lo[1].min(p.y), lo[2].min(p.z)],
                        [hi[0].max(p.x), hi[1].max(p.y), hi[2].max(p.z)],
                    )
                });
        let size: Vec<String> = (0..3).map(|k| format!("{:.4}", hi[k] - lo[k])).collect();
        println!(
            "{file}: {n} triangles, {} vertices, size {} , {:.0} ms, warnings {:?}",
            r.mesh.positions.len(),
            size.join(" × "),
            t.elapsed().as_secs_f64() * 1e3,
            r.warnings
        );
        let stem = file.split('.').next().unwrap_or_default();
        let want = EXPECTED
            .iter()
            .find(|(f, _)| *f == file || f.starts_with(&format!("{stem}__")))
            .map(|&(_, n)| n);
        if let Some(want) = want {
            assert_eq!(n, want, "{file}");
            checked += 1;
        }
    }
    assert!(
        checked >= 11,
        "only {checked} files matched the README table"
    );
}
