//! The depth safety net's decisions, as a record a user can write out (`eventtrack6d track --fallback-trace`):
//! at every fresh depth frame, the event-driven estimate, the depth-only candidates that could replace it, how
//! many model points the depth image confirms for each, and which one the tracker kept.

use nalgebra::Isometry3;
use std::fmt::Write as _;

/// Where a depth-only candidate's refinement started.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FallbackStart {
    /// The estimate at the previous depth frame.
    PreviousDepthPose,
    /// The estimate at the previous depth frame carried on at the tracker's velocity (measured between depth
    /// frames and updated by every tick since).
    Extrapolated,
    /// The estimate at the previous depth frame carried on at the motion between the two depth frames before,
    /// which the events since cannot have changed.
    AnchoredMotion,
}

/// Most depth-only candidates a safety-net check refines (one per [`FallbackStart`]).
pub const FALLBACK_STARTS: usize = 3;

/// The safety net's settings for choosing between the estimate and its candidates
/// ([`DepthFallbackCheck::replacement`]); the `depth_fallback_*` fields of [`crate::track::TrackerConfig`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FallbackRule {
    /// How much more agreeing a candidate must be than the estimate to replace it.
    pub margin: f64,
    /// How far below the best motion agreement a candidate's may fall and still compete; negative: no limit.
    pub motion_margin: f64,
    /// How far below the best candidate's motion agreement the estimate's may fall before the surroundings are
    /// taken to contradict it; negative: never.
    pub estimate_motion_margin: f64,
    /// Weight of the events' verdict in a candidate's score (0: depth alone).
    pub event_weight: f64,
}

impl FallbackStart {
    /// Name in the trace CSV (`previous`, `extrapolated`, `anchored`).
    pub fn as_str(self) -> &'static str {
        match self {
            Self::PreviousDepthPose => "previous",
            Self::Extrapolated => "extrapolated",
            Self::AnchoredMotion => "anchored",
        }
    }
}

/// One depth-only candidate of a safety-net check.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FallbackCandidate {
    /// Where its refinement started.
    pub start: FallbackStart,
    /// The refined pose, `T_cam_obj` (event camera frame), metres.
    pub pose: Isometry3<f64>,
    /// Fraction of the model's visible points the depth image confirms at `pose`, among those not hidden by a
    /// nearer measurement (at least 30 % of them), in [0, 1].
    pub agreeing: f64,
    /// Fraction of the previous frame's moved surfaces the depth image confirms under the motion to `pose`, in
    /// [0, 1] ([`crate::recon::MovingNeighbourhood::motion_agreement`]); `None` when too few could be scored or
    /// the check is off.
    pub motion_agreeing: Option<f64>,
    /// Fraction of the estimate's outline points that land, at `pose`, within two ROI bins of a kept recent event
    /// ([`crate::refine::EventEdges::contour_support`]), in [0, 1]; `None` without events in the ROI. The rule
    /// uses it only with a positive `depth_fallback_event_weight`.
    pub event_support: Option<f64>,
}

/// One object's safety-net check at one fresh depth frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DepthFallbackCheck {
    /// Index of the object (as in [`super::PoseEstimate::object`]).
    pub object: usize,
    /// Time the poses are at, microseconds on the event camera's clock: the depth frame's exposure (a tick).
    pub t_us: i64,
    /// Tick the check was made at, microseconds: `t_us` for a frame on time, later for a frame that arrived after
    /// its own tick (checked at its exposure, where it shows the object, or tracked again from there: the tick that
    /// tracked again).
    pub tick_us: i64,
    /// The event-driven estimate before the check, `T_cam_obj`, metres.
    pub estimate: Isometry3<f64>,
    /// The same agreeing fraction for `estimate` as [`FallbackCandidate::agreeing`].
    pub estimate_agreeing: f64,
    /// The same motion agreement for `estimate` as [`FallbackCandidate::motion_agreeing`].
    pub estimate_motion_agreeing: Option<f64>,
    /// The same event support for `estimate` as [`FallbackCandidate::event_support`].
    pub estimate_event_support: Option<f64>,
    /// The candidates, in the order they were refined (`None`: that start is not configured).
    pub candidates: [Option<FallbackCandidate>; FALLBACK_STARTS],
    /// Index into `candidates` of the one that replaced the estimate; `None` if the estimate was kept.
    pub replaced_by: Option<usize>,
}

