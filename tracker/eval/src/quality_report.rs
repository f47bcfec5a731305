//! How well a method's own quality score and state tell its true error (issue 5: "report how well quality
//! predicts ADD-S error and how often `lost` is raised on sequences where tracking truly failed versus when it
//! did not"): the rank correlation of quality with the error, the median error by quality band, and `lost`
//! against true failure per sequence.

use super::bench::results::{MethodResults, SequenceResult};
use serde::Serialize;

/// Lower edges of the quality bands, highest first; each band reaches up to the next higher edge (the first to 1).
pub const QUALITY_BAND_EDGES: [f64; 4] = [0.8, 0.5, 0.2, 0.0];

/// One tick of one sequence as the quality report sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QualityTick<'a> {
    /// The method's quality at the tick, in [0, 1].
    pub quality: f64,
    /// The method's state name at the tick (`tracking`, `degraded`, `lost`).
    pub state: &'a str,
    /// ADD-S error at the tick, metres (infinite when the method had no pose).
    pub error_m: f64,
}

/// Ticks of one quality band.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct QualityBand {
    /// Lowest quality in the band (inclusive).
    pub from: f64,
    /// Highest quality in the band (exclusive, except 1 for the top band).
    pub to: f64,
    /// Ticks in the band.
    pub ticks: usize,
    /// Median ADD-S error of those ticks, metres (`None` without ticks).
    pub median_error_m: Option<f64>,
}

/// The quality report of one method over a suite.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct QualityReport {
    /// Ticks with a finite error (the correlation and the bands use these).
    pub ticks: usize,
    /// Spearman rank correlation of quality with the negated ADD-S error over every tick of every sequence:
    /// +1 when a higher quality always means a smaller error. `None` when the quality or the error is constant.
    pub spearman: Option<f64>,
    /// Ticks and median error per band of [`QUALITY_BAND_EDGES`], highest band first.
    pub bands: Vec<QualityBand>,
    /// Sequences (objects of sequences) evaluated.
    pub sequences: usize,
    /// Sequences that truly failed: an ADD-S error above 0.1 x diameter (where the AUC gives a tick nothing) on
    /// more than half of the last quarter of their ticks.
    pub failed: usize,
    /// Failed sequences on which `lost` was raised at least once.
    pub failed_with_lost: usize,
    /// Sequences that did not fail on which `lost` was raised at least once.
    pub lost_without_failure: usize,
    /// Names of the failed sequences on which `lost` was never raised (the failures the state kept quiet about),
    /// in input order.
    pub silent_failures: Vec<String>,
    /// Names of the sequences that did not fail but raised `lost` (false alarms), in input order.
    pub false_alarms: Vec<String>,
    /// Of [`Self::false_alarms`], those whose `lost` ticks were mostly (more than half) off by more than
    /// 0.1 x diameter: true losses the tracker recovered from before the end, not alarms on a good pose.
    pub recovered_losses: Vec<String>,
    /// Ticks whose state differs from the tick before (in the same sequence).
    pub state_changes: usize,
    /// Ticks in state `lost`, over every sequence.
    pub lost_ticks: usize,
    /// Of [`Self::lost_ticks`], those with an ADD-S error above 0.1 x diameter (or no pose): `lost` was right.
    pub lost_ticks_off: usize,
    /// Ticks with an ADD-S error above 0.1 x diameter (or no pose), over every sequence.
    pub off_ticks: usize,
    /// Of [`Self::off_ticks`], those in state `lost`: how much of the time spent off the object was announced.
    pub off_ticks_lost: usize,
}

/// Whether an ADD-S error counts as off the object: above `0.1 x diameter_m`, or not a number (no pose).
fn is_off(error_m: f64, diameter_m: f64) -> bool {
    error_m.is_nan() || error_m > 0.1 * diameter_m
}

/// Whether a sequence truly failed: error above `0.1 x diameter_m` on more than half of its last quarter.
pub fn truly_failed(errors_m: &[f64], diameter_m: f64) -> bool {
    let last = &errors_m[errors_m.len() * 3 / 4..];
    let off = last.iter().filter(|&&e| is_off(e, diameter_m)).count();
    !last.is_empty() && 2 * off > last.len()
}

