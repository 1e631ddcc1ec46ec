//! An emulated motor-control board (MC4-style): two joints, each a second-order plant
//! under a position/velocity/torque controller, answering the polling protocol and
//! broadcasting encoders, status and PID values.
//!
//! Plant and controller (per joint, in encoder ticks): `q̈ = u − b·q̇` where, in the
//! position-like modes, `u = ωn²·(r − q) + 2ωn·(ṙ − q̇)` tracks a reference `r`
//! (critically damped, ωn = [`OMEGA_N`]); in torque mode `u = TORQUE_GAIN·τ`; in idle
//! `u = 0`. The PID gains the host sets are stored and reported back but, to stay stable
//! whatever the gains, do not change the emulated dynamics. Position moves slew the
//! reference toward the target at the commanded speed; velocity moves integrate the
//! commanded speed (ramped by the commanded acceleration) and expire after the velocity
//! timeout; direct position jumps the reference. References are clamped to the joint
//! limits once the host has set them.

use std::time::Duration;

use super::Board;
use crate::frame::CanFrame;
use crate::proto::mc::{per, FirmwareInfo};
use crate::proto::{
    BoardStatus, ControlMode, McCommand, McPeriodic, McReply, Message, Pid, PidKind, PidLimits,
};

/// Natural frequency of the emulated position loop, rad/s.
pub const OMEGA_N: f64 = 40.0;
/// Viscous damping of the plant, 1/s.
pub const DAMPING: f64 = 5.0;
/// Acceleration per unit of torque setpoint in torque mode, ticks/s².
pub const TORQUE_GAIN: f64 = 50.0;
/// Encoder distance under which a position move counts as done, ticks.
pub const DONE_TOLERANCE: f64 = 3.0;
/// Broadcasts enabled until the host sets a policy.
pub const DEFAULT_BCAST_POLICY: u32 = (1 << per::POSITION)
    | (1 << per::PID_VAL)
    | (1 << per::STATUS)
    | (1 << per::CURRENT)
    | (1 << per::VELOCITY)
    | (1 << per::ADDITIONAL_STATUS);

/// Emulated state of one joint.
#[derive(Debug, Clone)]
pub struct JointSim {
    /// Position, ticks.
    pub q: f64,
    /// Velocity, ticks/s.
    pub qd: f64,
    /// Acceleration of the last step, ticks/s².
    pub qdd: f64,
    pub mode: ControlMode,
    pub interaction: u8,
    reference: f64,
    reference_vel: f64,
    target: f64,
    /// Position-move speed, ticks/s.
    ref_speed: f64,
    vel_cmd: f64,
    vel_accel: f64,
    vel_remaining_ms: f64,
    vel_timeout_ms: f64,
    torque_ref: i16,
    limits: Option<(i32, i32)>,
    min_pos: i32,
    max_pos: i32,
    max_vel: i16,
    pwm_limit: i16,
    current_limit: i32,
    pids: [Pid; 4],
    pid_limits: [PidLimits; 4],
    vel_shift: u16,
    estim: [u8; 4],
    impedance: (i16, i16),
    output: f64,
}

impl JointSim {
    /// A joint at rest at `q` ticks, idle.
    pub fn new(q: f64) -> Self {
        Self {
            q,
            qd: 0.0,
            qdd: 0.0,
            mode: ControlMode::Idle,
            interaction: 0,
            reference: q,
            reference_vel: 0.0,
            target: q,
            ref_speed: 1000.0,
            vel_cmd: 0.0,
            vel_accel: 0.0,
            vel_remaining_ms: 0.0,
            vel_timeout_ms: 100.0,
            torque_ref: 0,
            limits: None,
            min_pos: i32::MIN,
            max_pos: i32::MAX,
            max_vel: 0,
            pwm_limit: 1333,
            current_limit: 0,
            pids: [Pid::default(); 4],
            pid_limits: [PidLimits {
                offset: 0,
                max_output: 1333,
                max_integral: 1333,
            }; 4],
            vel_shift: 0,
            estim: [0; 4],
            impedance: (0, 0),
            output: 0.0,
        }
    }

    fn clamp(&self, v: f64) -> f64 {
        match self.limits {
            Some((a, b)) => v.clamp(f64::from(a.min(b)), f64::from(a.max(b))),
            None => v,
        }
    }

