//! The configuration reference: every table and key of a run's TOML configuration, with its type, default and
//! doc comment, rendered as Markdown from the configuration types' own schema (their doc comments and defaults),
//! so that `docs/configuration.md` cannot drift from the code. A test compares the two.

use super::Config;
use serde_json::{Map, Value};
use std::fmt::Write as _;

/// The reference of [`Config`] as Markdown.
pub fn reference_markdown() -> String {
    let schema = schemars::schema_for!(Config);
    let root = schema.as_value();
    let defs = root.get("$defs").and_then(Value::as_object);
    let mut out = String::from(
        "# Configuration reference\n\n\
         Every table and key of a configuration file for `eventtrack6d run --config FILE` (`config/default.toml` is \
         the demo's, `config/rig-evk4-d435i.toml` the USB rig's, `config/rig-ros2.toml` the ROS 2 one's), generated from the configuration types' doc comments \
         by `cargo test -p eventtrack6d --lib reference` (`ET6D_WRITE_DOCS=1` rewrites this file). Every key \
         has its default unless it says `required`; unknown keys are refused. How the pieces work together: \
         [runtime.md](runtime.md) and [tracker.md](tracker.md).\n",
    );
    let mut tables = Vec::new();
    tables.push((String::new(), root.clone()));
    while let Some((name, schema)) = tables.pop() {
        let nested = table(&mut out, &name, &schema, defs);
        // Nested tables after their parent, in the order they appear.
        tables.extend(nested.into_iter().rev());
    }
    out
}

/// Writes the keys of one table (`name`, empty for the top level) and returns its nested tables.
fn table(
    out: &mut String,
    name: &str,
    schema: &Value,
    defs: Option<&Map<String, Value>>,
) -> Vec<(String, Value)> {
    let schema = resolve(schema, defs);
    let Some(properties) = schema.get("properties").and_then(Value::as_object) else {
        return Vec::new();
    };
    let required: Vec<&str> = schema
        .get("required")
        .and_then(Value::as_array)
        .map(|r| r.iter().filter_map(Value::as_str).collect())
        .unwrap_or_default();
    let mut nested = Vec::new();
    let mut rows = String::new();
    for (key, property) in properties {
        let target = resolve(property, defs);
        let path = if name.is_empty() {
            key.clone()
        } else {
            format!("{name}.{key}")
        };
        if target.get("properties").is_some() {
            nested.push((path, target.clone()));
            continue;
        }
        if let Some(items) = array_of_tables(target, defs) {
            nested.push((format!("[{path}]"), items.clone()));
            continue;
        }
        let description = describe(property, target);
        let default = if required.contains(&key.as_str()) {
            "required".to_string()
        } else {
            property
                .get("default")
                .map_or_else(String::new, |d| format!("`{}`", toml_value(d)))
        };
        let _ = writeln!(
            rows,
            "| `{key}` | {} | {default} | {} |",
            type_name(target, defs),
            cell(&description)
        );
    }
    if !name.is_empty() {
        let _ = writeln!(out, "\n## `[{name}]`\n");
        if let Some(d) = schema.get("description").and_then(Value::as_str) {
            let _ = writeln!(out, "{}\n", clean(d));
        }
    }
    if !rows.is_empty() {
        out.push_str(if name.is_empty() {
            "\n## Top level\n\n"
        } else {
            ""
        });
        out.push_str("| key | type | default | meaning |\n| --- | --- | --- | --- |\n");
        out.push_str(&rows);
    }
    nested
}

/// The definition `schema` names (through `$ref`, an optional's `anyOf`/`oneOf` with null, or `allOf`), else it.
fn resolve<'a>(schema: &'a Value, defs: Option<&'a Map<String, Value>>) -> &'a Value {
    if let Some(r) = schema.get("$ref").and_then(Value::as_str) {
        let name = r.trim_start_matches("#/$defs/");
        if let Some(def) = defs.and_then(|d| d.get(name)) {
            return resolve(def, defs);
        }
    }
    for combinator in ["anyOf", "oneOf", "allOf"] {
        if let Some(options) = schema.get(combinator).and_then(Value::as_array) {
            let not_null: Vec<&Value> = options
                .iter()
                .filter(|o| o.get("type").and_then(Value::as_str) != Some("null"))
                .collect();
            if let [only] = not_null.as_slice()
                && only.get("$ref").is_some()
            {
                return resolve(only, defs);
            }
        }
    }
    schema
}

