//! The motion-control parameters of `embObjMotionControl` (icub-main `eomcParser`), as
//! robots-configuration's `*-mc.xml` and the files it includes write them:
//!
//! - `GENERAL` (mechanicals): `Joints`, `AxisMap`, `AxisName`, `AxisType`, `Encoder`
//!   (angle to encoder units), `fullscalePWM`, `ampsToSensor`, `Gearbox_M2J`,
//!   `Gearbox_E2J`;
//! - `LIMITS`: `jntPosMax/Min`, `hardwareJntPosMax/Min`, `jntVelMax`,
//!   `motorNominalCurrents`, `motorPeakCurrents`, `motorOverloadCurrents`,
//!   `motorPwmLimit`, `rotorPosMin/Max`;
//! - `CONTROLS`: per joint, the group of each PID (`positionControl`, `torqueControl`,
//!   `currentPid`, `speedPid`; `none` for none) with `kp kd ki maxOutput maxInt
//!   stictionUp stictionDown kff` (+ `ko`, `ktau`, `fbkControlUnits`), one value per joint;
//! - `IMPEDANCE` (`stiffness`, `damping`), `TIMEOUTS` (`velocity`, `current`, `pwm`,
//!   `torque`, `torqueMeasures`; 100 ms by default), `2FOC` (motor sensors, poles);
//! - `SERVICE/PROPERTIES/JOINTMAPPING`: `ENCODER1`/`ENCODER2` `resolution` and
//!   `tolerance`.

use icub_eth::entities::mc::Pid as EoPid;
use yarp_proto::Property;

use super::config::{Node, ParamError};
use super::params::{read_service, ServiceKind};

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
    /// `fbkControlUnits metric_units`: gains per degree (converted per encoder unit).
    pub metric_feedback: bool,
    /// `ktau` (torque PIDs).
    pub ktau: f64,
    pub viscous_pos: f64,
    pub viscous_neg: f64,
    pub coulomb_pos: f64,
    pub coulomb_neg: f64,
    pub velocity_thres: f64,
    pub filter_type: f64,
}

impl PidParams {
    /// The firmware's PID (machine units): metric gains divided by `factor`.
    pub fn to_eo(&self, factor: f64) -> EoPid {
        let f = if self.metric_feedback && factor != 0.0 {
            factor
        } else {
            1.0
        };
        EoPid {
            kp: (self.kp / f) as f32,
            ki: (self.ki / f) as f32,
            kd: (self.kd / f) as f32,
            kff: self.kff as f32,
            limit_on_integral: self.max_int as f32,
            limit_on_output: self.max_output as f32,
            offset: self.offset as f32,
            stiction_up: self.stiction_up as f32,
            stiction_down: self.stiction_down as f32,
            scale: self.scale as i8,
        }
    }

