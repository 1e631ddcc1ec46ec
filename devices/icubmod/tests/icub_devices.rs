//! The iCub CAN devices against the board emulator, configured with the unmodified
//! iCubGenova01 files (read through the robotinterface XML loader), plus one
//! `canBackend` line. In-process and cannelloni/UDP buses; every wait is bounded.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use icub_can::bus::inproc::VirtualBus;
use icub_can::bus::udp::UdpBus;
use icub_can::emulator::network;
use icub_can::emulator::{BusEmulator, EmulatorHandle};
use icub_can::CanBus;
use icub_emulators::can_robot;
use yarp_devices::robotinterface::{read_robot_str, Param};
use yarp_devices::sensors::{AnalogStatus, MasStatus};
use yarp_devices::vocabs::{
    CM_IDLE, CM_POSITION, CM_TORQUE, IM_STIFF, JOINTTYPE_REVOLUTE, PIDTYPE_POSITION,
};
use yarp_devices::{shared, DeviceError, PolyDriver, Registry, SharedDevice};
use yarp_proto::Property;

fn icub_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/robots-configuration/iCubGenova01")
}

/// The `Property` of device `name` from iCubGenova01 file `file`, with `canBackend`.
fn icub_params(file: &str, name: &str, backend: &str) -> Option<Property> {
    let dir = icub_dir();
    if !dir.join(file).exists() {
        eprintln!("SKIPPED: {} not found", dir.join(file).display());
        return None;
    }
    let xml = format!(
        r#"<?xml version="1.0" encoding="UTF-8" ?>
<!DOCTYPE robot PUBLIC "-//YARP//DTD yarprobotinterface 3.0//EN" "http://www.yarp.it/DTD/yarprobotinterfaceV3.0.dtd">
<robot name="iCubGenova01" portprefix="/icub" build="0" xmlns:xi="http://www.w3.org/2001/XInclude">
<devices><xi:include href="{file}" /></devices></robot>"#
    );
    let mut robot = read_robot_str(&xml, &dir, &Property::new())
        .unwrap_or_else(|e| panic!("{e}"))
        .robot;
    let dev = robot
        .devices
        .iter_mut()
        .find(|d| d.name == name)
        .unwrap_or_else(|| panic!("{name} not in {file}"));
    dev.params.push(Param::new("canBackend", backend));
    Some(dev.to_property().unwrap_or_else(|e| panic!("{e}")))
}

/// Emulates preset network `num` on a fresh in-process bus; returns its URL.
fn inproc_network(num: u32, tag: &str) -> (String, EmulatorHandle) {
    let name = format!("icub-test-{tag}-{}", std::process::id());
    let bus: Arc<dyn CanBus> = Arc::new(VirtualBus::named(&name).endpoint());
    (format!("inproc://{name}"), emulate(bus, num))
}

/// Emulates preset network `num` behind a cannelloni hub on 127.0.0.1; returns its URL.
fn udp_network(num: u32) -> (String, EmulatorHandle) {
    let hub = UdpBus::hub("127.0.0.1:0").expect("hub");
    let url = format!("udp://{}", hub.local_addr().expect("addr"));
    (url, emulate(Arc::new(hub), num))
}

fn emulate(bus: Arc<dyn CanBus>, num: u32) -> EmulatorHandle {
    // iCubGenova01's boards, else those of the shipped simulated iCub (the same layout).
    let dir = Some(icub_dir()).filter(|d| d.exists()).unwrap_or_else(|| {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../launch-configs/icub-sim/robot")
    });
    let file = can_robot::robot_file(&dir).expect("robot file");
    let net = can_robot::networks(&file)
        .expect("CAN layout of the robot files")
        .into_iter()
        .find(|n| n.num == num)
        .expect("network");
    BusEmulator::new(bus, network::build(&net))
        .spawn()
        .expect("emulator")
}

