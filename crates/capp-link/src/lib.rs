//! # capp-link: the host end of the CAPP serial protocol
//!
//! A [`Link`] wraps any byte stream (a serial port from [`open_serial`], a TCP
//! socket from [`connect_tcp`], e.g. QEMU's emulated UART) and speaks
//! [`capp_proto`] over it: [`Link::upload`] sends a scenario given as
//! capp-core values, [`Link::run`] starts the plan and [`Link::receive_plan`]
//! collects every setpoint and the final status, reporting sequence gaps and
//! bad frames instead of hiding them. [`qemu`] boots the firmware under
//! `qemu-system-arm`.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod qemu;

use std::io::{self, Read, Write};
use std::net::{TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};

use capp_proto::{
    Accumulator, Command, ErrorCode, FrameError, Joints, Part, Reply, State, Status, MAX_FRAME,
};

/// What went wrong on the host side.
#[derive(Debug)]
pub enum LinkError {
    /// The byte stream failed.
    Io(io::Error),
    /// No answer in time.
    Timeout,
    /// The board refused a command.
    Refused {
        /// The command's code.
        command: u8,
        /// Why.
        code: ErrorCode,
        /// The item concerned, or 0xFF.
        index: u8,
    },
    /// A reply that does not answer the request.
    Unexpected(Box<Reply>),
    /// A value does not fit the protocol (too many joints, ...).
    TooLarge(&'static str),
}

impl std::fmt::Display for LinkError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LinkError::Io(e) => write!(f, "I/O: {e}"),
            LinkError::Timeout => write!(f, "no reply in time"),
            LinkError::Refused {
                command,
                code,
                index,
            } => write!(f, "command {command} refused: {code:?} (index {index})"),
            LinkError::Unexpected(r) => write!(f, "unexpected reply {r:?}"),
            LinkError::TooLarge(what) => write!(f, "too many {what} for the protocol"),
        }
    }
}

impl std::error::Error for LinkError {}

impl From<io::Error> for LinkError {
    fn from(e: io::Error) -> Self {
        LinkError::Io(e)
    }
}

/// Frames that arrived damaged, by kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameErrors {
    /// CRC mismatches.
    pub crc: u32,
    /// Bad COBS or short frames.
    pub framing: u32,
    /// Frames over the buffer size.
    pub overfull: u32,
    /// Good CRC but unknown message or wrong version.
    pub message: u32,
}

impl FrameErrors {
    /// All of them.
    pub fn total(&self) -> u32 {
        self.crc + self.framing + self.overfull + self.message
    }
}

/// A scenario as capp-core values: what the board is to plan.
#[derive(Clone, Debug)]
pub struct Upload<'a> {
    /// The robot's joints: DH rows, or general (URDF) joints with their
    /// origins and axes.
    pub joints: &'a [capp_core::Joint],
    /// The tool: the end effector's frame in the last joint's frame (the
    /// identity: none; sent only when it is not).
    pub tool: capp_core::robot::Placement,
    /// The link capsules' radii, one per joint, or none: no self-collision
    /// checks (the host's `Scenario::capsules().radii()`, so the board's
    /// scenario is the host's to the bit).
    pub capsule_radius: &'a [f32],
    /// The checked pairs, one row per link as the radii
    /// (`Scenario::capsules().checked_rows()`).
    pub capsule_rows: &'a [u64],
    /// The capsules' segments when they are not chords, one per capsule, or
    /// none (`Scenario::set_link_segments`' argument on the host).
    pub capsule_segments: &'a [[[f32; 3]; 2]],
    /// Each joint's drive limits, or none: the defaults from the rates
    /// (the host's `Scenario::drive_limits()`, so a tracked plan on the
    /// board keeps the host's limits to the bit; each joint's `max_rate` is
    /// its own and is not sent again).
    pub drive: &'a [capp_core::tracker::limits::DriveLimits],
    /// The obstacles.
    pub obstacles: &'a [capp_core::Solid],
    /// The hulls convex obstacles name, by index: each one's vertices (the
    /// host's `Scenario::hulls()`).
    pub hulls: &'a [&'a [[f32; 3]]],
    /// The waypoints (the last is the target).
    pub waypoints: &'a [capp_core::Waypoint],
    /// Which of them are joint configurations: (waypoint index, one value per
    /// joint); sent as `JointWaypoint` in their place.
    pub joint_goals: &'a [(usize, Vec<f32>)],
    /// The settings.
    pub settings: capp_core::Settings,
    /// The start configuration.
    pub start: &'a [f32],
}

