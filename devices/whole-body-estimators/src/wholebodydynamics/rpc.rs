//! `<prefix>/rpc`: whole-body-estimators' `wholeBodyDynamics_IDLServer` thrift service
//! (classic YARP thrift: a method's words may come joined by `_` or apart, optional
//! trailing arguments take their IDL defaults, `bool` replies are `[ok]`/`[fail]`).

use yarp_devices::thrift::split_method;
use yarp_proto::{Bottle, Value, Vocab32};

use super::core::{Core, KinematicSource};

/// The methods, by thrift name (IDL order).
pub const METHODS: &[&str] = &[
    "calib",
    "calibStanding",
    "calibStandingLeftFoot",
    "calibStandingRightFoot",
    "calibStandingOnOneLink",
    "calibStandingOnTwoLinks",
    "calibStandingWithJetsiRonCub",
    "resetOffset",
    "usePreEstimatedOffset",
    "quit",
    "resetSimpleLeggedOdometry",
    "changeFixedLinkSimpleLeggedOdometry",
    "set_imuFilterCutoffInHz",
    "get_imuFilterCutoffInHz",
    "set_forceTorqueFilterCutoffInHz",
    "get_forceTorqueFilterCutoffInHz",
    "set_jointVelFilterCutoffInHz",
    "get_jointVelFilterCutoffInHz",
    "set_jointAccFilterCutoffInHz",
    "get_jointAccFilterCutoffInHz",
    "useIMUAsKinematicSource",
    "useFixedFrameAsKinematicSource",
    "setUseOfJointVelocities",
    "setUseOfJointAccelerations",
    "getCurrentSettingsString",
    "help",
];

/// What the RPC acts on.
pub struct Target<'a> {
    pub core: &'a mut Core,
    /// Whether an IMU was attached (it can then be the kinematic source).
    pub imu_attached: bool,
}

fn ok(b: bool) -> Bottle {
    Bottle::new().with(Vocab32::new(if b { "ok" } else { "fail" }))
}

/// The arguments as read: strings, integers with defaults.
struct Args<'a>(&'a [Value]);

impl Args<'_> {
    fn text(&self, i: usize) -> Option<String> {
        self.0
            .get(i)
            .filter(|v| v.is_string() || v.is_vocab())
            .map(Value::to_string_bare)
    }
    fn int_or(&self, i: usize, default: i64) -> Option<i64> {
        match self.0.get(i) {
            None => Some(default),
            Some(v) => v.as_i64().filter(|_| v.is_int()),
        }
    }
    fn number(&self, i: usize) -> Option<f64> {
        self.0.get(i).and_then(Value::as_f64)
    }
    fn flag(&self, i: usize) -> Option<bool> {
        match self.0.get(i)? {
            v if v.is_vocab() || v.is_string() => match v.to_string_bare().as_str() {
                "ok" | "true" | "1" => Some(true),
                "fail" | "false" | "0" => Some(false),
                _ => None,
            },
            v => v.as_i64().map(|i| i != 0),
        }
    }
}

/// The samples of a calibration call's `nr_of_samples` (IDL default 100).
fn samples(a: &Args, i: usize) -> Option<usize> {
    a.int_or(i, 100).and_then(|n| usize::try_from(n).ok())
}

fn calibrate(t: &mut Target, frames: &[&str], n: usize) -> Bottle {
    match t.core.start_calibration(frames, n) {
        Ok(()) => ok(true),
        Err(e) => {
            tracing::error!("wholebodydynamics: {e}");
            ok(false)
        }
    }
}

