//! Reading a configuration: TOML text or file to [`Config`], path resolution, and parse errors that name the
//! line and the key.

use super::validate::{check_files, validate};
use super::*;
use std::path::Path;

/// Parses and validates TOML text; `origin` names it in errors. Relative paths stay relative.
pub fn from_toml(text: &str, origin: &str) -> Result<Config, ConfigError> {
    let config: Config = toml::from_str(text).map_err(|e| parse_error(text, origin, &e))?;
    validate(&config, origin)?;
    Ok(config)
}

/// The built-in demo configuration.
pub fn builtin_default() -> Result<Config, ConfigError> {
    from_toml(DEFAULT_CONFIG_TOML, "<built-in config/default.toml>")
}

/// Reads, parses, resolves paths against the file's directory, and validates (files included).
pub fn load(path: &Path) -> Result<Config, ConfigError> {
    let text = std::fs::read_to_string(path).map_err(|error| ConfigError::Read {
        path: path.to_path_buf(),
        error,
    })?;
    let origin = path.display().to_string();
    let mut config: Config = toml::from_str(&text).map_err(|e| parse_error(&text, &origin, &e))?;
    let base = path.parent().unwrap_or_else(|| Path::new("."));
    resolve_paths(&mut config, base);
    validate(&config, &origin)?;
    check_files(&config, &origin)?;
    Ok(config)
}

/// The tables of the TOML `text` this configuration was read from that it does not use, each with why: a
/// source table other than the chosen source's, `[zenoh]` with the zenoh sink off, `[can]` keys other than
/// `enabled` with CAN off. A user who edited one of them expects it to matter, so `run` warns about each.
pub fn unused_tables(config: &Config, text: &str) -> Vec<String> {
    let Ok(doc) = toml::from_str::<toml::Table>(text) else {
        return Vec::new();
    };
    let kind = config.source.kind.as_str();
    let mut unused = Vec::new();
    for (table, used) in [
        ("demo", config.source.kind == SourceKind::Demo),
        ("replay", config.source.kind == SourceKind::Replay),
        ("live", config.source.kind == SourceKind::Live),
        ("ros2", config.source.kind == SourceKind::Ros2),
    ] {
        if !used && doc.contains_key(table) {
            unused.push(format!("[{table}] is not used: [source] kind is `{kind}`"));
        }
    }
    // The ROS 2 source reads [zenoh]'s mode, scouting and domain id.
    if !config.sinks.zenoh && config.source.kind != SourceKind::Ros2 && doc.contains_key("zenoh") {
        unused.push("[zenoh] is not used: [sinks] zenoh is false".into());
    }
    let can_keys = doc
        .get("can")
        .and_then(toml::Value::as_table)
        .is_some_and(|t| t.keys().any(|k| k != "enabled"));
    if !config.can.enabled && can_keys {
        unused.push("[can] is not used: [can] enabled is false".into());
    }
    unused
}

/// Makes every relative path absolute-or-relative to `base` (the configuration file's directory).
pub fn resolve_paths(config: &mut Config, base: &Path) {
    let join = |p: &mut PathBuf| {
        if p.is_relative() {
            *p = base.join(&*p);
        }
    };
    if let Some(r) = &mut config.replay {
        join(&mut r.recording);
    }
    if let Some(l) = &mut config.live {
        join(&mut l.calibration);
        if let Some(r) = &mut l.depth_recording {
            join(r);
        }
    }
    if let Some(r) = &mut config.ros2 {
        join(&mut r.calibration);
    }
    for o in &mut config.objects {
        join(&mut o.mesh);
        if let Some(m) = &mut o.models_info {
            join(m);
        }
    }
    join(&mut config.output.dir);
}

/// Turns a TOML/serde error into a [`ConfigError::Parse`] with the line and the dotted key at the error.
fn parse_error(text: &str, origin: &str, e: &toml::de::Error) -> ConfigError {
    let message = e.message().trim().to_string();
    let (line, key) = match e.span() {
        Some(span) => key_at(text, span.start),
        None => (0, String::new()),
    };
    // An unknown field is reported at the offending key; a missing field at the table.
    let key = if key.is_empty() {
        "<top level>".into()
    } else {
        key
    };
    ConfigError::Parse {
        origin: origin.into(),
        line,
        key,
        message,
    }
}

/// The 1-based line of byte `offset` and the dotted key written there (`table.key`, or the table header).
pub(super) fn key_at(text: &str, offset: usize) -> (usize, String) {
    let offset = offset.min(text.len());
    let before = &text[..offset];
    let line_no = before.matches('\n').count() + 1;
    let mut table = String::new();
    for l in before.lines() {
        let t = l.trim();
        if t.starts_with('[') {
            table = t
                .trim_start_matches('[')
                .trim_end_matches(']')
                .trim()
                .to_string();
        }
    }
    let line = text.lines().nth(line_no - 1).unwrap_or("").trim();
    if line.starts_with('[') {
        let header = line
            .trim_start_matches('[')
            .split(']')
            .next()
            .unwrap_or("")
            .trim()
            .to_string();
        return (line_no, header);
    }
    let key = line.split('=').next().unwrap_or("").trim();
    let key = if key.is_empty() || line.is_empty() {
        table
    } else if table.is_empty() {
        key.to_string()
    } else {
        format!("{table}.{key}")
    };
    (line_no, key)
}
