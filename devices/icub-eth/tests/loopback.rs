//! Host state machine <-> board engine entirely in memory (no sockets), on a simulated
//! clock advanced 1 ms per step: start-up (presence, versions, config, services, regsig,
//! start), a position command reaching the plant, the encoder coming back in the joint
//! status, the regulars' rate, the board's torque (µN·m) and motor temperature units, and
//! the faults (silent board, version mismatch, garbage).

use icub_eth::board::{BoardConfig, BoardEngine};
use icub_eth::entities::analog::{FtConfig, FtStatus, FtTimedValue};
use icub_eth::entities::boards::EthBoardType;
use icub_eth::entities::mc::{
    control_mode, JointConfig, JointStatusCore, PositionLimits, Setpoint,
};
use icub_eth::entities::mn::{
    category, service_type, ApplConfig, ApplState, ServiceCommand, Version,
};
use icub_eth::entities::service::{
    CanSensorDescriptor, CanSensorsConfig, Coupling, JomoDescriptor, JomoDescriptors,
    McServiceConfig,
};
use icub_eth::host::{
    HostConfig, HostEvent, HostTransceiver, ServiceSpec, Startup, StartupError, StartupStatus,
};
use icub_eth::id::{entity as en, ids, tag};
use icub_eth::Entity;
use std::net::Ipv4Addr;
use std::time::Duration;

const MS: Duration = Duration::from_millis(1);
const IP: Ipv4Addr = Ipv4Addr::new(10, 0, 1, 1);

struct Loop {
    host: HostTransceiver,
    board: BoardEngine,
    now: Duration,
    board_to_host: bool,
    host_frames: u64,
    dt: Duration,
}

impl Loop {
    fn new(board: BoardConfig) -> Self {
        Self {
            host: HostTransceiver::new(HostConfig::new(
                "left_arm-eb1-j0_3",
                IP,
                EthBoardType::Ems4,
            )),
            board: BoardEngine::new(board),
            now: Duration::from_secs(1),
            board_to_host: true,
            host_frames: 0,
            dt: MS,
        }
    }

    fn tick(&mut self) {
        self.now += self.dt;
        while let Some(d) = self.host.poll_transmit(self.now) {
            self.board
                .handle_datagram(&d)
                .expect("host frames are valid");
        }
        self.board.step(self.dt.as_secs_f64());
        while let Some(d) = self.board.poll_transmit(self.now) {
            if self.board_to_host {
                self.host
                    .handle_datagram(&d, self.now)
                    .expect("board frames are valid");
                self.host_frames += 1;
            }
        }
        self.host.handle_timeout(self.now);
    }

    fn start(&mut self, services: &[ServiceSpec]) -> Result<Startup, StartupError> {
        let mut s = Startup::new(ApplConfig::default(), services);
        for _ in 0..30_000 {
            match s.poll(&mut self.host, self.now) {
                StartupStatus::Done => return Ok(s),
                StartupStatus::Failed(e) => return Err(e),
                StartupStatus::Busy => self.tick(),
            }
        }
        panic!("start-up did not end in 30 s (step {:?})", s.current_step());
    }
}

/// A sensor model writes the F/T status on the board; after a tick the host's copy equals it.
fn ft_status_reaches_host(l: &mut Loop, age: u64, values: [f32; 6]) {
    let ft = FtStatus {
        timed_value: FtTimedValue {
            age,
            values,
            ..Default::default()
        },
        ..Default::default()
    };
    l.board
        .store_mut()
        .write(ids::analog(en::AS_FT, 0, tag::AS_FT_STATUS), &ft)
        .unwrap();
    l.tick();
    let got: FtStatus = l
        .host
        .read(ids::analog(en::AS_FT, 0, tag::AS_FT_STATUS))
        .unwrap();
    assert_eq!(got, ft);
}

/// A board that knows only its address and type: the services' configurations tell it
/// its joints and sensors.
fn arm_board() -> BoardConfig {
    BoardConfig::new("left_arm-eb1-j0_3", IP, EthBoardType::Ems4)
}

