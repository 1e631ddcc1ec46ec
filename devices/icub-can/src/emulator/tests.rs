//! Emulator tests on the in-process bus and over UDP.

use std::sync::Arc;
use std::time::{Duration, Instant};

use super::*;
use crate::bus::inproc::VirtualBus;
use crate::bus::udp::UdpBus;
use crate::proto::analog::txmode;
use crate::proto::{
    AsCommand, AsPeriodic, AsReply, ControlMode, InertialMsg, McCommand, McPeriodic, McReply, Pid,
    PidKind,
};

const T: Duration = Duration::from_secs(3);

/// Sends a request and waits for the matching reply.
fn ask(bus: &dyn CanBus, dst: u8, axis: u8, cmd: McCommand) -> McReply {
    bus.send(
        &Message::McRequest {
            src: 0,
            dst,
            axis,
            cmd,
        }
        .encode(),
    )
    .unwrap();
    let deadline = Instant::now() + T;
    while Instant::now() < deadline {
        let f = bus.recv(T).unwrap();
        if let Ok(Message::McReply {
            src,
            axis: a,
            reply,
            ..
        }) = Message::decode(&f)
        {
            if src == dst && a == axis && reply.opcode() == cmd.opcode() {
                return reply;
            }
        }
    }
    panic!("no reply to {cmd:?}");
}

fn tell(bus: &dyn CanBus, dst: u8, axis: u8, cmd: McCommand) {
    bus.send(
        &Message::McRequest {
            src: 0,
            dst,
            axis,
            cmd,
        }
        .encode(),
    )
    .unwrap();
}

fn encoder(bus: &dyn CanBus, dst: u8, axis: u8) -> i32 {
    match ask(bus, dst, axis, McCommand::GetEncoderPosition) {
        McReply::EncoderPosition(p) => p,
        r => panic!("{r:?}"),
    }
}

