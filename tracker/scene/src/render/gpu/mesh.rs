//! Meshes uploaded once, at registration: an indexed vertex buffer (one vertex per distinct mesh vertex and material;
//! flat-shaded meshes, without vertex normals, get one vertex per triangle corner carrying the face normal), a
//! material table and the luminance texels of all textures.

use super::super::RenderError;
use super::super::cpu::prepared::{back_face_cull_sign, luminance};
use crate::mesh::Mesh;
use glam::Vec3A;
use std::collections::HashMap;
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
    /// The triangle list, three `u32` indices into `vertices` per triangle.
    pub(super) indices: wgpu::Buffer,
    pub(super) index_count: u32,
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

/// The device's vertices and the triangle list's indices into them.
///
/// A vertex is shared by the triangles that use the same mesh vertex with the same material, so the device's vertex
/// stage runs about once per mesh vertex rather than once per triangle corner; a mesh without vertex normals shades
/// each triangle flat, so its corners are not shared.
fn vertices_and_indices(mesh: &Mesh) -> (Vec<u8>, Vec<u32>) {
    let positions = mesh.positions();
    let triangles = mesh.triangles();
    let mut bytes = Vec::with_capacity(positions.len() * VERTEX_BYTES as usize);
    let mut indices = Vec::with_capacity(triangles.len() * 3);
    let mut shared: HashMap<(u32, u32), u32> = HashMap::with_capacity(positions.len());
    let mut count = 0u32;
    let mut push = |bytes: &mut Vec<u8>, i: usize, n: &nalgebra::Vector3<f32>, material: u32| {
        let p = positions[i];
        let uv = mesh.uvs().map_or([0.0; 2], |t| t[i]);
        push_f32s(bytes, &[p.x, p.y, p.z, n.x, n.y, n.z, uv[0], uv[1]]);
        bytes.extend_from_slice(&material.to_le_bytes());
        count += 1;
        count - 1
    };
    for (tri, &material) in triangles.iter().zip(mesh.triangle_materials()) {
        match mesh.normals() {
            Some(normals) => {
                for &i in tri {
                    let index = *shared.entry((i, material)).or_insert_with(|| {
                        push(&mut bytes, i as usize, &normals[i as usize], material)
                    });
                    indices.push(index);
                }
            }
            None => {
                let corners = tri.map(|i| positions[i as usize].coords);
                let face = (corners[1] - corners[0]).cross(&(corners[2] - corners[0]));
                let face = face
                    .try_normalize(0.0)
                    .unwrap_or_else(nalgebra::Vector3::zeros);
                for &i in tri {
                    indices.push(push(&mut bytes, i as usize, &face, material));
                }
            }
        }
    }
    (bytes, indices)
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
        let (vertices, indices) = vertices_and_indices(&mesh);
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
        let index_bytes: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        if index_bytes.len() as u64 > limits.max_buffer_size {
            return Err(too_big(
                "indices",
                index_bytes.len(),
                limits.max_buffer_size,
            ));
        }
        let index_count = u32::try_from(indices.len())
            .map_err(|_| too_big("indices", index_bytes.len(), u64::from(u32::MAX)))?;
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
        let indices = buffer_with(device, "indices", wgpu::BufferUsages::INDEX, &index_bytes);
        Ok(Self {
            _mesh: mesh,
            vertices,
            indices,
            index_count,
            bind_group,
            cull,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{Material, MeshParts};
    use nalgebra::{Point3, Vector3};

    /// Position, normal, uv and material of device vertex `index`.
    fn vertex(bytes: &[u8], index: u32) -> ([f32; 8], u32) {
        let start = index as usize * VERTEX_BYTES as usize;
        let word = |k: usize| {
            let b = &bytes[start + 4 * k..start + 4 * k + 4];
            [b[0], b[1], b[2], b[3]]
        };
        let floats = std::array::from_fn(|k| f32::from_le_bytes(word(k)));
        (floats, u32::from_le_bytes(word(8)))
    }

    /// A square of two triangles sharing an edge, on two materials, with or without vertex normals.
    fn square(normals: bool) -> Mesh {
        let parts = MeshParts {
            positions: vec![
                Point3::new(0.0, 0.0, 0.0),
                Point3::new(1.0, 0.0, 0.0),
                Point3::new(1.0, 1.0, 0.0),
                Point3::new(0.0, 1.0, 0.2),
            ],
            normals: if normals {
                vec![Vector3::z(), Vector3::z(), Vector3::x(), Vector3::y()]
            } else {
                Vec::new()
            },
            uvs: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
            triangles: vec![[0, 1, 2], [0, 2, 3], [2, 1, 3]],
            triangle_materials: vec![0, 0, 1],
            materials: vec![Material::default(), Material::default()],
        };
        Mesh::new("square", parts).expect("valid mesh")
    }

    #[test]
    fn every_corner_carries_its_mesh_vertex_and_triangle_material() {
        for with_normals in [true, false] {
            let mesh = square(with_normals);
            let (bytes, indices) = vertices_and_indices(&mesh);
            assert_eq!(indices.len(), mesh.triangles().len() * 3);
            let corners = mesh.triangles().iter().zip(mesh.triangle_materials());
            for (k, (tri, &material)) in corners.enumerate() {
                for (c, &i) in tri.iter().enumerate() {
                    let (v, m) = vertex(&bytes, indices[3 * k + c]);
                    let p = mesh.positions()[i as usize];
                    let uv = mesh.uvs().expect("uvs")[i as usize];
                    assert_eq!([v[0], v[1], v[2]], [p.x, p.y, p.z]);
                    assert_eq!([v[6], v[7]], uv);
                    assert_eq!(m, material);
                    if let Some(normals) = mesh.normals() {
                        let n = normals[i as usize];
                        assert_eq!([v[3], v[4], v[5]], [n.x, n.y, n.z]);
                    }
                }
            }
            let count = bytes.len() / VERTEX_BYTES as usize;
            if with_normals {
                // Vertices 0 and 2 are shared by the first two triangles; the third triangle's material differs.
                assert_eq!(count, 4 + 3);
            } else {
                // Flat: each corner its own vertex with its triangle's face normal.
                assert_eq!(count, 9);
                for k in 0..3 {
                    let face = [0, 1, 2].map(|c| vertex(&bytes, indices[3 * k + c]).0);
                    for f in &face {
                        assert_eq!([f[3], f[4], f[5]], [face[0][3], face[0][4], face[0][5]]);
                    }
                    assert!((face[0][3].hypot(face[0][4]).hypot(face[0][5]) - 1.0).abs() < 1e-6);
                }
            }
        }
    }
}
