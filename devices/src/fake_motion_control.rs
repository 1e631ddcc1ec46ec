//! `fakeMotionControl`: a simulated N-joint control board.
//!
//! Parameters (as the C++ device): `GENERAL::joints` (also `GENERAL::Joints`, or a
//! top-level `axes`/`joints`), default 1; optional `GENERAL::AxisName`,
//! `GENERAL::AxisType` (`revolute`/`prismatic`), `LIMITS::Min`, `LIMITS::Max`.
//!
//! Dynamics, advanced lazily by elapsed wall time on every call: in position mode a joint
//! moves toward its target at its reference speed (instantly if the speed is 0); in
//! velocity mode it integrates the commanded velocity; in position-direct mode it sits at
//! its last `set_position` reference; in PWM mode it moves at 0.1 x the duty cycle per
//! second. Motor encoders read 10x the joint.
//!
//! The values the C++ fake reports without simulating them are copied from it: motor
//! `m` starts with duty cycle `33 + m`, current `(33 + m) * 100`, maximum current
//! `(33 + m) * 1000`, temperature `37.5 + m`; a current reference sets the current to
//! half of it, a duty-cycle reference sets the duty cycle; PID errors are 0.1 / 0.2 /
//! 0.3 / 0.4 and outputs `1.1 + 10 j` ... by loop type (position, velocity, current,
//! torque); torque ranges and gearbox ratios read 0; a torque reference beyond +-1 puts
//! the joint in `CM_HW_FAULT`. What C++ 3.12.3's fake accepts without doing anything
//! ("not yet implemented", which succeeds) succeeds here too and changes nothing: joint
//! and velocity limits keep their configured values (`LIMITS::*`, velocity 0..50), the
//! gearbox ratio and temperature limit stay 0. One deliberate difference: C++'s
//! `checkMotionDone` is always false, ours true once the joint is at its target.
//!
//! Impedance, as the C++ fake: stiffness, damping and offset are stored (initially 0)
//! and have no effect on the motion; every joint's limits are stiffness 1..10 and
//! damping 2..20. Calibration, as the C++ fake: commands succeed at once and
//! `calibrationDone` answers true (its "not yet implemented" helper returns true).

use crate::driver::DeviceDriver;
use crate::error::{DevResult, DeviceError};
use crate::interfaces::*;
use crate::vocabs::*;
use std::collections::HashMap;
use std::time::Instant;
use yarp_proto::{Property, Vocab32};

const NAME: &str = "fakeMotionControl";

crate::device_params! {
    /// What `fakeMotionControl` reads: C++'s table (`FakeMotionControl_params.md`) and
    /// the older names of the number of joints.
    pub struct FakeMotionControlParams for "fakeMotionControl" {
        /// Number of degrees of freedom
        "GENERAL::Joints" joints: i64 = optional,
        /// a list of reordered indices for the axes (accepted; this fake does not reorder)
        "GENERAL::AxisMap" axis_map: Vec<i64> = optional,
        /// a list of strings representing the axes names
        "GENERAL::AxisName" axis_name: Vec<String> = optional,
        /// a list of strings representing the axes type (revolute/prismatic)
        "GENERAL::AxisType" axis_type: Vec<String> = optional,
        /// a list of scales for the ampsToSensor conversion factors (accepted, unused)
        "GENERAL::ampsToSensor" amps_to_sensor: Vec<f64> = optional,
        /// a list of scales for the fullscalePWM conversion factors (accepted, unused)
        "GENERAL::fullscalePWM" fullscale_pwm: Vec<f64> = optional,
        /// a list of scales for the encoders (accepted, unused)
        "GENERAL::Encoder" encoder: Vec<i64> = optional,
        /// max encoder position
        "LIMITS::Max" max: Vec<f64> = optional; "deg",
        /// min encoder position
        "LIMITS::Min" min: Vec<f64> = optional; "deg",
        /// Number of degrees of freedom (an older name of GENERAL::Joints)
        "GENERAL::joints" general_joints_lowercase: i64 = optional,
        /// Number of degrees of freedom (an older name of GENERAL::Joints)
        axes: i64 = optional,
        /// Number of degrees of freedom (an older name of GENERAL::Joints)
        "joints" joints_top_level: i64 = optional,
    }
}

pub(crate) const DRIVERS: &[(&str, crate::driver::Factory)] =
    &[(NAME, || Box::new(FakeMotionControl::new()))];
const GEARBOX: f64 = 10.0;
/// Joint speed per unit of duty cycle in PWM mode (C++ `PWM_CONSTANT`).
const PWM_CONSTANT: f64 = 0.1;

