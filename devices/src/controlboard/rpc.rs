//! The control-board RPC protocol served on `/<name>/rpc:i` (C++ `RPCMessagesParser`),
//! as a pure function of the command and the device: `handle_rpc`.
//!
//! Replies: `set` commands answer `[ok]`/`[fail]`; most `get` commands answer
//! `[is] <echoed token> <value> [tsta] <count> <time> [ok]`; commands shorter than two
//! elements answer `[nak]`; anything not understood (or failing) answers `[fail]`.

use crate::driver::DeviceDriver;
use crate::vocabs::*;
use std::time::{SystemTime, UNIX_EPOCH};
use yarp_proto::{Bottle, Stamp, Value, Vocab32};

/// The control-board protocol version this server speaks (`[get] [prot]`), as C++ 3.12.
pub const PROTOCOL_VERSION_NUMBER: (i32, i32, i32) = (1, 9, 0);

/// The stamp appended to `get` replies; its count increases with each one.
#[derive(Debug, Default, Clone)]
pub struct RpcStamp {
    next: i32,
}

impl RpcStamp {
    pub fn new() -> Self {
        Self::default()
    }
    /// Next stamp with the current wall-clock time.
    pub fn update(&mut self) -> Stamp {
        let t = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map(|d| d.as_secs_f64())
            .unwrap_or(0.0);
        let s = Stamp::new(self.next, t);
        self.next = self.next.wrapping_add(1);
        s
    }
}

/// C++ `Value::asVocab32`: vocabs, and strings (packed) as in `get axes`.
pub(super) fn vocab(v: Option<&Value>) -> i32 {
    match v {
        Some(Value::Vocab32(x)) => x.0,
        Some(Value::String(s)) => Vocab32::encode(s).0,
        _ => 0,
    }
}

fn int(cmd: &Bottle, i: usize) -> i32 {
    cmd.get(i).and_then(Value::as_i32).unwrap_or(0)
}
fn joint(cmd: &Bottle, i: usize) -> Option<usize> {
    usize::try_from(int(cmd, i)).ok()
}
fn float(cmd: &Bottle, i: usize) -> f64 {
    cmd.get(i).and_then(Value::as_f64).unwrap_or(0.0)
}
fn floats(cmd: &Bottle, i: usize) -> Option<Vec<f64>> {
    Some(
        cmd.get(i)?
            .as_list()?
            .iter()
            .map(|v| v.as_f64().unwrap_or(0.0))
            .collect(),
    )
}
fn joints(cmd: &Bottle, i: usize) -> Option<Vec<usize>> {
    cmd.get(i)?
        .as_list()?
        .iter()
        .map(|v| v.as_i64().and_then(|x| usize::try_from(x).ok()))
        .collect()
}
/// `n (joints) (values)` group arguments with matching sizes.
fn group(cmd: &Bottle, i: usize) -> Option<(Vec<usize>, Vec<f64>)> {
    let n = usize::try_from(int(cmd, i)).ok()?;
    let js = joints(cmd, i + 1)?;
    let vs = floats(cmd, i + 2)?;
    (js.len() == n && vs.len() == n).then_some((js, vs))
}
fn float_list(v: &[f64]) -> Value {
    Value::List(v.iter().copied().collect())
}
fn vocab_list(v: &[Vocab32]) -> Value {
    Value::List(v.iter().copied().collect())
}
fn stamp_into(resp: &mut Bottle, stamp: &mut RpcStamp) {
    let s = stamp.update();
    resp.push(Vocab32(TIMESTAMP)).push(s.count).push(s.time);
}

/// Serves one control-board RPC command against `dev` and returns the reply.
///
/// Malformed commands (wrong arity or types) and commands the device cannot serve get
/// `[fail]` (or `[nak]` when shorter than two elements), as in C++, plus a log line.
pub fn handle_rpc(cmd: &Bottle, dev: &mut dyn DeviceDriver, stamp: &mut RpcStamp) -> Bottle {
    let mut resp = Bottle::new();
    if cmd.len() < 2 {
        tracing::warn!("controlBoard rpc: `{cmd}` is too short: replying [nak]");
        resp.push(Vocab32(NAK));
        return resp;
    }
    if vocab(cmd.get(0)) == GET && vocab(cmd.get(1)) == PROTOCOL_VERSION {
        let (major, minor, tweak) = PROTOCOL_VERSION_NUMBER;
        resp.push(Vocab32(PROTOCOL_VERSION))
            .push(major)
            .push(minor)
            .push(tweak)
            .push(Vocab32(OK));
        return resp;
    }
    let ok = dispatch(cmd, dev, stamp, &mut resp).unwrap_or(false);
    if ok {
        resp.push(Vocab32(OK));
    } else {
        tracing::warn!("controlBoard rpc: cannot serve `{cmd}` (unknown, malformed or refused by the device): replying [fail]");
        resp.clear();
        resp.push(Vocab32(FAILED));
    }
    resp
}

