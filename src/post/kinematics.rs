//! Machine kinematics: the map between a tool pose in the part frame and the joint values
//! (X, Y, Z, A, C) a controller is commanded with.
//!
//! # Table-table A/C convention
//!
//! ```text
//!            spindle (tool along machine +Z, never tilts)
//!               │
//!               ▼ tool tip = (X, Y, Z) in machine coordinates
//!        ┌─────────────┐   C: round table, turns about its own axis (table +Z)
//!        │   part      │
//!        └──────┬──────┘
//!   ════════════╪════════  A: cradle, turns about machine X
//!              pivot  = table-frame origin = where the A and C axes meet
//! ```
//!
//! * The tool always points along machine +Z. The cradle rotates by `A` about machine X; the
//!   round table, mounted on the cradle, rotates by `C` about its own axis (table +Z).
//! * The part is clamped on the C table; `part_origin_in_table` (`o`) is where the part
//!   frame's origin sits in the table frame.
//! * A part point `p` maps to the machine point
//!   `m = R_x(a) · R_z(c) · (p + o)`, with right-handed rotations
//!   `R_x(a) = [[1,0,0],[0,cos a,−sin a],[0,sin a,cos a]]`,
//!   `R_z(c) = [[cos c,−sin c,0],[sin c,cos c,0],[0,0,1]]`.
//! * The tool axis `k` (part frame) must map to machine +Z:
//!   `R_x(a) R_z(c) k = Z ⇔ k = R_z(−c) R_x(−a) Z = (sin a · sin c, sin a · cos c, cos a)`
//!   (the third row of `R = R_x(a) R_z(c)`; checked by the closed-form tests, e.g.
//!   `k = (0, sin 30°, cos 30°) ⇒ a = 30°, c = 0°` and `k = (1, 0, 0) ⇒ a = 90°, c = 90°`).
//! * Machine X, Y, Z are the tool **tip** in machine coordinates, measured from the pivot
//!   (the work offset must put its origin at the pivot); the controller applies tool length
//!   compensation (G43).
//!
//! Inverse: with `h = √(k_x² + k_y²)`, `a = atan2(h, k_z) ∈ [0°, 180°]`, `c = atan2(k_x, k_y)`,
//! and the second branch `(−a, c + 180°)` gives the same axis. [`TableTableAC::inverse`] picks,
//! among the branches and the 360° wraps of C that are inside the limits, the one closest to the
//! previous joints (squared degree distance `Δa² + Δc²`), or, without previous joints, `a ≥ 0`
//! and `c ∈ (−180°, 180°]`.
//!
//! Singularity: when the tool axis is parallel to the C axis (`sin a = 0`) C is free; the exact
//! inverse keeps the previous C (the axis does not depend on `c` there, so the forward map stays
//! exact). Near it the exact C swings fast between neighbouring poses; the linearisation uses
//! [`MachineKinematics::inverse_relaxed`], which trades a bounded axis error for a calm C inside
//! the `singular_tolerance_deg` cone (see its docs).
//!
//! All joint angles are in **degrees**, as the controller sees them.

use nalgebra::{Matrix3, Point3, Unit, Vector3};
use serde::{Deserialize, Serialize};

use crate::geom::ToolPose;

/// The kinds of machine the post knows, as a job file names them (`machine.kinematics`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum KinematicsKind {
    /// Tool along machine Z; a cradle tilts by A about X, the round table on it turns by C
    /// ([`TableTableAC`]).
    #[default]
    TableTableAc,
    /// Three linear axes, the tool fixed along machine +Z ([`ThreeAxis`]): 2.5D contour
    /// programs.
    ThreeAxis,
    /// Tool along machine Z; a trunnion tilts by B about Y, the round table on it turns by C
    /// ([`super::RotaryChain`]).
    TableTableBc,
    /// A head tilting by B about Y over a round table turning by C.
    HeadTableBc,
    /// A head tilting by A about X over a round table turning by C.
    HeadTableAc,
    /// Both rotary axes in the head: a fork turning about Z carrying a head tilting about X or Y.
    HeadHead,
}

impl KinematicsKind {
    /// `true` when the kind can tilt the tool (has rotary axes).
    pub fn is_five_axis(self) -> bool {
        self != KinematicsKind::ThreeAxis
    }

