use super::*;
use crate::geom::{Direction, ToolPose, Vector3, closest_point_on_triangle};
use crate::mesh::fixtures::plate_and_wall;
use crate::mesh::{DrivePoint, Mesh};
use crate::path::place_ball;

const RADIUS: f64 = 2.0;

fn options() -> CoverOptions {
    CoverOptions {
        ball_radius: RADIUS,
        slack: 0.005,
        min_gap: 4.0,
        overlap: 1.0,
        around: 0.2,
    }
}

/// A pass of a vertical ball through `centres`.
fn pass(centres: &[Point3]) -> CutSegment {
    let axis = Direction::new_normalize(Vector3::z());
    CutSegment {
        poses: centres
            .iter()
            .map(|c| ToolPose {
                tip: c - axis.into_inner() * RADIUS,
                axis,
            })
            .collect(),
        pass_directions: vec![Vector3::x(); centres.len()],
        leads: false,
    }
}

/// Ball centres over the plate's top (z = 5) along x from `x0` to `x1` at `y`, 0.5 mm apart.
fn along_x(x0: f64, x1: f64, y: f64) -> Vec<Point3> {
    let n = ((x1 - x0) / 0.5).round() as usize;
    (0..=n)
        .map(|i| Point3::new(x0 + 0.5 * i as f64, y, 5.0 + RADIUS))
        .collect()
}

fn first_x(s: &CutSegment) -> f64 {
    s.poses[0].tip.x
}

fn last_x(s: &CutSegment) -> f64 {
    s.poses[s.poses.len() - 1].tip.x
}

#[test]
fn a_pass_within_the_slack_of_another_is_dropped_and_one_a_stepover_away_kept() {
    let part = plate_and_wall(5.0, 80.0);
    let surface = SurfaceDistance::new(&part);
    let mut swept = SweptBalls::new(options());
    let passes = vec![
        pass(&along_x(10.0, 40.0, 50.0)),
        // 0.02 mm aside: the first's ball comes 0.1 µm farther from where this one touches,
        // 2.1 µm farther from the point 0.2 mm beyond it.
        pass(&along_x(10.0, 40.0, 50.02)),
        // 0.05 mm aside: 5.6 µm farther from the point beyond, more than the slack.
        pass(&along_x(10.0, 40.0, 50.05)),
        // A stepover for 0.01 mm scallop aside: 0.04 mm farther where it touches.
        pass(&along_x(10.0, 40.0, 50.4)),
    ];
    let (kept, stats) = swept.keep_needed(passes, &surface);
    let kept_at: Vec<f64> = kept.iter().map(|s| s.poses[0].tip.y).collect();
    assert_eq!(kept_at, [50.0, 50.05, 50.4]);
    assert_eq!(
        (stats.passes, stats.passes_dropped, stats.passes_split),
        (4, 1, 0)
    );
    assert_eq!(stats.poses_dropped, 61);
    assert!((stats.length_dropped_mm - 30.0).abs() < 1e-9);
}

#[test]
fn covered_middles_are_dropped_only_when_longer_than_the_gap_and_ends_are_run_on() {
    let part = plate_and_wall(5.0, 80.0);
    let surface = SurfaceDistance::new(&part);
    let mut swept = SweptBalls::new(options());
    let passes = vec![
        pass(&along_x(10.0, 40.0, 50.0)),
        pass(&along_x(20.0, 23.0, 60.0)),
        // Covered from x = 10 to 40: split, each piece run on a millimetre into it.
        pass(&along_x(0.0, 60.0, 50.02)),
        // Covered from x = 20 to 23: less the overlap, a gap of 1 mm, kept whole.
        pass(&along_x(10.0, 40.0, 60.02)),
        // In the air, touching nothing: kept though the ball above it came near.
        pass(
            &along_x(10.0, 40.0, 50.0)
                .iter()
                .map(|c| c + Vector3::z() * 3.0)
                .collect::<Vec<_>>(),
        ),
    ];
    let (kept, stats) = swept.keep_needed(passes, &surface);
    assert_eq!(kept.len(), 6, "{kept:?}");
    let split = &kept[2..4];
    assert_eq!((first_x(&split[0]), last_x(&split[0])), (0.0, 10.5));
    assert_eq!((first_x(&split[1]), last_x(&split[1])), (39.5, 60.0));
    assert_eq!((first_x(&kept[4]), last_x(&kept[4])), (10.0, 40.0));
    assert_eq!(kept[5].poses.len(), 61);
    assert_eq!((stats.passes_dropped, stats.passes_split), (0, 1));
}

