//! Framing: `COBS(version | postcard(message) | crc32_le(version | message)) 0x00`.
//!
//! * [`encode`] writes one complete frame, delimiter included.
//! * [`Accumulator`] collects raw UART bytes into frames in a fixed buffer and
//!   says, for every byte, what happened (consumed, overfull, frame).
//! * [`decode`] checks a collected frame (COBS, length, CRC, version) and
//!   deserialises the message; every failure is a [`FrameError`], never a panic.

use serde::{de::DeserializeOwned, Serialize};

use crate::cobs;
use crate::crc::crc32;
use crate::VERSION;

/// Largest frame on the wire, delimiter included. Every message of this
/// protocol fits (the largest, a setpoint of 32 joints with their velocities
/// and accelerations, is 411 bytes); a receiver needs an accumulator of
/// `MAX_FRAME - 1` bytes.
pub const MAX_FRAME: usize = 512;

/// Largest unencoded frame body (version + message + CRC) that fits [`MAX_FRAME`].
pub const MAX_BODY: usize = MAX_FRAME - 1 - 1 - (MAX_FRAME - 2) / 254;

/// Why a frame could not be written or read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FrameError {
    /// Encoding: the message does not fit the output buffer or [`MAX_FRAME`].
    TooLong,
    /// The bytes between two delimiters are not valid COBS, or shorter than
    /// version + CRC.
    Cobs,
    /// The CRC does not match.
    Crc,
    /// The version byte is not [`VERSION`].
    Version {
        /// The version byte received.
        got: u8,
    },
    /// The CRC matched but the message is unknown or malformed (unknown
    /// discriminant, truncated, trailing bytes, over-long vector).
    Message,
    /// More than the accumulator's capacity arrived before a delimiter; the
    /// bytes up to the next delimiter were discarded.
    Overfull,
}

impl core::fmt::Display for FrameError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            FrameError::TooLong => write!(f, "message too long for a frame"),
            FrameError::Cobs => write!(f, "bad COBS encoding or short frame"),
            FrameError::Crc => write!(f, "CRC mismatch"),
            FrameError::Version { got } => write!(f, "protocol version {got}, expected {VERSION}"),
            FrameError::Message => write!(f, "unknown or malformed message"),
            FrameError::Overfull => write!(f, "frame longer than the receive buffer"),
        }
    }
}

/// Writes `message` as one frame (delimiter included) into `out`; returns its length.
pub fn encode<T: Serialize>(message: &T, out: &mut [u8]) -> Result<usize, FrameError> {
    let mut body = [0u8; MAX_BODY];
    body[0] = VERSION;
    let n = postcard::to_slice(message, &mut body[1..MAX_BODY - 4])
        .map_err(|_| FrameError::TooLong)?
        .len();
    // `get` instead of indexing: postcard wrote at most MAX_BODY - 5 bytes, so
    // these never fail, and no panic path is left for the optimiser to keep.
    let crc = crc32(body.get(..1 + n).ok_or(FrameError::TooLong)?);
    body.get_mut(1 + n..1 + n + 4)
        .ok_or(FrameError::TooLong)?
        .copy_from_slice(&crc.to_le_bytes());
    let len = 1 + n + 4;
    let body = body.get(..len).ok_or(FrameError::TooLong)?;
    let m = cobs::encode(body, out).map_err(|_| FrameError::TooLong)?;
    if m >= out.len() || m + 1 > MAX_FRAME {
        return Err(FrameError::TooLong);
    }
    out[m] = 0;
    Ok(m + 1)
}

/// Checks and deserialises the bytes of one frame as collected by an
/// [`Accumulator`] (no delimiter). Decodes in place: `frame` is clobbered.
pub fn decode<T: DeserializeOwned>(frame: &mut [u8]) -> Result<T, FrameError> {
    let n = cobs::decode_in_place(frame).map_err(|_| FrameError::Cobs)?;
    if n < 5 {
        return Err(FrameError::Cobs);
    }
    let body = frame.get(..n).ok_or(FrameError::Cobs)?;
    let (data, crc) = body.split_at(n - 4);
    let crc = u32::from_le_bytes([crc[0], crc[1], crc[2], crc[3]]);
    if crc32(data) != crc {
        return Err(FrameError::Crc);
    }
    if data[0] != VERSION {
        return Err(FrameError::Version { got: data[0] });
    }
    match postcard::take_from_bytes::<T>(&data[1..]) {
        Ok((message, [])) => Ok(message),
        _ => Err(FrameError::Message),
    }
}

/// [`decode`] for a [`Command`](crate::Command): the board's decoder, compiled
/// once, here (not generic, so it is built with capp-proto's optimisation
/// level: the firmware builds this crate for size, see firmware/Cargo.toml).
#[inline(never)]
pub fn decode_command(frame: &mut [u8]) -> Result<crate::Command, FrameError> {
    decode(frame)
}

/// What one byte did to an [`Accumulator`].
#[derive(Debug, PartialEq, Eq)]
pub enum Feed<'a> {
    /// Stored (or an empty frame / discarded byte): nothing to do yet.
    Consumed,
    /// A delimiter ended a frame that did not fit; it was discarded.
    Overfull,
    /// A delimiter ended a frame: its bytes, delimiter excluded, for [`decode`].
    Frame(&'a mut [u8]),
}

/// Collects UART bytes into frames in a fixed buffer of `N` bytes.
///
/// An empty frame (two delimiters in a row) is ignored, so a sender may send a
/// lone `0x00` at any time to resynchronise. After an overflow the bytes up to
/// the next delimiter are dropped and [`Feed::Overfull`] is reported once.
#[derive(Clone, Debug)]
pub struct Accumulator<const N: usize> {
    buf: [u8; N],
    len: usize,
    overfull: bool,
}

impl<const N: usize> Default for Accumulator<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Accumulator<N> {
    /// An empty accumulator.
    pub const fn new() -> Self {
        Accumulator {
            buf: [0; N],
            len: 0,
            overfull: false,
        }
    }

    /// Feeds one byte.
    pub fn feed(&mut self, byte: u8) -> Feed<'_> {
        if byte == 0 {
            let len = core::mem::replace(&mut self.len, 0);
            if core::mem::replace(&mut self.overfull, false) {
                return Feed::Overfull;
            }
            if len == 0 {
                return Feed::Consumed;
            }
            return match self.buf.get_mut(..len) {
                Some(frame) => Feed::Frame(frame),
                None => Feed::Overfull,
            };
        }
        if self.overfull {
            return Feed::Consumed;
        }
        // `len <= N` always: a full buffer (no slot at `len`) overflows.
        match self.buf.get_mut(self.len) {
            Some(slot) => {
                *slot = byte;
                self.len += 1;
            }
            None => {
                self.overfull = true;
                self.len = 0;
            }
        }
        Feed::Consumed
    }

    /// Feeds one byte and decodes a completed frame: `None` while a frame is
    /// incomplete, `Some(Err(..))` for a bad one.
    pub fn feed_message<T: DeserializeOwned>(&mut self, byte: u8) -> Option<Result<T, FrameError>> {
        match self.feed(byte) {
            Feed::Consumed => None,
            Feed::Overfull => Some(Err(FrameError::Overfull)),
            Feed::Frame(frame) => Some(decode(frame)),
        }
    }

    /// Forgets a partial frame.
    pub fn reset(&mut self) {
        self.len = 0;
        self.overfull = false;
    }
}
