//! Error quadrics (Garland and Heckbert): the weighted sum of squared distances from a point to a set of planes,
//! kept as one symmetric 4x4 form and a total weight, so that sets merge by addition.

use nalgebra::{Matrix3, Vector3};

/// `q(v) = vᵀ A v + 2 bᵀ v + c`: the weighted sum of squared distances from `v` to the planes added so far, and
/// the sum of their weights.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct Quadric {
    /// Upper triangle of the symmetric `A`: xx, xy, xz, yy, yz, zz.
    a: [f64; 6],
    b: [f64; 3],
    c: f64,
    weight: f64,
}

impl Quadric {
    /// `weight` times the squared distance to the plane through `point` with unit normal `normal`.
    pub(super) fn plane(normal: Vector3<f64>, point: Vector3<f64>, weight: f64) -> Self {
        let n = normal;
        let d = -n.dot(&point);
        let w = weight;
        Self {
            a: [
                w * n.x * n.x,
                w * n.x * n.y,
                w * n.x * n.z,
                w * n.y * n.y,
                w * n.y * n.z,
                w * n.z * n.z,
            ],
            b: [w * n.x * d, w * n.y * d, w * n.z * d],
            c: w * d * d,
            weight: w,
        }
    }

    /// Adds the planes of `other`.
    pub(super) fn add(&mut self, other: &Self) {
        for (s, o) in self.a.iter_mut().zip(other.a) {
            *s += o;
        }
        for (s, o) in self.b.iter_mut().zip(other.b) {
            *s += o;
        }
        self.c += other.c;
        self.weight += other.weight;
    }

    /// The weighted mean squared distance at `v`, square metres (never negative; 0 without planes).
    pub(super) fn mean_error(&self, v: &Vector3<f64>) -> f64 {
        if self.weight > 0.0 {
            self.error(v) / self.weight
        } else {
            0.0
        }
    }

    /// The weighted summed squared distance at `v` (never negative).
    fn error(&self, v: &Vector3<f64>) -> f64 {
        let [xx, xy, xz, yy, yz, zz] = self.a;
        let av = Vector3::new(
            xx * v.x + xy * v.y + xz * v.z,
            xy * v.x + yy * v.y + yz * v.z,
            xz * v.x + yz * v.y + zz * v.z,
        );
        let b = Vector3::from(self.b);
        (v.dot(&av) + 2.0 * b.dot(v) + self.c).max(0.0)
    }

    /// The point of least error, when the planes pin one down (their normals span all three directions well
    /// enough that the solution is not thrown far off by rounding).
    pub(super) fn minimiser(&self) -> Option<Vector3<f64>> {
        let [xx, xy, xz, yy, yz, zz] = self.a;
        let a = Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz);
        let scale = (xx + yy + zz) / 3.0;
        if scale.is_nan() || scale <= 0.0 || a.determinant().abs() < 1e-9 * scale * scale * scale {
            return None;
        }
        let v = a.try_inverse()? * -Vector3::from(self.b);
        v.iter().all(|c| c.is_finite()).then_some(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_is_the_summed_squared_plane_distance() {
        let mut q = Quadric::plane(Vector3::z(), Vector3::new(0.0, 0.0, 1.0), 1.0);
        q.add(&Quadric::plane(
            Vector3::x(),
            Vector3::new(2.0, 0.0, 0.0),
            3.0,
        ));
        let v = Vector3::new(0.5, 7.0, -1.0);
        assert!((q.error(&v) - (2.0f64.powi(2) + 3.0 * 1.5f64.powi(2))).abs() < 1e-12);
        assert!((q.mean_error(&v) - q.error(&v) / 4.0).abs() < 1e-12);
        assert_eq!(Quadric::default().mean_error(&v), 0.0);
    }

    #[test]
    fn three_planes_meet_in_their_minimiser_and_two_do_not_pin_a_point() {
        let corner = Vector3::new(0.1, -0.2, 0.3);
        let mut q = Quadric::plane(Vector3::x(), corner, 1.0);
        q.add(&Quadric::plane(Vector3::y(), corner, 2.0));
        assert_eq!(q.minimiser(), None);
        q.add(&Quadric::plane(
            Vector3::new(1.0, 1.0, 1.0).normalize(),
            corner,
            0.5,
        ));
        let m = q.minimiser().expect("three independent planes");
        assert!((m - corner).norm() < 1e-9, "{m:?}");
        assert!(q.error(&m) < 1e-18);
    }
}
