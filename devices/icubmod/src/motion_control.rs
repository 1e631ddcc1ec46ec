//! `canmotioncontrol` (icub-main `CanBusMotionControl`): the motor-control boards of one
//! robot part on one CAN network, behind the YARP motor interfaces.
//!
//! Configuration: the icub-main groups `CAN`, `GENERAL`, `LIMITS`, `VELOCITY`,
//! `POS_PIDS`, `TRQ_PIDS` as the iCub XML files give them (declared in
//! [`CanMotionControlParams`]; among them
//! `GENERAL::TorqueMax`, N·m at full sensor scale: torque references are sent and
//! measured torques read as `τ · 0x8000 / TorqueMax`, as icub-main does, and
//! `GENERAL::TorqueId`/`TorqueChan`, the analog-sensor board and channel whose
//! broadcasts carry each joint's measured torque, read by `getTorque`/`getTorques`). In
//! addition: `GENERAL::AxisType` (joint types),
//! `GENERAL::fullscalePWM` (for duty cycles), `LIMITS::motorOverloadCurrents` (reported
//! as the maximum current), `LIMITS::jntVelMax` (velocity limits). The bus comes from
//! `CAN::canBackend` (or `physDevice` + `CanDeviceNum`, see [`crate::common::CanBusParams`]).
//!
//! `IMPEDANCE::stiffness`/`damping` (N·m/°, N·m·s/°, one per joint, as icub-main's
//! `parseImpedanceGroup_NewFormat`; the iCubGenova01 legs have them) are sent to the
//! boards at open when the group is present. `IImpedanceControl` sends
//! `SET_IMPEDANCE_PARAMS`/`SET_IMPEDANCE_OFFSET` and polls the `GET_` ones; the limits are
//! icub-main's fixed `_impedance_limits` (stiffness 0.002..9.889, damping 0.001..9.888).
//! `IControlCalibration` sends `CALIBRATE_ENCODER`; a joint's calibration is done when
//! its board no longer reports the calibration (or not-configured) mode.
//!
//! Positions, encoders and modes come from the boards' broadcasts; a board that stops
//! broadcasting makes reads fail after 500 ms, one that does not answer a poll fails
//! after `CanTimeout`. Nothing blocks longer. A board that falls silent is reported (as
//! icub-main's "have not heard from board N"), and when it talks again its reads work
//! again and the log says what a reset board lost ([`crate::presence`]).

use std::sync::Arc;
use std::time::{Duration, Instant};

use icub_can::client::{JointPid, McParams, MotorControlClient};
use icub_can::proto::{ControlMode, PidKind};
use yarp_proto::{Property, Vocab32};

use crate::boards::{self, Registration};
use crate::common::{call_error, device_id, open_error, CanBusParams};
use yarp_devices::driver::DeviceDriver;
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::interfaces::*;
use yarp_devices::vocabs::*;

pub(crate) const NAME: &str = "canmotioncontrol";

// YARP control-mode and PID-type vocabs this device needs beyond `yarp_devices::vocabs`.
const PIDTYPE_VELOCITY: Vocab32 = Vocab32::new("vel");
const PIDTYPE_TORQUE: Vocab32 = Vocab32::new("trq");
const PIDTYPE_CURRENT: Vocab32 = Vocab32::new("cur");

/// The YARP vocab of a board control mode.
pub fn mode_vocab(m: ControlMode) -> Vocab32 {
    match m {
        ControlMode::Idle => CM_IDLE,
        ControlMode::ForceIdle => CM_FORCE_IDLE,
        ControlMode::Position => CM_POSITION,
        ControlMode::Velocity => CM_VELOCITY,
        ControlMode::Torque => CM_TORQUE,
        ControlMode::ImpedancePos => CM_IMPEDANCE_POS,
        ControlMode::ImpedanceVel => CM_IMPEDANCE_VEL,
        ControlMode::Current => CM_CURRENT,
        ControlMode::Mixed => CM_MIXED,
        ControlMode::Direct => CM_POSITION_DIRECT,
        ControlMode::OpenLoop => CM_PWM,
        ControlMode::Calibration => CM_CALIBRATING,
        ControlMode::HwFault => CM_HW_FAULT,
        ControlMode::NotConfigured => CM_NOT_CONFIGURED,
        ControlMode::Configured => CM_CONFIGURED,
        ControlMode::Other(_) => CM_UNKNOWN,
    }
}

/// The board control mode for a YARP vocab that a host may request.
pub fn vocab_mode(v: Vocab32) -> Option<ControlMode> {
    Some(match v {
        _ if v == CM_IDLE => ControlMode::Idle,
        _ if v == CM_FORCE_IDLE => ControlMode::ForceIdle,
        _ if v == CM_POSITION => ControlMode::Position,
        _ if v == CM_VELOCITY => ControlMode::Velocity,
        _ if v == CM_TORQUE => ControlMode::Torque,
        _ if v == CM_CURRENT => ControlMode::Current,
        _ if v == CM_MIXED => ControlMode::Mixed,
        _ if v == CM_POSITION_DIRECT => ControlMode::Direct,
        _ if v == CM_PWM => ControlMode::OpenLoop,
        _ if v == CM_IMPEDANCE_POS => ControlMode::ImpedancePos,
        _ if v == CM_IMPEDANCE_VEL => ControlMode::ImpedanceVel,
        _ => return None,
    })
}

