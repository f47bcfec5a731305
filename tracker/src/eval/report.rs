//! The benchmark report: `results.md` (tables shaped like the paper's Table 1) and `results.json`.

use super::bench::MethodResults;
use super::recall::AucLimit;
use super::sequence::Summary;
use serde_json::{Map, Value, json};
use std::collections::BTreeMap;
use std::fmt::Write as _;

fn summary_json(s: &Summary) -> Value {
    json!({"add_s": s.add_s, "add": s.add, "ar": s.ar, "frames": s.frames})
}

fn finite_or_null(x: f64) -> Value {
    if x.is_finite() { json!(x) } else { Value::Null }
}

/// The `results.json` document: per method the object-mean at 120 Hz and 30 Hz, the update rate, per-object and
/// per-sequence summaries (AUC and AR in percent, 0-100; AUC thresholds up to `limit`).
pub fn results_json(suite: &str, results: &[MethodResults], limit: AucLimit) -> Value {
    let mut methods = Map::new();
    for m in results {
        let mut seqs = Map::new();
        for s in &m.sequences {
            let a = s.scores.summary(false, limit);
            let b = s.scores.summary(true, limit);
            let key = if seqs.contains_key(&s.sequence.name) {
                format!("{}/{}", s.sequence.name, s.scores.object)
            } else {
                s.sequence.name.clone()
            };
            seqs.insert(
                key,
                json!({
                    "object": s.scores.object, "motion": s.sequence.motion, "speed": s.sequence.speed,
                    "add_s": a.add_s, "add": a.add, "ar": a.ar, "frames": a.frames,
                    "add_s_30hz": b.add_s, "add_30hz": b.add, "ar_30hz": b.ar, "frames_30hz": b.frames,
                    "diameter_m": s.scores.diameter,
                }),
            );
        }
        let objects: Map<String, Value> = m
            .per_object(false, limit)
            .into_iter()
            .zip(m.per_object(true, limit))
            .map(|((o, a), (_, b))| {
                (
                    o,
                    json!({"hz120": summary_json(&a), "hz30": summary_json(&b)}),
                )
            })
            .collect();
        methods.insert(
            m.name.clone(),
            json!({
                "mean": summary_json(&m.mean(false, limit)),
                "mean_30hz": summary_json(&m.mean(true, limit)),
                "update_hz": finite_or_null(m.update_hz()),
                "parameters": m.parameters.clone().unwrap_or(Value::Null),
                "objects": objects,
                "sequences": seqs,
            }),
        );
    }
    json!({"suite": suite, "auc_threshold": limit.describe(), "methods": methods})
}

fn cells(s: Option<&Summary>) -> String {
    match s {
        Some(s) => format!(" {:.1} | {:.1} | {:.1} |", s.add_s, s.add, s.ar),
        None => " - | - | - |".into(),
    }
}

fn table(
    out: &mut String,
    results: &[MethodResults],
    depth_only: bool,
    with_rate: bool,
    limit: AucLimit,
) {
    let per: Vec<BTreeMap<String, Summary>> = results
        .iter()
        .map(|m| m.per_object(depth_only, limit))
        .collect();
    let mut objects: Vec<&String> = per.iter().flat_map(|p| p.keys()).collect();
    objects.sort();
    objects.dedup();
    out.push_str("| object |");
    for m in results {
        let _ = write!(out, " {0} ADD-S | {0} ADD | {0} AR |", m.name);
    }
    out.push_str("\n| --- |");
    for _ in results {
        out.push_str(" ---: | ---: | ---: |");
    }
    out.push('\n');
    for o in &objects {
        let _ = write!(out, "| {o} |");
        for p in &per {
            out.push_str(&cells(p.get(*o)));
        }
        out.push('\n');
    }
    out.push_str("| **MEAN** |");
    for m in results {
        out.push_str(&cells(Some(&m.mean(depth_only, limit))));
    }
    out.push('\n');
    if with_rate {
        out.push_str("| update rate (Hz) |");
        for m in results {
            let hz = m.update_hz();
            if hz.is_finite() {
                let _ = write!(out, " {hz:.0} | | |");
            } else {
                out.push_str(" - | | |");
            }
        }
        out.push('\n');
    }
}

/// The `results.md` report: per-object tables (rows = objects, columns = ADD-S / ADD / AR per method) at 120 Hz
/// (every tick, with the update rate) and at 30 Hz (depth-exposure ticks), then a per-sequence table.
pub fn results_markdown(suite: &str, results: &[MethodResults], limit: AucLimit) -> String {
    let mut s = format!(
        "# Benchmark `{suite}`\n\nAUC of ADD-S and ADD (thresholds 0 to {}) and BOP AR \
         (mean of VSD, MSSD, MSPD recalls, per frame), in percent. Protocol: first pose from ground truth, no \
         re-initialisation. Update rate = poses per second of method run time.\n\n## 120 Hz (every tick)\n\n",
        limit.describe()
    );
    table(&mut s, results, false, true, limit);
    s.push_str("\n## 30 Hz (depth-exposure ticks only)\n\n");
    table(&mut s, results, true, false, limit);
    s.push_str("\n## Per sequence (120 Hz)\n\n| sequence | object | motion | speed |");
    for m in results {
        let _ = write!(s, " {0} ADD-S | {0} ADD | {0} AR |", m.name);
    }
    s.push_str("\n| --- | --- | --- | --- |");
    for _ in results {
        s.push_str(" ---: | ---: | ---: |");
    }
    s.push('\n');
    if let Some(first) = results.first() {
        for (i, r) in first.sequences.iter().enumerate() {
            let _ = write!(
                s,
                "| {} | {} | {} | {} |",
                r.sequence.name, r.scores.object, r.sequence.motion, r.sequence.speed
            );
            for m in results {
                let cell = m.sequences.get(i).map(|x| x.scores.summary(false, limit));
                s.push_str(&cells(cell.as_ref()));
            }
            s.push('\n');
        }
    }
    s
}
