//! The common 5-axis machines as one kinematic model: two rotary axes, each on the table side
//! (turning the part) or on the head side (turning the spindle), about lines given in the
//! machine frame. Table-table A/C and B/C trunnions, head-table machines (a B or A head over a C
//! table) and head-head machines (a C fork carrying an A or B head) are all a [`RotaryChain`];
//! `data/machines/*.toml` describe them ([`super::machine_file`]).
//!
//! # Frames
//!
//! *Home* is every rotary axis at 0°. At home the program's coordinates are the machine's, with
//! the origin where the work offset puts it, the tool points along +Z (from the tip towards the
//! spindle), and a rotary axis is the line through `point` along `direction` (right-handed
//! rotation by the joint angle; a machine whose axis turns the other way has the opposite
//! direction).
//!
//! * **Table side.** The table frame is the machine frame at home; the part's origin sits at
//!   `o = part_origin_in_table` in it. The first table axis (the cradle, nearest the bed) carries
//!   the second (the round table, which carries the part), so a part point `p` is at machine
//!   position `T(θ)(p + o)` with `T = L₁(θ₁) ∘ L₂(θ₂)`, where `L(θ)(x) = q + R(d, θ)(x − q)` turns
//!   about the line through `q` along `d`.
//! * **Head side.** Machine X, Y, Z command the head's reference point; the tip is at
//!   `XYZ + H(θ)(t)` with `H = L₁(θ₁) ∘ L₂(θ₂)` over the head axes (the first nearest the ram) and
//!   `t = (0, 0, −head_length)` at home: the pivot-to-tip length, the machine's pivot length plus
//!   the tool's gauge length. A machine without head axes has `head_length = 0`: X, Y, Z are the
//!   tip, the control's length compensation (G43) supplying the tool length.
//!
//! The tool axis `k` (part frame) therefore obeys `R_T(θ) k = R_H(θ) ẑ`, and the tip
//! `T(θ)(tip + o) = XYZ + H(θ)(t)`.
//!
//! # Inverse
//!
//! Every kind reduces the orientation to one equation `R(ω₁, θ₁) R(ω₂, θ₂) p = q` between unit
//! vectors (Paden–Kahan subproblem 2):
//!
//! | kind        | ω₁            | ω₂            | p    | q    | joints         |
//! |-------------|---------------|---------------|------|------|----------------|
//! | table-table | first table   | second table  | `k`  | `ẑ`  | `(θ₁, θ₂)`     |
//! | head-head   | first head    | second head   | `ẑ`  | `k`  | `(θ₁, θ₂)`     |
//! | head-table  | head          | table         | `k`  | `ẑ`  | `(−θ₁, θ₂)`    |
//!
//! The intermediate vector `c = R(ω₂, θ₂) p = R(ω₁, −θ₁) q` lies on both axes' cones
//! (`ω₂·c = ω₂·p`, `ω₁·c = ω₁·q`). It is found by turning about the *free* axis (below): for
//! the free second axis `c(θ₂) = p∥ + cos θ₂ p⊥ + sin θ₂ ω₂×p⊥` (the parts of `p` along and
//! across `ω₂`), and `ω₁·c = ω₁·q` reads `A cos θ₂ + B sin θ₂ = D`, so
//! `θ₂ = atan2(B, A) ± acos(D / √(A² + B²))`: two branches, none when `|D| > √(A² + B²)` (an axis
//! the machine cannot reach: axes that are not perpendicular reach a cone only). The free
//! first axis is the mirror image (`q` turned about `ω₁` by `−θ₁`). The other angle then
//! turns one vector onto another about one axis (subproblem 1: `θ = atan2(ω·(u′×v′), u′·v′)`
//! of the parts `u′`, `v′` normal to `ω`). Unlike the textbook solution through `ω₁×ω₂`, this
//! stays accurate to the last digits as the tool axis nears the free axis: for perpendicular
//! axes `D = 0` and the free angle is an `atan2` of the small but exact `A`, `B`.
//!
//! Among the branches and the 360° wraps of each axis inside its limits, the joints nearest the
//! previous ones are taken (`Δθ₁² + Δθ₂²`, degrees); without previous joints, the tilting axis
//! non-negative and the free axis in (−180°, 180°].
//!
//! # Singular cone
//!
//! The *free* axis is the one the tool axis can line up with: the second table axis
//! (table-table, head-table) or the first head axis (head-head). Along it the free angle does
//! not change the axis, so the exact inverse keeps the previous value. Near it the exact free
//! angle swings fast; [`MachineKinematics::inverse_relaxed`] keeps it near the preferred value
//! inside a cone of half-angle `singular_tolerance_deg`, moving the axis by at most the given
//! error and the tip not at all (the cone is documented in `docs/machines.md`).

