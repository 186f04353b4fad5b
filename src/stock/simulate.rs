//! A toolpath run on the stock: what each move removes, and what it does wrong.
//!
//! Two tri-dexel models at the same spacing: the stock, which every move's swept cutting body
//! cuts, and the part, which only a gouge may cut. The gouge test sweeps the body eroded by the
//! tolerance (the ball radius less the tolerance: exactly the points more than the tolerance
//! inside the body) through the part model: whatever it removes is material of the part the
//! tool went deeper into than the tolerance allows, so a finishing pass that touches the
//! surface within tolerance removes nothing there. The depth of a gouge is measured exactly at
//! the ends of the part material removed (points on the eroded body inside the part) against
//! the part's surface, plus the tolerance: an upper bound on the depth where lines cross it.
//! The first move that cuts a spot of the part is the one reported for it (a later move finds
//! it gone).
//!
//! Per move: volume removed from the stock, the removed volume per mm of the move (the
//! engagement a feed control would scale by), gouge volume and depth. Over the program:
//! rapids that removed material (through material at the rapid rate), and the share of cutting
//! length that removed nothing (air cutting).

use rayon::prelude::*;

use super::cutter::{CuttingBody, SweptSolid};
use super::replay::{BATCH, CutFrame, Guard, MoveWork, replay};
use super::sweep::{Frustum, LineInterval, SphereSweptHull};
use super::{Stock, StockError};
use crate::geom::{MoveKind, Point3, ToolPose, Toolpath, angle_between, slerp};
use crate::mesh::Mesh;
use crate::mesh::distance::SurfaceDistance;
use crate::tool::{Body, BodyRole};

/// Options of [`simulate`].
#[derive(Clone, Debug, PartialEq)]
pub struct SimulationOptions {
    /// How far the tool may go into the part before it is a gouge, mm; also the accuracy each
    /// move's sweep is split to.
    pub tolerance: f64,
    /// The part model's largest number of dexel lines.
    pub max_dexels: usize,
    /// The tool's bodies that must not touch material (shank, neck, holder; see
    /// [`crate::tool::ToolAssembly::bodies`]); flutes are cutting and left out.
    pub non_cutting: Vec<Body>,
}

impl Default for SimulationOptions {
    fn default() -> Self {
        SimulationOptions {
            tolerance: 0.01,
            max_dexels: super::DEFAULT_MAX_DEXELS,
            non_cutting: Vec::new(),
        }
    }
}

impl SimulationOptions {
    /// Options for `tool`: its shank, neck and holder guarded, at `tolerance`.
    pub fn for_tool(tool: &crate::tool::ToolAssembly, tolerance: f64) -> Self {
        SimulationOptions {
            tolerance,
            max_dexels: super::DEFAULT_MAX_DEXELS,
            non_cutting: tool
                .bodies()
                .into_iter()
                .filter(|b| b.role != BodyRole::Flutes)
                .collect(),
        }
    }
}

/// What one move did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MoveRecord {
    /// Volume of stock removed, mm³.
    pub removed_mm3: f64,
    /// Stock removed per mm of tip travel, mm³/mm (0 for a move that does not travel).
    pub removed_per_mm: f64,
    /// Volume of the part cut deeper than the tolerance, mm³.
    pub gouge_mm3: f64,
    /// Deepest the move went into the part, mm (0 without a gouge; see the module docs).
    pub gouge_depth_mm: f64,
    /// Axial depth of cut: the extent along the tool axis (at the move's end) of the stock
    /// the move removed, mm (0 when it removed nothing or did not travel across the axis).
    pub axial_depth_mm: f64,
    /// Radial width of cut: the extent of the removed stock across the feed direction and the
    /// axis, mm (likewise).
    pub radial_width_mm: f64,
}

/// The gouges of a program.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GougeSummary {
    /// Moves that gouge.
    pub count: usize,
    /// The deepest, mm.
    pub max_depth_mm: f64,
    /// Part volume cut away, mm³.
    pub volume_mm3: f64,
    /// The first move that gouges (index into the toolpath).
    pub first_move: Option<usize>,
}