/// `None` or `Some(false)`: failed / not understood.
fn dispatch(
    cmd: &Bottle,
    dev: &mut dyn DeviceDriver,
    stamp: &mut RpcStamp,
    resp: &mut Bottle,
) -> Option<bool> {
    let action = vocab(cmd.get(0));
    let family = vocab(cmd.get(1));
    match family {
        TORQUE => return torque(cmd, action, dev, stamp, resp),
        INTERACTION_MODE_IFACE => return interaction(cmd, action, dev, stamp, resp),
        PID => return pid(cmd, action, dev, resp),
        IMPEDANCE => return impedance(cmd, action, dev, stamp, resp),
        REMOTE_CALIBRATOR_IFACE => return remote_calibrator(cmd, action, dev, resp),
        // references are set on command:i only; no timestamp in these replies
        CURRENT_IFACE | PWM_IFACE if action == GET => {
            resp.push(Vocab32(IS)).push(cmd[1].clone());
            return open_loop(cmd, family, dev, resp);
        }
        CURRENT_IFACE | PWM_IFACE => return Some(false),
        _ => {}
    }
    match action {
        CALIBRATE_JOINT | CALIBRATE_JOINT_PARAMS | CALIBRATE | CALIBRATE_DONE | PARK => {
            calibration(cmd, action, dev)
        }
        SET => set(cmd, dev).map(|r| r.is_some()),
        GET => {
            resp.push(Vocab32(IS));
            if family == ICONTROLMODE {
                // C++: `[is] <axis> <mode>` for one joint, `[is] [cmds]|[cmog] ...` else
                match vocab(cmd.get(2)) {
                    CM_CONTROL_MODE => resp.push(int(cmd, 3)),
                    v => resp.push(Vocab32(v)),
                };
            } else {
                resp.push(cmd[1].clone());
            }
            get(cmd, dev, resp)?;
            stamp_into(resp, stamp);
            Some(true)
        }
        _ => Some(false),
    }
}

