//! One ROS 2 publisher over zenoh: its rmw_zenoh key, liveliness token, GID and sequence numbers.

use super::ZenohSetupError;
use crate::publish::ros2::{self, Attachment, EntityKind, RosNodeIdentity, RosType};
use std::hash::{BuildHasher, Hasher};
use std::time::{SystemTime, UNIX_EPOCH};
use zenoh::Wait;
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::Publisher;
use zenoh::qos::{CongestionControl, Priority};

/// How a publisher sends.
#[derive(Debug, Clone, Copy)]
pub(super) struct SendOptions {
    /// zenoh priority.
    pub priority: Priority,
    /// Unbatched samples.
    pub express: bool,
    /// What to do when the transport's queue is full.
    pub congestion: CongestionControl,
}

/// A declared publisher of one ROS 2 topic.
pub(super) struct RosPublisher {
    publisher: Publisher<'static>,
    /// The data key expression.
    pub key_expr: String,
    /// The liveliness token's key expression.
    pub token_key: String,
    /// The GID its samples carry.
    pub gid: [u8; ros2::GID_LEN],
    next_sequence: i64,
}

impl RosPublisher {
    /// Declares the publisher of `topic` (type `ty`) as entity `entity_id` of `node`, and its liveliness token
    /// (pushed onto `tokens`).
    pub fn declare(
        session: &zenoh::Session,
        node: &RosNodeIdentity,
        entity_id: u64,
        topic: &str,
        ty: &RosType,
        options: SendOptions,
        tokens: &mut Vec<LivelinessToken>,
    ) -> Result<Self, ZenohSetupError> {
        let key_expr = ros2::typed_key_expr(node.domain_id, topic, ty);
        let publisher = session
            .declare_publisher(key_expr.clone())
            .priority(options.priority)
            .express(options.express)
            .congestion_control(options.congestion)
            .wait()
            .map_err(|e| ZenohSetupError::Declare {
                what: "publisher",
                key: key_expr.clone(),
                message: e.to_string(),
            })?;
        let token_key = ros2::entity_liveliness_key_expr(
            node,
            entity_id,
            EntityKind::Publisher,
            topic,
            ty,
            ros2::DEFAULT_QOS_KEY,
        );
        tokens.push(declare_token(session, &token_key)?);
        Ok(Self {
            publisher,
            key_expr,
            token_key,
            gid: random_gid(&node.zid, entity_id),
            next_sequence: 1,
        })
    }

    /// Puts one CDR message with rmw_zenoh's attachment.
    pub fn put(&mut self, payload: &[u8]) -> Result<(), String> {
        let attachment = Attachment {
            sequence_number: self.next_sequence,
            source_timestamp_ns: system_time_ns(),
            gid: self.gid,
        }
        .to_bytes();
        self.next_sequence += 1;
        self.publisher
            .put(payload)
            .attachment(attachment)
            .wait()
            .map_err(|e| format!("put on {:?}: {e}", self.key_expr))
    }
}

/// Declares the liveliness token `key`.
pub(super) fn declare_token(
    session: &zenoh::Session,
    key: &str,
) -> Result<LivelinessToken, ZenohSetupError> {
    session
        .liveliness()
        .declare_token(key.to_owned())
        .wait()
        .map_err(|e| ZenohSetupError::Declare {
            what: "liveliness token",
            key: key.to_owned(),
            message: e.to_string(),
        })
}

/// Nanoseconds since the Unix epoch on the system clock (0 if the clock is before 1970, saturated past 2262).
pub(super) fn system_time_ns() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| i64::try_from(d.as_nanos()).unwrap_or(i64::MAX))
}

/// A random 16-byte GID: std's randomly keyed SipHash (keys seeded from the OS) over the session id, the entity id
/// and the time, as rmw_zenoh's publishers draw theirs at random.
pub(super) fn random_gid(zid: &str, entity_id: u64) -> [u8; ros2::GID_LEN] {
    let mut gid = [0u8; ros2::GID_LEN];
    for (half, chunk) in gid.chunks_mut(8).enumerate() {
        let mut h = std::collections::hash_map::RandomState::new().build_hasher();
        h.write(zid.as_bytes());
        h.write_u64(entity_id);
        h.write_usize(half);
        h.write_i64(system_time_ns());
        chunk.copy_from_slice(&h.finish().to_le_bytes());
    }
    gid
}
