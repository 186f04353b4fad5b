//! `wavemill contour`: the multiresolution (wavelet + loose hull) paths against the
//! contour-parallel baseline, end to end — on the project's own sample outline
//! (`data/mountain.svg`) through the binary, and on the shared test outlines through the
//! library. Both methods must never cut into the part, and the new one must leave no more
//! material than the baseline.

mod common;

use std::process::Command;

use wavemill::job::{ContourJobOptions, contour_compare};

fn wavemill(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_wavemill"))
        .args(args)
        .output()
        .expect("run wavemill")
}

/// One scanline row of the uncut-area measure is `row` mm high: two results may differ by
/// about a row times the stock width where a boundary falls between rows.
fn uncut_slack(report: &serde_json::Value) -> f64 {
    report["uncut_row_step_mm"].as_f64().unwrap_or(0.0) * 2.0
}

#[test]
fn mountain_sample_end_to_end_is_verified_and_deterministic() {
    let sample = common::repo_file("data/mountain.svg");
    let dir = std::env::temp_dir().join(format!("wavemill-contour-{}", std::process::id()));
    let (a, b) = (dir.join("a"), dir.join("b"));
    for out in [&a, &b] {
        let o = wavemill(&[
            "contour",
            sample.to_str().expect("utf-8 path"),
            "--tool",
            "flat:6",
            "--stock",
            "margin:10",
            "--compare",
            "--no-timings",
            "--out",
            out.to_str().expect("utf-8 path"),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    for f in [
        "wavelet.nc",
        "contour_parallel.nc",
        "compare.json",
        "paths.svg",
        "paths.png",
    ] {
        let (x, y) = (
            std::fs::read(a.join(f)).expect("output"),
            std::fs::read(b.join(f)).expect("output"),
        );
        assert!(!x.is_empty(), "{f} is empty");
        assert!(x == y, "{f} differs between two identical runs");
    }
    // Without --compare: the same wavelet.nc and nothing else.
    let c = dir.join("c");
    let o = wavemill(&[
        "contour",
        sample.to_str().expect("utf-8 path"),
        "--tool",
        "flat:6",
        "--stock",
        "margin:10",
        "--out",
        c.to_str().expect("utf-8 path"),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        std::fs::read(c.join("wavelet.nc")).expect("nc")
            == std::fs::read(a.join("wavelet.nc")).expect("nc")
    );
    assert!(!c.join("contour_parallel.nc").exists() && !c.join("compare.json").exists());
    let png = std::fs::read(a.join("paths.png")).expect("png");
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let gcode = std::fs::read_to_string(a.join("wavelet.nc")).expect("nc");
    assert!(
        gcode.contains("G2") || gcode.contains("G3"),
        "no arcs in wavelet.nc"
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(a.join("compare.json")).expect("json"))
            .expect("compare.json parses");
    assert!(report.get("timings_ms").is_none());
    let (w, p) = (&report["wavelet"], &report["contour_parallel"]);
    for m in [w, p] {
        assert!(m["min_clearance_minus_r_mm"].as_f64().expect("clearance") >= -1e-6);
    }
    let (wu, pu) = (
        w["uncut_area_mm2"].as_f64().expect("uncut"),
        p["uncut_area_mm2"].as_f64().expect("uncut"),
    );
    assert!(wu <= pu + uncut_slack(&report), "uncut {wu} vs {pu}");
    // The hull passes are a few lines and arcs each: fewer NC blocks than the offsets.
    assert!(w["nc_blocks"].as_u64() < p["nc_blocks"].as_u64());
    // The lower bound of any path with passes one stepover apart.
    let bound = report["area_over_stepover_mm"].as_f64().expect("bound");
    for m in [w, p] {
        assert!(m["cutting_length_mm"].as_f64().expect("length") >= 0.95 * bound);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_inputs_exit_1_naming_the_problem() {
    let dir = std::env::temp_dir().join(format!("wavemill-contour-bad-{}", std::process::id()));
    let out = dir.to_str().expect("utf-8 path");
    let o = wavemill(&[
        "contour",
        "/nonexistent/part.svg",
        "--tool",
        "flat:6",
        "--stock",
        "margin:5",
        "--out",
        out,
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("part.svg: cannot read"));
    let sample = common::repo_file("data/mountain.svg");
    let o = wavemill(&[
        "contour",
        sample.to_str().expect("utf-8 path"),
        "--tool",
        "ball:6",
        "--stock",
        "margin:5",
        "--out",
        out,
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--tool ball:6"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every single-shape test outline, the 24-unit icons scaled ×5 and the rabbit ×0.5 (to keep
/// the debug-build test short): no overcut for either method, no more uncut area.
#[test]
fn shared_outlines_no_overcut_no_more_uncut() {
    let Some(data) = common::testdata() else {
        return;
    };
    for (file, scale) in [
        ("clipper2_rabbit.svg", 0.5),
        ("mdi_airplane.svg", 5.0),
        ("mdi_phone-classic.svg", 5.0),
        ("mdi_flower.svg", 5.0),
    ] {
        let mut opts = ContourJobOptions::new(6.0, 10.0);
        opts.scale = scale;
        opts.timings = false;
        let c = contour_compare(&data.join("outlines").join(file), &opts).expect(file);
        let r = &c.report;
        for m in [&r.wavelet, &r.contour_parallel] {
            assert!(
                m.min_clearance_minus_r_mm >= -1e-6,
                "{file}: overcut {}",
                m.min_clearance_minus_r_mm
            );
        }
        assert!(
            r.wavelet.uncut_area_mm2
                <= r.contour_parallel.uncut_area_mm2 + 2.0 * r.uncut_row_step_mm,
            "{file}: uncut {} vs {}",
            r.wavelet.uncut_area_mm2,
            r.contour_parallel.uncut_area_mm2
        );
        assert!(
            r.wavelet.nc_blocks < r.contour_parallel.nc_blocks,
            "{file}: blocks"
        );
    }
}
