#![allow(clippy::unwrap_used)]

use super::*;
use proptest::prelude::*;

#[test]
fn a_register_write_is_the_documented_twenty_bytes() {
    // Start sequence step: register 0x9008 (time base) = 0x645, device 0.
    let bytes = Request::register_write(0x9008, 0x645).encode();
    assert_eq!(
        bytes,
        [
            0x02, 0x01, 0x01, 0x40, 0x0C, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x08, 0x90,
            0x00, 0x00, 0x45, 0x06, 0x00, 0x00
        ]
    );
}

#[test]
fn a_register_read_and_its_answer() {
    let request = Request::register_read(0x0014);
    let bytes = request.encode();
    assert_eq!(
        bytes,
        [
            0x02, 0x01, 0x01, 0x00, 0x0C, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x14, 0x00,
            0x00, 0x00, 0x01, 0x00, 0x00, 0x00
        ]
    );
    // The IMX636's chip id answer: the request's first 16 bytes, then the value.
    let mut answer = bytes[..16].to_vec();
    answer.extend_from_slice(&0xA040_1806u32.to_le_bytes());
    assert_eq!(request.check_register_answer(&answer).unwrap(), 0xA040_1806);
    // An answer for another address is refused with the register named.
    let mut other = answer.clone();
    other[12] = 0x18;
    let e = request.check_register_answer(&other).unwrap_err();
    assert!(e.to_string().contains("0x0014"), "{e}");
}

#[test]
fn a_serial_read_is_eight_bytes_and_returns_the_payload() {
    let request = Request::read(property::SERIAL);
    assert_eq!(request.encode(), [0x72, 0, 0, 0, 0, 0, 0, 0]);
    let answer = [
        0x72, 0, 0, 0, 8, 0, 0, 0, 0x78, 0x56, 0x34, 0x12, 0, 0, 0, 0,
    ];
    assert_eq!(
        request.check_answer(&answer).unwrap(),
        &[0x78, 0x56, 0x34, 0x12, 0, 0, 0, 0]
    );
}

#[test]
fn failures_unknown_commands_and_bad_frames_are_named() {
    let request = Request::register_write(0x1014, 0x11A1_504D);
    let failed = encode_answer(0xC001_0102, &[0, 0, 0, 0, 5, 0, 0, 0]);
    assert_eq!(
        request.check_answer(&failed),
        Err(TreuzellError::Failed {
            property: 0x4001_0102,
            errno: 5
        })
    );
    assert_eq!(
        request.check_answer(&encode_answer(UNKNOWN_COMMAND, &[])),
        Err(TreuzellError::UnknownCommand {
            property: 0x4001_0102
        })
    );
    assert!(matches!(
        request.check_answer(&[0x02, 0x01]),
        Err(TreuzellError::TooShort { len: 2, .. })
    ));
    let mut long = encode_answer(0x4001_0102, &[0; 12]);
    long.push(0);
    assert!(matches!(
        request.check_answer(&long),
        Err(TreuzellError::LengthMismatch {
            declared: 12,
            actual: 13,
            ..
        })
    ));
    assert!(matches!(
        request.check_answer(&encode_answer(0x72, &[])),
        Err(TreuzellError::PropertyMismatch { answered: 0x72, .. })
    ));
}

proptest! {
    #[test]
    fn checking_any_bytes_never_panics(property in any::<u32>(), bytes in proptest::collection::vec(any::<u8>(), 0..64)) {
        let request = Request { property, payload: vec![0; 12] };
        let _ = request.check_answer(&bytes);
        let _ = request.check_register_answer(&bytes);
        let _ = Request::register_read(0).check_register_answer(&bytes);
    }

    #[test]
    fn frames_split_back_into_their_parts(property in any::<u32>(), payload in proptest::collection::vec(any::<u8>(), 0..256)) {
        let bytes = Request { property, payload: payload.clone() }.encode();
        let (p, n, rest) = split_frame(&bytes).unwrap();
        prop_assert_eq!(p, property);
        prop_assert_eq!(n as usize, payload.len());
        prop_assert_eq!(rest, &payload[..]);
    }

    #[test]
    fn an_echoed_register_read_returns_its_value(address in any::<u32>(), value in any::<u32>()) {
        let request = Request::register_read(address);
        let mut answer = request.encode()[..16].to_vec();
        answer.extend_from_slice(&value.to_le_bytes());
        prop_assert_eq!(request.check_register_answer(&answer), Ok(value));
    }
}
