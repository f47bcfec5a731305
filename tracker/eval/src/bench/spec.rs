//! Method specs as `--methods` names them (`eventtrack6d`, `depth30@1:0.2:3`, `gt-noise:10:5`, ...): parsing,
//! building the method, and expanding first-pose seeds.

use super::harness_checks::{GtNoiseMethod, StaticMethod};
use super::method::Method;
use super::tracker_method::{InitNoise, TrackerMethod};
use tracker::track::DepthTransport;

/// The tracker method `spec` names (`NAME`, `NAME@DEG:CM` or `NAME@DEG:CM:SEED`; seed 1 when not given) on `base`
/// parameters; `None` when it names none.
fn tracker_method_from_spec(
    spec: &str,
    base: &tracker::track::TrackerConfig,
) -> Option<Result<TrackerMethod, String>> {
    if let Some(method) = tracker::track::TrackingMethod::from_name(spec) {
        return Some(Ok(TrackerMethod::new(method, base)));
    }
    let (name, noise) = spec.split_once('@')?;
    let method = tracker::track::TrackingMethod::from_name(name)?;
    let parsed = match noise.split(':').collect::<Vec<_>>().as_slice() {
        [deg, cm] => InitNoise::parse(&format!("{deg},{cm}"), 1),
        [deg, cm, seed] => seed
            .trim()
            .parse::<u64>()
            .map_err(|_| format!("seed `{seed}` is not a whole number >= 0"))
            .and_then(|seed| InitNoise::parse(&format!("{deg},{cm}"), seed)),
        _ => Err(format!(
            "first-pose error `{noise}`: expected DEG:CM or DEG:CM:SEED (e.g. 5:5 or 5:5:2)"
        )),
    };
    // `InitNoise` names the text it parsed (`DEG,CM`); name the one given here.
    let parsed = parsed.map_err(|e| match e.split_once("`: ") {
        Some((head, why)) if head.starts_with("init noise `") => {
            format!("first-pose error `{noise}`: {why}")
        }
        _ => e,
    });
    Some(
        parsed
            .map(|noise| TrackerMethod::new(method, base).with_init_noise(noise))
            .map_err(|e| format!("method `{spec}`: {e}")),
    )
}

/// `specs` with every perturbed tracker method given without a seed (`NAME@DEG:CM`) repeated at seeds 1 to
/// `seeds` (`NAME@DEG:CM:SEED`), in place; other specs, and everything when `seeds` is 1 or less, unchanged.
pub fn expand_seeds(specs: &[String], seeds: u64) -> Vec<String> {
    let mut out = Vec::new();
    for spec in specs {
        let spec = spec.trim();
        let unseeded = spec.split_once('@').is_some_and(|(name, noise)| {
            tracker::track::TrackingMethod::from_name(name).is_some()
                && noise.split(':').count() == 2
        });
        if unseeded && seeds > 1 {
            out.extend((1..=seeds).map(|k| format!("{spec}:{k}")));
        } else {
            out.push(spec.to_string());
        }
    }
    out
}

/// Builds a method from its spec: a tracker method (`eventtrack6d`, `depth30`, `events-only`, optionally
/// `NAME@DEG:CM` or `NAME@DEG:CM:SEED` with a perturbed first pose), `static`, `gt-noise` (5 mm, 2 deg) or `gt-noise:MM:DEG`. Tracker
/// methods use the default parameters.
pub fn method_from_spec(spec: &str) -> Result<Box<dyn Method>, String> {
    method_from_spec_with(spec, &tracker::track::TrackerConfig::default())
}

/// [`method_from_spec`] with tracker methods built on `base` parameters (each method's preset applied on top).
pub fn method_from_spec_with(
    spec: &str,
    base: &tracker::track::TrackerConfig,
) -> Result<Box<dyn Method>, String> {
    method_from_spec_timed(spec, base, DepthTransport::default())
}

