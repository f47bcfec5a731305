//! Per-render resources kept between renders: the output and depth textures and the readback buffer (sized to the
//! largest image seen), the uniforms (instance buffer sized to the most instances seen), and the unpacking of the
//! read-back pixels into a [`RenderTarget`].

use super::pipeline::{DEPTH_FORMAT, FRAME_BYTES, INSTANCE_BYTES, OUTPUT_BYTES, OUTPUT_FORMAT};
use crate::render::RenderTarget;

/// Bytes per row of a texture-to-buffer copy are a multiple of this.
const ROW_ALIGN: u32 = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;

/// Output and depth textures plus the readback buffer, for images up to `width x height`.
#[derive(Debug)]
pub(super) struct Targets {
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) output: wgpu::Texture,
    pub(super) output_view: wgpu::TextureView,
    pub(super) depth_view: wgpu::TextureView,
    pub(super) readback: wgpu::Buffer,
}

/// Bytes of one read-back row of an image `width` pixels wide.
pub(super) fn padded_row_bytes(width: u32) -> u32 {
    (width * OUTPUT_BYTES).div_ceil(ROW_ALIGN) * ROW_ALIGN
}

impl Targets {
    /// Textures and readback buffer for images up to `width x height`.
    pub(super) fn new(device: &wgpu::Device, width: u32, height: u32) -> Self {
        let texture = |label: &str, format, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let attachment = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let output = texture(
            "output",
            OUTPUT_FORMAT,
            attachment | wgpu::TextureUsages::COPY_SRC,
        );
        let depth = texture("depth", DEPTH_FORMAT, attachment);
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: u64::from(padded_row_bytes(width)) * u64::from(height),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Self {
            width,
            height,
            output_view: output.create_view(&Default::default()),
            depth_view: depth.create_view(&Default::default()),
            output,
            readback,
        }
    }

    /// Whether an image of `width x height` fits.
    pub(super) fn fits(&self, width: u32, height: u32) -> bool {
        width <= self.width && height <= self.height
    }
}

/// The frame uniform and the per-instance uniforms (their bytes are staged in a [`super::request::RenderRequest`]).
#[derive(Debug)]
pub(super) struct Uniforms {
    pub(super) frame: wgpu::Buffer,
    pub(super) instances: wgpu::Buffer,
    /// Instances the buffer holds.
    pub(super) capacity: usize,
    /// Distance between instances, bytes (the device's uniform offset alignment, at least [`INSTANCE_BYTES`]).
    pub(super) stride: u64,
    pub(super) bind_group: wgpu::BindGroup,
}

impl Uniforms {
    /// Uniforms for up to `capacity` instances.
    pub(super) fn new(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        alignment: u32,
        capacity: usize,
    ) -> Self {
        let stride = INSTANCE_BYTES.div_ceil(u64::from(alignment)) * u64::from(alignment);
        let capacity = capacity.max(1);
        let usage = wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST;
        let frame = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame"),
            size: FRAME_BYTES,
            usage,
            mapped_at_creation: false,
        });
        let instances = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("instances"),
            size: stride * capacity as u64,
            usage,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame"),
            layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: frame.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &instances,
                        offset: 0,
                        size: wgpu::BufferSize::new(INSTANCE_BYTES),
                    }),
                },
            ],
        });
        Self {
            frame,
            instances,
            capacity,
            stride,
            bind_group,
        }
    }
}

/// Appends little-endian words to `out`.
pub(super) fn push_words(out: &mut Vec<u8>, words: &[u32]) {
    for w in words {
        out.extend_from_slice(&w.to_le_bytes());
    }
}

/// Decodes a signed-normalised 16-bit value (as WGSL's `pack2x16snorm` writes it).
fn snorm16(bits: u32) -> f32 {
    (f32::from(bits as u16 as i16) / 32767.0).max(-1.0)
}

/// Unpacks `height` rows of `row_bytes` each (the mapped readback) into `target`, already reset to the image size.
pub(super) fn unpack(bytes: &[u8], row_bytes: usize, target: &mut RenderTarget) {
    let width = target.width as usize;
    for (v, row) in bytes.chunks_exact(row_bytes).enumerate() {
        for (u, px) in row[..width * OUTPUT_BYTES as usize]
            .chunks_exact(OUTPUT_BYTES as usize)
            .enumerate()
        {
            let word = |k: usize| u32::from_le_bytes([px[k], px[k + 1], px[k + 2], px[k + 3]]);
            let (depth, intensity, nxy, nz_mask) = (word(0), word(4), word(8), word(12));
            let mask = (nz_mask >> 16) as u16;
            if mask == 0 {
                continue; // Nothing rendered: the reset target already says so.
            }
            let idx = v * width + u;
            let n = [snorm16(nxy), snorm16(nxy >> 16), snorm16(nz_mask)];
            let norm = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            target.depth[idx] = f32::from_bits(depth);
            target.intensity[idx] = f32::from_bits(intensity);
            target.normals[idx] = if norm > 0.0 { n.map(|c| c / norm) } else { n };
            target.mask[idx] = mask;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn snorm16_matches_wgsl_packing() {
        // pack2x16snorm(x) = round(clamp(x, -1, 1) * 32767) as i16.
        assert_eq!(snorm16(32767), 1.0);
        assert_eq!(snorm16((-32767i16) as u16 as u32), -1.0);
        assert_eq!(snorm16((-32768i16) as u16 as u32), -1.0);
        assert_eq!(snorm16(0), 0.0);
        assert!((snorm16(16384) - 0.5).abs() < 1e-4);
    }

    #[test]
    fn rows_are_padded_to_the_copy_alignment() {
        assert_eq!(padded_row_bytes(160), 2560);
        assert_eq!(padded_row_bytes(1), 256);
        assert_eq!(padded_row_bytes(17), 512);
    }
}
