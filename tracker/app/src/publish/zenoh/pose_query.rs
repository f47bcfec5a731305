//! Poses on request at any timestamp: a zenoh queryable per object on `<prefix>/<object>/pose_at` answers
//! `get("<prefix>/<object>/pose_at?t_us=T")` (event camera clock, microseconds) or `?stamp_ns=S` (the pose topic's
//! `header.stamp` convention, nanoseconds) with the pose at that time as JSON, interpolated between the two ticks
//! around it or extrapolated at most one tick period past the latest. The answers come from the poses the sink
//! published (the last [`RECENT_TICKS`] ticks), on zenoh's threads: the tracker thread only records each tick's
//! poses under a short lock.

use super::query_parameters;
use nalgebra::Isometry3;
use scene::geometry::se3;
use std::collections::VecDeque;
use std::fmt;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use tracker::track::{PoseEstimate, TrackingState};

/// Published poses kept per object for queries: 2 s at 120 Hz.
pub const RECENT_TICKS: usize = 240;

/// Furthest a query may reach past the latest pose, microseconds: one 120 Hz tick period.
pub const MAX_EXTRAPOLATION_US: i64 = 8_333;

/// One published pose.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Kept {
    t_us: i64,
    pose: Isometry3<f64>,
    quality: f32,
    state: TrackingState,
    /// Whether the tracker revised it after it was published ([`RecentPoses::revise`]).
    revised: bool,
}

/// The answer to a pose query.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QueriedPose {
    /// The pose at the requested time.
    pub estimate: PoseEstimate,
    /// Whether a pose it comes from was revised after it was published: the tracker tracked that tick again
    /// from a depth frame that arrived late, so the answer differs from what the topic carried.
    pub revised: bool,
}

/// The poses the sink published recently, per object, oldest first; times strictly increase. Filled by the
/// publishing thread, read by the queryables' callbacks.
#[derive(Debug)]
pub struct RecentPoses {
    objects: Vec<VecDeque<Kept>>,
}

/// Why a query got no pose.
#[derive(Debug, Clone, PartialEq)]
pub enum PoseQueryError {
    /// The selector's parameters do not name one time.
    BadParameters(String),
    /// Nothing was published for the object yet.
    NoPoseYet,
    /// The time is before the oldest pose kept.
    TooOld {
        /// Requested time, microseconds.
        t_us: i64,
        /// Oldest pose kept, microseconds.
        oldest_us: i64,
    },
    /// The time is more than [`MAX_EXTRAPOLATION_US`] after the latest pose.
    TooNew {
        /// Requested time, microseconds.
        t_us: i64,
        /// Latest pose, microseconds.
        latest_us: i64,
    },
}

impl fmt::Display for PoseQueryError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BadParameters(m) => write!(f, "{m}"),
            Self::NoPoseYet => write!(f, "no pose published for this object yet"),
            Self::TooOld { t_us, oldest_us } => write!(
                f,
                "t_us {t_us} is before the oldest pose kept ({oldest_us} us; the last {RECENT_TICKS} ticks are kept)"
            ),
            Self::TooNew { t_us, latest_us } => write!(
                f,
                "t_us {t_us} is more than {MAX_EXTRAPOLATION_US} us after the latest pose ({latest_us} us)"
            ),
        }
    }
}

impl RecentPoses {
    /// Room for [`RECENT_TICKS`] poses of each of `objects` objects, allocated now.
    pub fn new(objects: usize) -> Self {
        Self {
            objects: (0..objects)
                .map(|_| VecDeque::with_capacity(RECENT_TICKS))
                .collect(),
        }
    }

    /// Keeps a published estimate (no allocation). One at or before the newest kept replaces the poses it does not
    /// follow, so times stay increasing; an unknown object is ignored.
    pub fn record(&mut self, e: &PoseEstimate) {
        let Some(kept) = self.objects.get_mut(e.object) else {
            return;
        };
        while kept.back().is_some_and(|k| k.t_us >= e.t_us) {
            kept.pop_back();
        }
        if kept.len() == RECENT_TICKS {
            kept.pop_front();
        }
        kept.push_back(Kept {
            t_us: e.t_us,
            pose: e.pose,
            quality: e.quality,
            state: e.state,
            revised: false,
        });
    }