use nalgebra::{Point3, Rotation3, Unit, Vector3};
use serde::{Deserialize, Serialize};

use super::kinematics::{
    Joints, KinematicsError, KinematicsKind, MachineKinematics, RotaryAxis, checked_axis,
    relaxed_free_angle, turns_within, within_limits,
};
use crate::geom::ToolPose;

/// Which side of the machine a rotary axis moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum AxisSide {
    /// It turns the part (a trunnion, cradle or round table).
    Table,
    /// It turns the spindle (a fork or swivel head).
    Head,
}

/// One rotary axis of a [`RotaryChain`].
#[derive(Clone, Debug, PartialEq)]
pub struct RotaryJoint {
    /// Its address letter in the program.
    pub letter: RotaryAxis,
    /// Table or head.
    pub side: AxisSide,
    /// Unit direction at home, machine frame (right-handed positive rotation).
    pub direction: Unit<Vector3<f64>>,
    /// A point on the axis at home, mm: machine frame for a table axis, relative to the head's
    /// reference point for a head axis.
    pub point: Vector3<f64>,
    /// Travel `(min, max)`, degrees; `None` = continuous.
    pub limits_deg: Option<(f64, f64)>,
}

/// A 5-axis machine with two rotary axes (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct RotaryChain {
    /// The kind, as machine files name it.
    pub kind: KinematicsKind,
    /// The first rotary axis: the cradle of a table-table machine, the head of a head-table
    /// machine, the ram-side axis of a head-head one. Its angle is [`Joints::a`].
    pub first: RotaryJoint,
    /// The second: the round table (table-table, head-table) or the spindle-side head axis
    /// (head-head). Its angle is [`Joints::c`].
    pub second: RotaryJoint,
    /// Where the part frame's origin sits in the table frame, mm.
    pub part_origin_in_table: Vector3<f64>,
    /// Head reference point to tool tip at home, mm (pivot length + tool gauge length); 0 on a
    /// machine without head axes.
    pub head_length: f64,
    /// Head reference point to the spindle's gauge line, mm (0 without head axes).
    pub pivot_length: f64,
    /// Linear travel `[(min, max); 3]` of X, Y, Z in program coordinates, mm; `None` = unchecked.
    pub travel: Option<[(f64, f64); 3]>,
    /// Half-angle of the cone about the free axis where the relaxed inverse may hold it, deg.
    pub singular_tolerance_deg: f64,
    /// A one-line name for program headers.
    pub name: String,
}

/// How far (radians, as `|v × ω|`) the tool axis may be from the free axis for the free angle
/// to count as undetermined.
const SINGULAR_EPS: f64 = 1e-12;

/// Which joint is free at the singularity, and the equation's layout.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Layout {
    /// `R₁(θ₁)R₂(θ₂)k = ẑ`, joints `(θ₁, θ₂)`, θ₂ free.
    TableTable,
    /// `R₁(θ₁)R₂(θ₂)ẑ = k`, joints `(θ₁, θ₂)`, θ₁ free.
    HeadHead,
    /// `R_h(−θ_h)R_t(θ_t)k = ẑ`, joints `(θ_h, θ_t) = (−θ₁, θ₂)`, θ₂ free.
    HeadTable,
}

/// A candidate solution in the equation's angles (degrees, before wrapping).
#[derive(Clone, Copy, Debug)]
struct Angles {
    first: f64,
    second: f64,
}

impl RotaryChain {
    fn layout(&self) -> Layout {
        match (self.first.side, self.second.side) {
            (AxisSide::Table, AxisSide::Table) => Layout::TableTable,
            (AxisSide::Head, AxisSide::Head) => Layout::HeadHead,
            _ => Layout::HeadTable,
        }
    }

