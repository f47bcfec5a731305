//! The demo sequence: generated once by the `hil-sim` executable (the way `bench` generates suites) into a cache
//! directory and reused afterwards.

use anyhow::{Context, Result, bail};
use drivers::recording::Recording;
use eventtrack6d::runtime::config::{Config, DemoConfig, ReplayConfig, SourceKind};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// The `hil-sim` executable: next to this one (or one level up), else on `PATH`.
pub fn hil_sim_executable() -> Option<PathBuf> {
    let name = format!("hil-sim{}", std::env::consts::EXE_SUFFIX);
    if let Ok(exe) = std::env::current_exe()
        && let Some(dir) = exe.parent()
    {
        for cand in [dir.join(&name), dir.join("..").join(&name)] {
            if cand.is_file() {
                return Some(cand);
            }
        }
    }
    std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|p| p.join(&name))
            .find(|p| p.is_file())
    })
}

/// Where demo sequences are cached: `target/demo/` when this executable lives in a cargo target directory, else
/// `$XDG_CACHE_HOME/eventtrack6d`, else `~/.cache/eventtrack6d`.
pub fn default_cache_dir() -> PathBuf {
    if let Ok(exe) = std::env::current_exe()
        && let Some(profile_dir) = exe.parent()
        && let Some(target) = profile_dir.parent()
        && target.join("CACHEDIR.TAG").is_file()
    {
        return target.join("demo");
    }
    if let Some(x) = std::env::var_os("XDG_CACHE_HOME").filter(|x| !x.is_empty()) {
        return PathBuf::from(x).join("eventtrack6d");
    }
    if let Some(h) = std::env::var_os("HOME").filter(|h| !h.is_empty()) {
        return PathBuf::from(h).join(".cache").join("eventtrack6d");
    }
    PathBuf::from("eventtrack6d-cache")
}

/// Directory name of a demo sequence: every generator parameter is in it, so a change regenerates.
pub fn sequence_name(d: &DemoConfig) -> String {
    format!(
        "{}-{}-{}-{}s-seed{}",
        d.object, d.motion, d.speed, d.seconds, d.seed
    )
}

/// Returns the demo recording, generating it with `hil-sim generate` when it is not cached yet.
pub fn ensure_sequence(d: &DemoConfig, cache: &Path) -> Result<PathBuf> {
    let dir = cache.join(sequence_name(d));
    if dir.join("meta.json").is_file() && Recording::open(&dir).is_ok() {
        eprintln!("demo sequence: reusing {}", dir.display());
        return Ok(dir);
    }
    let Some(exe) = hil_sim_executable() else {
        bail!(
            "the demo sequence must be generated but the hil-sim executable was found neither next to eventtrack6d \
             nor on PATH: build it with `cargo build --release -p hil-sim`, then run \
             `cargo run --release -p eventtrack6d -- demo` again"
        );
    };
    std::fs::create_dir_all(cache)
        .with_context(|| format!("cannot create the demo cache {}", cache.display()))?;
    let partial = cache.join(format!("{}.partial", sequence_name(d)));
    if partial.exists() {
        std::fs::remove_dir_all(&partial)
            .with_context(|| format!("cannot remove {}", partial.display()))?;
    }
    eprintln!(
        "demo sequence: generating {} s of `{}` ({} {}, seed {}) with {} ...",
        d.seconds,
        d.object,
        d.motion,
        d.speed,
        d.seed,
        exe.display()
    );
    let start = Instant::now();
    let status = Command::new(&exe)
        .arg("generate")
        .args([
            "--object", &d.object, "--motion", &d.motion, "--speed", &d.speed,
        ])
        .args([
            "--seconds",
            &d.seconds.to_string(),
            "--seed",
            &d.seed.to_string(),
        ])
        .arg("--out")
        .arg(&partial)
        .status()
        .with_context(|| format!("cannot run {}", exe.display()))?;
    if !status.success() {
        bail!("`{} generate` failed ({status})", exe.display());
    }
    if dir.exists() {
        std::fs::remove_dir_all(&dir)
            .with_context(|| format!("cannot replace {}", dir.display()))?;
    }
    std::fs::rename(&partial, &dir)
        .with_context(|| format!("cannot move {} to {}", partial.display(), dir.display()))?;
    eprintln!(
        "demo sequence: generated in {:.1} s into {}",
        start.elapsed().as_secs_f64(),
        dir.display()
    );
    Ok(dir)
}

/// Turns a `demo` source into a replay of the (generated or cached) demo recording.
pub fn resolve(config: &mut Config, cache: &Path) -> Result<PathBuf> {
    if config.source.kind != SourceKind::Demo {
        bail!("not a demo configuration");
    }
    let dir = ensure_sequence(&config.demo, cache)?;
    config.source.kind = SourceKind::Replay;
    config.replay = Some(ReplayConfig {
        recording: dir.clone(),
    });
    Ok(dir)
}