    /// The name job and machine files use.
    pub fn name(self) -> &'static str {
        match self {
            KinematicsKind::TableTableAc => "table-table-ac",
            KinematicsKind::ThreeAxis => "three-axis",
            KinematicsKind::TableTableBc => "table-table-bc",
            KinematicsKind::HeadTableBc => "head-table-bc",
            KinematicsKind::HeadTableAc => "head-table-ac",
            KinematicsKind::HeadHead => "head-head",
        }
    }
}

/// Horizontal component `√(k_x² + k_y²)` of the tool axis (part frame) at or below which the
/// exact inverse treats the pose as singular and keeps the previous C. Choosing C freely there
/// moves the forward-kinematics axis by at most this much (radians), far below the 1e-9
/// round-trip accuracy.
pub const SINGULAR_AXIS_EPS: f64 = 1e-12;

/// Slack (degrees) allowed when testing a joint value against a limit, to absorb rounding of
/// poses that sit exactly on a limit; values within the slack are clamped onto the limit.
pub const LIMIT_SLACK_DEG: f64 = 1e-9;

/// A rotary axis name, used in errors and G-code words.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum RotaryAxis {
    /// Rotation about machine X.
    A,
    /// Rotation about machine Y.
    B,
    /// Rotation about machine (or table) Z.
    C,
}

impl std::fmt::Display for RotaryAxis {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = match self {
            RotaryAxis::A => "A",
            RotaryAxis::B => "B",
            RotaryAxis::C => "C",
        };
        f.write_str(s)
    }
}

/// Errors of the kinematic maps.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum KinematicsError {
    /// No branch (and no 360° wrap of C) puts the rotary axes inside their limits.
    #[error("axis {axis} would need {value_deg:.4}° but its limits are [{min_deg}°, {max_deg}°]")]
    OutOfLimits {
        /// The axis that cannot reach the pose.
        axis: RotaryAxis,
        /// The value (degrees) the pose needs on that axis (first branch).
        value_deg: f64,
        /// Lower limit (degrees).
        min_deg: f64,
        /// Upper limit (degrees).
        max_deg: f64,
    },
    /// The pose or joints contain NaN or infinite values.
    #[error("non-finite pose or joint values")]
    NonFinite,
    /// The machine cannot tilt the tool to the pose's axis (a 3-axis machine keeps it along +Z).
    #[error("the tool axis is {angle_deg:.6}° from +Z and this machine cannot tilt the tool")]
    FixedAxis {
        /// Angle between the pose's axis and +Z, degrees.
        angle_deg: f64,
    },
    /// The machine description is inconsistent (e.g. limits not ordered, negative tolerance).
    #[error("invalid machine description: {0}")]
    InvalidMachine(String),
    /// No setting of the rotary axes turns the tool to this axis (axes that are not
    /// perpendicular reach a cone only).
    #[error("the machine cannot turn the tool to the axis ({:.6}, {:.6}, {:.6})", axis[0], axis[1], axis[2])]
    Unreachable {
        /// The part-frame tool axis asked for.
        axis: [f64; 3],
    },
    /// A linear axis would leave its travel.
    #[error("axis {axis} would need {value_mm:.4} mm but its travel is [{min_mm}, {max_mm}] mm")]
    OutOfTravel {
        /// X, Y or Z.
        axis: char,
        /// The position the move needs, mm.
        value_mm: f64,
        /// Lower travel limit, mm.
        min_mm: f64,
        /// Upper travel limit, mm.
        max_mm: f64,
    },
}

/// Joint values as the controller sees them: linear axes in mm, rotary axes in **degrees**.
///
/// For the table-table A/C machine, `a` is the cradle angle and `c` the round-table angle.
/// (Machines with other rotary pairs will reuse the two rotary slots with their own names;
/// see [`MachineKinematics::rotary_axes`].)
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Joints {
    /// Machine X (mm).
    pub x: f64,
    /// Machine Y (mm).
    pub y: f64,
    /// Machine Z (mm).
    pub z: f64,
    /// First rotary axis (degrees); A on an A/C machine.
    pub a: f64,
    /// Second rotary axis (degrees); C on an A/C machine.
    pub c: f64,
}

impl Joints {
    /// Linear interpolation in joint space (what the controller does between two blocks).
    pub fn lerp(&self, other: &Joints, t: f64) -> Joints {
        let l = |p: f64, q: f64| p + (q - p) * t;
        Joints {
            x: l(self.x, other.x),
            y: l(self.y, other.y),
            z: l(self.z, other.z),
            a: l(self.a, other.a),
            c: l(self.c, other.c),
        }
    }

