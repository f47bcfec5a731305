//! The 6x6 normal equations of one iteration, accumulated residual by residual.

use nalgebra::{Matrix6, Vector3, Vector6};

/// Accumulated weighted least-squares normal equations `H xi = -g` of one iteration.
///
/// `H` is symmetric, so only its upper triangle (row <= column) is accumulated; [`Self::hessian`] gives the whole
/// matrix.
#[derive(Debug, Clone, Copy)]
pub struct NormalEquations {
    /// Upper triangle (row <= column) of `sum w J J^T`; the entries below the diagonal stay zero.
    pub h: Matrix6<f64>,
    /// `sum w J r`.
    pub g: Vector6<f64>,
    /// `sum w r^2`.
    pub cost: f64,
    /// Residuals accumulated.
    pub count: usize,
}

impl Default for NormalEquations {
    fn default() -> Self {
        Self {
            h: Matrix6::zeros(),
            g: Vector6::zeros(),
            cost: 0.0,
            count: 0,
        }
    }
}

impl NormalEquations {
    /// Adds residual `r` with weight `w`, gradient `grad = dr/dP` at object point `p` about centre `c`.
    #[inline(always)]
    pub fn add_point(&mut self, grad: &Vector3<f64>, p_minus_c: &Vector3<f64>, r: f64, w: f64) {
        let rot = p_minus_c.cross(grad);
        let j = [grad.x, grad.y, grad.z, rot.x, rot.y, rot.z];
        let wj = j.map(|x| w * x);
        for (c, jc) in j.into_iter().enumerate() {
            for (r, wjr) in wj.into_iter().enumerate().take(c + 1) {
                self.h[(r, c)] += wjr * jc;
            }
        }
        let wr = w * r;
        for (g, jr) in self.g.iter_mut().zip(j) {
            *g += wr * jr;
        }
        self.cost += w * r * r;
        self.count += 1;
    }

    /// The whole symmetric `sum w J J^T`: the accumulated upper triangle mirrored below the diagonal.
    pub fn hessian(&self) -> Matrix6<f64> {
        let mut h = self.h;
        for c in 0..6 {
            for r in c + 1..6 {
                h[(r, c)] = h[(c, r)];
            }
        }
        h
    }

    /// Adds another set of equations scaled by `weight`.
    pub fn add_scaled(&mut self, other: &NormalEquations, weight: f64) {
        self.h += other.h * weight;
        self.g += other.g * weight;
        self.cost += other.cost * weight;
        self.count += other.count;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    proptest::proptest! {
        #[test]
        fn hessian_is_the_whole_weighted_sum_of_jacobian_products(
            points in proptest::collection::vec(
                (proptest::array::uniform3(-1.0f64..1.0), proptest::array::uniform3(-0.2f64..0.2), 0.01f64..10.0),
                1..40,
            ),
        ) {
            let mut ne = NormalEquations::default();
            let mut full = Matrix6::zeros();
            for (grad, arm, w) in &points {
                let grad = Vector3::from(*grad);
                let arm = Vector3::from(*arm);
                ne.add_point(&grad, &arm, 0.5, *w);
                let rot = arm.cross(&grad);
                let j = Vector6::new(grad.x, grad.y, grad.z, rot.x, rot.y, rot.z);
                full += j * j.transpose() * *w;
            }
            let h = ne.hessian();
            proptest::prop_assert_eq!(h, h.transpose());
            proptest::prop_assert!((h - full).abs().max() <= 1e-12 * full.abs().max().max(1.0));
            proptest::prop_assert_eq!(ne.count, points.len());
        }
    }
}