/// Header of the fallback trace CSV.
pub const FALLBACK_TRACE_HEADER: &str = "t_us,object,estimate_x,estimate_y,estimate_z,estimate_agreeing,start,candidate_x,candidate_y,candidate_z,candidate_agreeing,rotation_to_estimate_deg,replaced,estimate_motion_agreeing,candidate_motion_agreeing,estimate_qx,estimate_qy,estimate_qz,estimate_qw,candidate_qx,candidate_qy,candidate_qz,candidate_qw,estimate_event_support,candidate_event_support,tick_us";

impl DepthFallbackCheck {
    /// Index into `candidates` of the one that replaces the estimate, by the safety net's `rule`; `None` keeps it.
    ///
    /// A candidate is eligible unless the surroundings contradict its motion: its motion agreement is more than
    /// `rule.motion_margin` below the best of the estimate's and the candidates' ([`Self::motion_allows`]). Each
    /// eligible candidate scores its `agreeing` plus `rule.event_weight` times how much better the events support
    /// it than the estimate (`event_support` difference; no bonus when either support is unknown or the weight is
    /// 0). The best-scoring one (on a tie the first) replaces the estimate if its score exceeds the estimate's
    /// `agreeing` by more than `rule.margin`, or whatever the scores if the surroundings contradict the estimate's
    /// own motion ([`Self::estimate_contradicted`]).
    pub fn replacement(&self, rule: &FallbackRule) -> Option<usize> {
        let eligible = |c: &FallbackCandidate| self.motion_allows(c, rule.motion_margin);
        let mut best: Option<(usize, f64)> = None;
        for (k, c) in self.candidates.iter().enumerate() {
            let Some(c) = c.filter(eligible) else {
                continue;
            };
            let event_bonus = match (c.event_support, self.estimate_event_support) {
                (Some(v), Some(e)) if rule.event_weight > 0.0 => rule.event_weight * (v - e),
                _ => 0.0,
            };
            let score = c.agreeing + event_bonus;
            if best.is_none_or(|(_, b)| score > b) {
                best = Some((k, score));
            }
        }
        let contradicted = self.estimate_contradicted(rule.estimate_motion_margin);
        best.filter(|&(_, b)| contradicted || b > self.estimate_agreeing + rule.margin)
            .map(|(k, _)| k)
    }

    /// Whether the surroundings contradict the estimate's motion since the previous depth frame: its motion
    /// agreement is more than `estimate_motion_margin` below the best candidate's (either unknown, or a negative
    /// margin: not contradicted). An estimate that jumped onto the hand in front of the object can agree with
    /// more depth points than the object itself, mostly hidden behind that hand, yet the surfaces around it do not
    /// move the way the jump says.
    pub fn estimate_contradicted(&self, estimate_motion_margin: f64) -> bool {
        match (self.estimate_motion_agreeing, self.best_candidate_motion()) {
            (Some(e), Some(c)) if estimate_motion_margin >= 0.0 => e < c - estimate_motion_margin,
            _ => false,
        }
    }

    /// Whether the motion check lets `candidate` compete ([`Self::replacement`]): its motion agreement is at most
    /// `motion_margin` below the best of the estimate's and the candidates' (its own or all unknown, or a negative
    /// `motion_margin`: it may).
    pub fn motion_allows(&self, candidate: &FallbackCandidate, motion_margin: f64) -> bool {
        match (self.best_motion_agreeing(), candidate.motion_agreeing) {
            (Some(m), Some(x)) if motion_margin >= 0.0 => x >= m - motion_margin,
            _ => true,
        }
    }

    /// The best motion agreement of any hypothesis, the estimate's or a candidate's; `None` if all are unknown.
    fn best_motion_agreeing(&self) -> Option<f64> {
        self.best_candidate_motion()
            .into_iter()
            .chain(self.estimate_motion_agreeing)
            .reduce(f64::max)
    }

    /// The best motion agreement of the candidates; `None` if all are unknown.
    fn best_candidate_motion(&self) -> Option<f64> {
        self.candidates
            .iter()
            .flatten()
            .filter_map(|c| c.motion_agreeing)
            .reduce(f64::max)
    }

