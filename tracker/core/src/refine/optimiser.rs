//! The refinement's Gauss-Newton / Levenberg-Marquardt loop over a set of modalities, with a prior that holds
//! directions no measurement constrains where the refinement started.

use super::modality::Modality;
use super::model_view::ModelView;
use super::normal_equations::NormalEquations;
use super::step::{StepBounds, apply_step, solve_step};
use nalgebra::{Isometry3, Vector3, Vector6};

/// Inverse variances of the prior towards the refinement's start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StartPrior {
    /// Translation, 1/m^2.
    pub translation: f64,
    /// Rotation, 1/rad^2.
    pub rotation: f64,
    /// An extra weight on the translation along one unit direction (camera frame), 1/m^2, and that direction
    /// (zero weight: none).
    pub along: (f64, Vector3<f64>),
}

impl StartPrior {
    /// The prior of standard deviations `translation_m` (metres) and `rotation_rad` (radians).
    pub fn from_sigmas(translation_m: f64, rotation_rad: f64) -> Self {
        Self {
            translation: 1.0 / (translation_m * translation_m),
            rotation: 1.0 / rotation_rad.powi(2),
            along: (0.0, Vector3::zeros()),
        }
    }

    /// This prior for a step that extrapolates only `span` (0 < span <= 1) of the time the prior's standard
    /// deviations are given for: the motion model's uncertainty grows with the time it extrapolates, so the
    /// variances shrink in proportion (spans below 5 % count as 5 %).
    pub fn spread(self, span: f64) -> Self {
        let f = 1.0 / span.clamp(0.05, 1.0);
        Self {
            translation: self.translation * f,
            rotation: self.rotation * f,
            along: (self.along.0 * f, self.along.1),
        }
    }

    /// This prior with a standard deviation of `sigma_m` metres on the translation along `direction` (camera
    /// frame) on top of the isotropic one; unchanged for a zero or non-finite direction.
    pub fn with_along(self, direction: &Vector3<f64>, sigma_m: f64) -> Self {
        match direction.try_normalize(1e-12) {
            Some(l) if l.iter().all(|v| v.is_finite()) => Self {
                along: (1.0 / (sigma_m * sigma_m), l),
                ..self
            },
            _ => self,
        }
    }

    /// Adds the prior to `ne`: `offset` is the increment accumulated since the start.
    pub fn add_to(&self, ne: &mut NormalEquations, offset: &Vector6<f64>) {
        for k in 0..6 {
            let w = if k < 3 {
                self.translation
            } else {
                self.rotation
            };
            ne.h[(k, k)] += w;
            ne.g[k] += w * offset[k];
        }
        let (w, l) = self.along;
        if w > 0.0 {
            let along = l.dot(&offset.fixed_rows::<3>(0));
            // Upper triangle only, as the equations hold it.
            for i in 0..3 {
                for j in i..3 {
                    ne.h[(i, j)] += w * l[i] * l[j];
                }
                ne.g[i] += w * l[i] * along;
            }
        }
    }
}

/// How the refinement iterates: at most `iterations` bounded, damped steps, each over the weighted sum of the
/// modalities' equations plus the [`StartPrior`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Optimiser {
    /// Iterations at most.
    pub iterations: u32,
    /// Levenberg-Marquardt damping, relative to the diagonal.
    pub damping: f64,
    /// Largest step.
    pub bounds: StepBounds,
    /// Prior towards the start.
    pub prior: StartPrior,
    /// Stop once a step moves less than this (translation metres, rotation radians); `None` runs every iteration.
    pub converged_below: Option<(f64, f64)>,
}

