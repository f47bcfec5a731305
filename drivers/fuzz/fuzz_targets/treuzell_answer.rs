#![no_main]
//! Fuzz the Treuzell answer checks: any bytes from the camera's control endpoint give a value or an error, never
//! a panic; an accepted register value comes from an answer that repeats the request.

use drivers::evk4::treuzell::Request;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let address = data.get(..4).map_or(0, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    let answer = data.get(4..).unwrap_or_default();
    let read = Request::register_read(address);
    if let Ok(value) = read.check_register_answer(answer) {
        assert_eq!(&answer[..16], &read.encode()[..16]);
        assert_eq!(&answer[16..20], &value.to_le_bytes());
    }
    let _ = Request::register_write(address, 0).check_answer(answer);
    let _ = Request::read(0x72).check_answer(answer);
});
