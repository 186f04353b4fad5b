use super::*;
use crate::geom::{Point3, closest_point_on_triangle};
use crate::mesh::{PrepareOptions, prepare};
use crate::tool::{Cutter, Section, ToolAssembly};

/// A box [min, max] with every face split into `n × n` quads, welded and outward.
fn grid_box(min: [f64; 3], max: [f64; 3], n: usize) -> Mesh {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for axis in 0..3 {
        for high in [false, true] {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let base = positions.len() as u32;
            for i in 0..=n {
                for j in 0..=n {
                    let mut p = [0.0; 3];
                    p[axis] = if high { max[axis] } else { min[axis] };
                    p[u] = min[u] + (max[u] - min[u]) * i as f64 / n as f64;
                    p[v] = min[v] + (max[v] - min[v]) * j as f64 / n as f64;
                    positions.push(Point3::new(p[0], p[1], p[2]));
                }
            }
            let id = |i: usize, j: usize| base + (i * (n + 1) + j) as u32;
            for i in 0..n {
                for j in 0..n {
                    let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                    // (u, v, axis) is right-handed: counter-clockwise in (u, v) faces +axis.
                    if high {
                        triangles.extend([[a, b, c], [a, c, d]]);
                    } else {
                        triangles.extend([[a, c, b], [a, d, c]]);
                    }
                }
            }
        }
    }
    let (mesh, _) = prepare(
        &Mesh {
            positions,
            triangles,
        },
        &PrepareOptions::default(),
    )
    .unwrap();
    assert!(mesh.signed_volume() > 0.0);
    mesh
}

fn union(a: Mesh, b: &Mesh) -> Mesh {
    let mut m = a;
    let offset = m.positions.len() as u32;
    m.positions.extend_from_slice(&b.positions);
    m.triangles
        .extend(b.triangles.iter().map(|t| t.map(|v| v + offset)));
    m
}

const GAP: f64 = 7.0;

/// Two 20 mm blocks with a 7 mm slot between them (x from 20 to 27).
fn slotted_part() -> Mesh {
    union(
        grid_box([0.0, 0.0, 0.0], [20.0, 20.0, 20.0], 10),
        &grid_box([20.0 + GAP, 0.0, 0.0], [40.0 + GAP, 20.0, 20.0], 10),
    )
}

fn tool(id: u32, cutter: Cutter, stickout: f64) -> ToolAssembly {
    let shank = cutter.diameter().max(cutter.flute_top_radius() * 2.0);
    ToolAssembly {
        id,
        name: format!("T{id}"),
        cutter,
        neck: None,
        shank_diameter: shank,
        stickout,
        holder: vec![Section::cylinder(3.0 * shank, 40.0)],
    }
}

fn ball(id: u32, d: f64) -> ToolAssembly {
    tool(
        id,
        Cutter::Ball {
            diameter: d,
            flute_length: 2.0 * d,
        },
        40.0,
    )
}