    /// Replaces the kept pose of `e`'s object at exactly `e.t_us` with `e`'s pose, marked revised if it differs
    /// (quality and state stay as published); returns whether it did. A time or object not kept is ignored (no
    /// allocation).
    pub fn revise(&mut self, e: &PoseEstimate) -> bool {
        let Some(kept) = self.objects.get_mut(e.object) else {
            return false;
        };
        let i = kept.partition_point(|k| k.t_us < e.t_us);
        let Some(k) = kept.get_mut(i).filter(|k| k.t_us == e.t_us) else {
            return false;
        };
        if k.pose == e.pose {
            return false;
        }
        k.pose = e.pose;
        k.revised = true;
        true
    }

    /// The pose of `object` at `t_us`: a kept pose exactly at its own time, else interpolated on SE(3) between
    /// the poses around it (quality the lower of the two, state the worse), or extrapolated from the latest two
    /// at most [`MAX_EXTRAPOLATION_US`] past it (state at best `degraded` past one tick). Says whether a pose it
    /// comes from was revised.
    pub fn at(&self, object: usize, t_us: i64) -> Result<QueriedPose, PoseQueryError> {
        let kept = self.objects.get(object).ok_or(PoseQueryError::NoPoseYet)?;
        let (first, last) = match (kept.front(), kept.back()) {
            (Some(f), Some(l)) => (*f, *l),
            _ => return Err(PoseQueryError::NoPoseYet),
        };
        if t_us < first.t_us {
            return Err(PoseQueryError::TooOld {
                t_us,
                oldest_us: first.t_us,
            });
        }
        if t_us > last.t_us.saturating_add(MAX_EXTRAPOLATION_US) {
            return Err(PoseQueryError::TooNew {
                t_us,
                latest_us: last.t_us,
            });
        }
        let estimate = |pose, quality, state, revised| QueriedPose {
            estimate: PoseEstimate {
                object,
                t_us,
                pose,
                quality,
                state,
            },
            revised,
        };
        if t_us >= last.t_us {
            let Some(before) = kept
                .len()
                .checked_sub(2)
                .and_then(|i| kept.get(i))
                .filter(|_| t_us > last.t_us)
            else {
                return Ok(estimate(last.pose, last.quality, last.state, last.revised));
            };
            let s = (t_us - before.t_us) as f64 / (last.t_us - before.t_us) as f64;
            let state = if t_us > last.t_us && last.state == TrackingState::Tracking {
                TrackingState::Degraded
            } else {
                last.state
            };
            return Ok(estimate(
                se3::interpolate(&before.pose, &last.pose, s),
                last.quality,
                state,
                before.revised || last.revised,
            ));
        }
        // first.t_us <= t_us < last.t_us: the first kept pose after t_us exists and is not the front.
        let after = kept.partition_point(|k| k.t_us <= t_us);
        let (a, b) = (kept[after - 1], kept[after]);
        if t_us == a.t_us {
            return Ok(estimate(a.pose, a.quality, a.state, a.revised));
        }
        let s = (t_us - a.t_us) as f64 / (b.t_us - a.t_us) as f64;
        Ok(estimate(
            se3::interpolate(&a.pose, &b.pose, s),
            a.quality.min(b.quality),
            worse(a.state, b.state),
            a.revised || b.revised,
        ))
    }
}

/// The worse of two states (`lost` over `degraded` over `tracking`).
fn worse(a: TrackingState, b: TrackingState) -> TrackingState {
    let rank = |s| match s {
        TrackingState::Tracking => 0,
        TrackingState::Degraded => 1,
        TrackingState::Lost => 2,
    };
    if rank(b) > rank(a) { b } else { a }
}

/// The time a query's parameters name, on the camera clock in microseconds ([`query_parameters::requested_time`]);
/// a refusal is [`PoseQueryError::BadParameters`].
pub fn requested_time(parameters: &str, ros_time_offset_ns: i64) -> Result<i64, PoseQueryError> {
    query_parameters::requested_time(parameters, ros_time_offset_ns)
        .map_err(PoseQueryError::BadParameters)
}

/// The JSON answer to a query: the object's name, the time asked for on both clocks, the pose (`T_cam_obj`,
/// metres, unit quaternion x y z w, the event camera's frame as on the pose topic), quality, state, and whether
/// it comes from a pose the tracker revised after publishing it.
pub fn answer_json(name: &str, answer: &QueriedPose, ros_time_offset_ns: i64) -> String {
    let e = &answer.estimate;
    let t = e.pose.translation.vector;
    let q = e.pose.rotation.quaternion().coords;
    let stamp_ns = e
        .t_us
        .checked_mul(1000)
        .and_then(|ns| ns.checked_add(ros_time_offset_ns));
    // serde_json writes a non-finite number as `null`, so the answer is always valid JSON.
    serde_json::json!({
        "object": name,
        "t_us": e.t_us,
        "stamp_ns": stamp_ns,
        "position": [t.x, t.y, t.z],
        "orientation": [q.x, q.y, q.z, q.w],
        // The f32's shortest decimal form (0.7444, not 0.7444000244140625).
        "quality": e.quality.to_string().parse::<f64>().unwrap_or(f64::NAN),
        "state": e.state.as_str(),
        "revised": answer.revised,
    })
    .to_string()
}

