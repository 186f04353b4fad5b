//! The sample impeller (see [`super::impeller()`] and [`ImpellerParams`]).
//!
//! Geometry (cylindrical coordinates r, θ, z; lengths from [`ImpellerParams`]):
//!
//! * Hub profile: z_hub(r) = z_rim + (z_nose − z_rim) · e(u)/e(1), u = (R − r)/(R − r_bore),
//!   e(u) = 1 − √(1 − (k u)²), k = 0.95: a quarter ellipse centred above the rim, clipped at the
//!   nose so the slope there stays finite (about 45° at the defaults). Concave seen from above,
//!   flat where it meets the rim.
//! * Blade camber line at height fraction v ∈ [0, 1], with t = (r − r_in)/(r_out − r_in):
//!   θ(r, v) = φ_i + wrap · (1 − (1 − t)⁶) + v · h(r) · tan(lean) / r, nearly tangential at
//!   the inlet (an inducer: the channels there are a few mm wide), radial at the exit, and
//!   shifted tangentially with height by the lean. The blade height above the hub is
//!   h(r) = h_out + (h_in − h_out)(1 − t)².
//! * Blade section at level v: the camber line offset by ± w(v) along its in-plane normal,
//!   w(v) = (thickness / 2)(1 − 0.25 v), closed by half circles at the leading and trailing
//!   edges. A section vertex p sits at z = z_hub(|p|) + v · h(r_station), so level 0 lies on
//!   the hub and every level keeps its radius, which keeps the blades clear of the hub.
//!
//! Mesh: bore and rim are lofts of rings; the bottom is a CDT of the flat annulus with polar
//! Steiner rings; each blade is a loft of its sections, capped by a CDT of the tip section;
//! the hub top is one CDT of the annulus with every blade's level-0 section as a hole, Steiner
//! rings spaced by arc length along the profile and thinned away from the footprints, lifted to
//! z_hub. All seams share vertices, so the result is one closed 2-manifold of genus 1.

use std::f64::consts::{PI, TAU};

use nalgebra::Point3;

use super::builder::MeshBuilder;
use super::cdt::triangulate_region;
use super::loft::loft;
use super::poly::{self, ArcTable, Obstacles, P2};
use super::{ImpellerParams, MAX_TRIANGLES, SampleError, bounded, invalid, positive};
use crate::mesh::Mesh;

/// How far along the quarter ellipse the hub's nose reaches (1 would make it vertical).
const NOSE_K: f64 = 0.95;
/// Rim (back plate) height as a fraction of the hub height.
const RIM_HEIGHT_RATIO: f64 = 0.25;
/// Blade height at the trailing edge as a fraction of the blade height at the leading edge.
const EXIT_HEIGHT_RATIO: f64 = 0.35;
/// Radial gap between the trailing edge and the rim, as a fraction of the hub radius.
const RIM_GAP_RATIO: f64 = 0.03;
/// Blade thickness at the tip as a fraction of the thickness at the hub.
const TIP_THICKNESS_RATIO: f64 = 0.75;
/// Hub-top Steiner points keep at least this many `resolution`s from a blade footprint.
const STEINER_CLEARANCE: f64 = 0.6;
/// Smallest allowed gap between adjacent blades, in `resolution`s.
const MIN_BLADE_GAP: f64 = 0.25;
/// The camber line turns as 1 − (1 − t)^WRAP_EXPONENT: the higher, the more tangential
/// the blades are at the inlet and the narrower the channels there.
const WRAP_EXPONENT: i32 = 6;
/// Samples of the dense tables used for arc-length parametrisation.
const FINE: usize = 2048;

/// The hub's meridional profile z_hub(r).
#[derive(Debug)]
pub(super) struct HubProfile {
    pub(super) bore: f64,
    pub(super) rim: f64,
    pub(super) nose_z: f64,
    pub(super) rim_z: f64,
}

impl HubProfile {
    /// Height of the hub's top surface at radius `r` (clamped to the bore…rim range).
    pub(super) fn z(&self, r: f64) -> f64 {
        let u = ((self.rim - r) / (self.rim - self.bore)).clamp(0.0, 1.0);
        let e = |x: f64| 1.0 - (1.0 - (NOSE_K * x).powi(2)).sqrt();
        self.rim_z + (self.nose_z - self.rim_z) * e(u) / e(1.0)
    }
}

