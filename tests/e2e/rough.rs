//! `wavemill rough` on the bundled sample impeller: layer roughing from the default cylinder
//! blank with the library's flat D10, posted, read back, checked exactly against the offset
//! shape and run on the tri-dexel blank with the whole tool. A coarse stock model (1 mm) keeps
//! the run short; the checks do not depend on it.

use crate::common;
use crate::common::repo_file;
use wavemill::job::{self, RoughOptions};
use wavemill::tool::ToolLibrary;

fn library() -> ToolLibrary {
    ToolLibrary::read(&repo_file("data/tools.toml")).expect("data/tools.toml")
}

/// The flat D10 alone on a 1 mm stock model, every other option at its default: the run two
/// of the tests below compare against (the looped slots, the offsets layering), made once.
fn the_d10_alone() -> &'static job::RoughReport {
    static REPORT: std::sync::OnceLock<job::RoughReport> = std::sync::OnceLock::new();
    REPORT.get_or_init(|| {
        let raw = job::load_part(&repo_file("data/impeller.glb"), "mm").expect("sample");
        let options = RoughOptions {
            tool_id: Some(3),
            rest_tools: 0,
            resolution: Some(1.0),
            ..Default::default()
        };
        let out = job::rough(&raw, "data/impeller.glb", "mm", &library(), &options).expect("rough");
        assert_eq!(out.failure, None);
        out.report
    })
}

#[test]
fn the_sample_is_roughed_to_its_offset_shape_without_a_touch() {
    let raw = job::load_part(&repo_file("data/impeller.glb"), "mm").expect("sample");
    let options = RoughOptions {
        tool_id: Some(3),
        rest_tools: 1,
        resolution: Some(1.0),
        ..Default::default()
    };
    let out = job::rough(&raw, "data/impeller.glb", "mm", &library(), &options).expect("rough");
    let r = &out.report;
    assert_eq!(out.failure, None);
    let ids: Vec<u32> = r.tools.iter().map(|t| t.tool.id).collect();
    assert_eq!(
        ids,
        vec![3, 7],
        "the flat D10, then the flat D6 on the rest"
    );
    for t in &r.tools {
        // Each tool's moves as read back from the G-code stay outside S₀ (up to the posted
        // rounding), so at least the allowance off the part.
        assert!(
            t.overcut_vs_shape
                .as_ref()
                .expect("checked against the offset shape")
                .overcuts
                .is_empty(),
            "T{}",
            t.tool.id
        );
        assert!(
            t.overcut_vs_shape
                .as_ref()
                .expect("checked against the offset shape")
                .min_clearance_mm
                > -1e-4
        );
        assert!(t.overcut_vs_part.min_clearance_mm > options.allowance - 1e-4);
        // The tri-dexel run: nothing touched that must not be.
        let s = &t.stock;
        assert_eq!(
            (s.gouges, s.rapids_through_material, s.collisions),
            (0, 0, 0),
            "T{}",
            t.tool.id
        );
        // Layers within the depth of cut, entries ramped.
        assert!(
            t.layers
                .iter()
                .all(|l| l.layer.depth <= t.tool.planning.radius + 1e-9)
        );
        assert!(t.layers.iter().all(|l| l.plunges_into_material == 0));
        assert!(out.gcode.contains(&format!("\nT{} M6\n", t.tool.id)));
        // Feed control (on by default) holds the target force, and saves time.
        let feed = t.feed_control.as_ref().expect("feed control");
        assert!(
            feed.force_after.p99 <= feed.target_force_n * (1.0 + 1e-9),
            "{feed:?}"
        );
        assert!(feed.time_after_s < feed.time_before_s, "{feed:?}");
    }
    // The volume adds up, and roughing takes most of what stands outside the part.
    let removed: f64 = r.tools.iter().map(|t| t.stock.removed_volume_mm3).sum();
    let balance = r.blank_volume_mm3 - removed - r.volume_after_mm3;
    assert!(balance.abs() < 1e-6 * r.blank_volume_mm3, "{balance}");
    let part_volume = wavemill::mesh::prepare(&raw.mesh, &Default::default())
        .expect("prepare")
        .0
        .signed_volume();
    let excess = r.blank_volume_mm3 - part_volume;
    assert!(removed > 0.6 * excess, "{removed} of {excess}");
    // The rest tool works only where material stood: it removes something, less than the
    // first, and leaves less rest over the part.
    let (first, rest) = (&r.tools[0], &r.tools[1]);
    assert!(rest.stock.removed_volume_mm3 > 0.0);
    assert!(rest.stock.removed_volume_mm3 < first.stock.removed_volume_mm3);
    assert!(rest.stock.rest.mean_mm < first.stock.rest.mean_mm);
    assert!(
        rest.stock.air_cut_fraction < 0.9,
        "{}",
        rest.stock.air_cut_fraction
    );
    let table: String = library()
        .tools
        .iter()
        .map(|t| format!("T{0} P{0} D{1} ;{2}\n", t.id, t.cutter.diameter(), t.name))
        .collect();
    a_real_control_reads_the_program(&out.gcode, &out.cl_csv, &table);
}

