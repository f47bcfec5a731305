//! Procedural mesh construction: surfaces of revolution, swept tubes and cuboids, each mapped into its own region of
//! one texture atlas. Units: metres, object frame.

use nalgebra::{Isometry3, Point3, Vector3};

/// A rectangle of the texture atlas in OBJ texture coordinates (`v` up), `0 <= u0 < u1 <= 1`, `0 <= v0 < v1 <= 1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UvRect {
    /// Left.
    pub u0: f32,
    /// Bottom.
    pub v0: f32,
    /// Right.
    pub u1: f32,
    /// Top.
    pub v1: f32,
}

impl UvRect {
    /// The rectangle `[u0, u1] x [v0, v1]`.
    pub const fn new(u0: f32, v0: f32, u1: f32, v1: f32) -> Self {
        Self { u0, v0, u1, v1 }
    }
    /// Maps local coordinates `(s, t)` in `[0, 1]^2` into the atlas, with half a texel of margin (for a 512 atlas) so
    /// bilinear filtering does not bleed across regions.
    pub fn map(&self, s: f32, t: f32) -> [f32; 2] {
        const MARGIN: f32 = 1.0 / 1024.0;
        let lerp = |a: f32, b: f32, x: f32| a + MARGIN + (b - a - 2.0 * MARGIN) * x.clamp(0.0, 1.0);
        [lerp(self.u0, self.u1, s), lerp(self.v0, self.v1, t)]
    }
}

/// Accumulates vertices (position, unit normal, texture coordinate) and triangles.
#[derive(Debug, Clone, Default)]
pub struct MeshBuilder {
    /// Vertex positions, metres.
    pub positions: Vec<Point3<f32>>,
    /// Unit vertex normals, pointing out of the solid.
    pub normals: Vec<Vector3<f32>>,
    /// Texture coordinates in the atlas.
    pub uvs: Vec<[f32; 2]>,
    /// Triangles, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
}

impl MeshBuilder {
    fn vertex(&mut self, p: Point3<f32>, n: Vector3<f32>, uv: [f32; 2]) -> u32 {
        self.positions.push(p);
        self.normals
            .push(n.try_normalize(1e-12).unwrap_or_else(Vector3::z));
        self.uvs.push(uv);
        (self.positions.len() - 1) as u32
    }

    /// Adds a triangle, skipping degenerate ones and winding it so its face normal agrees with the vertex normals.
    fn triangle(&mut self, a: u32, b: u32, c: u32) {
        let [pa, pb, pc] = [a, b, c].map(|i| self.positions[i as usize]);
        let face = (pb - pa).cross(&(pc - pa));
        if face.norm_squared() < 1e-20 {
            return;
        }
        let reference =
            self.normals[a as usize] + self.normals[b as usize] + self.normals[c as usize];
        if face.dot(&reference) >= 0.0 {
            self.triangles.push([a, b, c]);
        } else {
            self.triangles.push([a, c, b]);
        }
    }

    /// A grid of `rows x cols` vertices (row-major, as produced by `vertex`) starting at index `base`, stitched into
    /// quads.
    fn stitch(&mut self, base: u32, rows: u32, cols: u32) {
        for i in 0..rows - 1 {
            for j in 0..cols - 1 {
                let a = base + i * cols + j;
                let (b, c, d) = (a + 1, a + cols, a + cols + 1);
                self.triangle(a, c, b);
                self.triangle(b, c, d);
            }
        }
    }

