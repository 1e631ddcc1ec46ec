//! Motion-control endpoint (`EoMotionControl.h`, `EoProtocolMC.h`): joints, motors and the
//! controller. Positions are `eOmeas_position_t` (i32 in the joint's raw units, iCub
//! degrees × 65536/360 for most joints), velocities raw units/s, torques µN·m (f32:
//! icub-main sends N·m × 1e6), currents mA (i16), PWM in duty units (i16), temperatures
//! raw (i16).

use crate::wire::{Entity, Reader, Writer};

/// `eOmc_controlmode_t` / `eOmc_controlmode_command_t` values (an `eOenum08_t`, negative
/// values as their byte).
pub mod control_mode {
    pub const IDLE: u8 = 0x00;
    pub const POSITION: u8 = 0x01;
    pub const VELOCITY: u8 = 0x02;
    pub const TORQUE: u8 = 0x03;
    pub const IMPEDANCE_POS: u8 = 0x04;
    pub const IMPEDANCE_VEL: u8 = 0x05;
    pub const CURRENT: u8 = 0x06;
    pub const VELOCITY_POS: u8 = 0x07;
    pub const MIXED: u8 = 0x08;
    pub const DIRECT: u8 = 0x09;
    pub const HW_FAULT: u8 = 0x0A;
    pub const NOT_CONFIGURED: u8 = 0x0B;
    pub const CONFIGURED: u8 = 0x0C;
    pub const FORCE_IDLE: u8 = 0x0D;
    pub const VEL_DIRECT: u8 = 0x0E;
    pub const OPENLOOP: u8 = 0x50;
    pub const EVERYTHING_OFF: u8 = 0xF0;
    pub const CALIB: u8 = 0xFE;
    pub const UNKNOWN_ERROR: u8 = 0xFF;
}

/// `eOmc_interactionmode_t`.
pub mod interaction_mode {
    pub const STIFF: u8 = 0;
    pub const COMPLIANT: u8 = 1;
}

/// `eOmc_PIDfl_t` (`eOmc_PID_t`, 40 bytes): gains as f32.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pid {
    pub kp: f32,
    pub ki: f32,
    pub kd: f32,
    pub kff: f32,
    pub limit_on_integral: f32,
    pub limit_on_output: f32,
    pub offset: f32,
    pub stiction_up: f32,
    pub stiction_down: f32,
    pub scale: i8,
}

impl Entity for Pid {
    const C_TYPE: &'static str = "eOmc_PIDfl_t";
    const SIZE: usize = 40;
    fn write(&self, w: &mut Writer) {
        for v in [
            self.kp,
            self.ki,
            self.kd,
            self.kff,
            self.limit_on_integral,
            self.limit_on_output,
            self.offset,
            self.stiction_up,
            self.stiction_down,
        ] {
            w.f32(v);
        }
        w.i8(self.scale);
        w.zeros(3);
    }
    fn read(r: &mut Reader) -> Self {
        let v = Self {
            kp: r.f32(),
            ki: r.f32(),
            kd: r.f32(),
            kff: r.f32(),
            limit_on_integral: r.f32(),
            limit_on_output: r.f32(),
            offset: r.f32(),
            stiction_up: r.f32(),
            stiction_down: r.f32(),
            scale: r.i8(),
        };
        r.skip(3);
        v
    }
}

/// `eOmeas_pwm_t` (2 bytes): a PWM value or limit in the board's duty units (the motor
/// config's `pwmLimit`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Pwm(pub i16);

impl Entity for Pwm {
    const C_TYPE: &'static str = "eOmeas_pwm_t";
    const SIZE: usize = 2;
    fn write(&self, w: &mut Writer) {
        w.i16(self.0);
    }
    fn read(r: &mut Reader) -> Self {
        Pwm(r.i16())
    }
}

/// `eOmeas_position_limits_t` (8 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PositionLimits {
    pub min: i32,
    pub max: i32,
}