fn mc_service(joints: u8) -> ServiceSpec {
    let mut configs = Vec::new();
    let mut regulars = Vec::new();
    for j in 0..joints {
        let cfg = JointConfig {
            user_limits: PositionLimits {
                min: -100_000,
                max: 100_000,
            },
            ..Default::default()
        };
        configs.push((ids::joint(j, tag::MC_JOINT_CONFIG), cfg.to_bytes()));
        regulars.push(ids::joint(j, tag::MC_JOINT_STATUS_CORE));
        regulars.push(ids::joint(j, tag::MC_JOINT_STATUS_ADDINFO_MULTIENC));
        regulars.push(ids::motor(j, tag::MC_MOTOR_STATUS));
    }
    ServiceSpec {
        category: category::MC,
        activate: Some(ServiceCommand::verify_activate(
            category::MC,
            service_type::MC_FOC,
            0,
            0,
            &McServiceConfig::Foc {
                version: [0; 5],
                board_type: 8,
                jomos: JomoDescriptors(vec![JomoDescriptor::default(); usize::from(joints)]),
                coupling: Coupling::default(),
            }
            .to_bytes(),
        )),
        configs,
        regulars,
    }
}

fn ft_service() -> ServiceSpec {
    let cfg = FtConfig {
        mode: 1,
        ftperiod: 10,
        calibration_set: 0,
        temperature_period: 1,
    };
    ServiceSpec {
        category: category::FT,
        activate: Some(ServiceCommand::verify_activate(
            category::FT,
            service_type::AS_FT,
            0,
            0,
            &CanSensorsConfig {
                can_monitor: [0; 4],
                sensors: vec![CanSensorDescriptor::default()],
            }
            .ft_bytes(),
        )),
        configs: vec![(ids::analog(en::AS_FT, 0, tag::AS_FT_CONFIG), cfg.to_bytes())],
        regulars: vec![ids::analog(en::AS_FT, 0, tag::AS_FT_STATUS)],
    }
}

#[test]
fn startup_position_command_and_encoder_feedback() {
    let mut l = Loop::new(arm_board());
    let t0 = l.now;
    let s = l.start(&[mc_service(4), ft_service()]).expect("start-up");
    let took = l.now - t0;
    assert!(took < Duration::from_millis(100), "start-up took {took:?}");
    assert_eq!(s.facts().management_version, Some(Version::new(2, 25)));
    assert!(s.facts().warnings.is_empty(), "{:?}", s.facts().warnings);
    assert_eq!(l.board.state(), ApplState::Running);
    assert_eq!(l.board.regulars().len(), 13);

    // The joints were configured (notConfigured -> idle); the regulars report it.
    for _ in 0..5 {
        l.tick();
    }
    let core: JointStatusCore = l
        .host
        .read(ids::joint(0, tag::MC_JOINT_STATUS_CORE))
        .unwrap();
    assert_eq!(core.control_mode, control_mode::IDLE);

    // setControlMode(position) then positionMove(10000 raw units at 50000 raw/s).
    l.host
        .set(
            ids::joint(0, tag::MC_JOINT_CMMNDS_CONTROLMODE),
            &[control_mode::POSITION],
            l.now,
        )
        .unwrap();
    l.host
        .set_value(
            ids::joint(0, tag::MC_JOINT_CMMNDS_SETPOINT),
            &Setpoint::Position {
                value: 10_000,
                velocity: 50_000,
            },
            l.now,
        )
        .unwrap();
    let sent = l.now;
    let mut reached = None;
    for _ in 0..2000 {
        l.tick();
        let core: JointStatusCore = l
            .host
            .read(ids::joint(0, tag::MC_JOINT_STATUS_CORE))
            .unwrap();
        assert_eq!(core.control_mode, control_mode::POSITION);
        if (core.position - 10_000).abs() <= 100 && core.motion_done {
            reached = Some(l.now - sent);
            break;
        }
    }
    let reached = reached.expect("joint 0 reaches 10000 and reports motion done");
    assert!(reached < Duration::from_millis(500), "{reached:?}");
    // The other joints did not move.
    let core1: JointStatusCore = l
        .host
        .read(ids::joint(1, tag::MC_JOINT_STATUS_CORE))
        .unwrap();
    assert_eq!(core1.position, 0);

    // A sensor model writes the F/T status on the board; it reaches the host's copy.
    ft_status_reaches_host(&mut l, 1, [1.0, 2.0, 3.0, 0.1, 0.2, 0.3]);

    // Regulars at the configured period: 1 ms x txratedivider 1 -> one frame per ms.
    let before = l.host_frames;
    for _ in 0..100 {
        l.tick();
    }
    assert_eq!(l.host_frames - before, 100);
    let c = l.host.counters();
    assert_eq!(c.sequence_gaps, 0);
    assert_eq!(c.invalid_frames + c.bad_rops + c.unknown_rops, 0);
    assert_eq!(l.board.counters().sequence_errors, 0);
    assert_eq!(l.board.counters().rejected_rops, 0);
}

