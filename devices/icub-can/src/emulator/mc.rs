//! An emulated motor-control board (MC4-style): two joints, each a motor-driven plant
//! under the board's position or torque PID, answering the polling protocol and
//! broadcasting encoders, status, PID outputs and (through a [`TorqueHub`]) the joint
//! torques a virtual joint-torque sensor would measure.
//!
//! # Controller (as the MC4 firmware, `pid.c` of icub-firmware `motorControllerDsp56f807`)
//!
//! Every [`CONTROL_PERIOD`] (1 ms, the firmware's `CONTROLLER_PERIOD`), per joint:
//!
//! - stiff position, velocity, position-direct and mixed modes run `compute_pid2` on
//!   the encoder error `e = reference − encoder` (ticks): `P = e·kp >> shift`,
//!   `D = (e − e_old)·kd >> shift` averaged over the last 10 periods (the firmware's
//!   `DerPort` filter), `I = Σ e·ki >> shift` clamped to ±`maxInt` (the accumulator is
//!   held at the clamp: anti-windup), `PWM = P + D + I + ko`. Velocity moves integrate
//!   the commanded speed into the reference (`step_velocity`), position moves slew it
//!   at the commanded speed, position-direct jumps it.
//! - torque mode runs `compute_pid_torque` on `e = τ_ref − τ_measured` in torque-sensor
//!   units (`0x8000` = `TorqueMax` N·m, as the host sends `SET_DESIRED_TORQUE`), same
//!   P/D/I structure with the torque gains, `PWM = P + D + I + ko_torque`. The MC4 has no
//!   torque feed-forward (`kff` exists only on the Ethernet boards), so none here.
//! - compliant joints (interaction mode `COMPLIANT` in position, velocity,
//!   position-direct or mixed mode, or the MC4's impedance modes) run the MC4 impedance
//!   control: the reference trajectory above and the joint speed make a torque
//!   reference `τref = k·(q_ref − q) − d·q̇ + offset` in sensor units (`k` sensor units
//!   per tick, `d` per tick/s, as `SET_IMPEDANCE_PARAMS` carries them with `d` ×1000;
//!   `offset` from `SET_IMPEDANCE_OFFSET`), which the torque PID tracks on the measured
//!   joint torque as in torque mode. With `k` 0 nothing pulls the joint to its
//!   reference; stiff joints use the position PID.
//! - open loop outputs the position `ko`; idle, hardware fault and the other modes
//!   output 0 and reset the PID state.
//!
//! The output saturates at ±`maxOutput` of the active PID (and at the `SET_PWM_LIMIT`
//! value): 0 gains or a 0 `maxOutput` give no output, so a board the host never
//! configured with gains does not move (boards start with [`McBoardConfig`]'s default
//! gains, see [`DEFAULT_POSITION_PID`]). The output is what the PID-value broadcast
//! reports. Differences from the firmware: arithmetic is floating point (no truncation
//! of the shifted terms), the integral clamp keeps the accumulator at the limit (the
//! firmware resets it to the unshifted limit), the torque D term differentiates the
//! torque error (the firmware, by a slip, uses the position error).
//!
//! # Plant
//!
//! The PWM drives a motor whose torque at the joint is `τm = s·Kτ·PWM/`[`PWM_FULL_SCALE`]
//! (`Kτ` = [`JointPlant::drive_torque`], `s` = ±1, the motor's direction against the
//! encoder); the joint (in encoder ticks) obeys `J·q̈ = τm − b·q̇ − c·sgn(q̇)` with
//! stiction (at rest it stays at rest while `|τm| ≤ c`), and hard stops at the joint
//! limits once the host has set them. `J = Kτ / (PWM_FULL_SCALE·`[`ACCEL_PER_PWM`]`)`,
//! `b = `[`VISCOUS`]`·J`, `c = `[`COULOMB`]`·Kτ`: expressed per tick, the motion does not
//! depend on `Kτ` nor on the encoder resolution, which is how the firmware gains are
//! tuned (iCubGenova01's position gains are 1.2…50 PWM counts per tick whatever the
//! joint). With `kp/2^shift = 3.9` (most iCubGenova01 joints) the proportional loop has
//! ωn ≈ 62 rad/s and damping ratio ≈ 0.9; with iCubGenova01's integral (ki 60 >> 13) a
//! 10° move of the left shoulder at 100°/s overshoots 3.5 % and is within 3 ticks after
//! 0.46 s, a 10° step of the reference overshoots 5 % and settles in 0.55 s (the tail is
//! the integral's). The stiffest gains (head neck yaw, 50 per tick) give ωn ≈ 220 rad/s,
//! ζ ≈ 0.35; at `maxOutput` 800 a joint tops at 7300 ticks/s (640°/s on an 11.375
//! ticks/° joint; 17°/s at `maxOutput` 1333 on the 706 ticks/° wrist pronosupination).
//! For an iCubGenova01 arm joint (`Kτ` 24 N·m, 11.375 ticks/°) that is J ≈ 0.012 kg·m²
//! and b ≈ 1.3 N·m·s/rad seen at the joint, c ≈ 0.05 N·m.
//! The plant is integrated in [`PLANT_STEPS`] sub-steps per control period
//! (semi-implicit Euler, viscous term implicit), so any emulator tick is stable.
//!
//! The joint torque is what passes from the drive to the link, `τj = τm − b·q̇ −
//! friction` (= `J·q̈` in free motion, the stop's reaction against a hard stop),
//! measured through a first-order sensor filter ([`TORQUE_SENSOR_FILTER`]) and
//! expressed in sensor units `σ·τj·0x8000/TorqueMax`. The sign `σ` relates the sensor to
//! the encoder: [`super::network::mc_boards`] uses the sign of the joint's `Encoder` (so
//! positive torques turn the joint in its positive YARP direction); otherwise it is the
//! one the host's torque gains assume. `s` follows the sign of the position `kp` the host
//! sets (a tuned robot's gains match its wiring: iCubGenova01 uses negative `kp` for
//! motors that turn against their encoder).
//!
//! Torque measurements from the host (a `canBusVirtualAnalogSensor` sending analog
//! broadcasts on a joint's sensor address) replace the board's own for
//! [`HOST_TORQUE_TIMEOUT`] after each message (the MC4's strain watchdog, `STRAIN_SAFE`).