    /// Back from the firmware's PID (the inverse of [`Self::to_eo`]).
    pub fn from_eo(p: &EoPid, metric_feedback: bool, factor: f64) -> Self {
        let f = if metric_feedback && factor != 0.0 {
            factor
        } else {
            1.0
        };
        Self {
            kp: f64::from(p.kp) * f,
            ki: f64::from(p.ki) * f,
            kd: f64::from(p.kd) * f,
            kff: f64::from(p.kff),
            max_int: f64::from(p.limit_on_integral),
            max_output: f64::from(p.limit_on_output),
            offset: f64::from(p.offset),
            stiction_up: f64::from(p.stiction_up),
            stiction_down: f64::from(p.stiction_down),
            scale: f64::from(p.scale),
            metric_feedback,
            ..Default::default()
        }
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
    pub joint_encoder_resolution: Vec<f64>,
    pub joint_encoder_tolerance: Vec<f64>,
    pub rotor_encoder_resolution: Vec<f64>,
    pub rotor_encoder_tolerance: Vec<f64>,
    pub has_hall_sensor: Vec<bool>,
    pub has_temp_sensor: Vec<bool>,
    pub has_rotor_encoder: Vec<bool>,
    pub has_rotor_encoder_index: Vec<bool>,
    pub has_speed_encoder: Vec<bool>,
    pub motor_poles: Vec<f64>,
    pub rotor_index_offset: Vec<f64>,
    pub service: ServiceKind,
}

fn pid_group(root: &Node, name: &str, j: usize, n: usize) -> Result<Option<PidParams>, ParamError> {
    let name = name.trim_matches('"');
    if name.eq_ignore_ascii_case("none") || name.is_empty() {
        return Ok(None);
    }
    let Some(g) = root.group(leak(name)) else {
        return Err(ParamError::missing(
            format!("CONTROLS -> {name}"),
            "the PID group CONTROLS names",
        ));
    };
    let get = |k: &str| -> Result<f64, ParamError> { Ok(g.numbers(k, n)?.map_or(0.0, |v| v[j])) };
    Ok(Some(PidParams {
        kp: get("kp")?,
        kd: get("kd")?,
        ki: get("ki")?,
        max_output: get("maxOutput")?,
        max_int: get("maxInt")?,
        stiction_up: get("stictionUp")?,
        stiction_down: get("stictionDown")?,
        kff: get("kff")?,
        offset: get("ko")?,
        scale: get("shift")?,
        metric_feedback: g.string("fbkControlUnits").as_deref() == Some("metric_units"),
        ktau: get("ktau")?,
        viscous_pos: get("viscousPos")?,
        viscous_neg: get("viscousNeg")?,
        coulomb_pos: get("coulombPos")?,
        coulomb_neg: get("coulombNeg")?,
        velocity_thres: get("velocityThres")?,
        filter_type: get("filterType")?,
    }))
}

/// Group names must live as long as the configuration for [`Node::group`]; the few PID
/// group names of a robot are interned once.
fn leak(name: &str) -> &'static str {
    use std::collections::HashSet;
    use std::sync::{Mutex, OnceLock};
    static NAMES: OnceLock<Mutex<HashSet<&'static str>>> = OnceLock::new();
    let mut set = NAMES
        .get_or_init(|| Mutex::new(HashSet::new()))
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    if let Some(s) = set.get(name) {
        return s;
    }
    let s: &'static str = Box::leak(name.to_string().into_boxed_str());
    set.insert(s);
    s
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
        let empty = Property::new();
        let empty_root = Node::root(&empty);
        let opt = |name: &'static str| root.group(name).unwrap_or(empty_root);
        let imp = opt("IMPEDANCE");
        let tmo = opt("TIMEOUTS");
        let foc = opt("2FOC");
        let flags = |k: &str| -> Result<Vec<bool>, ParamError> {
            Ok(per(&foc, k, 0.0)?.into_iter().map(|v| v != 0.0).collect())
        };
        let controls = root.group("CONTROLS");
        let pids = |k: &str| -> Result<Vec<Option<PidParams>>, ParamError> {
            let names = controls.and_then(|c| c.strings(k)).unwrap_or_default();
            (0..n)
                .map(|j| match names.get(j) {
                    Some(name) => pid_group(&root, name, j, n),
                    None => Ok(None),
                })
                .collect()
        };
        let mapping = root
            .group("SERVICE")
            .and_then(|s| s.group("PROPERTIES"))
            .and_then(|p| p.group("JOINTMAPPING"));
        let enc = |which: &'static str, k: &str| -> Vec<f64> {
            mapping
                .and_then(|m| m.group(which))
                .and_then(|e| e.numbers(k, n).ok().flatten())
                .unwrap_or_else(|| vec![0.0; n])
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
            stiffness: per(&imp, "stiffness", 0.0)?,
            damping: per(&imp, "damping", 0.0)?,
            velocity_timeout: per(&tmo, "velocity", 100.0)?,
            current_timeout: per(&tmo, "current", 100.0)?,
            pwm_timeout: per(&tmo, "pwm", 100.0)?,
            torque_timeout: per(&tmo, "torque", 100.0)?,
            torque_fbk_timeout: per(&tmo, "torqueMeasures", 100.0)?,
            pos_pids: pids("positionControl")?,
            trq_pids: pids("torqueControl")?,
            cur_pids: pids("currentPid")?,
            spd_pids: pids("speedPid")?,
            joint_encoder_resolution: enc("ENCODER1", "resolution"),
            joint_encoder_tolerance: enc("ENCODER1", "tolerance"),
            rotor_encoder_resolution: enc("ENCODER2", "resolution"),
            rotor_encoder_tolerance: enc("ENCODER2", "tolerance"),
            has_hall_sensor: flags("HasHallSensor")?,
            has_temp_sensor: flags("HasTempSensor")?,
            has_rotor_encoder: flags("HasRotorEncoder")?,
            has_rotor_encoder_index: flags("HasRotorEncoderIndex")?,
            has_speed_encoder: flags("HasSpeedEncoder")?,
            motor_poles: per(&foc, "MotorPoles", 0.0)?,
            rotor_index_offset: per(&foc, "RotorIndexOffset", 0.0)?,
            service: read_service(config)?,
        })
    }
}
