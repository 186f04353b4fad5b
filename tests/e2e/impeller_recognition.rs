//! Impeller recognition on real parts: the bundled sample impeller and the shared test data's
//! blower (9 blades) and compressor (main blades and splitters) are recognised with the blade
//! count their sources give, about an axis through their hub; a blade and non-impeller meshes
//! are refused. Each symmetry is checked on the surface by the recognition itself; on the
//! sample it is checked again here by the tests' own distance oracle.

use crate::common;
use wavemill::impeller::{
    HubPassage, NotAnImpeller, PassageOptions, PieceKind, RecogniseOptions, Region, blade_loops,
    blade_tip_passes, recognise,
};
use wavemill::mesh::io::{Units, read_mesh};
use wavemill::mesh::{Mesh, PrepareOptions, prepare};

fn load(path: &std::path::Path) -> Mesh {
    let raw = read_mesh(path, Units::Millimetres).expect("mesh");
    prepare(&raw.mesh, &PrepareOptions::default())
        .expect("prepared")
        .0
}

/// The largest distance from a sampled vertex turned by 2π/order about the axis to the
/// surface (the tests' own bucketed point–triangle oracle), up to 1 mm.
fn turned_miss(mesh: &Mesh, axis: [f64; 3], centre: [f64; 3], order: usize) -> f64 {
    let k = nalgebra::Unit::new_normalize(nalgebra::Vector3::from(axis));
    let c = nalgebra::Point3::from(centre);
    let turn = nalgebra::Rotation3::from_axis_angle(&k, std::f64::consts::TAU / order as f64);
    let oracle = common::Oracle::new(&mesh.positions, &mesh.triangles, 2.0);
    mesh.positions
        .iter()
        .step_by(7)
        .map(|p| oracle.distance_below(&(c + turn * (p - c)), 1.0))
        .fold(0.0, f64::max)
}

#[test]
fn the_sample_impeller_is_recognised_and_the_sample_blade_is_not() {
    let mesh = load(&common::repo_file("data/impeller.glb"));
    let found = recognise(&mesh, &RecogniseOptions::default()).expect("an impeller");
    assert_eq!(
        (found.order, found.blades, found.splitters),
        (7, 7, 0),
        "{found:?}"
    );
    assert!(found.axis[2] > 0.999, "{:?}", found.axis);
    let miss = turned_miss(&mesh, found.axis, found.centre, found.order);
    assert!(miss < 0.02, "{miss}");
    // The blades stand on the hub at a crease (60–120°): no ball finishes the corner.
    for piece in found.pieces.iter().filter(|p| p.kind == PieceKind::Blade) {
        let root = piece.root.as_ref().expect("a blade stands on the hub");
        assert_eq!(root.fillet_radius_mm, 0.0, "{root:?}");
        assert!(root.crease_deg > 60.0, "{root:?}");
        assert!(root.samples > 20, "{root:?}");
    }
    let blade = load(&common::repo_file("data/blade.glb"));
    assert!(recognise(&blade, &RecogniseOptions::default()).is_err());
}