/// The smallest distance from `c` to any triangle of `mesh`, triangle by triangle.
fn brute_distance(mesh: &Mesh, c: &Point3) -> f64 {
    (0..mesh.triangles.len())
        .map(|t| {
            let [a, b, d] = mesh.corners(t);
            (closest_point_on_triangle(c, &a, &b, &d).0 - c).norm()
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn the_largest_safe_ball_in_a_slot_is_half_its_width_plus_half_the_tolerance() {
    let part = slotted_part();
    let collider = PartCollider::new(&part).unwrap();
    let tolerance = 0.01;
    // Mid-wall points of both walls of the slot, off the grid vertices.
    for (x, n) in [(20.0, Vector3::x()), (20.0 + GAP, -Vector3::x())] {
        let p = Point3::new(x, 7.3, 11.1);
        let (fits, fails) = safe_ball(&collider, &p, &n, 10.0, tolerance);
        let exact = 0.5 * (GAP + tolerance);
        assert!(fits <= exact && exact <= fails, "{fits} {fails}");
        assert!(fails - fits <= 1e-2 + 1e-12);
    }
    // On the open top, nothing but the cap limits the ball.
    let (fits, fails) = safe_ball(
        &collider,
        &Point3::new(5.0, 5.0, 20.0),
        &Vector3::z(),
        10.0,
        0.0,
    );
    assert_eq!((fits, fails), (10.0, f64::INFINITY));
}

#[test]
fn flat_and_bull_nose_ends_touch_a_plane_at_any_tilt_but_not_below_it() {
    let part = grid_box([0.0, 0.0, 0.0], [60.0, 60.0, 20.0], 6);
    let collider = PartCollider::new(&part).unwrap();
    let margins = Margins {
        shank: 0.5,
        holder: 2.0,
    };
    let n = Vector3::z();
    for cutter in [
        Cutter::Flat {
            diameter: 10.0,
            flute_length: 20.0,
        },
        Cutter::BullNose {
            diameter: 10.0,
            corner_radius: 2.0,
            flute_length: 20.0,
        },
        Cutter::Ball {
            diameter: 10.0,
            flute_length: 20.0,
        },
    ] {
        let prepared = PreparedTool::new(&tool(1, cutter, 40.0), &margins);
        for tilt in [0.0f64, 15.0, 40.0, 70.0] {
            let t = tilt.to_radians();
            let axis = Vector3::new(t.sin(), 0.0, t.cos());
            let p = Point3::new(30.0, 30.0, 20.0);
            let pose = collider
                .check_touching(&prepared, &p, &n, &axis, 0.01)
                .unwrap_or_else(|e| panic!("{cutter:?} at {tilt}°: {e:?}"));
            // The lowest point of the tilted tool is on the plane (closed form: the corner
            // circle's lowest point), up to f64 round-off.
            assert!(
                (prepared.lowest_z(&pose, 0.0) - 20.0).abs() < 1e-9,
                "{cutter:?} {tilt}"
            );
            // The same tool 0.03 mm lower dips into the plane beyond the tolerance.
            let sunk = Point3::new(30.0, 30.0, 19.97);
            assert!(matches!(
                collider.check_touching(&prepared, &sunk, &n, &axis, 0.01),
                Err(Collision::Gouge { .. })
            ));
        }
    }
}

#[test]
fn tools_are_chosen_largest_first_and_every_choice_holds_against_brute_force() {
    let part = slotted_part();
    let library = ToolLibrary {
        tools: vec![ball(3, 6.0), ball(1, 12.0), ball(2, 8.0)],
    };
    let options = ToolChoiceOptions::default();
    let choice = choose_tools(&part, &library, &options).unwrap();
    assert_eq!(choice.points.len(), part.positions.len());
    let normals = part.vertex_normals();
    let mut in_slot = 0;
    for p in &choice.points {
        let v = p.vertex as usize;
        let x = part.positions[v];
        let n = normals[v];
        let on_slot_wall = (x.x == 20.0 && n.x > 0.99 || x.x == 20.0 + GAP && n.x < -0.99)
            // Deep enough and the D6's 12 mm flutes leave its shank below the top.
            && x.z > 12.0
            && x.z < 18.0
            && x.y > 2.0
            && x.y < 18.0;
        let on_top = x.z == 20.0 && n.z > 0.99;
        if on_top {
            assert_eq!(p.tool, Some(1), "top at {x:?}");
            // Nothing above the top: the holder-wide cylinder clears from the flute top on.
            assert_eq!(p.reach, Some(library.tools[1].flute_length()));
        }
        if on_slot_wall {
            // D12 and D8 do not fit a 7 mm slot; D6 does.
            assert_eq!(p.tool, Some(0), "slot wall at {x:?}: {p:?}");
            assert_eq!(p.refusal, Some(Refusal::Gouge));
            // The holder-wide cylinder (radius 9 + 2, 40 long) from the reported reach on holds
            // no vertex of the part (a 2 mm grid), checked point by point.
            let tip = library.tools[0]
                .cutter
                .tip_touching(&x, &n, &p.axis)
                .unwrap();
            let reach = p.reach.unwrap();
            for q in &part.positions {
                let d = q - tip;
                let h = d.dot(&p.axis);
                let rho = (d - p.axis * h).norm();
                assert!(
                    !(h >= reach && h <= reach + 40.0 && rho < 11.0 - 1e-6),
                    "{q:?} inside the cylinder from {reach} at {x:?}"
                );
            }
            in_slot += 1;
        }
        // Independent check: the chosen ball, touching along the normal, is within the
        // tolerance of every triangle; every larger ball would not be.
        if let Some(t) = p.tool {
            let r = library.tools[t].ball_radius().unwrap();
            let d = brute_distance(&part, &(x + n * r));
            assert!(d >= r - options.tolerance - 1e-9, "{x:?}: {d} < {r}");
            assert!(p.axis.dot(&n) > 0.0);
        }
    }
    assert!(in_slot > 20, "{in_slot}");
    let report = &choice.report;
    assert_eq!(report.proposal[0].id, 1);
    assert_eq!(report.proposal.last().unwrap().id, 3);
    // The slot's floor is the table: what stands on it (the bottom faces and the lowest bands
    // of the walls) is unreachable, and says why.
    assert!(report.unreachable.vertices > 0);
    assert!(
        report
            .unreachable
            .smallest_refused_for
            .contains_key(&Refusal::Table)
    );
    let shares: f64 =
        report.proposal.iter().map(|t| t.percent).sum::<f64>() + report.unreachable.percent;
    assert!((shares - 100.0).abs() < 1e-6);
}

#[test]
fn a_flat_end_mill_too_wide_for_the_slot_leaves_its_walls_and_the_choice_is_deterministic() {
    let part = slotted_part();
    let library = ToolLibrary {
        tools: vec![tool(
            7,
            Cutter::Flat {
                diameter: 10.0,
                flute_length: 20.0,
            },
            40.0,
        )],
    };
    let options = ToolChoiceOptions {
        max_points: 400,
        ..Default::default()
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| choose_tools(&part, &library, &options).unwrap())
    };
    let one = run(1);
    let two = run(2);
    assert_eq!(one.points, two.points);
    assert_eq!(one.vertex_tool, two.vertex_tool);
    assert!(one.points.len() <= 400);
    let normals = part.vertex_normals();
    for p in &one.points {
        let x = part.positions[p.vertex as usize];
        let n = normals[p.vertex as usize];
        if (x.x == 20.0 && n.x > 0.99) && x.z > 12.0 && x.z < 18.0 && x.y > 2.0 && x.y < 18.0 {
            assert_eq!(p.tool, None, "{x:?}");
        }
        if x.z == 20.0 && n.z > 0.99 && x.x > 6.0 && x.x < 14.0 {
            assert_eq!(p.tool, Some(0));
        }
    }
    // Every vertex has an answer, spread from the evaluated ones.
    assert_eq!(one.vertex_tool.len(), part.positions.len());
}
