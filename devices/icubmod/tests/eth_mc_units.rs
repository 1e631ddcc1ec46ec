//! What `embObjMotionControl` sends at start-up, in the firmware's units, from the robots'
//! unmodified files, with the numbers worked out from the files and icub-main's rules
//! (`embObjMotionControl::fromConfig_Step2` and `init()`, `eomcParser`, YARP's
//! `ControlBoardHelper`): torques in µN·m (`newtonsToSensor` 1e6), PID gains by their
//! units, `ktau2raw`, `impN2S`, the motor group of each service, the PT100 temperature
//! limit, the encoders by position, dead zones.

mod robot_files;
use icub_eth::entities::mc::{JointConfig, MotorConfig};
use icubmod::eth::mc_params::{McParams, PidKind, TemperatureSensor};
use icubmod::eth::EmbObjMotionControl;
use robot_files::{device_file, robot_devices};
use yarp_proto::Property;

fn mc(robot: &str, board: &str) -> McParams {
    let p = device_file(robot, &format!("hardware/motorControl/{board}-mc.xml"));
    McParams::read(&p).unwrap_or_else(|e| panic!("{board}: {e}"))
}

/// The same device's configuration with `edits` applied to its text.
fn edited(robot: &str, board: &str, edits: &[(&str, &str)]) -> Result<McParams, String> {
    let p = device_file(robot, &format!("hardware/motorControl/{board}-mc.xml"));
    let mut text = p.to_string();
    for (from, to) in edits {
        assert!(text.contains(from), "{from} not in {board}");
        text = text.replace(from, to);
    }
    McParams::read(&Property::from_text(&text)).map_err(|e| e.to_string())
}

fn configs(p: &McParams, j: usize) -> (JointConfig, MotorConfig) {
    EmbObjMotionControl::configs(p, j)
}

/// iCubGenova02 left_arm-eb1-j0_3-mc.xml, TRQ_PID_DEFAULT (fbkControlUnits metric_units,
/// outputControlUnits dutycycle_percent), joint 0 with fullscalePWM 32000 (320 PWM
/// counts per %): kp 0.5 × 320 / 1e6 = 1.6e-4, kp of joint 3 0.9 -> 2.88e-4,
/// maxOutput 25 × 320 = 8000, maxInt 1.56 × 320 = 499.2, kff 1 unchanged; ktau 0.68 ×
/// (320 / 1e6) = 2.176e-4; viscousPos 0.0032 as is (YARP's friction factors are 1).
#[test]
fn icub_left_arm_torque_pid_and_ktau_as_sent() {
    let p = mc("iCubGenova02", "left_arm-eb1-j0_3");
    assert_eq!(p.pid_factors(PidKind::Torque, 0), (1e6, 320.0));
    let (jc, _) = configs(&p, 0);
    let t = jc.pid_torque;
    assert_eq!(t.kp, (0.5 * 320.0 / 1e6) as f32);
    assert!((f64::from(t.kp) - 1.6e-4).abs() < 1e-10, "{}", t.kp);
    assert_eq!(t.ki, 0.0);
    assert_eq!(t.kd, 0.0);
    assert_eq!(t.limit_on_output, 8000.0);
    assert_eq!(t.limit_on_integral, (1.56f64 * 320.0) as f32);
    assert_eq!(t.kff, 1.0);
    assert_eq!(t.offset, 0.0);
    assert_eq!(t.scale, 0);
    let ktau = jc.motor_params.ktau_value;
    assert_eq!(ktau, (0.68 * (320.0 / 1e6)) as f32);
    assert!((f64::from(ktau) - 2.176e-4).abs() < 1e-10, "{ktau}");
    assert_eq!(jc.motor_params.friction[0], 0.0032);
    assert_eq!(jc.motor_params.bemf_value, 0.0, "no kbemf in the group");
    let (jc3, _) = configs(&p, 3);
    assert!((f64::from(jc3.pid_torque.kp) - 2.88e-4).abs() < 1e-10);
    // ktau 1.55 -> 4.96e-4
    assert!((f64::from(jc3.motor_params.ktau_value) - 4.96e-4).abs() < 1e-10);
}