#[test]
fn the_real_impellers_are_recognised_with_their_blade_counts() {
    let Some(dir) = common::testdata() else {
        return;
    };
    let blower = load(&dir.join("meshes/impeller_blower_9blade__necro-nemesis_aero2205.stl"));
    let found = recognise(&blower, &RecogniseOptions::default()).expect("the blower");
    assert_eq!((found.order, found.blades), (9, 9), "{found:?}");
    for piece in found.pieces.iter().filter(|p| p.kind == PieceKind::Blade) {
        let root = piece.root.as_ref().expect("a blade stands on the hub");
        assert_eq!(root.fillet_radius_mm, 0.0, "{root:?}");
    }
    let compressor =
        load(&dir.join("meshes/impeller_compressor_splitter__omorellAUS_Impellor-V3.stl"));
    let found = recognise(&compressor, &RecogniseOptions::default()).expect("the compressor");
    assert_eq!(
        (found.order, found.blades, found.splitters),
        (6, 6, 6),
        "{found:?}"
    );
    // Its blades and splitters are filleted to the hub: a 3 mm ball finishes the corner
    // (measured 3.015 mm, the facets' dip allowed for), the crease across the root small.
    for piece in found.pieces.iter().filter(|p| p.kind != PieceKind::Other) {
        let root = piece.root.as_ref().expect("stands on the hub");
        assert!((root.fillet_radius_mm - 3.0).abs() < 0.1, "{root:?}");
        assert!(root.crease_deg < 20.0, "{root:?}");
    }
    let turbine = load(&dir.join("meshes/turbine_blade_with_root__dengwirda_jigsaw-models.stl"));
    assert!(matches!(
        recognise(&turbine, &RecogniseOptions::default()),
        Err(NotAnImpeller::NoSymmetry { .. })
    ));
}

/// The compressor's hub is a coarse CAD tessellation (slivers up to 70 mm bending sharply
/// across the passages, their chords up to 2 mm inside the surface of revolution): grown
/// across gentle edges it falls apart and its largest piece is the rim. The passage stands on
/// the blades' roots instead: recomputed here from the regions, the vertices where blades and
/// splitters meet the hub lie on the stations' meridian.
#[test]
fn the_compressor_passage_stands_on_the_blade_roots() {
    let Some(dir) = common::testdata() else {
        return;
    };
    let compressor =
        load(&dir.join("meshes/impeller_compressor_splitter__omorellAUS_Impellor-V3.stl"));
    let found = recognise(&compressor, &RecogniseOptions::default()).expect("the compressor");
    let options = PassageOptions {
        station_step: 0.5,
        ball_radius: 4.0,
        scallop_height: 0.02,
        overlap: 3.0,
    };
    let passage = HubPassage::new(&compressor, &found, &options).expect("a passage");
    assert!(passage.roots_carried >= 0.8, "{}", passage.roots_carried);
    // The blades run 50 mm along the axis from the inducer to the outlet: the meridian
    // follows the hub over most of it.
    let meridian: Vec<[f64; 2]> = passage
        .stations
        .iter()
        .map(|s| [s.height, s.radius])
        .collect();
    let (low, high) = meridian
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
            (l.min(p[0]), h.max(p[0]))
        });
    assert!(high - low > 35.0, "{low} .. {high}");
    let standing = |r: &Region| matches!(r, Region::Blade(_) | Region::Splitter(_));
    let mut on_hub = vec![false; compressor.positions.len()];
    let mut on_piece = vec![false; compressor.positions.len()];
    for (tri, region) in compressor.triangles.iter().zip(&found.regions) {
        for &v in tri {
            if *region == Region::Hub {
                on_hub[v as usize] = true;
            } else if standing(region) {
                on_piece[v as usize] = true;
            }
        }
    }
    let axis = nalgebra::Vector3::from(found.axis).normalize();
    let centre = nalgebra::Point3::from(found.centre);
    let (mut roots, mut on_meridian) = (0, 0);
    for (k, p) in compressor.positions.iter().enumerate() {
        if !(on_hub[k] && on_piece[k]) {
            continue;
        }
        let d = p - centre;
        let height = d.dot(&axis);
        let radius = (d - axis * height).norm();
        let off = meridian
            .windows(2)
            .map(|w| segment_distance([height, radius], w[0], w[1]))
            .fold(f64::INFINITY, f64::min);
        roots += 1;
        on_meridian += usize::from(off <= 5.0 * found.tolerance_mm);
    }
    assert!(roots > 1000, "{roots}");
    assert!(
        on_meridian as f64 >= 0.8 * roots as f64,
        "{on_meridian} of {roots} root vertices on the meridian"
    );

    // One splitter stands in each passage; the loops round it lie on its own triangles.
    let splitters = passage.splitters(&found);
    assert_eq!(splitters.len(), 1, "{splitters:?}");
    let piece = splitters[0];
    let loops = blade_loops(&compressor, &found, &passage, piece, 0.8, 0.8);
    assert!(
        loops.levels >= 5 && !loops.curves.is_empty(),
        "{}",
        loops.levels
    );
    let own: Vec<[u32; 3]> = compressor
        .triangles
        .iter()
        .zip(&found.regions)
        .filter(|(_, r)| **r == Region::Splitter(piece as u32))
        .map(|(t, _)| *t)
        .collect();
    let oracle = common::Oracle::new(&compressor.positions, &own, 2.0);
    for curve in loops.curves.iter().chain(&loops.partial) {
        for p in &curve.points {
            let d = oracle.distance_below(&p.point, 1.0);
            assert!(d < 1e-6, "a loop point {d} mm off the splitter");
        }
    }
}

