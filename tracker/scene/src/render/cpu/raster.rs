//! Triangle setup, clipping and rasterisation into a visibility buffer.
//!
//! Triangles are clipped in the camera frame against the near plane and a guard band around the image, projected,
//! snapped to 1/256 pixel, and scanned with exact integer edge functions and the top-left fill rule: shared edges are
//! watertight and results are bit-reproducible. Each covered pixel centre keeps the nearest fragment's depth, instance,
//! triangle and perspective-correct barycentric coordinates (relative to the original, unclipped triangle); shading
//! happens afterwards, once per visible pixel.

use glam::{Vec3A, Vec4};

/// Sub-pixel precision: coordinates are snapped to `1 / SUBPIXEL` pixel.
const SUBPIXEL: i64 = 256;
/// Guard band beyond the image border, pixels: triangles are clipped only when they reach this far out.
const GUARD_PX: f32 = 2048.0;
/// Instance value of pixels with no fragment.
pub(super) const NO_INSTANCE: u16 = u16::MAX;

/// The per-pixel nearest fragment (structure of arrays).
#[derive(Debug, Default)]
pub(super) struct VisBuffer {
    pub(super) width: usize,
    pub(super) height: usize,
    /// Inverse depth `1 / z`, 1/metres; 0 where empty.
    pub(super) inv_z: Vec<f32>,
    /// Instance index, or [`NO_INSTANCE`].
    pub(super) instance: Vec<u16>,
    /// Triangle index within the instance's mesh (meaningful only where `instance` is set).
    pub(super) triangle: Vec<u32>,
    /// Perspective-correct barycentric coordinates `(b1, b2)` of the original triangle (`b0 = 1 - b1 - b2`;
    /// meaningful only where `instance` is set).
    pub(super) bary: Vec<[f32; 2]>,
}

impl VisBuffer {
    /// Resizes (keeping capacity) and clears.
    pub(super) fn reset(&mut self, width: usize, height: usize) {
        let n = width * height;
        self.width = width;
        self.height = height;
        self.inv_z.clear();
        self.inv_z.resize(n, 0.0);
        self.instance.clear();
        self.instance.resize(n, NO_INSTANCE);
        // Written together with `instance` and read only where it is set: resized, not cleared.
        self.triangle.resize(n, 0);
        self.bary.resize(n, [0.0; 2]);
    }
}

/// Intrinsics and clip planes for one render, f32.
#[derive(Debug, Clone, Copy)]
pub(super) struct Projector {
    fx: f32,
    fy: f32,
    cx: f32,
    cy: f32,
    /// Clip planes `(a, b, c, d)`: inside where `a x + b y + c z + d >= 0` (camera frame). Near first.
    planes: [Vec4; 5],
}

impl Projector {
    pub(super) fn new(
        fx: f32,
        fy: f32,
        cx: f32,
        cy: f32,
        width: u32,
        height: u32,
        near: f32,
    ) -> Self {
        let (w, h) = (width as f32, height as f32);
        let planes = [
            Vec4::new(0.0, 0.0, 1.0, -near),
            Vec4::new(fx, 0.0, cx + 0.5 + GUARD_PX, 0.0),
            Vec4::new(-fx, 0.0, w - 0.5 + GUARD_PX - cx, 0.0),
            Vec4::new(0.0, fy, cy + 0.5 + GUARD_PX, 0.0),
            Vec4::new(0.0, -fy, h - 0.5 + GUARD_PX - cy, 0.0),
        ];
        Self {
            fx,
            fy,
            cx,
            cy,
            planes,
        }
    }

    /// Bit `k` is set when `p` is outside clip plane `k`.
    #[inline]
    pub(super) fn outcode(&self, p: Vec3A) -> u8 {
        let mut code = 0;
        for (k, plane) in self.planes.iter().enumerate() {
            if plane.x * p.x + plane.y * p.y + plane.z * p.z + plane.w < 0.0 {
                code |= 1 << k;
            }
        }
        code
    }

    /// Projects a camera-frame point in front of the near plane to a raster vertex with barycentric tag `b`.
    #[inline]
    pub(super) fn project(&self, p: Vec3A, b: Vec3A) -> RasterVertex {
        let iz = 1.0 / p.z;
        let x = self.fx * p.x * iz + self.cx;
        let y = self.fy * p.y * iz + self.cy;
        RasterVertex {
            x: round_to_i64(x * SUBPIXEL as f32),
            y: round_to_i64(y * SUBPIXEL as f32),
            iz,
            b,
        }
    }
}

/// Rounds half away from zero with a truncating conversion (no libm call on baseline x86-64); saturates.
#[inline]
fn round_to_i64(v: f32) -> i64 {
    (v + 0.5f32.copysign(v)) as i64
}

/// A projected vertex: fixed-point pixel-centre coordinates, inverse depth and its barycentric coordinates with respect
/// to the original triangle.
#[derive(Debug, Clone, Copy)]
pub(super) struct RasterVertex {
    x: i64,
    y: i64,
    iz: f32,
    b: Vec3A,
}