/// The same board's POS_PID_DEFAULT (metric feedback, machine output): gains per
/// degree over Encoder 182.044 (kp 711.11 -> 3.90625..., ki 7111.09 -> 39.0625...),
/// limits as is; the 2FOC current and speed PIDs (machine units) as is, with `shift`;
/// piddirect left zero (C++ does not set it).
#[test]
fn icub_left_arm_position_and_low_level_pids_as_sent() {
    let p = mc("iCubGenova02", "left_arm-eb1-j0_3");
    let (jc, mc) = configs(&p, 0);
    let pos = jc.pid_trajectory;
    assert_eq!(pos.kp, (711.11 / 182.044) as f32);
    assert!((f64::from(pos.kp) - 3.906253).abs() < 1e-5);
    assert_eq!(pos.ki, (7111.09 / 182.044) as f32);
    assert_eq!(pos.limit_on_output, 8000.0);
    assert_eq!(pos.limit_on_integral, 200.0);
    assert_eq!(jc.pid_direct, Default::default());
    // 2FOC_CUR_CONTROL: kp 8, ki 2, shift 10, maxOutput 32000; 2FOC_VEL_CONTROL: kp 12, ki 16
    assert_eq!(
        (mc.pid_current.kp, mc.pid_current.ki, mc.pid_current.scale),
        (8.0, 2.0, 10)
    );
    assert_eq!(mc.pid_current.limit_on_output, 32000.0);
    assert_eq!((mc.pid_speed.kp, mc.pid_speed.ki), (12.0, 16.0));
}

/// IMPEDANCE stiffness 0.1 N·m/deg and damping 0.05 N·m/(deg/s) of iCubGenova02's left
/// arm: sent × 1e6 / 182.044 = 549.3177... and 274.6589... µN·m per encoder unit.
#[test]
fn icub_left_arm_impedance_as_sent() {
    let p = mc("iCubGenova02", "left_arm-eb1-j0_3");
    let (jc, _) = configs(&p, 0);
    assert_eq!(jc.impedance.stiffness, (0.1 * 1e6 / 182.044) as f32);
    assert!((f64::from(jc.impedance.stiffness) - 549.3177).abs() < 1e-3);
    assert!((f64::from(jc.impedance.damping) - 274.6589).abs() < 1e-3);
    assert_eq!(jc.impedance.offset, 0.0);
    // and back (impS2N)
    assert!((p.imp_from_raw(0, f64::from(jc.impedance.stiffness)) - 0.1).abs() < 1e-7);
}

/// iCubGenova02's left arm service: ENCODER1 aea atjoint (resolution -4096, tolerance
/// 0.703), ENCODER2 roie atmotor (-14400, 0); no OTHER_CONTROL_PARAMETERS, so the AEA
/// default dead zone 0.0494 deg = 8.9930 encoder units; 2FOC: hall sensor and rotor
/// encoder (flags 0b101), 8 poles, no temperature sensor (limit 0).
#[test]
fn icub_left_arm_encoders_deadzone_and_motor_config() {
    let p = mc("iCubGenova02", "left_arm-eb1-j0_3");
    assert_eq!(p.motor_group, Some("2FOC"));
    let (jc, mc) = configs(&p, 0);
    assert_eq!(jc.jnt_encoder_resolution, -4096);
    assert_eq!(jc.jnt_encoder_type, 1, "eomc_enc_aea");
    assert_eq!(jc.jnt_enc_tolerance, 0.703);
    assert_eq!(mc.rotor_encoder_resolution, -14400);
    assert_eq!(mc.rotor_encoder_type, 2, "eomc_enc_roie");
    assert_eq!(mc.rot_enc_tolerance, 0.0);
    assert_eq!(jc.deadzone, (0.0494 * 182.044) as f32);
    assert_eq!(mc.motor_poles, 8);
    assert_eq!(mc.flags, 0b101);
    assert_eq!(mc.temperature_limit, 0);
    assert_eq!(mc.kbemf, 0.0);
    assert_eq!(p.temperature_sensor[0], TemperatureSensor::None);
    // TIMEOUTS gives velocity only: the others 100 ms (eomn_serv_MC_foc)
    assert_eq!(jc.velocity_setpoint_timeout, 100);
    assert_eq!(jc.torque_feedback_timeout, 100);
}

