//! The sensors' half of generation, on its own thread: it composites each rendered region over the static
//! background, applies the optics and the logarithm, runs ESIM, renders and measures the depth frames, and writes
//! events, trigger edges and depth frames in time order. Rendering, the other half, runs ahead on the calling
//! thread. The recording is the same byte for byte as with both halves on one thread: each half does the same
//! work on the same data in the same order.

use super::GenerateError;
use super::optics::optics_log;
use crate::depth_sensor::DepthSensorModel;
use crate::esim::EventSimulator;
use crate::rng::SeedRng;
use drivers::event::{CdEvent, TriggerEdge};
use drivers::recording::RecordingWriter;
use scene::geometry::PinholeCamera;
use scene::render::{
    BackgroundMesh, Lighting, MASK_EMPTY, RenderTarget, Renderer, Scene, SceneObject,
};
use std::sync::mpsc::{Receiver, Sender};

/// The part of the event camera's image that can change in one step, and the region rendered for it.
#[derive(Debug, Clone, Copy)]
pub(super) struct ChangingRegion {
    /// The changing region: first column and row, width and height, pixels.
    pub(super) x0: u32,
    pub(super) y0: u32,
    pub(super) w: u32,
    pub(super) h: u32,
    /// The rendered region (the changing one and one pixel more on each side inside the image, for the blur):
    /// first column and row, width and height, pixels.
    pub(super) ex0: u32,
    pub(super) ey0: u32,
    pub(super) ew: u32,
    pub(super) eh: u32,
}

/// One depth frame's exposure: the scene posed at its time in the depth camera's frame.
#[derive(Debug)]
pub(super) struct DepthExposure {
    /// Frame index (the file name).
    pub(super) index: u64,
    /// Moving meshes and props.
    pub(super) objects: Vec<SceneObject>,
    pub(super) background: Vec<BackgroundMesh>,
}

/// The depth camera: renders each exposure and measures it through the sensor model.
pub(super) struct DepthCamera {
    pub(super) camera: PinholeCamera,
    pub(super) model: DepthSensorModel,
    /// The sensor model's random draws (frame drops, noise), in frame order.
    pub(super) rng: SeedRng,
    /// A renderer with the stage's meshes under the same handles.
    pub(super) renderer: Box<dyn Renderer + Send>,
    target: RenderTarget,
    mm: Vec<u16>,
}

impl DepthCamera {
    /// The depth camera `camera` measuring through `model` with draws from `rng`, rendering with `renderer`.
    pub(super) fn new(
        camera: PinholeCamera,
        model: DepthSensorModel,
        rng: SeedRng,
        renderer: Box<dyn Renderer + Send>,
    ) -> Self {
        Self {
            camera,
            model,
            rng,
            renderer,
            target: RenderTarget::new(),
            mm: Vec::new(),
        }
    }
}

/// One simulation step, from the renderer to the sensor: the interval, the moving meshes rendered at its end
/// over the changing region (if any), and the depth frames exposed during it.
#[derive(Debug, Default)]
pub(super) struct Step {
    /// Start and end of the step, microseconds of the event camera's clock.
    pub(super) t0_us: f64,
    pub(super) t1_us: f64,
    /// Where the image can change; `None` when nothing moving is in view.
    pub(super) region: Option<ChangingRegion>,
    /// The moving meshes at `t1_us` over the rendered region (without the props: empty pixels show the
    /// background).
    pub(super) target: RenderTarget,
    /// Depth frames exposed before `t1_us`, in order.
    pub(super) depth: Vec<DepthExposure>,
}

/// The sensor's state between steps.
pub(super) struct SensorSide<'a> {
    pub(super) sim: EventSimulator,
    pub(super) writer: RecordingWriter,
    pub(super) depth: DepthCamera,
    /// Linear intensity of the static props over the whole image, row-major.
    pub(super) background: &'a [f32],
    /// Event camera image width, pixels.
    pub(super) width: u32,
    /// `log_eps` of the sensor's logarithm.
    pub(super) eps: f32,
    /// Every trigger edge of the recording, in order.
    pub(super) edges: &'a [TriggerEdge],
    /// The first edge not yet written.
    next_edge: usize,
    /// Depth frames written.
    depth_frames: u64,
    /// Depth frames the sensor model dropped.
    depth_frames_dropped: u64,
    composite: Vec<f32>,
    log: Vec<f32>,
    events: Vec<CdEvent>,
}

