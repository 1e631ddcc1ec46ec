//! The motion-control parameters of `embObjMotionControl` (icub-main `eomcParser`), as
//! robots-configuration's `*-mc.xml` and the files it includes write them:
//!
//! - `GENERAL` (mechanicals): `Joints`, `AxisMap`, `AxisName`, `AxisType`, `Encoder`
//!   (angle to encoder units), `fullscalePWM`, `ampsToSensor`, `Gearbox_M2J`,
//!   `Gearbox_E2J`;
//! - `LIMITS`: `jntPosMax/Min`, `hardwareJntPosMax/Min`, `jntVelMax`,
//!   `motorNominalCurrents`, `motorPeakCurrents`, `motorOverloadCurrents`,
//!   `motorPwmLimit`, `rotorPosMin/Max`, `hardwareTemperatureLimits` and
//!   `warningTemperatureLimits` (°C, 0 when absent; the warning below 85 % of the
//!   hardware limit);
//! - `CONTROLS`: per joint, the group of each PID (`positionControl`, `torqueControl`,
//!   `currentPid`, `speedPid`; `none` for none) with `kp kd ki maxOutput maxInt
//!   stictionUp stictionDown kff` (C++ reads no `ko`; `shift` only in the current and
//!   speed groups; `ktau`, `kbemf`, friction and `filterType` in torque groups), one value
//!   per joint, and the group's `fbkControlUnits` (`metric_units`/`machine_units`) and
//!   `outputControlUnits` (`dutycycle_percent`/`machine_units`). As C++, the units of
//!   joint 0's group hold for the whole board ([`McParams::pid_factors`]);
//! - `IMPEDANCE` (`stiffness`, `damping`), `TIMEOUTS` (`velocity`, `current`, `pwm`,
//!   `torque`, `torque_measure`; 100 ms by default, 300 ms for `eomn_serv_MC_advfoc`);
//! - the motor group of a FOC service (C++ `Parser::parseFocGroup`): `2FOC` (service
//!   `eomn_serv_MC_foc` with `foc` CAN boards), `AMCBLDC` (`eomn_serv_MC_foc` with other
//!   boards) or `ADVFOC` (`eomn_serv_MC_advfoc`); other services have none (all zero);
//! - `OTHER_CONTROL_PARAMETERS/deadZone` (else a default per joint encoder type);
//! - `KALMAN_FILTER` (`kalmanFilterEnabled`, `x0`-`x2`, `Q0`-`Q2`, `R`, `P0`) and `LUGRE`
//!   (`Km`, `Kw`, `S0`, `S1`, `Vth`, `Fc_pos`, `Fc_neg`, `Fs_pos`, `Fs_neg`), optional
//!   groups whose lines are all needed once the group is there;
//! - `SERVICE/PROPERTIES/JOINTMAPPING`: the encoders `ENCODER1`/`ENCODER2`, the one
//!   `atjoint` being the joint encoder and the one `atmotor` the rotor encoder (C++
//!   `ServiceParser::getEncoderAtJoint/AtMotor`; none: resolution 1, tolerance 0).
//!
//! Conversions (YARP's `ControlBoardHelper` as `embObjMotionControl` sets it up): torques
//! in µN·m ([`NEWTONS_TO_SENSOR`]), stiffness and damping in µN·m per encoder unit,
//! PID gains by [`McParams::pid_factors`], `ktau` by [`McParams::ktau_to_raw`], motor
//! temperatures through the sensor's bridge ([`TemperatureSensor`]).

use icub_eth::entities::mc::{KalmanFilterConfig, Pid as EoPid};
use icub_eth::entities::mn::service_type;
use yarp_proto::Property;

use super::config::{parse_number, Node, ParamError};
use super::params::{read_service, ServiceKind};
use super::service_config::can_board_type;

/// C++ `measConvFactors.newtonsToSensor`: "conversion from Nm into microNm".
pub const NEWTONS_TO_SENSOR: f64 = 1_000_000.0;

/// `eObrd_cantype_t` of the 2FOC board (`eobrd_foc`).
const CAN_FOC: u8 = 8;

/// A PID group's `fbkControlUnits` and `outputControlUnits`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PidUnits {
    /// `fbkControlUnits metric_units` (else `machine_units`).
    pub metric_feedback: bool,
    /// `outputControlUnits dutycycle_percent` (else `machine_units`).
    pub dutycycle_output: bool,
}

/// The four PIDs of a joint, as YARP's `PidControlTypeEnum` names them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PidKind {
    Position,
    Velocity,
    Torque,
    Current,
}

/// One PID as its group gives it for one joint (user units).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PidParams {
    pub kp: f64,
    pub kd: f64,
    pub ki: f64,
    pub max_output: f64,
    pub max_int: f64,
    pub stiction_up: f64,
    pub stiction_down: f64,
    pub kff: f64,
    pub offset: f64,
    pub scale: f64,
    /// The group's units (the board uses joint 0's: [`McParams::pid_factors`]).
    pub units: PidUnits,
    /// `ktau` (torque PIDs).
    pub ktau: f64,
    /// `kbemf` (torque PIDs, optional).
    pub kbemf: f64,
    pub viscous_pos: f64,
    pub viscous_neg: f64,
    pub coulomb_pos: f64,
    pub coulomb_neg: f64,
    pub velocity_thres: f64,
    pub filter_type: f64,
}