fn segment_distance(q: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let d = [b[0] - a[0], b[1] - a[1]];
    let len2 = d[0] * d[0] + d[1] * d[1];
    let t = if len2 > 0.0 {
        (((q[0] - a[0]) * d[0] + (q[1] - a[1]) * d[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (q[0] - a[0] - t * d[0]).hypot(q[1] - a[1] - t * d[1])
}

/// The sample's passage axis from the visibility maps (`hub_axes = "visibility"`), checked
/// with plain rays for every direction of the same set: the axis is seen from as many of the
/// passage's ball centres as the best direction is (the maps are coarse-to-fine, 99.9 %
/// agreement: within 2 % of the points), and the figures say so.
#[test]
fn the_sample_passage_axis_is_seen_from_as_many_points_as_any_direction() {
    use wavemill::access::{DirectionSet, RayScene};
    let mesh = load(&common::repo_file("data/impeller.glb"));
    let found = recognise(&mesh, &RecogniseOptions::default()).expect("an impeller");
    let options = PassageOptions {
        station_step: 0.25,
        ball_radius: 2.0,
        scallop_height: 0.01,
        overlap: 0.5,
    };
    let passage = HubPassage::new(&mesh, &found, &options).expect("a passage");
    let (walls, middle) = passage.mean_wall_axis();
    let rays = RayScene::new(&mesh);
    let reach = 30.0;
    let (axis, figures, points) =
        wavemill::job::visible_passage_axis(&passage, walls, middle, &rays, 2.0, reach);
    assert_eq!(figures.points, points.len());
    assert!(points.len() > 100, "{}", points.len());
    let radial = passage.frame.radial(middle);
    let direction = passage.frame.axis * axis[0]
        + radial * axis[1]
        + passage.frame.axis.cross(&radial) * axis[2];
    assert!((direction.norm() - 1.0).abs() < 1e-9);
    let seen_from = |d: &nalgebra::Vector3<f64>| {
        points
            .iter()
            .filter(|p| {
                let n = p.normal.normalize();
                d.dot(&n) > 0.0 && rays.escapes(&(p.point + n * 2.0), d, reach)
            })
            .count()
    };
    let set = DirectionSet::new(4);
    let best = set.directions()[..set.count(4)]
        .iter()
        .map(seen_from)
        .max()
        .expect("directions");
    let slack = points.len() / 50;
    let axis_seen = seen_from(&direction);
    assert!(axis_seen + slack >= best, "{axis_seen} of {best}");
    assert!(
        figures.seen_by.abs_diff(axis_seen) <= slack,
        "{figures:?} {axis_seen}"
    );
    assert!(figures.from_walls_deg < 30.0, "{figures:?}");
}

/// The compressor's splitters get a root pass and tip passes like its blades: on the
/// splitter in passage 0,
/// with an 8 mm ball, every ball touches the part within the tolerance and never cuts into
/// it (the tests' own oracle), and rests beside the splitter: on its flank or fillet, or on
/// the hub within half a millimetre of it where the corner opens wider than the ball (its
/// nose, where it leans back). This coarse CAD hub lies off its surface of revolution by
/// millimetres, so the level a quarter step above it runs partly up the flank: most balls,
/// not all, touch the splitter.
#[test]
fn the_compressor_splitter_gets_root_and_tip_passes() {
    let Some(dir) = common::testdata() else {
        return;
    };
    let path = dir.join("meshes/impeller_compressor_splitter__omorellAUS_Impellor-V3.stl");
    let job = wavemill::job::Job::from_toml(
        "[part]\nup = [0.0, 1.0, 0.0]\n[stock]\nblank = \"none\"\n\
         [tool]\ndiameter = 8.0\nflute_length = 25.0\nshank_diameter = 8.0\nstickout = 65.0\n\
         [strategy]\nscallop_height = 0.02\ntolerance = 0.02\n",
        "compressor.toml",
    )
    .expect("job");
    let raw = read_mesh(&path, Units::Millimetres).expect("mesh");
    let prepared = wavemill::job::prepare_part(&raw, "compressor", &job).expect("prepared");
    let setup = wavemill::job::PlanSetup::new(&prepared, &job).expect("setup");
    let part = &prepared.part;
    let found = recognise(part, &RecogniseOptions::default()).expect("the compressor");
    let r = 4.0;
    let tolerance = 0.02;
    let passage = HubPassage::new(
        part,
        &found,
        &PassageOptions {
            station_step: 0.25,
            ball_radius: r,
            scallop_height: tolerance,
            overlap: 3.2,
        },
    )
    .expect("a passage");
    let splitter = passage.splitters(&found)[0];
    let loops = blade_loops(part, &found, &passage, splitter, 0.8, 0.8);
    let anywhere = |_: &nalgebra::Vector3<f64>| true;
    let ctx = setup.finishing_context(&setup.collider, &setup.rays, &anywhere);
    let (root, summary) = wavemill::job::root_pass(
        part,
        &found,
        &passage,
        Region::Splitter(splitter as u32),
        loops.level_step,
        &ctx,
        &setup.finishing,
    );
    let summary = summary.expect("a root pass on the splitter");
    // The splitter's root runs about 100 mm round it.
    assert!(summary.length_mm > 50.0, "{summary:?}");

    let oracle = common::Oracle::new(&part.positions, &part.triangles, 2.0 * r);
    let own: Vec<[u32; 3]> = part
        .triangles
        .iter()
        .zip(&found.regions)
        .filter(|(_, region)| **region == Region::Splitter(splitter as u32))
        .map(|(t, _)| *t)
        .collect();
    let on_splitter = common::Oracle::new(&part.positions, &own, 2.0 * r);
    let (mut poses, mut touching) = (0, 0);
    for pose in root.segments.iter().flat_map(|s| &s.poses) {
        poses += 1;
        let centre = pose.tip + pose.axis.into_inner() * r;
        let d = oracle.distance_below(&centre, 2.0 * r);
        assert!(
            d >= r - 1e-6 && d <= r + tolerance,
            "a ball {} mm off the part at {centre:?}",
            d - r
        );
        let to_splitter = on_splitter.distance_below(&centre, 2.0 * r);
        assert!(
            to_splitter <= r + 0.5,
            "a ball {to_splitter} mm from the splitter at {centre:?}"
        );
        touching += usize::from(to_splitter <= r + tolerance);
    }
    assert_eq!(poses, summary.poses);
    assert!(
        4 * touching >= 3 * poses,
        "{touching} of {poses} touch the splitter"
    );

    // Its tip has a land, and the passes along it lie on the splitter's own triangles.
    let tip = blade_tip_passes(part, &found, &passage, splitter, 0.8);
    assert!(!tip.curves.is_empty() && tip.land_area_mm2 > 0.0, "{tip:?}");
    for p in tip.curves.iter().flat_map(|c| &c.points) {
        let d = on_splitter.distance_below(&p.point, 1.0);
        assert!(d < 1e-6, "a tip pass point {d} mm off the splitter");
    }
}
