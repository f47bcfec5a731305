//! `eventtrack6d compare`: whether a change moved benchmark scores beyond chance, from two sets of `bench` runs
//! over the same sequences.

use anyhow::{Context, Result, bail};
use clap::Args;
use eval::paired::{PairedOptions, RunSide, comparison_markdown, pair_results};
use std::path::{Path, PathBuf};

/// Compare two sets of `bench` runs of the same sequences: per-sequence ADD-S paired, with the mean difference and
/// its 95 % bootstrap interval.
///
/// Reads the `results.json` of each run (a bench output directory or the file itself), pairs every sequence of the
/// base runs with the same suite's sequence in the candidate runs, and prints Markdown: the mean ADD-S over the
/// sequences on each side, the mean per-sequence difference (candidate - base) with its 95 % bootstrap interval
/// (the sequences resampled with replacement; fixed seed, so the same runs give the same interval), whether the
/// interval excludes 0, and how many sequences moved by more than --moved points; for all sequences, per suite and
/// per motion profile; then the sequences that moved most each way. Give several runs per side to pool suites (e.g.
/// `fast` and `fast-check`), and several runs of one suite (twins: the same parameters with one nudged by 1 %) to
/// score each sequence by their mean: tuned defaults' own run is luckier than their neighbourhood, so compare with
/// twins. Both sides must hold the same sequences; a sequence on one side only, a run given twice, a missing method
/// or a file that is not a bench's results.json is an error naming it. The statistics: docs/evaluation.md.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// A base run: a bench output directory or its results.json (repeat for several suites).
    #[arg(long, value_name = "RUN", required = true)]
    pub base: Vec<PathBuf>,
    /// A candidate run, as --base.
    #[arg(long, value_name = "RUN", required = true)]
    pub candidate: Vec<PathBuf>,
    /// Method whose scores to compare (a method name of the runs' tables, e.g. `eventtrack6d@1,0.2,s2`, the second draw of `--methods eventtrack6d@1:0.2 --seeds 3`).
    #[arg(long, default_value = "eventtrack6d")]
    pub method: String,
    /// The candidate's method, when it differs from --method (e.g. `depth30` against `eventtrack6d`).
    #[arg(long)]
    pub candidate_method: Option<String>,
    /// Bootstrap resamples, 100 to 1000000.
    #[arg(long, default_value_t = 10_000, value_parser = clap::value_parser!(u32).range(100..=1_000_000))]
    pub resamples: u32,
    /// A sequence counts as raised or lowered when it moves by more than this many points (0 to 100).
    #[arg(long, default_value_t = 10.0, value_parser = parse_points)]
    pub moved: f64,
    /// Sequences listed as moved most, each way (0 to 1000).
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(0..=1000))]
    pub movers: u32,
}

fn parse_points(text: &str) -> Result<f64, String> {
    text.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite() && (0.0..=100.0).contains(v))
        .ok_or_else(|| format!("`{text}` is not a number of points from 0 to 100"))
}

/// The results.json of `run` (a directory holding one, or the file), parsed.
fn read_run(run: &Path) -> Result<(String, serde_json::Value)> {
    let file = if run.is_dir() {
        run.join("results.json")
    } else {
        run.to_path_buf()
    };
    if !file.is_file() {
        bail!(
            "{}: no bench results.json there (give a bench --out directory or its results.json)",
            file.display()
        );
    }
    let text =
        std::fs::read_to_string(&file).with_context(|| format!("reading {}", file.display()))?;
    let doc = serde_json::from_str(&text)
        .with_context(|| format!("{}: not valid JSON", file.display()))?;
    Ok((file.display().to_string(), doc))
}

/// Runs `eventtrack6d compare`.
pub fn run(args: &CompareArgs) -> Result<()> {
    let base = args
        .base
        .iter()
        .map(|p| read_run(p))
        .collect::<Result<Vec<_>>>()?;
    let candidate = args
        .candidate
        .iter()
        .map(|p| read_run(p))
        .collect::<Result<Vec<_>>>()?;
    let pairs = pair_results(
        &RunSide {
            runs: &base,
            method: &args.method,
        },
        &RunSide {
            runs: &candidate,
            method: args.candidate_method.as_deref().unwrap_or(&args.method),
        },
    )?;
    let options = PairedOptions {
        resamples: args.resamples as usize,
        moved: args.moved,
        ..PairedOptions::default()
    };
    print!(
        "{}",
        comparison_markdown(&pairs, &options, args.movers as usize)
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_outside_0_to_100_are_refused_with_the_text() {
        assert_eq!(parse_points("12.5"), Ok(12.5));
        assert!(parse_points("-1").unwrap_err().contains("`-1`"));
        assert!(parse_points("nan").is_err());
        assert!(parse_points("101").is_err());
    }

    #[test]
    fn a_run_without_results_is_an_error_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let e = read_run(dir.path()).unwrap_err().to_string();
        assert!(
            e.contains("results.json") && e.contains("no bench results.json"),
            "{e}"
        );
        std::fs::write(dir.path().join("results.json"), "{").unwrap();
        let e = format!("{:#}", read_run(dir.path()).unwrap_err());
        assert!(e.contains("not valid JSON"), "{e}");
    }
}
