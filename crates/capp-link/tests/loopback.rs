//! capp-link against capp-node in a thread, over a socket pair: the whole
//! host-side protocol without QEMU. A UART that takes fewer bytes per tick
//! than a setpoint needs shows up as sequence gaps, all counted as drops.

use std::io::{ErrorKind, Read, Write};
use std::os::unix::net::UnixStream;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use capp_core::kinematics::{forward_kinematics, Frames};
use capp_core::{pips, SetpointFilter, Settings, Waypoint};
use capp_link::{Link, Upload};
use capp_node::Node;
use capp_proto::{Outcome, State};
use embedded_hal_nb::{nb, serial};

/// The board's end of the socket as a UART taking `budget` bytes per tick.
struct SocketUart {
    s: UnixStream,
    budget: usize,
    left: usize,
}

impl serial::ErrorType for SocketUart {
    type Error = serial::ErrorKind;
}
impl serial::Read<u8> for SocketUart {
    fn read(&mut self) -> nb::Result<u8, Self::Error> {
        let mut b = [0u8];
        match self.s.read(&mut b) {
            Ok(1) => Ok(b[0]),
            Ok(_) => Err(nb::Error::Other(serial::ErrorKind::Other)),
            Err(e) if e.kind() == ErrorKind::WouldBlock => Err(nb::Error::WouldBlock),
            Err(_) => Err(nb::Error::Other(serial::ErrorKind::Other)),
        }
    }
}
impl serial::Write<u8> for SocketUart {
    fn write(&mut self, b: u8) -> nb::Result<(), Self::Error> {
        if self.left == 0 {
            return Err(nb::Error::WouldBlock);
        }
        match self.s.write(&[b]) {
            Ok(1) => {
                self.left -= 1;
                Ok(())
            }
            _ => Err(nb::Error::WouldBlock),
        }
    }
    fn flush(&mut self) -> nb::Result<(), Self::Error> {
        Ok(())
    }
}

fn board(
    budget: usize,
) -> (
    Link<UnixStream>,
    Arc<AtomicBool>,
    std::thread::JoinHandle<()>,
) {
    let (host, dev) = UnixStream::pair().unwrap();
    host.set_read_timeout(Some(Duration::from_millis(20)))
        .unwrap();
    dev.set_nonblocking(true).unwrap();
    let quit = Arc::new(AtomicBool::new(false));
    let q = quit.clone();
    let t = std::thread::spawn(move || {
        let mut node = Box::new(Node::<2048>::new());
        let mut uart = SocketUart {
            s: dev,
            budget,
            left: budget,
        };
        while !q.load(Ordering::Relaxed) {
            uart.left = uart.budget;
            node.poll(&mut uart);
            // A fast line keeps up by definition: with an unlimited budget the
            // board steps only once its queue went out (the socket itself
            // can stall when the host thread is descheduled on a busy machine).
            if uart.budget != usize::MAX || node.tx_len() == 0 {
                node.tick(1);
            }
            std::thread::sleep(Duration::from_micros(50));
        }
    });
    (Link::new(host), quit, t)
}

fn target() -> Waypoint {
    let robot = pips::robot::<32>().unwrap();
    let mut q = pips::home();
    q[1] += 0.3;
    q[9] -= 0.3;
    let mut frames = Frames::<32>::default();
    forward_kinematics(&robot, &q, &mut frames);
    let p = frames.end_position();
    Waypoint::at([p.x, p.y, p.z])
}

fn plan(budget: usize) -> capp_link::PlanRecord {
    let (mut link, quit, t) = board(budget);
    let joints = pips::joints();
    let home = pips::home();
    let waypoints = [target()];
    link.upload(&Upload {
        joints: &joints,
        tool: capp_core::robot::Placement::IDENTITY,
        capsule_radius: &[],
        capsule_rows: &[],
        capsule_segments: &[],
        drive: &[],
        obstacles: &[],
        hulls: &[],
        waypoints: &waypoints,
        joint_goals: &[],
        settings: Settings::default(),
        start: &home,
    })
    .unwrap();
    link.run(SetpointFilter::Every(1)).unwrap();
    let record = link.receive_plan(Duration::from_secs(20)).unwrap();
    quit.store(true, Ordering::Relaxed);
    t.join().unwrap();
    record
}

#[test]
fn a_fast_line_delivers_every_setpoint() {
    let r = plan(usize::MAX);
    assert_eq!(
        (r.status.state, r.status.outcome),
        (State::Done, Some(Outcome::Reached))
    );
    assert!(r.missing.is_empty());
    assert_eq!(r.setpoints.len() as u32, r.status.setpoints);
    assert_eq!(r.frame_errors.total(), 0);
}

#[test]
fn a_slow_line_shows_gaps_equal_to_the_drops() {
    let r = plan(10);
    assert_eq!(r.status.state, State::Done);
    assert!(r.status.dropped > 0);
    assert_eq!(r.missing.len() as u32, r.status.dropped);
    assert_eq!(
        r.setpoints.len() as u32 + r.status.dropped,
        r.status.setpoints
    );
}