    /// Appends one CSV row per candidate (columns of [`FALLBACK_TRACE_HEADER`]) to `out`; `name` is the object's
    /// name. Positions are the translations of the poses, metres; `rotation_to_estimate_deg` is the angle between
    /// the candidate's and the estimate's orientation; the last eight columns are the two orientations as unit
    /// quaternions (x, y, z, w), so each row holds both whole poses, followed by the two event supports and the
    /// tick the check was made at.
    pub fn write_csv_rows(&self, name: &str, out: &mut String) {
        let e = self.estimate.translation.vector;
        let eq = self.estimate.rotation.coords;
        for (k, c) in self.candidates.iter().enumerate() {
            let Some(c) = c else { continue };
            let p = c.pose.translation.vector;
            let cq = c.pose.rotation.coords;
            let angle = c
                .pose
                .rotation
                .angle_to(&self.estimate.rotation)
                .to_degrees();
            // Writing into a String cannot fail.
            let _ = writeln!(
                out,
                "{},{},{:.6},{:.6},{:.6},{:.4},{},{:.6},{:.6},{:.6},{:.4},{:.3},{},{},{},{:.7},{:.7},{:.7},{:.7},{:.7},{:.7},{:.7},{:.7},{},{},{}",
                self.t_us,
                name,
                e.x,
                e.y,
                e.z,
                self.estimate_agreeing,
                c.start.as_str(),
                p.x,
                p.y,
                p.z,
                c.agreeing,
                angle,
                u8::from(self.replaced_by == Some(k)),
                optional_fraction(self.estimate_motion_agreeing),
                optional_fraction(c.motion_agreeing),
                eq.x,
                eq.y,
                eq.z,
                eq.w,
                cq.x,
                cq.y,
                cq.z,
                cq.w,
                optional_fraction(self.estimate_event_support),
                optional_fraction(c.event_support),
                self.tick_us,
            );
        }
    }
}