impl PidParams {
    /// The firmware's PID (machine units), as YARP's `convert_pid_to_machine`: the gains
    /// over the feedback factor `fbk` and times the output factor `out`; the limits,
    /// stictions and offset times `out` ([`McParams::pid_factors`]).
    pub fn to_eo(&self, fbk: f64, out: f64) -> EoPid {
        let g = out / fbk;
        EoPid {
            kp: (self.kp * g) as f32,
            ki: (self.ki * g) as f32,
            kd: (self.kd * g) as f32,
            kff: self.kff as f32,
            limit_on_integral: (self.max_int * out) as f32,
            limit_on_output: (self.max_output * out) as f32,
            offset: (self.offset * out) as f32,
            stiction_up: (self.stiction_up * out) as f32,
            stiction_down: (self.stiction_down * out) as f32,
            scale: self.scale as i8,
        }
    }

    /// Back from the firmware's PID (the inverse of [`Self::to_eo`], YARP's
    /// `convert_pid_to_user`).
    pub fn from_eo(p: &EoPid, fbk: f64, out: f64) -> Self {
        let g = fbk / out;
        Self {
            kp: f64::from(p.kp) * g,
            ki: f64::from(p.ki) * g,
            kd: f64::from(p.kd) * g,
            kff: f64::from(p.kff),
            max_int: f64::from(p.limit_on_integral) / out,
            max_output: f64::from(p.limit_on_output) / out,
            offset: f64::from(p.offset) / out,
            stiction_up: f64::from(p.stiction_up) / out,
            stiction_down: f64::from(p.stiction_down) / out,
            scale: f64::from(p.scale),
            ..Default::default()
        }
    }
}

/// A motor's temperature sensor (`TemperatureSensorType`; C++ `eomc::ITemperatureSensor`):
/// the board reports the raw reading of its temperature detection board.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TemperatureSensor {
    #[default]
    None,
    Pt100,
    Pt1000,
}

/// The voltage divider bridge of a PT sensor (C++ `TemperatureSensorPT100/PT1000`).
struct Bridge {
    r1: f64,
    r2: f64,
    r3: f64,
    ptc_offset: f64,
    ptc_gradient: f64,
}

const PGA_GAIN: f64 = 2.0;
const VCC: f64 = 5.0;
const RESOLUTION_PGA: f64 = 2.048;
const RESOLUTION_TDB: f64 = 32767.0;

impl Bridge {
    fn celsius_to_raw(&self, t: f64) -> f64 {
        let half = self.r3 / (self.r2 + self.r3);
        let r = self.ptc_offset + self.ptc_gradient * t;
        let tmp = ((r / (self.r1 + r)) - half) * VCC;
        (RESOLUTION_TDB + 1.0) * ((PGA_GAIN * tmp) / RESOLUTION_PGA)
    }

    fn raw_to_celsius(&self, raw: f64) -> f64 {
        let (r1, r2, r3, off) = (self.r1, self.r2, self.r3, self.ptc_offset);
        let first = r1 * r2 + r1 * r3 + off * r2 + off * r3;
        let second = r3 * r1 - r2 * off;
        let tmp = raw * (RESOLUTION_PGA / (PGA_GAIN * VCC * (RESOLUTION_TDB + 1.0)));
        let den = self.ptc_gradient * (r2 - r2 * tmp - r3 * tmp);
        (tmp * first / den) + (second / den)
    }
}

impl TemperatureSensor {
    fn bridge(self) -> Option<Bridge> {
        match self {
            Self::None => None,
            Self::Pt100 => Some(Bridge {
                r1: 4700.0,
                r2: 4700.0,
                r3: 100.0,
                ptc_offset: 100.0,
                ptc_gradient: 0.3851,
            }),
            Self::Pt1000 => Some(Bridge {
                r1: 4700.0,
                r2: 4700.0,
                r3: 1000.0,
                ptc_offset: 1000.0,
                ptc_gradient: 3.851,
            }),
        }
    }

    /// C++ `convertTempCelsiusToRaw` (0 without a sensor).
    pub fn celsius_to_raw(self, celsius: f64) -> f64 {
        self.bridge().map_or(0.0, |b| b.celsius_to_raw(celsius))
    }

    /// C++ `convertRawToTempCelsius` (0 without a sensor).
    pub fn raw_to_celsius(self, raw: f64) -> f64 {
        self.bridge().map_or(0.0, |b| b.raw_to_celsius(raw))
    }
}

/// One encoder of a joint (`JOINTMAPPING/ENCODERx`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EncoderInfo {
    /// `eOmc_encoder_t` (`eomc_enc_none` 0, `aea` 1, `roie` 2, ...).
    pub kind: u8,
    pub resolution: i32,
    pub tolerance: f64,
}