fn set(cmd: &Bottle, dev: &mut dyn DeviceDriver) -> Option<Option<()>> {
    let r = match vocab(cmd.get(1)) {
        POSITION_MOVE => dev
            .as_position_control()?
            .position_move(joint(cmd, 2)?, float(cmd, 3)),
        POSITION_MOVES => dev.as_position_control()?.position_moves(&floats(cmd, 2)?),
        POSITION_MOVE_GROUP => {
            let (js, vs) = group(cmd, 2)?;
            dev.as_position_control()?.position_move_group(&js, &vs)
        }
        RELATIVE_MOVE => dev
            .as_position_control()?
            .relative_move(joint(cmd, 2)?, float(cmd, 3)),
        RELATIVE_MOVES => dev.as_position_control()?.relative_moves(&floats(cmd, 2)?),
        RELATIVE_MOVE_GROUP => {
            let (js, vs) = group(cmd, 2)?;
            dev.as_position_control()?.relative_move_group(&js, &vs)
        }
        REF_SPEED => dev
            .as_position_control()?
            .set_ref_speed(joint(cmd, 2)?, float(cmd, 3)),
        REF_SPEEDS => dev.as_position_control()?.set_ref_speeds(&floats(cmd, 2)?),
        REF_SPEED_GROUP => {
            let (js, vs) = group(cmd, 2)?;
            dev.as_position_control()?.set_ref_speed_group(&js, &vs)
        }
        REF_ACCELERATION => dev
            .as_position_control()?
            .set_ref_acceleration(joint(cmd, 2)?, float(cmd, 3)),
        REF_ACCELERATIONS => dev
            .as_position_control()?
            .set_ref_accelerations(&floats(cmd, 2)?),
        REF_ACCELERATION_GROUP => {
            let (js, vs) = group(cmd, 2)?;
            dev.as_position_control()?
                .set_ref_acceleration_group(&js, &vs)
        }
        STOP => dev.as_position_control()?.stop(joint(cmd, 2)?),
        STOPS => dev.as_position_control()?.stops(),
        STOP_GROUP => {
            let n = usize::try_from(int(cmd, 2)).ok()?;
            let js = joints(cmd, 3)?;
            if js.len() != n {
                return None;
            }
            dev.as_position_control()?.stop_group(&js)
        }
        // single-joint velocity moves only travel on command:i in C++
        VELOCITY_MOVES => dev.as_velocity_control()?.velocity_moves(&floats(cmd, 2)?),
        E_RESET => dev.as_encoders()?.reset_encoder(joint(cmd, 2)?),
        MOTOR_CPR => dev
            .as_motor_encoders()?
            .set_motor_encoder_counts_per_revolution(joint(cmd, 2)?, float(cmd, 3)),
        E_RESETS => dev.as_encoders()?.reset_encoders(),
        ENCODER => dev
            .as_encoders()?
            .set_encoder(joint(cmd, 2)?, float(cmd, 3)),
        ENCODERS => dev.as_encoders()?.set_encoders(&floats(cmd, 2)?),
        LIMITS => dev
            .as_control_limits()?
            .set_limits(joint(cmd, 2)?, float(cmd, 3), float(cmd, 4)),
        VEL_LIMITS => {
            dev.as_control_limits()?
                .set_vel_limits(joint(cmd, 2)?, float(cmd, 3), float(cmd, 4))
        }
        AMP_ENABLE => dev.as_amplifier_control()?.enable_amp(joint(cmd, 2)?),
        AMP_DISABLE => dev.as_amplifier_control()?.disable_amp(joint(cmd, 2)?),
        AMP_MAXCURRENT => dev
            .as_amplifier_control()?
            .set_max_current(joint(cmd, 2)?, float(cmd, 3)),
        AMP_NOMINAL_CURRENT => dev
            .as_amplifier_control()?
            .set_nominal_current(joint(cmd, 2)?, float(cmd, 3)),
        AMP_PEAK_CURRENT => dev
            .as_amplifier_control()?
            .set_peak_current(joint(cmd, 2)?, float(cmd, 3)),
        AMP_PWM_LIMIT => dev
            .as_amplifier_control()?
            .set_pwm_limit(joint(cmd, 2)?, float(cmd, 3)),
        TEMPERATURE_LIMIT => dev
            .as_motor()?
            .set_temperature_limit(joint(cmd, 2)?, float(cmd, 3)),
        GEARBOX_RATIO => dev
            .as_motor()?
            .set_gearbox_ratio(joint(cmd, 2)?, float(cmd, 3)),
        ICONTROLMODE => {
            let cm = dev.as_control_mode()?;
            let modes = |i: usize| -> Option<Vec<Vocab32>> {
                Some(
                    cmd.get(i)?
                        .as_list()?
                        .iter()
                        .map(|v| Vocab32(vocab(Some(v))))
                        .collect(),
                )
            };
            match vocab(cmd.get(2)) {
                CM_CONTROL_MODE => cm.set_control_mode(joint(cmd, 3)?, Vocab32(vocab(cmd.get(4)))),
                CM_CONTROL_MODES => cm.set_control_modes(&modes(3)?),
                CM_CONTROL_MODE_GROUP => {
                    let n = usize::try_from(int(cmd, 3)).ok()?;
                    let js = joints(cmd, 4)?;
                    let ms = modes(5)?;
                    if js.len() != n || ms.len() != n {
                        return None;
                    }
                    cm.set_control_modes_group(&js, &ms)
                }
                _ => return None,
            }
        }
        _ => return None,
    };
    // The reply is a bare [fail] (as C++): the log says why.
    if let Err(e) = &r {
        tracing::warn!("controlBoard rpc: `{cmd}` refused by the device: {e}");
    }
    Some(r.ok())
}