    /// The linear axes as a vector (mm).
    pub fn xyz(&self) -> Vector3<f64> {
        Vector3::new(self.x, self.y, self.z)
    }

    /// `true` when every value is finite.
    pub fn is_finite(&self) -> bool {
        [self.x, self.y, self.z, self.a, self.c]
            .iter()
            .all(|v| v.is_finite())
    }
}

/// A 5-axis machine's kinematic model. Implemented for [`TableTableAC`]; B/C table-table,
/// head-table and head-head machines fit the same trait.
pub trait MachineKinematics {
    /// Exact inverse kinematics: the joints that put the tool tip at `pose.tip` with the tool
    /// along `pose.axis` (part frame). Chooses the branch and rotary wrap closest to `previous`
    /// among those inside the limits; without `previous`, a machine-specific default branch.
    fn inverse(
        &self,
        pose: &ToolPose,
        previous: Option<&Joints>,
    ) -> Result<Joints, KinematicsError>;

    /// Forward kinematics: the part-frame pose the joints produce.
    fn forward(&self, joints: &Joints) -> ToolPose;

    /// Whether some joints inside the limits hold the tool tip at `tip` along `axis` (part
    /// frame): what the planners ask of every candidate axis. The default solves the inverse.
    fn reaches_axis(&self, tip: &Point3<f64>, axis: &Vector3<f64>) -> bool {
        let pose = ToolPose {
            tip: *tip,
            axis: Unit::new_normalize(*axis),
        };
        self.inverse(&pose, None).is_ok()
    }

    /// Singularity-relaxed inverse used by linearisation: like [`Self::inverse`] with
    /// `preferred` as the previous joints, but near the singularity the machine may keep the
    /// rotary axes close to `preferred` at the cost of an axis error of at most
    /// `max_axis_error_deg` (the tip stays exact). The default is the exact inverse.
    fn inverse_relaxed(
        &self,
        pose: &ToolPose,
        preferred: &Joints,
        max_axis_error_deg: f64,
    ) -> Result<Joints, KinematicsError> {
        let _ = max_axis_error_deg;
        self.inverse(pose, Some(preferred))
    }

    /// Checks joint values against the machine's limits.
    fn check_limits(&self, joints: &Joints) -> Result<(), KinematicsError>;

    /// Every joint solution for `pose` inside the limits: both branches, and every turn of a
    /// limited rotary axis (a continuous one at the turn nearest `previous`). Where a pass
    /// starts, linearisation tries them in turn when the nearest cannot carry the pass within
    /// the limits. The default is the exact inverse alone.
    fn inverse_all(
        &self,
        pose: &ToolPose,
        previous: Option<&Joints>,
    ) -> Result<Vec<Joints>, KinematicsError> {
        Ok(vec![self.inverse(pose, previous)?])
    }

    /// Names of the rotary axes, in the order of [`Joints::a`] and [`Joints::c`]: two on a
    /// 5-axis machine, none on a 3-axis one (whose joints keep `a = c = 0`).
    fn rotary_axes(&self) -> Vec<RotaryAxis>;

    /// The limits (degrees) of the rotary axes, in the order of [`Self::rotary_axes`];
    /// `None` for a continuous axis.
    fn rotary_limits(&self) -> Vec<Option<(f64, f64)>> {
        vec![None; self.rotary_axes().len()]
    }

    /// The joints that put the tool tip at part point `tip` with the rotary axes at `first`,
    /// `second` (degrees): what the linear axes must do for a given orientation (the machine
    /// positions behind a tool-centre-point program).
    fn joints_for_tip(&self, tip: &Point3<f64>, first: f64, second: f64) -> Joints;

    /// One-line human description (for program headers).
    fn description(&self) -> String;

    /// `true` when a rotary axis turns the spindle: joint output then carries the tool length
    /// in X, Y, Z, and length compensation stays off.
    fn has_head_axes(&self) -> bool {
        false
    }

    /// Where the work offset's origin must be for the program's coordinates to mean what the
    /// post assumed (for program headers).
    fn work_offset(&self) -> &str;
}

