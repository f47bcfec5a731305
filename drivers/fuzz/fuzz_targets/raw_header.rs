#![no_main]
//! Fuzz the `.raw` header parser and the full reader behind it: errors, never panics; a parsed header
//! written back parses to the same format and geometry.

use drivers::event::EventCounter;
use drivers::raw::{RawHeader, RawReader};
use libfuzzer_sys::fuzz_target;
use std::io::Cursor;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(h) = RawHeader::read(&mut Cursor::new(data)) {
        assert!(h.data_offset as usize <= data.len());
        if let Some(g) = h.geometry {
            let mut out = Vec::new();
            RawHeader::new(h.format, g, &[]).write(&mut out).unwrap();
            let back = RawHeader::read(&mut Cursor::new(&out)).unwrap();
            assert_eq!(back.format, h.format);
            assert_eq!(back.geometry, Some(g));
        }
    }
    if let Ok(mut r) = RawReader::new(data, Path::new("fuzz.raw")) {
        let mut c = EventCounter::new();
        let _ = r.read_all(&mut c);
    }
});
