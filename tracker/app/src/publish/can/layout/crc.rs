//! CRC-8/AUTOSAR, the checksum in byte 0 of every pose frame.

/// CRC-8/AUTOSAR generator polynomial (x^8 + x^5 + x^3 + x^2 + x + 1, normal form).
pub const CRC8_POLY: u8 = 0x2F;
const CRC8_INIT: u8 = 0xFF;
const CRC8_XOROUT: u8 = 0xFF;

const CRC8_TABLE: [u8; 256] = {
    let mut table = [0u8; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u8;
        let mut b = 0;
        while b < 8 {
            c = if c & 0x80 != 0 {
                (c << 1) ^ CRC8_POLY
            } else {
                c << 1
            };
            b += 1;
        }
        table[i] = c;
        i += 1;
    }
    table
};

fn crc8_update(mut crc: u8, bytes: &[u8]) -> u8 {
    for &b in bytes {
        crc = CRC8_TABLE[usize::from(crc ^ b)];
    }
    crc
}

/// CRC-8/AUTOSAR of `bytes` (polynomial 0x2F, init 0xFF, final XOR 0xFF, not reflected).
pub fn crc8_autosar(bytes: &[u8]) -> u8 {
    crc8_update(CRC8_INIT, bytes) ^ CRC8_XOROUT
}

/// The frame CRC: CRC-8/AUTOSAR over the identifier as two bytes (low byte first) followed by `rest`
/// (bytes 1.. of the frame, i.e. everything but the CRC byte itself).
pub fn frame_crc(id: u16, rest: &[u8]) -> u8 {
    let crc = crc8_update(CRC8_INIT, &id.to_le_bytes());
    crc8_update(crc, rest) ^ CRC8_XOROUT
}