/// How far (degrees) the free rotary angle may stray from its exact value, mod 180°, when the
/// tool axis is `phi` degrees from the free axis and the axis may err by `s` degrees; `None`
/// beyond `2s`, where the exact inverse is taken. Straying by `δ` tilts the axis by
/// `asin(sin φ · |sin δ|)`.
///
/// Free (90°) up to `s/2`, then narrowing linearly to 0 at `2s`: `δ = 90°·(2s − φ)/(1.5 s)`.
/// The error `φ·sin δ` is then at most 0.9 s (greatest near φ = 1.2 s), and the angle narrows
/// at 60°/s per degree of `φ`, so a free angle held near the previous pose's value follows
/// the exact one at a bounded rate. (Allowing the whole `s` from `φ = s`, `δ = asin(s/φ)`,
/// narrows at an unbounded rate there: the free angle would have to swing through tens of
/// degrees between two poses a hair apart, which no block short enough can follow.)
pub(crate) fn relaxed_free_angle(phi: f64, s: f64) -> Option<f64> {
    if s <= 0.0 || phi >= 2.0 * s {
        None
    } else if phi <= 0.5 * s {
        Some(90.0)
    } else {
        Some(90.0 * (2.0 * s - phi) / (1.5 * s))
    }
}

/// A 3-axis machine: the tool along machine +Z, machine X, Y, Z = the tool tip in the part
/// frame (the work offset's origin at the part origin). Poses must have the axis +Z.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ThreeAxis;

/// Largest angle (radians) between a pose's axis and +Z that [`ThreeAxis`] accepts: round-off
/// of a vertical axis, nothing a tilted tool could produce.
pub const VERTICAL_AXIS_EPS: f64 = 1e-9;

impl MachineKinematics for ThreeAxis {
    fn inverse(
        &self,
        pose: &ToolPose,
        _previous: Option<&Joints>,
    ) -> Result<Joints, KinematicsError> {
        let (t, k) = (pose.tip, pose.axis.into_inner());
        if !(t.coords.iter().chain(k.iter()).all(|v| v.is_finite())) {
            return Err(KinematicsError::NonFinite);
        }
        let angle = crate::geom::angle_between(&k, &Vector3::z());
        if angle > VERTICAL_AXIS_EPS {
            return Err(KinematicsError::FixedAxis {
                angle_deg: angle.to_degrees(),
            });
        }
        Ok(Joints {
            x: t.x,
            y: t.y,
            z: t.z,
            a: 0.0,
            c: 0.0,
        })
    }

    fn forward(&self, j: &Joints) -> ToolPose {
        ToolPose {
            tip: Point3::new(j.x, j.y, j.z),
            axis: Unit::new_unchecked(Vector3::z()),
        }
    }

    fn check_limits(&self, joints: &Joints) -> Result<(), KinematicsError> {
        if joints.is_finite() {
            Ok(())
        } else {
            Err(KinematicsError::NonFinite)
        }
    }

    fn rotary_axes(&self) -> Vec<RotaryAxis> {
        Vec::new()
    }

    fn joints_for_tip(&self, tip: &Point3<f64>, _first: f64, _second: f64) -> Joints {
        Joints {
            x: tip.x,
            y: tip.y,
            z: tip.z,
            a: 0.0,
            c: 0.0,
        }
    }

    fn description(&self) -> String {
        "3-axis: tool along +Z".to_string()
    }

    fn work_offset(&self) -> &str {
        "origin at the part origin"
    }
}

/// Table-table A/C 5-axis machine (tool fixed along +Z, A cradle about X carrying a C round
/// table). See the module docs for the convention and formulas.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TableTableAC {
    /// Where the part frame's origin sits in the table frame (mm); the table frame's origin
    /// is the pivot, where the A and C axes meet. Serialised as `[x, y, z]`.
    #[serde(with = "vec3_as_array")]
    pub part_origin_in_table: Vector3<f64>,
    /// A limits `(min, max)` in degrees.
    pub a_limits_deg: (f64, f64),
    /// C limits `(min, max)` in degrees; `None` means continuous (unlimited) C.
    pub c_limits_deg: Option<(f64, f64)>,
    /// Half-angle (degrees) of the cone around the C axis where C is treated as nearly free
    /// by [`MachineKinematics::inverse_relaxed`]. Default 0.05°.
    pub singular_tolerance_deg: f64,
}

impl Default for TableTableAC {
    /// Pivot at the part origin, A in [−120°, 120°], continuous C, singular tolerance 0.05°.
    fn default() -> Self {
        TableTableAC {
            part_origin_in_table: Vector3::zeros(),
            a_limits_deg: (-120.0, 120.0),
            c_limits_deg: None,
            singular_tolerance_deg: 0.05,
        }
    }
}

