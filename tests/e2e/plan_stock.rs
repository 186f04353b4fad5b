//! `plan` with a `[stock]` blank: the planned operations run on the in-process stock.
//!
//! Three cases on the bundled sample impeller (a coarse job, so a debug build stays quick):
//! a blank that is the part itself, which a finishing program within tolerance leaves as it
//! is (nothing removed beyond the tolerance's skin, no rest, no collision); a box over the
//! whole part, through which the same program rapids and drags its shank and holder, which
//! must fail the plan with only the report written; and the default bar stock, roughed,
//! rest-roughed and finished with the ball's shank and holder kept off the material the
//! roughing left.

use crate::common;
use crate::common::repo_file;
use wavemill::job::{self, Job, PlanOutput, Quiet};

fn coarse_job(blank: &str) -> Job {
    let mut job = Job::load(&repo_file("data/impeller.toml")).expect("data/impeller.toml");
    job.strategy.scallop_height = 0.4;
    job.strategy.max_step = 2.0;
    job.stock.blank = Some(blank.to_string());
    job.stock.resolution = Some(0.4);
    job
}

fn plan(job: &Job) -> PlanOutput {
    let raw = job::load_part(&repo_file("data/impeller.glb"), "mm").unwrap();
    job::plan(&raw, "data/impeller.glb", "mm", job, &Quiet).unwrap()
}

