//! Driver cores against the emulator, on the in-process bus and over UDP.

use std::collections::HashMap;
use std::sync::Arc;
use std::time::{Duration, Instant};

use super::mc::{broadcast_masks, torque_sensors, BROADCAST_FLAGS};
use super::strain::AnalogFormat;
use super::*;
use crate::bus::inproc::VirtualBus;
use crate::bus::udp::UdpBus;
use crate::bus::{BusError, CanBus};
use crate::emulator::network::{self, BoardKind, NetworkSpec};
use crate::emulator::{BusEmulator, EmulatorHandle, McBoard, McBoardConfig, MtbBoard, StrainBoard};
use crate::proto::{ControlMode, PidKind};

// A robot's file read as the tests need it (an XML lookup); the devices read these
// parameters through icubmod's declarations (`CanMotionControlParams`).
impl McParams {
    /// Reads the parameters from an XML-like source: `get(group, key)` returns the
    /// values after the key (e.g. `get("GENERAL", "Encoder")`), or `None` when absent.
    fn from_lookup(get: &dyn Fn(&str, &str) -> Option<Vec<String>>) -> Result<Self, ClientError> {
        let cfg = |m: String| ClientError::Config(m);
        let nums = |group: &str, key: &str| -> Result<Option<Vec<f64>>, ClientError> {
            match get(group, key) {
                None => Ok(None),
                Some(v) => v
                    .iter()
                    .map(|s| {
                        let s = s.trim();
                        let parsed = match s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
                            Some(h) => i64::from_str_radix(h, 16).map(|x| x as f64).ok(),
                            None => s.parse::<f64>().ok(),
                        };
                        parsed.ok_or_else(|| cfg(format!("[{group}] {key}: {s:?} is not a number")))
                    })
                    .collect::<Result<Vec<f64>, _>>()
                    .map(Some),
            }
        };
        let joints = nums("GENERAL", "Joints")?
            .and_then(|v| v.first().copied())
            .ok_or_else(|| cfg("[GENERAL] Joints is missing".into()))?
            as usize;
        let per_joint =
            |group: &str, key: &str, default: Option<f64>| -> Result<Vec<f64>, ClientError> {
                match nums(group, key)? {
                    Some(v) if v.len() >= joints => Ok(v[..joints].to_vec()),
                    Some(v) => Err(cfg(format!(
                        "[{group}] {key} has {} values, {joints} joints",
                        v.len()
                    ))),
                    None => default
                        .map(|d| vec![d; joints])
                        .ok_or_else(|| cfg(format!("[{group}] {key} is missing"))),
                }
            };
        let addresses = nums("CAN", "CanAddresses")?
            .ok_or_else(|| cfg("[CAN] CanAddresses is missing".into()))?;
        let can_addresses = addresses
            .iter()
            .map(|a| {
                if (1.0..=14.0).contains(a) {
                    Ok(*a as u8)
                } else {
                    Err(cfg(format!("[CAN] CanAddresses: {a} is not 1..14")))
                }
            })
            .collect::<Result<Vec<u8>, _>>()?;
        let axis_map: Vec<usize> = per_joint("GENERAL", "AxisMap", None)
            .or_else(|_| Ok::<_, ClientError>((0..joints).map(|j| j as f64).collect()))?
            .into_iter()
            .map(|a| a as usize)
            .collect();
        let min = per_joint("LIMITS", "jntPosMin", Some(f64::NEG_INFINITY))?;
        let max = per_joint("LIMITS", "jntPosMax", Some(f64::INFINITY))?;
        let pids = |group: &str| -> Result<Option<Vec<JointPid>>, ClientError> {
            if get(group, "kp").is_none() {
                return Ok(None);
            }
            let g = |k: &str| per_joint(group, k, Some(0.0));
            let (kp, kd, ki, max_int, scale, max_output, offset) = (
                g("kp")?,
                g("kd")?,
                g("ki")?,
                g("maxInt")?,
                g("shift")?,
                g("maxOutput")?,
                g("ko")?,
            );
            Ok(Some(
                (0..joints)
                    .map(|j| JointPid {
                        kp: kp[j],
                        kd: kd[j],
                        ki: ki[j],
                        max_int: max_int[j],
                        scale: scale[j],
                        max_output: max_output[j],
                        offset: offset[j],
                    })
                    .collect(),
            ))
        };
        let jv = per_joint("VELOCITY", "JNT_speed_estimation", Some(0.0))?;
        let ja = per_joint("VELOCITY", "JNT_accel_estimation", Some(0.0))?;
        let mv = per_joint("VELOCITY", "MOT_speed_estimation", Some(0.0))?;
        let ma = per_joint("VELOCITY", "MOT_accel_estimation", Some(0.0))?;
        let flags = BROADCAST_FLAGS
            .iter()
            .map(|(key, _)| nums("CAN", key))
            .collect::<Result<Vec<_>, _>>()?;
        let broadcast_policy = broadcast_masks(&flags, can_addresses.len());
        let ms = |group: &str, key: &str, default: u64| -> Result<Duration, ClientError> {
            Ok(Duration::from_millis(
                nums(group, key)?
                    .and_then(|v| v.first().copied())
                    .map_or(default, |v| v.max(1.0) as u64),
            ))
        };
        let lenient = |key: &str| nums("GENERAL", key).ok().flatten().unwrap_or_default();
        let torque_max = lenient("TorqueMax");
        let params = Self {
            host_address: nums("CAN", "CanMyAddress")?
                .and_then(|v| v.first().copied())
                .unwrap_or(0.0) as u8,
            reply_timeout: ms("CAN", "CanTimeout", 500)?,
            broadcast_timeout: Duration::from_millis(500),
            axis_names: get("GENERAL", "AxisName")
                .map(|v| {
                    v.into_iter()
                        .map(|s| s.trim_matches('"').to_string())
                        .collect()
                })
                .unwrap_or_else(|| (0..joints).map(|j| format!("joint{j}")).collect()),
            encoder: per_joint("GENERAL", "Encoder", None)?,
            zeros: per_joint("GENERAL", "Zeros", Some(0.0))?,
            // As icub-main, a missing or short list means "no sensor" / scale 1, not an error.
            torque_scale: (0..joints)
                .map(|j| match torque_max.get(j) {
                    Some(&max) if max > 0.0 => f64::from(0x8000u16) / max,
                    _ => 1.0,
                })
                .collect(),
            torque_sensors: torque_sensors(&lenient("TorqueId"), &lenient("TorqueChan"), joints),
            rotor: per_joint("GENERAL", "Rotor", Some(1.0))?,
            limits: min.into_iter().zip(max).collect(),
            vel_shifts: per_joint("VELOCITY", "Shifts", Some(0.0))?
                .into_iter()
                .map(|v| v as u16)
                .collect(),
            estimation_shifts: (0..joints)
                .map(|j| [jv[j] as u8, ja[j] as u8, mv[j] as u8, ma[j] as u8])
                .collect(),
            vel_timeouts: per_joint("VELOCITY", "Timeout", Some(100.0))?
                .into_iter()
                .map(|v| v as u16)
                .collect(),
            position_pids: pids("POS_PIDS")?,
            torque_pids: pids("TRQ_PIDS")?,
            broadcast_policy,
            can_addresses,
            axis_map,
        };
        params.validate()?;
        Ok(params)
    }
}

