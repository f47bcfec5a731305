//! The benchmark: pose-tracking methods behind one trait ([`Method`]), run over recordings with only the first pose
//! given and no re-initialisation (the paper's protocol), evaluated per sequence and aggregated per object. The
//! report (`results.md`, `results.json`) is [`crate::report`].
//!
//! - [`method`]: the [`Method`] interface; [`tracker_method`]: the tracker and its baselines as methods;
//!   [`harness_checks`]: the harness's own `static` and `gt-noise`; [`spec`]: method names as `--methods` gives
//!   them.
//! - [`run`]: one method over one sequence; [`results`]: what a run produces.

pub mod harness_checks;
pub mod method;
pub mod results;
pub mod run;
pub mod spec;
pub mod tracker_method;

pub use harness_checks::{GtNoiseMethod, StaticMethod};
pub use method::{Method, MethodInput};
pub use results::{MethodResults, SequenceResult, SuiteSequence};
pub use run::{open_sequence, run_sequence};
pub use spec::{expand_seeds, method_from_spec, method_from_spec_timed, method_from_spec_with};
pub use tracker_method::{InitNoise, TrackerMethod};