/// The table schema of an array of tables (`[[objects]]`), if `schema` is one.
fn array_of_tables<'a>(
    schema: &'a Value,
    defs: Option<&'a Map<String, Value>>,
) -> Option<&'a Value> {
    let items = resolve(schema.get("items")?, defs);
    items.get("properties").is_some().then_some(items)
}

/// A key's type in words: `string`, `integer`, `number`, `boolean`, `3 numbers`, one of the values of an enum.
fn type_name(schema: &Value, defs: Option<&Map<String, Value>>) -> String {
    if let Some(values) = enum_values(schema) {
        return values
            .iter()
            .map(|v| format!("`\"{v}\"`"))
            .collect::<Vec<_>>()
            .join(" \\| ");
    }
    let types: Vec<&str> = match schema.get("type") {
        Some(Value::String(t)) => vec![t.as_str()],
        Some(Value::Array(ts)) => ts.iter().filter_map(Value::as_str).collect(),
        _ => Vec::new(),
    };
    let optional = types.contains(&"null")
        || schema
            .get("anyOf")
            .and_then(Value::as_array)
            .is_some_and(|o| {
                o.iter()
                    .any(|s| s.get("type").and_then(Value::as_str) == Some("null"))
            });
    let base = match types.iter().find(|t| **t != "null") {
        Some(&"array") => {
            let item = schema
                .get("items")
                .map(|i| type_name(resolve(i, defs), defs));
            match (schema.get("minItems"), schema.get("maxItems"), item) {
                (Some(a), Some(b), Some(item)) if a == b => format!("{a} × {item}"),
                (_, _, Some(item)) => format!("list of {item}"),
                _ => "list".into(),
            }
        }
        Some(t) => (*t).to_string(),
        None => {
            let inner = resolve(schema, defs);
            if inner != schema {
                return type_name(inner, defs);
            }
            "value".into()
        }
    };
    if optional {
        format!("{base} (optional)")
    } else {
        base
    }
}

/// The values of an enum schema (`enum`, or `oneOf` of constants).
fn enum_values(schema: &Value) -> Option<Vec<String>> {
    if let Some(values) = schema.get("enum").and_then(Value::as_array) {
        return Some(
            values
                .iter()
                .filter_map(|v| v.as_str().map(String::from))
                .collect(),
        );
    }
    let options = schema.get("oneOf").and_then(Value::as_array)?;
    let values: Vec<String> = options
        .iter()
        .filter_map(|o| {
            o.get("const")
                .and_then(Value::as_str)
                .map(String::from)
                .or_else(|| {
                    o.get("enum")
                        .and_then(Value::as_array)
                        .and_then(|e| e.first())
                        .and_then(Value::as_str)
                        .map(String::from)
                })
        })
        .collect();
    (values.len() == options.len()).then_some(values)
}

/// A key's meaning: its doc comment, then its type's (an enum's values with theirs).
fn describe(property: &Value, target: &Value) -> String {
    let mut text = property
        .get("description")
        .and_then(Value::as_str)
        .map(clean)
        .unwrap_or_default();
    if let Some(options) = target.get("oneOf").and_then(Value::as_array) {
        let variants: Vec<String> = options
            .iter()
            .filter_map(|o| {
                let value = o
                    .get("const")
                    .and_then(Value::as_str)
                    .or_else(|| o.get("enum")?.as_array()?.first()?.as_str())?;
                let doc = o.get("description").and_then(Value::as_str).map(clean)?;
                Some(format!("`\"{value}\"`: {doc}"))
            })
            .collect();
        if !variants.is_empty() {
            text = format!("{text} {}", variants.join(" "));
        }
    }
    text.trim().to_string()
}