impl Entity for PositionLimits {
    const C_TYPE: &'static str = "eOmeas_position_limits_t";
    const SIZE: usize = 8;
    fn write(&self, w: &mut Writer) {
        w.i32(self.min);
        w.i32(self.max);
    }
    fn read(r: &mut Reader) -> Self {
        Self {
            min: r.i32(),
            max: r.i32(),
        }
    }
}

/// `eOmc_impedance_t` (12 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Impedance {
    pub stiffness: f32,
    pub damping: f32,
    pub offset: f32,
}

impl Entity for Impedance {
    const C_TYPE: &'static str = "eOmc_impedance_t";
    const SIZE: usize = 12;
    fn write(&self, w: &mut Writer) {
        w.f32(self.stiffness);
        w.f32(self.damping);
        w.f32(self.offset);
    }
    fn read(r: &mut Reader) -> Self {
        Self {
            stiffness: r.f32(),
            damping: r.f32(),
            offset: r.f32(),
        }
    }
}

/// `eOmc_motor_params_t` (32 bytes) with its `eOmc_FrictionParams_t` (20).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MotorParams {
    pub bemf_value: f32,
    pub ktau_value: f32,
    /// viscous_pos, viscous_neg, coulomb_pos, coulomb_neg, velocityThres.
    pub friction: [f32; 5],
    pub bemf_scale: i8,
    pub ktau_scale: i8,
}

impl Entity for MotorParams {
    const C_TYPE: &'static str = "eOmc_motor_params_t";
    const SIZE: usize = 32;
    fn write(&self, w: &mut Writer) {
        w.f32(self.bemf_value);
        w.f32(self.ktau_value);
        for f in self.friction {
            w.f32(f);
        }
        w.i8(self.bemf_scale);
        w.i8(self.ktau_scale);
        w.zeros(2);
    }
    fn read(r: &mut Reader) -> Self {
        let v = Self {
            bemf_value: r.f32(),
            ktau_value: r.f32(),
            friction: [r.f32(), r.f32(), r.f32(), r.f32(), r.f32()],
            bemf_scale: r.i8(),
            ktau_scale: r.i8(),
        };
        r.skip(2);
        v
    }
}

/// `eOmc_kalman_filter_config_t` (36 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct KalmanFilterConfig {
    pub enabled: bool,
    pub x0: [f32; 3],
    pub q: [f32; 3],
    pub r: f32,
    pub p0: f32,
}

impl Entity for KalmanFilterConfig {
    const C_TYPE: &'static str = "eOmc_kalman_filter_config_t";
    const SIZE: usize = 36;
    fn write(&self, w: &mut Writer) {
        w.u8(u8::from(self.enabled));
        w.zeros(3);
        for v in self.x0.iter().chain(self.q.iter()) {
            w.f32(*v);
        }
        w.f32(self.r);
        w.f32(self.p0);
    }
    fn read(r: &mut Reader) -> Self {
        let enabled = r.u8() != 0;
        r.skip(3);
        Self {
            enabled,
            x0: [r.f32(), r.f32(), r.f32()],
            q: [r.f32(), r.f32(), r.f32()],
            r: r.f32(),
            p0: r.f32(),
        }
    }
}

/// `eOmc_joint_config_t` (248 bytes): what `embObjMotionControl::init()` sets with
/// `setcheck<joint config>` for every joint.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JointConfig {
    pub pid_trajectory: Pid,
    pub pid_direct: Pid,
    pub pid_torque: Pid,
    pub user_limits: PositionLimits,
    pub hardware_limits: PositionLimits,
    pub impedance: Impedance,
    pub max_velocity_of_joint: i32,
    pub jnt_encoder_resolution: i32,
    pub motor_params: MotorParams,
    /// ms: velocity, current, openloop, torque set points, torque feedback.
    pub velocity_setpoint_timeout: u16,
    pub current_setpoint_timeout: u16,
    pub openloop_setpoint_timeout: u16,
    pub torque_setpoint_timeout: u16,
    pub torque_feedback_timeout: u16,
    pub tc_filter_type: u8,
    pub jnt_encoder_type: u8,
    pub jnt_enc_tolerance: f32,
    pub gearbox_e2j: f32,
    pub deadzone: f32,
    pub kalman: KalmanFilterConfig,
}