/// One received setpoint.
#[derive(Clone, Debug, PartialEq)]
pub struct Setpoint {
    /// Sequence number.
    pub seq: u32,
    /// Planner step.
    pub step: u32,
    /// Joint vector.
    pub joints: Vec<f32>,
    /// Plan time, seconds.
    pub time_s: f32,
    /// The waypoint being approached, 0-based.
    pub waypoint: u8,
    /// Each joint's velocity, per second (tracked: the drive state; stepped:
    /// the step's rate).
    pub velocity: Vec<f32>,
    /// Each joint's acceleration, per second squared (stepped: zeros).
    pub acceleration: Vec<f32>,
}

/// Everything received for one plan.
#[derive(Clone, Debug)]
pub struct PlanRecord {
    /// Setpoints in arrival order.
    pub setpoints: Vec<Setpoint>,
    /// Sequence numbers in `0..status.setpoints` that never arrived (dropped
    /// by the board, whose count is `status.dropped`, or lost on the line).
    pub missing: Vec<u32>,
    /// The final status.
    pub status: Status,
    /// Damaged frames seen while receiving.
    pub frame_errors: FrameErrors,
}

/// A connection to a board over a byte stream.
pub struct Link<T: Read + Write> {
    io: T,
    rx: Accumulator<{ MAX_FRAME - 1 }>,
    buf: [u8; 512],
    start: usize,
    end: usize,
    /// Damaged frames seen since the link was opened.
    pub frame_errors: FrameErrors,
    /// How long a request waits for its reply.
    pub timeout: Duration,
}

/// Opens a serial port (a board's USB serial, an adapter) at `baud`.
pub fn open_serial(
    path: &str,
    baud: u32,
) -> Result<Link<Box<dyn serialport::SerialPort>>, LinkError> {
    let port = serialport::new(path, baud)
        .timeout(Duration::from_millis(50))
        .open()
        .map_err(|e| LinkError::Io(e.into()))?;
    Ok(Link::new(port))
}

/// Connects to a TCP serial (QEMU's `-serial tcp:...`).
pub fn connect_tcp(addr: impl ToSocketAddrs) -> Result<Link<TcpStream>, LinkError> {
    let s = TcpStream::connect(addr)?;
    s.set_read_timeout(Some(Duration::from_millis(50)))?;
    s.set_nodelay(true)?;
    Ok(Link::new(s))
}

impl<T: Read + Write> Link<T> {
    /// A link over `io`, whose reads must time out (return `TimedOut` or
    /// `WouldBlock`) now and then so deadlines are kept.
    pub fn new(io: T) -> Self {
        Link {
            io,
            rx: Accumulator::new(),
            buf: [0; 512],
            start: 0,
            end: 0,
            frame_errors: FrameErrors::default(),
            timeout: Duration::from_secs(5),
        }
    }

    /// The underlying stream.
    pub fn get_mut(&mut self) -> &mut T {
        &mut self.io
    }

    /// Sends one command (a leading delimiter resynchronises the board's receiver).
    pub fn send(&mut self, command: &Command) -> Result<(), LinkError> {
        let mut frame = [0u8; MAX_FRAME + 1];
        let n = capp_proto::encode(command, &mut frame[1..])
            .map_err(|_| LinkError::TooLarge("values"))?;
        self.send_raw(&frame[..n + 1])
    }

    /// Sends raw bytes (for tests of the board's error handling).
    pub fn send_raw(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        self.io.write_all(bytes)?;
        self.io.flush()?;
        Ok(())
    }

    /// The next good reply before `deadline`; damaged frames are counted and skipped.
    pub fn recv(&mut self, deadline: Instant) -> Result<Reply, LinkError> {
        loop {
            while self.start < self.end {
                let b = self.buf[self.start];
                self.start += 1;
                match self.rx.feed_message::<Reply>(b) {
                    None => {}
                    Some(Ok(reply)) => return Ok(reply),
                    Some(Err(e)) => {
                        let c = &mut self.frame_errors;
                        match e {
                            FrameError::Crc => c.crc += 1,
                            FrameError::Cobs | FrameError::TooLong => c.framing += 1,
                            FrameError::Overfull => c.overfull += 1,
                            FrameError::Message | FrameError::Version { .. } => c.message += 1,
                        }
                    }
                }
            }
            if Instant::now() >= deadline {
                return Err(LinkError::Timeout);
            }
            match self.io.read(&mut self.buf) {
                Ok(0) => {
                    return Err(LinkError::Io(io::Error::new(
                        io::ErrorKind::UnexpectedEof,
                        "the board closed the connection",
                    )))
                }
                Ok(n) => {
                    self.start = 0;
                    self.end = n;
                }
                Err(e)
                    if matches!(
                        e.kind(),
                        io::ErrorKind::TimedOut
                            | io::ErrorKind::WouldBlock
                            | io::ErrorKind::Interrupted
                    ) => {}
                Err(e) => return Err(e.into()),
            }
        }
    }

