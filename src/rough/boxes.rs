//! Roughing to seed 002's convex-hull boxes ([`crate::cad::boxes`]) instead of an offset
//! shape: the layers and the guarantee.
//!
//! * [`box_layers`] — §4's non-uniform layers: a slicing plane at the top face of every box;
//!   where two planes lie farther apart than the maximum depth of cut, the Bézier patches
//!   whose boxes meet that slab are split by de Casteljau (fig. 11–12), and their children's
//!   tops become planes, until no thick slab is left or the patches have been split
//!   [`MAX_SPLITS`] times; then layers thinner than the minimum are merged upward (fig. 13)
//!   and what is still too thick (above the highest box, where no patch can help) is split
//!   evenly ([`super::layers::merge_and_split`]).
//! * The pocket boundary of a layer is the union of the boxes standing above it, each grown
//!   by the stock to leave ([`super::envelope::TopEnvelope::of_boxes`]).
//! * [`box_clearance`] — the guarantee checked on a program as written: no move brings the
//!   cutter's body (its radius, from the tip up) into any box above its tip. It shares
//!   nothing with the planning but the boxes.

use rayon::prelude::*;
use serde::Serialize;

use super::layers::{Layer, LayerOptions, merge_and_split};
use crate::cad::boxes::{HullBoxes, HullPatch};
use crate::geom::{Aabb, Aabb2, Point2, Toolpath};

/// How many times a patch of a surface's own decomposition may be split for the layers.
pub const MAX_SPLITS: u8 = 6;

/// Patches at most, whatever the splits want (a hostile file must not cost gigabytes).
pub const MAX_PATCHES: usize = 400_000;

/// The layers of [`box_layers`] and the boxes they keep out of.
#[derive(Clone, Debug, PartialEq)]
pub struct BoxLayers {
    /// Top first; the last is the bottom.
    pub layers: Vec<Layer>,
    /// Every patch's box after the splits, grown by the stock to leave.
    pub boxes: Vec<Aabb>,
    /// What was done to get there.
    pub summary: BoxSummary,
}

/// Counts of [`box_layers`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BoxSummary {
    /// Patches of the surfaces' own Bézier decomposition.
    pub patches: usize,
    /// Patches split for the layers, and the patches after the splits.
    pub splits: usize,
    pub patches_after_splits: usize,
    /// Slabs still thicker than the maximum depth with no patch to split in them (above the
    /// highest box, or where the splits ran out), split evenly.
    pub even_slabs: usize,
    /// Layers before merging (planes at box tops) and after.
    pub planes_at_box_tops: usize,
    pub layers: usize,
}

