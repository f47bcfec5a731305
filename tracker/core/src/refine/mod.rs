//! Render-and-compare pose refinement (paper section 3.2, as Gauss-Newton / Levenberg-Marquardt): residual terms
//! ("modalities") accumulate into 6x6 normal equations over a pose increment; the solver bounds every step the way
//! the paper's refiner is bounded (about 20 degrees and half a diameter).
//!
//! The increment is parametrised about the object's centre `c` (camera frame): `xi = [v; w]` moves a point `P` of
//! the object to `R(w) (P - c) + c + v`. A residual `r(P)` with gradient `g = dr/dP` then has the Jacobian
//! `[g; (P - c) x g]`.

//!
//! Pieces: [`NormalEquations`] and the bounded step ([`solve_step`], [`apply_step`]); the [`Modality`]
//! interface and its three implementations, [`DepthModality`] (point-to-plane against `D_t`),
//! [`EventModality`] (the outline against the event window) and [`IntensityModality`] (the outline against
//! edges of `I_t`); and the [`Optimiser`] that iterates over a set of them with a [`StartPrior`]. Adding a
//! residual term means adding one file with a type that implements [`Modality`].

mod contour;
mod depth_term;
mod event_term;
mod intensity_term;
mod modality;
mod model_view;
mod normal_equations;
mod optimiser;
mod step;

pub(crate) use contour::{ContourResiduals, normal_offset};
pub use depth_term::{DepthModality, DepthTerm, DepthTermStats};
pub use event_term::{
    BinnedWindow, EventEdges, EventModality, EventTerm, EventTermKind, EventTermStats,
};
pub use intensity_term::{IntensityEdges, IntensityModality, IntensityTerm};
pub use modality::Modality;
pub use model_view::{ContourPoint, ModelView, SurfacePoint};
pub use normal_equations::NormalEquations;
pub use optimiser::{Optimiser, StartPrior};
pub use step::{StepBounds, apply_step, clamp_step, solve_step};