fn get(cmd: &Bottle, dev: &mut dyn DeviceDriver, resp: &mut Bottle) -> Option<()> {
    let _ = match vocab(cmd.get(1)) {
        AXES => {
            let n = dev.as_encoders()?.get_axes().ok()?;
            resp.push(n as i32)
        }
        ENCODER => resp.push(dev.as_encoders()?.get_encoder(joint(cmd, 2)?).ok()?),
        ENCODERS => resp.push(float_list(&dev.as_encoders()?.get_encoders().ok()?)),
        ENCODER_SPEED => resp.push(dev.as_encoders()?.get_encoder_speed(joint(cmd, 2)?).ok()?),
        ENCODER_SPEEDS => resp.push(float_list(&dev.as_encoders()?.get_encoder_speeds().ok()?)),
        ENCODER_ACCELERATION => resp.push(
            dev.as_encoders()?
                .get_encoder_acceleration(joint(cmd, 2)?)
                .ok()?,
        ),
        ENCODER_ACCELERATIONS => resp.push(float_list(
            &dev.as_encoders()?.get_encoder_accelerations().ok()?,
        )),
        MOTION_DONE => {
            let d = dev
                .as_position_control()?
                .check_motion_done(joint(cmd, 2)?)
                .ok()?;
            resp.push(i32::from(d))
        }
        MOTION_DONES => {
            let d = dev.as_position_control()?.check_motion_dones().ok()?;
            resp.push(i32::from(d))
        }
        MOTION_DONE_GROUP => {
            let js = joints(cmd, 3)?;
            let d = dev
                .as_position_control()?
                .check_motion_done_group(&js)
                .ok()?;
            resp.push(i32::from(d))
        }
        POSITION_MOVE => resp.push(
            dev.as_position_control()?
                .get_target_position(joint(cmd, 2)?)
                .ok()?,
        ),
        POSITION_MOVES => resp.push(float_list(
            &dev.as_position_control()?.get_target_positions().ok()?,
        )),
        POSITION_MOVE_GROUP => {
            let js = joints(cmd, 3)?;
            let v = dev
                .as_position_control()?
                .get_target_position_group(&js)
                .ok()?;
            resp.push(float_list(&v))
        }
        REF_SPEED => resp.push(
            dev.as_position_control()?
                .get_ref_speed(joint(cmd, 2)?)
                .ok()?,
        ),
        REF_SPEEDS => resp.push(float_list(
            &dev.as_position_control()?.get_ref_speeds().ok()?,
        )),
        REF_ACCELERATION => resp.push(
            dev.as_position_control()?
                .get_ref_acceleration(joint(cmd, 2)?)
                .ok()?,
        ),
        REF_SPEED_GROUP => {
            let js = joints(cmd, 3)?;
            resp.push(float_list(
                &dev.as_position_control()?.get_ref_speed_group(&js).ok()?,
            ))
        }
        REF_ACCELERATION_GROUP => {
            let js = joints(cmd, 3)?;
            resp.push(float_list(
                &dev.as_position_control()?
                    .get_ref_acceleration_group(&js)
                    .ok()?,
            ))
        }
        VELOCITY_MOVE_GROUP => {
            let js = joints(cmd, 3)?;
            let v = dev.as_velocity_control()?;
            let refs = js
                .iter()
                .map(|&j| v.get_ref_velocity(j))
                .collect::<Result<Vec<_>, _>>();
            resp.push(float_list(&refs.ok()?))
        }
        MOTOR_CPR => resp.push(
            dev.as_motor_encoders()?
                .get_motor_encoder_counts_per_revolution(joint(cmd, 2)?)
                .ok()?,
        ),
        REF_ACCELERATIONS => resp.push(float_list(
            &dev.as_position_control()?.get_ref_accelerations().ok()?,
        )),
        VELOCITY_MOVE => resp.push(
            dev.as_velocity_control()?
                .get_ref_velocity(joint(cmd, 2)?)
                .ok()?,
        ),
        VELOCITY_MOVES => resp.push(float_list(
            &dev.as_velocity_control()?.get_ref_velocities().ok()?,
        )),
        LIMITS => {
            let (a, b) = dev.as_control_limits()?.get_limits(joint(cmd, 2)?).ok()?;
            resp.push(a).push(b)
        }
        VEL_LIMITS => {
            let (a, b) = dev
                .as_control_limits()?
                .get_vel_limits(joint(cmd, 2)?)
                .ok()?;
            resp.push(a).push(b)
        }
        INFO_NAME => {
            let n = dev.as_axis_info()?.get_axis_name(joint(cmd, 2)?).ok()?;
            resp.push(n)
        }
        INFO_TYPE => {
            let t = dev.as_axis_info()?.get_joint_type(joint(cmd, 2)?).ok()?;
            resp.push(t.0)
        }
        MOTOR_ENCODER_NUMBER => {
            let n = dev.as_motor_encoders()?.get_num_of_motor_encoders().ok()?;
            resp.push(n as i32)
        }
        MOTOR_ENCODER => resp.push(
            dev.as_motor_encoders()?
                .get_motor_encoder(joint(cmd, 2)?)
                .ok()?,
        ),
        MOTOR_ENCODERS => resp.push(float_list(
            &dev.as_motor_encoders()?.get_motor_encoders().ok()?,
        )),
        AMP_STATUS => {
            let s = dev.as_amplifier_control()?.get_amp_statuses().ok()?;
            resp.push(Value::List(s.into_iter().collect()))
        }
        AMP_CURRENT => resp.push(
            dev.as_amplifier_control()?
                .get_current(joint(cmd, 2)?)
                .ok()?,
        ),
        AMP_MAXCURRENT => resp.push(
            dev.as_amplifier_control()?
                .get_max_current(joint(cmd, 2)?)
                .ok()?,
        ),
        AMP_CURRENTS => {
            let n = dev.as_encoders()?.get_axes().ok()?;
            let amp = dev.as_amplifier_control()?;
            let v = (0..n)
                .map(|j| amp.get_current(j))
                .collect::<Result<Vec<_>, _>>();
            resp.push(float_list(&v.ok()?))
        }
        AMP_STATUS_SINGLE => resp.push(
            dev.as_amplifier_control()?
                .get_amp_status(joint(cmd, 2)?)
                .ok()?,
        ),
        AMP_NOMINAL_CURRENT => resp.push(
            dev.as_amplifier_control()?
                .get_nominal_current(joint(cmd, 2)?)
                .ok()?,
        ),
        AMP_PEAK_CURRENT => resp.push(
            dev.as_amplifier_control()?
                .get_peak_current(joint(cmd, 2)?)
                .ok()?,
        ),
        AMP_PWM => resp.push(dev.as_amplifier_control()?.get_pwm(joint(cmd, 2)?).ok()?),
        AMP_PWM_LIMIT => resp.push(
            dev.as_amplifier_control()?
                .get_pwm_limit(joint(cmd, 2)?)
                .ok()?,
        ),
        AMP_VOLTAGE_SUPPLY => resp.push(
            dev.as_amplifier_control()?
                .get_power_supply_voltage(joint(cmd, 2)?)
                .ok()?,
        ),
        TEMPERATURE_LIMIT => resp.push(dev.as_motor()?.get_temperature_limit(joint(cmd, 2)?).ok()?),
        TEMPERATURES => {
            let motor = dev.as_motor()?;
            let n = motor.get_number_of_motors().ok()?;
            let v = (0..n)
                .map(|m| motor.get_temperature(m))
                .collect::<Result<Vec<_>, _>>();
            resp.push(float_list(&v.ok()?))
        }
        TEMPERATURE => resp.push(dev.as_motor()?.get_temperature(joint(cmd, 2)?).ok()?),
        MOTORS_NUMBER => {
            let n = dev.as_motor()?.get_number_of_motors().ok()?;
            resp.push(i32::try_from(n).ok()?)
        }
        GEARBOX_RATIO => resp.push(dev.as_motor()?.get_gearbox_ratio(joint(cmd, 2)?).ok()?),
        MOTOR_ENCODER_SPEED => resp.push(
            dev.as_motor_encoders()?
                .get_motor_encoder_speed(joint(cmd, 2)?)
                .ok()?,
        ),
        MOTOR_ENCODER_SPEEDS => resp.push(float_list(
            &dev.as_motor_encoders()?.get_motor_encoder_speeds().ok()?,
        )),
        MOTOR_ENCODER_ACCELERATION => resp.push(
            dev.as_motor_encoders()?
                .get_motor_encoder_acceleration(joint(cmd, 2)?)
                .ok()?,
        ),
        MOTOR_ENCODER_ACCELERATIONS => resp.push(float_list(
            &dev.as_motor_encoders()?
                .get_motor_encoder_accelerations()
                .ok()?,
        )),
        // position-direct references are set on command:i only
        POSITION_DIRECT => resp.push(
            dev.as_position_direct()?
                .get_ref_position(joint(cmd, 2)?)
                .ok()?,
        ),
        POSITION_DIRECTS => resp.push(float_list(
            &dev.as_position_direct()?.get_ref_positions().ok()?,
        )),
        POSITION_DIRECT_GROUP => {
            let n = usize::try_from(int(cmd, 2)).ok()?;
            let js = joints(cmd, 3)?;
            if js.len() != n {
                return None;
            }
            resp.push(float_list(
                &dev.as_position_direct()?
                    .get_ref_positions_group(&js)
                    .ok()?,
            ))
        }
        ICONTROLMODE => {
            let cm = dev.as_control_mode()?;
            match vocab(cmd.get(2)) {
                CM_CONTROL_MODE => resp.push(cm.get_control_mode(joint(cmd, 3)?).ok()?),
                CM_CONTROL_MODES => resp.push(vocab_list(&cm.get_control_modes().ok()?)),
                CM_CONTROL_MODE_GROUP => {
                    let n = usize::try_from(int(cmd, 3)).ok()?;
                    let js = joints(cmd, 4)?;
                    if js.len() != n {
                        return None;
                    }
                    resp.push(vocab_list(&cm.get_control_modes_group(&js).ok()?))
                }
                _ => return None,
            }
        }
        _ => return None,
    };
    Some(())
}

