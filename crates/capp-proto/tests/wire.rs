//! The protocol's bytes, pinned: every message's payload, whole frames
//! (CRC-32 and COBS cross-checked with zlib and a reference COBS encoder),
//! round trips, and the accumulator fed byte by byte, in random chunks, with
//! garbage between frames.

use capp_proto::*;

fn payload<T: serde::Serialize>(m: &T) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME];
    postcard::to_slice(m, &mut buf).unwrap().to_vec()
}

/// Frames `m`, checks the frame decodes back to `m`, returns the payload.
fn check<T>(m: &T, expected_payload: &[u8])
where
    T: serde::Serialize + serde::de::DeserializeOwned + PartialEq + std::fmt::Debug,
{
    assert_eq!(payload(m), expected_payload, "payload of {m:?}");
    let mut frame = [0u8; MAX_FRAME];
    let n = encode(m, &mut frame).unwrap();
    assert_eq!(frame[n - 1], 0);
    assert!(!frame[..n - 1].contains(&0));
    let back: T = decode(&mut frame[..n - 1]).unwrap();
    assert_eq!(&back, m);
}

const ONE: [u8; 4] = [0x00, 0x00, 0x80, 0x3F]; // 1.0f32
const MINUS_ONE: [u8; 4] = [0x00, 0x00, 0x80, 0xBF];
const TWO: [u8; 4] = [0x00, 0x00, 0x00, 0x40];
const HALF: [u8; 4] = [0x00, 0x00, 0x00, 0x3F];
const ZERO: [u8; 4] = [0; 4];

fn cat(parts: &[&[u8]]) -> Vec<u8> {
    parts.concat()
}

#[test]
fn whole_frames_are_pinned() {
    // Ping { nonce: 1 }: body 0C 00 01, CRC-32 0x815C10E0 (zlib), COBS, 00.
    let mut f = [0u8; MAX_FRAME];
    let n = encode(&Command::Ping { nonce: 1 }, &mut f).unwrap();
    assert_eq!(
        &f[..n],
        &[0x02, 0x0c, 0x06, 0x01, 0xe0, 0x10, 0x5c, 0x81, 0x00]
    );
    // Ack { command: 8 }.
    let n = encode(&Reply::Ack { command: 8 }, &mut f).unwrap();
    assert_eq!(
        &f[..n],
        &[0x08, 0x0c, 0x01, 0x08, 0x05, 0x99, 0x9b, 0xe1, 0x00]
    );
    // Error { command: NO_COMMAND, code: Crc, index: NO_INDEX }.
    let e = Reply::Error {
        command: NO_COMMAND,
        code: ErrorCode::Crc,
        index: NO_INDEX,
    };
    let n = encode(&e, &mut f).unwrap();
    assert_eq!(
        &f[..n],
        &[0x0a, 0x0c, 0x02, 0xff, 0x01, 0xff, 0xb6, 0x38, 0x5a, 0x23, 0x00]
    );
}