/// Seed 002's layers from `stock_top` down to `bottom` over `model`'s boxes grown by
/// `allowance` (see the module docs).
pub fn box_layers(
    model: &HullBoxes,
    allowance: f64,
    stock_top: f64,
    bottom: f64,
    options: &LayerOptions,
    max_box_width: f64,
    merge: LayerMerge,
) -> BoxLayers {
    let mut patches: Vec<HullPatch> = model.patches.clone();
    let mut splits = 0;
    // Boxes wider than asked are split first: a tighter model, whatever the layers.
    while split_where(&mut patches, &mut splits, |p| {
        let e = p.bounds.extent();
        e.x.max(e.y) > max_box_width
    }) {}
    let top_of = |p: &HullPatch| p.bounds.max.z + allowance;
    let low_of = |p: &HullPatch| p.bounds.min.z - allowance;
    let planes_of = |patches: &[HullPatch]| {
        let mut planes: Vec<f64> = patches
            .iter()
            .map(top_of)
            .filter(|&z| z > bottom && z < stock_top)
            .collect();
        planes.push(stock_top);
        planes.push(bottom);
        planes.sort_by(|a, b| b.total_cmp(a));
        planes.dedup();
        planes
    };
    let thick_slabs = |planes: &[f64]| -> Vec<(f64, f64)> {
        planes
            .windows(2)
            .filter(|w| w[0] - w[1] > options.max_depth)
            .map(|w| (w[1], w[0]))
            .collect()
    };
    loop {
        let slabs = thick_slabs(&planes_of(&patches));
        if slabs.is_empty() {
            break;
        }
        // A patch meets a slab when its box overlaps the slab's open interior; slabs are
        // disjoint and sorted, so the first slab ending above the box's bottom decides.
        let mut ascending = slabs.clone();
        ascending.sort_by(|a, b| a.0.total_cmp(&b.0));
        let meets = |p: &HullPatch| {
            let (low, top) = (low_of(p), top_of(p));
            let k = ascending.partition_point(|s| s.1 <= low);
            ascending.get(k).is_some_and(|s| s.0 < top)
        };
        if !split_where(&mut patches, &mut splits, meets) {
            break;
        }
    }
    let planes = planes_of(&patches);
    let even_slabs = thick_slabs(&planes).len();
    let planes_at_box_tops = planes.len() - 2;
    let planes = match merge {
        LayerMerge::Upward => planes,
        LayerMerge::Deepest => deepest_steps(&planes, stock_top, bottom, options),
    };
    let marked: Vec<(f64, bool)> = planes
        .into_iter()
        .filter(|&z| z < stock_top)
        .map(|z| (z, z != bottom))
        .collect();
    let layers = merge_and_split(marked, stock_top, options);
    BoxLayers {
        boxes: patches
            .iter()
            .map(|p| p.bounds.inflated(allowance))
            .collect(),
        summary: BoxSummary {
            patches: model.patches.len(),
            splits,
            patches_after_splits: patches.len(),
            even_slabs,
            planes_at_box_tops,
            layers: layers.len(),
        },
        layers,
    }
}

/// How the planes at the box tops become layers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LayerMerge {
    /// The seed's rule: a layer thinner than the minimum is merged with the one above until
    /// it is not. With thousands of box tops (a real part), nearly every layer then ends up
    /// just over the minimum depth.
    #[default]
    Upward,
    /// From the top down, the deepest box top within the maximum depth (and at least the
    /// minimum) below the layer above: every layer still at a box top, as few as the depths
    /// allow.
    Deepest,
}

/// From `stock_top` down, the lowest plane of `planes` (descending, `bottom` the last) in
/// the window [above − max, above − min]; where the window holds none, the first plane
/// below it (a slab the even split then divides). Strictly descending, ending at `bottom`.
fn deepest_steps(planes: &[f64], stock_top: f64, bottom: f64, options: &LayerOptions) -> Vec<f64> {
    let mut kept = Vec::new();
    let mut above = stock_top;
    while above > bottom {
        let (low, high) = (above - options.max_depth, above - options.min_depth);
        let next = planes
            .iter()
            .copied()
            // `z < above` also when the minimum depth is 0: the plane just cut is no step.
            .filter(|&z| z >= low && z <= high && z < above)
            .reduce(f64::min)
            .or_else(|| planes.iter().copied().find(|&z| z < low))
            .unwrap_or(bottom);
        kept.push(next);
        above = next;
    }
    kept
}

/// Replaces every patch `wanted` picks (and not yet split [`MAX_SPLITS`] times) by its
/// quarters, in order, counting them in `splits`; false when none was picked or the patches
/// would pass [`MAX_PATCHES`].
fn split_where(
    patches: &mut Vec<HullPatch>,
    splits: &mut usize,
    wanted: impl Fn(&HullPatch) -> bool,
) -> bool {
    let chosen: Vec<bool> = patches
        .iter()
        .map(|p| p.splits < MAX_SPLITS && wanted(p))
        .collect();
    let count = chosen.iter().filter(|&&c| c).count();
    if count == 0 || patches.len() + 3 * count > MAX_PATCHES {
        return false;
    }
    *patches = patches
        .par_iter()
        .zip(&chosen)
        .flat_map_iter(|(p, &split)| {
            if split {
                p.split().to_vec()
            } else {
                vec![p.clone()]
            }
        })
        .collect();
    *splits += count;
    true
}

