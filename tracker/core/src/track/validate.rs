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

fn check(
    key: &'static str,
    value: f64,
    ok: impl Fn(f64) -> bool,
    expected: &'static str,
) -> Result<(), InvalidParameter> {
    if value.is_finite() && ok(value) {
        Ok(())
    } else {
        Err(InvalidParameter {
            key,
            value: value.to_string(),
            expected,
        })
    }
}

const POSITIVE: &str = "must be a finite number > 0";
const NON_NEGATIVE: &str = "must be a finite number >= 0";
const UNIT: &str = "must be a finite number in [0, 1]";

impl TrackerConfig {
    /// Checks every numeric parameter's range; the first offending key is reported.
    pub fn validate(&self) -> Result<(), InvalidParameter> {
        let pos = |v: f64| v > 0.0;
        let non_neg = |v: f64| v >= 0.0;
        let unit = |v: f64| (0.0..=1.0).contains(&v);
        check(
            "roi_size",
            f64::from(self.roi_size),
            |v| (16.0..=1024.0).contains(&v),
            "must be 16 to 1024 pixels",
        )?;
        check(
            "object_threads",
            self.object_threads as f64,
            |v| v <= 256.0,
            "must be 0 (one per core) to 256",
        )?;
        check(
            "roi_scale",
            self.roi_scale,
            |v| (0.5..=4.0).contains(&v),
            "must be 0.5 to 4 diameters",
        )?;
        check(
            "render_mesh_simplify_above",
            self.render_mesh_simplify_above as f64,
            |v| v <= 100_000_000.0,
            "must be at most 100000000 triangles",
        )?;
        check(
            "render_mesh_tolerance_px",
            self.render_mesh_tolerance_px,
            |v| (0.0..=2.0).contains(&v),
            "must be 0 (the mesh as loaded) to 2 ROI pixels",
        )?;
        check(
            "iterations",
            f64::from(self.iterations),
            |v| v <= 100.0,
            "must be at most 100",
        )?;
        check("damping", self.damping, non_neg, NON_NEGATIVE)?;
        check(
            "max_depth_age_ms",
            self.max_depth_age_ms,
            |v| (0.0..=MAX_DEPTH_AGE_LIMIT_MS).contains(&v),
            "must be 0 to 500 ms",
        )?;
        check(
            "retrack_max_events",
            self.retrack_max_events as f64,
            |v| v <= 100_000_000.0,
            "must be at most 100000000 (2.4 GB)",
        )?;
        check(
            "prediction_gain",
            self.prediction_gain,
            |v| (0.0..=2.0).contains(&v),
            "must be 0 to 2",
        )?;
        check(
            "hide_occluded_max_share",
            self.hide_occluded_max_share,
            |v| (0.0..=1.0).contains(&v),
            "must be 0 to 1",
        )?;
        check(
            "depth_fallback_margin",
            self.depth_fallback_margin,
            |_| true,
            "must be a finite number",
        )?;
        check(
            "depth_fallback_motion_margin",
            self.depth_fallback_motion_margin,
            |_| true,
            "must be a finite number",
        )?;
        check(
            "depth_fallback_estimate_motion_margin",
            self.depth_fallback_estimate_motion_margin,
            |_| true,
            "must be a finite number",
        )?;
        check(
            "depth_fallback_event_weight",
            self.depth_fallback_event_weight,
            |v| v >= 0.0,
            "must be 0 or more",
        )?;
        check(
            "carried_depth_weight",
            self.carried_depth_weight,
            non_neg,
            NON_NEGATIVE,
        )?;
        check("event_weight", self.event_weight, non_neg, NON_NEGATIVE)?;
        check("event_window_px", self.event_window_px, pos, POSITIVE)?;
        check(
            "min_event_window_us",
            self.min_event_window_us as f64,
            non_neg,
            NON_NEGATIVE,
        )?;
        check(
            "max_event_window_us",
            self.max_event_window_us as f64,
            |v| v >= self.min_event_window_us as f64,
            "must be >= min_event_window_us",
        )?;
        check(
            "max_step_rotation_deg",
            self.max_step_rotation_deg,
            pos,
            POSITIVE,
        )?;
        check(
            "max_step_translation_diameters",
            self.max_step_translation_diameters,
            pos,
            POSITIVE,
        )?;
        check(
            "max_surface_points",
            self.max_surface_points as f64,
            pos,
            "must be at least 1",
        )?;
        check(
            "max_contour_points",
            self.max_contour_points as f64,
            pos,
            "must be at least 1",
        )?;
        check(
            "max_event_points",
            self.max_event_points as f64,
            pos,
            "must be at least 1",
        )?;
        check("velocity_smoothing", self.velocity_smoothing, unit, UNIT)?;
        check(
            "velocity_smoothing_depth",
            self.velocity_smoothing_depth,
            unit,
            UNIT,
        )?;
        check("max_speed", self.max_speed, pos, POSITIVE)?;
        check("max_angular_speed", self.max_angular_speed, pos, POSITIVE)?;
        check(
            "prior_translation_m",
            self.prior_translation_m,
            pos,
            POSITIVE,
        )?;
        check("prior_rotation_deg", self.prior_rotation_deg, pos, POSITIVE)?;
        check(
            "intensity.contrast",
            f64::from(self.intensity.contrast),
            pos,
            POSITIVE,
        )?;
        check(
            "intensity.cutoff_hz",
            f64::from(self.intensity.cutoff_hz),
            non_neg,
            NON_NEGATIVE,
        )?;
        let d = &self.depth_term;
        check("depth_term.sigma_0", d.sigma_0, pos, POSITIVE)?;
        check("depth_term.sigma_z2", d.sigma_z2, non_neg, NON_NEGATIVE)?;
        check("depth_term.occlusion_gap", d.occlusion_gap, pos, POSITIVE)?;
        check("depth_term.max_residual", d.max_residual, pos, POSITIVE)?;
        check(
            "event_term.contrast_step_translation",
            self.event_term.contrast_step_translation,
            non_neg,
            NON_NEGATIVE,
        )?;
        check(
            "event_term.contrast_step_rotation",
            self.event_term.contrast_step_rotation,
            non_neg,
            NON_NEGATIVE,
        )?;
        check(
            "event_term.contrast_rounds",
            f64::from(self.event_term.contrast_rounds),
            |v| v <= 16.0,
            "must be at most 16",
        )?;
        let it = &self.intensity_term;
        check("intensity_term.weight", it.weight, non_neg, NON_NEGATIVE)?;
        check(
            "intensity_term.box_px",
            f64::from(it.box_px),
            |v| (1.0..=16.0).contains(&v),
            "must be 1 to 16",
        )?;
        check(
            "intensity_term.min_step",
            it.min_step,
            non_neg,
            NON_NEGATIVE,
        )?;
        check("intensity_term.full_step", it.full_step, pos, POSITIVE)?;
        check(
            "intensity_term.max_distance_px",
            it.max_distance_px,
            |v| (0.0..=100.0).contains(&v),
            "must be 0 to 100",
        )?;
        check("intensity_term.sigma_px", it.sigma_px, pos, POSITIVE)?;
        let e = &self.event_term;
        check(
            "event_term.line_box_bins",
            f64::from(e.line_box_bins),
            |v| (1.0..=32.0).contains(&v),
            "must be 1 to 32",
        )?;
        check(
            "event_term.line_min_contrast",
            e.line_min_contrast,
            |v| v > 0.0 && v <= 1.0,
            "must be in (0, 1]",
        )?;
        check("event_term.sigma_px", e.sigma_px, pos, POSITIVE)?;
        check(
            "event_term.max_distance_px",
            e.max_distance_px,
            pos,
            POSITIVE,
        )?;
        check(
            "event_term.match_distance_px",
            e.match_distance_px,
            non_neg,
            NON_NEGATIVE,
        )?;
        check(
            "event_term.match_weight",
            e.match_weight,
            non_neg,
            NON_NEGATIVE,
        )?;
        check(
            "event_term.min_sweep_px",
            e.min_sweep_px,
            non_neg,
            NON_NEGATIVE,
        )?;
        check(
            "event_term.edge_tolerance_px",
            e.edge_tolerance_px,
            non_neg,
            NON_NEGATIVE,
        )?;
        check(
            "event_term.hinge_weight",
            e.hinge_weight,
            non_neg,
            NON_NEGATIVE,
        )?;
        check(
            "event_term.search_px",
            e.search_px,
            |v| (0.0..=200.0).contains(&v),
            "must be 0 to 200 pixels",
        )?;
        check(
            "event_term.search_min_px",
            e.search_min_px,
            non_neg,
            NON_NEGATIVE,
        )?;
        check(
            "event_term.search_speed_factor",
            e.search_speed_factor,
            non_neg,
            NON_NEGATIVE,
        )?;
        check(
            "event_term.search_min_gain",
            e.search_min_gain,
            non_neg,
            NON_NEGATIVE,
        )?;
        check(
            "event_term.search_aperture_tolerance",
            e.search_aperture_tolerance,
            unit,
            UNIT,
        )?;
        let q = &self.quality;
        check(
            "quality.degraded_below",
            f64::from(q.degraded_below),
            unit,
            UNIT,
        )?;
        check("quality.lost_below", f64::from(q.lost_below), unit, UNIT)?;
        check(
            "quality.lost_mean_below",
            f64::from(q.lost_mean_below),
            unit,
            UNIT,
        )?;
        check(
            "quality.lost_mean_ticks",
            f64::from(q.lost_mean_ticks),
            |v| v <= 12_000.0,
            "must be at most 12000 ticks (100 s at 120 Hz)",
        )?;
        check(
            "quality.recover_ticks",
            f64::from(q.recover_ticks),
            |v| v <= 12_000.0,
            "must be at most 12000 ticks (100 s at 120 Hz)",
        )?;
        let r = &self.redetect;
        check(
            "redetect.cell_px",
            f64::from(r.cell_px),
            |v| (1.0..=64.0).contains(&v),
            "must be 1 to 64 depth pixels",
        )?;
        check(
            "redetect.foreground_margin_m",
            r.foreground_margin_m,
            non_neg,
            NON_NEGATIVE,
        )?;
        check(
            "redetect.candidates",
            r.candidates as f64,
            |v| v <= 16.0,
            "must be at most 16",
        )?;
        check(
            "redetect.foreground_sigmas",
            r.foreground_sigmas,
            non_neg,
            NON_NEGATIVE,
        )?;
        check("redetect.min_support", r.min_support, non_neg, NON_NEGATIVE)?;
        check("redetect.margin", r.margin, non_neg, NON_NEGATIVE)?;
        check("redetect.min_score", r.min_score, unit, UNIT)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid() {
        assert_eq!(TrackerConfig::default().validate(), Ok(()));
    }

    #[test]
    fn errors_name_the_key() {
        let parse = |text: &str| toml::from_str::<TrackerConfig>(text).unwrap().validate();
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
