//! Round trips of every message variant, byte layouts checked against the C++ sources,
//! malformed input, and a randomized decode/encode consistency sweep.

use super::*;
use crate::frame::CanFrame;

fn every_mc_command() -> Vec<McCommand> {
    use McCommand::*;
    let mut v = vec![
        ControllerRun,
        ControllerIdle,
        CalibrateEncoder {
            kind: 3,
            p1: -2,
            p2: 300,
            p3: i16::MIN,
        },
        EnablePwm,
        DisablePwm,
        GetControlMode,
        MotionDone,
        SetControlMode(ControlMode::Velocity),
        SetControlMode(ControlMode::Other(0x42)),
        SetSpeedEstimShift {
            jnt_vel: 5,
            jnt_acc: 5,
            mot_vel: 1,
            mot_acc: 1,
        },
        GetEncoderPosition,
        PositionMove {
            position: -123_456,
            speed: 250,
        },
        VelocityMove {
            speed: -700,
            accel: 1,
        },
        SetEncoderPosition(42),
        SetDesiredTorque(-1234),
        GetDesiredTorque,
        StopTrajectory,
        SetPwmLimit(1333),
        GetPwmLimit,
        SetCommandPosition(i32::MAX),
        SetMinPosition(i32::MIN),
        GetMinPosition,
        SetMaxPosition(99),
        GetMaxPosition,
        SetMaxVelocity(-1),
        GetMaxVelocity,
        SetCurrentLimit(7000),
        SetBcastPolicy(0x0000_008E),
        SetVelShift(8),
        SetVelTimeout(100),
        SetImpedanceParams {
            stiffness: 10,
            damping: -3,
        },
        GetImpedanceParams,
        SetImpedanceOffset(-300),
        GetImpedanceOffset,
        GetFirmwareVersion {
            proto_major: 1,
            proto_minor: 6,
        },
        SetInteractionMode(1),
        GetInteractionMode,
    ];
    for k in PidKind::ALL {
        v.push(SetPid(
            k,
            Pid {
                kp: 32000,
                ki: -60,
                kd: 50,
                shift: 13,
            },
        ));
        v.push(GetPid(k));
        v.push(SetPidLimits(
            k,
            PidLimits {
                offset: -5,
                max_output: 800,
                max_integral: 1333,
            },
        ));
        v.push(GetPidLimits(k));
    }
    v
}

fn every_mc_reply() -> Vec<McReply> {
    use McReply::*;
    let mut v = vec![
        ControlMode(super::ControlMode::Torque),
        MotionDone(true),
        MotionDone(false),
        EncoderPosition(-5),
        DesiredTorque(77),
        PwmLimit(800),
        MinPosition(-1000),
        MaxPosition(1000),
        MaxVelocity(300),
        ImpedanceParams {
            stiffness: 1,
            damping: 2,
        },
        ImpedanceOffset(-7),
        FirmwareVersion(mc::FirmwareInfo {
            board_type: 3,
            version: 1,
            release: 2,
            build: 3,
            proto_major: 1,
            proto_minor: 6,
            compatible: true,
        }),
        InteractionMode(0),
    ];
    for k in PidKind::ALL {
        v.push(Pid(
            k,
            super::Pid {
                kp: 1,
                ki: 2,
                kd: 3,
                shift: 4,
            },
        ));
        v.push(PidLimits(
            k,
            super::PidLimits {
                offset: 1,
                max_output: 2,
                max_integral: 3,
            },
        ));
    }
    v
}

