//! The control-board protocol, one typed method per remote call: its arguments, its
//! reply, its 3.12 form and how a device serves it, declared once in the table below.
//! The server (`rpc.rs`) decodes a [`Request`] and serves it; the client
//! (`remote_controlboard`) sends the method structs. A method added here must be
//! handled wherever [`Request`] is matched.

use super::rpc::RpcStamp;
use super::v3::{self, Done, Flat, Form, Group, Listed, PidType, Style, Wire3, J16};
use super::v4::{self, Wire4};
use crate::driver::DeviceDriver;
use crate::error::{DevResult, DeviceError};
use crate::interfaces::{CalibrationParameters, Pid, PidExtraInfo};
use crate::sensors::wire::WireWriter;
use crate::vocabs::*;
use yarp_proto::{Bottle, Vocab32};

/// One remote call of the control board.
pub trait Method: Sized {
    type Reply: Wire3 + Wire4;
    const V3: Form;
    /// Its name in YARP 4.0's thrift `ControlBoardMsgs`, if 4.0 has it in our form.
    const V4: Option<&'static str>;
    /// The elements its arguments make in a 4.0 call.
    const ARGS4: usize;
    fn put_args(&self, b: &mut Bottle);
    fn take_args(c: &mut v3::Cursor<'_>) -> Option<Self>;
    fn put_args4(&self, w: &mut WireWriter);
    fn take_args4(c: &mut v4::Cursor4<'_>) -> Option<Self>;
    /// Serves the call on `dev`.
    fn serve(self, dev: &mut dyn DeviceDriver) -> DevResult<Self::Reply>;
}

/// The device's interface `as_x`, or `NoInterface`.
macro_rules! via {
    ($d:ident . $as:ident) => {
        $d.$as().ok_or(DeviceError::NoInterface(stringify!($as)))?
    };
}

/// The first of `names` (a table row's optional thrift name).
const fn first(names: &[&'static str]) -> Option<&'static str> {
    match names {
        [n, ..] => Some(n),
        [] => None,
    }
}

/// A group command needs one value per joint.
pub fn sized<T>(joints: &[usize], values: &[T]) -> DevResult<()> {
    if joints.len() == values.len() {
        Ok(())
    } else {
        Err(DeviceError::WrongSize {
            expected: joints.len(),
            got: values.len(),
        })
    }
}

/// The number of controlled joints (C++ `controlledJoints`).
fn axes(d: &mut dyn DeviceDriver) -> DevResult<usize> {
    if let Some(e) = d.as_encoders() {
        return e.get_axes();
    }
    if let Some(p) = d.as_position_control() {
        return p.get_axes();
    }
    via!(d.as_velocity_control).get_axes()
}

/// `f(j)` for every joint.
fn each<T>(n: usize, f: impl FnMut(usize) -> DevResult<T>) -> DevResult<Vec<T>> {
    (0..n).map(f).collect()
}

macro_rules! control_board_methods {
    ($(
        $(#[$doc:meta])*
        $name:ident { $($arg:ident : $ty:ty),* } -> $reply:ty,
            $style:ident [$($head:ident),*] $(, v4 $v4:literal)? => |$d:ident| $serve:expr;
    )*) => {
        $(
            $(#[$doc])*
            #[derive(Debug, Clone, PartialEq)]
            pub struct $name { $(pub $arg: $ty),* }

            impl Method for $name {
                type Reply = $reply;
                const V3: Form = Form { head: &[$($head),*], style: Style::$style };
                const V4: Option<&'static str> = first(&[$($v4)?]);
                const ARGS4: usize = 0 $(+ <$ty as Wire4>::COUNT)*;
                fn put_args(&self, _b: &mut Bottle) {
                    $( self.$arg.put(_b); )*
                }
                fn take_args(_c: &mut v3::Cursor<'_>) -> Option<Self> {
                    Some(Self { $($arg: Wire3::take(_c)?),* })
                }
                fn put_args4(&self, _w: &mut WireWriter) {
                    $( self.$arg.put4(_w); )*
                }
                fn take_args4(_c: &mut v4::Cursor4<'_>) -> Option<Self> {
                    Some(Self { $($arg: Wire4::take4(_c)?),* })
                }
                #[allow(unused_variables)]
                fn serve(self, $d: &mut dyn DeviceDriver) -> DevResult<$reply> {
                    let Self { $($arg),* } = self;
                    $serve
                }
            }
        )*

        /// Any control-board call, as a server receives it.
        #[derive(Debug, Clone, PartialEq)]
        pub enum Request { $($name($name)),* }

        impl Request {
            /// The call `cmd` makes in 3.12's encoding, if it is one this protocol has.
            pub fn from_v3(cmd: &Bottle) -> Option<Request> {
                $( if let Some(m) = v3::decode::<$name>(cmd) { return Some(Request::$name(m)); } )*
                None
            }

            /// Serves the call on `dev` and answers `cmd` in 3.12's encoding.
            pub fn serve_v3(self, cmd: &Bottle, dev: &mut dyn DeviceDriver, stamp: &mut RpcStamp) -> Bottle {
                match self { $(Request::$name(m) => v3::reply::<$name>(cmd, m.serve(dev), stamp)),* }
            }

            /// The call named `name` in 4.0's thrift form, with its arguments `args`, if it
            /// is one this protocol has in that form.
            pub fn from_v4(name: &str, args: &[yarp_proto::Value]) -> Option<Request> {
                $( if <$name as Method>::V4 == Some(name) {
                    return v4::decode::<$name>(args).map(Request::$name);
                } )*
                None
            }

            /// The call in 4.0's thrift form, as a client writes it.
            pub fn to_v4(&self) -> Vec<u8> {
                match self { $(Request::$name(m) => v4::request(m)),* }
            }

            /// Serves the call on `dev` and answers it in 4.0's thrift form.
            pub fn serve_v4(self, dev: &mut dyn DeviceDriver) -> Vec<u8> {
                match self { $(Request::$name(m) => v4::reply::<$name>(m.serve(dev))),* }
            }

            /// Every method's 3.12 form, in the table's order.
            pub const FORMS: &'static [Form] = &[$(<$name as Method>::V3),*];

            /// The thrift names of the methods 4.0 has in our form.
            pub const V4_NAMES: &'static [&'static str] = &{
                const ALL: [Option<&str>; [$(stringify!($name)),*].len()] = [$(<$name as Method>::V4),*];
                const N: usize = {
                    let mut n = 0;
                    let mut i = 0;
                    while i < ALL.len() {
                        if ALL[i].is_some() {
                            n += 1;
                        }
                        i += 1;
                    }
                    n
                };
                let mut out = [""; N];
                let (mut i, mut k) = (0, 0);
                while i < ALL.len() {
                    if let Some(n) = ALL[i] {
                        out[k] = n;
                        k += 1;
                    }
                    i += 1;
                }
                out
            };
        }
    };
}

control_board_methods! {
    /// `[get] [prot]`: the protocol version this server speaks.
    ProtocolVersion {} -> (i32, i32, i32), Echo [GET, PROTOCOL_VERSION] =>
        |d| Ok(super::PROTOCOL_VERSION_NUMBER);
    Axes {} -> usize, Get [GET, AXES], v4 "getAxesRPC" => |d| via!(d.as_encoders).get_axes();

    // IPositionControl
    PositionMove { j: usize, target: f64 } -> (), Set [SET, POSITION_MOVE], v4 "positionMoveOneRPC" =>
        |d| via!(d.as_position_control).position_move(j, target);
    PositionMoves { targets: Vec<f64> } -> (), Set [SET, POSITION_MOVES], v4 "positionMoveAllRPC" =>
        |d| via!(d.as_position_control).position_moves(&targets);
    PositionMoveGroup { joints: Group, targets: Vec<f64> } -> (), Set [SET, POSITION_MOVE_GROUP], v4 "positionMoveGroupRPC" =>
        |d| { sized(&joints, &targets)?; via!(d.as_position_control).position_move_group(&joints, &targets) };
    RelativeMove { j: usize, delta: f64 } -> (), Set [SET, RELATIVE_MOVE], v4 "relativeMoveOneRPC" =>
        |d| via!(d.as_position_control).relative_move(j, delta);
    RelativeMoves { deltas: Vec<f64> } -> (), Set [SET, RELATIVE_MOVES], v4 "relativeMoveAllRPC" =>
        |d| via!(d.as_position_control).relative_moves(&deltas);
    RelativeMoveGroup { joints: Group, deltas: Vec<f64> } -> (), Set [SET, RELATIVE_MOVE_GROUP], v4 "relativeMoveGroupRPC" =>
        |d| { sized(&joints, &deltas)?; via!(d.as_position_control).relative_move_group(&joints, &deltas) };
    SetRefSpeed { j: usize, speed: f64 } -> (), Set [SET, REF_SPEED], v4 "setTrajSpeedOneRPC" =>
        |d| via!(d.as_position_control).set_ref_speed(j, speed);
    SetRefSpeeds { speeds: Vec<f64> } -> (), Set [SET, REF_SPEEDS], v4 "setTrajSpeedAllRPC" =>
        |d| via!(d.as_position_control).set_ref_speeds(&speeds);
    SetRefSpeedGroup { joints: Group, speeds: Vec<f64> } -> (), Set [SET, REF_SPEED_GROUP], v4 "setTrajSpeedGroupRPC" =>
        |d| { sized(&joints, &speeds)?; via!(d.as_position_control).set_ref_speed_group(&joints, &speeds) };
    SetRefAcceleration { j: usize, acc: f64 } -> (), Set [SET, REF_ACCELERATION], v4 "setTrajAccelerationOneRPC" =>
        |d| via!(d.as_position_control).set_ref_acceleration(j, acc);
    SetRefAccelerations { accs: Vec<f64> } -> (), Set [SET, REF_ACCELERATIONS], v4 "setTrajAccelerationsAllRPC" =>
        |d| via!(d.as_position_control).set_ref_accelerations(&accs);
    SetRefAccelerationGroup { joints: Group, accs: Vec<f64> } -> (), Set [SET, REF_ACCELERATION_GROUP], v4 "setTrajAccelerationsGroupRPC" =>
        |d| { sized(&joints, &accs)?; via!(d.as_position_control).set_ref_acceleration_group(&joints, &accs) };
    Stop { j: usize } -> (), Set [SET, STOP], v4 "stopOneRPC" => |d| via!(d.as_position_control).stop(j);
    Stops {} -> (), Set [SET, STOPS], v4 "stopAllRPC" => |d| via!(d.as_position_control).stops();
    StopGroup { joints: Group } -> (), Set [SET, STOP_GROUP], v4 "stopGroupRPC" =>
        |d| via!(d.as_position_control).stop_group(&joints);
    CheckMotionDone { j: usize } -> bool, Get [GET, MOTION_DONE], v4 "checkMotionDoneOneRPC" =>
        |d| via!(d.as_position_control).check_motion_done(j);
    CheckMotionDones {} -> bool, Get [GET, MOTION_DONES], v4 "checkMotionDoneAllRPC" =>
        |d| via!(d.as_position_control).check_motion_dones();
    CheckMotionDoneGroup { joints: Group } -> bool, Get [GET, MOTION_DONE_GROUP], v4 "checkMotionDoneGroupRPC" =>
        |d| via!(d.as_position_control).check_motion_done_group(&joints);
    GetTargetPosition { j: usize } -> f64, Get [GET, POSITION_MOVE], v4 "getTargetPositionOneRPC" =>
        |d| via!(d.as_position_control).get_target_position(j);
    GetTargetPositions {} -> Vec<f64>, Get [GET, POSITION_MOVES], v4 "getTargetPositionAllRPC" =>
        |d| via!(d.as_position_control).get_target_positions();
    GetTargetPositionGroup { joints: Group } -> Vec<f64>, Get [GET, POSITION_MOVE_GROUP], v4 "getTargetPositionGroupRPC" =>
        |d| via!(d.as_position_control).get_target_position_group(&joints);
    GetRefSpeed { j: usize } -> f64, Get [GET, REF_SPEED], v4 "getTrajSpeedOneRPC" =>
        |d| via!(d.as_position_control).get_ref_speed(j);
    GetRefSpeeds {} -> Vec<f64>, Get [GET, REF_SPEEDS], v4 "getTrajSpeedsAllRPC" =>
        |d| via!(d.as_position_control).get_ref_speeds();
    GetRefSpeedGroup { joints: Group } -> Vec<f64>, Get [GET, REF_SPEED_GROUP], v4 "getTrajSpeedsGroupRPC" =>
        |d| via!(d.as_position_control).get_ref_speed_group(&joints);
    GetRefAcceleration { j: usize } -> f64, Get [GET, REF_ACCELERATION], v4 "getTrajAccelerationOneRPC" =>
        |d| via!(d.as_position_control).get_ref_acceleration(j);
    GetRefAccelerations {} -> Vec<f64>, Get [GET, REF_ACCELERATIONS], v4 "getTrajAccelerationAllRPC" =>
        |d| via!(d.as_position_control).get_ref_accelerations();
    GetRefAccelerationGroup { joints: Group } -> Vec<f64>, Get [GET, REF_ACCELERATION_GROUP], v4 "getTrajAccelerationGroupRPC" =>
        |d| via!(d.as_position_control).get_ref_acceleration_group(&joints);

    // IVelocityControl (single-joint and group moves travel on command:i only)
    VelocityMoves { speeds: Vec<f64> } -> (), Set [SET, VELOCITY_MOVES], v4 "velocityMoveAllRPC" =>
        |d| via!(d.as_velocity_control).velocity_moves(&speeds);
    GetRefVelocity { j: usize } -> f64, Get [GET, VELOCITY_MOVE], v4 "getTargetVelocityOneRPC" =>
        |d| via!(d.as_velocity_control).get_ref_velocity(j);
    GetRefVelocities {} -> Vec<f64>, Get [GET, VELOCITY_MOVES], v4 "getTargetVelocityAllRPC" =>
        |d| via!(d.as_velocity_control).get_ref_velocities();
    GetRefVelocityGroup { joints: Group } -> Vec<f64>, Get [GET, VELOCITY_MOVE_GROUP], v4 "getTargetVelocityGroupRPC" =>
        |d| { let v = via!(d.as_velocity_control); joints.iter().map(|&j| v.get_ref_velocity(j)).collect() };

    // IEncoders (readings come from the state port; these are what RPC serves)
    GetEncoder { j: usize } -> f64, Get [GET, ENCODER], v4 "getEncoderOneRPC" => |d| via!(d.as_encoders).get_encoder(j);
    GetEncoders {} -> Vec<f64>, Get [GET, ENCODERS], v4 "getEncoderAllRPC" => |d| via!(d.as_encoders).get_encoders();
    GetEncoderSpeed { j: usize } -> f64, Get [GET, ENCODER_SPEED], v4 "getEncoderSpeedOneRPC" =>
        |d| via!(d.as_encoders).get_encoder_speed(j);
    GetEncoderSpeeds {} -> Vec<f64>, Get [GET, ENCODER_SPEEDS], v4 "getEncoderSpeedAllRPC" =>
        |d| via!(d.as_encoders).get_encoder_speeds();
    GetEncoderAcceleration { j: usize } -> f64, Get [GET, ENCODER_ACCELERATION], v4 "getEncoderAccelerationOneRPC" =>
        |d| via!(d.as_encoders).get_encoder_acceleration(j);
    GetEncoderAccelerations {} -> Vec<f64>, Get [GET, ENCODER_ACCELERATIONS], v4 "getEncoderAccelerationAllRPC" =>
        |d| via!(d.as_encoders).get_encoder_accelerations();
    SetEncoder { j: usize, value: f64 } -> (), Set [SET, ENCODER], v4 "setEncoderOneRPC" =>
        |d| via!(d.as_encoders).set_encoder(j, value);
    SetEncoders { values: Vec<f64> } -> (), Set [SET, ENCODERS], v4 "setEncoderAllRPC" =>
        |d| via!(d.as_encoders).set_encoders(&values);
    ResetEncoder { j: usize } -> (), Set [SET, E_RESET], v4 "resetEncoderOneRPC" => |d| via!(d.as_encoders).reset_encoder(j);
    ResetEncoders {} -> (), Set [SET, E_RESETS], v4 "resetEncoderAllRPC" => |d| via!(d.as_encoders).reset_encoders();

    // IMotorEncoders
    GetNumOfMotorEncoders {} -> usize, Get [GET, MOTOR_ENCODER_NUMBER], v4 "getNumberOfMotorEncodersRPC" =>
        |d| via!(d.as_motor_encoders).get_num_of_motor_encoders();
    GetMotorEncoder { m: usize } -> f64, Get [GET, MOTOR_ENCODER], v4 "getMotorEncoderOneRPC" =>
        |d| via!(d.as_motor_encoders).get_motor_encoder(m);
    GetMotorEncoders {} -> Vec<f64>, Get [GET, MOTOR_ENCODERS], v4 "getMotorEncoderAllRPC" =>
        |d| via!(d.as_motor_encoders).get_motor_encoders();
    GetMotorEncoderSpeed { m: usize } -> f64, Get [GET, MOTOR_ENCODER_SPEED], v4 "getMotorEncoderSpeedOneRPC" =>
        |d| via!(d.as_motor_encoders).get_motor_encoder_speed(m);
    GetMotorEncoderSpeeds {} -> Vec<f64>, Get [GET, MOTOR_ENCODER_SPEEDS], v4 "getMotorEncoderSpeedAllRPC" =>
        |d| via!(d.as_motor_encoders).get_motor_encoder_speeds();
    GetMotorEncoderAcceleration { m: usize } -> f64, Get [GET, MOTOR_ENCODER_ACCELERATION], v4 "getMotorEncoderAccelerationOneRPC" =>
        |d| via!(d.as_motor_encoders).get_motor_encoder_acceleration(m);
    GetMotorEncoderAccelerations {} -> Vec<f64>, Get [GET, MOTOR_ENCODER_ACCELERATIONS], v4 "getMotorEncoderAccelerationAllRPC" =>
        |d| via!(d.as_motor_encoders).get_motor_encoder_accelerations();
    SetMotorEncoder { m: usize, value: f64 } -> (), Set [SET, MOTOR_ENCODER], v4 "setMotorEncoderRPC" =>
        |d| via!(d.as_motor_encoders).set_motor_encoder(m, value);
    /// One value per motor (C++ checks the count against the joints).
    SetMotorEncoders { values: Vec<f64> } -> (), Set [SET, MOTOR_ENCODERS], v4 "setMotorEncodersAllRPC" =>
        |d| { let n = axes(d)?; sized(&(0..n).collect::<Vec<_>>(), &values)?; via!(d.as_motor_encoders).set_motor_encoders(&values) };
    ResetMotorEncoder { m: usize } -> (), Set [SET, MOTOR_E_RESET], v4 "resetMotorEncoderRPC" =>
        |d| via!(d.as_motor_encoders).reset_motor_encoder(m);
    ResetMotorEncoders {} -> (), Set [SET, MOTOR_E_RESETS], v4 "resetMotorEncodersRPC" =>
        |d| via!(d.as_motor_encoders).reset_motor_encoders();
    GetMotorEncoderCpr { m: usize } -> f64, Get [GET, MOTOR_CPR], v4 "getMotorEncoderCountsPerRevolutionRPC" =>
        |d| via!(d.as_motor_encoders).get_motor_encoder_counts_per_revolution(m);
    SetMotorEncoderCpr { m: usize, cpr: f64 } -> (), Set [SET, MOTOR_CPR], v4 "setMotorEncoderCountsPerRevolutionRPC" =>
        |d| via!(d.as_motor_encoders).set_motor_encoder_counts_per_revolution(m, cpr);

    // IControlLimits
    GetLimits { j: J16 } -> (f64, f64), Get [GET, LIMITS], v4 "getPosLimitsRPC" => |d| via!(d.as_control_limits).get_limits(j.0);
    SetLimits { j: J16, min: f64, max: f64 } -> (), Set [SET, LIMITS], v4 "setPosLimitsRPC" =>
        |d| via!(d.as_control_limits).set_limits(j.0, min, max);
    GetVelLimits { j: J16 } -> (f64, f64), Get [GET, VEL_LIMITS], v4 "getVelLimitsRPC" =>
        |d| via!(d.as_control_limits).get_vel_limits(j.0);
    SetVelLimits { j: J16, min: f64, max: f64 } -> (), Set [SET, VEL_LIMITS], v4 "setVelLimitsRPC" =>
        |d| via!(d.as_control_limits).set_vel_limits(j.0, min, max);

    // IAxisInfo (the joint type travels as its int32 value)
    GetAxisName { j: usize } -> String, Get [GET, INFO_NAME], v4 "getAxisNameRPC" => |d| via!(d.as_axis_info).get_axis_name(j);
    GetJointType { j: usize } -> i32, Get [GET, INFO_TYPE], v4 "getJointTypeRPC" =>
        |d| via!(d.as_axis_info).get_joint_type(j).map(|t| t.0);

    // IAmplifierControl
    EnableAmp { j: usize } -> (), Set [SET, AMP_ENABLE], v4 "enableAmpRPC" => |d| via!(d.as_amplifier_control).enable_amp(j);
    DisableAmp { j: usize } -> (), Set [SET, AMP_DISABLE], v4 "disableAmpRPC" => |d| via!(d.as_amplifier_control).disable_amp(j);
    GetAmpStatuses {} -> Vec<i32>, Get [GET, AMP_STATUS], v4 "getAmpStatusAllRPC" => |d| via!(d.as_amplifier_control).get_amp_statuses();
    GetAmpStatus { j: usize } -> i32, Get [GET, AMP_STATUS_SINGLE], v4 "getAmpStatusOneRPC" =>
        |d| via!(d.as_amplifier_control).get_amp_status(j);
    GetCurrent { j: usize } -> f64, Get [GET, AMP_CURRENT], v4 "getCurrentOneRPC" => |d| via!(d.as_amplifier_control).get_current(j);
    GetCurrents {} -> Vec<f64>, Get [GET, AMP_CURRENTS], v4 "getCurrentAllRPC" =>
        |d| { let n = via!(d.as_encoders).get_axes()?; let a = via!(d.as_amplifier_control); each(n, |j| a.get_current(j)) };
    GetMaxCurrent { j: usize } -> f64, Get [GET, AMP_MAXCURRENT], v4 "getMaxCurrentRPC" =>
        |d| via!(d.as_amplifier_control).get_max_current(j);
    SetMaxCurrent { j: usize, value: f64 } -> (), Set [SET, AMP_MAXCURRENT], v4 "setMaxCurrentRPC" =>
        |d| via!(d.as_amplifier_control).set_max_current(j, value);
    GetNominalCurrent { m: usize } -> f64, Get [GET, AMP_NOMINAL_CURRENT], v4 "getNominalCurrentRPC" =>
        |d| via!(d.as_amplifier_control).get_nominal_current(m);
    SetNominalCurrent { m: usize, value: f64 } -> (), Set [SET, AMP_NOMINAL_CURRENT], v4 "setNominalCurrentRPC" =>
        |d| via!(d.as_amplifier_control).set_nominal_current(m, value);
    GetPeakCurrent { m: usize } -> f64, Get [GET, AMP_PEAK_CURRENT], v4 "getPeakCurrentRPC" =>
        |d| via!(d.as_amplifier_control).get_peak_current(m);
    SetPeakCurrent { m: usize, value: f64 } -> (), Set [SET, AMP_PEAK_CURRENT], v4 "setPeakCurrentRPC" =>
        |d| via!(d.as_amplifier_control).set_peak_current(m, value);
    GetPwm { m: usize } -> f64, Get [GET, AMP_PWM], v4 "getPWMRPC" => |d| via!(d.as_amplifier_control).get_pwm(m);
    GetPwmLimit { m: usize } -> f64, Get [GET, AMP_PWM_LIMIT], v4 "getPWMLimitRPC" =>
        |d| via!(d.as_amplifier_control).get_pwm_limit(m);
    SetPwmLimit { m: usize, value: f64 } -> (), Set [SET, AMP_PWM_LIMIT], v4 "setPWMLimitRPC" =>
        |d| via!(d.as_amplifier_control).set_pwm_limit(m, value);
    GetPowerSupplyVoltage { m: usize } -> f64, Get [GET, AMP_VOLTAGE_SUPPLY], v4 "getPowerSupplyVoltageRPC" =>
        |d| via!(d.as_amplifier_control).get_power_supply_voltage(m);

    // IMotor
    GetNumberOfMotors {} -> usize, Get [GET, MOTORS_NUMBER], v4 "getNumberOfMotorsRPC" => |d| via!(d.as_motor).get_number_of_motors();
    GetTemperature { m: usize } -> f64, Get [GET, TEMPERATURE], v4 "getTemperatureOneRPC" => |d| via!(d.as_motor).get_temperature(m);
    GetTemperatures {} -> Vec<f64>, Get [GET, TEMPERATURES], v4 "getTemperatureAllRPC" =>
        |d| { let motor = via!(d.as_motor); let n = motor.get_number_of_motors()?; each(n, |m| motor.get_temperature(m)) };
    GetTemperatureLimit { m: usize } -> f64, Get [GET, TEMPERATURE_LIMIT], v4 "getTemperatureLimitRPC" =>
        |d| via!(d.as_motor).get_temperature_limit(m);
    SetTemperatureLimit { m: usize, value: f64 } -> (), Set [SET, TEMPERATURE_LIMIT], v4 "setTemperatureLimitRPC" =>
        |d| via!(d.as_motor).set_temperature_limit(m, value);
    GetGearboxRatio { m: usize } -> f64, Get [GET, GEARBOX_RATIO], v4 "getGearboxRatioRPC" => |d| via!(d.as_motor).get_gearbox_ratio(m);
    SetGearboxRatio { m: usize, value: f64 } -> (), Set [SET, GEARBOX_RATIO], v4 "setGearboxRatioRPC" =>
        |d| via!(d.as_motor).set_gearbox_ratio(m, value);

    // IPositionDirect (references are set on command:i only)
    GetRefPosition { j: usize } -> f64, Get [GET, POSITION_DIRECT], v4 "getRefPositionOneRPC" =>
        |d| via!(d.as_position_direct).get_ref_position(j);
    GetRefPositions {} -> Vec<f64>, Get [GET, POSITION_DIRECTS], v4 "getRefPositionAllRPC" =>
        |d| via!(d.as_position_direct).get_ref_positions();
    GetRefPositionsGroup { joints: Group } -> Vec<f64>, Get [GET, POSITION_DIRECT_GROUP], v4 "getRefPositionGroupRPC" =>
        |d| via!(d.as_position_direct).get_ref_positions_group(&joints);

    // IControlMode (readings come from the state port)
    GetControlMode { j: usize } -> Vocab32, GetMode [GET, ICONTROLMODE, CM_CONTROL_MODE] =>
        |d| via!(d.as_control_mode).get_control_mode(j);
    GetControlModes {} -> Vec<Vocab32>, GetMode [GET, ICONTROLMODE, CM_CONTROL_MODES] =>
        |d| via!(d.as_control_mode).get_control_modes();
    GetControlModesGroup { joints: Group } -> Vec<Vocab32>, GetMode [GET, ICONTROLMODE, CM_CONTROL_MODE_GROUP] =>
        |d| via!(d.as_control_mode).get_control_modes_group(&joints);
    SetControlMode { j: usize, mode: Vocab32 } -> (), Set [SET, ICONTROLMODE, CM_CONTROL_MODE], v4 "setControlModeOneRPC" =>
        |d| via!(d.as_control_mode).set_control_mode(j, mode);
    SetControlModes { modes: Vec<Vocab32> } -> (), Set [SET, ICONTROLMODE, CM_CONTROL_MODES], v4 "setControlModeAllRPC" =>
        |d| via!(d.as_control_mode).set_control_modes(&modes);
    SetControlModesGroup { joints: Group, modes: Vec<Vocab32> } -> (), Set [SET, ICONTROLMODE, CM_CONTROL_MODE_GROUP], v4 "setControlModeGroupRPC" =>
        |d| { sized(&joints, &modes)?; via!(d.as_control_mode).set_control_modes_group(&joints, &modes) };

    // IInteractionMode
    GetInteractionMode { j: usize } -> Vocab32, GetPlain [GET, INTERACTION_MODE_IFACE, INTERACTION_MODE], v4 "getInteractionModeOneRPC" =>
        |d| via!(d.as_interaction_mode).get_interaction_mode(j);
    GetInteractionModes {} -> Vec<Vocab32>, GetPlain [GET, INTERACTION_MODE_IFACE, INTERACTION_MODES], v4 "getInteractionModesAllRPC" =>
        |d| via!(d.as_interaction_mode).get_interaction_modes();
    GetInteractionModesGroup { joints: Group } -> Vec<Vocab32>, GetPlain [GET, INTERACTION_MODE_IFACE, INTERACTION_MODE_GROUP], v4 "getInteractionModesGroupRPC" =>
        |d| via!(d.as_interaction_mode).get_interaction_modes_group(&joints);
    SetInteractionMode { j: usize, mode: Vocab32 } -> (), Set [SET, INTERACTION_MODE_IFACE, INTERACTION_MODE], v4 "setInteractionModeOneRPC" =>
        |d| via!(d.as_interaction_mode).set_interaction_mode(j, mode);
    SetInteractionModes { modes: Vec<Vocab32> } -> (), Set [SET, INTERACTION_MODE_IFACE, INTERACTION_MODES], v4 "setInteractionModesAllRPC" =>
        |d| via!(d.as_interaction_mode).set_interaction_modes(&modes);
    SetInteractionModesGroup { joints: Group, modes: Vec<Vocab32> } -> (), Set [SET, INTERACTION_MODE_IFACE, INTERACTION_MODE_GROUP], v4 "setInteractionModesGroupRPC" =>
        |d| via!(d.as_interaction_mode).set_interaction_modes_group(&joints, &modes);

    // ITorqueControl (references are set one by one or all, here or on command:i)
    GetTorque { j: usize } -> f64, Get [GET, TORQUE, TRQ] => |d| via!(d.as_torque_control).get_torque(j);
    GetTorques {} -> Vec<f64>, Get [GET, TORQUE, TRQS] => |d| via!(d.as_torque_control).get_torques();
    GetRefTorque { j: usize } -> f64, Get [GET, TORQUE, REF], v4 "getRefTorqueOneRPC" => |d| via!(d.as_torque_control).get_ref_torque(j);
    GetRefTorques {} -> Vec<f64>, Get [GET, TORQUE, REFS], v4 "getRefTorqueAllRPC" => |d| via!(d.as_torque_control).get_ref_torques();
    SetRefTorque { j: usize, value: f64 } -> (), Set [SET, TORQUE, REF], v4 "setRefTorqueOneRPC" =>
        |d| via!(d.as_torque_control).set_ref_torque(j, value);
    SetRefTorques { values: Vec<f64> } -> (), Set [SET, TORQUE, REFS], v4 "setRefTorqueAllRPC" =>
        |d| {
            // C++ wants exactly the controlled joints
            let t = via!(d.as_torque_control);
            let n = t.get_axes()?;
            if values.len() != n {
                return Err(DeviceError::WrongSize { expected: n, got: values.len() });
            }
            values.iter().enumerate().try_for_each(|(j, v)| t.set_ref_torque(j, *v))
        };
    GetTorqueRange { j: usize } -> (f64, f64), Get [GET, TORQUE, RANGE], v4 "getTorqueRangeOneRPC" =>
        |d| via!(d.as_torque_control).get_torque_range(j);
    GetTorqueRanges {} -> (Vec<f64>, Vec<f64>), Get [GET, TORQUE, RANGES], v4 "getTorqueRangeAllRPC" =>
        |d| { let t = via!(d.as_torque_control); let n = t.get_axes()?; Ok(each(n, |j| t.get_torque_range(j))?.into_iter().unzip()) };
    /// 3.12: one list of the nine; 4.0: the nine flat (`yMotorTorqueParameters` written
    /// field by field, its call 11 elements long).
    SetMotorTorqueParams { j: usize, params: Listed<9> } -> (), Set [SET, TORQUE, MOTOR_PARAMS], v4 "setMotorTorqueParamsRPC" =>
        |d| { let p: [f64; 9] = params.0.as_slice().try_into().map_err(|_| DeviceError::WrongSize { expected: 9, got: params.0.len() })?; via!(d.as_torque_control).set_motor_torque_params(j, p) };
    /// The same nine: 4.0's reply is ten elements, the return value and the nine flat.
    GetMotorTorqueParams { j: usize } -> Listed<9>, Get [GET, TORQUE, MOTOR_PARAMS], v4 "getMotorTorqueParamsRPC" =>
        |d| via!(d.as_torque_control).get_motor_torque_params(j).map(|p| Listed(p.to_vec()));

    // ICurrentControl, IPwmControl readings (references are set on command:i only)
    GetCurrentRange { j: usize } -> (f64, f64), GetBare [GET, CURRENT_IFACE, RANGE], v4 "getCurrentRangeOneRPC" =>
        |d| via!(d.as_current_control).get_current_range(j);
    GetCurrentRanges {} -> (Vec<f64>, Vec<f64>), GetBare [GET, CURRENT_IFACE, RANGES], v4 "getCurrentRangeAllRPC" =>
        |d| { let n = axes(d)?; let c = via!(d.as_current_control); Ok(each(n, |j| c.get_current_range(j))?.into_iter().unzip()) };
    GetRefCurrent { j: usize } -> f64, GetBare [GET, CURRENT_IFACE, REF], v4 "getRefCurrentOneRPC" =>
        |d| via!(d.as_current_control).get_ref_current(j);
    GetRefCurrents {} -> Vec<f64>, GetBare [GET, CURRENT_IFACE, REFS], v4 "getRefCurrentAllRPC" =>
        |d| { let n = axes(d)?; let c = via!(d.as_current_control); each(n, |j| c.get_ref_current(j)) };
    GetRefDutyCycle { j: usize } -> f64, GetBare [GET, PWM_IFACE, REF], v4 "getRefDutyCycleOneRPC" =>
        |d| via!(d.as_pwm_control).get_ref_duty_cycle(j);
    GetRefDutyCycles {} -> Vec<f64>, GetBare [GET, PWM_IFACE, REFS], v4 "getRefDutyCycleAllRPC" =>
        |d| { let n = axes(d)?; let p = via!(d.as_pwm_control); each(n, |j| p.get_ref_duty_cycle(j)) };
    GetDutyCycle { j: usize } -> f64, GetBare [GET, PWM_IFACE, PWM_OUTPUT], v4 "getDutyCycleOneRPC" =>
        |d| via!(d.as_pwm_control).get_duty_cycle(j);
    /// C++ answers the references here (sic), which we copy.
    GetDutyCycles {} -> Vec<f64>, GetBare [GET, PWM_IFACE, PWM_OUTPUTS], v4 "getDutyCycleAllRPC" =>
        |d| { let n = axes(d)?; let p = via!(d.as_pwm_control); each(n, |j| p.get_ref_duty_cycle(j)) };

    // IPidControl: `[set|get] [pid] <what> <pid type> <joint> ...`
    SetPid { ty: PidType, j: J16, pid: Pid } -> (), Set [SET, PID, PID], v4 "setPidRPC" =>
        |d| via!(d.as_pid_control).set_pid(ty.0, j.0, pid);
    EnablePid { ty: PidType, j: J16 } -> (), Set [SET, PID, PID_ENABLE], v4 "enablePidRPC" =>
        |d| via!(d.as_pid_control).enable_pid(ty.0, j.0);
    DisablePid { ty: PidType, j: J16 } -> (), Set [SET, PID, PID_DISABLE], v4 "disablePidRPC" =>
        |d| via!(d.as_pid_control).disable_pid(ty.0, j.0);
    SetPidReference { ty: PidType, j: J16, value: f64 } -> (), Set [SET, PID, REF], v4 "setPidReferenceRPC" =>
        |d| via!(d.as_pid_control).set_pid_reference(ty.0, j.0, value);
    ResetPid { ty: PidType, j: J16 } -> (), Set [SET, PID, PID_RESET], v4 "resetPidRPC" =>
        |d| via!(d.as_pid_control).reset_pid(ty.0, j.0);
    SetPidErrorLimit { ty: PidType, j: J16, value: f64 } -> (), Set [SET, PID, PID_ERROR_LIMIT], v4 "setPidErrorLimitRPC" =>
        |d| via!(d.as_pid_control).set_pid_error_limit(ty.0, j.0, value);
    SetPidOffset { ty: PidType, j: J16, value: f64 } -> (), Set [SET, PID, PID_OFFSET], v4 "setPidOffsetOneRPC" =>
        |d| via!(d.as_pid_control).set_pid_offset(ty.0, j.0, value);
    GetPid { ty: PidType, j: J16 } -> Pid, GetBare [GET, PID, PID], v4 "getPidRPC" => |d| via!(d.as_pid_control).get_pid(ty.0, j.0);
    IsPidEnabled { ty: PidType, j: J16 } -> bool, GetBare [GET, PID, PID_ENABLE], v4 "isPidEnabledRPC" =>
        |d| via!(d.as_pid_control).is_pid_enabled(ty.0, j.0);
    GetPidReference { ty: PidType, j: J16 } -> f64, GetBare [GET, PID, REF], v4 "getPidReferenceRPC" =>
        |d| via!(d.as_pid_control).get_pid_reference(ty.0, j.0);
    GetPidError { ty: PidType, j: J16 } -> f64, GetBare [GET, PID, PID_ERROR], v4 "getPidErrorRPC" =>
        |d| via!(d.as_pid_control).get_pid_error(ty.0, j.0);
    GetPidOutput { ty: PidType, j: J16 } -> f64, GetBare [GET, PID, PID_OUTPUT], v4 "getPidOutputRPC" =>
        |d| via!(d.as_pid_control).get_pid_output(ty.0, j.0);
    GetPidErrorLimit { ty: PidType, j: J16 } -> f64, GetBare [GET, PID, PID_ERROR_LIMIT], v4 "getPidErrorLimitRPC" =>
        |d| via!(d.as_pid_control).get_pid_error_limit(ty.0, j.0);
    /// A PID per joint (C++ checks the count against the joints).
    SetPids { ty: PidType, pids: Vec<Pid> } -> (), Set [SET, PID, PIDS], v4 "setPidsRPC" =>
        |d| { let n = axes(d)?; sized(&(0..n).collect::<Vec<_>>(), &pids)?; let p = via!(d.as_pid_control); pids.into_iter().enumerate().try_for_each(|(j, pid)| p.set_pid(ty.0, j, pid)) };
    SetPidReferences { ty: PidType, refs: Vec<f64> } -> (), Set [SET, PID, REFS], v4 "setPidReferencesRPC" =>
        |d| { let n = axes(d)?; sized(&(0..n).collect::<Vec<_>>(), &refs)?; let p = via!(d.as_pid_control); refs.into_iter().enumerate().try_for_each(|(j, r)| p.set_pid_reference(ty.0, j, r)) };
    SetPidErrorLimits { ty: PidType, limits: Vec<f64> } -> (), Set [SET, PID, PID_ERROR_LIMITS], v4 "setPidErrorLimitsRPC" =>
        |d| { let n = axes(d)?; sized(&(0..n).collect::<Vec<_>>(), &limits)?; let p = via!(d.as_pid_control); limits.into_iter().enumerate().try_for_each(|(j, l)| p.set_pid_error_limit(ty.0, j, l)) };
    GetPids { ty: PidType } -> Vec<Pid>, GetBare [GET, PID, PIDS], v4 "getPidsRPC" =>
        |d| { let n = axes(d)?; let p = via!(d.as_pid_control); each(n, |j| p.get_pid(ty.0, j)) };
    GetPidReferences { ty: PidType } -> Vec<f64>, GetBare [GET, PID, REFS], v4 "getPidReferencesRPC" =>
        |d| { let n = axes(d)?; let p = via!(d.as_pid_control); each(n, |j| p.get_pid_reference(ty.0, j)) };
    GetPidErrorLimits { ty: PidType } -> Vec<f64>, GetBare [GET, PID, PID_ERROR_LIMITS], v4 "getPidErrorLimitsRPC" =>
        |d| { let n = axes(d)?; let p = via!(d.as_pid_control); each(n, |j| p.get_pid_error_limit(ty.0, j)) };
    GetPidErrors { ty: PidType } -> Vec<f64>, GetBare [GET, PID, PID_ERRORS], v4 "getPidErrorsRPC" =>
        |d| { let n = axes(d)?; let p = via!(d.as_pid_control); each(n, |j| p.get_pid_error(ty.0, j)) };
    GetPidOutputs { ty: PidType } -> Vec<f64>, GetBare [GET, PID, PID_OUTPUTS], v4 "getPidOutputsRPC" =>
        |d| { let n = axes(d)?; let p = via!(d.as_pid_control); each(n, |j| p.get_pid_output(ty.0, j)) };

    // IImpedanceControl: values travel in a list, which C++ reads padded with zeros
    SetImpedance { j: usize, values: Listed<2> } -> (), Set [SET, IMPEDANCE, IMP_PARAM], v4 "setImpedanceRPC" =>
        |d| { let v = padded(values.0); via!(d.as_impedance_control).set_impedance(j, v[0], v[1]) };
    SetImpedanceOffset { j: usize, values: Listed<1> } -> (), Set [SET, IMPEDANCE, IMP_OFFSET], v4 "setImpedanceOffsetRPC" =>
        |d| via!(d.as_impedance_control).set_impedance_offset(j, padded(values.0)[0]);
    GetImpedance { j: usize } -> Listed<2>, Get [GET, IMPEDANCE, IMP_PARAM], v4 "getImpedanceRPC" =>
        |d| via!(d.as_impedance_control).get_impedance(j).map(|(k, b)| Listed(vec![k, b]));
    GetImpedanceOffset { j: usize } -> Listed<1>, Get [GET, IMPEDANCE, IMP_OFFSET], v4 "getImpedanceOffsetRPC" =>
        |d| via!(d.as_impedance_control).get_impedance_offset(j).map(|o| Listed(vec![o]));
    /// 3.12 names the limits with the generic `[llim]`.
    GetImpedanceLimits { j: usize } -> Listed<4>, Get [GET, IMPEDANCE, LIMITS], v4 "getCurrentImpedanceLimitRPC" =>
        |d| via!(d.as_impedance_control).get_current_impedance_limit(j)
            .map(|l| Listed(vec![l.min_stiffness, l.max_stiffness, l.min_damping, l.max_damping]));

    // IControlCalibration, which C++ recognises by its first vocab
    CalibrateAxisWithParams { j: usize, kind: u32, p1: f64, p2: f64, p3: f64 } -> (), Set [CALIBRATE_JOINT], v4 "calibrateAxisWithParamsRPC" =>
        |d| via!(d.as_control_calibration).calibrate_axis_with_params(j, kind, p1, p2, p3);
    /// C++ sends the type and param1..4 only.
    SetCalibrationParameters { j: usize, kind: u32, p1: f64, p2: f64, p3: f64, p4: f64 } -> (), Set [CALIBRATE_JOINT_PARAMS], v4 "setCalibrationParametersRPC" =>
        |d| {
            let params = CalibrationParameters { kind, param1: p1, param2: p2, param3: p3, param4: p4, ..Default::default() };
            via!(d.as_control_calibration).set_calibration_parameters(j, &params)
        };
    /// `[fail]` (4.0: a failed return value) means "not done".
    CalibrationDone { j: usize } -> Done, Check [CALIBRATE_DONE], v4 "calibrationDoneRPC" =>
        |d| via!(d.as_control_calibration).calibration_done(j).map(Done);
    // These four are a lone vocab from C++'s client, which a 3.12 server refuses as
    // shorter than two elements.
    CalibrateRobot {} -> (), Set [CALIBRATE], v4 "calibrateRobotRPC" => |d| via!(d.as_control_calibration).calibrate_robot();
    AbortCalibration {} -> (), Set [ABORTCALIB], v4 "abortCalibrationRPC" => |d| via!(d.as_control_calibration).abort_calibration();
    AbortPark {} -> (), Set [ABORTPARK], v4 "abortParkRPC" => |d| via!(d.as_control_calibration).abort_park();
    /// As C++: "client would get stuck if returning false".
    Park { wait: Option<bool> } -> (), Set [PARK], v4 "parkRPC" =>
        |d| {
            if let Err(e) = via!(d.as_control_calibration).park(wait.unwrap_or(false)) {
                tracing::warn!("controlBoard rpc: park failed: {e}");
            }
            Ok(())
        };

    // IRemoteCalibrator: `[set|get] [reca] <what> [j]`
    IsCalibratorPresent {} -> bool, GetBare [GET, REMOTE_CALIBRATOR_IFACE, IS_CALIBRATOR_PRESENT], v4 "isCalibratorDevicePresentRPC" =>
        |d| via!(d.as_remote_calibrator).is_calibrator_device_present();
    CalibrateSingleJoint { j: usize } -> (), Set [SET, REMOTE_CALIBRATOR_IFACE, CALIBRATE_SINGLE_JOINT], v4 "calibrateSingleJointRPC" =>
        |d| via!(d.as_remote_calibrator).calibrate_single_joint(j);
    CalibrateWholePart {} -> (), Set [SET, REMOTE_CALIBRATOR_IFACE, CALIBRATE_WHOLE_PART], v4 "calibrateWholePartRPC" =>
        |d| via!(d.as_remote_calibrator).calibrate_whole_part();
    HomingSingleJoint { j: usize } -> (), Set [SET, REMOTE_CALIBRATOR_IFACE, HOMING_SINGLE_JOINT], v4 "homingSingleJointRPC" =>
        |d| via!(d.as_remote_calibrator).homing_single_joint(j);
    HomingWholePart {} -> (), Set [SET, REMOTE_CALIBRATOR_IFACE, HOMING_WHOLE_PART], v4 "homingWholePartRPC" =>
        |d| via!(d.as_remote_calibrator).homing_whole_part();
    /// C++ calls `parkSingleJoint(j)`, whose default waits; the flag does not travel.
    ParkSingleJoint { j: usize } -> (), Set [SET, REMOTE_CALIBRATOR_IFACE, PARK_SINGLE_JOINT], v4 "parkSingleJointRPC" =>
        |d| via!(d.as_remote_calibrator).park_single_joint(j, true);
    ParkWholePart {} -> (), Set [SET, REMOTE_CALIBRATOR_IFACE, PARK_WHOLE_PART], v4 "parkWholePartRPC" =>
        |d| via!(d.as_remote_calibrator).park_whole_part();
    QuitCalibrate {} -> (), Set [SET, REMOTE_CALIBRATOR_IFACE, QUIT_CALIBRATE], v4 "quitCalibrateRPC" =>
        |d| via!(d.as_remote_calibrator).quit_calibrate();
    QuitPark {} -> (), Set [SET, REMOTE_CALIBRATOR_IFACE, QUIT_PARK], v4 "quitParkRPC" =>
        |d| via!(d.as_remote_calibrator).quit_park();

    // 4.0 only: references 3.12 streams on command:i, which 4.0's client sends by RPC
    // (always for one joint's current and duty cycle; all of them without streaming)
    SetRefCurrent { j: usize, value: f64 } -> (), Set [], v4 "setRefCurrentOneRPC" =>
        |d| via!(d.as_current_control).set_ref_current(j, value);
    SetRefCurrents { values: Vec<f64> } -> (), Set [], v4 "setRefCurrentAllRPC" =>
        |d| via!(d.as_current_control).set_ref_currents(&values);
    SetRefCurrentGroup { joints: Group, values: Vec<f64> } -> (), Set [], v4 "setRefCurrentGroupRPC" =>
        |d| { sized(&joints, &values)?; via!(d.as_current_control).set_ref_current_group(&joints, &values) };
    SetRefDutyCycle { j: usize, value: f64 } -> (), Set [], v4 "setRefDutyCycleOneRPC" =>
        |d| via!(d.as_pwm_control).set_ref_duty_cycle(j, value);
    SetRefDutyCycles { values: Vec<f64> } -> (), Set [], v4 "setRefDutyCycleAllRPC" =>
        |d| via!(d.as_pwm_control).set_ref_duty_cycles(&values);
    /// C++ 4.0.0's wrapper leaves it unserved (`[miss]`; its client sends duty cycles on
    /// `command:i`), and so do we: `yarp rpc` users of either get the same answer.
    SetRefDutyCycleGroup { joints: Group, values: Vec<f64> } -> (), Set [], v4 "setRefDutyCycleGroupRPC" =>
        |_d| { let _ = (joints, values); Err(DeviceError::UnservedByCpp("setRefDutyCycleGroupRPC")) };
    VelocityMove { j: usize, value: f64 } -> (), Set [], v4 "velocityMoveOneRPC" =>
        |d| via!(d.as_velocity_control).velocity_move(j, value);
    VelocityMoveGroup { joints: Group, values: Vec<f64> } -> (), Set [], v4 "velocityMoveGroupRPC" =>
        |d| { sized(&joints, &values)?; via!(d.as_velocity_control).velocity_move_group(&joints, &values) };
    SetPosition { j: usize, value: f64 } -> (), Set [], v4 "setRefPositionOneRPC" =>
        |d| via!(d.as_position_direct).set_position(j, value);
    SetPositions { values: Vec<f64> } -> (), Set [], v4 "setRefPositionAllRPC" =>
        |d| via!(d.as_position_direct).set_positions(&values);
    SetPositionsGroup { joints: Group, values: Vec<f64> } -> (), Set [], v4 "setRefPositionGroupRPC" =>
        |d| { sized(&joints, &values)?; via!(d.as_position_direct).set_positions_group(&joints, &values) };
    SetRefTorqueGroup { joints: Group, values: Vec<f64> } -> (), Set [], v4 "setRefTorqueGroupRPC" =>
        |d| {
            sized(&joints, &values)?;
            let t = via!(d.as_torque_control);
            joints.iter().zip(&values).try_for_each(|(j, v)| t.set_ref_torque(*j, *v))
        };
    GetRefTorqueGroup { joints: Group } -> Vec<f64>, Get [], v4 "getRefTorqueGroupRPC" =>
        |d| { let t = via!(d.as_torque_control); joints.iter().map(|&j| t.get_ref_torque(j)).collect() };
    // 4.0's IVelocityDirect (VELOCITY_DIRECT): references set by RPC or streamed
    SetRefVelocityDirect { j: usize, value: f64 } -> (), Set [], v4 "setRefVelocityOneRPC" =>
        |d| via!(d.as_velocity_direct).set_ref_velocity_direct(j, value);
    SetRefVelocitiesDirect { values: Vec<f64> } -> (), Set [], v4 "setRefVelocityAllRPC" =>
        |d| via!(d.as_velocity_direct).set_ref_velocities_direct(&values);
    SetRefVelocitiesDirectGroup { joints: Group, values: Vec<f64> } -> (), Set [], v4 "setRefVelocityGroupRPC" =>
        |d| { sized(&joints, &values)?; via!(d.as_velocity_direct).set_ref_velocities_direct_group(&joints, &values) };
    GetRefVelocityDirect { j: usize } -> f64, Get [], v4 "getRefVelocityOneRPC" =>
        |d| via!(d.as_velocity_direct).get_ref_velocity_direct(j);
    GetRefVelocitiesDirect {} -> Vec<f64>, Get [], v4 "getRefVelocityAllRPC" =>
        |d| via!(d.as_velocity_direct).get_ref_velocities_direct();
    GetRefVelocitiesDirectGroup { joints: Group } -> Vec<f64>, Get [], v4 "getRefVelocityGroupRPC" =>
        |d| via!(d.as_velocity_direct).get_ref_velocities_direct_group(&joints);
    // IRemoteVariables: `[get] [ivar] [mvar] "key"` -> `[is] [ivar] (value) [ok]`; a set
    // carries the value's elements after the key
    GetRemoteVariable { key: String } -> Bottle, GetBare [GET, REMOTE_VARIABLE_IFACE, VARIABLE], v4 "getRemoteVariableRPC" =>
        |d| via!(d.as_remote_variables).get_remote_variable(&key);
    SetRemoteVariable { key: String, value: Flat } -> (), Set [SET, REMOTE_VARIABLE_IFACE, VARIABLE], v4 "setRemoteVariableRPC" =>
        |d| via!(d.as_remote_variables).set_remote_variable(&key, &value.0);
    GetRemoteVariablesList {} -> v4::Keys, GetBare [GET, REMOTE_VARIABLE_IFACE, VARIABLE_LIST], v4 "getRemoteVariablesListRPC" =>
        |d| via!(d.as_remote_variables).get_remote_variables_list().map(v4::Keys);

    // 4.0 only: the modes a joint takes, a PID's offset
    GetAvailableControlModes { j: J16 } -> Vec<Vocab32>, Get [], v4 "getAvailableControlModesRPC" =>
        |d| via!(d.as_control_mode).get_available_control_modes(j.0);
    GetPidOffset { ty: PidType, j: J16 } -> f64, GetBare [], v4 "getPidOffsetRPC" =>
        |d| via!(d.as_pid_control).get_pid(ty.0, j.0).map(|p| p.offset);
    /// 4.0's numbered names on the wire.
    GetAvailablePids { j: J16 } -> Vec<Vocab32>, GetBare [], v4 "getAvailablePidsRPC" =>
        |d| via!(d.as_pid_control).get_available_pids(j.0).map(|ts| ts.into_iter().map(|t| PidType(t).to_v4()).collect());
    SetPidFeedforward { ty: PidType, j: J16, value: f64 } -> (), Set [], v4 "setPidFeedforwardOneRPC" =>
        |d| via!(d.as_pid_control).set_pid_feedforward(ty.0, j.0, value);
    GetPidFeedforward { ty: PidType, j: J16 } -> f64, GetBare [], v4 "getPidFeedforwardRPC" =>
        |d| via!(d.as_pid_control).get_pid_feedforward(ty.0, j.0);
    GetPidExtraInfo { ty: PidType, j: J16 } -> PidExtraInfo, GetBare [], v4 "getPidExtraInfoRPC" =>
        |d| via!(d.as_pid_control).get_pid_extra_info(ty.0, j.0);
    GetPidExtraInfos { ty: PidType } -> Vec<PidExtraInfo>, GetBare [], v4 "getPidExtraInfosRPC" =>
        |d| {
            let n = axes(d)?;
            let p = via!(d.as_pid_control);
            each(n, |j| p.get_pid_extra_info(ty.0, j))
        };

    // IJointFault: `[get] [ijfl] [jhfl] j` -> `[is] code "message" [ok]`
    GetLastJointFault { j: usize } -> (i32, String), Is [GET, JOINT_FAULT_IFACE, GET_JOINT_FAULT], v4 "getLastJointFaultRPC" =>
        |d| via!(d.as_joint_fault).get_last_joint_fault(j);

    // 4.0's IJointBrake
    IsJointBraked { j: usize } -> bool, Get [], v4 "isJointBrakedRPC" =>
        |d| via!(d.as_joint_brake).is_joint_braked(j);
    SetManualBrakeActive { j: usize, active: bool } -> (), Set [], v4 "setManualBrakeActiveRPC" =>
        |d| via!(d.as_joint_brake).set_manual_brake_active(j, active);
    SetAutoBrakeEnabled { j: usize, enabled: bool } -> (), Set [], v4 "setAutoBrakeEnabledRPC" =>
        |d| via!(d.as_joint_brake).set_auto_brake_enabled(j, enabled);
    GetAutoBrakeEnabled { j: usize } -> bool, Get [], v4 "getAutoBrakeEnabledRPC" =>
        |d| via!(d.as_joint_brake).get_auto_brake_enabled(j);
    GetMotorEncoderTimed { m: usize } -> (f64, f64), Get [], v4 "getMotorEncoderTimedOneRPC" =>
        |d| via!(d.as_motor_encoders).get_motor_encoder_timed(m);
    /// Unserved by C++ 4.0.0's wrapper (`[miss] () ()`; its client reads the motor
    /// encoders from `stateExt:o`), and so by ours.
    GetMotorEncodersTimed {} -> (Vec<f64>, Vec<f64>), Get [], v4 "getMotorEncodersTimedAllRPC" =>
        |_d| Err(DeviceError::UnservedByCpp("getMotorEncodersTimedAllRPC"));
    GetEncoderTimed { j: usize } -> (f64, f64), Get [], v4 "getEncoderTimedOneRPC" =>
        |d| via!(d.as_encoders).get_encoder_timed(j);
    GetEncodersTimed {} -> (Vec<f64>, Vec<f64>), Get [], v4 "getEncoderTimedAllRPC" =>
        |d| via!(d.as_encoders).get_encoders_timed();
}

/// An impedance list padded with zeros to the values C++ reads.
fn padded(mut v: Vec<f64>) -> Vec<f64> {
    v.resize(v.len().max(2), 0.0);
    v
}

impl Request {
    /// Whether the call is one of `IRemoteCalibrator`'s, which a part forwards to its
    /// calibrator device.
    pub fn is_remote_calibrator(&self) -> bool {
        matches!(
            self,
            Request::IsCalibratorPresent(_)
                | Request::CalibrateSingleJoint(_)
                | Request::CalibrateWholePart(_)
                | Request::HomingSingleJoint(_)
                | Request::HomingWholePart(_)
                | Request::ParkSingleJoint(_)
                | Request::ParkWholePart(_)
                | Request::QuitCalibrate(_)
                | Request::QuitPark(_)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_head_is_a_prefix_of_another() {
        // a request must decode as one method only
        for (i, a) in Request::FORMS.iter().enumerate() {
            for (k, b) in Request::FORMS.iter().enumerate() {
                // an empty head: a method 3.12 does not have
                if i != k && !a.head.is_empty() && b.head.len() >= a.head.len() {
                    assert_ne!(
                        a.head,
                        &b.head[..a.head.len()],
                        "{a:?} is a prefix of {b:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn requests_round_trip_through_3_12_bottles() {
        let group = || Group(vec![0, 2]);
        let cases: Vec<Request> = vec![
            Request::PositionMoveGroup(PositionMoveGroup {
                joints: group(),
                targets: vec![1.0, 2.0],
            }),
            Request::SetPid(SetPid {
                ty: PidType(Vocab32::new("pos")),
                j: J16(1),
                pid: Pid::from_slice(&[1.0, 2.0, 3.0]),
            }),
            Request::SetControlModesGroup(SetControlModesGroup {
                joints: group(),
                modes: vec![Vocab32::new("idl"); 2],
            }),
            Request::CalibrateAxisWithParams(CalibrateAxisWithParams {
                j: 3,
                kind: 4,
                p1: 1.0,
                p2: 2.0,
                p3: 3.0,
            }),
            Request::Park(Park { wait: None }),
            Request::QuitPark(QuitPark {}),
        ];
        for r in cases {
            let b = match &r {
                Request::PositionMoveGroup(m) => v3::request(m),
                Request::SetPid(m) => v3::request(m),
                Request::SetControlModesGroup(m) => v3::request(m),
                Request::CalibrateAxisWithParams(m) => v3::request(m),
                Request::Park(m) => v3::request(m),
                Request::QuitPark(m) => v3::request(m),
                _ => unreachable!(),
            };
            assert_eq!(Request::from_v3(&b), Some(r), "{b}");
        }
    }

    #[test]
    fn group_counts_must_match() {
        let b = Bottle::from_text("[set] [pmg] 3 (0 1) (1.0 2.0)");
        assert_eq!(Request::from_v3(&b), None);
    }

    /// A device whose only interface is IRemoteVariables.
    #[derive(Default)]
    struct Vars(std::collections::BTreeMap<String, Bottle>);
    impl DeviceDriver for Vars {
        fn open(&mut self, _: &yarp_proto::Property) -> DevResult<()> {
            Ok(())
        }
        crate::views!(as_remote_variables);
    }
    impl crate::interfaces::IRemoteVariables for Vars {
        fn get_remote_variable(&mut self, key: &str) -> DevResult<Bottle> {
            self.0
                .get(key)
                .cloned()
                .ok_or(DeviceError::Unsupported("no such key"))
        }
        fn set_remote_variable(&mut self, key: &str, value: &Bottle) -> DevResult<()> {
            self.0.insert(key.to_string(), value.clone());
            Ok(())
        }
        fn get_remote_variables_list(&mut self) -> DevResult<Bottle> {
            Ok(self.0.keys().fold(Bottle::new(), |b, k| b.with(k.as_str())))
        }
    }

    #[test]
    fn remote_variables_in_both_forms() {
        let mut dev = Vars::default();
        let mut stamp = RpcStamp::new();
        let mut ask3 = |text: &str, dev: &mut Vars| {
            super::super::rpc::handle_rpc(&Bottle::from_text(text), dev, &mut stamp).to_string()
        };
        // 3.12: the value's elements follow the key; read back nested
        assert_eq!(
            ask3("[set] [ivar] [mvar] \"kin\" 1 2.5 x", &mut dev),
            "[ok]"
        );
        assert_eq!(
            ask3("[get] [ivar] [mvar] \"kin\"", &mut dev),
            "[is] [ivar] (1 2.5 x) [ok]"
        );
        assert_eq!(
            ask3("[get] [ivar] [lvar]", &mut dev),
            "[is] [ivar] (kin) [ok]"
        );
        // 4.0: the value nested in the call and the reply
        let set = v4::request(&SetRemoteVariable {
            key: "other".into(),
            value: Flat(Bottle::from_text("7 8")),
        });
        let reply = v4::handle_rpc(&Bottle::decode(&set).unwrap(), &mut dev);
        assert_eq!(Bottle::decode(&reply).unwrap().to_string(), "[ok]");
        let get = v4::request(&GetRemoteVariable {
            key: "other".into(),
        });
        let reply =
            Bottle::decode(&v4::handle_rpc(&Bottle::decode(&get).unwrap(), &mut dev)).unwrap();
        let (ret, value) = v4::answer::<GetRemoteVariable>(&reply).unwrap();
        assert_eq!(
            (ret, value),
            (v4::ReturnValue::Ok, Some(Bottle::from_text("7 8")))
        );
        let list = v4::request(&GetRemoteVariablesList {});
        let reply =
            Bottle::decode(&v4::handle_rpc(&Bottle::decode(&list).unwrap(), &mut dev)).unwrap();
        let keys = v4::answer::<GetRemoteVariablesList>(&reply)
            .unwrap()
            .1
            .unwrap();
        assert_eq!(keys.0.to_string(), "kin other");
    }
}