#[test]
fn a_board_with_fixed_entities_needs_no_configuration() {
    let mut b = arm_board();
    b.auto_entities = false;
    b.joints = 2;
    let mut l = Loop::new(b);
    let mut mc = mc_service(2);
    mc.activate = None; // eomn_serv_MC_generic: no parameter
    l.start(&[mc]).expect("start-up");
    assert_eq!(l.board.regulars().len(), 6);
}

/// As a board checks its joint-motor descriptors: a motion-control configuration that
/// names no joint (an empty one), or another number of joints than the board drives,
/// fails the verification, and the host's start-up names the step.
#[test]
fn a_motion_control_configuration_that_does_not_fit_fails_verification() {
    for (named, why) in [(0usize, "empty"), (3, "three joints on a four-joint board")] {
        let mut b = arm_board();
        b.auto_entities = false;
        b.joints = 4;
        let mut l = Loop::new(b);
        let mut mc = mc_service(4);
        let data = if named == 0 {
            Vec::new()
        } else {
            McServiceConfig::Foc {
                version: [0; 5],
                board_type: 8,
                jomos: JomoDescriptors(vec![JomoDescriptor::default(); named]),
                coupling: Coupling::default(),
            }
            .to_bytes()
        };
        mc.activate = Some(ServiceCommand::verify_activate(
            category::MC,
            service_type::MC_FOC,
            0,
            0,
            &data,
        ));
        let e = l.start(&[mc]).expect_err(why);
        let text = format!("{e:?}");
        assert!(
            text.contains("serviceVerifyActivate") && text.contains("latestcommandisok = false"),
            "{why}: {text}"
        );
    }
}

#[test]
fn a_silent_board_is_reported_within_its_timeout() {
    let mut l = Loop::new(arm_board());
    l.start(&[mc_service(4)]).expect("start-up");
    while l.host.poll_event().is_some() {}
    l.board_to_host = false;
    let silent_from = l.now;
    let mut lost = None;
    for _ in 0..100 {
        l.tick();
        while let Some(e) = l.host.poll_event() {
            if let HostEvent::BoardLost { .. } = e {
                lost = Some((l.now - silent_from, e.describe(l.host.config())));
            }
        }
        if lost.is_some() {
            break;
        }
    }
    let (after, msg) = lost.expect("board reported lost");
    // Presence timeout 20 ms (icub-main's default): reported on the first check past it.
    assert!(
        after > Duration::from_millis(20) && after <= Duration::from_millis(22),
        "{after:?}"
    );
    assert!(msg.contains("10.0.1.1 (left_arm-eb1-j0_3)"), "{msg}");
    assert!(msg.contains("its timeout is 0.020 sec"), "{msg}");
    assert!(l.host.board_lost());
    l.board_to_host = true;
    l.tick();
    let mut recovered = false;
    let mut gap = None;
    while let Some(e) = l.host.poll_event() {
        recovered |= matches!(e, HostEvent::BoardRecovered { .. });
        if matches!(e, HostEvent::SequenceGap { .. }) {
            gap = Some(e.describe(l.host.config()));
        }
    }
    assert!(recovered);
    let gap = gap.expect("sequence gap reported");
    assert!(
        gap.contains("ERROR in sequence number from IP = 10.0.1.1"),
        "{gap}"
    );
    // The board's frames kept their numbering: the host sees the gap.
    assert_eq!(l.host.counters().sequence_gaps, 1);
}

