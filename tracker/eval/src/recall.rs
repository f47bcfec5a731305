//! Scores: AUC of ADD / ADD-S and the BOP average recalls (VSD, MSSD, MSPD, AR).

/// Maximum threshold of an ADD / ADD-S AUC curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AucLimit {
    /// Thresholds from 0 to 0.1 x object diameter (the paper's convention, as FoundationPose).
    Diameter,
    /// Thresholds from 0 to 0.1 m (the YCB-Video convention).
    Metres,
}

impl AucLimit {
    /// The largest threshold, metres, for an object of `diameter` metres.
    pub fn max_threshold(self, diameter: f64) -> f64 {
        match self {
            AucLimit::Diameter => 0.1 * diameter,
            AucLimit::Metres => 0.1,
        }
    }

    /// How reports name the convention: `0.1 x diameter` or `0.1 m`.
    pub fn describe(self) -> &'static str {
        match self {
            AucLimit::Diameter => "0.1 x diameter",
            AucLimit::Metres => "0.1 m",
        }
    }
}

/// Number of threshold intervals of the AUC curve (the YCB-Video code's 1 mm step over 0.1 m: 100 intervals).
pub const AUC_STEPS: usize = 100;

/// Area under the accuracy-threshold curve, percent (0-100): accuracy(x) = fraction of `errors` (metres) `<= x`
/// at `AUC_STEPS + 1` evenly spaced thresholds from 0 to `max_threshold`, integrated with the trapezoid rule and
/// divided by `max_threshold`. Non-finite errors (no prediction) count as failures. Empty input gives 0.
pub fn auc(errors: &[f64], max_threshold: f64) -> f64 {
    if errors.is_empty() || max_threshold <= 0.0 {
        return 0.0;
    }
    let mut sorted: Vec<f64> = errors
        .iter()
        .map(|e| if e.is_nan() { f64::INFINITY } else { *e })
        .collect();
    sorted.sort_by(f64::total_cmp);
    // Trapezoid rule in integer counts (exact): sum over intervals of (count_i + count_{i+1}).
    let count = |i: usize| {
        sorted.partition_point(|e| *e <= max_threshold * i as f64 / AUC_STEPS as f64) as u64
    };
    let mut total = 0u64;
    let mut prev = count(0);
    for i in 1..=AUC_STEPS {
        let c = count(i);
        total += prev + c;
        prev = c;
    }
    100.0 * total as f64 / (2 * AUC_STEPS * sorted.len()) as f64
}

/// BOP 2019 correctness thresholds shared by VSD (on its error) and MSSD (times the diameter): 0.05 to 0.5 in
/// steps of 0.05.
pub fn bop_fraction_thresholds() -> [f64; 10] {
    std::array::from_fn(|i| 0.05 * (i + 1) as f64)
}

/// VSD misalignment tolerances tau as fractions of the object diameter: 0.05 to 0.5 in steps of 0.05.
pub fn vsd_taus() -> [f64; 10] {
    bop_fraction_thresholds()
}

/// VSD's visibility tolerance delta, metres (15 mm).
pub const VSD_DELTA: f64 = 0.015;

/// MSPD correctness thresholds, pixels at a 640-pixel-wide image: 5 to 50 in steps of 5.
pub fn mspd_thresholds_px() -> [f64; 10] {
    std::array::from_fn(|i| 5.0 * (i + 1) as f64)
}

/// Fraction of `thresholds` that `error` is strictly below (BOP: a pose is correct when `e < th`).
pub fn recall_over(error: f64, thresholds: &[f64]) -> f64 {
    if thresholds.is_empty() {
        return 0.0;
    }
    thresholds.iter().filter(|th| error < **th).count() as f64 / thresholds.len() as f64
}

