//! Feed control from engagement (seed 004 ch. 5 step 8): "the feed rate will be adjusted so
//! that a uniform cutting force is maintained", with a mechanistic cutting-force model
//! (DeVor et al. 1980, as the seed cites).
//!
//! **The model.** A cutter of diameter D turning at n rev/min and fed at f mm/min through
//! material whose cross-section across the feed is A mm² (the volume a move removes per mm
//! of travel, measured by the stock model) removes Q = A·f mm³/min. The tangential force on
//! the flutes is proportional to the chip area they cut, F = K_t·(chip area). Averaged over
//! a revolution, the chips of all teeth add up to the volume removed, so the power is
//! P = K_t·Q and the mean tangential force at the periphery, P over the cutting speed
//! v = π·D·n, is
//!
//! ```text
//!     F = K_t · A · f / (π · D · n)        [N, with K_t in N/mm², A in mm², f and v in mm/min]
//! ```
//!
//! K_t is the material's specific cutting force (`[cutting] specific_force`; 800 N/mm² for
//! aluminium 7075 at roughing chip loads, about 2000 for Ti-6Al-4V, 3000 for Inconel 718).
//! Holding F at a target F* sets each move's feed to f = F*·π·D·n / (K_t·A). The target by
//! default is the force of the tool's nominal cut: half its diameter wide, half its diameter
//! deep, at the programmed pass feed. Feeds rise where a move takes less than that (the thin
//! rest of a terrace, a loop's light side) and fall where it takes more (a full slot, a corner).
//!
//! **Limits.** Every feed stays within the machine's `[min_feed, max_feed]`. A pass through
//! air goes at `max_feed`. Moves programmed slower than the pass feed (ramps into material)
//! are only ever slowed, never sped up: their feed is bounded by what the tool can take
//! axially, which this model does not see. A finishing tool's cutting moves are only slowed
//! too ([`Cutter::speed_up`] off): their feed per tooth also sets the surface the ball leaves,
//! which the force does not. Rapids are left alone. A move that removes material even at
//! `min_feed` above the target is reported (`over_target_at_min_feed`).
//!
//! This stage takes plain data: the moves and the volume each removes (from
//! [`crate::stock::Stock::remove_cutting`] on the stock the operations before leave), and
//! returns the feeds and what they change.

use serde::Serialize;

use crate::geom::{MoveKind, Toolpath};

/// The cutting model and the machine's feed limits.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct CuttingModel {
    /// K_t: tangential force per mm² of chip area, N/mm².
    pub specific_force: f64,
    /// F*: the mean tangential force to hold, N; `None`: the tool's nominal cut's (module docs).
    pub target_force: Option<f64>,
    /// The machine's feed limits, mm/min.
    pub min_feed: f64,
    pub max_feed: f64,
}

impl Default for CuttingModel {
    /// Aluminium 7075 on a machine that feeds 100 to 6000 mm/min.
    fn default() -> Self {
        CuttingModel {
            specific_force: 800.0,
            target_force: None,
            min_feed: 100.0,
            max_feed: 6000.0,
        }
    }
}

impl CuttingModel {
    /// The mean tangential force of a move that removes `area` mm² across its travel at
    /// `feed` mm/min with a cutter of `diameter` mm at `spindle_rpm`.
    pub fn force(&self, area: f64, feed: f64, diameter: f64, spindle_rpm: f64) -> f64 {
        self.specific_force * area * feed / (std::f64::consts::PI * diameter * spindle_rpm)
    }

    /// The target force for a cutter of `diameter` at `spindle_rpm` whose passes are
    /// programmed at `pass_feed`: the explicit one, or the nominal cut's (D/2 × D/2).
    pub fn target(&self, diameter: f64, spindle_rpm: f64, pass_feed: f64) -> f64 {
        self.target_force.unwrap_or_else(|| {
            self.force(0.25 * diameter * diameter, pass_feed, diameter, spindle_rpm)
        })
    }

