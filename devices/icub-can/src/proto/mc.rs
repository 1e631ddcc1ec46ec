//! Motor-control messages: class 0 polling commands and replies, class 1 broadcasts
//! (`iCubCanProto_motorControlMessages.h`, payloads as `CanBusMotionControl` and the
//! firmware's `eocanprotMCpolling` formers lay them out).

use super::{i16_at, i32_at, need, u16_at, MsgClass, Payload, ProtoError};

/// Polling opcodes (`ICUBCANPROTO_POL_MC_CMD__*`).
pub mod op {
    pub const CONTROLLER_RUN: u8 = 1;
    pub const CONTROLLER_IDLE: u8 = 2;
    pub const CALIBRATE_ENCODER: u8 = 4;
    pub const ENABLE_PWM_PAD: u8 = 5;
    pub const DISABLE_PWM_PAD: u8 = 6;
    pub const GET_CONTROL_MODE: u8 = 7;
    pub const MOTION_DONE: u8 = 8;
    pub const SET_CONTROL_MODE: u8 = 9;
    pub const SET_SPEED_ESTIM_SHIFT: u8 = 14;
    pub const GET_ENCODER_POSITION: u8 = 20;
    pub const POSITION_MOVE: u8 = 27;
    pub const VELOCITY_MOVE: u8 = 28;
    pub const SET_ENCODER_POSITION: u8 = 29;
    pub const SET_DESIRED_TORQUE: u8 = 44;
    pub const GET_DESIRED_TORQUE: u8 = 45;
    pub const STOP_TRAJECTORY: u8 = 46;
    pub const SET_PWM_LIMIT: u8 = 47;
    pub const GET_PWM_LIMIT: u8 = 48;
    pub const SET_COMMAND_POSITION: u8 = 62;
    pub const SET_MIN_POSITION: u8 = 64;
    pub const GET_MIN_POSITION: u8 = 65;
    pub const SET_MAX_POSITION: u8 = 66;
    pub const GET_MAX_POSITION: u8 = 67;
    pub const SET_MAX_VELOCITY: u8 = 68;
    pub const GET_MAX_VELOCITY: u8 = 69;
    pub const SET_CURRENT_LIMIT: u8 = 72;
    pub const SET_BCAST_POLICY: u8 = 73;
    pub const SET_VEL_SHIFT: u8 = 74;
    pub const SET_TORQUE_PID: u8 = 78;
    pub const SET_POS_PID: u8 = 82;
    pub const SET_VEL_TIMEOUT: u8 = 86;
    pub const SET_IMPEDANCE_PARAMS: u8 = 87;
    pub const GET_IMPEDANCE_PARAMS: u8 = 88;
    pub const SET_IMPEDANCE_OFFSET: u8 = 89;
    pub const GET_IMPEDANCE_OFFSET: u8 = 90;
    pub const GET_FIRMWARE_VERSION: u8 = 91;
    pub const SET_CURRENT_PID: u8 = 101;
    pub const SET_VELOCITY_PID: u8 = 105;
    pub const SET_INTERACTION_MODE: u8 = 116;
    pub const GET_INTERACTION_MODE: u8 = 117;
}

/// Broadcast message types (`ICUBCANPROTO_PER_MC_MSG__*`).
pub mod per {
    pub const POSITION: u8 = 1;
    pub const PID_VAL: u8 = 2;
    pub const STATUS: u8 = 3;
    pub const CURRENT: u8 = 4;
    pub const OVERFLOW: u8 = 5;
    pub const PRINT: u8 = 6;
    pub const VELOCITY: u8 = 7;
    pub const PID_ERROR: u8 = 8;
    pub const MOTOR_POSITION: u8 = 10;
    pub const MOTOR_SPEED: u8 = 11;
    pub const ADDITIONAL_STATUS: u8 = 12;
}

/// Control modes (`icubCanProto_controlmode_t`); unknown codes are kept.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ControlMode {
    Idle,
    Position,
    Velocity,
    Torque,
    ImpedancePos,
    ImpedanceVel,
    Current,
    Mixed,
    Direct,
    ForceIdle,
    OpenLoop,
    Calibration,
    HwFault,
    NotConfigured,
    Configured,
    Other(u8),
}