fn out_dir(name: &str) -> std::path::PathBuf {
    let dir =
        std::env::temp_dir().join(format!("wavemill-plan-stock-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn a_blank_that_is_the_part_is_finished_without_removing_the_part() {
    let blank = format!("mesh:{}", repo_file("data/impeller.glb").display());
    let job = coarse_job(&blank);
    let out = plan(&job);
    assert_eq!(out.verification_failure, None);
    let stock = out.report.stock.as_ref().expect("the stock section");
    assert_eq!(stock.operations.len(), out.operations.len());
    let finish = stock.operations.last().unwrap();
    // Only the tolerance's skin of the part may go: at most its area × (tolerance + the
    // lines' own error), far less than any real cut.
    let skin = out.part.surface_area() * (job.strategy.tolerance + 0.05);
    assert!(
        finish.removed_volume_mm3 < skin,
        "{} mm³ removed from a blank equal to the part (skin {skin})",
        finish.removed_volume_mm3
    );
    assert_eq!(finish.gouge.count, 0);
    assert_eq!(finish.collision_count, 0, "{:?}", finish.collisions);
    assert_eq!(finish.rapids_through_material, 0);
    assert!(
        finish.rest.max_mm <= stock.resolution_mm,
        "{:?}",
        finish.rest
    );
    // Volume is conserved through the operations.
    let removed: f64 = stock.operations.iter().map(|o| o.removed_volume_mm3).sum();
    assert!(
        (stock.blank_volume_mm3 - removed - finish.volume_after_mm3).abs()
            < 1e-9 * stock.blank_volume_mm3,
        "{} − {removed} ≠ {}",
        stock.blank_volume_mm3,
        finish.volume_after_mm3
    );
    // The stock after each operation is written with the program.
    let dir = out_dir("part");
    job::write_outputs(&dir, &out, false).unwrap();
    for (k, _) in stock.operations.iter().enumerate() {
        let glb = std::fs::read(dir.join(format!("stock-{}.glb", k + 1))).unwrap();
        assert_eq!(&glb[..4], b"glTF");
    }
    assert!(dir.join("job.nc").is_file());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_finishing_program_run_on_a_raw_box_fails_with_its_collisions() {
    let raw = job::load_part(&repo_file("data/impeller.glb"), "mm").unwrap();
    let b = raw.mesh.aabb();
    let blank = format!(
        "box:{},{},{},{},{},{}",
        b.min.x - 2.0,
        b.min.y - 2.0,
        b.min.z,
        b.max.x + 2.0,
        b.max.y + 2.0,
        b.max.z + 5.0
    );
    // Finishing alone, as listed: a box blank would otherwise be roughed first.
    let mut job = coarse_job(&blank);
    // Coarser still: the failure is the point, not the finish. The holder ploughs through
    // the whole box, which 1 mm lines see as well as 0.4 mm ones at a sixth of the work.
    job.strategy.scallop_height = 1.0;
    job.strategy.max_step = 3.0;
    job.stock.resolution = Some(1.0);
    job.operations = toml::from_str::<Job>("[[operation]]\nkind = \"finish\"\n")
        .expect("operations")
        .operations;
    job.corner_tool = None;
    let out = plan(&job);
    let failure = out.verification_failure.clone().expect("a failure");
    assert!(
        failure.contains("operation 'finish' on the stock"),
        "{failure}"
    );
    let finish = out
        .report
        .stock
        .as_ref()
        .unwrap()
        .operations
        .last()
        .unwrap();
    assert!(finish.collision_count > 0, "{failure}");
    assert!(finish.rapids_through_material > 0, "{failure}");
    // The first collision is a real one: its depth is beyond the tolerance and it lies inside
    // the blank.
    let first = &finish.collisions[0];
    assert!(first.depth_mm > 0.01);
    assert!(first.at[2] <= b.max.z + 5.0 + 1e-6, "{first:?}");
    // Only the report is written, and it carries the stock section.
    let dir = out_dir("box");
    let e = job::write_outputs(&dir, &out, false).unwrap_err();
    assert!(matches!(e, wavemill::Error::Verification(_)), "{e}");
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, vec!["report.json".to_string()]);
    let report = std::fs::read_to_string(dir.join("report.json")).unwrap();
    assert!(report.contains("\"collision_count\""));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The job's default blank, the bar stock: two end mills rough it, and the ball finishes with
/// its axes chosen clear of the material they leave, so the stock run (the independent check)
/// finds no shank or holder in material, no gouge and no rapid through material; the points
/// only that material blocks are reported, and so is the rest left on the part; feed control
/// slows the ball where it cuts into the rest.
#[test]
fn the_bar_stock_is_roughed_and_finished_without_touching_the_rest() {
    let mut job = coarse_job("cylinder");
    job.stock.blank = Job::default().stock.blank;
    job.stock.resolution = Some(1.0);
    let out = plan(&job);
    assert_eq!(out.verification_failure, None);
    let stock = out.report.stock.as_ref().expect("a stock run");
    assert_eq!(stock.blank, "cylinder");
    let names: Vec<&str> = stock.operations.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "rough to 0.5 mm",
            "rest-rough to 0.5 mm",
            "finish",
            "corner-finish"
        ]
    );
    for op in &stock.operations {
        assert_eq!(op.collision_count, 0, "{}", op.name);
        assert_eq!(op.rapids_through_material, 0, "{}", op.name);
        assert_eq!(op.gouge.count, 0, "{}", op.name);
        assert!(op.removed_volume_mm3 > 0.0, "{}", op.name);
    }
    let material = out
        .report
        .unreachable
        .by_reason
        .get("material")
        .copied()
        .unwrap_or(0);
    assert!(material > 0, "{:?}", out.report.unreachable.by_reason);
    let finish = stock.operations.last().unwrap();
    assert!(
        finish.rest.max_mm > 0.0 && finish.rest.mean_mm < 1.0,
        "{:?}",
        finish.rest
    );
    // Feed control of each ball: where it meets the rest it is slowed to the target force,
    // and no cutting move is sped up beyond its programmed feed (only air goes faster).
    let [ball, corner] = out.report.ball_feed_control.as_slice() else {
        panic!("two ball operations: {:?}", out.report.ball_feed_control);
    };
    assert_eq!(ball.operation, "finish");
    assert_eq!(corner.operation, "corner-finish");
    assert!(ball.feed_control.moves_slower > 0);
    assert!(ball.feed_control.force_before.max > ball.feed_control.target_force_n);
    for control in [&ball.feed_control, &corner.feed_control] {
        assert_eq!(control.moves_faster, control.moves_in_air);
        assert!(control.force_after.max <= control.target_force_n * (1.0 + 1e-9));
    }
    let (cut_feed, max_feed) = (job.feeds.cut, job.cutting.max_feed);
    for span in &out.operations[2..] {
        assert!(
            out.toolpath.moves[span.moves.clone()]
                .iter()
                .filter(|m| m.kind == wavemill::geom::MoveKind::Cut)
                .all(|m| m.feed <= cut_feed || m.feed == max_feed)
        );
    }
    // The corner finish's ball after the finishing one, by its own number.
    let corner_tool = job.corner_tool.as_ref().expect("[corner_tool]").id;
    assert_eq!(
        common::plan_checks::tool_changes(&out.gcode),
        [
            "T2 M6".to_string(),
            "T7 M6".into(),
            "T1 M6".into(),
            format!("T{corner_tool} M6")
        ]
    );
}