/// Serde for `Vector3<f64>` as `[x, y, z]` (nalgebra's own serde feature is not enabled).
mod vec3_as_array {
    use nalgebra::Vector3;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(v: &Vector3<f64>, s: S) -> Result<S::Ok, S::Error> {
        [v.x, v.y, v.z].serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vector3<f64>, D::Error> {
        let [x, y, z] = <[f64; 3]>::deserialize(d)?;
        Ok(Vector3::new(x, y, z))
    }
}

/// One inverse-kinematics candidate.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    a: f64,
    c: f64,
}

impl TableTableAC {
    /// A machine with the given part offset and the [`Default`] limits.
    pub fn new(part_origin_in_table: Vector3<f64>) -> Self {
        TableTableAC {
            part_origin_in_table,
            ..TableTableAC::default()
        }
    }

    /// Sets the A limits (degrees).
    pub fn with_a_limits(mut self, min_deg: f64, max_deg: f64) -> Self {
        self.a_limits_deg = (min_deg, max_deg);
        self
    }

    /// Sets the C limits (degrees); `None` = continuous C.
    pub fn with_c_limits(mut self, limits: Option<(f64, f64)>) -> Self {
        self.c_limits_deg = limits;
        self
    }

    /// Sets the singular tolerance (degrees).
    pub fn with_singular_tolerance(mut self, deg: f64) -> Self {
        self.singular_tolerance_deg = deg;
        self
    }

    /// Checks the description: finite ordered limits, non-negative finite tolerance.
    pub fn validate(&self) -> Result<(), KinematicsError> {
        let bad = |s: &str| Err(KinematicsError::InvalidMachine(s.to_string()));
        if !self.part_origin_in_table.iter().all(|v| v.is_finite()) {
            return bad("part_origin_in_table is not finite");
        }
        let (lo, hi) = self.a_limits_deg;
        if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
            return bad("A limits must be finite and ordered");
        }
        if let Some((lo, hi)) = self.c_limits_deg
            && !(lo.is_finite() && hi.is_finite() && lo <= hi && hi - lo <= 1e6)
        {
            return bad("C limits must be finite, ordered and at most 1e6 degrees apart");
        }
        if !(self.singular_tolerance_deg.is_finite() && self.singular_tolerance_deg >= 0.0) {
            return bad("singular_tolerance_deg must be finite and >= 0");
        }
        Ok(())
    }

    /// `R = R_x(a) · R_z(c)` (angles in degrees): maps table-frame vectors to machine ones.
    pub fn rotation(a_deg: f64, c_deg: f64) -> Matrix3<f64> {
        let (sa, ca) = a_deg.to_radians().sin_cos();
        let (sc, cc) = c_deg.to_radians().sin_cos();
        Matrix3::new(cc, -sc, 0.0, ca * sc, ca * cc, -sa, sa * sc, sa * cc, ca)
    }

    /// The joints for rotary values `(a, c)`: tip mapped to machine coordinates.
    fn joints_for(&self, pose: &ToolPose, a: f64, c: f64) -> Joints {
        let m = Self::rotation(a, c) * (pose.tip.coords + self.part_origin_in_table);
        Joints {
            x: m.x,
            y: m.y,
            z: m.z,
            a,
            c,
        }
    }

    /// Snaps `v` onto `[lo, hi]` if within [`LIMIT_SLACK_DEG`]; `None` if outside.
    fn within(v: f64, (lo, hi): (f64, f64)) -> Option<f64> {
        within_limits(v, Some((lo, hi)))
    }

    /// The 360° wraps of `c` to consider ([`turns_within`] of the C limits).
    fn c_wraps(&self, c: f64, reference: Option<f64>) -> Vec<f64> {
        turns_within(c, self.c_limits_deg, reference)
    }

    /// The two joint branches for unit axis `k` (before C wrapping): tilt A one way or the
    /// other, C turned half a turn between them.
    fn branches(k: &Vector3<f64>, previous: Option<&Joints>) -> [Candidate; 2] {
        let h = k.x.hypot(k.y);
        let tilt = h.atan2(k.z).to_degrees(); // in [0, 180]
        if h <= SINGULAR_AXIS_EPS {
            // Singular: C is free; keep the previous C (the axis does not depend on it). Both
            // tilt signs give the same axis; a = ±0 or ±180 with unchanged C.
            let c = previous.map_or(0.0, |p| p.c);
            [Candidate { a: tilt, c }, Candidate { a: -tilt, c }]
        } else {
            let c = atan2_deg(k.x, k.y);
            [
                Candidate { a: tilt, c },
                Candidate {
                    a: -tilt,
                    c: c + 180.0,
                },
            ]
        }
    }

    /// Picks the best candidate among `branches` (values before C wrapping).
    fn choose(
        &self,
        branches: &[Candidate],
        previous: Option<&Joints>,
    ) -> Result<Candidate, KinematicsError> {
        let mut feasible: Vec<Candidate> = Vec::new();
        let mut a_ok = false;
        for b in branches {
            let Some(a) = Self::within(b.a, self.a_limits_deg) else {
                continue;
            };
            a_ok = true;
            for c in self.c_wraps(b.c, previous.map(|p| p.c)) {
                feasible.push(Candidate { a, c });
            }
        }
        let best = match previous {
            Some(p) => feasible.iter().copied().min_by(|u, v| {
                let cost = |w: &Candidate| (w.a - p.a).powi(2) + (w.c - p.c).powi(2);
                cost(u)
                    .total_cmp(&cost(v))
                    .then((u.a < 0.0).cmp(&(v.a < 0.0)))
                    .then(u.c.total_cmp(&v.c))
            }),
            None => feasible.iter().copied().min_by(|u, v| {
                let outside = |w: &Candidate| !(w.c > -180.0 && w.c <= 180.0);
                (u.a < 0.0)
                    .cmp(&(v.a < 0.0))
                    .then(outside(u).cmp(&outside(v)))
                    .then(u.c.abs().total_cmp(&v.c.abs()))
                    .then(u.c.total_cmp(&v.c))
            }),
        };
        match best {
            Some(b) => Ok(b),
            None if !a_ok => {
                let (min_deg, max_deg) = self.a_limits_deg;
                Err(KinematicsError::OutOfLimits {
                    axis: RotaryAxis::A,
                    value_deg: branches.first().map_or(f64::NAN, |b| b.a),
                    min_deg,
                    max_deg,
                })
            }
            None => {
                let (min_deg, max_deg) = self.c_limits_deg.unwrap_or((f64::MIN, f64::MAX));
                Err(KinematicsError::OutOfLimits {
                    axis: RotaryAxis::C,
                    value_deg: branches.first().map_or(f64::NAN, |b| b.c),
                    min_deg,
                    max_deg,
                })
            }
        }
    }

    /// Validates a pose and returns its axis as a plain vector.
    fn checked_axis(pose: &ToolPose) -> Result<Vector3<f64>, KinematicsError> {
        checked_axis(pose)
    }
}