/// One blade's shape in its own angular frame (blade 0).
#[derive(Debug)]
pub(super) struct BladeShape {
    /// Camber line start and end radius.
    pub(super) r_in: f64,
    pub(super) r_out: f64,
    /// Wrap angle, radians.
    pub(super) wrap: f64,
    /// tan(lean angle).
    pub(super) lean_tan: f64,
    /// Blade height at the leading and trailing edge.
    pub(super) h_in: f64,
    pub(super) h_out: f64,
    /// Half thickness at the hub.
    pub(super) w0: f64,
}

impl BladeShape {
    fn t(&self, r: f64) -> f64 {
        (r - self.r_in) / (self.r_out - self.r_in)
    }

    /// Blade height above the hub at camber radius `r`.
    pub(super) fn height(&self, r: f64) -> f64 {
        let s = 1.0 - self.t(r);
        self.h_out + (self.h_in - self.h_out) * s * s
    }

    fn height_dr(&self, r: f64) -> f64 {
        -2.0 * (self.h_in - self.h_out) * (1.0 - self.t(r)) / (self.r_out - self.r_in)
    }

    /// Half thickness at height fraction `v`.
    pub(super) fn half_thickness(&self, v: f64) -> f64 {
        self.w0 * (1.0 - (1.0 - TIP_THICKNESS_RATIO) * v)
    }

    fn theta(&self, r: f64, v: f64) -> f64 {
        let s = 1.0 - self.t(r);
        self.wrap * (1.0 - s.powi(WRAP_EXPONENT)) + v * self.height(r) * self.lean_tan / r
    }

    fn theta_dr(&self, r: f64, v: f64) -> f64 {
        let s = 1.0 - self.t(r);
        self.wrap * f64::from(WRAP_EXPONENT) * s.powi(WRAP_EXPONENT - 1) / (self.r_out - self.r_in)
            + v * self.lean_tan * (self.height_dr(r) / r - self.height(r) / (r * r))
    }

    /// Camber point at radius `r`, height fraction `v`, and the unit tangent (towards larger r).
    pub(super) fn camber(&self, r: f64, v: f64) -> (P2, P2) {
        let (s, c) = self.theta(r, v).sin_cos();
        let rt = r * self.theta_dr(r, v);
        let d = [c - rt * s, s + rt * c];
        let len = (d[0] * d[0] + d[1] * d[1]).sqrt();
        ([r * c, r * s], [d[0] / len, d[1] / len])
    }

    /// The section polygon at height fraction `v`, counter-clockwise, as (point, camber radius
    /// of its station). `stations` are the camber radii, `cap` the segments per end half circle.
    fn section(&self, stations: &[f64], v: f64, cap: usize) -> Vec<(P2, f64)> {
        let w = self.half_thickness(v);
        let frames: Vec<(P2, P2, f64)> = stations
            .iter()
            .map(|&r| {
                let (c, t) = self.camber(r, v);
                (c, t, r)
            })
            .collect();
        let at = |c: P2, d: [f64; 2]| [c[0] + w * d[0], c[1] + w * d[1]];
        let mut out = Vec::with_capacity(2 * stations.len() + 2 * cap);
        // Right side (−N) from the leading to the trailing edge.
        for &(c, t, r) in &frames {
            out.push((at(c, [t[1], -t[0]]), r));
        }
        // Trailing-edge half circle from −N through +T to +N.
        if let Some(&(c, t, r)) = frames.last() {
            for m in 1..cap {
                let (sa, ca) = (PI * m as f64 / cap as f64).sin_cos();
                out.push((at(c, [t[1] * ca + t[0] * sa, -t[0] * ca + t[1] * sa]), r));
            }
        }
        // Left side (+N) back to the leading edge.
        for &(c, t, r) in frames.iter().rev() {
            out.push((at(c, [-t[1], t[0]]), r));
        }
        // Leading-edge half circle from +N through −T to −N.
        if let Some(&(c, t, r)) = frames.first() {
            for m in 1..cap {
                let (sa, ca) = (PI * m as f64 / cap as f64).sin_cos();
                out.push((at(c, [-t[1] * ca - t[0] * sa, t[0] * ca - t[1] * sa]), r));
            }
        }
        out
    }
}

