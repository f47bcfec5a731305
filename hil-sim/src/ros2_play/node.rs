//! The ROS 2 node `ros2-play` presents over zenoh in rmw_zenoh's form: a session (peer or client, multicast
//! scouting off), one publisher per topic whose samples carry rmw_zenoh's attachment, the node's and publishers'
//! liveliness tokens (so `ros2 node list` and `ros2 topic list` show them), and the wait for a subscription.

use super::{Ros2PlayError, SessionMode, SessionOptions};
use ros2::types::RosType;
use ros2::{Attachment, EntityKind, GID_LEN, RosNodeIdentity};
use std::hash::{BuildHasher, Hasher};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};
use zenoh::Wait;
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::Publisher;
use zenoh::qos::CongestionControl;
use zenoh::sample::SampleKind;

/// The node's name in the ROS graph.
pub const NODE_NAME: &str = "hil_sim_ros2_play";

fn zenoh_error(what: String) -> impl FnOnce(zenoh::Error) -> Ros2PlayError {
    move |e| Ros2PlayError::Zenoh {
        what,
        message: e.to_string(),
    }
}

/// One topic's publisher and its rmw_zenoh bookkeeping.
pub struct Topic {
    publisher: Publisher<'static>,
    key_expr: String,
    gid: [u8; GID_LEN],
    next_sequence: i64,
}

impl Topic {
    /// Publishes one encoded message with rmw_zenoh's attachment (the next sequence number, the system time).
    pub fn put(&mut self, payload: Vec<u8>) -> Result<(), Ros2PlayError> {
        let attachment = Attachment {
            sequence_number: self.next_sequence,
            source_timestamp_ns: system_time_ns(),
            gid: self.gid,
        }
        .to_bytes();
        self.next_sequence += 1;
        self.publisher
            .put(payload)
            .attachment(attachment.to_vec())
            .wait()
            .map_err(zenoh_error(format!("put on {}", self.key_expr)))
    }
}

/// The zenoh session and what it declared.
pub struct Node {
    session: zenoh::Session,
    tokens: Vec<LivelinessToken>,
    identity: RosNodeIdentity,
}

impl Node {
    /// Opens the session described by `options` and declares the node's liveliness token.
    pub fn open(options: &SessionOptions, domain_id: u32) -> Result<Self, Ros2PlayError> {
        let mut c = zenoh::Config::default();
        let mode = match options.mode {
            SessionMode::Peer => "\"peer\"",
            SessionMode::Client => "\"client\"",
        };
        let list = |v: &Vec<String>| serde_json::to_string(v).unwrap_or_else(|_| "[]".into());
        for (option, path, json) in [
            ("--mode", "mode", mode.to_string()),
            ("--connect", "connect/endpoints", list(&options.connect)),
            ("--listen", "listen/endpoints", list(&options.listen)),
            ("scouting", "scouting/multicast/enabled", "false".into()),
        ] {
            c.insert_json5(path, &json)
                .map_err(|e| Ros2PlayError::Option {
                    option,
                    problem: format!("{json}: {e}"),
                })?;
        }
        let session = zenoh::open(c)
            .wait()
            .map_err(zenoh_error("opening the zenoh session".into()))?;
        let identity = RosNodeIdentity {
            domain_id,
            zid: session.zid().to_string(),
            node_id: 0,
            enclave: "/".into(),
            namespace: "/".into(),
            name: NODE_NAME.into(),
        };
        let mut node = Self {
            session,
            tokens: Vec::new(),
            identity,
        };
        node.token(ros2::node_liveliness_key_expr(&node.identity))?;
        Ok(node)
    }

    fn token(&mut self, key: String) -> Result<(), Ros2PlayError> {
        let token = self
            .session
            .liveliness()
            .declare_token(key.clone())
            .wait()
            .map_err(zenoh_error(format!("declaring the liveliness token {key}")))?;
        self.tokens.push(token);
        Ok(())
    }

    /// Declares the publisher of `topic` (type `ty`, entity `entity_id`): reliable, blocking when the transport is
    /// congested (nothing is dropped), default priority; and its liveliness token.
    pub fn publisher(
        &mut self,
        entity_id: u64,
        topic: &str,
        ty: &RosType,
    ) -> Result<Topic, Ros2PlayError> {
        let key_expr = ros2::typed_key_expr(self.identity.domain_id, topic, ty);
        let publisher = self
            .session
            .declare_publisher(key_expr.clone())
            .congestion_control(CongestionControl::Block)
            .wait()
            .map_err(zenoh_error(format!("declaring the publisher {key_expr}")))?;
        self.token(ros2::entity_liveliness_key_expr(
            &self.identity,
            entity_id,
            EntityKind::Publisher,
            topic,
            ty,
            ros2::DEFAULT_QOS_KEY,
        ))?;
        Ok(Topic {
            publisher,
            key_expr,
            gid: random_gid(&self.identity.zid, entity_id),
            next_sequence: 1,
        })
    }

    /// Waits up to `timeout` until the ROS graph has a subscription to `topic`: a liveliness token
    /// `@ros2_lv/<domain>/.../MS/.../<mangled topic>/...`, as rmw_zenoh declares for each subscription.
    pub fn wait_for_subscription(
        &self,
        topic: &str,
        timeout: Duration,
    ) -> Result<(), Ros2PlayError> {
        let domain_id = self.identity.domain_id;
        let selector = format!("{}/{domain_id}/**/MS/**", ros2::LIVELINESS_ADMIN_SPACE);
        let mangled = ros2::mangle_name(&ros2::fully_qualified_topic(topic));
        let subscriber = self
            .session
            .liveliness()
            .declare_subscriber(selector.clone())
            .history(true)
            .wait()
            .map_err(zenoh_error(format!("subscribing to liveliness {selector}")))?;
        let deadline = Instant::now() + timeout;
        loop {
            match subscriber.recv_deadline(deadline) {
                Ok(Some(sample)) => {
                    let key = sample.key_expr().as_str();
                    let mut chunks = key
                        .split('/')
                        .skip_while(|c| *c != EntityKind::Subscription.code());
                    if sample.kind() == SampleKind::Put && chunks.any(|c| c == mangled) {
                        return Ok(());
                    }
                }
                Ok(None) | Err(_) => {
                    return Err(Ros2PlayError::NoSubscriber {
                        topic: ros2::fully_qualified_topic(topic),
                        domain_id,
                        seconds: timeout.as_secs_f64(),
                    });
                }
            }
        }
    }

    /// Undeclares the liveliness tokens and closes the session.
    pub fn close(mut self) -> Result<(), Ros2PlayError> {
        for token in self.tokens.drain(..) {
            token
                .undeclare()
                .wait()
                .map_err(zenoh_error("undeclaring a liveliness token".into()))?;
        }
        self.session
            .close()
            .wait()
            .map_err(zenoh_error("closing the zenoh session".into()))
    }
}

/// Nanoseconds since the Unix epoch on the system clock (0 before it).
pub fn system_time_ns() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| i64::try_from(d.as_nanos()).unwrap_or(i64::MAX))
}

/// A random 16-byte GID: std's randomly keyed SipHash (keys seeded from the OS) over the session id, the entity id
/// and the time, as rmw_zenoh's publishers draw theirs at random.
fn random_gid(zid: &str, entity_id: u64) -> [u8; GID_LEN] {
    let mut gid = [0u8; GID_LEN];
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
