//! `eventtrack6d track`: runs a tracking method over a recording as fast as possible and writes the poses.

use crate::progress::bytes_bar;
use anyhow::{Context, Result, bail};
use clap::Args;
use drivers::recording::Recording;
use eval::{InitNoise, OverlayRenderer, OverlayWriter};
use scene::render::{Renderer, RendererKind, create_renderer};
use std::path::PathBuf;
use std::time::Instant;
use tracker::recording::{
    PoseRecord, PoseTrack, format_pose_csv, ground_truth_objects, parse_pose_csv, recording_object,
    recording_rig, recording_ticks,
};
use tracker::track::{
    DepthFallbackCheck, EventTrack6d, FALLBACK_TRACE_HEADER, OfflineTiming, TrackingMethod,
    track_recording_timed,
};

/// Track the objects of a recording offline and write their poses as a CSV.
///
/// Every 120 Hz tick from the first pose on gets one row per object:
/// `t_us,object,x,y,z,qx,qy,qz,qw,quality,state`. Runs as fast as possible (no real-time pacing; a progress bar on
/// stderr) and sees exactly the events up to each tick, as the real-time runtime does. All objects are tracked in
/// one tracker, hiding each other through their rendered masks. Each object's mesh is `models/<name>.obj` of the
/// recording, and its diameter and symmetries come from `models/models_info.json`. Outputs are checked before any
/// work: --out and --fallback-trace must be two files in existing folders, and neither may be a file the command
/// reads. How the tracker works, its parameters (--params) and late depth frames: docs/tracker.md.
#[derive(Debug, Args)]
pub struct TrackArgs {
    /// Recording directory (events.raw, depth/, camera.json, models/).
    pub recording: PathBuf,
    /// Tracking method: eventtrack6d (events + depth), depth30 (depth frames only, pose held in between) or
    /// events-only (no depth after the first frame).
    #[arg(long, default_value = "eventtrack6d")]
    pub method: String,
    /// Output pose CSV.
    #[arg(long, value_name = "CSV")]
    pub out: PathBuf,
    /// Objects to track, each named once; default: the objects of --first-poses when it is given, else every
    /// object in the ground truth.
    #[arg(long, value_delimiter = ',')]
    pub objects: Vec<String>,
    /// First poses as a pose CSV (the first row of each object is used; every tracked object needs one, and none
    /// may lie after the recording's last tick); default: the recording's ground truth at its first tick.
    #[arg(long, value_name = "CSV")]
    pub first_poses: Option<PathBuf>,
    /// Perturb each first pose by DEG degrees about a random axis and CM centimetres in a random direction, e.g.
    /// `5,5` (at most 180 degrees and 100 cm).
    #[arg(long, value_name = "DEG,CM")]
    pub init_noise: Option<String>,
    /// Seed of the first-pose perturbation (with --init-noise).
    #[arg(long, default_value_t = 1, requires = "init_noise")]
    pub seed: u64,
    /// Tracker parameters: a TOML file with the keys of the configuration's `[tracker.parameters]` table at top
    /// level (the parameters are listed in docs/tracker.md). Unknown keys are errors.
    #[arg(long, value_name = "TOML")]
    pub params: Option<PathBuf>,
    /// Renderer of the render-and-compare: cpu (deterministic) or gpu (wgpu / Vulkan; Mesa's lavapipe on a machine
    /// without a GPU, slower than cpu there). See docs/renderer.md.
    #[arg(long, default_value = "cpu")]
    pub renderer: RendererKind,
    /// Also write overlay images into DIR: the reconstructed intensity `I_t` with each object's outline at its
    /// estimate (green tracking, yellow degraded, red lost). The poses are the same with or without it.
    #[arg(long, value_name = "DIR")]
    pub overlay: Option<PathBuf>,
    /// With --overlay: draw an overlay every N ticks, 1 to 1000000 (120 Hz ticks; 12 = 10 per second).
    #[arg(long, default_value_t = 12, value_name = "N", requires = "overlay",
          value_parser = clap::value_parser!(u64).range(1..=1_000_000))]
    pub overlay_every: u64,
    /// Also write the depth safety net's decisions as CSV: at every fresh depth frame and object, one row per
    /// depth-only candidate (where its refinement started, its pose, the fraction of model points the depth
    /// confirms for it and for the event-driven estimate, and whether it replaced the estimate). `eventtrack6d`
    /// only; the columns are described in docs/tracker.md.
    #[arg(long, value_name = "CSV")]
    pub fallback_trace: Option<PathBuf>,
    /// Hand each depth frame to the tracker this long after its exposure, 0 to 1000 ms, at the first tick that
    /// late, as a live depth camera's transport delivers it (0 = with its own tick). The tracker uses a frame up to
    /// its `max_depth_age_ms` old. The closing lines count the frames used late and those still in transit at the
    /// end.
    #[arg(long, value_name = "MS", default_value_t = 0.0, value_parser = crate::args::parse_latency_ms)]
    pub depth_latency_ms: f64,
    /// Add up to this much to each frame's latency, 0 to 1000 ms, drawn per frame from its exposure time (the same
    /// in every run, and the same draw as a replay's `[source] depth_latency_jitter_ms`), frames kept in order: a
    /// live camera's latency varies from frame to frame.
    #[arg(long, value_name = "MS", default_value_t = 0.0, value_parser = crate::args::parse_latency_ms)]
    pub depth_latency_jitter_ms: f64,
}

