//! CRC-32/ISO-HDLC (the zlib/Ethernet CRC): reflected polynomial `0xEDB88320`,
//! initial value `0xFFFFFFFF`, final XOR `0xFFFFFFFF`. Check value: the CRC of
//! the ASCII bytes `123456789` is `0xCBF43926`.

/// The CRC of each 4-bit value: the byte-wise table's 1 KiB of flash is a
/// twentieth of the firmware's budget; two nibble steps a byte (a few more
/// instructions per byte, on a stream of some 240 bytes a setpoint) cost
/// 64 bytes.
const fn table() -> [u32; 16] {
    let mut t = [0u32; 16];
    let mut i = 0;
    while i < 16 {
        let mut c = i as u32;
        let mut k = 0;
        while k < 4 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
            k += 1;
        }
        t[i] = c;
        i += 1;
    }
    t
}

static TABLE: [u32; 16] = table();

/// The CRC-32 of `bytes`.
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut c = 0xFFFF_FFFFu32;
    for &b in bytes {
        c ^= b as u32;
        c = TABLE[(c & 0xF) as usize] ^ (c >> 4);
        c = TABLE[(c & 0xF) as usize] ^ (c >> 4);
    }
    c ^ 0xFFFF_FFFF
}

#[cfg(test)]
mod tests {
    #[test]
    fn check_value() {
        assert_eq!(super::crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(super::crc32(b""), 0);
    }

    /// The nibble-wise CRC against the bit-wise definition.
    #[test]
    fn agrees_with_the_bitwise_definition() {
        let bitwise = |bytes: &[u8]| {
            let mut c = 0xFFFF_FFFFu32;
            for &b in bytes {
                c ^= b as u32;
                for _ in 0..8 {
                    c = if c & 1 != 0 {
                        0xEDB8_8320 ^ (c >> 1)
                    } else {
                        c >> 1
                    };
                }
            }
            c ^ 0xFFFF_FFFF
        };
        let mut x = 0x1234_5678u32;
        for len in 0..300 {
            let bytes: std::vec::Vec<u8> = (0..len)
                .map(|_| {
                    x ^= x << 13;
                    x ^= x >> 17;
                    x ^= x << 5;
                    x as u8
                })
                .collect();
            assert_eq!(super::crc32(&bytes), bitwise(&bytes));
        }
    }
}