impl EncoderInfo {
    /// No encoder at that position: C++ uses resolution 1, tolerance 0.
    pub const NONE: Self = Self {
        kind: 0,
        resolution: 1,
        tolerance: 0.0,
    };
}

/// `eOmc_encoder_t` values with a default dead zone.
const ENC_AEA: u8 = 1;
const ENC_AMO: u8 = 9;
const ENC_AEA3: u8 = 12;
const ENC_AKSIM2: u8 = 13;

/// C++ `updateDeadZoneWithDefaultValues` (`motionControlDefaultValues.h`), degrees. As in
/// C++, `aksim2` falls through to the `amo` value (a missing `break`).
pub fn default_deadzone(joint_encoder: u8) -> f64 {
    match joint_encoder {
        ENC_AEA => 0.0494,
        ENC_AEA3 => 0.0,
        ENC_AKSIM2 | ENC_AMO => 0.0055,
        _ => 0.0,
    }
}

/// Everything `embObjMotionControl` reads besides the Ethernet groups.
#[derive(Debug, Clone, PartialEq)]
pub struct McParams {
    pub joints: usize,
    /// Logical joint -> board joint (`AxisMap`).
    pub axis_map: Vec<usize>,
    pub axis_names: Vec<String>,
    pub axis_types: Vec<String>,
    /// Encoder units per degree (`Encoder`).
    pub angle_to_encoder: Vec<f64>,
    pub full_scale_pwm: Vec<f64>,
    pub amps_to_sensor: Vec<f64>,
    pub gearbox_m2j: Vec<f64>,
    pub gearbox_e2j: Vec<f64>,
    pub pos_min: Vec<f64>,
    pub pos_max: Vec<f64>,
    pub hw_pos_min: Vec<f64>,
    pub hw_pos_max: Vec<f64>,
    pub vel_max: Vec<f64>,
    pub nominal_current: Vec<f64>,
    pub peak_current: Vec<f64>,
    pub overload_current: Vec<f64>,
    pub pwm_limit: Vec<f64>,
    pub rotor_min: Vec<f64>,
    pub rotor_max: Vec<f64>,
    /// `hardwareTemperatureLimits`, °C (0: none).
    pub hw_temperature_limit: Vec<f64>,
    /// `warningTemperatureLimits`, °C (0: none).
    pub warning_temperature_limit: Vec<f64>,
    pub stiffness: Vec<f64>,
    pub damping: Vec<f64>,
    pub velocity_timeout: Vec<f64>,
    pub current_timeout: Vec<f64>,
    pub pwm_timeout: Vec<f64>,
    pub torque_timeout: Vec<f64>,
    pub torque_fbk_timeout: Vec<f64>,
    pub pos_pids: Vec<Option<PidParams>>,
    pub trq_pids: Vec<Option<PidParams>>,
    pub cur_pids: Vec<Option<PidParams>>,
    pub spd_pids: Vec<Option<PidParams>>,
    /// The encoder `atjoint` of each joint.
    pub joint_encoder: Vec<EncoderInfo>,
    /// The encoder `atmotor` of each joint.
    pub rotor_encoder: Vec<EncoderInfo>,
    /// Degrees (`OTHER_CONTROL_PARAMETERS/deadZone`, else [`default_deadzone`]).
    pub deadzone: Vec<f64>,
    /// Each joint's `KALMAN_FILTER` settings (disabled and zero without the group).
    pub kalman: Vec<KalmanFilterConfig>,
    /// Each motor's `LUGRE` friction model (Km, Kw, S0, S1, Vth, Fc_pos, Fc_neg, Fs_pos,
    /// Fs_neg); without the group Km is -1, which the firmware reads as "no model".
    pub lugre: Vec<[f32; 9]>,
    /// The motor group C++ read (`2FOC`, `AMCBLDC`, `ADVFOC`; `None` for other services).
    pub motor_group: Option<&'static str>,
    pub has_hall_sensor: Vec<bool>,
    pub has_temp_sensor: Vec<bool>,
    pub temperature_sensor: Vec<TemperatureSensor>,
    pub has_rotor_encoder: Vec<bool>,
    pub has_rotor_encoder_index: Vec<bool>,
    pub has_speed_encoder: Vec<bool>,
    pub motor_verbose: Vec<bool>,
    /// The motor group's `Kbemf` (sent as is in the motor config).
    pub motor_kbemf: Vec<f64>,
    pub motor_poles: Vec<f64>,
    /// Degrees in [0, 359], or -1 with `AutoCalibration`.
    pub rotor_index_offset: Vec<f64>,
    pub service: ServiceKind,
}

