//! Hand-built meshes and a camera shared by the scene, tracker and evaluation tests (the tracker's and the
//! evaluation's tests include this file by path).
#![allow(dead_code)]

use nalgebra::{Point3, Vector3};
use scene::geometry::PinholeCamera;
use scene::mesh::{Material, Mesh, MeshParts, Texture};
use std::sync::Arc;

/// A 640x480 camera with a 60 degree horizontal field of view.
pub fn vga() -> PinholeCamera {
    PinholeCamera::new(525.0, 525.0, 319.5, 239.5, 640, 480).unwrap()
}

/// An axis-aligned cube of edge `side` centred at the origin, 24 vertices (flat faces), outward normals.
pub fn cube(side: f32) -> Mesh {
    cuboid(Vector3::new(side, side, side))
}

/// An axis-aligned box of edges `size` (x, y, z) centred at the origin, 24 vertices (flat faces), outward normals.
pub fn cuboid(size: Vector3<f32>) -> Mesh {
    let h = size / 2.0;
    let mut parts = MeshParts::default();
    // (normal, two in-face axes)
    let faces = [
        (Vector3::x(), Vector3::y(), Vector3::z()),
        (-Vector3::x(), Vector3::z(), Vector3::y()),
        (Vector3::y(), Vector3::z(), Vector3::x()),
        (-Vector3::y(), Vector3::x(), Vector3::z()),
        (Vector3::z(), Vector3::x(), Vector3::y()),
        (-Vector3::z(), Vector3::y(), Vector3::x()),
    ];
    for (n, a, b) in faces {
        let base = parts.positions.len() as u32;
        for (s, t) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            let p = (n + a * s + b * t).component_mul(&h);
            parts.positions.push(Point3::from(p));
            parts.normals.push(n);
            parts.uvs.push([(s + 1.0) / 2.0, (t + 1.0) / 2.0]);
        }
        // Orient each triangle outward.
        let (i, j, k) = if a.cross(&b).dot(&n) > 0.0 {
            (0, 1, 2)
        } else {
            (0, 2, 1)
        };
        parts.triangles.push([base + i, base + j, base + k]);
        let (i, j, k) = if a.cross(&b).dot(&n) > 0.0 {
            (0, 2, 3)
        } else {
            (0, 3, 2)
        };
        parts.triangles.push([base + i, base + j, base + k]);
    }
    Mesh::new("test-cube", parts).unwrap()
}

/// A square of edge `size` in the object's z = 0 plane, centred at the origin, normal -z (towards a camera looking
/// along +z), texture coordinates spanning [0, 1] (u along +x, v along -y so the image is upright in the camera).
pub fn square(size: f32, texture: Option<Texture>) -> Mesh {
    let h = size / 2.0;
    let parts = MeshParts {
        positions: vec![
            Point3::new(-h, -h, 0.0),
            Point3::new(h, -h, 0.0),
            Point3::new(h, h, 0.0),
            Point3::new(-h, h, 0.0),
        ],
        normals: vec![-Vector3::z(); 4],
        uvs: vec![[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]],
        triangles: vec![[0, 2, 1], [0, 3, 2]],
        triangle_materials: vec![],
        materials: vec![Material {
            name: "square".into(),
            diffuse: [1.0, 1.0, 1.0],
            texture: texture.map(Arc::new),
        }],
    };
    Mesh::new("test-square", parts).unwrap()
}

/// A checkerboard texture of `cells x cells` squares, each `texels_per_cell` texels wide, values 0 and 1 (linear).
pub fn checker(cells: u32, texels_per_cell: u32) -> Texture {
    let n = cells * texels_per_cell;
    let texels = (0..n * n)
        .map(|i| {
            let (x, y) = (i % n / texels_per_cell, i / n / texels_per_cell);
            if (x + y) % 2 == 0 { [1.0; 3] } else { [0.0; 3] }
        })
        .collect();
    Texture::from_linear(n, n, texels).unwrap()
}

/// A UV sphere of radius `r` with smooth vertex normals.
pub fn sphere(r: f32, rings: u32, segments: u32) -> Mesh {
    let mut parts = MeshParts::default();
    for i in 0..=rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..=segments {
            let phi = 2.0 * std::f32::consts::PI * j as f32 / segments as f32;
            let n = Vector3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            parts.positions.push(Point3::from(n * r));
            parts.normals.push(n);
            parts
                .uvs
                .push([j as f32 / segments as f32, 1.0 - i as f32 / rings as f32]);
        }
    }
    let row = segments + 1;
    for i in 0..rings {
        for j in 0..segments {
            let a = i * row + j;
            parts.triangles.push([a, a + row, a + 1]);
            parts.triangles.push([a + 1, a + row, a + row + 1]);
        }
    }
    Mesh::new("test-sphere", parts).unwrap()
}