    /// Checks the description: unit, non-parallel directions, finite points and ordered limits,
    /// a head-table machine listing its head first, no head length without a head.
    pub fn validate(&self) -> Result<(), KinematicsError> {
        let bad = |s: String| Err(KinematicsError::InvalidMachine(s));
        for joint in [&self.first, &self.second] {
            let l = joint.letter;
            if !joint
                .direction
                .iter()
                .chain(joint.point.iter())
                .all(|v| v.is_finite())
            {
                return bad(format!("axis {l}: direction and point must be finite"));
            }
            if (joint.direction.norm() - 1.0).abs() > 1e-9 {
                return bad(format!("axis {l}: direction is not a unit vector"));
            }
            if let Some((lo, hi)) = joint.limits_deg
                && !(lo.is_finite() && hi.is_finite() && lo <= hi && hi - lo <= 1e6)
            {
                return bad(format!(
                    "axis {l}: limits must be finite, ordered and at most 1e6 degrees apart"
                ));
            }
        }
        if self.first.letter == self.second.letter {
            return bad(format!("both rotary axes are called {}", self.first.letter));
        }
        if self.first.direction.cross(&self.second.direction).norm() < 1e-6 {
            return bad("the two rotary axes are parallel: they cannot tilt the tool".into());
        }
        if self.first.side == AxisSide::Table && self.second.side == AxisSide::Head {
            return bad(
                "a head-table machine lists its head axis first and its table axis second".into(),
            );
        }
        if !self.part_origin_in_table.iter().all(|v| v.is_finite()) {
            return bad("part_origin_in_table is not finite".into());
        }
        if !(self.head_length.is_finite() && self.head_length >= 0.0) {
            return bad("head length must be finite and >= 0".into());
        }
        if self.layout() == Layout::TableTable && self.head_length != 0.0 {
            return bad(
                "a table-table machine has no head length (G43 supplies the tool's)".into(),
            );
        }
        if let Some(travel) = self.travel
            && !travel
                .iter()
                .all(|&(lo, hi)| lo.is_finite() && hi.is_finite() && lo <= hi)
        {
            return bad("linear travel limits must be finite and ordered".into());
        }
        if !(self.singular_tolerance_deg.is_finite() && self.singular_tolerance_deg >= 0.0) {
            return bad("singular_tolerance_deg must be finite and >= 0".into());
        }
        Ok(())
    }

    /// The same machine with a tool of gauge length `gauge_mm` on a head of pivot length
    /// `pivot_mm` (no change on a table-table machine, where G43 carries the tool length).
    pub fn with_tool(mut self, pivot_mm: f64, gauge_mm: f64) -> Self {
        self.pivot_length = pivot_mm;
        self.with_gauge_length(gauge_mm)
    }

    /// The same machine with a tool of gauge length `gauge_mm` in place of the present one (the
    /// pivot length kept).
    pub fn with_gauge_length(mut self, gauge_mm: f64) -> Self {
        if self.layout() != Layout::TableTable {
            self.head_length = self.pivot_length + gauge_mm;
        }
        self
    }

    /// The same machine with the part clamped at `o` in the table frame.
    pub fn with_part_origin(mut self, o: Vector3<f64>) -> Self {
        self.part_origin_in_table = o;
        self
    }

    /// `(ω₁, ω₂, p, q)` of the orientation equation for part-frame axis `k`.
    fn equation(&self, k: &Vector3<f64>) -> [Vector3<f64>; 4] {
        let (w1, w2) = (
            self.first.direction.into_inner(),
            self.second.direction.into_inner(),
        );
        match self.layout() {
            Layout::TableTable | Layout::HeadTable => [w1, w2, *k, Vector3::z()],
            Layout::HeadHead => [w1, w2, Vector3::z(), *k],
        }
    }

    /// Joint angles from the equation's angles.
    fn joints_of(&self, a: Angles) -> (f64, f64) {
        match self.layout() {
            Layout::HeadTable => (-a.first, a.second),
            _ => (a.first, a.second),
        }
    }

    /// Equation angles from joint angles.
    fn angles_of(&self, first: f64, second: f64) -> Angles {
        match self.layout() {
            Layout::HeadTable => Angles {
                first: -first,
                second,
            },
            _ => Angles { first, second },
        }
    }

    /// Whether the free axis is the second (else the first).
    fn free_is_second(&self) -> bool {
        self.layout() != Layout::HeadHead
    }

