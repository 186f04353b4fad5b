//! `wavemill contour`: the multiresolution (wavelet + loose hull) paths against the
//! contour-parallel baseline, end to end — on the project's own sample outline
//! (`data/mountain.svg`) through the binary, and on the shared test outlines through the
//! library. Both methods must never cut into the part, and the new one must leave no more
//! material than the baseline.

use crate::common;
use std::process::Command;

use wavemill::job::{
    CompareReport, ContourJobOptions, StockSpec, contour_compare, contour_wavelet,
};

fn wavemill(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_wavemill"))
        .args(args)
        .output()
        .expect("run wavemill")
}

/// `wavemill contour OUTLINE --tool flat:6 --stock margin:10 EXTRA… --out OUT`, which must
/// succeed.
fn contour_flat6_margin10(outline: &std::path::Path, out: &std::path::Path, extra: &[&str]) {
    let (outline, out) = (
        outline.to_str().expect("utf-8 path"),
        out.to_str().expect("utf-8 path"),
    );
    let mut args = vec![
        "contour",
        outline,
        "--tool",
        "flat:6",
        "--stock",
        "margin:10",
    ];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["--out", out]);
    let o = wavemill(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// One scanline row of the uncut-area measure is `row` mm high: two results may differ by
/// about a row times the stock width where a boundary falls between rows.
fn uncut_slack(report: &serde_json::Value) -> f64 {
    report["uncut_row_step_mm"].as_f64().unwrap_or(0.0) * 2.0
}

/// No overcut for either method in `compare.json`, and no more uncut area for the new one.
fn assert_verified_json(report: &serde_json::Value) {
    let (w, p) = (&report["wavelet"], &report["contour_parallel"]);
    for m in [w, p] {
        assert!(m["min_clearance_minus_r_mm"].as_f64().expect("clearance") >= -1e-6);
    }
    let (wu, pu) = (
        w["uncut_area_mm2"].as_f64().expect("uncut"),
        p["uncut_area_mm2"].as_f64().expect("uncut"),
    );
    assert!(wu <= pu + uncut_slack(report), "uncut {wu} vs {pu}");
}

/// The same for a report in memory.
fn assert_verified(r: &CompareReport, what: &str) {
    for m in [&r.wavelet, &r.contour_parallel] {
        assert!(
            m.min_clearance_minus_r_mm >= -1e-6,
            "{what}: overcut {}",
            m.min_clearance_minus_r_mm
        );
    }
    assert!(
        r.wavelet.uncut_area_mm2 <= r.contour_parallel.uncut_area_mm2 + 2.0 * r.uncut_row_step_mm,
        "{what}: uncut {} vs {}",
        r.wavelet.uncut_area_mm2,
        r.contour_parallel.uncut_area_mm2
    );
    // Two independent measures of what each path removes: the material map's replay (plunges,
    // passes, links) and the exact scanline region minus the exact uncut area. They agree to
    // the map's quantisation (cells of min(r, s)/16 along the region's boundaries).
    for (m, name) in [
        (&r.wavelet, "wavelet"),
        (&r.contour_parallel, "contour-parallel"),
    ] {
        // Traverses at depth run through air: the replay finds (almost) nothing under them —
        // at most a few cells whose centres sit on the stock's edge.
        assert!(
            m.traverse_area_mm2 <= 0.05,
            "{what}, {name}: traverses removed {} mm²",
            m.traverse_area_mm2
        );
        let replayed = m.pass_area_mm2 + m.entry_area_mm2 + m.link_area_mm2;
        let exact = r.region_area_mm2 - m.uncut_area_mm2;
        assert!(
            (replayed - exact).abs() <= 0.01 * exact,
            "{what}, {name}: the map removed {replayed} mm², the exact measure {exact} mm²"
        );
        assert!(
            m.engagement_mean_mm <= m.engagement_p99_mm
                && m.engagement_p99_mm <= m.engagement_max_mm,
            "{what}, {name}: engagement {} / {} / {}",
            m.engagement_mean_mm,
            m.engagement_p99_mm,
            m.engagement_max_mm
        );
    }
    // The baseline's passes remove no more than a stepover per mm of pass on average: the
    // stepover is the engagement of passes one stepover apart, less on passes around convex
    // shapes.
    assert!(
        r.contour_parallel.engagement_mean_mm <= r.stepover_mm,
        "{what}: contour-parallel mean engagement {}",
        r.contour_parallel.engagement_mean_mm
    );
}

/// One motion of a 2.5D program: where it ends and, for an arc, its centre and sense.
#[derive(Debug)]
struct PlanarMotion {
    rapid: bool,
    end: [f64; 3],
    arc: Option<([f64; 2], bool)>,
}

/// Reads the motions of a 2.5D program the way the post documents them (modal G0–G3, X Y Z,
/// arc centres as I J from the start), sharing no code with the post; checks each arc's
/// start and end radii agree within a grid unit.
fn read_planar_program(text: &str) -> Vec<PlanarMotion> {
    let (mut position, mut mode, mut out) = ([f64::NAN; 3], None::<u8>, Vec::new());
    for line in text.lines() {
        let code = line.split('(').next().unwrap_or("").trim();
        if code.is_empty() || code == "%" {
            continue;
        }
        let (mut end, mut moved, mut ij) = (position, false, [None::<f64>; 2]);
        for word in code.split_whitespace() {
            let (letter, number) = word.split_at(1);
            let v: f64 = number
                .parse()
                .unwrap_or_else(|_| panic!("word {word} in {line}"));
            match letter {
                "G" if v <= 3.0 => mode = Some(v as u8),
                "X" | "Y" | "Z" => {
                    end["XYZ".find(letter).unwrap()] = v;
                    moved = true;
                }
                "I" => ij[0] = Some(v),
                "J" => ij[1] = Some(v),
                _ => {}
            }
        }
        if !moved {
            continue;
        }
        let mode = mode.expect("a motion before any motion word");
        let arc = (mode >= 2).then(|| {
            let c = [
                position[0] + ij[0].expect("I"),
                position[1] + ij[1].expect("J"),
            ];
            let r0 = (position[0] - c[0]).hypot(position[1] - c[1]);
            let r1 = (end[0] - c[0]).hypot(end[1] - c[1]);
            assert!((r0 - r1).abs() <= 1e-4, "radii {r0} and {r1}: {line}");
            (c, mode == 3)
        });
        out.push(PlanarMotion {
            rapid: mode == 0,
            end,
            arc,
        });
        position = end;
    }
    out
}

/// LinuxCNC's interpreter (`rs274 -g`) reads a 2.5D program into the motions the tests'
/// reader sees: the same kind, end, arc centre and sense, one for one. Skipped, saying so,
/// where `rs274` is not installed.
fn a_real_control_reads_the_contour_program(gcode: &str) {
    let Ok(rs274) = common::plan_checks::which("rs274") else {
        eprintln!("skipped: rs274 not found (apt-get install linuxcnc-uspace)");
        return;
    };
    let dir = std::env::temp_dir().join(format!("wavemill-rs274-2d-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (program, canon) = (dir.join("contour.nc"), dir.join("contour.canon"));
    std::fs::write(&program, gcode).unwrap();
    let run = Command::new(rs274)
        .arg("-g")
        .arg(&program)
        .arg(&canon)
        .stdin(std::process::Stdio::null())
        .output()
        .expect("run rs274");
    assert!(
        run.status.success(),
        "rs274: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    let text = std::fs::read_to_string(&canon).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    let numbers = |rest: &str| -> Vec<f64> {
        rest.trim_end_matches(')')
            .split(',')
            .map(|x| x.trim().parse().unwrap())
            .collect()
    };
    let mut canonical = Vec::new();
    for l in text.lines() {
        if let Some(i) = l.find("STRAIGHT_TRAVERSE(") {
            let v = numbers(&l[i + 18..]);
            canonical.push((true, [v[0], v[1], v[2]], None));
        } else if let Some(i) = l.find("STRAIGHT_FEED(") {
            let v = numbers(&l[i + 14..]);
            canonical.push((false, [v[0], v[1], v[2]], None));
        } else if let Some(i) = l.find("ARC_FEED(") {
            // first_end, second_end, first_axis, second_axis, rotation, axis_end_point, …
            let v = numbers(&l[i + 9..]);
            canonical.push((false, [v[0], v[1], v[5]], Some(([v[2], v[3]], v[4] > 0.0))));
        }
    }
    let read = read_planar_program(gcode);
    assert!(read.len() > 20 && read.iter().any(|m| m.arc.is_some()));
    assert_eq!(
        canonical.len(),
        read.len(),
        "rs274 and the reader count different motions"
    );
    for (c, m) in canonical.iter().zip(&read) {
        // An axis not yet commanded (NaN in the reader) is wherever the control was.
        let near = |a: &[f64], b: &[f64]| {
            a.iter()
                .zip(b)
                .all(|(x, y)| y.is_nan() || (x - y).abs() < 1e-9)
        };
        assert_eq!(c.0, m.rapid, "{m:?}");
        assert!(
            near(&c.1, &m.end),
            "rs274 ends at {:?}, the reader at {m:?}",
            c.1
        );
        match (&c.2, &m.arc) {
            (None, None) => {}
            (Some((cc, ccw)), Some((mc, mccw))) => {
                assert!(
                    near(cc, mc) && ccw == mccw,
                    "rs274 arc {:?}, the reader's {m:?}",
                    c.2
                );
            }
            _ => panic!("rs274 and the reader disagree on an arc: {:?} / {m:?}", c.2),
        }
    }
}

#[test]
fn mountain_sample_end_to_end_is_verified_and_deterministic() {
    let sample = common::repo_file("data/mountain.svg");
    let dir = std::env::temp_dir().join(format!("wavemill-contour-{}", std::process::id()));
    let (a, b) = (dir.join("a"), dir.join("b"));
    for out in [&a, &b] {
        contour_flat6_margin10(&sample, out, &["--compare", "--no-timings"]);
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
    contour_flat6_margin10(&sample, &c, &[]);
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
    for f in ["wavelet.nc", "contour_parallel.nc"] {
        let text = std::fs::read_to_string(a.join(f)).expect("nc");
        a_real_control_reads_the_contour_program(&text);
    }
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(a.join("compare.json")).expect("json"))
            .expect("compare.json parses");
    assert!(report.get("timings_ms").is_none());
    assert_verified_json(&report);
    let (w, p) = (&report["wavelet"], &report["contour_parallel"]);
    // The hull passes are a few lines and arcs each: fewer NC blocks than the offsets.
    assert!(w["nc_blocks"].as_u64() < p["nc_blocks"].as_u64());
    // The lower bound of any path with passes one stepover apart.
    let bound = report["area_over_stepover_mm"].as_f64().expect("bound");
    for m in [w, p] {
        assert!(m["cutting_length_mm"].as_f64().expect("length") >= 0.95 * bound);
    }
    // --direction climb: the same passes (same length), none reversed, so more retracts.
    let climb = dir.join("climb");
    contour_flat6_margin10(
        &sample,
        &climb,
        &["--compare", "--no-timings", "--direction", "climb"],
    );
    let climbing = compare_json(&climb);
    assert_eq!(report["cut_direction"], "mixed");
    assert_eq!(climbing["cut_direction"], "climb");
    assert_verified_json(&climbing);
    for m in ["wavelet", "contour_parallel"] {
        let length = |r: &serde_json::Value| r[m]["cutting_length_mm"].as_f64().expect("length");
        let rapids = |r: &serde_json::Value| r[m]["rapid_links"].as_u64().expect("rapids");
        assert!((length(&climbing) - length(&report)).abs() < 1e-6 * length(&report));
        assert!(
            rapids(&climbing) > rapids(&report),
            "{m}: climb needs more retracts"
        );
    }
    let o = wavemill(&["contour", "--direction", "sideways", "x.svg"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("sideways"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_inputs_exit_with_their_codes_naming_the_problem() {
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
    // A bad command-line value is a usage error (issue 17 item 13).
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--tool") && err.contains("ball:6"), "{err}");
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
        assert_verified(r, file);
        assert!(
            r.wavelet.nc_blocks < r.contour_parallel.nc_blocks,
            "{file}: blocks"
        );
    }
}

fn compare_json(dir: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("compare.json")).expect("json"))
        .expect("compare.json parses")
}

/// The bundled impeller (90 mm wide, 30 mm tall) cut at z = 10: hub with its bore and six
/// blades. Both methods clear the section without cutting into it; an outline-only option
/// and a plane above the part are refused naming the file and the Z.
#[test]
fn impeller_section_end_to_end() {
    let part = common::repo_file("data/impeller.glb");
    let part = part.to_str().expect("utf-8 path");
    let dir = std::env::temp_dir().join(format!("wavemill-contour-z-{}", std::process::id()));
    let out = dir.to_str().expect("utf-8 path");
    let run = |extra: &[&str]| {
        let mut args = vec![
            "contour",
            part,
            "--tool",
            "flat:6",
            "--stock",
            "margin:10",
            "--out",
            out,
        ];
        args.extend_from_slice(extra);
        wavemill(&args)
    };
    let o = run(&["--z", "10", "--compare", "--no-timings"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report = compare_json(&dir);
    assert_eq!(report["section_z_mm"].as_f64(), Some(10.0));
    // The default band keeps consecutive passes within r: eq. 3.3 asks for no curve.
    assert_eq!(
        report["wavelet_planner"]["adaptive_curves"].as_u64(),
        Some(0)
    );
    assert_verified_json(&report);
    // Stock 110 × 110 mm minus the section: the hub (r ≈ 15 mm with its bore) and the
    // blades take a few thousand mm², far from nothing and far from all of it.
    let region = report["region_area_mm2"].as_f64().expect("area");
    assert!(
        region > 0.6 * 110.0 * 110.0 && region < 0.99 * 110.0 * 110.0,
        "{region}"
    );

    let o = run(&["--z", "10", "--band=-1"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--band: band = -1: must be"));
    // A mesh part without --z is an incomplete command line.
    let o = run(&[]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--z: impeller.glb: z is needed for a mesh part"),
        "{err}"
    );
    let o = run(&["--z", "40"]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("impeller.glb: the plane z = 40 mm misses the part"),
        "{err}"
    );
    let sample = common::repo_file("data/mountain.svg");
    let mut args = vec!["contour", sample.to_str().expect("utf-8 path"), "--z", "3"];
    args.extend(["--tool", "flat:6", "--stock", "margin:5", "--out", out]);
    let o = wavemill(&args);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--z: mountain.svg: z = 3 applies to mesh"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A square part in a circular stock outline: the region is the disc minus the square (closed
/// form), both methods stay off the part, the new one leaves no more material; a stock
/// outline that does not contain the part is refused.
#[test]
fn stock_given_as_an_outline() {
    let dir = std::env::temp_dir().join(format!("wavemill-contour-stock-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let svg = |name: &str, body: &str| write_svg(&dir, name, "0 0 200 200", body);
    let part = svg(
        "part.svg",
        r#"<rect x="85" y="90" width="30" height="20"/>"#,
    );
    let disc = svg("disc.svg", r#"<circle cx="105" cy="100" r="40"/>"#);
    let small = svg("small.svg", r#"<circle cx="100" cy="100" r="12"/>"#);
    let mut opts = ContourJobOptions::new(6.0, 0.0);
    opts.stock = StockSpec::Outline(disc);
    opts.timings = false;
    let c = contour_compare(&part, &opts).expect("disc stock");
    let r = &c.report;
    assert_eq!(r.stock, "outline:disc.svg");
    let exact = std::f64::consts::PI * 1600.0 - 600.0;
    assert!(
        (r.region_area_mm2 - exact).abs() < 80.0 * 2.0 * r.uncut_row_step_mm,
        "{} vs {exact}",
        r.region_area_mm2
    );
    assert_verified(r, "disc stock");
    // Nothing may be cut outside the stock grown by the tool radius (SVG y is flipped: the
    // disc's centre is (105, −100) mm).
    assert!(
        c.wavelet_nc
            .lines()
            .filter_map(|l| {
                let x = l.split_whitespace().find_map(|w| w.strip_prefix('X'))?;
                let y = l.split_whitespace().find_map(|w| w.strip_prefix('Y'))?;
                Some((x.parse::<f64>().ok()?, y.parse::<f64>().ok()?))
            })
            .all(|(x, y)| ((x - 105.0).hypot(y + 100.0)) <= 43.0 + 1e-3)
    );

    opts.stock = StockSpec::Outline(small);
    let e = contour_compare(&part, &opts).unwrap_err().to_string();
    assert!(
        e.starts_with("small.svg: the part part.svg touches or crosses the stock outline"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 17 items 9, 11 and 13 through the binary: bad command-line values exit 2 naming the
/// value; an absurd transform is refused naming the file; a run estimated too large is
/// refused at once, saying how to raise the limit; a stock with nothing to machine exits 4
/// and writes no program; a bow-tie says where it crosses itself; a part far smaller than the
/// tool still gets a program.
#[test]
fn hardening_errors_exit_with_their_codes() {
    let dir = std::env::temp_dir().join(format!("wavemill-contour-hard-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let svg = |name: &str, body: &str| {
        write_svg(&dir, name, "0 0 100 100", body)
            .to_str()
            .expect("utf-8 path")
            .to_string()
    };
    let rect = svg(
        "rect.svg",
        r#"<rect x="10" y="10" width="30" height="20"/>"#,
    );
    let huge = svg(
        "huge.svg",
        r#"<g transform="scale(1e30)"><rect x="10" y="10" width="30" height="20"/></g>"#,
    );
    let bowtie = svg("bowtie.svg", r#"<polygon points="0,0 10,10 10,0 0,10"/>"#);
    let tiny = svg(
        "tiny.svg",
        r#"<rect x="10" y="10" width="1e-6" height="1e-6"/>"#,
    );
    let out = dir.join("out");
    let out_s = out.to_str().expect("utf-8 path").to_string();
    let run = |part: &str, extra: &[&str]| {
        let _ = std::fs::remove_dir_all(&out);
        let mut args = vec!["contour", part, "--out", &out_s];
        args.extend_from_slice(extra);
        for (flag, default) in [("--tool", "flat:6"), ("--stock", "margin:10")] {
            if !extra.contains(&flag) {
                args.extend([flag, default]);
            }
        }
        let o = wavemill(&args);
        (
            o.status.code(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    // A bad value names its flag and itself.
    for (extra, flag, value) in [
        (&["--tool", "flat:x"][..], "--tool", "flat:x"),
        (&["--tool", "ball:6"][..], "--tool", "ball:6"),
        (&["--stock", "margin:-1"][..], "--stock", "margin:-1"),
        (&["--stock", "box:3"][..], "--stock", "box:3"),
        (&["--stepover=-1"][..], "--stepover", "-1"),
        (&["--scale", "0"][..], "--scale", "0"),
        (&["--scale", "inf"][..], "--scale", "inf"),
    ] {
        let (code, err) = run(&rect, extra);
        assert_eq!(code, Some(2), "{extra:?}: {err}");
        assert!(
            err.contains(flag) && err.contains(value),
            "{extra:?}: {err}"
        );
    }
    let (code, err) = run(&huge, &[]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("huge.svg: coordinates reach"), "{err}");
    assert!(!out.join("wavelet.nc").exists());
    let started = std::time::Instant::now();
    let (code, err) = run(&rect, &["--scale", "1e6"]);
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("rect.svg") && err.contains("--max-levels"),
        "{err}"
    );
    assert!(
        started.elapsed().as_secs() < 20,
        "refused only after planning"
    );
    // All corners: a 2,000-point star keeps every vertex after thinning, and is refused
    // before any offset when the limit is below that; a dense straight-edged rectangle
    // thins to its 4 corners and passes the same limit.
    let star_points: Vec<String> = (0..2000)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 2000.0;
            let r = if k % 2 == 0 { 45.0 } else { 30.0 };
            format!("{:.6},{:.6}", 50.0 + r * a.cos(), 50.0 + r * a.sin())
        })
        .collect();
    let star = svg(
        "star.svg",
        &format!(r#"<polygon points="{}"/>"#, star_points.join(" ")),
    );
    let (code, err) = run(&star, &["--max-outline-vertices", "1000"]);
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("star.svg")
            && err.contains("2000 vertices")
            && err.contains("--max-outline-vertices"),
        "{err}"
    );
    assert!(!out.join("wavelet.nc").exists());
    let dense_rect_points: Vec<String> = (0..4000)
        .map(|k| {
            let t = (k % 1000) as f64 * 0.03;
            let (x, y) = match k / 1000 {
                0 => (10.0 + t, 10.0),
                1 => (40.0, 10.0 + t),
                2 => (40.0 - t, 40.0),
                _ => (10.0, 40.0 - t),
            };
            format!("{x:.6},{y:.6}")
        })
        .collect();
    let dense_rect = svg(
        "dense-rect.svg",
        &format!(r#"<polygon points="{}"/>"#, dense_rect_points.join(" ")),
    );
    let (code, err) = run(&dense_rect, &["--max-outline-vertices", "1000"]);
    assert_eq!(code, Some(0), "{err}");
    let (code, err) = run(&rect, &["--stock", "margin:0"]);
    assert_eq!(code, Some(4), "{err}");
    assert!(
        err.contains("nothing to cut: ") && err.contains("rect.svg"),
        "{err}"
    );
    assert!(!out.join("wavelet.nc").exists());
    let (code, err) = run(&bowtie, &[]);
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("bowtie.svg") && err.contains("and itself cross at (5.000000"),
        "{err}"
    );
    let (code, err) = run(&tiny, &[]);
    assert_eq!(code, Some(0), "{err}");
    let nc = std::fs::read_to_string(out.join("wavelet.nc")).expect("program");
    assert!(nc.contains("G1"), "no cutting move");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 17 item 12: dense outlines — a 2,000-point star (1,000 narrow spikes between radii
/// 30 and 50 mm, each 0.16 mm wide at its base), a 2,000-point polygon circle and a
/// 100,000-point smooth 5-lobe star (the offset engine returned 1,248 loops for it, some
/// crossing the part: "cuts 3 mm into the part", exit 3) — plan in a debug build in seconds
/// and give verified paths (no overcut). With `--compare`, a 10,000-point smooth star: the
/// baseline's finishing offset came 3.2e-5 mm inside r (exit 3).
#[test]
fn dense_star_and_circle_outlines_plan_verified_paths() {
    let dir = std::env::temp_dir().join(format!("wavemill-contour-dense-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let polygon = |name: &str, n: usize, radius: &dyn Fn(usize, f64) -> f64| {
        let points: Vec<String> = (0..n)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / n as f64;
                let r = radius(k, a);
                format!("{:.6},{:.6}", r * a.cos(), r * a.sin())
            })
            .collect();
        write_svg(
            &dir,
            name,
            "-60 -60 120 120",
            &format!(r#"<polygon points="{}"/>"#, points.join(" ")),
        )
    };
    let smooth_star = |_: usize, a: f64| 35.0 * (1.0 + 0.3 * (5.0 * a).cos());
    let star = polygon("star.svg", 2000, &|k, _| {
        if k % 2 == 0 { 50.0 } else { 30.0 }
    });
    let circle = polygon("circle.svg", 2000, &|_, _| 50.0);
    let dense_smooth = polygon("smooth-100k.svg", 100_000, &smooth_star);
    for part in [star, circle, dense_smooth] {
        let mut opts = ContourJobOptions::new(6.0, 10.0);
        opts.timings = false;
        // The wavelet path alone (the baseline's figures cost more than the plan here); it is
        // verified against the part before it is returned.
        let (nc, figures) = contour_wavelet(&part, &opts).expect("dense outline");
        assert!(
            figures.min_clearance_minus_r_mm >= -1e-6,
            "{}",
            part.display()
        );
        assert!(
            figures.passes > 0 && nc.contains("G1"),
            "{}",
            part.display()
        );
    }
    let smooth = polygon("smooth-10k.svg", 10_000, &smooth_star);
    let mut opts = ContourJobOptions::new(6.0, 10.0);
    opts.timings = false;
    let c = contour_compare(&smooth, &opts).expect("10k smooth star, both methods");
    for figures in [&c.report.wavelet, &c.report.contour_parallel] {
        assert!(figures.min_clearance_minus_r_mm >= -1e-6);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Writes an SVG file `name` in `dir` with the given view box and body; returns its path.
fn write_svg(dir: &std::path::Path, name: &str, view_box: &str, body: &str) -> std::path::PathBuf {
    let path = dir.join(name);
    std::fs::write(
        &path,
        format!(r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="{view_box}">{body}</svg>"#),
    )
    .expect("write svg");
    path
}