fn pid_units(g: &Node, name: &str) -> Result<PidUnits, ParamError> {
    let fbk = g.string("fbkControlUnits").ok_or_else(|| {
        ParamError::missing(
            format!("{name}/fbkControlUnits"),
            "metric_units or machine_units",
        )
    })?;
    let out = g.string("outputControlUnits").ok_or_else(|| {
        ParamError::missing(
            format!("{name}/outputControlUnits"),
            "dutycycle_percent or machine_units",
        )
    })?;
    let metric_feedback = match fbk.as_str() {
        "metric_units" => true,
        "machine_units" => false,
        _ => {
            return Err(ParamError::bad(
                format!("{name}/fbkControlUnits"),
                "metric_units or machine_units",
                fbk,
            ))
        }
    };
    let dutycycle_output = match out.as_str() {
        "dutycycle_percent" => true,
        "machine_units" => false,
        _ => {
            return Err(ParamError::bad(
                format!("{name}/outputControlUnits"),
                "dutycycle_percent or machine_units",
                out,
            ))
        }
    };
    Ok(PidUnits {
        metric_feedback,
        dutycycle_output,
    })
}

/// One joint's PID of the group `name`; `low_level` for the current and speed groups
/// (C++ `parsePidsGroup2FOC`, the only ones with `shift`).
fn pid_group(
    root: &Node,
    name: &str,
    j: usize,
    n: usize,
    low_level: bool,
) -> Result<Option<PidParams>, ParamError> {
    let name = name.trim_matches('"');
    if name.eq_ignore_ascii_case("none") || name.is_empty() {
        return Ok(None);
    }
    let Some(g) = root.group(name) else {
        return Err(ParamError::missing(
            format!("CONTROLS -> {name}"),
            "the PID group CONTROLS names",
        ));
    };
    let get = |k: &str| -> Result<f64, ParamError> { Ok(g.numbers(k, n)?.map_or(0.0, |v| v[j])) };
    // optional keys: C++ takes a line of the wrong length as absent
    let opt = |k: &str| -> f64 { g.numbers(k, n).ok().flatten().map_or(0.0, |v| v[j]) };
    Ok(Some(PidParams {
        kp: get("kp")?,
        kd: get("kd")?,
        ki: get("ki")?,
        max_output: get("maxOutput")?,
        max_int: get("maxInt")?,
        stiction_up: if low_level { 0.0 } else { get("stictionUp")? },
        stiction_down: if low_level { 0.0 } else { get("stictionDown")? },
        kff: get("kff")?,
        offset: 0.0,
        scale: if low_level { get("shift")? } else { 0.0 },
        units: pid_units(&g, name)?,
        ktau: get("ktau")?,
        kbemf: opt("kbemf"),
        viscous_pos: opt("viscousPos"),
        viscous_neg: opt("viscousNeg"),
        coulomb_pos: opt("coulombPos"),
        coulomb_neg: opt("coulombNeg"),
        velocity_thres: opt("velocityThres"),
        filter_type: get("filterType")?,
    }))
}

/// The encoders of `JOINTMAPPING` by position (C++ `getEncoderAtJoint/AtMotor`).
fn mapped_encoders(
    root: &Node,
    n: usize,
) -> Result<(Vec<EncoderInfo>, Vec<EncoderInfo>), ParamError> {
    let none = || (vec![EncoderInfo::NONE; n], vec![EncoderInfo::NONE; n]);
    let Some(mapping) = root
        .group("SERVICE")
        .and_then(|s| s.group("PROPERTIES"))
        .and_then(|p| p.group("JOINTMAPPING"))
    else {
        return Ok(none());
    };
    // (type, position, resolution, tolerance) of each joint's ENCODER1 and ENCODER2
    let mut rows = Vec::new();
    for (which, path) in [
        ("ENCODER1", "JOINTMAPPING/ENCODER1"),
        ("ENCODER2", "JOINTMAPPING/ENCODER2"),
    ] {
        let Some(g) = mapping.group(which) else {
            return Ok(none());
        };
        let row = |k: &str| -> Result<Vec<String>, ParamError> {
            let v = g
                .strings(k)
                .ok_or_else(|| ParamError::missing(format!("{path}/{k}"), "one value per joint"))?;
            if v.len() != n {
                return Err(ParamError::bad(
                    format!("{path}/{k}"),
                    "one value per joint",
                    v.join(" "),
                ));
            }
            Ok(v)
        };
        let (kinds, pos, res, tol) = (
            row("type")?,
            row("position")?,
            row("resolution")?,
            row("tolerance")?,
        );
        let mut encs = Vec::with_capacity(n);
        for j in 0..n {
            let kind = super::service_config::encoder_type(&kinds[j]).ok_or_else(|| {
                ParamError::bad(format!("{path}/type"), "an encoder type", kinds[j].clone())
            })?;
            let position = super::service_config::encoder_position(&pos[j]).ok_or_else(|| {
                ParamError::bad(
                    format!("{path}/position"),
                    "a position (atjoint, atmotor, none)",
                    pos[j].clone(),
                )
            })?;
            let num = |v: &String, k: &str| {
                parse_number(v)
                    .ok_or_else(|| ParamError::bad(format!("{path}/{k}"), "a number", v.clone()))
            };
            encs.push((
                position,
                EncoderInfo {
                    kind,
                    // asInt32
                    resolution: num(&res[j], "resolution")? as i32,
                    tolerance: num(&tol[j], "tolerance")?,
                },
            ));
        }
        rows.push(encs);
    }
    let at = |j: usize, p: u8| -> EncoderInfo {
        rows.iter()
            .map(|r| r[j])
            .find(|(pos, _)| *pos == p)
            .map_or(EncoderInfo::NONE, |(_, e)| e)
    };
    Ok((
        (0..n).map(|j| at(j, 1)).collect(),
        (0..n).map(|j| at(j, 2)).collect(),
    ))
}

