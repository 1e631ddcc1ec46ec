//! Motor-control interface traits, named after their C++ counterparts
//! (`yarp::dev::IEncodersTimed`, `IPositionControl`, ...). Methods return
//! `DevResult` where C++ returns `bool`; joints are `usize`, control modes vocabs.
//! The "all joints" and "group" variants have default implementations in terms of
//! the single-joint methods.

use crate::error::{DevResult, DeviceError};
use yarp_proto::Vocab32;

fn check_len(expected: usize, got: usize) -> DevResult<()> {
    if expected == got {
        Ok(())
    } else {
        Err(DeviceError::WrongSize { expected, got })
    }
}

/// `IEncodersTimed`.
pub trait IEncoders {
    fn get_axes(&mut self) -> DevResult<usize>;
    fn get_encoder(&mut self, j: usize) -> DevResult<f64>;
    fn get_encoder_speed(&mut self, j: usize) -> DevResult<f64>;
    fn get_encoder_acceleration(&mut self, j: usize) -> DevResult<f64>;
    /// Position and the time it was read.
    fn get_encoder_timed(&mut self, j: usize) -> DevResult<(f64, f64)>;
    fn set_encoder(&mut self, j: usize, value: f64) -> DevResult<()>;
    fn reset_encoder(&mut self, j: usize) -> DevResult<()> {
        self.set_encoder(j, 0.0)
    }
    fn reset_encoders(&mut self) -> DevResult<()> {
        (0..self.get_axes()?).try_for_each(|j| self.reset_encoder(j))
    }
    fn set_encoders(&mut self, values: &[f64]) -> DevResult<()> {
        check_len(self.get_axes()?, values.len())?;
        values
            .iter()
            .enumerate()
            .try_for_each(|(j, v)| self.set_encoder(j, *v))
    }
    fn get_encoders(&mut self) -> DevResult<Vec<f64>> {
        (0..self.get_axes()?).map(|j| self.get_encoder(j)).collect()
    }
    fn get_encoder_speeds(&mut self) -> DevResult<Vec<f64>> {
        (0..self.get_axes()?)
            .map(|j| self.get_encoder_speed(j))
            .collect()
    }
    fn get_encoder_accelerations(&mut self) -> DevResult<Vec<f64>> {
        (0..self.get_axes()?)
            .map(|j| self.get_encoder_acceleration(j))
            .collect()
    }
    /// (positions, times).
    fn get_encoders_timed(&mut self) -> DevResult<(Vec<f64>, Vec<f64>)> {
        let mut p = Vec::new();
        let mut t = Vec::new();
        for j in 0..self.get_axes()? {
            let (a, b) = self.get_encoder_timed(j)?;
            p.push(a);
            t.push(b);
        }
        Ok((p, t))
    }
}

/// `IPositionControl` (trajectory generation toward a target at a reference speed).
pub trait IPositionControl {
    fn get_axes(&mut self) -> DevResult<usize>;
    fn position_move(&mut self, j: usize, target: f64) -> DevResult<()>;
    fn relative_move(&mut self, j: usize, delta: f64) -> DevResult<()>;
    fn check_motion_done(&mut self, j: usize) -> DevResult<bool>;
    fn set_ref_speed(&mut self, j: usize, speed: f64) -> DevResult<()>;
    fn set_ref_acceleration(&mut self, j: usize, acc: f64) -> DevResult<()>;
    fn get_ref_speed(&mut self, j: usize) -> DevResult<f64>;
    fn get_ref_acceleration(&mut self, j: usize) -> DevResult<f64>;
    fn stop(&mut self, j: usize) -> DevResult<()>;
    fn get_target_position(&mut self, j: usize) -> DevResult<f64>;

