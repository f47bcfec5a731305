//! The tracker thread's side of the control commands ([`crate::publish::control`]): before each tick, every
//! waiting command is checked and carried out on the tracker, or refused with the reason, and answered.

use crate::publish::control::{ControlCommand, ControlInbox, ControlOutcome};
use nalgebra::Isometry3;
use tracker::track::PoseTracker;

/// What the control commands did so far (the status topic's `control`).
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize)]
pub struct ControlCounters {
    /// Objects re-seeded by a set-pose command.
    pub poses_set: u64,
    /// Resets carried out.
    pub resets: u64,
    /// Commands refused.
    pub refused: u64,
    /// The latest command's outcome, in words.
    pub last: Option<String>,
}

/// Carries out control commands on the tracker thread.
pub struct ControlApplier {
    inbox: ControlInbox,
    /// Every object's configured first pose, for a reset.
    first_poses: Vec<Isometry3<f64>>,
    /// The pose topics' stamp offset: `stamp_ns = t_us * 1000 + ros_time_offset_ns`.
    ros_time_offset_ns: i64,
    /// Oldest (and furthest ahead) stamp a set-pose may carry, microseconds from the tick.
    max_age_us: i64,
    counters: ControlCounters,
}

impl ControlApplier {
    /// An applier of the commands arriving in `inbox`; `first_poses` in object order.
    pub fn new(
        inbox: ControlInbox,
        first_poses: Vec<Isometry3<f64>>,
        ros_time_offset_ns: i64,
        max_age_ms: u64,
    ) -> Self {
        Self {
            inbox,
            first_poses,
            ros_time_offset_ns,
            max_age_us: i64::try_from(max_age_ms.saturating_mul(1000)).unwrap_or(i64::MAX),
            counters: ControlCounters::default(),
        }
    }

    /// What the commands did so far.
    pub fn counters(&self) -> &ControlCounters {
        &self.counters
    }

    /// Carries out the waiting commands before the tick at `tick_us`, the latest tick having been at
    /// `last_tick_us`; returns whether any was carried out (or refused: the counters changed).
    pub fn apply(
        &mut self,
        tracker: &mut dyn PoseTracker,
        tick_us: i64,
        last_tick_us: Option<i64>,
    ) -> bool {
        let mut any = false;
        while let Some(request) = self.inbox.try_next() {
            any = true;
            let outcome = self.carry_out(tracker, &request.command, tick_us, last_tick_us);
            if outcome.accepted {
                match request.command {
                    ControlCommand::SetPose { .. } => self.counters.poses_set += 1,
                    ControlCommand::Reset => self.counters.resets += 1,
                }
            } else {
                self.counters.refused += 1;
            }
            self.counters.last = Some(format!(
                "{}: {}",
                if outcome.accepted { "done" } else { "refused" },
                outcome.message
            ));
            (request.reply)(outcome);
        }
        any
    }

    fn carry_out(
        &self,
        tracker: &mut dyn PoseTracker,
        command: &ControlCommand,
        tick_us: i64,
        last_tick_us: Option<i64>,
    ) -> ControlOutcome {
        // The new estimate stands at the latest tick, so the next one is an ordinary step from it.
        let Some(at_us) = last_tick_us else {
            return ControlOutcome::refused(
                "no tick yet: the objects still stand at their first poses",
            );
        };
        let names = tracker.objects().to_vec();
        match command {
            ControlCommand::SetPose {
                object,
                stamp_ns,
                pose,
            } => {
                let Some(name) = names.get(*object) else {
                    return ControlOutcome::refused(format!("unknown object {object}"));
                };
                if let Err(why) = self.check_stamp(*stamp_ns, tick_us) {
                    return ControlOutcome::refused(format!("{name}: {why}"));
                }
                match tracker.reseed(*object, at_us, *pose) {
                    Ok(()) => {
                        ControlOutcome::done(format!("{name} re-seeded at the tick of {at_us} us"))
                    }
                    Err(why) => ControlOutcome::refused(format!("{name}: {why}")),
                }
            }
            ControlCommand::Reset => {
                for (k, pose) in self.first_poses.iter().enumerate() {
                    if let Err(why) = tracker.reseed(k, at_us, *pose) {
                        let name = names.get(k).map_or("?", String::as_str);
                        return ControlOutcome::refused(format!("{name}: {why}"));
                    }
                }
                let n = self.first_poses.len();
                ControlOutcome::done(format!(
                    "{n} object{} reset to {} first pose{} at the tick of {at_us} us",
                    if n == 1 { "" } else { "s" },
                    if n == 1 { "its" } else { "their" },
                    if n == 1 { "" } else { "s" },
                ))
            }
        }
    }