/// A pose's axis as a plain vector, once tip and axis are known finite.
pub(super) fn checked_axis(pose: &ToolPose) -> Result<Vector3<f64>, KinematicsError> {
    let k = pose.axis.into_inner();
    if k.iter()
        .chain(pose.tip.coords.iter())
        .all(|v| v.is_finite())
    {
        Ok(k)
    } else {
        Err(KinematicsError::NonFinite)
    }
}

/// `v` snapped onto `limits` (degrees) when within [`LIMIT_SLACK_DEG`] of them, `None` outside;
/// `v` itself for a continuous axis (`None` limits).
pub(super) fn within_limits(v: f64, limits: Option<(f64, f64)>) -> Option<f64> {
    match limits {
        None => Some(v),
        Some((lo, hi)) if v >= lo - LIMIT_SLACK_DEG && v <= hi + LIMIT_SLACK_DEG => {
            Some(v.clamp(lo, hi))
        }
        Some(_) => None,
    }
}

/// The 360° turns of angle `v` (degrees) an axis with `limits` may take: for a continuous axis
/// the one nearest `reference` (or, without one, the one in (−180°, 180°]); for a limited one
/// every turn inside the limits.
pub(super) fn turns_within(v: f64, limits: Option<(f64, f64)>, reference: Option<f64>) -> Vec<f64> {
    match limits {
        None => vec![match reference {
            Some(r) => v + 360.0 * ((r - v) / 360.0).round(),
            None => normalize_deg(v),
        }],
        Some((lo, hi)) => {
            let k0 = ((lo - LIMIT_SLACK_DEG - v) / 360.0).ceil() as i64;
            let k1 = ((hi + LIMIT_SLACK_DEG - v) / 360.0).floor() as i64;
            (k0..=k1)
                .filter_map(|k| within_limits(v + 360.0 * k as f64, limits))
                .collect()
        }
    }
}