/// Answers one request; `None` for what is no call of the service (C++'s generated
/// `read` fails and writes no reply).
pub fn answer(cmd: &Bottle, t: &mut Target) -> Option<Bottle> {
    let (method, rest) = split_method(cmd, METHODS)?;
    let a = Args(rest);
    let s = &mut t.core.settings;
    let reply = match method {
        "calib" => {
            a.text(0)?;
            calibrate(t, &["base_link"], samples(&a, 1)?)
        }
        "calibStanding" => {
            a.text(0)?;
            calibrate(t, &["r_sole", "l_sole"], samples(&a, 1)?)
        }
        "calibStandingLeftFoot" => {
            a.text(0)?;
            calibrate(t, &["l_sole"], samples(&a, 1)?)
        }
        "calibStandingRightFoot" => {
            a.text(0)?;
            calibrate(t, &["r_sole"], samples(&a, 1)?)
        }
        "calibStandingOnOneLink" => {
            let f = a.text(0)?;
            calibrate(t, &[&f], samples(&a, 1)?)
        }
        "calibStandingOnTwoLinks" => {
            let (f1, f2) = (a.text(0)?, a.text(1)?);
            calibrate(t, &[&f1, &f2], samples(&a, 2)?)
        }
        "calibStandingWithJetsiRonCub" => {
            let model = a.text(0)?;
            a.text(1)?;
            samples(&a, 2)?;
            tracing::error!("wholebodydynamics: calibStandingWithJetsiRonCub: iRonCub model {model} has no jet turbines in this model");
            ok(false)
        }
        "resetOffset" => {
            a.text(0)?;
            t.core.reset_offsets();
            ok(true)
        }
        "usePreEstimatedOffset" => {
            t.core.use_pre_estimated_offsets();
            ok(true)
        }
        "quit" | "resetSimpleLeggedOdometry" | "changeFixedLinkSimpleLeggedOdometry" => {
            tracing::error!("wholebodydynamics: {method} is not implemented (nor in C++)");
            ok(false)
        }
        "set_imuFilterCutoffInHz" => {
            s.imu_cutoff = a.number(0)?;
            ok(true)
        }
        "set_forceTorqueFilterCutoffInHz" => {
            s.ft_cutoff = a.number(0)?;
            ok(true)
        }
        "set_jointVelFilterCutoffInHz" => {
            s.joint_vel_cutoff = a.number(0)?;
            ok(true)
        }
        "set_jointAccFilterCutoffInHz" => {
            s.joint_acc_cutoff = a.number(0)?;
            ok(true)
        }
        "get_imuFilterCutoffInHz" => Bottle::new().with(s.imu_cutoff),
        "get_forceTorqueFilterCutoffInHz" => Bottle::new().with(s.ft_cutoff),
        "get_jointVelFilterCutoffInHz" => Bottle::new().with(s.joint_vel_cutoff),
        "get_jointAccFilterCutoffInHz" => Bottle::new().with(s.joint_acc_cutoff),
        "useIMUAsKinematicSource" => {
            if t.imu_attached {
                s.kinematic_source = KinematicSource::Imu;
                ok(true)
            } else {
                tracing::error!("wholebodydynamics: IMU was not attached during startup, impossible to use it as kinematic source");
                ok(false)
            }
        }
        "useFixedFrameAsKinematicSource" => {
            let f = a.text(0)?;
            if t.core.est.model.frame(&f).is_ok() {
                t.core.settings.kinematic_source = KinematicSource::FixedFrame(f);
                ok(true)
            } else {
                tracing::error!("wholebodydynamics: useFixedFrameAsKinematicSource: frame {f} not found in the model");
                ok(false)
            }
        }
        "setUseOfJointVelocities" => {
            s.use_joint_velocity = a.flag(0)?;
            ok(true)
        }
        "setUseOfJointAccelerations" => {
            s.use_joint_acceleration = a.flag(0)?;
            ok(true)
        }
        "getCurrentSettingsString" => Bottle::new().with(s.text()),
        "help" => {
            let mut list = Bottle::new().with("*** Available commands:");
            for m in METHODS {
                list.push(*m);
            }
            Bottle::new()
                .with(Vocab32::new("many"))
                .with(Value::from(list))
        }
        _ => return None,
    };
    Some(reply)
}
