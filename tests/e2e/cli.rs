//! The command-line tool as a script would use it: help, exit codes, errors that name the
//! file, the four outputs, regenerated sample data, byte-identical runs.

use crate::common;
use std::process::{Command, Output};

use crate::common::repo_file;
use wavemill::job::{SamplePart, sample_files};

fn wavemill(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_wavemill"))
        .args(args)
        .output()
        .expect("run wavemill")
}

fn temp_dir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("wavemill-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn every_subcommand_has_help() {
    for sub in [
        &["--help"][..],
        &["info", "--help"],
        &["sample", "--help"],
        &["subdivide", "--help"],
        &["levels", "--help"],
        &["offsets", "--help"],
        &["plan", "--help"],
        &["access", "--help"],
        &["contour", "--help"],
        &["tools", "--help"],
        &["tessellate", "--help"],
        &["simulate", "--help"],
        &["rough", "--help"],
        &["rough-boxes", "--help"],
        &["lens", "--help"],
    ] {
        let out = wavemill(sub);
        assert_eq!(out.status.code(), Some(0), "{sub:?}");
        assert!(
            String::from_utf8_lossy(&out.stdout).contains("Usage"),
            "{sub:?}"
        );
    }
}

#[test]
fn bad_input_gives_exit_code_and_names_the_problem() {
    let out_dir = temp_dir("bad");
    let out = out_dir.to_str().unwrap();
    let missing = wavemill(&["plan", "no/such/part.stl", "--out", out]);
    assert_eq!(missing.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("no/such/part.stl"));

    let garbage = out_dir.with_extension("stl");
    std::fs::write(
        &garbage,
        b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 zero\n",
    )
    .unwrap();
    let parse = wavemill(&["info", garbage.to_str().unwrap()]);
    assert_eq!(parse.status.code(), Some(1));
    let err = String::from_utf8_lossy(&parse.stderr);
    assert!(
        err.contains(garbage.file_name().unwrap().to_str().unwrap()) && err.contains("line 4"),
        "{err}"
    );
    std::fs::remove_file(&garbage).unwrap();

    let tool = wavemill(&[
        "plan",
        "data/impeller.glb",
        "--tool",
        "ball:x",
        "--out",
        out,
    ]);
    assert_eq!(
        tool.status.code(),
        Some(2),
        "a bad flag value is a usage error"
    );
    assert!(String::from_utf8_lossy(&tool.stderr).contains("ball:x"));

    let job = out_dir.with_extension("toml");
    std::fs::write(&job, "[strategy]\nscallop_heigth = 0.1\n").unwrap();
    let bad_job = wavemill(&[
        "plan",
        "data/impeller.glb",
        "--job",
        job.to_str().unwrap(),
        "--out",
        out,
    ]);
    assert_eq!(bad_job.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&bad_job.stderr).contains("scallop_heigth"));
    std::fs::remove_file(&job).unwrap();

    assert_eq!(wavemill(&["plan", "--no-such-flag"]).status.code(), Some(2));
    assert!(!out_dir.join("job.nc").exists(), "no output after errors");

    // Convex-hull boxes need surfaces, and a flat or bull-nose end mill.
    let mesh = wavemill(&[
        "rough-boxes",
        "data/impeller.glb",
        "--tool",
        "flat:6",
        "--out",
        out,
    ]);
    assert_eq!(mesh.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&mesh.stderr).contains("IGES"));
    let ball = wavemill(&["rough-boxes", "part.igs", "--tool", "ball:6", "--out", out]);
    assert_eq!(ball.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&ball.stderr).contains("flat or bull-nose"));
    assert!(!out_dir.join("rough.nc").exists(), "no output after errors");
}

/// The committed sample files are exactly what the generator makes today.
#[test]
fn regenerating_the_sample_parts_gives_identical_bytes() {
    for part in [
        SamplePart::Impeller(Default::default()),
        SamplePart::Blade(Default::default()),
    ] {
        let (_, files) = sample_files(&part).unwrap();
        for (name, bytes) in files {
            let committed = std::fs::read(repo_file(&format!("data/{name}"))).unwrap();
            assert!(
                committed == bytes,
                "data/{name} differs from the generator's output: run `cargo run --release -- sample {}`",
                part.name()
            );
        }
    }
}