impl StrainParams {
    /// Reads `canAddress`, `period`, `useCalibration`, `channels`, `format`.
    fn from_lookup(get: &dyn Fn(&str) -> Option<String>) -> Result<Self, ClientError> {
        let num = |k: &str| -> Result<Option<i64>, ClientError> {
            let Some(v) = get(k) else { return Ok(None) };
            let v = v.trim().trim_matches('"').to_string();
            let parsed = match v.strip_prefix("0x").or_else(|| v.strip_prefix("0X")) {
                Some(h) => i64::from_str_radix(h, 16).ok(),
                None => v.parse().ok(),
            };
            parsed
                .map(Some)
                .ok_or_else(|| ClientError::Config(format!("{k}: {v:?} is not a number")))
        };
        let address = num("canAddress")?
            .ok_or_else(|| ClientError::Config("canAddress is missing".into()))?;
        if !(1..=14).contains(&address) {
            return Err(ClientError::Config(format!(
                "canAddress {address} is not 1..14"
            )));
        }
        let format = match num("format")?.unwrap_or(16) {
            16 => AnalogFormat::Bits16,
            8 => AnalogFormat::Bits8,
            f => return Err(ClientError::Config(format!("format {f} is not 8 or 16"))),
        };
        let channels = num("channels")?.unwrap_or(6);
        let max = if format == AnalogFormat::Bits16 {
            6
        } else {
            16
        };
        if !(1..=max).contains(&channels) {
            return Err(ClientError::Config(format!(
                "channels {channels} is not 1..{max}"
            )));
        }
        Ok(Self {
            address: address as u8,
            period_ms: num("period")?.unwrap_or(1).clamp(1, 255) as u8,
            use_calibration: num("useCalibration")?.unwrap_or(0) > 0,
            channels: channels as usize,
            format,
            host_address: 0,
            reply_timeout: Duration::from_millis(100),
        })
    }
}