fn pid_kind(t: Vocab32) -> DevResult<PidKind> {
    match t {
        _ if t == PIDTYPE_POSITION => Ok(PidKind::Position),
        _ if t == PIDTYPE_TORQUE => Ok(PidKind::Torque),
        _ if t == PIDTYPE_VELOCITY => Ok(PidKind::Velocity),
        _ if t == PIDTYPE_CURRENT => Ok(PidKind::Current),
        _ => Err(DeviceError::Unsupported("unknown PID type")),
    }
}

/// The `canmotioncontrol` device.
#[derive(Default)]
pub struct CanMotionControl {
    id: String,
    client: Option<Arc<MotorControlClient>>,
    _registration: Option<Registration>,
    _presence: Option<crate::presence::PresenceWatch>,
    joint_types: Vec<Vocab32>,
    targets: Vec<f64>,
    ref_velocities: Vec<f64>,
    vel_limits: Vec<(f64, f64)>,
    max_currents: Vec<f64>,
    full_scale_pwm: Vec<f64>,
    /// When each joint's mode was last commanded: older broadcasts are not trusted.
    mode_set_at: Vec<Option<Instant>>,
}

impl CanMotionControl {
    pub fn new() -> Self {
        Self::default()
    }

    /// The driver core (to reach board health, bus counters, ...).
    pub fn client(&self) -> Option<&Arc<MotorControlClient>> {
        self.client.as_ref()
    }

    fn c(&self) -> DevResult<&MotorControlClient> {
        self.client.as_deref().ok_or(DeviceError::NotOpen)
    }

    fn axes(&self) -> DevResult<usize> {
        Ok(self.c()?.joints())
    }

    fn check(&self, j: usize) -> DevResult<()> {
        let axes = self.axes()?;
        if j < axes {
            Ok(())
        } else {
            Err(DeviceError::InvalidJoint {
                joint: j as i64,
                axes,
            })
        }
    }

    /// Runs a driver-core call, mapping its error.
    fn run<T>(
        &self,
        f: impl FnOnce(&MotorControlClient) -> Result<T, icub_can::client::ClientError>,
    ) -> DevResult<T> {
        f(self.c()?).map_err(|e| call_error(&self.id, e))
    }
}