#[test]
fn a_different_management_protocol_is_refused_naming_both_versions() {
    let mut b = arm_board();
    b.protocol[0] = Version::new(2, 24);
    let mut l = Loop::new(b);
    let e = l.start(&[mc_service(4)]).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, StartupError::ProtocolVersion { .. }), "{msg}");
    assert!(
        msg.contains("pc104.version = 2.25 and board.version = 2.24"),
        "{msg}"
    );
    assert!(
        msg.contains("BOARD left_arm-eb1-j0_3 with IP 10.0.1.1"),
        "{msg}"
    );
    assert!(msg.contains("eoprot_endpoint_management"), "{msg}");
}

#[test]
fn a_different_motion_control_protocol_is_refused() {
    let mut b = arm_board();
    b.protocol[1] = Version::new(1, 19);
    let mut l = Loop::new(b);
    let e = l.start(&[mc_service(4)]).unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("eoprot_endpoint_motioncontrol"), "{msg}");
    assert!(
        msg.contains("pc104.version = 1.27 and board.version = 1.19"),
        "{msg}"
    );
}

#[test]
fn a_wrong_board_type_is_a_warning_and_a_missing_service_an_error() {
    let mut b = arm_board();
    b.board_type = EthBoardType::Mc4plus;
    b.auto_entities = false;
    b.joints = 4;
    let mut l = Loop::new(b);
    let e = l.start(&[mc_service(4), ft_service()]).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("serviceVerifyActivate(eomn_serv_category_ft)"),
        "{msg}"
    );
    assert!(msg.contains("latestcommandisok = false"), "{msg}");

    let mut b = arm_board();
    b.board_type = EthBoardType::Mc4plus;
    let mut l = Loop::new(b);
    let s = l.start(&[mc_service(4)]).unwrap();
    assert_eq!(
        s.facts().warnings,
        vec!["EthResource::askBoardVersion(): detected wrong board. expecting ems4 and detected mc4plus"]
    );
}

#[test]
fn no_board_means_no_reply_after_21_attempts_of_1_s() {
    let mut l = Loop::new(arm_board());
    l.board_to_host = false;
    l.dt = 10 * MS;
    let t0 = l.now;
    let e = l.start(&[mc_service(4)]).unwrap_err();
    let waited = l.now - t0;
    assert!(matches!(e, StartupError::NoReply { .. }), "{e}");
    assert!(
        waited >= Duration::from_secs(21) && waited <= Duration::from_millis(21_100),
        "{waited:?}"
    );
    let msg = e.to_string();
    assert!(
        msg.contains("DID NOT have replies from BOARD left_arm-eb1-j0_3 with IP 10.0.1.1"),
        "{msg}"
    );
}

#[test]
fn garbage_is_counted_and_dropped() {
    let mut l = Loop::new(arm_board());
    l.start(&[mc_service(2)]).expect("start-up");
    for g in [&b""[..], &[0u8; 27][..], &[0xff; 64][..]] {
        assert!(l.host.handle_datagram(g, l.now).is_err());
        assert!(l.board.handle_datagram(g).is_err());
    }
    assert_eq!(l.host.counters().invalid_frames, 3);
    assert_eq!(l.board.counters().invalid_frames, 3);
    // A set with the wrong size is rejected by the board, and the rest still works.
    let mut frame = icub_eth::FrameBuilder::new(768);
    frame
        .push(&icub_eth::Rop::set(
            ids::joint(0, tag::MC_JOINT_CMMNDS_SETPOINT),
            vec![1, 2, 3],
        ))
        .unwrap();
    l.board.handle_datagram(&frame.finish(1000, 0)).unwrap();
    assert_eq!(l.board.counters().rejected_rops, 1);
    l.tick();
    assert_eq!(l.board.state(), ApplState::Running);
}