fn robot_dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/robots-configuration/iCubGenova01")
}

/// `<param name="X"> values </param>` (first occurrence, comments removed).
fn xml_params(text: &str) -> HashMap<String, Vec<String>> {
    let mut clean = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find("<!--") {
        clean.push_str(&rest[..start]);
        rest = rest[start..]
            .find("-->")
            .map_or("", |end| &rest[start + end + 3..]);
    }
    clean.push_str(rest);
    let mut out = HashMap::new();
    let mut s = clean.as_str();
    while let Some(pos) = s.find("<param") {
        s = &s[pos + 6..];
        let Some(close) = s.find('>') else { break };
        let attrs = &s[..close];
        let Some(end) = s.find("</param>") else { break };
        if close < end {
            if let Some(name) = attrs
                .split("name=\"")
                .nth(1)
                .and_then(|n| n.split('"').next())
            {
                let values = s[close + 1..end]
                    .split_whitespace()
                    .map(|v| v.trim_matches('"').to_string())
                    .collect();
                out.entry(name.to_string()).or_insert(values);
            }
        }
        s = &s[end..];
    }
    out
}

/// `(group, key) -> values` from an iCub device XML.
fn xml_groups(text: &str) -> HashMap<(String, String), Vec<String>> {
    let mut out = HashMap::new();
    for chunk in text.split("<group name=\"").skip(1) {
        let Some((group, body)) = chunk.split_once('"') else {
            continue;
        };
        let body = body.split("</group>").next().unwrap_or("");
        for (k, v) in xml_params(body) {
            out.insert((group.to_string(), k), v);
        }
    }
    out
}

fn left_arm_groups() -> HashMap<(String, String), Vec<String>> {
    let text = std::fs::read_to_string(robot_dir().join("hardware/motorControl/icub_left_arm.xml"))
        .expect("../shared/robots-configuration must be beside the repository");
    xml_groups(&text)
}

fn left_arm_params() -> McParams {
    let groups = left_arm_groups();
    let mut p = McParams::from_lookup(&|g, k| groups.get(&(g.to_string(), k.to_string())).cloned())
        .unwrap();
    p.reply_timeout = Duration::from_millis(200);
    p.broadcast_timeout = Duration::from_millis(200);
    p
}

/// The left arm's network of iCubGenova01: its motor boards as its file lays them out
/// (with the joint-torque sensor they name) and the arm's strain.
fn left_arm_network(bus: &VirtualBus) -> EmulatorHandle {
    let torque_max: Vec<f64> = left_arm_groups()
        .get(&("GENERAL".to_string(), "TorqueMax".to_string()))
        .map(|v| v.iter().filter_map(|x| x.parse().ok()).collect())
        .unwrap_or_default();
    let p = left_arm_params();
    let mut boards = network::mc_boards(&network::McLayout {
        can_addresses: p.can_addresses,
        axis_map: p.axis_map,
        encoder: p.encoder,
        zeros: p.zeros,
        limits: p.limits,
        torque_max,
        torque_sensors: p.torque_sensors,
    });
    boards.push(BoardKind::Strain(0x0D));
    let net = NetworkSpec { num: 1, boards };
    BusEmulator::new(Arc::new(bus.endpoint()), network::build(&net))
        .spawn()
        .unwrap()
}

