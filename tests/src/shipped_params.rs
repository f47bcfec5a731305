//! The tracker parameter files shipped in `config/tracker/`, for tests and benchmarks that pin a behaviour other
//! than the defaults.

use std::path::PathBuf;
use tracker::track::TrackerConfig;

/// `config/tracker/ticks-only.toml`: one refinement per tick and the motion model before issue #54.
pub fn ticks_only_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../config/tracker/ticks-only.toml")
}

/// The text of `config/tracker/ticks-only.toml`.
pub fn ticks_only_toml() -> String {
    std::fs::read_to_string(ticks_only_path()).unwrap()
}

/// The tracker configuration `config/tracker/ticks-only.toml` gives (its keys over the defaults).
pub fn ticks_only() -> TrackerConfig {
    toml::from_str(&ticks_only_toml()).unwrap()
}