yarp_devices::device_params! {
    /// What `canmotioncontrol` reads (icub-main's `CanBusMotionControl`), besides its bus
    /// ([`CanBusParams`], in the `CAN` group or at the top). Per-joint lines have at least
    /// one value per joint (extra values are ignored, as icub-main does).
    pub struct CanMotionControlParams for "canmotioncontrol" {
        /// Number of joints
        "GENERAL::Joints" joints: usize = required,
        /// The CAN axis of each joint (identity when absent or short)
        "GENERAL::AxisMap" axis_map: Vec<f64> = optional,
        /// Name of each joint (joint<j> when absent)
        "GENERAL::AxisName" axis_name: Vec<String> = optional,
        /// revolute or prismatic, per joint
        "GENERAL::AxisType" axis_type: Vec<String> = optional,
        /// Encoder ticks per degree of each joint (negative flips it; 0: unused axis)
        "GENERAL::Encoder" encoder: Vec<f64> = required,
        /// Zero of each joint
        "GENERAL::Zeros" zeros: Vec<f64> = optional; "deg",
        /// Full scale of each joint's torque sensor
        "GENERAL::TorqueMax" torque_max: Vec<f64> = optional; "Nm",
        /// CAN address of the board measuring each joint's torque (0: none)
        "GENERAL::TorqueId" torque_id: Vec<f64> = optional,
        /// Channel (0..5) of that board
        "GENERAL::TorqueChan" torque_chan: Vec<f64> = optional,
        /// Motor encoder ticks per degree of each joint (1 when absent)
        "GENERAL::Rotor" rotor: Vec<f64> = optional,
        /// Full-scale PWM of each joint
        "GENERAL::fullscalePWM" fullscale_pwm: Vec<f64> = optional,
        /// The boards' CAN addresses (1..14), one per two axes
        "CAN::CanAddresses" can_addresses: Vec<i64> = required,
        /// The host's CAN address (0)
        "CAN::CanMyAddress" can_my_address: f64 = optional,
        /// How long to wait for a polling reply (500)
        "CAN::CanTimeout" can_timeout: f64 = optional; "ms",
        /// 1 where the axis broadcasts its positions
        "CAN::broadcast_pos" broadcast_pos: Vec<f64> = optional,
        /// 1 where the axis broadcasts its PID values
        "CAN::broadcast_pid" broadcast_pid: Vec<f64> = optional,
        /// 1 where the axis broadcasts its faults
        "CAN::broadcast_fault" broadcast_fault: Vec<f64> = optional,
        /// 1 where the axis broadcasts its currents
        "CAN::broadcast_current" broadcast_current: Vec<f64> = optional,
        /// 1 where the axis broadcasts its overflows
        "CAN::broadcast_overflow" broadcast_overflow: Vec<f64> = optional,
        /// 1 where the axis broadcasts its board prints
        "CAN::broadcast_canprint" broadcast_canprint: Vec<f64> = optional,
        /// 1 where the axis broadcasts its speeds and accelerations
        "CAN::broadcast_vel_acc" broadcast_vel_acc: Vec<f64> = optional,
        /// 1 where the axis broadcasts its PID errors
        "CAN::broadcast_pid_err" broadcast_pid_err: Vec<f64> = optional,
        /// 1 where the axis broadcasts its rotor positions
        "CAN::broadcast_rotor_pos" broadcast_rotor_pos: Vec<f64> = optional,
        /// 1 where the axis broadcasts its rotor speeds and accelerations
        "CAN::broadcast_rotor_vel_acc" broadcast_rotor_vel_acc: Vec<f64> = optional,
        /// Lowest position of each joint
        "LIMITS::jntPosMin" jnt_pos_min: Vec<f64> = optional; "deg",
        /// Highest position of each joint
        "LIMITS::jntPosMax" jnt_pos_max: Vec<f64> = optional; "deg",
        /// Highest speed of each joint
        "LIMITS::jntVelMax" jnt_vel_max: Vec<f64> = optional; "deg/s",
        /// Current limit of each motor
        "LIMITS::motorOverloadCurrents" motor_overload_currents: Vec<f64> = optional; "mA",
        /// Velocity command shift of each joint (at most 15)
        "VELOCITY::Shifts" velocity_shifts: Vec<f64> = optional,
        /// Time a velocity command lasts (100)
        "VELOCITY::Timeout" velocity_timeout: Vec<f64> = optional; "ms",
        /// JNT speed estimation shift of each joint (at most 15)
        "VELOCITY::JNT_speed_estimation" jnt_speed_estimation: Vec<f64> = optional,
        /// JNT accel estimation shift of each joint (at most 15)
        "VELOCITY::JNT_accel_estimation" jnt_accel_estimation: Vec<f64> = optional,
        /// MOT speed estimation shift of each joint (at most 15)
        "VELOCITY::MOT_speed_estimation" mot_speed_estimation: Vec<f64> = optional,
        /// MOT accel estimation shift of each joint (at most 15)
        "VELOCITY::MOT_accel_estimation" mot_accel_estimation: Vec<f64> = optional,
        /// The position PID's proportional gain of each joint (sent at open with kp)
        "POS_PIDS::kp" pos_pids_kp: Vec<f64> = optional,
        /// The position PID's derivative gain of each joint (sent at open with kp)
        "POS_PIDS::kd" pos_pids_kd: Vec<f64> = optional,
        /// The position PID's integral gain of each joint (sent at open with kp)
        "POS_PIDS::ki" pos_pids_ki: Vec<f64> = optional,
        /// The position PID's integral limit of each joint (sent at open with kp)
        "POS_PIDS::maxInt" pos_pids_max_int: Vec<f64> = optional,
        /// The position PID's output shift of each joint (sent at open with kp)
        "POS_PIDS::shift" pos_pids_shift: Vec<f64> = optional,
        /// The position PID's output limit of each joint (sent at open with kp)
        "POS_PIDS::maxOutput" pos_pids_max_output: Vec<f64> = optional,
        /// The position PID's output offset of each joint (sent at open with kp)
        "POS_PIDS::ko" pos_pids_ko: Vec<f64> = optional,
        /// The torque PID's proportional gain of each joint (sent at open with kp)
        "TRQ_PIDS::kp" trq_pids_kp: Vec<f64> = optional,
        /// The torque PID's derivative gain of each joint (sent at open with kp)
        "TRQ_PIDS::kd" trq_pids_kd: Vec<f64> = optional,
        /// The torque PID's integral gain of each joint (sent at open with kp)
        "TRQ_PIDS::ki" trq_pids_ki: Vec<f64> = optional,
        /// The torque PID's integral limit of each joint (sent at open with kp)
        "TRQ_PIDS::maxInt" trq_pids_max_int: Vec<f64> = optional,
        /// The torque PID's output shift of each joint (sent at open with kp)
        "TRQ_PIDS::shift" trq_pids_shift: Vec<f64> = optional,
        /// The torque PID's output limit of each joint (sent at open with kp)
        "TRQ_PIDS::maxOutput" trq_pids_max_output: Vec<f64> = optional,
        /// The torque PID's output offset of each joint (sent at open with kp)
        "TRQ_PIDS::ko" trq_pids_ko: Vec<f64> = optional,
        /// Impedance stiffness of each joint (with damping)
        "IMPEDANCE::stiffness" stiffness: Vec<f64> = optional; "Nm/deg",
        /// Impedance damping of each joint
        "IMPEDANCE::damping" damping: Vec<f64> = optional; "Nm/(deg/s)",
    }
}

