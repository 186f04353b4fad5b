//! End to end on the bundled sample impeller: plan it, then check the outputs with code that
//! shares nothing with the planner's own queries.

use crate::common::plan_checks::{
    a_real_control_reads_the_program_as_the_tests_do, passes_never_step_backwards,
    posted_program_keeps_the_ball_within_the_tolerance,
};
use crate::common::{Oracle, parse_cl, repo_file, surface_samples};
use nalgebra::Point3;
use wavemill::job::{self, Job, Quiet};

/// A coarse job (few passes) so the test stays quick in a debug build; the geometry checks do
/// not depend on the density.
fn coarse_job() -> Job {
    let mut job = Job::load(&repo_file("data/impeller.toml")).expect("data/impeller.toml");
    job.strategy.scallop_height = 0.4;
    // Finishing only: the part is taken as roughed (tests/e2e/plan_stock.rs roughs it).
    job.stock.blank = None;
    job.strategy.max_step = 2.0;
    job
}

fn plan_with_threads(threads: usize) -> job::PlanOutput {
    let path = repo_file("data/impeller.glb");
    let job = coarse_job();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let raw = job::load_part(&path, "mm").unwrap();
        job::plan(&raw, "data/impeller.glb", "mm", &job, &Quiet).unwrap()
    })
}

