//! The benchmark report: `results.md` (tables shaped like the paper's Table 1) and `results.json`.

use super::bench::results::MethodResults;
use super::quality_report::{QualityReport, method_quality_report};
use super::recall::AucLimit;
use super::seed_spread::{seed_spread_markdown, seed_spreads};
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
                "quality": serde_json::to_value(method_quality_report(m)).unwrap_or(Value::Null),
            }),
        );
    }
    let spreads = serde_json::to_value(seed_spreads(results, limit)).unwrap_or(Value::Null);
    json!({"suite": suite, "auc_threshold": limit.describe(), "methods": methods, "seed_spread": spreads})
}

fn millimetres(m: Option<f64>) -> String {
    m.map_or_else(|| "-".into(), |m| format!("{:.1}", m * 1000.0))
}

/// The quality section: per method, the rank correlation of quality with the error, the median ADD-S error per
/// quality band, and `lost` against true failure.
fn quality_table(out: &mut String, results: &[MethodResults]) {
    let reports: Vec<(&str, QualityReport)> = results
        .iter()
        .map(|m| (m.name.as_str(), method_quality_report(m)))
        .collect();
    let Some((_, first)) = reports.first() else {
        return;
    };
    out.push_str(
        "\n## Quality and `lost` against the error (120 Hz)\n\nSpearman: rank correlation of the method's \
         quality with the negated ADD-S error over every tick (+1: higher quality, smaller error). Then the \
         median ADD-S error (mm) and ticks per quality band. Failed: ADD-S error above 0.1 x diameter on more \
         than half of a sequence's last quarter. Off: a tick whose ADD-S error is above 0.1 x diameter; `lost` \
         ticks off: how many `lost` ticks were right; off ticks `lost`: how much of the time off the object was \
         announced.\n\n| method | Spearman |",
    );
    for b in &first.bands {
        let _ = write!(out, " q {:.1}-{:.1}: mm (ticks) |", b.from, b.to);
    }
    out.push_str(
        " sequences | failed | failed with `lost` | `lost`, not failed | state changes | `lost` ticks off | off ticks `lost` |\n| --- | ---: |",
    );
    for _ in &first.bands {
        out.push_str(" ---: |");
    }
    out.push_str(" ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
    for (name, r) in &reports {
        let rho = r
            .spearman
            .map_or_else(|| "-".into(), |x| format!("{x:+.2}"));
        let _ = write!(out, "| {name} | {rho} |");
        for b in &r.bands {
            let _ = write!(out, " {} ({}) |", millimetres(b.median_error_m), b.ticks);
        }
        let _ = writeln!(
            out,
            " {} | {} | {} | {} | {} | {} | {} |",
            r.sequences,
            r.failed,
            r.failed_with_lost,
            r.lost_without_failure,
            r.state_changes,
            share(r.lost_ticks_off, r.lost_ticks),
            share(r.off_ticks_lost, r.off_ticks)
        );
    }
    out.push('\n');
    for (name, r) in &reports {
        // A false alarm whose `lost` ticks were mostly off the object was a true loss it recovered from.
        let recovered = if r.false_alarms.is_empty() {
            String::new()
        } else {
            format!(
                " (of them, off by more than 0.1 x diameter on most of their `lost` ticks, recovered later: {})",
                names_or_none(&r.recovered_losses)
            )
        };
        let _ = writeln!(
            out,
            "- {name}: failed without `lost`: {}; `lost` without failure: {}{recovered}.",
            names_or_none(&r.silent_failures),
            names_or_none(&r.false_alarms),
        );
    }
}

/// `part / whole` as "part / whole (percent)", or "0 / 0" without a whole.
fn share(part: usize, whole: usize) -> String {
    if whole == 0 {
        "0 / 0".into()
    } else {
        format!(
            "{part} / {whole} ({:.0} %)",
            100.0 * part as f64 / whole as f64
        )
    }
}

fn names_or_none(names: &[String]) -> String {
    if names.is_empty() {
        "none".into()
    } else {
        names.join(", ")
    }
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
/// (every tick, with the update rate) and at 30 Hz (depth-exposure ticks), how well each method's quality and
/// `lost` tell its error, then a per-sequence table.
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
    quality_table(&mut s, results);
    s.push_str(&seed_spread_markdown(&seed_spreads(results, limit)));
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