/// A per-joint line as icub-main reads it: its first `joints` values (more are ignored),
/// `default` for every joint when absent.
fn first_joints(
    id: &str,
    key: &str,
    line: &Option<Vec<f64>>,
    joints: usize,
    default: Option<f64>,
) -> DevResult<Vec<f64>> {
    match line {
        Some(v) if v.len() >= joints => Ok(v[..joints].to_vec()),
        Some(v) => Err(DeviceError::BadParam {
            device: id.to_string(),
            param: key.to_string(),
            expected: "one number per joint",
            got: format!("{} values for {joints} joints", v.len()),
        }),
        None => default
            .map(|d| vec![d; joints])
            .ok_or_else(|| DeviceError::MissingParam {
                device: id.to_string(),
                param: key.to_string(),
            }),
    }
}

/// A per-joint line read leniently, as icub-main reads its optional ones: a value per
/// joint where given, `default` elsewhere.
fn lenient(line: &Option<Vec<f64>>, joints: usize, default: f64) -> Vec<f64> {
    let v = line.as_deref().unwrap_or_default();
    (0..joints)
        .map(|j| v.get(j).copied().unwrap_or(default))
        .collect()
}

impl CanMotionControlParams {
    /// The driver core's parameters (icub-main's `CanBusMotionControlParameters`).
    fn mc_params(&self, id: &str) -> DevResult<McParams> {
        use icub_can::client::mc::{broadcast_masks, torque_sensors};
        let n = self.joints;
        let pj = |key: &str, line: &Option<Vec<f64>>, default: Option<f64>| {
            first_joints(id, key, line, n, default)
        };
        let can_addresses = self
            .can_addresses
            .iter()
            .map(|a| match u8::try_from(*a) {
                Ok(a @ 1..=14) => Ok(a),
                _ => Err(DeviceError::BadParam {
                    device: id.to_string(),
                    param: "CAN::CanAddresses".into(),
                    expected: "board addresses 1..14",
                    got: a.to_string(),
                }),
            })
            .collect::<DevResult<Vec<u8>>>()?;
        let axis_map = pj("GENERAL::AxisMap", &self.axis_map, None)
            .unwrap_or_else(|_| (0..n).map(|j| j as f64).collect())
            .into_iter()
            .map(|a| a as usize)
            .collect();
        let min = pj(
            "LIMITS::jntPosMin",
            &self.jnt_pos_min,
            Some(f64::NEG_INFINITY),
        )?;
        let max = pj("LIMITS::jntPosMax", &self.jnt_pos_max, Some(f64::INFINITY))?;
        let pids =
            |group: &str, gains: [&Option<Vec<f64>>; 7]| -> DevResult<Option<Vec<JointPid>>> {
                if gains[0].is_none() {
                    return Ok(None);
                }
                const KEYS: [&str; 7] = ["kp", "kd", "ki", "maxInt", "shift", "maxOutput", "ko"];
                let g = (0..7)
                    .map(|k| pj(&format!("{group}::{}", KEYS[k]), gains[k], Some(0.0)))
                    .collect::<DevResult<Vec<Vec<f64>>>>()?;
                Ok(Some(
                    (0..n)
                        .map(|j| JointPid {
                            kp: g[0][j],
                            kd: g[1][j],
                            ki: g[2][j],
                            max_int: g[3][j],
                            scale: g[4][j],
                            max_output: g[5][j],
                            offset: g[6][j],
                        })
                        .collect(),
                ))
            };
        let estimation = [
            pj(
                "VELOCITY::JNT_speed_estimation",
                &self.jnt_speed_estimation,
                Some(0.0),
            )?,
            pj(
                "VELOCITY::JNT_accel_estimation",
                &self.jnt_accel_estimation,
                Some(0.0),
            )?,
            pj(
                "VELOCITY::MOT_speed_estimation",
                &self.mot_speed_estimation,
                Some(0.0),
            )?,
            pj(
                "VELOCITY::MOT_accel_estimation",
                &self.mot_accel_estimation,
                Some(0.0),
            )?,
        ];
        // in the order of icub-can's BROADCAST_FLAGS
        let flags = [
            &self.broadcast_pos,
            &self.broadcast_pid,
            &self.broadcast_fault,
            &self.broadcast_current,
            &self.broadcast_overflow,
            &self.broadcast_canprint,
            &self.broadcast_vel_acc,
            &self.broadcast_pid_err,
            &self.broadcast_rotor_pos,
            &self.broadcast_rotor_vel_acc,
        ]
        .map(Clone::clone);
        let broadcast_policy = broadcast_masks(&flags, can_addresses.len());
        let torque_max = self.torque_max.clone().unwrap_or_default();
        let (ids, chans) = (
            self.torque_id.clone().unwrap_or_default(),
            self.torque_chan.clone().unwrap_or_default(),
        );
        let params = McParams {
            host_address: self.can_my_address.unwrap_or(0.0) as u8,
            reply_timeout: Duration::from_millis(
                self.can_timeout.map_or(500, |v| v.max(1.0) as u64),
            ),
            broadcast_timeout: Duration::from_millis(500),
            axis_names: self
                .axis_name
                .clone()
                .unwrap_or_else(|| (0..n).map(|j| format!("joint{j}")).collect()),
            encoder: pj("GENERAL::Encoder", &Some(self.encoder.clone()), None)?,
            zeros: pj("GENERAL::Zeros", &self.zeros, Some(0.0))?,
            // as icub-main, a missing or short list means "no sensor" / scale 1
            torque_scale: (0..n)
                .map(|j| match torque_max.get(j) {
                    Some(&max) if max > 0.0 => f64::from(0x8000u16) / max,
                    _ => 1.0,
                })
                .collect(),
            torque_sensors: torque_sensors(&ids, &chans, n),
            rotor: pj("GENERAL::Rotor", &self.rotor, Some(1.0))?,
            limits: min.into_iter().zip(max).collect(),
            vel_shifts: pj("VELOCITY::Shifts", &self.velocity_shifts, Some(0.0))?
                .into_iter()
                .map(|v| v as u16)
                .collect(),
            estimation_shifts: (0..n)
                .map(|j| estimation.each_ref().map(|e| e[j] as u8))
                .collect(),
            vel_timeouts: pj("VELOCITY::Timeout", &self.velocity_timeout, Some(100.0))?
                .into_iter()
                .map(|v| v as u16)
                .collect(),
            position_pids: pids(
                "POS_PIDS",
                [
                    &self.pos_pids_kp,
                    &self.pos_pids_kd,
                    &self.pos_pids_ki,
                    &self.pos_pids_max_int,
                    &self.pos_pids_shift,
                    &self.pos_pids_max_output,
                    &self.pos_pids_ko,
                ],
            )?,
            torque_pids: pids(
                "TRQ_PIDS",
                [
                    &self.trq_pids_kp,
                    &self.trq_pids_kd,
                    &self.trq_pids_ki,
                    &self.trq_pids_max_int,
                    &self.trq_pids_shift,
                    &self.trq_pids_max_output,
                    &self.trq_pids_ko,
                ],
            )?,
            broadcast_policy,
            can_addresses,
            axis_map,
        };
        params.validate().map_err(|e| open_error(id, &e))?;
        Ok(params)
    }
}