impl ControlMode {
    pub fn from_u8(v: u8) -> Self {
        match v {
            0x00 => Self::Idle,
            0x01 => Self::Position,
            0x02 => Self::Velocity,
            0x03 => Self::Torque,
            0x04 => Self::ImpedancePos,
            0x05 => Self::ImpedanceVel,
            0x06 => Self::Current,
            0x07 => Self::Mixed,
            0x08 => Self::Direct,
            0x09 => Self::ForceIdle,
            0x50 => Self::OpenLoop,
            0x60 => Self::Calibration,
            0xA0 => Self::HwFault,
            0xB0 => Self::NotConfigured,
            0xB1 => Self::Configured,
            v => Self::Other(v),
        }
    }
    pub fn to_u8(self) -> u8 {
        match self {
            Self::Idle => 0x00,
            Self::Position => 0x01,
            Self::Velocity => 0x02,
            Self::Torque => 0x03,
            Self::ImpedancePos => 0x04,
            Self::ImpedanceVel => 0x05,
            Self::Current => 0x06,
            Self::Mixed => 0x07,
            Self::Direct => 0x08,
            Self::ForceIdle => 0x09,
            Self::OpenLoop => 0x50,
            Self::Calibration => 0x60,
            Self::HwFault => 0xA0,
            Self::NotConfigured => 0xB0,
            Self::Configured => 0xB1,
            Self::Other(v) => v,
        }
    }
}

/// Which PID a PID command addresses; each has its own four opcodes (set, get, set limits, get limits).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PidKind {
    Position,
    Torque,
    Current,
    Velocity,
}

impl PidKind {
    pub const ALL: [PidKind; 4] = [Self::Position, Self::Torque, Self::Current, Self::Velocity];
    fn base(self) -> u8 {
        match self {
            Self::Position => op::SET_POS_PID,
            Self::Torque => op::SET_TORQUE_PID,
            Self::Current => op::SET_CURRENT_PID,
            Self::Velocity => op::SET_VELOCITY_PID,
        }
    }
    /// The kind and offset (0 set, 1 get, 2 set limits, 3 get limits) of a PID opcode.
    fn of(op: u8) -> Option<(Self, u8)> {
        Self::ALL.into_iter().find_map(|k| {
            (k.base()..k.base() + 4)
                .contains(&op)
                .then(|| (k, op - k.base()))
        })
    }
}

/// PID gains as the boards store them: output = (kp·e + ki·∫e + kd·ė) >> shift.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Pid {
    pub kp: i16,
    pub ki: i16,
    pub kd: i16,
    pub shift: u8,
}

/// PID limits: feed-forward offset, output saturation, integral saturation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct PidLimits {
    pub offset: i16,
    pub max_output: i16,
    pub max_integral: i16,
}

/// Host -> board polling commands (class 0). Positions are encoder ticks; the
/// position-move speed is ticks/s ÷ 10; velocity-move speed and acceleration are
/// ticks/ms × 2^velocity-shift (as `CanBusMotionControl` sends them).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum McCommand {
    ControllerRun,
    ControllerIdle,
    CalibrateEncoder {
        kind: u8,
        p1: i16,
        p2: i16,
        p3: i16,
    },
    EnablePwm,
    DisablePwm,
    GetControlMode,
    MotionDone,
    SetControlMode(ControlMode),
    SetSpeedEstimShift {
        jnt_vel: u8,
        jnt_acc: u8,
        mot_vel: u8,
        mot_acc: u8,
    },
    GetEncoderPosition,
    PositionMove {
        position: i32,
        speed: i16,
    },
    VelocityMove {
        speed: i16,
        accel: i16,
    },
    SetEncoderPosition(i32),
    SetDesiredTorque(i16),
    GetDesiredTorque,
    StopTrajectory,
    SetPwmLimit(i16),
    GetPwmLimit,
    SetCommandPosition(i32),
    SetMinPosition(i32),
    GetMinPosition,
    SetMaxPosition(i32),
    GetMaxPosition,
    SetMaxVelocity(i16),
    GetMaxVelocity,
    SetCurrentLimit(i32),
    /// Bit `n` enables broadcast type `n` (see [`per`]).
    SetBcastPolicy(u32),
    SetVelShift(u16),
    SetPid(PidKind, Pid),
    GetPid(PidKind),
    SetPidLimits(PidKind, PidLimits),
    GetPidLimits(PidKind),
    /// Milliseconds after which a velocity command expires.
    SetVelTimeout(u16),
    /// Impedance spring as `CanBusMotionControl::setImpedanceRaw` sends it (8 bytes:
    /// stiffness, damping, 0, 0): stiffness in torque-sensor units per encoder tick,
    /// damping in sensor units per tick/s, times 1000 (icub-main sends `S_16(damp*1000)`
    /// and divides the reply by 1000).
    SetImpedanceParams {
        stiffness: i16,
        damping: i16,
    },
    GetImpedanceParams,
    /// Torque offset of the impedance law, sensor units (3 bytes, as
    /// `setImpedanceOffsetRaw` and the firmware's `SET_IMPEDANCE_OFFSET` former).
    SetImpedanceOffset(i16),
    GetImpedanceOffset,
    GetFirmwareVersion {
        proto_major: u8,
        proto_minor: u8,
    },
    SetInteractionMode(u8),
    GetInteractionMode,
}