/// The C++ fake's PID error by loop type.
fn pid_error_of(pid_type: Vocab32) -> f64 {
    match pid_type {
        PIDTYPE_POSITION => 0.1,
        PIDTYPE_VELOCITY => 0.2,
        PIDTYPE_CURRENT => 0.3,
        PIDTYPE_TORQUE => 0.4,
        _ => 0.0,
    }
}

#[derive(Debug, Clone)]
struct Joint {
    pos: f64,
    speed: f64,
    acc: f64,
    target: f64,
    ref_speed: f64,
    ref_acc: f64,
    ref_vel: f64,
    /// YARP 4.0's direct velocity reference (`IVelocityDirect`).
    ref_vel_direct: f64,
    /// YARP 4.0's brake (`IJointBrake`): engaged, and engaged automatically.
    braked: bool,
    auto_brake: bool,
    /// The last hardware fault (`IJointFault`): code (0: none) and message.
    fault: (i32, String),
    /// The motor torque parameters last set (C++ `MotorTorqueParameters`, zeros at first).
    torque_params: [f64; 9],
    mode: Vocab32,
    interaction: Vocab32,
    name: String,
    jtype: Vocab32,
    limits: (f64, f64),
    vel_limits: (f64, f64),
    ref_torque: f64,
    amp_enabled: bool,
    /// Position-direct reference.
    pos_direct: f64,
    ref_duty: f64,
    duty: f64,
    ref_current: f64,
    current: f64,
    max_current: f64,
    peak_current: f64,
    nominal_current: f64,
    pwm_limit: f64,
    supply_voltage: f64,
    stiffness: f64,
    damping: f64,
    impedance_offset: f64,
}

/// The simulated control board.
#[derive(Debug)]
pub struct FakeMotionControl {
    joints: Vec<Joint>,
    pids: HashMap<(i32, usize), (Pid, bool, f64)>,
    /// YARP 4.0's PID feedforward terms, by (type, joint): 0 until set, as C++ 4.0's.
    feedforwards: HashMap<(i32, usize), f64>,
    pid_error_limits: HashMap<(i32, usize), f64>,
    last: Instant,
}

impl Default for FakeMotionControl {
    fn default() -> Self {
        Self::new()
    }
}

use yarp_proto::stamp::now;

impl FakeMotionControl {
    /// A PID type the fake has no words for (C++ 4.0: `method failed`).
    fn no_such_pid(&self, pid_type: Vocab32) -> DeviceError {
        DeviceError::Failed {
            device: NAME.into(),
            reason: format!("no PID of type {}", pid_type.as_string()),
        }
    }

    /// An unopened device with no joints.
    pub fn new() -> Self {
        FakeMotionControl {
            joints: Vec::new(),
            pids: HashMap::new(),
            feedforwards: HashMap::new(),
            pid_error_limits: HashMap::new(),
            last: Instant::now(),
        }
    }

    /// Shortcut: a device opened with `n` joints.
    pub fn with_joints(n: usize) -> Self {
        let mut d = Self::new();
        d.setup(n);
        d
    }

    fn setup(&mut self, n: usize) {
        self.joints = (0..n)
            .map(|i| Joint {
                fault: (0, String::new()),
                torque_params: [0.0; 9],
                pos: 0.0,
                speed: 0.0,
                acc: 0.0,
                target: 0.0,
                ref_speed: 0.0,
                ref_acc: 0.0,
                ref_vel: 0.0,
                ref_vel_direct: 0.0,
                braked: false,
                auto_brake: false,
                mode: CM_POSITION,
                // the C++ fake starts with zeroed (unknown) interaction modes
                interaction: IM_UNKNOWN,
                name: format!("joint{i}"),
                jtype: JOINTTYPE_REVOLUTE,
                // the C++ defaults (LIMITS::Min 0, LIMITS::Max 100, max velocity 50)
                limits: (0.0, 100.0),
                vel_limits: (0.0, 50.0),
                ref_torque: 0.0,
                amp_enabled: false,
                pos_direct: 0.0,
                ref_duty: 0.0,
                duty: 33.0 + i as f64,
                ref_current: 0.0,
                current: (33.0 + i as f64) * 100.0,
                max_current: (33.0 + i as f64) * 1000.0,
                peak_current: (33.0 + i as f64) * 2.0,
                nominal_current: (33.0 + i as f64) * 20.0,
                pwm_limit: (33.0 + i as f64) * 10.0,
                supply_voltage: (33.0 + i as f64) * 200.0,
                stiffness: 0.0,
                damping: 0.0,
                impedance_offset: 0.0,
            })
            .collect();
        self.pids.clear();
        self.last = Instant::now();
    }

