//! The dual-modal reconstruction (paper section 3.1, training-free): intensity `I_t` from events and depth `D_t`
//! carried from the last depth exposure to any time `t` by the scene's motion.

mod depth;
mod intensity;
mod neighbourhood;

pub use depth::{CarriedDepth, DepthImage, DepthRig, MAX_CARRIED_POINTS};
pub use intensity::{EventSurface, IntensityFilterConfig, SurfaceLog};
pub use neighbourhood::{MIN_MOTION_POINTS, MOTION_TOLERANCE_M, MovingNeighbourhood};
