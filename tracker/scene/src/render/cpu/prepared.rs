//! Meshes converted once, at registration, into the layout the CPU rasteriser wants (f32 `glam` vectors, luminance
//! textures).

use crate::mesh::texture::wrap_unit;
use crate::mesh::{Mesh, Texture};
use glam::{Vec2, Vec3A};
use std::sync::Arc;

/// Rec. 709 luminance of a linear RGB colour.
pub(in crate::render) fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// A single-channel (luminance) texture with wrap-around bilinear sampling; same addressing as [`Texture`].
#[derive(Debug)]
pub(super) struct LumTexture {
    width: usize,
    height: usize,
    texels: Vec<f32>,
}

impl LumTexture {
    /// Luminance of `texture` modulated by the material's diffuse colour.
    fn new(texture: &Texture, diffuse: [f32; 3]) -> Self {
        let texels = texture
            .texels()
            .iter()
            .map(|t| luminance([t[0] * diffuse[0], t[1] * diffuse[1], t[2] * diffuse[2]]))
            .collect();
        Self {
            width: texture.width() as usize,
            height: texture.height() as usize,
            texels,
        }
    }

    /// Bilinear sample at OBJ texture coordinates (`v` up), repeating outside `[0, 1)`.
    #[inline]
    pub(super) fn sample(&self, uv: Vec2) -> f32 {
        let x = wrap_unit(uv.x) * self.width as f32 - 0.5;
        let y = (1.0 - wrap_unit(uv.y)) * self.height as f32 - 0.5;
        let (x0f, y0f) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0f, y - y0f);
        // Coordinates are in [-0.5, n - 0.5), so the lower neighbour is in [-1, n - 1]: wrap with two compares.
        let wrap = |i: f32, n: usize| -> (usize, usize) {
            let i = i as i64;
            let lo = if i < 0 {
                n - 1
            } else {
                (i as usize).min(n - 1)
            };
            let hi = if lo + 1 >= n { 0 } else { lo + 1 };
            (lo, hi)
        };
        let (x0, x1) = wrap(x0f, self.width);
        let (y0, y1) = wrap(y0f, self.height);
        let row0 = y0 * self.width;
        let row1 = y1 * self.width;
        let top = self.texels[row0 + x0] + (self.texels[row0 + x1] - self.texels[row0 + x0]) * fx;
        let bottom =
            self.texels[row1 + x0] + (self.texels[row1 + x1] - self.texels[row1 + x0]) * fx;
        top + (bottom - top) * fy
    }
}

/// How a material's albedo (luminance) is obtained.
#[derive(Debug)]
pub(super) enum Albedo {
    /// A constant.
    Constant(f32),
    /// From a texture via the mesh's texture coordinates.
    Textured(LumTexture),
}

/// A mesh in rasteriser layout.
#[derive(Debug)]
pub(super) struct PreparedMesh {
    /// Keeps the source mesh alive (and identifies it).
    pub(super) _mesh: Arc<Mesh>,
    pub(super) positions: Vec<Vec3A>,
    /// Unit vertex normals, or empty for flat shading.
    pub(super) normals: Vec<Vec3A>,
    /// Texture coordinates, or empty.
    pub(super) uvs: Vec<Vec2>,
    pub(super) triangles: Vec<[u32; 3]>,
    /// Unit face normals (zero for degenerate triangles), object frame.
    pub(super) face_normals: Vec<Vec3A>,
    pub(super) triangle_materials: Vec<u32>,
    pub(super) albedo: Vec<Albedo>,
    /// Back-face culling for this mesh as an object: `+1` cull triangles with positive screen area, `-1` negative,
    /// `0` never (the mesh is not a closed, consistently wound surface).
    pub(super) cull: i8,
}

