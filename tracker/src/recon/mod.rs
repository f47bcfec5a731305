//! The dual-modal reconstruction (paper section 3.1, training-free): intensity `I_t` from events and depth `D_t`
//! carried from the last depth exposure to any time `t` by the scene's motion.

mod depth;
mod intensity;

pub use depth::{CarriedDepth, DepthImage, DepthRig};
pub use intensity::{EventSurface, IntensityFilterConfig};
