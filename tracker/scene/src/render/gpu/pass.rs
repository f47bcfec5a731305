//! One render on the device: recording and submitting its pass and the copy of its image into a readback buffer,
//! then waiting for it and unpacking the image into a [`RenderTarget`].

use super::device::Gpu;
use super::frame::{Targets, Uniforms, padded_row_bytes};
use super::mesh::GpuMesh;
use super::pipeline::Pipelines;
use super::readback::MapResult;
use super::request::RenderRequest;
use crate::render::RenderError;
use std::sync::Arc;

/// A backend error naming the adapter.
pub(super) fn backend(gpu: &Gpu, what: String) -> RenderError {
    RenderError::Backend(format!("{what} on {}", gpu.description))
}

/// Writes the request's uniforms, records its render pass and the copy of the image into `targets`' readback
/// buffer, submits them and requests the buffer's mapping (reported in `mapped`). Does not wait.
pub(super) fn submit(
    gpu: &Gpu,
    pipelines: &Pipelines,
    meshes: &[GpuMesh],
    uniforms: &Uniforms,
    request: &RenderRequest,
    targets: &Targets,
    mapped: &MapResult,
) -> Result<wgpu::SubmissionIndex, RenderError> {
    let (w, h) = request.size();
    gpu.queue.write_buffer(&uniforms.frame, 0, &request.frame);
    if !request.instances.is_empty() {
        gpu.queue
            .write_buffer(&uniforms.instances, 0, &request.instances);
    }
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
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
        for (i, inst) in request.draws.iter().enumerate() {
            let mesh = &meshes[inst.mesh];
            // In range: the buffer holds `capacity` strides and fewer than 65535 instances are drawn.
            let offset = (i as u64 * uniforms.stride) as u32;
            pass.set_pipeline(pipelines.for_cull(inst.cull, request.shade_intensity));
            pass.set_bind_group(0, &uniforms.bind_group, &[offset]);
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
    let submission = gpu.queue.submit([encoder.finish()]);
    gpu.take_error()?;
    let slice = targets
        .readback
        .slice(..u64::from(row_bytes) * u64::from(h));
    let slot = Arc::clone(mapped);
    slice.map_async(wgpu::MapMode::Read, move |result| {
        if let Ok(mut slot) = slot.lock() {
            *slot = Some(result);
        }
    });
    Ok(submission)
}
