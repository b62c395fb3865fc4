//! A faulty serial line between a host and a board: a TCP proxy that forwards
//! COBS frames both ways and, on a seeded schedule, flips bits, drops and
//! duplicates bytes, cuts frames short, repeats whole frames and pauses.
//!
//! The proxy keeps one connection to the board (QEMU's UART socket, which
//! must stay open: QEMU waits for it before its CPU starts) and accepts host
//! connections one after another on [`FaultProxy::port`], so a command-line
//! run of `capp serial --tcp` can go through it, then another.
//!
//! It decodes every frame it forwards from the board (with capp-proto, before
//! any fault) and records the sequence numbers of the setpoints it damaged or
//! repeated: the ground truth a test compares the host's report with.

use std::collections::BTreeSet;
use std::io::{self, Read, Write};
use std::net::{Shutdown, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

use capp_proto::Reply;

/// What to do to the frames going one way. Probabilities are per frame; a
/// damaged frame gets exactly one kind of damage.
#[derive(Clone, Copy, Debug)]
pub struct Faults {
    /// Seed of the schedule.
    pub seed: u64,
    /// Frames passed untouched before the faults start.
    pub after_frames: u64,
    /// Frames the faults last for (then the line is clean again).
    pub for_frames: u64,
    /// Flip one bit of one byte of the frame.
    pub flip: f64,
    /// Drop one byte of the frame.
    pub drop: f64,
    /// Send one byte of the frame twice.
    pub duplicate: f64,
    /// Cut the frame short (its delimiter still follows).
    pub cut: f64,
    /// Send the whole frame twice (intact both times).
    pub repeat: f64,
    /// Wait before the frame.
    pub pause: f64,
    /// How long a pause lasts.
    pub pause_for: Duration,
}

impl Faults {
    /// A clean line.
    pub const NONE: Faults = Faults {
        seed: 0,
        after_frames: 0,
        for_frames: 0,
        flip: 0.0,
        drop: 0.0,
        duplicate: 0.0,
        cut: 0.0,
        repeat: 0.0,
        pause: 0.0,
        pause_for: Duration::ZERO,
    };
}

/// What the proxy did, one direction.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FaultLog {
    /// Frames forwarded, bare delimiters not counted (since the last
    /// [`FaultProxy::set_faults`]).
    pub frames: u64,
    /// Frames with a flipped bit.
    pub flipped: u64,
    /// Frames with a dropped byte.
    pub dropped_byte: u64,
    /// Frames with a duplicated byte.
    pub duplicated_byte: u64,
    /// Frames cut short.
    pub cut: u64,
    /// Frames sent twice.
    pub repeated: u64,
    /// Pauses.
    pub paused: u64,
    /// Setpoint sequence numbers whose frame was damaged (flip, drop,
    /// duplicate byte, cut): the host must never accept these.
    pub damaged_setpoints: BTreeSet<u32>,
    /// Setpoint sequence numbers sent twice.
    pub repeated_setpoints: BTreeSet<u32>,
    /// Bytes from the board while no host was connected (discarded).
    pub discarded_bytes: u64,
}

impl FaultLog {
    /// Frames damaged in any way (pauses and intact repeats excluded).
    pub fn damaged(&self) -> u64 {
        self.flipped + self.dropped_byte + self.duplicated_byte + self.cut
    }
}

struct Direction {
    faults: Faults,
    rng: u64,
    log: FaultLog,
}

impl Direction {
    fn new(faults: Faults) -> Self {
        Direction {
            faults,
            rng: faults.seed ^ 0x9E37_79B9_7F4A_7C15,
            log: FaultLog::default(),
        }
    }