    /// Advances the simulation to now.
    fn update(&mut self) {
        let t = Instant::now();
        let dt = t.duration_since(self.last).as_secs_f64();
        self.last = t;
        if dt <= 0.0 {
            return;
        }
        for j in &mut self.joints {
            let old = j.pos;
            let old_speed = j.speed;
            if j.mode == CM_VELOCITY {
                j.pos += j.ref_vel * dt;
            } else if j.mode == CM_POSITION_DIRECT {
                j.pos = j.pos_direct;
            } else if j.mode == CM_PWM {
                j.pos += j.ref_duty * dt * PWM_CONSTANT;
            } else if j.mode == CM_POSITION {
                let err = j.target - j.pos;
                let step = j.ref_speed.abs() * dt;
                if j.ref_speed <= 0.0 || err.abs() <= step {
                    j.pos = j.target;
                } else {
                    j.pos += step * err.signum();
                }
            }
            j.speed = (j.pos - old) / dt;
            j.acc = (j.speed - old_speed) / dt;
        }
    }

    fn joint(&mut self, j: usize) -> DevResult<&mut Joint> {
        let axes = self.joints.len();
        self.joints.get_mut(j).ok_or(DeviceError::InvalidJoint {
            joint: j as i64,
            axes,
        })
    }

    fn updated(&mut self, j: usize) -> DevResult<&mut Joint> {
        self.update();
        self.joint(j)
    }
}

impl DeviceDriver for FakeMotionControl {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        FakeMotionControlParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = FakeMotionControlParams::read(config)?;
        // C++ reads only GENERAL::Joints; the other names are older ones we still take
        let n = [
            ("GENERAL::joints", p.general_joints_lowercase),
            ("GENERAL::Joints", p.joints),
            ("axes", p.axes),
            ("joints", p.joints_top_level),
        ]
        .into_iter()
        .find_map(|(key, n)| Some((key, n?)));
        let n = match n {
            None => 1,
            Some((key, v)) if !(1..=1024).contains(&v) => {
                return Err(DeviceError::BadParam {
                    device: NAME.into(),
                    param: key.into(),
                    expected: "an integer in 1..=1024",
                    got: v.to_string(),
                })
            }
            Some((_, v)) => v as usize,
        };
        self.setup(n);
        let size_check = |key: &str, len: usize| -> DevResult<()> {
            if len == n {
                Ok(())
            } else {
                Err(DeviceError::BadParam {
                    device: NAME.into(),
                    param: key.into(),
                    expected: "one value per joint",
                    got: format!("{len} values for {n} joints"),
                })
            }
        };
        if let Some(names) = p.axis_name {
            size_check("GENERAL::AxisName", names.len())?;
            for (j, name) in self.joints.iter_mut().zip(names) {
                j.name = name;
            }
        }
        if let Some(types) = p.axis_type {
            size_check("GENERAL::AxisType", types.len())?;
            for (j, t) in self.joints.iter_mut().zip(types) {
                j.jtype = match t.as_str() {
                    "revolute" => JOINTTYPE_REVOLUTE,
                    "prismatic" => JOINTTYPE_PRISMATIC,
                    _ => {
                        return Err(DeviceError::BadParam {
                            device: NAME.into(),
                            param: "GENERAL::AxisType".into(),
                            expected: "revolute or prismatic",
                            got: t,
                        })
                    }
                };
            }
        }
        if let Some(mins) = p.min {
            size_check("LIMITS::Min", mins.len())?;
            for (j, m) in self.joints.iter_mut().zip(mins) {
                j.limits.0 = m;
            }
        }
        if let Some(maxs) = p.max {
            size_check("LIMITS::Max", maxs.len())?;
            for (j, m) in self.joints.iter_mut().zip(maxs) {
                j.limits.1 = m;
            }
        }
        Ok(())
    }

    crate::motor_control_views!();
    crate::views!(as_velocity_direct, as_joint_brake, as_joint_fault);
}