/// ergoCubSN001 left_arm-eb2-j0_1 (eomn_serv_MC_foc with foc boards: group 2FOC):
/// joint 1 has a PT100 (TemperatureSensorType NONE PT100) with hardware limit 110 °C:
/// temperatureLimit = S_16(PT100 raw of 110 °C) = S_16(1370.52) = 1371; joint 0 none (0).
/// TRQ_PID_OUTPUT_CURR has machine-unit output: ktau 250 / 1e6 = 2.5e-4, kp 150 / 1e6,
/// maxOutput 2500 as is. OTHER_CONTROL_PARAMETERS deadZone 0.0049 deg × 182.044.
/// ENCODER1 amo atjoint -16384 / 0.703, ENCODER2 roie atmotor 14400 / 3.6; TIMEOUTS
/// torque_measure 300.
#[test]
fn ergocub_foc_board_pt100_limit_torque_units_deadzone() {
    let p = mc("ergoCubSN001", "left_arm-eb2-j0_1");
    assert_eq!(p.motor_group, Some("2FOC"));
    assert_eq!(
        p.temperature_sensor,
        [TemperatureSensor::None, TemperatureSensor::Pt100]
    );
    let (jc0, mc0) = configs(&p, 0);
    let (jc1, mc1) = configs(&p, 1);
    assert_eq!(mc0.temperature_limit, 0);
    assert_eq!(mc1.temperature_limit, 1371);
    assert_eq!(mc0.flags & 0b10, 0);
    assert_eq!(mc1.flags & 0b10, 0b10, "hasTempSensor");
    assert_eq!(mc1.motor_poles, 8);
    assert_eq!(mc1.rotor_index_offset, 279);
    assert_eq!(p.pid_factors(PidKind::Torque, 0), (1e6, 1.0));
    assert_eq!(jc0.motor_params.ktau_value, (250.0 / 1e6) as f32);
    assert_eq!(jc0.pid_torque.kp, (150.0 / 1e6) as f32);
    assert_eq!(jc0.pid_torque.limit_on_output, 2500.0);
    assert_eq!(jc0.deadzone, (0.0049 * 182.044) as f32);
    assert_eq!(jc0.jnt_encoder_type, 9, "eomc_enc_amo");
    assert_eq!(jc0.jnt_encoder_resolution, -16384);
    assert_eq!(mc1.rotor_encoder_resolution, 14400);
    assert_eq!(mc1.rot_enc_tolerance, 3.6);
    assert_eq!(jc1.torque_feedback_timeout, 300);
    // stiffness 0.3 -> 1647.953...
    assert!((f64::from(jc0.impedance.stiffness) - 1647.9532).abs() < 1e-3);
}

