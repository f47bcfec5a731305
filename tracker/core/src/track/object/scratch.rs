//! The buffers one tick of an object fills and reads: its ROI render, the model view extracted from it, the
//! depth rendered for the refinement, and the event and intensity matches. Rebuilt at every tick and never saved;
//! they are kept between ticks only so that steady-state ticks do not allocate.

use crate::recon::DepthImage;
use crate::refine::{EventEdges, IntensityEdges, ModelView};
use crate::track::config::TrackerConfig;
use scene::render::RenderTarget;

/// One object's per-tick buffers.
#[derive(Debug)]
pub(crate) struct TickScratch {
    /// The ROI render at the predicted poses of all objects.
    pub target: RenderTarget,
    /// Surface and contour points of the model in `target`.
    pub view: ModelView,
    /// `D_t`: the carried depth rendered in this tick's ROI.
    pub depth_now: DepthImage,
    /// A late frame's depth around the object where it was at the exposure, in that ROI's camera.
    pub late_depth: DepthImage,
    /// The event term's bins and matches.
    pub edges: EventEdges,
    /// The intensity term's matches.
    pub intensity_edges: IntensityEdges,
    /// Per surface sample, measured minus model depth, metres ([`super::range_align::aligned_range`]).
    pub range_offsets: Vec<f64>,
}

impl TickScratch {
    /// Buffers sized for `config`'s ROI and point counts.
    pub fn new(config: &TrackerConfig) -> Self {
        let n = config.roi.roi_size as usize;
        Self {
            target: RenderTarget::with_capacity(config.roi.roi_size, config.roi.roi_size),
            view: ModelView::with_capacity(
                config.correspond.max_surface_points,
                config.correspond.max_contour_points,
            ),
            depth_now: DepthImage {
                width: config.roi.roi_size,
                height: config.roi.roi_size,
                z: Vec::with_capacity(n * n),
            },
            late_depth: DepthImage {
                width: config.roi.roi_size,
                height: config.roi.roi_size,
                z: Vec::with_capacity(n * n),
            },
            edges: EventEdges::default(),
            intensity_edges: IntensityEdges::default(),
            range_offsets: Vec::with_capacity(config.correspond.max_surface_points),
        }
    }
}