impl IEncoders for FakeMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        Ok(self.joints.len())
    }
    fn get_encoder(&mut self, j: usize) -> DevResult<f64> {
        Ok(self.updated(j)?.pos)
    }
    fn get_encoder_speed(&mut self, j: usize) -> DevResult<f64> {
        Ok(self.updated(j)?.speed)
    }
    fn get_encoder_acceleration(&mut self, j: usize) -> DevResult<f64> {
        Ok(self.updated(j)?.acc)
    }
    fn get_encoder_timed(&mut self, j: usize) -> DevResult<(f64, f64)> {
        Ok((self.updated(j)?.pos, now()))
    }
    fn set_encoder(&mut self, j: usize, value: f64) -> DevResult<()> {
        let jt = self.updated(j)?;
        jt.pos = value;
        jt.target = value;
        Ok(())
    }
}

impl IPositionControl for FakeMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        Ok(self.joints.len())
    }
    fn position_move(&mut self, j: usize, target: f64) -> DevResult<()> {
        self.updated(j)?.target = target;
        Ok(())
    }
    fn relative_move(&mut self, j: usize, delta: f64) -> DevResult<()> {
        self.updated(j)?.target += delta;
        Ok(())
    }
    fn check_motion_done(&mut self, j: usize) -> DevResult<bool> {
        let jt = self.updated(j)?;
        Ok(jt.mode != CM_POSITION || (jt.pos - jt.target).abs() < 1e-9)
    }
    fn set_ref_speed(&mut self, j: usize, speed: f64) -> DevResult<()> {
        self.joint(j)?.ref_speed = speed;
        Ok(())
    }
    fn set_ref_acceleration(&mut self, j: usize, acc: f64) -> DevResult<()> {
        self.joint(j)?.ref_acc = acc;
        Ok(())
    }
    fn get_ref_speed(&mut self, j: usize) -> DevResult<f64> {
        Ok(self.joint(j)?.ref_speed)
    }
    fn get_ref_acceleration(&mut self, j: usize) -> DevResult<f64> {
        Ok(self.joint(j)?.ref_acc)
    }
    fn stop(&mut self, j: usize) -> DevResult<()> {
        let jt = self.updated(j)?;
        jt.target = jt.pos;
        jt.ref_vel = 0.0;
        Ok(())
    }
    fn get_target_position(&mut self, j: usize) -> DevResult<f64> {
        Ok(self.joint(j)?.target)
    }
}

impl IVelocityControl for FakeMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        Ok(self.joints.len())
    }
    fn velocity_move(&mut self, j: usize, speed: f64) -> DevResult<()> {
        self.updated(j)?.ref_vel = speed;
        Ok(())
    }
    fn get_ref_velocity(&mut self, j: usize) -> DevResult<f64> {
        Ok(self.joint(j)?.ref_vel)
    }
}

impl IVelocityDirect for FakeMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        Ok(self.joints.len())
    }
    fn set_ref_velocity_direct(&mut self, j: usize, v: f64) -> DevResult<()> {
        self.updated(j)?.ref_vel_direct = v;
        Ok(())
    }
    fn get_ref_velocity_direct(&mut self, j: usize) -> DevResult<f64> {
        Ok(self.joint(j)?.ref_vel_direct)
    }
}

/// As C++'s fake: the fault a high torque reference caused.
impl IJointFault for FakeMotionControl {
    fn get_last_joint_fault(&mut self, j: usize) -> DevResult<(i32, String)> {
        Ok(self.joint(j)?.fault.clone())
    }
}

/// As C++ 4.0's fake: flags kept, nothing else moves.
impl IJointBrake for FakeMotionControl {
    fn is_joint_braked(&mut self, j: usize) -> DevResult<bool> {
        Ok(self.joint(j)?.braked)
    }
    fn set_manual_brake_active(&mut self, j: usize, active: bool) -> DevResult<()> {
        self.updated(j)?.braked = active;
        Ok(())
    }
    fn set_auto_brake_enabled(&mut self, j: usize, enabled: bool) -> DevResult<()> {
        self.updated(j)?.auto_brake = enabled;
        Ok(())
    }
    fn get_auto_brake_enabled(&mut self, j: usize) -> DevResult<bool> {
        Ok(self.joint(j)?.auto_brake)
    }
}

impl IControlMode for FakeMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        Ok(self.joints.len())
    }
    /// C++ 4.0's fake: the same ten modes for every joint.
    fn get_available_control_modes(&mut self, j: usize) -> DevResult<Vec<Vocab32>> {
        self.joint(j)?;
        Ok([
            "idl", "torq", "pos", "posd", "vel", "veld", "icur", "ipwm", "mix", "fidl",
        ]
        .into_iter()
        .map(Vocab32::new)
        .collect())
    }
    fn get_control_mode(&mut self, j: usize) -> DevResult<Vocab32> {
        Ok(self.joint(j)?.mode)
    }
    fn set_control_mode(&mut self, j: usize, mode: Vocab32) -> DevResult<()> {
        let jt = self.updated(j)?;
        if mode == CM_POSITION && jt.mode != CM_POSITION {
            jt.target = jt.pos;
        }
        jt.mode = mode;
        Ok(())
    }
}

