//! `eventtrack6d inspect`: what is in an event file.

use anyhow::Context;
use clap::Args;
use drivers::summary::{StreamSummary, summarize_raw};
use drivers::timeline::TimelineConfig;
use serde_json::json;
use std::path::PathBuf;

/// Print what is in a `.raw` event file (EVT 3.0, EVT 2.0 or EVT 2.1).
///
/// Reads the file once, in constant memory, and prints its format, geometry, header fields, data size, time span,
/// event count and rate, ON/OFF counts, trigger edges per channel, the trigger timeline of one channel (ticks,
/// depth exposures, period, missing, extra and jittered pulses, phase errors) and anomaly counters by kind. The
/// text and JSON output: docs/event-files.md.
#[derive(Debug, Args)]
pub struct InspectArgs {
    /// The `.raw` file to read.
    pub file: PathBuf,
    /// Print one JSON object instead of text (its keys: docs/event-files.md).
    #[arg(long)]
    pub json: bool,
    /// Trigger channel carrying the 120 Hz tick pulses (for the timeline report), 0 to 31 (EVT 2.0 / 2.1 carry
    /// 0..31, EVT 3.0 0..15).
    #[arg(long, value_name = "N", default_value_t = 0, value_parser = clap::value_parser!(u8).range(0..=31))]
    pub trigger_channel: u8,
}

pub fn run(args: &InspectArgs) -> anyhow::Result<()> {
    let total = std::fs::metadata(&args.file)
        .with_context(|| format!("{}", args.file.display()))?
        .len();
    let bar = super::progress::bytes_bar(total, "reading");
    let config = TimelineConfig {
        channel: args.trigger_channel,
        ..TimelineConfig::default()
    };
    let summary = summarize_raw(&args.file, config, |done, _| bar.set_position(done));
    bar.finish_and_clear();
    let s = summary?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&to_json(&s))?);
    } else {
        print_text(&args.file, &s, args.trigger_channel);
    }
    Ok(())
}

fn duration_us(s: &StreamSummary) -> i64 {
    match (s.counts.t_first_us(), s.counts.t_last_us()) {
        (Some(a), Some(b)) => b - a,
        _ => 0,
    }
}

fn to_json(s: &StreamSummary) -> serde_json::Value {
    let d = duration_us(s);
    let rate = if d > 0 {
        s.counts.cd_events() as f64 / (d as f64 * 1e-6)
    } else {
        0.0
    };
    let triggers: serde_json::Map<String, serde_json::Value> = s
        .trigger_edges()
        .iter()
        .map(|(ch, (r, f))| (ch.to_string(), json!(r + f)))
        .collect();
    let triggers_by_edge: serde_json::Map<String, serde_json::Value> = s
        .trigger_edges()
        .iter()
        .map(|(ch, (r, f))| (ch.to_string(), json!({"rising": r, "falling": f})))
        .collect();
    let anomalies: serde_json::Map<String, serde_json::Value> = s
        .anomalies
        .iter()
        .map(|(k, n)| (k.name().to_string(), json!(n)))
        .collect();
    let header: serde_json::Map<String, serde_json::Value> = s
        .header
        .iter()
        .map(|(k, v)| (k.clone(), json!(v)))
        .collect();
    json!({
        "format": s.format.format_name(),
        "evt": s.format.evt_version(),
        "width": s.width,
        "height": s.height,
        "header": header,
        "data_bytes": s.data_bytes,
        "cd_events": s.counts.cd_events(),
        "positive": s.counts.positive,
        "negative": s.counts.negative,
        "t_first_us": s.counts.t_first_us(),
        "t_last_us": s.counts.t_last_us(),
        "duration_us": d,
        "event_rate_hz": rate,
        "trigger_edges": triggers,
        "trigger_edges_by_polarity": triggers_by_edge,
        "anomalies": anomalies,
        "anomalies_total": s.anomalies.total(),
        "skipped_before_sync": s.anomalies.skipped_before_sync,
        "ignored_vendor_words": s.anomalies.ignored_vendor_words,
        "timeline": s.timeline.map(|t| json!({
            "ticks": t.ticks,
            "depth_exposures": t.depth_exposures,
            "period_us": t.period_us,
            "pulses": t.counters.pulses,
            "missing": t.counters.missing,
            "gaps": t.counters.gaps,
            "unbridged": t.counters.unbridged,
            "extra": t.counters.extra,
            "jittered": t.counters.jittered,
            "phase_errors": t.counters.phase_errors,
            "missing_phase_code": t.counters.missing_phase_code,
            "unpaired_rising": t.counters.unpaired_rising,
            "unpaired_falling": t.counters.unpaired_falling,
        })),
    })
}

fn print_text(path: &std::path::Path, s: &StreamSummary, channel: u8) {
    let d = duration_us(s);
    println!("file        {}", path.display());
    println!("format      {} (evt {})", s.format, s.format.evt_version());
    match (s.width, s.height) {
        (Some(w), Some(h)) => println!("geometry    {w}x{h}"),
        _ => println!(
            "geometry    unknown (no geometry, format size or known plugin_name in the header)"
        ),
    }
    for (k, v) in &s.header {
        println!("header      {k} = {v}");
    }
    println!("data        {} bytes", s.data_bytes);
    match (s.counts.t_first_us(), s.counts.t_last_us()) {
        (Some(a), Some(b)) => println!("time        {a} .. {b} us ({:.3} ms)", d as f64 / 1e3),
        _ => println!("time        no timestamped records"),
    }
    let rate = if d > 0 {
        s.counts.cd_events() as f64 / (d as f64 * 1e-6)
    } else {
        0.0
    };
    println!(
        "cd events   {} ({} ON, {} OFF), {:.3} Mev/s",
        s.counts.cd_events(),
        s.counts.positive,
        s.counts.negative,
        rate / 1e6
    );
    let edges = s.trigger_edges();
    if edges.is_empty() {
        println!("triggers    none");
    }
    for (ch, (r, f)) in edges {
        println!("triggers    channel {ch}: {r} rising, {f} falling");
    }
    if s.timeline.is_none() {
        println!("timeline    none: no trigger edges on channel {channel} (--trigger-channel)");
    }
    if let Some(t) = s.timeline {
        let c = t.counters;
        println!(
            "timeline    {} ticks ({} depth exposures), period {:.3} us ({:.4} Hz)",
            t.ticks,
            t.depth_exposures,
            t.period_us,
            1e6 / t.period_us
        );
        println!(
            "            missing {} (bridged), gaps {} ({} ticks not bridged), extra {}, jittered {}, phase errors {}, \
             missing phase code {}, unpaired rising {}, unpaired falling {}",
            c.missing,
            c.gaps,
            c.unbridged,
            c.extra,
            c.jittered,
            c.phase_errors,
            c.missing_phase_code,
            c.unpaired_rising,
            c.unpaired_falling
        );
    }
    println!("anomalies   {} total", s.anomalies.total());
    for (k, n) in s.anomalies.iter().filter(|(_, n)| *n > 0) {
        println!("            {k}: {n}");
    }
    println!(
        "skipped     {} words before synchronisation, {} vendor words (OTHERS/CONTINUED/IMU) ignored",
        s.anomalies.skipped_before_sync, s.anomalies.ignored_vendor_words
    );
}