/// Polls `f` until it holds, for at most `limit`.
fn eventually(limit: Duration, mut f: impl FnMut() -> bool) -> bool {
    let start = Instant::now();
    while start.elapsed() < limit {
        if f() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    false
}

fn open_left_arm(backend: &str) -> Option<PolyDriver> {
    let p = icub_params(
        "hardware/motorControl/icub_left_arm.xml",
        "left_arm_mc",
        backend,
    )?;
    Some(PolyDriver::open(&p).unwrap_or_else(|e| panic!("{e}")))
}

/// Position mode, a move of the elbow to 50°, and encoders that follow.
fn move_elbow(pd: &mut PolyDriver) {
    let dev = pd.device();
    let enc = dev.as_encoders().unwrap();
    assert_eq!(enc.get_axes().unwrap(), 8);
    // the emulator starts every joint at 0° clamped into its limits: the elbow at 15°
    assert!(eventually(Duration::from_secs(2), || enc
        .get_encoder(3)
        .is_ok()));
    let start = enc.get_encoder(3).unwrap();
    assert!((start - 15.0).abs() < 0.5, "elbow starts at {start}");
    let info = dev.as_axis_info().unwrap();
    assert_eq!(info.get_axis_name(3).unwrap(), "l_elbow");
    assert_eq!(info.get_joint_type(3).unwrap(), JOINTTYPE_REVOLUTE);
    let (lo, hi) = dev.as_control_limits().unwrap().get_limits(3).unwrap();
    assert!(
        (lo - 15.0).abs() < 0.2 && (hi - 106.0).abs() < 0.2,
        "{lo} {hi}"
    );

    let cm = dev.as_control_mode().unwrap();
    assert_eq!(cm.get_control_mode(3).unwrap(), CM_IDLE);
    cm.set_control_mode(3, CM_POSITION).unwrap();
    assert!(eventually(Duration::from_secs(1), || cm
        .get_control_mode(3)
        .unwrap()
        == CM_POSITION));
    assert_eq!(
        dev.as_interaction_mode()
            .unwrap()
            .get_interaction_mode(3)
            .unwrap(),
        IM_STIFF
    );
    let pos = dev.as_position_control().unwrap();
    pos.set_ref_speed(3, 40.0).unwrap();
    pos.position_move(3, 50.0).unwrap();
    assert_eq!(pos.get_target_position(3).unwrap(), 50.0);
    let pos_ok = eventually(Duration::from_secs(5), || {
        pos.check_motion_done(3).unwrap_or(false)
    });
    assert!(pos_ok, "motion not done");
    let at = dev.as_encoders().unwrap().get_encoder(3).unwrap();
    assert!((at - 50.0).abs() < 1.0, "elbow at {at}");
    let (all, stamps) = dev.as_encoders().unwrap().get_encoders_timed().unwrap();
    assert_eq!(all.len(), 8);
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_secs_f64();
    assert!(stamps.iter().all(|t| (now - t).abs() < 1.0));
}

#[test]
fn registry_names_the_icub_devices() {
    yarp_devices::Registry::install(icubmod::register);
    let names = Registry::names();
    for n in [
        "canmotioncontrol",
        "canBusAnalogSensor",
        "canBusFtSensor",
        "canBusSkin",
        "canBusInertialMTB",
        "parametricCalibrator",
    ] {
        assert!(names.contains(&n), "{n} missing");
    }
}

#[test]
fn left_arm_moves_a_joint_on_the_inproc_bus() {
    yarp_devices::Registry::install(icubmod::register);
    let (url, _emu) = inproc_network(1, "move");
    let Some(mut pd) = open_left_arm(&url) else {
        return;
    };
    move_elbow(&mut pd);
    // the configured PIDs reached the board
    let pid = pd
        .device()
        .as_pid_control()
        .unwrap()
        .get_pid(PIDTYPE_POSITION, 0)
        .unwrap();
    assert_eq!(
        (pid.kp, pid.kd, pid.ki, pid.scale),
        (32000.0, 50.0, 60.0, 13.0)
    );
}

/// Measured joint torques: iCubGenova01's left arm reads joints 0..4 from the virtual
/// sensor 0x0C, channels 0..4 (`TorqueId`/`TorqueChan`), `TorqueMax` 8 N·m; the emulator
/// broadcasts its simulated joint torques there.
#[test]
fn left_arm_reads_measured_torques_and_runs_torque_mode() {
    yarp_devices::Registry::install(icubmod::register);
    let name = format!("icub-test-torque-{}", std::process::id());
    let bus = VirtualBus::named(&name);
    let _emu = emulate(Arc::new(bus.endpoint()), 1);
    let Some(mut pd) = open_left_arm(&format!("inproc://{name}")) else {
        return;
    };
    let dev = pd.device();
    let trq = dev.as_torque_control().unwrap();
    assert!(eventually(Duration::from_secs(2), || trq
        .get_torque(3)
        .is_ok()));
    // At rest, idle: no torque; joints 5..7 have no sensor and read 0, as in icub-main.
    let all = trq.get_torques().unwrap();
    assert_eq!(all.len(), 8);
    assert!(all.iter().all(|t| t.abs() < 0.05), "{all:?}");
    assert_eq!(trq.get_torque(7).unwrap(), 0.0);

    // Torque mode on the elbow (TRQ_PIDS kp -288 shift 14, proportional only): +1 N·m
    // turns it toward 106°, where the stop holds it; the board's P loop leaves it at
    // about half the reference (see the emulator's `torque_mode_tracks_a_torque_reference`).
    let cm = dev.as_control_mode().unwrap();
    cm.set_control_mode(3, CM_TORQUE).unwrap();
    assert!(eventually(Duration::from_secs(1), || cm
        .get_control_mode(3)
        .unwrap()
        == CM_TORQUE));
    let trq = dev.as_torque_control().unwrap();
    trq.set_ref_torque(3, 1.0).unwrap();
    assert!((trq.get_ref_torque(3).unwrap() - 1.0).abs() < 1e-3);
    let enc = |pd: &mut PolyDriver| pd.device().as_encoders().unwrap().get_encoder(3).unwrap();
    let at_stop = |pd: &mut PolyDriver, deg: f64, nm: (f64, f64)| {
        eventually(Duration::from_secs(5), || {
            let t = pd
                .device()
                .as_torque_control()
                .unwrap()
                .get_torque(3)
                .unwrap();
            (enc(pd) - deg).abs() < 0.5 && t > nm.0 && t < nm.1
        })
    };
    assert!(
        at_stop(&mut pd, 106.0, (0.45, 0.65)),
        "elbow at {}, torque {:?}",
        enc(&mut pd),
        pd.device().as_torque_control().unwrap().get_torque(3)
    );
    pd.device()
        .as_torque_control()
        .unwrap()
        .set_ref_torque(3, -1.0)
        .unwrap();
    assert!(
        at_stop(&mut pd, 15.0, (-0.65, -0.45)),
        "elbow at {}, torque {:?}",
        enc(&mut pd),
        pd.device().as_torque_control().unwrap().get_torque(3)
    );

    // A host-side virtual sensor (canBusVirtualAnalogSensor) sending on 0x0C takes over:
    // the emulator keeps quiet and every reader sees the host's values.
    let dev = pd.device();
    dev.as_control_mode()
        .unwrap()
        .set_control_mode(3, CM_POSITION)
        .unwrap();
    let host = bus.endpoint();
    let frame = |v: i16| {
        icub_can::proto::Message::AsPeriodic {
            board: 0x0C,
            msg: icub_can::proto::AsPeriodic::vector(
                icub_can::proto::VectorKind::Torque,
                [v, 0, 0],
            ),
        }
        .encode()
    };
    let trq = dev.as_torque_control().unwrap();
    let mut seen = Vec::new();
    for _ in 0..40 {
        // channel 3 = 0.5 N·m at TorqueMax 8: 0.5 · 0x8000 / 8 = 2048
        host.send(&frame(2048)).unwrap();
        std::thread::sleep(Duration::from_millis(10));
        seen.push(trq.get_torque(3).unwrap());
    }
    assert!(
        seen[10..].iter().all(|t| (t - 0.5).abs() < 1e-9),
        "{seen:?}"
    );
    // joint 4 (channel 4) is on the same message: the host sent 0
    assert_eq!(trq.get_torque(4).unwrap(), 0.0);
}

#[test]
fn left_arm_moves_a_joint_over_udp() {
    yarp_devices::Registry::install(icubmod::register);
    let (url, _emu) = udp_network(1);
    let Some(mut pd) = open_left_arm(&url) else {
        return;
    };
    move_elbow(&mut pd);
}

#[test]
fn velocity_and_group_moves() {
    yarp_devices::Registry::install(icubmod::register);
    let (url, _emu) = inproc_network(1, "vel");
    let Some(mut pd) = open_left_arm(&url) else {
        return;
    };
    let dev = pd.device();
    assert!(eventually(Duration::from_secs(2), || dev
        .as_encoders()
        .unwrap()
        .get_encoders()
        .is_ok()));
    let cm = dev.as_control_mode().unwrap();
    cm.set_control_modes(&[CM_POSITION; 8]).unwrap();
    let start = dev.as_encoders().unwrap().get_encoders().unwrap();
    let mut target = start.clone();
    target[0] -= 5.0;
    target[1] += 5.0;
    let pos = dev.as_position_control().unwrap();
    pos.set_ref_speeds(&[50.0; 8]).unwrap();
    pos.position_moves(&target).unwrap();
    assert!(eventually(Duration::from_secs(5), || pos
        .check_motion_dones()
        .unwrap_or(false)));
    // done is the board's trajectory ended (the MC4's `_ended`): the joints then settle
    let mut now = Vec::new();
    assert!(
        eventually(Duration::from_secs(2), || {
            now = dev.as_encoders().unwrap().get_encoders().unwrap();
            (0..2).all(|j| (now[j] - target[j]).abs() < 1.0)
        }),
        "{now:?} against {target:?}"
    );
    // a wrong-sized command is refused, not sent
    let pos = dev.as_position_control().unwrap();
    assert!(matches!(
        pos.position_moves(&[0.0; 3]),
        Err(DeviceError::WrongSize { .. })
    ));
}

#[test]
fn strain_streams_forces_and_torques() {
    yarp_devices::Registry::install(icubmod::register);
    let (url, _emu) = inproc_network(1, "ft");
    let Some(p) = icub_params("hardware/FT/left_arm_strain.xml", "left_arm_strain", &url) else {
        return;
    };
    assert_eq!(
        p.find("device").and_then(|v| v.as_str()),
        Some("canBusFtSensor")
    );
    let mut pd = PolyDriver::open(&p).unwrap_or_else(|e| panic!("{e}"));
    let dev = pd.device();
    let ft = dev.as_six_axis_force_torque_sensors().unwrap();
    assert_eq!(ft.get_nr_of_six_axis_force_torque_sensors(), 1);
    assert_eq!(
        ft.get_six_axis_force_torque_sensor_name(0).unwrap(),
        "l_arm_ft"
    );
    assert!(eventually(Duration::from_secs(2), || ft
        .get_six_axis_force_torque_sensor_status(0)
        == MasStatus::Ok));
    let m = ft.get_six_axis_force_torque_sensor_measure(0).unwrap();
    assert_eq!(m.values.len(), 6);
    // the emulated wrench: fz = 10 ± 5 N, tx = 0.1 ± 0.2 N·m
    assert!((5.0..=15.0).contains(&m.values[2]), "{:?}", m.values);
    assert!((-0.15..=0.35).contains(&m.values[3]), "{:?}", m.values);
    let analog = dev.as_analog_sensor().unwrap();
    assert_eq!(analog.get_channels(), 6);
    let mut v = Vec::new();
    assert_eq!(analog.read(&mut v), AnalogStatus::Ok);
    assert_eq!(v.len(), 6);
}

#[test]
fn silent_boards_fail_calls_within_their_timeouts() {
    yarp_devices::Registry::install(icubmod::register);
    let (url, emu) = inproc_network(1, "silent");
    let Some(mut pd) = open_left_arm(&url) else {
        return;
    };
    let dev = pd.device();
    let enc = dev.as_encoders().unwrap();
    assert!(eventually(Duration::from_secs(2), || enc
        .get_encoder(2)
        .is_ok()));
    emu.set_silent(2, true); // joints 2 and 3
    let t = Instant::now();
    assert!(eventually(Duration::from_secs(2), || enc
        .get_encoder(2)
        .is_err()));
    assert!(
        t.elapsed() < Duration::from_millis(1500),
        "{:?}",
        t.elapsed()
    );
    let err = enc.get_encoders().unwrap_err().to_string();
    // the error says which device and which board, not just that something failed
    assert!(
        err.contains("left_arm_mc") && err.contains("board 2"),
        "{err}"
    );
    assert!(enc.get_encoder(0).is_ok(), "other boards unaffected");
    let t = Instant::now();
    let done = dev.as_position_control().unwrap().check_motion_done(3);
    assert!(done.is_err());
    assert!(t.elapsed() < Duration::from_secs(2), "{:?}", t.elapsed());

    // opening with a board already silent fails at once, naming the board
    let t = Instant::now();
    let p = icub_params(
        "hardware/motorControl/icub_left_arm.xml",
        "left_arm_mc",
        &url,
    )
    .unwrap();
    let err = PolyDriver::open(&p).err().expect("open must fail");
    assert!(t.elapsed() < Duration::from_secs(3), "{:?}", t.elapsed());
    assert!(err.to_string().contains("[2]"), "{err}");

    // the strain of a network nobody emulates: a clear error, no hang
    let (quiet, _) = (format!("inproc://nobody-{}", std::process::id()), ());
    let p = icub_params("hardware/FT/left_arm_strain.xml", "left_arm_strain", &quiet).unwrap();
    let t = Instant::now();
    assert!(PolyDriver::open(&p).is_err());
    assert!(t.elapsed() < Duration::from_secs(3));
}

#[test]
fn missing_backend_is_a_clear_error() {
    yarp_devices::Registry::install(icubmod::register);
    let Some(mut p) = icub_params(
        "hardware/motorControl/icub_left_arm.xml",
        "left_arm_mc",
        "inproc://unused",
    ) else {
        return;
    };
    p.unput("canBackend");
    if std::env::var_os(icubmod::common::BACKEND_ENV).is_some() {
        return;
    }
    let err = PolyDriver::open(&p).err().expect("cfw2can has no driver");
    assert!(err.to_string().contains("canBackend"), "{err}");
    assert!(err.to_string().contains("cfw2can"), "{err}");
}

#[test]
fn skin_and_inertial_of_the_left_arm() {
    yarp_devices::Registry::install(icubmod::register);
    let (url, _emu) = inproc_network(7, "skin");
    let Some(p) = icub_params("hardware/skin/left_arm.xml", "left_arm_skin", &url) else {
        return;
    };
    let mut skin = PolyDriver::open(&p).unwrap_or_else(|e| panic!("{e}"));
    let analog = skin.device().as_analog_sensor().unwrap();
    assert_eq!(analog.get_channels(), 7 * 192);
    let mut v = Vec::new();
    assert!(eventually(Duration::from_secs(2), || analog.read(&mut v)
        == AnalogStatus::Ok));
    assert_eq!(v.len(), 1344);
    let patches = skin.device().as_skin_patches().unwrap();
    assert_eq!(patches.get_skin_patch_size(0), 1344);

    let p = icub_params(
        "hardware/skin/left_hand_inertial_mtb.xml",
        "left_hand_inertial_mtb",
        &url,
    )
    .unwrap();
    let mut imu = PolyDriver::open(&p).unwrap_or_else(|e| panic!("{e}"));
    let dev = imu.device();
    let analog = dev.as_analog_sensor().unwrap();
    assert_eq!(analog.get_channels(), 6);
    assert!(eventually(Duration::from_secs(2), || analog.read(&mut v)
        == AnalogStatus::Ok));
    let acc = dev.as_three_axis_linear_accelerometers().unwrap();
    assert_eq!(acc.get_nr_of_three_axis_linear_accelerometers(), 1);
    assert_eq!(
        acc.get_three_axis_linear_accelerometer_measure(0)
            .unwrap()
            .values
            .len(),
        3
    );
    let gyro = dev.as_three_axis_gyroscopes().unwrap();
    assert_eq!(
        gyro.get_three_axis_gyroscope_measure(0)
            .unwrap()
            .values
            .len(),
        3
    );
}

fn calibrator() -> Option<PolyDriver> {
    let p = icub_params(
        "calibrators/left_arm_calib.xml",
        "left_arm_calibrator",
        "unused",
    )?;
    Some(PolyDriver::open(&p).unwrap_or_else(|e| panic!("{e}")))
}

#[test]
fn parametric_calibrator_calibrates_and_parks_the_left_arm() {
    yarp_devices::Registry::install(icubmod::register);
    let (url, _emu) = inproc_network(1, "calib");
    let Some(pd) = open_left_arm(&url) else {
        return;
    };
    let target: SharedDevice = shared(pd);
    let mut cal = calibrator().unwrap();
    let c = cal.device().as_calibrator().unwrap();
    std::thread::sleep(Duration::from_millis(100));
    c.calibrate(target.clone())
        .unwrap_or_else(|e| panic!("{e}"));
    let startup = [-30.0, 30.0, 0.0, 45.0, 0.0, 0.0, 0.0, 30.0];
    let mut t = target.lock();
    let enc = t.device().as_encoders().unwrap().get_encoders().unwrap();
    for j in 0..8 {
        assert!((enc[j] - startup[j]).abs() < 2.0, "joint {j}: {enc:?}");
    }
    assert_eq!(
        t.device()
            .as_control_mode()
            .unwrap()
            .get_control_modes()
            .unwrap(),
        vec![CM_POSITION; 8]
    );
    drop(t);
    c.park(target.clone(), true)
        .unwrap_or_else(|e| panic!("{e}"));
    // positionHome, with the wrist yaw's 40° clamped by the board to jntPosMax 25°
    let home = [-30.0, 30.0, 0.0, 45.0, 0.0, 0.0, 25.0, 30.0];
    let mut t = target.lock();
    let enc = t.device().as_encoders().unwrap().get_encoders().unwrap();
    for j in 0..8 {
        assert!((enc[j] - home[j]).abs() < 2.0, "joint {j}: {enc:?}");
    }
}

#[test]
fn calibrator_reports_a_silent_board() {
    yarp_devices::Registry::install(icubmod::register);
    let (url, emu) = inproc_network(1, "calib-silent");
    let Some(pd) = open_left_arm(&url) else {
        return;
    };
    let target: SharedDevice = shared(pd);
    let mut cal = calibrator().unwrap();
    emu.set_silent(1, true);
    let t = Instant::now();
    let c = cal.device().as_calibrator().unwrap();
    assert!(c.calibrate(target).is_err());
    assert!(t.elapsed() < Duration::from_secs(5), "{:?}", t.elapsed());
}

#[test]
fn malformed_frames_are_counted_and_ignored() {
    yarp_devices::Registry::install(icubmod::register);
    use icub_can::proto::{make_id, mc::per, MsgClass};
    use icubmod::CanMotionControl;
    use yarp_devices::DeviceDriver;
    let (url, _emu) = inproc_network(1, "malformed");
    let Some(p) = icub_params(
        "hardware/motorControl/icub_left_arm.xml",
        "left_arm_mc",
        &url,
    ) else {
        return;
    };
    let mut mc = CanMotionControl::new();
    mc.open(&p).unwrap_or_else(|e| panic!("{e}"));
    let enc = mc.as_encoders().unwrap();
    assert!(eventually(Duration::from_secs(2), || enc
        .get_encoders()
        .is_ok()));
    // a position broadcast of board 1 carries 8 bytes: 3 is malformed
    let bad = icub_can::CanFrame::new(
        make_id(MsgClass::PeriodicMotorControl, 1, per::POSITION),
        &[1, 2, 3],
    )
    .unwrap();
    let name = url.trim_start_matches("inproc://");
    let injector = VirtualBus::named(name).endpoint();
    for _ in 0..5 {
        injector.send(&bad).unwrap();
    }
    let client = mc.client().unwrap().clone();
    assert!(eventually(Duration::from_secs(1), || client
        .malformed_frames()
        >= 5));
    let enc = mc.as_encoders().unwrap();
    assert!(enc.get_encoders().is_ok());
    assert!(mc.client().unwrap().board_health().iter().all(|b| b.alive));
}

#[test]
fn impedance_round_trips_and_a_compliant_elbow_follows_its_spring() {
    yarp_devices::Registry::install(icubmod::register);
    let (url, _emu) = inproc_network(1, "impedance");
    let Some(mut pd) = open_left_arm(&url) else {
        return;
    };
    move_elbow(&mut pd);
    let dev = pd.device();
    let imp = dev.as_impedance_control().unwrap();
    imp.set_impedance(3, 0.3, 0.003).unwrap();
    let (k, d) = imp.get_impedance(3).unwrap();
    // quantized to whole sensor units per tick: 0.3 N·m/° · 4096 / 11.375 ≈ 108
    assert!(
        (k - 0.3).abs() < 3e-3 && (d - 0.003).abs() < 3e-5,
        "{k} {d}"
    );
    imp.set_impedance_offset(3, -0.25).unwrap();
    assert!((imp.get_impedance_offset(3).unwrap() + 0.25).abs() < 1e-3);
    imp.set_impedance_offset(3, 0.0).unwrap();
    assert!(imp.get_impedance(8).is_err());
    // Compliant in position mode: the MC4 impedance law through the torque PID pulls the
    // joint to its reference.
    dev.as_interaction_mode()
        .unwrap()
        .set_interaction_mode(3, yarp_devices::vocabs::IM_COMPLIANT)
        .unwrap();
    let pos = dev.as_position_control().unwrap();
    pos.position_move(3, 40.0).unwrap();
    let reached = eventually(Duration::from_secs(5), || {
        dev.as_encoders()
            .unwrap()
            .get_encoder(3)
            .is_ok_and(|q| (q - 40.0).abs() < 1.0)
    });
    assert!(reached, "compliant elbow did not reach 40°");
    // Without stiffness (damping only) nothing holds the reference: the joint stays.
    let imp = dev.as_impedance_control().unwrap();
    imp.set_impedance(3, 0.0, 0.003).unwrap();
    std::thread::sleep(Duration::from_millis(100));
    let at = dev.as_encoders().unwrap().get_encoder(3).unwrap();
    dev.as_position_control()
        .unwrap()
        .position_move(3, 60.0)
        .unwrap();
    std::thread::sleep(Duration::from_millis(800));
    let now = dev.as_encoders().unwrap().get_encoder(3).unwrap();
    assert!((now - at).abs() < 2.0, "{at} -> {now}");
}

#[test]
fn remote_calibrator_homes_parks_and_quits_without_locking_its_target() {
    yarp_devices::Registry::install(icubmod::register);
    use icubmod::ParametricCalibrator;
    use yarp_devices::DeviceDriver;
    let (url, _emu) = inproc_network(1, "remote-calib");
    let Some(pd) = open_left_arm(&url) else {
        return;
    };
    let target: SharedDevice = shared(pd);
    let p = icub_params(
        "calibrators/left_arm_calib.xml",
        "left_arm_calibrator",
        "unused",
    )
    .unwrap();
    let mut cal = ParametricCalibrator::new();
    cal.open(&p).unwrap_or_else(|e| panic!("{e}"));
    use yarp_devices::interfaces::IRemoteCalibrator;
    // nothing to drive before the target is known
    assert!(cal.homing_single_joint(3).is_err());
    std::thread::sleep(Duration::from_millis(100));
    cal.as_calibrator()
        .unwrap()
        .calibrate(target.clone())
        .unwrap_or_else(|e| panic!("{e}"));

    // The remote calls come while the caller holds the target: hold it here too.
    let mut t = target.lock();
    let dev = t.device();
    dev.as_position_control()
        .unwrap()
        .position_move(3, 60.0)
        .unwrap();
    assert!(eventually(Duration::from_secs(5), || dev
        .as_encoders()
        .unwrap()
        .get_encoder(3)
        .is_ok_and(|q| (q - 60.0).abs() < 1.0)));
    let start = Instant::now();
    cal.homing_single_joint(3).unwrap_or_else(|e| panic!("{e}"));
    assert!(start.elapsed() < Duration::from_secs(5));
    let q = dev.as_encoders().unwrap().get_encoder(3).unwrap();
    assert!((q - 45.0).abs() < 1.0, "elbow homed to {q}");
    assert!(
        cal.homing_single_joint(8).is_err(),
        "only the calibrator's joints"
    );

    // calibrateSingleJoint: the board's calibration, then the startup position.
    dev.as_position_control()
        .unwrap()
        .position_move(3, 70.0)
        .unwrap();
    std::thread::sleep(Duration::from_millis(300));
    cal.calibrate_single_joint(3)
        .unwrap_or_else(|e| panic!("{e}"));
    let q = dev.as_encoders().unwrap().get_encoder(3).unwrap();
    assert!((q - 45.0).abs() < 2.0, "elbow back at startup: {q}");

    // quitPark stops a running homing: the elbow far away, homing at 10°/s takes
    // seconds; the quit flag ends the wait at once.
    dev.as_position_control()
        .unwrap()
        .set_ref_speed(3, 100.0)
        .unwrap();
    dev.as_position_control()
        .unwrap()
        .position_move(3, 100.0)
        .unwrap();
    assert!(eventually(Duration::from_secs(5), || dev
        .as_encoders()
        .unwrap()
        .get_encoder(3)
        .is_ok_and(|q| (q - 100.0).abs() < 1.0)));
    let quit = cal.quit_handle();
    let stopper = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(300));
        quit.store(true, std::sync::atomic::Ordering::SeqCst);
    });
    let start = Instant::now();
    assert!(cal.homing_whole_part().is_err(), "stopped by the quit");
    assert!(
        start.elapsed() < Duration::from_secs(2),
        "{:?}",
        start.elapsed()
    );
    stopper.join().unwrap();
    cal.quit_park().unwrap();

    // parkWholePart: every calibrated joint at positionHome (wrist yaw clamped at 25°).
    cal.park_whole_part().unwrap_or_else(|e| panic!("{e}"));
    let home = [-30.0, 30.0, 0.0, 45.0, 0.0, 0.0, 25.0, 30.0];
    let enc = dev.as_encoders().unwrap().get_encoders().unwrap();
    for j in 0..8 {
        assert!((enc[j] - home[j]).abs() < 2.0, "joint {j}: {enc:?}");
    }
    drop(t);
}