impl IAxisInfo for FakeMotionControl {
    fn get_axis_name(&mut self, j: usize) -> DevResult<String> {
        Ok(self.joint(j)?.name.clone())
    }
    fn get_joint_type(&mut self, j: usize) -> DevResult<Vocab32> {
        Ok(self.joint(j)?.jtype)
    }
}

impl IControlLimits for FakeMotionControl {
    // C++ 3.12.3's fake accepts new limits and keeps its configured ones (`LIMITS::Min`
    // / `LIMITS::Max`, default 0..100): `setLimitsRaw` does nothing
    fn set_limits(&mut self, j: usize, _min: f64, _max: f64) -> DevResult<()> {
        self.joint(j)?;
        Ok(())
    }
    fn get_limits(&mut self, j: usize) -> DevResult<(f64, f64)> {
        Ok(self.joint(j)?.limits)
    }
    // C++ 3.12.3's fake: "not yet implemented", which succeeds doing nothing (its
    // velocity limits stay 0..50)
    fn set_vel_limits(&mut self, j: usize, _min: f64, _max: f64) -> DevResult<()> {
        self.joint(j)?;
        Ok(())
    }
    fn get_vel_limits(&mut self, j: usize) -> DevResult<(f64, f64)> {
        Ok(self.joint(j)?.vel_limits)
    }
}

impl IInteractionMode for FakeMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        Ok(self.joints.len())
    }
    fn get_interaction_mode(&mut self, j: usize) -> DevResult<Vocab32> {
        Ok(self.joint(j)?.interaction)
    }
    fn set_interaction_mode(&mut self, j: usize, mode: Vocab32) -> DevResult<()> {
        self.joint(j)?.interaction = mode;
        Ok(())
    }
}

impl ITorqueControl for FakeMotionControl {
    fn get_motor_torque_params(&mut self, j: usize) -> DevResult<[f64; 9]> {
        Ok(self.joint(j)?.torque_params)
    }
    fn set_motor_torque_params(&mut self, j: usize, params: [f64; 9]) -> DevResult<()> {
        self.joint(j)?.torque_params = params;
        Ok(())
    }
    fn get_axes(&mut self) -> DevResult<usize> {
        Ok(self.joints.len())
    }
    fn get_torque(&mut self, j: usize) -> DevResult<f64> {
        self.joint(j)?;
        Ok(0.0)
    }
    fn set_ref_torque(&mut self, j: usize, t: f64) -> DevResult<()> {
        let jt = self.joint(j)?;
        jt.ref_torque = t;
        // as the C++ fake: a "high" torque puts the joint in hardware fault
        if t.abs() > 1.0 {
            tracing::error!(
                "{NAME}: joint {j} received a high torque command ({t}): hardware fault"
            );
            jt.mode = CM_HW_FAULT;
            jt.fault = (1, format!("test{j} torque"));
        }
        Ok(())
    }
    fn get_ref_torque(&mut self, j: usize) -> DevResult<f64> {
        Ok(self.joint(j)?.ref_torque)
    }
    fn get_torque_range(&mut self, j: usize) -> DevResult<(f64, f64)> {
        self.joint(j)?;
        Ok((0.0, 0.0))
    }
}

impl IMotorEncoders for FakeMotionControl {
    // the C++ fake does not keep counts per revolution: it answers 0 and accepts a value
    fn get_motor_encoder_counts_per_revolution(&mut self, m: usize) -> DevResult<f64> {
        self.joint(m)?;
        Ok(0.0)
    }
    fn set_motor_encoder_counts_per_revolution(&mut self, m: usize, _v: f64) -> DevResult<()> {
        self.joint(m)?;
        Ok(())
    }
    fn get_num_of_motor_encoders(&mut self) -> DevResult<usize> {
        Ok(self.joints.len())
    }
    // C++'s NOT_YET_IMPLEMENTED: accepted, nothing done
    fn set_motor_encoder(&mut self, m: usize, _v: f64) -> DevResult<()> {
        self.joint(m)?;
        Ok(())
    }
    fn reset_motor_encoder(&mut self, m: usize) -> DevResult<()> {
        self.joint(m)?;
        Ok(())
    }
    fn get_motor_encoder(&mut self, m: usize) -> DevResult<f64> {
        Ok(self.updated(m)?.pos * GEARBOX)
    }
    fn get_motor_encoder_speed(&mut self, m: usize) -> DevResult<f64> {
        // the C++ fake reports 0 here (not the simulated speed)
        self.joint(m)?;
        Ok(0.0)
    }
    fn get_motor_encoder_acceleration(&mut self, m: usize) -> DevResult<f64> {
        self.joint(m)?;
        Ok(0.0)
    }
}

