#![no_main]
//! Fuzz the pose query's parameter parser: no panic on any input, and a time it accepts is what the parameters say.

#[path = "../../app/src/publish/zenoh/query_parameters.rs"]
mod query_parameters;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let offset = text.len() as i64 * 1_000_003 - 500;
    let Ok(t_us) = query_parameters::requested_time(text, offset) else {
        return;
    };
    // Accepted: exactly one time parameter, and it reads back the same way.
    let again = if text.contains("t_us=") {
        query_parameters::requested_time(&format!("t_us={t_us}"), offset)
    } else {
        let Some(stamp_ns) = t_us.checked_mul(1000).and_then(|ns| ns.checked_add(offset)) else {
            return;
        };
        query_parameters::requested_time(&format!("stamp_ns={stamp_ns}"), offset)
    };
    let back = again.expect("the canonical form of an accepted time parses");
    assert_eq!(back, t_us);
});