    fn position_moves(&mut self, targets: &[f64]) -> DevResult<()> {
        check_len(self.get_axes()?, targets.len())?;
        targets
            .iter()
            .enumerate()
            .try_for_each(|(j, v)| self.position_move(j, *v))
    }
    fn position_move_group(&mut self, joints: &[usize], targets: &[f64]) -> DevResult<()> {
        check_len(joints.len(), targets.len())?;
        joints
            .iter()
            .zip(targets)
            .try_for_each(|(j, v)| self.position_move(*j, *v))
    }
    fn relative_moves(&mut self, deltas: &[f64]) -> DevResult<()> {
        check_len(self.get_axes()?, deltas.len())?;
        deltas
            .iter()
            .enumerate()
            .try_for_each(|(j, v)| self.relative_move(j, *v))
    }
    fn relative_move_group(&mut self, joints: &[usize], deltas: &[f64]) -> DevResult<()> {
        check_len(joints.len(), deltas.len())?;
        joints
            .iter()
            .zip(deltas)
            .try_for_each(|(j, v)| self.relative_move(*j, *v))
    }
    fn check_motion_dones(&mut self) -> DevResult<bool> {
        let mut all = true;
        for j in 0..self.get_axes()? {
            all &= self.check_motion_done(j)?;
        }
        Ok(all)
    }
    fn check_motion_done_group(&mut self, joints: &[usize]) -> DevResult<bool> {
        let mut all = true;
        for j in joints {
            all &= self.check_motion_done(*j)?;
        }
        Ok(all)
    }
    fn set_ref_speeds(&mut self, speeds: &[f64]) -> DevResult<()> {
        check_len(self.get_axes()?, speeds.len())?;
        speeds
            .iter()
            .enumerate()
            .try_for_each(|(j, v)| self.set_ref_speed(j, *v))
    }
    fn set_ref_speed_group(&mut self, joints: &[usize], speeds: &[f64]) -> DevResult<()> {
        check_len(joints.len(), speeds.len())?;
        joints
            .iter()
            .zip(speeds)
            .try_for_each(|(j, v)| self.set_ref_speed(*j, *v))
    }
    fn set_ref_accelerations(&mut self, accs: &[f64]) -> DevResult<()> {
        check_len(self.get_axes()?, accs.len())?;
        accs.iter()
            .enumerate()
            .try_for_each(|(j, v)| self.set_ref_acceleration(j, *v))
    }
    fn set_ref_acceleration_group(&mut self, joints: &[usize], accs: &[f64]) -> DevResult<()> {
        check_len(joints.len(), accs.len())?;
        joints
            .iter()
            .zip(accs)
            .try_for_each(|(j, v)| self.set_ref_acceleration(*j, *v))
    }
    fn get_ref_speeds(&mut self) -> DevResult<Vec<f64>> {
        (0..self.get_axes()?)
            .map(|j| self.get_ref_speed(j))
            .collect()
    }
    fn get_ref_speed_group(&mut self, joints: &[usize]) -> DevResult<Vec<f64>> {
        joints.iter().map(|j| self.get_ref_speed(*j)).collect()
    }
    fn get_ref_accelerations(&mut self) -> DevResult<Vec<f64>> {
        (0..self.get_axes()?)
            .map(|j| self.get_ref_acceleration(j))
            .collect()
    }
    fn get_ref_acceleration_group(&mut self, joints: &[usize]) -> DevResult<Vec<f64>> {
        joints
            .iter()
            .map(|j| self.get_ref_acceleration(*j))
            .collect()
    }
    fn stops(&mut self) -> DevResult<()> {
        (0..self.get_axes()?).try_for_each(|j| self.stop(j))
    }
    fn stop_group(&mut self, joints: &[usize]) -> DevResult<()> {
        joints.iter().try_for_each(|j| self.stop(*j))
    }
    fn get_target_positions(&mut self) -> DevResult<Vec<f64>> {
        (0..self.get_axes()?)
            .map(|j| self.get_target_position(j))
            .collect()
    }
    fn get_target_position_group(&mut self, joints: &[usize]) -> DevResult<Vec<f64>> {
        joints
            .iter()
            .map(|j| self.get_target_position(*j))
            .collect()
    }
}

/// `IVelocityControl`.
pub trait IVelocityControl {
    fn get_axes(&mut self) -> DevResult<usize>;
    fn velocity_move(&mut self, j: usize, speed: f64) -> DevResult<()>;
    fn get_ref_velocity(&mut self, j: usize) -> DevResult<f64>;
    fn velocity_moves(&mut self, speeds: &[f64]) -> DevResult<()> {
        check_len(self.get_axes()?, speeds.len())?;
        speeds
            .iter()
            .enumerate()
            .try_for_each(|(j, v)| self.velocity_move(j, *v))
    }
    fn velocity_move_group(&mut self, joints: &[usize], speeds: &[f64]) -> DevResult<()> {
        check_len(joints.len(), speeds.len())?;
        joints
            .iter()
            .zip(speeds)
            .try_for_each(|(j, v)| self.velocity_move(*j, *v))
    }
    fn get_ref_velocities(&mut self) -> DevResult<Vec<f64>> {
        (0..self.get_axes()?)
            .map(|j| self.get_ref_velocity(j))
            .collect()
    }
}

