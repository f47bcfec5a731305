//! Tests of the zenoh sink's configuration and publishing.

use super::entity::random_gid;
use super::*;

#[test]
fn config_defaults_and_unknown_keys() {
    let c: ZenohConfig = serde_json::from_str("{}").unwrap();
    assert_eq!(c, ZenohConfig::default());
    assert_eq!(c.connect, ["tcp/127.0.0.1:7447"]);
    assert_eq!(c.listen, ["tcp/127.0.0.1:0"]);
    assert!(!c.multicast_scouting);
    assert_eq!(c.mode, SessionMode::Peer);
    assert_eq!(c.congestion_control, CongestionPolicy::Drop);
    assert_eq!(c.pose_topic("mug"), "eventtrack6d/mug/pose");
    assert_eq!(c.status_key_expr(), "eventtrack6d/status");
    assert!(c.pose_queries);
    assert_eq!(c.pose_query_key_expr("mug"), "eventtrack6d/mug/pose_at");
    let e = serde_json::from_str::<ZenohConfig>(r#"{"conect": []}"#).unwrap_err();
    assert!(e.to_string().contains("unknown field `conect`"), "{e}");
    let c: ZenohConfig =
        serde_json::from_str(r#"{"congestion_control": "block", "mode": "client"}"#).unwrap();
    assert_eq!(
        (c.congestion_control, c.mode),
        (CongestionPolicy::Block, SessionMode::Client)
    );
    assert!(serde_json::from_str::<ZenohConfig>(r#"{"congestion_control": "wait"}"#).is_err());
}

#[test]
fn bad_config_values_name_the_key() {
    let c = ZenohConfig {
        topic_prefix: "robot/*".into(),
        ..Default::default()
    };
    let e = c.to_zenoh_config().unwrap_err();
    assert!(e.to_string().starts_with("zenoh.topic_prefix:"), "{e}");
    let c = ZenohConfig {
        connect: vec!["nonsense".into()],
        ..Default::default()
    };
    let e = c.to_zenoh_config().unwrap_err();
    assert!(e.to_string().starts_with("zenoh.connect:"), "{e}");
    let c = ZenohConfig {
        node_name: "my node".into(),
        ..Default::default()
    };
    assert!(
        c.to_zenoh_config()
            .unwrap_err()
            .to_string()
            .starts_with("zenoh.node_name:")
    );
    assert!(ZenohConfig::default().to_zenoh_config().is_ok());
    let root = ZenohConfig {
        topic_prefix: "/".into(),
        ..Default::default()
    };
    assert_eq!(root.pose_topic("mug"), "mug/pose");
}

#[test]
fn gids_differ() {
    let a = random_gid("abc", 1);
    let b = random_gid("abc", 1);
    let c = random_gid("abc", 2);
    assert_ne!(a, b);
    assert_ne!(a, c);
    assert_ne!(a, [0; 16]);
}