/// ergoCubSN001 left_arm-eb31-j4_6 (eomn_serv_MC_advfoc): the ADVFOC group of its
/// mechanicals: 14 poles, hall sensor only (flags 1), no temperature sensor; its
/// encoders: aea3 atjoint 16384 / 0.4 (dead zone 0 by default for AEA3), ENCODER2 "none"
/// atmotor with resolution 0.
#[test]
fn ergocub_advfoc_board_reads_its_advfoc_group() {
    let p = mc("ergoCubSN001", "left_arm-eb31-j4_6");
    assert_eq!(p.motor_group, Some("ADVFOC"));
    for j in 0..3 {
        let (jc, mc) = configs(&p, j);
        assert_eq!(mc.motor_poles, 14);
        assert_eq!(mc.flags, 0b1);
        assert_eq!(mc.temperature_limit, 0);
        assert_eq!(jc.jnt_encoder_type, 12, "eomc_enc_aea3");
        assert_eq!(jc.jnt_encoder_resolution, 16384);
        assert_eq!(jc.jnt_enc_tolerance, 0.4);
        assert_eq!(jc.deadzone, 0.0);
        assert_eq!(mc.rotor_encoder_type, 0);
        assert_eq!(mc.rotor_encoder_resolution, 0);
        assert_eq!(jc.pid_torque, Default::default(), "torqueControl none");
    }
}

/// The advfoc default timeout is 300 ms, 100 ms for the others (C++ `defaultTimeout`).
#[test]
fn advfoc_timeouts_default_to_300_ms() {
    let p = edited(
        "ergoCubSN001",
        "left_arm-eb31-j4_6",
        &[("(torque_measure 300 300 300)", "")],
    )
    .unwrap();
    assert_eq!(p.torque_fbk_timeout, [300.0; 3]);
    let p = edited(
        "ergoCubSN001",
        "left_arm-eb2-j0_1",
        &[("(torque_measure 300 300)", "")],
    )
    .unwrap();
    assert_eq!(p.torque_fbk_timeout, [100.0; 2]);
}

/// An `eomn_serv_MC_foc` service whose CAN boards are not 2FOC reads `AMCBLDC` (as C++):
/// ergoCub's left_arm-eb4-j2_3 with amcbldc boards and its motor group so named.
#[test]
fn foc_service_with_amc_boards_reads_amcbldc() {
    let amc = [
        ("(CANBOARDS (type foc)", "(CANBOARDS (type amcbldc)"),
        ("(\"2FOC\" ", "(AMCBLDC "),
    ];
    let p = edited("ergoCubSN001", "left_arm-eb4-j2_3", &amc).unwrap();
    assert_eq!(p.motor_group, Some("AMCBLDC"));
    let (_, mc) = configs(&p, 1);
    assert_eq!(mc.motor_poles, 8);
    assert_eq!(mc.rotor_index_offset, 96);
    // without the group: refused, naming it
    let e = edited("ergoCubSN001", "left_arm-eb4-j2_3", &amc[..1]).unwrap_err();
    assert!(e.contains("AMCBLDC"), "{e}");
}