/// Whether angle `v` (degrees) has a 360° turn within `limits` ([`turns_within`] not empty).
pub(super) fn has_turn_within(v: f64, limits: Option<(f64, f64)>) -> bool {
    match limits {
        None => true,
        Some((lo, hi)) => {
            let k0 = ((lo - LIMIT_SLACK_DEG - v) / 360.0).ceil() as i64;
            let k1 = ((hi + LIMIT_SLACK_DEG - v) / 360.0).floor() as i64;
            (k0..=k1).any(|k| within_limits(v + 360.0 * k as f64, limits).is_some())
        }
    }
}

/// An angle (degrees) wrapped into `(−180°, 180°]`, without negative zero.
pub(super) fn normalize_deg(d: f64) -> f64 {
    let w = d - 360.0 * (d / 360.0).round(); // in [−180, 180]
    if w <= -180.0 { w + 360.0 } else { w + 0.0 }
}

/// `atan2` in degrees normalised to `(−180°, 180°]` (so `−0.0` and `−180°` never appear).
fn atan2_deg(y: f64, x: f64) -> f64 {
    normalize_deg(y.atan2(x).to_degrees())
}

impl MachineKinematics for TableTableAC {
    fn inverse(
        &self,
        pose: &ToolPose,
        previous: Option<&Joints>,
    ) -> Result<Joints, KinematicsError> {
        self.validate()?;
        let k = Self::checked_axis(pose)?;
        if previous.is_some_and(|p| !p.is_finite()) {
            return Err(KinematicsError::NonFinite);
        }
        let best = self.choose(&Self::branches(&k, previous), previous)?;
        // `+ 0.0` turns a −0.0 into +0.0.
        Ok(self.joints_for(pose, best.a + 0.0, best.c + 0.0))
    }

    /// Either branch's A inside the limits with a turn of its C inside C's: what
    /// [`Self::inverse`] asks before it builds the joints (the linear axes have no limits).
    fn reaches_axis(&self, tip: &Point3<f64>, axis: &Vector3<f64>) -> bool {
        if self.validate().is_err() || !axis.iter().chain(tip.coords.iter()).all(|v| v.is_finite())
        {
            return false;
        }
        let k = axis.normalize();
        Self::branches(&k, None).iter().any(|b| {
            Self::within(b.a, self.a_limits_deg).is_some()
                && has_turn_within(b.c, self.c_limits_deg)
        })
    }

    fn forward(&self, j: &Joints) -> ToolPose {
        let r = Self::rotation(j.a, j.c);
        let tip = r.transpose() * j.xyz() - self.part_origin_in_table;
        // Third row of R = R^T · Z = (sin a sin c, sin a cos c, cos a): unit by construction.
        let axis = Unit::new_unchecked(Vector3::new(r[(2, 0)], r[(2, 1)], r[(2, 2)]));
        ToolPose {
            tip: Point3::from(tip),
            axis,
        }
    }