impl IAmplifierControl for FakeMotionControl {
    fn enable_amp(&mut self, j: usize) -> DevResult<()> {
        self.joint(j)?.amp_enabled = true;
        Ok(())
    }
    fn disable_amp(&mut self, j: usize) -> DevResult<()> {
        self.joint(j)?.amp_enabled = false;
        Ok(())
    }
    fn get_amp_statuses(&mut self) -> DevResult<Vec<i32>> {
        // the C++ fake reports 0 for every amplifier
        Ok(vec![0; self.joints.len()])
    }
    fn get_current(&mut self, j: usize) -> DevResult<f64> {
        Ok(self.joint(j)?.current)
    }
    fn get_max_current(&mut self, j: usize) -> DevResult<f64> {
        Ok(self.joint(j)?.max_current)
    }
    fn set_max_current(&mut self, j: usize, v: f64) -> DevResult<()> {
        self.joint(j)?.max_current = v;
        Ok(())
    }
    fn get_nominal_current(&mut self, m: usize) -> DevResult<f64> {
        Ok(self.joint(m)?.nominal_current)
    }
    fn set_nominal_current(&mut self, m: usize, v: f64) -> DevResult<()> {
        self.joint(m)?.nominal_current = v;
        Ok(())
    }
    fn get_peak_current(&mut self, m: usize) -> DevResult<f64> {
        Ok(self.joint(m)?.peak_current)
    }
    fn set_peak_current(&mut self, m: usize, v: f64) -> DevResult<()> {
        self.joint(m)?.peak_current = v;
        Ok(())
    }
    fn get_pwm(&mut self, m: usize) -> DevResult<f64> {
        Ok(self.joint(m)?.duty)
    }
    fn get_pwm_limit(&mut self, m: usize) -> DevResult<f64> {
        Ok(self.joint(m)?.pwm_limit)
    }
    fn set_pwm_limit(&mut self, m: usize, v: f64) -> DevResult<()> {
        self.joint(m)?.pwm_limit = v;
        Ok(())
    }
    fn get_power_supply_voltage(&mut self, m: usize) -> DevResult<f64> {
        Ok(self.joint(m)?.supply_voltage)
    }
}

impl IMotor for FakeMotionControl {
    fn get_temperature(&mut self, m: usize) -> DevResult<f64> {
        self.joint(m)?;
        Ok(37.5 + m as f64)
    }
    fn get_number_of_motors(&mut self) -> DevResult<usize> {
        Ok(self.joints.len())
    }
    fn get_gearbox_ratio(&mut self, m: usize) -> DevResult<f64> {
        // not implemented by the C++ fake, which answers 0
        self.joint(m)?;
        Ok(0.0)
    }
    // C++ 3.12.3's fake: "not yet implemented", which succeeds doing nothing
    fn set_gearbox_ratio(&mut self, m: usize, _v: f64) -> DevResult<()> {
        self.joint(m)?;
        Ok(())
    }
    fn get_temperature_limit(&mut self, m: usize) -> DevResult<f64> {
        self.joint(m)?;
        Ok(0.0)
    }
    fn set_temperature_limit(&mut self, m: usize, _v: f64) -> DevResult<()> {
        self.joint(m)?;
        Ok(())
    }
}