#[test]
fn every_command_is_pinned() {
    check(
        &Command::Ping { nonce: 0x1234_5678 },
        &[0x00, 0xF8, 0xAC, 0xD1, 0x91, 0x01],
    );
    check(&Command::Clear(Part::All), &[0x01, 0x00]);
    check(&Command::Clear(Part::Robot), &[0x01, 0x01]);
    check(&Command::Clear(Part::Obstacles), &[0x01, 0x02]);
    check(&Command::Clear(Part::Waypoints), &[0x01, 0x03]);
    check(&Command::Clear(Part::Capsules), &[0x01, 0x04]);
    check(&Command::Clear(Part::Drives), &[0x01, 0x05]);
    check(&Command::Preset(Preset::Pips), &[0x02, 0x00]);
    let joint = Joint {
        kind: JointKind::Prismatic,
        alpha: 1.0,
        a: 0.0,
        theta: 0.5,
        d: 2.0,
        min: -1.0,
        max: 1.0,
        max_rate: 2.0,
        weight: 1.0,
        origin: None,
    };
    check(
        &Command::Joint { index: 3, joint },
        &cat(&[
            &[0x03, 0x03, 0x01],
            &ONE,
            &ZERO,
            &HALF,
            &TWO,
            &MINUS_ONE,
            &ONE,
            &TWO,
            &ONE,
            &[0x00],
        ]),
    );
    // A general (URDF) joint: revolute about its z, half a unit up from the
    // previous joint's frame, turned a quarter about z (rows 0 -1 0, 1 0 0,
    // 0 0 1); its DH fields are not used (zeros).
    let general = Joint {
        kind: JointKind::Revolute,
        alpha: 0.0,
        a: 0.0,
        theta: 0.0,
        d: 0.0,
        min: -1.0,
        max: 1.0,
        max_rate: 2.0,
        weight: 1.0,
        origin: Some(Origin {
            placement: Placement {
                rotation: [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
                translation: [0.0, 0.0, 0.5],
            },
            axis: [0.0, 0.0, 1.0],
        }),
    };
    check(
        &Command::Joint {
            index: 0,
            joint: general,
        },
        &cat(&[
            &[0x03, 0x00, 0x00],
            &ZERO,
            &ZERO,
            &ZERO,
            &ZERO,
            &MINUS_ONE,
            &ONE,
            &TWO,
            &ONE,
            &[0x01],
            &ZERO,
            &MINUS_ONE,
            &ZERO,
            &ONE,
            &ZERO,
            &ZERO,
            &ZERO,
            &ZERO,
            &ONE,
            &ZERO,
            &ZERO,
            &HALF,
            &ZERO,
            &ZERO,
            &ONE,
        ]),
    );
    // The tool: no rotation, two units along z.
    check(
        &Command::Tool(Placement {
            rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            translation: [0.0, 0.0, 2.0],
        }),
        &cat(&[
            &[0x0E],
            &ONE,
            &ZERO,
            &ZERO,
            &ZERO,
            &ONE,
            &ZERO,
            &ZERO,
            &ZERO,
            &ONE,
            &ZERO,
            &ZERO,
            &TWO,
        ]),
    );
    let obstacle = Obstacle {
        centre: [1.0, -1.0, 0.0],
        semi_axes: [2.0, 2.0, 0.5],
        exponents: [2.0, 2.0, 2.0],
        euler_123: [0.0, 0.0, 1.0],
        primitive: None,
    };
    check(
        &Command::Obstacle {
            index: 63,
            obstacle,
        },
        &cat(&[
            &[0x04, 0x3F],
            &ONE,
            &MINUS_ONE,
            &ZERO,
            &TWO,
            &TWO,
            &HALF,
            &TWO,
            &TWO,
            &TWO,
            &ZERO,
            &ZERO,
            &ONE,
            &[0x00],
        ]),
    );
    // A capsule (since version 10): the super-ellipsoid's fields zero, then
    // `Some` (1), the variant (2) and its radius and length.
    let capsule = Obstacle {
        centre: [1.0, -1.0, 0.0],
        semi_axes: [0.0; 3],
        exponents: [0.0; 3],
        euler_123: [0.0, 0.0, 1.0],
        primitive: Some(Primitive::Capsule {
            radius: 0.5,
            length: 2.0,
        }),
    };
    check(
        &Command::Obstacle {
            index: 2,
            obstacle: capsule,
        },
        &cat(&[
            &[0x04, 0x02],
            &ONE,
            &MINUS_ONE,
            &ZERO,
            &ZERO,
            &ZERO,
            &ZERO,
            &ZERO,
            &ZERO,
            &ZERO,
            &ZERO,
            &ZERO,
            &ONE,
            &[0x01, 0x02],
            &HALF,
            &TWO,
        ]),
    );
    // A convex obstacle (since version 11): `Some` (1), the variant (4)
    // and the hull's index.
    let convex = Obstacle {
        centre: [0.0; 3],
        semi_axes: [0.0; 3],
        exponents: [0.0; 3],
        euler_123: [0.0; 3],
        primitive: Some(Primitive::Convex { hull: 3 }),
    };
    check(
        &Command::Obstacle {
            index: 0,
            obstacle: convex,
        },
        &cat(&[&[0x04, 0x00], &[0; 48], &[0x01, 0x04, 0x03]]),
    );
    // A hull (since version 11): the command (15), its index, the vertex
    // count, then x, y, z of each vertex.
    let tetrahedron =
        HullVertices::from_slice(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 0.5]])
            .unwrap();
    check(
        &Command::Hull {
            index: 1,
            vertices: tetrahedron,
        },
        &cat(&[
            &[0x0f, 0x01, 0x04],
            &[0; 12],
            &ONE,
            &ZERO,
            &ZERO,
            &ZERO,
            &TWO,
            &ZERO,
            &ZERO,
            &ZERO,
            &HALF,
        ]),
    );
    // The largest hull fits a frame.
    let largest = Command::Hull {
        index: 7,
        vertices: HullVertices::from_slice(&[[1.0e4, -1.0e4, 3.5e3]; MAX_HULL_VERTICES]).unwrap(),
    };
    let mut frame = [0u8; MAX_FRAME];
    assert!(encode(&largest, &mut frame).is_ok());
    check(
        &Command::Waypoint {
            index: 1,
            waypoint: Waypoint {
                position: [1.0, 2.0, 0.5],
                orientation: None,
            },
        },
        &cat(&[&[0x05, 0x01], &ONE, &TWO, &HALF, &[0x00]]),
    );
    check(
        &Command::Waypoint {
            index: 0,
            waypoint: Waypoint {
                position: [0.0, 0.0, 0.0],
                orientation: Some([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
            },
        },
        &cat(&[
            &[0x05, 0x00],
            &ZERO,
            &ZERO,
            &ZERO,
            &[0x01],
            &ONE,
            &ZERO,
            &ZERO,
            &ZERO,
            &ONE,
            &ZERO,
            &ZERO,
            &ZERO,
            &ONE,
        ]),
    );
    let settings = Settings {
        time_step_s: 0.05,
        fine_radius: 1.0,
        fine_step_fraction: 0.25,
        position_tolerance: 0.1,
        orientation_tolerance: 0.05,
        law: LawKind::DampedLeastSquares,
        orientation_scale: 10.0,
        approach_radius: 2.0,
        joint_margin: 6.0,
        link_margin: 3.0,
        points_per_link: 1,
        influence_distance: 24.0,
        engage_clearance: 1.0,
        advance_fraction: 1.0,
        damping: 1.0e-3,
        max_steps: 20_000,
        stall_window: 400,
        stall_progress: 0.01,
        max_halvings: 8,
        escape_attempts: 64,
        escape_window: 20,
        escape_walk_steps: 200,
        escape_reach: 0.5,
        escape_seed: 0x2545_F491,
        escape_searches: 4,
        saturation: true,
        tracked: false,
    };
    check(
        &Command::Settings(settings),
        &[
            0x06, //
            0xCD, 0xCC, 0x4C, 0x3D, // 0.05
            0x00, 0x00, 0x80, 0x3F, // 1.0
            0x00, 0x00, 0x80, 0x3E, // 0.25
            0xCD, 0xCC, 0xCC, 0x3D, // 0.1
            0xCD, 0xCC, 0x4C, 0x3D, // 0.05
            0x02, // DampedLeastSquares
            0x00, 0x00, 0x20, 0x41, // 10.0
            0x00, 0x00, 0x00, 0x40, // 2.0
            0x00, 0x00, 0xC0, 0x40, // 6.0
            0x00, 0x00, 0x40, 0x40, // 3.0
            0x01, // points_per_link
            0x00, 0x00, 0xC0, 0x41, // 24.0
            0x00, 0x00, 0x80, 0x3F, // 1.0
            0x00, 0x00, 0x80, 0x3F, // 1.0
            0x6F, 0x12, 0x83, 0x3A, // 0.001
            0xA0, 0x9C, 0x01, // 20000
            0x90, 0x03, // 400
            0x0A, 0xD7, 0x23, 0x3C, // 0.01
            0x08, // max_halvings
            0x40, // escape_attempts 64
            0x14, // escape_window 20
            0xC8, 0x01, // escape_walk_steps 200
            0x00, 0x00, 0x00, 0x3F, // 0.5
            0x91, 0xE9, 0x97, 0xAA, 0x02, // 0x2545F491
            0x04, // escape_searches 4
            0x01, // saturation
            0x00, // tracked
        ],
    );
    #[cfg(feature = "core")]
    check(
        &Command::Settings(settings),
        &payload(&Command::Settings(capp_core_settings_default())),
    );
    check(
        &Command::Start(Joints::from_slice(&[0.5, -1.0]).unwrap()),
        &cat(&[&[0x07, 0x02], &HALF, &MINUS_ONE]),
    );
    check(
        &Command::Run {
            every: 300,
            error_change: None,
        },
        &[0x08, 0xAC, 0x02, 0x00],
    );
    check(
        &Command::Run {
            every: 1,
            error_change: Some(ErrorChange {
                position: 1.0,
                orientation: 0.1,
            }),
        },
        &cat(&[&[0x08, 0x01, 0x01], &ONE, &[0xCD, 0xCC, 0xCC, 0x3D]]),
    );
    check(&Command::Stop, &[0x09]);
    check(&Command::Status, &[0x0A]);
    check(
        &Command::JointWaypoint {
            index: 2,
            joints: Joints::from_slice(&[0.5, -1.0]).unwrap(),
        },
        &cat(&[&[0x0B, 0x02, 0x02], &HALF, &MINUS_ONE]),
    );
    // Link 2's capsule, radius 1.5, checked against links 4 and 31: the row
    // 0x8000_0010 as a varint.
    check(
        &Command::Capsule {
            index: 2,
            capsule: Capsule {
                radius: 1.5,
                checked: (1 << 4) | (1 << 31),
                segment: None,
            },
        },
        &[
            0x0C, 0x02, 0x00, 0x00, 0xC0, 0x3F, 0x90, 0x80, 0x80, 0x80, 0x08, 0x00,
        ],
    );
    // Round a segment of its own (since version 12): from (0.5, 0, 0) to
    // (0, 0, -1), after the row.
    check(
        &Command::Capsule {
            index: 2,
            capsule: Capsule {
                radius: 1.5,
                checked: 0,
                segment: Some([[0.5, 0.0, 0.0], [0.0, 0.0, -1.0]]),
            },
        },
        &cat(&[
            &[0x0C, 0x02, 0x00, 0x00, 0xC0, 0x3F, 0x00, 0x01],
            &HALF,
            &[0; 4],
            &[0; 4],
            &[0; 4],
            &[0; 4],
            &MINUS_ONE,
        ]),
    );
    // No pair: one byte.
    check(
        &Command::Capsule {
            index: 31,
            capsule: Capsule {
                radius: 1.5,
                checked: 0,
                segment: None,
            },
        },
        &[0x0C, 0x1F, 0x00, 0x00, 0xC0, 0x3F, 0x00, 0x00],
    );
    // Joint 3's drive: 0.5 per second squared, 2.0 per second cubed.
    check(
        &Command::Drive {
            index: 3,
            drive: Drive {
                max_accel: 0.5,
                max_jerk: 2.0,
            },
        },
        &cat(&[&[0x0D, 0x03], &HALF, &[0x00, 0x00, 0x00, 0x40]]),
    );
}

/// capp-core's defaults, through the `core` conversion: the same bytes as above.
#[cfg(feature = "core")]
fn capp_core_settings_default() -> Settings {
    capp_core::Settings::default().into()
}

#[test]
fn every_reply_is_pinned() {
    check(
        &Reply::Pong {
            nonce: 7,
            version: VERSION,
            max_joints: 32,
            max_obstacles: 64,
            max_waypoints: 16,
        },
        &[0x00, 0x07, 0x0c, 0x20, 0x40, 0x10],
    );
    check(&Reply::Ack { command: 8 }, &[0x01, 0x08]);
    for (i, code) in [
        ErrorCode::Framing,
        ErrorCode::Crc,
        ErrorCode::Version,
        ErrorCode::UnknownMessage,
        ErrorCode::Overfull,
        ErrorCode::NotFinite,
        ErrorCode::OutOfOrder,
        ErrorCode::Capacity,
        ErrorCode::InvalidRobot,
        ErrorCode::InvalidObstacle,
        ErrorCode::InvalidMission,
        ErrorCode::InvalidStart,
        ErrorCode::Busy,
        ErrorCode::NotRunning,
        ErrorCode::InvalidCapsules,
        ErrorCode::InvalidDrive,
        ErrorCode::InvalidHull,
    ]
    .into_iter()
    .enumerate()
    {
        check(
            &Reply::Error {
                command: 3,
                code,
                index: 5,
            },
            &[0x02, 0x03, i as u8, 0x05],
        );
    }
    check(
        &Reply::Setpoint {
            seq: 128,
            step: 129,
            joints: Joints::from_slice(&[1.0, 0.5]).unwrap(),
            time_s: 2.0,
            waypoint: 1,
            velocity: Joints::from_slice(&[-1.0, 0.0]).unwrap(),
            acceleration: Joints::from_slice(&[2.0, 0.5]).unwrap(),
        },
        &cat(&[
            &[0x03, 0x80, 0x01, 0x81, 0x01, 0x02],
            &ONE,
            &HALF,
            &TWO,
            &[0x01],
            // Since version 7: the velocities, then the accelerations.
            &[0x02],
            &MINUS_ONE,
            &ZERO,
            &[0x02],
            &TWO,
            &HALF,
        ]),
    );
    let status = Status {
        state: State::Done,
        outcome: Some(Outcome::Stalled),
        step: 300,
        v: 0.5,
        position_error: 1.0,
        orientation_error: 2.0,
        clearance: Some(-1.0),
        setpoints: 3,
        dropped: 1,
        rx_errors: 2,
        overruns: 0,
        stack_peak: 128,
        rx_overflows: 5,
        step_cycles_min: 1,
        step_cycles_mean: 300,
        step_cycles_max: 20_000,
        escape: EscapeMode::Detouring,
        escape_attempt: 3,
        period_overruns: 300,
    };
    check(
        &Reply::Status(status),
        &cat(&[
            &[0x04, 0x02, 0x01, 0x01, 0xAC, 0x02],
            &HALF,
            &ONE,
            &TWO,
            &[0x01],
            &MINUS_ONE,
            &[0x03, 0x01, 0x02, 0x00, 0x80, 0x01],
            &[0x05, 0x01, 0xAC, 0x02, 0xA0, 0x9C, 0x01],
            &[0x02, 0x03],
            // Since version 7: period_overruns.
            &[0xAC, 0x02],
        ]),
    );
    // The escape modes of version 4: searching (4) and following (5).
    for (mode, tag) in [(EscapeMode::Searching, 0x04), (EscapeMode::Following, 0x05)] {
        let s = Status {
            escape: mode,
            ..status
        };
        check(
            &Reply::Status(s),
            &cat(&[
                &[0x04, 0x02, 0x01, 0x01, 0xAC, 0x02],
                &HALF,
                &ONE,
                &TWO,
                &[0x01],
                &MINUS_ONE,
                &[0x03, 0x01, 0x02, 0x00, 0x80, 0x01],
                &[0x05, 0x01, 0xAC, 0x02, 0xA0, 0x9C, 0x01],
                &[tag, 0x03],
                &[0xAC, 0x02],
            ]),
        );
    }
    let idle = Status {
        state: State::Idle,
        outcome: None,
        clearance: None,
        ..status
    };
    check(
        &Reply::Status(idle),
        &cat(&[
            &[0x04, 0x00, 0x00, 0xAC, 0x02],
            &HALF,
            &ONE,
            &TWO,
            &[0x00],
            &[0x03, 0x01, 0x02, 0x00, 0x80, 0x01],
            &[0x05, 0x01, 0xAC, 0x02, 0xA0, 0x9C, 0x01],
            &[0x02, 0x03],
            &[0xAC, 0x02],
        ]),
    );
    for (i, s) in [State::Idle, State::Running, State::Done, State::Stopped]
        .into_iter()
        .enumerate()
    {
        assert_eq!(
            payload(&Reply::Status(Status { state: s, ..idle }))[1],
            i as u8
        );
    }
}

#[test]
fn the_largest_messages_fit_a_frame() {
    let full = Joints::from_slice(&[f32::MAX; MAX_JOINTS]).unwrap();
    let mut f = [0u8; MAX_FRAME];
    let m = Reply::Setpoint {
        seq: u32::MAX,
        step: u32::MAX,
        joints: full.clone(),
        time_s: f32::MAX,
        waypoint: u8::MAX,
        velocity: full.clone(),
        acceleration: full.clone(),
    };
    let n = encode(&m, &mut f).unwrap();
    // 403 payload bytes, 408 of body, one COBS block of 254 and one of 154,
    // the delimiter (PROTOCOL.md, section 1).
    assert_eq!(n, 411);
    assert!(n <= MAX_FRAME);
    let n = encode(&Command::Start(full), &mut f).unwrap();
    assert!(n <= MAX_FRAME);
    // Every reply but a setpoint fits 256 bytes (capp-node keeps 512 bytes
    // of its transmit queue for two of them): the largest is a status.
    let status = Status {
        state: State::Stopped,
        outcome: Some(Outcome::Capped),
        step: u32::MAX,
        v: f32::MAX,
        position_error: f32::MAX,
        orientation_error: f32::MAX,
        clearance: Some(f32::MAX),
        setpoints: u32::MAX,
        dropped: u32::MAX,
        rx_errors: u32::MAX,
        overruns: u32::MAX,
        stack_peak: u32::MAX,
        rx_overflows: u32::MAX,
        step_cycles_min: u32::MAX,
        step_cycles_mean: u32::MAX,
        step_cycles_max: u32::MAX,
        escape: EscapeMode::Following,
        escape_attempt: u8::MAX,
        period_overruns: u32::MAX,
    };
    for reply in [
        Reply::Status(status),
        Reply::Pong {
            nonce: u32::MAX,
            version: VERSION,
            max_joints: u8::MAX,
            max_obstacles: u8::MAX,
            max_waypoints: u8::MAX,
        },
        Reply::Error {
            command: u8::MAX,
            code: ErrorCode::InvalidCapsules,
            index: u8::MAX,
        },
    ] {
        let n = encode(&reply, &mut f).unwrap();
        assert!(n <= 256, "{reply:?}: {n} bytes");
    }
    let capsule = Command::Capsule {
        index: u8::MAX,
        capsule: Capsule {
            radius: f32::MAX,
            checked: u64::MAX,
            segment: Some([[f32::MAX; 3]; 2]),
        },
    };
    let n = encode(&capsule, &mut f).unwrap();
    assert!(n <= MAX_FRAME);
    // The largest joint: a general one (96 payload bytes: its `Joint` is 94).
    let m = f32::MAX;
    let general = Command::Joint {
        index: u8::MAX,
        joint: Joint {
            kind: JointKind::Prismatic,
            alpha: m,
            a: m,
            theta: m,
            d: m,
            min: m,
            max: m,
            max_rate: m,
            weight: m,
            origin: Some(Origin {
                placement: Placement {
                    rotation: [[m; 3]; 3],
                    translation: [m; 3],
                },
                axis: [m; 3],
            }),
        },
    };
    assert_eq!(payload(&general).len(), 96);
    let n = encode(&general, &mut f).unwrap();
    assert!(n <= 256, "{n} bytes");
    // Too many joints for the wire: 33 values do not decode.
    let mut body = vec![VERSION, 0x07, 33];
    body.extend(std::iter::repeat_n(0x3Fu8, 33 * 4));
    let mut raw = raw_frame(&body);
    let len = raw.len() - 1;
    assert_eq!(decode::<Command>(&mut raw[..len]), Err(FrameError::Message));
}

fn raw_frame(body: &[u8]) -> Vec<u8> {
    framed_with_crc(body, crc::crc32(body))
}

/// `body` and the CRC-32 `crc`, COBS-encoded and terminated.
fn framed_with_crc(body: &[u8], crc: u32) -> Vec<u8> {
    let mut b = body.to_vec();
    b.extend_from_slice(&crc.to_le_bytes());
    let mut out = vec![0u8; cobs::max_encoded_len(b.len())];
    let n = cobs::encode(&b, &mut out).unwrap();
    out.truncate(n);
    out.push(0);
    out
}

#[test]
fn bad_frames_are_reported_not_decoded() {
    // CRC: a whole Run frame whose CRC has one bit flipped.
    let run = Command::Run {
        every: 1,
        error_change: None,
    };
    let body = cat(&[&[VERSION], &payload(&run)]);
    let mut bad = framed_with_crc(&body, crc::crc32(&body) ^ 0x0100);
    let l = bad.len() - 1;
    assert_eq!(decode::<Command>(&mut bad[..l]), Err(FrameError::Crc));
    let mut good = raw_frame(&body);
    let l = good.len() - 1;
    assert_eq!(decode::<Command>(&mut good[..l]), Ok(run));
    // Version.
    let mut v1 = raw_frame(&[1, 0x08, 0x01, 0x00]);
    let l = v1.len() - 1;
    assert_eq!(
        decode::<Command>(&mut v1[..l]),
        Err(FrameError::Version { got: 1 })
    );
    // Unknown variant, trailing bytes, truncated payload.
    for body in [
        &[VERSION, 11][..],
        &[VERSION, 13],
        &[VERSION, 14, 0, 0],
        &[VERSION, 15],
        &[VERSION, 9, 0],
        &[VERSION, 8],
        &[VERSION, 12, 0, 0, 0, 0xC0],
    ] {
        let mut r = raw_frame(body);
        let l = r.len() - 1;
        assert_eq!(
            decode::<Command>(&mut r[..l]),
            Err(FrameError::Message),
            "{body:?}"
        );
    }
    // Short and malformed COBS.
    assert_eq!(decode::<Command>(&mut [0x02, 0x01]), Err(FrameError::Cobs));
    assert_eq!(decode::<Command>(&mut [0x09, 0x01]), Err(FrameError::Cobs));
}

/// xorshift32: a deterministic source for the chunk sizes and the garbage.
struct Rng(u32);
impl Rng {
    fn next(&mut self) -> u32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 17;
        self.0 ^= self.0 << 5;
        self.0
    }
}