    /// SplitMix64.
    fn next(&mut self) -> u64 {
        self.rng = self.rng.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.rng;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn chance(&mut self, p: f64) -> bool {
        p > 0.0 && ((self.next() >> 11) as f64 / (1u64 << 53) as f64) < p
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }

    /// The bytes to send for one frame (`body` without its delimiter), and a
    /// pause to take first.
    fn process(&mut self, body: &[u8]) -> (Vec<u8>, Option<Duration>) {
        let mut out = body.to_vec();
        out.push(0);
        if body.is_empty() {
            // A bare delimiter (hosts send one before each command): not a frame.
            return (out, None);
        }
        let index = self.log.frames;
        self.log.frames += 1;
        let f = self.faults;
        if index < f.after_frames || index >= f.after_frames + f.for_frames {
            return (out, None);
        }
        let seq = setpoint_seq(body);
        let pause = self.chance(f.pause).then_some(f.pause_for);
        if pause.is_some() {
            self.log.paused += 1;
        }
        let damaged = if self.chance(f.flip) {
            let i = self.below(body.len());
            out[i] ^= 1 << self.below(8);
            self.log.flipped += 1;
            true
        } else if self.chance(f.drop) && body.len() > 1 {
            out.remove(self.below(body.len()));
            self.log.dropped_byte += 1;
            true
        } else if self.chance(f.duplicate) {
            let i = self.below(body.len());
            out.insert(i, out[i]);
            self.log.duplicated_byte += 1;
            true
        } else if self.chance(f.cut) && body.len() > 1 {
            let keep = 1 + self.below(body.len() - 1);
            out.truncate(keep);
            out.push(0);
            self.log.cut += 1;
            true
        } else {
            false
        };
        if damaged {
            if let Some(seq) = seq {
                self.log.damaged_setpoints.insert(seq);
            }
        } else if self.chance(f.repeat) {
            out.extend_from_slice(body);
            out.push(0);
            self.log.repeated += 1;
            if let Some(seq) = seq {
                self.log.repeated_setpoints.insert(seq);
            }
        }
        (out, pause)
    }
}

/// The sequence number of a setpoint frame (COBS body without delimiter).
fn setpoint_seq(body: &[u8]) -> Option<u32> {
    let mut copy = body.to_vec();
    match capp_proto::decode::<Reply>(&mut copy) {
        Ok(Reply::Setpoint { seq, .. }) => Some(seq),
        _ => None,
    }
}

type Shared = Arc<Mutex<[Direction; 2]>>;
const TO_HOST: usize = 0;
const TO_BOARD: usize = 1;

/// The running proxy; stops when dropped.
pub struct FaultProxy {
    /// Where hosts connect.
    pub port: u16,
    shared: Shared,
    host: Arc<Mutex<Option<TcpStream>>>,
    quit: Arc<AtomicBool>,
    threads: Vec<JoinHandle<()>>,
}

impl FaultProxy {
    /// Connects to the board at `board` and listens for hosts on a free local port.
    pub fn start(board: TcpStream) -> io::Result<FaultProxy> {
        let listener = TcpListener::bind("127.0.0.1:0")?;
        let port = listener.local_addr()?.port();
        listener.set_nonblocking(true)?;
        board.set_read_timeout(Some(Duration::from_millis(20)))?;
        board.set_nodelay(true)?;
        let shared: Shared = Arc::new(Mutex::new([
            Direction::new(Faults::NONE),
            Direction::new(Faults::NONE),
        ]));
        let host: Arc<Mutex<Option<TcpStream>>> = Arc::new(Mutex::new(None));
        let quit = Arc::new(AtomicBool::new(false));
        let mut threads = Vec::new();

        // Board to host: frame by frame, through the TO_HOST faults.
        {
            let (shared, host, quit) = (shared.clone(), host.clone(), quit.clone());
            let mut board = board.try_clone()?;
            threads.push(std::thread::spawn(move || {
                let mut frame = Vec::new();
                let mut buf = [0u8; 1024];
                while !quit.load(Ordering::Relaxed) {
                    let n = match board.read(&mut buf) {
                        Ok(0) => return,
                        Ok(n) => n,
                        Err(e) if is_timeout(&e) => continue,
                        Err(_) => return,
                    };
                    for &b in &buf[..n] {
                        if b != 0 {
                            frame.push(b);
                            continue;
                        }
                        let (bytes, pause) = shared.lock().unwrap()[TO_HOST].process(&frame);
                        frame.clear();
                        if let Some(p) = pause {
                            std::thread::sleep(p);
                        }
                        let mut guard = host.lock().unwrap();
                        match guard.as_mut() {
                            Some(h) => {
                                if h.write_all(&bytes).is_err() {
                                    *guard = None;
                                }
                            }
                            None => {
                                shared.lock().unwrap()[TO_HOST].log.discarded_bytes +=
                                    bytes.len() as u64
                            }
                        }
                    }
                }
            }));
        }

        // Hosts, one after another; host to board through the TO_BOARD faults.
        {
            let (shared, host, quit) = (shared.clone(), host.clone(), quit.clone());
            let mut board = board;
            threads.push(std::thread::spawn(move || {
                while !quit.load(Ordering::Relaxed) {
                    let stream = match listener.accept() {
                        Ok((s, _)) => s,
                        Err(e) if is_timeout(&e) => {
                            std::thread::sleep(Duration::from_millis(10));
                            continue;
                        }
                        Err(_) => return,
                    };
                    let _ = stream.set_nonblocking(false);
                    let _ = stream.set_read_timeout(Some(Duration::from_millis(20)));
                    let _ = stream.set_nodelay(true);
                    let Ok(writer) = stream.try_clone() else {
                        continue;
                    };
                    *host.lock().unwrap() = Some(writer);
                    let mut reader = stream;
                    let mut frame = Vec::new();
                    let mut buf = [0u8; 1024];
                    'host: while !quit.load(Ordering::Relaxed) {
                        let n = match reader.read(&mut buf) {
                            Ok(0) => break 'host,
                            Ok(n) => n,
                            Err(e) if is_timeout(&e) => continue,
                            Err(_) => break 'host,
                        };
                        for &b in &buf[..n] {
                            if b != 0 {
                                frame.push(b);
                                continue;
                            }
                            let (bytes, pause) = shared.lock().unwrap()[TO_BOARD].process(&frame);
                            frame.clear();
                            if let Some(p) = pause {
                                std::thread::sleep(p);
                            }
                            if board.write_all(&bytes).is_err() {
                                return;
                            }
                        }
                    }
                    if let Some(h) = host.lock().unwrap().take() {
                        let _ = h.shutdown(Shutdown::Both);
                    }
                }
            }));
        }
        Ok(FaultProxy {
            port,
            shared,
            host,
            quit,
            threads,
        })
    }

    /// Replaces the faults of both directions and clears their logs.
    pub fn set_faults(&self, to_host: Faults, to_board: Faults) {
        let mut d = self.shared.lock().unwrap();
        d[TO_HOST] = Direction::new(to_host);
        d[TO_BOARD] = Direction::new(to_board);
    }

    /// What was done since the last [`FaultProxy::set_faults`]: (to host, to board).
    pub fn logs(&self) -> (FaultLog, FaultLog) {
        let d = self.shared.lock().unwrap();
        (d[TO_HOST].log.clone(), d[TO_BOARD].log.clone())
    }
}

impl Drop for FaultProxy {
    fn drop(&mut self) {
        self.quit.store(true, Ordering::Relaxed);
        if let Some(h) = self.host.lock().unwrap().take() {
            let _ = h.shutdown(Shutdown::Both);
        }
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

fn is_timeout(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut | io::ErrorKind::Interrupted
    )
}