/// A doc comment as plain Markdown on one line: code blocks (examples) and rustdoc's intra-doc link brackets
/// dropped.
fn clean(doc: &str) -> String {
    let mut prose = String::with_capacity(doc.len());
    let mut in_code = false;
    for line in doc.lines() {
        if line.trim_start().starts_with("```") {
            in_code = !in_code;
        } else if !in_code {
            prose.push_str(line);
            prose.push('\n');
        }
    }
    let mut out = String::with_capacity(prose.len());
    let mut rest = prose.as_str();
    while let Some(start) = rest.find("[`") {
        out.push_str(&rest[..start]);
        let after = &rest[start + 1..];
        match after.find("`]") {
            Some(end) => {
                // A sibling key, `Self::x`, is named as the table names it.
                let code = &after[..end + 1];
                match code.strip_prefix("`Self::") {
                    Some(key) => {
                        out.push('`');
                        out.push_str(key);
                    }
                    None => out.push_str(code),
                }
                rest = &after[end + 2..];
                // A link target in parentheses, as `[x](y)`, goes too.
                if rest.starts_with('(')
                    && let Some(close) = rest.find(')')
                {
                    rest = &rest[close + 1..];
                }
            }
            None => {
                out.push('[');
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// A Markdown table cell: no line breaks, no bare pipes.
fn cell(text: &str) -> String {
    text.replace('|', "\\|")
}

/// A default value as TOML writes it.
fn toml_value(v: &Value) -> String {
    match v {
        Value::Null => "none".into(),
        Value::String(s) => format!("\"{s}\""),
        Value::Array(items) => format!(
            "[{}]",
            items.iter().map(toml_value).collect::<Vec<_>>().join(", ")
        ),
        Value::Object(_) => "{…}".into(),
        other => other.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn docs_configuration_md_is_the_generated_reference() {
        let generated = reference_markdown();
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/configuration.md");
        if std::env::var_os("ET6D_WRITE_DOCS").is_some() {
            std::fs::write(path, &generated).unwrap();
        }
        let shipped = std::fs::read_to_string(path).unwrap_or_default();
        assert!(
            shipped == generated,
            "docs/configuration.md differs from the configuration types' reference; after changing a configuration \
             key or its doc comment, regenerate it with `ET6D_WRITE_DOCS=1 cargo test -p eventtrack6d --lib reference`"
        );
    }

    #[test]
    fn every_key_of_the_shipped_configurations_is_in_the_reference() {
        let reference = reference_markdown();
        for file in ["default.toml", "rig-evk4-d435i.toml", "rig-ros2.toml"] {
            let path = format!("{}/../../config/{file}", env!("CARGO_MANIFEST_DIR"));
            let text = std::fs::read_to_string(&path).unwrap();
            let doc: toml::Table = toml::from_str(&text).unwrap();
            let mut keys = Vec::new();
            fn collect(prefix: &str, t: &toml::Table, keys: &mut Vec<String>) {
                for (k, v) in t {
                    match v {
                        toml::Value::Table(inner) => collect(&format!("{prefix}{k}."), inner, keys),
                        toml::Value::Array(items) if items.iter().all(toml::Value::is_table) => {
                            for item in items.iter().filter_map(toml::Value::as_table) {
                                collect(&format!("{prefix}{k}."), item, keys);
                            }
                        }
                        _ => keys.push(format!("{prefix}{k}")),
                    }
                }
            }
            collect("", &doc, &mut keys);
            assert!(!keys.is_empty());
            for key in keys {
                let (table, leaf) = key.rsplit_once('.').unwrap_or(("", &key));
                assert!(
                    reference.contains(&format!("| `{leaf}` |")),
                    "{file}: `{key}` has no row in the reference"
                );
                if !table.is_empty() {
                    assert!(
                        reference.contains(&format!("`[{table}]`"))
                            || reference.contains(&format!("`[[{table}]]`")),
                        "{file}: table `[{table}]` is not in the reference"
                    );
                }
            }
        }
    }

    #[test]
    fn doc_links_lose_their_brackets() {
        assert_eq!(
            clean("see [`Self::x`] and\n [`y`](z) [plain]"),
            "see `x` and `y` [plain]"
        );
    }
}
