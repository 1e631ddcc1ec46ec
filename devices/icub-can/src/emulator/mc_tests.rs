//! The emulated joint under the firmware PIDs: step responses with iCubGenova01's gains,
//! zero gains, saturation, anti-windup, torque mode, host torque measurements and the
//! virtual joint-torque sensor. Pure simulation: no bus, no threads, no sleeps.

use super::*;

/// iCubGenova01 `hardware/motorControl/icub_left_arm.xml`, POS_PIDS per joint:
/// kp, kd, ki, shift, maxOutput (= maxInt), and the joint's `Encoder` (ticks/°).
const LEFT_ARM_POS: [(i16, i16, i16, u8, i16, f64); 8] = [
    (32000, 50, 60, 13, 800, -11.375),
    (32000, 50, 60, 13, 800, -11.375),
    (10000, 0, 10, 13, 800, -11.375),
    (32000, 20, 60, 13, 800, -11.375),
    (-200, -1000, -1, 6, 1333, 706.67),
    (1000, 10000, 1, 7, 1333, -11.375),
    (-1000, -10000, -1, 7, 1333, 11.375),
    (200, 200, 1, 4, 1333, -6.244),
];

fn left_arm_joint(j: usize, q: f64) -> JointSim {
    let (kp, kd, ki, shift, max, _) = LEFT_ARM_POS[j];
    let mut sim = JointSim::new(q);
    sim.set_gains(
        PidKind::Position,
        Pid { kp, ki, kd, shift },
        PidLimits {
            offset: 0,
            max_output: max,
            max_integral: max,
        },
    );
    sim
}

fn cmd(sim: &mut JointSim, c: McCommand) {
    assert_eq!(sim.apply(&c), None, "{c:?} should not answer");
}

/// Step-response figures of a joint moving from its position to `target`.
#[derive(Debug)]
struct Response {
    /// Largest excursion past the target, as a fraction of the move.
    overshoot: f64,
    /// When the joint entered ±`band` ticks of the target for good, s.
    settled: Option<f64>,
    max_output: f64,
}

/// Simulates `secs` at 1 ms ticks and measures the approach to `target`.
fn run(sim: &mut JointSim, target: f64, secs: f64, band: f64) -> Response {
    let start = sim.q;
    let dir = (target - start).signum();
    let mut r = Response {
        overshoot: 0.0,
        settled: None,
        max_output: 0.0,
    };
    let n = (secs * 1000.0).round() as usize;
    for i in 0..n {
        sim.step(0.001);
        r.overshoot = r
            .overshoot
            .max((sim.q - target) * dir / (target - start).abs());
        r.max_output = r.max_output.max(sim.output().abs());
        if (sim.q - target).abs() > band {
            r.settled = None;
        } else if r.settled.is_none() {
            r.settled = Some((i + 1) as f64 / 1000.0);
        }
    }
    r
}

#[test]
fn left_arm_shoulder_step_settles_fast_with_little_overshoot() {
    // A 10° position move at 100°/s (the reference ramps for 0.1 s).
    let mut sim = left_arm_joint(0, 0.0);
    cmd(&mut sim, McCommand::SetControlMode(ControlMode::Position));
    let target: f64 = 10.0 * 11.375;
    cmd(
        &mut sim,
        McCommand::PositionMove {
            position: target as i32,
            speed: 114,
        },
    );
    let r = run(&mut sim, target.round(), 2.0, 3.0);
    eprintln!("shoulder 10° move: {r:?}");
    assert!(r.overshoot < 0.08, "{r:?}");
    assert!(r.settled.is_some_and(|t| t < 0.8), "{r:?}");
    assert!(sim.motion_done());

    // A 10° step of the reference (position direct).
    let mut sim = left_arm_joint(0, 0.0);
    cmd(&mut sim, McCommand::SetControlMode(ControlMode::Direct));
    cmd(&mut sim, McCommand::SetCommandPosition(114));
    let r = run(&mut sim, 114.0, 2.0, 3.0);
    eprintln!("shoulder 10° step: {r:?}");
    assert!(r.overshoot < 0.1, "{r:?}");
    assert!(r.settled.is_some_and(|t| t < 1.0), "{r:?}");
    // The output is the firmware PID's: P alone is 114·32000/8192 = 445 at the step.
    assert!(r.max_output > 440.0 && r.max_output <= 800.0, "{r:?}");
}