/// What [`box_clearance`] found.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BoxClearance {
    pub boxes: usize,
    pub moves: usize,
    /// The least horizontal distance between the cutter's body and a box standing above its
    /// tip, mm, over the pairs within `reach` of each other (`reach` when none is).
    pub min_clearance_mm: f64,
    /// Moves that bring the body into a box by more than the tolerance: the first 20.
    pub violations: Vec<BoxViolation>,
    pub violation_count: usize,
}

/// A move into a box.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BoxViolation {
    pub move_index: usize,
    pub box_index: usize,
    /// How far the body reaches into the box horizontally, mm.
    pub depth_mm: f64,
}

/// Checks every move of `toolpath` (vertical axis, tip positions) against `boxes`: along the
/// part of the move where the tip is below a box's top by more than `tolerance`, the tip's
/// horizontal path must stay `radius` (the widest radius below the holder) from the box's
/// footprint, to within `tolerance`. Exact: the tip's height is linear along a move, so
/// that part is one sub-segment, and the distance from a segment to a rectangle is the least
/// of the endpoint and corner distances when they do not cross. Pairs farther apart than
/// `reach` are not measured.
pub fn box_clearance(
    toolpath: &Toolpath,
    boxes: &[Aabb],
    radius: f64,
    tolerance: f64,
    reach: f64,
) -> BoxClearance {
    let moves = &toolpath.moves;
    let index = BoxGrid::new(boxes, radius + reach);
    let highest = boxes
        .iter()
        .map(|b| b.max.z)
        .fold(f64::NEG_INFINITY, f64::max);
    let per_move: Vec<(f64, Vec<BoxViolation>)> = (1..moves.len())
        .into_par_iter()
        .map(|m| {
            let (a, b) = (moves[m - 1].pose.tip, moves[m].pose.tip);
            let mut least = reach;
            let mut found = Vec::new();
            if a.z.min(b.z) >= highest - tolerance {
                return (least, found);
            }
            let (pa, pb) = (Point2::new(a.x, a.y), Point2::new(b.x, b.y));
            for k in index.near(pa, pb) {
                let bx = &boxes[k];
                let limit = bx.max.z - tolerance;
                // The part of the move with the tip below the box's top.
                let (mut t0, mut t1) = (0.0f64, 1.0f64);
                if (b.z - a.z).abs() < 1e-15 {
                    if a.z >= limit {
                        continue;
                    }
                } else {
                    let t = (limit - a.z) / (b.z - a.z);
                    if b.z > a.z {
                        t1 = t1.min(t);
                    } else {
                        t0 = t0.max(t);
                    }
                    if t0 >= t1 {
                        continue;
                    }
                }
                let (qa, qb) = (pa + (pb - pa) * t0, pa + (pb - pa) * t1);
                let clearance = segment_rectangle_distance(qa, qb, bx) - radius;
                least = least.min(clearance);
                if clearance < -tolerance {
                    found.push(BoxViolation {
                        move_index: m,
                        box_index: k,
                        depth_mm: -clearance,
                    });
                }
            }
            (least, found)
        })
        .collect();
    let violation_count = per_move.iter().map(|m| m.1.len()).sum();
    BoxClearance {
        boxes: boxes.len(),
        moves: moves.len(),
        min_clearance_mm: per_move.iter().map(|m| m.0).fold(reach, f64::min),
        violations: per_move.into_iter().flat_map(|m| m.1).take(20).collect(),
        violation_count,
    }
}

