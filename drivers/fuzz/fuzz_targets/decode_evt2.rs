#![no_main]
//! Fuzz the streaming EVT2 decoder: no panic, chunking-independent, bounds respected.

mod common;

use drivers::formats::any::EventFormat;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| common::check(EventFormat::Evt2, data));