#[test]
fn every_left_arm_joint_is_stable_under_its_genova01_gains() {
    for (j, &(.., enc)) in LEFT_ARM_POS.iter().enumerate() {
        let mut sim = left_arm_joint(j, 1000.0);
        cmd(&mut sim, McCommand::SetControlMode(ControlMode::Direct));
        // 5° on this joint's encoder.
        let target = 1000.0 + (5.0 * enc).abs().round();
        cmd(&mut sim, McCommand::SetCommandPosition(target as i32));
        let r = run(&mut sim, target, 3.0, 3.0);
        eprintln!("left_arm joint {j}: {r:?}");
        assert!(r.overshoot < 0.35, "joint {j}: {r:?}");
        assert!(r.settled.is_some_and(|t| t < 2.5), "joint {j}: {r:?}");
        assert!(sim.qd.abs() < 30.0, "joint {j} still moving at {}", sim.qd);
    }
}

#[test]
fn zero_gains_do_not_move() {
    let mut sim = JointSim::new(500.0);
    sim.set_gains(PidKind::Position, Pid::default(), PidLimits::default());
    cmd(&mut sim, McCommand::SetControlMode(ControlMode::Position));
    cmd(
        &mut sim,
        McCommand::PositionMove {
            position: 5000,
            speed: 500,
        },
    );
    let r = run(&mut sim, 5000.0, 1.0, 3.0);
    assert_eq!(sim.q, 500.0);
    assert_eq!(r.max_output, 0.0);
    // Gains without an output range (maxOutput 0, as a never-configured firmware) neither.
    let mut sim = left_arm_joint(0, 500.0);
    sim.set_gains(
        PidKind::Position,
        Pid {
            kp: 32000,
            ki: 60,
            kd: 50,
            shift: 13,
        },
        PidLimits::default(),
    );
    cmd(&mut sim, McCommand::SetControlMode(ControlMode::Direct));
    cmd(&mut sim, McCommand::SetCommandPosition(5000));
    let r = run(&mut sim, 5000.0, 1.0, 3.0);
    assert_eq!((sim.q, r.max_output), (500.0, 0.0));
    // Idle outputs nothing whatever the gains.
    let mut sim = left_arm_joint(0, 500.0);
    sim.target = 5000.0;
    sim.reference = 5000.0;
    let r = run(&mut sim, 5000.0, 0.5, 3.0);
    assert_eq!((sim.q, r.max_output), (500.0, 0.0));
}

#[test]
fn max_output_saturates_the_pwm() {
    let mut sim = left_arm_joint(0, 0.0);
    let (pid, mut lim) = sim.gains(PidKind::Position);
    lim.max_output = 200;
    sim.set_gains(PidKind::Position, pid, lim);
    cmd(&mut sim, McCommand::SetControlMode(ControlMode::Direct));
    cmd(&mut sim, McCommand::SetCommandPosition(3000));
    sim.step(0.001);
    assert_eq!(sim.output(), 200.0);
    // Saturated, the joint runs at the plant's speed for 200 PWM counts, less friction.
    for _ in 0..300 {
        sim.step(0.001);
    }
    assert_eq!(sim.output(), 200.0);
    let top = (200.0 - COULOMB * PWM_FULL_SCALE) * ACCEL_PER_PWM / VISCOUS;
    assert!((sim.qd - top).abs() < 0.02 * top, "{} vs {top}", sim.qd);
    // SET_PWM_LIMIT caps it further.
    cmd(&mut sim, McCommand::SetPwmLimit(120));
    sim.step(0.001);
    assert_eq!(sim.output(), 120.0);
}

#[test]
fn integral_is_clamped_to_max_int() {
    // Strong integral, 100 counts at most: the clamp bounds the windup of a long move.
    let overshoot = |max_int: i16| {
        let mut sim = JointSim::new(0.0);
        sim.set_gains(
            PidKind::Position,
            Pid {
                kp: 32000,
                ki: 2000,
                kd: 50,
                shift: 13,
            },
            PidLimits {
                offset: 0,
                max_output: 800,
                max_integral: max_int,
            },
        );
        cmd(&mut sim, McCommand::SetControlMode(ControlMode::Direct));
        cmd(&mut sim, McCommand::SetCommandPosition(2000));
        let mut peak_integral = 0.0f64;
        let mut r = Response {
            overshoot: 0.0,
            settled: None,
            max_output: 0.0,
        };
        for _ in 0..2000 {
            sim.step(0.001);
            peak_integral = peak_integral.max(sim.pos_pid.integral.abs());
            r.overshoot = r.overshoot.max((sim.q - 2000.0) / 2000.0);
        }
        assert!(peak_integral <= f64::from(max_int), "{peak_integral}");
        assert!((sim.q - 2000.0).abs() <= 3.0, "ends at {}", sim.q);
        (r.overshoot, peak_integral)
    };
    let (small, peak) = overshoot(100);
    assert_eq!(peak, 100.0, "the integral reaches its clamp");
    let (large, _) = overshoot(1333);
    eprintln!("overshoot with maxInt 100: {small:.3}, with 1333: {large:.3}");
    assert!(small < 0.03 && large > 2.0 * small, "{small} {large}");
}