fn wait_for<T>(what: &str, timeout: Duration, mut f: impl FnMut() -> Option<T>) -> T {
    let deadline = Instant::now() + timeout;
    loop {
        if let Some(v) = f() {
            return v;
        }
        assert!(Instant::now() < deadline, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(10));
    }
}

#[test]
fn params_from_the_real_left_arm_xml() {
    let p = left_arm_params();
    assert_eq!(p.joints(), 8);
    assert_eq!(p.can_addresses, vec![1, 2, 3, 4]);
    assert_eq!(p.axis_names[0], "l_shoulder_pitch");
    assert_eq!(p.encoder[4], 706.67);
    assert_eq!(p.limits[1], (0.0, 160.8));
    assert_eq!(p.vel_shifts[0], 8);
    assert_eq!(p.estimation_shifts[0], [5, 5, 1, 1]);
    let pos = p.position_pids.as_ref().unwrap();
    assert_eq!(
        (pos[0].kp, pos[0].scale, pos[0].max_output),
        (32000.0, 13.0, 800.0)
    );
    assert_eq!(p.torque_pids.as_ref().unwrap()[3].kp, -288.0);
    // TorqueId 0x0C, TorqueChan 0..4 for joints 0..4, TorqueId 0 after; TorqueMax 8 / 2.
    let s = |ch| Some((0x0C, ch));
    assert_eq!(
        p.torque_sensors,
        [s(0), s(1), s(2), s(3), s(4), None, None, None]
    );
    assert_eq!((p.torque_scale[0], p.torque_scale[4]), (4096.0, 16384.0));
    // broadcast_pid is set for axes 0..3 only: boards 1 and 2.
    let policy = p.broadcast_policy.as_ref().unwrap();
    assert_ne!(policy[0] & (1 << 2), 0);
    assert_eq!(policy[3] & (1 << 2), 0);
}

#[test]
fn bad_params_are_rejected() {
    let lookup = |pairs: &'static [(&str, &str, &str)]| {
        move |g: &str, k: &str| {
            pairs
                .iter()
                .find(|(a, b, _)| *a == g && *b == k)
                .map(|(_, _, v)| v.split_whitespace().map(String::from).collect())
        }
    };
    let err = McParams::from_lookup(&lookup(&[("CAN", "CanAddresses", "1")])).unwrap_err();
    assert!(err.to_string().contains("Joints"), "{err}");
    let err = McParams::from_lookup(&lookup(&[
        ("GENERAL", "Joints", "2"),
        ("CAN", "CanAddresses", "1"),
        ("GENERAL", "Encoder", "1"),
    ]))
    .unwrap_err();
    assert!(err.to_string().contains("Encoder"), "{err}");
    let err = McParams::from_lookup(&lookup(&[
        ("GENERAL", "Joints", "4"),
        ("CAN", "CanAddresses", "1"),
        ("GENERAL", "Encoder", "1 1 1 1"),
    ]))
    .unwrap_err();
    assert!(err.to_string().contains("axis 2"), "{err}");
    let err = McParams::from_lookup(&lookup(&[
        ("GENERAL", "Joints", "1"),
        ("CAN", "CanAddresses", "15"),
        ("GENERAL", "Encoder", "1"),
    ]))
    .unwrap_err();
    assert!(err.to_string().contains("1..14"), "{err}");
    let err = McParams::from_lookup(&lookup(&[
        ("GENERAL", "Joints", "1"),
        ("CAN", "CanAddresses", "1"),
        ("GENERAL", "Encoder", "x"),
    ]))
    .unwrap_err();
    assert!(err.to_string().contains("not a number"), "{err}");
}