/// What C++ `parseFocGroup` reads of the motor group.
struct Foc {
    group: Option<&'static str>,
    hall: Vec<bool>,
    temp: Vec<bool>,
    sensor: Vec<TemperatureSensor>,
    rotor_encoder: Vec<bool>,
    rotor_index: Vec<bool>,
    speed_encoder: Vec<bool>,
    verbose: Vec<bool>,
    kbemf: Vec<f64>,
    poles: Vec<f64>,
    index_offset: Vec<f64>,
}

impl Foc {
    /// A service without a FOC group: everything zero (C++ allocates it zeroed).
    fn none(n: usize) -> Self {
        Self {
            group: None,
            hall: vec![false; n],
            temp: vec![false; n],
            sensor: vec![TemperatureSensor::None; n],
            rotor_encoder: vec![false; n],
            rotor_index: vec![false; n],
            speed_encoder: vec![false; n],
            verbose: vec![false; n],
            kbemf: vec![0.0; n],
            poles: vec![0.0; n],
            index_offset: vec![0.0; n],
        }
    }

    /// C++ `fromConfig_Step2`: the group by service and CAN board type, then
    /// `Parser::parseFocGroup`.
    fn read(root: &Node, service: ServiceKind, n: usize) -> Result<Self, ParamError> {
        let name: &'static str = match service.service_type {
            service_type::MC_FOC => {
                let board = root
                    .group("SERVICE")
                    .and_then(|s| s.group("PROPERTIES"))
                    .and_then(|p| p.group("CANBOARDS"))
                    .and_then(|c| c.string("type"))
                    .and_then(|t| can_board_type(&t));
                if board == Some(CAN_FOC) {
                    "2FOC"
                } else {
                    "AMCBLDC"
                }
            }
            service_type::MC_ADVFOC => "ADVFOC",
            _ => return Ok(Self::none(n)),
        };
        let g = root.need_group(name)?;
        let path = |k: &str| format!("{name}/{k}");
        // mandatory: a missing line or one of the wrong length fails (C++ extractGroup)
        let need = |k: &str| -> Result<Vec<f64>, ParamError> { g.need_numbers(k, n) };
        // optional: absent or of the wrong length counts as absent
        let opt = |k: &str| -> Option<Vec<f64>> { g.numbers(k, n).ok().flatten() };
        let flags = |v: Vec<f64>| -> Vec<bool> { v.into_iter().map(|x| x as i32 != 0).collect() };
        let hall = flags(need("HasHallSensor")?);
        let (temp, sensor) = match g.strings("TemperatureSensorType").filter(|v| v.len() == n) {
            Some(types) => types
                .iter()
                .map(|s| match s.as_str() {
                    "PT100" => (true, TemperatureSensor::Pt100),
                    "PT1000" => (true, TemperatureSensor::Pt1000),
                    other => {
                        if other != "NONE" {
                            tracing::warn!(
                                "{}: TemperatureSensorType {other} is not supported, NONE used",
                                path("TemperatureSensorType")
                            );
                        }
                        (false, TemperatureSensor::None)
                    }
                })
                .unzip(),
            None => {
                if let Some(old) = opt("HasTempSensor") {
                    if let Some(v) = old.iter().find(|v| **v as i32 != 0) {
                        return Err(ParamError::bad(
                            path("HasTempSensor"),
                            "0 (HasTempSensor cannot be used alone: use TemperatureSensorType and the LIMITS temperature limits)",
                            v.to_string(),
                        ));
                    }
                }
                (vec![false; n], vec![TemperatureSensor::None; n])
            }
        };
        let rotor_encoder = flags(need("HasRotorEncoder")?);
        let rotor_index = flags(need("HasRotorEncoderIndex")?);
        let verbose = flags(opt("Verbose").unwrap_or_else(|| vec![0.0; n]));
        let autocal = opt("AutoCalibration").unwrap_or_else(|| vec![0.0; n]);
        // read as float32
        let kbemf = opt("Kbemf")
            .unwrap_or_else(|| vec![0.0; n])
            .into_iter()
            .map(|v| f64::from(v as f32))
            .collect();
        let offsets = need("RotorIndexOffset")?;
        let mut index_offset = Vec::with_capacity(n);
        for j in 0..n {
            if autocal[j] as i32 == 0 {
                let o = offsets[j] as i32;
                if !(0..=359).contains(&o) {
                    return Err(ParamError::bad(
                        path("RotorIndexOffset"),
                        "degrees in [0, 359]",
                        offsets[j].to_string(),
                    ));
                }
                index_offset.push(f64::from(o));
            } else {
                tracing::warn!("{}: motor autocalibration of joint {j} is enabled", name);
                index_offset.push(-1.0);
            }
        }
        if let Some(j) = (0..n).find(|j| !rotor_index[*j] && index_offset[*j] != 0.0) {
            return Err(ParamError::bad(
                path("RotorIndexOffset"),
                "0 for a rotor encoder without index (HasRotorEncoderIndex 0)",
                format!("{} (joint {j})", index_offset[j]),
            ));
        }
        let poles = need("MotorPoles")?
            .into_iter()
            .map(|v| f64::from(v as i32))
            .collect();
        let speed_encoder = flags(opt("HasSpeedEncoder").unwrap_or_else(|| vec![0.0; n]));
        Ok(Self {
            group: Some(name),
            hall,
            temp,
            sensor,
            rotor_encoder,
            rotor_index,
            speed_encoder,
            verbose,
            kbemf,
            poles,
            index_offset,
        })
    }
}