use parking_lot::Mutex;
use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;

use super::Board;
use crate::frame::CanFrame;
use crate::proto::mc::{per, FirmwareInfo};
use crate::proto::{
    AsPeriodic, BoardStatus, ControlMode, McCommand, McPeriodic, McReply, Message, Pid, PidKind,
    PidLimits, VectorKind,
};

/// The firmware's control period (MC4 `CONTROLLER_PERIOD`, 1 ms), seconds.
pub const CONTROL_PERIOD: f64 = 0.001;
/// Plant integration sub-steps per control period.
pub const PLANT_STEPS: usize = 4;
/// PWM counts at 100 % duty (the MC4's PWM period, iCubGenova01's `fullscalePWM` 1333).
pub const PWM_FULL_SCALE: f64 = 1333.0;
/// Acceleration of a free joint per PWM count, ticks/s²: `Kτ / (PWM_FULL_SCALE·J)`.
/// Chosen with [`VISCOUS`] so that the common iCubGenova01 gain (kp 32000 >> 13 = 3.9
/// PWM/tick) gives ωn = √(1000·3.9) ≈ 62 rad/s at a damping ratio 110/(2·62) ≈ 0.9, fast
/// enough that the integral gains (ki 60 >> 13) wind up little during a move.
pub const ACCEL_PER_PWM: f64 = 1000.0;
/// Viscous friction over inertia `b/J` (the motor's back-EMF damping), 1/s.
pub const VISCOUS: f64 = 110.0;
/// Coulomb friction as a fraction of the drive's full torque (≈ 2.7 PWM counts: below one
/// tick of error at kp 3.9, so the joints settle within the `MotionDone` tolerance).
pub const COULOMB: f64 = 0.002;
/// Time constant of the joint-torque measurement, s (a virtual sensor computed at 100 Hz).
pub const TORQUE_SENSOR_FILTER: f64 = 0.01;
/// How long a torque measurement sent by the host replaces the board's own
/// (MC4 `strain_board.h`: `STRAIN_SAFE` 200 ms).
pub const HOST_TORQUE_TIMEOUT: Duration = Duration::from_millis(200);
/// Drive torque at 100 % PWM per N·m of torque-sensor full scale (`TorqueMax`): the
/// iCubGenova01 arm (`TorqueMax` 8) gets a 24 N·m drive, of which its `maxOutput` 800
/// lets out 14 N·m.
pub const DRIVE_PER_TORQUE_MAX: f64 = 3.0;
/// `TorqueMax` (N·m at sensor full scale) of joints with no configured sensor: the
/// iCubGenova01 shoulder's.
pub const DEFAULT_TORQUE_MAX: f64 = 8.0;
/// Number of periods the firmware averages the derivative term over (`DerPort`).
const DERIVATIVE_TAPS: usize = 10;
/// Broadcasts enabled until the host sets a policy.
pub const DEFAULT_BCAST_POLICY: u32 = (1 << per::POSITION)
    | (1 << per::PID_VAL)
    | (1 << per::STATUS)
    | (1 << per::CURRENT)
    | (1 << per::VELOCITY)
    | (1 << per::ADDITIONAL_STATUS);

