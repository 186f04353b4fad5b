//! End to end from CAD: the SolidWorks impeller IGES read, tessellated and planned as a user
//! would (`wavemill plan part.igs --up 0,0,-1`: the file has the hub below the blades' tips
//! pointing down), finishing with a 6 mm ball and a 2 mm scallop, coarse enough for a debug
//! build (the part has eleven blades and 146k drive points at a 1 mm scallop), the posted
//! program read back and interpolated by the tests' own code against the tessellated part.

use crate::common::plan_checks::posted_program_keeps_the_ball_within_the_tolerance;
use crate::common::{Oracle, parse_cl, testdata};
use wavemill::cad::tessellate::TessellateOptions;
use wavemill::job::{self, Job, Quiet};

#[test]
#[ignore = "70 s in a release build and several minutes in a debug one, beyond the CI budget: \
            cargo test --release --test e2e cad_plan -- --ignored"]
fn the_iges_impeller_plans_end_to_end_without_a_gouge() {
    let Some(dir) = testdata() else { return };
    let path = dir.join("cad/impeller_solidworks__pyvista_pyiges.igs");
    let mut job = Job::default();
    job.part.up = Some([0.0, 0.0, -1.0]);
    job.stock.blank = None;
    job.tool.diameter = 6.0;
    job.tool.shank_diameter = 6.0;
    job.strategy.scallop_height = 2.0;
    job.strategy.max_step = 6.0;
    // Tessellated at 0.05 mm (57k triangles rather than 288k at 0.01 mm), so that the
    // brute-force check below stays affordable; the plan is checked against the mesh it was
    // planned on, and the tessellation against the surfaces in `cad_tessellate.rs`.
    let raw = job::load_iges_part(&path, &TessellateOptions { tolerance: 0.05 }).unwrap();
    let out = job::plan(&raw, "impeller.igs", "mm", &job, &Quiet).unwrap();
    assert!(
        out.verification_failure.is_none(),
        "{:?}",
        out.verification_failure
    );
    let rows = parse_cl(&out.cl_csv);
    assert!(rows.iter().filter(|r| r.kind == "cut").count() > 1000);
    let oracle = Oracle::new(&out.part.positions, &out.part.triangles, 4.0);
    posted_program_keeps_the_ball_within_the_tolerance(&out, &job, &oracle);
}

/// A job that roughs the IGES impeller to its convex-hull boxes (seed 002, the deepest box top
/// per layer, boxes split to 6 mm) before finishing: the roughing's posted moves keep out of
/// every box and off the part, and the stock run finds no gouge.
#[test]
#[ignore = "two minutes in a release build, beyond the CI budget: \
            cargo test --release --test e2e cad_plan -- --ignored"]
fn the_iges_impeller_roughs_to_its_hull_boxes_in_a_job() {
    let Some(dir) = testdata() else { return };
    let path = dir.join("cad/impeller_solidworks__pyvista_pyiges.igs");
    let text = "[part]\nup = [0.0, 0.0, -1.0]\n[stock]\nblank = \"cylinder\"\n\
                [tool]\ndiameter = 6.0\nshank_diameter = 6.0\n\
                [strategy]\nscallop_height = 2.0\nmax_step = 6.0\n\
                [[operation]]\nkind = \"rough\"\nstock_to_leave = 0.5\nbound = \"hull-boxes\"\n\
                box_width = 6.0\nbox_layers = \"deepest\"\n[[operation]]\nkind = \"finish\"\n";
    let job = Job::from_toml(text, "job.toml").unwrap();
    let (raw, surfaces) = job::load_part_with_surfaces(&path, "mm").unwrap();
    assert!(surfaces.is_some());
    let out = job::plan_with_surfaces(&raw, surfaces, "impeller.igs", "mm", &job, &Quiet).unwrap();
    assert!(
        out.verification_failure.is_none(),
        "{:?}",
        out.verification_failure
    );
    let report = serde_json::to_value(&out.report).unwrap();
    let rough = &report["roughing"][0];
    assert_eq!(rough["shape_triangles"], 0, "{rough}");
    let boxes = &rough["overcut_vs_shape"];
    assert!(boxes["overcuts"].as_array().unwrap().is_empty(), "{boxes}");
    assert!(
        boxes["min_clearance_mm"].as_f64().unwrap() > -1e-4,
        "{boxes}"
    );
    assert!(
        rough["overcut_vs_part"]["min_clearance_mm"]
            .as_f64()
            .unwrap()
            > 0.4
    );
    // The same job on the part's mesh alone is refused at once, naming what is missing.
    let err = job::plan(&raw, "impeller.stl", "mm", &job, &Quiet)
        .err()
        .unwrap();
    assert!(err.to_string().contains("IGES"), "{err}");
}