fn put_i16(b: &mut [u8], i: usize, v: i16) {
    b[i..i + 2].copy_from_slice(&v.to_le_bytes());
}
fn put_i32(b: &mut [u8], i: usize, v: i32) {
    b[i..i + 4].copy_from_slice(&v.to_le_bytes());
}

impl McCommand {
    /// The opcode this command uses.
    pub fn opcode(&self) -> u8 {
        use McCommand::*;
        match self {
            ControllerRun => op::CONTROLLER_RUN,
            ControllerIdle => op::CONTROLLER_IDLE,
            CalibrateEncoder { .. } => op::CALIBRATE_ENCODER,
            EnablePwm => op::ENABLE_PWM_PAD,
            DisablePwm => op::DISABLE_PWM_PAD,
            GetControlMode => op::GET_CONTROL_MODE,
            MotionDone => op::MOTION_DONE,
            SetControlMode(_) => op::SET_CONTROL_MODE,
            SetSpeedEstimShift { .. } => op::SET_SPEED_ESTIM_SHIFT,
            GetEncoderPosition => op::GET_ENCODER_POSITION,
            PositionMove { .. } => op::POSITION_MOVE,
            VelocityMove { .. } => op::VELOCITY_MOVE,
            SetEncoderPosition(_) => op::SET_ENCODER_POSITION,
            SetDesiredTorque(_) => op::SET_DESIRED_TORQUE,
            GetDesiredTorque => op::GET_DESIRED_TORQUE,
            StopTrajectory => op::STOP_TRAJECTORY,
            SetPwmLimit(_) => op::SET_PWM_LIMIT,
            GetPwmLimit => op::GET_PWM_LIMIT,
            SetCommandPosition(_) => op::SET_COMMAND_POSITION,
            SetMinPosition(_) => op::SET_MIN_POSITION,
            GetMinPosition => op::GET_MIN_POSITION,
            SetMaxPosition(_) => op::SET_MAX_POSITION,
            GetMaxPosition => op::GET_MAX_POSITION,
            SetMaxVelocity(_) => op::SET_MAX_VELOCITY,
            GetMaxVelocity => op::GET_MAX_VELOCITY,
            SetCurrentLimit(_) => op::SET_CURRENT_LIMIT,
            SetBcastPolicy(_) => op::SET_BCAST_POLICY,
            SetVelShift(_) => op::SET_VEL_SHIFT,
            SetPid(k, _) => k.base(),
            GetPid(k) => k.base() + 1,
            SetPidLimits(k, _) => k.base() + 2,
            GetPidLimits(k) => k.base() + 3,
            SetVelTimeout(_) => op::SET_VEL_TIMEOUT,
            SetImpedanceParams { .. } => op::SET_IMPEDANCE_PARAMS,
            GetImpedanceParams => op::GET_IMPEDANCE_PARAMS,
            SetImpedanceOffset(_) => op::SET_IMPEDANCE_OFFSET,
            GetImpedanceOffset => op::GET_IMPEDANCE_OFFSET,
            GetFirmwareVersion { .. } => op::GET_FIRMWARE_VERSION,
            SetInteractionMode(_) => op::SET_INTERACTION_MODE,
            GetInteractionMode => op::GET_INTERACTION_MODE,
        }
    }

    /// Whether the board answers this command with a reply of the same opcode.
    pub fn expects_reply(&self) -> bool {
        use McCommand::*;
        matches!(
            self,
            GetControlMode
                | MotionDone
                | GetEncoderPosition
                | GetDesiredTorque
                | GetPwmLimit
                | GetMinPosition
                | GetMaxPosition
                | GetMaxVelocity
                | GetPid(_)
                | GetPidLimits(_)
                | GetImpedanceParams
                | GetImpedanceOffset
                | GetFirmwareVersion { .. }
                | GetInteractionMode
        )
    }