    fn update_limits(&mut self) {
        if self.min_pos != i32::MIN && self.max_pos != i32::MAX {
            self.limits = Some((self.min_pos, self.max_pos));
        }
    }

    fn hold(&mut self) {
        self.reference = self.q;
        self.reference_vel = 0.0;
        self.target = self.q;
        self.vel_cmd = 0.0;
    }

    fn set_mode(&mut self, m: ControlMode) {
        let m = if m == ControlMode::ForceIdle {
            ControlMode::Idle
        } else {
            m
        };
        if m != self.mode {
            self.hold();
        }
        self.mode = m;
    }

    fn tracks_reference(&self) -> bool {
        matches!(
            self.mode,
            ControlMode::Position
                | ControlMode::Velocity
                | ControlMode::Direct
                | ControlMode::Mixed
                | ControlMode::ImpedancePos
                | ControlMode::ImpedanceVel
        )
    }

    /// Whether the last position move has finished: the reference reached the target
    /// and the joint settled there (at rest, so no overshoot follows).
    pub fn motion_done(&self) -> bool {
        (self.reference - self.target).abs() < 0.5
            && (self.q - self.target).abs() <= DONE_TOLERANCE
            && self.qd.abs() <= DONE_TOLERANCE * 10.0
    }

    /// Advances by `dt` seconds.
    pub fn step(&mut self, dt: f64) {
        match self.mode {
            ControlMode::Position | ControlMode::Mixed | ControlMode::ImpedancePos => {
                let err = self.target - self.reference;
                let stepmax = self.ref_speed.abs().max(1.0) * dt;
                if err.abs() <= stepmax {
                    self.reference = self.target;
                    self.reference_vel = 0.0;
                } else {
                    self.reference += stepmax * err.signum();
                    self.reference_vel = self.ref_speed.abs() * err.signum();
                }
            }
            ControlMode::Velocity | ControlMode::ImpedanceVel => {
                self.vel_remaining_ms -= dt * 1000.0;
                let goal = if self.vel_remaining_ms > 0.0 {
                    self.vel_cmd
                } else {
                    0.0
                };
                let dv = goal - self.reference_vel;
                let maxdv = if self.vel_accel > 0.0 {
                    self.vel_accel * dt
                } else {
                    f64::INFINITY
                };
                self.reference_vel += dv.clamp(-maxdv, maxdv);
                let next = self.clamp(self.reference + self.reference_vel * dt);
                if next == self.reference {
                    self.reference_vel = 0.0;
                }
                self.reference = next;
            }
            _ => {}
        }
        let u = if self.tracks_reference() {
            OMEGA_N * OMEGA_N * (self.reference - self.q)
                + 2.0 * OMEGA_N * (self.reference_vel - self.qd)
        } else if self.mode == ControlMode::Torque {
            TORQUE_GAIN * f64::from(self.torque_ref)
        } else {
            0.0
        };
        self.qdd = u - DAMPING * self.qd;
        self.qd += self.qdd * dt;
        self.q += self.qd * dt;
        // Report the controller effort scaled into PWM counts, saturated like the board.
        let max_out = f64::from(self.pid_limits[0].max_output.max(1));
        self.output = (u / (OMEGA_N * OMEGA_N)).clamp(-max_out, max_out);
    }