/// Spearman rank correlation of `a` with `b` (average ranks for ties); `None` for fewer than two pairs or a
/// constant side.
pub fn spearman(a: &[f64], b: &[f64]) -> Option<f64> {
    if a.len() != b.len() || a.len() < 2 {
        return None;
    }
    let (ra, rb) = (ranks(a), ranks(b));
    let n = ra.len() as f64;
    let (ma, mb) = (ra.iter().sum::<f64>() / n, rb.iter().sum::<f64>() / n);
    let (mut cov, mut va, mut vb) = (0.0, 0.0, 0.0);
    for (x, y) in ra.iter().zip(&rb) {
        cov += (x - ma) * (y - mb);
        va += (x - ma) * (x - ma);
        vb += (y - mb) * (y - mb);
    }
    (va > 0.0 && vb > 0.0).then(|| (cov / (va * vb).sqrt()).clamp(-1.0, 1.0))
}

/// Ranks from 0, ties sharing their average rank. NaN sorts last.
fn ranks(x: &[f64]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..x.len()).collect();
    order.sort_by(|&i, &j| x[i].total_cmp(&x[j]));
    let mut out = vec![0.0; x.len()];
    let mut i = 0;
    while i < order.len() {
        let mut j = i;
        while j + 1 < order.len() && x[order[j + 1]] == x[order[i]] {
            j += 1;
        }
        for &k in &order[i..=j] {
            out[k] = (i + j) as f64 / 2.0;
        }
        i = j + 1;
    }
    out
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[v.len() / 2])
}

/// The ticks of one sequence (one object of it) for the quality report.
#[derive(Debug, Clone, PartialEq)]
pub struct SequenceTicks<'a> {
    /// The sequence's name in the report (`sequence` or `sequence/object`).
    pub name: String,
    /// Its ticks in time order.
    pub ticks: Vec<QualityTick<'a>>,
    /// The object's diameter, metres.
    pub diameter_m: f64,
}

/// The report over `sequences`.
pub fn quality_report(sequences: &[SequenceTicks<'_>]) -> QualityReport {
    let mut report = QualityReport {
        ticks: 0,
        spearman: None,
        bands: Vec::new(),
        sequences: sequences.len(),
        failed: 0,
        failed_with_lost: 0,
        lost_without_failure: 0,
        silent_failures: Vec::new(),
        false_alarms: Vec::new(),
        recovered_losses: Vec::new(),
        state_changes: 0,
        lost_ticks: 0,
        lost_ticks_off: 0,
        off_ticks: 0,
        off_ticks_lost: 0,
    };
    let (mut qualities, mut negated) = (Vec::new(), Vec::new());
    let mut banded: Vec<Vec<f64>> = vec![Vec::new(); QUALITY_BAND_EDGES.len()];
    for SequenceTicks {
        name,
        ticks,
        diameter_m,
    } in sequences
    {
        let errors: Vec<f64> = ticks.iter().map(|t| t.error_m).collect();
        let lost = ticks.iter().any(|t| t.state == "lost");
        let lost_ticks = ticks.iter().filter(|t| t.state == "lost").count();
        let lost_off = ticks
            .iter()
            .filter(|t| t.state == "lost" && is_off(t.error_m, *diameter_m))
            .count();
        let off: Vec<_> = ticks
            .iter()
            .filter(|t| is_off(t.error_m, *diameter_m))
            .collect();
        report.lost_ticks += lost_ticks;
        report.lost_ticks_off += lost_off;
        report.off_ticks += off.len();
        report.off_ticks_lost += off.iter().filter(|t| t.state == "lost").count();
        if truly_failed(&errors, *diameter_m) {
            report.failed += 1;
            report.failed_with_lost += usize::from(lost);
            if !lost {
                report.silent_failures.push(name.clone());
            }
        } else if lost {
            report.lost_without_failure += 1;
            report.false_alarms.push(name.clone());
            if 2 * lost_off > lost_ticks {
                report.recovered_losses.push(name.clone());
            }
        }
        report.state_changes += ticks
            .windows(2)
            .filter(|w| w[0].state != w[1].state)
            .count();
        for t in ticks.iter().filter(|t| t.error_m.is_finite()) {
            qualities.push(t.quality);
            negated.push(-t.error_m);
            if let Some(band) = QUALITY_BAND_EDGES.iter().position(|&lo| t.quality >= lo) {
                banded[band].push(t.error_m);
            }
        }
    }
    report.ticks = qualities.len();
    report.spearman = spearman(&qualities, &negated);
    report.bands = QUALITY_BAND_EDGES
        .iter()
        .zip(banded)
        .enumerate()
        .map(|(k, (&from, errors))| QualityBand {
            from,
            to: if k == 0 {
                1.0
            } else {
                QUALITY_BAND_EDGES[k - 1]
            },
            ticks: errors.len(),
            median_error_m: median(errors),
        })
        .collect();
    report
}

/// The ticks of one evaluated sequence: each scored frame with the method's quality and state at that time (the
/// latest pose row at or before it, as the scores hold it; a frame before the first row has quality 0 and no
/// state).
pub fn sequence_ticks(s: &SequenceResult) -> Vec<QualityTick<'_>> {
    let rows = &s.records;
    s.scores
        .frames
        .iter()
        .map(|f| {
            let k = rows.partition_point(|r| r.t_us <= f.t_us);
            let row = k.checked_sub(1).map(|k| &rows[k]);
            QualityTick {
                quality: row.map_or(0.0, |r| r.quality),
                state: row.map_or("", |r| r.state.as_str()),
                error_m: f.errors.add_s,
            }
        })
        .collect()
}