impl Entity for JointConfig {
    const C_TYPE: &'static str = "eOmc_joint_config_t";
    const SIZE: usize = 248;
    fn write(&self, w: &mut Writer) {
        w.entity(&self.pid_trajectory);
        w.entity(&self.pid_direct);
        w.entity(&self.pid_torque);
        w.entity(&self.user_limits);
        w.entity(&self.hardware_limits);
        w.entity(&self.impedance);
        w.i32(self.max_velocity_of_joint);
        w.i32(self.jnt_encoder_resolution);
        w.entity(&self.motor_params);
        w.u16(self.velocity_setpoint_timeout);
        w.u16(self.current_setpoint_timeout);
        w.u16(self.openloop_setpoint_timeout);
        w.u16(self.torque_setpoint_timeout);
        w.u16(self.torque_feedback_timeout);
        w.u8(self.tc_filter_type);
        w.u8(self.jnt_encoder_type);
        w.f32(self.jnt_enc_tolerance);
        w.f32(self.gearbox_e2j);
        w.f32(self.deadzone);
        w.entity(&self.kalman);
    }
    fn read(r: &mut Reader) -> Self {
        Self {
            pid_trajectory: r.entity(),
            pid_direct: r.entity(),
            pid_torque: r.entity(),
            user_limits: r.entity(),
            hardware_limits: r.entity(),
            impedance: r.entity(),
            max_velocity_of_joint: r.i32(),
            jnt_encoder_resolution: r.i32(),
            motor_params: r.entity(),
            velocity_setpoint_timeout: r.u16(),
            current_setpoint_timeout: r.u16(),
            openloop_setpoint_timeout: r.u16(),
            torque_setpoint_timeout: r.u16(),
            torque_feedback_timeout: r.u16(),
            tc_filter_type: r.u8(),
            jnt_encoder_type: r.u8(),
            jnt_enc_tolerance: r.f32(),
            gearbox_e2j: r.f32(),
            deadzone: r.f32(),
            kalman: r.entity(),
        }
    }
}

/// `eOmc_joint_status_core_t` (40 bytes): the measures, the PID status and the modes.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JointStatusCore {
    pub position: i32,
    pub velocity: i32,
    pub acceleration: i32,
    /// µN·m (`eOmeas_torque_t`, f32: icub-main converts N·m × 1e6).
    pub torque: f32,
    /// `eOmc_joint_status_ofpid_t` as its generic view: reference1, reference2, error1,
    /// error2, output.
    pub ofpid: [i32; 5],
    /// Use [`control_mode`].
    pub control_mode: u8,
    /// Use [`interaction_mode`].
    pub interaction_mode: u8,
    pub motion_done: bool,
}

impl Entity for JointStatusCore {
    const C_TYPE: &'static str = "eOmc_joint_status_core_t";
    const SIZE: usize = 40;
    fn write(&self, w: &mut Writer) {
        w.i32(self.position);
        w.i32(self.velocity);
        w.i32(self.acceleration);
        w.f32(self.torque);
        for v in self.ofpid {
            w.i32(v);
        }
        w.u8(self.control_mode);
        w.u8(self.interaction_mode);
        w.u8(u8::from(self.motion_done));
        w.u8(0);
    }
    fn read(r: &mut Reader) -> Self {
        let v = Self {
            position: r.i32(),
            velocity: r.i32(),
            acceleration: r.i32(),
            torque: r.f32(),
            ofpid: [r.i32(), r.i32(), r.i32(), r.i32(), r.i32()],
            control_mode: r.u8(),
            interaction_mode: r.u8(),
            motion_done: r.u8() != 0,
        };
        r.skip(1);
        v
    }
}

/// `eOmc_joint_status_target_t` (28 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JointStatusTarget {
    pub position: i32,
    pub position_raw: i32,
    pub velocity: i32,
    pub acceleration: i32,
    pub torque: f32,
    pub pwm: i32,
    pub current: i32,
}

