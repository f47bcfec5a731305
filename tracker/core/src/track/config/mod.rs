//! Tracker parameters and the method presets (`eventtrack6d`, `depth30`, `events-only`).

use super::estimate::TrackingState;
use serde::{Deserialize, Serialize};

#[macro_use]
mod flat_keys;
mod parameters;

pub use parameters::{
    CorrespondConfig, ExecutionConfig, InnerStepConfig, LateDepthConfig, ModalityConfig,
    MotionConfig, OptimiserConfig, RoiConfig, SafetyNetConfig, TrackerConfig, TrackerParameterKeys,
};

/// When the depth modality is used.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum DepthUse {
    /// `D_t` at every tick: the fresh frame at depth-exposure ticks, the carried `D_0` in between (ours).
    EveryTick,
    /// Only at depth-exposure ticks; no refinement in between (the `depth30` baseline holds the pose).
    DepthFramesOnly,
    /// Only the first depth frame (the `events-only` baseline).
    FirstFrameOnly,
    /// Never.
    Off,
}

/// Quality thresholds that set the tracking state.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct QualityConfig {
    /// Below this quality the state is `degraded`.
    pub degraded_below: f32,
    /// Below this quality for `lost_after_ticks` consecutive ticks the state is `lost`.
    pub lost_below: f32,
    /// Consecutive low-quality ticks before `lost` is raised.
    pub lost_after_ticks: u32,
    /// `lost` is also raised while the mean quality over the last `lost_mean_ticks` ticks is below this: a track
    /// that stays mediocre (an estimate off the object that the data half supports) without ever dropping below
    /// `lost_below` for long. A re-detection restarts this window but not the run of `lost_after_ticks`.
    pub lost_mean_below: f32,
    /// Length of that window, ticks (0 disables the rule; 60 is 0.5 s at 120 Hz).
    pub lost_mean_ticks: u32,
    /// A better state is reported (pose CSV, zenoh, CAN, status) only after better states held for this many
    /// ticks in a row; a worse one at once. 0 or 1 reports every tick's state. The tracker's own decisions
    /// (prediction, re-detection) use each tick's state.
    pub recover_ticks: u32,
}

impl Default for QualityConfig {
    fn default() -> Self {
        Self {
            degraded_below: 0.5,
            lost_below: 0.2,
            lost_after_ticks: 12,
            lost_mean_below: 0.35,
            lost_mean_ticks: 60,
            recover_ticks: 6,
        }
    }
}

impl QualityConfig {
    /// The state of an estimate of `quality`, after `low_ticks` consecutive ticks below `lost_below` (this one
    /// included) and with `recent_mean` the mean quality over the last `lost_mean_ticks` ticks (`None` until
    /// that many ticks have passed).
    pub fn state(&self, quality: f32, low_ticks: u32, recent_mean: Option<f64>) -> TrackingState {
        let mediocre = recent_mean.is_some_and(|m| m < f64::from(self.lost_mean_below));
        if low_ticks >= self.lost_after_ticks || mediocre {
            TrackingState::Lost
        } else if quality < self.degraded_below {
            TrackingState::Degraded
        } else {
            TrackingState::Tracking
        }
    }
}

/// Largest [`LateDepthConfig::max_depth_age_ms`]: the span the per-object pose history covers at 120 Hz, less a
/// tick.
pub const MAX_DEPTH_AGE_LIMIT_MS: f64 = 500.0;

/// Largest [`InnerStepConfig::max_inner_steps`]: the pose history keeps 64 ticks' estimates with this many steps
/// between each two.
pub const MAX_INNER_STEPS: u32 = 7;

/// A named tracking method: ours or one of the baselines, all on the same tracker code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TrackingMethod {
    /// EventTrack6D: events + carried depth at every tick, fresh depth at exposures.
    #[serde(rename = "eventtrack6d")]
    EventTrack6d,
    /// Render-and-compare on depth only at depth frames (30 Hz), pose held in between.
    #[serde(rename = "depth30")]
    Depth30,
    /// Events only after the first depth frame.
    EventsOnly,
}