/// C++ `Parser::parseTemperatureLimits`: (hardware, warning) °C.
fn temperature_limits(limits: &Node, n: usize) -> Result<(Vec<f64>, Vec<f64>), ParamError> {
    let opt = |k: &str| -> Option<Vec<f64>> { limits.numbers(k, n).ok().flatten() };
    let (hw, warn) = match opt("hardwareTemperatureLimits") {
        None => (vec![0.0; n], vec![0.0; n]),
        Some(hw) => {
            let warn = opt("warningTemperatureLimits").unwrap_or_else(|| vec![0.0; n]);
            (hw, warn)
        }
    };
    if let Some(j) = (0..n).find(|j| warn[*j] > 0.85 * hw[*j]) {
        return Err(ParamError::bad(
            "LIMITS/warningTemperatureLimits",
            "below 85 % of hardwareTemperatureLimits",
            format!("{} (joint {j}, hardware limit {})", warn[j], hw[j]),
        ));
    }
    Ok((hw, warn))
}

/// `KALMAN_FILTER` (C++ `parseKalmanFilterParams`, sent in each joint's config): without
/// the group every joint's filter is disabled and zero; with it, each of its nine lines is
/// needed, one value per joint (C++ fails the device's open otherwise).
fn kalman_filters(root: &Node, n: usize) -> Result<Vec<KalmanFilterConfig>, ParamError> {
    let Some(g) = root.group("KALMAN_FILTER") else {
        return Ok(vec![KalmanFilterConfig::default(); n]);
    };
    let enabled = g.need_strings("kalmanFilterEnabled", n)?;
    let line = |k: &str| g.need_numbers(k, n);
    let (x0, x1, x2) = (line("x0")?, line("x1")?, line("x2")?);
    let (q0, q1, q2) = (line("Q0")?, line("Q1")?, line("Q2")?);
    let (r, p0) = (line("R")?, line("P0")?);
    Ok((0..n)
        .map(|j| KalmanFilterConfig {
            // YARP's asBool: a non-zero number or `true`
            enabled: match enabled[j].trim_matches('"') {
                "true" | "TRUE" | "True" => true,
                other => parse_number(other).is_some_and(|v| v != 0.0),
            },
            x0: [x0[j] as f32, x1[j] as f32, x2[j] as f32],
            q: [q0[j] as f32, q1[j] as f32, q2[j] as f32],
            r: r[j] as f32,
            p0: p0[j] as f32,
        })
        .collect())
}

/// `LUGRE` (C++ `parseLugreGroup`, sent in each motor's config): without the group Km is
/// -1 and the rest 0; with it, each of its nine lines is needed, one value per joint.
fn lugre_models(root: &Node, n: usize) -> Result<Vec<[f32; 9]>, ParamError> {
    let Some(g) = root.group("LUGRE") else {
        let mut none = [0.0; 9];
        none[0] = -1.0;
        return Ok(vec![none; n]);
    };
    let keys = [
        "Km", "Kw", "S0", "S1", "Vth", "Fc_pos", "Fc_neg", "Fs_pos", "Fs_neg",
    ];
    let lines = keys
        .iter()
        .map(|k| g.need_numbers(k, n))
        .collect::<Result<Vec<_>, _>>()?;
    Ok((0..n)
        .map(|j| std::array::from_fn(|k| lines[k][j] as f32))
        .collect())
}

