//! A static 3-D k-d tree for nearest-neighbour distances (ADD-S).

use nalgebra::Point3;

/// A balanced k-d tree over a fixed set of 3-D points (any frame, metres), answering nearest-neighbour queries.
#[derive(Debug, Clone)]
pub struct KdTree {
    /// Points reordered so that each subtree is a contiguous slice; the median of a slice is its split point.
    points: Vec<Point3<f64>>,
}

impl KdTree {
    /// Builds the tree over `points` (O(n log^2 n)).
    pub fn new(points: &[Point3<f64>]) -> Self {
        let mut points = points.to_vec();
        build(&mut points, 0);
        Self { points }
    }

    /// Number of points in the tree.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether the tree holds no point.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Euclidean distance from `q` to the nearest point of the tree (infinite for an empty tree).
    pub fn nearest_distance(&self, q: &Point3<f64>) -> f64 {
        let mut best = f64::INFINITY;
        search(&self.points, 0, q, &mut best);
        best.sqrt()
    }
}

fn build(points: &mut [Point3<f64>], depth: usize) {
    if points.len() <= 1 {
        return;
    }
    let axis = depth % 3;
    let mid = points.len() / 2;
    points.select_nth_unstable_by(mid, |a, b| a[axis].total_cmp(&b[axis]));
    let (left, right) = points.split_at_mut(mid);
    build(left, depth + 1);
    build(&mut right[1..], depth + 1);
}

/// Updates `best` (squared distance) with the nearest point of `points` to `q`.
fn search(points: &[Point3<f64>], depth: usize, q: &Point3<f64>, best: &mut f64) {
    if points.is_empty() {
        return;
    }
    let axis = depth % 3;
    let mid = points.len() / 2;
    let p = &points[mid];
    let d2 = (p - q).norm_squared();
    if d2 < *best {
        *best = d2;
    }
    let diff = q[axis] - p[axis];
    let (near, far) = if diff < 0.0 {
        (&points[..mid], &points[mid + 1..])
    } else {
        (&points[mid + 1..], &points[..mid])
    };
    search(near, depth + 1, q, best);
    if diff * diff < *best {
        search(far, depth + 1, q, best);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn hand_computed_nearest() {
        let pts = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 2.0, 0.0),
        ];
        let tree = KdTree::new(&pts);
        assert_eq!(tree.len(), 3);
        assert!((tree.nearest_distance(&Point3::new(0.9, 0.0, 0.0)) - 0.1).abs() < 1e-12);
        assert!((tree.nearest_distance(&Point3::new(0.0, 1.5, 0.0)) - 0.5).abs() < 1e-12);
        assert!(
            KdTree::new(&[])
                .nearest_distance(&Point3::origin())
                .is_infinite()
        );
    }

    proptest! {
        #[test]
        fn matches_brute_force(
            pts in prop::collection::vec((-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0), 1..200),
            q in (-1.5f64..1.5, -1.5f64..1.5, -1.5f64..1.5),
        ) {
            let pts: Vec<Point3<f64>> = pts.into_iter().map(|(x, y, z)| Point3::new(x, y, z)).collect();
            let q = Point3::new(q.0, q.1, q.2);
            let brute = pts.iter().map(|p| (p - q).norm()).fold(f64::INFINITY, f64::min);
            prop_assert!((KdTree::new(&pts).nearest_distance(&q) - brute).abs() < 1e-12);
        }
    }
}
