//! Command-line values several commands share: depth latencies and the tracker parameters file.

use anyhow::{Context, Result};
use std::path::Path;
use tracker::track::TrackerConfig;

/// A depth latency in milliseconds: a finite number from 0 to 1000.
pub fn parse_latency_ms(text: &str) -> Result<f64, String> {
    text.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite() && (0.0..=1000.0).contains(v))
        .ok_or_else(|| format!("`{text}` is not a latency from 0 to 1000 ms"))
}

/// Tracker parameters from a `--params` TOML file (the `[tracker]` table's keys at top level), validated; the
/// defaults without one.
pub fn tracker_params(path: Option<&Path>) -> Result<TrackerConfig> {
    let Some(path) = path else {
        return Ok(TrackerConfig::default());
    };
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let config = toml::from_str::<TrackerConfig>(&text)
        .with_context(|| format!("{}: invalid tracker parameters", path.display()))?;
    tracker::track::validate(&config)
        .with_context(|| format!("{}: invalid tracker parameters", path.display()))?;
    Ok(config)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn the_shipped_ticks_only_parameters_turn_the_fast_motion_options_off() {
        let path =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config/tracker/ticks-only.toml");
        let config = tracker_params(Some(&path)).unwrap();
        let defaults = TrackerConfig::default();
        assert_eq!(defaults.inner_steps.inner_step_px, 6.0);
        assert_eq!(config.inner_steps.inner_step_px, 0.0);
        assert!(defaults.motion.velocity_start_corrected);
        assert!(!config.motion.velocity_start_corrected);
        assert!(defaults.motion.range_from_depth);
        assert!(!config.motion.range_from_depth);
        assert!(!defaults.correspond.events_at_first_pose);
        assert!(config.correspond.events_at_first_pose);
    }

    proptest! {
        /// Any `--depth-latency-ms` text gives a latency of 0..=1000 ms or an error quoting it; written ones read back.
        #[test]
        fn any_latency_text_parses_or_quotes_it(text in "[0-9.eE+ -]{0,10}", ms in 0.0f64..=1000.0) {
            match parse_latency_ms(&text) {
                Ok(v) => prop_assert!((0.0..=1000.0).contains(&v)),
                Err(e) => prop_assert!(e.contains(&format!("`{text}`")), "{}", e),
            }
            prop_assert_eq!(parse_latency_ms(&ms.to_string()), Ok(ms));
        }
    }
}