    /// Whether a set-pose stamped `stamp_ns` may be used at the tick at `tick_us` (0: now).
    fn check_stamp(&self, stamp_ns: i64, tick_us: i64) -> Result<(), String> {
        if stamp_ns == 0 {
            return Ok(());
        }
        let t_us = stamp_ns
            .saturating_sub(self.ros_time_offset_ns)
            .div_euclid(1000);
        let age_us = tick_us.saturating_sub(t_us);
        let limit_ms = self.max_age_us as f64 * 1e-3;
        if age_us > self.max_age_us {
            return Err(format!(
                "stamp too old: {:.1} ms before the tick at {tick_us} us (limit {limit_ms:.0} ms, \
                 zenoh.control_max_age_ms; stamp 0 means now)",
                age_us as f64 * 1e-3
            ));
        }
        if -age_us > self.max_age_us {
            return Err(format!(
                "stamp {:.1} ms after the tick at {tick_us} us (limit {limit_ms:.0} ms; stamps are the pose \
                 topics' clock, stamp 0 means now)",
                -age_us as f64 * 1e-3
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::publish::control::{ControlRequest, control_channel};
    use nalgebra::{Translation3, UnitQuaternion};
    use std::sync::{Arc, Mutex};
    use tracker::track::HoldPoseTracker;

    fn at(x: f64) -> Isometry3<f64> {
        Isometry3::from_parts(Translation3::new(x, 0.0, 0.5), UnitQuaternion::identity())
    }

    #[test]
    fn commands_are_carried_out_or_refused_with_the_reason() {
        let (tx, inbox) = control_channel();
        let mut applier = ControlApplier::new(inbox, vec![at(0.0), at(0.1)], 0, 500);
        let mut tracker = HoldPoseTracker::new(vec![("a".into(), at(0.0)), ("b".into(), at(0.1))]);
        let seen = Arc::new(Mutex::new(Vec::new()));
        let send = |command| {
            let s = seen.clone();
            tx.send(ControlRequest {
                command,
                reply: Box::new(move |o| s.lock().unwrap().push(o)),
            });
        };
        let set = |object, stamp_ns, pose| ControlCommand::SetPose {
            object,
            stamp_ns,
            pose,
        };
        send(set(1, 0, at(0.3)));
        assert!(applier.apply(&mut tracker, 100_000, None));
        assert!(seen.lock().unwrap()[0].message.contains("no tick yet"));
        send(set(1, 0, at(0.3)));
        send(set(2, 0, at(0.3)));
        send(set(0, 1_000 * (100_000 - 600_000), at(0.3)));
        send(set(0, 1_000 * (100_000 + 700_000), at(0.3)));
        let mut nan = at(0.0);
        nan.translation.x = f64::NAN;
        send(set(0, 0, nan));
        assert!(applier.apply(&mut tracker, 100_000, Some(91_667)));
        let out: Vec<_> = seen.lock().unwrap().drain(..).skip(1).collect();
        assert!(out[0].accepted, "{out:?}");
        assert_eq!(out[0].message, "b re-seeded at the tick of 91667 us");
        assert!(!out[1].accepted && out[1].message.contains("unknown object 2"));
        assert!(!out[2].accepted && out[2].message.contains("stamp too old: 600.0 ms"));
        assert!(!out[3].accepted && out[3].message.contains("700.0 ms after"));
        assert!(!out[4].accepted && out[4].message.contains("not finite"));
        assert_eq!(tracker.pose_at(1, 0), None, "no tick yet");
        let mut est = Vec::new();
        let tick = drivers::timeline::Tick {
            index: 0,
            t_us: 100_000,
            depth_frame: None,
            synthesized: false,
        };
        tracker.tick(&tick, &mut est);
        assert!((est[1].pose.translation.x - 0.3).abs() < 1e-12);
        send(ControlCommand::Reset);
        assert!(applier.apply(&mut tracker, 108_333, Some(100_000)));
        assert!(seen.lock().unwrap()[0].accepted);
        est.clear();
        tracker.tick(&tick, &mut est);
        assert!((est[1].pose.translation.x - 0.1).abs() < 1e-12);
        let c = applier.counters();
        assert_eq!((c.poses_set, c.resets, c.refused), (1, 1, 5));
        assert!(!applier.apply(&mut tracker, 116_667, Some(108_333)));
    }
}
