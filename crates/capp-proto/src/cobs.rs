//! Consistent Overhead Byte Stuffing: removes every `0x00` from a frame so
//! that `0x00` can delimit frames on the wire.
//!
//! The input is cut into runs of at most 254 non-zero bytes; each run is sent
//! as a code byte `len + 1` followed by the run. A code below `0xFF` means a
//! zero followed the run in the input (except after the last run); `0xFF`
//! means a full run of 254 bytes with no zero after it. Encoding `n` bytes
//! yields at most `n + n / 254 + 1` bytes.

/// The largest encoded size of `n` input bytes (without the delimiter).
pub const fn max_encoded_len(n: usize) -> usize {
    n + n / 254 + 1
}

/// Why a COBS operation failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CobsError {
    /// The output buffer is too small.
    OutputFull,
    /// The input holds a `0x00`, or a code points past the end.
    Malformed,
}

/// Writes `byte` at `at`, or fails with `error`: no indexing, so no panic path
/// (the callers' length checks make the error unreachable).
fn put(buf: &mut [u8], at: usize, byte: u8, error: CobsError) -> Result<(), CobsError> {
    *buf.get_mut(at).ok_or(error)? = byte;
    Ok(())
}

/// Encodes `input` into `output`; returns the encoded length.
pub fn encode(input: &[u8], output: &mut [u8]) -> Result<usize, CobsError> {
    if output.len() < max_encoded_len(input.len()) {
        return Err(CobsError::OutputFull);
    }
    let full = CobsError::OutputFull;
    let mut code_at = 0;
    let mut out = 1;
    let mut code: u8 = 1;
    for &b in input {
        if b == 0 {
            put(output, code_at, code, full)?;
            code_at = out;
            out += 1;
            code = 1;
        } else {
            put(output, out, b, full)?;
            out += 1;
            code += 1;
            if code == 0xFF {
                put(output, code_at, code, full)?;
                code_at = out;
                out += 1;
                code = 1;
            }
        }
    }
    put(output, code_at, code, full)?;
    Ok(out)
}

/// Decodes `buf` in place (no delimiter in it); returns the decoded length.
pub fn decode_in_place(buf: &mut [u8]) -> Result<usize, CobsError> {
    let mut read = 0;
    let mut write = 0;
    while read < buf.len() {
        let code = buf[read];
        if code == 0 {
            return Err(CobsError::Malformed);
        }
        read += 1;
        let run = code as usize - 1;
        if read + run > buf.len() {
            return Err(CobsError::Malformed);
        }
        for i in 0..run {
            let b = buf.get(read + i).copied().unwrap_or(0);
            if b == 0 {
                return Err(CobsError::Malformed);
            }
            put(buf, write, b, CobsError::Malformed)?;
            write += 1;
        }
        read += run;
        if code != 0xFF && read < buf.len() {
            put(buf, write, 0, CobsError::Malformed)?;
            write += 1;
        }
    }
    Ok(write)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round(input: &[u8]) -> ([u8; 600], usize) {
        let mut enc = [0u8; 600];
        let n = encode(input, &mut enc).unwrap();
        assert!(n <= max_encoded_len(input.len()));
        assert!(!enc[..n].contains(&0));
        let mut dec = enc;
        let m = decode_in_place(&mut dec[..n]).unwrap();
        assert_eq!(&dec[..m], input);
        (enc, n)
    }

    #[test]
    fn known_vectors() {
        // The examples of the COBS paper / Wikipedia.
        let cases: &[(&[u8], &[u8])] = &[
            (&[0x00], &[0x01, 0x01]),
            (&[0x00, 0x00], &[0x01, 0x01, 0x01]),
            (&[0x11, 0x22, 0x00, 0x33], &[0x03, 0x11, 0x22, 0x02, 0x33]),
            (&[0x11, 0x22, 0x33, 0x44], &[0x05, 0x11, 0x22, 0x33, 0x44]),
            (&[0x11, 0x00, 0x00, 0x00], &[0x02, 0x11, 0x01, 0x01, 0x01]),
            (&[], &[0x01]),
        ];
        for (input, expected) in cases {
            let (enc, n) = round(input);
            assert_eq!(&enc[..n], *expected);
        }
    }

    #[test]
    fn long_runs() {
        let mut v = [0u8; 520];
        for (i, b) in v.iter_mut().enumerate() {
            *b = (i % 255) as u8 + 1;
        }
        for len in [253, 254, 255, 508, 509, 520] {
            round(&v[..len]);
        }
        let (enc, n) = round(&v[..254]);
        assert_eq!(enc[0], 0xFF);
        assert_eq!(n, 256);
        assert_eq!(enc[255], 0x01);
    }

    #[test]
    fn malformed() {
        assert_eq!(
            decode_in_place(&mut [0x05, 1, 2]),
            Err(CobsError::Malformed)
        );
        assert_eq!(decode_in_place(&mut [0x02, 0]), Err(CobsError::Malformed));
    }
}