impl TrackingMethod {
    /// Every method, in report order.
    pub const ALL: [TrackingMethod; 3] = [Self::EventTrack6d, Self::Depth30, Self::EventsOnly];

    /// The method's name in configs, CLIs and reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::EventTrack6d => "eventtrack6d",
            Self::Depth30 => "depth30",
            Self::EventsOnly => "events-only",
        }
    }

    /// The method for a name, if any.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }

    /// `base` with this method's modality schedule applied.
    pub fn configure(self, base: &TrackerConfig) -> TrackerConfig {
        let mut c = base.clone();
        match self {
            Self::EventTrack6d => {}
            Self::Depth30 => {
                c.modalities.depth = DepthUse::DepthFramesOnly;
                c.modalities.events = false;
                c.motion.prediction = false;
            }
            Self::EventsOnly => {
                c.modalities.depth = DepthUse::FirstFrameOnly;
                c.modalities.events = true;
                // No depth after the first frame: nothing to re-detect with.
                c.redetect.enabled = false;
            }
        }
        c
    }
}

impl std::fmt::Display for TrackingMethod {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn state_is_lost_after_a_run_of_low_ticks_or_a_mediocre_window() {
        let q = QualityConfig::default();
        assert_eq!(q.state(0.9, 0, Some(0.9)), TrackingState::Tracking);
        assert_eq!(q.state(0.3, 0, Some(0.9)), TrackingState::Degraded);
        assert_eq!(q.state(0.1, 11, None), TrackingState::Degraded);
        assert_eq!(q.state(0.1, 12, None), TrackingState::Lost);
        // Never 12 low ticks in a row, but mediocre for the whole window: lost even on a good tick.
        assert_eq!(q.state(0.9, 0, Some(0.3)), TrackingState::Lost);
        assert_eq!(q.state(0.3, 0, Some(0.4)), TrackingState::Degraded);
        assert_eq!(q.state(0.3, 0, None), TrackingState::Degraded);
    }

    #[test]
    fn flat_keys_land_in_their_groups_and_round_trip() {
        let text = "roi_size = 128\nevents = false\nprediction_gain = 0.25\nmax_event_points = 50\n\
                    iterations = 7\ndepth_fallback_anchored = false\nretrack_max_events = 9\n\
                    object_threads = 3\n[quality]\nrecover_ticks = 2\n";
        let c: TrackerConfig = toml::from_str(text).unwrap();
        assert_eq!(c.roi.roi_size, 128);
        assert!(!c.modalities.events);
        assert_eq!(c.motion.prediction_gain, 0.25);
        assert_eq!(c.correspond.max_event_points, 50);
        assert_eq!(c.optimiser.iterations, 7);
        assert!(!c.safety_net.depth_fallback_anchored);
        assert_eq!(c.late_depth.retrack_max_events, 9);
        assert_eq!(c.execution.object_threads, 3);
        assert_eq!(c.quality.recover_ticks, 2);
        // Keys not given keep their defaults.
        assert_eq!(c.roi.roi_scale, TrackerConfig::default().roi.roi_scale);
        let written = serde_json::to_value(&c).unwrap();
        assert_eq!(written["roi_size"], 128, "the keys stay flat: {written}");
        assert!(written.get("roi").is_none(), "{written}");
        assert_eq!(serde_json::from_value::<TrackerConfig>(written).unwrap(), c);
    }

    #[test]
    fn an_unknown_or_mistyped_key_is_named_with_its_line() {
        let e = toml::from_str::<TrackerConfig>("roi_size = 128\nroi_sise = 1\n").unwrap_err();
        let e = e.to_string();
        assert!(e.contains("roi_sise") && e.contains("line 2"), "{e}");
        let e = toml::from_str::<TrackerConfig>("\niterations = \"five\"\n").unwrap_err();
        let e = e.to_string();
        assert!(e.contains("line 2") && e.contains("iterations"), "{e}");
    }
}