/// Queries answered and refused so far (all objects).
#[derive(Debug, Default)]
pub struct PoseQueryCounters {
    answered: AtomicU64,
    refused: AtomicU64,
}

impl PoseQueryCounters {
    /// (answered, refused).
    pub fn get(&self) -> (u64, u64) {
        (
            self.answered.load(Ordering::Relaxed),
            self.refused.load(Ordering::Relaxed),
        )
    }
}

/// What one object's queryable needs to answer.
pub(super) struct QueryContext {
    pub(super) name: String,
    pub(super) object: usize,
    pub(super) recent: Arc<Mutex<RecentPoses>>,
    pub(super) counters: Arc<PoseQueryCounters>,
    pub(super) ros_time_offset_ns: i64,
}

impl QueryContext {
    /// The answer to a query with `parameters`: the JSON pose, or the reason for refusing it.
    pub(super) fn answer(&self, parameters: &str) -> Result<String, PoseQueryError> {
        let t_us = requested_time(parameters, self.ros_time_offset_ns)?;
        let answer = match self.recent.lock() {
            Ok(recent) => recent.at(self.object, t_us)?,
            // A publishing thread that panicked holding the lock left no poses to trust.
            Err(_) => return Err(PoseQueryError::NoPoseYet),
        };
        Ok(answer_json(&self.name, &answer, self.ros_time_offset_ns))
    }

    /// Answers `query` on zenoh (a reply, or an error reply naming the problem) and counts it.
    pub(super) fn reply(&self, query: &zenoh::query::Query) {
        use zenoh::Wait;
        let sent = match self.answer(query.parameters().as_str()) {
            Ok(json) => {
                self.counters.answered.fetch_add(1, Ordering::Relaxed);
                query
                    .reply(query.key_expr().clone(), json)
                    .encoding(zenoh::bytes::Encoding::APPLICATION_JSON)
                    .wait()
            }
            Err(e) => {
                self.counters.refused.fetch_add(1, Ordering::Relaxed);
                query.reply_err(e.to_string()).wait()
            }
        };
        if let Err(e) = sent {
            // The asker went away; nothing to retry.
            log_once_reply_failure(&self.name, &e.to_string());
        }
    }
}