    /// A surface of revolution about the local z axis, placed by `frame`.
    ///
    /// `strips` are polylines of `(radius, z)` points traversed so that the solid lies on the left (counter-clockwise
    /// in the `(r, z)` half-plane); normals are smooth within a strip and creased between strips. Texture: `u`
    /// around (one turn across `uv`), `v` along the profile's arc length.
    pub fn lathe(
        &mut self,
        strips: &[&[(f32, f32)]],
        segments: u32,
        uv: UvRect,
        frame: &Isometry3<f32>,
    ) {
        let total: f32 = strips.iter().map(|s| arc_length(s)).sum::<f32>().max(1e-9);
        let mut travelled = 0.0;
        for strip in strips {
            if strip.len() < 2 {
                continue;
            }
            let base = self.positions.len() as u32;
            let mut along = 0.0;
            for (k, &(r, z)) in strip.iter().enumerate() {
                if k > 0 {
                    let (pr, pz) = strip[k - 1];
                    along += ((r - pr).powi(2) + (z - pz).powi(2)).sqrt();
                }
                // Tangent averaged over the neighbouring segments; outward normal is the tangent turned clockwise.
                let prev = strip[k.saturating_sub(1)];
                let next = strip[(k + 1).min(strip.len() - 1)];
                let (dr, dz) = (next.0 - prev.0, next.1 - prev.1);
                let t = (travelled + along) / total;
                for j in 0..=segments {
                    let phi = std::f32::consts::TAU * j as f32 / segments as f32;
                    let (s, c) = phi.sin_cos();
                    let p = Point3::new(r * c, r * s, z);
                    let n = Vector3::new(dz * c, dz * s, -dr);
                    self.vertex(frame * p, frame * n, uv.map(j as f32 / segments as f32, t));
                }
            }
            travelled += along;
            self.stitch(base, strip.len() as u32, segments + 1);
        }
    }

    /// A tube swept along `path` (at least 2 points) with per-point `radii`, `segments` around, closed by flat end
    /// caps. Texture: `u` around, `v` along the path (caps map to the strip's ends).
    pub fn tube(&mut self, path: &[Point3<f32>], radii: &[f32], segments: u32, uv: UvRect) {
        let n = path.len().min(radii.len());
        if n < 2 {
            return;
        }
        let tangent = |k: usize| (path[(k + 1).min(n - 1)] - path[k.saturating_sub(1)]).normalize();
        // Parallel transport of a normal along the path, so the surface does not twist.
        let t0 = tangent(0);
        let helper = if t0.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let mut normal = t0.cross(&helper).normalize();
        let mut frames = Vec::with_capacity(n);
        for k in 0..n {
            let t = tangent(k);
            normal = (normal - t * normal.dot(&t))
                .try_normalize(1e-9)
                .unwrap_or(normal);
            frames.push((t, normal, t.cross(&normal)));
        }
        let length: f32 = (1..n)
            .map(|k| (path[k] - path[k - 1]).norm())
            .sum::<f32>()
            .max(1e-9);
        let base = self.positions.len() as u32;
        let mut along = 0.0;
        for k in 0..n {
            if k > 0 {
                along += (path[k] - path[k - 1]).norm();
            }
            let (t, a, b) = frames[k];
            // Radius slope tilts the normal towards the thinner end.
            let slope = (radii[(k + 1).min(n - 1)] - radii[k.saturating_sub(1)])
                / (path[(k + 1).min(n - 1)] - path[k.saturating_sub(1)])
                    .norm()
                    .max(1e-9);
            for j in 0..=segments {
                let phi = std::f32::consts::TAU * j as f32 / segments as f32;
                let radial = a * phi.cos() + b * phi.sin();
                let p = path[k] + radial * radii[k];
                self.vertex(
                    p,
                    radial - t * slope,
                    uv.map(j as f32 / segments as f32, along / length),
                );
            }
        }
        self.stitch(base, n as u32, segments + 1);
        // End caps: fans around the end centres with flat normals.
        for (k, sign) in [(0, -1.0f32), (n - 1, 1.0)] {
            let (t, a, b) = frames[k];
            let cap_n = t * sign;
            let v = if k == 0 { 0.0 } else { 1.0 };
            let centre = self.vertex(path[k], cap_n, uv.map(0.5, v));
            let ring = self.positions.len() as u32;
            for j in 0..=segments {
                let phi = std::f32::consts::TAU * j as f32 / segments as f32;
                let p = path[k] + (a * phi.cos() + b * phi.sin()) * radii[k];
                self.vertex(p, cap_n, uv.map(j as f32 / segments as f32, v));
            }
            for j in 0..segments {
                self.triangle(centre, ring + j, ring + j + 1);
            }
        }
    }