/// Which triangles to skip by the sign of their screen-space area (back faces of closed meshes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Cull(pub(super) i8);

/// The triangle `v` (camera frame) with per-vertex outcodes; clips if needed and rasterises into `vis`.
#[allow(clippy::too_many_arguments)] // One call site; the arguments are the triangle's data.
pub(super) fn draw_triangle(
    vis: &mut VisBuffer,
    proj: &Projector,
    instance: u16,
    triangle: u32,
    v: [Vec3A; 3],
    codes: [u8; 3],
    projected: Option<[RasterVertex; 3]>,
    cull: Cull,
) {
    if codes[0] & codes[1] & codes[2] != 0 {
        return; // Entirely outside one plane.
    }
    let tags = [Vec3A::X, Vec3A::Y, Vec3A::Z];
    if codes[0] | codes[1] | codes[2] == 0 {
        let rv = match projected {
            Some(mut p) => {
                for (p, tag) in p.iter_mut().zip(tags) {
                    p.b = tag;
                }
                p
            }
            None => [0, 1, 2].map(|i| proj.project(v[i], tags[i])),
        };
        rasterise(vis, instance, triangle, rv, cull);
        return;
    }
    // Sutherland-Hodgman against the planes that some vertex violates; at most 3 + 5 vertices.
    let mut poly = [(Vec3A::ZERO, Vec3A::ZERO); 8];
    let mut scratch = [(Vec3A::ZERO, Vec3A::ZERO); 8];
    let mut n = 3;
    for i in 0..3 {
        poly[i] = (v[i], tags[i]);
    }
    let violated = codes[0] | codes[1] | codes[2];
    for (k, plane) in proj.planes.iter().enumerate() {
        if violated & (1 << k) == 0 {
            continue;
        }
        let dist = |p: Vec3A| plane.x * p.x + plane.y * p.y + plane.z * p.z + plane.w;
        let mut m = 0;
        for i in 0..n {
            let (a, ba) = poly[i];
            let (b, bb) = poly[(i + 1) % n];
            let (da, db) = (dist(a), dist(b));
            if da >= 0.0 && m < scratch.len() {
                scratch[m] = (a, ba);
                m += 1;
            }
            if (da >= 0.0) != (db >= 0.0) && m < scratch.len() {
                let t = da / (da - db);
                scratch[m] = (a + (b - a) * t, ba + (bb - ba) * t);
                m += 1;
            }
        }
        n = m;
        poly[..n].copy_from_slice(&scratch[..n]);
        if n < 3 {
            return;
        }
    }
    let first = proj.project(poly[0].0, poly[0].1);
    for i in 1..n - 1 {
        let rv = [
            first,
            proj.project(poly[i].0, poly[i].1),
            proj.project(poly[i + 1].0, poly[i + 1].1),
        ];
        rasterise(vis, instance, triangle, rv, cull);
    }
}

/// Edge function of `p` against the directed edge `a -> b` (positive on the inside for positive-area triangles in
/// y-down image coordinates).
#[inline]
fn edge(a: &RasterVertex, b: &RasterVertex, px: i64, py: i64) -> i64 {
    (b.x - a.x) * (py - a.y) - (b.y - a.y) * (px - a.x)
}

/// Top-left fill rule: pixels exactly on a top or left edge belong to the triangle, others not.
#[inline]
fn fill_bias(a: &RasterVertex, b: &RasterVertex) -> i64 {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    if dy < 0 || (dy == 0 && dx > 0) { 0 } else { -1 }
}