impl IPidControl for FakeMotionControl {
    fn get_pid(&mut self, pid_type: Vocab32, j: usize) -> DevResult<Pid> {
        self.joint(j)?;
        Ok(self
            .pids
            .get(&(pid_type.0, j))
            .map(|p| p.0)
            .unwrap_or_default())
    }
    fn set_pid(&mut self, pid_type: Vocab32, j: usize, pid: Pid) -> DevResult<()> {
        self.joint(j)?;
        self.pids.entry((pid_type.0, j)).or_default().0 = pid;
        Ok(())
    }
    fn enable_pid(&mut self, pid_type: Vocab32, j: usize) -> DevResult<()> {
        self.joint(j)?;
        self.pids.entry((pid_type.0, j)).or_default().1 = true;
        Ok(())
    }
    fn disable_pid(&mut self, pid_type: Vocab32, j: usize) -> DevResult<()> {
        self.joint(j)?;
        self.pids.entry((pid_type.0, j)).or_default().1 = false;
        Ok(())
    }
    fn is_pid_enabled(&mut self, pid_type: Vocab32, j: usize) -> DevResult<bool> {
        self.joint(j)?;
        Ok(self.pids.get(&(pid_type.0, j)).is_some_and(|p| p.1))
    }
    fn set_pid_reference(&mut self, pid_type: Vocab32, j: usize, r: f64) -> DevResult<()> {
        self.joint(j)?;
        self.pids.entry((pid_type.0, j)).or_default().2 = r;
        Ok(())
    }
    fn get_pid_reference(&mut self, pid_type: Vocab32, j: usize) -> DevResult<f64> {
        self.joint(j)?;
        Ok(self.pids.get(&(pid_type.0, j)).map(|p| p.2).unwrap_or(0.0))
    }
    fn get_pid_error(&mut self, pid_type: Vocab32, j: usize) -> DevResult<f64> {
        self.joint(j)?;
        Ok(pid_error_of(pid_type))
    }
    fn get_pid_output(&mut self, pid_type: Vocab32, j: usize) -> DevResult<f64> {
        self.joint(j)?;
        let base = pid_error_of(pid_type);
        // 1.1, 1.2, ... as C++ (base + 1.0), 0 for unknown loop types
        Ok(if base == 0.0 {
            0.0
        } else {
            base + 1.0 + 10.0 * j as f64
        })
    }
    fn reset_pid(&mut self, _pid_type: Vocab32, j: usize) -> DevResult<()> {
        self.joint(j)?;
        Ok(())
    }
    fn set_pid_error_limit(&mut self, pid_type: Vocab32, j: usize, l: f64) -> DevResult<()> {
        self.joint(j)?;
        self.pid_error_limits.insert((pid_type.0, j), l);
        Ok(())
    }
    fn get_pid_error_limit(&mut self, pid_type: Vocab32, j: usize) -> DevResult<f64> {
        self.joint(j)?;
        Ok(self
            .pid_error_limits
            .get(&(pid_type.0, j))
            .copied()
            .unwrap_or(0.0))
    }
    fn set_pid_offset(&mut self, pid_type: Vocab32, j: usize, v: f64) -> DevResult<()> {
        self.joint(j)?;
        self.pids.entry((pid_type.0, j)).or_default().0.offset = v;
        Ok(())
    }
    fn set_pid_feedforward(&mut self, pid_type: Vocab32, j: usize, v: f64) -> DevResult<()> {
        self.joint(j)?;
        self.feedforwards.insert((pid_type.0, j), v);
        Ok(())
    }
    /// C++ 4.0's fake: three of each kind, for every joint.
    fn get_available_pids(&mut self, j: usize) -> DevResult<Vec<Vocab32>> {
        self.joint(j)?;
        Ok(["pos", "pod", "vel", "ved", "mix", "cur", "trq"]
            .iter()
            .flat_map(|k| {
                (1..=3).map(move |n| match (*k, n) {
                    // 3.12's names for the first of its four
                    ("pos" | "vel" | "cur" | "trq", 1) => Vocab32::new(k),
                    _ => Vocab32::new(&format!("{k}{n}")),
                })
            })
            .collect())
    }
    /// C++ 4.0's fake's words, the same for every joint (its units are left empty).
    fn get_pid_extra_info(&mut self, pid_type: Vocab32, j: usize) -> DevResult<PidExtraInfo> {
        self.joint(j)?;
        let name = pid_type.as_string();
        // 3.12's names are the first of their kind (`pos` is 4.0's `pos1`)
        let (kind, index) = match name.as_bytes() {
            [a, b, c] => ([*a, *b, *c], 0),
            [a, b, c, d @ b'1'..=b'3'] => ([*a, *b, *c], usize::from(d - b'1')),
            _ => return Err(self.no_such_pid(pid_type)),
        };
        let outputs = ["PWM", "Velocity", "Current"];
        let (what, input, output) = match &kind {
            b"pos" => ("Position", "Encoder Value", outputs[index]),
            b"pod" => ("Position Direct", "Encoder Value", outputs[index]),
            b"trq" => ("Torque", "Torque", outputs[index]),
            b"vel" => (
                "Velocity",
                "Velocity Value",
                ["PWM", "PWM", "Current"][index],
            ),
            b"ved" => (
                "Velocity Direct",
                "Velocity Value",
                ["PWM", "PWM", "Current"][index],
            ),
            b"cur" => ("Current", "Current Value", "PWM"),
            // C++ 4.0 calls the third mixed PID "Current PID 2"
            b"mix" if index == 2 => ("Current", "Encoder Value", "PWM"),
            b"mix" => ("Mixed", "Encoder Value", "PWM"),
            _ => return Err(self.no_such_pid(pid_type)),
        };
        Ok(PidExtraInfo {
            pid_description: format!("{what} PID {index}"),
            input_data_description: input.into(),
            output_data_description: output.into(),
            units: Default::default(),
        })
    }
    fn get_pid_feedforward(&mut self, pid_type: Vocab32, j: usize) -> DevResult<f64> {
        self.joint(j)?;
        Ok(self
            .feedforwards
            .get(&(pid_type.0, j))
            .copied()
            .unwrap_or(0.0))
    }
}

