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
}

impl StartPrior {
    /// The prior of standard deviations `translation_m` (metres) and `rotation_rad` (radians).
    pub fn from_sigmas(translation_m: f64, rotation_rad: f64) -> Self {
        Self {
            translation: 1.0 / (translation_m * translation_m),
            rotation: 1.0 / rotation_rad.powi(2),
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