impl Entity for JointStatusTarget {
    const C_TYPE: &'static str = "eOmc_joint_status_target_t";
    const SIZE: usize = 28;
    fn write(&self, w: &mut Writer) {
        w.i32(self.position);
        w.i32(self.position_raw);
        w.i32(self.velocity);
        w.i32(self.acceleration);
        w.f32(self.torque);
        w.i32(self.pwm);
        w.i32(self.current);
    }
    fn read(r: &mut Reader) -> Self {
        Self {
            position: r.i32(),
            position_raw: r.i32(),
            velocity: r.i32(),
            acceleration: r.i32(),
            torque: r.f32(),
            pwm: r.i32(),
            current: r.i32(),
        }
    }
}

/// `eOmc_joint_status_additionalInfo_t` (12 bytes): up to three encoder readings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MultiEncoders(pub [i32; 3]);

impl Entity for MultiEncoders {
    const C_TYPE: &'static str = "eOmc_joint_status_additionalInfo_t";
    const SIZE: usize = 12;
    fn write(&self, w: &mut Writer) {
        for v in self.0 {
            w.i32(v);
        }
    }
    fn read(r: &mut Reader) -> Self {
        Self([r.i32(), r.i32(), r.i32()])
    }
}

/// `eOmc_joint_status_t` (96 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JointStatus {
    pub core: JointStatusCore,
    pub target: JointStatusTarget,
    pub multienc: MultiEncoders,
    pub debug: [u8; 16],
}

impl Entity for JointStatus {
    const C_TYPE: &'static str = "eOmc_joint_status_t";
    const SIZE: usize = 96;
    fn write(&self, w: &mut Writer) {
        w.entity(&self.core);
        w.entity(&self.target);
        w.entity(&self.multienc);
        w.bytes(&self.debug);
    }
    fn read(r: &mut Reader) -> Self {
        Self {
            core: r.entity(),
            target: r.entity(),
            multienc: r.entity(),
            debug: r.array(),
        }
    }
}

/// `eOmc_calibrator32_t` (28 bytes): calibration type and its parameters (a union of six
/// 32-bit words; see `eOmc_calibrator_params_typeN_t`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Calibrator {
    /// `eOmc_calibration_type_t` (0..14, 254 mixed, 255 undefined).
    pub calibration_type: u8,
    pub params: [i32; 6],
}

impl Entity for Calibrator {
    const C_TYPE: &'static str = "eOmc_calibrator32_t";
    const SIZE: usize = 28;
    fn write(&self, w: &mut Writer) {
        w.u8(self.calibration_type);
        w.zeros(3);
        for v in self.params {
            w.i32(v);
        }
    }
    fn read(r: &mut Reader) -> Self {
        let calibration_type = r.u8();
        r.skip(3);
        Self {
            calibration_type,
            params: [r.i32(), r.i32(), r.i32(), r.i32(), r.i32(), r.i32()],
        }
    }
}

/// `eOmc_setpoint_t` (12 bytes: type, 3 fillers, an 8-byte union).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Setpoint {
    /// `eomc_setpoint_position` (0): target and speed of a trajectory.
    Position { value: i32, velocity: i32 },
    /// `eomc_setpoint_velocity` (1).
    Velocity { value: i32, acceleration: i32 },
    /// `eomc_setpoint_torque` (2), µN·m.
    Torque { value: f32 },
    /// `eomc_setpoint_current` (3), mA.
    Current { value: i16 },
    /// `eomc_setpoint_positionraw` (4): position-direct.
    PositionRaw { value: i32 },
    /// `eomc_setpoint_openloop` (5), PWM.
    OpenLoop { value: i16 },
    /// Any other type, as received.
    Other { setpoint_type: u8, data: [u8; 8] },
}

