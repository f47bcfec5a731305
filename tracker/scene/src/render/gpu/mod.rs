//! The `wgpu` (Vulkan) renderer backend: same outputs as the CPU rasteriser, rasterised by a GPU or by Mesa's
//! lavapipe CPU driver.
//!
//! One render pass draws every instance (objects first, then background, as the CPU backend) into a packed
//! `Rgba32Uint` target (depth, intensity, snorm16 normal, mask) with a `near / z` depth buffer; the target is copied
//! into a reused readback buffer, mapped, and unpacked into the caller's [`RenderTarget`]. Textures, buffers and
//! uniforms are sized to the largest image and the most instances seen and then reused. A render can be started
//! ahead of its request ([`Renderer::prefetch_roi`], module `request`).

mod device;
mod frame;
mod mesh;
mod pass;
mod pipeline;
mod readback;
mod request;

use super::{
    MASK_BACKGROUND, MASK_EMPTY, MAX_PIXELS, MeshId, PrefetchCounts, RenderDevice, RenderError,
    RenderTarget, Renderer, Scene,
};
use crate::geometry::{PinholeCamera, Roi};
use crate::mesh::Mesh;
use device::Gpu;
use frame::{Targets, Uniforms, padded_row_bytes, push_words};
use mesh::GpuMesh;
use nalgebra::Isometry3;
use pass::{backend, submit};
use pipeline::Pipelines;
use readback::{MapResult, UnpackJob, Unpacker, read_back};
use request::{Instance, PREFETCH_SLOTS, PrefetchSlot, RenderRequest};
use std::sync::Arc;

/// A renderer on `wgpu` over Vulkan: depth, normals, object mask and shaded intensity, matching [`CpuRenderer`]
/// (depth to float precision, masks except on a few silhouette pixels, normals to 16-bit precision).
///
/// Each render waits for the device and reads the image back (16 bytes per pixel), so a render costs a round trip
/// to the device on top of the rasterisation, unless it was prefetched: then the device rasterised it while the
/// caller did other work. `Send`: it can live on the tracker's thread.
///
/// [`CpuRenderer`]: super::CpuRenderer
#[derive(Debug)]
pub struct GpuRenderer {
    gpu: Gpu,
    pipelines: Pipelines,
    meshes: Vec<GpuMesh>,
    targets: Option<Targets>,
    uniforms: Uniforms,
    /// The request being rendered or prefetched.
    request: RenderRequest,
    mapped: MapResult,
    /// Renders started ahead of their request (at most [`PREFETCH_SLOTS`]).
    prefetched: Vec<PrefetchSlot>,
    /// The slot the next prefetch replaces when all are taken.
    next_slot: usize,
    /// The thread that unpacks prefetched renders (started by the first prefetch).
    unpacker: Option<Unpacker>,
    counts: PrefetchCounts,
}

const _: () = {
    const fn assert_send<T: Send>() {}
    assert_send::<GpuRenderer>()
};

fn pose_is_finite(pose: &Isometry3<f64>) -> bool {
    pose.translation.vector.iter().all(|v| v.is_finite())
        && pose.rotation.coords.iter().all(|v| v.is_finite())
}

fn f32_bits(values: &[f64]) -> impl Iterator<Item = u32> + '_ {
    values.iter().map(|&v| (v as f32).to_bits())
}

impl GpuRenderer {
    /// Opens a Vulkan device (a hardware GPU if present, else a CPU driver such as Mesa's lavapipe) and builds the
    /// pipelines. Fails with [`RenderError::Unavailable`] when there is no Vulkan adapter.
    pub fn new() -> Result<Self, RenderError> {
        let gpu = Gpu::open()?;
        let pipelines = Pipelines::new(&gpu.device);
        let uniforms = Uniforms::new(
            &gpu.device,
            &pipelines.frame_layout,
            gpu.limits.min_uniform_buffer_offset_alignment,
            4,
        );
        gpu.take_error()?;
        Ok(Self {
            gpu,
            pipelines,
            meshes: Vec::new(),
            targets: None,
            uniforms,
            request: RenderRequest::default(),
            mapped: MapResult::default(),
            prefetched: Vec::new(),
            next_slot: 0,
            unpacker: None,
            counts: PrefetchCounts::default(),
        })
    }

    /// The adapter in use: name, driver and device type (e.g. `llvmpipe (...) (Mesa ..., Cpu)`).
    pub fn adapter(&self) -> &str {
        &self.gpu.description
    }