/// LinuxCNC's interpreter, given the library as its tool table, reads the program into one
/// straight motion per planned move (after the first, Z-only block, and the Z-only block after
/// each tool change), ending where the plan does to the posted decimals. Skipped, saying so,
/// where `rs274` is not installed.
fn a_real_control_reads_the_program(gcode: &str, cl_csv: &str, tool_table: &str) {
    let Some(motions) = common::plan_checks::rs274_motions(gcode, Some(tool_table)) else {
        return;
    };
    let ends: Vec<[f64; 3]> = motions.iter().map(|(_, v)| [v[0], v[1], v[2]]).collect();
    // The planned tips, every tool's, in order (cl.csv: x, y, z first on each row).
    let planned: Vec<[f64; 3]> = cl_csv
        .lines()
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l.split(',').take(3).map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    // Moves too short to show at 4 decimals are not posted; a tool change repeats the safe
    // height.
    let mut posted = planned.iter().copied();
    let mut last: Option<[f64; 3]> = None;
    let mut matched = 0usize;
    let same = |a: [f64; 3], b: [f64; 3]| (0..3).all(|i| (a[i] - b[i]).abs() < 5e-5);
    for e in &ends[1..] {
        if last.is_some_and(|l| same(l, *e)) {
            continue; // the Z-only block after a tool change, where the tool already is
        }
        let tip = loop {
            let tip = posted
                .next()
                .expect("rs274 read more motions than were planned");
            if !last.is_some_and(|l| same(l, tip)) {
                break tip;
            }
        };
        for i in 0..3 {
            assert!((e[i] - tip[i]).abs() <= 5e-5 + 1e-9, "{e:?} vs {tip:?}");
        }
        last = Some(*e);
        matched += 1;
    }
    // Whatever rs274 did not read is no motion at the posted decimals.
    let last = last.expect("rs274 read no motion");
    for tip in posted {
        assert!(same(last, tip), "unread {tip:?}");
    }
    assert!(matched > 1000, "{matched} motions");
}

#[test]
fn a_library_without_end_mills_a_mesh_blank_and_a_zero_up_are_refused() {
    let raw = job::load_part(&repo_file("data/impeller.glb"), "mm").expect("sample");
    let balls = ToolLibrary {
        tools: library()
            .tools
            .into_iter()
            .filter(|t| t.cutter.ball_radius().is_some())
            .collect(),
    };
    let err = job::rough(&raw, "sample", "mm", &balls, &RoughOptions::default())
        .err()
        .expect("no end mill");
    assert!(
        err.to_string().contains("no flat or bull-nose end mill"),
        "{err}"
    );
    let options = RoughOptions {
        blank: Some(job::BlankSpec::Offset(2.0)),
        ..Default::default()
    };
    let err = job::rough(&raw, "sample", "mm", &library(), &options)
        .err()
        .expect("offset blank");
    assert!(
        err.to_string().contains("a box or a cylinder blank"),
        "{err}"
    );
    assert_eq!(err.exit_code(), 2);
    let options = RoughOptions {
        up: Some([0.0, 0.0, 0.0]),
        ..Default::default()
    };
    let err = job::rough(&raw, "sample", "mm", &library(), &options)
        .err()
        .expect("no up");
    assert!(
        err.to_string().contains("up must be a non-zero vector"),
        "{err}"
    );
}

/// The conventional baseline (`--conventional`): equal layers at the largest depth of cut, no
/// plane at a flat; `--layer-depth` thins them, which leaves less material and takes longer —
/// what lets a route be compared with the baseline at equal material left.
#[test]
fn the_conventional_baseline_cuts_equal_layers_at_the_depth_asked_for() {
    let raw = job::load_part(&repo_file("data/impeller.glb"), "mm").expect("sample");
    let run = |max_depth: Option<f64>| {
        let options = RoughOptions {
            tool_id: Some(3),
            rest_tools: 0,
            resolution: Some(1.0),
            uniform_layers: true,
            feed_control: None,
            max_depth,
            ..Default::default()
        };
        let out = job::rough(&raw, "data/impeller.glb", "mm", &library(), &options).expect("rough");
        assert_eq!(out.failure, None);
        out.report
    };
    let (deep, thin) = (run(None), run(Some(2.5)));
    for (report, depth) in [(&deep, 5.0), (&thin, 2.5)] {
        let layers = &report.tools[0].layers;
        assert!(layers.iter().all(|l| !l.layer.at_flat));
        assert!(layers.iter().all(|l| l.layer.depth <= depth + 1e-9));
        // Equal layers: every one as deep as the first (the blank's top to the floor, split
        // evenly).
        let first = layers[0].layer.depth;
        assert!(layers.iter().all(|l| (l.layer.depth - first).abs() < 1e-9));
    }
    assert!(thin.tools[0].layers.len() > deep.tools[0].layers.len());
    assert!(thin.volume_after_mm3 < deep.volume_after_mm3);
    assert!(thin.estimated_time_s > deep.estimated_time_s);
    assert_eq!(thin.max_depth_mm, Some(2.5));
}

