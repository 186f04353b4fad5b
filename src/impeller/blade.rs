//! Point-milling loops around a blade or a splitter (issue 21 item 2, blade finishing): the
//! curves on the blade where its height above the hub is constant, from the tip down to the
//! root, so that
//! the ball goes round the blade — pressure side, trailing edge, suction side, leading edge —
//! once per level and steps down between levels like a spiral from shroud to hub.
//!
//! The height above the hub is measured in the meridional half-plane from the hub's meridian
//! ([`HubPassage::above_hub`]); each level set is a plane-section-like curve of that function
//! on the blade's triangles ([`crate::mesh::level_section`]). The levels are spaced so that
//! neighbouring loops are a stepover apart along the blade where they are farthest apart:
//! the spacing in height is the stepover times the surface gradient of the height (1 on a
//! flank square to the hub, less on a leaning one), taken at its low percentile over the
//! flanks. Where the tip's land is nearly level the loops cross it far apart: passes along
//! the land itself follow it ([`blade_tip_passes`]).

use std::collections::HashMap;

use crate::geom::{
    Point3, Vector3, arc_lengths, closest_point_on_segment, run_on, runs_of_set, weighted_quantile,
};
use crate::mesh::{Mesh, SectionCurve, level_section};

use super::passage::HubPassage;
use super::recognise::{Impeller, Region};

/// Deepest halving of the level step for partial loops: down to an eighth.
const MAX_PARTIAL_DEPTH: u32 = 3;

/// What the loops of one blade are.
#[derive(Clone, Debug, PartialEq)]
pub struct BladeLoops {
    /// The full levels' loops, from the tip down.
    pub curves: Vec<SectionCurve>,
    /// Stretches of levels in between, where the full loops stand too far apart.
    pub partial: Vec<SectionCurve>,
    pub levels: usize,
    /// Height between levels, mm.
    pub level_step: f64,
    /// The blade's greatest height above the hub, mm.
    pub top: f64,
}

/// The loops around blade (or splitter) `piece` of `impeller` (recognised in `mesh`),
/// neighbouring loops at most `stepover` apart along the flanks; each loop starts where the
/// one above it ended. A partial loop runs on `overlap` past where it is needed.
pub fn blade_loops(
    mesh: &Mesh,
    impeller: &Impeller,
    passage: &HubPassage,
    piece: usize,
    stepover: f64,
    overlap: f64,
) -> BladeLoops {
    let (blade, height, normals) = blade_heights(mesh, impeller, passage, piece);

    // The surface gradient of the height on each triangle, weighted by area.
    let gradients: Vec<(f64, f64)> = blade
        .triangles
        .iter()
        .map(|tri| {
            let [a, b, c] = tri.map(|i| blade.positions[i as usize]);
            let [ha, hb, hc] = tri.map(|i| height[i as usize]);
            let (e1, e2) = (b - a, c - a);
            let n = e1.cross(&e2);
            let n2 = n.norm_squared();
            if n2 <= 0.0 {
                return (0.0, 0.0);
            }
            let gradient = ((hb - ha) * e2.cross(&n) + (hc - ha) * n.cross(&e1)) / n2;
            (gradient.norm(), 0.5 * n2.sqrt())
        })
        .filter(|(g, _)| *g >= 0.3)
        .collect();
    let steepness = weighted_quantile(gradients, 0.1).unwrap_or(1.0);
    let level_step = (stepover * steepness.min(1.0)).max(1e-3);
    let top = height.iter().copied().fold(0.0, f64::max);
    let section = |level: f64| {
        let shifted: Vec<f64> = height.iter().map(|h| h - level).collect();
        level_section(&blade, &normals, &shifted)
    };
    let mut curves: Vec<SectionCurve> = Vec::new();
    let mut near = LevelGrid::new(stepover);
    let mut levels: usize = 0;
    let first = top - 0.5 * level_step;
    let mut level = first;
    while level > 0.5 * level_step {
        for mut curve in section(level) {
            if let Some(end) = curves.last().and_then(|c| c.points.last()).map(|p| p.point)
                && curve.closed
                && let Some(nearest) = (0..curve.points.len()).min_by(|&i, &k| {
                    (curve.points[i].point - end)
                        .norm()
                        .total_cmp(&(curve.points[k].point - end).norm())
                })
            {
                curve.points.rotate_left(nearest);
            }
            near.insert(&curve, level);
            curves.push(curve);
        }
        levels += 1;
        level -= level_step;
    }

    // Alg. 5.1 between the full levels.
    let mut partial = Vec::new();
    for depth in 1..=MAX_PARTIAL_DEPTH {
        let half = level_step / f64::from(1u32 << depth);
        let mut found = Vec::new();
        for k in 0..(levels.saturating_sub(1) << (depth - 1)) {
            let level = first - (2 * k + 1) as f64 * half;
            for curve in section(level) {
                let needed: Vec<bool> = curve
                    .points
                    .iter()
                    .map(|p| {
                        let above = near.distance(&p.point, level, true);
                        above >= stepover
                            || above + near.distance(&p.point, level, false) > stepover
                    })
                    .collect();
                for piece in needed_stretches(&curve, &needed, overlap) {
                    found.push((piece, level));
                }
            }
        }
        for (piece, level) in found {
            near.insert(&piece, level);
            partial.push(piece);
        }
    }
    BladeLoops {
        curves,
        partial,
        levels,
        level_step,
        top,
    }
}

