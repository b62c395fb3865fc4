//! The serial protocol's receive side on arbitrary bytes: the accumulator
//! (the board's 511-byte one and a tiny one that overflows often), `decode`
//! of commands and replies, and, when a message decodes, encode -> decode ->
//! encode giving the same bytes.
//!
//! Input: first byte = mode. Mode odd: the rest is a frame *body* (version +
//! postcard payload) that this target wraps with a correct CRC and COBS, so
//! the fuzzer reaches the message decoder past the CRC. Mode even: the rest is
//! raw line bytes.
#![no_main]

use capp_proto::{cobs, crc::crc32, decode, encode, Accumulator, Command, Feed, Reply, MAX_FRAME};
use libfuzzer_sys::fuzz_target;

/// A decoded message survives a round trip: its encoding decodes, and encodes
/// to the same bytes again.
fn round_trip<T>(message: &T)
where
    T: serde::Serialize + serde::de::DeserializeOwned,
{
    let mut first = [0u8; MAX_FRAME];
    // A message that decoded may still be too long to send (e.g. a long
    // vector): that is an encode error, not a panic.
    let Ok(n) = encode(message, &mut first) else {
        return;
    };
    assert_eq!(first[n - 1], 0, "a frame ends with its delimiter");
    assert!(
        first[..n - 1].iter().all(|&b| b != 0),
        "no zero inside a frame"
    );
    let mut copy = first;
    let again: T = decode(&mut copy[..n - 1]).expect("an encoded message decodes");
    let mut second = [0u8; MAX_FRAME];
    let m = encode(&again, &mut second).expect("it encoded once");
    assert_eq!(
        &first[..n],
        &second[..m],
        "encode -> decode -> encode changed the bytes"
    );
}

fn check_frame(frame: &[u8]) {
    let mut a = [0u8; MAX_FRAME];
    let n = frame.len().min(a.len());
    a[..n].copy_from_slice(&frame[..n]);
    let mut b = a;
    if let Ok(c) = decode::<Command>(&mut a[..n]) {
        round_trip(&c);
    }
    if let Ok(r) = decode::<Reply>(&mut b[..n]) {
        round_trip(&r);
    }
}

fn feed_line(line: &[u8]) {
    let mut big = Accumulator::<{ MAX_FRAME - 1 }>::new();
    let mut small = Accumulator::<16>::new();
    for &byte in line {
        if let Feed::Frame(frame) = big.feed(byte) {
            assert!(!frame.is_empty() && frame.len() < MAX_FRAME);
            check_frame(frame);
        }
        if let Feed::Frame(frame) = small.feed(byte) {
            assert!(!frame.is_empty() && frame.len() <= 16);
        }
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    if mode & 1 == 1 {
        let mut body = [0u8; MAX_FRAME];
        let n = rest.len().min(MAX_FRAME - 8);
        body[..n].copy_from_slice(&rest[..n]);
        let crc = crc32(&body[..n]);
        body[n..n + 4].copy_from_slice(&crc.to_le_bytes());
        let mut line = [0u8; MAX_FRAME + 2];
        let Ok(m) = cobs::encode(&body[..n + 4], &mut line) else {
            return;
        };
        // line[m] is already the delimiter.
        feed_line(&line[..m + 1]);
        check_frame(&line[..m]);
    } else {
        feed_line(rest);
    }
});
