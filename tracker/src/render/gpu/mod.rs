//! The `wgpu` (Vulkan) renderer backend: same outputs as the CPU rasteriser, rasterised by a GPU or by Mesa's
//! lavapipe CPU driver.
//!
//! One render pass draws every instance (objects first, then background, as the CPU backend) into a packed
//! `Rgba32Uint` target (depth, intensity, snorm16 normal, mask) with a `near / z` depth buffer; the target is copied
//! into a reused readback buffer, mapped, and unpacked into the caller's [`RenderTarget`]. Textures, buffers and
//! uniforms are sized to the largest image and the most instances seen and then reused.

mod device;
mod frame;
mod mesh;
mod pipeline;

use super::{
    MASK_BACKGROUND, MASK_EMPTY, MAX_PIXELS, MeshId, RenderError, RenderTarget, Renderer, Scene,
};
use crate::geometry::PinholeCamera;
use crate::mesh::Mesh;
use device::Gpu;
use frame::{Targets, Uniforms, padded_row_bytes, push_words, unpack};
use mesh::GpuMesh;
use nalgebra::Isometry3;
use pipeline::Pipelines;
use std::sync::{Arc, Mutex};

/// One posed instance of the current render.
#[derive(Debug, Clone, Copy)]
struct Instance {
    mesh: usize,
    /// Cull sign used for this instance (0 for background meshes, which may surround the camera).
    cull: i8,
}

/// Result slot of the readback buffer's map request.
type MapResult = Arc<Mutex<Option<Result<(), wgpu::BufferAsyncError>>>>;

/// A renderer on `wgpu` over Vulkan: depth, normals, object mask and shaded intensity, matching [`CpuRenderer`]
/// (depth to float precision, masks except on a few silhouette pixels, normals to 16-bit precision).
///
/// Each render waits for the device and reads the image back (16 bytes per pixel), so a render costs a round trip
/// to the device on top of the rasterisation. `Send`: it can live on the tracker's thread.
///
/// [`CpuRenderer`]: super::CpuRenderer
#[derive(Debug)]
pub struct GpuRenderer {
    gpu: Gpu,
    pipelines: Pipelines,
    meshes: Vec<GpuMesh>,
    targets: Option<Targets>,
    uniforms: Uniforms,
    instances: Vec<Instance>,
    mapped: MapResult,
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
            instances: Vec::new(),
            mapped: MapResult::default(),
        })
    }

    /// The adapter in use: name, driver and device type (e.g. `llvmpipe (...) (Mesa ..., Cpu)`).
    pub fn adapter(&self) -> &str {
        &self.gpu.description
    }

    /// Validates the scene, fills `self.instances` and stages the instance uniforms (objects, then background).
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
        self.instances.clear();
        let staging = &mut self.uniforms.staging;
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
            let start = self.instances.len() * self.uniforms.stride as usize;
            staging.resize(start, 0);
            staging.extend(f32_bits(&values).flat_map(u32::to_le_bytes));
            push_words(
                staging,
                &[u32::from(id.unwrap_or(MASK_BACKGROUND)), 0, 0, 0],
            );
            self.instances.push(Instance {
                mesh: mesh_index,
                cull: if id.is_some() { gpu_mesh.cull } else { 0 },
            });
        }
        Ok(())
    }

    /// Stages the frame uniform: intrinsics, image size, near plane, lighting, whether to shade intensity.
    fn write_frame(&self, scene: &Scene<'_>, camera: &PinholeCamera) {
        let l = &scene.lighting;
        let light = l.direction.try_normalize(0.0).unwrap_or_default();
        let mut bytes = [0u8; pipeline::FRAME_BYTES as usize];
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
        for (chunk, bits) in bytes.chunks_exact_mut(4).zip(f32_bits(&values)) {
            chunk.copy_from_slice(&bits.to_le_bytes());
        }
        self.gpu.queue.write_buffer(&self.uniforms.frame, 0, &bytes);
        if !self.uniforms.staging.is_empty() {
            self.gpu
                .queue
                .write_buffer(&self.uniforms.instances, 0, &self.uniforms.staging);
        }
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
        camera.validate()?;
        let (w, h) = (camera.width, camera.height);
        self.check_size(w, h)?;
        if !(scene.near.is_finite() && scene.near > 0.0) {
            return Err(RenderError::InvalidNear(scene.near));
        }
        self.stage_instances(scene)?;
        let targets = match self.targets.take() {
            Some(t) if t.fits(w, h) => t,
            old => {
                let (ow, oh) = old.as_ref().map_or((0, 0), |t| (t.width, t.height));
                Targets::new(&self.gpu.device, w.max(ow), h.max(oh))
            }
        };
        self.write_frame(scene, camera);
        let targets = &*self.targets.insert(targets);
        let device = &self.gpu.device;
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("render"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &targets.output_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &targets.depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(0.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_viewport(0.0, 0.0, w as f32, h as f32, 0.0, 1.0);
            pass.set_scissor_rect(0, 0, w, h);
            for (i, inst) in self.instances.iter().enumerate() {
                let mesh = &self.meshes[inst.mesh];
                // In range: the buffer holds `capacity` strides and fewer than 65535 instances are drawn.
                let offset = (i as u64 * self.uniforms.stride) as u32;
                pass.set_pipeline(self.pipelines.for_cull(inst.cull, scene.shade_intensity));
                pass.set_bind_group(0, &self.uniforms.bind_group, &[offset]);
                pass.set_bind_group(1, &mesh.bind_group, &[]);
                pass.set_vertex_buffer(0, mesh.vertices.slice(..));
                pass.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..mesh.index_count, 0, 0..1);
            }
        }
        let row_bytes = padded_row_bytes(w);
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &targets.output,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &targets.readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row_bytes),
                    rows_per_image: Some(h),
                },
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
        self.gpu.queue.submit([encoder.finish()]);
        self.gpu.take_error()?;
        let slice = targets
            .readback
            .slice(..u64::from(row_bytes) * u64::from(h));
        let mapped = Arc::clone(&self.mapped);
        slice.map_async(wgpu::MapMode::Read, move |result| {
            if let Ok(mut slot) = mapped.lock() {
                *slot = Some(result);
            }
        });
        let polled = device.poll(wgpu::PollType::wait_indefinitely());
        let map_result = self.mapped.lock().ok().and_then(|mut slot| slot.take());
        let backend =
            |what: String| RenderError::Backend(format!("{what} on {}", self.gpu.description));
        polled.map_err(|e| backend(format!("waiting for the GPU failed: {e}")))?;
        match map_result {
            Some(Ok(())) => {}
            Some(Err(e)) => return Err(backend(format!("reading the image back failed: {e}"))),
            None => return Err(backend("the image read-back never completed".into())),
        }
        target.reset(w, h);
        target.camera = Some(*camera);
        let unpacked = slice
            .get_mapped_range()
            .map(|view| unpack(&view, row_bytes as usize, target))
            .map_err(|e| backend(format!("mapping the read-back buffer failed: {e}")));
        targets.readback.unmap();
        unpacked?;
        self.gpu.take_error()
    }
}