    /// Writes the payload (opcode in `b[0]`, without the axis bit); returns its length.
    pub fn encode(&self, b: &mut [u8; 8]) -> usize {
        use McCommand::*;
        b[0] = self.opcode();
        match *self {
            CalibrateEncoder { kind, p1, p2, p3 } => {
                b[1] = kind;
                put_i16(b, 2, p1);
                put_i16(b, 4, p2);
                put_i16(b, 6, p3);
                8
            }
            SetControlMode(m) => {
                b[1] = m.to_u8();
                2
            }
            SetSpeedEstimShift {
                jnt_vel,
                jnt_acc,
                mot_vel,
                mot_acc,
            } => {
                b[1..5].copy_from_slice(&[jnt_vel, jnt_acc, mot_vel, mot_acc]);
                5
            }
            PositionMove { position, speed } => {
                put_i32(b, 1, position);
                put_i16(b, 5, speed);
                7
            }
            VelocityMove { speed, accel } => {
                put_i16(b, 1, speed);
                put_i16(b, 3, accel);
                5
            }
            SetDesiredTorque(t) => {
                // The firmware reads a 32-bit value: the 16-bit torque, sign-extended.
                put_i32(b, 1, i32::from(t));
                5
            }
            SetEncoderPosition(v)
            | SetCommandPosition(v)
            | SetMinPosition(v)
            | SetMaxPosition(v)
            | SetCurrentLimit(v) => {
                put_i32(b, 1, v);
                5
            }
            SetBcastPolicy(mask) => {
                b[1..5].copy_from_slice(&mask.to_le_bytes());
                5
            }
            SetPwmLimit(v) | SetMaxVelocity(v) | SetImpedanceOffset(v) => {
                put_i16(b, 1, v);
                3
            }
            SetVelShift(v) | SetVelTimeout(v) => {
                b[1..3].copy_from_slice(&v.to_le_bytes());
                3
            }
            SetPid(_, p) => {
                put_i16(b, 1, p.kp);
                put_i16(b, 3, p.ki);
                put_i16(b, 5, p.kd);
                b[7] = p.shift;
                8
            }
            SetPidLimits(_, l) => {
                // Eight bytes although seven are used: the firmware discards shorter frames.
                put_i16(b, 1, l.offset);
                put_i16(b, 3, l.max_output);
                put_i16(b, 5, l.max_integral);
                b[7] = 0;
                8
            }
            SetImpedanceParams { stiffness, damping } => {
                put_i16(b, 1, stiffness);
                put_i16(b, 3, damping);
                b[5..8].fill(0);
                8
            }
            GetFirmwareVersion {
                proto_major,
                proto_minor,
            } => {
                b[1] = proto_major;
                b[2] = proto_minor;
                3
            }
            SetInteractionMode(m) => {
                b[1] = m;
                2
            }
            ControllerRun | ControllerIdle | EnablePwm | DisablePwm | GetControlMode
            | MotionDone | GetEncoderPosition | GetDesiredTorque | StopTrajectory | GetPwmLimit
            | GetMinPosition | GetMaxPosition | GetMaxVelocity | GetPid(_) | GetPidLimits(_)
            | GetImpedanceParams | GetImpedanceOffset | GetInteractionMode => 1,
        }
    }