/// YARP 4.0's `IVelocityDirect`: velocity references a joint follows directly, in the
/// control mode VELOCITY_DIRECT (`[veld]`), unlike `IVelocityControl`'s trajectories.
pub trait IVelocityDirect {
    fn get_axes(&mut self) -> DevResult<usize>;
    fn set_ref_velocity_direct(&mut self, j: usize, v: f64) -> DevResult<()>;
    fn get_ref_velocity_direct(&mut self, j: usize) -> DevResult<f64>;
    fn set_ref_velocities_direct(&mut self, v: &[f64]) -> DevResult<()> {
        check_len(self.get_axes()?, v.len())?;
        v.iter()
            .enumerate()
            .try_for_each(|(j, x)| self.set_ref_velocity_direct(j, *x))
    }
    fn set_ref_velocities_direct_group(&mut self, joints: &[usize], v: &[f64]) -> DevResult<()> {
        check_len(joints.len(), v.len())?;
        joints
            .iter()
            .zip(v)
            .try_for_each(|(j, x)| self.set_ref_velocity_direct(*j, *x))
    }
    fn get_ref_velocities_direct(&mut self) -> DevResult<Vec<f64>> {
        (0..self.get_axes()?)
            .map(|j| self.get_ref_velocity_direct(j))
            .collect()
    }
    fn get_ref_velocities_direct_group(&mut self, joints: &[usize]) -> DevResult<Vec<f64>> {
        joints
            .iter()
            .map(|&j| self.get_ref_velocity_direct(j))
            .collect()
    }
}

/// Named settings a board offers beyond the interfaces (C++ `IRemoteVariables`, e.g.
/// embObjMotionControl's `kinematic_mj`): each value a Bottle.
pub trait IRemoteVariables {
    fn get_remote_variable(&mut self, key: &str) -> DevResult<yarp_proto::Bottle>;
    fn set_remote_variable(&mut self, key: &str, value: &yarp_proto::Bottle) -> DevResult<()>;
    /// The keys, as a Bottle.
    fn get_remote_variables_list(&mut self) -> DevResult<yarp_proto::Bottle>;
}

/// The last fault of a joint (C++ `IJointFault`): a device-specific code (0: none) and
/// its description.
pub trait IJointFault {
    fn get_last_joint_fault(&mut self, j: usize) -> DevResult<(i32, String)>;
}

/// YARP 4.0's `IJointBrake`: a joint's brake, engaged by hand or automatically.
pub trait IJointBrake {
    fn is_joint_braked(&mut self, j: usize) -> DevResult<bool>;
    fn set_manual_brake_active(&mut self, j: usize, active: bool) -> DevResult<()>;
    fn set_auto_brake_enabled(&mut self, j: usize, enabled: bool) -> DevResult<()>;
    fn get_auto_brake_enabled(&mut self, j: usize) -> DevResult<bool>;
}

/// `IControlMode`: modes are vocabs (`crate::vocabs::CM_*`).
pub trait IControlMode {
    fn get_axes(&mut self) -> DevResult<usize>;
    fn get_control_mode(&mut self, j: usize) -> DevResult<Vocab32>;
    /// The modes joint `j` can be put in (YARP 4.0's `getAvailableControlModes`).
    fn get_available_control_modes(&mut self, _j: usize) -> DevResult<Vec<Vocab32>> {
        Err(DeviceError::Unsupported("getAvailableControlModes"))
    }
    fn set_control_mode(&mut self, j: usize, mode: Vocab32) -> DevResult<()>;
    fn get_control_modes(&mut self) -> DevResult<Vec<Vocab32>> {
        (0..self.get_axes()?)
            .map(|j| self.get_control_mode(j))
            .collect()
    }
    fn get_control_modes_group(&mut self, joints: &[usize]) -> DevResult<Vec<Vocab32>> {
        joints.iter().map(|j| self.get_control_mode(*j)).collect()
    }
    fn set_control_modes(&mut self, modes: &[Vocab32]) -> DevResult<()> {
        check_len(self.get_axes()?, modes.len())?;
        modes
            .iter()
            .enumerate()
            .try_for_each(|(j, m)| self.set_control_mode(j, *m))
    }
    fn set_control_modes_group(&mut self, joints: &[usize], modes: &[Vocab32]) -> DevResult<()> {
        check_len(joints.len(), modes.len())?;
        joints
            .iter()
            .zip(modes)
            .try_for_each(|(j, m)| self.set_control_mode(*j, *m))
    }
}