    /// Sends `command` and waits for its reply (an ack, pong, status or error),
    /// skipping setpoints (and statuses, unless `command` asks for one). A
    /// refusal is an error.
    pub fn request(&mut self, command: &Command) -> Result<Reply, LinkError> {
        self.send(command)?;
        let deadline = Instant::now() + self.timeout;
        let wants_status = matches!(command, Command::Status);
        loop {
            match self.recv(deadline)? {
                Reply::Setpoint { .. } => continue,
                // A plan's final status (or the answer to a status poll)
                // that arrived after its stream was read.
                Reply::Status(_) if !wants_status => continue,
                Reply::Error {
                    command,
                    code,
                    index,
                } => {
                    return Err(LinkError::Refused {
                        command,
                        code,
                        index,
                    })
                }
                reply => return Ok(reply),
            }
        }
    }

    fn expect_ack(&mut self, command: &Command) -> Result<(), LinkError> {
        match self.request(command)? {
            Reply::Ack { command: c } if c == command.code() => Ok(()),
            other => Err(LinkError::Unexpected(Box::new(other))),
        }
    }

    /// Pings; returns the board's protocol version.
    pub fn ping(&mut self, nonce: u32) -> Result<u8, LinkError> {
        match self.request(&Command::Ping { nonce })? {
            Reply::Pong {
                nonce: n, version, ..
            } if n == nonce => Ok(version),
            other => Err(LinkError::Unexpected(Box::new(other))),
        }
    }

    /// The board's status.
    pub fn status(&mut self) -> Result<Status, LinkError> {
        match self.request(&Command::Status)? {
            Reply::Status(s) => Ok(s),
            other => Err(LinkError::Unexpected(Box::new(other))),
        }
    }

    /// Replaces the board's load by `upload`, one frame per item, each acknowledged.
    pub fn upload(&mut self, upload: &Upload<'_>) -> Result<(), LinkError> {
        if upload.joints.len() > capp_proto::MAX_JOINTS
            || upload.start.len() > capp_proto::MAX_JOINTS
        {
            return Err(LinkError::TooLarge("joints"));
        }
        if upload.capsule_radius.len() != upload.capsule_rows.len() {
            return Err(LinkError::TooLarge("capsule rows (not one per radius)"));
        }
        if !upload.capsule_segments.is_empty()
            && upload.capsule_segments.len() != upload.capsule_radius.len()
        {
            return Err(LinkError::TooLarge("capsule segments (not one per radius)"));
        }
        if upload.capsule_radius.len() > capp_proto::MAX_JOINTS {
            return Err(LinkError::TooLarge("capsules"));
        }
        if upload.drive.len() > capp_proto::MAX_JOINTS {
            return Err(LinkError::TooLarge("drive limits"));
        }
        if upload.obstacles.len() > capp_proto::MAX_OBSTACLES {
            return Err(LinkError::TooLarge("obstacles"));
        }
        if upload.hulls.len() > capp_proto::MAX_HULLS {
            return Err(LinkError::TooLarge("hulls"));
        }
        if upload.waypoints.len() > capp_proto::MAX_WAYPOINTS {
            return Err(LinkError::TooLarge("waypoints"));
        }
        self.expect_ack(&Command::Clear(Part::All))?;
        for (i, j) in upload.joints.iter().enumerate() {
            self.expect_ack(&Command::Joint {
                index: i as u8,
                joint: (*j).into(),
            })?;
        }
        if !upload.tool.is_identity() {
            self.expect_ack(&Command::Tool(upload.tool.into()))?;
        }
        for (i, (&radius, &checked)) in upload
            .capsule_radius
            .iter()
            .zip(upload.capsule_rows)
            .enumerate()
        {
            self.expect_ack(&Command::Capsule {
                index: i as u8,
                capsule: capp_proto::Capsule {
                    radius,
                    checked,
                    segment: upload.capsule_segments.get(i).copied(),
                },
            })?;
        }
        for (i, d) in upload.drive.iter().enumerate() {
            self.expect_ack(&Command::Drive {
                index: i as u8,
                drive: capp_proto::Drive {
                    max_accel: d.max_accel,
                    max_jerk: d.max_jerk,
                },
            })?;
        }
        for (i, h) in upload.hulls.iter().enumerate() {
            let vertices = capp_proto::HullVertices::from_slice(h)
                .map_err(|_| LinkError::TooLarge("hull vertices"))?;
            self.expect_ack(&Command::Hull {
                index: i as u8,
                vertices,
            })?;
        }
        for (i, o) in upload.obstacles.iter().enumerate() {
            self.expect_ack(&Command::Obstacle {
                index: i as u8,
                obstacle: (*o).into(),
            })?;
        }
        for (i, w) in upload.waypoints.iter().enumerate() {
            match upload.joint_goals.iter().find(|(k, _)| *k == i) {
                Some((_, q)) => {
                    let joints =
                        Joints::from_slice(q).map_err(|_| LinkError::TooLarge("joints"))?;
                    self.expect_ack(&Command::JointWaypoint {
                        index: i as u8,
                        joints,
                    })?
                }
                None => self.expect_ack(&Command::Waypoint {
                    index: i as u8,
                    waypoint: (*w).into(),
                })?,
            }
        }
        self.expect_ack(&Command::Settings(upload.settings.into()))?;
        let start = Joints::from_slice(upload.start).map_err(|_| LinkError::TooLarge("joints"))?;
        self.expect_ack(&Command::Start(start))
    }