/// What `plan` writes (the report third: the test reads it).
const PLAN_FILES: [&str; 7] = [
    "job.nc",
    "cl.csv",
    "report.json",
    "paths.glb",
    "cl.apt",
    "scallop.glb",
    "scallop.png",
];

/// A coarse plan through the CLI with 1 and with 2 threads: the outputs exist, are
/// complete, and are byte-identical (with --no-timings).
#[test]
fn plan_writes_identical_outputs_for_any_thread_count() {
    let job = temp_dir("job").with_extension("toml");
    let text = std::fs::read_to_string(repo_file("data/impeller.toml")).unwrap();
    let text = text.replace(
        "path = \"impeller.glb\"",
        &format!("path = {:?}", repo_file("data/impeller.glb")),
    );
    let text = text
        .replace("scallop_height = 0.01", "scallop_height = 0.5")
        .replace("max_step = 1.0", "max_step = 3.0");
    std::fs::write(&job, text).unwrap();
    let mut outputs = Vec::new();
    for threads in ["1", "2"] {
        let dir = temp_dir(&format!("plan{threads}"));
        let out = wavemill(&[
            "plan",
            "--job",
            job.to_str().unwrap(),
            "--threads",
            threads,
            "--blank",
            "none",
            "--no-timings",
            "--out",
            dir.to_str().unwrap(),
        ]);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let files: Vec<Vec<u8>> = PLAN_FILES
            .iter()
            .map(|f| std::fs::read(dir.join(f)).unwrap())
            .collect();
        let gcode = String::from_utf8_lossy(&files[0]);
        assert!(
            gcode.trim_end().ends_with('%') && gcode.contains("M30"),
            "G-code must be complete"
        );
        let report: serde_json::Value = serde_json::from_slice(&files[2]).unwrap();
        assert!(report.get("timings_ms").is_none());
        assert!(report["poses"]["cut"].as_u64().unwrap() > 100);
        outputs.push(files);
        std::fs::remove_dir_all(&dir).unwrap();
    }
    for (k, name) in PLAN_FILES.iter().enumerate() {
        assert!(
            outputs[0][k] == outputs[1][k],
            "{name} differs between 1 and 2 threads"
        );
    }
    std::fs::remove_file(&job).unwrap();
}