/// Slots and concave corners are cut as trochoidal loops: with every pass straight the D10
/// takes a full slot somewhere (the first pass between two blades); with the default bound of
/// half its diameter, no layer's pass takes much more than the bound (the stretches with no
/// room for a loop beside them are the rest), and the looped program is still exact against
/// the shape and clean on the tri-dexel stock.
#[test]
fn slots_and_corners_are_looped_within_the_engagement_bound() {
    let raw = job::load_part(&repo_file("data/impeller.glb"), "mm").expect("sample");
    let run = |max_engagement: f64| {
        let options = RoughOptions {
            tool_id: Some(3),
            rest_tools: 0,
            resolution: Some(1.0),
            max_engagement,
            ..Default::default()
        };
        let out = job::rough(&raw, "data/impeller.glb", "mm", &library(), &options).expect("rough");
        assert_eq!(out.failure, None);
        out.report.tools.into_iter().next().expect("one tool")
    };
    let widest = |t: &job::RoughToolRun| {
        t.layers
            .iter()
            .map(|l| l.max_engagement_mm)
            .fold(0.0, f64::max)
    };
    assert_eq!(RoughOptions::default().max_engagement, 0.5);
    let (straight, looped) = (run(1.0), the_d10_alone().tools[0].clone());
    let d = 10.0;
    assert!(widest(&straight) > 0.95 * d, "{}", widest(&straight));
    assert!(straight.layers.iter().all(|l| l.looped_stretches == 0));
    assert!(
        looped
            .layers
            .iter()
            .map(|l| l.looped_stretches)
            .sum::<usize>()
            > 10
    );
    assert!(widest(&looped) <= 1.3 * 0.5 * d, "{}", widest(&looped));
    assert!(
        looped
            .overcut_vs_shape
            .as_ref()
            .expect("checked against the offset shape")
            .overcuts
            .is_empty()
    );
    assert!(
        looped
            .overcut_vs_shape
            .as_ref()
            .expect("checked against the offset shape")
            .min_clearance_mm
            > -1e-4
    );
    let s = &looped.stock;
    assert_eq!(
        (s.gouges, s.rapids_through_material, s.collisions),
        (0, 0, 0)
    );
}

/// The layers cleared by the contour engine's other method, seed 004's wavelet passes inside
/// the loose convex hull: the same checks hold (exact against the shape, clean on the
/// tri-dexel stock), and the layers are cleared to about the same material.
#[test]
fn wavelet_layers_rough_the_sample_as_cleanly() {
    let raw = job::load_part(&repo_file("data/impeller.glb"), "mm").expect("sample");
    let run = |layer_paths| {
        let options = RoughOptions {
            tool_id: Some(3),
            rest_tools: 0,
            resolution: Some(1.0),
            layer_paths,
            ..Default::default()
        };
        let out = job::rough(&raw, "data/impeller.glb", "mm", &library(), &options).expect("rough");
        assert_eq!(out.failure, None);
        out.report
    };
    assert_eq!(
        RoughOptions::default().layer_paths,
        wavemill::rough::LayerPaths::Offsets
    );
    let (offsets, wavelet) = (
        the_d10_alone().clone(),
        run(wavemill::rough::LayerPaths::Wavelet),
    );
    let t = &wavelet.tools[0];
    assert!(
        t.overcut_vs_shape
            .as_ref()
            .expect("checked against the offset shape")
            .overcuts
            .is_empty()
    );
    assert!(
        t.overcut_vs_shape
            .as_ref()
            .expect("checked against the offset shape")
            .min_clearance_mm
            > -1e-4
    );
    let s = &t.stock;
    assert_eq!(
        (s.gouges, s.rapids_through_material, s.collisions),
        (0, 0, 0)
    );
    let left = |r: &job::RoughReport| r.volume_after_mm3;
    assert!(
        (left(&wavelet) - left(&offsets)).abs() < 0.02 * left(&offsets),
        "{} against {}",
        left(&wavelet),
        left(&offsets)
    );
}