/// The `[get] [icur]|[ipwm] ...` readings (C++ `handleCurrentMsg` / `handlePWMMsg`).
fn open_loop(
    cmd: &Bottle,
    family: i32,
    dev: &mut dyn DeviceDriver,
    resp: &mut Bottle,
) -> Option<bool> {
    let what = vocab(cmd.get(2));
    let all = |dev: &mut dyn DeviceDriver,
               f: &mut dyn FnMut(&mut dyn DeviceDriver, usize) -> Option<f64>| {
        let n = axes(dev)?;
        (0..n).map(|j| f(dev, j)).collect::<Option<Vec<f64>>>()
    };
    let v = match (family, what) {
        (CURRENT_IFACE, RANGE) => {
            let (lo, hi) = dev
                .as_current_control()?
                .get_current_range(joint(cmd, 3)?)
                .ok()?;
            resp.push(lo).push(hi);
            return Some(true);
        }
        (CURRENT_IFACE, RANGES) => {
            let r = all(dev, &mut |d, j| {
                d.as_current_control()?
                    .get_current_range(j)
                    .ok()
                    .map(|x| x.0)
            })?;
            let h = all(dev, &mut |d, j| {
                d.as_current_control()?
                    .get_current_range(j)
                    .ok()
                    .map(|x| x.1)
            })?;
            resp.push(float_list(&r)).push(float_list(&h));
            return Some(true);
        }
        (CURRENT_IFACE, REF) => dev
            .as_current_control()?
            .get_ref_current(joint(cmd, 3)?)
            .ok()?
            .into(),
        (CURRENT_IFACE, REFS) => float_list(&all(dev, &mut |d, j| {
            d.as_current_control()?.get_ref_current(j).ok()
        })?),
        (PWM_IFACE, REF) => dev
            .as_pwm_control()?
            .get_ref_duty_cycle(joint(cmd, 3)?)
            .ok()?
            .into(),
        (PWM_IFACE, REFS) => float_list(&all(dev, &mut |d, j| {
            d.as_pwm_control()?.get_ref_duty_cycle(j).ok()
        })?),
        (PWM_IFACE, PWM_OUTPUT) => dev
            .as_pwm_control()?
            .get_duty_cycle(joint(cmd, 3)?)
            .ok()?
            .into(),
        // C++ answers the references here (sic), which we copy
        (PWM_IFACE, PWM_OUTPUTS) => float_list(&all(dev, &mut |d, j| {
            d.as_pwm_control()?.get_ref_duty_cycle(j).ok()
        })?),
        _ => return Some(false),
    };
    resp.push(v);
    Some(true)
}

