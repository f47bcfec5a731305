//! Mesh measurements: bounding box, area, diameter and area-weighted surface sampling.

use nalgebra::{Point3, Vector3};
use rand::Rng;

/// An axis-aligned bounding box, object frame, metres. Invariant: `min <= max` component-wise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Minimum corner.
    pub min: Point3<f64>,
    /// Maximum corner.
    pub max: Point3<f64>,
}

impl Aabb {
    /// Bounding box of a non-empty point set (an empty set gives a degenerate box at the origin).
    pub fn of_points(points: &[Point3<f32>]) -> Self {
        let Some(first) = points.first() else {
            return Self {
                min: Point3::origin(),
                max: Point3::origin(),
            };
        };
        let first = first.cast::<f64>();
        let (min, max) = points.iter().fold((first, first), |(lo, hi), p| {
            let p = p.cast::<f64>();
            (lo.inf(&p), hi.sup(&p))
        });
        Self { min, max }
    }
    /// Edge lengths, metres.
    pub fn size(&self) -> Vector3<f64> {
        self.max - self.min
    }
    /// Centre point, metres.
    pub fn center(&self) -> Point3<f64> {
        nalgebra::center(&self.min, &self.max)
    }
}

/// A point sampled on a mesh surface, object frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// Position, metres.
    pub position: Point3<f64>,
    /// Unit geometric normal of the triangle it lies on (orientation follows the triangle's winding).
    pub normal: Vector3<f64>,
    /// Index of that triangle.
    pub triangle: u32,
}

fn triangle_vertices(positions: &[Point3<f32>], t: &[u32; 3]) -> [Point3<f64>; 3] {
    t.map(|i| positions[i as usize].cast::<f64>())
}

fn triangle_area(v: &[Point3<f64>; 3]) -> f64 {
    0.5 * (v[1] - v[0]).cross(&(v[2] - v[0])).norm()
}

/// Total area of the triangles, square metres. Indices must be in range.
pub(crate) fn total_area(positions: &[Point3<f32>], triangles: &[[u32; 3]]) -> f64 {
    triangles
        .iter()
        .map(|t| triangle_area(&triangle_vertices(positions, t)))
        .sum()
}

/// Largest distance between two points, metres: exact, by branch and bound so that it is fast on large meshes.
///
/// With `c` the bounding-box centre, `|p - q| <= |p - c| + |q - c|`; points are visited in decreasing distance from
/// `c`, and a pair (or every later pair) is skipped as soon as that bound cannot beat the best distance found so far.
pub(crate) fn diameter(points: &[Point3<f32>]) -> f64 {
    let c = Aabb::of_points(points).center();
    let mut pts: Vec<([f64; 3], f64)> = points
        .iter()
        .map(|p| {
            let q = [f64::from(p.x), f64::from(p.y), f64::from(p.z)];
            let r = ((q[0] - c.x).powi(2) + (q[1] - c.y).powi(2) + (q[2] - c.z).powi(2)).sqrt();
            (q, r)
        })
        .collect();
    pts.sort_by(|a, b| {
        b.1.total_cmp(&a.1)
            .then(a.0[0].total_cmp(&b.0[0]))
            .then(a.0[1].total_cmp(&b.0[1]))
    });
    pts.dedup_by(|a, b| a.0 == b.0);
    let mut best_sq = 0.0f64;
    let mut best = 0.0f64;
    for (i, (p, rp)) in pts.iter().enumerate() {
        if pts.first().is_some_and(|first| rp + first.1 <= best) {
            break;
        }
        for (q, rq) in &pts[i + 1..] {
            if rp + rq <= best {
                break;
            }
            let d = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2);
            if d > best_sq {
                best_sq = d;
                best = d.sqrt();
            }
        }
    }
    best
}

/// Samples `count` points uniformly over the surface of `triangles` (area-weighted over triangles, uniform within
/// each), using `rng` so that callers control determinism. Indices must be in range and `triangles` not empty.
pub(crate) fn sample_surface<R: Rng + ?Sized>(
    positions: &[Point3<f32>],
    triangles: &[[u32; 3]],
    count: usize,
    rng: &mut R,
) -> Vec<SurfacePoint> {
    let mut cumulative = Vec::with_capacity(triangles.len());
    let mut acc = 0.0;
    for t in triangles {
        acc += triangle_area(&triangle_vertices(positions, t));
        cumulative.push(acc);
    }
    let total = acc;
    (0..count)
        .map(|_| {
            let target = rng.random::<f64>() * total;
            // First triangle whose cumulative area exceeds the target; zero-area triangles are never chosen.
            let idx = cumulative
                .partition_point(|&c| c <= target)
                .min(cumulative.len() - 1);
            let v = triangle_vertices(positions, &triangles[idx]);
            let (r1, r2) = (rng.random::<f64>(), rng.random::<f64>());
            let s = r1.sqrt();
            let (b0, b1, b2) = (1.0 - s, s * (1.0 - r2), s * r2);
            let position = Point3::from(v[0].coords * b0 + v[1].coords * b1 + v[2].coords * b2);
            let n = (v[1] - v[0]).cross(&(v[2] - v[0]));
            let normal = if n.norm() > 0.0 {
                n.normalize()
            } else {
                Vector3::z()
            };
            SurfacePoint {
                position,
                normal,
                triangle: idx as u32,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn brute_diameter(points: &[Point3<f32>]) -> f64 {
        let mut best: f64 = 0.0;
        for p in points {
            for q in points {
                best = best.max((p.cast::<f64>() - q.cast::<f64>()).norm());
            }
        }
        best
    }

    proptest! {
        #[test]
        fn pruned_diameter_equals_brute_force(
            pts in proptest::collection::vec(proptest::array::uniform3(-1.0f32..1.0), 2..80),
            stretch in 0.1f32..5.0,
        ) {
            let points: Vec<Point3<f32>> = pts.iter().map(|p| Point3::new(p[0] * stretch, p[1], p[2])).collect();
            let fast = diameter(&points);
            let slow = brute_diameter(&points);
            prop_assert!((fast - slow).abs() < 1e-9, "{fast} vs {slow}");
        }
    }

    #[test]
    fn aabb_of_points() {
        let b = Aabb::of_points(&[Point3::new(1.0, -2.0, 0.5), Point3::new(-1.0, 3.0, 0.0)]);
        assert_eq!(b.min, Point3::new(-1.0, -2.0, 0.0));
        assert_eq!(b.size(), Vector3::new(2.0, 5.0, 0.5));
    }
}
