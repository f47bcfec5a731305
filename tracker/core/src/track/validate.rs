//! Range checks of [`TrackerConfig`]: a parameter file is user input, and a value such as a zero prior or a NaN
//! gain would otherwise turn into silent NaN poses. Every error names the TOML key.

use super::config::{MAX_DEPTH_AGE_LIMIT_MS, TrackerConfig};

/// A tracker parameter outside its valid range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("tracker parameter `{key}` = {value}: {expected}")]
pub struct InvalidParameter {
    /// The TOML key (with its table, e.g. `event_term.sigma_px`).
    pub key: &'static str,
    /// The value given.
    pub value: String,
    /// What the key accepts.
    pub expected: &'static str,
}

const POSITIVE: &str = "must be a finite number > 0";
const NON_NEGATIVE: &str = "must be a finite number >= 0";
const UNIT: &str = "must be a finite number in [0, 1]";

/// What a parameter must be.
#[derive(Debug, Clone, Copy)]
enum Rule {
    /// Greater than 0 (the message says how).
    Positive(&'static str),
    /// 0 or more.
    NonNegative,
    /// In [0, 1].
    Unit,
    /// In (0, 1] (the message says how).
    PositiveUnit(&'static str),
    /// Any finite number.
    Finite,
    /// In [low, high] (the message says so in the key's units).
    Within(f64, f64, &'static str),
    /// At most the bound.
    AtMost(f64, &'static str),
    /// At least the bound.
    AtLeast(f64, &'static str),
}

impl Rule {
    /// Whether finite `v` follows the rule, and how the rule is worded.
    fn accepts(self, v: f64) -> (bool, &'static str) {
        match self {
            Rule::Positive(expected) => (v > 0.0, expected),
            Rule::NonNegative => (v >= 0.0, NON_NEGATIVE),
            Rule::Unit => ((0.0..=1.0).contains(&v), UNIT),
            Rule::PositiveUnit(expected) => (v > 0.0 && v <= 1.0, expected),
            Rule::Finite => (true, "must be a finite number"),
            Rule::Within(low, high, expected) => ((low..=high).contains(&v), expected),
            Rule::AtMost(high, expected) => (v <= high, expected),
            Rule::AtLeast(low, expected) => (v >= low, expected),
        }
    }
}

/// One parameter's value and the rule it must follow.
#[derive(Debug, Clone, Copy)]
struct Check {
    key: &'static str,
    value: f64,
    rule: Rule,
}

impl Check {
    fn new(key: &'static str, value: f64, rule: Rule) -> Self {
        Self { key, value, rule }
    }

    /// `Ok` if the value is finite and follows the rule, else the error naming the key.
    fn run(&self) -> Result<(), InvalidParameter> {
        let (ok, expected) = self.rule.accepts(self.value);
        if self.value.is_finite() && ok {
            Ok(())
        } else {
            Err(InvalidParameter {
                key: self.key,
                value: self.value.to_string(),
                expected,
            })
        }
    }
}

/// Checks every numeric parameter of `config`; the first offending key is reported.
pub fn validate(config: &TrackerConfig) -> Result<(), InvalidParameter> {
    view_checks(config).iter().try_for_each(Check::run)?;
    optimiser_checks(config).iter().try_for_each(Check::run)?;
    motion_checks(config).iter().try_for_each(Check::run)?;
    depth_use_checks(config).iter().try_for_each(Check::run)?;
    event_use_checks(config).iter().try_for_each(Check::run)?;
    depth_term_checks(config).iter().try_for_each(Check::run)?;
    intensity_term_checks(config)
        .iter()
        .try_for_each(Check::run)?;
    event_term_checks(config).iter().try_for_each(Check::run)?;
    quality_checks(config).iter().try_for_each(Check::run)?;
    redetect_checks(config).iter().try_for_each(Check::run)?;
    Ok(())
}

/// The checks of the region of interest, rendering and threads, in the order they are reported.
fn view_checks(config: &TrackerConfig) -> [Check; 8] {
    [
        Check::new(
            "roi_size",
            f64::from(config.roi.roi_size),
            Rule::Within(16.0, 1024.0, "must be 16 to 1024 pixels"),
        ),
        Check::new(
            "roi_scale",
            config.roi.roi_scale,
            Rule::Within(0.5, 4.0, "must be 0.5 to 4 diameters"),
        ),
        Check::new(
            "object_threads",
            config.execution.object_threads as f64,
            Rule::AtMost(256.0, "must be 0 (one per core) to 256"),
        ),
        Check::new(
            "render_mesh_simplify_above",
            config.execution.render_mesh_simplify_above as f64,
            Rule::AtMost(100_000_000.0, "must be at most 100000000 triangles"),
        ),
        Check::new(
            "render_mesh_tolerance_px",
            config.execution.render_mesh_tolerance_px,
            Rule::Within(0.0, 2.0, "must be 0 (the mesh as loaded) to 2 ROI pixels"),
        ),
        Check::new(
            "max_surface_points",
            config.correspond.max_surface_points as f64,
            Rule::Positive("must be at least 1"),
        ),
        Check::new(
            "max_contour_points",
            config.correspond.max_contour_points as f64,
            Rule::Positive("must be at least 1"),
        ),
        Check::new(
            "max_event_points",
            config.correspond.max_event_points as f64,
            Rule::Positive("must be at least 1"),
        ),
    ]
}

/// The checks of the optimiser and its prior, in the order they are reported.
fn optimiser_checks(config: &TrackerConfig) -> [Check; 6] {
    [
        Check::new(
            "iterations",
            f64::from(config.optimiser.iterations),
            Rule::AtMost(100.0, "must be at most 100"),
        ),
        Check::new("damping", config.optimiser.damping, Rule::NonNegative),
        Check::new(
            "max_step_rotation_deg",
            config.optimiser.max_step_rotation_deg,
            Rule::Positive(POSITIVE),
        ),
        Check::new(
            "max_step_translation_diameters",
            config.optimiser.max_step_translation_diameters,
            Rule::Positive(POSITIVE),
        ),
        Check::new(
            "prior_translation_m",
            config.optimiser.prior_translation_m,
            Rule::Positive(POSITIVE),
        ),
        Check::new(
            "prior_rotation_deg",
            config.optimiser.prior_rotation_deg,
            Rule::Positive(POSITIVE),
        ),
    ]
}

/// The checks of the motion model, in the order they are reported.
fn motion_checks(config: &TrackerConfig) -> [Check; 9] {
    [
        Check::new(
            "inner_step_px",
            config.inner_steps.inner_step_px,
            Rule::NonNegative,
        ),
        Check::new(
            "max_inner_steps",
            f64::from(config.inner_steps.max_inner_steps),
            Rule::AtMost(
                crate::track::config::MAX_INNER_STEPS as f64,
                "must be at most 7",
            ),
        ),
        Check::new(
            "line_of_sight_sigma_m",
            config.inner_steps.line_of_sight_sigma_m,
            Rule::Positive(POSITIVE),
        ),
        Check::new(
            "prediction_gain",
            config.motion.prediction_gain,
            Rule::Within(0.0, 2.0, "must be 0 to 2"),
        ),
        Check::new(
            "velocity_smoothing",
            config.motion.velocity_smoothing,
            Rule::Unit,
        ),
        Check::new(
            "velocity_smoothing_depth",
            config.motion.velocity_smoothing_depth,
            Rule::Unit,
        ),
        Check::new(
            "range_acceleration_share",
            config.motion.range_acceleration_share,
            Rule::Unit,
        ),
        Check::new(
            "max_speed",
            config.motion.max_speed,
            Rule::Positive(POSITIVE),
        ),
        Check::new(
            "max_angular_speed",
            config.motion.max_angular_speed,
            Rule::Positive(POSITIVE),
        ),
    ]
}

/// The checks of the use of depth: carried, late, the safety net, in the order they are reported.
fn depth_use_checks(config: &TrackerConfig) -> [Check; 8] {
    [
        Check::new(
            "carried_depth_weight",
            config.modalities.carried_depth_weight,
            Rule::NonNegative,
        ),
        Check::new(
            "hide_occluded_max_share",
            config.correspond.hide_occluded_max_share,
            Rule::Within(0.0, 1.0, "must be 0 to 1"),
        ),
        Check::new(
            "max_depth_age_ms",
            config.late_depth.max_depth_age_ms,
            Rule::Within(0.0, MAX_DEPTH_AGE_LIMIT_MS, "must be 0 to 500 ms"),
        ),
        Check::new(
            "retrack_max_events",
            config.late_depth.retrack_max_events as f64,
            Rule::AtMost(100_000_000.0, "must be at most 100000000 (2.4 GB)"),
        ),
        Check::new(
            "depth_fallback_margin",
            config.safety_net.depth_fallback_margin,
            Rule::Finite,
        ),
        Check::new(
            "depth_fallback_motion_margin",
            config.safety_net.depth_fallback_motion_margin,
            Rule::Finite,
        ),
        Check::new(
            "depth_fallback_estimate_motion_margin",
            config.safety_net.depth_fallback_estimate_motion_margin,
            Rule::Finite,
        ),
        Check::new(
            "depth_fallback_event_weight",
            config.safety_net.depth_fallback_event_weight,
            Rule::AtLeast(0.0, "must be 0 or more"),
        ),
    ]
}

/// The checks of the use of events and intensity, in the order they are reported.
fn event_use_checks(config: &TrackerConfig) -> [Check; 6] {
    [
        Check::new(
            "event_weight",
            config.modalities.event_weight,
            Rule::NonNegative,
        ),
        Check::new(
            "event_window_px",
            config.correspond.event_window_px,
            Rule::Positive(POSITIVE),
        ),
        Check::new(
            "min_event_window_us",
            config.correspond.min_event_window_us as f64,
            Rule::NonNegative,
        ),
        Check::new(
            "max_event_window_us",
            config.correspond.max_event_window_us as f64,
            Rule::AtLeast(
                config.correspond.min_event_window_us as f64,
                "must be >= min_event_window_us",
            ),
        ),
        Check::new(
            "intensity.contrast",
            f64::from(config.intensity.contrast),
            Rule::Positive(POSITIVE),
        ),
        Check::new(
            "intensity.cutoff_hz",
            f64::from(config.intensity.cutoff_hz),
            Rule::NonNegative,
        ),
    ]
}

/// The checks of the depth term, in the order they are reported.
fn depth_term_checks(config: &TrackerConfig) -> [Check; 7] {
    let d = &config.depth_term;
    [
        Check::new("depth_term.sigma_0", d.sigma_0, Rule::Positive(POSITIVE)),
        Check::new("depth_term.sigma_z2", d.sigma_z2, Rule::NonNegative),
        Check::new(
            "depth_term.occlusion_gap",
            d.occlusion_gap,
            Rule::Positive(POSITIVE),
        ),
        Check::new(
            "depth_term.max_residual",
            d.max_residual,
            Rule::Positive(POSITIVE),
        ),
        Check::new(
            "event_term.contrast_step_translation",
            config.event_term.contrast_step_translation,
            Rule::NonNegative,
        ),
        Check::new(
            "event_term.contrast_step_rotation",
            config.event_term.contrast_step_rotation,
            Rule::NonNegative,
        ),
        Check::new(
            "event_term.contrast_rounds",
            f64::from(config.event_term.contrast_rounds),
            Rule::AtMost(16.0, "must be at most 16"),
        ),
    ]
}

/// The checks of the intensity term, in the order they are reported.
fn intensity_term_checks(config: &TrackerConfig) -> [Check; 6] {
    let it = &config.intensity_term;
    [
        Check::new("intensity_term.weight", it.weight, Rule::NonNegative),
        Check::new(
            "intensity_term.box_px",
            f64::from(it.box_px),
            Rule::Within(1.0, 16.0, "must be 1 to 16"),
        ),
        Check::new("intensity_term.min_step", it.min_step, Rule::NonNegative),
        Check::new(
            "intensity_term.full_step",
            it.full_step,
            Rule::Positive(POSITIVE),
        ),
        Check::new(
            "intensity_term.max_distance_px",
            it.max_distance_px,
            Rule::Within(0.0, 100.0, "must be 0 to 100"),
        ),
        Check::new(
            "intensity_term.sigma_px",
            it.sigma_px,
            Rule::Positive(POSITIVE),
        ),
    ]
}

/// The checks of the event term, in the order they are reported.
fn event_term_checks(config: &TrackerConfig) -> [Check; 14] {
    let e = &config.event_term;
    [
        Check::new(
            "event_term.line_box_bins",
            f64::from(e.line_box_bins),
            Rule::Within(1.0, 32.0, "must be 1 to 32"),
        ),
        Check::new(
            "event_term.line_min_contrast",
            e.line_min_contrast,
            Rule::PositiveUnit("must be in (0, 1]"),
        ),
        Check::new("event_term.sigma_px", e.sigma_px, Rule::Positive(POSITIVE)),
        Check::new(
            "event_term.max_distance_px",
            e.max_distance_px,
            Rule::Positive(POSITIVE),
        ),
        Check::new(
            "event_term.match_distance_px",
            e.match_distance_px,
            Rule::NonNegative,
        ),
        Check::new("event_term.match_weight", e.match_weight, Rule::NonNegative),
        Check::new("event_term.min_sweep_px", e.min_sweep_px, Rule::NonNegative),
        Check::new(
            "event_term.edge_tolerance_px",
            e.edge_tolerance_px,
            Rule::NonNegative,
        ),
        Check::new("event_term.hinge_weight", e.hinge_weight, Rule::NonNegative),
        Check::new(
            "event_term.search_px",
            e.search_px,
            Rule::Within(0.0, 200.0, "must be 0 to 200 pixels"),
        ),
        Check::new(
            "event_term.search_min_px",
            e.search_min_px,
            Rule::NonNegative,
        ),
        Check::new(
            "event_term.search_speed_factor",
            e.search_speed_factor,
            Rule::NonNegative,
        ),
        Check::new(
            "event_term.search_min_gain",
            e.search_min_gain,
            Rule::NonNegative,
        ),
        Check::new(
            "event_term.search_aperture_tolerance",
            e.search_aperture_tolerance,
            Rule::Unit,
        ),
    ]
}

/// The checks of quality and state, in the order they are reported.
fn quality_checks(config: &TrackerConfig) -> [Check; 5] {
    let q = &config.quality;
    [
        Check::new(
            "quality.degraded_below",
            f64::from(q.degraded_below),
            Rule::Unit,
        ),
        Check::new("quality.lost_below", f64::from(q.lost_below), Rule::Unit),
        Check::new(
            "quality.lost_mean_below",
            f64::from(q.lost_mean_below),
            Rule::Unit,
        ),
        Check::new(
            "quality.lost_mean_ticks",
            f64::from(q.lost_mean_ticks),
            Rule::AtMost(12_000.0, "must be at most 12000 ticks (100 s at 120 Hz)"),
        ),
        Check::new(
            "quality.recover_ticks",
            f64::from(q.recover_ticks),
            Rule::AtMost(12_000.0, "must be at most 12000 ticks (100 s at 120 Hz)"),
        ),
    ]
}

/// The checks of re-detection, in the order they are reported.
fn redetect_checks(config: &TrackerConfig) -> [Check; 11] {
    let r = &config.redetect;
    [
        Check::new(
            "redetect.cell_px",
            f64::from(r.cell_px),
            Rule::Within(1.0, 64.0, "must be 1 to 64 depth pixels"),
        ),
        Check::new(
            "redetect.foreground_margin_m",
            r.foreground_margin_m,
            Rule::NonNegative,
        ),
        Check::new(
            "redetect.candidates",
            r.candidates as f64,
            Rule::AtMost(16.0, "must be at most 16"),
        ),
        Check::new(
            "redetect.foreground_sigmas",
            r.foreground_sigmas,
            Rule::NonNegative,
        ),
        Check::new("redetect.min_support", r.min_support, Rule::NonNegative),
        Check::new("redetect.margin", r.margin, Rule::NonNegative),
        Check::new("redetect.min_score", r.min_score, Rule::Unit),
        Check::new(
            "redetect.pose_search_views",
            r.pose_search_views as f64,
            Rule::AtMost(1000.0, "must be at most 1000"),
        ),
        Check::new(
            "redetect.pose_search_rolls",
            r.pose_search_rolls as f64,
            Rule::AtMost(64.0, "must be at most 64"),
        ),
        Check::new(
            "redetect.pose_search_places",
            r.pose_search_places as f64,
            Rule::AtMost(16.0, "must be at most 16"),
        ),
        Check::new(
            "redetect.pose_search_pulls",
            r.pose_search_pulls as f64,
            Rule::AtMost(8.0, "must be at most 8"),
        ),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid() {
        assert_eq!(validate(&TrackerConfig::default()), Ok(()));
    }

    #[test]
    fn errors_name_the_key() {
        let parse = |text: &str| validate(&toml::from_str::<TrackerConfig>(text).unwrap());
        let e = parse("prior_translation_m = 0.0").unwrap_err();
        assert_eq!(e.key, "prior_translation_m");
        let e = parse("hide_occluded_max_share = 1.5").unwrap_err();
        assert!(
            e.to_string().contains("`hide_occluded_max_share` = 1.5"),
            "{e}"
        );
        let e = parse("prediction_gain = nan").unwrap_err();
        assert!(e.to_string().contains("`prediction_gain` = NaN"), "{e}");
        let e = parse("[event_term]\nsigma_px = -1.0").unwrap_err();
        assert_eq!(e.key, "event_term.sigma_px");
        let e = parse("min_event_window_us = 5000\nmax_event_window_us = 1000").unwrap_err();
        assert_eq!(e.key, "max_event_window_us");
        assert_eq!(parse("[event_term]\nsearch_px = 0.0"), Ok(()));
        let e = parse("[redetect]\ncell_px = 0").unwrap_err();
        assert_eq!(e.key, "redetect.cell_px");
        let e = parse("[redetect]\nmin_score = 1.5").unwrap_err();
        assert_eq!(e.key, "redetect.min_score");
        let e = parse("[quality]\nrecover_ticks = 20000").unwrap_err();
        assert_eq!(e.key, "quality.recover_ticks");
        let e = parse("[quality]\nlost_mean_ticks = 20000").unwrap_err();
        assert_eq!(e.key, "quality.lost_mean_ticks");
        // The pose history covers 500 ms; a depth frame older than that could not be placed.
        assert_eq!(parse("retrack_max_events = 0"), Ok(()));
        assert_eq!(
            parse("retrack_max_events = 100000001").unwrap_err().key,
            "retrack_max_events"
        );
        for ok in [
            "render_mesh_tolerance_px = 0.0",
            "render_mesh_tolerance_px = 2.0",
            "render_mesh_simplify_above = 0",
        ] {
            assert_eq!(parse(ok), Ok(()), "{ok}");
        }
        for bad in [
            "render_mesh_tolerance_px = -0.1",
            "render_mesh_tolerance_px = 2.5",
            "render_mesh_tolerance_px = nan",
        ] {
            assert_eq!(
                parse(bad).unwrap_err().key,
                "render_mesh_tolerance_px",
                "{bad}"
            );
        }
        assert_eq!(
            parse("render_mesh_simplify_above = 100000001")
                .unwrap_err()
                .key,
            "render_mesh_simplify_above"
        );
        assert_eq!(parse("max_depth_age_ms = 0.0"), Ok(()));
        assert_eq!(parse("max_depth_age_ms = 500.0"), Ok(()));
        for bad in ["max_depth_age_ms = 501.0", "max_depth_age_ms = -1.0"] {
            assert_eq!(parse(bad).unwrap_err().key, "max_depth_age_ms", "{bad}");
        }
    }
}