impl DeviceDriver for CanMotionControl {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        [CanMotionControlParams::PARAMS, CanBusParams::PARAMS].concat()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.close()?;
        self.id = device_id(config, NAME);
        yarp_devices::params::help_if_asked(NAME, config, &self.parameters());
        let p = CanMotionControlParams::parse(&self.id, config)?;
        let bus_params = CanBusParams::parse_in_group(&self.id, config, "CAN")?;
        let params = p.mc_params(&self.id)?;
        let n = params.joints();
        let bus = bus_params.open(&self.id)?;
        let client =
            Arc::new(MotorControlClient::open(bus, params).map_err(|e| open_error(&self.id, &e))?);
        let types = p.axis_type.clone().unwrap_or_default();
        self.joint_types = (0..n)
            .map(|j| match types.get(j).map(String::as_str) {
                Some("prismatic") => JOINTTYPE_PRISMATIC,
                _ => JOINTTYPE_REVOLUTE,
            })
            .collect();
        let vmax = lenient(&p.jnt_vel_max, n, 0.0);
        self.vel_limits = vmax.into_iter().map(|v| (0.0, v)).collect();
        self.max_currents = lenient(&p.motor_overload_currents, n, 0.0);
        self.full_scale_pwm = lenient(&p.fullscale_pwm, n, 0.0);
        self.targets = vec![0.0; n];
        self.ref_velocities = vec![0.0; n];
        self.mode_set_at = vec![None; n];
        // icub-main `CanBusMotionControlParameters::fromConfig`: the IMPEDANCE group is
        // optional; when present its two lists must have one value per joint.
        if config.find_group("IMPEDANCE").is_some() {
            let id = self.id.as_str();
            let list = |k: &str, v: &Option<Vec<f64>>| {
                yarp_devices::params::per_joint(
                    id,
                    &format!("IMPEDANCE::{k}"),
                    v.clone().unwrap_or_default(),
                    n,
                )
            };
            let (stiff, damp) = (
                list("stiffness", &p.stiffness)?,
                list("damping", &p.damping)?,
            );
            for j in 0..n {
                client
                    .set_impedance(j, stiff[j], damp[j])
                    .map_err(|e| call_error(&self.id, e))?;
            }
        }
        self._registration = Some(boards::register(&client));
        self._presence = Some(crate::presence::PresenceWatch::start(&self.id, &client));
        self.client = Some(client);
        tracing::info!(device = %self.id, joints = n, "canmotioncontrol open");
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self._registration = None;
        self._presence = None;
        self.client = None;
        Ok(())
    }

    yarp_devices::views!(
        as_encoders,
        as_position_control,
        as_position_direct,
        as_velocity_control,
        as_control_mode,
        as_axis_info,
        as_control_limits,
        as_interaction_mode,
        as_torque_control,
        as_motor_encoders,
        as_amplifier_control,
        as_pid_control,
        as_pwm_control,
        as_impedance_control,
        as_control_calibration
    );
}