    /// The exact solutions of the orientation equation (one or two branches), or the axis the
    /// machine cannot reach. `previous_free` is kept for an undetermined free angle.
    fn orientations(
        &self,
        k: &Vector3<f64>,
        previous_free: Option<f64>,
    ) -> Result<Vec<Angles>, KinematicsError> {
        let [w1, w2, p, q] = self.equation(k);
        let free_default = previous_free.unwrap_or(0.0);
        if self.free_is_second() && p.cross(&w2).norm() <= SINGULAR_EPS {
            // The axis lies along the free axis: θ₂ is free, c = p.
            let first = turn_angle(&w1, &p, &q).unwrap_or(0.0);
            return Ok(vec![Angles {
                first,
                second: free_default,
            }]);
        }
        if !self.free_is_second() && q.cross(&w1).norm() <= SINGULAR_EPS {
            let second = turn_angle(&w2, &p, &q).unwrap_or(0.0);
            return Ok(vec![Angles {
                first: free_default,
                second,
            }]);
        }
        // The free angle first: turning `v` (p about ω₂, or q about ω₁ backwards) by it must
        // bring it onto the cone `ω·c = d` of the other axis. `v(θ) = v∥ + cos θ v⊥ + sin θ
        // ω×v⊥` makes that `A cos θ + B sin θ = D`, solved by atan2, which stays accurate as
        // `v⊥` shrinks towards the singularity (for perpendicular axes `D = 0` exactly).
        let (free_axis, other_axis, v, target, sense) = if self.free_is_second() {
            (w2, w1, p, q, 1.0)
        } else {
            (w1, w2, q, p, -1.0)
        };
        let along = free_axis * free_axis.dot(&v);
        let across = v - along;
        let side = free_axis.cross(&across) * sense;
        let (a_, b_) = (other_axis.dot(&across), other_axis.dot(&side));
        let d_ = other_axis.dot(&target) - other_axis.dot(&along);
        let r = a_.hypot(b_);
        let ratio = d_ / r;
        if !ratio.is_finite() || ratio.abs() > 1.0 + 1e-9 {
            return Err(KinematicsError::Unreachable {
                axis: [k.x, k.y, k.z],
            });
        }
        let base = b_.atan2(a_);
        let spread = ratio.clamp(-1.0, 1.0).acos();
        let mut out = Vec::with_capacity(2);
        for free in [base + spread, base - spread] {
            let c = along + across * free.cos() + side * free.sin();
            let free_deg = free.to_degrees();
            let angles = if self.free_is_second() {
                turn_angle(&w1, &c, &q).map(|first| Angles {
                    first,
                    second: free_deg,
                })
            } else {
                turn_angle(&w2, &p, &c).map(|second| Angles {
                    first: free_deg,
                    second,
                })
            };
            if let Some(angles) = angles {
                out.push(angles);
            }
            if spread == 0.0 {
                break;
            }
        }
        if out.is_empty() {
            return Err(KinematicsError::NonFinite);
        }
        Ok(out)
    }

    /// Rotation of a head or table frame at the given joint angles (degrees): `R₁ R₂` over the
    /// axes on `side` (identity when that side has none).
    fn side_rotation(&self, side: AxisSide, first: f64, second: f64) -> Rotation3<f64> {
        let mut r = Rotation3::identity();
        for (joint, angle) in [(&self.first, first), (&self.second, second)] {
            if joint.side == side {
                r *= Rotation3::from_axis_angle(&joint.direction, angle.to_radians());
            }
        }
        r
    }

    /// The side's rigid motion applied to point `x` (turns about each axis line in turn, the
    /// axis nearest the part or tool first), or with `undo` its inverse (the other order, the
    /// opposite angles).
    fn side_motion(
        &self,
        side: AxisSide,
        first: f64,
        second: f64,
        x: &Vector3<f64>,
        undo: bool,
    ) -> Vector3<f64> {
        let mut turns = [(&self.second, second), (&self.first, first)];
        let sign = if undo {
            turns.reverse();
            -1.0
        } else {
            1.0
        };
        let mut v = *x;
        for (joint, angle) in turns {
            if joint.side == side {
                let r = Rotation3::from_axis_angle(&joint.direction, sign * angle.to_radians());
                v = joint.point + r * (v - joint.point);
            }
        }
        v
    }