/// parametricCalibrator sends each joint's calibration through the target's
/// `IControlCalibration` (C++ `calibrateAxisWithParams`), so it calibrates any board that
/// offers it, here a fakeMotionControl, then moves the joints to their startup position.
#[test]
fn parametric_calibrator_calibrates_a_fake_board_through_icontrolcalibration() {
    yarp_devices::Registry::install(icubmod::register);
    let fake = shared(PolyDriver::from_driver(
        "fakeMotionControl",
        Box::new(yarp_devices::FakeMotionControl::with_joints(2)),
    ));
    let mut cal = PolyDriver::open(
        &Property::from_config_text(
            "device parametricCalibrator\nCALIB_ORDER (0) (1)\n\
             [GENERAL]\ndeviceName fake_calibrator\njoints 2\n\
             [CALIBRATION]\ncalibrationType 3 3\ncalibration1 0 0\ncalibration2 0 0\n\
             calibration3 0 0\nstartupPosition 10 -20\nstartupVelocity 10 10\n\
             startupPosThreshold 2 2\n\
             [HOME]\npositionHome 0 0\nvelocityHome 10 10\n\
",
        )
        .unwrap(),
    )
    .expect("open parametricCalibrator");
    cal.device()
        .as_calibrator()
        .unwrap()
        .calibrate(fake.clone())
        .expect("calibrate the fake");
    let mut pd = fake.lock();
    let enc = pd.device().as_encoders().unwrap();
    let (q0, q1) = (enc.get_encoder(0).unwrap(), enc.get_encoder(1).unwrap());
    assert!(
        (q0 - 10.0).abs() <= 2.0 && (q1 + 20.0).abs() <= 2.0,
        "{q0} {q1}"
    );
}