    /// Relaxed inverse for the A/C table-table machine.
    ///
    /// Let `φ` be the angle between the tool axis and the C axis line (`min(tilt, 180° − tilt)`)
    /// and `s = min(singular_tolerance_deg, max_axis_error_deg)`. With C fixed at some value,
    /// the best A is `a = atan2(k_x sin c + k_y cos c, k_z)` and the axis error is
    /// `asin(sin φ · |sin(c − c_exact)|)`; C may be anywhere within `δ(φ)` of `c_exact`
    /// (mod 180°: free up to `s/2`, then narrowing linearly to 0 at `2s`), which keeps that
    /// error within `0.9 s`, and the point of that set nearest `preferred.c` is chosen. `δ` narrows at a bounded rate as the axis leaves
    /// the pole, so C turns at a bounded rate too and linearisation converges through and
    /// around the pole instead of chasing the exact C's half-turn. The tip stays exact. Falls
    /// back to the exact inverse when the relaxed joints would leave the limits.
    fn inverse_relaxed(
        &self,
        pose: &ToolPose,
        preferred: &Joints,
        max_axis_error_deg: f64,
    ) -> Result<Joints, KinematicsError> {
        self.validate()?;
        let k = Self::checked_axis(pose)?;
        if !preferred.is_finite() || !max_axis_error_deg.is_finite() {
            return Err(KinematicsError::NonFinite);
        }
        let s = self.singular_tolerance_deg.min(max_axis_error_deg);
        let h = k.x.hypot(k.y);
        let tilt = h.atan2(k.z).to_degrees();
        let phi = tilt.min(180.0 - tilt);
        let Some(delta) = relaxed_free_angle(phi, s) else {
            return self.inverse(pose, Some(preferred));
        };
        let c = if h <= SINGULAR_AXIS_EPS || delta >= 90.0 {
            preferred.c
        } else {
            let c_exact = atan2_deg(k.x, k.y);
            let d = preferred.c - c_exact;
            let n = (d / 180.0).round();
            let r = d - 180.0 * n; // in [−90, 90]
            c_exact + 180.0 * n + r.clamp(-delta, delta)
        };
        let (sc, cc) = c.to_radians().sin_cos();
        let a = (k.x * sc + k.y * cc).atan2(k.z).to_degrees();
        let (Some(a), Some(c)) = (
            Self::within(a, self.a_limits_deg),
            self.c_limits_deg.map_or(Some(c), |l| Self::within(c, l)),
        ) else {
            return self.inverse(pose, Some(preferred));
        };
        Ok(self.joints_for(pose, a + 0.0, c + 0.0))
    }

    fn inverse_all(
        &self,
        pose: &ToolPose,
        previous: Option<&Joints>,
    ) -> Result<Vec<Joints>, KinematicsError> {
        let nearest = self.inverse(pose, previous)?;
        let k = Self::checked_axis(pose)?;
        let h = k.x.hypot(k.y);
        let tilt = h.atan2(k.z).to_degrees();
        let c0 = if h <= SINGULAR_AXIS_EPS {
            nearest.c
        } else {
            atan2_deg(k.x, k.y)
        };
        let mut all = vec![nearest];
        for (a, c) in [(tilt, c0), (-tilt, c0 + 180.0)] {
            let Some(a) = Self::within(a, self.a_limits_deg) else {
                continue;
            };
            for c in self.c_wraps(c, previous.map(|p| p.c)) {
                let j = self.joints_for(pose, a + 0.0, c + 0.0);
                if !all
                    .iter()
                    .any(|o| (o.a - j.a).abs() < 1e-9 && (o.c - j.c).abs() < 1e-9)
                {
                    all.push(j);
                }
            }
        }
        Ok(all)
    }

    fn check_limits(&self, j: &Joints) -> Result<(), KinematicsError> {
        if !j.is_finite() {
            return Err(KinematicsError::NonFinite);
        }
        let (lo, hi) = self.a_limits_deg;
        if Self::within(j.a, (lo, hi)).is_none() {
            return Err(KinematicsError::OutOfLimits {
                axis: RotaryAxis::A,
                value_deg: j.a,
                min_deg: lo,
                max_deg: hi,
            });
        }
        if let Some((lo, hi)) = self.c_limits_deg
            && Self::within(j.c, (lo, hi)).is_none()
        {
            return Err(KinematicsError::OutOfLimits {
                axis: RotaryAxis::C,
                value_deg: j.c,
                min_deg: lo,
                max_deg: hi,
            });
        }
        Ok(())
    }

    fn rotary_axes(&self) -> Vec<RotaryAxis> {
        vec![RotaryAxis::A, RotaryAxis::C]
    }

    fn rotary_limits(&self) -> Vec<Option<(f64, f64)>> {
        vec![Some(self.a_limits_deg), self.c_limits_deg]
    }

    fn joints_for_tip(&self, tip: &Point3<f64>, first: f64, second: f64) -> Joints {
        self.joints_for(
            &ToolPose {
                tip: *tip,
                axis: Unit::new_unchecked(Vector3::z()),
            },
            first,
            second,
        )
    }

    fn work_offset(&self) -> &str {
        "origin at the rotary pivot"
    }

    fn description(&self) -> String {
        let o = self.part_origin_in_table;
        let c = match self.c_limits_deg {
            None => "continuous".to_string(),
            Some((lo, hi)) => format!("{lo}..{hi} deg"),
        };
        format!(
            "table-table A/C: tool +Z, A about X, C on cradle; part origin in table ({}, {}, {}) mm; A {}..{} deg; C {}",
            o.x, o.y, o.z, self.a_limits_deg.0, self.a_limits_deg.1, c
        )
    }
}
