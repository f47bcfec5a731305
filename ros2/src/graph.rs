//! rmw_zenoh's side of the ROS 2 graph: the per-sample attachment, topic key expressions, name checks and
//! the liveliness tokens of a node and its publishers.

use crate::types::{POSE_STAMPED, RosType};
use crate::{ATTACHMENT_LEN, CdrError, GID_LEN, LIVELINESS_ADMIN_SPACE};

/// rmw_zenoh's per-sample attachment.
///
/// Wire layout (33 bytes, zenoh-ext serialization as in rmw_zenoh's `AttachmentData::serialize_to_zbytes`):
/// `0..8` sequence number `i64` LE; `8..16` source timestamp `i64` LE (ns since the Unix epoch, system clock);
/// `16` the GID's sequence length as a LEB128 varint, always `0x10`; `17..33` the 16 GID bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Attachment {
    /// Per-publisher sequence number; rmw_zenoh starts at 1 and increments by 1 per sample.
    pub sequence_number: i64,
    /// Publication time, nanoseconds since the Unix epoch (system clock).
    pub source_timestamp_ns: i64,
    /// The publisher's GID.
    pub gid: [u8; GID_LEN],
}

impl Attachment {
    /// The 33 wire bytes.
    pub fn to_bytes(&self) -> [u8; ATTACHMENT_LEN] {
        let mut b = [0u8; ATTACHMENT_LEN];
        b[0..8].copy_from_slice(&self.sequence_number.to_le_bytes());
        b[8..16].copy_from_slice(&self.source_timestamp_ns.to_le_bytes());
        b[16] = GID_LEN as u8;
        b[17..33].copy_from_slice(&self.gid);
        b
    }

    /// Parses the 33 wire bytes.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, CdrError> {
        let b: &[u8; ATTACHMENT_LEN] = bytes
            .try_into()
            .map_err(|_| CdrError::AttachmentLength { len: bytes.len() })?;
        if b[16] != GID_LEN as u8 {
            return Err(CdrError::AttachmentGidLength(b[16]));
        }
        let mut seq = [0u8; 8];
        seq.copy_from_slice(&b[0..8]);
        let mut ts = [0u8; 8];
        ts.copy_from_slice(&b[8..16]);
        let mut gid = [0u8; GID_LEN];
        gid.copy_from_slice(&b[17..33]);
        Ok(Self {
            sequence_number: i64::from_le_bytes(seq),
            source_timestamp_ns: i64::from_le_bytes(ts),
            gid,
        })
    }
}

/// Fully qualified ROS topic name: exactly one leading `/`, no trailing `/` (`eventtrack6d/a/pose` ->
/// `/eventtrack6d/a/pose`).
pub fn fully_qualified_topic(topic: &str) -> String {
    format!("/{}", topic.trim_matches('/'))
}

/// The zenoh key expression rmw_zenoh uses for a topic's data: `<domain>/<topic>/<type name>/<type hash>` with the
/// topic's leading and trailing `/` removed.
pub fn topic_key_expr(domain_id: u32, topic: &str, type_name: &str, type_hash: &str) -> String {
    format!(
        "{domain_id}/{}/{type_name}/{type_hash}",
        topic.trim_matches('/')
    )
}

/// The rmw_zenoh data key expression of a `geometry_msgs/msg/PoseStamped` topic.
pub fn pose_stamped_key_expr(domain_id: u32, topic: &str) -> String {
    typed_key_expr(domain_id, topic, &POSE_STAMPED)
}

/// The rmw_zenoh data key expression of a topic or service of type `ty`.
pub fn typed_key_expr(domain_id: u32, name: &str, ty: &RosType) -> String {
    topic_key_expr(domain_id, name, ty.key_name, ty.hash)
}

/// rmw_zenoh's name mangling for liveliness key components: every `/` becomes `%`.
pub fn mangle_name(name: &str) -> String {
    name.replace('/', "%")
}

/// Identity of the ROS 2 node that a zenoh session presents to the ROS graph.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RosNodeIdentity {
    /// ROS domain id (`ROS_DOMAIN_ID`).
    pub domain_id: u32,
    /// The zenoh session id as zenoh prints it (`Session::zid().to_string()`).
    pub zid: String,
    /// Node entity id, unique within the session.
    pub node_id: u64,
    /// Security enclave, `/` by default.
    pub enclave: String,
    /// Node namespace, `/` for the root namespace.
    pub namespace: String,
    /// Node name.
    pub name: String,
}