/// A body that must not cut touching material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Collision {
    /// The move (index into the toolpath).
    pub move_index: usize,
    /// Which body.
    pub role: BodyRole,
    /// The longest run of material inside the body along a dexel line, mm.
    pub depth_mm: f64,
    /// Where.
    pub at: Point3,
}

/// A simulated program.
#[derive(Clone, Debug, PartialEq)]
pub struct Simulation {
    /// One record per move of the toolpath (the first, where the tool starts, is empty).
    pub moves: Vec<MoveRecord>,
    /// Stock volume removed by the whole program, mm³.
    pub removed_volume_mm3: f64,
    /// The gouges.
    pub gouge: GougeSummary,
    /// Rapid moves that removed material (indices): more than one dexel cell of the tolerance's
    /// depth (tolerance × spacing²), so a rapid grazing a wall the program has just cut to the
    /// tool's radius, where round-off leaves 10⁻⁷ mm³ on a dexel end, is not one.
    pub rapids_through_material: Vec<usize>,
    /// Non-cutting bodies touching material, one per move and body (the deepest).
    pub collisions: Vec<Collision>,
    /// Share of the feed moves' length that removed nothing.
    pub air_cut_fraction: f64,
}

/// Runs `toolpath` with a cutter's `body` on `stock`, checking it against `part`.
pub fn simulate(
    stock: &mut Stock,
    part: &Mesh,
    toolpath: &Toolpath,
    body: &CuttingBody,
    options: &SimulationOptions,
) -> Result<Simulation, StockError> {
    simulate_with_progress(stock, part, toolpath, body, options, &|_| {})
}