/// The left elbow (joint 3) of iCubGenova01: TRQ_PIDS kp -288, shift 14, maxOutput 800;
/// TorqueMax 8; Encoder -11.375; limits 15°..106° = ticks 1975..940.
fn left_elbow_in_torque_mode(ki: i16) -> JointSim {
    let mut sim = left_arm_joint(3, 1500.0);
    sim.set_gains(
        PidKind::Torque,
        Pid {
            kp: -288,
            ki,
            kd: 0,
            shift: 14,
        },
        PidLimits {
            offset: 0,
            max_output: 800,
            max_integral: 800,
        },
    );
    let mut plant = JointPlant::with_torque_max(8.0);
    plant.sensor_sign = Some(-1.0);
    sim.set_plant(plant);
    cmd(&mut sim, McCommand::SetMinPosition(940));
    cmd(&mut sim, McCommand::SetMaxPosition(1975));
    cmd(&mut sim, McCommand::SetControlMode(ControlMode::Torque));
    sim
}

#[test]
fn torque_mode_tracks_a_torque_reference() {
    // With the proportional gain alone, against a stop, τ = g·(τref − τ) − c: the loop
    // settles at (g·τref − c)/(1+g), g = Kτ/PWM_FULL_SCALE · 288/2^14 · 0x8000/TorqueMax,
    // c the Coulomb friction.
    let mut sim = left_elbow_in_torque_mode(0);
    let g = DRIVE_PER_TORQUE_MAX * 8.0 / PWM_FULL_SCALE * 288.0 / 16384.0 * 32768.0 / 8.0;
    for (nm, stop) in [(1.0, 940.0), (-1.0, 1975.0)] {
        cmd(&mut sim, McCommand::SetDesiredTorque((nm * 4096.0) as i16));
        // In free motion the joint accelerates until the stop.
        for _ in 0..3000 {
            sim.step(0.001);
        }
        // Positive torques turn the joint toward positive degrees: fewer ticks here.
        assert_eq!(sim.q, stop, "{nm} N·m ends at a hard stop");
        let measured = f64::from(sim.torque_sensor_units()) / 4096.0;
        let c = COULOMB * DRIVE_PER_TORQUE_MAX * 8.0;
        let expect = (nm * g - c * nm.signum()) / (1.0 + g);
        eprintln!("torque reference {nm} N·m: measured {measured:.3} (expected {expect:.3})");
        assert!((measured - expect).abs() < 0.02, "{measured} vs {expect}");
    }
    // An integral term removes the error.
    let mut sim = left_elbow_in_torque_mode(-40);
    cmd(&mut sim, McCommand::SetDesiredTorque(4096));
    for _ in 0..3000 {
        sim.step(0.001);
    }
    let measured = f64::from(sim.torque_sensor_units()) / 4096.0;
    assert!((measured - 1.0).abs() < 0.02, "{measured}");
    // Back to position mode the joint holds where it is.
    cmd(&mut sim, McCommand::SetControlMode(ControlMode::Position));
    let at = sim.q;
    for _ in 0..500 {
        sim.step(0.001);
    }
    assert!((sim.q - at).abs() <= 3.0, "{at} -> {}", sim.q);
}

fn elbow_board() -> McBoard {
    let mut cfg = McBoardConfig::new(2);
    let mut plant = JointPlant::with_torque_max(8.0);
    plant.sensor_sign = Some(-1.0);
    plant.sensor = Some(TorqueLink {
        address: 0x0C,
        channel: 3,
    });
    cfg.plants[1] = plant;
    cfg.initial = [0.0, 1500.0];
    cfg.torque_hub = Some(TorqueHub::new());
    let mut board = McBoard::new(cfg);
    board.joints[1] = {
        let mut j = left_elbow_in_torque_mode(0);
        j.set_plant(plant);
        j
    };
    board
}