/// icub-main `CanBusMotionControlParameters::fromConfig`, "IMPEDANCE LIMITS (UNDER
/// TESTING)": the same fixed values for every joint, reported without asking the board.
const IMPEDANCE_LIMITS: ImpedanceLimits = ImpedanceLimits {
    min_stiffness: 0.002,
    max_stiffness: 9.889,
    min_damping: 0.001,
    max_damping: 9.888,
};

impl IImpedanceControl for CanMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    fn get_impedance(&mut self, j: usize) -> DevResult<(f64, f64)> {
        self.run(|c| c.impedance(j))
    }
    fn set_impedance(&mut self, j: usize, stiffness: f64, damping: f64) -> DevResult<()> {
        self.run(|c| c.set_impedance(j, stiffness, damping))
    }
    fn get_impedance_offset(&mut self, j: usize) -> DevResult<f64> {
        self.run(|c| c.impedance_offset(j))
    }
    fn set_impedance_offset(&mut self, j: usize, offset: f64) -> DevResult<()> {
        self.run(|c| c.set_impedance_offset(j, offset))
    }
    fn get_current_impedance_limit(&mut self, j: usize) -> DevResult<ImpedanceLimits> {
        self.check(j)?;
        Ok(IMPEDANCE_LIMITS)
    }
}

impl IControlCalibration for CanMotionControl {
    /// `CALIBRATE_ENCODER` with the type and the three parameters (as
    /// `calibrateAxisWithParamsRaw`), the command `parametricCalibrator` sends.
    fn calibrate_axis_with_params(
        &mut self,
        j: usize,
        kind: u32,
        p1: f64,
        p2: f64,
        p3: f64,
    ) -> DevResult<()> {
        let kind = u8::try_from(kind)
            .map_err(|_| DeviceError::Unsupported("calibration type above 255"))?;
        self.run(|c| c.calibrate(j, kind, p1, p2, p3))?;
        self.mode_set_at[j] = Some(Instant::now());
        Ok(())
    }
    /// The same command with `params.kind` and `param1..3` (the CAN message has no room
    /// for the others).
    fn set_calibration_parameters(
        &mut self,
        j: usize,
        params: &CalibrationParameters,
    ) -> DevResult<()> {
        self.calibrate_axis_with_params(j, params.kind, params.param1, params.param2, params.param3)
    }
    /// Done when the board's control mode (status broadcast, or asked) is no longer the
    /// calibration or a not-yet-configured one.
    fn calibration_done(&mut self, j: usize) -> DevResult<bool> {
        let mode = self.get_control_mode(j)?;
        Ok(mode != CM_CALIBRATING && mode != CM_NOT_CONFIGURED && mode != CM_CONFIGURED)
    }
}

impl IEncoders for CanMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    fn get_encoder(&mut self, j: usize) -> DevResult<f64> {
        self.run(|c| c.encoder(j))
    }
    fn get_encoder_speed(&mut self, j: usize) -> DevResult<f64> {
        self.run(|c| c.encoder_speed(j))
    }
    fn get_encoder_acceleration(&mut self, j: usize) -> DevResult<f64> {
        self.run(|c| c.encoder_acceleration(j))
    }
    fn get_encoder_timed(&mut self, j: usize) -> DevResult<(f64, f64)> {
        let pos = self.run(|c| c.encoder(j))?;
        let age = self.run(|c| c.joint_status(j))?.position_age;
        let t = crate::common::now() - age.map_or(0.0, |a| a.as_secs_f64());
        Ok((pos, t))
    }
    fn set_encoder(&mut self, _j: usize, _value: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported(
            "setEncoder: CAN boards have absolute encoders",
        ))
    }
    fn get_encoders(&mut self) -> DevResult<Vec<f64>> {
        self.run(|c| c.encoders())
    }
    fn get_encoders_timed(&mut self) -> DevResult<(Vec<f64>, Vec<f64>)> {
        let v = self.run(|c| c.encoders_timed())?;
        Ok(v.into_iter()
            .map(|(p, at)| (p, crate::common::wall_time(at)))
            .unzip())
    }
}

impl IPositionControl for CanMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    fn position_move(&mut self, j: usize, target: f64) -> DevResult<()> {
        self.run(|c| c.position_move(j, target))?;
        self.targets[j] = target;
        Ok(())
    }
    fn position_moves(&mut self, targets: &[f64]) -> DevResult<()> {
        let axes = self.axes()?;
        if targets.len() != axes {
            return Err(DeviceError::WrongSize {
                expected: axes,
                got: targets.len(),
            });
        }
        self.run(|c| c.position_move_all(targets))?;
        self.targets.copy_from_slice(targets);
        Ok(())
    }
    fn relative_move(&mut self, j: usize, delta: f64) -> DevResult<()> {
        let now = self.run(|c| c.encoder(j))?;
        self.position_move(j, now + delta)
    }
    fn check_motion_done(&mut self, j: usize) -> DevResult<bool> {
        self.run(|c| c.motion_done(j))
    }
    fn set_ref_speed(&mut self, j: usize, speed: f64) -> DevResult<()> {
        self.run(|c| c.set_ref_speed(j, speed))
    }
    fn set_ref_acceleration(&mut self, j: usize, acc: f64) -> DevResult<()> {
        self.run(|c| c.set_ref_acceleration(j, acc))
    }
    fn get_ref_speed(&mut self, j: usize) -> DevResult<f64> {
        self.run(|c| c.ref_speed(j))
    }
    fn get_ref_acceleration(&mut self, j: usize) -> DevResult<f64> {
        self.run(|c| c.ref_acceleration(j))
    }
    fn stop(&mut self, j: usize) -> DevResult<()> {
        self.run(|c| c.stop(j))
    }
    fn get_target_position(&mut self, j: usize) -> DevResult<f64> {
        self.check(j)?;
        Ok(self.targets[j])
    }
}