impl McParams {
    /// Reads the parameters (C++ `fromConfig`); errors name the parameter.
    pub fn read(config: &Property) -> Result<Self, ParamError> {
        let root = Node::root(config);
        let general = root.need_group("GENERAL")?;
        let n = general
            .number("Joints")?
            .ok_or_else(|| ParamError::missing("GENERAL/Joints", "the number of joints"))?
            as usize;
        if n == 0 || n > 32 {
            return Err(ParamError::bad("GENERAL/Joints", "1..32", n.to_string()));
        }
        let service = read_service(config)?;
        let per = |g: &Node, k: &str, d: f64| -> Result<Vec<f64>, ParamError> {
            Ok(g.numbers(k, n)?.unwrap_or_else(|| vec![d; n]))
        };
        let axis_map: Vec<usize> = per(&general, "AxisMap", f64::NAN)?
            .iter()
            .enumerate()
            .map(|(j, v)| if v.is_nan() { j } else { *v as usize })
            .collect();
        if let Some(bad) = axis_map.iter().find(|a| **a >= n) {
            return Err(ParamError::bad(
                "GENERAL/AxisMap",
                "board joints below Joints",
                bad.to_string(),
            ));
        }
        let axis_names = general.need_strings("AxisName", n)?;
        let axis_types = general
            .strings("AxisType")
            .filter(|v| v.len() == n)
            .unwrap_or_else(|| vec!["revolute".into(); n]);
        let angle_to_encoder = general.need_numbers("Encoder", n)?;
        let limits = root.need_group("LIMITS")?;
        let pos_max = limits.need_numbers("jntPosMax", n)?;
        let pos_min = limits.need_numbers("jntPosMin", n)?;
        let hw_pos_max = per(&limits, "hardwareJntPosMax", 0.0)?;
        let hw_pos_min = per(&limits, "hardwareJntPosMin", 0.0)?;
        let (hw_temperature_limit, warning_temperature_limit) = temperature_limits(&limits, n)?;
        let empty = Property::new();
        let empty_root = Node::root(&empty);
        let opt = |name: &'static str| root.group(name).unwrap_or(empty_root);
        let imp = opt("IMPEDANCE");
        let tmo = opt("TIMEOUTS");
        let controls = root.group("CONTROLS");
        let pids = |k: &str, low_level: bool| -> Result<Vec<Option<PidParams>>, ParamError> {
            let names = controls.and_then(|c| c.strings(k)).unwrap_or_default();
            (0..n)
                .map(|j| match names.get(j) {
                    Some(name) => pid_group(&root, name, j, n, low_level),
                    None => Ok(None),
                })
                .collect()
        };
        let (joint_encoder, rotor_encoder) = mapped_encoders(&root, n)?;
        // OTHER_CONTROL_PARAMETERS/deadZone, else the default of the joint encoder
        let deadzone = root
            .group("OTHER_CONTROL_PARAMETERS")
            .and_then(|g| g.numbers("deadZone", n).ok().flatten())
            .unwrap_or_else(|| {
                joint_encoder
                    .iter()
                    .map(|e| default_deadzone(e.kind))
                    .collect()
            });
        let kalman = kalman_filters(&root, n)?;
        let lugre = lugre_models(&root, n)?;
        let foc = Foc::read(&root, service, n)?;
        // C++: a joint with a temperature sensor needs both temperature limits
        if let Some(j) = (0..n).find(|j| {
            foc.sensor[*j] != TemperatureSensor::None
                && (hw_temperature_limit[*j] == 0.0 || warning_temperature_limit[*j] == 0.0)
        }) {
            return Err(ParamError::bad(
                "LIMITS/hardwareTemperatureLimits",
                "non-zero hardware and warning temperature limits for a joint with a TemperatureSensorType",
                format!(
                    "{} and {} (joint {j})",
                    hw_temperature_limit[j], warning_temperature_limit[j]
                ),
            ));
        }
        // C++: "in this case the default timeout is 300 ms because there is some lag in AMC"
        let timeout = if service.service_type == service_type::MC_ADVFOC {
            300.0
        } else {
            100.0
        };
        // TIMEOUTS lines of the wrong length count as absent (C++ extractGroup)
        let tmo_of = |k: &str| -> Vec<f64> {
            tmo.numbers(k, n)
                .ok()
                .flatten()
                .unwrap_or_else(|| vec![timeout; n])
        };
        Ok(Self {
            joints: n,
            axis_map,
            axis_names,
            axis_types,
            angle_to_encoder,
            full_scale_pwm: per(&general, "fullscalePWM", 32000.0)?,
            amps_to_sensor: per(&general, "ampsToSensor", 1000.0)?,
            gearbox_m2j: per(&general, "Gearbox_M2J", 1.0)?,
            gearbox_e2j: per(&general, "Gearbox_E2J", 1.0)?,
            pos_min,
            pos_max,
            hw_pos_min,
            hw_pos_max,
            vel_max: per(&limits, "jntVelMax", 0.0)?,
            nominal_current: per(&limits, "motorNominalCurrents", 0.0)?,
            peak_current: per(&limits, "motorPeakCurrents", 0.0)?,
            overload_current: per(&limits, "motorOverloadCurrents", 0.0)?,
            pwm_limit: per(&limits, "motorPwmLimit", 0.0)?,
            rotor_min: per(&limits, "rotorPosMin", 0.0)?,
            rotor_max: per(&limits, "rotorPosMax", 0.0)?,
            hw_temperature_limit,
            warning_temperature_limit,
            stiffness: per(&imp, "stiffness", 0.0)?,
            damping: per(&imp, "damping", 0.0)?,
            velocity_timeout: tmo_of("velocity"),
            current_timeout: tmo_of("current"),
            pwm_timeout: tmo_of("pwm"),
            torque_timeout: tmo_of("torque"),
            torque_fbk_timeout: tmo_of("torque_measure"),
            pos_pids: pids("positionControl", false)?,
            trq_pids: pids("torqueControl", false)?,
            cur_pids: pids("currentPid", true)?,
            spd_pids: pids("speedPid", true)?,
            joint_encoder,
            rotor_encoder,
            deadzone,
            kalman,
            lugre,
            motor_group: foc.group,
            has_hall_sensor: foc.hall,
            has_temp_sensor: foc.temp,
            temperature_sensor: foc.sensor,
            has_rotor_encoder: foc.rotor_encoder,
            has_rotor_encoder_index: foc.rotor_index,
            has_speed_encoder: foc.speed_encoder,
            motor_verbose: foc.verbose,
            motor_kbemf: foc.kbemf,
            motor_poles: foc.poles,
            rotor_index_offset: foc.index_offset,
            service,
        })
    }

