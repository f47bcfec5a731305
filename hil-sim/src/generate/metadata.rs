//! What a recording says about itself besides the sensor data: the ground-truth poses and the generation
//! parameters in `meta.json`.

use super::GenerateConfig;
use super::GenerateReport;
use super::stage::{BuiltObject, StageObject};
use drivers::event::TriggerEdge;
use drivers::recording::PoseSample;
use serde_json::json;

/// Every object's true pose (camera frame) at each whole millisecond before `t_end_us` and at every tick (the
/// rising trigger edges), in time order.
pub(super) fn ground_truth(
    objects: &[StageObject],
    scene_objects: &[BuiltObject],
    edges: &[TriggerEdge],
    t_end_us: f64,
) -> Vec<PoseSample> {
    let mut times: Vec<i64> = (0..)
        .map(|k| k * 1000)
        .take_while(|&t| (t as f64) < t_end_us)
        .collect();
    times.extend(edges.iter().filter(|e| e.rising).map(|e| e.t_us));
    times.sort_unstable();
    times.dedup();
    times
        .iter()
        .flat_map(|&t| {
            objects.iter().zip(scene_objects).map(move |(o, b)| {
                let p = o.pose(t as f64 * 1e-6);
                let q = p.rotation.into_inner();
                PoseSample {
                    t_us: t,
                    object: b.name.clone(),
                    translation: [p.translation.x, p.translation.y, p.translation.z],
                    rotation_xyzw: [q.i, q.j, q.k, q.w],
                }
            })
        })
        .collect()
}

/// The `parameters` of `meta.json`: how the recording was made (object, motion, seed, event camera model) and
/// what the generation counted; `contrast_threshold` is the one the simulator drew.
pub(super) fn parameters(
    config: &GenerateConfig,
    scene_objects: &[BuiltObject],
    contrast_threshold: f64,
    report: &GenerateReport,
) -> serde_json::Map<String, serde_json::Value> {
    let mut parameters = serde_json::Map::new();
    for (k, v) in [
        ("object", json!(scene_objects[0].name)),
        ("motion", json!(config.motion.name())),
        ("speed", json!(config.speed.name())),
        ("seconds", json!(config.seconds)),
        ("seed", json!(config.seed)),
        ("contrast_threshold", json!(contrast_threshold)),
        ("contrast_spread", json!(config.esim.contrast_spread)),
        ("refractory_us", json!(config.esim.refractory_us)),
        ("noise_rate_hz", json!(config.esim.noise_rate_hz)),
        ("hands", json!(config.hands)),
        ("max_step_px", json!(config.max_step_px)),
        ("renders", json!(report.renders)),
        ("signal_events", json!(report.esim.signal_events)),
        ("noise_events", json!(report.esim.noise_events)),
        ("refractory_dropped", json!(report.esim.refractory_dropped)),
        ("depth_frames_dropped", json!(report.depth_frames_dropped)),
    ] {
        parameters.insert(k.to_string(), v);
    }
    // Only recordings with companions carry them (a single-object recording's metadata is unchanged).
    if !config.companions.is_empty() {
        let companions: Vec<_> = config
            .companions
            .iter()
            .zip(&scene_objects[1..])
            .map(|(c, b)| {
                json!({"object": b.name, "motion": c.motion.name(), "speed": c.speed.name(),
                       "offset_m": c.offset_m})
            })
            .collect();
        parameters.insert("companions".into(), json!(companions));
    }
    parameters
}