#[test]
fn sample_impeller_plan_is_gouge_free_collision_free_and_deterministic() {
    let out = plan_with_threads(2);
    let job = coarse_job();
    let r = job.tool.diameter / 2.0;
    // The bundled job finishes the roots with a smaller ball after the finishing.
    let corner_tool = job
        .corner_tool
        .clone()
        .expect("[corner_tool] in data/impeller.toml");
    let radius_of = |tool: u32| {
        if tool == corner_tool.id {
            corner_tool.diameter / 2.0
        } else {
            assert_eq!(tool, job.tool.id);
            r
        }
    };
    let report = &out.report;
    assert!(
        report.poses.cut > 1000,
        "too few cut poses: {:?}",
        report.poses
    );
    assert!(
        report.unreachable.count < report.strategy.drive_points,
        "everything unreachable"
    );

    // --- CL data, checked independently -------------------------------------------------
    let rows = parse_cl(&out.cl_csv);
    assert_eq!(rows.len(), out.toolpath.moves.len());
    let part = &out.part;
    let oracle = Oracle::new(&part.positions, &part.triangles, 4.0);
    // Clearance of each ball off the part (distance of its centre less its radius).
    let mut worst = f64::INFINITY;
    let mut farthest: f64 = 0.0;
    let mut cutting = 0;
    let mut corner_cutting = 0;
    for row in rows
        .iter()
        .filter(|r| r.kind == "cut" || r.kind == "approach")
    {
        cutting += 1;
        assert!(
            (row.axis.norm() - 1.0).abs() < 1e-6,
            "axis not unit: {row:?}"
        );
        let radius = radius_of(row.tool);
        if row.tool == corner_tool.id {
            corner_cutting += 1;
        }
        let centre = row.tip + row.axis * radius;
        let d = oracle.distance_below(&centre, radius + 1.0) - radius;
        assert!(
            !oracle.inside(&centre),
            "ball centre inside the part at {row:?}"
        );
        worst = worst.min(d);
        farthest = farthest.max(d);
    }
    assert!(cutting > 1000);
    assert!(corner_cutting > 100, "{corner_cutting} corner poses");
    assert!(worst >= -1e-6, "gouge: a ball {worst} mm into the part");
    // Every cut pose touches the part: the ball is not cutting air. It rides on the drive
    // surface (the hierarchy's finest level), which may lie up to its fit off the part.
    let fit = report.surface.hausdorff_to_part_mm;
    assert!(fit <= report.surface.tolerance_mm, "{:?}", report.surface);
    assert!(
        farthest <= fit + 1e-3,
        "a cut pose floats {farthest} mm above the part (drive surface fit {fit} mm)"
    );

    // --- Shank and holder: every sampled point of the part stays outside each body grown by
    // its margin (minus a sampling allowance), at every cut pose. ---------------------------
    let samples = surface_samples(&oracle.triangles, 1.0);
    let sample_grid = PointGrid::new(&samples, 10.0);
    let bodies_of = |tool: u32| {
        if tool == corner_tool.id {
            corner_tool.assembly().bodies()
        } else {
            job.tool.assembly().bodies()
        }
    };
    let (bodies, corner_bodies) = (bodies_of(job.tool.id), bodies_of(corner_tool.id));
    let allowance = 0.6; // half the sample spacing, rounded up: a gap between samples
    for row in rows.iter().filter(|r| r.kind == "cut").step_by(3) {
        let bodies = if row.tool == corner_tool.id {
            &corner_bodies
        } else {
            &bodies
        };
        for body in bodies
            .iter()
            .filter(|b| b.role != wavemill::tool::BodyRole::Flutes)
        {
            let margin = match body.role {
                wavemill::tool::BodyRole::Holder => job.safety.holder_margin,
                _ => job.safety.shank_margin,
            };
            let centre = row.tip + row.axis * (0.5 * (body.from + body.to));
            let reach = 0.5 * (body.to - body.from) + body.radius_from.max(body.radius_to) + margin;
            for p in sample_grid.near(&centre, reach) {
                let rel = p - row.tip;
                let h = rel.dot(&row.axis);
                if h < body.from || h > body.to {
                    continue;
                }
                let t = (h - body.from) / (body.to - body.from);
                let radius = body.radius_from + t * (body.radius_to - body.radius_from);
                let rho = (rel - row.axis * h).norm();
                assert!(
                    rho >= radius + margin - allowance,
                    "{:?} within {} mm of the part at {row:?}",
                    body.role,
                    rho - radius
                );
            }
        }
    }

    // --- The table: the part stands on it (its lowest point), and no point of the tool comes
    // within the table margin of it: the ball's bottom and the rims of every body. -----------
    let table_z = part
        .positions
        .iter()
        .map(|p| p.z)
        .fold(f64::INFINITY, f64::min);
    for row in rows.iter().filter(|r| r.kind != "rapid") {
        let lateral = (1.0 - row.axis.z * row.axis.z).max(0.0).sqrt();
        let radius = radius_of(row.tool);
        let mut lowest = row.tip.z + row.axis.z * radius - radius;
        let bodies = if row.tool == corner_tool.id {
            &corner_bodies
        } else {
            &bodies
        };
        for body in bodies {
            for (h, radius) in [(body.from, body.radius_from), (body.to, body.radius_to)] {
                lowest = lowest.min(row.tip.z + row.axis.z * h - radius * lateral);
            }
        }
        assert!(
            lowest >= table_z + job.safety.table_margin - 1e-6,
            "tool {} mm above the table at {row:?}",
            lowest - table_z
        );
    }

    let (finish_rows, corner_rows): (Vec<_>, Vec<_>) = rows
        .iter()
        .cloned()
        .partition(|row| row.tool == job.tool.id);
    passes_never_step_backwards(&finish_rows, r);
    assert!(corner_rows.iter().all(|row| row.tool == corner_tool.id));
    posted_program_keeps_the_ball_within_the_tolerance(&out, &job, &oracle);
    a_real_control_reads_the_program_as_the_tests_do(&out.gcode);
    // The program says what finished the part (once "parallel planes" for every plan).
    let impeller = report
        .impeller_finishing
        .as_ref()
        .expect("impeller strategies");
    // A pass round the blade's root, its balls in the corner (touching hub and blade where
    // the root is sharp), and passes that cut nothing new dropped.
    let blade = impeller.blade.as_ref().expect("blade finishing");
    // The blade's tip has a land the tip passes run along.
    let tip = blade.tip.as_ref().expect("tip passes");
    assert!(tip.curves >= 1 && tip.land_area_mm2 > 50.0, "{tip:?}");
    let root = blade.root_pass.as_ref().expect("a root pass");
    assert!(blade.no_root_pass.is_none());
    assert!(
        root.length_mm > 50.0 && root.touching_both > 0.5,
        "{root:?}"
    );
    assert!(
        impeller.covered.length_dropped_mm > 0.0,
        "{:?}",
        impeller.covered
    );
    // The copies are measured among the passes as copied: every passage's blade and hub,
    // the first passage's area once per passage (the part is symmetric to 0.01 mm).
    let first = impeller
        .rest
        .as_ref()
        .expect("rest passes over the first passage");
    let copies = impeller
        .copies_rest
        .as_ref()
        .expect("rest passes over the copies");
    let every = first.measured_mm2 * impeller.passages as f64;
    assert!(
        (copies.measured_mm2 - every).abs() < 0.01 * every,
        "copies measured over {} mm², passages {} × {} mm²",
        copies.measured_mm2,
        impeller.passages,
        first.measured_mm2
    );

    // --- The corner finish: the smaller ball along the roots, after the finishing, takes
    // what the finishing ball left there. Measured on the finishing's moves alone, more of
    // the part is left over the scallop target than with the corner finish's too. --------
    let corner = report.corner_finishing.as_ref().expect("a corner finish");
    assert_eq!(corner.ball_radius_mm, corner_tool.diameter / 2.0);
    assert!(
        corner.cutting_length_mm > 200.0 && corner.impeller.passages == 7,
        "{corner:?}"
    );
    let corner_blade = corner.impeller.blade.as_ref().expect("loops up the blade");
    assert!(corner_blade.root_pass.is_some(), "{corner_blade:?}");
    assert!(out.gcode.contains(&format!("T{} M6", corner_tool.id)));
    assert_eq!(out.operations.len(), 2);
    let finish_moves = wavemill::geom::Toolpath {
        tool_id: job.tool.id,
        moves: out.toolpath.moves[out.operations[0].moves.clone()].to_vec(),
    };
    let both = report.finish_scallop.as_ref().expect("the scallop measure");
    let alone = wavemill::verify::measure_scallop(
        part,
        &finish_moves,
        &wavemill::verify::ScallopOptions {
            radius: r,
            target: both.target_mm,
            spacing: both.sample_spacing_mm,
            reach: r,
            table_z: report.machine.table_z_mm,
            flutes_above_ball: job.tool.flute_length - r,
        },
        None,
    );
    assert!(
        both.over_target_area_mm2 < 0.8 * alone.over_target_area_mm2 && both.p99_mm < alone.p99_mm,
        "over the target with the corner finish {} mm² (p99 {} mm), without {} mm² ({} mm)",
        both.over_target_area_mm2,
        both.p99_mm,
        alone.over_target_area_mm2,
        alone.p99_mm
    );
    assert!(
        out.gcode
            .lines()
            .take(20)
            .any(|l| l.starts_with("(impeller: hub flow lines")),
        "the header names the impeller strategies"
    );

    // --- The estimate is the program's: in inverse time (the bundled job's G93) a feed block
    // lasts 1/F minutes, so the feed moves' estimated time is the sum of the F words read
    // back, through the tool change to the corner finish's smaller ball. -------------------
    assert!(out.gcode.contains("G93"), "an inverse-time program");
    let mut modal_feed = false;
    let mut from_program = 0.0;
    for line in out.gcode.lines().filter(|l| !l.starts_with('(')) {
        let words: Vec<&str> = line.split_whitespace().collect();
        if words.contains(&"G0") {
            modal_feed = false;
        }
        if words.contains(&"G1") {
            modal_feed = true;
        }
        if let Some(f) = words.iter().find_map(|w| w.strip_prefix('F'))
            && modal_feed
        {
            from_program += 60.0 / f.parse::<f64>().unwrap();
        }
    }
    let by_kind = &report.estimated_time.by_kind;
    let estimated = by_kind.cut_s + by_kind.approach_s + by_kind.retract_s;
    assert!(
        (estimated - from_program).abs() < 1e-6 * from_program,
        "feed moves estimated at {estimated} s, the program's F words say {from_program} s"
    );

    // --- Report consistency --------------------------------------------------------------
    assert!(report.clearance.min_cutter_clearance >= -1e-6);
    let measured = |c: Option<f64>| c.expect("a plan measures shank and holder at every pose");
    assert!(measured(report.clearance.min_holder_clearance) >= job.safety.holder_margin);
    assert!(measured(report.clearance.min_shank_clearance) >= job.safety.shank_margin);
    // The flutes are the back-simulation's, measured along every posted block.
    assert_eq!(report.clearance.min_flutes_clearance, None);
    let posted_flutes = report.posted.as_ref().and_then(|p| p.flutes.as_ref());
    assert!(posted_flutes.is_some_and(|f| f.min_feed_clearance_mm >= -job.strategy.tolerance));
    assert_eq!(report.poses.total, rows.len());
    // Axis smoothing evened the passes: fewer moves over the per-mm bound, never a faster turn
    // (every smoothed axis passed the same collision tests, checked again above).
    let smoothing = &report.strategy.axis_smoothing;
    assert!(smoothing.max_change_deg_per_mm > 0.0);
    assert!(
        smoothing.moves_over_bound < smoothing.moves_over_bound_before,
        "{smoothing:?}"
    );
    assert!(smoothing.max_rate_after_deg_per_mm <= smoothing.max_rate_before_deg_per_mm);
    let cut_length: f64 = out
        .toolpath
        .moves
        .windows(2)
        .filter(|w| w[1].kind == wavemill::geom::MoveKind::Cut)
        .map(|w| (w[1].pose.tip - w[0].pose.tip).norm())
        .sum();
    assert!((report.cutting_length_mm - cut_length).abs() < 1e-6 * cut_length.max(1.0));

    // --- The preview is a valid glTF: reading it back gives the part's triangles, and the
    // toolpath lines are there (skipped by the mesh reader with a warning). ---------------
    let preview = wavemill::mesh::io::read_mesh_bytes(
        &out.preview_glb,
        wavemill::mesh::io::Format::Glb,
        "paths.glb",
        None,
        wavemill::mesh::io::Units::Millimetres,
    )
    .unwrap();
    assert_eq!(preview.mesh.triangles.len(), part.triangles.len());
    assert!(
        preview
            .warnings
            .iter()
            .any(|w| w.to_lowercase().contains("line")),
        "{:?}",
        preview.warnings
    );

    // --- The scallop pictures: the part coloured by what the passes leave, and its views. --
    let names: Vec<&str> = out
        .scallop_pictures
        .iter()
        .map(|(n, _)| n.as_str())
        .collect();
    assert_eq!(names, ["scallop.glb", "scallop.png"]);
    let coloured = wavemill::mesh::io::read_mesh_bytes(
        &out.scallop_pictures[0].1,
        wavemill::mesh::io::Format::Glb,
        "scallop.glb",
        None,
        wavemill::mesh::io::Units::Millimetres,
    )
    .unwrap();
    // The part split as it was sampled: the same surface, in more pieces.
    assert!(coloured.mesh.triangles.len() >= part.triangles.len());
    let (painted, whole) = (coloured.mesh.surface_area(), part.surface_area());
    assert!(
        (painted - whole).abs() < 1e-4 * whole,
        "{painted} vs {whole}"
    );
    assert!(out.scallop_pictures[1].1.starts_with(b"\x89PNG"));
    // Within, over, far over, narrow, blocked, not reached, the table.
    assert_eq!(
        report.finish_scallop_colours.as_ref().map(Vec::len),
        Some(7)
    );

    // --- Determinism across thread counts ------------------------------------------------
    let single = plan_with_threads(1);
    assert_eq!(
        single.gcode, out.gcode,
        "G-code differs between 1 and 2 threads"
    );
    assert_eq!(single.cl_csv, out.cl_csv);
    assert_eq!(single.preview_glb, out.preview_glb);
    assert_eq!(single.scallop_pictures, out.scallop_pictures);
    assert_eq!(single.report.to_json(false), out.report.to_json(false));
}