fn wait_until(what: &str, mut f: impl FnMut() -> bool) {
    let deadline = Instant::now() + T;
    while Instant::now() < deadline {
        if f() {
            return;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    panic!("timed out waiting for {what}");
}

fn mc_on_virtual_bus(name: &str) -> (VirtualBus, EmulatorHandle) {
    let bus = VirtualBus::new(name);
    let mut cfg = McBoardConfig::new(1);
    cfg.initial = [100.0, -50.0];
    let emu = BusEmulator::new(Arc::new(bus.endpoint()), vec![Box::new(McBoard::new(cfg))])
        .spawn()
        .unwrap();
    (bus, emu)
}

#[test]
fn mc_board_answers_polling_and_moves() {
    let (bus, _emu) = mc_on_virtual_bus("mc");
    let host = bus.endpoint();
    assert_eq!(encoder(&host, 1, 0), 100);
    assert_eq!(encoder(&host, 1, 1), -50);
    assert_eq!(
        ask(&host, 1, 0, McCommand::GetControlMode),
        McReply::ControlMode(ControlMode::Idle)
    );

    let pid = Pid {
        kp: 32000,
        ki: 60,
        kd: 50,
        shift: 13,
    };
    tell(&host, 1, 0, McCommand::SetPid(PidKind::Position, pid));
    assert_eq!(
        ask(&host, 1, 0, McCommand::GetPid(PidKind::Position)),
        McReply::Pid(PidKind::Position, pid)
    );
    tell(&host, 1, 0, McCommand::SetMinPosition(-1000));
    tell(&host, 1, 0, McCommand::SetMaxPosition(2000));
    assert_eq!(
        ask(&host, 1, 0, McCommand::GetMaxPosition),
        McReply::MaxPosition(2000)
    );

    tell(
        &host,
        1,
        0,
        McCommand::SetControlMode(ControlMode::Position),
    );
    tell(
        &host,
        1,
        0,
        McCommand::PositionMove {
            position: 1500,
            speed: 500,
        },
    );
    wait_until("motion done", || {
        ask(&host, 1, 0, McCommand::MotionDone) == McReply::MotionDone(true)
    });
    // done means the trajectory ended (the firmware's `_ended`): the joint settles after
    wait_until("settled at 1500", || {
        (encoder(&host, 1, 0) - 1500).abs() <= 3
    });
    // Beyond the limits the target is clamped.
    tell(
        &host,
        1,
        0,
        McCommand::PositionMove {
            position: 100_000,
            speed: 2000,
        },
    );
    wait_until("clamped move", || {
        ask(&host, 1, 0, McCommand::MotionDone) == McReply::MotionDone(true)
    });
    wait_until("settled at 2000", || {
        (encoder(&host, 1, 0) - 2000).abs() <= 3
    });
    // The other joint did not move.
    assert_eq!(encoder(&host, 1, 1), -50);
}

#[test]
fn mc_board_velocity_mode_expires() {
    let (bus, _emu) = mc_on_virtual_bus("vel");
    let host = bus.endpoint();
    tell(&host, 1, 1, McCommand::SetVelTimeout(200));
    tell(
        &host,
        1,
        1,
        McCommand::SetControlMode(ControlMode::Velocity),
    );
    // 2 ticks/ms with shift 0 = 2000 ticks/s.
    tell(&host, 1, 1, McCommand::VelocityMove { speed: 2, accel: 0 });
    std::thread::sleep(Duration::from_millis(100));
    let mid = encoder(&host, 1, 1);
    assert!(mid > 50, "joint should move up, at {mid}");
    std::thread::sleep(Duration::from_millis(400));
    let a = encoder(&host, 1, 1);
    std::thread::sleep(Duration::from_millis(100));
    let b = encoder(&host, 1, 1);
    assert!((a - b).abs() <= 2, "velocity command expired: {a} -> {b}");
}

#[test]
fn mc_board_broadcasts_and_goes_silent() {
    let (bus, emu) = mc_on_virtual_bus("bcast");
    let host = bus.endpoint();
    let mut seen_pos = 0;
    let mut seen_status = false;
    let deadline = Instant::now() + T;
    while (seen_pos < 5 || !seen_status) && Instant::now() < deadline {
        match Message::decode(&host.recv(T).unwrap()).unwrap() {
            Message::McPeriodic {
                board: 1,
                msg: McPeriodic::Position(p),
            } => {
                assert_eq!(p, [100, -50]);
                seen_pos += 1;
            }
            Message::McPeriodic {
                board: 1,
                msg: McPeriodic::Status(s),
            } => {
                assert_eq!(s.control_mode, [ControlMode::Idle; 2]);
                seen_status = true;
            }
            _ => {}
        }
    }
    assert!(seen_pos >= 5 && seen_status);
    // A broadcast policy of position only.
    tell(&host, 1, 0, McCommand::SetBcastPolicy(1 << 1));
    std::thread::sleep(Duration::from_millis(50));
    while host.try_recv().unwrap().is_some() {}
    for _ in 0..20 {
        let m = Message::decode(&host.recv(T).unwrap()).unwrap();
        assert!(
            matches!(
                m,
                Message::McPeriodic {
                    msg: McPeriodic::Position(_),
                    ..
                }
            ),
            "{m:?}"
        );
    }
    emu.set_silent(1, true);
    std::thread::sleep(Duration::from_millis(50));
    while host.try_recv().unwrap().is_some() {}
    tell(&host, 1, 0, McCommand::GetEncoderPosition);
    assert!(matches!(
        host.recv(Duration::from_millis(200)),
        Err(BusError::Timeout(_))
    ));
    emu.set_silent(1, false);
    assert!(host.recv(T).is_ok());
}

#[test]
fn malformed_frames_are_counted_and_ignored() {
    let (bus, emu) = mc_on_virtual_bus("bad");
    let host = bus.endpoint();
    host.send(&CanFrame::new(0x001, &[]).unwrap()).unwrap();
    host.send(&CanFrame::new(0x001, &[0x7E]).unwrap()).unwrap();
    host.send(&CanFrame::new_extended(0x123456, &[1]).unwrap())
        .unwrap();
    assert_eq!(encoder(&host, 1, 0), 100);
    assert_eq!(emu.stats().malformed.load(Ordering::Relaxed), 3);
}

#[test]
fn strain_board_streams_after_start() {
    let bus = VirtualBus::new("strain");
    let _emu = BusEmulator::new(
        Arc::new(bus.endpoint()),
        vec![Box::new(StrainBoard::new(0x0D))],
    )
    .spawn()
    .unwrap();
    let host = bus.endpoint();
    let req = |cmd| {
        host.send(
            &Message::AsRequest {
                src: 0,
                dst: 0x0D,
                cmd,
            }
            .encode(),
        )
        .unwrap()
    };
    req(AsCommand::GetFullScale { channel: 2 });
    let reply = Message::decode(&host.recv(T).unwrap()).unwrap();
    assert_eq!(
        reply,
        Message::AsReply {
            src: 0x0D,
            dst: 0,
            reply: AsReply::FullScale {
                channel: 2,
                value: 1000
            }
        }
    );
    assert!(
        matches!(
            host.recv(Duration::from_millis(50)),
            Err(BusError::Timeout(_))
        ),
        "silent until started"
    );
    req(AsCommand::SetCanDataRate(2));
    req(AsCommand::SetTxMode(txmode::CALIBRATED));
    let (mut forces, mut torques) = (0, 0);
    while forces < 10 || torques < 10 {
        if let Message::AsPeriodic {
            board: 0x0D,
            msg: AsPeriodic::Vector { kind, raw, .. },
        } = Message::decode(&host.recv(T).unwrap()).unwrap()
        {
            let v = AsPeriodic::signed(raw);
            match kind {
                VectorKind::Force => {
                    forces += 1;
                    // Fz = 10 ± 5 N at full scale 1000 N.
                    let fz = f64::from(v[2]) * 1000.0 / 32768.0;
                    assert!((4.9..=15.1).contains(&fz), "fz {fz}");
                }
                VectorKind::Torque => torques += 1,
                k => panic!("{k:?}"),
            }
        }
    }
    req(AsCommand::SetTxMode(txmode::STOP));
    std::thread::sleep(Duration::from_millis(20));
    while host.try_recv().unwrap().is_some() {}
    assert!(matches!(
        host.recv(Duration::from_millis(50)),
        Err(BusError::Timeout(_))
    ));
}

use crate::proto::VectorKind;
use std::sync::atomic::Ordering;

#[test]
fn mtb_streams_skin_and_inertial() {
    let bus = VirtualBus::new("mtb");
    let boards: Vec<Box<dyn Board>> = vec![
        Box::new(MtbBoard::new(14, true)),
        Box::new(MtbBoard::new(12, false)),
    ];
    let _emu = BusEmulator::new(Arc::new(bus.endpoint()), boards)
        .spawn()
        .unwrap();
    let host = bus.endpoint();
    host.send(
        &Message::AsRequest {
            src: 0,
            dst: 12,
            cmd: AsCommand::AccGyroSetup {
                sensors: 0x0C,
                period: 5,
            },
        }
        .encode(),
    )
    .unwrap();
    let (mut heads, mut tails, mut acc, mut gyro) = (0, 0, 0, 0);
    let deadline = Instant::now() + T;
    while (heads < 16 || tails < 16 || acc < 3 || gyro < 3) && Instant::now() < deadline {
        match Message::decode(&host.recv(T).unwrap()).unwrap() {
            Message::Skin { board: 14, msg } => {
                assert_eq!(msg.taxels().len(), if msg.is_tail() { 5 } else { 7 });
                if msg.is_tail() {
                    tails += 1
                } else {
                    heads += 1
                }
            }
            Message::Inertial {
                board: 12,
                msg: InertialMsg::Accelerometer(a),
            } => {
                assert_eq!(a, [0, 0, 16384]);
                acc += 1
            }
            Message::Inertial {
                board: 12,
                msg: InertialMsg::Gyroscope(_),
            } => gyro += 1,
            m => panic!("unexpected {m:?}"),
        }
    }
    assert!(
        heads >= 16 && tails >= 16 && acc >= 3 && gyro >= 3,
        "{heads} {tails} {acc} {gyro}"
    );
}

#[test]
fn board_specs_and_files() {
    assert_eq!(board_from_spec("1:mc").unwrap().kind(), "mc");
    assert_eq!(board_from_spec("0x0D:strain").unwrap().address(), 13);
    assert!(board_from_spec("0:mc").is_err());
    assert!(board_from_spec("15:mc").is_err());
    assert!(board_from_spec("3:robot").is_err());
    assert!(board_from_spec("3").is_err());
}

#[test]
fn emulator_over_udp_between_threads() {
    let hub = UdpBus::hub("127.0.0.1:0").unwrap();
    let addr = hub.local_addr().unwrap().to_string();
    let mut cfg = McBoardConfig::new(3);
    cfg.initial = [7.0, 8.0];
    let _emu = BusEmulator::new(Arc::new(hub), vec![Box::new(McBoard::new(cfg))])
        .spawn()
        .unwrap();
    let host = UdpBus::connect(&addr, None).unwrap();
    assert_eq!(encoder(&host, 3, 1), 8);
    let mut positions = 0;
    while positions < 3 {
        if let Ok(Message::McPeriodic {
            msg: McPeriodic::Position(p),
            ..
        }) = Message::decode(&host.recv(T).unwrap())
        {
            assert_eq!(p, [7, 8]);
            positions += 1;
        }
    }
}