#[test]
fn left_arm_moves_through_the_emulator() {
    let bus = VirtualBus::new("left_arm");
    let _emu = left_arm_network(&bus);
    let mut params = left_arm_params();
    // The XML disables velocity broadcasts (broadcast_vel_acc 0); enable them to read speeds.
    for mask in params.broadcast_policy.as_mut().unwrap() {
        *mask |= 1 << crate::proto::mc::per::VELOCITY;
    }
    let mc = MotorControlClient::open(Arc::new(bus.endpoint()), params).unwrap();
    let enc = wait_for("encoders", Duration::from_secs(2), || mc.encoders().ok());
    if robot_dir().exists() {
        // Every joint starts at 0 deg clamped into its limits.
        let expected = [0.0, 0.0, 0.0, 15.0, 0.0, 0.0, 0.0, 15.0];
        for (j, (e, x)) in enc.iter().zip(expected).enumerate() {
            assert!((e - x).abs() < 0.2, "joint {j}: {e} vs {x}");
        }
    }
    // Limits were sent at open and read back in degrees.
    let (lo, hi) = mc.limits(1).unwrap();
    assert!(
        (lo - 0.0).abs() < 0.1 && (hi - 160.8).abs() < 0.1,
        "{lo} {hi}"
    );

    mc.set_control_mode(0, ControlMode::Position).unwrap();
    assert_eq!(mc.control_mode(0).unwrap(), ControlMode::Position);
    mc.set_ref_speed(0, 60.0).unwrap();
    let start = enc[0];
    mc.position_move(0, -20.0).unwrap();
    let moving = wait_for("speed", Duration::from_secs(2), || {
        mc.encoder_speed(0).ok().filter(|v| *v < -5.0)
    });
    assert!(moving < 0.0);
    wait_for("motion done", Duration::from_secs(5), || {
        mc.motion_done(0).ok().filter(|d| *d)
    });
    // Broadcasts trail the poll by up to one broadcast period.
    let at = wait_for("encoder at target", Duration::from_secs(2), || {
        mc.encoder(0).ok().filter(|p| (p - -20.0).abs() < 0.5)
    });
    assert!((at - -20.0).abs() < 0.5, "reached {at} from {start}");
    assert!((mc.poll_encoder(0).unwrap() - at).abs() < 0.5);
    // Targets beyond the limits stop at the limit.
    mc.position_move(0, -150.0).unwrap();
    wait_for("limit", Duration::from_secs(5), || {
        mc.motion_done(0).ok().filter(|d| *d)
    });
    wait_for("encoder at the limit", Duration::from_secs(2), || {
        mc.encoder(0).ok().filter(|p| (p - -95.5).abs() < 0.5)
    });

    // Velocity mode on the elbow.
    mc.set_control_mode(3, ControlMode::Velocity).unwrap();
    let e0 = mc.encoder(3).unwrap();
    for _ in 0..20 {
        mc.velocity_move(3, 30.0).unwrap();
        std::thread::sleep(Duration::from_millis(20));
    }
    let e1 = mc.encoder(3).unwrap();
    assert!(e1 - e0 > 5.0, "elbow moved {e0} -> {e1}");

    // PIDs round trip in board units.
    let pid = JointPid {
        kp: 100.0,
        kd: 2.0,
        ki: 1.0,
        max_int: 500.0,
        scale: 4.0,
        max_output: 900.0,
        offset: 0.0,
    };
    mc.set_pid(2, PidKind::Position, &pid).unwrap();
    assert_eq!(mc.pid(2, PidKind::Position).unwrap(), pid);
    let status = mc.joint_status(0).unwrap();
    assert!(status.mode.is_some() && status.position_age.unwrap() < Duration::from_millis(200));
    assert!(mc.board_health().iter().all(|b| b.alive));
    assert_eq!(mc.malformed_frames(), 0);
    assert!(matches!(mc.encoder(8), Err(ClientError::BadJoint { .. })));
}

#[test]
fn silent_boards_are_reported_within_the_timeout() {
    let bus = VirtualBus::new("silent");
    let emu = left_arm_network(&bus);
    emu.set_silent(3, true);
    let t0 = Instant::now();
    match MotorControlClient::open(Arc::new(bus.endpoint()), left_arm_params()) {
        Err(ClientError::BoardsSilent { boards }) => assert_eq!(boards, vec![3]),
        other => panic!("expected BoardsSilent, got {:?}", other.err()),
    }
    assert!(t0.elapsed() < Duration::from_secs(2));
    emu.set_silent(3, false);
    let mc = MotorControlClient::open(Arc::new(bus.endpoint()), left_arm_params()).unwrap();
    wait_for("encoders", Duration::from_secs(2), || mc.encoders().ok());
    emu.set_silent(2, true);
    // Joint 2 is on board 2: its broadcasts go stale, polls time out, others keep working.
    let err = wait_for("stale", Duration::from_secs(2), || mc.encoder(2).err());
    assert!(matches!(err, ClientError::Stale { board: 2, .. }), "{err}");
    let t0 = Instant::now();
    assert!(matches!(
        mc.motion_done(2),
        Err(ClientError::BoardTimeout { board: 2, .. })
    ));
    assert!(t0.elapsed() < Duration::from_millis(400));
    assert!(mc.encoder(0).is_ok());
    let health = mc.board_health();
    assert!(!health[1].alive && health[0].alive, "{health:?}");
}