    /// Validates the scene, fills the request's draws and stages the instance uniforms (objects, then background).
    fn stage_instances(&mut self, scene: &Scene<'_>) -> Result<(), RenderError> {
        let total = scene.objects.len() + scene.background.len();
        if total >= usize::from(u16::MAX) {
            return Err(RenderError::TooManyInstances(total));
        }
        if total > self.uniforms.capacity {
            self.uniforms = Uniforms::new(
                &self.gpu.device,
                &self.pipelines.frame_layout,
                self.gpu.limits.min_uniform_buffer_offset_alignment,
                total.next_power_of_two(),
            );
        }
        self.request.draws.clear();
        let staging = &mut self.request.instances;
        staging.clear();
        let objects = scene.objects.iter().enumerate();
        let items = objects
            .map(|(i, o)| (o.mesh, &o.pose, Some(o.id), i))
            .chain((scene.background.iter().enumerate()).map(|(i, b)| (b.mesh, &b.pose, None, i)));
        for (mesh, pose, id, i) in items {
            let mesh_index = mesh.0 as usize;
            let Some(gpu_mesh) = self.meshes.get(mesh_index) else {
                return Err(RenderError::UnknownMesh(mesh));
            };
            if let Some(id) = id
                && (id == MASK_EMPTY || id == MASK_BACKGROUND)
            {
                return Err(RenderError::ReservedObjectId(id));
            }
            if !pose_is_finite(pose) {
                let what = match id {
                    Some(id) => format!("object #{i} (id {id})"),
                    None => format!("background mesh #{i}"),
                };
                return Err(RenderError::NonFinitePose { what });
            }
            let r = pose.rotation.to_rotation_matrix();
            let (r, t) = (r.matrix(), &pose.translation.vector);
            #[rustfmt::skip]
            let values = [
                r[(0, 0)], r[(0, 1)], r[(0, 2)], 0.0,
                r[(1, 0)], r[(1, 1)], r[(1, 2)], 0.0,
                r[(2, 0)], r[(2, 1)], r[(2, 2)], 0.0,
                t.x, t.y, t.z, 0.0,
            ];
            let start = self.request.draws.len() * self.uniforms.stride as usize;
            staging.resize(start, 0);
            staging.extend(f32_bits(&values).flat_map(u32::to_le_bytes));
            push_words(
                staging,
                &[u32::from(id.unwrap_or(MASK_BACKGROUND)), 0, 0, 0],
            );
            self.request.draws.push(Instance {
                mesh: mesh_index,
                cull: if id.is_some() { gpu_mesh.cull } else { 0 },
            });
        }
        Ok(())
    }

    /// Stages the frame uniform in the request: intrinsics, image size, near plane, lighting, whether to shade
    /// intensity.
    fn stage_frame(&mut self, scene: &Scene<'_>, camera: &PinholeCamera) {
        let l = &scene.lighting;
        let light = l.direction.try_normalize(0.0).unwrap_or_default();
        let values = [
            camera.fx,
            camera.fy,
            camera.cx,
            camera.cy,
            f64::from(camera.width),
            f64::from(camera.height),
            scene.near,
            0.0,
            light.x,
            light.y,
            light.z,
            l.ambient,
            l.diffuse,
            if scene.shade_intensity { 1.0 } else { 0.0 },
            0.0,
            0.0,
        ];
        let request = &mut self.request;
        request.frame.clear();
        request
            .frame
            .extend(f32_bits(&values).flat_map(u32::to_le_bytes));
        debug_assert_eq!(request.frame.len() as u64, pipeline::FRAME_BYTES);
        request.camera = Some(*camera);
        request.shade_intensity = scene.shade_intensity;
    }

    /// Validates the render of `scene` by `camera` and stages it as the current request.
    fn stage(&mut self, scene: &Scene<'_>, camera: &PinholeCamera) -> Result<(), RenderError> {
        camera.validate()?;
        self.check_size(camera.width, camera.height)?;
        if !(scene.near.is_finite() && scene.near > 0.0) {
            return Err(RenderError::InvalidNear(scene.near));
        }
        self.stage_instances(scene)?;
        self.stage_frame(scene, camera);
        Ok(())
    }

    /// Checks the image size against the renderer's and the device's limits.
    fn check_size(&self, width: u32, height: u32) -> Result<(), RenderError> {
        let limits = &self.gpu.limits;
        let side = limits.max_texture_dimension_2d;
        let readback = u64::from(padded_row_bytes(width)) * u64::from(height);
        if width > side
            || height > side
            || u64::from(width) * u64::from(height) > MAX_PIXELS
            || readback > limits.max_buffer_size
        {
            return Err(RenderError::ImageTooLarge { width, height });
        }
        Ok(())
    }
}

impl Renderer for GpuRenderer {
    fn device(&self) -> RenderDevice {
        RenderDevice::Vulkan {
            adapter: self.gpu.description.clone(),
            on_cpu: self.gpu.on_cpu,
        }
    }