impl Entity for Setpoint {
    const C_TYPE: &'static str = "eOmc_setpoint_t";
    const SIZE: usize = 12;
    fn write(&self, w: &mut Writer) {
        let mut d = Writer::with_capacity(8);
        let t = match *self {
            Self::Position { value, velocity } => {
                d.i32(value);
                d.i32(velocity);
                0
            }
            Self::Velocity {
                value,
                acceleration,
            } => {
                d.i32(value);
                d.i32(acceleration);
                1
            }
            Self::Torque { value } => {
                d.f32(value);
                2
            }
            Self::Current { value } => {
                d.i16(value);
                3
            }
            Self::PositionRaw { value } => {
                d.i32(value);
                4
            }
            Self::OpenLoop { value } => {
                d.i16(value);
                5
            }
            Self::Other {
                setpoint_type,
                data,
            } => {
                d.bytes(&data);
                setpoint_type
            }
        };
        let mut d = d.into_inner();
        d.resize(8, 0);
        w.u8(t);
        w.zeros(3);
        w.bytes(&d);
    }
    fn read(r: &mut Reader) -> Self {
        let t = r.u8();
        r.skip(3);
        let data: [u8; 8] = r.array();
        let mut d = Reader::new(&data);
        match t {
            0 => Self::Position {
                value: d.i32(),
                velocity: d.i32(),
            },
            1 => Self::Velocity {
                value: d.i32(),
                acceleration: d.i32(),
            },
            2 => Self::Torque { value: d.f32() },
            3 => Self::Current { value: d.i16() },
            4 => Self::PositionRaw { value: d.i32() },
            5 => Self::OpenLoop { value: d.i16() },
            _ => Self::Other {
                setpoint_type: t,
                data,
            },
        }
    }
}

/// `eOmc_current_limits_params_t` (6 bytes), mA.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CurrentLimits {
    pub nominal: i16,
    pub peak: i16,
    pub overload: i16,
}

impl Entity for CurrentLimits {
    const C_TYPE: &'static str = "eOmc_current_limits_params_t";
    const SIZE: usize = 6;
    fn write(&self, w: &mut Writer) {
        w.i16(self.nominal);
        w.i16(self.peak);
        w.i16(self.overload);
    }
    fn read(r: &mut Reader) -> Self {
        Self {
            nominal: r.i16(),
            peak: r.i16(),
            overload: r.i16(),
        }
    }
}

/// `eOmc_motor_config_t` (160 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MotorConfig {
    pub pid_current: Pid,
    pub pid_speed: Pid,
    pub gearbox_m2j: f32,
    pub rotor_encoder_resolution: i32,
    pub max_velocity_of_motor: i32,
    pub current_limits: CurrentLimits,
    pub rotor_index_offset: i16,
    pub motor_poles: u8,
    /// hasHallSensor:1, hasTempSensor:1, hasRotorEncoder:1, hasRotorEncoderIndex:1,
    /// hasSpeedEncoder:1, useSpeedFbkFromMotor:1, verbose:1 (from bit 0).
    pub flags: u8,
    pub rotor_encoder_type: u8,
    pub rot_enc_tolerance: f32,
    pub kbemf: f32,
    pub pwm_limit: i16,
    pub temperature_limit: i16,
    pub limits_of_rotor: PositionLimits,
    /// `eOmc_LuGre_params_t`: Km, Kw, S0, S1, Vth, Fc_pos, Fc_neg, Fs_pos, Fs_neg.
    pub lugre: [f32; 9],
}