/// Points bucketed in a uniform grid.
struct PointGrid {
    cell: f64,
    map: std::collections::HashMap<(i64, i64, i64), Vec<Point3<f64>>>,
}

impl PointGrid {
    fn new(points: &[Point3<f64>], cell: f64) -> Self {
        let mut map: std::collections::HashMap<(i64, i64, i64), Vec<Point3<f64>>> =
            Default::default();
        for p in points {
            map.entry(Self::key(p, cell)).or_default().push(*p);
        }
        Self { cell, map }
    }
    fn key(p: &Point3<f64>, cell: f64) -> (i64, i64, i64) {
        (
            (p.x / cell).floor() as i64,
            (p.y / cell).floor() as i64,
            (p.z / cell).floor() as i64,
        )
    }
    fn near(&self, c: &Point3<f64>, reach: f64) -> impl Iterator<Item = &Point3<f64>> {
        let r = (reach / self.cell).ceil() as i64;
        let k = Self::key(c, self.cell);
        let keys: Vec<(i64, i64, i64)> = (k.0 - r..=k.0 + r)
            .flat_map(|x| {
                (k.1 - r..=k.1 + r).flat_map(move |y| (k.2 - r..=k.2 + r).map(move |z| (x, y, z)))
            })
            .collect();
        keys.into_iter()
            .filter_map(|key| self.map.get(&key))
            .flatten()
            .filter(move |p| (*p - c).norm() <= reach)
    }
}

/// The oracle's inside test itself, on points whose side is known from the part's design:
/// the bore (radius 8) is air, the hub just above its base is solid, and above the blades is air.
#[test]
fn oracle_knows_inside_from_outside_on_the_sample() {
    let raw = job::load_part(&repo_file("data/impeller.glb"), "mm").unwrap();
    let oracle = Oracle::new(&raw.mesh.positions, &raw.mesh.triangles, 4.0);
    for z in [0.5, 3.0, 6.0, 10.0] {
        assert!(!oracle.inside(&Point3::new(0.0, 0.0, z)), "bore at z = {z}");
        assert!(
            !oracle.inside(&Point3::new(-4.0, 5.0, z)),
            "bore at z = {z}"
        );
        assert!(oracle.inside(&Point3::new(20.0, 3.0, 1.0)), "hub");
    }
    assert!(
        !oracle.inside(&Point3::new(20.0, 3.0, 40.0)),
        "above the part"
    );
}