/// Validated impeller geometry plus its discretisation.
#[derive(Debug)]
pub(super) struct Impeller {
    pub(super) blades: u32,
    pub(super) hub: HubProfile,
    pub(super) blade: BladeShape,
    res: f64,
    /// Blade 0's sections, level 0 (footprint) to the tip.
    sections: Vec<Vec<(P2, f64)>>,
}

/// Number of points on a ring of radius `r`.
fn ring_count(r: f64, res: f64, min: usize) -> usize {
    ((TAU * r / res).round() as usize).max(min)
}

/// Points of a ring of radius `r` with `n` points, starting at angle `offset`.
fn ring(r: f64, n: usize, offset: f64) -> impl Iterator<Item = P2> {
    (0..n).map(move |k| {
        let (s, c) = (offset + TAU * k as f64 / n as f64).sin_cos();
        [r * c, r * s]
    })
}

fn rotate(p: P2, (s, c): (f64, f64)) -> P2 {
    [c * p[0] - s * p[1], s * p[0] + c * p[1]]
}

fn norm(p: P2) -> f64 {
    (p[0] * p[0] + p[1] * p[1]).sqrt()
}

impl Impeller {
    /// Validates `p` and computes the blade sections.
    pub(super) fn new(p: &ImpellerParams) -> Result<Self, SampleError> {
        let blades = p.blade_count;
        if !(1..=128).contains(&blades) {
            return Err(invalid(
                "blade_count",
                format!("must be in 1..=128, got {blades}"),
            ));
        }
        let rb = positive("bore_radius", p.bore_radius)?;
        let rr = positive("hub_radius", p.hub_radius)?;
        if rb >= rr {
            return Err(invalid(
                "bore_radius",
                format!("must be smaller than hub_radius ({rr}), got {rb}"),
            ));
        }
        let nose_z = positive("hub_height", p.hub_height)?;
        let h_in = positive("blade_height", p.blade_height)?;
        let r_in = positive("blade_inner_radius", p.blade_inner_radius)?;
        let wrap = bounded("wrap_angle_deg", p.wrap_angle_deg, 360.0)?.to_radians();
        let lean = bounded("lean_angle_deg", p.lean_angle_deg, 60.0)?.to_radians();
        let thickness = positive("blade_thickness", p.blade_thickness)?;
        let res = positive("resolution", p.resolution)?;
        if res > (rr - rb) / 4.0 {
            return Err(invalid(
                "resolution",
                format!(
                    "must be at most (hub_radius − bore_radius)/4 = {}, got {res}",
                    (rr - rb) / 4.0
                ),
            ));
        }
        if thickness > (rr - rb) / 4.0 {
            return Err(invalid(
                "blade_thickness",
                format!(
                    "must be at most (hub_radius − bore_radius)/4 = {}, got {thickness}",
                    (rr - rb) / 4.0
                ),
            ));
        }
        let w0 = thickness / 2.0;
        let gap = RIM_GAP_RATIO * rr;
        let r_out = rr - gap - w0;
        if r_in - w0 < rb + 0.5 * res {
            return Err(invalid(
                "blade_inner_radius",
                format!(
                    "the leading edge (radius {r_in} − thickness/2) must clear the bore \
                     (radius {rb}) by at least resolution/2; need ≥ {}",
                    rb + 0.5 * res + w0
                ),
            ));
        }
        if r_in > r_out - 2.0 * res {
            return Err(invalid(
                "blade_inner_radius",
                format!(
                    "the blade would end at radius {r_out} (just inside the rim), so the \
                     leading edge must be at most {}, got {r_in}",
                    r_out - 2.0 * res
                ),
            ));
        }
        let hub = HubProfile {
            bore: rb,
            rim: rr,
            nose_z,
            rim_z: RIM_HEIGHT_RATIO * nose_z,
        };
        let blade = BladeShape {
            r_in,
            r_out,
            wrap,
            lean_tan: lean.tan(),
            h_in,
            h_out: EXIT_HEIGHT_RATIO * h_in,
            w0,
        };

        // Discretisation, with a size guard before anything large is allocated.
        let camber = ArcTable::new(r_in, r_out, FINE, |r| blade.camber(r, 0.0).0);
        let n_st = (camber.length() / res).ceil().max(2.0);
        let cap = (PI * w0 / res).ceil().max(2.0);
        let levels = (h_in / res).ceil().max(1.0);
        let ring_tris = 2.0 * PI * (rr * rr - rb * rb) / (0.433 * res * res);
        let blade_tris = f64::from(blades) * 2.0 * (2.0 * n_st + 2.0 * cap) * (levels + 1.0);
        if ring_tris + blade_tris > MAX_TRIANGLES {
            return Err(invalid(
                "resolution",
                format!(
                    "{res} mm would give about {:.0} triangles (limit {MAX_TRIANGLES:.0})",
                    ring_tris + blade_tris
                ),
            ));
        }
        let (n_st, cap, levels) = (n_st as usize, cap as usize, levels as usize);
        let stations: Vec<f64> = (0..=n_st)
            .map(|j| camber.param_at(camber.length() * j as f64 / n_st as f64))
            .collect();
        let sections: Vec<Vec<(P2, f64)>> = (0..=levels)
            .map(|k| blade.section(&stations, k as f64 / levels as f64, cap))
            .collect();

        let pitch = (TAU / f64::from(blades)).sin_cos();
        for (k, sec) in sections.iter().enumerate() {
            let v = k as f64 / levels as f64;
            let pts: Vec<P2> = sec.iter().map(|&(q, _)| q).collect();
            if !poly::polygon_is_simple(&pts) || poly::signed_area2(&pts) <= 0.0 {
                return Err(invalid(
                    "blade_thickness",
                    format!(
                        "the blade section at height fraction {v:.2} folds over itself: the \
                         camber line turns too sharply for the thickness (reduce \
                         blade_thickness, wrap_angle_deg or lean_angle_deg)"
                    ),
                ));
            }
            let r_min = pts.iter().map(|&q| norm(q)).fold(f64::INFINITY, f64::min);
            let r_max = pts.iter().map(|&q| norm(q)).fold(0.0, f64::max);
            if r_min < rb + 0.5 * res {
                return Err(invalid(
                    "blade_inner_radius",
                    format!("the blade reaches radius {r_min:.3}, too close to the bore"),
                ));
            }
            if r_max > rr - 0.5 * gap {
                return Err(invalid(
                    "blade_thickness",
                    format!("the blade reaches radius {r_max:.3}, off the hub's rim"),
                ));
            }
            if blades > 1 {
                let next: Vec<P2> = pts.iter().map(|&q| rotate(q, pitch)).collect();
                let d = poly::polygon_distance(&pts, &next);
                if d < MIN_BLADE_GAP * res {
                    return Err(invalid(
                        "blade_count",
                        format!(
                            "adjacent blades are {d:.3} mm apart at height fraction {v:.2} \
                             (need ≥ {:.3}); reduce blade_count, blade_thickness, \
                             wrap_angle_deg or lean_angle_deg",
                            MIN_BLADE_GAP * res
                        ),
                    ));
                }
            }
        }
        Ok(Self {
            blades,
            hub,
            blade,
            res,
            sections,
        })
    }