impl<'a> SensorSide<'a> {
    /// The sensor from `sim`'s initial state, writing to `writer`.
    pub(super) fn new(
        sim: EventSimulator,
        writer: RecordingWriter,
        depth: DepthCamera,
        background: &'a [f32],
        width: u32,
        eps: f32,
        edges: &'a [TriggerEdge],
    ) -> Self {
        Self {
            sim,
            writer,
            depth,
            background,
            width,
            eps,
            edges,
            next_edge: 0,
            depth_frames: 0,
            depth_frames_dropped: 0,
            composite: Vec::new(),
            log: Vec::new(),
            events: Vec::new(),
        }
    }

    /// Turns one step into events and writes them, the trigger edges before its end and its depth frames.
    pub(super) fn step(&mut self, step: &Step) -> Result<(), GenerateError> {
        self.events.clear();
        if let Some(r) = &step.region {
            self.composite.clear();
            let target = &step.target;
            let (ex0, ey0, ew) = (r.ex0 as usize, r.ey0 as usize, r.ew as usize);
            let width = self.width as usize;
            let rows = target
                .intensity()
                .chunks_exact(ew)
                .zip(target.mask().chunks_exact(ew));
            for (y, (intensity, mask)) in (ey0..).zip(rows) {
                let background = &self.background[y * width + ex0..][..ew];
                let pixels = intensity.iter().zip(mask).zip(background);
                self.composite
                    .extend(pixels.map(|((&v, &m), &b)| if m == MASK_EMPTY { b } else { v }));
            }
            let inner = (r.x0 - r.ex0, r.y0 - r.ey0);
            optics_log(
                &self.composite,
                r.ew,
                r.eh,
                inner,
                (r.w, r.h),
                self.eps,
                &mut self.log,
            );
            self.sim.update_region(
                step.t0_us,
                step.t1_us,
                r.x0,
                r.y0,
                r.w,
                r.h,
                &self.log,
                &mut self.events,
            );
        }
        self.sim.noise(step.t0_us, step.t1_us, &mut self.events);
        self.events
            .sort_unstable_by_key(|e| (e.t_us, e.y, e.polarity, e.x));
        let edge_start = self.next_edge;
        while self.next_edge < self.edges.len()
            && (self.edges[self.next_edge].t_us as f64) < step.t1_us.floor()
        {
            self.next_edge += 1;
        }
        self.writer
            .write_events(&self.events, &self.edges[edge_start..self.next_edge])?;
        for exposure in &step.depth {
            let d = &mut self.depth;
            if d.model.drops_frame(&mut d.rng) {
                self.depth_frames_dropped += 1;
                continue;
            }
            let scene = Scene {
                lighting: Lighting::default(),
                ..Scene::objects(&exposure.objects).with_background(&exposure.background)
            };
            d.renderer.render(&scene, &d.camera, &mut d.target)?;
            let t = &d.target;
            d.model
                .measure(t.depth(), t.width(), t.height(), &mut d.rng, &mut d.mm);
            self.writer.write_depth_mm(exposure.index, &d.mm)?;
            self.depth_frames += 1;
        }
        Ok(())
    }

    /// Runs the steps from `steps` until its sender is gone, handing each back on `spent` for reuse. Returns the
    /// sensor (to write what is left) or the first error, after which it reads no further step.
    pub(super) fn run(
        mut self,
        steps: Receiver<Step>,
        spent: Sender<Step>,
    ) -> Result<Self, GenerateError> {
        for step in steps {
            self.step(&step)?;
            // The renderer may be done already; a step it does not take back is simply dropped.
            let _ = spent.send(step);
        }
        Ok(self)
    }

    /// Writes the trigger edges left at the very end.
    pub(super) fn finish(mut self) -> Result<SensorTotals, GenerateError> {
        if self.next_edge < self.edges.len() {
            self.writer
                .write_events(&[], &self.edges[self.next_edge..])?;
        }
        Ok(SensorTotals {
            writer: self.writer,
            sim: self.sim,
            trigger_edges: self.edges.len() as u64,
            depth_frames: self.depth_frames,
            depth_frames_dropped: self.depth_frames_dropped,
        })
    }
}

/// What the sensor's half leaves: the writer to finish the recording with, the simulator's counters, and what was
/// written.
pub(super) struct SensorTotals {
    pub(super) writer: RecordingWriter,
    pub(super) sim: EventSimulator,
    /// Trigger edges written.
    pub(super) trigger_edges: u64,
    /// Depth frames written.
    pub(super) depth_frames: u64,
    /// Depth frames the sensor model dropped.
    pub(super) depth_frames_dropped: u64,
}