/// The number of controlled joints (C++ `controlledJoints`).
fn axes(dev: &mut dyn DeviceDriver) -> Option<usize> {
    if let Some(e) = dev.as_encoders() {
        return e.get_axes().ok();
    }
    if let Some(p) = dev.as_position_control() {
        return p.get_axes().ok();
    }
    dev.as_velocity_control()?.get_axes().ok()
}

fn torque(
    cmd: &Bottle,
    action: i32,
    dev: &mut dyn DeviceDriver,
    stamp: &mut RpcStamp,
    resp: &mut Bottle,
) -> Option<bool> {
    let t = dev.as_torque_control()?;
    match action {
        SET => Some(match vocab(cmd.get(2)) {
            REF => t.set_ref_torque(joint(cmd, 3)?, float(cmd, 4)).is_ok(),
            // every joint's reference (C++ wants exactly the controlled joints)
            REFS => {
                let refs: Vec<f64> = cmd
                    .get(3)?
                    .as_list()?
                    .iter()
                    .map(|v| v.as_f64().unwrap_or(0.0))
                    .collect();
                refs.len() == t.get_axes().ok()?
                    && refs
                        .iter()
                        .enumerate()
                        .all(|(j, r)| t.set_ref_torque(j, *r).is_ok())
            }
            _ => false,
        }),
        GET => {
            resp.push(Vocab32(IS)).push(cmd[1].clone());
            match vocab(cmd.get(2)) {
                TRQ => resp.push(t.get_torque(joint(cmd, 3)?).ok()?),
                TRQS => resp.push(float_list(&t.get_torques().ok()?)),
                REF => resp.push(t.get_ref_torque(joint(cmd, 3)?).ok()?),
                REFS => resp.push(float_list(&t.get_ref_torques().ok()?)),
                RANGE => {
                    let (lo, hi) = t.get_torque_range(joint(cmd, 3)?).ok()?;
                    resp.push(lo).push(hi)
                }
                RANGES => {
                    let n = t.get_axes().ok()?;
                    let r = (0..n)
                        .map(|j| t.get_torque_range(j))
                        .collect::<Result<Vec<_>, _>>()
                        .ok()?;
                    let lo: Vec<f64> = r.iter().map(|x| x.0).collect();
                    let hi: Vec<f64> = r.iter().map(|x| x.1).collect();
                    resp.push(float_list(&lo)).push(float_list(&hi))
                }
                MOTOR_PARAMS => {
                    resp.push(float_list(&t.get_motor_torque_params(joint(cmd, 3)?).ok()?))
                }
                _ => return Some(false),
            };
            stamp_into(resp, stamp);
            Some(true)
        }
        _ => Some(false),
    }
}