impl ICurrentControl for FakeMotionControl {
    fn get_ref_current(&mut self, j: usize) -> DevResult<f64> {
        Ok(self.joint(j)?.ref_current)
    }
    fn get_current_range(&mut self, j: usize) -> DevResult<(f64, f64)> {
        // "just for testing purposes" in C++ too
        let r = self.joint(j)?.ref_current;
        Ok((r / 100.0, r * 100.0))
    }
    fn set_ref_current(&mut self, j: usize, current: f64) -> DevResult<()> {
        let jt = self.joint(j)?;
        jt.ref_current = current;
        jt.current = current / 2.0;
        Ok(())
    }
}

impl IPwmControl for FakeMotionControl {
    fn get_ref_duty_cycle(&mut self, j: usize) -> DevResult<f64> {
        Ok(self.joint(j)?.ref_duty)
    }
    fn set_ref_duty_cycle(&mut self, j: usize, duty: f64) -> DevResult<()> {
        self.update();
        let jt = self.joint(j)?;
        jt.ref_duty = duty;
        jt.duty = duty;
        Ok(())
    }
    fn get_duty_cycle(&mut self, m: usize) -> DevResult<f64> {
        Ok(self.joint(m)?.duty)
    }
}

impl IPositionDirect for FakeMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        Ok(self.joints.len())
    }
    fn set_position(&mut self, j: usize, reference: f64) -> DevResult<()> {
        self.updated(j)?.pos_direct = reference;
        Ok(())
    }
    fn get_ref_position(&mut self, j: usize) -> DevResult<f64> {
        Ok(self.joint(j)?.pos_direct)
    }
}

impl IImpedanceControl for FakeMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        Ok(self.joints.len())
    }
    fn get_impedance(&mut self, j: usize) -> DevResult<(f64, f64)> {
        let jt = self.joint(j)?;
        Ok((jt.stiffness, jt.damping))
    }
    fn set_impedance(&mut self, j: usize, stiffness: f64, damping: f64) -> DevResult<()> {
        let jt = self.joint(j)?;
        jt.stiffness = stiffness;
        jt.damping = damping;
        Ok(())
    }
    fn get_impedance_offset(&mut self, j: usize) -> DevResult<f64> {
        Ok(self.joint(j)?.impedance_offset)
    }
    fn set_impedance_offset(&mut self, j: usize, offset: f64) -> DevResult<()> {
        self.joint(j)?.impedance_offset = offset;
        Ok(())
    }
    fn get_current_impedance_limit(&mut self, j: usize) -> DevResult<ImpedanceLimits> {
        self.joint(j)?;
        // the C++ fake's constants
        Ok(ImpedanceLimits {
            min_stiffness: 1.0,
            max_stiffness: 10.0,
            min_damping: 2.0,
            max_damping: 20.0,
        })
    }
}

impl IControlCalibration for FakeMotionControl {
    fn calibrate_axis_with_params(
        &mut self,
        j: usize,
        kind: u32,
        _p1: f64,
        _p2: f64,
        _p3: f64,
    ) -> DevResult<()> {
        self.joint(j)?;
        tracing::debug!("{NAME}: calibrate joint {j} (type {kind}): done at once");
        Ok(())
    }
    fn set_calibration_parameters(
        &mut self,
        j: usize,
        _params: &CalibrationParameters,
    ) -> DevResult<()> {
        self.joint(j)?;
        Ok(())
    }
    fn calibration_done(&mut self, j: usize) -> DevResult<bool> {
        self.joint(j)?;
        Ok(true)
    }
}
