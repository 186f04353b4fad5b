//! Seed 002's convex-hull-box roughing of the real SolidWorks impeller IGES
//! (`../shared/testdata/cad/`), end to end through `wavemill rough-boxes` with the seed's own
//! example settings (tool radius 6, maximum depth 6, minimum depth 2): the boxes enclose every
//! vertex of the part's tessellation, every layer lies at a box top within the depths, the
//! posted program keeps out of every box and off the part, the tri-dexel run finds no gouge,
//! the uniform route is planned beside it, and a single-threaded run posts the same program.

use crate::common;
use std::process::Command;

use serde_json::Value;

fn rough_boxes(part: &std::path::Path, out: &std::path::Path, extra: &[&str], threads: &str) {
    let output = Command::new(env!("CARGO_BIN_EXE_wavemill"))
        .env("RAYON_NUM_THREADS", threads)
        .arg("rough-boxes")
        .arg(part)
        .args([
            "--tool",
            "flat:12",
            "--max-depth",
            "6",
            "--min-depth",
            "2",
            "--up",
            "0,0,-1",
            // A coarse mesh and stock model keep the test quick; the boxes are exact.
            "--tolerance",
            "0.05",
            "--resolution",
            "1",
            "--no-timings",
            "--out",
        ])
        .arg(out)
        .args(extra)
        .output()
        .expect("run wavemill");
    assert_eq!(
        output.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
}

#[test]
fn the_impeller_is_roughed_inside_no_box_and_compared_with_uniform_layers() {
    let Some(dir) = common::testdata() else {
        return;
    };
    let part = dir.join("cad/impeller_solidworks__pyvista_pyiges.igs");
    let out = std::env::temp_dir().join(format!("wavemill-rough-boxes-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    rough_boxes(&part, &out.join("compared"), &["--compare"], "2");
    let report: Value = serde_json::from_slice(
        &std::fs::read(out.join("compared/rough.json")).expect("rough.json"),
    )
    .expect("json");

    let boxes = &report["hull_boxes"];
    assert_eq!(boxes["faces"], 277);
    assert!(boxes["trimmed_away"].as_u64().unwrap() > 0);
    assert!(boxes["mesh_enclosure"]["samples"].as_u64().unwrap() > 100_000);
    assert_eq!(boxes["mesh_enclosure"]["outside"], 0);
    assert_eq!(boxes["enclosure"]["outside"], 0);

    let tool = &report["tools"][0];
    let layers = tool["layers"].as_array().unwrap();
    assert!(layers.len() >= 4, "{layers:?}");
    let mut above = f64::INFINITY;
    for l in layers {
        let (z, depth) = (l["z"].as_f64().unwrap(), l["depth"].as_f64().unwrap());
        assert!(z < above && depth <= 6.0 + 1e-9, "{l}");
        // Every layer on this part lies at a box top (planes are dense), at least the
        // minimum below the one above it.
        assert_eq!(l["at_flat"], true, "{l}");
        assert!(depth >= 2.0 - 1e-9, "{l}");
        above = z;
    }
    let check = &tool["overcut_vs_boxes"];
    assert_eq!(check["violation_count"], 0, "{check}");
    assert!(
        check["min_clearance_mm"].as_f64().unwrap() > -1e-4,
        "{check}"
    );
    assert!(check["moves"].as_u64().unwrap() > 1000);
    assert!(
        tool["overcut_vs_part"]["overcuts"]
            .as_array()
            .unwrap()
            .is_empty()
    );
    assert!(
        tool["overcut_vs_part"]["min_clearance_mm"]
            .as_f64()
            .unwrap()
            > 0.0
    );
    let stock = &tool["stock"];
    assert_eq!(stock["gouges"], 0);
    assert_eq!(stock["collisions"], 0);
    assert_eq!(stock["rapids_through_material"], 0);
    assert!(stock["removed_volume_mm3"].as_f64().unwrap() > 10_000.0);

    // The comparison: the uniform route cuts equal layers to the part's sections, the box
    // route's at box tops; both keep off the part (to the posted rounding).
    let rows = report["comparison"].as_array().expect("comparison");
    assert_eq!(rows.len(), 2);
    assert_eq!(
        (rows[0]["route"].as_str(), rows[1]["route"].as_str()),
        (Some("hull-boxes"), Some("uniform"))
    );
    assert_eq!(rows[1]["layers_at_tops"], 0);
    for row in rows {
        assert!(
            row["min_clearance_to_part_mm"].as_f64().unwrap() > -1e-4,
            "{row}"
        );
        assert!(row["material_left_mm3"].as_f64().unwrap() > 0.0, "{row}");
        assert!(
            row["path_length_mm"].as_f64().unwrap() > row["cutting_length_mm"].as_f64().unwrap()
        );
    }

    // One thread, no comparison: the same program, byte for byte.
    rough_boxes(&part, &out.join("single"), &[], "1");
    let program = |d: &str| std::fs::read(out.join(d).join("rough.nc")).expect("rough.nc");
    assert!(program("compared") == program("single"));
    let _ = std::fs::remove_dir_all(&out);
}