/// `subdivide` multiplies the triangles by 4 per level, keeps a closed part closed with its
/// genus, and writes OBJ or GLB by extension (anything else is an error).
#[test]
fn subdivide_writes_obj_and_glb() {
    let dir = temp_dir("subdivide");
    std::fs::create_dir_all(&dir).unwrap();
    for ext in ["obj", "glb"] {
        let out = dir.join(format!("blade.{ext}"));
        let run = wavemill(&[
            "subdivide",
            "data/blade.glb",
            "--levels",
            "2",
            "--crease-angle",
            "60",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(
            run.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let raw =
            wavemill::mesh::io::read_mesh(&out, wavemill::mesh::io::Units::Millimetres).unwrap();
        let (_, report) = wavemill::mesh::prepare(&raw.mesh, &Default::default()).unwrap();
        let (_, coarse) = wavemill::mesh::prepare(
            &wavemill::job::load_part(&repo_file("data/blade.glb"), "mm")
                .unwrap()
                .mesh,
            &Default::default(),
        )
        .unwrap();
        assert_eq!(report.triangles, 16 * coarse.triangles);
        assert!(report.watertight);
        assert_eq!(report.genus, Some(0));
    }
    let bad = wavemill(&[
        "subdivide",
        "data/blade.glb",
        "--out",
        dir.join("blade.stl").to_str().unwrap(),
    ]);
    assert_eq!(bad.status.code(), Some(2), "a bad --out is a usage error");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `levels` on the sample blade: a level file per level, a report whose finest level fits the
/// part within the tolerance, exact reconstruction, and deviations that shrink to zero at the
/// finest level.
#[test]
fn levels_describes_every_level() {
    let dir = temp_dir("levels");
    let run = wavemill(&[
        "levels",
        "data/blade.glb",
        "--tolerance",
        "0.05",
        "--base-triangles",
        "1000",
        "--no-timings",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(
        run.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("levels.json")).unwrap()).unwrap();
    let levels = report["levels"].as_array().unwrap();
    assert!(!levels.is_empty());
    assert!(report["finest_hausdorff_mm"].as_f64().unwrap() <= 0.05);
    assert!(report["reconstruction_error_mm"].as_f64().unwrap() <= 1e-12 * 100.0);
    for (j, level) in levels.iter().enumerate() {
        assert!(dir.join(format!("level-{j}.glb")).is_file());
        if j > 0 {
            assert_eq!(
                level["triangles"].as_u64().unwrap(),
                4 * levels[j - 1]["triangles"].as_u64().unwrap()
            );
        }
    }
    assert_eq!(
        levels.last().unwrap()["max_deviation_mm"].as_f64().unwrap(),
        0.0
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

fn run_offsets(dir: &std::path::Path, threads: &str, extra: &[&str]) -> Output {
    let mut args = vec![
        "offsets",
        "data/blade.glb",
        "--allowances",
        "1.5,0.5",
        "--base-triangles",
        "300",
        "--grid-cells",
        "60",
        "--no-timings",
        "--out",
        dir.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    Command::new(env!("CARGO_BIN_EXE_wavemill"))
        .args(&args)
        .env("RAYON_NUM_THREADS", threads)
        .output()
        .expect("run wavemill")
}

/// `offsets` on the sample blade, with a ball: one closed, coloured GLB per allowance, a
/// verified report, the same bytes for one thread and two; bad allowances and tools are
/// refused by name with exit code 1.
#[test]
fn offsets_writes_verified_shapes_identically_for_any_thread_count() {
    let (one, two) = (temp_dir("offsets-1"), temp_dir("offsets-2"));
    for (dir, threads) in [(&one, "1"), (&two, "2")] {
        let run = run_offsets(dir, threads, &["--tool", "ball:4"]);
        assert_eq!(
            run.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
    }
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(one.join("offsets.json")).unwrap()).unwrap();
    assert_eq!(report["verified"], true);
    assert_eq!(report["tool_radius_mm"], 2.0);
    for (j, shape) in report["shapes"].as_array().unwrap().iter().enumerate() {
        assert!(shape["min_clearance_minus_allowance_mm"].as_f64().unwrap() >= -1e-6);
        let glb = std::fs::read(one.join(format!("offset-{j}.glb"))).unwrap();
        assert!(String::from_utf8_lossy(&glb).contains("COLOR_0"));
    }
    for file in ["offsets.json", "offset-0.glb", "offset-1.glb"] {
        assert_eq!(
            std::fs::read(one.join(file)).unwrap(),
            std::fs::read(two.join(file)).unwrap(),
            "{file} differs between 1 and 2 threads"
        );
    }
    let bad = run_offsets(&one, "1", &["--allowances", "0.5,1.0"]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--allowances"));
    let bad = run_offsets(&one, "1", &["--tool", "flat:4"]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--tool"));
    for d in [one, two] {
        std::fs::remove_dir_all(&d).unwrap();
    }
}

/// `access` on the sample impeller: heat-map GLB with a colour per vertex, statistics, and a
/// query CSV whose counts match the closed-form expectation (a point far above the part sees
/// its whole open hemisphere); bad query files and K are named.
#[test]
fn access_writes_maps_statistics_and_query_answers() {
    let dir = temp_dir("access");
    let out = dir.to_str().unwrap();
    let part = repo_file("data/impeller.glb");
    let part = part.to_str().unwrap();
    let query = dir.with_extension("points.csv");
    // A point far above the part looking up and one far below it looking down: each sees its
    // whole open hemisphere.
    std::fs::write(&query, "x,y,z,nx,ny,nz\n0,0,500,0,0,1\n0,0,-500,0,0,-1\n").unwrap();
    let query_run = |to: &str| {
        wavemill(&[
            "access",
            part,
            "--directions",
            "162",
            "--query",
            query.to_str().unwrap(),
            "--no-timings",
            "--out",
            to,
        ])
    };
    let run = query_run(out);
    assert_eq!(
        run.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("access.json")).unwrap()).unwrap();
    assert_eq!(report["directions"], 162);
    assert!(report.get("timings_ms").is_none());
    assert!(report["agreement"]["percent"].as_f64().unwrap() >= 99.9);
    let rays = &report["rays"];
    assert!(rays["hierarchical"].as_u64().unwrap() < rays["brute_force"].as_u64().unwrap());
    let glb = std::fs::read(dir.join("access.glb")).unwrap();
    assert_eq!(&glb[..4], b"glTF");
    assert!(String::from_utf8_lossy(&glb).contains("COLOR_0"));
    let csv = std::fs::read_to_string(dir.join("query.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("x,y,z,visible,total,axis_i,axis_j,axis_k")
    );
    // Directions on the equator z = 0 face neither way; count the open hemispheres from the set.
    let set = wavemill::access::DirectionSet::new(2);
    let up = set.directions().iter().filter(|d| d.z > 0.0).count();
    let down = set.directions().iter().filter(|d| d.z < 0.0).count();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 2);
    assert_eq!(rows[0][3], up.to_string());
    assert_eq!(rows[1][3], down.to_string());
    assert!(rows.iter().all(|r| r[4] == "162"));
    // Far from the part nothing collides: the axis is the preferred one, leaning 10° toward +X.
    let axis: Vec<f64> = rows[0][5..8].iter().map(|v| v.parse().unwrap()).collect();
    assert!(
        (axis[2] - 10f64.to_radians().cos()).abs() < 1e-5 && axis[0] > 0.17,
        "{axis:?}"
    );
    // Identical bytes on a second run.
    let again = temp_dir("access-again");
    let run = query_run(again.to_str().unwrap());
    assert_eq!(run.status.code(), Some(0));
    for f in ["access.glb", "access.json", "query.csv"] {
        assert_eq!(
            std::fs::read(dir.join(f)).unwrap(),
            std::fs::read(again.join(f)).unwrap(),
            "{f}"
        );
    }

    let fails_with = |code: i32, args: &[&str], needles: &[&str]| {
        let r = wavemill(args);
        assert_eq!(r.status.code(), Some(code), "{args:?}");
        let err = String::from_utf8_lossy(&r.stderr);
        for n in needles {
            assert!(err.contains(n), "{args:?}: {err}");
        }
    };
    let fails = |args: &[&str], needles: &[&str]| fails_with(1, args, needles);
    fails_with(
        2,
        &["access", part, "--directions", "100", "--out", out],
        &["100", "10242"],
    );
    for (text, needles) in [
        ("x,y,z,nx,ny\n1,2,3,0,0\n", &["bad.csv", "nz"][..]),
        (
            "x,y,z,nx,ny,nz\n1,2,abc,0,0,1\n",
            &["bad.csv", "line 2", "abc"],
        ),
        (
            "x,y,z,nx,ny,nz\n1,2,3,0,0,0\n",
            &["bad.csv", "line 2", "zero"],
        ),
    ] {
        let bad = dir.with_extension("bad.csv");
        std::fs::write(&bad, text).unwrap();
        fails(
            &[
                "access",
                part,
                "--query",
                bad.to_str().unwrap(),
                "--out",
                out,
            ],
            needles,
        );
    }
    fails(&["access", "no/such.stl", "--out", out], &["no/such.stl"]);
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::remove_dir_all(&again).unwrap();
    let _ = std::fs::remove_file(&query);
    let _ = std::fs::remove_file(dir.with_extension("bad.csv"));
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Issue 17 item 7: `--out` naming an existing file failed after the whole plan with a raw
/// "File exists (os error 17)". It is checked first: with a part that does not exist either,
/// the answer is about --out, and it is a usage error.
#[test]
fn out_is_checked_before_any_work() {
    let dir = temp_dir("out-first");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("a-file");
    std::fs::write(&file, "mine").unwrap();
    let run = wavemill(&["plan", "no/such/part.stl", "--out", file.to_str().unwrap()]);
    assert_eq!(run.status.code(), Some(2), "{}", stderr(&run));
    assert!(
        stderr(&run).contains("a-file") && stderr(&run).contains("not a folder"),
        "{}",
        stderr(&run)
    );
    // A folder holding files the command does not write is refused before any work, and the
    // files are left alone (the output set replaces the folder's contents).
    let run = wavemill(&["levels", "no/such/part.stl", "--out", dir.to_str().unwrap()]);
    assert_eq!(run.status.code(), Some(2), "{}", stderr(&run));
    assert!(stderr(&run).contains("a-file"), "{}", stderr(&run));
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "mine");
    let run = wavemill(&[
        "subdivide",
        "no/such/part.stl",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(run.status.code(), Some(2), "{}", stderr(&run));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 17 items 9, 11, 13: values that gave an empty program, ran for minutes or were
/// silently ignored are refused at once: bad flag values with exit code 2, work past a limit
/// with a message saying how to raise it, a part with nothing to cut with exit code 4.
#[test]
fn hostile_values_are_refused_with_clear_errors() {
    let dir = temp_dir("hostile");
    let out = dir.join("out");
    let out = out.to_str().unwrap();
    let part = repo_file("data/impeller.glb");
    let part = part.to_str().unwrap();
    for (args, needle) in [
        (&["plan", part, "--threads", "10000"][..], "--threads"),
        (&["plan", part, "--up", "0,0,0"], "--up"),
        (&["plan", part, "--up", "1,nan,0"], "--up"),
        (&["plan", part, "--scallop", "nan"], "--scallop"),
        (&["plan", part, "--tolerance=-1"], "--tolerance"),
        (&["plan", part, "--scallop", "3"], "--scallop"),
        (&["plan", part, "--units", "furlong"], "--units"),
        (&["levels", part, "--crease-angle", "nan"], "--crease-angle"),
        (
            &["subdivide", part, "--crease-angle", "nan"],
            "--crease-angle",
        ),
        (&["subdivide", part, "--levels", "9"], "--levels"),
        (&["offsets", part, "--allowances", "1,nan"], "--allowances"),
        (&["sample", "impeller", "--blades", "0"], "--blades"),
    ] {
        let mut full = args.to_vec();
        full.extend(["--out", out]);
        let run = wavemill(&full);
        assert_eq!(run.status.code(), Some(2), "{args:?}: {}", stderr(&run));
        assert!(stderr(&run).contains(needle), "{args:?}: {}", stderr(&run));
    }

    // --up 1e200,1e200,0 is a direction (it was silently ignored): the plan goes on to the
    // drive-point limit, which a tiny --max-drive-points trips at once.
    let run = wavemill(&[
        "plan",
        part,
        "--up",
        "1e200,1e200,0",
        "--max-drive-points",
        "1",
        "--out",
        out,
    ]);
    assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
    assert!(
        stderr(&run).contains("--max-drive-points"),
        "{}",
        stderr(&run)
    );

    // A part read in inches that is plainly in millimetres: a warning, and the work estimate
    // refuses it instead of running for minutes.
    let run = wavemill(&["plan", part, "--units", "in", "--out", out]);
    assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
    let err = stderr(&run);
    assert!(
        err.contains("warning") && err.contains("suggests millimetres"),
        "{err}"
    );
    assert!(
        err.contains("drive points") && err.contains("limit"),
        "{err}"
    );

    // subdivide --levels 8 aborted on a failed allocation: now an estimate refuses it.
    let obj = dir.join("x.obj");
    let run = wavemill(&[
        "subdivide",
        part,
        "--levels",
        "8",
        "--out",
        obj.to_str().unwrap(),
    ]);
    assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
    assert!(stderr(&run).contains("--max-triangles"), "{}", stderr(&run));
    assert!(!obj.exists());

    // Job-file values that gave an empty program with exit 0 are named by their key.
    std::fs::create_dir_all(&dir).unwrap();
    for (text, key) in [
        ("[strategy]\nlead_deg = nan\n", "strategy.lead_deg"),
        ("[strategy]\ntilt_deg = nan\n", "strategy.tilt_deg"),
        ("[strategy]\nlead_deg = inf\n", "strategy.lead_deg"),
        ("[strategy]\nlead_deg = 720\n", "strategy.lead_deg"),
        ("[machine]\ntable_z = 100\n", "machine.table_z"),
        ("[part]\nunits = \"furlong\"\n", "part.units"),
    ] {
        let job = dir.join("job.toml");
        std::fs::write(&job, text).unwrap();
        let run = wavemill(&["plan", part, "--job", job.to_str().unwrap(), "--out", out]);
        assert_eq!(run.status.code(), Some(1), "{text}: {}", stderr(&run));
        assert!(stderr(&run).contains(key), "{text}: {}", stderr(&run));
        assert!(
            !stderr(&run).contains("--units"),
            "{text}: {}",
            stderr(&run)
        );
    }
    assert!(!std::path::Path::new(out).join("job.nc").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 17 item 9: a part far smaller than the tool (the sample impeller scaled by 1e-3, or
/// by 1e-6) gave an empty program with exit 0. Nothing to cut is its own exit code (4); a part
/// that collapses below the weld tolerance is refused naming its size; neither writes a
/// program.
#[test]
fn a_part_with_nothing_to_cut_is_exit_code_4() {
    let dir = temp_dir("tiny");
    std::fs::create_dir_all(&dir).unwrap();
    let source = std::fs::read_to_string(repo_file("data/impeller.obj")).unwrap();
    for (scale, code, needle) in [(1e-3, 4, "nothing to cut"), (1e-6, 1, "check its units")] {
        let tiny: String = source
            .lines()
            .map(|l| match l.strip_prefix("v ") {
                Some(rest) => {
                    let c: Vec<f64> = rest
                        .split_whitespace()
                        .map(|v| v.parse().unwrap())
                        .collect();
                    format!(
                        "v {:e} {:e} {:e}\n",
                        c[0] * scale,
                        c[1] * scale,
                        c[2] * scale
                    )
                }
                None => format!("{l}\n"),
            })
            .collect();
        let part = dir.join("tiny.obj");
        std::fs::write(&part, tiny).unwrap();
        let out = dir.join("out");
        let run = wavemill(&[
            "plan",
            part.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(run.status.code(), Some(code), "{scale}: {}", stderr(&run));
        assert!(stderr(&run).contains(needle), "{scale}: {}", stderr(&run));
        assert!(!out.join("job.nc").exists());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 17 item 13: `offsets` of an open surface said "verified"; shapes that enclose the part
/// need inside and outside, so an open surface is refused, saying so.
#[test]
fn offsets_of_an_open_surface_are_refused() {
    let dir = temp_dir("open");
    std::fs::create_dir_all(&dir).unwrap();
    let part = dir.join("open.obj");
    std::fs::write(
        &part,
        "v 0 0 0\nv 40 0 0\nv 40 40 0\nv 0 40 0\nv 20 20 5\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\n",
    )
    .unwrap();
    let out = dir.join("out");
    let run = wavemill(&[
        "offsets",
        part.to_str().unwrap(),
        "--allowances",
        "0.5,0",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
    let err = stderr(&run);
    assert!(err.contains("open.obj") && err.contains("closed"), "{err}");
    assert!(!out.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `info` recognises the sample impeller (in its JSON as in its text) and pictures it as a
/// GLB; on a part that is not an impeller it says why, and `--glb` is a usage error.
#[test]
fn info_reports_the_impeller_and_writes_its_picture() {
    let json = wavemill(&["info", "data/impeller.glb", "--json"]);
    assert_eq!(json.status.code(), Some(0));
    let report: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
    assert_eq!(report["impeller"]["order"], 7);
    assert_eq!(report["impeller"]["blades"], 7);
    assert_eq!(report["triangles"], 38502, "the mesh report stays flat");
    // The roots (sharp: no fillet), the edges (leading by the bore, trailing at the rim).
    assert_eq!(
        report["impeller"]["pieces"][0]["root"]["fillet_radius_mm"],
        0.0
    );
    let edges = &report["blade_edges"];
    assert!(edges["leading"].as_array().is_some_and(|c| !c.is_empty()));
    assert!(edges["trailing"][0][2].as_f64().is_some_and(|r| r > 40.0));
    let dir = temp_dir("impeller-glb");
    std::fs::create_dir_all(&dir).unwrap();
    let glb = dir.join("impeller.glb");
    let out = wavemill(&["info", "data/impeller.glb", "--glb", glb.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&out.stdout).contains("7 blades, 7-fold symmetric"));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("blade roots    sharp"), "{text}");
    assert!(text.contains("leading edge   radius"), "{text}");
    let bytes = std::fs::read(&glb).unwrap();
    assert_eq!(&bytes[..4], b"glTF");
    let named = |name: &str| bytes.windows(name.len()).any(|w| w == name.as_bytes());
    assert!(named("blade 1 leading edge") && named("blade 7 trailing edge"));
    let blade = wavemill(&["info", "data/blade.glb"]);
    assert!(String::from_utf8_lossy(&blade.stdout).contains("impeller         no: "));
    let refused = wavemill(&["info", "data/blade.glb", "--glb", glb.to_str().unwrap()]);
    assert_eq!(refused.status.code(), Some(2));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `[impeller]` keys are checked on the part: the sample has seven blades, not five, and the
/// plan says so before it plans anything.
#[test]
fn a_stated_impeller_that_does_not_match_is_refused() {
    let dir = temp_dir("impeller-given");
    std::fs::create_dir_all(&dir).unwrap();
    let job = dir.join("job.toml");
    std::fs::write(&job, "[impeller]\nblades = 5\n").unwrap();
    let out = wavemill(&[
        "plan",
        "data/impeller.glb",
        "--job",
        job.to_str().unwrap(),
        "--out",
        dir.join("out").to_str().unwrap(),
    ]);
    assert_ne!(out.status.code(), Some(0));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("[impeller]") && err.contains("order"), "{err}");
    assert!(!dir.join("out").join("job.nc").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--machine` names a shipped machine or a file; one that is neither is a usage error naming
/// the flag and listing the shipped ones, and an output mode the control cannot run is refused
/// naming `--output`.
#[test]
fn plan_refuses_an_unknown_machine_and_an_impossible_mode_by_flag() {
    let part = env!("CARGO_MANIFEST_DIR").to_string() + "/data/impeller.glb";
    let out = wavemill(&[
        "plan",
        &part,
        "--machine",
        "no-such-mill",
        "--out",
        "/nonexistent/x",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--machine") && err.contains("no-such-mill") && err.contains("head-head"),
        "{err}"
    );
    let out = wavemill(&[
        "plan",
        &part,
        "--machine",
        "trunnion-bc",
        "--feed",
        "inverse-time",
        "--out",
        "/nonexistent/x",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--feed") && err.contains("Heidenhain"),
        "{err}"
    );
}

/// `tessellate` writes the IGES impeller as STL and OBJ that read back as the same closed
/// mesh, reports the measured deviation within the tolerance, and refuses what it cannot do
/// before any work: a mesh input, an unknown output format, a damaged file (by its line).
#[test]
fn tessellate_writes_the_iges_part_and_refuses_bad_input() {
    let dir = temp_dir("tessellate");
    std::fs::create_dir_all(&dir).unwrap();
    let not_iges = wavemill(&[
        "tessellate",
        "data/impeller.glb",
        "--out",
        dir.join("x.stl").to_str().unwrap(),
    ]);
    assert_eq!(not_iges.status.code(), Some(2), "{}", stderr(&not_iges));
    assert!(stderr(&not_iges).contains("IGES"));

    let damaged = dir.join("damaged.igs");
    std::fs::write(&damaged, "not an iges file\n").unwrap();
    let out = wavemill(&[
        "tessellate",
        damaged.to_str().unwrap(),
        "--out",
        dir.join("x.stl").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("damaged.igs") && stderr(&out).contains("line 1"),
        "{}",
        stderr(&out)
    );
    assert!(!dir.join("x.stl").exists(), "no output after an error");

    let Some(data) = common::testdata() else {
        return;
    };
    let part = data.join("cad/impeller_solidworks__pyvista_pyiges.igs");
    let part = part.to_str().unwrap();
    let wrong = wavemill(&[
        "tessellate",
        part,
        "--out",
        dir.join("x.ply").to_str().unwrap(),
    ]);
    assert_eq!(wrong.status.code(), Some(2));

    let mut meshes = Vec::new();
    for name in ["part.stl", "part.obj"] {
        let path = dir.join(name);
        let run = wavemill(&[
            "tessellate",
            part,
            "--json",
            "--out",
            path.to_str().unwrap(),
        ]);
        assert_eq!(run.status.code(), Some(0), "{}", stderr(&run));
        let report: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
        assert_eq!(report["faces"], 277);
        assert_eq!(report["open_seam_edges"], 0);
        let deviation = report["deviation"]["max"].as_f64().unwrap();
        assert!(deviation > 0.0 && deviation <= 0.0105, "{deviation}");
        let raw =
            wavemill::mesh::io::read_mesh(&path, wavemill::mesh::io::Units::Millimetres).unwrap();
        let (mesh, prepared) = wavemill::mesh::prepare(&raw.mesh, &Default::default()).unwrap();
        assert!(prepared.watertight, "{name}: {:?}", prepared.problems());
        meshes.push(mesh);
    }
    // STL keeps f32 coordinates, OBJ f64: the same surface either way.
    assert_eq!(meshes[0].triangles.len(), meshes[1].triangles.len());
    assert!((meshes[0].signed_volume() - meshes[1].signed_volume()).abs() < 1e-3);
    std::fs::remove_dir_all(&dir).unwrap();
}