#[test]
fn bus_off_is_an_error() {
    let bus = VirtualBus::new("busoff");
    let _emu = left_arm_network(&bus);
    let mc = MotorControlClient::open(Arc::new(bus.endpoint()), left_arm_params()).unwrap();
    bus.set_bus_off(true);
    assert!(matches!(
        mc.position_move(0, 1.0),
        Err(ClientError::Bus(BusError::BusOff(_)))
    ));
    assert!(matches!(
        mc.control_mode(0),
        Err(ClientError::Bus(BusError::BusOff(_)))
    ));
    bus.set_bus_off(false);
    assert!(mc.control_mode(0).is_ok());
}

#[test]
fn malformed_frames_are_counted_by_the_client() {
    let bus = VirtualBus::new("garbage");
    let _emu = left_arm_network(&bus);
    let mc = MotorControlClient::open(Arc::new(bus.endpoint()), left_arm_params()).unwrap();
    wait_for("encoders", Duration::from_secs(2), || mc.encoders().ok());
    let noise = bus.endpoint();
    // A position broadcast of board 1 that is too short, and a reply with an unknown opcode.
    noise
        .send(&crate::CanFrame::new(0x111, &[1, 2]).unwrap())
        .unwrap();
    noise
        .send(&crate::CanFrame::new(0x010, &[0x7E]).unwrap())
        .unwrap();
    wait_for("malformed count", Duration::from_secs(2), || {
        (mc.malformed_frames() == 2).then_some(())
    });
    assert!(mc.encoder(0).is_ok());
}

#[test]
fn strain_client_reads_forces_and_calibration() {
    let bus = VirtualBus::new("ft");
    let _emu = BusEmulator::new(
        Arc::new(bus.endpoint()),
        vec![Box::new(StrainBoard::new(0x0D))],
    )
    .spawn()
    .unwrap();
    let params = StrainParams::from_lookup(&|k| {
        [
            ("canAddress", "0x0D"),
            ("format", "16"),
            ("channels", "6"),
            ("period", "1"),
            ("useCalibration", "1"),
        ]
        .iter()
        .find(|(a, _)| *a == k)
        .map(|(_, v)| v.to_string())
    })
    .unwrap();
    let ft = StrainClient::open(Arc::new(bus.endpoint()), params).unwrap();
    assert_eq!(ft.full_scales(), [1000.0, 1000.0, 1000.0, 30.0, 30.0, 30.0]);
    let v = wait_for("F/T data", Duration::from_secs(2), || {
        ft.read_checked().ok()
    });
    assert_eq!(v.len(), 6);
    assert!((4.9..=15.1).contains(&v[2]), "fz {}", v[2]);
    assert!((0.05..=0.55).contains(&v[5]), "tz {}", v[5]);
    let m = ft.calibration_matrix().unwrap();
    assert!((m[3][3] - 1.0).abs() < 1e-3 && m[0][1] == 0.0);
}

#[test]
fn strain_client_reports_a_missing_board() {
    let bus = VirtualBus::new("ft-missing");
    let t0 = Instant::now();
    let err = StrainClient::open(Arc::new(bus.endpoint()), StrainParams::strain(0x0E))
        .err()
        .unwrap();
    assert!(
        matches!(err, ClientError::BoardTimeout { board: 0x0E, .. }),
        "{err}"
    );
    assert!(t0.elapsed() < Duration::from_secs(1));
    let mut raw = StrainParams::strain(0x0E);
    raw.use_calibration = false;
    let ft = StrainClient::open(Arc::new(bus.endpoint()), raw).unwrap();
    assert_eq!(ft.read().1, SensorStatus::Timeout);
    assert!(ft.read_checked().is_err());
}