/// Position gains a board starts with: iCubGenova01 `icub_right_arm.xml` POS_PIDS of the
/// shoulder pitch (kp 32000, kd 50, ki 60, shift 13, maxOutput 1333, maxInt 1333, ko 0).
pub const DEFAULT_POSITION_PID: (Pid, PidLimits) = (
    Pid {
        kp: 32000,
        ki: 60,
        kd: 50,
        shift: 13,
    },
    PidLimits {
        offset: 0,
        max_output: 1333,
        max_integral: 1333,
    },
);

/// Torque gains a board starts with: the MC4 firmware defaults (`_kp_torque` 32,
/// `_kr_torque` 10, no kd/ki), saturated at the full PWM.
pub const DEFAULT_TORQUE_PID: (Pid, PidLimits) = (
    Pid {
        kp: 32,
        ki: 0,
        kd: 0,
        shift: 10,
    },
    PidLimits {
        offset: 0,
        max_output: 1333,
        max_integral: 1333,
    },
);

/// Where a joint's measured torque is broadcast: an analog-sensor address and channel
/// (icub-main `GENERAL::TorqueId` / `TorqueChan`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TorqueLink {
    /// Source address of the analog broadcasts (`TorqueId`, e.g. 0x0C).
    pub address: u8,
    /// Channel 0..=5: 0..2 ride on message type 0xA, 3..5 on type 0xB.
    pub channel: u8,
}

/// Physical parameters of one emulated joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointPlant {
    /// Torque at the joint at 100 % PWM, N·m (`Kτ`).
    pub drive_torque: f64,
    /// N·m at the torque sensor's full scale (icub-main `TorqueMax`): sensor units are
    /// `τ·0x8000/TorqueMax`.
    pub torque_max: f64,
    /// Sign between the torque sensor and the encoder ticks; `None`: the one the host's
    /// torque gains assume.
    pub sensor_sign: Option<f64>,
    /// Where the measured torque is broadcast, if anywhere.
    pub sensor: Option<TorqueLink>,
}

impl Default for JointPlant {
    fn default() -> Self {
        Self::with_torque_max(DEFAULT_TORQUE_MAX)
    }
}

impl JointPlant {
    /// A joint whose torque sensor reads `torque_max` N·m at full scale, with a drive of
    /// [`DRIVE_PER_TORQUE_MAX`] times that.
    pub fn with_torque_max(torque_max: f64) -> Self {
        let torque_max = if torque_max > 0.0 {
            torque_max
        } else {
            DEFAULT_TORQUE_MAX
        };
        Self {
            drive_torque: DRIVE_PER_TORQUE_MAX * torque_max,
            torque_max,
            sensor_sign: None,
            sensor: None,
        }
    }
}