/// `parseFocGroup`'s checks: HasTempSensor non-zero alone, a rotor index offset out of
/// [0, 359] or non-zero without an index, a missing MotorPoles; a PT100 without
/// temperature limits; a warning limit above 85 % of the hardware limit.
#[test]
fn motor_group_and_temperature_checks_as_cpp() {
    let arm = ("iCubGenova02", "left_arm-eb1-j0_3");
    let e = edited(
        arm.0,
        arm.1,
        &[("(HasTempSensor 0 0 0 0)", "(HasTempSensor 0 1 0 0)")],
    )
    .unwrap_err();
    assert!(e.contains("2FOC/HasTempSensor"), "{e}");
    let e = edited(
        arm.0,
        arm.1,
        &[
            (
                "(HasRotorEncoderIndex 0 0 0 0)",
                "(HasRotorEncoderIndex 1 1 1 1)",
            ),
            ("(RotorIndexOffset 0 0 0 0)", "(RotorIndexOffset 0 360 0 0)"),
        ],
    )
    .unwrap_err();
    assert!(
        e.contains("2FOC/RotorIndexOffset") && e.contains("360"),
        "{e}"
    );
    let e = edited(
        arm.0,
        arm.1,
        &[("(RotorIndexOffset 0 0 0 0)", "(RotorIndexOffset 0 10 0 0)")],
    )
    .unwrap_err();
    assert!(e.contains("without index"), "{e}");
    let e = edited(arm.0, arm.1, &[("(MotorPoles 8 8 8 8)", "")]).unwrap_err();
    assert!(e.contains("2FOC/MotorPoles"), "{e}");
    // AutoCalibration: the offset becomes -1 (which C++ then refuses without an index)
    let p = edited(
        arm.0,
        arm.1,
        &[
            (
                "(HasRotorEncoderIndex 0 0 0 0)",
                "(HasRotorEncoderIndex 1 1 1 1)",
            ),
            (
                "(MotorPoles 8 8 8 8)",
                "(MotorPoles 8 8 8 8) (AutoCalibration 0 1 0 0)",
            ),
        ],
    )
    .unwrap();
    assert_eq!(p.rotor_index_offset, [0.0, -1.0, 0.0, 0.0]);
    // a PT100 needs both temperature limits
    let e = edited(
        arm.0,
        arm.1,
        &[(
            "(HasTempSensor 0 0 0 0)",
            "(TemperatureSensorType PT100 NONE NONE NONE)",
        )],
    )
    .unwrap_err();
    assert!(e.contains("temperature limits"), "{e}");
    let p = edited(
        arm.0,
        arm.1,
        &[
            (
                "(HasTempSensor 0 0 0 0)",
                "(TemperatureSensorType PT100 NONE PT1000 NONE)",
            ),
            (
                "(motorPwmLimit 10000 10000 10000 10000)",
                "(motorPwmLimit 10000 10000 10000 10000) (hardwareTemperatureLimits 110 110 110 110) (warningTemperatureLimits 90 90 90 90)",
            ),
        ],
    )
    .unwrap();
    let (_, mc) = configs(&p, 0);
    assert_eq!(mc.temperature_limit, 1371);
    // PT1000 at 110 °C: 9126.45 -> 9126
    assert_eq!(configs(&p, 2).1.temperature_limit, 9126);
    let e = edited(
        arm.0,
        arm.1,
        &[(
            "(motorPwmLimit 10000 10000 10000 10000)",
            "(motorPwmLimit 10000 10000 10000 10000) (hardwareTemperatureLimits 100 100 100 100) (warningTemperatureLimits 90 90 90 90)",
        )],
    )
    .unwrap_err();
    assert!(e.contains("warningTemperatureLimits"), "{e}");
}

/// C++ `TemperatureSensorPT100`: 110 °C -> 1370.5208 raw, 35 °C -> 438.69; raw 439 ->
/// 35.0247 °C, raw 1371 -> 110.0388 °C; none gives 0.
#[test]
fn pt_sensor_conversions() {
    let pt = TemperatureSensor::Pt100;
    assert!((pt.celsius_to_raw(110.0) - 1370.52084).abs() < 1e-5);
    assert!((pt.celsius_to_raw(35.0) - 438.691409).abs() < 1e-5);
    assert!((pt.raw_to_celsius(439.0) - 35.024689).abs() < 1e-5);
    assert!((pt.raw_to_celsius(1371.0) - 110.038798).abs() < 1e-5);
    assert!(pt.raw_to_celsius(0.0).abs() < 1e-9, "0 °C reads 0");
    assert!((TemperatureSensor::Pt1000.celsius_to_raw(110.0) - 9126.445509).abs() < 1e-5);
    assert_eq!(TemperatureSensor::None.celsius_to_raw(110.0), 0.0);
    // the emulated board's sensor model agrees with the host's
    assert_eq!(icub_eth::plant::pt100_raw(35.0), 439);
    assert_eq!(icub_eth::plant::pt100_raw(110.0), 1371);
}