/// Passes along a blade's tip: the curves across its land (see [`blade_tip_passes`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BladeTip {
    pub curves: Vec<SectionCurve>,
    /// Area of the land, mm², and its greatest width between the crest edges, mm.
    pub land_area_mm2: f64,
    pub width_mm: f64,
}

/// Least cosine between a land triangle's normal and the hub's rising direction at it (45°):
/// the tip faces away from the hub, the flanks across (a raked leading edge's flank leans up to
/// 60°: the loops finish it).
const LAND_FACING: f64 = 0.7;

/// The land stands at least this share of the blade's greatest height above the hub (a
/// centrifugal wheel's blade is a quarter as tall at the rim as at the inducer; a fillet
/// faces up too, but at the root).
const LAND_LEAST_HEIGHT: f64 = 0.15;

/// Passes along the tip of blade (or splitter) `piece`: its land is the blade's triangles
/// facing away from the hub (normal within 45° of the hub's rising direction there), away
/// from the root; the land meets the flanks along two crest edges, told apart by which way the
/// flank beside them faces round the axis. Across the land, each point's position is half
/// the difference of its distances to the two crest edges (0 half-way, ± half the width at
/// the edges); the passes are the curves where it is constant, evenly across at most a
/// `stepover` apart, the outermost half a spacing in from the edges. A level loop crosses a
/// land that is nearly level far from the next loop's crossing; these follow it. Empty when
/// the blade has no land or it meets only one side.
pub fn blade_tip_passes(
    mesh: &Mesh,
    impeller: &Impeller,
    passage: &HubPassage,
    piece: usize,
    stepover: f64,
) -> BladeTip {
    let none = BladeTip::default();
    let (blade, height, normals) = blade_heights(mesh, impeller, passage, piece);
    let top = height.iter().copied().fold(0.0, f64::max);
    let centroid = |t: usize| {
        let [a, b, c] = blade.corners(t);
        Point3::from((a.coords + b.coords + c.coords) / 3.0)
    };
    let land: Vec<bool> = (0..blade.triangles.len())
        .map(|t| {
            let c = centroid(t);
            let (above, up) = passage.above_hub(&c);
            above >= LAND_LEAST_HEIGHT * top && normals[t].dot(&up) >= LAND_FACING
        })
        .collect();
    // Crest points: land corners a flank triangle shares, on the side the flank faces.
    let mut side = vec![0.0f64; blade.positions.len()];
    let mut on_land = vec![false; blade.positions.len()];
    for (t, tri) in blade.triangles.iter().enumerate() {
        if land[t] {
            tri.iter().for_each(|&v| on_land[v as usize] = true);
        }
    }
    for (t, tri) in blade.triangles.iter().enumerate() {
        if land[t] {
            continue;
        }
        let (_, angle, _) = passage.frame.cylindrical(&centroid(t));
        let round = passage.frame.axis.cross(&passage.frame.radial(angle));
        let facing = normals[t].dot(&round);
        for &v in tri {
            if on_land[v as usize] {
                side[v as usize] += facing;
            }
        }
    }
    let crest = |positive: bool| -> Vec<Point3> {
        (0..blade.positions.len())
            .filter(|&v| on_land[v] && side[v] != 0.0 && (side[v] > 0.0) == positive)
            .map(|v| blade.positions[v])
            .collect()
    };
    let (plus, minus) = (crest(true), crest(false));
    if plus.is_empty() || minus.is_empty() {
        return none;
    }
    let lands = Mesh::compacted(
        &blade.positions,
        blade
            .triangles
            .iter()
            .zip(&land)
            .filter(|(_, l)| **l)
            .map(|(t, _)| *t),
    );
    let land_normals: Vec<Vector3> = (0..lands.triangles.len())
        .map(|t| lands.face_normal(t))
        .collect();
    let nearest = |p: &Point3, set: &[Point3]| {
        set.iter()
            .map(|q| (q - p).norm_squared())
            .fold(f64::INFINITY, f64::min)
            .sqrt()
    };
    let across: Vec<f64> = lands
        .positions
        .iter()
        .map(|p| 0.5 * (nearest(p, &minus) - nearest(p, &plus)))
        .collect();
    let half = across.iter().fold(0.0f64, |m, a| m.max(a.abs()));
    // Evenly across, at most a stepover apart, the outermost half a spacing in from the
    // crest edges.
    let count = (2.0 * half / stepover.max(1e-3)).ceil().max(1.0) as usize;
    let spacing = 2.0 * half / count as f64;
    let curves = (0..count)
        .flat_map(|k| {
            let level = -half + (k as f64 + 0.5) * spacing;
            let shifted: Vec<f64> = across.iter().map(|a| a - level).collect();
            level_section(&lands, &land_normals, &shifted)
        })
        .collect();
    BladeTip {
        curves,
        land_area_mm2: lands.surface_area(),
        width_mm: 2.0 * half,
    }
}

