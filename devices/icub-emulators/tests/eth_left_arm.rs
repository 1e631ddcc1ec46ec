//! iCubGenova02's left arm, unmodified from robots-configuration, against the emulated
//! Ethernet boards on loopback (through the address map 10.0.1.0/24 -> 127.0.1.0/24):
//! `embObjMotionControl` opens both boards (bring-up, service activation, joint and
//! motor configuration, regulars), a position move reaches the encoders, a calibration
//! ends, the PWM limit is asked and set, torque references and measures, the external
//! torque input and the impedance round-trip through the board's µN·m, the arm's strain,
//! the hand's MAIS and a foot's
//! strain2 with its temperature stream, and a board that stops answering is reported
//! naming its IP and name.
//!
//! The host's socket is a process singleton (as C++'s `TheEthManager`), so everything
//! runs in one test function.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use icub_emulators::eth::{robot_boards, serve};
use icub_emulators::eth::{AddressMap, ADDRESS_MAP_ENV};
use icubmod::eth::{EmbObjFtSensor, EmbObjMais, EmbObjMotionControl};
use yarp_devices::interfaces::CalibrationParameters;
use yarp_devices::robotinterface::read_robot_file;
use yarp_devices::vocabs::{CM_IDLE, CM_POSITION, PIDTYPE_CURRENT, PIDTYPE_POSITION};
use yarp_devices::DeviceDriver;
use yarp_proto::Property;

const MAP: &str = "10.0.1.0/24=127.0.1.0/24";

fn robot_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/robots-configuration/iCubGenova02")
}

fn wait_for(what: &str, timeout: Duration, mut f: impl FnMut() -> bool) {
    let start = Instant::now();
    while !f() {
        assert!(start.elapsed() < timeout, "{what}: not within {timeout:?}");
        std::thread::sleep(Duration::from_millis(10));
    }
}