    /// An axis-aligned (in its frame) box of edge lengths `size`, centred on `frame`'s origin, flat faces. `faces`
    /// gives each face's atlas region in the order +x, -x, +y, -y, +z, -z.
    pub fn cuboid(&mut self, size: Vector3<f32>, frame: &Isometry3<f32>, faces: [UvRect; 6]) {
        let h = size / 2.0;
        let axes = [
            (Vector3::x(), Vector3::y(), Vector3::z()),
            (-Vector3::x(), -Vector3::y(), Vector3::z()),
            (Vector3::y(), -Vector3::x(), Vector3::z()),
            (-Vector3::y(), Vector3::x(), Vector3::z()),
            (Vector3::z(), Vector3::x(), Vector3::y()),
            (-Vector3::z(), Vector3::x(), -Vector3::y()),
        ];
        for ((n, a, b), uv) in axes.into_iter().zip(faces) {
            let base = self.positions.len() as u32;
            // 2x2 grid over the face: s along a, t along b.
            for (t, s) in [(0.0, 0.0), (0.0, 1.0), (1.0, 0.0), (1.0, 1.0)] {
                let p = n.component_mul(&h)
                    + a.component_mul(&h) * (2.0 * s - 1.0)
                    + b.component_mul(&h) * (2.0 * t - 1.0);
                self.vertex(frame * Point3::from(p), frame * n, uv.map(s, t));
            }
            self.stitch(base, 2, 2);
        }
    }

    /// Moves every vertex so that the bounding-box centre is at the origin; returns the applied shift.
    pub fn center_on_bounding_box(&mut self) -> Vector3<f32> {
        let Some(first) = self.positions.first().copied() else {
            return Vector3::zeros();
        };
        let (lo, hi) = self
            .positions
            .iter()
            .fold((first, first), |(lo, hi), p| (lo.inf(p), hi.sup(p)));
        let shift = -(lo.coords + hi.coords) / 2.0;
        for p in &mut self.positions {
            *p += shift;
        }
        shift
    }
}

fn arc_length(points: &[(f32, f32)]) -> f32 {
    points
        .windows(2)
        .map(|w| ((w[1].0 - w[0].0).powi(2) + (w[1].1 - w[0].1).powi(2)).sqrt())
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lathe_cylinder_normals_point_outwards() {
        let mut b = MeshBuilder::default();
        let side: &[(f32, f32)] = &[(0.05, 0.0), (0.05, 0.1)];
        b.lathe(
            &[side],
            32,
            UvRect::new(0.0, 0.0, 1.0, 1.0),
            &Isometry3::identity(),
        );
        assert_eq!(b.triangles.len(), 64);
        for (p, n) in b.positions.iter().zip(&b.normals) {
            let radial = Vector3::new(p.x, p.y, 0.0).normalize();
            assert!((n - radial).norm() < 1e-5);
        }
        // Winding agrees with normals.
        for t in &b.triangles {
            let [a, c, d] = t.map(|i| b.positions[i as usize]);
            let face = (c - a).cross(&(d - a));
            assert!(face.dot(&b.normals[t[0] as usize]) > 0.0);
        }
    }

    #[test]
    fn cuboid_is_closed_with_six_faces() {
        let mut b = MeshBuilder::default();
        b.cuboid(
            Vector3::new(0.1, 0.2, 0.3),
            &Isometry3::identity(),
            [UvRect::new(0.0, 0.0, 1.0, 1.0); 6],
        );
        assert_eq!(b.triangles.len(), 12);
        // Closed: with corners welded by position, every edge is used once in each direction.
        let corner = |i: u32| {
            let p = b.positions[i as usize];
            [p.x, p.y, p.z].map(|c| (c * 1e6).round() as i64)
        };
        let mut edges = std::collections::HashMap::new();
        for t in &b.triangles {
            for (x, y) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                *edges.entry((corner(x), corner(y))).or_insert(0) += 1;
            }
        }
        assert_eq!(
            edges.len(),
            36,
            "12 triangles of a closed box have 36 directed edges"
        );
        for (&(a, c), &n) in &edges {
            assert_eq!(n, 1, "edge {a:?} -> {c:?} used {n} times");
            assert_eq!(
                edges.get(&(c, a)),
                Some(&1),
                "edge {a:?} -> {c:?} has no twin"
            );
        }
        for (p, n) in b.positions.iter().zip(&b.normals) {
            // Each vertex lies on the face its normal names.
            let d = p.coords.dot(n);
            let expected = (n.x.abs() * 0.05) + (n.y.abs() * 0.1) + (n.z.abs() * 0.15);
            assert!((d - expected).abs() < 1e-6);
        }
    }
}
