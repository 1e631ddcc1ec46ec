//! The joint model a [`BoardEngine`](crate::board::BoardEngine) drives: the board engine
//! turns the host's joint commands into calls on a [`JointModel`] and publishes what the
//! model reports in the joint and motor status. Any plant can be plugged in (e.g. the CAN
//! emulator's PID-and-motor plant, once shared); [`SimpleJoint`] is the built-in one.
//!
//! Units are the wire's for positions (the joint's raw units, `eOmeas_position_t`),
//! velocities (raw units/s), currents (mA) and PWM (duty counts); torques are in N·m and
//! motor temperatures in °C: the board engine converts them at its boundary (the wire's
//! torques are µN·m, [`TORQUE_TO_WIRE`]; its motor temperatures the raw reading of the
//! motor's PT100 sensor, [`pt100_raw`]).

use crate::entities::mc::{control_mode, Calibrator, JointConfig, Setpoint};

/// What a joint reports each control period.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JointFeedback {
    pub position: f64,
    pub velocity: f64,
    pub acceleration: f64,
    /// N·m.
    pub torque: f64,
    /// The torque reference the controller tracks (torque control), N·m.
    pub torque_reference: f64,
    /// The control mode status (`eOmc_controlmode_t`, see [`control_mode`]).
    pub control_mode: u8,
    pub interaction_mode: u8,
    pub motion_done: bool,
    /// The reference the controller tracks (position modes).
    pub reference: f64,
    pub target_position: f64,
    pub target_velocity: f64,
    pub pwm: i16,
    pub current: i16,
    /// Motor temperature, °C.
    pub temperature: f64,
}

/// µN·m per N·m: the wire's torques (`eOmeas_torque_t`, torque set points, joint inputs,
/// status) are in µN·m.
pub const TORQUE_TO_WIRE: f64 = 1_000_000.0;

/// The motor temperature [`SimpleJoint`] reports, °C.
pub const MOTOR_TEMPERATURE: f64 = 35.0;

/// The raw reading a board reports for a PT100 motor sensor at `celsius`: the sensor in
/// its voltage divider bridge (4.7 kΩ, 4.7 kΩ, 100 Ω; PT100: 100 Ω + 0.3851 Ω/°C, 5 V)
/// through the temperature detection board (PGA gain 2, 2.048 V full scale, 15 bits), as
/// icub-main's `TemperatureSensorPT100` models it; rounded.
pub fn pt100_raw(celsius: f64) -> i16 {
    let r = 100.0 + 0.3851 * celsius;
    let v = (r / (4700.0 + r) - 100.0 / 4800.0) * 5.0;
    (32768.0 * (2.0 * v / 2.048)).round() as i16
}

/// A joint plant with its controller, as the board's motion-control service sees it.
pub trait JointModel: Send {
    /// `set<joint config>`: gains, limits, timeouts.
    fn configure(&mut self, config: &JointConfig);
    /// `set<joint cmmnds controlmode>` (an `eOmc_controlmode_command_t`).
    fn set_control_mode(&mut self, mode: u8);
    /// `set<joint cmmnds interactionmode>`.
    fn set_interaction_mode(&mut self, mode: u8);
    /// `set<joint cmmnds setpoint>`.
    fn setpoint(&mut self, setpoint: &Setpoint);
    /// `set<joint cmmnds stoptrajectory>`.
    fn stop_trajectory(&mut self);
    /// `set<joint cmmnds calibration>`.
    fn calibrate(&mut self, calibrator: &Calibrator);
    /// `set<joint inputs externallymeasuredtorque>`: the joint torque the host measured or
    /// estimated, N·m (the board reports it as its torque measure).
    fn set_external_torque(&mut self, _torque: f64) {}
    /// Advances the joint by `dt` seconds.
    fn step(&mut self, dt: f64);
    fn feedback(&self) -> JointFeedback;
}

/// How long [`SimpleJoint`] stays in the calibration mode, s.
pub const CALIBRATION_TIME: f64 = 0.1;
/// Time constant with which [`SimpleJoint`] follows its reference, s.
pub const TRACKING_TIME_CONSTANT: f64 = 0.02;
/// Distance (raw units) under which a position move counts as done.
pub const MOTION_DONE_TOLERANCE: f64 = 100.0;
/// Trajectory speed when the set point gives none, raw units/s (10°/s in iCub degrees).
pub const DEFAULT_TRAJECTORY_SPEED: f64 = 10.0 * 65536.0 / 360.0;