    /// Decodes the payload of a request with opcode `op` (`d[0]` is the opcode byte).
    pub fn decode(op: u8, d: &[u8]) -> Result<Self, ProtoError> {
        use McCommand::*;
        let n = |min: usize, what: &'static str, exp: &'static str| need(what, d, min, 8, exp);
        if let Some((kind, which)) = PidKind::of(op) {
            return Ok(match which {
                0 => {
                    n(8, "set PID", "8")?;
                    SetPid(
                        kind,
                        Pid {
                            kp: i16_at(d, 1),
                            ki: i16_at(d, 3),
                            kd: i16_at(d, 5),
                            shift: d[7],
                        },
                    )
                }
                1 => GetPid(kind),
                2 => {
                    n(7, "set PID limits", "at least 7")?;
                    SetPidLimits(
                        kind,
                        PidLimits {
                            offset: i16_at(d, 1),
                            max_output: i16_at(d, 3),
                            max_integral: i16_at(d, 5),
                        },
                    )
                }
                _ => GetPidLimits(kind),
            });
        }
        Ok(match op {
            op::CONTROLLER_RUN => ControllerRun,
            op::CONTROLLER_IDLE => ControllerIdle,
            op::CALIBRATE_ENCODER => {
                n(8, "calibrate", "8")?;
                CalibrateEncoder {
                    kind: d[1],
                    p1: i16_at(d, 2),
                    p2: i16_at(d, 4),
                    p3: i16_at(d, 6),
                }
            }
            op::ENABLE_PWM_PAD => EnablePwm,
            op::DISABLE_PWM_PAD => DisablePwm,
            op::GET_CONTROL_MODE => GetControlMode,
            op::MOTION_DONE => MotionDone,
            op::SET_CONTROL_MODE => {
                n(2, "set control mode", "at least 2")?;
                SetControlMode(ControlMode::from_u8(d[1]))
            }
            op::SET_SPEED_ESTIM_SHIFT => {
                n(5, "set speed estimation shift", "at least 5")?;
                SetSpeedEstimShift {
                    jnt_vel: d[1],
                    jnt_acc: d[2],
                    mot_vel: d[3],
                    mot_acc: d[4],
                }
            }
            op::GET_ENCODER_POSITION => GetEncoderPosition,
            op::POSITION_MOVE => {
                n(7, "position move", "at least 7")?;
                PositionMove {
                    position: i32_at(d, 1),
                    speed: i16_at(d, 5),
                }
            }
            op::VELOCITY_MOVE => {
                n(5, "velocity move", "at least 5")?;
                VelocityMove {
                    speed: i16_at(d, 1),
                    accel: i16_at(d, 3),
                }
            }
            op::SET_ENCODER_POSITION => {
                n(5, "set encoder", "at least 5")?;
                SetEncoderPosition(i32_at(d, 1))
            }
            op::SET_DESIRED_TORQUE => {
                n(3, "set torque", "at least 3")?;
                SetDesiredTorque(i16_at(d, 1))
            }
            op::GET_DESIRED_TORQUE => GetDesiredTorque,
            op::STOP_TRAJECTORY => StopTrajectory,
            op::SET_PWM_LIMIT => {
                n(3, "set PWM limit", "at least 3")?;
                SetPwmLimit(i16_at(d, 1))
            }
            op::GET_PWM_LIMIT => GetPwmLimit,
            op::SET_COMMAND_POSITION => {
                n(5, "set command position", "at least 5")?;
                SetCommandPosition(i32_at(d, 1))
            }
            op::SET_MIN_POSITION => {
                n(5, "set min position", "at least 5")?;
                SetMinPosition(i32_at(d, 1))
            }
            op::GET_MIN_POSITION => GetMinPosition,
            op::SET_MAX_POSITION => {
                n(5, "set max position", "at least 5")?;
                SetMaxPosition(i32_at(d, 1))
            }
            op::GET_MAX_POSITION => GetMaxPosition,
            op::SET_MAX_VELOCITY => {
                n(3, "set max velocity", "at least 3")?;
                SetMaxVelocity(i16_at(d, 1))
            }
            op::GET_MAX_VELOCITY => GetMaxVelocity,
            op::SET_CURRENT_LIMIT => {
                n(5, "set current limit", "at least 5")?;
                SetCurrentLimit(i32_at(d, 1))
            }
            op::SET_BCAST_POLICY => {
                n(5, "set broadcast policy", "at least 5")?;
                SetBcastPolicy(u32::from_le_bytes([d[1], d[2], d[3], d[4]]))
            }
            op::SET_VEL_SHIFT => {
                n(3, "set velocity shift", "at least 3")?;
                SetVelShift(u16_at(d, 1))
            }
            op::SET_VEL_TIMEOUT => {
                n(3, "set velocity timeout", "at least 3")?;
                SetVelTimeout(u16_at(d, 1))
            }
            op::SET_IMPEDANCE_PARAMS => {
                n(5, "set impedance", "at least 5")?;
                SetImpedanceParams {
                    stiffness: i16_at(d, 1),
                    damping: i16_at(d, 3),
                }
            }
            op::GET_IMPEDANCE_PARAMS => GetImpedanceParams,
            op::SET_IMPEDANCE_OFFSET => {
                n(3, "set impedance offset", "at least 3")?;
                SetImpedanceOffset(i16_at(d, 1))
            }
            op::GET_IMPEDANCE_OFFSET => GetImpedanceOffset,
            op::GET_FIRMWARE_VERSION => {
                n(3, "get firmware version", "at least 3")?;
                GetFirmwareVersion {
                    proto_major: d[1],
                    proto_minor: d[2],
                }
            }
            op::SET_INTERACTION_MODE => {
                n(2, "set interaction mode", "at least 2")?;
                SetInteractionMode(d[1])
            }
            op::GET_INTERACTION_MODE => GetInteractionMode,
            code => {
                return Err(ProtoError::Unknown {
                    class: MsgClass::PollingMotorControl,
                    code,
                })
            }
        })
    }
}

