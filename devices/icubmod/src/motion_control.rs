//! `canmotioncontrol` (icub-main `CanBusMotionControl`): the motor-control boards of one
//! robot part on one CAN network, behind the YARP motor interfaces.
//!
//! Configuration: the icub-main groups `CAN`, `GENERAL`, `LIMITS`, `VELOCITY`,
//! `POS_PIDS`, `TRQ_PIDS` as the iCub XML files give them (read by
//! [`McParams::from_lookup`]; its docs list which keys are used, among them
//! `GENERAL::TorqueMax`, N·m at full sensor scale: torque references are sent and
//! measured torques read as `τ · 0x8000 / TorqueMax`, as icub-main does, and
//! `GENERAL::TorqueId`/`TorqueChan`, the analog-sensor board and channel whose
//! broadcasts carry each joint's measured torque, read by `getTorque`/`getTorques`). In
//! addition: `GENERAL::AxisType` (joint types),
//! `GENERAL::fullscalePWM` (for duty cycles), `LIMITS::motorOverloadCurrents` (reported
//! as the maximum current), `LIMITS::jntVelMax` (velocity limits). The bus comes from
//! `CAN::canBackend` (or `physDevice` + `CanDeviceNum`, see [`crate::common::open_bus`]).
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
use std::time::Instant;

use icub_can::client::{JointPid, McParams, MotorControlClient};
use icub_can::proto::{ControlMode, PidKind};
use yarp_proto::{Property, Vocab32};

use crate::boards::{self, Registration};
use crate::common::{call_error, device_id, lookup, open_bus, open_error};
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

    /// Per-joint numbers of `group::key`, `default` when absent or short.
    fn per_joint(config: &Property, group: &str, key: &str, n: usize, default: f64) -> Vec<f64> {
        let v: Vec<f64> = lookup(config, Some(group), key)
            .unwrap_or_default()
            .iter()
            .filter_map(|s| s.parse().ok())
            .collect();
        (0..n)
            .map(|j| v.get(j).copied().unwrap_or(default))
            .collect()
    }
}

impl DeviceDriver for CanMotionControl {
    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.close()?;
        self.id = device_id(config, NAME);
        let get = |g: &str, k: &str| lookup(config, Some(g), k);
        let params = McParams::from_lookup(&get).map_err(|e| open_error(&self.id, &e))?;
        let n = params.joints();
        let bus = open_bus(&self.id, config, Some("CAN"))?;
        let client =
            Arc::new(MotorControlClient::open(bus, params).map_err(|e| open_error(&self.id, &e))?);
        let types = lookup(config, Some("GENERAL"), "AxisType").unwrap_or_default();
        self.joint_types = (0..n)
            .map(|j| match types.get(j).map(String::as_str) {
                Some("prismatic") => JOINTTYPE_PRISMATIC,
                _ => JOINTTYPE_REVOLUTE,
            })
            .collect();
        let vmax = Self::per_joint(config, "LIMITS", "jntVelMax", n, 0.0);
        self.vel_limits = vmax.into_iter().map(|v| (0.0, v)).collect();
        self.max_currents = Self::per_joint(config, "LIMITS", "motorOverloadCurrents", n, 0.0);
        self.full_scale_pwm = Self::per_joint(config, "GENERAL", "fullscalePWM", n, 0.0);
        self.targets = vec![0.0; n];
        self.ref_velocities = vec![0.0; n];
        self.mode_set_at = vec![None; n];
        // icub-main `CanBusMotionControlParameters::fromConfig`: the IMPEDANCE group is
        // optional; when present its two lists must have one value per joint.
        if config.find_group("IMPEDANCE").is_some() {
            let list = |k: &str| -> DevResult<Vec<f64>> {
                let v = lookup(config, Some("IMPEDANCE"), k).unwrap_or_default();
                let nums: Vec<f64> = v.iter().filter_map(|s| s.parse().ok()).collect();
                if nums.len() == n && v.len() == n {
                    Ok(nums)
                } else {
                    Err(DeviceError::BadParam {
                        device: self.id.clone(),
                        param: format!("IMPEDANCE::{k}"),
                        expected: "one number per joint",
                        got: v.join(" "),
                    })
                }
            };
            let (stiff, damp) = (list("stiffness")?, list("damping")?);
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

    fn as_encoders(&mut self) -> Option<&mut dyn IEncoders> {
        Some(self)
    }
    fn as_position_control(&mut self) -> Option<&mut dyn IPositionControl> {
        Some(self)
    }
    fn as_velocity_control(&mut self) -> Option<&mut dyn IVelocityControl> {
        Some(self)
    }
    fn as_control_mode(&mut self) -> Option<&mut dyn IControlMode> {
        Some(self)
    }
    fn as_axis_info(&mut self) -> Option<&mut dyn IAxisInfo> {
        Some(self)
    }
    fn as_control_limits(&mut self) -> Option<&mut dyn IControlLimits> {
        Some(self)
    }
    fn as_interaction_mode(&mut self) -> Option<&mut dyn IInteractionMode> {
        Some(self)
    }
    fn as_torque_control(&mut self) -> Option<&mut dyn ITorqueControl> {
        Some(self)
    }
    fn as_motor_encoders(&mut self) -> Option<&mut dyn IMotorEncoders> {
        Some(self)
    }
    fn as_amplifier_control(&mut self) -> Option<&mut dyn IAmplifierControl> {
        Some(self)
    }
    fn as_pid_control(&mut self) -> Option<&mut dyn IPidControl> {
        Some(self)
    }
    fn as_pwm_control(&mut self) -> Option<&mut dyn IPwmControl> {
        Some(self)
    }
    fn as_impedance_control(&mut self) -> Option<&mut dyn IImpedanceControl> {
        Some(self)
    }
    fn as_control_calibration(&mut self) -> Option<&mut dyn IControlCalibration> {
        Some(self)
    }
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