    fn add_mesh(&mut self, mesh: Arc<Mesh>) -> Result<MeshId, RenderError> {
        let id = u32::try_from(self.meshes.len())
            .map_err(|_| RenderError::Backend("too many meshes".into()))?;
        let gpu = &self.gpu;
        let uploaded =
            GpuMesh::upload(&gpu.device, &gpu.limits, &self.pipelines.mesh_layout, mesh)?;
        gpu.take_error()?;
        self.meshes.push(uploaded);
        Ok(MeshId(id))
    }

    fn render(
        &mut self,
        scene: &Scene<'_>,
        camera: &PinholeCamera,
        target: &mut RenderTarget,
    ) -> Result<(), RenderError> {
        self.stage(scene, camera)?;
        let request = &self.request;
        if let Some(slot) = self
            .prefetched
            .iter_mut()
            .find(|s| s.holds_render && s.request == *request)
        {
            slot.holds_render = false;
            self.counts.used += 1;
            let taken = slot.unpacked.take(target);
            return taken
                .map_err(|e| backend(&self.gpu, e))
                .and_then(|()| self.gpu.take_error());
        }
        let (w, h) = request.size();
        let targets = match self.targets.take() {
            Some(t) if t.fits(w, h) => t,
            old => {
                let (ow, oh) = old.as_ref().map_or((0, 0), |t| (t.width, t.height));
                Targets::new(&self.gpu.device, w.max(ow), h.max(oh))
            }
        };
        let targets = &*self.targets.insert(targets);
        let submission = submit(
            &self.gpu,
            &self.pipelines,
            &self.meshes,
            &self.uniforms,
            request,
            targets,
            &self.mapped,
        )?;
        read_back(
            &self.gpu.device,
            &targets.readback,
            &self.mapped,
            Some(submission),
            camera,
            target,
        )
        .map_err(|e| backend(&self.gpu, e))?;
        self.gpu.take_error()
    }

    fn prefetch_roi(
        &mut self,
        scene: &Scene<'_>,
        camera: &PinholeCamera,
        roi: &Roi,
    ) -> Result<bool, RenderError> {
        self.stage(scene, &camera.crop(roi))?;
        let request = &self.request;
        if self
            .prefetched
            .iter()
            .any(|s| s.holds_render && s.request == *request)
        {
            return Ok(true);
        }
        let unpacker = match &mut self.unpacker {
            Some(u) => &*u,
            empty => match Unpacker::start(PREFETCH_SLOTS) {
                Ok(u) => &*empty.insert(u),
                // No thread for it: render on request only.
                Err(_) => return Ok(false),
            },
        };
        let index = match self.prefetched.iter().position(|s| !s.holds_render) {
            Some(i) => i,
            None if self.prefetched.len() < PREFETCH_SLOTS => {
                self.prefetched.push(PrefetchSlot::default());
                self.prefetched.len() - 1
            }
            None => {
                let i = self.next_slot % self.prefetched.len();
                self.next_slot = i + 1;
                i
            }
        };
        let slot = &mut self.prefetched[index];
        // A render never taken: let its unpacking finish (it releases the buffer) before the slot is reused.
        slot.unpacked.settle().map_err(|e| backend(&self.gpu, e))?;
        slot.holds_render = false;
        let (w, h) = request.size();
        let Some(camera) = request.camera else {
            return Ok(false);
        };
        let targets = match slot.targets.take() {
            Some(t) if t.fits(w, h) => t,
            _ => Targets::new(&self.gpu.device, w, h),
        };
        let targets = &*slot.targets.insert(targets);
        let submission = submit(
            &self.gpu,
            &self.pipelines,
            &self.meshes,
            &self.uniforms,
            request,
            targets,
            &slot.mapped,
        )?;
        slot.unpacked.begin().map_err(|e| backend(&self.gpu, e))?;
        let job = UnpackJob {
            device: self.gpu.device.clone(),
            readback: targets.readback.clone(),
            mapped: Arc::clone(&slot.mapped),
            submission,
            camera,
            into: Arc::clone(&slot.unpacked),
        };
        if let Err(job) = unpacker.send(job) {
            // The thread has ended: unpack here, so the slot is still consistent.
            job.run();
        }
        slot.request.assign(request);
        slot.holds_render = true;
        self.counts.started += 1;
        Ok(true)
    }

    fn prefetch_counts(&self) -> PrefetchCounts {
        self.counts
    }

    fn forget_prefetched(&mut self) {
        // A slot's unpacking may still run; reusing the slot waits for it (`settle`).
        for slot in &mut self.prefetched {
            slot.holds_render = false;
        }
    }

    fn renders_ahead(&self) -> bool {
        true
    }
}
