//! Tool choice on the sample impeller (issue 5 item 6): every choice holds against the
//! independent oracle (grid + brute-force point–triangle distances, ray-parity inside tests),
//! and `wavemill tools` writes the same bytes for any thread count and names bad libraries.

use std::process::Command;

use crate::common::{Oracle, repo_file};
use nalgebra::{Point3, Vector3};
use wavemill::geom::orthonormal_frame;
use wavemill::job;
use wavemill::mesh::{PrepareOptions, prepare};
use wavemill::tool::ToolLibrary;
use wavemill::tool_choice::{ToolChoiceOptions, choose_tools};

#[test]
fn every_tool_choice_on_the_sample_impeller_holds_against_the_oracle() {
    let raw = job::load_part(&repo_file("data/impeller.glb"), "mm").unwrap();
    let (part, _) = prepare(&raw.mesh, &PrepareOptions::default()).unwrap();
    let library = ToolLibrary::read(&repo_file("data/tools.toml")).unwrap();
    let options = ToolChoiceOptions {
        max_points: 700,
        ..Default::default()
    };
    let tolerance = options.tolerance;
    let choice = choose_tools(&part, &library, &options).unwrap();
    let oracle = Oracle::new(&part.positions, &part.triangles, 2.0);
    let normals = part.vertex_normals();
    let table_z = part.aabb().min.z;
    let (mut balls, mut ends, mut kinds) = (0, 0, std::collections::BTreeSet::new());
    for p in &choice.points {
        let Some(t) = p.tool else { continue };
        let tool = &library.tools[t];
        let v = p.vertex as usize;
        let (x, n, axis) = (part.positions[v], normals[v], p.axis);
        assert!((axis.norm() - 1.0).abs() < 1e-9 && axis.dot(&n) >= -1e-12);
        kinds.insert(tool.cutter.kind());
        let tip = tool.cutter.tip_touching(&x, &n, &axis).unwrap();
        if let Some(r) = tool.ball_radius() {
            // The ball touching along the normal dips in by at most the tolerance.
            let c = x + n * r;
            assert!(!oracle.inside(&c), "T{} centre inside at {x:?}", tool.id);
            let d = oracle.distance_below(&c, r);
            assert!(
                d >= r - tolerance - 1e-9,
                "T{} at {x:?}: {d} < {r}",
                tool.id
            );
            balls += 1;
        } else {
            // Points on the cutting end's surface (rings up the corner and the flank, and the
            // flat bottom) are nowhere deeper in the part than the tolerance (+ parry's f32).
            let (s1, s2) = orthonormal_frame(&axis);
            let top = (2.0 * tool.cutter.corner_radius()).min(tool.flute_length()) + 1.0;
            for i in 0..=12 {
                let h = top * i as f64 / 12.0;
                let radii = [tool.cutter.radius_at(h), 0.5 * tool.cutter.flat_radius()];
                for (k, radius) in radii.into_iter().enumerate() {
                    if k == 1 && i > 0 {
                        continue;
                    }
                    for j in 0..48 {
                        let a = std::f64::consts::TAU * j as f64 / 48.0;
                        let q: Point3<f64> =
                            tip + axis * h + (s1 * a.cos() + s2 * a.sin()) * radius;
                        if oracle.inside(&q) {
                            let depth = oracle.distance_below(&q, 1.0);
                            assert!(
                                depth <= tolerance + 2e-3,
                                "T{} at {x:?}: dips {depth} mm at {q:?}",
                                tool.id
                            );
                        }
                    }
                }
            }
            ends += 1;
        }
        // The whole tool above the table's margin: its lowest point is on the cutter's end.
        let lateral = (1.0 - axis.z * axis.z).max(0.0).sqrt();
        let rc = tool.cutter.corner_radius();
        let lowest = tip.z + axis.z * rc - tool.cutter.flat_radius() * lateral - rc;
        assert!(lowest >= table_z + 2.0 - 1e-9, "T{} at {x:?}", tool.id);
    }
    assert!(
        balls > 50 && ends > 50,
        "{balls} ball and {ends} flat/bull choices"
    );
    assert!(kinds.len() >= 3, "{kinds:?}");
    let up = Vector3::z();
    // Something on top of the hub is finished by the largest tool.
    assert!(
        choice
            .points
            .iter()
            .any(|p| p.tool == Some(library.largest_first()[0])
                && normals[p.vertex as usize].dot(&up) > 0.99)
    );
}

fn run_tools(
    dir: &std::path::Path,
    threads: &str,
    library: &std::path::Path,
) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_wavemill"))
        .env("RAYON_NUM_THREADS", threads)
        .args(["tools", "data/impeller.glb", "--library"])
        .arg(library)
        .args(["--points", "1500", "--no-timings", "--out"])
        .arg(dir)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run wavemill")
}

#[test]
fn tools_cli_writes_the_same_proposal_for_any_thread_count_and_names_bad_libraries() {
    let base = std::env::temp_dir().join(format!("wavemill-tools-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    let library = repo_file("data/tools.toml");
    let (one, two) = (base.join("one"), base.join("two"));
    for (dir, threads) in [(&one, "1"), (&two, "2")] {
        let out = run_tools(dir, threads, &library);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(String::from_utf8_lossy(&out.stdout).contains("unreachable"));
    }
    for file in ["tools.json", "tools.glb"] {
        assert_eq!(
            std::fs::read(one.join(file)).unwrap(),
            std::fs::read(two.join(file)).unwrap(),
            "{file}"
        );
    }
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(one.join("tools.json")).unwrap()).unwrap();
    let proposal = report["proposal"].as_array().unwrap();
    assert!(!proposal.is_empty());
    let total: f64 = proposal
        .iter()
        .map(|t| t["percent"].as_f64().unwrap())
        .sum::<f64>()
        + report["unreachable"]["percent"].as_f64().unwrap();
    assert!((total - 100.0).abs() < 1e-6, "{total}");
    // At most --points, thinned evenly (every 13th of 19,251 vertices).
    let evaluated = report["points_evaluated"].as_u64().unwrap();
    assert!((1400..=1500).contains(&evaluated), "{evaluated}");
    assert!(report.get("timings_ms").is_none());
    let glb = std::fs::read(one.join("tools.glb")).unwrap();
    assert_eq!(&glb[..4], b"glTF");

    // A library with a bull-nose whose corner is half the diameter: exit 1, file and tool named,
    // nothing written.
    let bad = base.join("bad.toml");
    std::fs::write(
        &bad,
        "[[tool]]\nid = 4\ncutter = { kind = \"bull_nose\", diameter = 6, corner_radius = 3, flute_length = 12 }\nshank_diameter = 6\nstickout = 30\nholder = [{ diameter = 20, length = 30 }]\n",
    )
    .unwrap();
    let out_dir = base.join("bad-out");
    let out = run_tools(&out_dir, "1", &bad);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.toml") && err.contains("tool 1 (id 4)"),
        "{err}"
    );
    assert!(!out_dir.exists());

    // The 5-axis planner drives a ball: other cutters are refused by name, as a bad
    // command-line value (exit 2).
    let flat = Command::new(env!("CARGO_BIN_EXE_wavemill"))
        .args(["access", "data/impeller.glb", "--tool", "flat:6", "--out"])
        .arg(base.join("flat"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert_eq!(flat.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&flat.stderr).contains("ball-end"));
    let _ = std::fs::remove_dir_all(&base);
}