/// A minimal joint: a trajectory generator (position, velocity, direct) and a first-order
/// lag from reference to position; open-loop PWM and current move the joint at a speed
/// proportional to the command. In torque control the joint holds its position and its
/// torque follows the reference with the same lag; otherwise the torque it reports is the
/// host's external measure (0 until one comes). The motor is at [`MOTOR_TEMPERATURE`]. It starts `notConfigured` and goes idle when configured,
/// as the boards do; calibration lasts [`CALIBRATION_TIME`] and ends in position control
/// holding the pose.
///
/// A joint physically sits inside its mechanical range: while it has not moved, a joint
/// configuration clamps its position into the hardware limits it carries (a joint made at
/// raw 0 whose range excludes 0 starts at the nearest end of its range).
#[derive(Debug, Clone)]
pub struct SimpleJoint {
    q: f64,
    qd: f64,
    qdd: f64,
    mode: u8,
    interaction: u8,
    reference: f64,
    target: f64,
    speed: f64,
    velocity_cmd: f64,
    open_loop: f64,
    limits: Option<(f64, f64)>,
    calibrating: f64,
    current: i16,
    pwm: i16,
    torque: f64,
    torque_reference: f64,
    external_torque: f64,
    /// Whether the joint has moved since it was made (then a configuration no longer
    /// places it inside its hardware limits).
    moved: bool,
}

impl SimpleJoint {
    pub fn new(position: f64) -> Self {
        Self {
            q: position,
            qd: 0.0,
            qdd: 0.0,
            mode: control_mode::NOT_CONFIGURED,
            interaction: 0,
            reference: position,
            target: position,
            speed: DEFAULT_TRAJECTORY_SPEED,
            velocity_cmd: 0.0,
            open_loop: 0.0,
            limits: None,
            calibrating: 0.0,
            current: 0,
            pwm: 0,
            torque: 0.0,
            torque_reference: 0.0,
            external_torque: 0.0,
            moved: false,
        }
    }

    fn clamp(&self, v: f64) -> f64 {
        match self.limits {
            Some((a, b)) => v.clamp(a, b),
            None => v,
        }
    }

    fn hold(&mut self) {
        self.reference = self.q;
        self.target = self.q;
        self.velocity_cmd = 0.0;
        self.open_loop = 0.0;
        self.torque_reference = self.torque;
    }
}

impl JointModel for SimpleJoint {
    fn configure(&mut self, config: &JointConfig) {
        let (a, b) = (config.user_limits.min, config.user_limits.max);
        self.limits = (a < b).then_some((f64::from(a), f64::from(b)));
        // the hardware limits in raw units, whichever way the encoder counts (a negative
        // encoder factor gives min > max); none when both are 0
        let (h0, h1) = (
            f64::from(config.hardware_limits.min),
            f64::from(config.hardware_limits.max),
        );
        if !self.moved && (h0 != 0.0 || h1 != 0.0) {
            let q = self.q.clamp(h0.min(h1), h0.max(h1));
            if q != self.q {
                self.q = q;
                self.reference = q;
                self.target = q;
            }
        }
        if self.mode == control_mode::NOT_CONFIGURED {
            self.mode = control_mode::IDLE;
        }
    }

    fn set_control_mode(&mut self, mode: u8) {
        if matches!(
            self.mode,
            control_mode::NOT_CONFIGURED | control_mode::HW_FAULT
        ) {
            return;
        }
        let mode = match mode {
            control_mode::FORCE_IDLE | control_mode::EVERYTHING_OFF => control_mode::IDLE,
            m => m,
        };
        if mode != self.mode {
            self.hold();
        }
        self.mode = mode;
    }

    fn set_interaction_mode(&mut self, mode: u8) {
        self.interaction = mode;
    }

    fn setpoint(&mut self, setpoint: &Setpoint) {
        match (*setpoint, self.mode) {
            (
                Setpoint::Position { value, velocity },
                control_mode::POSITION | control_mode::MIXED,
            ) => {
                self.target = self.clamp(f64::from(value));
                self.speed = if velocity != 0 {
                    f64::from(velocity).abs()
                } else {
                    DEFAULT_TRAJECTORY_SPEED
                };
            }
            (Setpoint::PositionRaw { value }, control_mode::DIRECT | control_mode::POSITION) => {
                let v = self.clamp(f64::from(value));
                self.reference = v;
                self.target = v;
            }
            (
                Setpoint::Velocity { value, .. },
                control_mode::VELOCITY | control_mode::MIXED | control_mode::VEL_DIRECT,
            ) => {
                self.velocity_cmd = f64::from(value);
            }
            (Setpoint::OpenLoop { value }, control_mode::OPENLOOP) => {
                self.open_loop = f64::from(value);
                self.pwm = value;
            }
            (Setpoint::Current { value }, control_mode::CURRENT) => {
                self.open_loop = f64::from(value);
                self.current = value;
            }
            (Setpoint::Torque { value }, control_mode::TORQUE) => {
                self.torque_reference = f64::from(value);
            }
            _ => {}
        }
    }

    fn stop_trajectory(&mut self) {
        self.target = self.reference;
        self.velocity_cmd = 0.0;
    }