/// Runs the command.
pub fn run(args: &TrackArgs) -> Result<()> {
    let method = TrackingMethod::from_name(&args.method).with_context(|| {
        format!(
            "unknown method `{}`: available are eventtrack6d, depth30, events-only",
            args.method
        )
    })?;
    let mut base = crate::args::tracker_params(args.params.as_deref())?;
    // The overlays draw the tracker's own `I_t`.
    base.intensity.always |= args.overlay.is_some();
    let config = method.configure(&base);
    let noise = args
        .init_noise
        .as_deref()
        .map(|s| InitNoise::parse(s, args.seed))
        .transpose()
        .map_err(anyhow::Error::msg)?;
    crate::paths::refuse_repeats(&args.objects, "--objects")?;
    let recording_files = crate::paths::recording_inputs(&args.recording);
    let mut inputs: Vec<crate::paths::NamedPath<'_>> = recording_files
        .iter()
        .map(|(name, path)| (*name, path.as_path()))
        .collect();
    inputs.extend(args.first_poses.as_deref().map(|p| ("--first-poses", p)));
    inputs.extend(args.params.as_deref().map(|p| ("--params", p)));
    let mut outputs = vec![("--out", args.out.as_path())];
    outputs.extend(
        args.fallback_trace
            .as_deref()
            .map(|p| ("--fallback-trace", p)),
    );
    crate::paths::check_outputs(&inputs, &outputs)?;
    let rec = Recording::open(&args.recording)?;
    let first_poses: Vec<PoseRecord> = match &args.first_poses {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("reading {}", path.display()))?;
            let rows = parse_pose_csv(&text).with_context(|| format!("{}", path.display()))?;
            if rows.is_empty() {
                bail!("--first-poses {}: holds no poses", path.display());
            }
            rows
        }
        None => Vec::new(),
    };
    let names: Vec<String> = if !args.objects.is_empty() {
        args.objects.clone()
    } else if !first_poses.is_empty() {
        crate::paths::first_of_each(first_poses.iter().map(|r| r.object.clone()))
    } else {
        if rec.ground_truth.is_none() {
            bail!(
                "{}: the recording has no ground truth (groundtruth.csv) to take the first poses from: give them \
                 with --first-poses",
                args.recording.display()
            );
        }
        ground_truth_objects(&rec)?
    };
    let ticks = recording_ticks(&rec)?;
    let mut objects = Vec::with_capacity(names.len());
    let last_tick = ticks.last().map_or(i64::MIN, |t| t.t_us);
    for name in &names {
        let (t0, pose) = if let Some(r) = first_poses.iter().find(|r| &r.object == name) {
            if r.t_us > last_tick {
                bail!(
                    "--first-poses: the first pose of `{name}` at {} us comes after the recording's last tick ({} us)",
                    r.t_us,
                    last_tick
                );
            }
            (r.t_us, r.pose)
        } else if let Some(path) = &args.first_poses {
            let there = crate::paths::first_of_each(first_poses.iter().map(|r| r.object.clone()));
            bail!(
                "--first-poses {}: no first pose for `{name}` (objects there: {})",
                path.display(),
                there.join(", ")
            );
        } else {
            let gt = rec.ground_truth.as_deref().with_context(|| {
                format!("no first pose for `{name}`: the recording has no ground truth; pass --first-poses")
            })?;
            let track = PoseTrack::from_samples(gt, name);
            let (start, _) = track
                .first()
                .with_context(|| format!("object `{name}` has no ground-truth pose"))?;
            let tick = ticks.iter().find(|t| t.t_us >= start).with_context(|| {
                format!("object `{name}`: no tick after its first ground-truth pose")
            })?;
            let pose = track.interpolated_at(tick.t_us).with_context(|| {
                format!("object `{name}`: no ground truth at tick {}", tick.t_us)
            })?;
            (tick.t_us, pose)
        };
        let pose = noise.map_or(pose, |n| n.apply(&pose));
        objects.push(recording_object(&rec, name, t0, pose)?);
    }
    if objects.is_empty() {
        bail!("nothing to track: no object given");
    }
    let start = objects.iter().map(|o| o.first_t_us).min().unwrap_or(0);
    let meshes: Vec<_> = objects.iter().map(|o| o.mesh.clone()).collect();
    let rig = recording_rig(&rec)?;
    let renderer: Box<dyn Renderer + Send> = create_renderer(args.renderer)?;
    if let Some(warning) = renderer.device().warning() {
        eprintln!("warning: {warning}");
    }
    let mut tracker = EventTrack6d::new(config, rig, objects, renderer)?;
    for (name, s) in names.iter().zip(tracker.render_meshes()) {
        if s.triangles_after < s.triangles_before {
            eprintln!(
                "{name}: rendering {} of the mesh's {} triangles (within {:.3} mm of it)",
                s.triangles_after,
                s.triangles_before,
                s.largest_error_m * 1e3
            );
        }
    }
    let mut overlay = match &args.overlay {
        Some(dir) => Some(OverlayWriter::new(
            dir,
            args.overlay_every,
            OverlayRenderer::new(rig.event_camera, &meshes)?,
        )?),
        None => None,
    };
    let total = std::fs::metadata(rec.dir().join("events.raw"))
        .map(|m| m.len())
        .unwrap_or(0);
    let bar = bytes_bar(
        total,
        &format!("{} {}", method.name(), args.recording.display()),
    );
    let mut out = Vec::new();
    let mut trace = args
        .fallback_trace
        .as_ref()
        .map(|_| format!("{FALLBACK_TRACE_HEADER}\n"));
    let mut checks: Vec<DepthFallbackCheck> = Vec::with_capacity(names.len());
    let mut overlay_error = None;
    let started = Instant::now();
    let timing = OfflineTiming {
        start_us: start,
        depth_latency_us: (args.depth_latency_ms * 1e3).round() as i64,
        depth_jitter_us: (args.depth_latency_jitter_ms * 1e3).round() as i64,
    };
    let stats = track_recording_timed(
        &rec,
        &mut tracker,
        timing,
        |tick, estimates, t| {
            for e in estimates {
                out.push(PoseRecord {
                    t_us: e.t_us,
                    object: names[e.object].clone(),
                    pose: e.pose,
                    quality: f64::from(e.quality),
                    state: e.state.as_str().into(),
                });
            }
            if let Some(trace) = trace.as_mut() {
                checks.clear();
                t.depth_fallback_checks(&mut checks);
                for c in &checks {
                    c.write_csv_rows(&names[c.object], trace);
                }
            }
            if let (Some(w), Some(surface)) = (overlay.as_mut(), t.event_surface())
                && overlay_error.is_none()
            {
                overlay_error = w.tick(tick.index, surface, tick.t_us, estimates).err();
            }
        },
        |bytes| bar.set_position(bytes),
    )?;
    bar.finish_and_clear();
    let elapsed = started.elapsed().as_secs_f64();
    if let Some(e) = overlay_error {
        bail!("overlay: {e}");
    }
    std::fs::write(&args.out, format_pose_csv(&out))
        .with_context(|| format!("writing {}", args.out.display()))?;
    if let (Some(path), Some(trace)) = (&args.fallback_trace, &trace) {
        std::fs::write(path, trace).with_context(|| format!("writing {}", path.display()))?;
    }
    let counters = tracker.counters();
    eprintln!(
        "{}: {} ticks, {} objects, {} events, {} depth frames ({} missing) in {:.2} s ({:.1} ticks/s); {} poses -> {}",
        method.name(),
        stats.ticks,
        names.len(),
        stats.events,
        stats.depth_frames,
        stats.depth_frames_missing,
        elapsed,
        stats.ticks as f64 / elapsed.max(1e-9),
        out.len(),
        args.out.display()
    );
    if counters.depth_fallbacks > 0 {
        eprintln!(
            "{} depth frames replaced an event-driven estimate by the depth-only one",
            counters.depth_fallbacks
        );
    }
    if counters.redetections > 0 || counters.redetect_places_checked > 0 {
        eprintln!(
            "{} depth frames re-detected an object that was not tracking (moved it to a better-fitting place); {} places checked",
            counters.redetections, counters.redetect_places_checked
        );
    }
    if counters.redetect_places_dropped > 0 {
        eprintln!(
            "{} re-detection places left unchecked: more than the ticks until the next depth frame could check ([redetect] places_per_tick, pose_search_places)",
            counters.redetect_places_dropped
        );
    }
    if counters.inner_steps > 0 {
        eprintln!(
            "{} steps between ticks ({:.2} per tick: fast objects refined again as their events came, inner_step_px)",
            counters.inner_steps,
            counters.inner_steps as f64 / counters.ticks.max(1) as f64
        );
    }
    if counters.renders_prefetched > 0 {
        eprintln!(
            "{} renders started ahead of their tick, {} of them used (the rest rendered again: the tick's ROI or poses differed)",
            counters.renders_prefetched, counters.prefetched_renders_used
        );
    }
    if counters.depth_frames_late > 0 {
        eprintln!(
            "{} depth frames used after their own tick (delivered late: --depth-latency-ms plus --depth-latency-jitter-ms); {} times an object's pose history did not reach back to the exposure",
            counters.depth_frames_late, counters.late_depth_unplaced
        );
        eprintln!(
            "{} of them tracked again from their exposure ({} ticks again), {} carried from it instead (no state saved there, or their events no longer in the log)",
            counters.late_frames_retracked,
            counters.ticks_retracked,
            counters.late_frames_not_retracked
        );
    }
    if stats.depth_frames_in_transit > 0 {
        eprintln!(
            "{} depth frames were still in transit after the last tick",
            stats.depth_frames_in_transit
        );
    }
    if counters.render_errors > 0 || counters.depth_frames_unused > 0 {
        eprintln!(
            "warning: {} render errors, {} depth frames unused (replaced before a tick, or older than max_depth_age_ms)",
            counters.render_errors, counters.depth_frames_unused
        );
    }
    let lost = out.iter().filter(|r| r.state == "lost").count();
    if lost > 0 {
        eprintln!("warning: {lost} poses reported `lost`");
    }
    if let Some(path) = &args.fallback_trace {
        eprintln!("depth safety-net decisions -> {}", path.display());
    }
    if let Some(w) = &overlay {
        eprintln!(
            "{} overlay images in {}",
            w.written(),
            args.overlay
                .as_ref()
                .map(|p| p.display().to_string())
                .unwrap_or_default()
        );
    }
    Ok(())
}