#[test]
fn calibration_ends_in_position_control() {
    use icub_eth::entities::mc::Calibrator;
    let mut l = Loop::new(arm_board());
    l.start(&[mc_service(4)]).expect("start-up");
    // parametricCalibratorEth: calibrateAxisWithParams -> set<joint cmmnds calibration>.
    let cal = Calibrator {
        calibration_type: 12, // eomc_calibration_type12_absolute_sensor
        params: [1000, 0, 0, 0, 0, 0],
    };
    l.host
        .set_value(ids::joint(2, tag::MC_JOINT_CMMNDS_CALIBRATION), &cal, l.now)
        .unwrap();
    let mut seen_calib = false;
    let mut done_after = None;
    let t0 = l.now;
    for _ in 0..500 {
        l.tick();
        let core: JointStatusCore = l
            .host
            .read(ids::joint(2, tag::MC_JOINT_STATUS_CORE))
            .unwrap();
        seen_calib |= core.control_mode == control_mode::CALIB;
        // embObjMotionControl::calibrationDoneRaw: done when no longer calib (nor idle).
        if seen_calib && core.control_mode == control_mode::POSITION {
            done_after = Some(l.now - t0);
            break;
        }
    }
    let done_after = done_after.expect("calibration ends in position control");
    assert!(
        done_after >= Duration::from_millis(100) && done_after < Duration::from_millis(110),
        "{done_after:?}"
    );
}

/// The board's torques are µN·m on the wire (`eOmeas_torque_t`) and its motor
/// temperatures the raw reading of the motor's sensor: a torque reference of 2.5e6 µN·m
/// in torque control is reported back (joint status core: measure, `ofpid` reftrq and
/// errtrq) in µN·m while the plant works in N·m; the host's external torque input
/// (µN·m) is the measure out of torque control; a motor whose config says it has a
/// temperature sensor reports the PT100 reading of its 35 °C (439), the others 0.
#[test]
fn torques_in_micro_newton_metres_and_raw_motor_temperatures() {
    use icub_eth::entities::mc::{MotorConfig, MotorStatus};
    let mut l = Loop::new(arm_board());
    l.start(&[mc_service(4)]).expect("start-up");
    l.host
        .set(
            ids::joint(0, tag::MC_JOINT_CMMNDS_CONTROLMODE),
            &[control_mode::TORQUE],
            l.now,
        )
        .unwrap();
    l.tick();
    l.host
        .set_value(
            ids::joint(0, tag::MC_JOINT_CMMNDS_SETPOINT),
            &Setpoint::Torque { value: 2.5e6 },
            l.now,
        )
        .unwrap();
    for _ in 0..300 {
        l.tick();
    }
    let core: JointStatusCore = l
        .host
        .read(ids::joint(0, tag::MC_JOINT_STATUS_CORE))
        .unwrap();
    assert_eq!(core.control_mode, control_mode::TORQUE);
    assert!((core.torque - 2.5e6).abs() < 10.0, "{}", core.torque);
    assert_eq!(core.ofpid[1], 2_500_000, "reftrq");
    assert!(core.ofpid[3].abs() < 10, "errtrq {}", core.ofpid[3]);
    assert_eq!(l.board.joint(0).unwrap().feedback().torque_reference, 2.5);

    // joint 1 (idle) measures what the host sends as its external torque
    let mut bytes = (-1.25e6f32).to_le_bytes().to_vec();
    bytes.resize(
        ids::joint(1, tag::MC_JOINT_INPUTS_EXTERNALLYMEASUREDTORQUE)
            .size()
            .unwrap(),
        0,
    );
    l.host
        .set(
            ids::joint(1, tag::MC_JOINT_INPUTS_EXTERNALLYMEASUREDTORQUE),
            &bytes,
            l.now,
        )
        .unwrap();
    for _ in 0..5 {
        l.tick();
    }
    let core1: JointStatusCore = l
        .host
        .read(ids::joint(1, tag::MC_JOINT_STATUS_CORE))
        .unwrap();
    assert_eq!(core1.torque, -1.25e6);
    assert_eq!(
        core1.ofpid[1], 0,
        "no torque reference out of torque control"
    );

    // motor 2 with a temperature sensor (hasTempSensor, bit 1), motor 3 without
    let with_sensor = MotorConfig {
        flags: 0b10,
        ..Default::default()
    };
    l.host
        .set_value(ids::motor(2, tag::MC_MOTOR_CONFIG), &with_sensor, l.now)
        .unwrap();
    l.host
        .set_value(
            ids::motor(3, tag::MC_MOTOR_CONFIG),
            &MotorConfig::default(),
            l.now,
        )
        .unwrap();
    for _ in 0..5 {
        l.tick();
    }
    let m2: MotorStatus = l.host.read(ids::motor(2, tag::MC_MOTOR_STATUS)).unwrap();
    let m3: MotorStatus = l.host.read(ids::motor(3, tag::MC_MOTOR_STATUS)).unwrap();
    assert_eq!(m2.basic.temperature, 439);
    assert_eq!(m3.basic.temperature, 0);
}

