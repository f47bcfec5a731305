//! Probes the refinement on a recording with ground truth: before every tick the estimate is reset to the ground
//! truth (`--mode bias`: at this tick, so any change is a bias of the residual terms) or to the ground truth a
//! fraction of a tick earlier (`--mode lag`, `--lag-fraction F`, default 1: how much of that motion a single
//! refinement recovers). Prints the mean errors after refinement, split by ticks with a fresh depth frame and
//! ticks between depth frames, and the rotation error per object axis. `--dump TICK WINDOW_US` writes
//! `probe.png`: that tick's events of the last WINDOW_US with the true (green) and refined (red) outlines.
//!
//! `cargo run --release -p eventtrack6d-core --example probe_refinement -- REC [--mode bias|lag] [--lag-fraction F]
//! [--method M] [--params TOML] [--dump TICK WINDOW_US]`

#![allow(clippy::unwrap_used, clippy::expect_used)]

use drivers::event::CdEvent;
use drivers::recording::{DepthFrame, Recording};
use drivers::timeline::Tick;
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use scene::render::CpuRenderer;
use std::path::PathBuf;
use tracker::recording::{recording_object, recording_rig};
use tracker::track::DepthHandling;
use tracker::track::{
    EventTrack6d, PoseEstimate, PoseTracker, TrackerConfig, TrackingMethod, track_recording,
};

/// One probed tick: errors before and after the refinement (metres, radians).
struct ProbeRow {
    fresh_depth: bool,
    start_translation: f64,
    start_rotation: f64,
    final_translation: f64,
    final_rotation: f64,
    /// Final translation error along the ground truth's motion over the tick.
    final_along_motion: f64,
}

struct Probe {
    inner: EventTrack6d,
    gt: Vec<(i64, Isometry3<f64>)>,
    lag: bool,
    lag_fraction: f64,
    last_tick: Option<i64>,
    depth_pending: bool,
    rows: Vec<ProbeRow>,
    dz: Vec<(bool, f64)>,
    rot_axes: [f64; 3],
    dump: Option<(usize, i64)>,
    ticks: usize,
    mesh: std::sync::Arc<scene::mesh::Mesh>,
    camera: scene::geometry::PinholeCamera,
}

impl Probe {
    fn gt_at(&self, t: i64) -> Isometry3<f64> {
        let i = self.gt.partition_point(|(tt, _)| *tt < t);
        let cands = [i.saturating_sub(1), i.min(self.gt.len() - 1)];
        let k = cands
            .into_iter()
            .min_by_key(|&k| (self.gt[k].0 - t).abs())
            .unwrap_or(0);
        self.gt[k].1
    }
}

impl Probe {
    /// Writes `probe.png`: events of the last `window` us (white), the ground-truth outline (green) and the
    /// refined outline (red), cropped around the object.
    fn draw(&self, t: i64, window: i64, truth: &Isometry3<f64>, est: &Isometry3<f64>) {
        use scene::render::{Renderer, Scene, SceneObject};
        let mut r = CpuRenderer::new();
        let id = r.add_mesh(self.mesh.clone()).expect("mesh");
        let cam = self.camera;
        let (w, h) = (cam.width, cam.height);
        let mut img = image::RgbImage::new(w, h);
        let surface = self.inner.event_surface();
        for y in 0..h {
            for x in 0..w {
                if let Some(te) = surface.last_event_us(x, y)
                    && te > t - window
                    && te <= t
                {
                    img.put_pixel(x, y, image::Rgb([200, 200, 200]));
                }
            }
        }
        for (pose, colour) in [(truth, [40, 230, 60]), (est, [240, 40, 40])] {
            let mut target = scene::render::RenderTarget::new();
            let objs = [SceneObject {
                mesh: id,
                pose: *pose,
                id: 1,
            }];
            r.render(&Scene::objects(&objs), &cam, &mut target)
                .expect("render");
            let m = target.mask();
            let wu = w as usize;
            for y in 1..h as usize - 1 {
                for x in 1..wu - 1 {
                    let k = y * wu + x;
                    if m[k] == 1
                        && (m[k - 1] != 1 || m[k + 1] != 1 || m[k - wu] != 1 || m[k + wu] != 1)
                    {
                        img.put_pixel(x as u32, y as u32, image::Rgb(colour));
                    }
                }
            }
        }
        let c = truth.translation.vector;
        let u = (cam.fx * c.x / c.z + cam.cx) as i64;
        let v = (cam.fy * c.y / c.z + cam.cy) as i64;
        let half = 160i64;
        let x0 = (u - half).clamp(0, i64::from(w) - 2 * half) as u32;
        let y0 = (v - half).clamp(0, i64::from(h) - 2 * half) as u32;
        let crop =
            image::imageops::crop_imm(&img, x0, y0, 2 * half as u32, 2 * half as u32).to_image();
        let big = image::imageops::resize(&crop, 640, 640, image::imageops::FilterType::Nearest);
        big.save("probe.png").expect("save");
        eprintln!("wrote probe.png (t = {t} us)");
    }
}

