//! The interface every residual term of the refinement implements.

use super::model_view::ModelView;
use super::normal_equations::NormalEquations;
use nalgebra::{Isometry3, Vector3};

/// A residual term of the refinement (a "modality"): it matches the model's view to its own measurement at a
/// pose (depth image, event window, reconstructed intensity) and linearises its residuals there into normal
/// equations over the pose increment about the object's centre.
///
/// A modality is built for one refinement from the tick's measurement and the buffers it reuses; the
/// [`super::Optimiser`] drives it. Adding a residual term means adding one type that implements this trait.
pub trait Modality {
    /// Short name, for diagnostics (`depth`, `events`, `intensity`).
    fn name(&self) -> &'static str;

    /// Scale of this term's equations in the sum of all terms (unitless).
    fn weight(&self) -> f64;

    /// Whether the term takes part in this refinement. One without a measurement or switched off takes none:
    /// it is neither matched nor linearised.
    fn is_active(&self) -> bool;

    /// Finds what each model point or contour point of `view` corresponds to in the measurement at `pose`
    /// (`T_cam_obj`). The optimiser calls it at the first iteration and at every second one after, since matching
    /// costs more than linearising; a term that matches by projection at every accumulation does nothing here.
    fn correspond(&mut self, view: &ModelView, pose: &Isometry3<f64>);

    /// Adds this term's residuals at `pose`, unweighted, to `ne`, linearised about the object's centre
    /// `center_obj` (object frame, metres).
    fn accumulate(
        &mut self,
        view: &ModelView,
        pose: &Isometry3<f64>,
        center_obj: &Vector3<f64>,
        ne: &mut NormalEquations,
    );
}
