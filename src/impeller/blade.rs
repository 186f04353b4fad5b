//! Point-milling loops around a blade (issue 21 item 2, blade finishing): the curves on the
//! blade where its height above the hub is constant, from the tip down to the root, so that
//! the ball goes round the blade — pressure side, trailing edge, suction side, leading edge —
//! once per level and steps down between levels like a spiral from shroud to hub.
//!
//! The height above the hub is measured in the meridional half-plane from the hub's meridian
//! ([`HubPassage::above_hub`]); each level set is a plane-section-like curve of that function
//! on the blade's triangles ([`crate::mesh::level_section`]). The levels are spaced so that
//! neighbouring loops are a stepover apart along the blade where they are farthest apart:
//! the spacing in height is the stepover times the surface gradient of the height (1 on a
//! flank square to the hub, less on a leaning one), taken at its low percentile over the
//! flanks.

use crate::geom::Vector3;
use crate::mesh::{Mesh, SectionCurve, level_section};

use super::passage::HubPassage;
use super::recognise::{Impeller, Region};

/// What the loops of one blade are.
#[derive(Clone, Debug, PartialEq)]
pub struct BladeLoops {
    pub curves: Vec<SectionCurve>,
    pub levels: usize,
    /// Height between levels, mm.
    pub level_step: f64,
    /// The blade's greatest height above the hub, mm.
    pub top: f64,
}

/// The loops around blade `piece` of `impeller` (recognised in `mesh`), neighbouring loops at
/// most `stepover` apart along the flanks; each loop starts where the one above it ended.
pub fn blade_loops(
    mesh: &Mesh,
    impeller: &Impeller,
    passage: &HubPassage,
    piece: usize,
    stepover: f64,
) -> BladeLoops {
    let triangles: Vec<[u32; 3]> = mesh
        .triangles
        .iter()
        .zip(&impeller.regions)
        .filter(|(_, r)| **r == Region::Blade(piece as u32))
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

    // The surface gradient of the height on each triangle, weighted by area.
    let mut gradients: Vec<(f64, f64)> = blade
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
    gradients.sort_by(|a, b| a.0.total_cmp(&b.0));
    let total: f64 = gradients.iter().map(|g| g.1).sum();
    let mut seen = 0.0;
    let mut steepness = 1.0;
    for (g, area) in &gradients {
        seen += area;
        if seen >= 0.1 * total {
            steepness = *g;
            break;
        }
    }
    let level_step = (stepover * steepness.min(1.0)).max(1e-3);
    let top = height.iter().copied().fold(0.0, f64::max);
    let mut curves: Vec<SectionCurve> = Vec::new();
    let mut levels = 0;
    let mut level = top - 0.5 * level_step;
    while level > 0.5 * level_step {
        let shifted: Vec<f64> = height.iter().map(|h| h - level).collect();
        for mut curve in level_section(&blade, &normals, &shifted) {
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
            curves.push(curve);
        }
        levels += 1;
        level -= level_step;
    }
    BladeLoops {
        curves,
        levels,
        level_step,
        top,
    }
}