/// `IAxisInfo`.
pub trait IAxisInfo {
    fn get_axis_name(&mut self, j: usize) -> DevResult<String>;
    /// `crate::vocabs::JOINTTYPE_*`.
    fn get_joint_type(&mut self, j: usize) -> DevResult<Vocab32>;
}

/// `IControlLimits`.
pub trait IControlLimits {
    fn set_limits(&mut self, j: usize, min: f64, max: f64) -> DevResult<()>;
    fn get_limits(&mut self, j: usize) -> DevResult<(f64, f64)>;
    fn set_vel_limits(&mut self, j: usize, min: f64, max: f64) -> DevResult<()>;
    fn get_vel_limits(&mut self, j: usize) -> DevResult<(f64, f64)>;
}

/// `IInteractionMode`: modes are vocabs (`IM_STIFF`, `IM_COMPLIANT`).
pub trait IInteractionMode {
    fn get_axes(&mut self) -> DevResult<usize>;
    fn get_interaction_mode(&mut self, j: usize) -> DevResult<Vocab32>;
    fn set_interaction_mode(&mut self, j: usize, mode: Vocab32) -> DevResult<()>;
    fn get_interaction_modes(&mut self) -> DevResult<Vec<Vocab32>> {
        (0..self.get_axes()?)
            .map(|j| self.get_interaction_mode(j))
            .collect()
    }
    fn get_interaction_modes_group(&mut self, joints: &[usize]) -> DevResult<Vec<Vocab32>> {
        joints
            .iter()
            .map(|j| self.get_interaction_mode(*j))
            .collect()
    }
    fn set_interaction_modes(&mut self, modes: &[Vocab32]) -> DevResult<()> {
        check_len(self.get_axes()?, modes.len())?;
        modes
            .iter()
            .enumerate()
            .try_for_each(|(j, m)| self.set_interaction_mode(j, *m))
    }
    fn set_interaction_modes_group(
        &mut self,
        joints: &[usize],
        modes: &[Vocab32],
    ) -> DevResult<()> {
        check_len(joints.len(), modes.len())?;
        joints
            .iter()
            .zip(modes)
            .try_for_each(|(j, m)| self.set_interaction_mode(*j, *m))
    }
}

/// `ITorqueControl` (subset).
pub trait ITorqueControl {
    fn get_axes(&mut self) -> DevResult<usize>;
    fn get_torque(&mut self, j: usize) -> DevResult<f64>;
    fn set_ref_torque(&mut self, j: usize, t: f64) -> DevResult<()>;
    fn get_ref_torque(&mut self, j: usize) -> DevResult<f64>;
    fn get_torques(&mut self) -> DevResult<Vec<f64>> {
        (0..self.get_axes()?).map(|j| self.get_torque(j)).collect()
    }
    fn get_ref_torques(&mut self) -> DevResult<Vec<f64>> {
        (0..self.get_axes()?)
            .map(|j| self.get_ref_torque(j))
            .collect()
    }
    /// (min, max) torque of joint `j`.
    fn get_torque_range(&mut self, _j: usize) -> DevResult<(f64, f64)> {
        Err(DeviceError::Unsupported("getTorqueRange"))
    }
    /// C++ 3.12 `MotorTorqueParameters` of joint `j`: (bemf, bemf_scale, ktau,
    /// ktau_scale, viscousPos, viscousNeg, coulombPos, coulombNeg, velocityThres).
    fn get_motor_torque_params(&mut self, _j: usize) -> DevResult<[f64; 9]> {
        Err(DeviceError::Unsupported("getMotorTorqueParams"))
    }
    /// bemf, bemf_scale, ktau, ktau_scale, viscousPos, viscousNeg, coulombPos,
    /// coulombNeg, velocityThres (C++ `MotorTorqueParameters`).
    fn set_motor_torque_params(&mut self, _j: usize, _params: [f64; 9]) -> DevResult<()> {
        Err(DeviceError::Unsupported("setMotorTorqueParams"))
    }
}