/// Firmware identification returned by `GET_FIRMWARE_VERSION`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct FirmwareInfo {
    pub board_type: u8,
    pub version: u8,
    pub release: u8,
    pub build: u8,
    pub proto_major: u8,
    pub proto_minor: u8,
    /// Whether the board judged the host's protocol version compatible.
    pub compatible: bool,
}

/// Board -> host replies (class 0), with the same opcode as the request.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum McReply {
    ControlMode(ControlMode),
    MotionDone(bool),
    EncoderPosition(i32),
    DesiredTorque(i16),
    PwmLimit(i16),
    MinPosition(i32),
    MaxPosition(i32),
    MaxVelocity(i16),
    Pid(PidKind, Pid),
    PidLimits(PidKind, PidLimits),
    ImpedanceParams {
        stiffness: i16,
        damping: i16,
    },
    /// Sensor units, read as a 16-bit value at `data[1]` (`getImpedanceOffsetRaw`).
    ImpedanceOffset(i16),
    FirmwareVersion(FirmwareInfo),
    InteractionMode(u8),
}

impl McReply {
    pub fn opcode(&self) -> u8 {
        use McReply::*;
        match self {
            ControlMode(_) => op::GET_CONTROL_MODE,
            MotionDone(_) => op::MOTION_DONE,
            EncoderPosition(_) => op::GET_ENCODER_POSITION,
            DesiredTorque(_) => op::GET_DESIRED_TORQUE,
            PwmLimit(_) => op::GET_PWM_LIMIT,
            MinPosition(_) => op::GET_MIN_POSITION,
            MaxPosition(_) => op::GET_MAX_POSITION,
            MaxVelocity(_) => op::GET_MAX_VELOCITY,
            Pid(k, _) => k.base() + 1,
            PidLimits(k, _) => k.base() + 3,
            ImpedanceParams { .. } => op::GET_IMPEDANCE_PARAMS,
            ImpedanceOffset(_) => op::GET_IMPEDANCE_OFFSET,
            FirmwareVersion(_) => op::GET_FIRMWARE_VERSION,
            InteractionMode(_) => op::GET_INTERACTION_MODE,
        }
    }

    pub fn encode(&self, b: &mut [u8; 8]) -> usize {
        use McReply::*;
        b[0] = self.opcode();
        match *self {
            ControlMode(m) => {
                b[1] = m.to_u8();
                2
            }
            MotionDone(done) => {
                put_i16(b, 1, i16::from(done));
                3
            }
            EncoderPosition(v) | MinPosition(v) | MaxPosition(v) => {
                put_i32(b, 1, v);
                5
            }
            DesiredTorque(v) | PwmLimit(v) | MaxVelocity(v) | ImpedanceOffset(v) => {
                put_i16(b, 1, v);
                3
            }
            Pid(_, p) => {
                put_i16(b, 1, p.kp);
                put_i16(b, 3, p.ki);
                put_i16(b, 5, p.kd);
                b[7] = p.shift;
                8
            }
            PidLimits(_, l) => {
                put_i16(b, 1, l.offset);
                put_i16(b, 3, l.max_output);
                put_i16(b, 5, l.max_integral);
                7
            }
            ImpedanceParams { stiffness, damping } => {
                put_i16(b, 1, stiffness);
                put_i16(b, 3, damping);
                5
            }
            FirmwareVersion(f) => {
                b[1..8].copy_from_slice(&[
                    f.board_type,
                    f.version,
                    f.release,
                    f.build,
                    f.proto_major,
                    f.proto_minor,
                    u8::from(f.compatible),
                ]);
                8
            }
            InteractionMode(m) => {
                b[1] = m;
                2
            }
        }
    }