impl Optimiser {
    /// Refines `start` (`T_cam_obj`) over the active `modalities`, summed in the order given, about the object's centre
    /// `center_obj` (object frame). Stops early when the equations cannot be solved (too few residuals) or a step
    /// falls below [`Self::converged_below`].
    pub fn run(
        &self,
        modalities: &mut [&mut dyn Modality],
        view: &ModelView,
        center_obj: &Vector3<f64>,
        start: Isometry3<f64>,
    ) -> Isometry3<f64> {
        let mut pose = start;
        let mut offset = Vector6::zeros();
        for it in 0..self.iterations {
            let mut ne = NormalEquations::default();
            for m in modalities.iter_mut().filter(|m| m.is_active()) {
                if it % 2 == 0 {
                    m.correspond(view, &pose);
                }
                let mut e = NormalEquations::default();
                m.accumulate(view, &pose, center_obj, &mut e);
                ne.add_scaled(&e, m.weight());
            }
            self.prior.add_to(&mut ne, &offset);
            let Some(step) = solve_step(&ne, self.damping, &self.bounds) else {
                break;
            };
            offset += step;
            pose = apply_step(&pose, center_obj, &step);
            if let Some((t_min, r_min)) = self.converged_below {
                let (t, r) = (
                    step.fixed_rows::<3>(0).norm(),
                    step.fixed_rows::<3>(3).norm(),
                );
                if t < t_min && r < r_min {
                    break;
                }
            }
        }
        pose
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn equations_with(prior: &StartPrior, offset: &Vector6<f64>) -> NormalEquations {
        let mut ne = NormalEquations::default();
        prior.add_to(&mut ne, offset);
        ne
    }

    #[test]
    fn a_prior_spread_over_a_quarter_period_weighs_four_times() {
        let prior =
            StartPrior::from_sigmas(0.01, 0.05).with_along(&Vector3::new(0.0, 0.0, 2.0), 0.002);
        let spread = prior.spread(0.25);
        assert!((spread.translation / prior.translation - 4.0).abs() < 1e-12);
        assert!((spread.rotation / prior.rotation - 4.0).abs() < 1e-12);
        assert!((spread.along.0 / prior.along.0 - 4.0).abs() < 1e-12);
        assert_eq!(prior.spread(1.0), prior);
        assert_eq!(prior.spread(0.0), prior.spread(0.05));
    }

    #[test]
    fn no_line_of_sight_prior_without_a_direction() {
        let base = StartPrior::from_sigmas(0.01, 0.05);
        assert_eq!(base.with_along(&Vector3::zeros(), 0.001), base);
        assert_eq!(
            base.with_along(&Vector3::new(f64::NAN, 0.0, 1.0), 0.001),
            base
        );
    }

    #[test]
    fn the_line_of_sight_prior_holds_only_its_direction() {
        let l = Vector3::new(1.0, 0.0, 1.0).normalize();
        let base = StartPrior::from_sigmas(0.01, 0.05);
        let prior = base.with_along(&(l * 0.7), 0.001);
        let offset = Vector6::new(0.003, -0.002, 0.001, 0.01, 0.0, 0.0);
        let h = equations_with(&prior, &offset).hessian();
        let g = equations_with(&prior, &offset).g;
        let h0 = equations_with(&base, &offset).hessian();
        let g0 = equations_with(&base, &offset).g;
        let w = 1e6;
        let along = l.dot(&offset.fixed_rows::<3>(0));
        for i in 0..3 {
            for j in 0..3 {
                assert!(
                    (h[(i, j)] - h0[(i, j)] - w * l[i] * l[j]).abs() < 1e-6,
                    "h[{i},{j}]"
                );
            }
            assert!((g[i] - g0[i] - w * l[i] * along).abs() < 1e-9);
        }
        // A translation across the line of sight is weighed as without it.
        let across = Vector3::new(0.0, 1.0, 0.0);
        assert!(
            (across.dot(&(h.fixed_view::<3, 3>(0, 0) * across)) - base.translation).abs() < 1e-6
        );
        assert_eq!(h.fixed_view::<3, 3>(3, 3), h0.fixed_view::<3, 3>(3, 3));
    }
}