/// The report of one method's results (every sequence, 120 Hz ticks). A sequence with several objects is named
/// `sequence/object`.
pub fn method_quality_report(m: &MethodResults) -> QualityReport {
    let sequences: Vec<_> = m
        .sequences
        .iter()
        .map(|s| SequenceTicks {
            name: sequence_label(m, s),
            ticks: sequence_ticks(s),
            diameter_m: s.scores.diameter,
        })
        .collect();
    quality_report(&sequences)
}

/// How the reports name one result of `m`: the sequence, or `sequence/object` where the sequence has several
/// objects.
pub fn sequence_label(m: &MethodResults, s: &SequenceResult) -> String {
    let objects = m
        .sequences
        .iter()
        .filter(|o| o.sequence.name == s.sequence.name)
        .count();
    if objects > 1 {
        format!("{}/{}", s.sequence.name, s.scores.object)
    } else {
        s.sequence.name.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn tick(quality: f64, state: &str, error_m: f64) -> QualityTick<'_> {
        QualityTick {
            quality,
            state,
            error_m,
        }
    }

    #[test]
    fn spearman_is_one_for_a_monotone_relation_and_minus_one_reversed() {
        let a = [0.1, 0.5, 0.2, 0.9];
        let b = [1.0, 30.0, 2.0, 1000.0];
        assert!((spearman(&a, &b).unwrap() - 1.0).abs() < 1e-12);
        let c: Vec<f64> = b.iter().map(|x| -x).collect();
        assert!((spearman(&a, &c).unwrap() + 1.0).abs() < 1e-12);
        assert_eq!(spearman(&a, &[1.0; 4]), None);
        assert_eq!(spearman(&[1.0], &[2.0]), None);
        // Ties share a rank: [0, 0, 1] against [1, 2, 3] is 0.866.
        let r = spearman(&[0.0, 0.0, 1.0], &[1.0, 2.0, 3.0]).unwrap();
        assert!((r - 0.75f64.sqrt()).abs() < 1e-12, "{r}");
    }

    #[test]
    fn failure_lost_and_bands_are_counted_per_sequence() {
        let d = 0.1; // failure above 1 cm
        // Fine throughout, `lost` once: a false alarm.
        let fine: Vec<_> = (0..8)
            .map(|i| tick(0.9, if i == 3 { "lost" } else { "tracking" }, 0.002))
            .collect();
        // Off over its whole last quarter, with `lost`.
        let failed: Vec<_> = (0..8)
            .map(|i| {
                if i < 6 {
                    tick(0.6, "tracking", 0.004)
                } else {
                    tick(0.1, "lost", 0.05)
                }
            })
            .collect();
        // Off at the end without `lost`; a missing pose counts as off.
        let quiet: Vec<_> = (0..8)
            .map(|i| tick(0.3, "degraded", if i < 6 { 0.003 } else { f64::INFINITY }))
            .collect();
        let named = |name: &str, ticks| SequenceTicks {
            name: name.into(),
            ticks,
            diameter_m: d,
        };
        let r = quality_report(&[
            named("fine", fine),
            named("failed", failed),
            named("quiet", quiet),
        ]);
        assert_eq!(r.sequences, 3);
        assert_eq!(
            (r.failed, r.failed_with_lost, r.lost_without_failure),
            (2, 1, 1)
        );
        assert_eq!(r.silent_failures, ["quiet"]);
        assert_eq!(r.false_alarms, ["fine"]);
        // Its one `lost` tick was on the object: an alarm on a good pose, not a recovered loss.
        assert!(r.recovered_losses.is_empty());
        assert_eq!(r.state_changes, 2 + 1);
        // `lost` ticks: one on the object ("fine"), two off ("failed"); off ticks: those two and the two
        // missing poses of "quiet".
        assert_eq!((r.lost_ticks, r.lost_ticks_off), (3, 2));
        assert_eq!((r.off_ticks, r.off_ticks_lost), (4, 2));
        assert_eq!(r.ticks, 22);
        let counts: Vec<usize> = r.bands.iter().map(|b| b.ticks).collect();
        assert_eq!(counts, vec![8, 6, 6, 2]);
        assert_eq!(r.bands[0].median_error_m, Some(0.002));
        assert_eq!(r.bands[3].median_error_m, Some(0.05));
        assert_eq!((r.bands[0].from, r.bands[0].to), (0.8, 1.0));
        assert_eq!((r.bands[3].from, r.bands[3].to), (0.0, 0.2));
        // Higher quality, smaller error here.
        assert!(r.spearman.unwrap() > 0.5);
    }

    #[test]
    fn a_loss_the_tracker_recovered_from_is_told_apart_from_an_alarm_on_a_good_pose() {
        let d = 0.1;
        // Off by 5 cm for three ticks, `lost` on two of them and on one tick after it was back; fine at the end.
        let errors = [0.002, 0.05, 0.05, 0.05, 0.003, 0.002, 0.002, 0.002];
        let states = [
            "tracking", "degraded", "lost", "lost", "lost", "tracking", "tracking", "tracking",
        ];
        let recovered: Vec<_> = errors
            .iter()
            .zip(states)
            .map(|(&e, s)| tick(0.5, s, e))
            .collect();
        // The same `lost` ticks, but on the object throughout.
        let alarm: Vec<_> = states.iter().map(|&s| tick(0.5, s, 0.002)).collect();
        let r = quality_report(&[
            SequenceTicks {
                name: "recovered".into(),
                ticks: recovered,
                diameter_m: d,
            },
            SequenceTicks {
                name: "alarm".into(),
                ticks: alarm,
                diameter_m: d,
            },
        ]);
        assert_eq!(r.failed, 0);
        assert_eq!(r.false_alarms, ["recovered", "alarm"]);
        assert_eq!(r.recovered_losses, ["recovered"]);
        assert_eq!((r.lost_ticks, r.lost_ticks_off), (6, 2));
        assert_eq!((r.off_ticks, r.off_ticks_lost), (3, 2));
    }

    #[test]
    fn a_sequence_off_on_half_its_last_quarter_exactly_did_not_fail() {
        let errors = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        assert!(!truly_failed(&errors, 0.1));
        assert!(truly_failed(&[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0], 0.1));
        assert!(!truly_failed(&[], 0.1));
    }

    proptest! {
        #[test]
        fn spearman_stays_in_range_and_ignores_monotone_rescaling(
            pairs in prop::collection::vec((0.0f64..1.0, 0.0f64..1.0), 2..60)
        ) {
            let (a, b): (Vec<f64>, Vec<f64>) = pairs.into_iter().unzip();
            if let Some(r) = spearman(&a, &b) {
                prop_assert!((-1.0..=1.0).contains(&r));
                let scaled: Vec<f64> = a.iter().map(|x| 0.5 * x + x * x).collect();
                let s = spearman(&scaled, &b).unwrap();
                prop_assert!((r - s).abs() < 1e-9);
                prop_assert!((spearman(&b, &a).unwrap() - r).abs() < 1e-9);
            }
        }
    }
}