fn rasterise(
    vis: &mut VisBuffer,
    instance: u16,
    triangle: u32,
    mut v: [RasterVertex; 3],
    cull: Cull,
) {
    let mut area = edge(&v[0], &v[1], v[2].x, v[2].y);
    if area == 0 || (cull.0 > 0 && area > 0) || (cull.0 < 0 && area < 0) {
        return;
    }
    if area < 0 {
        // Two-sided: reorder so that the inside is positive.
        v.swap(1, 2);
        area = -area;
    }
    let (w, h) = (vis.width as i64, vis.height as i64);
    let min_x = v.iter().map(|p| p.x).min().unwrap_or(0);
    let max_x = v.iter().map(|p| p.x).max().unwrap_or(-1);
    let min_y = v.iter().map(|p| p.y).min().unwrap_or(0);
    let max_y = v.iter().map(|p| p.y).max().unwrap_or(-1);
    // Pixel centres i * SUBPIXEL inside the box, clamped to the image.
    let x0 = (min_x + SUBPIXEL - 1).div_euclid(SUBPIXEL).max(0);
    let x1 = max_x.div_euclid(SUBPIXEL).min(w - 1);
    let y0 = (min_y + SUBPIXEL - 1).div_euclid(SUBPIXEL).max(0);
    let y1 = max_y.div_euclid(SUBPIXEL).min(h - 1);
    if x0 > x1 || y0 > y1 {
        return;
    }
    // Edge k is opposite vertex k, so its value is vertex k's (unnormalised) barycentric weight.
    let edges = [(1, 2), (2, 0), (0, 1)];
    let (px, py) = (x0 * SUBPIXEL, y0 * SUBPIXEL);
    let mut row = [0i64; 3];
    let mut step_x = [0i64; 3];
    let mut step_y = [0i64; 3];
    let mut bias = [0i64; 3];
    for (k, &(a, b)) in edges.iter().enumerate() {
        row[k] = edge(&v[a], &v[b], px, py);
        bias[k] = fill_bias(&v[a], &v[b]);
        step_x[k] = -(v[b].y - v[a].y) * SUBPIXEL;
        step_y[k] = (v[b].x - v[a].x) * SUBPIXEL;
    }
    // Inverse depth and the perspective-weighted barycentric tags are affine in the pixel position: evaluate them as
    // planes `value = v0 + vx * dx + vy * dy` relative to the box's first pixel centre (f64 setup, f32 per pixel).
    let inv_area = 1.0 / area as f64;
    let plane = |attr: [f64; 3]| -> [f32; 3] {
        let mut out = [0.0f64; 3];
        for k in 0..3 {
            out[0] += attr[k] * row[k] as f64 * inv_area;
            out[1] += attr[k] * step_x[k] as f64 * inv_area;
            out[2] += attr[k] * step_y[k] as f64 * inv_area;
        }
        out.map(|v| v as f32)
    };
    let iz = [v[0].iz, v[1].iz, v[2].iz].map(f64::from);
    let inv_z = plane(iz);
    let tag1 = plane([0, 1, 2].map(|k| iz[k] * f64::from(v[k].b.y)));
    let tag2 = plane([0, 1, 2].map(|k| iz[k] * f64::from(v[k].b.z)));
    // The fill rule's bias folded in: a pixel is covered where every edge value is >= 0.
    for k in 0..3 {
        row[k] += bias[k];
    }
    for y in y0..=y1 {
        let dy = (y - y0) as f32;
        let (iz_row, b1_row, b2_row) = (
            inv_z[0] + inv_z[2] * dy,
            tag1[0] + tag1[2] * dy,
            tag2[0] + tag2[2] * dy,
        );
        let span = covered_span(&row, &step_x, x1 - x0);
        for k in 0..3 {
            row[k] += step_y[k];
        }
        let Some((first, last)) = span else {
            continue;
        };
        let base = y as usize * vis.width + x0 as usize;
        for d in first..last + 1 {
            let dx = d as f32;
            let w = iz_row + inv_z[1] * dx;
            let idx = base + d as usize;
            // Larger inverse depth = nearer; ties keep the first drawn fragment (deterministic order).
            if w > vis.inv_z[idx] {
                let z = 1.0 / w;
                vis.inv_z[idx] = w;
                vis.instance[idx] = instance;
                vis.triangle[idx] = triangle;
                vis.bary[idx] = [(b1_row + tag1[1] * dx) * z, (b2_row + tag2[1] * dx) * z];
            }
        }
    }
}

/// The offsets `d` in `0..=last` from a row's first pixel where every edge value `row[k] + d * step_x[k]` is
/// non-negative, as `(first, last)`; `None` when there are none. Exact integer bounds, so the row covers the same
/// pixels a per-pixel test would.
#[inline]
fn covered_span(row: &[i64; 3], step_x: &[i64; 3], last: i64) -> Option<(i64, i64)> {
    let (mut lo, mut hi) = (0i64, last);
    for k in 0..3 {
        let (e, s) = (row[k], step_x[k]);
        if s > 0 {
            if e < 0 {
                // Smallest d with e + d s >= 0: ceil(-e / s).
                lo = lo.max((-e + s - 1) / s);
            }
        } else if s < 0 {
            if e < 0 {
                return None;
            }
            // Largest d with e + d s >= 0: floor(e / -s).
            hi = hi.min(e / -s);
        } else if e < 0 {
            return None;
        }
    }
    (lo <= hi).then_some((lo, hi))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The span covers exactly the offsets a per-pixel test of the three edge values accepts.
        #[test]
        fn covered_span_equals_the_per_pixel_test(
            row in proptest::array::uniform3(-1_000_000i64..1_000_000),
            step_x in proptest::array::uniform3(-40_000i64..40_000),
            last in 0i64..64,
        ) {
            let covered = |d: i64| (0..3).all(|k| row[k] + d * step_x[k] >= 0);
            let expected: Vec<i64> = (0..=last).filter(|&d| covered(d)).collect();
            let got: Vec<i64> = covered_span(&row, &step_x, last)
                .map(|(a, b)| (a..=b).collect())
                .unwrap_or_default();
            prop_assert_eq!(got, expected);
        }
    }

    #[test]
    fn covered_span_handles_edges_parallel_to_the_row() {
        // A zero step keeps the whole row or none of it.
        assert_eq!(covered_span(&[0, 5, 5], &[0, 1, -1], 3), Some((0, 3)));
        assert_eq!(covered_span(&[-1, 5, 5], &[0, 1, -1], 3), None);
        // Bounds meet in a single pixel.
        assert_eq!(covered_span(&[-3, 3, 0], &[3, -3, 0], 5), Some((1, 1)));
    }
}