/// Blade (or splitter) `piece` of `impeller` as a mesh of its own, with each vertex's height
/// above the hub and each triangle's normal.
fn blade_heights(
    mesh: &Mesh,
    impeller: &Impeller,
    passage: &HubPassage,
    piece: usize,
) -> (Mesh, Vec<f64>, Vec<Vector3>) {
    let triangles: Vec<[u32; 3]> = mesh
        .triangles
        .iter()
        .zip(&impeller.regions)
        .filter(
            |(_, r)| matches!(r, Region::Blade(k) | Region::Splitter(k) if *k as usize == piece),
        )
        .map(|(t, _)| *t)
        .collect();
    let blade = Mesh::compacted(&mesh.positions, triangles);
    let height: Vec<f64> = blade
        .positions
        .iter()
        .map(|p| passage.above_hub(p).0)
        .collect();
    let normals: Vec<Vector3> = (0..blade.triangles.len())
        .map(|t| blade.face_normal(t))
        .collect();
    (blade, height, normals)
}

/// The curves on blade (or splitter) `piece` at `level` mm above the hub: a loop round it,
/// or open stretches where the level runs into the hub.
pub fn blade_section_at(
    mesh: &Mesh,
    impeller: &Impeller,
    passage: &HubPassage,
    piece: usize,
    level: f64,
) -> Vec<SectionCurve> {
    let (blade, height, normals) = blade_heights(mesh, impeller, passage, piece);
    let shifted: Vec<f64> = height.iter().map(|h| h - level).collect();
    level_section(&blade, &normals, &shifted)
}