    fn apply(&mut self, cmd: &McCommand) -> Option<McReply> {
        use McCommand::*;
        let kind_index = |k: PidKind| {
            PidKind::ALL
                .iter()
                .position(|x| *x == k)
                .expect("all kinds listed")
        };
        match *cmd {
            ControllerRun | EnablePwm => {
                if self.mode == ControlMode::Idle {
                    self.set_mode(ControlMode::Position);
                }
            }
            ControllerIdle | DisablePwm => self.set_mode(ControlMode::Idle),
            CalibrateEncoder { .. } => {
                // The emulated encoders are absolute: calibration ends holding the current pose.
                self.set_mode(ControlMode::Position);
                self.hold();
            }
            GetControlMode => return Some(McReply::ControlMode(self.mode)),
            MotionDone => return Some(McReply::MotionDone(self.motion_done())),
            SetControlMode(m) => self.set_mode(m),
            SetSpeedEstimShift {
                jnt_vel,
                jnt_acc,
                mot_vel,
                mot_acc,
            } => self.estim = [jnt_vel, jnt_acc, mot_vel, mot_acc],
            GetEncoderPosition => return Some(McReply::EncoderPosition(self.q.round() as i32)),
            PositionMove { position, speed } => {
                if matches!(
                    self.mode,
                    ControlMode::Position | ControlMode::Mixed | ControlMode::ImpedancePos
                ) {
                    self.target = self.clamp(f64::from(position));
                    self.ref_speed = f64::from(speed).abs() * 10.0;
                }
            }
            VelocityMove { speed, accel } => {
                if matches!(
                    self.mode,
                    ControlMode::Velocity | ControlMode::Mixed | ControlMode::ImpedanceVel
                ) {
                    let scale = 1000.0 / f64::from(1u32 << self.vel_shift.min(15));
                    self.vel_cmd = f64::from(speed) * scale;
                    self.vel_accel = f64::from(accel).abs() * scale * 1000.0;
                    self.vel_remaining_ms = self.vel_timeout_ms;
                }
            }
            SetEncoderPosition(v) => {
                self.q = f64::from(v);
                self.hold();
            }
            SetDesiredTorque(t) => self.torque_ref = t,
            GetDesiredTorque => return Some(McReply::DesiredTorque(self.torque_ref)),
            StopTrajectory => {
                self.target = self.reference;
                self.vel_cmd = 0.0;
            }
            SetPwmLimit(v) => self.pwm_limit = v,
            GetPwmLimit => return Some(McReply::PwmLimit(self.pwm_limit)),
            SetCommandPosition(p) => {
                if matches!(
                    self.mode,
                    ControlMode::Direct | ControlMode::Position | ControlMode::Mixed
                ) {
                    let p = self.clamp(f64::from(p));
                    self.reference = p;
                    self.target = p;
                    self.reference_vel = 0.0;
                }
            }
            SetMinPosition(v) => {
                self.min_pos = v;
                self.update_limits();
            }
            GetMinPosition => return Some(McReply::MinPosition(self.min_pos)),
            SetMaxPosition(v) => {
                self.max_pos = v;
                self.update_limits();
            }
            GetMaxPosition => return Some(McReply::MaxPosition(self.max_pos)),
            SetMaxVelocity(v) => self.max_vel = v,
            GetMaxVelocity => return Some(McReply::MaxVelocity(self.max_vel)),
            SetCurrentLimit(v) => self.current_limit = v,
            SetBcastPolicy(_) => {}
            SetVelShift(v) => self.vel_shift = v,
            SetPid(k, p) => self.pids[kind_index(k)] = p,
            GetPid(k) => return Some(McReply::Pid(k, self.pids[kind_index(k)])),
            SetPidLimits(k, l) => self.pid_limits[kind_index(k)] = l,
            GetPidLimits(k) => return Some(McReply::PidLimits(k, self.pid_limits[kind_index(k)])),
            SetVelTimeout(ms) => self.vel_timeout_ms = f64::from(ms),
            SetImpedanceParams { stiffness, damping } => self.impedance = (stiffness, damping),
            GetImpedanceParams => {
                return Some(McReply::ImpedanceParams {
                    stiffness: self.impedance.0,
                    damping: self.impedance.1,
                })
            }
            GetFirmwareVersion {
                proto_major,
                proto_minor,
            } => {
                return Some(McReply::FirmwareVersion(FirmwareInfo {
                    board_type: 3,
                    version: 1,
                    release: 0,
                    build: 0,
                    proto_major: 1,
                    proto_minor: 6,
                    compatible: proto_major == 1 && proto_minor <= 6,
                }))
            }
            SetInteractionMode(m) => self.interaction = m,
            GetInteractionMode => return Some(McReply::InteractionMode(self.interaction)),
        }
        None
    }
}

/// Configuration of an emulated motor board.
#[derive(Debug, Clone)]
pub struct McBoardConfig {
    pub address: u8,
    /// Initial encoder value of each joint, ticks.
    pub initial: [f64; 2],
    /// Period of the encoder/velocity/PID broadcasts.
    pub broadcast_period: Duration,
    /// Period of the status broadcasts.
    pub status_period: Duration,
}

impl McBoardConfig {
    pub fn new(address: u8) -> Self {
        Self {
            address,
            initial: [0.0; 2],
            broadcast_period: Duration::from_millis(10),
            status_period: Duration::from_millis(100),
        }
    }
}

/// An emulated two-joint motor board.
pub struct McBoard {
    cfg: McBoardConfig,
    pub joints: [JointSim; 2],
    policy: u32,
    since_bcast: Duration,
    since_status: Duration,
}