/// Regulars that do not fit one datagram go out in several, each once per period: the
/// board engine used to restart them with every frame and so resent the first one for
/// ever (the emulator worked around it with 60 kB datagrams).
#[test]
fn regulars_larger_than_a_datagram_go_out_in_several_once_per_period() {
    let mut board = arm_board();
    board.max_tx_packet = 300;
    let mut l = Loop::new(board);
    l.start(&[mc_service(4), ft_service()]).expect("start-up");
    assert_eq!(l.board.regulars().len(), 13);

    // Bounded by hand: the bug made `poll_transmit` endless.
    let mut per_period = Vec::new();
    for _ in 0..50 {
        l.now += l.dt;
        l.board.step(l.dt.as_secs_f64());
        let mut frames = 0;
        while let Some(d) = l.board.poll_transmit(l.now) {
            assert!(d.len() <= 300, "a datagram of {} bytes", d.len());
            l.host
                .handle_datagram(&d, l.now)
                .expect("board frames are valid");
            frames += 1;
            assert!(frames < 20, "the board never stops sending this period");
        }
        l.host.handle_timeout(l.now);
        per_period.push(frames);
    }
    let n = per_period[10];
    assert!(n >= 2, "13 regulars in {n} datagram(s) of 300 bytes");
    assert!(per_period[10..].iter().all(|&f| f == n), "{per_period:?}");

    // The last regular (the F/T status, after the joints') reaches the host.
    ft_status_reaches_host(&mut l, 7, [6.0, 5.0, 4.0, 0.3, 0.2, 0.1]);
    let c = l.host.counters();
    assert_eq!(c.sequence_gaps, 0);
    assert_eq!(c.invalid_frames + c.bad_rops + c.unknown_rops, 0);
}

#[test]
fn regulars_keep_the_phase_of_their_period_after_a_late_poll() {
    let mut l = Loop::new(arm_board());
    l.start(&[mc_service(4), ft_service()]).expect("start-up");
    let period = l.board.regular_period();
    assert_eq!(period, MS, "the default cycle of 1 ms, every cycle");
    // Drain whatever is due now; from here the schedule is on the period's multiples
    // (of the board's time), as the firmware's cycle.
    while l.board.poll_transmit(l.now).is_some() {}
    let next = l
        .board
        .next_transmit()
        .expect("running: regulars are scheduled");
    assert_eq!(next.as_nanos() % period.as_nanos(), 0, "{next:?}");

    // Polled 0.3 ms late: one frame, and the next stays on the multiple after it.
    let late = next + Duration::from_micros(300);
    assert!(l.board.poll_transmit(late).is_some());
    assert!(l.board.poll_transmit(late).is_none());
    assert_eq!(l.board.next_transmit(), Some(next + period));

    // Polled 2.5 ms late (a host thread descheduled): one frame, not the missed ones in
    // a burst, and the cycle goes on at the next multiple.
    let very_late = next + period + Duration::from_micros(2500);
    assert!(l.board.poll_transmit(very_late).is_some());
    assert!(l.board.poll_transmit(very_late).is_none());
    assert_eq!(l.board.next_transmit(), Some(next + 4 * period));
}