fn every_message() -> Vec<Message> {
    let mut v = Vec::new();
    for (i, cmd) in every_mc_command().into_iter().enumerate() {
        v.push(Message::McRequest {
            src: 0,
            dst: 1 + (i % 14) as u8,
            axis: (i % 2) as u8,
            cmd,
        });
    }
    for (i, reply) in every_mc_reply().into_iter().enumerate() {
        v.push(Message::McReply {
            src: 1 + (i % 14) as u8,
            dst: 0,
            axis: (i % 2) as u8,
            reply,
        });
    }
    let status = BoardStatus {
        axis_faults: [0x08, 0],
        control_mode: [ControlMode::Position, ControlMode::Idle],
        can_status: 0x02,
        board_status: 1,
        can_tx_errors: 3,
        can_rx_errors: 4,
    };
    for msg in [
        McPeriodic::Position([1, -2]),
        McPeriodic::PidValue([3, -4]),
        McPeriodic::Status(status),
        McPeriodic::Current([5, 6]),
        McPeriodic::Overflow,
        McPeriodic::Print(Payload::new(b"hello")),
        McPeriodic::Velocity {
            speed: [1, 2],
            accel: [3, 4],
        },
        McPeriodic::PidError {
            position: [-1, -2],
            torque: [-3, -4],
        },
        McPeriodic::MotorPosition([i32::MIN, i32::MAX]),
        McPeriodic::MotorSpeed {
            speed: [9, 8],
            accel: [7, 6],
        },
        McPeriodic::AdditionalStatus {
            interaction: [1, 0],
        },
    ] {
        v.push(Message::McPeriodic { board: 5, msg });
    }
    for cmd in [
        AsCommand::SetMatrixRc {
            row: 5,
            col: 4,
            value: -12345,
        },
        AsCommand::SetTxMode(analog::txmode::RAW),
        AsCommand::SetCanDataRate(1),
        AsCommand::SaveToEeprom,
        AsCommand::GetMatrixRc { row: 1, col: 2 },
        AsCommand::SetCalibTare(TareOp::Reset),
        AsCommand::SetCalibTare(TareOp::UseCurrent),
        AsCommand::SetCalibTare(TareOp::Set {
            channel: 3,
            value: 0x8001,
        }),
        AsCommand::SetFullScale {
            channel: 2,
            value: 1500,
        },
        AsCommand::GetFullScale { channel: 5 },
        AsCommand::SkinTactSetup([1, 1, 1, 0, 0x20, 0, 0]),
        AsCommand::SkinSetBoardCfg {
            skin_type: 1,
            period: 50,
            no_load: 0xF0,
        },
        AsCommand::SkinTactSetup2([2, 0x22, 0xF0, 0, 0xFF, 0xFF, 0x0A]),
        AsCommand::AccGyroSetup {
            sensors: 0x0C,
            period: 10,
        },
        AsCommand::SkinSetTriangleCfg {
            start: 0,
            end: 15,
            shift: 2,
            flags: 1,
            cdc_offset: 0x2200,
        },
    ] {
        v.push(Message::AsRequest {
            src: 0,
            dst: 13,
            cmd,
        });
    }
    for reply in [
        AsReply::FullScale {
            channel: 1,
            value: 0xABCD,
        },
        AsReply::MatrixRc {
            row: 0,
            col: 5,
            value: -1,
        },
    ] {
        v.push(Message::AsReply {
            src: 13,
            dst: 0,
            reply,
        });
    }
    for msg in [
        AsPeriodic::vector(VectorKind::Force, [-32768, 0, 32767]),
        AsPeriodic::vector(VectorKind::Torque, [1, 2, 3]),
        AsPeriodic::Vector {
            kind: VectorKind::UncalibForce,
            raw: [1, 2, 3],
            saturation: Some(1),
        },
        AsPeriodic::Vector {
            kind: VectorKind::UncalibTorque,
            raw: [4, 5, 6],
            saturation: None,
        },
        AsPeriodic::Hes0To6([1, 2, 3, 4, 5, 6, 7]),
        AsPeriodic::Hes7To14([8, 9, 10, 11, 12, 13, 14, 15]),
    ] {
        v.push(Message::AsPeriodic { board: 14, msg });
    }
    v.push(Message::Skin {
        board: 8,
        msg: SkinFrame::head(3, [255, 254, 253, 252, 251, 250, 249]),
    });
    v.push(Message::Skin {
        board: 8,
        msg: SkinFrame::tail(15, [1, 2, 3, 4, 5]),
    });
    v.push(Message::Inertial {
        board: 14,
        msg: InertialMsg::Gyroscope([-1, 0, 1]),
    });
    v.push(Message::Inertial {
        board: 14,
        msg: InertialMsg::Accelerometer([100, -200, 300]),
    });
    v
}