    /// Starts the plan; `filter` picks the setpoints streamed (the start and
    /// the last step always are).
    pub fn run(&mut self, filter: capp_core::SetpointFilter) -> Result<(), LinkError> {
        self.expect_ack(&capp_proto::run_command(filter))
    }

    /// Stops a running plan.
    pub fn stop(&mut self) -> Result<(), LinkError> {
        self.expect_ack(&Command::Stop)
    }

    /// Receives a running plan's stream up to its final status; gives up if
    /// nothing arrives for `idle`.
    pub fn receive_plan(&mut self, idle: Duration) -> Result<PlanRecord, LinkError> {
        self.receive_plan_watching(idle, |_| {})
    }

    /// [`Link::receive_plan`], asking for a `Status` whenever the line has
    /// been quiet for a quarter of `idle` (a plan may go seconds without a
    /// setpoint, and a final status may be lost on the line); every status
    /// that arrives is passed to `watch`. Gives up after `idle` without a
    /// good frame.
    pub fn receive_plan_watching(
        &mut self,
        idle: Duration,
        mut watch: impl FnMut(&Status),
    ) -> Result<PlanRecord, LinkError> {
        let errors_before = self.frame_errors;
        let poll = idle / 4;
        let mut setpoints = Vec::new();
        let mut last_frame = Instant::now();
        let mut next_poll = last_frame + poll;
        let status = loop {
            let reply = match self.recv(next_poll.min(last_frame + idle)) {
                Ok(reply) => reply,
                Err(LinkError::Timeout) => {
                    let now = Instant::now();
                    if now >= last_frame + idle {
                        return Err(LinkError::Timeout);
                    }
                    self.send(&Command::Status)?;
                    next_poll = now + poll;
                    continue;
                }
                Err(e) => return Err(e),
            };
            last_frame = Instant::now();
            next_poll = last_frame + poll;
            match reply {
                Reply::Setpoint {
                    seq,
                    step,
                    joints,
                    time_s,
                    waypoint,
                    velocity,
                    acceleration,
                } => setpoints.push(Setpoint {
                    seq,
                    step,
                    joints: joints.to_vec(),
                    time_s,
                    waypoint,
                    velocity: velocity.to_vec(),
                    acceleration: acceleration.to_vec(),
                }),
                Reply::Status(s) => {
                    watch(&s);
                    if s.state != State::Running {
                        break s;
                    }
                }
                other => return Err(LinkError::Unexpected(Box::new(other))),
            }
        };
        let mut seen = vec![false; status.setpoints as usize];
        for s in &setpoints {
            if let Some(x) = seen.get_mut(s.seq as usize) {
                *x = true;
            }
        }
        let missing = (0..status.setpoints)
            .filter(|&i| !seen[i as usize])
            .collect();
        let e = self.frame_errors;
        Ok(PlanRecord {
            setpoints,
            missing,
            status,
            frame_errors: FrameErrors {
                crc: e.crc - errors_before.crc,
                framing: e.framing - errors_before.framing,
                overfull: e.overfull - errors_before.overfull,
                message: e.message - errors_before.message,
            },
        })
    }
}
