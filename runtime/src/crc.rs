//! CRC-16 of Modbus RTU frames: preset 0xFFFF, reflected polynomial 0xA001, sent low byte first.
//!
//! Every manual here describes the same algorithm (V7 `000_032dced3a1e91a75.txt:595`, TDS-V8
//! `002_661580cce154f322.txt:124`, MEMOBUS `003_8bcf5d50afb8e230.txt:413`). Several of them label
//! the first CRC byte on the wire "upper" or "high"; it is the low byte of the CRC register.

/// Lookup table for the reflected polynomial 0xA001, one entry per byte value.
const TABLE: [u16; 256] = build_table();

const fn build_table() -> [u16; 256] {
    let mut table = [0u16; 256];
    let mut i = 0;
    while i < 256 {
        let mut crc = i as u16;
        let mut bit = 0;
        while bit < 8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xA001
            } else {
                crc >> 1
            };
            bit += 1;
        }
        table[i] = crc;
        i += 1;
    }
    table
}

/// CRC-16/MODBUS of `bytes`.
pub fn crc16(bytes: &[u8]) -> u16 {
    let mut crc = 0xFFFFu16;
    for &b in bytes {
        crc = (crc >> 8) ^ TABLE[usize::from((crc ^ u16::from(b)) as u8)];
    }
    crc
}

/// The two CRC bytes in wire order (low byte first) for `bytes`.
pub fn crc_bytes(bytes: &[u8]) -> [u8; 2] {
    crc16(bytes).to_le_bytes()
}

/// Splits a frame into body and CRC and checks it. Returns the body, or the computed and the
/// received CRC when they differ. Frames shorter than 3 bytes have no body to check.
pub fn check(frame: &[u8]) -> Result<&[u8], (u16, u16)> {
    let Some(split) = frame.len().checked_sub(2) else {
        return Err((crc16(frame), 0));
    };
    let (body, tail) = frame.split_at(split);
    let received = u16::from_le_bytes([tail[0], tail[1]]);
    let computed = crc16(body);
    if computed == received {
        Ok(body)
    } else {
        Err((computed, received))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bitwise(bytes: &[u8]) -> u16 {
        // The manuals' own procedure, bit by bit (002_661580cce154f322.txt:126-130).
        let mut crc = 0xFFFFu16;
        for &b in bytes {
            crc ^= u16::from(b);
            for _ in 0..8 {
                crc = if crc & 1 != 0 {
                    (crc >> 1) ^ 0xA001
                } else {
                    crc >> 1
                };
            }
        }
        crc
    }

    #[test]
    fn table_matches_the_bitwise_procedure() {
        let data: Vec<u8> = (0..=255u8).chain((0..=255u8).rev()).collect();
        for len in 0..data.len() {
            assert_eq!(crc16(&data[..len]), bitwise(&data[..len]), "len {len}");
        }
    }

    #[test]
    fn worked_example_slave_2_function_7() {
        // 003_8bcf5d50afb8e230.txt:434-482 and 001_ef66da56d29a05af.txt:946-953: 41h then 12h.
        assert_eq!(crc_bytes(&[0x02, 0x07]), [0x41, 0x12]);
        assert_eq!(crc16(&[0x02, 0x07]), 0x1241);
    }

    #[test]
    fn check_splits_and_rejects() {
        assert_eq!(check(&[0x02, 0x07, 0x41, 0x12]), Ok(&[0x02u8, 0x07][..]));
        assert_eq!(check(&[0x02, 0x07, 0x12, 0x41]), Err((0x1241, 0x4112)));
        assert!(check(&[0x02]).is_err());
        assert!(check(&[]).is_err());
    }
}