fn sample_commands() -> Vec<Command> {
    let mut v = vec![
        Command::Ping { nonce: 0 },
        Command::Clear(Part::All),
        Command::Preset(Preset::Pips),
        Command::Clear(Part::Obstacles),
        Command::Start(Joints::from_slice(&[0.0; 32]).unwrap()),
        Command::Run {
            every: 10,
            error_change: None,
        },
        Command::Stop,
        Command::Status,
    ];
    for i in 0..18u8 {
        v.push(Command::Capsule {
            index: i,
            capsule: Capsule {
                radius: 1.5,
                checked: !((2u64 << i) - 1) & ((1 << 18) - 1),
                segment: (i % 2 == 1).then_some([[0.25, -0.5, 1.0], [0.0, 2.0, -0.125]]),
            },
        });
    }
    for i in 0..18u8 {
        v.push(Command::Drive {
            index: i,
            drive: Drive {
                max_accel: 0.4 + i as f32,
                max_jerk: 4.0 * (i as f32 + 1.0),
            },
        });
    }
    for i in 0..18u8 {
        let x = i as f32;
        v.push(Command::Joint {
            index: i,
            joint: Joint {
                kind: JointKind::Revolute,
                alpha: x * 0.1,
                a: -x,
                theta: 0.0,
                d: 1.0 / (x + 1.0),
                min: -1.5,
                max: 1.5,
                max_rate: 0.2,
                weight: 1.0,
                origin: (i % 2 == 1).then_some(Origin {
                    placement: Placement {
                        rotation: [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]],
                        translation: [x, 0.0, -0.25],
                    },
                    axis: [0.0, 1.0, 0.0],
                }),
            },
        });
    }
    v.push(Command::Tool(Placement {
        rotation: [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
        translation: [0.1, -0.2, 0.3],
    }));
    v
}

