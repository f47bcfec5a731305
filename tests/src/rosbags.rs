//! The independent ROS 2 type system: `tests/ros2/rosbags_check.py` (the `rosbags` Python package, installed by
//! `.ci/setup`, `pip install rosbags==0.11.9`), run as a child process. Its JSON form of a message: nested
//! messages are objects, arrays and sequences lists, byte arrays lowercase hex, floats strings holding Python's
//! repr (which parses back exactly).

use serde_json::Value;
use std::io::Write;
use std::path::PathBuf;
use std::process::{Command, Stdio};

/// The script.
pub fn script() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("ros2/rosbags_check.py")
}

/// Runs `rosbags_check.py ARGS` with `stdin`; its stdout. Panics with the reason (and how to install rosbags).
pub fn rosbags(args: &[&str], stdin: &[u8]) -> Vec<u8> {
    let mut child = match Command::new("python3")
        .arg(script())
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
    {
        Ok(c) => c,
        Err(e) => panic!("python3 is needed for the independent ROS 2 type system (rosbags): {e}"),
    };
    // The script reads all of stdin before it writes anything, so writing first cannot deadlock.
    child.stdin.take().unwrap().write_all(stdin).unwrap();
    let out = child.wait_with_output().unwrap();
    // Without rosbags the script says so and how to install it (`bash .ci/setup`).
    assert!(
        out.status.success(),
        "rosbags_check.py {args:?} failed ({}):\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

/// Each payload (CDR with its encapsulation header, as rmw_zenoh carries it) decoded by rosbags as `ty`.
pub fn rosbags_decode(ty: &str, payloads: &[Vec<u8>]) -> Vec<Value> {
    let dir = tempfile::tempdir().unwrap();
    let files: Vec<String> = payloads
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let f = dir.path().join(format!("{i}.cdr"));
            std::fs::write(&f, p).unwrap();
            f.to_str().unwrap().to_owned()
        })
        .collect();
    let mut args = vec!["decode", ty];
    args.extend(files.iter().map(String::as_str));
    let out = String::from_utf8(rosbags(&args, b"")).unwrap();
    let decoded: Vec<Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(decoded.len(), payloads.len(), "{out}");
    decoded
}

/// Checks rosbags' JSON of a message (`actual`) against the expected one, field by field: the same fields at every
/// level (none missing, none extra), integers, strings, booleans and hex byte arrays equal, and floats (rosbags
/// writes them as Python's repr, which parses back exactly; expected: JSON numbers) equal to the bit, or within
/// `tolerance(path)` where that gives one (a value computed differently on each side).
pub fn assert_fields_within(
    actual: &Value,
    expected: &Value,
    path: &str,
    tolerance: &dyn Fn(&str) -> Option<f64>,
) {
    match expected {
        Value::Object(exp) => {
            let Value::Object(act) = actual else {
                panic!("{path}: rosbags gives {actual}, expected a message {expected}");
            };
            let act_keys: Vec<&String> = act.keys().collect();
            let exp_keys: Vec<&String> = exp.keys().collect();
            assert_eq!(act_keys, exp_keys, "{path}: fields (rosbags vs expected)");
            for (k, v) in exp {
                assert_fields_within(&act[k], v, &format!("{path}.{k}"), tolerance);
            }
        }
        Value::Array(exp) => {
            let Value::Array(act) = actual else {
                panic!("{path}: rosbags gives {actual}, expected a list {expected}");
            };
            assert_eq!(act.len(), exp.len(), "{path}: length (rosbags vs expected)");
            for (i, (a, e)) in act.iter().zip(exp).enumerate() {
                assert_fields_within(a, e, &format!("{path}[{i}]"), tolerance);
            }
        }
        Value::Number(n) if n.is_f64() => {
            let e = n.as_f64().unwrap_or(f64::NAN);
            let Some(a) = actual.as_str().and_then(|s| s.parse::<f64>().ok()) else {
                panic!("{path}: rosbags gives {actual}, expected a float {e:?}");
            };
            match tolerance(path) {
                Some(tol) => assert!(
                    (a - e).abs() <= tol,
                    "{path}: rosbags reads {a:?}, expected {e:?} within {tol:e}"
                ),
                None => assert_eq!(
                    a.to_bits(),
                    e.to_bits(),
                    "{path}: rosbags reads {actual} ({a:?}), expected {e:?}"
                ),
            }
        }
        _ => assert_eq!(actual, expected, "{path}: rosbags vs expected"),
    }
}

/// [`assert_fields_within`] with every float equal to the bit.
pub fn assert_fields(actual: &Value, expected: &Value, path: &str) {
    assert_fields_within(actual, expected, path, &|_| None);
}