/// The longest closed loop round blade (or splitter) `piece` at `level` mm above the hub.
pub fn blade_loop_at(
    mesh: &Mesh,
    impeller: &Impeller,
    passage: &HubPassage,
    piece: usize,
    level: f64,
) -> Option<SectionCurve> {
    let length = |c: &SectionCurve| {
        c.points
            .windows(2)
            .map(|w| (w[1].point - w[0].point).norm())
            .sum::<f64>()
    };
    blade_section_at(mesh, impeller, passage, piece, level)
        .into_iter()
        .filter(|c| c.closed)
        .max_by(|a, b| length(a).total_cmp(&length(b)))
}

/// The stretches of `curve` where `needed`, each run on by `overlap` (arc length) both ways, as
/// open curves; the whole curve when it is needed all round.
pub fn needed_stretches(curve: &SectionCurve, needed: &[bool], overlap: f64) -> Vec<SectionCurve> {
    let n = curve.points.len();
    if n < 2 || !needed.iter().any(|&k| k) {
        return Vec::new();
    }
    if needed.iter().all(|&k| k) {
        return vec![curve.clone()];
    }
    // A closed curve is cut open in the middle of its longest unneeded stretch.
    let start = if curve.closed {
        let mut best = (0, 0);
        let mut run = 0;
        for i in 0..2 * n {
            if needed[i % n] {
                run = 0;
            } else {
                run += 1;
                if run > best.1 && run <= n {
                    best = ((i + 1 + n - run / 2) % n, run);
                }
            }
        }
        best.0
    } else {
        0
    };
    let order: Vec<usize> = (0..n).map(|i| (start + i) % n).collect();
    let points: Vec<Point3> = order.iter().map(|&i| curve.points[i].point).collect();
    let along = arc_lengths(&points);
    let keep: Vec<bool> = order.iter().map(|&i| needed[i]).collect();
    runs_of_set(&run_on(&keep, &along, overlap))
        .into_iter()
        .filter(|run| run.len() >= 2)
        .map(|run| SectionCurve {
            points: order[run].iter().map(|&i| curve.points[i]).collect(),
            closed: false,
        })
        .collect()
}

/// The segments of the loops kept so far, by level, in a uniform grid of cells as large as
/// the distance asked about.
struct LevelGrid {
    cell: f64,
    segments: Vec<(Point3, Point3, f64)>,
    cells: HashMap<[i64; 3], Vec<u32>>,
}

impl LevelGrid {
    fn new(cell: f64) -> LevelGrid {
        LevelGrid {
            cell: cell.max(1e-6),
            segments: Vec::new(),
            cells: HashMap::new(),
        }
    }

    fn key(&self, p: &Point3) -> [i64; 3] {
        [p.x, p.y, p.z].map(|c| (c / self.cell).floor() as i64)
    }

    fn insert(&mut self, curve: &SectionCurve, level: f64) {
        let n = curve.points.len();
        let count = if curve.closed { n } else { n.saturating_sub(1) };
        for i in 0..count {
            let (a, b) = (curve.points[i].point, curve.points[(i + 1) % n].point);
            let index = self.segments.len() as u32;
            self.segments.push((a, b, level));
            let (lo, hi) = (self.key(&a.inf(&b)), self.key(&a.sup(&b)));
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        self.cells.entry([x, y, z]).or_default().push(index);
                    }
                }
            }
        }
    }

    /// Distance from `p` to the nearest segment of a level above `level` (or below), up to
    /// the cell size: farther is reported as the cell size.
    fn distance(&self, p: &Point3, level: f64, above: bool) -> f64 {
        let key = self.key(p);
        let mut best = self.cell;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(list) = self.cells.get(&[key[0] + dx, key[1] + dy, key[2] + dz])
                    else {
                        continue;
                    };
                    for &i in list {
                        let (a, b, l) = self.segments[i as usize];
                        if (l > level) == above && l != level {
                            best = best.min((p - closest_point_on_segment(p, &a, &b)).norm());
                        }
                    }
                }
            }
        }
        best
    }
}