    /// The tool tip relative to the head's reference point at the given angles.
    fn tip_from_head(&self, first: f64, second: f64) -> Vector3<f64> {
        let home = Vector3::new(0.0, 0.0, -self.head_length);
        self.side_motion(AxisSide::Head, first, second, &home, false)
    }

    /// The joints that put the tip at part point `tip` with rotary angles `(first, second)`.
    pub fn joints_at(&self, tip: &Point3<f64>, first: f64, second: f64) -> Joints {
        let on_table = self.side_motion(
            AxisSide::Table,
            first,
            second,
            &(tip.coords + self.part_origin_in_table),
            false,
        );
        let m = on_table - self.tip_from_head(first, second);
        Joints {
            x: m.x + 0.0,
            y: m.y + 0.0,
            z: m.z + 0.0,
            a: first + 0.0,
            c: second + 0.0,
        }
    }

    /// The 360° turns of `v` to consider on `joint` ([`turns_within`]).
    fn wraps(joint: &RotaryJoint, v: f64, reference: Option<f64>) -> Vec<f64> {
        turns_within(v, joint.limits_deg, reference)
    }

    /// Picks, among the branches and wraps inside the limits, the joints nearest `previous`
    /// (or the default branch), as joint angles.
    fn choose(
        &self,
        branches: &[Angles],
        previous: Option<&Joints>,
    ) -> Result<(f64, f64), KinematicsError> {
        let mut feasible = Vec::new();
        let mut first_ok = false;
        for b in branches {
            let (j1, j2) = self.joints_of(*b);
            let firsts = Self::wraps(&self.first, j1, previous.map(|p| p.a));
            first_ok |= !firsts.is_empty();
            for f in firsts {
                for s in Self::wraps(&self.second, j2, previous.map(|p| p.c)) {
                    feasible.push((f, s));
                }
            }
        }
        let free_second = self.free_is_second();
        let best = match previous {
            Some(p) => feasible.iter().copied().min_by(|u, v| {
                let cost = |w: &(f64, f64)| (w.0 - p.a).powi(2) + (w.1 - p.c).powi(2);
                cost(u)
                    .total_cmp(&cost(v))
                    .then(u.0.total_cmp(&v.0))
                    .then(u.1.total_cmp(&v.1))
            }),
            None => feasible.iter().copied().min_by(|u, v| {
                let split = |w: &(f64, f64)| if free_second { (w.0, w.1) } else { (w.1, w.0) };
                let ((tu, fu), (tv, fv)) = (split(u), split(v));
                let outside = |f: f64| !(f > -180.0 && f <= 180.0);
                (tu < 0.0)
                    .cmp(&(tv < 0.0))
                    .then(outside(fu).cmp(&outside(fv)))
                    .then(fu.abs().total_cmp(&fv.abs()))
                    .then(tu.abs().total_cmp(&tv.abs()))
                    .then(fu.total_cmp(&fv))
            }),
        };
        match best {
            Some(b) => Ok(b),
            None => {
                let (joint, value) = if first_ok {
                    (
                        &self.second,
                        branches.first().map_or(f64::NAN, |b| self.joints_of(*b).1),
                    )
                } else {
                    (
                        &self.first,
                        branches.first().map_or(f64::NAN, |b| self.joints_of(*b).0),
                    )
                };
                let (min_deg, max_deg) = joint.limits_deg.unwrap_or((f64::MIN, f64::MAX));
                Err(KinematicsError::OutOfLimits {
                    axis: joint.letter,
                    value_deg: value,
                    min_deg,
                    max_deg,
                })
            }
        }
    }

    /// The part-frame tool axis at joint angles `(first, second)`.
    pub fn axis_at(&self, first: f64, second: f64) -> Vector3<f64> {
        let table = self.side_rotation(AxisSide::Table, first, second);
        let head = self.side_rotation(AxisSide::Head, first, second);
        table.inverse() * (head * Vector3::z())
    }