#[test]
fn every_variant_round_trips() {
    let all = every_message();
    assert!(all.len() > 90, "{} messages", all.len());
    for m in all {
        let frame = m.encode();
        let back = Message::decode(&frame).unwrap_or_else(|e| panic!("{m:?} -> {frame}: {e}"));
        assert_eq!(back, m, "frame {frame}");
        assert_eq!(back.encode(), frame);
    }
}

#[test]
fn byte_layouts_match_the_cpp_driver() {
    // positionMove on joint 1 of board 3: id 0x003, data[0] = 0x80 | 27, pos LE, speed LE.
    let f = Message::McRequest {
        src: 0,
        dst: 3,
        axis: 1,
        cmd: McCommand::PositionMove {
            position: 0x0102_0304,
            speed: 0x0506,
        },
    }
    .encode();
    assert_eq!(f.id(), 0x003);
    assert_eq!(f.data(), &[0x80 | 27, 4, 3, 2, 1, 6, 5]);
    // Position broadcast of board 2: id 0x121, two int32 LE.
    let f = Message::McPeriodic {
        board: 2,
        msg: McPeriodic::Position([1, -1]),
    }
    .encode();
    assert_eq!(f.id(), 0x121);
    assert_eq!(f.data(), &[1, 0, 0, 0, 0xFF, 0xFF, 0xFF, 0xFF]);
    // Torque setpoint: 16-bit value sign-extended to 32 bits.
    let f = Message::McRequest {
        src: 0,
        dst: 1,
        axis: 0,
        cmd: McCommand::SetDesiredTorque(-2),
    }
    .encode();
    assert_eq!(f.data(), &[44, 0xFE, 0xFF, 0xFF, 0xFF]);
    // Strain: start streaming calibrated data (0x200 + board, 0x07 0x00).
    let f = Message::AsRequest {
        src: 0,
        dst: 0xD,
        cmd: AsCommand::SetTxMode(0),
    }
    .encode();
    assert_eq!((f.id(), f.data()), (0x20D, &[7u8, 0][..]));
    // Full scale reply: id 0x200 | board << 4, big-endian value.
    let f = Message::AsReply {
        src: 0xD,
        dst: 0,
        reply: AsReply::FullScale {
            channel: 2,
            value: 0x1234,
        },
    }
    .encode();
    assert_eq!((f.id(), f.data()), (0x2D0, &[0x18u8, 2, 0x12, 0x34][..]));
    // Force vector: 0x300 + board << 4 + 0xA, values + 0x8000 LE.
    let f = Message::AsPeriodic {
        board: 0xD,
        msg: AsPeriodic::vector(VectorKind::Force, [0, 1, -1]),
    }
    .encode();
    assert_eq!(
        (f.id(), f.data()),
        (0x3DA, &[0, 0x80, 1, 0x80, 0xFF, 0x7F][..])
    );
    // MTB accelerometer: 0x500 + board << 4 + 1.
    let f = Message::Inertial {
        board: 0xE,
        msg: InertialMsg::Accelerometer([1, 2, 3]),
    }
    .encode();
    assert_eq!((f.id(), f.data()), (0x5E1, &[1u8, 0, 2, 0, 3, 0][..]));
    // Inertial setup as CanBusInertialMTB sends it.
    let f = Message::AsRequest {
        src: 0,
        dst: 0xE,
        cmd: AsCommand::AccGyroSetup {
            sensors: 0x0C,
            period: 10,
        },
    }
    .encode();
    assert_eq!((f.id(), f.data()), (0x20E, &[0x4Fu8, 0x0C, 10][..]));
}