/// [`simulate`], calling `progress` with the number of moves done after each batch.
pub fn simulate_with_progress(
    stock: &mut Stock,
    part: &Mesh,
    toolpath: &Toolpath,
    body: &CuttingBody,
    options: &SimulationOptions,
    progress: &dyn Fn(usize),
) -> Result<Simulation, StockError> {
    let tolerance = options.tolerance;
    if !(tolerance.is_finite() && tolerance >= 0.0 && tolerance < body.radius()) {
        return Err(StockError::Blank(format!(
            "the gouge tolerance {tolerance} mm must be ≥ 0 and below the cutter's radius {}",
            body.radius()
        )));
    }
    let mut part_model = Stock::from_mesh(part, stock.spacing(), options.max_dexels)?;
    let surface = SurfaceDistance::new(part);
    let split = tolerance.max(0.1 * stock.spacing()).max(1e-4);
    let mut moves = vec![MoveRecord::default(); toolpath.moves.len()];
    let (mut feed_length, mut air_length) = (0.0, 0.0);
    let mut rapids_through_material = Vec::new();
    let rapid_allowance = tolerance * stock.spacing() * stock.spacing();
    let mut gouge = GougeSummary::default();
    let mut collisions = Vec::new();
    // Material only shrinks: what is outside this box now stays clear.
    let material = stock.material_bounds();
    let step = 0.5 * stock.spacing();
    let pairs: Vec<_> = toolpath.moves.windows(2).collect();
    let mut done = 0;
    for batch in pairs.chunks(BATCH) {
        let work: Vec<MoveWork<SweptSolid>> = batch
            .par_iter()
            .map(|pair| {
                let (from, to) = (&pair[0].pose, &pair[1].pose);
                MoveWork {
                    cut: body.sweep(from, to, split),
                    gouge: body.gouge_sweep(from, to, tolerance, split),
                    guards: options
                        .non_cutting
                        .iter()
                        .enumerate()
                        .filter_map(|(index, body)| {
                            guard_sweep(&material, index, body, from, to, step)
                        })
                        .collect(),
                    frame: cut_frame(from, to),
                }
            })
            .collect();
        let outcomes = replay(
            stock,
            Some(&mut part_model),
            &work,
            options.non_cutting.len(),
        );
        // The depth of each gouge: its removed ends measured against the part, in parallel.
        let depths: Vec<f64> = outcomes
            .par_iter()
            .map(|o| {
                if o.gouge_mm3 > 0.0 {
                    o.gouge_ends
                        .iter()
                        .filter_map(|p| surface.closest(p, f64::INFINITY))
                        .map(|c| c.distance)
                        .fold(0.0, f64::max)
                } else {
                    0.0
                }
            })
            .collect();
        for (b, (outcome, deepest)) in outcomes.into_iter().zip(depths).enumerate() {
            let k = done + b;
            let pair = batch[b];
            let (from, to) = (&pair[0].pose, &pair[1].pose);
            let record = &mut moves[k + 1];
            record.removed_mm3 = outcome.removed_mm3;
            let travel = (to.tip - from.tip).norm();
            if travel > 0.0 {
                record.removed_per_mm = record.removed_mm3 / travel;
            }
            record.gouge_mm3 = outcome.gouge_mm3;
            if let Some(extent) = outcome.extent {
                record.axial_depth_mm = extent.axial_depth();
                record.radial_width_mm = extent.radial_width();
            }
            if record.gouge_mm3 > 0.0 {
                record.gouge_depth_mm = deepest + tolerance;
                gouge.count += 1;
                gouge.volume_mm3 += record.gouge_mm3;
                gouge.max_depth_mm = gouge.max_depth_mm.max(record.gouge_depth_mm);
                gouge.first_move.get_or_insert(k + 1);
            }
            for (index, touch) in outcome.touches.into_iter().enumerate() {
                if let Some(touch) = touch
                    && touch.depth_mm > tolerance
                {
                    collisions.push(Collision {
                        move_index: k + 1,
                        role: options.non_cutting[index].role,
                        depth_mm: touch.depth_mm,
                        at: touch.at,
                    });
                }
            }
            match pair[1].kind {
                MoveKind::Rapid if record.removed_mm3 > rapid_allowance => {
                    rapids_through_material.push(k + 1)
                }
                MoveKind::Rapid => {}
                _ => {
                    feed_length += travel;
                    if record.removed_mm3 == 0.0 {
                        air_length += travel;
                    }
                }
            }
        }
        done += batch.len();
        progress(done);
    }
    Ok(Simulation {
        removed_volume_mm3: moves.iter().map(|m| m.removed_mm3).sum(),
        moves,
        gouge,
        rapids_through_material,
        collisions,
        air_cut_fraction: if feed_length > 0.0 {
            air_length / feed_length
        } else {
            0.0
        },
    })
}

/// The frame a move's depths of cut are measured in: at its end, the axis and the direction
/// across the feed and the axis; `None` for a move along its axis (a plunge or retract) or one
/// that does not travel.
fn cut_frame(from: &ToolPose, to: &ToolPose) -> Option<CutFrame> {
    let axis = to.axis.into_inner();
    let side = axis.cross(&(to.tip - from.tip));
    let norm = side.norm();
    (norm > 1e-9 * (to.tip - from.tip).norm().max(1e-9)).then(|| CutFrame {
        tip: to.tip,
        axis,
        side: side / norm,
    })
}