    /// Travel check of the linear axes.
    fn check_travel(&self, j: &Joints) -> Result<(), KinematicsError> {
        let Some(travel) = self.travel else {
            return Ok(());
        };
        for ((letter, v), (lo, hi)) in ['X', 'Y', 'Z'].into_iter().zip([j.x, j.y, j.z]).zip(travel)
        {
            if v < lo - 1e-9 || v > hi + 1e-9 {
                return Err(KinematicsError::OutOfTravel {
                    axis: letter,
                    value_mm: v,
                    min_mm: lo,
                    max_mm: hi,
                });
            }
        }
        Ok(())
    }
}

/// Subproblem 1: the angle (degrees) turning `u` onto `v` about unit `w` (their parts normal to
/// `w`); `None` when `u` lies along `w` (any angle does).
fn turn_angle(w: &Vector3<f64>, u: &Vector3<f64>, v: &Vector3<f64>) -> Option<f64> {
    let u1 = u - w * w.dot(u);
    let v1 = v - w * w.dot(v);
    if u1.norm() <= SINGULAR_EPS || v1.norm() <= SINGULAR_EPS {
        return None;
    }
    Some(w.dot(&u1.cross(&v1)).atan2(u1.dot(&v1)).to_degrees())
}

impl MachineKinematics for RotaryChain {
    fn inverse(
        &self,
        pose: &ToolPose,
        previous: Option<&Joints>,
    ) -> Result<Joints, KinematicsError> {
        self.validate()?;
        let k = checked_axis(pose)?;
        if previous.is_some_and(|p| !p.is_finite()) {
            return Err(KinematicsError::NonFinite);
        }
        let previous_free = previous.map(|p| {
            let a = self.angles_of(p.a, p.c);
            if self.free_is_second() {
                a.second
            } else {
                a.first
            }
        });
        let branches = self.orientations(&k, previous_free)?;
        let (first, second) = self.choose(&branches, previous)?;
        Ok(self.joints_at(&pose.tip, first, second))
    }

    fn forward(&self, j: &Joints) -> ToolPose {
        let tip_machine = j.xyz() + self.tip_from_head(j.a, j.c);
        let tip = self.side_motion(AxisSide::Table, j.a, j.c, &tip_machine, true)
            - self.part_origin_in_table;
        ToolPose {
            tip: Point3::from(tip),
            axis: Unit::new_normalize(self.axis_at(j.a, j.c)),
        }
    }

    /// Near the free axis (angle `φ` between it and the tool axis below `2s`, `s` the smaller of
    /// the singular tolerance and `max_axis_error_deg`), the free angle may stay anywhere within
    /// `δ(φ)` of the exact one (free up to `s/2`, then narrowing linearly to 0 at `2s`, as on
    /// the A/C table-table machine), the point of that set nearest
    /// `preferred` being taken, and the other angle is the one that brings the axis nearest the
    /// pose's. For perpendicular axes the error is `asin(sin φ · |sin Δ|) ≤ s`; it is measured,
    /// and the exact inverse taken when it is not within `s` (axes at other angles) or the
    /// limits refuse.
    fn inverse_relaxed(
        &self,
        pose: &ToolPose,
        preferred: &Joints,
        max_axis_error_deg: f64,
    ) -> Result<Joints, KinematicsError> {
        self.validate()?;
        let k = checked_axis(pose)?;
        if !preferred.is_finite() || !max_axis_error_deg.is_finite() {
            return Err(KinematicsError::NonFinite);
        }
        let s = self.singular_tolerance_deg.min(max_axis_error_deg);
        let [w1, w2, p, q] = self.equation(&k);
        let free_second = self.free_is_second();
        let (free_dir, along) = if free_second { (w2, p) } else { (w1, q) };
        let cos = along.dot(&free_dir).abs().min(1.0);
        let phi = cos.acos().to_degrees();
        let Some(delta) = relaxed_free_angle(phi, s) else {
            return self.inverse(pose, Some(preferred));
        };
        let pref = self.angles_of(preferred.a, preferred.c);
        let pref_free = if free_second { pref.second } else { pref.first };
        let free = match self.orientations(&k, Some(pref_free)) {
            Ok(branches) if delta < 90.0 => {
                let exact = if free_second {
                    branches[0].second
                } else {
                    branches[0].first
                };
                let d = pref_free - exact;
                let n = (d / 180.0).round();
                let r = d - 180.0 * n;
                exact + 180.0 * n + r.clamp(-delta, delta)
            }
            _ => pref_free,
        };
        let angles = if free_second {
            let c = Rotation3::from_axis_angle(&Unit::new_unchecked(w2), free.to_radians()) * p;
            Angles {
                first: turn_angle(&w1, &c, &q).unwrap_or(pref.first),
                second: free,
            }
        } else {
            let c = Rotation3::from_axis_angle(&Unit::new_unchecked(w1), -free.to_radians()) * q;
            Angles {
                first: free,
                second: turn_angle(&w2, &p, &c).unwrap_or(pref.second),
            }
        };
        let (j1, j2) = self.joints_of(angles);
        // The tilting angle comes back from atan2 in (−180°, 180°]: bring it to the preferred turn.
        let j1 = j1 + 360.0 * ((preferred.a - j1) / 360.0).round();
        let j2 = j2 + 360.0 * ((preferred.c - j2) / 360.0).round();
        let error = crate::geom::angle_between(&self.axis_at(j1, j2), &k).to_degrees();
        let (Some(j1), Some(j2)) = (
            within_limits(j1, self.first.limits_deg),
            within_limits(j2, self.second.limits_deg),
        ) else {
            return self.inverse(pose, Some(preferred));
        };
        if error > s + 1e-9 {
            return self.inverse(pose, Some(preferred));
        }
        Ok(self.joints_at(&pose.tip, j1, j2))
    }