/// Position direct (C++ `setPositionRaw`): the reference streamed to the board
/// (`SET_COMMAND_POSITION`) only while the joint is in position direct (or idle); in
/// another mode the command is skipped with an error message, and the call still succeeds,
/// as C++'s. The reference read back is the last position move's (C++'s `_ref_positions`).
impl IPositionDirect for CanMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    fn set_position(&mut self, j: usize, reference: f64) -> DevResult<()> {
        let mode = IControlMode::get_control_mode(self, j)?;
        if mode != CM_POSITION_DIRECT && mode != CM_IDLE {
            tracing::error!(
                "setPositionRaw: skipping command because {} joint {j} is not in VOCAB_CM_POSITION_DIRECT mode",
                self.id
            );
            return Ok(());
        }
        self.run(|c| c.set_position(j, reference))
    }
    fn get_ref_position(&mut self, j: usize) -> DevResult<f64> {
        self.check(j)?;
        Ok(self.targets[j])
    }
}

impl IVelocityControl for CanMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    fn velocity_move(&mut self, j: usize, speed: f64) -> DevResult<()> {
        self.run(|c| c.velocity_move(j, speed))?;
        self.ref_velocities[j] = speed;
        Ok(())
    }
    fn get_ref_velocity(&mut self, j: usize) -> DevResult<f64> {
        self.check(j)?;
        Ok(self.ref_velocities[j])
    }
}

impl IControlMode for CanMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    /// From the status broadcast when it is fresh (as icub-main) and newer than the last
    /// mode command, else asked to the board.
    fn get_control_mode(&mut self, j: usize) -> DevResult<Vocab32> {
        let c = self.c()?;
        let status = self.run(|c| c.joint_status(j))?;
        let since_set = self.mode_set_at[j].map(|t| t.elapsed());
        let fresh = status
            .status_age
            .is_some_and(|a| a <= c.params().broadcast_timeout && since_set.is_none_or(|s| a < s));
        match status.mode {
            Some(m) if fresh => Ok(mode_vocab(m)),
            _ => self.run(|c| c.control_mode(j)).map(mode_vocab),
        }
    }
    fn set_control_mode(&mut self, j: usize, mode: Vocab32) -> DevResult<()> {
        let m = vocab_mode(mode).ok_or(DeviceError::Unsupported(
            "control mode not available on CAN boards",
        ))?;
        self.run(|c| c.set_control_mode(j, m))?;
        self.mode_set_at[j] = Some(Instant::now());
        Ok(())
    }
}

impl IInteractionMode for CanMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    fn get_interaction_mode(&mut self, j: usize) -> DevResult<Vocab32> {
        let status = self.run(|c| c.joint_status(j))?;
        let m = match status.interaction {
            Some(m) => m,
            None => self.run(|c| c.interaction_mode(j))?,
        };
        Ok(match m {
            0 => IM_STIFF,
            1 => IM_COMPLIANT,
            _ => IM_UNKNOWN,
        })
    }
    fn set_interaction_mode(&mut self, j: usize, mode: Vocab32) -> DevResult<()> {
        let m = match mode {
            _ if mode == IM_STIFF => 0,
            _ if mode == IM_COMPLIANT => 1,
            _ => return Err(DeviceError::Unsupported("unknown interaction mode")),
        };
        self.run(|c| c.set_interaction_mode(j, m))
    }
}

impl IAxisInfo for CanMotionControl {
    fn get_axis_name(&mut self, j: usize) -> DevResult<String> {
        self.check(j)?;
        Ok(self.c()?.params().axis_names[j].clone())
    }
    fn get_joint_type(&mut self, j: usize) -> DevResult<Vocab32> {
        self.check(j)?;
        Ok(self.joint_types[j])
    }
}

impl IControlLimits for CanMotionControl {
    fn set_limits(&mut self, j: usize, min: f64, max: f64) -> DevResult<()> {
        self.run(|c| c.set_limits(j, min, max))
    }
    fn get_limits(&mut self, j: usize) -> DevResult<(f64, f64)> {
        self.run(|c| c.limits(j))
    }
    fn set_vel_limits(&mut self, j: usize, min: f64, max: f64) -> DevResult<()> {
        self.check(j)?;
        self.vel_limits[j] = (min, max);
        Ok(())
    }
    fn get_vel_limits(&mut self, j: usize) -> DevResult<(f64, f64)> {
        self.check(j)?;
        Ok(self.vel_limits[j])
    }
}