/// Reports the first failed reply on stderr (later ones would repeat it); the query itself was counted.
fn log_once_reply_failure(name: &str, message: &str) {
    static LOGGED: std::sync::Once = std::sync::Once::new();
    LOGGED.call_once(|| {
        eprintln!(
            "warning: zenoh: replying to a pose query for `{name}` failed: {message} (later failures are not reported)"
        );
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion, Vector3};
    use proptest::prelude::*;

    /// Object 0 moves along x and turns about z by `x` radians; object 1 only moves (its geodesic is a line).
    fn estimate(object: usize, t_us: i64, x: f64, state: TrackingState) -> PoseEstimate {
        let turn = if object == 0 { x } else { 0.0 };
        PoseEstimate {
            object,
            t_us,
            pose: Isometry3::from_parts(
                Translation3::new(x, 0.0, 0.5),
                UnitQuaternion::from_scaled_axis(Vector3::new(0.0, 0.0, turn)),
            ),
            quality: (1.0 - x) as f32,
            state,
        }
    }

    fn published(estimate: PoseEstimate) -> QueriedPose {
        QueriedPose {
            estimate,
            revised: false,
        }
    }

    #[test]
    fn a_revised_tick_is_answered_as_revised_and_the_others_are_not() {
        let mut recent = RecentPoses::new(1);
        for (k, t) in [0, 8_333, 16_667, 25_000].into_iter().enumerate() {
            recent.record(&estimate(0, t, 0.1 * k as f64, TrackingState::Degraded));
        }
        // The tracker tracked 16_667 again: another pose.
        let better = estimate(0, 16_667, 0.25, TrackingState::Tracking);
        assert!(recent.revise(&better));
        let same_pose = PoseEstimate {
            quality: f32::NAN,
            ..better
        };
        assert!(!recent.revise(&same_pose), "only the pose is revised");
        assert!(
            !recent.revise(&better),
            "the same pose again is no revision"
        );
        assert!(
            !recent.revise(&estimate(0, 16_000, 0.3, TrackingState::Tracking)),
            "not a kept time"
        );
        assert!(
            !recent.revise(&estimate(3, 16_667, 0.3, TrackingState::Tracking)),
            "no such object"
        );
        let at = recent.at(0, 16_667).unwrap();
        assert!(at.revised);
        assert_eq!(at.estimate.pose, better.pose);
        assert_eq!(
            at.estimate.state,
            TrackingState::Degraded,
            "the state stays as published"
        );
        // Between a revised tick and another: revised; between two published ones: not.
        assert!(recent.at(0, 20_000).unwrap().revised);
        assert!(recent.at(0, 10_000).unwrap().revised);
        assert!(!recent.at(0, 4_000).unwrap().revised);
        assert!(!recent.at(0, 25_000).unwrap().revised);
        // A record at a later time keeps the revision of the earlier ones.
        recent.record(&estimate(0, 33_333, 0.5, TrackingState::Tracking));
        assert!(recent.at(0, 16_667).unwrap().revised);
        let v: serde_json::Value =
            serde_json::from_str(&answer_json("mug", &recent.at(0, 16_667).unwrap(), 0)).unwrap();
        assert_eq!(v["revised"], true);
    }

    #[test]
    fn the_time_comes_from_t_us_or_stamp_ns() {
        assert_eq!(requested_time("t_us=1234", 0), Ok(1234));
        assert_eq!(requested_time("t_us=-5", 0), Ok(-5));
        assert_eq!(requested_time("stamp_ns=5000999;", 1_000), Ok(4_999));
        assert_eq!(requested_time("stamp_ns=3000&", 5_000), Ok(-2));
        for (parameters, says) in [
            ("", "no time given"),
            ("t_us=1;stamp_ns=2", "not both"),
            ("t_us=1&t_us=2", "given twice"),
            ("t_us=12.5", "`t_us` = `12.5` is not a whole number"),
            ("t_us", "`t_us` = `` is not a whole number"),
            ("time=3", "unknown parameter `time`"),
        ] {
            match requested_time(parameters, 0) {
                Err(PoseQueryError::BadParameters(m)) => {
                    assert!(m.contains(says), "{parameters}: {m}")
                }
                other => panic!("{parameters}: {other:?}"),
            }
        }
        let out_of_range = requested_time(&format!("stamp_ns={}", i64::MIN), 1);
        assert!(
            matches!(out_of_range, Err(PoseQueryError::BadParameters(m)) if m.contains("out of range"))
        );
    }

    proptest! {
        #[test]
        fn any_parameters_give_a_time_or_a_reason(parameters in ".{0,40}", offset in any::<i64>()) {
            if let Err(e) = requested_time(&parameters, offset) {
                prop_assert!(matches!(&e, PoseQueryError::BadParameters(m) if !m.is_empty()), "{:?}", e);
            }
        }

        #[test]
        fn a_given_t_us_is_the_time(t in any::<i64>(), sep in prop::sample::select(vec![";", "&", ""])) {
            prop_assert_eq!(requested_time(&format!("{sep}t_us={t}{sep}"), 7), Ok(t));
        }
    }

    #[test]
    fn poses_between_ticks_are_interpolated_and_the_latest_extrapolated_one_period_at_most() {
        let mut recent = RecentPoses::new(3);
        assert_eq!(recent.at(0, 0), Err(PoseQueryError::NoPoseYet));
        assert_eq!(recent.at(5, 0), Err(PoseQueryError::NoPoseYet));
        for object in [0, 1] {
            recent.record(&estimate(object, 1_000, 0.0, TrackingState::Tracking));
        }
        // One pose: its own, at its time and up to a period after.
        let first = estimate(0, 0, 0.0, TrackingState::Tracking).pose;
        assert_eq!(recent.at(0, 1_000).unwrap().estimate.pose, first);
        assert_eq!(recent.at(0, 2_000).unwrap().estimate.pose, first);
        for object in [0, 1] {
            recent.record(&estimate(object, 9_000, 0.4, TrackingState::Degraded));
            recent.record(&estimate(object, 17_000, 0.8, TrackingState::Tracking));
        }
        let mid = recent.at(0, 5_000).unwrap().estimate;
        assert!((mid.pose.rotation.angle() - 0.2).abs() < 1e-9, "{mid:?}");
        assert_eq!(mid.t_us, 5_000);
        assert_eq!(mid.state, TrackingState::Degraded, "the worse of the two");
        assert!(
            (mid.quality - 0.6).abs() < 1e-6,
            "the lower of the two: {}",
            mid.quality
        );
        let line = recent.at(1, 5_000).unwrap().estimate;
        assert!((line.pose.translation.x - 0.2).abs() < 1e-12, "{line:?}");
        let at_tick = recent.at(1, 9_000).unwrap().estimate;
        assert!((at_tick.pose.translation.x - 0.4).abs() < 1e-12);
        assert_eq!(
            recent.at(0, 17_000).unwrap().estimate.state,
            TrackingState::Tracking
        );
        // Past the latest: carried on at the last two poses' motion, and no longer `tracking`.
        let t_ahead = 17_000 + MAX_EXTRAPOLATION_US;
        let expected = 0.8 + 0.4 * MAX_EXTRAPOLATION_US as f64 / 8_000.0;
        let ahead = recent.at(1, t_ahead).unwrap().estimate;
        assert!(
            (ahead.pose.translation.x - expected).abs() < 1e-9,
            "{ahead:?}"
        );
        assert_eq!(ahead.state, TrackingState::Degraded);
        let turned = recent.at(0, t_ahead).unwrap().estimate;
        assert!(
            (turned.pose.rotation.angle() - expected).abs() < 1e-9,
            "{turned:?}"
        );
        assert_eq!(
            recent.at(0, t_ahead + 1),
            Err(PoseQueryError::TooNew {
                t_us: t_ahead + 1,
                latest_us: 17_000
            })
        );
        assert_eq!(
            recent.at(0, 999),
            Err(PoseQueryError::TooOld {
                t_us: 999,
                oldest_us: 1_000
            })
        );
        // Each object has its own poses.
        assert_eq!(recent.at(2, 5_000), Err(PoseQueryError::NoPoseYet));
    }

    #[test]
    fn the_last_ticks_are_kept_and_a_pose_back_in_time_replaces_the_later_ones() {
        let mut recent = RecentPoses::new(1);
        let n = RECENT_TICKS as i64 + 60;
        for k in 0..n {
            recent.record(&estimate(
                0,
                k * 100,
                0.001 * k as f64,
                TrackingState::Tracking,
            ));
        }
        let oldest_us = 60 * 100;
        assert_eq!(
            recent.at(0, oldest_us - 1),
            Err(PoseQueryError::TooOld {
                t_us: oldest_us - 1,
                oldest_us
            })
        );
        assert!(recent.at(0, oldest_us).is_ok());
        // A tracker reset to an earlier time: the poses after it are gone.
        recent.record(&estimate(0, 10_050, 0.5, TrackingState::Lost));
        let latest = recent.at(0, 10_050).unwrap().estimate;
        assert_eq!(latest.state, TrackingState::Lost);
        assert!(recent.at(0, 10_050 + MAX_EXTRAPOLATION_US + 1).is_err());
        assert!(recent.objects[0].capacity() >= RECENT_TICKS);
    }

    #[test]
    fn the_answer_is_json_with_the_pose_on_both_clocks() {
        let e = estimate(0, 1_500, 0.25, TrackingState::Tracking);
        let json = answer_json("mug", &published(e), 1_000_000);
        let v: serde_json::Value = serde_json::from_str(&json).expect("valid JSON");
        assert_eq!(v["object"], "mug");
        assert_eq!(v["t_us"], 1_500);
        assert_eq!(v["stamp_ns"], 2_500_000);
        assert_eq!(v["position"][0], 0.25);
        assert_eq!(v["state"], "tracking");
        assert_eq!(v["revised"], false);
        assert!(json.contains("\"quality\":0.75"), "{json}");
        let q: Vec<f64> = (0..4)
            .map(|i| v["orientation"][i].as_f64().unwrap())
            .collect();
        assert!(
            (q[2] - (0.125f64).sin()).abs() < 1e-12 && (q[3] - (0.125f64).cos()).abs() < 1e-12,
            "{q:?}"
        );
        let overflow = answer_json(
            "mug",
            &published(estimate(0, i64::MAX / 10, 0.0, TrackingState::Lost)),
            0,
        );
        let v: serde_json::Value = serde_json::from_str(&overflow).expect("valid JSON");
        assert!(v["stamp_ns"].is_null());
        // A non-finite number would not be JSON: it is written as null.
        let mut broken = estimate(0, 0, 0.0, TrackingState::Lost);
        broken.quality = f32::NAN;
        let v: serde_json::Value =
            serde_json::from_str(&answer_json("mug", &published(broken), 0)).expect("valid JSON");
        assert!(v["quality"].is_null());
        assert_eq!(v["state"], "lost");
    }
}