/// Frusta whose union holds every point `body` passes through from `from` to `to` (tip along
/// the chord, axis along the great circle, as the cutter moves), and their cover; `None` when
/// the cover's box misses the material's.
///
/// Poses are taken so no point of the body moves more than `step` from one to the next (a
/// point at height h and radius ρ moves |Δtip| + Δθ·√(h² + ρ²) at most over the move), so
/// every pose in between is within `step / 2` of one taken; each frustum taken is grown by
/// that much (radii by (step/2)·(√(1 + s²) + |s|) for a side of slope s, ends by step/2),
/// which holds the body at every pose in between. A touch is therefore never missed between
/// poses; one reported may be a near miss by up to `step / 2`.
///
/// The cover is the hull of the grown body's axis segments at the two ends, thickened by its
/// larger radius and by h·(1 − cos Δθ/2) (h the farther end's height): the axis at a pose in
/// between is off the chord between the end axes by at most 1 − cos Δθ/2, and the segment on
/// that chord lies in the hull.
fn guard_sweep(
    material: &crate::geom::Aabb,
    index: usize,
    body: &Body,
    from: &ToolPose,
    to: &ToolPose,
    step: f64,
) -> Option<Guard> {
    let (k0, k1) = (from.axis.into_inner(), to.axis.into_inner());
    let reach = body
        .from
        .abs()
        .hypot(body.radius_from)
        .max(body.to.abs().hypot(body.radius_to));
    let travel = (to.tip - from.tip).norm() + angle_between(&k0, &k1) * reach;
    let samples = ((travel / step).ceil() as usize).clamp(1, 100_000);
    let grow = 0.5 * travel / samples as f64;
    let slope = (body.radius_to - body.radius_from) / (body.to - body.from);
    let widen = grow * ((1.0 + slope * slope).sqrt() + slope.abs());
    let (h0, h1) = (body.from - grow, body.to + grow);
    let (r0, r1) = (body.radius_from + widen, body.radius_to + widen);
    let bow = h0.abs().max(h1.abs()) * (1.0 - (0.5 * angle_between(&k0, &k1)).cos());
    let cover = SphereSweptHull::new(
        &[
            from.tip + h0 * k0,
            from.tip + h1 * k0,
            to.tip + h0 * k1,
            to.tip + h1 * k1,
        ],
        r0.max(r1) + bow + 1e-9 * (1.0 + reach),
    );
    if cover.bounds().distance_squared_to_box(material) > 0.0 {
        return None;
    }
    let frusta = (0..=samples)
        .map(|s| {
            let t = s as f64 / samples as f64;
            Frustum {
                base: from.tip + t * (to.tip - from.tip),
                axis: slerp(&k0, &k1, t),
                from: h0,
                to: h1,
                radius_from: r0,
                radius_to: r1,
            }
        })
        .filter(|f| f.bounds().distance_squared_to_box(material) <= 0.0)
        .collect();
    Some(Guard {
        index,
        cover,
        frusta,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{Aabb, Move, Point3, ToolPose, Vector3};
    use crate::mesh::fixtures::cuboid;
    use std::f64::consts::PI;

    fn path(points: &[([f64; 3], MoveKind)]) -> Toolpath {
        Toolpath {
            tool_id: 1,
            moves: points
                .iter()
                .map(|&(p, kind)| Move {
                    pose: ToolPose {
                        tip: Point3::new(p[0], p[1], p[2]),
                        axis: nalgebra::Unit::new_normalize(Vector3::z()),
                    },
                    kind,
                    feed: 1000.0,
                })
                .collect(),
        }
    }

    /// A 20 × 20 × 10 part (a box from the origin), a block of stock 2 mm above it. A pass
    /// 1 mm above the part is clean; a pass dipping 0.5 mm into it gouges, first at that move,
    /// with the depth of the dip and the volume of the ball's cap below the surface swept
    /// along the dip; a rapid through the stock is caught.
    #[test]
    fn a_deliberate_gouge_and_a_rapid_through_material_are_found() {
        let part = cuboid(20.0, 20.0, 10.0);
        let blank = Aabb::from_points(&[Point3::new(0.0, 0.0, 0.0), Point3::new(20.0, 20.0, 12.0)]);
        let mut stock = Stock::block(&blank, 0.1, super::super::DEFAULT_MAX_DEXELS).unwrap();
        let body = CuttingBody::Ball(crate::stock::cutter::BallEndBody::new(4.0, 12.0));
        use MoveKind::*;
        let program = path(&[
            ([5.0, 5.0, 30.0], Rapid),
            ([5.0, 5.0, 11.0], Approach),
            ([15.0, 5.0, 11.0], Cut), // 1 mm above the part: clean
            ([15.0, 10.0, 9.5], Cut), // dips 0.5 mm into the part on the way
            ([5.0, 10.0, 9.5], Cut),  // 10 mm along, 0.5 mm deep
            ([5.0, 10.0, 30.0], Retract),
            ([10.0, 15.0, 11.0], Rapid), // a rapid down into the stock
        ]);
        let sim = simulate(
            &mut stock,
            &part,
            &program,
            &body,
            &SimulationOptions {
                tolerance: 0.01,
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(sim.gouge.first_move, Some(3));
        assert_eq!(sim.gouge.count, 2);
        assert_eq!(sim.moves[2].gouge_mm3, 0.0);
        // The dip is 0.5 mm; the depth is measured at lines, within the spacing's reach.
        assert!(
            (sim.gouge.max_depth_mm - 0.5).abs() < 0.02,
            "{}",
            sim.gouge.max_depth_mm
        );
        // Along the 10 mm run at 0.5 mm deep the ball (r 2) cuts a circular segment of depth
        // 0.49 (beyond the tolerance): area r²acos((r−h)/r) − (r−h)√(2rh − h²).
        let (r, h): (f64, f64) = (1.99, 0.49);
        let segment = r * r * ((r - h) / r).acos() - (r - h) * (2.0 * r * h - h * h).sqrt();
        let run = sim.moves[4].gouge_mm3;
        let expected = segment * 10.0;
        // The run also gets the end cap of the ball beyond the first move's cut, a little more.
        assert!(
            run > 0.95 * expected && run < expected + PI * r * h * h,
            "{run} vs {expected}"
        );
        assert_eq!(sim.rapids_through_material, vec![6]);
        // A pass 0.005 mm into the part (half the tolerance) is not a gouge, though the tool's
        // tip is below the surface: only the body eroded by the tolerance is tested.
        let mut stock = Stock::block(&blank, 0.1, super::super::DEFAULT_MAX_DEXELS).unwrap();
        let within = path(&[
            ([2.0, 15.0, 30.0], Rapid),
            ([2.0, 15.0, 9.995], Approach),
            ([18.0, 15.0, 9.995], Cut),
        ]);
        let options = SimulationOptions {
            tolerance: 0.01,
            ..Default::default()
        };
        let clean = simulate(&mut stock, &part, &within, &body, &options).unwrap();
        assert_eq!(clean.gouge.count, 0, "{:?}", clean.gouge);
        assert!(clean.moves[2].removed_mm3 > 0.0);
        assert!(sim.removed_volume_mm3 > 0.0);
        // The approach ends where the cut starts: some air cutting (the retract and the
        // approach down through air), but not all.
        assert!(
            sim.air_cut_fraction > 0.0 && sim.air_cut_fraction < 1.0,
            "{:?}",
            sim
        );
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

        /// Every point of a shank or holder at any pose of a move, turning and travelling, lies
        /// in one of the frusta its check sweeps (so no touch between them is missed).
        #[test]
        fn the_guard_frusta_hold_the_body_at_every_pose_between(
            tip in proptest::array::uniform3(-5.0..5.0f64),
            travel in proptest::array::uniform3(-3.0..3.0f64),
            lean0 in proptest::array::uniform2(-0.6..0.6f64),
            lean1 in proptest::array::uniform2(-0.6..0.6f64),
            (from, length, r0, r1) in (0.0..30.0f64, 1.0..40.0f64, 0.5..12.0f64, 0.5..12.0f64),
            t in 0.0..1.0f64,
            (height, around, out) in (0.0..1.0f64, 0.0..std::f64::consts::TAU, 0.0..1.0f64),
        ) {
            let pose = |tip: [f64; 3], lean: [f64; 2]| ToolPose {
                tip: Point3::from(tip),
                axis: nalgebra::Unit::new_normalize(Vector3::new(lean[0], lean[1], 1.0)),
            };
            let end = [tip[0] + travel[0], tip[1] + travel[1], tip[2] + travel[2]];
            let (a, b) = (pose(tip, lean0), pose(end, lean1));
            let body = Body {
                role: BodyRole::Holder,
                from,
                to: from + length,
                radius_from: r0,
                radius_to: r1,
            };
            let everywhere = Aabb::from_points(&[Point3::new(-1e3, -1e3, -1e3), Point3::new(1e3, 1e3, 1e3)]);
            let guard = guard_sweep(&everywhere, 0, &body, &a, &b, 0.05).unwrap();
            let frusta = guard.frusta;
            // A point of the body at time t: at its height, on its side or inside.
            let axis = slerp(&a.axis.into_inner(), &b.axis.into_inner(), t);
            let (u, v) = crate::geom::orthonormal_frame(&axis);
            let h = from + height * length;
            let radius = out * (r0 + height * (r1 - r0));
            let point = a.tip + t * (b.tip - a.tip) + h * axis
                + radius * (around.cos() * u + around.sin() * v);
            let deepest = frusta.iter().map(|f| f.depth(&point)).fold(f64::NEG_INFINITY, f64::max);
            proptest::prop_assert!(deepest >= -1e-9, "{deepest}");
            // The cover holds every frustum: a point of one, as above.
            let f = &frusta[((t * frusta.len() as f64) as usize).min(frusta.len() - 1)];
            let (u, v) = crate::geom::orthonormal_frame(&f.axis);
            let h = f.from + height * (f.to - f.from);
            let radius = out * (f.radius_from + height * (f.radius_to - f.radius_from));
            let point = f.base + h * f.axis + radius * (around.cos() * u + around.sin() * v);
            let cover = guard.cover.line_interval(2, &point);
            proptest::prop_assert!(
                cover.is_some_and(|(t0, t1)| t0 <= point.z + 1e-9 && point.z <= t1 + 1e-9),
                "{cover:?} {point:?}"
            );
        }
    }

    /// A ball of 4 mm with 4 mm flutes on a 6 mm shank and a 20 mm holder, plunged into a
    /// block: the shank is found in material at the first plunge (1 mm radially into the wall
    /// of the 4 mm hole the flutes cut), the holder at the second; a plunge within the flutes
    /// is clean.
    #[test]
    fn a_shank_and_a_holder_in_material_are_found_at_their_moves() {
        let part = cuboid(10.0, 10.0, 1.0);
        let blank = Aabb::from_points(&[Point3::new(0.0, 0.0, 0.0), Point3::new(40.0, 40.0, 20.0)]);
        let mut stock = Stock::block(&blank, 0.1, super::super::DEFAULT_MAX_DEXELS).unwrap();
        let body = CuttingBody::Ball(crate::stock::cutter::BallEndBody::new(4.0, 4.0));
        let non_cutting = vec![
            Body {
                role: BodyRole::Shank,
                from: 4.0,
                to: 20.0,
                radius_from: 3.0,
                radius_to: 3.0,
            },
            Body {
                role: BodyRole::Holder,
                from: 20.0,
                to: 50.0,
                radius_from: 10.0,
                radius_to: 10.0,
            },
        ];
        use MoveKind::*;
        let program = path(&[
            ([30.0, 30.0, 60.0], Rapid),
            ([30.0, 30.0, 17.0], Approach), // within the flutes: clean
            ([30.0, 30.0, 60.0], Retract),
            ([20.0, 20.0, 60.0], Rapid),
            ([20.0, 20.0, 14.0], Approach), // the shank 2 mm into the block
            ([20.0, 20.0, -5.0], Cut),      // the holder 5 mm into it
        ]);
        let options = SimulationOptions {
            tolerance: 0.01,
            non_cutting,
            ..Default::default()
        };
        let sim = simulate(&mut stock, &part, &program, &body, &options).unwrap();
        let at = |m: usize| sim.collisions.iter().filter(move |c| c.move_index == m);
        assert_eq!(at(1).count(), 0, "{:?}", sim.collisions);
        let shank: Vec<_> = at(4).collect();
        assert_eq!(shank.len(), 1, "{:?}", sim.collisions);
        assert_eq!(shank[0].role, BodyRole::Shank);
        assert!((shank[0].depth_mm - 1.0).abs() < 0.15, "{:?}", shank[0]);
        assert!(
            at(5).any(|c| c.role == BodyRole::Holder && c.depth_mm > 4.0),
            "{:?}",
            sim.collisions
        );
    }
}