/// The joint torques that the motor boards of one bus publish for the virtual
/// joint-torque sensors ([`JointTorqueSensor`]) on that bus: sensor address → six
/// channels in sensor units.
#[derive(Debug, Clone, Default)]
pub struct TorqueHub(Arc<Mutex<HashMap<u8, [Option<i16>; 6]>>>);

impl TorqueHub {
    pub fn new() -> Self {
        Self::default()
    }

    fn publish(&self, link: TorqueLink, value: i16) {
        let mut m = self.0.lock();
        if let Some(slot) = m
            .entry(link.address)
            .or_default()
            .get_mut(usize::from(link.channel))
        {
            *slot = Some(value);
        }
    }

    /// The latest values of a sensor's channels.
    pub fn channels(&self, address: u8) -> [Option<i16>; 6] {
        let m = self.0.lock();
        m.get(&address).copied().unwrap_or_default()
    }
}

/// Running state of one firmware PID.
#[derive(Debug, Clone, Copy, Default)]
struct PidState {
    /// Shifted integral term, PWM counts.
    integral: f64,
    err_old: Option<f64>,
    der: [f64; DERIVATIVE_TAPS],
    der_at: usize,
}

impl PidState {
    /// One control period: the PID output before saturation (`PWM = P + D + I + ko`).
    fn run(&mut self, (pid, lim): (Pid, PidLimits), err: f64) -> f64 {
        let scale = f64::from(1u32 << pid.shift.min(31)).recip();
        let p = err * f64::from(pid.kp) * scale;
        let d_now = (err - self.err_old.unwrap_or(err)) * f64::from(pid.kd) * scale;
        self.err_old = Some(err);
        self.der[self.der_at] = d_now;
        self.der_at = (self.der_at + 1) % DERIVATIVE_TAPS;
        let d = self.der.iter().sum::<f64>() / DERIVATIVE_TAPS as f64;
        let max_int = f64::from(lim.max_integral).abs();
        self.integral = (self.integral + err * f64::from(pid.ki) * scale).clamp(-max_int, max_int);
        p + d + self.integral + f64::from(lim.offset)
    }
}

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
    /// Impedance stiffness (sensor units per tick) and damping (sensor units per tick/s,
    /// ×1000), as `SET_IMPEDANCE_PARAMS` carries them.
    impedance: (i16, i16),
    /// Impedance torque offset, sensor units (`SET_IMPEDANCE_OFFSET`).
    impedance_offset: i16,
    /// Torque reference of the impedance law in the last control period, sensor units.
    impedance_torque: f64,
    /// PWM output of the last control period (what the PID-value broadcast reports).
    output: f64,
    plant: JointPlant,
    /// Direction of the motor against the encoder (+1: positive PWM, increasing ticks).
    motor_sign: f64,
    pos_pid: PidState,
    trq_pid: PidState,
    /// Torque passed from the drive to the link in the last sub-step, N·m (ticks sense).
    tau_joint: f64,
    /// The filtered measurement of `tau_joint`, N·m.
    tau_measured: f64,
    /// A torque measurement from the host (sensor units) and how long it stays valid, s.
    host_torque: Option<(i16, f64)>,
}

fn kind_index(k: PidKind) -> usize {
    PidKind::ALL
        .iter()
        .position(|x| *x == k)
        .expect("all kinds listed")
}