/// VSD recall of one pose: the fraction of (tau, threshold) pairs, over [`vsd_taus`] x [`bop_fraction_thresholds`],
/// whose VSD error (`errors_per_tau[i]` for tau i, unitless 0-1) is below the threshold.
pub fn vsd_recall(errors_per_tau: &[f64]) -> f64 {
    let ths = bop_fraction_thresholds();
    if errors_per_tau.is_empty() {
        return 0.0;
    }
    let hits: usize = errors_per_tau
        .iter()
        .map(|e| ths.iter().filter(|th| e < th).count())
        .sum();
    hits as f64 / (errors_per_tau.len() * ths.len()) as f64
}

/// MSSD recall of one pose: fraction of thresholds `0.05..0.5 x diameter` that `mssd` (metres) is below.
pub fn mssd_recall(mssd: f64, diameter: f64) -> f64 {
    let ths = bop_fraction_thresholds().map(|f| f * diameter);
    recall_over(mssd, &ths)
}

/// MSPD recall of one pose: the error (pixels of an image `image_width` wide) is scaled by `640 / image_width`
/// and compared with 5..50 px.
pub fn mspd_recall(mspd_px: f64, image_width: u32) -> f64 {
    let scaled = mspd_px * 640.0 / image_width as f64;
    recall_over(scaled, &mspd_thresholds_px())
}

/// Average recall of one pose: the mean of the VSD, MSSD and MSPD recalls (BOP 2019 AR), 0-1.
pub fn average_recall(vsd: f64, mssd: f64, mspd: f64) -> f64 {
    (vsd + mssd + mspd) / 3.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auc_of_zero_errors_is_full_and_of_huge_errors_is_zero() {
        assert!((auc(&[0.0, 0.0], 0.01) - 100.0).abs() < 1e-9);
        assert_eq!(auc(&[1.0, f64::INFINITY, f64::NAN], 0.01), 0.0);
        assert_eq!(auc(&[], 0.01), 0.0);
    }

    #[test]
    fn auc_hand_computed() {
        // One error between thresholds 50 and 51 (of 100): accuracy 0 up to 50, 1 from 51 on; the trapezoid over
        // the step interval adds half a step -> 49.5 of 100 steps.
        assert!((auc(&[0.00505], 0.01) - 49.5).abs() < 1e-9);
        // Half the frames perfect, half failed -> 50.
        assert!((auc(&[0.0, 1.0], 0.01) - 50.0).abs() < 1e-9);
        // One of two frames perfect, the other between thresholds 25 and 26: 25 steps at 0.5, one at 0.75, 74 at 1.
        assert!((auc(&[0.0, 0.00255], 0.01) - 87.25).abs() < 1e-9);
    }

    #[test]
    fn auc_limits() {
        assert!((AucLimit::Diameter.max_threshold(0.2) - 0.02).abs() < 1e-15);
        assert_eq!(AucLimit::Metres.max_threshold(0.2), 0.1);
    }

    #[test]
    fn recalls_hand_computed() {
        // 0.12 x diameter is below 0.15..0.5: 8 of 10 thresholds.
        assert!((mssd_recall(0.012, 0.1) - 0.8).abs() < 1e-12);
        assert_eq!(mssd_recall(0.0, 0.1), 1.0);
        // Exactly on a threshold is not below it.
        assert!((recall_over(5.0, &mspd_thresholds_px()) - 0.9).abs() < 1e-12);
        // VSD: every tau error 0 -> 1; every tau error 0.5 -> none (0.5 < 0.5 is false).
        assert_eq!(vsd_recall(&[0.0; 10]), 1.0);
        assert_eq!(vsd_recall(&[0.5; 10]), 0.0);
        assert!((average_recall(1.0, 0.5, 0.0) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn mspd_scales_with_image_width() {
        // 20 px on a 1280-wide image is 10 px at 640: below 15..50 -> 8 of 10.
        assert!((mspd_recall(20.0, 1280) - 0.8).abs() < 1e-12);
        // The same 20 px at 640 wide: below 25..50 -> 6 of 10.
        assert!((mspd_recall(20.0, 640) - 0.6).abs() < 1e-12);
        // 20 px at 320 wide is 40 px: below 45, 50 -> 2 of 10.
        assert!((mspd_recall(20.0, 320) - 0.2).abs() < 1e-12);
    }
}