impl ITorqueControl for CanMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    /// The joint torque broadcast on the joint's `TorqueId`/`TorqueChan` (N·m); 0 for a
    /// joint without a sensor (`TorqueId` 0), as icub-main's never-updated value.
    fn get_torque(&mut self, j: usize) -> DevResult<f64> {
        self.check(j)?;
        if self.c()?.params().torque_sensors[j].is_none() {
            return Ok(0.0);
        }
        self.run(|c| c.torque(j))
    }
    fn set_ref_torque(&mut self, j: usize, t: f64) -> DevResult<()> {
        self.run(|c| c.set_ref_torque(j, t))
    }
    fn get_ref_torque(&mut self, j: usize) -> DevResult<f64> {
        self.run(|c| c.ref_torque(j))
    }
}

impl IMotorEncoders for CanMotionControl {
    fn get_num_of_motor_encoders(&mut self) -> DevResult<usize> {
        self.axes()
    }
    fn get_motor_encoder(&mut self, m: usize) -> DevResult<f64> {
        self.run(|c| c.motor_encoder(m))
    }
}

impl IAmplifierControl for CanMotionControl {
    fn enable_amp(&mut self, j: usize) -> DevResult<()> {
        self.run(|c| c.enable_amp(j))
    }
    fn disable_amp(&mut self, j: usize) -> DevResult<()> {
        self.run(|c| c.disable_amp(j))
    }
    /// The fault bits of each joint's last status broadcast (0 = no fault).
    fn get_amp_statuses(&mut self) -> DevResult<Vec<i32>> {
        (0..self.axes()?)
            .map(|j| self.run(|c| c.joint_status(j)).map(|s| i32::from(s.faults)))
            .collect()
    }
    fn get_current(&mut self, j: usize) -> DevResult<f64> {
        self.run(|c| c.current(j))
    }
    fn get_max_current(&mut self, j: usize) -> DevResult<f64> {
        self.check(j)?;
        Ok(self.max_currents[j])
    }
}

impl IPidControl for CanMotionControl {
    fn get_pid(&mut self, pid_type: Vocab32, j: usize) -> DevResult<Pid> {
        let kind = pid_kind(pid_type)?;
        let p = self.run(|c| c.pid(j, kind))?;
        Ok(Pid {
            kp: p.kp,
            kd: p.kd,
            ki: p.ki,
            max_int: p.max_int,
            scale: p.scale,
            max_output: p.max_output,
            offset: p.offset,
            ..Pid::default()
        })
    }
    fn set_pid(&mut self, pid_type: Vocab32, j: usize, pid: Pid) -> DevResult<()> {
        let kind = pid_kind(pid_type)?;
        let p = JointPid {
            kp: pid.kp,
            kd: pid.kd,
            ki: pid.ki,
            max_int: pid.max_int,
            scale: pid.scale,
            max_output: pid.max_output,
            offset: pid.offset,
        };
        self.run(|c| c.set_pid(j, kind, &p))
    }
    fn enable_pid(&mut self, pid_type: Vocab32, j: usize) -> DevResult<()> {
        pid_kind(pid_type)?;
        self.run(|c| c.enable_amp(j))
    }
    fn disable_pid(&mut self, pid_type: Vocab32, j: usize) -> DevResult<()> {
        pid_kind(pid_type)?;
        self.run(|c| c.disable_amp(j))
    }
    fn is_pid_enabled(&mut self, pid_type: Vocab32, j: usize) -> DevResult<bool> {
        pid_kind(pid_type)?;
        let mode = self.get_control_mode(j)?;
        Ok(mode != CM_IDLE && mode != CM_FORCE_IDLE && mode != CM_HW_FAULT)
    }
    fn set_pid_reference(&mut self, pid_type: Vocab32, j: usize, r: f64) -> DevResult<()> {
        match pid_kind(pid_type)? {
            PidKind::Position => self.run(|c| c.set_position(j, r)),
            PidKind::Torque => self.run(|c| c.set_ref_torque(j, r)),
            _ => Err(DeviceError::Unsupported("PID reference of this type")),
        }
    }
    fn get_pid_reference(&mut self, pid_type: Vocab32, j: usize) -> DevResult<f64> {
        match pid_kind(pid_type)? {
            PidKind::Position => self.get_target_position(j),
            PidKind::Torque => self.run(|c| c.ref_torque(j)),
            _ => Err(DeviceError::Unsupported("PID reference of this type")),
        }
    }
}

impl IPwmControl for CanMotionControl {
    /// The PID output broadcast as a percentage of `fullscalePWM`.
    fn get_ref_duty_cycle(&mut self, j: usize) -> DevResult<f64> {
        let out = self.run(|c| c.pid_output(j))?;
        let full = self.full_scale_pwm[j];
        Ok(if full > 0.0 { out / full * 100.0 } else { out })
    }
}
