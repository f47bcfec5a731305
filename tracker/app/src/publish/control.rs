//! Commands to the tracker from outside (re-seed an object, reset all of them), as the network sinks receive them
//! and the tracker thread carries them out: a bounded queue between the two, and the answer each command gets.
//! No transport here; the zenoh sink fills the queue from ROS 2 topics and a service (`docs/zenoh-ros2.md`).

use nalgebra::Isometry3;
use std::sync::mpsc::{Receiver, SyncSender, TrySendError, sync_channel};

/// Commands waiting for the tracker thread at most (a burst beyond is refused, never queued without bound).
pub const CONTROL_QUEUE_LEN: usize = 64;

/// What to do.
#[derive(Debug, Clone, PartialEq)]
pub enum ControlCommand {
    /// Re-seed object `object` (index into the tracker's objects) at `pose` (`T_cam_obj`, the event camera's
    /// frame), a pose stamped `stamp_ns` in the pose topics' convention (`t_us * 1000 + ros_time_offset_ns`; 0:
    /// now).
    SetPose {
        /// The object's index.
        object: usize,
        /// The pose's stamp, nanoseconds (0: now).
        stamp_ns: i64,
        /// The pose.
        pose: Isometry3<f64>,
    },
    /// Re-seed every object at its configured first pose.
    Reset,
}

/// How a command ended: carried out (with what was done) or refused (with why).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ControlOutcome {
    /// Whether it was carried out.
    pub accepted: bool,
    /// What was done, or why not.
    pub message: String,
}

impl ControlOutcome {
    /// Carried out.
    pub fn done(message: impl Into<String>) -> Self {
        Self {
            accepted: true,
            message: message.into(),
        }
    }
    /// Refused.
    pub fn refused(message: impl Into<String>) -> Self {
        Self {
            accepted: false,
            message: message.into(),
        }
    }
}

/// Called once with a command's outcome (replies to a service request, records a topic command's result).
pub type ControlReply = Box<dyn FnOnce(ControlOutcome) + Send>;

/// A command and where its outcome goes.
pub struct ControlRequest {
    /// The command.
    pub command: ControlCommand,
    /// Called with the outcome when the tracker thread has carried it out or refused it.
    pub reply: ControlReply,
}

/// The sending side (the transports); cloneable.
#[derive(Clone)]
pub struct ControlSender(SyncSender<ControlRequest>);

impl ControlSender {
    /// Queues `request` for the tracker thread; when the queue is full or the tracker has stopped, the request is
    /// answered at once as refused.
    pub fn send(&self, request: ControlRequest) {
        match self.0.try_send(request) {
            Ok(()) => {}
            Err(TrySendError::Full(r)) => (r.reply)(ControlOutcome::refused(format!(
                "busy: {CONTROL_QUEUE_LEN} commands already wait for the tracker"
            ))),
            Err(TrySendError::Disconnected(r)) => {
                (r.reply)(ControlOutcome::refused("the tracker has stopped"))
            }
        }
    }
}

/// The receiving side (the tracker thread).
pub struct ControlInbox(Receiver<ControlRequest>);

impl ControlInbox {
    /// The next waiting request, if any (never blocks).
    pub fn try_next(&self) -> Option<ControlRequest> {
        self.0.try_recv().ok()
    }
}

/// A control queue of [`CONTROL_QUEUE_LEN`] commands.
pub fn control_channel() -> (ControlSender, ControlInbox) {
    let (tx, rx) = sync_channel(CONTROL_QUEUE_LEN);
    (ControlSender(tx), ControlInbox(rx))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::{Arc, Mutex};

    fn recorder() -> (Arc<Mutex<Vec<ControlOutcome>>>, impl Fn() -> ControlReply) {
        let seen = Arc::new(Mutex::new(Vec::new()));
        let s = seen.clone();
        (seen, move || {
            let s = s.clone();
            Box::new(move |o| s.lock().unwrap().push(o)) as ControlReply
        })
    }

    #[test]
    fn a_full_queue_refuses_at_once_and_a_stopped_tracker_too() {
        let (tx, rx) = control_channel();
        let (seen, reply) = recorder();
        for _ in 0..CONTROL_QUEUE_LEN + 2 {
            tx.send(ControlRequest {
                command: ControlCommand::Reset,
                reply: reply(),
            });
        }
        let refused = seen.lock().unwrap().clone();
        assert_eq!(refused.len(), 2);
        assert!(
            refused
                .iter()
                .all(|o| !o.accepted && o.message.starts_with("busy"))
        );
        let mut queued = 0;
        while let Some(r) = rx.try_next() {
            assert_eq!(r.command, ControlCommand::Reset);
            queued += 1;
        }
        assert_eq!(queued, CONTROL_QUEUE_LEN);
        drop(rx);
        tx.send(ControlRequest {
            command: ControlCommand::Reset,
            reply: reply(),
        });
        assert_eq!(
            seen.lock().unwrap().last().unwrap().message,
            "the tracker has stopped"
        );
    }
}