fn host_torques(values: [i16; 3]) -> Message {
    Message::AsPeriodic {
        board: 0x0C,
        msg: AsPeriodic::vector(VectorKind::Torque, values),
    }
}

#[test]
fn host_torque_measurements_replace_the_boards_own_for_a_while() {
    let mut board = elbow_board();
    let mut out = Vec::new();
    board.tick(Duration::from_millis(5), &mut out);
    assert_eq!(board.joints[1].output(), 0.0, "reference 0, measured 0");
    // The host says channel 3 (first of a type-0xB message) measures -1 N·m.
    board.on_message(&host_torques([-4096, 0, 0]), &mut out);
    board.tick(Duration::from_millis(1), &mut out);
    // error +4096 · -288 >> 14 = -72 PWM counts
    assert!(
        (board.joints[1].output() + 72.0).abs() < 1.0,
        "{}",
        board.joints[1].output()
    );
    // Other sensors' messages and other channels are not this joint's.
    board.on_message(
        &Message::AsPeriodic {
            board: 0x0D,
            msg: AsPeriodic::vector(VectorKind::Torque, [9999, 0, 0]),
        },
        &mut out,
    );
    assert_eq!(board.joints[1].host_torque.map(|h| h.0), Some(-4096));
    // Without further messages the board's own measurement is back after the timeout.
    board.tick(HOST_TORQUE_TIMEOUT, &mut out);
    assert_eq!(board.joints[1].host_torque, None);
    assert!(board.joints[1].torque_feedback() != -4096.0);
}

#[test]
fn joint_torque_sensor_broadcasts_the_published_torques() {
    let mut board = elbow_board();
    let hub = board.cfg.torque_hub.clone().expect("hub");
    let mut sensor = JointTorqueSensor::new(0x0C, hub, Duration::from_millis(10));
    let mut out = Vec::new();
    // The elbow is pushed by -1 N·m (sensor units) toward its low-degree stop.
    board.on_message(
        &Message::McRequest {
            src: 0,
            dst: 2,
            axis: 1,
            cmd: McCommand::SetDesiredTorque(-4096),
        },
        &mut out,
    );
    for _ in 0..1000 {
        board.tick(Duration::from_millis(1), &mut out);
    }
    out.clear();
    for _ in 0..10 {
        sensor.tick(Duration::from_millis(1), &mut out);
    }
    let msgs: Vec<Message> = out.iter().map(|f| Message::decode(f).unwrap()).collect();
    // Only channel 3 is published: one type-0xB message, channels 4 and 5 zero.
    assert_eq!(msgs.len(), 1, "{msgs:?}");
    let Message::AsPeriodic {
        board: 0x0C,
        msg:
            AsPeriodic::Vector {
                kind: VectorKind::Torque,
                raw,
                ..
            },
    } = msgs[0]
    else {
        panic!("{msgs:?}")
    };
    let v = AsPeriodic::signed(raw);
    assert_eq!(v[1..], [0, 0]);
    assert_eq!(i32::from(board.joints[1].torque_sensor_units()), v[0]);
    assert!(v[0] < -1500, "{v:?}");
    // While the host sends on 0x0C the emulated sensor keeps quiet.
    sensor.on_message(&host_torques([1, 2, 3]), &mut out);
    out.clear();
    for _ in 0..150 {
        sensor.tick(Duration::from_millis(1), &mut out);
    }
    assert!(out.is_empty());
    for _ in 0..100 {
        sensor.tick(Duration::from_millis(1), &mut out);
    }
    assert!(!out.is_empty(), "broadcasting again after the host stopped");
}

#[test]
fn long_emulator_ticks_are_stable() {
    // The emulator may tick every 100 ms: control still runs at 1 ms.
    let mut a = left_arm_joint(0, 0.0);
    let mut b = left_arm_joint(0, 0.0);
    for s in [&mut a, &mut b] {
        cmd(s, McCommand::SetControlMode(ControlMode::Direct));
        cmd(s, McCommand::SetCommandPosition(300));
    }
    for _ in 0..20 {
        a.step(0.1);
    }
    for _ in 0..2000 {
        b.step(0.001);
    }
    assert!(
        (a.q - b.q).abs() < 1e-6 && (a.q - 300.0).abs() <= 3.0,
        "{} {}",
        a.q,
        b.q
    );
}