    pub fn decode(op: u8, d: &[u8]) -> Result<Self, ProtoError> {
        use McReply::*;
        let n = |min: usize, what: &'static str, exp: &'static str| need(what, d, min, 8, exp);
        if let Some((kind, which)) = PidKind::of(op) {
            return match which {
                1 => {
                    n(8, "PID reply", "8")?;
                    Ok(Pid(
                        kind,
                        super::Pid {
                            kp: i16_at(d, 1),
                            ki: i16_at(d, 3),
                            kd: i16_at(d, 5),
                            shift: d[7],
                        },
                    ))
                }
                3 => {
                    n(7, "PID limits reply", "at least 7")?;
                    Ok(PidLimits(
                        kind,
                        super::PidLimits {
                            offset: i16_at(d, 1),
                            max_output: i16_at(d, 3),
                            max_integral: i16_at(d, 5),
                        },
                    ))
                }
                _ => Err(ProtoError::Unknown {
                    class: MsgClass::PollingMotorControl,
                    code: op,
                }),
            };
        }
        Ok(match op {
            op::GET_CONTROL_MODE => {
                n(2, "control mode reply", "at least 2")?;
                ControlMode(super::ControlMode::from_u8(d[1]))
            }
            op::MOTION_DONE => {
                n(3, "motion done reply", "at least 3")?;
                MotionDone(i16_at(d, 1) != 0)
            }
            op::GET_ENCODER_POSITION => {
                n(5, "encoder reply", "at least 5")?;
                EncoderPosition(i32_at(d, 1))
            }
            op::GET_MIN_POSITION => {
                n(5, "min position reply", "at least 5")?;
                MinPosition(i32_at(d, 1))
            }
            op::GET_MAX_POSITION => {
                n(5, "max position reply", "at least 5")?;
                MaxPosition(i32_at(d, 1))
            }
            op::GET_DESIRED_TORQUE => {
                n(3, "torque reply", "at least 3")?;
                DesiredTorque(i16_at(d, 1))
            }
            op::GET_PWM_LIMIT => {
                n(3, "PWM limit reply", "at least 3")?;
                PwmLimit(i16_at(d, 1))
            }
            op::GET_MAX_VELOCITY => {
                n(3, "max velocity reply", "at least 3")?;
                MaxVelocity(i16_at(d, 1))
            }
            op::GET_IMPEDANCE_PARAMS => {
                n(5, "impedance reply", "at least 5")?;
                ImpedanceParams {
                    stiffness: i16_at(d, 1),
                    damping: i16_at(d, 3),
                }
            }
            op::GET_IMPEDANCE_OFFSET => {
                n(3, "impedance offset reply", "at least 3")?;
                ImpedanceOffset(i16_at(d, 1))
            }
            op::GET_FIRMWARE_VERSION => {
                n(8, "firmware version reply", "8")?;
                FirmwareVersion(FirmwareInfo {
                    board_type: d[1],
                    version: d[2],
                    release: d[3],
                    build: d[4],
                    proto_major: d[5],
                    proto_minor: d[6],
                    compatible: d[7] != 0,
                })
            }
            op::GET_INTERACTION_MODE => {
                n(2, "interaction mode reply", "at least 2")?;
                InteractionMode(d[1])
            }
            code => {
                return Err(ProtoError::Unknown {
                    class: MsgClass::PollingMotorControl,
                    code,
                })
            }
        })
    }
}

/// Fault and mode summary of one board (`ICUBCANPROTO_PER_MC_MSG__STATUS`).
///
/// Layout: `fault0, mode0, fault1, mode1, can_status, board_status, can_tx_errors, can_rx_errors`.
/// Axis fault bits: 0x01 undervoltage, 0x02 overload, 0x04 external fault, 0x08
/// overcurrent, 0x10 hall sensor, 0x20 absolute encoder, 0x40 optical encoder. CAN
/// status bits: 0x01 tx overflow, 0x02 bus off, 0x04 tx error, 0x08 rx error, 0x10 tx
/// overrun, 0x20 rx warning, 0x40 rx overrun.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct BoardStatus {
    pub axis_faults: [u8; 2],
    pub control_mode: [ControlMode; 2],
    pub can_status: u8,
    pub board_status: u8,
    pub can_tx_errors: u8,
    pub can_rx_errors: u8,
}

/// Board broadcasts (class 1). Each carries both joints of the board.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum McPeriodic {
    /// Joint encoders, ticks.
    Position([i32; 2]),
    /// PID outputs (PWM counts).
    PidValue([i16; 2]),
    Status(BoardStatus),
    /// Motor currents (board units).
    Current([i16; 2]),
    /// The board's transmit buffer overflowed.
    Overflow,
    /// A fragment of a text message printed by the board firmware.
    Print(Payload),
    /// Joint speed (ticks/ms × 2^shift) and acceleration.
    Velocity {
        speed: [i16; 2],
        accel: [i16; 2],
    },
    PidError {
        position: [i16; 2],
        torque: [i16; 2],
    },
    MotorPosition([i32; 2]),
    MotorSpeed {
        speed: [i16; 2],
        accel: [i16; 2],
    },
    /// Interaction mode per joint (0 stiff, 1 compliant), one nibble each.
    AdditionalStatus {
        interaction: [u8; 2],
    },
}