/// [`method_from_spec_with`] with the tracker methods' depth frames handed over as `transport` delivers them
/// ([`TrackerMethod::with_depth_latency`], [`TrackerMethod::with_depth_jitter`]);
/// the harness methods ignore it.
pub fn method_from_spec_timed(
    spec: &str,
    base: &tracker::track::TrackerConfig,
    transport: DepthTransport,
) -> Result<Box<dyn Method>, String> {
    let spec = spec.trim();
    if let Some(method) = tracker_method_from_spec(spec, base) {
        return Ok(Box::new(
            method?
                .with_depth_latency(transport.latency_us)
                .with_depth_jitter(transport.jitter_us),
        ));
    }
    if spec == "static" {
        return Ok(Box::new(StaticMethod));
    }
    if spec == "gt-noise" {
        return Ok(Box::new(GtNoiseMethod::new(
            spec,
            GtNoiseMethod::DEFAULT_MM,
            GtNoiseMethod::DEFAULT_DEG,
            1,
        )));
    }
    if let Some(rest) = spec.strip_prefix("gt-noise:") {
        let parts: Vec<&str> = rest.split(':').collect();
        let parse = |s: &str, what: &str| -> Result<f64, String> {
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && *v >= 0.0)
                .ok_or_else(|| format!("method `{spec}`: {what} `{s}` is not a number >= 0"))
        };
        if parts.len() != 2 {
            return Err(format!(
                "method `{spec}`: expected gt-noise:MM:DEG (e.g. gt-noise:10:5)"
            ));
        }
        let mm = parse(parts[0], "translation noise (mm)")?;
        let deg = parse(parts[1], "rotation noise (degrees)")?;
        return Ok(Box::new(GtNoiseMethod::new(spec, mm, deg, 1)));
    }
    Err(format!(
        "unknown method `{spec}`: available are eventtrack6d, depth30, events-only (each optionally \
         with a first-pose error NAME@DEG:CM or NAME@DEG:CM:SEED), static, gt-noise, gt-noise:MM:DEG"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Any `--methods` entry builds a method or an error quoting it; it never panics.
        #[test]
        fn any_method_spec_builds_or_quotes_it(spec in "[a-z0-9@:.,-]{0,24}") {
            match method_from_spec(&spec) {
                Ok(m) => prop_assert!(!m.name().is_empty()),
                Err(e) => prop_assert!(e.contains(&format!("`{}`", spec.trim())), "{}", e),
            }
        }

        /// A perturbed tracker method written as `NAME@DEG:CM[:SEED]` builds, and reports the perturbation.
        #[test]
        fn written_perturbed_methods_build(
            name in proptest::sample::select(vec!["eventtrack6d", "depth30", "events-only"]),
            degrees in 0u32..=180,
            centimetres in 0u32..=100,
            seed in proptest::option::of(0u64..1000),
        ) {
            let spec = match seed {
                Some(s) => format!("{name}@{degrees}:{centimetres}:{s}"),
                None => format!("{name}@{degrees}:{centimetres}"),
            };
            let m = method_from_spec(&spec).map_err(TestCaseError::fail)?;
            let expected = format!("{name}@{degrees},{centimetres}");
            prop_assert!(m.name().starts_with(&expected), "{} for {}", m.name(), spec);
        }

        /// `gt-noise:MM:DEG` with any two numbers >= 0 builds under its own name.
        #[test]
        fn written_gt_noise_methods_build(mm in 0.0f64..50.0, deg in 0.0f64..30.0) {
            let spec = format!("gt-noise:{mm}:{deg}");
            let m = method_from_spec(&spec).map_err(TestCaseError::fail)?;
            prop_assert_eq!(m.name(), spec.as_str());
        }
    }

    #[test]
    fn tracker_methods_are_built_on_the_given_parameters() {
        let mut base = tracker::track::TrackerConfig {
            optimiser: tracker::track::OptimiserConfig {
                iterations: 3,
                ..Default::default()
            },
            ..Default::default()
        };
        base.redetect.places_per_tick = 5;
        for spec in ["eventtrack6d", "depth30", "events-only@5:5"] {
            let m = tracker_method_from_spec(spec, &base).unwrap().unwrap();
            assert_eq!(m.config().optimiser.iterations, 3, "{spec}");
            assert_eq!(m.config().redetect.places_per_tick, 5, "{spec}");
            // The report records exactly the parameters it tracks with.
            let recorded = m.parameters().unwrap();
            assert_eq!(recorded["redetect"]["places_per_tick"], 5, "{spec}");
            let back: tracker::track::TrackerConfig = serde_json::from_value(recorded).unwrap();
            assert_eq!(&back, m.config(), "{spec}");
        }
        assert!(method_from_spec("static").unwrap().parameters().is_none());
        // The method's preset still applies on top: events-only never re-detects.
        let m = tracker_method_from_spec("events-only", &base)
            .unwrap()
            .unwrap();
        assert!(!m.config().redetect.enabled);
        assert!(tracker_method_from_spec("static", &base).is_none());
        let e = tracker_method_from_spec("depth30@x:1", &base)
            .unwrap()
            .err()
            .unwrap();
        assert!(e.contains("depth30@x:1"), "{e}");
    }

    #[test]
    fn perturbed_specs_take_an_optional_seed() {
        let base = tracker::track::TrackerConfig::default();
        let m = tracker_method_from_spec("eventtrack6d@1:0.2", &base)
            .unwrap()
            .unwrap();
        assert_eq!(m.name(), "eventtrack6d@1,0.2");
        let m = tracker_method_from_spec("eventtrack6d@1:0.2:3", &base)
            .unwrap()
            .unwrap();
        assert_eq!(m.name(), "eventtrack6d@1,0.2,s3");
        // Seed 1 given explicitly is the same method as none given.
        let m = tracker_method_from_spec("depth30@5:5:1", &base)
            .unwrap()
            .unwrap();
        assert_eq!(m.name(), "depth30@5,5");
        for bad in [
            "eventtrack6d@1:0.2:x",
            "eventtrack6d@1:0.2:-1",
            "eventtrack6d@1:0.2:3:4",
        ] {
            let e = tracker_method_from_spec(bad, &base).unwrap().err().unwrap();
            assert!(e.contains(bad), "{e}");
        }
    }

    #[test]
    fn seeds_expand_only_unseeded_perturbed_tracker_methods() {
        let specs: Vec<String> = [
            "eventtrack6d",
            "depth30@3:3",
            "events-only@3:3:7",
            "gt-noise:1:1",
        ]
        .map(String::from)
        .to_vec();
        assert_eq!(
            expand_seeds(&specs, 3),
            [
                "eventtrack6d",
                "depth30@3:3:1",
                "depth30@3:3:2",
                "depth30@3:3:3",
                "events-only@3:3:7",
                "gt-noise:1:1"
            ]
        );
        assert_eq!(expand_seeds(&specs, 1), specs);
        // Every expanded spec builds, with the seed in its name.
        let names: Vec<String> = expand_seeds(&specs[1..2], 2)
            .iter()
            .map(|s| method_from_spec(s).unwrap().name().to_string())
            .collect();
        assert_eq!(names, ["depth30@3,3", "depth30@3,3,s2"]);
    }

    #[test]
    fn method_specs() {
        assert_eq!(method_from_spec("static").unwrap().name(), "static");
        assert_eq!(method_from_spec("gt-noise").unwrap().name(), "gt-noise");
        assert_eq!(
            method_from_spec("gt-noise:10:5").unwrap().name(),
            "gt-noise:10:5"
        );
        let e = method_from_spec("gt-noise:x:5").err().unwrap();
        assert!(e.contains("translation noise"), "{e}");
        let e = method_from_spec("foundationpose").err().unwrap();
        assert!(e.contains("unknown method `foundationpose`"), "{e}");
        assert!(method_from_spec("gt-noise:1").is_err());
    }
}