/// `IMotorEncoders` (subset).
pub trait IMotorEncoders {
    fn get_num_of_motor_encoders(&mut self) -> DevResult<usize>;
    fn get_motor_encoder(&mut self, m: usize) -> DevResult<f64>;
    fn get_motor_encoders(&mut self) -> DevResult<Vec<f64>> {
        (0..self.get_num_of_motor_encoders()?)
            .map(|m| self.get_motor_encoder(m))
            .collect()
    }
    fn get_motor_encoder_counts_per_revolution(&mut self, _m: usize) -> DevResult<f64> {
        Err(DeviceError::Unsupported(
            "getMotorEncoderCountsPerRevolution",
        ))
    }
    fn set_motor_encoder_counts_per_revolution(&mut self, _m: usize, _v: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported(
            "setMotorEncoderCountsPerRevolution",
        ))
    }
    fn get_motor_encoder_speed(&mut self, _m: usize) -> DevResult<f64> {
        Err(DeviceError::Unsupported("getMotorEncoderSpeed"))
    }
    /// What C++'s fake says to the setters: not implemented.
    fn set_motor_encoder(&mut self, _m: usize, _v: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported("setMotorEncoder"))
    }
    fn set_motor_encoders(&mut self, values: &[f64]) -> DevResult<()> {
        values
            .iter()
            .enumerate()
            .try_for_each(|(m, v)| self.set_motor_encoder(m, *v))
    }
    fn reset_motor_encoder(&mut self, _m: usize) -> DevResult<()> {
        Err(DeviceError::Unsupported("resetMotorEncoder"))
    }
    fn reset_motor_encoders(&mut self) -> DevResult<()> {
        (0..self.get_num_of_motor_encoders()?).try_for_each(|m| self.reset_motor_encoder(m))
    }
    fn get_motor_encoder_acceleration(&mut self, _m: usize) -> DevResult<f64> {
        Err(DeviceError::Unsupported("getMotorEncoderAcceleration"))
    }
    /// A motor's position and the time it was read (by default, now).
    fn get_motor_encoder_timed(&mut self, m: usize) -> DevResult<(f64, f64)> {
        Ok((self.get_motor_encoder(m)?, yarp_proto::stamp::now()))
    }
    fn get_motor_encoder_speeds(&mut self) -> DevResult<Vec<f64>> {
        (0..self.get_num_of_motor_encoders()?)
            .map(|m| self.get_motor_encoder_speed(m))
            .collect()
    }
    fn get_motor_encoder_accelerations(&mut self) -> DevResult<Vec<f64>> {
        (0..self.get_num_of_motor_encoders()?)
            .map(|m| self.get_motor_encoder_acceleration(m))
            .collect()
    }
}

/// `IAmplifierControl`. The setters and the per-motor readings other than the current
/// default to "not supported" (a `[fail]` on the wire, as C++ devices that lack them).
pub trait IAmplifierControl {
    fn enable_amp(&mut self, j: usize) -> DevResult<()>;
    fn disable_amp(&mut self, j: usize) -> DevResult<()>;
    fn get_amp_statuses(&mut self) -> DevResult<Vec<i32>>;
    fn get_amp_status(&mut self, j: usize) -> DevResult<i32> {
        let all = self.get_amp_statuses()?;
        let axes = all.len();
        all.get(j).copied().ok_or(DeviceError::InvalidJoint {
            joint: j as i64,
            axes,
        })
    }
    fn get_current(&mut self, j: usize) -> DevResult<f64>;
    fn get_max_current(&mut self, j: usize) -> DevResult<f64>;
    fn set_max_current(&mut self, _j: usize, _v: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported("setMaxCurrent"))
    }
    fn get_nominal_current(&mut self, _m: usize) -> DevResult<f64> {
        Err(DeviceError::Unsupported("getNominalCurrent"))
    }
    fn set_nominal_current(&mut self, _m: usize, _v: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported("setNominalCurrent"))
    }
    fn get_peak_current(&mut self, _m: usize) -> DevResult<f64> {
        Err(DeviceError::Unsupported("getPeakCurrent"))
    }
    fn set_peak_current(&mut self, _m: usize, _v: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported("setPeakCurrent"))
    }
    fn get_pwm(&mut self, _m: usize) -> DevResult<f64> {
        Err(DeviceError::Unsupported("getPWM"))
    }
    fn get_pwm_limit(&mut self, _m: usize) -> DevResult<f64> {
        Err(DeviceError::Unsupported("getPWMLimit"))
    }
    fn set_pwm_limit(&mut self, _m: usize, _v: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported("setPWMLimit"))
    }
    fn get_power_supply_voltage(&mut self, _m: usize) -> DevResult<f64> {
        Err(DeviceError::Unsupported("getPowerSupplyVoltage"))
    }
}

