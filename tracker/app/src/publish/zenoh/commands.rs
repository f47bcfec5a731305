//! The control side of the zenoh sink: one `geometry_msgs/msg/PoseStamped` subscription per object
//! (`<prefix>/<object>/set_pose`, re-seed) and the `std_srvs/srv/Trigger` service `<prefix>/reset`, each on its
//! rmw_zenoh key with its liveliness token. Requests go to the tracker thread through a
//! [`ControlSender`]; a service call is answered when the tracker has carried it out or refused it.

use super::entity::{declare_token, system_time_ns};
use super::outputs::LastControl;
use super::{ZenohConfig, ZenohSetupError};
use crate::publish::control::{
    ControlCommand, ControlOutcome, ControlReply, ControlRequest, ControlSender,
};
use crate::publish::ros2::trigger::{
    TriggerResponse, decode_trigger_request, encode_trigger_response,
};
use crate::publish::ros2::{self, Attachment, EntityKind, RosNodeIdentity, types};
use zenoh::Wait;
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::Subscriber;
use zenoh::query::{Query, Queryable};

/// The declared control entities; undeclared when dropped.
pub(super) struct ControlEntities {
    _subscribers: Vec<Subscriber<()>>,
    _service: Queryable<()>,
    /// Their liveliness tokens' key expressions.
    pub token_keys: Vec<String>,
}

/// Declares the control subscriptions and service as entities `first_entity..` of `node`; their commands go to
/// the sender, their outcomes into `last_control`.
pub(super) fn declare(
    session: &zenoh::Session,
    node: &RosNodeIdentity,
    first_entity: u64,
    config: &ZenohConfig,
    objects: &[String],
    (sender, last_control): (ControlSender, LastControl),
    tokens: &mut Vec<LivelinessToken>,
) -> Result<ControlEntities, ZenohSetupError> {
    let mut token_keys = Vec::new();
    let mut subscribers = Vec::new();
    let mut entity = first_entity;
    for (object, name) in objects.iter().enumerate() {
        let topic = config.set_pose_topic(name);
        let key = ros2::typed_key_expr(config.domain_id, &topic, &types::POSE_STAMPED);
        let context = SetPose {
            object,
            name: name.clone(),
            frame_id: config.frame_id.clone(),
            sender: sender.clone(),
            last_control: last_control.clone(),
        };
        let subscriber = session
            .declare_subscriber(key.clone())
            .callback(move |sample| context.receive(&sample.payload().to_bytes()))
            .wait()
            .map_err(|e| declare_error("subscriber", &key, e))?;
        subscribers.push(subscriber);
        let token = ros2::entity_liveliness_key_expr(
            node,
            entity,
            EntityKind::Subscription,
            &topic,
            &types::POSE_STAMPED,
            ros2::DEFAULT_QOS_KEY,
        );
        tokens.push(declare_token(session, &token)?);
        token_keys.push(token);
        entity += 1;
    }
    let service = config.reset_service();
    let key = ros2::typed_key_expr(config.domain_id, &service, &types::TRIGGER);
    let gid = super::entity::random_gid(&node.zid, entity);
    let reset = Reset {
        sender,
        last_control,
        objects: objects.len(),
        gid,
    };
    let queryable = session
        .declare_queryable(key.clone())
        .complete(true)
        .callback(move |query| reset.receive(query))
        .wait()
        .map_err(|e| declare_error("queryable", &key, e))?;
    let token = ros2::entity_liveliness_key_expr(
        node,
        entity,
        EntityKind::ServiceServer,
        &service,
        &types::TRIGGER,
        ros2::DEFAULT_QOS_KEY,
    );
    tokens.push(declare_token(session, &token)?);
    token_keys.push(token);
    Ok(ControlEntities {
        _subscribers: subscribers,
        _service: queryable,
        token_keys,
    })
}

fn declare_error(what: &'static str, key: &str, e: impl std::fmt::Display) -> ZenohSetupError {
    ZenohSetupError::Declare {
        what,
        key: key.to_owned(),
        message: e.to_string(),
    }
}