/// The points of `part` within `radius` of `centre`, by brute force over every triangle.
fn touched_brute_force(part: &Mesh, centre: &Point3, radius: f64) -> Vec<Point3> {
    part.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| part.positions[i as usize]);
            closest_point_on_triangle(centre, &a, &b, &c).0
        })
        .filter(|q| (q - centre).norm() <= radius)
        .collect()
}

#[test]
fn passes_beside_a_wall_collapse_to_the_pencil_line_which_alone_is_kept() {
    // The plate's top z = 5, a wall from x = 60 up to z = 60: drive lines on the floor less
    // than the ball's radius from it all land on the ball touching floor and wall.
    let part = plate_and_wall(5.0, 60.0);
    let surface = SurfaceDistance::new(&part);
    let line = |x: f64| -> CutSegment {
        let centres: Vec<Point3> = (0..=120)
            .map(|i| {
                let drive = DrivePoint {
                    point: Point3::new(x, 20.0 + 0.5 * f64::from(i), 5.0),
                    normal: Vector3::z(),
                };
                place_ball(&surface, &drive, RADIUS).unwrap()
            })
            .collect();
        pass(&centres)
    };
    let passes: Vec<CutSegment> = [59.5, 59.0, 58.5, 58.2, 57.0].map(line).to_vec();
    let originals = passes.clone();
    let mut swept = SweptBalls::new(options());
    let (kept, stats) = swept.keep_needed(passes, &surface);
    assert_eq!(kept.len(), 2);
    assert!((kept[0].poses[0].tip.x - 58.0).abs() < 1e-6);
    assert!((kept[1].poses[0].tip.x - 57.0).abs() < 1e-6);
    assert_eq!(stats.passes_dropped, 3);
    // Every point any original ball touched lies within the radius and the slack of a kept
    // move, measured without the grid.
    let kept_moves: Vec<[Point3; 2]> = kept
        .iter()
        .flat_map(|s| {
            centres(s, RADIUS)
                .windows(2)
                .map(|w| [w[0], w[1]])
                .collect::<Vec<_>>()
        })
        .collect();
    for segment in &originals {
        for centre in centres(segment, RADIUS) {
            let touched = touched_brute_force(&part, &centre, RADIUS + CONTACT_BAND);
            assert!(!touched.is_empty());
            for q in touched {
                let nearest = kept_moves
                    .iter()
                    .map(|[a, b]| (closest_point_on_segment(&q, a, b) - q).norm())
                    .fold(f64::INFINITY, f64::min);
                assert!(nearest <= RADIUS + options().slack, "{q:?}: {nearest}");
            }
        }
    }
}

/// Another operation's toolpath counts by its cut moves alone: a point beside a cut is
/// covered within the radius and the reach asked, one beside a rapid or an approach is not.
#[test]
fn a_linked_toolpath_covers_along_its_cuts_only() {
    use crate::geom::{Move, MoveKind, Toolpath};
    let axis = Direction::new_normalize(Vector3::z());
    let at = |x: f64, z: f64, kind: MoveKind| Move {
        pose: ToolPose {
            tip: Point3::new(x, 0.0, z),
            axis,
        },
        kind,
        feed: 1000.0,
    };
    // Down to the plate at x = 0, cut to x = 10, up, across to x = 20 by rapid, down again.
    let toolpath = Toolpath {
        tool_id: 1,
        moves: vec![
            at(0.0, 20.0, MoveKind::Rapid),
            at(0.0, 0.0, MoveKind::Approach),
            at(10.0, 0.0, MoveKind::Cut),
            at(10.0, 20.0, MoveKind::Retract),
            at(20.0, 20.0, MoveKind::Rapid),
            at(20.0, 0.0, MoveKind::Approach),
        ],
    };
    let mut swept = SweptBalls::new(CoverOptions {
        slack: 0.01,
        around: 0.0,
        ..options()
    });
    swept.insert_cuts(&toolpath);
    // The ball's centres run 2 mm above the plate from x = 0 to 10.
    let reach = RADIUS + 0.01;
    assert!(swept.covers(&Point3::new(5.0, 0.0, 0.0), reach));
    assert!(swept.covers(&Point3::new(5.0, 0.0, -0.009), reach));
    assert!(!swept.covers(&Point3::new(5.0, 0.0, -0.011), reach));
    assert!(!swept.covers(&Point3::new(5.0, 2.1, 0.0), reach));
    // 1.5 mm under the rapid's centres, and 1 mm beside the second approach's: not cut there.
    assert!(!swept.covers(&Point3::new(15.0, 0.0, 20.5), reach));
    assert!(!swept.covers(&Point3::new(21.0, 0.0, 5.0), reach));
}