    /// Why the model cannot be used, if it cannot.
    pub fn validate(&self) -> Result<(), String> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !positive(self.specific_force) {
            return Err(format!(
                "specific_force must be a positive number of N/mm², got {}",
                self.specific_force
            ));
        }
        if let Some(t) = self.target_force
            && !positive(t)
        {
            return Err(format!(
                "target_force must be a positive number of N, got {t}"
            ));
        }
        if !(positive(self.min_feed) && self.max_feed.is_finite() && self.min_feed < self.max_feed)
        {
            return Err(format!(
                "the feed limits must satisfy 0 < min_feed < max_feed, got {} and {}",
                self.min_feed, self.max_feed
            ));
        }
        Ok(())
    }
}

/// The tool and how its moves were programmed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cutter {
    pub diameter: f64,
    pub spindle_rpm: f64,
    /// The feed of its passes; moves programmed slower (entries) are only slowed.
    pub pass_feed: f64,
    /// Rapid rate, mm/min, for the time of the rapids.
    pub rapid_feed: f64,
    /// Whether cutting passes lighter than the target may go faster than programmed (up to
    /// `max_feed`): yes for roughing, no for finishing (module docs). Passes through air go
    /// at `max_feed` either way.
    pub speed_up: bool,
}

/// A distribution of forces over the moves that cut, N.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ForceSpread {
    pub max: f64,
    pub p99: f64,
    pub mean: f64,
    /// max / mean: 1 is a perfectly even load.
    pub max_over_mean: f64,
}

impl ForceSpread {
    fn of(mut forces: Vec<f64>) -> ForceSpread {
        if forces.is_empty() {
            return ForceSpread::default();
        }
        forces.sort_by(f64::total_cmp);
        let n = forces.len();
        let mean = forces.iter().sum::<f64>() / n as f64;
        let max = forces[n - 1];
        ForceSpread {
            max,
            p99: forces[((n as f64 * 0.99) as usize).min(n - 1)],
            mean,
            max_over_mean: if mean > 0.0 { max / mean } else { 0.0 },
        }
    }
}

/// What feed control changed for one tool's moves.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FeedReport {
    pub model: CuttingModel,
    pub target_force_n: f64,
    /// At the programmed feeds, and at the controlled ones, with rapids at the rapid rate, s.
    pub time_before_s: f64,
    pub time_after_s: f64,
    /// The mean tangential force of the moves that cut, before and after.
    pub force_before: ForceSpread,
    pub force_after: ForceSpread,
    pub moves_slower: usize,
    pub moves_faster: usize,
    /// Passes through air, now at the maximum feed.
    pub moves_in_air: usize,
    /// Moves whose force stays above the target even at the minimum feed.
    pub over_target_at_min_feed: usize,
}