/// Every motion-control device of both robots reads its motor group as C++ does: the
/// FOC services have one, the others none.
#[test]
fn every_mc_device_of_both_robots_reads() {
    for (robot, top) in [
        ("iCubGenova02", "icub_all.xml"),
        ("ergoCubSN001", "ergocub.xml"),
    ] {
        for d in robot_devices(robot, top)
            .iter()
            .filter(|d| d.kind == "embObjMotionControl")
        {
            let p = McParams::read(&d.to_property().unwrap())
                .unwrap_or_else(|e| panic!("{robot} {}: {e}", d.name));
            let foc = matches!(p.service.service_type, 1 | 15);
            assert_eq!(p.motor_group.is_some(), foc, "{robot} {}", d.name);
            for j in 0..p.joints {
                let (_, mc) = configs(&p, j);
                if foc {
                    assert!(mc.motor_poles > 0, "{robot} {} joint {j}", d.name);
                }
            }
        }
    }
}

/// ergoCubSN001 torso-eb5-j0_2's KALMAN_FILTER reaches each joint's config (C++
/// `parseKalmanFilterParams`, `jconfig.kalman_params`); a board file without the group
/// (iCubGenova02's left arm) sends it disabled and zero; a group missing one of its lines
/// fails the open naming it.
#[test]
fn kalman_filter_as_sent() {
    let p = mc("ergoCubSN001", "torso-eb5-j0_2");
    let (jc0, _) = configs(&p, 0);
    let (jc2, _) = configs(&p, 2);
    assert!(jc0.kalman.enabled && jc2.kalman.enabled);
    assert_eq!(jc0.kalman.x0, [0.0; 3]);
    // the file's f64 text as f32, as C++ `asFloat32`
    let f = |v: f64| v as f32;
    assert_eq!(
        jc0.kalman.q,
        [
            f(0.0002531597161334673),
            f(0.022162080623563264),
            f(23.988142473281066)
        ]
    );
    assert_eq!(jc0.kalman.r, f(0.0007037200315177511));
    assert_eq!(jc2.kalman.p0, f(0.31787791884813843));

    let icub = mc("iCubGenova02", "left_arm-eb1-j0_3");
    assert_eq!(configs(&icub, 0).0.kalman, Default::default());

    let err = edited("ergoCubSN001", "torso-eb5-j0_2", &[("(P0 ", "(Pzero ")])
        .err()
        .unwrap_or_default();
    assert!(err.contains("KALMAN_FILTER/P0"), "{err}");
}

/// LUGRE (C++ `parseLugreGroup`, `motor_cfg.LuGre_params`): neither robot has the group,
/// so each motor is sent Km -1 ("no model") and zeros; a group gives its nine values per
/// joint, and one missing line fails the open naming it.
#[test]
fn lugre_model_as_sent() {
    let p = mc("ergoCubSN001", "torso-eb5-j0_2");
    let (_, m0) = configs(&p, 0);
    assert_eq!(m0.lugre, [-1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);

    let group = "(LUGRE (Km 1 2 3) (Kw 4 5 6) (S0 7 8 9) (S1 10 11 12) (Vth 13 14 15) \
                 (Fc_pos 16 17 18) (Fc_neg 19 20 21) (Fs_pos 22 23 24) (Fs_neg 25 26 27)) \
                 (KALMAN_FILTER ";
    let p = edited(
        "ergoCubSN001",
        "torso-eb5-j0_2",
        &[("(KALMAN_FILTER ", group)],
    );
    let p = p.unwrap_or_else(|e| panic!("{e}"));
    let (_, m2) = configs(&p, 2);
    assert_eq!(
        m2.lugre,
        [3.0, 6.0, 9.0, 12.0, 15.0, 18.0, 21.0, 24.0, 27.0]
    );
    let without_vth = group.replace("(Vth 13 14 15) ", "");
    let err = edited(
        "ergoCubSN001",
        "torso-eb5-j0_2",
        &[("(KALMAN_FILTER ", &without_vth)],
    )
    .err()
    .unwrap_or_default();
    assert!(err.contains("LUGRE/Vth"), "{err}");
}
