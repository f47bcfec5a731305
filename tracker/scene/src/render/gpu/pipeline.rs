//! The shader, bind group layouts and render pipelines (one per back-face culling mode and shading: full, or
//! geometry only).

use super::mesh::{VERTEX_ATTRIBUTES, VERTEX_BYTES};

/// Format of the packed output: depth bits, intensity bits, normal x/y (snorm16), normal z (snorm16) | mask << 16.
pub(super) const OUTPUT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;
/// Bytes per pixel of [`OUTPUT_FORMAT`].
pub(super) const OUTPUT_BYTES: u32 = 16;
/// Format of the depth buffer (near / z, nearest = greatest).
pub(super) const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Size of the frame uniform (camera and lighting), bytes.
pub(super) const FRAME_BYTES: u64 = 64;
/// Size of one instance uniform (rotation rows, translation, mask), bytes.
pub(super) const INSTANCE_BYTES: u64 = 80;

/// Layouts and pipelines, created once per device.
#[derive(Debug)]
pub(super) struct Pipelines {
    /// Group 0: frame uniform, instance uniform (dynamic offset).
    pub(super) frame_layout: wgpu::BindGroupLayout,
    /// Group 1: material table, texels.
    pub(super) mesh_layout: wgpu::BindGroupLayout,
    /// Depth, normal, mask and shaded intensity.
    full: CullModes,
    /// Depth, normal and mask only, with fewer interpolated values (intensity 0).
    geometry: CullModes,
}

/// The pipelines of one shader pair, one per back-face culling mode.
#[derive(Debug)]
struct CullModes {
    /// Two-sided.
    no_cull: wgpu::RenderPipeline,
    /// Skips triangles of positive image-space area (CPU backend's cull sign 1).
    cull_positive: wgpu::RenderPipeline,
    /// Skips triangles of negative image-space area (cull sign -1).
    cull_negative: wgpu::RenderPipeline,
}

fn uniform_entry(binding: u32, dynamic: bool, size: u64) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: dynamic,
            min_binding_size: wgpu::BufferSize::new(size),
        },
        count: None,
    }
}

fn storage_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

impl Pipelines {
    pub(super) fn new(device: &wgpu::Device) -> Self {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("render.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("render.wgsl").into()),
        });
        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("frame"),
            entries: &[
                uniform_entry(0, false, FRAME_BYTES),
                uniform_entry(1, true, INSTANCE_BYTES),
            ],
        });
        let mesh_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("mesh"),
            entries: &[storage_entry(0), storage_entry(1)],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("render"),
            bind_group_layouts: &[Some(&frame_layout), Some(&mesh_layout)],
            immediate_size: 0,
        });
        let pipeline = |label: &str,
                        (vs, fs): (&str, &str),
                        front_face: wgpu::FrontFace,
                        cull_mode: Option<wgpu::Face>| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &shader,
                    entry_point: Some(vs),
                    compilation_options: Default::default(),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: VERTEX_BYTES,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &VERTEX_ATTRIBUTES,
                    })],
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    front_face,
                    cull_mode,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::Greater),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &shader,
                    entry_point: Some(fs),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: OUTPUT_FORMAT,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        // Positive area in y-down pixel coordinates is clockwise in y-up NDC.
        let modes = |shaders: (&str, &str)| CullModes {
            no_cull: pipeline("two-sided", shaders, wgpu::FrontFace::Ccw, None),
            cull_positive: pipeline(
                "cull cw",
                shaders,
                wgpu::FrontFace::Ccw,
                Some(wgpu::Face::Back),
            ),
            cull_negative: pipeline(
                "cull ccw",
                shaders,
                wgpu::FrontFace::Cw,
                Some(wgpu::Face::Back),
            ),
        };
        Self {
            full: modes(("vs_main", "fs_main")),
            geometry: modes(("vs_geometry", "fs_geometry")),
            frame_layout,
            mesh_layout,
        }
    }

    /// The pipeline for a mesh's cull sign (background meshes are always drawn with sign 0), shading intensity or
    /// geometry only.
    pub(super) fn for_cull(&self, cull: i8, shade_intensity: bool) -> &wgpu::RenderPipeline {
        let modes = if shade_intensity {
            &self.full
        } else {
            &self.geometry
        };
        match cull {
            1 => &modes.cull_positive,
            -1 => &modes.cull_negative,
            _ => &modes.no_cull,
        }
    }
}