/// Decides whether back faces can be culled: only for closed, consistently oriented surfaces (every edge, after
/// welding positions within a micrometre, used exactly once in each direction; exporters and lathes often leave
/// seams whose two copies differ in the last bits). Returns the sign of screen-space area to cull
/// (see [`PreparedMesh::cull`]); outward winding (positive enclosed volume) culls positive area.
pub(in crate::render) fn back_face_cull_sign(positions: &[Vec3A], triangles: &[[u32; 3]]) -> i8 {
    use std::collections::HashMap;
    let mut weld: HashMap<[i64; 3], u32> = HashMap::with_capacity(positions.len());
    let ids: Vec<u32> = positions
        .iter()
        .map(|p| {
            let next = weld.len() as u32;
            let key = crate::mesh::weld_key(p.to_array());
            *weld.entry(key).or_insert(next)
        })
        .collect();
    let mut edges: HashMap<(u32, u32), (u32, u32)> = HashMap::with_capacity(triangles.len() * 2);
    let mut volume = 0.0f64;
    for t in triangles {
        let w = t.map(|i| ids[i as usize]);
        if w[0] == w[1] || w[1] == w[2] || w[0] == w[2] {
            continue; // Collapsed (e.g. at a pole): contributes no surface.
        }
        let [a, b, c] = t.map(|i| positions[i as usize].as_dvec3());
        volume += a.dot(b.cross(c));
        for (x, y) in [(w[0], w[1]), (w[1], w[2]), (w[2], w[0])] {
            let entry = edges.entry((x.min(y), x.max(y))).or_insert((0, 0));
            if x < y {
                entry.0 += 1;
            } else {
                entry.1 += 1;
            }
        }
    }
    let closed = !edges.is_empty() && edges.values().all(|&(f, b)| f == 1 && b == 1);
    match (closed, volume) {
        (true, v) if v > 0.0 => 1,
        (true, v) if v < 0.0 => -1,
        _ => 0,
    }
}

impl PreparedMesh {
    pub(super) fn new(mesh: Arc<Mesh>) -> Self {
        let positions: Vec<Vec3A> = mesh
            .positions()
            .iter()
            .map(|p| Vec3A::new(p.x, p.y, p.z))
            .collect();
        let normals = mesh.normals().map_or_else(Vec::new, |n| {
            n.iter().map(|v| Vec3A::new(v.x, v.y, v.z)).collect()
        });
        let uvs: Vec<Vec2> = mesh.uvs().map_or_else(Vec::new, |t| {
            t.iter().map(|t| Vec2::new(t[0], t[1])).collect()
        });
        let triangles = mesh.triangles().to_vec();
        let face_normals = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| positions[i as usize]);
                (b - a).cross(c - a).normalize_or_zero()
            })
            .collect();
        let albedo = mesh
            .materials()
            .iter()
            .map(|m| match (&m.texture, uvs.is_empty()) {
                (Some(t), false) => Albedo::Textured(LumTexture::new(t, m.diffuse)),
                _ => Albedo::Constant(luminance(m.diffuse)),
            })
            .collect();
        let triangle_materials = mesh.triangle_materials().to_vec();
        let cull = back_face_cull_sign(&positions, &triangles);
        Self {
            _mesh: mesh,
            positions,
            normals,
            uvs,
            triangles,
            face_normals,
            triangle_materials,
            albedo,
            cull,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetrahedron() -> (Vec<Vec3A>, Vec<[u32; 3]>) {
        let p = vec![Vec3A::ZERO, Vec3A::X, Vec3A::Y, Vec3A::Z];
        // Outward (counter-clockwise seen from outside).
        let t = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        (p, t)
    }

    #[test]
    fn closed_outward_mesh_culls_positive_area() {
        let (p, t) = tetrahedron();
        assert_eq!(back_face_cull_sign(&p, &t), 1);
        let inverted: Vec<[u32; 3]> = t.iter().map(|&[a, b, c]| [a, c, b]).collect();
        assert_eq!(back_face_cull_sign(&p, &inverted), -1);
    }

    #[test]
    fn open_or_inconsistent_meshes_are_never_culled() {
        let (p, mut t) = tetrahedron();
        let open = t[..3].to_vec();
        assert_eq!(back_face_cull_sign(&p, &open), 0);
        t[3] = [1, 3, 2]; // one face flipped
        assert_eq!(back_face_cull_sign(&p, &t), 0);
        // Split vertices at identical positions are welded: still closed.
        let mut p2 = p.clone();
        p2.push(Vec3A::Z);
        let t2 = vec![[0, 2, 1], [0, 1, 3], [0, 4, 2], [1, 2, 4]];
        assert_eq!(back_face_cull_sign(&p2, &t2), 1);
        // ... and so are copies a few nanometres apart (a lathe's seam at 2 pi), but not a millimetre apart.
        p2[4] = Vec3A::new(6e-9, -4e-9, 1.0);
        assert_eq!(back_face_cull_sign(&p2, &t2), 1);
        p2[4] = Vec3A::new(1e-3, 0.0, 1.0);
        assert_eq!(back_face_cull_sign(&p2, &t2), 0);
    }
}
