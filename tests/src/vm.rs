//! The test VM of `tests/vm/` (a stock Debian kernel in QEMU with the USB/IP host side): where it is, whether it
//! can run here, and running a guest script with the workspace's binaries.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The workspace root.
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map_or_else(|| PathBuf::from("."), Path::to_path_buf)
}

/// The directory of the workspace's built binaries (`target/debug`): the parent of the test executable's
/// `deps` directory.
pub fn bin_dir() -> PathBuf {
    std::env::current_exe()
        .ok()
        .and_then(|p| p.parent().and_then(Path::parent).map(Path::to_path_buf))
        .unwrap_or_else(|| repo_root().join("target/debug"))
}

/// Why the VM cannot run here, if it cannot (no QEMU, or `tests/vm/setup.sh` has not fetched the kernel).
pub fn unavailable() -> Option<String> {
    let root = repo_root();
    if Command::new("qemu-system-x86_64")
        .arg("--version")
        .output()
        .is_err()
    {
        return Some("qemu-system-x86_64 is not installed (tests/vm/setup.sh installs it)".into());
    }
    if !root.join("target/vm/kernel/current").exists() {
        return Some("no VM kernel under target/vm (run tests/vm/setup.sh)".into());
    }
    None
}

/// A directory for a VM test's files, under `target/vm/work` (next to the build the guest runs), removed when
/// dropped.
pub fn work_dir() -> std::io::Result<tempfile::TempDir> {
    let base = repo_root().join("target/vm/work");
    std::fs::create_dir_all(&base)?;
    tempfile::Builder::new().prefix("test-").tempdir_in(base)
}

/// Runs `args` in the VM with the USB/IP host side loaded and the `env` variables (`K=V`) set, giving up after
/// `timeout_s`.
pub fn run(timeout_s: u32, env: &[&str], args: &[&str]) -> std::io::Result<Output> {
    let root = repo_root();
    let mut command = Command::new("bash");
    command.arg(root.join("tests/vm/run.sh")).args([
        "--timeout",
        &timeout_s.to_string(),
        "--modules",
        "usbip-core,vhci-hcd",
    ]);
    for e in env {
        command.args(["--env", e]);
    }
    command.arg("--").args(args).current_dir(&root).output()
}

/// The text between `=== name ===` and the next `===` marker line (or the end) of a guest's output.
pub fn section<'a>(stdout: &'a str, name: &str) -> Option<&'a str> {
    let marker = format!("=== {name} ===\n");
    let start = stdout.find(&marker)? + marker.len();
    let rest = &stdout[start..];
    Some(rest.find("\n=== ").map_or(rest, |end| &rest[..=end]))
}
