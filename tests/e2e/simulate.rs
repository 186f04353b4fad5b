//! `wavemill simulate` end to end on a box part written here: a clean pass, a deliberate gouge
//! (exit 3, the report says where), a rapid through the stock, bad input with its exit code
//! and message, and byte-identical reports from identical runs.

use std::path::{Path, PathBuf};
use std::process::Command;

fn wavemill(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_wavemill"))
        .args(args)
        .output()
        .expect("run wavemill")
}

/// A 20 × 20 × 10 box from the origin, outward, as OBJ.
fn box_obj(dir: &Path) -> PathBuf {
    let v = [
        (0, 0, 0),
        (20, 0, 0),
        (20, 20, 0),
        (0, 20, 0),
        (0, 0, 10),
        (20, 0, 10),
        (20, 20, 10),
        (0, 20, 10),
    ];
    let f = [
        [1, 3, 2],
        [1, 4, 3],
        [5, 6, 7],
        [5, 7, 8],
        [1, 2, 6],
        [1, 6, 5],
        [2, 3, 7],
        [2, 7, 6],
        [3, 4, 8],
        [3, 8, 7],
        [4, 1, 5],
        [4, 5, 8],
    ];
    let mut text = String::new();
    for (x, y, z) in v {
        text += &format!("v {x} {y} {z}\n");
    }
    for [a, b, c] in f {
        text += &format!("f {a} {b} {c}\n");
    }
    let path = dir.join("box.obj");
    std::fs::write(&path, text).unwrap();
    path
}

fn cl(dir: &Path, name: &str, rows: &[&str]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(
        &path,
        format!("x,y,z,i,j,k,kind,feed,tool\n{}\n", rows.join("\n")),
    )
    .unwrap();
    path
}