#[test]
fn accumulator_byte_by_byte_and_in_random_chunks_with_garbage() {
    let commands = sample_commands();
    let mut rng = Rng(0x1234_5678);
    for round in 0..50 {
        // The stream: each frame, then garbage that ends with a delimiter.
        let mut stream = Vec::new();
        let mut garbage_frames = 0;
        for c in &commands {
            let mut f = [0u8; MAX_FRAME];
            let n = encode(c, &mut f).unwrap();
            stream.extend_from_slice(&f[..n]);
            if round > 0 && rng.next() & 1 == 0 {
                let len = 1 + rng.next() % 400;
                for _ in 0..len {
                    stream.push((rng.next() % 255) as u8 + 1);
                }
                stream.push(0);
                garbage_frames += 1;
            }
        }
        let mut acc = Accumulator::<{ MAX_FRAME - 1 }>::new();
        let mut got = Vec::new();
        let mut errors = 0;
        let mut i = 0;
        while i < stream.len() {
            // Round 0: byte by byte; then chunks of 1 to 64 bytes.
            let chunk = if round == 0 {
                1
            } else {
                1 + rng.next() as usize % 64
            };
            for &b in &stream[i..(i + chunk).min(stream.len())] {
                match acc.feed_message::<Command>(b) {
                    None => {}
                    Some(Ok(c)) => got.push(c),
                    Some(Err(_)) => errors += 1,
                }
            }
            i += chunk;
        }
        assert_eq!(got, commands, "round {round}");
        assert_eq!(errors, garbage_frames, "round {round}");
    }
}

#[test]
fn accumulator_overfull_recovers_at_the_next_delimiter() {
    let mut acc = Accumulator::<16>::new();
    for _ in 0..40 {
        assert_eq!(acc.feed(0x55), Feed::Consumed);
    }
    assert_eq!(acc.feed(0), Feed::Overfull);
    assert_eq!(acc.feed(0), Feed::Consumed); // an empty frame is ignored
    let mut f = [0u8; 16];
    let n = encode(&Command::Stop, &mut f).unwrap();
    let mut out = None;
    for &b in &f[..n] {
        if let Some(r) = acc.feed_message::<Command>(b) {
            out = Some(r);
        }
    }
    assert_eq!(out, Some(Ok(Command::Stop)));
}

#[test]
fn random_bytes_never_panic() {
    let mut rng = Rng(42);
    let mut acc = Accumulator::<{ MAX_FRAME - 1 }>::new();
    for _ in 0..200_000 {
        let b = (rng.next() % 256) as u8;
        let _ = acc.feed_message::<Command>(if b < 8 { 0 } else { b });
        let _ = acc.feed_message::<Reply>(b);
    }
}