#[test]
fn impedance_byte_layouts_match_can_bus_motion_control() {
    // setImpedanceRaw: 8 bytes, opcode 87, stiffness and damping·1000 LE, then zeros.
    let f = Message::McRequest {
        src: 0,
        dst: 5,
        axis: 1,
        cmd: McCommand::SetImpedanceParams {
            stiffness: 0x0102,
            damping: -2,
        },
    }
    .encode();
    assert_eq!(f.id(), 0x005);
    assert_eq!(f.data(), &[0x80 | 87, 2, 1, 0xFE, 0xFF, 0, 0, 0]);
    // setImpedanceOffsetRaw: 3 bytes, opcode 89, the offset LE.
    let req = Message::McRequest {
        src: 0,
        dst: 5,
        axis: 0,
        cmd: McCommand::SetImpedanceOffset(-300),
    };
    let f = req.encode();
    assert_eq!(f.data(), &[89, 0xD4, 0xFE]);
    assert_eq!(Message::decode(&f), Ok(req));
    // getImpedanceOffsetRaw: 1-byte request (90), the reply's data[1..3] is the offset.
    let f = Message::McRequest {
        src: 0,
        dst: 5,
        axis: 1,
        cmd: McCommand::GetImpedanceOffset,
    }
    .encode();
    assert_eq!(f.data(), &[0x80 | 90]);
    let reply = Message::McReply {
        src: 5,
        dst: 0,
        axis: 1,
        reply: McReply::ImpedanceOffset(0x1234),
    };
    let f = reply.encode();
    assert_eq!((f.id(), f.data()), (0x050, &[0x80 | 90, 0x34, 0x12][..]));
    assert_eq!(Message::decode(&f), Ok(reply));
    // getImpedanceRaw: data[1..3] stiffness, data[3..5] damping·1000.
    let f = frame(0x050, &[88, 10, 0, 0xE8, 0x03]);
    assert_eq!(
        Message::decode(&f),
        Ok(Message::McReply {
            src: 5,
            dst: 0,
            axis: 0,
            reply: McReply::ImpedanceParams {
                stiffness: 10,
                damping: 1000
            }
        })
    );
    // Too short an offset command is an error, not a guess.
    assert!(Message::decode(&frame(0x005, &[89, 1])).is_err());
}

fn frame(id: u16, data: &[u8]) -> CanFrame {
    CanFrame::new(id, data).unwrap()
}

#[test]
fn malformed_frames_are_errors() {
    type Check = fn(&ProtoError) -> bool;
    let cases: Vec<(CanFrame, Check)> = vec![
        (CanFrame::new_extended(0x100, &[]).unwrap(), |e| {
            *e == ProtoError::Extended
        }),
        (CanFrame::new_remote(0x101, false, 8).unwrap(), |e| {
            *e == ProtoError::NotData
        }),
        (frame(0x600, &[1]), |e| *e == ProtoError::UnknownClass(6)),
        (frame(0x700, &[1]), |e| *e == ProtoError::UnknownClass(7)),
        (frame(0x001, &[]), |e| *e == ProtoError::NoOpcode),
        (frame(0x001, &[0x7F]), |e| {
            matches!(e, ProtoError::Unknown { code: 0x7F, .. })
        }),
        (frame(0x001, &[27, 1, 2]), |e| {
            matches!(e, ProtoError::Length { .. })
        }),
        (frame(0x010, &[20, 1]), |e| {
            matches!(e, ProtoError::Length { .. })
        }),
        (frame(0x010, &[1]), |e| {
            matches!(e, ProtoError::Unknown { .. })
        }),
        (frame(0x111, &[1, 2, 3]), |e| {
            matches!(e, ProtoError::Length { .. })
        }),
        (frame(0x11F, &[]), |e| {
            matches!(e, ProtoError::Unknown { code: 0xF, .. })
        }),
        (frame(0x20D, &[]), |e| *e == ProtoError::NoOpcode),
        (frame(0x20D, &[0x13, 9]), |e| {
            matches!(e, ProtoError::Value { .. })
        }),
        (frame(0x20D, &[0x77]), |e| {
            matches!(e, ProtoError::Unknown { .. })
        }),
        (frame(0x2D0, &[0x18, 1]), |e| {
            matches!(e, ProtoError::Length { .. })
        }),
        (frame(0x2D0, &[0x07, 1]), |e| {
            matches!(e, ProtoError::Unknown { .. })
        }),
        (frame(0x3DA, &[0; 5]), |e| {
            matches!(e, ProtoError::Length { .. })
        }),
        (frame(0x3DA, &[0; 8]), |e| {
            matches!(e, ProtoError::Length { .. })
        }),
        (frame(0x3D1, &[0; 6]), |e| {
            matches!(e, ProtoError::Unknown { .. })
        }),
        (frame(0x480, &[0x40, 1, 2]), |e| {
            matches!(e, ProtoError::Length { .. })
        }),
        (frame(0x480, &[0xC0, 1]), |e| {
            matches!(e, ProtoError::Length { .. })
        }),
        (frame(0x480, &[]), |e| {
            matches!(e, ProtoError::Length { .. })
        }),
        (frame(0x5E1, &[1, 2]), |e| {
            matches!(e, ProtoError::Length { .. })
        }),
        (frame(0x5E4, &[0; 8]), |e| {
            matches!(e, ProtoError::Unknown { .. })
        }),
    ];
    for (f, check) in cases {
        let err = Message::decode(&f).expect_err(&format!("{f} must not decode"));
        assert!(check(&err), "{f}: unexpected error {err:?}");
        assert!(!err.to_string().is_empty());
    }
}