#[test]
fn left_arm_boards_open_move_calibrate_and_report_silence() {
    std::env::set_var(ADDRESS_MAP_ENV, MAP);
    let dir = robot_dir();
    let top = dir.join("icub_all.xml");
    let specs = robot_boards(&dir, Some(&top)).expect("robot boards");
    let stop = Arc::new(AtomicBool::new(false));
    let (_served, threads) = serve(specs, &AddressMap::parse(MAP).unwrap(), stop.clone())
        .expect("the emulator binds 127.0.1.x");

    let robot = read_robot_file(&top, &Property::default())
        .expect("icub_left_arm.xml")
        .robot;
    let cfg = |name: &str| robot.device(name).expect(name).to_property().unwrap();

    let t0 = Instant::now();
    let mut eb1 = EmbObjMotionControl::new();
    eb1.open(&cfg("left_arm-eb1-j0_3-mc")).expect("eb1 opens");
    let mut eb2 = EmbObjMotionControl::new();
    eb2.open(&cfg("left_arm-eb2-j4_15-mc")).expect("eb2 opens");
    eprintln!("two boards up in {:?}", t0.elapsed());

    let enc = eb1.as_encoders().unwrap();
    assert_eq!(enc.get_axes().unwrap(), 4);
    assert_eq!(eb2.as_encoders().unwrap().get_axes().unwrap(), 12);
    assert_eq!(
        eb1.as_axis_info().unwrap().get_axis_name(3).unwrap(),
        "l_elbow"
    );
    // Joints start idle, inside their limits (l_shoulder_roll: 9..160 deg).
    assert_eq!(
        eb1.as_control_mode().unwrap().get_control_mode(0).unwrap(),
        CM_IDLE
    );
    let roll = eb1.as_encoders().unwrap().get_encoder(1).unwrap();
    assert!((roll - 9.0).abs() < 0.1, "l_shoulder_roll at {roll}");
    // asked of the board, 2 raw units inside them (C++ getLimitsRaw's SAFETY_THRESHOLD)
    let (lo, hi) = eb1.as_control_limits().unwrap().get_limits(0).unwrap();
    assert!(
        (lo + 95.5).abs() < 0.02 && (hi - 8.0).abs() < 0.02,
        "{lo} {hi}"
    );

    // Calibration (type 12, as left_arm-calib.xml) ends in position control.
    let cal = eb1.as_control_calibration().unwrap();
    cal.set_calibration_parameters(
        0,
        &CalibrationParameters {
            kind: 12,
            param1: 35711.0,
            ..Default::default()
        },
    )
    .unwrap();
    wait_for("calibration done", Duration::from_secs(5), || {
        eb1.as_control_calibration()
            .unwrap()
            .calibration_done(0)
            .unwrap()
    });

    // The motor config's PWM limit (what parametricCalibratorEth lowers to startupMaxPwm
    // while calibrating), asked of and set on the board.
    let amp = eb1.as_amplifier_control().unwrap();
    let limit = amp.get_pwm_limit(0).unwrap();
    assert!(limit > 0.0, "pwmLimit {limit}");
    amp.set_pwm_limit(0, 1234.0).unwrap();
    assert_eq!(amp.get_pwm_limit(0).unwrap(), 1234.0);
    assert!(
        amp.set_pwm_limit(0, -1.0).is_err(),
        "a negative limit is refused"
    );
    amp.set_pwm_limit(0, limit).unwrap();
    assert_eq!(amp.get_pwm_limit(0).unwrap(), limit);

    // Position control: the encoder follows.
    eb1.as_control_mode()
        .unwrap()
        .set_control_mode(0, CM_POSITION)
        .unwrap();
    let pc = eb1.as_position_control().unwrap();
    pc.set_ref_speed(0, 50.0).unwrap();
    pc.position_move(0, -20.0).unwrap();
    let sent = Instant::now();
    wait_for("joint 0 at -20 deg", Duration::from_secs(5), || {
        (eb1.as_encoders().unwrap().get_encoder(0).unwrap() + 20.0).abs() < 0.5
    });
    eprintln!("command to encoder within 0.5 deg: {:?}", sent.elapsed());
    wait_for("motion done", Duration::from_secs(5), || {
        eb1.as_position_control()
            .unwrap()
            .check_motion_done(0)
            .unwrap()
    });

    // A relative move starts from the last goal in this mode (-20 + 5)...
    eb1.as_position_control()
        .unwrap()
        .relative_move(0, 5.0)
        .unwrap();
    wait_for("joint 0 at -15 deg", Duration::from_secs(5), || {
        (eb1.as_encoders().unwrap().get_encoder(0).unwrap() + 15.0).abs() < 0.5
    });
    // ...and after a change of control mode, from where the joint is; a position move in
    // velocity mode is skipped (as C++), not sent.
    let cm = eb1.as_control_mode().unwrap();
    cm.set_control_mode(0, yarp_devices::vocabs::CM_VELOCITY)
        .unwrap();
    eb1.as_position_control()
        .unwrap()
        .position_move(0, -60.0)
        .unwrap();
    std::thread::sleep(Duration::from_millis(200));
    let here = eb1.as_encoders().unwrap().get_encoder(0).unwrap();
    assert!(
        (here + 15.0).abs() < 0.5,
        "a skipped move moved the joint to {here}"
    );
    eb1.as_control_mode()
        .unwrap()
        .set_control_mode(0, CM_POSITION)
        .unwrap();
    eb1.as_position_control()
        .unwrap()
        .relative_move(0, -3.0)
        .unwrap();
    wait_for("joint 0 at -18 deg", Duration::from_secs(5), || {
        (eb1.as_encoders().unwrap().get_encoder(0).unwrap() + 18.0).abs() < 0.5
    });
    // the deprecated disableAmp leaves the joint as it is (a no-op in C++)
    eb1.as_amplifier_control().unwrap().disable_amp(0).unwrap();
    assert_eq!(
        eb1.as_control_mode().unwrap().get_control_mode(0).unwrap(),
        CM_POSITION
    );

    torque_impedance_and_temperature(&mut eb1);

    // The arm's F/T sensor (strain on eb1) and the hand's MAIS (eb2) stream.
    let mut ft = EmbObjFtSensor::new();
    ft.open(&cfg("left_arm-eb1-j0_3-strain"))
        .expect("strain opens");
    let fts = ft.as_six_axis_force_torque_sensors().unwrap();
    assert_eq!(
        fts.get_six_axis_force_torque_sensor_name(0).unwrap(),
        "l_arm_ft"
    );
    wait_for("an F/T reading", Duration::from_secs(2), || {
        ft.as_six_axis_force_torque_sensors()
            .unwrap()
            .get_six_axis_force_torque_sensor_measure(0)
            .is_ok_and(|m| m.values.len() == 6 && (m.values[2] - 200.0).abs() < 1.0)
    });
    let mut mais = EmbObjMais::new();
    mais.open(&cfg("left_arm-eb2-j4_15-mais"))
        .expect("mais opens");
    let mut v = Vec::new();
    wait_for("MAIS values", Duration::from_secs(2), || {
        mais.as_analog_sensor().unwrap().read(&mut v)
            == yarp_devices::sensors::interfaces::AnalogStatus::Ok
            && v.len() == 15
            && v.iter().any(|x| *x != 0.0)
    });
    // as icub-main 2.11, one encoder array (what the robot's multipleanalogsensorsserver
    // publishes) named by SENSORS/id
    let arrays = mais.as_encoder_arrays().expect("IEncoderArrays");
    assert_eq!(arrays.get_nr_of_encoder_arrays(), 1);
    assert_eq!(arrays.get_encoder_array_name(0).unwrap(), "l_hand_mais");
    assert_eq!(arrays.get_encoder_array_size(0), 15);
    // the same values as the analog reading (the MAIS streams on: two reads in a row agree
    // once no new sample came between them)
    wait_for(
        "the encoder array as the analog reading",
        Duration::from_secs(2),
        || {
            let _ = mais.as_analog_sensor().unwrap().read(&mut v);
            let arrays = mais.as_encoder_arrays().unwrap();
            arrays.get_encoder_array_measure(0).unwrap().values == v
        },
    );

    // The hand's skin with its skinSpec (new style): every triangle disabled by
    // default, then 20 special sets enable some (board 14: triangles 0-6 and 8-11).
    // Enabled triangles stream; the others keep the boards' noLoad (0xf0).
    let mut skin = icubmod::eth::EmbObjSkin::new();
    skin.open(&cfg("left_arm-eb2-j4_15-skin"))
        .expect("the skin opens and configures its MTBs");
    let mut taxels = Vec::new();
    wait_for(
        "the enabled triangles stream",
        Duration::from_secs(3),
        || {
            skin.as_analog_sensor().unwrap().read(&mut taxels)
                == yarp_devices::sensors::interfaces::AnalogStatus::Ok
                && taxels.len() == 7 * 192
                && taxels[0] != 240.0
                && taxels[8 * 12] != 240.0
        },
    );
    // board 14 (the first of the patch): triangle 7 and 12-15 stay disabled
    assert!(
        taxels[7 * 12..8 * 12].iter().all(|t| *t == 240.0),
        "{:?}",
        &taxels[84..96]
    );
    assert!(taxels[12 * 12..16 * 12].iter().all(|t| *t == 240.0));
    skin.close().unwrap();

    // The left foot's strain2 (its file asks for the temperature every 1000 ms): the
    // temperature service comes up beside the strain, and its reading is in °C.
    let mut foot = EmbObjFtSensor::new();
    foot.open(&cfg("left_leg-eb7-j4_5-strain"))
        .expect("the foot's strain2 opens with its temperature");
    let mut celsius = 0.0;
    wait_for(
        "a temperature reading",
        Duration::from_secs(3),
        || match foot
            .as_temperature_sensors()
            .unwrap()
            .get_temperature_sensor_measure(0)
        {
            Ok(m) => {
                celsius = m.values[0];
                true
            }
            Err(_) => false,
        },
    );
    assert!((20.0..31.0).contains(&celsius), "{celsius} °C");
    assert_eq!(
        foot.as_six_axis_force_torque_sensors()
            .unwrap()
            .get_six_axis_force_torque_sensor_name(0)
            .unwrap(),
        "l_foot_ft"
    );
    foot.close().unwrap();

    // The board falls silent: reported after its 20 ms presence timeout; readings fail
    // after ten times that (at least 0.5 s), naming IP and board.
    stop.store(true, Ordering::SeqCst);
    for t in threads {
        t.join().unwrap();
    }
    let silent = Instant::now();
    let mut err = None;
    wait_for("silence reported", Duration::from_secs(2), || {
        match eb1.as_encoders().unwrap().get_encoder(0) {
            Err(e) => {
                err = Some(e.to_string());
                true
            }
            Ok(_) => false,
        }
    });
    let err = err.unwrap();
    eprintln!("after {:?}: {err}", silent.elapsed());
    assert!(silent.elapsed() < Duration::from_millis(1000));
    assert!(err.contains("10.0.1.1 (left_arm-eb1-j0_3)"), "{err}");
    eb1.close().unwrap();
    eb2.close().unwrap();
}