impl JointSim {
    /// A joint at rest at `q` ticks, idle, with the default gains and plant.
    pub fn new(q: f64) -> Self {
        let mut pids = [Pid::default(); 4];
        let mut pid_limits = [PidLimits {
            offset: 0,
            max_output: 1333,
            max_integral: 1333,
        }; 4];
        for (k, (p, l)) in [
            (PidKind::Position, DEFAULT_POSITION_PID),
            (PidKind::Torque, DEFAULT_TORQUE_PID),
        ] {
            pids[kind_index(k)] = p;
            pid_limits[kind_index(k)] = l;
        }
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
            pids,
            pid_limits,
            vel_shift: 0,
            estim: [0; 4],
            impedance: (0, 0),
            impedance_offset: 0,
            impedance_torque: 0.0,
            output: 0.0,
            plant: JointPlant::default(),
            motor_sign: 1.0,
            pos_pid: PidState::default(),
            trq_pid: PidState::default(),
            tau_joint: 0.0,
            tau_measured: 0.0,
            host_torque: None,
        }
    }

    /// Replaces the physical parameters.
    pub fn set_plant(&mut self, plant: JointPlant) {
        self.plant = plant;
    }

    /// The physical parameters.
    pub fn plant(&self) -> &JointPlant {
        &self.plant
    }

    /// Sets the gains and limits of one PID, as `SET_*_PID` + `SET_*_PID_LIMITS` do.
    pub fn set_gains(&mut self, kind: PidKind, pid: Pid, limits: PidLimits) {
        self.set_pid(kind, pid);
        self.pid_limits[kind_index(kind)] = limits;
    }

    fn set_pid(&mut self, kind: PidKind, pid: Pid) {
        self.pids[kind_index(kind)] = pid;
        if kind == PidKind::Position && pid.kp != 0 {
            self.motor_sign = f64::from(pid.kp.signum());
        }
    }

    fn gains(&self, kind: PidKind) -> (Pid, PidLimits) {
        let i = kind_index(kind);
        (self.pids[i], self.pid_limits[i])
    }

    /// PWM output of the last control period, counts.
    pub fn output(&self) -> f64 {
        self.output
    }

    /// The joint torque the (filtered) sensor measures, N·m, in the encoder's sense.
    pub fn measured_torque(&self) -> f64 {
        self.tau_measured
    }

    /// Sign between torque-sensor units and the encoder's sense.
    fn sensor_sign(&self) -> f64 {
        if let Some(s) = self.plant.sensor_sign {
            return if s < 0.0 { -1.0 } else { 1.0 };
        }
        match self.pids[kind_index(PidKind::Torque)].kp.signum() {
            0 => 1.0,
            s => f64::from(s) * self.motor_sign,
        }
    }

    /// The board's own torque measurement in sensor units (`τ·0x8000/TorqueMax`).
    pub fn torque_sensor_units(&self) -> i16 {
        let v = self.sensor_sign() * self.tau_measured * 32768.0 / self.plant.torque_max;
        v.round().clamp(-32768.0, 32767.0) as i16
    }

    /// The torque the controller uses, sensor units: the host's while it keeps sending.
    fn torque_feedback(&self) -> f64 {
        match self.host_torque {
            Some((v, _)) => f64::from(v),
            None => f64::from(self.torque_sensor_units()),
        }
    }

    /// Takes a torque measurement sent by the host (sensor units).
    pub fn host_torque_measurement(&mut self, value: i16) {
        self.host_torque = Some((value, HOST_TORQUE_TIMEOUT.as_secs_f64()));
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
        self.reference = self.q.round();
        self.reference_vel = 0.0;
        self.target = self.reference;
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
            self.pos_pid = PidState::default();
            self.trq_pid = PidState::default();
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

    /// Whether the joint runs the impedance law: the compliant interaction mode in a
    /// position or velocity mode (position-direct and mixed included), or the MC4's own
    /// impedance modes.
    pub fn compliant(&self) -> bool {
        match self.mode {
            ControlMode::ImpedancePos | ControlMode::ImpedanceVel => true,
            ControlMode::Position
            | ControlMode::Velocity
            | ControlMode::Direct
            | ControlMode::Mixed => self.interaction == 1,
            _ => false,
        }
    }

    /// The impedance law's torque reference of the last control period, sensor units.
    pub fn impedance_torque(&self) -> f64 {
        self.impedance_torque
    }

    /// `CAN_MOTION_DONE`, as the MC4 firmware answers it (`check_in_position` of
    /// `pid.c`): in position, mixed and impedance-position modes, whether the trajectory
    /// generator has ended (the reference reached the target: the joint itself may still
    /// be settling, as on the board, which no longer checks `INPOSITION_THRESHOLD`); in
    /// the velocity modes, whether no position trajectory is pending; always in position
    /// direct; never in the other modes (idle, torque, open loop, calibration).
    pub fn motion_done(&self) -> bool {
        match self.mode {
            ControlMode::Position | ControlMode::Mixed | ControlMode::ImpedancePos => {
                (self.reference - self.target).abs() < 0.5
            }
            ControlMode::Velocity | ControlMode::ImpedanceVel | ControlMode::Direct => true,
            _ => false,
        }
    }

    /// Advances by `dt` seconds, one control period at a time.
    pub fn step(&mut self, dt: f64) {
        let mut left = dt;
        while left > 1e-9 {
            let h = left.min(CONTROL_PERIOD);
            self.control_period(h);
            left -= h;
        }
    }

    /// Moves the position reference (trajectory generation), for `h` seconds.
    fn advance_reference(&mut self, h: f64) {
        match self.mode {
            ControlMode::Position | ControlMode::Mixed | ControlMode::ImpedancePos => {
                let err = self.target - self.reference;
                let stepmax = self.ref_speed.abs().max(1.0) * h;
                if err.abs() <= stepmax {
                    self.reference = self.target;
                    self.reference_vel = 0.0;
                } else {
                    self.reference += stepmax * err.signum();
                    self.reference_vel = self.ref_speed.abs() * err.signum();
                }
            }
            ControlMode::Velocity | ControlMode::ImpedanceVel => {
                self.vel_remaining_ms -= h * 1000.0;
                let goal = if self.vel_remaining_ms > 0.0 {
                    self.vel_cmd
                } else {
                    0.0
                };
                let dv = goal - self.reference_vel;
                let maxdv = if self.vel_accel > 0.0 {
                    self.vel_accel * h
                } else {
                    f64::INFINITY
                };
                self.reference_vel += dv.clamp(-maxdv, maxdv);
                let next = self.clamp(self.reference + self.reference_vel * h);
                if next == self.reference {
                    self.reference_vel = 0.0;
                }
                self.reference = next;
            }
            _ => {}
        }
    }

    /// One firmware control period of `h` seconds: reference, PID, then the plant.
    fn control_period(&mut self, h: f64) {
        self.advance_reference(h);
        let pwm = if self.compliant() {
            // MC4 impedance control: the position error and the joint speed make a torque
            // reference, τ = k·(q_ref − q) − d·q̇ + offset (sensor units; d arrives ×1000),
            // which the torque PID then tracks on the measured joint torque.
            let (k, d) = (
                f64::from(self.impedance.0),
                f64::from(self.impedance.1) / 1000.0,
            );
            let tau = k * (self.reference - self.q.round()) - d * self.qd
                + f64::from(self.impedance_offset);
            self.impedance_torque = tau.clamp(-32768.0, 32767.0);
            let err = self.impedance_torque - self.torque_feedback();
            let g = self.gains(PidKind::Torque);
            (self.trq_pid.run(g, err), g.1.max_output)
        } else if self.tracks_reference() {
            // The firmware's error is in whole encoder ticks.
            let err = self.reference - self.q.round();
            let g = self.gains(PidKind::Position);
            (self.pos_pid.run(g, err), g.1.max_output)
        } else if self.mode == ControlMode::Torque {
            let err = f64::from(self.torque_ref) - self.torque_feedback();
            let g = self.gains(PidKind::Torque);
            (self.trq_pid.run(g, err), g.1.max_output)
        } else if self.mode == ControlMode::OpenLoop {
            let g = self.gains(PidKind::Position);
            (f64::from(g.1.offset), g.1.max_output)
        } else {
            self.pos_pid = PidState::default();
            self.trq_pid = PidState::default();
            (0.0, 0)
        };
        let limit = f64::from(pwm.1).abs().min(f64::from(self.pwm_limit).abs());
        self.output = pwm.0.clamp(-limit, limit);
        let sub = h / PLANT_STEPS as f64;
        let q0 = self.qd;
        for _ in 0..PLANT_STEPS {
            self.plant_step(sub);
        }
        self.qdd = (self.qd - q0) / h;
        if let Some((v, left)) = self.host_torque {
            self.host_torque = (left > h).then_some((v, left - h));
        }
    }

    /// Integrates the joint for `h` seconds under the current PWM output.
    fn plant_step(&mut self, h: f64) {
        let kt = self.plant.drive_torque.max(1e-6);
        let inertia = kt / (PWM_FULL_SCALE * ACCEL_PER_PWM);
        let b = VISCOUS * inertia;
        let c = COULOMB * kt;
        let tau_m = self.motor_sign * kt * self.output / PWM_FULL_SCALE;
        let before = self.q;
        if self.qd == 0.0 && tau_m.abs() <= c {
            // Stiction holds the drive: nothing reaches the link.
            self.tau_joint = 0.0;
        } else {
            let dir = if self.qd != 0.0 {
                self.qd.signum()
            } else {
                tau_m.signum()
            };
            let mut qd = (inertia * self.qd + h * (tau_m - c * dir)) / (inertia + h * b);
            if self.qd != 0.0 && qd.signum() != self.qd.signum() {
                // Coulomb friction stops the joint; it does not reverse it.
                qd = 0.0;
            }
            self.tau_joint = tau_m - c * dir - b * qd;
            self.q += qd * h;
            self.qd = qd;
        }
        if let Some((a, b)) = self.limits {
            // Hard stops at the joint limits: the stop takes the drive's torque.
            let (lo, hi) = (f64::from(a.min(b)), f64::from(a.max(b)));
            if (self.q > hi && before <= hi) || (self.q < lo && before >= lo) {
                self.q = self.q.clamp(lo, hi);
                self.qd = 0.0;
            }
        }
        let k = h / (TORQUE_SENSOR_FILTER + h);
        self.tau_measured += (self.tau_joint - self.tau_measured) * k;
    }

    fn apply(&mut self, cmd: &McCommand) -> Option<McReply> {
        use McCommand::*;
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
            SetPid(k, p) => self.set_pid(k, p),
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
            SetImpedanceOffset(v) => self.impedance_offset = v,
            GetImpedanceOffset => return Some(McReply::ImpedanceOffset(self.impedance_offset)),
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
            SetInteractionMode(m) => {
                if m != self.interaction {
                    // Switching between the position and the torque PID starts both afresh.
                    self.pos_pid = PidState::default();
                    self.trq_pid = PidState::default();
                }
                self.interaction = m;
            }
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
    /// Period of the encoder/velocity/PID broadcasts (and of the joint torques published
    /// to the [`TorqueHub`]).
    pub broadcast_period: Duration,
    /// Period of the status broadcasts.
    pub status_period: Duration,
    /// Gains each joint starts with (the host's `SET_POS_PID`… replace them).
    pub position_pid: (Pid, PidLimits),
    pub torque_pid: (Pid, PidLimits),
    /// Physical parameters and torque sensor of each joint.
    pub plants: [JointPlant; 2],
    /// Where joint torques are published for the bus's [`JointTorqueSensor`]s.
    pub torque_hub: Option<TorqueHub>,
}

impl McBoardConfig {
    pub fn new(address: u8) -> Self {
        Self {
            address,
            initial: [0.0; 2],
            broadcast_period: Duration::from_millis(10),
            status_period: Duration::from_millis(100),
            position_pid: DEFAULT_POSITION_PID,
            torque_pid: DEFAULT_TORQUE_PID,
            plants: [JointPlant::default(); 2],
            torque_hub: None,
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
        let joints = [0, 1].map(|i| {
            let mut j = JointSim::new(cfg.initial[i]);
            j.set_plant(cfg.plants[i]);
            j.set_gains(PidKind::Position, cfg.position_pid.0, cfg.position_pid.1);
            j.set_gains(PidKind::Torque, cfg.torque_pid.0, cfg.torque_pid.1);
            j
        });
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

    /// Analog broadcasts on a joint's torque-sensor address carry the host's measurement.
    fn host_torques(&mut self, board: u8, kind: VectorKind, raw: [u16; 3]) {
        if !matches!(kind, VectorKind::Force | VectorKind::Torque) {
            return;
        }
        let first = kind.first_channel();
        let values = AsPeriodic::signed(raw);
        for j in &mut self.joints {
            if let Some(link) = j.plant.sensor {
                let ch = usize::from(link.channel);
                if link.address == board && (first..first + 3).contains(&ch) {
                    j.host_torque_measurement(values[ch - first].clamp(-32768, 32767) as i16);
                }
            }
        }
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
        if let Message::AsPeriodic {
            board,
            msg: AsPeriodic::Vector { kind, raw, .. },
        } = msg
        {
            self.host_torques(*board, *kind, *raw);
            return;
        }
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

    fn next_output(&self) -> Option<Duration> {
        use per::*;
        let bcast = [POSITION, VELOCITY, PID_VAL, MOTOR_POSITION, CURRENT]
            .into_iter()
            .any(|k| self.enabled(k));
        let status = self.enabled(STATUS) || self.enabled(ADDITIONAL_STATUS);
        // The torque hub is fed at broadcast time too: its sensors read it in order.
        let hub = self.cfg.torque_hub.is_some();
        let a = super::due_in(bcast || hub, self.cfg.broadcast_period, self.since_bcast);
        let b = super::due_in(status, self.cfg.status_period, self.since_status);
        a.into_iter().chain(b).min()
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
            if let Some(hub) = &self.cfg.torque_hub {
                for j in &self.joints {
                    if let Some(link) = j.plant.sensor {
                        hub.publish(link, j.torque_sensor_units());
                    }
                }
            }
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
                // Current proportional to the PWM: a plausible signal for the amplifier interface.
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

/// A virtual joint-torque sensor: broadcasts, as analog-sensor messages from `address`
/// (type 0xA for channels 0..2, 0xB for 3..5, values offset by 0x8000 like a strain
/// board's), the joint torques the motor boards of its bus publish to its [`TorqueHub`]
/// for this address. On iCub these messages come from the host's
/// `canBusVirtualAnalogSensor`: while the host sends on this address, the emulated
/// sensor keeps quiet (for [`HOST_TORQUE_TIMEOUT`] after each host message).
pub struct JointTorqueSensor {
    address: u8,
    hub: TorqueHub,
    period: Duration,
    since: Duration,
    host_quiet: Duration,
}

impl JointTorqueSensor {
    /// A sensor broadcasting every `period`.
    pub fn new(address: u8, hub: TorqueHub, period: Duration) -> Self {
        Self {
            address,
            hub,
            period,
            since: Duration::ZERO,
            host_quiet: Duration::ZERO,
        }
    }
}

impl Board for JointTorqueSensor {
    fn address(&self) -> u8 {
        self.address
    }

    fn kind(&self) -> &'static str {
        "jts"
    }

    fn on_message(&mut self, msg: &Message, _out: &mut Vec<CanFrame>) {
        if matches!(msg, Message::AsPeriodic { board, msg: AsPeriodic::Vector { .. } } if *board == self.address)
        {
            self.host_quiet = HOST_TORQUE_TIMEOUT;
        }
    }

    fn next_output(&self) -> Option<Duration> {
        super::due_in(true, self.period, self.since)
    }

    fn tick(&mut self, dt: Duration, out: &mut Vec<CanFrame>) {
        self.host_quiet = self.host_quiet.saturating_sub(dt);
        self.since += dt;
        if self.since < self.period {
            return;
        }
        self.since = Duration::ZERO;
        if !self.host_quiet.is_zero() {
            return;
        }
        let ch = self.hub.channels(self.address);
        for (kind, first) in [(VectorKind::Force, 0), (VectorKind::Torque, 3)] {
            let part = &ch[first..first + 3];
            if part.iter().any(Option::is_some) {
                let values = [0, 1, 2].map(|i| part[i].unwrap_or(0));
                out.push(
                    Message::AsPeriodic {
                        board: self.address,
                        msg: AsPeriodic::vector(kind, values),
                    }
                    .encode(),
                );
            }
        }
    }
}
#[cfg(test)]
#[path = "mc_tests.rs"]
mod tests;
