#![no_main]
//! Fuzz the text parsers of recordings and event CSV: errors, never panics.

use drivers::formats::csv::EventCsvParser;
use drivers::recording::{format_ground_truth, parse_ground_truth, parse_models_info};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut p = EventCsvParser::new();
    let mut n = 0usize;
    for chunk in data.chunks(7) {
        p.feed(chunk, &mut |_| n += 1, &mut |_| {});
    }
    p.finish(&mut |_| n += 1, &mut |_| {});
    if let Ok(text) = std::str::from_utf8(data) {
        if let Ok(poses) = parse_ground_truth(text) {
            let again = parse_ground_truth(&format_ground_truth(&poses)).expect("written table parses");
            // Parsed values are finite, so the written table reads back equal, field for field.
            assert_eq!(again, poses);
        }
        let _ = parse_models_info(text);
    }
});