impl McBoard {
    pub fn new(cfg: McBoardConfig) -> Self {
        let joints = [JointSim::new(cfg.initial[0]), JointSim::new(cfg.initial[1])];
        Self {
            cfg,
            joints,
            policy: DEFAULT_BCAST_POLICY,
            since_bcast: Duration::ZERO,
            since_status: Duration::ZERO,
        }
    }

    fn bcast(&self, msg: McPeriodic, out: &mut Vec<CanFrame>) {
        out.push(
            Message::McPeriodic {
                board: self.cfg.address,
                msg,
            }
            .encode(),
        );
    }

    fn enabled(&self, kind: u8) -> bool {
        self.policy & (1 << kind) != 0
    }
}

impl Board for McBoard {
    fn address(&self) -> u8 {
        self.cfg.address
    }

    fn kind(&self) -> &'static str {
        "mc"
    }

    fn on_message(&mut self, msg: &Message, out: &mut Vec<CanFrame>) {
        let Message::McRequest {
            src,
            dst,
            axis,
            cmd,
        } = msg
        else {
            return;
        };
        if *dst != self.cfg.address && *dst != 0xF {
            return;
        }
        if let McCommand::SetBcastPolicy(mask) = cmd {
            self.policy = *mask;
        }
        let j = usize::from(*axis & 1);
        if let Some(reply) = self.joints[j].apply(cmd) {
            out.push(
                Message::McReply {
                    src: self.cfg.address,
                    dst: *src,
                    axis: *axis,
                    reply,
                }
                .encode(),
            );
        }
    }

    fn tick(&mut self, dt: Duration, out: &mut Vec<CanFrame>) {
        let secs = dt.as_secs_f64();
        for j in &mut self.joints {
            j.step(secs);
        }
        self.since_bcast += dt;
        self.since_status += dt;
        if self.since_bcast >= self.cfg.broadcast_period {
            self.since_bcast = Duration::ZERO;
            let [a, b] = &self.joints;
            if self.enabled(per::POSITION) {
                self.bcast(
                    McPeriodic::Position([a.q.round() as i32, b.q.round() as i32]),
                    out,
                );
            }
            if self.enabled(per::VELOCITY) {
                let vel = |j: &JointSim| {
                    (j.qd / 1000.0 * f64::from(1u32 << j.estim[0].min(15)))
                        .round()
                        .clamp(-32768.0, 32767.0) as i16
                };
                let acc = |j: &JointSim| {
                    (j.qdd / 1e6 * f64::from(1u32 << j.estim[1].min(15)))
                        .round()
                        .clamp(-32768.0, 32767.0) as i16
                };
                self.bcast(
                    McPeriodic::Velocity {
                        speed: [vel(a), vel(b)],
                        accel: [acc(a), acc(b)],
                    },
                    out,
                );
            }
            if self.enabled(per::PID_VAL) {
                self.bcast(
                    McPeriodic::PidValue([a.output.round() as i16, b.output.round() as i16]),
                    out,
                );
            }
            if self.enabled(per::MOTOR_POSITION) {
                // A direct-drive rotor: motor ticks follow the joint ticks.
                self.bcast(
                    McPeriodic::MotorPosition([a.q.round() as i32, b.q.round() as i32]),
                    out,
                );
            }
            if self.enabled(per::CURRENT) {
                // Current proportional to effort: a plausible signal for the amplifier interface.
                self.bcast(
                    McPeriodic::Current([(a.output * 2.0) as i16, (b.output * 2.0) as i16]),
                    out,
                );
            }
        }
        if self.since_status >= self.cfg.status_period {
            self.since_status = Duration::ZERO;
            let [a, b] = &self.joints;
            if self.enabled(per::STATUS) {
                let status = BoardStatus {
                    axis_faults: [0, 0],
                    control_mode: [a.mode, b.mode],
                    can_status: 0,
                    board_status: 0,
                    can_tx_errors: 0,
                    can_rx_errors: 0,
                };
                self.bcast(McPeriodic::Status(status), out);
            }
            if self.enabled(per::ADDITIONAL_STATUS) {
                self.bcast(
                    McPeriodic::AdditionalStatus {
                        interaction: [a.interaction, b.interaction],
                    },
                    out,
                );
            }
        }
    }
}