    /// Smallest distance between adjacent blades over all sections (∞ for one blade).
    #[cfg(test)]
    pub(super) fn min_gap(&self) -> f64 {
        if self.blades < 2 {
            return f64::INFINITY;
        }
        let pitch = (TAU / f64::from(self.blades)).sin_cos();
        self.sections
            .iter()
            .map(|sec| {
                let pts: Vec<P2> = sec.iter().map(|&(q, _)| q).collect();
                let next: Vec<P2> = pts.iter().map(|&q| rotate(q, pitch)).collect();
                poly::polygon_distance(&pts, &next)
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// Builds the mesh.
    pub(super) fn build(&self) -> Result<Mesh, SampleError> {
        let (hub, res) = (&self.hub, self.res);
        let mut b = MeshBuilder::default();
        let up = |q: P2, z: f64| Point3::new(q[0], q[1], z);

        // Bore and rim walls: lofts of rings; ring 0 is on z = 0, the last on the hub top.
        let n_bore = ring_count(hub.bore, res, 8);
        let n_rim = ring_count(hub.rim, res, 8);
        let wall = |b: &mut MeshBuilder, r: f64, n: usize, top: f64| {
            let levels = (top / res).ceil().max(1.0) as usize;
            (0..=levels)
                .map(|l| {
                    let z = if l == levels {
                        top
                    } else {
                        top * l as f64 / levels as f64
                    };
                    b.vertex_loop(ring(r, n, 0.0).map(|q| up(q, z)))
                })
                .collect::<Result<Vec<_>, _>>()
        };
        let bore = wall(&mut b, hub.bore, n_bore, hub.z(hub.bore))?;
        let rim = wall(&mut b, hub.rim, n_rim, hub.z(hub.rim))?;
        for pair in bore.windows(2) {
            // Reversed (clockwise from above): the bore's outside is towards the axis.
            let lo: Vec<u32> = pair[0].iter().rev().copied().collect();
            let hi: Vec<u32> = pair[1].iter().rev().copied().collect();
            loft(&mut b, &lo, &hi);
        }
        for pair in rim.windows(2) {
            loft(&mut b, &pair[0], &pair[1]);
        }
        let (bore_bottom, bore_top) = (&bore[0], &bore[bore.len() - 1]);
        let (rim_bottom, rim_top) = (&rim[0], &rim[rim.len() - 1]);

        // Bottom: flat annulus, evenly spaced staggered rings.
        let m = ((hub.rim - hub.bore) / res).ceil().max(2.0) as usize;
        let mut steiner = Vec::new();
        for i in 1..m {
            let r = hub.bore + (hub.rim - hub.bore) * i as f64 / m as f64;
            let n = ring_count(r, res, 3);
            let offset = (i % 2) as f64 * PI / n as f64;
            for q in ring(r, n, offset) {
                steiner.push(b.vertex(up(q, 0.0))?);
            }
        }
        let tris = triangulate_region(&b, &[rim_bottom, bore_bottom], &steiner, "impeller bottom")?;
        b.triangles_flipped(tris);

        // Blades: lofted sections, tip capped.
        let levels = self.sections.len() - 1;
        let mut footprints = Vec::new();
        let mut obstacles = Obstacles::default();
        for i in 0..self.blades {
            let rot = (TAU * f64::from(i) / f64::from(self.blades)).sin_cos();
            let mut loops = Vec::with_capacity(self.sections.len());
            for (k, sec) in self.sections.iter().enumerate() {
                let v = k as f64 / levels as f64;
                let lp = b.vertex_loop(sec.iter().map(|&(q, r_st)| {
                    let q = rotate(q, rot);
                    let z = hub.z(norm(q)) + v * self.blade.height(r_st);
                    up(q, z)
                }))?;
                loops.push(lp);
            }
            for pair in loops.windows(2) {
                loft(&mut b, &pair[0], &pair[1]);
            }
            let tip = &loops[levels];
            let tris = triangulate_region(&b, &[tip], &[], "impeller blade tip")?;
            b.triangles(tris);
            let foot = loops.swap_remove(0);
            obstacles.add(
                foot.iter()
                    .map(|&v| {
                        let q = b.position(v);
                        [q.x, q.y]
                    })
                    .collect(),
            );
            footprints.push(foot);
        }

        // Hub top: rings evenly spaced along the profile, thinned around the blades, lifted.
        let profile = ArcTable::new(hub.bore, hub.rim, FINE, |r| [r, hub.z(r)]);
        let m = (profile.length() / res).ceil().max(2.0) as usize;
        let mut steiner = Vec::new();
        for i in 1..m {
            let r = profile.param_at(profile.length() * i as f64 / m as f64);
            let n = ring_count(r, res, 3);
            let offset = (i % 2) as f64 * PI / n as f64;
            for q in ring(r, n, offset) {
                if obstacles.is_clear(q, STEINER_CLEARANCE * res) {
                    steiner.push(b.vertex(up(q, hub.z(r)))?);
                }
            }
        }
        let mut loops: Vec<&[u32]> = vec![rim_top, bore_top];
        loops.extend(footprints.iter().map(Vec::as_slice));
        let tris = triangulate_region(&b, &loops, &steiner, "impeller hub top")?;
        b.triangles(tris);
        Ok(b.finish())
    }
}

#[cfg(test)]
mod tests {
    use super::super::check;
    use super::*;

    /// Independent volume estimate: the hub by Pappus (∫ 2π r z_hub(r) dr, Simpson), plus each
    /// blade as the integral of the Jacobian of its continuous parametrisation
    /// (camber radius, across-thickness, height fraction), plus the two end half-cylinders.
    fn volume_estimate(imp: &Impeller) -> f64 {
        let hub = &imp.hub;
        let n = 4000;
        let h = (hub.rim - hub.bore) / n as f64;
        let mut hub_v = 0.0;
        for i in 0..=n {
            let r = hub.bore + h * i as f64;
            let w = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            hub_v += w * TAU * r * hub.z(r);
        }
        hub_v *= h / 3.0;

        let bl = &imp.blade;
        // Blade body: X(r, s, v) = C_v(r) + s w(v) N_v(r), z = z_hub(|p|) + v h(r).
        let body = |r: f64, s: f64, v: f64| -> [f64; 3] {
            let (c, t) = bl.camber(r, v);
            let w = bl.half_thickness(v) * s;
            let p = [c[0] - w * t[1], c[1] + w * t[0]];
            [p[0], p[1], hub.z(norm(p)) + v * bl.height(r)]
        };
        let mut blade_v = jacobian_integral(&body, [bl.r_in, bl.r_out], [-1.0, 1.0], 300, 4, 40);
        // End caps: half disks of radius w(v) around the camber ends.
        for (r_end, sign) in [(bl.r_in, -1.0), (bl.r_out, 1.0)] {
            let cap = |rho: f64, a: f64, v: f64| -> [f64; 3] {
                let (c, t) = bl.camber(r_end, v);
                let w = bl.half_thickness(v) * rho;
                let (sa, ca) = a.sin_cos();
                let d = [sign * t[0] * ca - t[1] * sa, sign * t[1] * ca + t[0] * sa];
                let p = [c[0] + w * d[0], c[1] + w * d[1]];
                [p[0], p[1], hub.z(norm(p)) + v * bl.height(r_end)]
            };
            blade_v += jacobian_integral(&cap, [0.0, 1.0], [-PI / 2.0, PI / 2.0], 20, 40, 40);
        }
        hub_v + f64::from(imp.blades) * blade_v
    }

    /// ∫∫∫ |det J| over a box, midpoint rule, central-difference Jacobian.
    fn jacobian_integral(
        f: &dyn Fn(f64, f64, f64) -> [f64; 3],
        a: [f64; 2],
        b: [f64; 2],
        na: usize,
        nb: usize,
        nv: usize,
    ) -> f64 {
        let (da, db, dv) = (
            (a[1] - a[0]) / na as f64,
            (b[1] - b[0]) / nb as f64,
            1.0 / nv as f64,
        );
        let mut sum = 0.0;
        for i in 0..na {
            let x = a[0] + da * (i as f64 + 0.5);
            for j in 0..nb {
                let y = b[0] + db * (j as f64 + 0.5);
                for k in 0..nv {
                    let v = dv * (k as f64 + 0.5);
                    let diff = |g: &dyn Fn(f64) -> [f64; 3], e: f64| {
                        let (p, q) = (g(e), g(-e));
                        nalgebra::Vector3::new(
                            (p[0] - q[0]) / (2.0 * e),
                            (p[1] - q[1]) / (2.0 * e),
                            (p[2] - q[2]) / (2.0 * e),
                        )
                    };
                    let ja = diff(&|e| f(x + e, y, v), 1e-5 * da);
                    let jb = diff(&|e| f(x, y + e, v), 1e-5 * db);
                    let jv = diff(&|e| f(x, y, v + e), 1e-5 * dv);
                    sum += ja.cross(&jb).dot(&jv).abs();
                }
            }
        }
        sum * da * db * dv
    }

    fn coarse() -> ImpellerParams {
        ImpellerParams {
            resolution: 3.0,
            ..ImpellerParams::default()
        }
    }

    fn other() -> ImpellerParams {
        ImpellerParams {
            blade_count: 9,
            bore_radius: 6.0,
            hub_radius: 38.0,
            hub_height: 15.0,
            blade_height: 16.0,
            blade_inner_radius: 11.0,
            wrap_angle_deg: -40.0,
            lean_angle_deg: -15.0,
            blade_thickness: 1.6,
            resolution: 1.5,
        }
    }

    /// Generates the part and runs every check: closed manifold, Euler characteristic, outward
    /// volume near the independent estimate, minimum angle, no self-intersections.
    fn check_part(p: &ImpellerParams, vol_tol: f64, min_angle: f64) -> check::Report {
        let mesh = impeller(p);
        let mesh = mesh.unwrap_or_else(|e| panic!("{e}"));
        let rep = check::closed_manifold(&mesh).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(rep.euler, 0, "genus 1 expected: {rep:?}");
        let est = volume_estimate(&Impeller::new(p).unwrap());
        let rel = (rep.volume - est) / est;
        println!(
            "impeller channel: narrowest gap between blades {:.2} mm",
            Impeller::new(p).unwrap().min_gap()
        );
        println!(
            "impeller res {}: {}; estimate {est:.1} mm³ ({:+.3} %)",
            p.resolution,
            rep.summary(),
            100.0 * rel
        );
        assert!(rep.min_edge > 1e-3, "{}", rep.summary());
        assert!(rep.volume > 0.0);
        assert!(rel.abs() < vol_tol, "volume {} vs {est}", rep.volume);
        assert!(rep.min_angle_deg > min_angle, "{rep:?}");
        // Cheap enough (sweep over x, then exact tests) to run at every resolution.
        let bad = check::self_intersections(&mesh, 10);
        assert!(bad.is_empty(), "self-intersecting pairs: {bad:?}");
        rep
    }

    fn impeller(p: &ImpellerParams) -> Result<Mesh, SampleError> {
        super::super::impeller(p)
    }

    #[test]
    fn default_is_closed_genus1_and_sized() {
        let p = ImpellerParams::default();
        let rep = check_part(&p, 0.01, 10.0);
        assert!((20_000..=60_000).contains(&rep.triangles), "{rep:?}");
        // The part is meant to be hard to machine: narrow channels between the blades.
        let gap = Impeller::new(&p).unwrap().min_gap();
        assert!((2.0..5.0).contains(&gap), "narrowest channel {gap} mm");
    }

    #[test]
    fn other_params_are_closed_genus1() {
        check_part(&other(), 0.01, 10.0);
    }

    /// Coarse versions (a few thousand triangles), as the planner's fast tests will use them.
    #[test]
    fn coarse_versions_are_valid() {
        for p in [
            coarse(),
            ImpellerParams {
                resolution: 2.5,
                ..other()
            },
        ] {
            let rep = check_part(&p, 0.03, 10.0);
            assert!(rep.triangles < 12_000, "{rep:?}");
        }
    }

    /// The checks can fail on this part: pushing one blade-tip vertex down through the hub
    /// keeps the topology valid but must be reported as self-intersecting.
    #[test]
    fn pushed_vertex_is_caught() {
        let mut m = impeller(&coarse()).unwrap();
        let top = (0..m.positions.len())
            .max_by(|&a, &b| m.positions[a].z.total_cmp(&m.positions[b].z))
            .unwrap();
        m.positions[top].z = -5.0;
        assert!(check::closed_manifold(&m).is_ok());
        assert!(!check::self_intersections(&m, 1).is_empty());
    }

    #[test]
    fn deterministic() {
        let p = ImpellerParams::default();
        let (a, b) = (impeller(&p).unwrap(), impeller(&p).unwrap());
        assert!(check::bitwise_equal(&a, &b));
    }

    #[test]
    fn invalid_parameters_are_errors() {
        let with = |f: &dyn Fn(&mut ImpellerParams)| {
            let mut p = ImpellerParams::default();
            f(&mut p);
            p
        };
        let cases = [
            (with(&|p| p.blade_count = 0), "blade_count"),
            (with(&|p| p.bore_radius = -1.0), "bore_radius"),
            (with(&|p| p.bore_radius = 50.0), "bore_radius"),
            (with(&|p| p.hub_radius = f64::NAN), "hub_radius"),
            (with(&|p| p.hub_height = 0.0), "hub_height"),
            (with(&|p| p.blade_height = f64::INFINITY), "blade_height"),
            (with(&|p| p.blade_inner_radius = 8.5), "blade_inner_radius"),
            (with(&|p| p.blade_inner_radius = 44.0), "blade_inner_radius"),
            (with(&|p| p.wrap_angle_deg = f64::NAN), "wrap_angle_deg"),
            (with(&|p| p.lean_angle_deg = 75.0), "lean_angle_deg"),
            (with(&|p| p.blade_thickness = -2.0), "blade_thickness"),
            (with(&|p| p.blade_thickness = 12.0), "blade_thickness"),
            (with(&|p| p.resolution = 0.0), "resolution"),
            (with(&|p| p.resolution = 20.0), "resolution"),
            (with(&|p| p.resolution = 0.01), "resolution"),
            // Blades that would overlap their neighbours.
            (with(&|p| p.blade_count = 30), "blade_count"),
            (with(&|p| p.blade_thickness = 7.0), "blade_count"),
        ];
        for (p, name) in cases {
            match impeller(&p) {
                Err(SampleError::InvalidParameter { name: n, reason }) => {
                    assert_eq!(n, name, "{reason}");
                    println!("{name}: {reason}");
                }
                other => panic!(
                    "{name}: expected an error, got {:?}",
                    other.map(|m| m.triangles.len())
                ),
            }
        }
    }

    /// Robustness sweep over 1620 parameter combinations (run with `--ignored`, ~15 s): each
    /// is either rejected with `InvalidParameter` or gives a closed genus-1 manifold, free of
    /// self-intersections at the coarse resolutions.
    #[test]
    #[ignore]
    fn sweep() {
        let mut ok = 0;
        let mut errs = std::collections::BTreeMap::new();
        let mut worst: f64 = 90.0;
        for n in [1u32, 3, 7, 12, 20] {
            for wrap in [-120.0, 0.0, 60.0, 200.0] {
                for lean in [-30.0, 0.0, 30.0] {
                    for t in [0.5, 2.0, 5.0] {
                        for res in [0.9, 2.0, 4.0] {
                            for ri in [9.0, 14.0, 25.0] {
                                let p = ImpellerParams {
                                    blade_count: n,
                                    wrap_angle_deg: wrap,
                                    lean_angle_deg: lean,
                                    blade_thickness: t,
                                    resolution: res,
                                    blade_inner_radius: ri,
                                    ..Default::default()
                                };
                                match impeller(&p) {
                                    Ok(m) => {
                                        let r = check::closed_manifold(&m)
                                            .unwrap_or_else(|e| panic!("{p:?}: {e}"));
                                        assert_eq!(r.euler, 0, "{p:?}");
                                        assert!(r.volume > 0.0);
                                        if p.resolution >= 2.5 {
                                            let bad = check::self_intersections(&m, 5);
                                            assert!(bad.is_empty(), "{p:?}: {bad:?}");
                                        }
                                        worst = worst.min(r.min_angle_deg);
                                        ok += 1;
                                    }
                                    Err(SampleError::InvalidParameter { name, .. }) => {
                                        *errs.entry(name).or_insert(0) += 1
                                    }
                                    Err(e) => panic!("{p:?}: {e}"),
                                }
                            }
                        }
                    }
                }
            }
        }
        println!("valid {ok}, rejected {errs:?}, worst angle {worst:.2}°");
    }
}