/// The feeds that hold `model`'s target force along `toolpath`, whose k-th move removes
/// `removed[k]` mm³ (`removed[0]`, where the tool starts, is ignored); `skin` is the volume
/// below which a move counts as cutting air (the stock model's round-off), mm³. Returns one
/// feed per move (rapids keep theirs) and the report.
pub fn control_feeds(
    toolpath: &Toolpath,
    removed: &[f64],
    cutter: &Cutter,
    model: &CuttingModel,
    skin: f64,
) -> (Vec<f64>, FeedReport) {
    let moves = &toolpath.moves;
    let target = model.target(cutter.diameter, cutter.spindle_rpm, cutter.pass_feed);
    let mut feeds: Vec<f64> = moves.iter().map(|m| m.feed).collect();
    let (mut before, mut after) = (Vec::new(), Vec::new());
    let mut report = FeedReport {
        model: *model,
        target_force_n: target,
        time_before_s: 0.0,
        time_after_s: 0.0,
        force_before: ForceSpread::default(),
        force_after: ForceSpread::default(),
        moves_slower: 0,
        moves_faster: 0,
        moves_in_air: 0,
        over_target_at_min_feed: 0,
    };
    for k in 1..moves.len() {
        let m = &moves[k];
        let length = (m.pose.tip - moves[k - 1].pose.tip).norm();
        if m.kind == MoveKind::Rapid || m.feed <= 0.0 {
            let t = 60.0 * length / cutter.rapid_feed;
            report.time_before_s += t;
            report.time_after_s += t;
            continue;
        }
        // Entries keep at most their programmed feed; passes may go up to the machine's in air,
        // and when cutting if the tool may speed up.
        let air_cap = if m.feed < cutter.pass_feed {
            m.feed
        } else {
            model.max_feed
        };
        let cap = if cutter.speed_up {
            air_cap
        } else {
            air_cap.min(m.feed)
        };
        let volume = removed.get(k).copied().unwrap_or(0.0);
        let feed = if length <= 0.0 {
            m.feed
        } else if volume <= skin {
            if air_cap > m.feed {
                report.moves_in_air += 1;
            }
            air_cap
        } else {
            let area = volume / length;
            before.push(model.force(area, m.feed, cutter.diameter, cutter.spindle_rpm));
            let ideal = target * std::f64::consts::PI * cutter.diameter * cutter.spindle_rpm
                / (model.specific_force * area);
            if ideal < model.min_feed {
                report.over_target_at_min_feed += 1;
            }
            let feed = ideal.clamp(model.min_feed, cap.max(model.min_feed));
            after.push(model.force(area, feed, cutter.diameter, cutter.spindle_rpm));
            feed
        };
        if feed < m.feed {
            report.moves_slower += 1;
        } else if feed > m.feed {
            report.moves_faster += 1;
        }
        feeds[k] = feed;
        if length > 0.0 {
            report.time_before_s += 60.0 * length / m.feed;
            report.time_after_s += 60.0 * length / feed;
        }
    }
    report.force_before = ForceSpread::of(before);
    report.force_after = ForceSpread::of(after);
    (feeds, report)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{Move, Point3, ToolPose, Vector3};

    fn path(points: &[(f64, MoveKind, f64)]) -> Toolpath {
        Toolpath {
            tool_id: 1,
            moves: points
                .iter()
                .map(|&(x, kind, feed)| Move {
                    pose: ToolPose {
                        tip: Point3::new(x, 0.0, 0.0),
                        axis: nalgebra::Unit::new_normalize(Vector3::z()),
                    },
                    kind,
                    feed,
                })
                .collect(),
        }
    }

    const CUTTER: Cutter = Cutter {
        diameter: 10.0,
        spindle_rpm: 8000.0,
        pass_feed: 2000.0,
        rapid_feed: 15000.0,
        speed_up: true,
    };

    /// The force is K_t·A·f/(πDn): a D10 at 8000 rev/min taking 5 × 5 mm at 2000 mm/min in
    /// aluminium (800 N/mm²) pulls 800·25·2000/(π·10·8000) ≈ 159.2 N, the nominal target;
    /// a full slot (10 × 5) at the same feed twice that.
    #[test]
    fn the_force_is_the_specific_force_times_the_removal_rate_over_the_cutting_speed() {
        let model = CuttingModel::default();
        let nominal = 800.0 * 25.0 * 2000.0 / (std::f64::consts::PI * 10.0 * 8000.0);
        assert!((model.target(10.0, 8000.0, 2000.0) - nominal).abs() < 1e-9);
        assert!((model.force(50.0, 2000.0, 10.0, 8000.0) - 2.0 * nominal).abs() < 1e-9);
    }

    /// A rapid, then five 10 mm moves: a nominal cut, a slot, a skim, air, and a ramp in a
    /// slot, with the volume each removes.
    fn five_moves() -> (Toolpath, [f64; 7]) {
        let p = path(&[
            (0.0, MoveKind::Rapid, 15000.0),
            (10.0, MoveKind::Rapid, 15000.0),
            (20.0, MoveKind::Cut, 2000.0),
            (30.0, MoveKind::Cut, 2000.0),
            (40.0, MoveKind::Cut, 2000.0),
            (50.0, MoveKind::Cut, 2000.0),
            (60.0, MoveKind::Cut, 800.0),
        ]);
        // Volumes over 10 mm: 25 mm², 50 mm², 2.5 mm², air, 50 mm².
        (p, [0.0, 0.0, 250.0, 500.0, 25.0, 0.0, 500.0])
    }

    /// Five 10 mm moves: a rapid, a nominal cut, a slot, a skim, air, and a ramp in a slot.
    /// The slot halves its feed, the skim (a tenth of the area) goes to the machine's limit,
    /// air to the limit, the ramp halves too but is never sped up; every cutting move that
    /// is not at a limit then pulls exactly the target.
    #[test]
    fn feeds_hold_the_target_within_the_limits() {
        let (p, removed) = five_moves();
        let model = CuttingModel::default();
        let (feeds, r) = control_feeds(&p, &removed, &CUTTER, &model, 1e-6);
        assert_eq!(feeds[1], 15000.0);
        assert!((feeds[2] - 2000.0).abs() < 1e-9);
        assert!((feeds[3] - 1000.0).abs() < 1e-9);
        assert_eq!(feeds[4], 6000.0); // 20000 wanted, the machine's limit
        assert_eq!(feeds[5], 6000.0); // air
        assert!((feeds[6] - 800.0).abs() < 1e-9); // the slot wants 1000: the ramp keeps 800
        assert_eq!((r.moves_slower, r.moves_faster, r.moves_in_air), (1, 2, 1));
        assert!((r.force_after.max - r.target_force_n).abs() < 1e-9);
        assert!((r.force_before.max - 2.0 * r.target_force_n).abs() < 1e-9);
        // Time: 10 mm at each feed, s.
        let t = |f: f64| 600.0 / f;
        let before = t(15000.0) + 4.0 * t(2000.0) + t(800.0);
        let after = t(15000.0) + t(2000.0) + t(1000.0) + 2.0 * t(6000.0) + t(800.0);
        assert!((r.time_before_s - before).abs() < 1e-9);
        assert!((r.time_after_s - after).abs() < 1e-9);
    }

    /// A finishing tool on the same moves: the slot and the ramp are slowed as before, the
    /// skim keeps its programmed feed (no faster for a light cut), air still goes at the limit.
    #[test]
    fn a_finishing_tool_is_only_slowed_where_it_cuts() {
        let (p, removed) = five_moves();
        let finishing = Cutter {
            speed_up: false,
            ..CUTTER
        };
        let (feeds, r) = control_feeds(&p, &removed, &finishing, &Default::default(), 1e-6);
        assert_eq!(feeds[2], 2000.0);
        assert!((feeds[3] - 1000.0).abs() < 1e-9);
        assert_eq!(feeds[4], 2000.0);
        assert_eq!(feeds[5], 6000.0);
        assert!((feeds[6] - 800.0).abs() < 1e-9);
        assert_eq!((r.moves_slower, r.moves_faster, r.moves_in_air), (1, 1, 1));
        assert!(r.force_after.max <= r.target_force_n + 1e-9);
    }

    /// A cut too heavy for the target even at the minimum feed is reported, at the minimum.
    #[test]
    fn a_cut_beyond_the_target_at_the_minimum_feed_is_reported() {
        let p = path(&[(0.0, MoveKind::Cut, 2000.0), (1.0, MoveKind::Cut, 2000.0)]);
        let model = CuttingModel {
            target_force: Some(1.0),
            ..Default::default()
        };
        let (feeds, r) = control_feeds(&p, &[0.0, 100.0], &CUTTER, &model, 1e-6);
        assert_eq!(feeds[1], model.min_feed);
        assert_eq!(r.over_target_at_min_feed, 1);
        assert!(model.validate().is_ok());
        assert!(
            CuttingModel {
                min_feed: 7000.0,
                ..model
            }
            .validate()
            .is_err()
        );
    }
}
