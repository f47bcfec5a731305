//! Meshes uploaded once, at registration: a non-indexed vertex buffer (so flat-shaded meshes carry their face normal
//! per vertex and each triangle its material), a material table and the luminance texels of all textures.

use super::super::RenderError;
use super::super::cpu::prepared::{back_face_cull_sign, luminance};
use crate::mesh::Mesh;
use glam::Vec3A;
use std::sync::Arc;

/// Bytes of one vertex: position (3 x f32), normal (3 x f32), uv (2 x f32), material (u32).
pub(super) const VERTEX_BYTES: u64 = 36;

/// The vertex layout matching [`VERTEX_BYTES`] and the shader's `VertexIn`.
pub(super) const VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 4] = wgpu::vertex_attr_array![
    0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Uint32
];

/// A mesh resident on the device.
#[derive(Debug)]
pub(super) struct GpuMesh {
    /// Keeps the source mesh alive (and identifies it).
    _mesh: Arc<Mesh>,
    pub(super) vertices: wgpu::Buffer,
    pub(super) vertex_count: u32,
    /// Materials and texels (group 1).
    pub(super) bind_group: wgpu::BindGroup,
    /// Back faces to skip for closed, consistently wound meshes: 1 = positive image-space area (x right, y down),
    /// -1 = negative, 0 = none. Same rule as the CPU backend.
    pub(super) cull: i8,
}

fn push_f32s(out: &mut Vec<u8>, values: &[f32]) {
    for v in values {
        out.extend_from_slice(&v.to_le_bytes());
    }
}

/// The material table (albedo, texel offset, width, height per material) and the concatenated luminance texels.
fn materials_and_texels(mesh: &Mesh) -> (Vec<u8>, Vec<u8>) {
    let mut table = Vec::with_capacity(mesh.materials().len() * 16);
    let mut texels: Vec<u8> = Vec::new();
    let has_uvs = mesh.uvs().is_some();
    for m in mesh.materials() {
        let (offset, width, height) = match (&m.texture, has_uvs) {
            (Some(t), true) => {
                let offset = (texels.len() / 4) as u32;
                let d = m.diffuse;
                for t in t.texels() {
                    let l = luminance([t[0] * d[0], t[1] * d[1], t[2] * d[2]]);
                    texels.extend_from_slice(&l.to_le_bytes());
                }
                (offset, t.width(), t.height())
            }
            _ => (0, 0, 0),
        };
        table.extend_from_slice(&luminance(m.diffuse).to_le_bytes());
        for v in [offset, width, height] {
            table.extend_from_slice(&v.to_le_bytes());
        }
    }
    if texels.is_empty() {
        texels.extend_from_slice(&0f32.to_le_bytes()); // Bindings must not be empty.
    }
    (table, texels)
}

/// Expands the indexed mesh into one vertex per triangle corner.
fn vertex_bytes(mesh: &Mesh) -> Vec<u8> {
    let positions = mesh.positions();
    let mut out = Vec::with_capacity(mesh.triangles().len() * 3 * VERTEX_BYTES as usize);
    for (tri, &material) in mesh.triangles().iter().zip(mesh.triangle_materials()) {
        let corners = tri.map(|i| positions[i as usize].coords);
        let face = (corners[1] - corners[0]).cross(&(corners[2] - corners[0]));
        let face = face
            .try_normalize(0.0)
            .unwrap_or_else(nalgebra::Vector3::zeros);
        for &i in tri {
            let i = i as usize;
            let p = positions[i];
            let n = mesh.normals().map_or(face, |n| n[i]);
            let uv = mesh.uvs().map_or([0.0; 2], |t| t[i]);
            push_f32s(&mut out, &[p.x, p.y, p.z, n.x, n.y, n.z, uv[0], uv[1]]);
            out.extend_from_slice(&material.to_le_bytes());
        }
    }
    out
}

fn buffer_with(
    device: &wgpu::Device,
    label: &str,
    usage: wgpu::BufferUsages,
    bytes: &[u8],
) -> wgpu::Buffer {
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes.len() as u64,
        usage: usage | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: true,
    });
    // A buffer mapped at creation is fully mapped: this cannot fail.
    if let Ok(mut view) = buffer.get_mapped_range_mut(..) {
        view.copy_from_slice(bytes);
    }
    buffer.unmap();
    buffer
}

impl GpuMesh {
    /// Uploads `mesh`; `layout` is the mesh bind group layout (group 1).
    pub(super) fn upload(
        device: &wgpu::Device,
        limits: &wgpu::Limits,
        layout: &wgpu::BindGroupLayout,
        mesh: Arc<Mesh>,
    ) -> Result<Self, RenderError> {
        let vertices = vertex_bytes(&mesh);
        let (table, texels) = materials_and_texels(&mesh);
        let too_big = |what: &str, bytes: usize, limit: u64| {
            RenderError::Backend(format!(
                "mesh {}: {what} of {bytes} bytes exceed the device's limit of {limit} bytes",
                mesh.source().display()
            ))
        };
        let storage_limit = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        if texels.len() as u64 > storage_limit {
            return Err(too_big("textures", texels.len(), storage_limit));
        }
        if vertices.len() as u64 > limits.max_buffer_size {
            return Err(too_big("vertices", vertices.len(), limits.max_buffer_size));
        }
        let vertex_count = u32::try_from(mesh.triangles().len() * 3)
            .map_err(|_| too_big("vertices", vertices.len(), u64::from(u32::MAX)))?;
        let positions: Vec<Vec3A> = mesh
            .positions()
            .iter()
            .map(|p| Vec3A::new(p.x, p.y, p.z))
            .collect();
        let cull = back_face_cull_sign(&positions, mesh.triangles());
        let storage = wgpu::BufferUsages::STORAGE;
        let table = buffer_with(device, "materials", storage, &table);
        let texels = buffer_with(device, "texels", storage, &texels);
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("mesh"),
            layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: table.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: texels.as_entire_binding(),
                },
            ],
        });
        let vertices = buffer_with(device, "vertices", wgpu::BufferUsages::VERTEX, &vertices);
        Ok(Self {
            _mesh: mesh,
            vertices,
            vertex_count,
            bind_group,
            cull,
        })
    }
}