fn interaction(
    cmd: &Bottle,
    action: i32,
    dev: &mut dyn DeviceDriver,
    stamp: &mut RpcStamp,
    resp: &mut Bottle,
) -> Option<bool> {
    let im = dev.as_interaction_mode()?;
    let modes = |i: usize| -> Option<Vec<Vocab32>> {
        Some(
            cmd.get(i)?
                .as_list()?
                .iter()
                .map(|v| Vocab32(vocab(Some(v))))
                .collect(),
        )
    };
    match action {
        SET => Some(
            match vocab(cmd.get(2)) {
                INTERACTION_MODE => {
                    im.set_interaction_mode(joint(cmd, 3)?, Vocab32(vocab(cmd.get(4))))
                }
                INTERACTION_MODES => im.set_interaction_modes(&modes(3)?),
                INTERACTION_MODE_GROUP => {
                    let js = joints(cmd, 4)?;
                    im.set_interaction_modes_group(&js, &modes(5)?)
                }
                _ => return Some(false),
            }
            .is_ok(),
        ),
        GET => {
            // no [is] and no echo here, as in C++
            match vocab(cmd.get(2)) {
                INTERACTION_MODE => resp.push(im.get_interaction_mode(joint(cmd, 3)?).ok()?),
                INTERACTION_MODES => resp.push(vocab_list(&im.get_interaction_modes().ok()?)),
                INTERACTION_MODE_GROUP => {
                    let js = joints(cmd, 4)?;
                    resp.push(vocab_list(&im.get_interaction_modes_group(&js).ok()?))
                }
                _ => return Some(false),
            };
            stamp_into(resp, stamp);
            Some(true)
        }
        _ => Some(false),
    }
}

/// `[set|get] [pid] <what> <pid type> <joint> ...` (no timestamp in these replies).
fn pid(cmd: &Bottle, action: i32, dev: &mut dyn DeviceDriver, resp: &mut Bottle) -> Option<bool> {
    let n = axes(dev);
    let p = dev.as_pid_control()?;
    let ty = Vocab32(vocab(cmd.get(3)));
    let j = || joint(cmd, 4);
    match action {
        SET => Some(
            match vocab(cmd.get(2)) {
                PID => p.set_pid(
                    ty,
                    j()?,
                    crate::interfaces::Pid::from_slice(&floats(cmd, 5)?),
                ),
                PID_ENABLE => p.enable_pid(ty, j()?),
                PID_DISABLE => p.disable_pid(ty, j()?),
                REF => p.set_pid_reference(ty, j()?, float(cmd, 5)),
                PID_RESET => p.reset_pid(ty, j()?),
                PID_ERROR_LIMIT => p.set_pid_error_limit(ty, j()?, float(cmd, 5)),
                PID_OFFSET => p.set_pid_offset(ty, j()?, float(cmd, 5)),
                _ => return Some(false),
            }
            .is_ok(),
        ),
        GET => {
            resp.push(Vocab32(IS)).push(cmd[1].clone());
            // the all-joints forms: one value (a list for `pids`) per joint
            let each = |f: &mut dyn FnMut(usize) -> Option<Value>| -> Option<Value> {
                (0..n?)
                    .map(f)
                    .collect::<Option<Vec<Value>>>()
                    .map(|v| Value::List(v.into_iter().collect()))
            };
            let v: Value = match vocab(cmd.get(2)) {
                PID => float_list(&p.get_pid(ty, j()?).ok()?.to_array()),
                PID_ENABLE => Value::from(i32::from(p.is_pid_enabled(ty, j()?).ok()?)),
                REF => p.get_pid_reference(ty, j()?).ok()?.into(),
                PID_ERROR => p.get_pid_error(ty, j()?).ok()?.into(),
                PID_OUTPUT => p.get_pid_output(ty, j()?).ok()?.into(),
                PID_ERROR_LIMIT => p.get_pid_error_limit(ty, j()?).ok()?.into(),
                PIDS => each(&mut |k| Some(float_list(&p.get_pid(ty, k).ok()?.to_array())))?,
                REFS => each(&mut |k| Some(p.get_pid_reference(ty, k).ok()?.into()))?,
                PID_ERROR_LIMITS => each(&mut |k| Some(p.get_pid_error_limit(ty, k).ok()?.into()))?,
                PID_ERRORS => each(&mut |k| Some(p.get_pid_error(ty, k).ok()?.into()))?,
                PID_OUTPUTS => each(&mut |k| Some(p.get_pid_output(ty, k).ok()?.into()))?,
                _ => return Some(false),
            };
            resp.push(v);
            Some(true)
        }
        _ => Some(false),
    }
}