fn errors(a: &Isometry3<f64>, b: &Isometry3<f64>) -> (f64, f64) {
    (
        (a.translation.vector - b.translation.vector).norm(),
        a.rotation.angle_to(&b.rotation),
    )
}

impl PoseTracker for Probe {
    fn objects(&self) -> &[String] {
        self.inner.objects()
    }
    fn push_events(&mut self, events: &[CdEvent]) {
        self.inner.push_events(events);
    }
    fn push_depth(&mut self, t_us: i64, frame: &mut DepthFrame, handling: DepthHandling) {
        self.depth_pending = true;
        self.inner.push_depth(t_us, frame, handling);
    }
    fn tick(&mut self, tick: &Tick, out: &mut Vec<PoseEstimate>) {
        let truth = self.gt_at(tick.t_us);
        let Some(prev) = self.last_tick else {
            self.last_tick = Some(tick.t_us);
            self.depth_pending = false;
            self.inner.tick(tick, out);
            return;
        };
        let start = if self.lag {
            let back = self.gt_at(prev);
            let f = self.lag_fraction;
            Isometry3::from_parts(
                Translation3::from(truth.translation.vector.lerp(&back.translation.vector, f)),
                truth.rotation.slerp(&back.rotation, f),
            )
        } else {
            truth
        };
        self.inner.reset_pose(0, prev, start);
        self.inner.tick(tick, out);
        if let Some(e) = out.first() {
            let (ti, ri) = errors(&start, &truth);
            let (tf, rf) = errors(&e.pose, &truth);
            let motion = truth.translation.vector - self.gt_at(prev).translation.vector;
            let along = if motion.norm() > 1e-6 {
                (e.pose.translation.vector - truth.translation.vector).dot(&motion.normalize())
            } else {
                0.0
            };
            self.rows.push(ProbeRow {
                fresh_depth: self.depth_pending,
                start_translation: ti,
                start_rotation: ri,
                final_translation: tf,
                final_rotation: rf,
                final_along_motion: along,
            });
            self.dz.push((
                self.depth_pending,
                e.pose.translation.z - truth.translation.z,
            ));
            let d = (truth.rotation.inverse() * e.pose.rotation).scaled_axis();
            for k in 0..3 {
                self.rot_axes[k] += d[k].abs();
            }
        }
        self.depth_pending = false;
        self.last_tick = Some(tick.t_us);
        self.ticks += 1;
        if let Some((k, window)) = self.dump
            && k == self.ticks
            && let Some(e) = out.first()
        {
            self.draw(tick.t_us, window, &truth, &e.pose);
        }
    }
    fn pose_at(&self, object: usize, t_us: i64) -> Option<PoseEstimate> {
        self.inner.pose_at(object, t_us)
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let mut rec_dir = None;
    let mut lag = false;
    let mut method = TrackingMethod::EventTrack6d;
    let mut base = TrackerConfig::default();
    let mut dump = None;
    let mut lag_fraction = 1.0;
    while let Some(a) = args.next() {
        match a.as_str() {
            "--mode" => lag = args.next().as_deref() == Some("lag"),
            "--method" => {
                let m = args.next().unwrap_or_default();
                method = TrackingMethod::from_name(&m).ok_or(format!("unknown method {m}"))?;
            }
            "--params" => {
                let p = args.next().ok_or("--params needs a file")?;
                base = toml::from_str(&std::fs::read_to_string(p)?)?;
                tracker::track::validate(&base)?;
            }
            "--lag-fraction" => lag_fraction = args.next().ok_or("--lag-fraction F")?.parse()?,
            "--dump" => {
                let k: usize = args.next().ok_or("--dump TICK")?.parse()?;
                let w: i64 = args.next().ok_or("--dump TICK WINDOW_US")?.parse()?;
                dump = Some((k, w));
            }
            _ => rec_dir = Some(PathBuf::from(a)),
        }
    }
    let rec = Recording::open(&rec_dir.ok_or("usage: probe_refinement REC")?)?;
    let samples = rec.ground_truth.clone().ok_or("no ground truth")?;
    let name = samples.first().ok_or("empty ground truth")?.object.clone();
    let gt: Vec<(i64, Isometry3<f64>)> = samples
        .iter()
        .filter(|s| s.object == name)
        .map(|s| {
            let [x, y, z, w] = s.rotation_xyzw;
            let [tx, ty, tz] = s.translation;
            (
                s.t_us,
                Isometry3::from_parts(
                    Translation3::new(tx, ty, tz),
                    UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z)),
                ),
            )
        })
        .collect();
    let (t0, p0) = gt[0];
    let object = recording_object(&rec, &name, t0, p0)?;
    let mesh = object.mesh.clone();
    let camera = recording_rig(&rec)?.event_camera;
    let tracker = EventTrack6d::new(
        method.configure(&base),
        recording_rig(&rec)?,
        vec![object],
        Box::new(CpuRenderer::new()),
    )?;
    let mut probe = Probe {
        inner: tracker,
        gt,
        lag,
        lag_fraction,
        last_tick: None,
        depth_pending: false,
        rows: Vec::new(),
        dz: Vec::new(),
        rot_axes: [0.0; 3],
        dump,
        ticks: 0,
        mesh,
        camera,
    };
    track_recording(&rec, &mut probe, t0, |_, _, _| {}, |_| {})?;
    for fresh in [true, false] {
        let rows: Vec<&ProbeRow> = probe
            .rows
            .iter()
            .filter(|r| r.fresh_depth == fresh)
            .collect();
        let n = rows.len().max(1) as f64;
        let mean = |f: fn(&ProbeRow) -> f64| rows.iter().map(|r| f(r)).sum::<f64>() / n;
        println!(
            "{:>8} ticks {:4}: init {:5.1} mm {:5.2} deg -> final {:5.1} mm {:5.2} deg (along motion {:+5.1} mm)",
            if fresh { "depth" } else { "between" },
            rows.len(),
            mean(|r| r.start_translation) * 1e3,
            mean(|r| r.start_rotation.to_degrees()),
            mean(|r| r.final_translation) * 1e3,
            mean(|r| r.final_rotation.to_degrees()),
            mean(|r| r.final_along_motion) * 1e3,
        );
        let dz: Vec<f64> = probe
            .dz
            .iter()
            .filter(|r| r.0 == fresh)
            .map(|r| r.1)
            .collect();
        println!(
            "          z error: mean {:+5.1} mm, mean |z| {:5.1} mm",
            dz.iter().sum::<f64>() / n * 1e3,
            dz.iter().map(|v| v.abs()).sum::<f64>() / n * 1e3
        );
    }
    let n = probe.rows.len().max(1) as f64;
    println!(
        "rotation error about the object's x, y, z axes: {:.2} {:.2} {:.2} deg",
        (probe.rot_axes[0] / n).to_degrees(),
        (probe.rot_axes[1] / n).to_degrees(),
        (probe.rot_axes[2] / n).to_degrees()
    );
    Ok(())
}