    /// Encoder units per degree of joint `j` (1 when not given or 0).
    pub fn a2e(&self, j: usize) -> f64 {
        self.angle_to_encoder
            .get(j)
            .copied()
            .filter(|f| *f != 0.0)
            .unwrap_or(1.0)
    }

    /// PWM counts per duty-cycle percent of joint `j` (C++ `dutycycleToPWM`,
    /// `fullscalePWM / 100`).
    pub fn dutycycle_to_pwm(&self, j: usize) -> f64 {
        self.full_scale_pwm.get(j).copied().unwrap_or(32000.0) / 100.0
    }

    /// The units of a kind of PID on this board: joint 0's group's (C++ passes
    /// `_trj_pids->fbk_PidUnits`, i.e. element 0, for every joint); machine units when
    /// joint 0 has no such PID.
    pub fn pid_units(&self, kind: PidKind) -> PidUnits {
        let pids = match kind {
            PidKind::Position => &self.pos_pids,
            PidKind::Velocity => &self.spd_pids,
            PidKind::Torque => &self.trq_pids,
            PidKind::Current => &self.cur_pids,
        };
        pids.first()
            .copied()
            .flatten()
            .map(|p| p.units)
            .unwrap_or_default()
    }

    /// (feedback, output) factors of joint `j`'s PID of a kind, user to machine (YARP's
    /// `get_pid_conversion_factors`): metric feedback is per degree (position, velocity:
    /// `Encoder`), per N·m (torque: [`NEWTONS_TO_SENSOR`]) or per A (current:
    /// `ampsToSensor`); a `dutycycle_percent` output is `fullscalePWM / 100` counts per %.
    pub fn pid_factors(&self, kind: PidKind, j: usize) -> (f64, f64) {
        let u = self.pid_units(kind);
        let fbk = if u.metric_feedback {
            match kind {
                PidKind::Position | PidKind::Velocity => self.a2e(j),
                PidKind::Torque => NEWTONS_TO_SENSOR,
                PidKind::Current => self
                    .amps_to_sensor
                    .get(j)
                    .copied()
                    .filter(|f| *f != 0.0)
                    .unwrap_or(1.0),
            }
        } else {
            1.0
        };
        let out = if u.dutycycle_output {
            self.dutycycle_to_pwm(j)
        } else {
            1.0
        };
        (fbk, if out != 0.0 { out } else { 1.0 })
    }

    /// C++ `ktau2raw`: `dutycycleToPWM / newtonsToSensor` when the torque PIDs' output is
    /// `dutycycle_percent`, else `1 / newtonsToSensor`.
    pub fn ktau_to_raw(&self, j: usize) -> f64 {
        if self.pid_units(PidKind::Torque).dutycycle_output {
            self.dutycycle_to_pwm(j) / NEWTONS_TO_SENSOR
        } else {
            1.0 / NEWTONS_TO_SENSOR
        }
    }

    /// C++ `bemf2raw`: `newtonsToSensor / angleToEncoder`.
    pub fn bemf_to_raw(&self, j: usize) -> f64 {
        NEWTONS_TO_SENSOR / self.a2e(j)
    }

    /// YARP `impN2S`: stiffness (N·m/deg) or damping (N·m/(deg/s)) to the board's µN·m
    /// per encoder unit.
    pub fn imp_to_raw(&self, j: usize, v: f64) -> f64 {
        v * NEWTONS_TO_SENSOR / self.a2e(j)
    }

    /// The inverse of [`Self::imp_to_raw`] (YARP `impS2N`).
    pub fn imp_from_raw(&self, j: usize, raw: f64) -> f64 {
        raw * self.a2e(j) / NEWTONS_TO_SENSOR
    }

    /// The motor config's `temperatureLimit` of joint `j`: C++
    /// `S_16(convertTempCelsiusToRaw(hardwareTemperatureLimit))`.
    pub fn temperature_limit_raw(&self, j: usize) -> i16 {
        s16(self.temperature_sensor[j].celsius_to_raw(self.hw_temperature_limit[j]))
    }
}

/// C++ `S_32` (eomcUtils): saturated to i32, rounded half away from zero.
pub fn s32(x: f64) -> i32 {
    if x.is_nan() {
        return 0;
    }
    x.round() as i32
}

/// C++ `S_16` (eomcUtils): saturated to i16, rounded half away from zero.
pub fn s16(x: f64) -> i16 {
    if x.is_nan() {
        return 0;
    }
    x.round() as i16
}