/// The left elbow with iCubGenova01's torque gains, in position mode and compliant, with
/// a spring of `stiffness` N·m/° and `damping` N·m·s/° converted as icub-main does
/// (`ImplementImpedanceControl`: × `0x8000/TorqueMax` ÷ `Encoder`; damping sent ×1000).
fn compliant_elbow(stiffness: f64, damping: f64) -> JointSim {
    let mut sim = left_elbow_in_torque_mode(0);
    let per_tick = 4096.0 / -11.375;
    cmd(
        &mut sim,
        McCommand::SetImpedanceParams {
            stiffness: (stiffness * per_tick).round() as i16,
            damping: (damping * per_tick * 1000.0).round() as i16,
        },
    );
    cmd(&mut sim, McCommand::SetControlMode(ControlMode::Position));
    cmd(&mut sim, McCommand::SetInteractionMode(1));
    assert!(sim.compliant());
    sim
}

#[test]
fn impedance_parameters_and_offset_are_stored_and_answered() {
    let mut sim = JointSim::new(0.0);
    cmd(
        &mut sim,
        McCommand::SetImpedanceParams {
            stiffness: 72,
            damping: -1800,
        },
    );
    cmd(&mut sim, McCommand::SetImpedanceOffset(-50));
    assert_eq!(
        sim.apply(&McCommand::GetImpedanceParams),
        Some(McReply::ImpedanceParams {
            stiffness: 72,
            damping: -1800
        })
    );
    assert_eq!(
        sim.apply(&McCommand::GetImpedanceOffset),
        Some(McReply::ImpedanceOffset(-50))
    );
    // Stiff interaction, torque mode and idle do not run the impedance law.
    assert!(!sim.compliant());
    cmd(&mut sim, McCommand::SetInteractionMode(1));
    cmd(&mut sim, McCommand::SetControlMode(ControlMode::Torque));
    assert!(!sim.compliant());
    cmd(&mut sim, McCommand::SetControlMode(ControlMode::Velocity));
    assert!(sim.compliant());
}

#[test]
fn a_compliant_joint_with_stiffness_settles_at_its_position_reference() {
    let mut sim = compliant_elbow(0.3, 0.003);
    // 10° toward positive degrees (fewer ticks: Encoder −11.375) at 50°/s.
    let target = 1500.0 - 114.0;
    cmd(
        &mut sim,
        McCommand::PositionMove {
            position: target as i32,
            speed: 57,
        },
    );
    let r = run(&mut sim, target, 3.0, 12.0);
    eprintln!("compliant 10° move: {r:?}, at {}", sim.q);
    // The spring pulls the joint to the reference: within ~1° (12 ticks; the
    // proportional torque loop and the Coulomb friction leave a small error) after 1.5 s,
    // without oscillating.
    assert!(r.settled.is_some_and(|t| t < 1.5), "{r:?}");
    assert!(r.overshoot < 0.3, "{r:?}");
    assert!(sim.qd.abs() < 20.0, "still moving at {} ticks/s", sim.qd);
    assert!((sim.q - target).abs() <= 4.0, "{} vs {target}", sim.q);
    // The law's torque then is the spring's, small.
    assert!(sim.impedance_torque().abs() < 0.3 * 4096.0 * 1.2);
}

#[test]
fn a_compliant_joint_without_stiffness_does_not_hold_a_position_reference() {
    let mut sim = compliant_elbow(0.0, 0.003);
    let start = sim.q;
    cmd(
        &mut sim,
        McCommand::PositionMove {
            position: (start - 114.0) as i32,
            speed: 57,
        },
    );
    for _ in 0..2000 {
        sim.step(0.001);
    }
    // Only damping: nothing pulls the joint toward the reference, which has gone 10° away.
    assert!((sim.q - start).abs() < 12.0, "{start} -> {}", sim.q);
    assert!(sim.impedance_torque().abs() < 100.0);
    // The same joint stiff follows the reference with the position PID.
    cmd(&mut sim, McCommand::SetInteractionMode(0));
    assert!(!sim.compliant());
    cmd(
        &mut sim,
        McCommand::PositionMove {
            position: (start - 114.0) as i32,
            speed: 57,
        },
    );
    let r = run(&mut sim, start - 114.0, 1.5, 3.0);
    assert!(r.settled.is_some(), "{r:?}");
}
