//! End to end on a real part nobody on the team made: the 9-blade blower of the shared test
//! data, planned with a 3 mm ball as a user would, checked with the tests' own code (CL data,
//! G-code read back and interpolated as the control does). Skipped, saying so, without
//! `../shared/testdata`.

use crate::common::plan_checks::{
    passes_never_step_backwards, posted_program_keeps_the_ball_within_the_tolerance,
};
use crate::common::{Oracle, parse_cl, testdata};
use wavemill::job::{self, Job, Quiet};

#[test]
fn real_blower_posted_program_is_gouge_free_and_its_passes_move_forward() {
    let Some(dir) = testdata() else { return };
    let path = dir.join("meshes/impeller_blower_9blade__necro-nemesis_aero2205.stl");
    // `--tool ball:3`, coarser than a finishing scallop so that a debug build stays quick.
    let mut job = Job::default();
    // Finishing only: the part is taken as roughed.
    job.stock.blank = None;
    job.tool.diameter = 3.0;
    job.tool.shank_diameter = 3.0;
    job.strategy.scallop_height = 0.5;
    job.strategy.max_step = 3.0;
    let raw = job::load_part(&path, "mm").unwrap();
    let out = job::plan(&raw, "blower", "mm", &job, &Quiet).unwrap();
    assert!(
        out.verification_failure.is_none(),
        "{:?}",
        out.verification_failure
    );
    let rows = parse_cl(&out.cl_csv);
    assert!(rows.iter().filter(|r| r.kind == "cut").count() > 1000);
    passes_never_step_backwards(&rows, job.tool.diameter / 2.0);
    let oracle = Oracle::new(&out.part.positions, &out.part.triangles, 4.0);
    posted_program_keeps_the_ball_within_the_tolerance(&out, &job, &oracle);
}
