//! Checks on the files a command reads and writes, made before any work starts: an output must not overwrite an
//! input or another output, and its folder must exist.

use anyhow::{Result, bail};
use std::path::{Path, PathBuf};

/// A file a command reads or writes, with the option (or role) that names it in messages.
pub type NamedPath<'a> = (&'a str, &'a Path);

/// Whether `a` and `b` name the same file: the same device and inode where both exist (links, `./` and `..`
/// included), else the same absolute path.
pub fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(x), Ok(y)) = (std::fs::metadata(a), std::fs::metadata(b)) {
            return x.dev() == y.dev() && x.ino() == y.ino();
        }
    }
    absolute(a) == absolute(b)
}

fn absolute(p: &Path) -> PathBuf {
    std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf())
}

/// Whether `p` exists and is not a plain file or directory (after links): a device such as `/dev/null`, a pipe
/// or a socket, which writing does not overwrite.
fn is_special(p: &Path) -> bool {
    std::fs::metadata(p).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

/// Refuses a set of outputs that would overwrite one of `inputs` or each other, or whose parent folder does not
/// exist; a directory where a file is to be written is refused too. Devices and pipes (`/dev/null`) are taken
/// as they are.
pub fn check_outputs(inputs: &[NamedPath<'_>], outputs: &[NamedPath<'_>]) -> Result<()> {
    for (i, (name, out)) in outputs.iter().enumerate() {
        if is_special(out) {
            continue;
        }
        if out.is_dir() {
            bail!("{name} {}: is a directory, not a file", out.display());
        }
        let parent = match out.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        if !parent.is_dir() {
            bail!(
                "{name} {}: the folder {} does not exist",
                out.display(),
                parent.display()
            );
        }
        for (input_name, input) in inputs {
            if same_file(out, input) {
                bail!(
                    "{name} {} would overwrite the {input_name} it reads ({})",
                    out.display(),
                    input.display()
                );
            }
        }
        for (other_name, other) in &outputs[..i] {
            if same_file(out, other) {
                bail!(
                    "{other_name} and {name} name the same file ({}): give each its own",
                    out.display()
                );
            }
        }
    }
    Ok(())
}

/// The files of a recording directory that a command reads (those that exist), for [`check_outputs`]: its
/// event stream, ground truth, cameras and metadata, and every file in `models/` and `depth/`.
pub fn recording_inputs(dir: &Path) -> Vec<(&'static str, PathBuf)> {
    let mut files: Vec<(&'static str, PathBuf)> = [
        ("recording's events", "events.raw"),
        ("recording's ground truth", "groundtruth.csv"),
        ("recording's cameras", "camera.json"),
        ("recording's metadata", "meta.json"),
    ]
    .into_iter()
    .map(|(name, file)| (name, dir.join(file)))
    .filter(|(_, p)| p.exists())
    .collect();
    for (name, sub) in [
        ("recording's models", "models"),
        ("recording's depth frames", "depth"),
    ] {
        if let Ok(entries) = std::fs::read_dir(dir.join(sub)) {
            files.extend(entries.flatten().map(|e| (name, e.path())));
        }
    }
    files
}

/// `items` without repeats, in the order each first appears.
pub fn first_of_each(items: impl IntoIterator<Item = String>) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for item in items {
        if !out.contains(&item) {
            out.push(item);
        }
    }
    out
}

/// Names each entry of `items` at most once; `what` says what they are (`--objects`).
pub fn refuse_repeats(items: &[String], what: &str) -> Result<()> {
    for (i, item) in items.iter().enumerate() {
        if items[..i].contains(item) {
            bail!("{what}: `{item}` is given twice");
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_output_may_not_overwrite_an_input_or_another_output() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("in.csv");
        std::fs::write(&input, "x").unwrap();
        let out = dir.path().join("out.csv");
        let fine = check_outputs(&[("--pred", &input)], &[("--json", &out)]);
        assert!(fine.is_ok(), "{fine:?}");
        // The same file by another spelling.
        let dotted = dir.path().join(".").join("in.csv");
        let e = check_outputs(&[("--pred", &input)], &[("--json", &dotted)]).unwrap_err();
        assert!(e.to_string().contains("would overwrite the --pred"), "{e}");
        let e = check_outputs(&[], &[("--json", &out), ("--bop", &out)]).unwrap_err();
        assert!(e.to_string().contains("--json and --bop"), "{e}");
        #[cfg(unix)]
        {
            let link = dir.path().join("link.csv");
            std::os::unix::fs::symlink(&input, &link).unwrap();
            assert!(check_outputs(&[("IN", &input)], &[("OUT", &link)]).is_err());
        }
        let e = check_outputs(&[], &[("--out", &dir.path().join("nowhere/x.csv"))]).unwrap_err();
        assert!(e.to_string().contains("does not exist"), "{e}");
        let e = check_outputs(&[], &[("--out", dir.path())]).unwrap_err();
        assert!(e.to_string().contains("is a directory"), "{e}");
        // A bare file name lives in the working directory, which exists.
        assert!(check_outputs(&[], &[("--out", Path::new("x.csv"))]).is_ok());
        // A device is no file to overwrite: both outputs may go there.
        let null = Path::new("/dev/null");
        if null.exists() {
            assert!(check_outputs(&[], &[("--json", null), ("--bop", null)]).is_ok());
        }
    }

    #[test]
    fn repeats_are_named() {
        let items = ["mug".to_string(), "can".into(), "mug".into()];
        let e = refuse_repeats(&items, "--objects").unwrap_err();
        assert_eq!(e.to_string(), "--objects: `mug` is given twice");
        assert!(refuse_repeats(&items[..2], "--objects").is_ok());
        // Interleaved rows of two objects (as the pose sinks write them) name two objects.
        let rows = ["drill", "mug", "drill", "mug"].map(String::from);
        assert_eq!(first_of_each(rows), ["drill", "mug"]);
    }
}