#[test]
fn simulate_finds_gouges_and_rapids_and_refuses_bad_input() {
    let dir = std::env::temp_dir().join(format!("wavemill-simulate-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let part = box_obj(&dir);
    let clean = cl(
        &dir,
        "clean.csv",
        &[
            "5,5,30,0,0,1,rapid,15000,1",
            "5,5,11,0,0,1,approach,600,1",
            "15,5,10.5,0,0,1,cut,2000,1",
            "15,5,30,0,0,1,retract,3000,1",
        ],
    );
    let gouging = cl(
        &dir,
        "gouge.csv",
        &[
            "5,5,30,0,0,1,rapid,15000,1",
            "5,5,11,0,0,1,approach,600,1",
            "15,5,9.7,0,0,1,cut,2000,1",
            "15,5,30,0,0,1,retract,3000,1",
            "10,15,10.5,0,0,1,rapid,15000,1",
        ],
    );
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let run = |program: &Path, out: &str, extra: &[&str]| {
        let out = s(&dir.join(out));
        let (part, program) = (s(&part), s(program));
        let mut args = vec![
            "simulate",
            part.as_str(),
            "--cl",
            program.as_str(),
            "--stock",
            "box:0,0,0,20,20,12",
            "--no-timings",
            "--out",
        ];
        args.push(out.as_str());
        if !extra.contains(&"--tool") {
            args.extend(["--tool", "ball:4"]);
        }
        if !extra.contains(&"--resolution") {
            args.extend(["--resolution", "0.2"]);
        }
        args.extend_from_slice(extra);
        wavemill(&args)
    };
    let report = |out: &str| -> serde_json::Value {
        serde_json::from_str(
            &std::fs::read_to_string(dir.join(out).join("simulation.json")).unwrap(),
        )
        .unwrap()
    };

    let o = run(&clean, "clean", &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = report("clean");
    assert_eq!(r["gouge"]["count"], 0);
    assert!(r["removed_volume_mm3"].as_f64().unwrap() > 10.0);
    assert_eq!(r["moves"], 4);
    // The blank stands 2 mm over the part's top, untouched beside the pass: the rest there,
    // within half the resolution.
    let rest = r["rest"]["max_mm"].as_f64().unwrap();
    assert!((rest - 2.0).abs() <= 0.1 + 1e-9, "{rest}");
    // The pass ends with the tip at z = 10.5 under a top at 12: an axial depth of 1.5 mm, and
    // a width of the ball's chord at the top, 2√(2² − 0.5²) mm (lines 0.2 mm apart).
    let axial = r["depth_of_cut"]["axial_mm"]["max"].as_f64().unwrap();
    let radial = r["depth_of_cut"]["radial_mm"]["max"].as_f64().unwrap();
    assert!((axial - 1.5).abs() < 0.1, "{axial}");
    assert!((radial - 2.0 * 3.75f64.sqrt()).abs() < 0.45, "{radial}");
    // The same pass with a flat end of the same diameter: its square bottom takes more.
    let o = run(&clean, "clean-flat", &["--tool", "flat:4"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let flat = report("clean-flat");
    assert_eq!(flat["gouge"]["count"], 0);
    assert!(
        flat["tool"].as_str().unwrap().contains("flat"),
        "{}",
        flat["tool"]
    );
    let (ball_volume, flat_volume) = (
        r["removed_volume_mm3"].as_f64().unwrap(),
        flat["removed_volume_mm3"].as_f64().unwrap(),
    );
    assert!(flat_volume > ball_volume, "{flat_volume} vs {ball_volume}");
    // The pictures: a GLB and a PNG.
    let glb = std::fs::read(dir.join("clean/stock.glb")).unwrap();
    assert_eq!(&glb[..4], b"glTF");
    let png = std::fs::read(dir.join("clean/stock.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");

    let o = run(&gouging, "gouge", &[]);
    assert_eq!(
        o.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let r = report("gouge");
    assert_eq!(r["gouge"]["first_move"], 2);
    let depth = r["gouge"]["max_depth_mm"].as_f64().unwrap();
    assert!((depth - 0.3).abs() < 0.02, "{depth}");
    assert_eq!(r["rapids_through_material"], serde_json::json!([4]));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("gouging") && err.contains("rapid"), "{err}");
    // The same run again: the same bytes.
    let again = run(&gouging, "gouge-again", &[]);
    assert_eq!(again.status.code(), Some(3));
    for file in ["simulation.json", "stock.glb", "stock.png"] {
        assert_eq!(
            std::fs::read(dir.join("gouge").join(file)).unwrap(),
            std::fs::read(dir.join("gouge-again").join(file)).unwrap(),
            "{file}"
        );
    }

    // Bad input: a stock spec (usage, 2), a CL line (1, naming the line), a resolution whose
    // model would be too large (1, naming the flag that raises the limit).
    let bad_stock = wavemill(&[
        "simulate",
        &s(&part),
        "--cl",
        &s(&clean),
        "--stock",
        "sphere:3",
        "--tool",
        "ball:4",
        "--out",
        &s(&dir.join("x")),
    ]);
    assert_eq!(bad_stock.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad_stock.stderr).contains("sphere:3"));
    let broken = cl(
        &dir,
        "broken.csv",
        &["5,5,30,0,0,1,rapid,15000,1", "5,5,oops,0,0,1,cut,600,1"],
    );
    let o = run(&broken, "broken", &[]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("broken.csv: line 3") && err.contains("oops"),
        "{err}"
    );
    assert!(!dir.join("broken/simulation.json").exists());
    // A posted program without a single complete motion block is an error, not an empty run.
    let empty = dir.join("empty.nc");
    std::fs::write(&empty, "%\n(nothing)\nM30\n").unwrap();
    let o = run(&empty, "empty", &[]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("empty.nc") && err.contains("nothing to run"),
        "{err}"
    );
    assert!(!dir.join("empty/simulation.json").exists());
    let o = run(&clean, "huge", &["--resolution", "0.0001"]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--max-dexels"), "{err}");

    // With the job's tool (4 mm ball, 4 mm flutes, 6 mm shank, 20 mm stickout, 20 mm holder):
    // a plunge 2 mm past the flutes puts the shank in the stock — a collision, exit 3.
    let job = dir.join("job.toml");
    std::fs::write(
        &job,
        "[tool]\ndiameter = 4.0\nflute_length = 4.0\nshank_diameter = 6.0\nstickout = 20.0\n\
         holder = [{ diameter = 20.0, length = 30.0 }]\n",
    )
    .unwrap();
    let plunge = cl(
        &dir,
        "plunge.csv",
        &[
            "10,10,40,0,0,1,rapid,15000,1",
            "10,10,13,0,0,1,approach,600,1",
            "10,10,6,0,0,1,cut,600,1",
        ],
    );
    let o = wavemill(&[
        "simulate",
        &s(&part),
        "--cl",
        &s(&plunge),
        "--stock",
        "box:0,0,10,20,20,12",
        "--job",
        &s(&job),
        "--resolution",
        "0.2",
        "--no-timings",
        "--out",
        &s(&dir.join("plunge")),
    ]);
    assert_eq!(
        o.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let r = report("plunge");
    assert_eq!(r["collisions"][0]["move"], 2, "{r}");
    assert_eq!(r["collisions"][0]["body"], "shank");
    assert!(r["checked"].to_string().contains("collisions"));
    // The approach stops 1 mm above the stock: no collision there; the cut ends with the tip
    // at z 6, 4 mm into the part's box (the part is the box below z 10): a gouge too.
    assert_eq!(r["gouge"]["first_move"], 2);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The same program as CL data and posted for a table-table A/C machine (the real post, then
/// read back through `verify`'s own forward kinematics) leaves the same stock: the removed
/// volumes and the rest agree within the tolerance's share, neither gouges.
#[test]
fn a_posted_program_and_its_cl_data_give_the_same_stock() {
    use nalgebra::Unit;
    use wavemill::geom::{Move, MoveKind, Point3, ToolPose, Toolpath, Vector3};
    use wavemill::post::{self, GcodeOptions, LineariseOptions, ProgramHeader, TableTableAC};
    let dir = std::env::temp_dir().join(format!("wavemill-posted-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let part = box_obj(&dir);
    // Passes over the top with the axis leaning and turning: the rotary axes move along them.
    let mut moves = vec![Move {
        pose: ToolPose {
            tip: Point3::new(2.0, 2.0, 40.0),
            axis: Unit::new_normalize(Vector3::z()),
        },
        kind: MoveKind::Rapid,
        feed: 15000.0,
    }];
    for row in 0..4 {
        let y = 3.0 + 4.0 * row as f64;
        for k in 0..=16 {
            let x = if row % 2 == 0 {
                2.0 + k as f64
            } else {
                18.0 - k as f64
            };
            let lean = 0.35 * (0.4 * x).sin();
            let axis = Unit::new_normalize(Vector3::new(lean, 0.2 * lean, 1.0));
            // The ball's bottom 0.02 mm over the top face, whatever the lean.
            let centre = Point3::new(x, y, 12.02);
            moves.push(Move {
                pose: ToolPose {
                    tip: centre - 2.0 * axis.into_inner(),
                    axis,
                },
                kind: if k == 0 {
                    MoveKind::Approach
                } else {
                    MoveKind::Cut
                },
                feed: 2000.0,
            });
        }
    }
    let toolpath = Toolpath { tool_id: 1, moves };
    let machine = TableTableAC::new(Vector3::new(-10.0, -10.0, 0.0));
    let gcode = post::post_gcode(
        &machine,
        &toolpath,
        &ProgramHeader {
            tool_number: 1,
            ..ProgramHeader::default()
        },
        &LineariseOptions::default().with_tolerance_mm(0.002),
        &GcodeOptions::default(),
    )
    .unwrap();
    std::fs::write(dir.join("job.nc"), &gcode).unwrap();
    std::fs::write(dir.join("cl.csv"), post::write_cl_csv(&toolpath)).unwrap();
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let run = |program: &str, out: &str| {
        let o = wavemill(&[
            "simulate",
            &s(&part),
            "--program",
            &s(&dir.join(program)),
            "--stock",
            "box:0,0,0,20,20,11",
            "--tool",
            "ball:4",
            "--resolution",
            "0.2",
            "--no-timings",
            "--out",
            &s(&dir.join(out)),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let r: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(dir.join(out).join("simulation.json")).unwrap(),
        )
        .unwrap();
        r
    };
    let (cl, nc) = (run("cl.csv", "from-cl"), run("job.nc", "from-nc"));
    assert!(
        nc["program_format"]
            .as_str()
            .unwrap()
            .starts_with("posted program, table-table A/C")
    );
    let volume = |r: &serde_json::Value| r["removed_volume_mm3"].as_f64().unwrap();
    // The post's linearisation and rounding move the tip by a few µm over the ~100 mm² cut.
    assert!(volume(&cl) > 50.0, "{}", volume(&cl));
    assert!(
        (volume(&cl) - volume(&nc)).abs() < 0.01 * volume(&cl),
        "{} vs {}",
        volume(&cl),
        volume(&nc)
    );
    for r in [&cl, &nc] {
        assert_eq!(r["gouge"]["count"], 0);
    }
    let rest = |r: &serde_json::Value| r["rest"]["mean_mm"].as_f64().unwrap();
    assert!(
        (rest(&cl) - rest(&nc)).abs() < 0.02,
        "{} vs {}",
        rest(&cl),
        rest(&nc)
    );
}