/// `[set|get] [iimp] <what> <joint> ...` (C++ `handleImpedanceMsg`): values travel in a
/// list; `get` replies carry the timestamp.
fn impedance(
    cmd: &Bottle,
    action: i32,
    dev: &mut dyn DeviceDriver,
    stamp: &mut RpcStamp,
    resp: &mut Bottle,
) -> Option<bool> {
    let imp = dev.as_impedance_control()?;
    let j = joint(cmd, 3)?;
    match action {
        SET => {
            // C++ reads missing list items as 0 but needs the list itself
            let v = floats(cmd, 4)?;
            let at = |i: usize| v.get(i).copied().unwrap_or(0.0);
            Some(
                match vocab(cmd.get(2)) {
                    IMP_PARAM => imp.set_impedance(j, at(0), at(1)),
                    IMP_OFFSET => imp.set_impedance_offset(j, at(0)),
                    _ => return Some(false),
                }
                .is_ok(),
            )
        }
        GET => {
            resp.push(Vocab32(IS)).push(cmd[1].clone());
            let values = match vocab(cmd.get(2)) {
                IMP_PARAM => {
                    let (k, d) = imp.get_impedance(j).ok()?;
                    vec![k, d]
                }
                IMP_OFFSET => vec![imp.get_impedance_offset(j).ok()?],
                // 3.12 names the limits with the generic `[llim]`
                LIMITS => {
                    let l = imp.get_current_impedance_limit(j).ok()?;
                    vec![
                        l.min_stiffness,
                        l.max_stiffness,
                        l.min_damping,
                        l.max_damping,
                    ]
                }
                _ => return Some(false),
            };
            resp.push(float_list(&values));
            stamp_into(resp, stamp);
            Some(true)
        }
        _ => Some(false),
    }
}

/// The `IControlCalibration` commands, which C++ recognises by their first vocab:
/// `[calj] j type p1 p2 p3`, `[cljp] j type p1 p2 p3 p4`, `[cal] ...` (calibrate the
/// robot), `[cald] j`, `[park] wait`. Replies are `[ok]` / `[fail]`.
fn calibration(cmd: &Bottle, action: i32, dev: &mut dyn DeviceDriver) -> Option<bool> {
    let c = dev.as_control_calibration()?;
    let kind = || u32::try_from(int(cmd, 2)).ok();
    Some(match action {
        CALIBRATE_JOINT => c
            .calibrate_axis_with_params(
                joint(cmd, 1)?,
                kind()?,
                float(cmd, 3),
                float(cmd, 4),
                float(cmd, 5),
            )
            .is_ok(),
        CALIBRATE_JOINT_PARAMS => {
            let params = crate::interfaces::CalibrationParameters {
                kind: kind()?,
                param1: float(cmd, 3),
                param2: float(cmd, 4),
                param3: float(cmd, 5),
                param4: float(cmd, 6),
                ..Default::default()
            };
            c.set_calibration_parameters(joint(cmd, 1)?, &params)
                .is_ok()
        }
        CALIBRATE => c.calibrate_robot().is_ok(),
        CALIBRATE_DONE => c.calibration_done(joint(cmd, 1)?) == Ok(true),
        PARK => {
            if let Err(e) = c.park(int(cmd, 1) != 0) {
                tracing::warn!("controlBoard rpc: park failed: {e}");
            }
            // as C++: "client would get stuck if returning false"
            true
        }
        _ => false,
    })
}

/// `[set|get] [reca] <what> ...` (C++ `handleRemoteCalibratorMsg`); no timestamp.
fn remote_calibrator(
    cmd: &Bottle,
    action: i32,
    dev: &mut dyn DeviceDriver,
    resp: &mut Bottle,
) -> Option<bool> {
    let rc = dev.as_remote_calibrator()?;
    match action {
        SET => Some(
            match vocab(cmd.get(2)) {
                CALIBRATE_SINGLE_JOINT => rc.calibrate_single_joint(joint(cmd, 3)?),
                CALIBRATE_WHOLE_PART => rc.calibrate_whole_part(),
                HOMING_SINGLE_JOINT => rc.homing_single_joint(joint(cmd, 3)?),
                HOMING_WHOLE_PART => rc.homing_whole_part(),
                // C++ calls `parkSingleJoint(j)`: IRemoteCalibrator's default waits
                PARK_SINGLE_JOINT => rc.park_single_joint(joint(cmd, 3)?, true),
                PARK_WHOLE_PART => rc.park_whole_part(),
                QUIT_CALIBRATE => rc.quit_calibrate(),
                QUIT_PARK => rc.quit_park(),
                _ => return Some(false),
            }
            .is_ok(),
        ),
        GET => match vocab(cmd.get(2)) {
            IS_CALIBRATOR_PRESENT => {
                let present = rc.is_calibrator_device_present().ok()?;
                resp.push(Vocab32(IS))
                    .push(cmd[1].clone())
                    .push(i32::from(present));
                Some(true)
            }
            _ => Some(false),
        },
        _ => Some(false),
    }
}