/// Records a command's outcome for `objects` (the diagnostics' `last_control`), and reports a refusal.
fn record(last_control: &LastControl, objects: &[usize], what: &str, outcome: &ControlOutcome) {
    let text = format!(
        "{}: {}",
        if outcome.accepted { "done" } else { "refused" },
        outcome.message
    );
    if !outcome.accepted {
        eprintln!("warning: {what} refused: {}", outcome.message);
    }
    if let Ok(mut last) = last_control.lock() {
        for &k in objects {
            if let Some(slot) = last.get_mut(k) {
                *slot = Some(text.clone());
            }
        }
    }
}

/// One object's set-pose subscription.
struct SetPose {
    object: usize,
    name: String,
    frame_id: String,
    sender: ControlSender,
    last_control: LastControl,
}

impl SetPose {
    fn receive(&self, payload: &[u8]) {
        let what = format!("set_pose of {}", self.name);
        let refuse = |why: String| {
            record(
                &self.last_control,
                &[self.object],
                &what,
                &ControlOutcome::refused(why),
            )
        };
        let msg = match ros2::decode_pose_stamped(payload) {
            Ok(m) => m,
            Err(e) => return refuse(format!("{}: not a PoseStamped: {e}", self.name)),
        };
        if !msg.frame_id.is_empty() && msg.frame_id != self.frame_id {
            return refuse(format!(
                "{}: frame_id {:?} is not the camera frame {:?} (poses are T_cam_obj; empty also means the camera frame)",
                self.name, msg.frame_id, self.frame_id
            ));
        }
        if !msg
            .position
            .iter()
            .chain(&msg.orientation_xyzw)
            .all(|v| v.is_finite())
        {
            return refuse(format!("{}: the pose is not finite", self.name));
        }
        let norm = msg
            .orientation_xyzw
            .iter()
            .map(|v| v * v)
            .sum::<f64>()
            .sqrt();
        if (norm - 1.0).abs() > 1e-3 {
            return refuse(format!(
                "{}: the orientation is not a unit quaternion (norm {norm:.6})",
                self.name
            ));
        }
        let last_control = self.last_control.clone();
        let object = self.object;
        let reply: ControlReply =
            Box::new(move |outcome| record(&last_control, &[object], &what, &outcome));
        self.sender.send(ControlRequest {
            command: ControlCommand::SetPose {
                object: self.object,
                stamp_ns: msg.stamp.as_nanos(),
                pose: msg.to_isometry(),
            },
            reply,
        });
    }
}

/// The reset service.
struct Reset {
    sender: ControlSender,
    last_control: LastControl,
    objects: usize,
    gid: [u8; ros2::GID_LEN],
}

impl Reset {
    fn receive(&self, query: Query) {
        let request = query
            .attachment()
            .and_then(|a| Attachment::from_bytes(&a.to_bytes()).ok());
        let payload = query
            .payload()
            .map(|p| p.to_bytes().into_owned())
            .unwrap_or_default();
        let last_control = self.last_control.clone();
        let all: Vec<usize> = (0..self.objects).collect();
        let gid = self.gid;
        let reply: ControlReply = Box::new(move |outcome| {
            record(&last_control, &all, "reset", &outcome);
            answer(&query, request, gid, &outcome);
        });
        if let Err(e) = decode_trigger_request(&payload) {
            return reply(ControlOutcome::refused(format!(
                "not a std_srvs/srv/Trigger request: {e}"
            )));
        }
        self.sender.send(ControlRequest {
            command: ControlCommand::Reset,
            reply,
        });
    }
}

/// Replies to a service call with a `Trigger_Response` and rmw_zenoh's attachment: the request's sequence number
/// and the client's GID (what rmw_zenoh's clients match replies by), the time of the reply.
fn answer(
    query: &Query,
    request: Option<Attachment>,
    server_gid: [u8; ros2::GID_LEN],
    outcome: &ControlOutcome,
) {
    let mut payload = Vec::new();
    encode_trigger_response(
        &mut payload,
        &TriggerResponse {
            success: outcome.accepted,
            message: outcome.message.clone(),
        },
    );
    let attachment = Attachment {
        sequence_number: request.map_or(0, |a| a.sequence_number),
        source_timestamp_ns: system_time_ns(),
        gid: request.map_or(server_gid, |a| a.gid),
    };
    if let Err(e) = query
        .reply(query.key_expr().clone(), payload)
        .attachment(attachment.to_bytes())
        .wait()
    {
        eprintln!("warning: reset: the reply could not be sent: {e}");
    }
}
