//! Driving a tracker tick by tick: the [`TickDriver`] (trigger timeline and event gate) that both the real-time
//! runtime and the offline driver run on, and the offline driver over a recording.

mod driver;
mod offline;
mod pulse_hold;

pub use driver::TickDriver;
pub use offline::{OfflineStats, OfflineTiming, track_recording, track_recording_timed};
pub use pulse_hold::{MAX_OVERDUE_EVENTS, PulseHold};