/// Distance between the segment `a`–`b` and the box's footprint (0 when they meet).
fn segment_rectangle_distance(a: Point2, b: Point2, bx: &Aabb) -> f64 {
    let footprint = Aabb2 {
        min: Point2::new(bx.min.x, bx.min.y),
        max: Point2::new(bx.max.x, bx.max.y),
    };
    if footprint.meets_segment(a, b) {
        return 0.0;
    }
    let (lo, hi) = (footprint.min, footprint.max);
    let to_segment = |p: Point2| {
        let d = b - a;
        let t = if d.norm_squared() > 0.0 {
            ((p - a).dot(&d) / d.norm_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (a + d * t - p).norm()
    };
    [
        footprint.point_distance(a),
        footprint.point_distance(b),
        to_segment(lo),
        to_segment(hi),
        to_segment(Point2::new(lo.x, hi.y)),
        to_segment(Point2::new(hi.x, lo.y)),
    ]
    .into_iter()
    .fold(f64::INFINITY, f64::min)
}

/// Boxes bucketed on a square grid over their footprints, each in every cell its footprint
/// grown by `margin` meets: the boxes within `margin` of a segment are in the cells of the
/// segment's bounding square.
struct BoxGrid {
    origin: Point2,
    cell: f64,
    width: usize,
    height: usize,
    cells: Vec<Vec<usize>>,
}

impl BoxGrid {
    fn new(boxes: &[Aabb], margin: f64) -> BoxGrid {
        let bounds = boxes.iter().fold(Aabb::empty(), |a, b| a.merge(b));
        let origin = Point2::new(bounds.min.x - margin, bounds.min.y - margin);
        let span = (bounds.extent().x.max(bounds.extent().y) + 2.0 * margin).max(1e-9);
        let cell = (span / 256.0).max(margin);
        let width = ((bounds.extent().x + 2.0 * margin) / cell).ceil().max(1.0) as usize;
        let height = ((bounds.extent().y + 2.0 * margin) / cell).ceil().max(1.0) as usize;
        let mut grid = BoxGrid {
            origin,
            cell,
            width,
            height,
            cells: vec![Vec::new(); width * height],
        };
        for (k, b) in boxes.iter().enumerate() {
            let (i0, j0) = grid.cell_of(Point2::new(b.min.x - margin, b.min.y - margin));
            let (i1, j1) = grid.cell_of(Point2::new(b.max.x + margin, b.max.y + margin));
            for j in j0..=j1 {
                for i in i0..=i1 {
                    grid.cells[i + j * width].push(k);
                }
            }
        }
        grid
    }

    fn cell_of(&self, p: Point2) -> (usize, usize) {
        let i = ((p.x - self.origin.x) / self.cell).floor();
        let j = ((p.y - self.origin.y) / self.cell).floor();
        (
            i.clamp(0.0, (self.width - 1) as f64) as usize,
            j.clamp(0.0, (self.height - 1) as f64) as usize,
        )
    }

    /// The boxes bucketed in the cells of the segment's bounding square, each once, sorted.
    fn near(&self, a: Point2, b: Point2) -> Vec<usize> {
        let (i0, j0) = self.cell_of(Point2::new(a.x.min(b.x), a.y.min(b.y)));
        let (i1, j1) = self.cell_of(Point2::new(a.x.max(b.x), a.y.max(b.y)));
        let mut out = Vec::new();
        for j in j0..=j1 {
            for i in i0..=i1 {
                out.extend_from_slice(&self.cells[i + j * self.width]);
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{Direction, Move, MoveKind, Point3, ToolPose, Vector3};

    /// A minimum depth of 0 lets the window reach the plane just cut: it must not be taken
    /// again (the loop would never end); past an empty window the next plane below is taken.
    #[test]
    fn deepest_steps_descend_strictly_even_with_no_minimum_depth() {
        let options = LayerOptions {
            max_depth: 6.0,
            min_depth: 0.0,
            flat_band: 0.1,
            flat_area: 1.0,
        };
        let steps = deepest_steps(&[30.0, 20.0, 17.0, 4.0, 0.0], 40.0, 0.0, &options);
        assert_eq!(steps, [30.0, 20.0, 17.0, 4.0, 0.0]);
    }

    fn patch_box(min: [f64; 3], max: [f64; 3]) -> Aabb {
        Aabb {
            min: Point3::from(min),
            max: Point3::from(max),
        }
    }

    fn path(points: &[[f64; 3]]) -> Toolpath {
        Toolpath {
            tool_id: 1,
            moves: points
                .iter()
                .map(|p| Move {
                    pose: ToolPose {
                        tip: Point3::from(*p),
                        axis: Direction::new_normalize(Vector3::z()),
                    },
                    kind: MoveKind::Cut,
                    feed: 1000.0,
                })
                .collect(),
        }
    }

    /// The clearance is the closed-form distance: a pass at 3 mm beside a box with a tool
    /// of radius 2 clears it by 1; the same pass above the box clears it whatever the
    /// distance; a ramp that comes down beside the box is measured only below its top.
    #[test]
    fn clearance_to_boxes_is_exact() {
        let boxes = [patch_box([0.0, 0.0, 0.0], [10.0, 10.0, 5.0])];
        let beside = path(&[[-3.0, -5.0, 2.0], [-3.0, 15.0, 2.0]]);
        let c = box_clearance(&beside, &boxes, 2.0, 1e-6, 10.0);
        assert!((c.min_clearance_mm - 1.0).abs() < 1e-12, "{c:?}");
        assert_eq!(c.violation_count, 0);
        let over = path(&[[5.0, -5.0, 5.0], [5.0, 15.0, 5.0]]);
        let c = box_clearance(&over, &boxes, 2.0, 1e-6, 10.0);
        assert_eq!((c.min_clearance_mm, c.violation_count), (10.0, 0));
        // Diagonal past the corner (10, 10): the nearest point of the line x + y = 24 is
        // √2·2 from it.
        let corner = path(&[[4.0, 20.0, 1.0], [20.0, 4.0, 1.0]]);
        let c = box_clearance(&corner, &boxes, 2.0, 1e-6, 10.0);
        assert!((c.min_clearance_mm - (2.0 * 2f64.sqrt() - 2.0)).abs() < 1e-12);
        // Ramp from above the box down beside it: over the box (x = 8) the tip is still
        // above the top; it goes below at x = 12, 2 from the box.
        let ramp = path(&[[8.0, 5.0, 9.0], [16.0, 5.0, 1.0]]);
        let c = box_clearance(&ramp, &boxes, 1.5, 1e-6, 10.0);
        assert!((c.min_clearance_mm - 0.5).abs() < 1e-5, "{c:?}");
        let c = box_clearance(&ramp, &boxes, 2.5, 1e-6, 10.0);
        assert_eq!(c.violation_count, 1);
        assert!((c.violations[0].depth_mm - 0.5).abs() < 1e-5);
        // Straight through the box at its mid-height.
        let through = path(&[[-5.0, 5.0, 2.0], [15.0, 5.0, 2.0]]);
        let c = box_clearance(&through, &boxes, 1.0, 1e-6, 10.0);
        assert_eq!(c.violation_count, 1);
        assert!((c.min_clearance_mm + 1.0).abs() < 1e-12);
    }

    /// A vertical wall 16 high under a stock top at its top: one slab of 16 > 6, so the wall
    /// is split (tops at 8 and 16), the two slabs of 8 split again (tops at 4 and 12): layers
    /// at 12, 8, 4, 0, each 4 deep and at a box top, after 1 + 4 splits. With a minimum depth
    /// of 5 the planes at 12 and 4 are merged away and the slabs of 8 split evenly again.
    #[test]
    fn a_thick_slab_is_sliced_at_the_tops_of_split_patches() {
        use crate::cad::iges::{Face, Surface};
        use crate::cad::nurbs::NurbsSurface;
        let net: Vec<Vec<Point3>> = (0..2)
            .map(|i| {
                (0..2)
                    .map(|j| Point3::new(10.0 * i as f64, 5.0, 16.0 * j as f64))
                    .collect()
            })
            .collect();
        let wall = NurbsSurface::new(
            [1, 1],
            vec![0.0, 0.0, 1.0, 1.0],
            vec![0.0, 0.0, 1.0, 1.0],
            &net,
            &[vec![1.0; 2], vec![1.0; 2]],
        )
        .unwrap();
        let face = Face {
            de: 1,
            line: 1,
            surface: Surface::Nurbs {
                surface: wall,
                u: (0.0, 1.0),
                v: (0.0, 1.0),
            },
            outer: None,
            holes: Vec::new(),
            model_boundaries: Vec::new(),
        };
        let model = HullBoxes::of_faces(&[face], nalgebra::Rotation3::identity()).unwrap();
        let mut options = LayerOptions {
            max_depth: 6.0,
            min_depth: 2.0,
            flat_band: 0.1,
            flat_area: 1.0,
        };
        let planned = box_layers(
            &model,
            0.0,
            16.0,
            0.0,
            &options,
            f64::INFINITY,
            LayerMerge::Upward,
        );
        let zs: Vec<f64> = planned.layers.iter().map(|l| l.z).collect();
        let near = |a: &[f64], b: &[f64]| {
            a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-9)
        };
        assert!(near(&zs, &[12.0, 8.0, 4.0, 0.0]), "{zs:?}");
        assert!(
            planned.layers[..3]
                .iter()
                .all(|l| l.at_flat && (l.depth - 4.0).abs() < 1e-9)
        );
        assert_eq!(planned.summary.splits, 5);
        assert_eq!(planned.summary.patches_after_splits, 16);
        assert_eq!(planned.boxes.len(), 16);
        options.min_depth = 5.0;
        let merged = box_layers(
            &model,
            0.0,
            16.0,
            0.0,
            &options,
            f64::INFINITY,
            LayerMerge::Upward,
        );
        let zs: Vec<f64> = merged.layers.iter().map(|l| l.z).collect();
        assert!(near(&zs, &[12.0, 8.0, 4.0, 0.0]), "{zs:?}");
        assert_eq!(
            merged.layers.iter().map(|l| l.at_flat).collect::<Vec<_>>(),
            [false, true, false, false]
        );
        // Grown by a 1 mm allowance, every box the layers keep out of is 1 mm wider.
        let grown = box_layers(
            &model,
            1.0,
            16.0,
            0.0,
            &options,
            f64::INFINITY,
            LayerMerge::Upward,
        );
        assert!(grown.boxes.iter().all(|b| b.min.y <= 4.0 && b.max.y >= 6.0));
    }

    /// The segment–rectangle distance agrees with a brute-force minimum over dense points of
    /// both.
    #[test]
    fn segment_rectangle_distance_matches_brute_force() {
        let bx = patch_box([1.0, 2.0, 0.0], [4.0, 3.0, 1.0]);
        let mut random = crate::geom::SeededRandom::new(7);
        let mut next = || random.range(-2.5, 7.5);
        for _ in 0..200 {
            let (a, b) = (Point2::new(next(), next()), Point2::new(next(), next()));
            let exact = segment_rectangle_distance(a, b, &bx);
            let mut brute = f64::INFINITY;
            for i in 0..=400 {
                let p = a + (b - a) * (i as f64 / 400.0);
                let dx = (1.0 - p.x).max(p.x - 4.0).max(0.0);
                let dy = (2.0 - p.y).max(p.y - 3.0).max(0.0);
                brute = brute.min(dx.hypot(dy));
            }
            assert!(
                exact <= brute + 1e-12 && brute - exact < 0.02,
                "{exact} {brute}"
            );
        }
    }
}