/// A fraction with four decimals, or nothing (an empty CSV field) when unknown.
fn optional_fraction(v: Option<f64>) -> String {
    v.map(|v| format!("{v:.4}")).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion, Vector3};

    #[test]
    fn one_row_per_candidate_and_only_the_replacing_one_is_marked() {
        let estimate = Isometry3::from_parts(
            Translation3::new(0.1, -0.02, 0.6),
            UnitQuaternion::identity(),
        );
        let turned = Isometry3::from_parts(
            Translation3::new(0.12, -0.02, 0.61),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 10f64.to_radians()),
        );
        let check = DepthFallbackCheck {
            object: 0,
            t_us: 33_833,
            tick_us: 58_833,
            estimate,
            estimate_agreeing: 0.35,
            estimate_motion_agreeing: Some(0.9),
            estimate_event_support: Some(0.75),
            candidates: [
                Some(FallbackCandidate {
                    start: FallbackStart::PreviousDepthPose,
                    pose: turned,
                    agreeing: 0.52,
                    motion_agreeing: Some(0.85),
                    event_support: Some(0.4),
                }),
                None,
                None,
            ],
            replaced_by: Some(0),
        };
        let mut out = String::new();
        check.write_csv_rows("marker", &mut out);
        let rows: Vec<&str> = out.lines().collect();
        assert_eq!(rows.len(), 1);
        let cols: Vec<&str> = rows[0].split(',').collect();
        assert_eq!(cols.len(), FALLBACK_TRACE_HEADER.split(',').count());
        assert_eq!(&cols[..2], &["33833", "marker"]);
        assert_eq!(cols[6], "previous");
        assert_eq!(cols[7], "0.120000");
        assert_eq!(cols[11], "10.000");
        assert_eq!(cols[12], "1");
        assert_eq!(&cols[13..15], &["0.9000", "0.8500"]);
        // Both orientations: the estimate's identity, the candidate's 10 degrees about z.
        let half = 5f64.to_radians();
        let q: Vec<f64> = cols[15..23].iter().map(|c| c.parse().unwrap()).collect();
        let want = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, half.sin(), half.cos()];
        assert!(
            q.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-6),
            "{q:?}"
        );
        assert_eq!(&cols[23..], &["0.7500", "0.4000", "58833"]);

        let kept = DepthFallbackCheck {
            replaced_by: None,
            candidates: [
                check.candidates[0],
                Some(FallbackCandidate {
                    start: FallbackStart::Extrapolated,
                    pose: estimate,
                    agreeing: 0.33,
                    motion_agreeing: None,
                    event_support: None,
                }),
                None,
            ],
            ..check
        };
        let mut out = String::new();
        kept.write_csv_rows("marker", &mut out);
        let cols: Vec<Vec<&str>> = out.lines().map(|l| l.split(',').collect()).collect();
        let replaced: Vec<&str> = cols.iter().map(|c| c[12]).collect();
        assert_eq!(replaced, ["0", "0"]);
        // An unknown motion agreement is an empty field.
        assert_eq!(&cols[1][13..15], &["0.9000", ""]);
        assert!(out.lines().nth(1).unwrap().contains(",extrapolated,"));
        // An unknown event support is an empty field too.
        assert_eq!(&cols[1][23..25], &["0.7500", ""]);
    }

    /// A rule with the estimate's own motion never taken as contradicted.
    fn rule(margin: f64, motion_margin: f64, event_weight: f64) -> FallbackRule {
        FallbackRule {
            margin,
            motion_margin,
            estimate_motion_margin: -1.0,
            event_weight,
        }
    }

    /// A check of an estimate (agreeing fraction, motion agreement) against two candidates, without event support.
    fn two_candidates(
        estimate_agreeing: f64,
        estimate_motion_agreeing: Option<f64>,
        a: FallbackCandidate,
        b: FallbackCandidate,
    ) -> DepthFallbackCheck {
        DepthFallbackCheck {
            object: 0,
            t_us: 0,
            tick_us: 0,
            estimate: Isometry3::identity(),
            estimate_agreeing,
            estimate_motion_agreeing,
            estimate_event_support: None,
            candidates: [Some(a), Some(b), None],
            replaced_by: None,
        }
    }

    fn candidate(start: FallbackStart, agreeing: f64, motion: Option<f64>) -> FallbackCandidate {
        FallbackCandidate {
            start,
            pose: Isometry3::identity(),
            agreeing,
            motion_agreeing: motion,
            event_support: None,
        }
    }

    #[test]
    fn replacement_takes_the_best_eligible_candidate_above_the_margin() {
        let check = two_candidates;
        let prev = FallbackStart::PreviousDepthPose;
        let extr = FallbackStart::Extrapolated;
        // The better-agreeing candidate wins, if it beats the estimate by more than the margin.
        let c = check(
            0.3,
            None,
            candidate(prev, 0.4, None),
            candidate(extr, 0.5, None),
        );
        assert_eq!(c.replacement(&rule(0.05, 0.3, 0.0)), Some(1));
        assert_eq!(c.replacement(&rule(0.25, 0.3, 0.0)), None);
        // A candidate whose motion the surroundings contradict is not taken; the other one still can be.
        let c = check(
            0.3,
            Some(0.9),
            candidate(prev, 0.5, Some(0.95)),
            candidate(extr, 0.7, Some(0.1)),
        );
        assert_eq!(c.replacement(&rule(0.05, 0.3, 0.0)), Some(0));
        // Within the motion margin, or with the motion check off, it is eligible again.
        assert_eq!(c.replacement(&rule(0.05, 0.85, 0.0)), Some(1));
        assert_eq!(c.replacement(&rule(0.05, -1.0, 0.0)), Some(1));
        // An unknown motion agreement on either side does not refuse a candidate.
        let c = check(
            0.3,
            None,
            candidate(prev, 0.5, Some(0.0)),
            candidate(extr, 0.2, None),
        );
        assert_eq!(c.replacement(&rule(0.05, 0.3, 0.0)), Some(0));
        // A candidate whose motion the other candidate explains far better is not taken, even when the estimate
        // explains its motion no better (the thin marker crossing the image: 0.36 / 0.16 against 0.29 / 0.97).
        let c = check(
            0.12,
            Some(0.2),
            candidate(prev, 0.36, Some(0.16)),
            candidate(extr, 0.29, Some(0.97)),
        );
        assert_eq!(c.replacement(&rule(0.05, 0.3, 0.0)), Some(1));
        // Every candidate refused: the estimate is kept however poorly it agrees.
        let c = check(
            0.0,
            Some(1.0),
            candidate(prev, 0.9, Some(0.2)),
            candidate(extr, 0.8, Some(0.3)),
        );
        assert_eq!(c.replacement(&rule(0.05, 0.3, 0.0)), None);
        // A missing candidate is skipped.
        let mut c = check(
            0.3,
            None,
            candidate(prev, 0.9, None),
            candidate(extr, 0.1, None),
        );
        c.candidates[0] = None;
        assert_eq!(c.replacement(&rule(0.05, 0.3, 0.0)), None);
    }

    #[test]
    fn an_estimate_whose_motion_the_surroundings_contradict_gives_way() {
        // Holdout can rotation moderate at 1.133 s: the estimate jumped 4 cm forward onto the hand that hides most
        // of the can. More of its model points agree (0.44) than of the candidate's at the can (0.16), but the
        // surroundings confirm the candidate's motion (0.72) and not the jump (0.0).
        let check = |estimate_motion: Option<f64>, a: FallbackCandidate, b: FallbackCandidate| {
            two_candidates(0.44, estimate_motion, a, b)
        };
        let prev = FallbackStart::PreviousDepthPose;
        let extr = FallbackStart::Extrapolated;
        let c = check(
            Some(0.0),
            candidate(prev, 0.16, Some(0.72)),
            candidate(extr, 0.49, Some(0.0)),
        );
        let contradicting = FallbackRule {
            estimate_motion_margin: 0.5,
            ..rule(0.05, 0.3, 0.0)
        };
        assert!(c.estimate_contradicted(0.5));
        // Without the estimate's check it is kept: the candidate that made the same jump is refused for its motion
        // and the one at the can agrees with fewer points. With it, that one replaces the estimate.
        assert_eq!(c.replacement(&rule(0.05, 0.3, 0.0)), None);
        assert_eq!(c.replacement(&contradicting), Some(0));
        // Within the margin, or with the estimate's motion unknown, the agreeing fractions decide as before.
        assert!(!c.estimate_contradicted(0.8));
        let unknown = check(
            None,
            candidate(prev, 0.16, Some(0.72)),
            candidate(extr, 0.3, Some(0.0)),
        );
        assert!(!unknown.estimate_contradicted(0.5));
        assert_eq!(unknown.replacement(&contradicting), None);
        // Without candidates there is nothing to contradict the estimate with: it is kept.
        let mut none = check(
            Some(0.0),
            candidate(prev, 0.16, Some(0.72)),
            candidate(extr, 0.3, None),
        );
        none.candidates = [None; FALLBACK_STARTS];
        assert!(!none.estimate_contradicted(0.5));
        assert_eq!(none.replacement(&contradicting), None);
    }

    #[test]
    fn event_support_shifts_the_choice_only_when_weighted_and_known() {
        let with_support = |agreeing: f64, support: Option<f64>| FallbackCandidate {
            event_support: support,
            ..candidate(FallbackStart::PreviousDepthPose, agreeing, None)
        };
        let check = |estimate_support: Option<f64>, a: FallbackCandidate, b: FallbackCandidate| {
            DepthFallbackCheck {
                estimate_event_support: estimate_support,
                ..two_candidates(0.5, None, a, b)
            }
        };
        // Depth alone prefers the first candidate; the events contradict it and favour the second.
        let c = check(
            Some(0.6),
            with_support(0.62, Some(0.2)),
            with_support(0.58, Some(0.7)),
        );
        assert_eq!(c.replacement(&rule(0.05, 0.3, 0.0)), Some(0));
        // Weighted, the first drops to 0.62 - 0.4 = 0.22 and the second rises to 0.58 + 0.1 = 0.68.
        assert_eq!(c.replacement(&rule(0.05, 0.3, 1.0)), Some(1));
        // Events that contradict every candidate keep the estimate.
        let c = check(
            Some(0.9),
            with_support(0.62, Some(0.2)),
            with_support(0.58, Some(0.5)),
        );
        assert_eq!(c.replacement(&rule(0.05, 0.3, 1.0)), None);
        // Events that favour a candidate let it replace the estimate below the depth-only margin.
        let c = check(
            Some(0.3),
            with_support(0.53, Some(0.6)),
            with_support(0.4, None),
        );
        assert_eq!(c.replacement(&rule(0.05, 0.3, 0.0)), None);
        assert_eq!(c.replacement(&rule(0.05, 0.3, 0.5)), Some(0));
        // An unknown support on either side gives no bonus.
        let c = check(
            None,
            with_support(0.53, Some(0.6)),
            with_support(0.4, Some(0.9)),
        );
        assert_eq!(c.replacement(&rule(0.05, 0.3, 1.0)), None);
    }
}