/// `IMotor` (subset).
pub trait IMotor {
    fn get_temperature(&mut self, m: usize) -> DevResult<f64>;
    fn get_number_of_motors(&mut self) -> DevResult<usize> {
        Err(DeviceError::Unsupported("getNumberOfMotors"))
    }
    fn get_gearbox_ratio(&mut self, _m: usize) -> DevResult<f64> {
        Err(DeviceError::Unsupported("getGearboxRatio"))
    }
    fn set_gearbox_ratio(&mut self, _m: usize, _v: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported("setGearboxRatio"))
    }
    fn get_temperature_limit(&mut self, _m: usize) -> DevResult<f64> {
        Err(DeviceError::Unsupported("getTemperatureLimit"))
    }
    fn set_temperature_limit(&mut self, _m: usize, _v: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported("setTemperatureLimit"))
    }
}

/// YARP 4.0's `PidExtraInfo` (`PidDataExtraInfo`): what a PID controls, in words, and the
/// units of its gains, as a tuning GUI shows them.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct PidExtraInfo {
    pub pid_description: String,
    pub input_data_description: String,
    pub output_data_description: String,
    /// The units of kp, kd, ki, max_int, scale, max_output, offset, stiction_up_val,
    /// stiction_down_val and kff, in that order.
    pub units: [String; 10],
}

/// `yarp::dev::Pid`: the 10 gains.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Pid {
    pub kp: f64,
    pub kd: f64,
    pub ki: f64,
    pub max_int: f64,
    pub scale: f64,
    pub max_output: f64,
    pub offset: f64,
    pub stiction_up: f64,
    pub stiction_down: f64,
    pub kff: f64,
}

impl Pid {
    /// The gains in the order C++ puts them on the wire (`RPCMessagesParser`, PID
    /// messages): kp, kd, ki, max_int, max_output, offset, scale, stiction up and down,
    /// kff.
    pub fn to_array(&self) -> [f64; 10] {
        [
            self.kp,
            self.kd,
            self.ki,
            self.max_int,
            self.max_output,
            self.offset,
            self.scale,
            self.stiction_up,
            self.stiction_down,
            self.kff,
        ]
    }
    /// From the wire order (see `to_array`); missing values are 0.
    pub fn from_slice(v: &[f64]) -> Pid {
        let g = |i: usize| v.get(i).copied().unwrap_or(0.0);
        Pid {
            kp: g(0),
            kd: g(1),
            ki: g(2),
            max_int: g(3),
            max_output: g(4),
            offset: g(5),
            scale: g(6),
            stiction_up: g(7),
            stiction_down: g(8),
            kff: g(9),
        }
    }
}

/// `IPidControl` (subset); `pid_type` is a vocab such as `PIDTYPE_POSITION`.
pub trait IPidControl {
    fn get_pid(&mut self, pid_type: Vocab32, j: usize) -> DevResult<Pid>;
    fn set_pid(&mut self, pid_type: Vocab32, j: usize, pid: Pid) -> DevResult<()>;
    fn enable_pid(&mut self, pid_type: Vocab32, j: usize) -> DevResult<()>;
    fn disable_pid(&mut self, pid_type: Vocab32, j: usize) -> DevResult<()>;
    fn is_pid_enabled(&mut self, pid_type: Vocab32, j: usize) -> DevResult<bool>;
    fn set_pid_reference(&mut self, pid_type: Vocab32, j: usize, r: f64) -> DevResult<()>;
    fn get_pid_reference(&mut self, pid_type: Vocab32, j: usize) -> DevResult<f64>;
    /// The current error of the loop.
    fn get_pid_error(&mut self, _pid_type: Vocab32, _j: usize) -> DevResult<f64> {
        Err(DeviceError::Unsupported("getPidError"))
    }
    /// The current output of the loop.
    fn get_pid_output(&mut self, _pid_type: Vocab32, _j: usize) -> DevResult<f64> {
        Err(DeviceError::Unsupported("getPidOutput"))
    }
    /// Resets the loop (integral term).
    fn reset_pid(&mut self, _pid_type: Vocab32, _j: usize) -> DevResult<()> {
        Err(DeviceError::Unsupported("resetPid"))
    }
    fn set_pid_error_limit(&mut self, _pid_type: Vocab32, _j: usize, _l: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported("setPidErrorLimit"))
    }
    fn get_pid_error_limit(&mut self, _pid_type: Vocab32, _j: usize) -> DevResult<f64> {
        Err(DeviceError::Unsupported("getPidErrorLimit"))
    }
    fn set_pid_offset(&mut self, _pid_type: Vocab32, _j: usize, _v: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported("setPidOffset"))
    }
    /// The PID types joint `j` has (YARP 4.0; 3.12's names where 3.12 has them).
    fn get_available_pids(&mut self, _j: usize) -> DevResult<Vec<Vocab32>> {
        Err(DeviceError::Unsupported("getAvailablePids"))
    }
    /// YARP 4.0's feedforward term of a PID.
    fn set_pid_feedforward(&mut self, _pid_type: Vocab32, _j: usize, _v: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported("setPidFeedforward"))
    }
    fn get_pid_feedforward(&mut self, _pid_type: Vocab32, _j: usize) -> DevResult<f64> {
        Err(DeviceError::Unsupported("getPidFeedforward"))
    }
    /// YARP 4.0's description and units of a PID.
    fn get_pid_extra_info(&mut self, _pid_type: Vocab32, _j: usize) -> DevResult<PidExtraInfo> {
        Err(DeviceError::Unsupported("getPidExtraInfo"))
    }
}