impl McPeriodic {
    /// Writes the payload; returns (message type, length).
    pub fn encode(&self, b: &mut [u8; 8]) -> (u8, usize) {
        use McPeriodic::*;
        let pair16 = |b: &mut [u8; 8], a: [i16; 2], c: [i16; 2]| {
            put_i16(b, 0, a[0]);
            put_i16(b, 2, a[1]);
            put_i16(b, 4, c[0]);
            put_i16(b, 6, c[1]);
        };
        match *self {
            Position(p) => {
                put_i32(b, 0, p[0]);
                put_i32(b, 4, p[1]);
                (per::POSITION, 8)
            }
            MotorPosition(p) => {
                put_i32(b, 0, p[0]);
                put_i32(b, 4, p[1]);
                (per::MOTOR_POSITION, 8)
            }
            PidValue(v) => {
                put_i16(b, 0, v[0]);
                put_i16(b, 2, v[1]);
                (per::PID_VAL, 4)
            }
            Current(v) => {
                put_i16(b, 0, v[0]);
                put_i16(b, 2, v[1]);
                (per::CURRENT, 4)
            }
            Status(s) => {
                *b = [
                    s.axis_faults[0],
                    s.control_mode[0].to_u8(),
                    s.axis_faults[1],
                    s.control_mode[1].to_u8(),
                    s.can_status,
                    s.board_status,
                    s.can_tx_errors,
                    s.can_rx_errors,
                ];
                (per::STATUS, 8)
            }
            Overflow => (per::OVERFLOW, 0),
            Print(p) => {
                b[..p.as_slice().len()].copy_from_slice(p.as_slice());
                (per::PRINT, p.as_slice().len())
            }
            Velocity { speed, accel } => {
                pair16(b, speed, accel);
                (per::VELOCITY, 8)
            }
            PidError { position, torque } => {
                pair16(b, position, torque);
                (per::PID_ERROR, 8)
            }
            MotorSpeed { speed, accel } => {
                pair16(b, speed, accel);
                (per::MOTOR_SPEED, 8)
            }
            AdditionalStatus { interaction } => {
                b[0] = (interaction[0] & 0xF) | (interaction[1] << 4);
                (per::ADDITIONAL_STATUS, 1)
            }
        }
    }

    pub fn decode(kind: u8, d: &[u8]) -> Result<Self, ProtoError> {
        use McPeriodic::*;
        let n = |min: usize, what: &'static str, exp: &'static str| need(what, d, min, 8, exp);
        let pairs = |d: &[u8]| ([i16_at(d, 0), i16_at(d, 2)], [i16_at(d, 4), i16_at(d, 6)]);
        Ok(match kind {
            per::POSITION => {
                n(8, "position broadcast", "8")?;
                Position([i32_at(d, 0), i32_at(d, 4)])
            }
            per::MOTOR_POSITION => {
                n(8, "motor position broadcast", "8")?;
                MotorPosition([i32_at(d, 0), i32_at(d, 4)])
            }
            per::PID_VAL => {
                n(4, "PID broadcast", "at least 4")?;
                PidValue([i16_at(d, 0), i16_at(d, 2)])
            }
            per::CURRENT => {
                n(4, "current broadcast", "at least 4")?;
                Current([i16_at(d, 0), i16_at(d, 2)])
            }
            per::STATUS => {
                n(8, "status broadcast", "8")?;
                Status(BoardStatus {
                    axis_faults: [d[0], d[2]],
                    control_mode: [ControlMode::from_u8(d[1]), ControlMode::from_u8(d[3])],
                    can_status: d[4],
                    board_status: d[5],
                    can_tx_errors: d[6],
                    can_rx_errors: d[7],
                })
            }
            per::OVERFLOW => Overflow,
            per::PRINT => Print(Payload::new(d)),
            per::VELOCITY => {
                n(8, "velocity broadcast", "8")?;
                let (speed, accel) = pairs(d);
                Velocity { speed, accel }
            }
            per::PID_ERROR => {
                n(8, "PID error broadcast", "8")?;
                let (position, torque) = pairs(d);
                PidError { position, torque }
            }
            per::MOTOR_SPEED => {
                n(8, "motor speed broadcast", "8")?;
                let (speed, accel) = pairs(d);
                MotorSpeed { speed, accel }
            }
            per::ADDITIONAL_STATUS => {
                n(1, "additional status broadcast", "at least 1")?;
                AdditionalStatus {
                    interaction: [d[0] & 0xF, d[0] >> 4],
                }
            }
            code => {
                return Err(ProtoError::Unknown {
                    class: MsgClass::PeriodicMotorControl,
                    code,
                })
            }
        })
    }
}