#[test]
fn skin_and_inertial_clients() {
    let bus = VirtualBus::new("skin");
    let boards: Vec<Box<dyn crate::emulator::Board>> = vec![
        Box::new(MtbBoard::new(13, true)),
        Box::new(MtbBoard::new(14, true)),
    ];
    let _emu = BusEmulator::new(Arc::new(bus.endpoint()), boards)
        .spawn()
        .unwrap();
    let skin = SkinClient::open(Arc::new(bus.endpoint()), &[14, 13]).unwrap();
    assert_eq!(skin.channels(), 384);
    // Patches arrive one CAN frame at a time: wait until every taxel has been heard
    // (before that, unheard taxels read 0 with an Ok status, as icub-main's).
    let (taxels, _) = wait_for("skin", Duration::from_secs(2), || {
        let r = skin.read(Duration::from_millis(200));
        (r.1 == SensorStatus::Ok && r.0.iter().all(|t| *t != 0.0)).then_some(r)
    });
    assert!(taxels.iter().all(|t| *t == 244.0));
    let imu = InertialClient::open(Arc::new(bus.endpoint()), &[14], "extAccAndGyro", 5).unwrap();
    let (v, _) = wait_for("inertial", Duration::from_secs(2), || {
        let r = imu.read();
        (r.1 == SensorStatus::Ok).then_some(r)
    });
    assert_eq!(v, vec![0.0, 0.0, 16384.0, 0.0, 0.0, 0.0]);
    assert!(InertialClient::open(Arc::new(bus.endpoint()), &[14], "magnetometer", 5).is_err());
    assert!(SkinClient::open(Arc::new(bus.endpoint()), &[15]).is_err());
    assert_eq!(
        skin.silent_boards(Duration::from_millis(200)),
        Vec::<u8>::new()
    );
}

#[test]
fn motor_client_over_udp() {
    let hub = UdpBus::hub("127.0.0.1:0").unwrap();
    let addr = hub.local_addr().unwrap().to_string();
    let boards: Vec<Box<dyn crate::emulator::Board>> = [1, 2, 3]
        .map(|a| -> Box<dyn crate::emulator::Board> {
            Box::new(McBoard::new(McBoardConfig::new(a)))
        })
        .into();
    let _emu = BusEmulator::new(Arc::new(hub), boards).spawn().unwrap();
    let bus: Arc<dyn CanBus> = crate::bus::config::open_from_params(&|k| match k {
        "canBackend" => Some(format!("udp://{addr}")),
        _ => None,
    })
    .unwrap();
    let mut params = McParams::uniform(&[1, 2, 3], 6, 11.375);
    params.reply_timeout = Duration::from_millis(300);
    let mc = MotorControlClient::open(bus, params).unwrap();
    mc.set_control_mode(4, ControlMode::Position).unwrap();
    mc.set_ref_speed(4, 100.0).unwrap();
    mc.position_move(4, 12.0).unwrap();
    wait_for("head move", Duration::from_secs(5), || {
        mc.motion_done(4).ok().filter(|d| *d)
    });
    wait_for("head at target", Duration::from_secs(2), || {
        mc.encoder(4).ok().filter(|p| (p - 12.0).abs() < 0.5)
    });
}

#[test]
fn motor_encoders_follow_when_broadcast() {
    let bus = VirtualBus::new("rotor");
    let _emu = left_arm_network(&bus);
    let mut params = left_arm_params();
    let rotor = params.rotor[0];
    assert_eq!(rotor, 21.888);
    for mask in params.broadcast_policy.as_mut().unwrap() {
        *mask |= 1 << crate::proto::mc::per::MOTOR_POSITION;
    }
    let mc = MotorControlClient::open(Arc::new(bus.endpoint()), params.clone()).unwrap();
    let m = wait_for("motor encoder", Duration::from_secs(2), || {
        mc.motor_encoder(0).ok()
    });
    let joint_ticks = (mc.encoder(0).unwrap() + params.zeros[0]) * params.encoder[0];
    assert!(
        (m * rotor - joint_ticks).abs() < 2.0,
        "{m} vs {joint_ticks}"
    );
}