/// Torque, impedance and temperature through the board in its units (µN·m, µN·m per
/// encoder unit, the motor sensor's raw reading), in N·m, N·m/deg and °C at the device.
fn torque_impedance_and_temperature(eb1: &mut EmbObjMotionControl) {
    use yarp_devices::vocabs::{CM_TORQUE, PIDTYPE_TORQUE};
    // l_shoulder_pitch (TRQ_PID_DEFAULT) in torque control: the reference goes as
    // 1.5e6 µN·m; the board reports it back (ofpid reftrq) and its measure follows it.
    eb1.as_control_mode()
        .unwrap()
        .set_control_mode(0, CM_TORQUE)
        .unwrap();
    let trq = eb1.as_torque_control().unwrap();
    trq.set_ref_torque(0, 1.5).unwrap();
    wait_for("torque reference reported", Duration::from_secs(2), || {
        let t = eb1.as_torque_control().unwrap();
        (t.get_ref_torque(0).unwrap() - 1.5).abs() < 1e-6
            && (t.get_torque(0).unwrap() - 1.5).abs() < 1e-3
    });
    // the torque PID error (µN·m on the board) in N·m
    let err = eb1
        .as_pid_control()
        .unwrap()
        .get_pid_error(PIDTYPE_TORQUE, 0)
        .unwrap();
    assert!(err.abs() < 1e-3, "torque error {err} N·m");
    let trq = eb1.as_torque_control().unwrap();
    trq.set_ref_torque(0, -0.25).unwrap();
    wait_for("a negative torque", Duration::from_secs(2), || {
        let t = eb1.as_torque_control().unwrap();
        (t.get_ref_torque(0).unwrap() + 0.25).abs() < 1e-6
            && (t.get_torque(0).unwrap() + 0.25).abs() < 1e-3
    });
    eb1.as_control_mode()
        .unwrap()
        .set_control_mode(0, CM_POSITION)
        .unwrap();
    // out of torque control C++ reads no torque reference
    assert_eq!(
        eb1.as_torque_control().unwrap().get_ref_torque(0).unwrap(),
        0.0
    );

    // wholeBodyDynamics' estimate (virtual analog sensor) goes as µN·m and comes back
    // as the joint's torque measure.
    eb1.as_virtual_analog_sensor()
        .unwrap()
        .update_virtual_analog_sensor_channel(1, 0.75)
        .unwrap();
    wait_for(
        "the external torque measured",
        Duration::from_secs(2),
        || (eb1.as_torque_control().unwrap().get_torque(1).unwrap() - 0.75).abs() < 1e-6,
    );

    // Impedance: N·m/deg on the device, µN·m per encoder unit on the board; the file's
    // 0.1 and 0.05 first, then a new value and an offset (1e6 µN·m per N·m).
    let imp = eb1.as_impedance_control().unwrap();
    let (k, d) = imp.get_impedance(2).unwrap();
    assert!((k - 0.1).abs() < 1e-6 && (d - 0.05).abs() < 1e-6, "{k} {d}");
    imp.set_impedance(2, 0.3, 0.02).unwrap();
    let (k, d) = imp.get_impedance(2).unwrap();
    assert!((k - 0.3).abs() < 1e-6 && (d - 0.02).abs() < 1e-6, "{k} {d}");
    imp.set_impedance_offset(2, -0.4).unwrap();
    assert!((imp.get_impedance_offset(2).unwrap() + 0.4).abs() < 1e-9);

    // PIDs are asked of the board (C++ `helper_get*PidRaw`): a new position gain set on
    // the board reads back through its units (f32 on the wire).
    let pids = eb1.as_pid_control().unwrap();
    let mut pid = pids.get_pid(PIDTYPE_POSITION, 0).unwrap();
    assert!(pid.kp != 0.0, "the file's position PID: {pid:?}");
    pid.kp *= 2.0;
    pid.max_output *= 0.5;
    pids.set_pid(PIDTYPE_POSITION, 0, pid).unwrap();
    let back = pids.get_pid(PIDTYPE_POSITION, 0).unwrap();
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-6 * a.abs().max(1.0);
    assert!(
        close(back.kp, pid.kp) && close(back.max_output, pid.max_output),
        "{back:?} {pid:?}"
    );
    let current = pids.get_pid(PIDTYPE_CURRENT, 0).unwrap();
    assert!(current.kp.is_finite(), "{current:?}");

    // The amplifier's current limits are asked of the board and changed there (A over
    // the board's mA, `ampsToSensor`); PWM and supply voltage are the board's raw values.
    let amp = eb1.as_amplifier_control().unwrap();
    let nominal = amp.get_nominal_current(1).unwrap();
    let peak = amp.get_peak_current(1).unwrap();
    let max = amp.get_max_current(1).unwrap();
    assert!(
        nominal > 0.0 && peak >= nominal && max > 0.0,
        "{nominal} {peak} {max}"
    );
    amp.set_peak_current(1, peak - 0.25).unwrap();
    amp.set_max_current(1, max + 0.5).unwrap();
    assert!((amp.get_peak_current(1).unwrap() - (peak - 0.25)).abs() < 2e-3);
    assert!((amp.get_max_current(1).unwrap() - (max + 0.5)).abs() < 2e-3);
    assert_eq!(
        amp.get_nominal_current(1).unwrap(),
        nominal,
        "the others kept"
    );
    assert_eq!(amp.get_power_supply_voltage(0).unwrap(), 4800.0);
    assert!(amp.get_pwm(0).unwrap().is_finite());

    // The reference acceleration is kept in encoder units, saturated at 1e6 (C++).
    let pc = eb1.as_position_control().unwrap();
    pc.set_ref_acceleration(0, 1e9).unwrap();
    let acc = pc.get_ref_acceleration(0).unwrap();
    assert!((acc - 1e6 / 182.044).abs() < 1e-6, "{acc}");
    pc.set_ref_acceleration(0, 100.0).unwrap();
    assert!((pc.get_ref_acceleration(0).unwrap() - 100.0).abs() < 1e-9);

    // iCubGenova02's arm motors have no temperature sensor (HasTempSensor 0): NaN, as C++.
    let t = eb1.as_motor().unwrap().get_temperature(0).unwrap();
    assert!(t.is_nan(), "{t}");
}