#[test]
fn replies_are_addressed_to_the_host() {
    let f = frame(0x030, &[0x80 | 20, 1, 0, 0, 0]);
    assert_eq!(
        Message::decode(&f).unwrap(),
        Message::McReply {
            src: 3,
            dst: 0,
            axis: 1,
            reply: McReply::EncoderPosition(1)
        }
    );
    // With another host address the same frame is a request to board 0.
    assert!(matches!(
        Message::decode_for(&f, 5).unwrap(),
        Message::McRequest { .. }
    ));
}

/// xorshift64*: deterministic pseudo-random bytes without a dependency.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
}

#[test]
fn random_frames_decode_consistently() {
    let mut rng = Rng(0x1234_5678_9ABC_DEF1);
    let mut decoded = 0;
    for _ in 0..200_000 {
        let r = rng.next();
        let id = (r & 0x7FF) as u16;
        let len = ((r >> 11) % 9) as usize;
        let bytes = rng.next().to_le_bytes();
        let f = frame(id, &bytes[..len]);
        if let Ok(m) = Message::decode(&f) {
            decoded += 1;
            // Decoding is idempotent through the canonical encoding.
            let again = Message::decode(&m.encode()).expect("canonical encoding decodes");
            assert_eq!(again, m, "{f}");
        }
    }
    assert!(decoded > 10_000, "only {decoded} random frames decoded");
}

#[test]
fn decode_any_walks_datagrams() {
    let msgs = every_message();
    let frames: Vec<CanFrame> = msgs.iter().map(Message::encode).collect();
    let mut total = Vec::new();
    for p in crate::bus::cannelloni::encode_packets(0, &frames) {
        total.extend(decode_any(&p).unwrap());
    }
    assert_eq!(total, msgs);
    assert!(matches!(
        decode_any(&[1, 2, 3]),
        Err(DecodeAnyError::Datagram(_))
    ));
    let mut bad = Vec::new();
    crate::bus::cannelloni::encode(0, &[frame(0x001, &[])], &mut bad);
    assert!(matches!(
        decode_any(&bad),
        Err(DecodeAnyError::Message { index: 0, .. })
    ));
    let mut rng = Rng(99);
    for _ in 0..20_000 {
        let n = (rng.next() % 40) as usize;
        let mut buf: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
        if buf.len() >= 2 {
            buf[0] = 2;
            buf[1] = 0;
        }
        let _ = decode_any(&buf);
    }
}