    fn calibrate(&mut self, _calibrator: &Calibrator) {
        if self.mode == control_mode::NOT_CONFIGURED {
            return;
        }
        self.mode = control_mode::CALIB;
        self.calibrating = CALIBRATION_TIME;
        self.hold();
    }

    fn set_external_torque(&mut self, torque: f64) {
        self.external_torque = torque;
    }

    fn step(&mut self, dt: f64) {
        if dt <= 0.0 {
            return;
        }
        let k = dt / (TRACKING_TIME_CONSTANT + dt);
        self.torque = if self.mode == control_mode::TORQUE {
            self.torque + (self.torque_reference - self.torque) * k
        } else {
            self.external_torque
        };
        let q0 = self.q;
        let qd0 = self.qd;
        match self.mode {
            control_mode::CALIB => {
                self.calibrating -= dt;
                if self.calibrating <= 0.0 {
                    self.mode = control_mode::POSITION;
                    self.hold();
                }
            }
            control_mode::POSITION | control_mode::MIXED | control_mode::DIRECT => {
                let err = self.target - self.reference;
                let step = self.speed * dt;
                self.reference = if err.abs() <= step {
                    self.target
                } else {
                    self.reference + step * err.signum()
                };
                if self.mode == control_mode::MIXED {
                    self.reference = self.clamp(self.reference + self.velocity_cmd * dt);
                }
            }
            control_mode::VELOCITY | control_mode::VEL_DIRECT => {
                self.reference = self.clamp(self.reference + self.velocity_cmd * dt);
                self.target = self.reference;
            }
            control_mode::OPENLOOP | control_mode::CURRENT => {
                self.reference = self.clamp(self.q + self.open_loop * 10.0 * dt);
                self.target = self.reference;
            }
            _ => {}
        }
        let tracking = !matches!(
            self.mode,
            control_mode::IDLE | control_mode::NOT_CONFIGURED | control_mode::HW_FAULT
        );
        if tracking {
            self.q = self.clamp(self.q + (self.reference - self.q) * k);
        }
        self.moved |= self.q != q0;
        self.qd = (self.q - q0) / dt;
        self.qdd = (self.qd - qd0) / dt;
    }

    fn feedback(&self) -> JointFeedback {
        JointFeedback {
            position: self.q,
            velocity: self.qd,
            acceleration: self.qdd,
            torque: self.torque,
            torque_reference: self.torque_reference,
            control_mode: self.mode,
            interaction_mode: self.interaction,
            motion_done: (self.reference - self.target).abs() < 0.5
                && (self.q - self.target).abs() <= MOTION_DONE_TOLERANCE,
            reference: self.reference,
            target_position: self.target,
            target_velocity: self.velocity_cmd,
            pwm: self.pwm,
            current: self.current,
            temperature: MOTOR_TEMPERATURE,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::entities::mc::PositionLimits;

    fn config(hw: (i32, i32), user: (i32, i32)) -> JointConfig {
        JointConfig {
            hardware_limits: PositionLimits {
                min: hw.0,
                max: hw.1,
            },
            user_limits: PositionLimits {
                min: user.0,
                max: user.1,
            },
            ..Default::default()
        }
    }

    #[test]
    fn a_joint_starts_inside_its_hardware_limits() {
        // a range that excludes 0: the nearest end
        let mut j = SimpleJoint::new(0.0);
        j.configure(&config((1000, 5000), (2000, 4000)));
        assert_eq!(j.feedback().position, 1000.0);
        assert_eq!(j.feedback().reference, 1000.0);
        // a negative encoder factor gives min > max: the same range
        let mut j = SimpleJoint::new(0.0);
        j.configure(&config((-1000, -5000), (-2000, -4000)));
        assert_eq!(j.feedback().position, -1000.0);
        // a range with 0 inside, or no hardware limits: it stays
        let mut j = SimpleJoint::new(0.0);
        j.configure(&config((-1000, 5000), (0, 0)));
        assert_eq!(j.feedback().position, 0.0);
        j.configure(&config((0, 0), (0, 0)));
        assert_eq!(j.feedback().position, 0.0);
    }

    #[test]
    fn a_moved_joint_is_not_placed_again() {
        let mut j = SimpleJoint::new(0.0);
        j.configure(&config((-10_000, 10_000), (-10_000, 10_000)));
        j.set_control_mode(control_mode::POSITION);
        j.setpoint(&Setpoint::PositionRaw { value: 5000 });
        for _ in 0..100 {
            j.step(0.01);
        }
        let at = j.feedback().position;
        assert!(at > 4000.0, "{at}");
        // new limits that exclude where it is: a configuration does not teleport it
        j.configure(&config((6000, 9000), (-10_000, 10_000)));
        assert_eq!(j.feedback().position, at);
    }
}