impl RosNodeIdentity {
    fn prefix(&self, entity_id: u64, kind: &str) -> String {
        format!(
            "{LIVELINESS_ADMIN_SPACE}/{}/{}/{}/{entity_id}/{kind}/{}/{}/{}",
            self.domain_id,
            self.zid,
            self.node_id,
            mangle_name(&self.enclave),
            mangle_name(&self.namespace),
            mangle_name(&self.name),
        )
    }
}

/// Liveliness token of a node (entity kind `NN`; the entity id is the node id):
/// `@ros2_lv/<domain>/<zid>/<node id>/<node id>/NN/<enclave>/<namespace>/<name>`, each name mangled.
pub fn node_liveliness_key_expr(node: &RosNodeIdentity) -> String {
    node.prefix(node.node_id, "NN")
}

/// Liveliness token of a publisher (entity kind `MP`):
/// `@ros2_lv/<domain>/<zid>/<node id>/<entity id>/MP/<enclave>/<namespace>/<node name>/<topic>/<type>/<hash>/<qos>`,
/// where the topic is fully qualified and every name mangled (`/` -> `%`), and `qos` is rmw_zenoh's QoS string
/// ([`DEFAULT_QOS_KEY`] for the default profile).
pub fn publisher_liveliness_key_expr(
    node: &RosNodeIdentity,
    entity_id: u64,
    topic: &str,
    type_name: &str,
    type_hash: &str,
    qos: &str,
) -> String {
    entity_token(
        node,
        entity_id,
        EntityKind::Publisher,
        topic,
        type_name,
        type_hash,
        qos,
    )
}

/// The kinds of ROS 2 entities a liveliness token announces.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EntityKind {
    /// A topic publisher (`MP`).
    Publisher,
    /// A topic subscription (`MS`).
    Subscription,
    /// A service server (`SS`).
    ServiceServer,
    /// A service client (`SC`).
    ServiceClient,
}

impl EntityKind {
    /// The two letters rmw_zenoh writes for the kind.
    pub fn code(self) -> &'static str {
        match self {
            Self::Publisher => "MP",
            Self::Subscription => "MS",
            Self::ServiceServer => "SS",
            Self::ServiceClient => "SC",
        }
    }
}

/// Liveliness token of a publisher, subscription, service server or client of type `ty` on `name` (a topic or
/// service name), with rmw_zenoh's QoS string `qos`; see [`publisher_liveliness_key_expr`] for the layout.
pub fn entity_liveliness_key_expr(
    node: &RosNodeIdentity,
    entity_id: u64,
    kind: EntityKind,
    name: &str,
    ty: &RosType,
    qos: &str,
) -> String {
    entity_token(node, entity_id, kind, name, ty.key_name, ty.hash, qos)
}

fn entity_token(
    node: &RosNodeIdentity,
    entity_id: u64,
    kind: EntityKind,
    name: &str,
    type_name: &str,
    type_hash: &str,
    qos: &str,
) -> String {
    format!(
        "{}/{}/{}/{}/{qos}",
        node.prefix(entity_id, kind.code()),
        mangle_name(&fully_qualified_topic(name)),
        mangle_name(type_name),
        mangle_name(type_hash),
    )
}

/// Checks that `name` is a valid ROS 2 name token (letters, digits and `_`, not starting with a digit), so that it
/// can appear in a topic name and in a zenoh key expression. Returns what is wrong otherwise.
pub fn check_name_token(name: &str) -> Result<(), String> {
    if name.is_empty() {
        return Err("is empty".into());
    }
    if name.starts_with(|c: char| c.is_ascii_digit()) {
        return Err("starts with a digit".into());
    }
    if let Some(c) = name
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || *c == '_'))
    {
        return Err(format!(
            "contains {c:?} (only ASCII letters, digits and '_' are allowed)"
        ));
    }
    Ok(())
}

/// Checks a topic prefix or namespace made of `/`-separated name tokens (leading/trailing `/` ignored; `/` alone
/// or empty is the root and is valid).
pub fn check_name_path(path: &str) -> Result<(), String> {
    let trimmed = path.trim_matches('/');
    if trimmed.is_empty() {
        return Ok(());
    }
    for token in trimmed.split('/') {
        check_name_token(token).map_err(|e| format!("component {token:?} {e}"))?;
    }
    Ok(())
}