impl Entity for MotorConfig {
    const C_TYPE: &'static str = "eOmc_motor_config_t";
    const SIZE: usize = 160;
    fn write(&self, w: &mut Writer) {
        w.entity(&self.pid_current);
        w.entity(&self.pid_speed);
        w.f32(self.gearbox_m2j);
        w.i32(self.rotor_encoder_resolution);
        w.i32(self.max_velocity_of_motor);
        w.entity(&self.current_limits);
        w.i16(self.rotor_index_offset);
        w.u8(self.motor_poles);
        w.u8(self.flags);
        w.u8(self.rotor_encoder_type);
        w.u8(0);
        w.f32(self.rot_enc_tolerance);
        w.f32(self.kbemf);
        w.i16(self.pwm_limit);
        w.i16(self.temperature_limit);
        w.entity(&self.limits_of_rotor);
        for v in self.lugre {
            w.f32(v);
        }
    }
    fn read(r: &mut Reader) -> Self {
        let mut v = Self {
            pid_current: r.entity(),
            pid_speed: r.entity(),
            gearbox_m2j: r.f32(),
            rotor_encoder_resolution: r.i32(),
            max_velocity_of_motor: r.i32(),
            current_limits: r.entity(),
            rotor_index_offset: r.i16(),
            motor_poles: r.u8(),
            flags: r.u8(),
            rotor_encoder_type: r.u8(),
            ..Default::default()
        };
        r.skip(1);
        v.rot_enc_tolerance = r.f32();
        v.kbemf = r.f32();
        v.pwm_limit = r.i16();
        v.temperature_limit = r.i16();
        v.limits_of_rotor = r.entity();
        for x in v.lugre.iter_mut() {
            *x = r.f32();
        }
        v
    }
}

/// `eOmc_motor_status_basic_t` (20 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MotorStatusBasic {
    pub position: i32,
    pub velocity: i32,
    pub acceleration: i32,
    /// mA.
    pub current: i16,
    pub temperature: i16,
    pub pwm: i16,
}

impl Entity for MotorStatusBasic {
    const C_TYPE: &'static str = "eOmc_motor_status_basic_t";
    const SIZE: usize = 20;
    fn write(&self, w: &mut Writer) {
        w.i32(self.position);
        w.i32(self.velocity);
        w.i32(self.acceleration);
        w.i16(self.current);
        w.i16(self.temperature);
        w.i16(self.pwm);
        w.u16(0);
    }
    fn read(r: &mut Reader) -> Self {
        let v = Self {
            position: r.i32(),
            velocity: r.i32(),
            acceleration: r.i32(),
            current: r.i16(),
            temperature: r.i16(),
            pwm: r.i16(),
        };
        r.skip(2);
        v
    }
}

/// `eOmc_motor_status_t` (24 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MotorStatus {
    pub basic: MotorStatusBasic,
    /// `eOmc_motorFaultState_t` bit mask.
    pub mc_fault_state: u32,
}

impl Entity for MotorStatus {
    const C_TYPE: &'static str = "eOmc_motor_status_t";
    const SIZE: usize = 24;
    fn write(&self, w: &mut Writer) {
        w.entity(&self.basic);
        w.u32(self.mc_fault_state);
    }
    fn read(r: &mut Reader) -> Self {
        Self {
            basic: r.entity(),
            mc_fault_state: r.u32(),
        }
    }
}

/// `eOmc_controller_status_t` (16 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ControllerStatus {
    /// `eOmc_stateofcontroller_t`: 0 config, 1 ready, 2 active.
    pub state_of_controller: u8,
    pub num_of_joints: u8,
    pub num_of_motors: u8,
    pub all_jomo_initted: bool,
    pub flags_initted_joints: u16,
    pub flags_initted_motors: u16,
    pub supply_voltage: i16,
}

impl Entity for ControllerStatus {
    const C_TYPE: &'static str = "eOmc_controller_status_t";
    const SIZE: usize = 16;
    fn write(&self, w: &mut Writer) {
        w.u8(self.state_of_controller);
        w.u8(self.num_of_joints);
        w.u8(self.num_of_motors);
        w.u8(u8::from(self.all_jomo_initted));
        w.u16(self.flags_initted_joints);
        w.u16(self.flags_initted_motors);
        w.i16(self.supply_voltage);
        w.zeros(6);
    }
    fn read(r: &mut Reader) -> Self {
        let v = Self {
            state_of_controller: r.u8(),
            num_of_joints: r.u8(),
            num_of_motors: r.u8(),
            all_jomo_initted: r.u8() != 0,
            flags_initted_joints: r.u16(),
            flags_initted_motors: r.u16(),
            supply_voltage: r.i16(),
        };
        r.skip(6);
        v
    }
}