/// `ICurrentControl` (subset).
pub trait ICurrentControl {
    fn get_ref_current(&mut self, j: usize) -> DevResult<f64>;
    fn set_ref_current(&mut self, _j: usize, _current: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported("setRefCurrent"))
    }
    /// (min, max) current reference of joint `j`.
    fn get_current_range(&mut self, _j: usize) -> DevResult<(f64, f64)> {
        Err(DeviceError::Unsupported("getCurrentRange"))
    }
    /// One reference per joint, in joint order.
    fn set_ref_currents(&mut self, currents: &[f64]) -> DevResult<()> {
        currents
            .iter()
            .enumerate()
            .try_for_each(|(j, c)| self.set_ref_current(j, *c))
    }
    fn set_ref_current_group(&mut self, joints: &[usize], currents: &[f64]) -> DevResult<()> {
        check_len(joints.len(), currents.len())?;
        joints
            .iter()
            .zip(currents)
            .try_for_each(|(j, c)| self.set_ref_current(*j, *c))
    }
}

/// `IPWMControl` (subset).
pub trait IPwmControl {
    fn get_ref_duty_cycle(&mut self, j: usize) -> DevResult<f64>;
    fn set_ref_duty_cycle(&mut self, _j: usize, _duty: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported("setRefDutyCycle"))
    }
    /// One reference per joint, in joint order.
    fn set_ref_duty_cycles(&mut self, duties: &[f64]) -> DevResult<()> {
        duties
            .iter()
            .enumerate()
            .try_for_each(|(j, d)| self.set_ref_duty_cycle(j, *d))
    }
    /// The measured duty cycle of motor `m`.
    fn get_duty_cycle(&mut self, _m: usize) -> DevResult<f64> {
        Err(DeviceError::Unsupported("getDutyCycle"))
    }
}

/// `IPositionDirect`: joints follow streamed position references directly (no
/// trajectory), in the `CM_POSITION_DIRECT` control mode.
pub trait IPositionDirect {
    fn get_axes(&mut self) -> DevResult<usize>;
    fn set_position(&mut self, j: usize, reference: f64) -> DevResult<()>;
    /// The last reference given to joint `j`.
    fn get_ref_position(&mut self, j: usize) -> DevResult<f64>;
    fn set_positions(&mut self, references: &[f64]) -> DevResult<()> {
        check_len(self.get_axes()?, references.len())?;
        references
            .iter()
            .enumerate()
            .try_for_each(|(j, r)| self.set_position(j, *r))
    }
    fn set_positions_group(&mut self, joints: &[usize], references: &[f64]) -> DevResult<()> {
        check_len(joints.len(), references.len())?;
        joints
            .iter()
            .zip(references)
            .try_for_each(|(j, r)| self.set_position(*j, *r))
    }
    fn get_ref_positions(&mut self) -> DevResult<Vec<f64>> {
        (0..self.get_axes()?)
            .map(|j| self.get_ref_position(j))
            .collect()
    }
    fn get_ref_positions_group(&mut self, joints: &[usize]) -> DevResult<Vec<f64>> {
        joints.iter().map(|j| self.get_ref_position(*j)).collect()
    }
}

/// The stiffness and damping ranges a joint accepts (C++ `getCurrentImpedanceLimit`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ImpedanceLimits {
    pub min_stiffness: f64,
    pub max_stiffness: f64,
    pub min_damping: f64,
    pub max_damping: f64,
}