    fn inverse_all(
        &self,
        pose: &ToolPose,
        previous: Option<&Joints>,
    ) -> Result<Vec<Joints>, KinematicsError> {
        let nearest = self.inverse(pose, previous)?;
        let k = checked_axis(pose)?;
        let free = {
            let a = self.angles_of(nearest.a, nearest.c);
            if self.free_is_second() {
                a.second
            } else {
                a.first
            }
        };
        let mut all = vec![nearest];
        for b in self.orientations(&k, Some(free))? {
            let (j1, j2) = self.joints_of(b);
            for f in Self::wraps(&self.first, j1, previous.map(|p| p.a)) {
                for s in Self::wraps(&self.second, j2, previous.map(|p| p.c)) {
                    if !all
                        .iter()
                        .any(|o| (o.a - f).abs() < 1e-9 && (o.c - s).abs() < 1e-9)
                    {
                        all.push(self.joints_at(&pose.tip, f, s));
                    }
                }
            }
        }
        Ok(all)
    }

    fn check_limits(&self, j: &Joints) -> Result<(), KinematicsError> {
        if !j.is_finite() {
            return Err(KinematicsError::NonFinite);
        }
        for (joint, v) in [(&self.first, j.a), (&self.second, j.c)] {
            if let Some((lo, hi)) = joint.limits_deg
                && within_limits(v, joint.limits_deg).is_none()
            {
                return Err(KinematicsError::OutOfLimits {
                    axis: joint.letter,
                    value_deg: v,
                    min_deg: lo,
                    max_deg: hi,
                });
            }
        }
        self.check_travel(j)
    }

    fn rotary_axes(&self) -> Vec<RotaryAxis> {
        vec![self.first.letter, self.second.letter]
    }

    fn rotary_limits(&self) -> Vec<Option<(f64, f64)>> {
        vec![self.first.limits_deg, self.second.limits_deg]
    }

    fn description(&self) -> String {
        let axis = |j: &RotaryJoint| {
            let side = match j.side {
                AxisSide::Table => "table",
                AxisSide::Head => "head",
            };
            let d = j.direction;
            let limits = match j.limits_deg {
                None => "continuous".to_string(),
                Some((lo, hi)) => format!("{lo}..{hi} deg"),
            };
            format!(
                "{} {side} about ({}, {}, {}) {limits}",
                j.letter, d.x, d.y, d.z
            )
        };
        format!(
            "{} ({}): {}; {}; head length {} mm",
            self.name,
            self.kind.name(),
            axis(&self.first),
            axis(&self.second),
            self.head_length
        )
    }

    fn work_offset(&self) -> &str {
        "origin at the machine file's table reference point (its axis points are measured from it)"
    }

    fn joints_for_tip(&self, tip: &Point3<f64>, first: f64, second: f64) -> Joints {
        self.joints_at(tip, first, second)
    }

    fn has_head_axes(&self) -> bool {
        self.layout() != Layout::TableTable
    }
}