/// `IImpedanceControl`: the joint's spring (stiffness, damping) and force offset used
/// in the compliant interaction mode.
pub trait IImpedanceControl {
    fn get_axes(&mut self) -> DevResult<usize>;
    /// (stiffness, damping).
    fn get_impedance(&mut self, j: usize) -> DevResult<(f64, f64)>;
    fn set_impedance(&mut self, j: usize, stiffness: f64, damping: f64) -> DevResult<()>;
    fn get_impedance_offset(&mut self, j: usize) -> DevResult<f64>;
    fn set_impedance_offset(&mut self, j: usize, offset: f64) -> DevResult<()>;
    fn get_current_impedance_limit(&mut self, j: usize) -> DevResult<ImpedanceLimits>;
}

/// `yarp::dev::CalibrationParameters` (only `type` and `param1..4` travel over RPC).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CalibrationParameters {
    pub kind: u32,
    pub param1: f64,
    pub param2: f64,
    pub param3: f64,
    pub param4: f64,
    pub param5: f64,
    pub param_zero: f64,
}

const NO_CALIBRATOR: &str = "no calibrator set on this device (C++ setCalibrator)";

/// `IControlCalibration`: per-joint calibration commands. The robot-wide ones go
/// through a calibrator set on the device; C++ fails them when none is set, as the
/// defaults here do.
pub trait IControlCalibration {
    fn calibrate_axis_with_params(
        &mut self,
        j: usize,
        kind: u32,
        p1: f64,
        p2: f64,
        p3: f64,
    ) -> DevResult<()>;
    fn set_calibration_parameters(
        &mut self,
        _j: usize,
        _params: &CalibrationParameters,
    ) -> DevResult<()> {
        Err(DeviceError::Unsupported("setCalibrationParameters"))
    }
    /// Whether joint `j` finished calibrating (non-blocking).
    fn calibration_done(&mut self, j: usize) -> DevResult<bool>;
    fn calibrate_robot(&mut self) -> DevResult<()> {
        Err(DeviceError::Unsupported(NO_CALIBRATOR))
    }
    fn park(&mut self, _wait: bool) -> DevResult<()> {
        Err(DeviceError::Unsupported(NO_CALIBRATOR))
    }
    fn abort_calibration(&mut self) -> DevResult<()> {
        Err(DeviceError::Unsupported(NO_CALIBRATOR))
    }
    fn abort_park(&mut self) -> DevResult<()> {
        Err(DeviceError::Unsupported(NO_CALIBRATOR))
    }
}

/// `IRemoteCalibrator`: lets clients ask the part's calibrator device (which knows the
/// procedure and parameters) to calibrate, home or park joints.
pub trait IRemoteCalibrator {
    fn is_calibrator_device_present(&mut self) -> DevResult<bool>;
    fn calibrate_single_joint(&mut self, j: usize) -> DevResult<()>;
    fn calibrate_whole_part(&mut self) -> DevResult<()>;
    fn homing_single_joint(&mut self, j: usize) -> DevResult<()>;
    fn homing_whole_part(&mut self) -> DevResult<()>;
    fn park_single_joint(&mut self, j: usize, wait: bool) -> DevResult<()>;
    fn park_whole_part(&mut self) -> DevResult<()>;
    fn quit_calibrate(&mut self) -> DevResult<()>;
    fn quit_park(&mut self) -> DevResult<()>;
    /// Points a wrapper's calls at `device`, a calibrator offering `IRemoteCalibrator`
    /// (C++ `setCalibratorDevice`, called by yarprobotinterface on `calibrate`); devices
    /// that serve the calls themselves refuse it.
    fn set_calibrator_device(
        &mut self,
        _device: Option<crate::driver::SharedDevice>,
    ) -> DevResult<()> {
        Err(DeviceError::Unsupported(
            "this device does not forward to a calibrator device",
        ))
    }
    /// The calibrator device this one forwards to (C++ `getCalibratorDevice`), so a
    /// network wrapper can call it without holding this device meanwhile.
    fn calibrator_device(&self) -> Option<crate::driver::SharedDevice> {
        None
    }
    /// The flag `quitCalibrate`/`quitPark` raise, for a calibrator whose running
    /// procedure checks it: a quit must reach a procedure that holds the device.
    fn quit_signal(&self) -> Option<std::sync::Arc<std::sync::atomic::AtomicBool>> {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pid_gains_travel_in_the_cpp_order() {
        let wire = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0];
        let p = Pid::from_slice(&wire);
        assert_eq!((p.max_output, p.offset, p.scale), (5.0, 6.0, 7.0));
        assert_eq!(p.to_array(), wire);
        assert_eq!(Pid::from_slice(&[1.5]).kd, 0.0);
    }
}
