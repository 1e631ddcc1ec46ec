//! `parametricCalibratorEth` (icub-main): calibrates a robot part of `embObj` boards at
//! start-up, parks it at shutdown, and serves the part's remote calibration, homing and
//! parking (`IRemoteCalibrator`: `[set] [reca] …` on the part's `rpc:i`, yarpmotorgui's
//! buttons), all through its target (the part's `controlboardremapper`).
//!
//! Parameters as `calibrators/*-calib.xml` and `general.xml` write them:
//! - `GENERAL::deviceName`, `joints` (or `Joints`), `skipCalibration`,
//!   `useRawEncoderData` (true forces `skipCalibration`), `clearHwFaultBeforeCalibration`;
//!   `MAINTENANCE::skipRecalibration`;
//! - `CALIBRATION::calibrationType`, `calibration1`..`calibration5`, `calibrationZero`,
//!   `calibrationDelta` (added to the zero), `calibrationTimeout` (s, default 20),
//!   `startupPosition`, `startupVelocity`, `startupMaxPwm`, `startupPosThreshold`,
//!   `startupDisablePosCheck`, `startupTimeout` (s, default 10);
//! - the park pose: `PARKING_SEQUENCE` (`numberOfSequences`, `SEQUENCE_<i>::position`,
//!   `velocity`), else `HOME::positionHome`, `velocityHome`; `HOME::disableHomeAndPark`;
//! - `CALIB_ORDER`: the sets of joints calibrated together, in order.
//!
//! `calibrate`, as C++: a joint in hardware fault stops it (unless
//! `clearHwFaultBeforeCalibration`, which tries a force-idle). Per set, the PWM limit
//! of each joint is lowered to its `startupMaxPwm` when that is lower (0: unchanged);
//! with `skipCalibration` that is all. Each joint then gets `setCalibrationParameters`
//! (all five parameters and the zero, which the board uses by type: 0 hard stops,
//! 3 absolute digital sensor, 5 hard stops (MC4plus), 6 MAIS, 7 hall sensor,
//! 10 absolute + hard stop, 12 absolute sensor, 14 quadrature encoder + hard stop + FAP,
//! ...) and the set waits until each board reports its joint calibrated. Joints that time
//! out are set idle and the set goes no further (its joints keep the safe limit).
//! Otherwise the set moves to `startupPosition` at `startupVelocity` and waits until each
//! joint is done moving within `startupPosThreshold`; those that get there have their PWM
//! limit back, the others (timed out, idle, faulted) are set idle. The part then counts
//! as calibrated; a quit (`quitCalibrate`) idles the set being calibrated instead.
//!
//! `park` (yarprobotinterface's `interrupt1`): the calibrated joints that are not idle,
//! faulted or unconfigured go to position mode and to `HOME` (waiting up to 30 s each
//! when asked), or through the next `PARKING_SEQUENCE` step (one step per call, as C++);
//! then they are set idle. Remote calls, as C++: `calibrateSingleJoint` sends that
//! joint's calibration parameters; `calibrateWholePart` runs `calibrate` again;
//! `homingSingleJoint`/`homingWholePart` send the joints to their startup position;
//! `parkSingleJoint` moves the joint to its startup position (C++ does, not `HOME`) or
//! the sequence's last step, waits when asked, and idles it; `parkWholePart` is `park`;
//! `quitCalibrate`/`quitPark` stop the running procedure's waits. Every wait is bounded;
//! the target is taken only while each call runs, and a target held by someone else
//! for [`TARGET_WAIT`] is an error, never a hang.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use yarp_devices::interfaces::{CalibrationParameters, IRemoteCalibrator};
use yarp_devices::params::per_joint;
use yarp_devices::vocabs::{
    CM_FORCE_IDLE, CM_HW_FAULT, CM_IDLE, CM_NOT_CONFIGURED, CM_POSITION, CM_UNKNOWN,
};
use yarp_devices::{DevResult, DeviceDriver, DeviceError, ICalibrator, SharedDevice};
use yarp_proto::{Property, Value, Vocab32};

use super::config::{Node, ParamError};

pub const NAME: &str = "parametricCalibratorEth";

/// C++ defaults of `calibrationTimeout` and `startupTimeout`.
const CALIBRATION_TIMEOUT: f64 = 20.0;
const STARTUP_TIMEOUT: f64 = 10.0;
const PARK_TIMEOUT: Duration = Duration::from_secs(30);
const POLL: Duration = Duration::from_millis(20);
/// How long a call waits for the target when another holder keeps it.
pub const TARGET_WAIT: Duration = Duration::from_secs(10);

#[derive(Debug, Clone, Default)]
struct JointCalib {
    params: CalibrationParameters,
    startup_pos: f64,
    startup_vel: f64,
    /// The PWM limit while calibrating and reaching `startup_pos` (0: left as it is).
    startup_max_pwm: f64,
    threshold: f64,
    calibration_timeout: Duration,
    startup_timeout: Duration,
    /// `startupDisablePosCheck`: not sent to, nor checked at, the startup position.
    no_startup: bool,
    /// `disableHomeAndPark`: never homed; parked on its own.
    no_home_and_park: bool,
}

/// A pose of the part: a position and a velocity per joint.
#[derive(Debug, Clone, Default)]
struct Pose {
    positions: Vec<f64>,
    velocities: Vec<f64>,
}

/// Where `park` takes the part.
#[derive(Debug, Clone)]
enum Parking {
    /// `HOME::positionHome` / `velocityHome` (C++'s legacy parking).
    Home(Pose),
    /// `PARKING_SEQUENCE`: one step per `park`.
    Sequence { steps: Vec<Pose>, next: usize },
}

impl Default for Parking {
    fn default() -> Self {
        Parking::Home(Pose::default())
    }
}

/// The `parametricCalibratorEth` device.
#[derive(Default)]
pub struct ParametricCalibratorEth {
    name: String,
    skip: bool,
    skip_recalibration: bool,
    clear_hw_fault: bool,
    joints: Vec<JointCalib>,
    order: Vec<Vec<usize>>,
    parking: Parking,
    calibrated: bool,
    /// The part given to `calibrate` (C++ `dev2calibrate`), for the remote calls.
    target: Option<SharedDevice>,
    /// Raised by `quitCalibrate`/`quitPark`; the running procedure's waits stop.
    quit: Arc<AtomicBool>,
}

fn missing(what: &'static str) -> DeviceError {
    DeviceError::Unsupported(what)
}

impl ParametricCalibratorEth {
    pub fn new() -> Self {
        Self::default()
    }

    /// Whether the last `calibrate` succeeded.
    pub fn is_calibrated(&self) -> bool {
        self.calibrated
    }

    fn read(&mut self, id: &str, config: &Property) -> DevResult<()> {
        yarp_devices::params::help_if_asked(NAME, config, ParametricCalibratorEthParams::PARAMS);
        let p = ParametricCalibratorEthParams::parse(id, config)?;
        let root = Node::root(config);
        self.name = p.device_name;
        self.clear_hw_fault = p.clear_hw_fault;
        let raw = p.use_raw_encoder_data;
        self.skip = raw || p.skip_calibration;
        if raw {
            tracing::warn!(device = %self.name, "MotionControl is using raw data from encoders: forcing skipCalibration");
        } else if self.skip {
            tracing::warn!(device = %self.name, "skipping calibration (skipCalibration): be careful using the robot in this configuration");
        }
        self.skip_recalibration = p.skip_recalibration;
        let n = p
            .joints
            .or(p.joints_cap)
            .ok_or_else(|| DeviceError::MissingParam {
                device: id.to_string(),
                param: "GENERAL::joints".into(),
            })? as usize;
        let c = |k: &str, v: Vec<f64>| per_joint(id, &format!("CALIBRATION::{k}"), v, n);
        let or = |k: &str, v: Option<Vec<f64>>, default: f64| match v {
            Some(v) => c(k, v),
            None => Ok(vec![default; n]),
        };
        let kind = c("calibrationType", p.calibration_type)?;
        let (p1, p2, p3, p4, p5) = (
            c("calibration1", p.calibration1)?,
            c("calibration2", p.calibration2)?,
            c("calibration3", p.calibration3)?,
            c("calibration4", p.calibration4)?,
            c("calibration5", p.calibration5)?,
        );
        let zero = c("calibrationZero", p.calibration_zero)?;
        let delta = or("calibrationDelta", p.calibration_delta, 0.0)?;
        let (pos, vel, thr, max_pwm) = (
            c("startupPosition", p.startup_position)?,
            c("startupVelocity", p.startup_velocity)?,
            c("startupPosThreshold", p.startup_pos_threshold)?,
            c("startupMaxPwm", p.startup_max_pwm)?,
        );
        let calib_timeout = or(
            "calibrationTimeout",
            p.calibration_timeout,
            CALIBRATION_TIMEOUT,
        )?;
        let startup_timeout = or("startupTimeout", p.startup_timeout, STARTUP_TIMEOUT)?;
        let no_startup = or("startupDisablePosCheck", p.startup_disable_pos_check, 0.0)?;
        let no_park = match p.disable_home_and_park {
            Some(v) => per_joint(id, "HOME::disableHomeAndPark", v, n)?,
            None => vec![0.0; n],
        };
        let seconds = |s: f64| Duration::from_secs_f64(s.max(0.0));
        self.joints = (0..n)
            .map(|j| JointCalib {
                params: CalibrationParameters {
                    kind: kind[j] as u32,
                    param1: p1[j],
                    param2: p2[j],
                    param3: p3[j],
                    param4: p4[j],
                    param5: p5[j],
                    param_zero: zero[j] + delta[j],
                },
                startup_pos: pos[j],
                startup_vel: vel[j],
                startup_max_pwm: max_pwm[j],
                threshold: thr[j],
                calibration_timeout: seconds(calib_timeout[j]),
                startup_timeout: seconds(startup_timeout[j]),
                no_startup: no_startup[j] != 0.0,
                no_home_and_park: no_park[j] != 0.0,
            })
            .collect();
        self.parking = match root.group("PARKING_SEQUENCE") {
            Some(seq) => Parking::Sequence {
                steps: read_sequence(&seq, n).map_err(|e| e.for_device(id))?,
                next: 0,
            },
            None => match (p.position_home, p.velocity_home) {
                (Some(positions), Some(velocities)) => Parking::Home(Pose {
                    positions: per_joint(id, "HOME::positionHome", positions, n)?,
                    velocities: per_joint(id, "HOME::velocityHome", velocities, n)?,
                }),
                (None, _) if root.group("HOME").is_none() => {
                    return Err(
                        ParamError::missing("HOME", "the park pose (or PARKING_SEQUENCE)")
                            .for_device(id),
                    )
                }
                (None, _) => {
                    return Err(DeviceError::MissingParam {
                        device: id.to_string(),
                        param: "HOME::positionHome".into(),
                    })
                }
                (_, None) => {
                    return Err(DeviceError::MissingParam {
                        device: id.to_string(),
                        param: "HOME::velocityHome".into(),
                    })
                }
            },
        };
        let order = config
            .find_group("CALIB_ORDER")
            .ok_or_else(|| ParamError::missing("CALIB_ORDER", "lists of joints").for_device(id))?;
        self.order = order
            .iter()
            .skip(1)
            .map(|set| {
                set.as_list()
                    .and_then(|l| {
                        l.iter()
                            .map(|v| v.as_i64().and_then(|j| usize::try_from(j).ok()))
                            .collect::<Option<Vec<usize>>>()
                    })
                    .filter(|js| js.iter().all(|j| *j < n))
                    .ok_or_else(|| {
                        ParamError::bad(
                            "CALIB_ORDER",
                            "lists of joint indices below `joints`",
                            set.to_string_bare(),
                        )
                        .for_device(id)
                    })
            })
            .collect::<DevResult<_>>()?;
        if self.order.is_empty() {
            return Err(ParamError::missing("CALIB_ORDER", "lists of joints").for_device(id));
        }
        Ok(())
    }

    fn calib_joints(&self) -> impl Iterator<Item = usize> + '_ {
        self.order.iter().flatten().copied()
    }

    /// `f` on the target, taken for this call only; an error when another holder keeps
    /// it for [`TARGET_WAIT`] (a remote call may come while the part is held in-process).
    fn with<T>(
        &self,
        target: &SharedDevice,
        f: impl FnOnce(&mut dyn DeviceDriver) -> DevResult<T>,
    ) -> DevResult<T> {
        let end = Instant::now() + TARGET_WAIT;
        loop {
            match target.try_lock() {
                Some(mut pd) => return f(pd.device()),
                None if Instant::now() < end => {
                    std::thread::sleep(Duration::from_millis(1));
                }
                None => {
                    return Err(DeviceError::failed(
                        &self.name,
                        format!("the part stayed busy for {TARGET_WAIT:?}"),
                    ))
                }
            }
        }
    }

    fn quitting(&self) -> bool {
        self.quit.load(Ordering::SeqCst)
    }

    /// The part given to `calibrate`, for the remote calls.
    fn target(&self) -> DevResult<SharedDevice> {
        self.target.clone().ok_or_else(|| {
            DeviceError::failed(&self.name, "no part to work on: not calibrated yet")
        })
    }

    /// `j` must be one of the joints this calibrator handles (C++ "out of range").
    fn own_joint(&self, j: usize, what: &str) -> DevResult<()> {
        if self.calib_joints().any(|k| k == j) {
            return Ok(());
        }
        let joints: Vec<usize> = self.calib_joints().collect();
        Err(DeviceError::failed(
            &self.name,
            format!("cannot perform '{what}' operation because joint number {j} is out of range {joints:?}"),
        ))
    }

    fn control_mode(&self, target: &SharedDevice, j: usize) -> DevResult<Vocab32> {
        self.with(target, |d| {
            d.as_control_mode()
                .ok_or(missing("target without IControlMode"))?
                .get_control_mode(j)
        })
    }

    fn set_mode(&self, target: &SharedDevice, joints: &[usize], mode: Vocab32) {
        for &j in joints {
            let r = self.with(target, |d| {
                d.as_control_mode()
                    .ok_or(missing("target without IControlMode"))?
                    .set_control_mode(j, mode)
            });
            if let Err(e) = r {
                tracing::error!(device = %self.name, joint = j, "cannot set control mode {mode}: {e}");
            }
        }
    }

    fn move_to(
        &self,
        target: &SharedDevice,
        joints: &[usize],
        pose: impl Fn(usize) -> (f64, f64),
    ) -> DevResult<()> {
        self.with(target, |d| {
            let p = d
                .as_position_control()
                .ok_or(missing("target without IPositionControl"))?;
            for &j in joints {
                let (pos, vel) = pose(j);
                p.set_ref_speed(j, vel)?;
                p.position_move(j, pos)?;
            }
            Ok(())
        })
    }

    /// Polls `done(j)` for each joint of `set` until it holds or the joint's `timeout`
    /// passes (or a quit); the joints that never got there.
    fn wait_until(
        &self,
        target: &SharedDevice,
        set: &[usize],
        timeout: impl Fn(usize) -> Duration,
        mut done: impl FnMut(&mut dyn DeviceDriver, usize) -> DevResult<Wait>,
    ) -> DevResult<Vec<usize>> {
        let start = Instant::now();
        let mut pending: Vec<usize> = set.to_vec();
        let mut failed = Vec::new();
        while !pending.is_empty() && !self.quitting() {
            let mut still = Vec::new();
            for &j in &pending {
                match self.with(target, |d| done(d, j))? {
                    Wait::Done => {}
                    Wait::Failed => failed.push(j),
                    Wait::Pending if start.elapsed() > timeout(j) => {
                        tracing::error!(device = %self.name, joint = j, "timed out after {:?}", timeout(j));
                        failed.push(j);
                    }
                    Wait::Pending => still.push(j),
                }
            }
            pending = still;
            if !pending.is_empty() {
                std::thread::sleep(POLL);
            }
        }
        failed.extend(pending);
        Ok(failed)
    }

    /// C++ `checkHwFault`: a joint in hardware fault stops the calibration, unless
    /// `clearHwFaultBeforeCalibration` and a force-idle clears it.
    fn check_hw_fault(&self, target: &SharedDevice) -> DevResult<()> {
        for j in self.calib_joints() {
            if self.control_mode(target, j)? != CM_HW_FAULT {
                continue;
            }
            if !self.clear_hw_fault {
                return Err(DeviceError::failed(
                    &self.name,
                    format!("detected a hardware fault on joint {j} before starting the calibration procedure"),
                ));
            }
            tracing::warn!(device = %self.name, "detected a hardware fault on joint {j}: an attempt will be made to clear it");
            self.set_mode(target, &[j], CM_FORCE_IDLE);
            std::thread::sleep(Duration::from_millis(20));
            match self.control_mode(target, j)? {
                m if m == CM_IDLE => {
                    tracing::warn!(device = %self.name, "hardware fault on joint {j} successfully cleared")
                }
                m => {
                    return Err(DeviceError::failed(
                        &self.name,
                        format!("unable to clear the hardware fault of joint {j} (mode {m}) before the calibration procedure"),
                    ))
                }
            }
        }
        Ok(())
    }

    /// Lowers the PWM limit of each joint of `set` to its `startupMaxPwm` when that is
    /// lower (0 keeps the limit), as C++ does before calibrating a set; the limits found.
    fn limit_pwm(&self, target: &SharedDevice, set: &[usize]) -> DevResult<Vec<(usize, f64)>> {
        self.with(target, |d| {
            let amp = d
                .as_amplifier_control()
                .ok_or(missing("target without IAmplifierControl"))?;
            let mut original = Vec::new();
            for &j in set {
                let limit = amp.get_pwm_limit(j).map_err(|e| {
                    DeviceError::failed(
                        &self.name,
                        format!("getPWMLimit of joint {j} failed ({e}): aborting calibration"),
                    )
                })?;
                original.push((j, limit));
                // C++: no startup limit sets the original again (its result ignored), a
                // lower one is set for the calibration
                let safe = self.joints[j].startup_max_pwm;
                if safe == 0.0 {
                    let _ = amp.set_pwm_limit(j, limit);
                } else if safe < limit {
                    amp.set_pwm_limit(j, safe)?;
                }
            }
            Ok(original)
        })
    }

    /// Gives the joints of `original` their limits back.
    fn restore_pwm(&self, target: &SharedDevice, original: &[(usize, f64)]) {
        let restored = self.with(target, |d| {
            let amp = d
                .as_amplifier_control()
                .ok_or(missing("target without IAmplifierControl"))?;
            original
                .iter()
                .try_for_each(|&(j, limit)| amp.set_pwm_limit(j, limit))
        });
        if let Err(e) = restored {
            tracing::error!(device = %self.name, "could not restore the PWM limits: {e}");
        }
    }

    /// C++ `calibrateJoint`: the joint's calibration parameters, to its board.
    fn calibrate_joint(&self, target: &SharedDevice, j: usize) -> DevResult<()> {
        let params = &self.joints[j].params;
        tracing::debug!(device = %self.name, joint = j, kind = params.kind, "calibrateJoint");
        self.with(target, |d| {
            d.as_control_calibration()
                .ok_or(missing("target without IControlCalibration"))?
                .set_calibration_parameters(j, params)
        })
    }

    /// C++ `goToStartupPosition`.
    fn go_to_startup(&self, target: &SharedDevice, j: usize) -> DevResult<()> {
        let c = &self.joints[j];
        if c.no_startup {
            tracing::warn!(device = %self.name, joint = j, "goToZero disabled on user request (startupDisablePosCheck)");
            return Ok(());
        }
        if self.quitting() {
            return Ok(());
        }
        if self.skip_recalibration && self.control_mode(target, j)? == CM_IDLE {
            tracing::warn!(device = %self.name, joint = j, "idle and skipRecalibration: not going to the startup position");
            return Ok(());
        }
        self.move_to(target, &[j], |j| {
            (self.joints[j].startup_pos, self.joints[j].startup_vel)
        })
    }

    /// One set of `CALIB_ORDER`, as C++ `calibrate`'s loop body.
    fn calibrate_set(&self, target: &SharedDevice, set: &[usize]) -> DevResult<()> {
        let original = self.limit_pwm(target, set)?;
        if self.skip {
            return Ok(());
        }
        std::thread::sleep(Duration::from_millis(100));
        for &j in set {
            if self.quitting() {
                return Ok(());
            }
            self.calibrate_joint(target, j)?;
        }
        std::thread::sleep(Duration::from_millis(100));
        let failed = self.wait_until(
            target,
            set,
            |j| self.joints[j].calibration_timeout,
            |d, j| {
                let done = d
                    .as_control_calibration()
                    .ok_or(missing("target without IControlCalibration"))?
                    .calibration_done(j)?;
                Ok(if done { Wait::Done } else { Wait::Pending })
            },
        )?;
        if self.quitting() {
            return Ok(());
        }
        if !failed.is_empty() {
            tracing::error!(device = %self.name, "joints {failed:?} failed the calibration: idling them; the set {set:?} keeps its safe PWM limits");
            self.set_mode(target, &failed, CM_IDLE);
            return Ok(());
        }
        std::thread::sleep(Duration::from_millis(500));
        for &j in set {
            self.go_to_startup(target, j)?;
        }
        let far = self.wait_until(
            target,
            set,
            |j| self.joints[j].startup_timeout,
            |d, j| self.gone_to_startup(d, j),
        )?;
        if self.quitting() {
            return Ok(());
        }
        if !far.is_empty() {
            tracing::error!(device = %self.name, "joints {far:?} did not reach their startupPosition: idling them with their safe PWM limits");
            self.set_mode(target, &far, CM_IDLE);
        }
        let reached: Vec<(usize, f64)> = original
            .into_iter()
            .filter(|(j, _)| !far.contains(j))
            .collect();
        self.restore_pwm(target, &reached);
        Ok(())
    }

    /// C++ `checkGoneToZeroThreshold`, one look.
    fn gone_to_startup(&self, d: &mut dyn DeviceDriver, j: usize) -> DevResult<Wait> {
        let c = &self.joints[j];
        if c.no_startup {
            return Ok(Wait::Done);
        }
        let mode = d
            .as_control_mode()
            .ok_or(missing("target without IControlMode"))?
            .get_control_mode(j)?;
        if self.skip_recalibration && mode == CM_IDLE {
            return Ok(Wait::Done);
        }
        let at = d
            .as_encoders()
            .ok_or(missing("target without IEncoders"))?
            .get_encoder(j)?;
        let done = d
            .as_position_control()
            .ok_or(missing("target without IPositionControl"))?
            .check_motion_done(j)?;
        Ok(if (at - c.startup_pos).abs() < c.threshold && done {
            Wait::Done
        } else if mode == CM_IDLE || mode == CM_HW_FAULT {
            tracing::error!(device = %self.name, joint = j, "{mode} while going to its startup position");
            Wait::Failed
        } else {
            Wait::Pending
        })
    }

    /// C++ `calibrate()`: every set of `CALIB_ORDER` on `target`.
    fn run_calibration(&mut self, target: &SharedDevice) -> DevResult<()> {
        self.calibrated = false;
        self.quit.store(false, Ordering::SeqCst);
        let axes = self.with(target, |d| {
            d.as_encoders()
                .ok_or(missing("target without IEncoders"))?
                .get_axes()
        })?;
        if axes != self.joints.len() {
            return Err(DeviceError::failed(
                &self.name,
                format!(
                    "number of joints of device to calibrate ({axes}) does not match the number of joints in calibrator config file ({})",
                    self.joints.len()
                ),
            ));
        }
        self.check_hw_fault(target)?;
        let count = self.calib_joints().count();
        if count < axes {
            tracing::warn!(device = %self.name, "calibrating only a subset of the part: {count} of {axes} joints");
        }
        if self.skip {
            tracing::warn!(device = %self.name, "skipCalibration is on: setting safe PWM limits but skipping calibration");
        } else {
            tracing::info!(device = %self.name, "starting calibration");
        }
        for set in &self.order {
            if self.quitting() {
                tracing::error!(device = %self.name, "calibration has been aborted: idling the joints {set:?}");
                self.set_mode(target, set, CM_IDLE);
                return Err(DeviceError::failed(
                    &self.name,
                    "calibration aborted (quitCalibrate)",
                ));
            }
            self.calibrate_set(target, set)?;
        }
        if self.quitting() {
            let last = self.order.last().cloned().unwrap_or_default();
            self.set_mode(target, &last, CM_IDLE);
            return Err(DeviceError::failed(
                &self.name,
                "calibration aborted (quitCalibrate)",
            ));
        }
        self.calibrated = true;
        tracing::info!(device = %self.name, "calibration done");
        Ok(())
    }

    /// Whether the park of this call may move joint `j` (C++: not idle, faulted,
    /// unconfigured or unknown).
    fn parkable(&self, mode: Vocab32, j: usize) -> bool {
        let why = match mode {
            m if m == CM_IDLE => "is idle",
            m if m == CM_HW_FAULT => "has a hardware fault",
            m if m == CM_NOT_CONFIGURED => "is not configured",
            m if m == CM_UNKNOWN => "is in an unknown state",
            _ => return true,
        };
        tracing::error!(device = %self.name, "joint {j} {why}: skipping park");
        false
    }

    /// Waits (up to [`PARK_TIMEOUT`] each, stoppable) until `joints` are done moving;
    /// those that are not.
    fn wait_parked(&self, target: &SharedDevice, joints: &[usize]) -> DevResult<Vec<usize>> {
        let late = self.wait_until(
            target,
            joints,
            |_| PARK_TIMEOUT,
            |d, j| {
                let done = d
                    .as_position_control()
                    .ok_or(missing("target without IPositionControl"))?
                    .check_motion_done(j)?;
                Ok(if done { Wait::Done } else { Wait::Pending })
            },
        )?;
        if !late.is_empty() && !self.quitting() {
            tracing::error!(device = %self.name, "joints {late:?} not in their park position after {PARK_TIMEOUT:?}");
        }
        Ok(late)
    }

    /// The start of every park, as C++: the quit flag is cleared; an uncalibrated part,
    /// or one whose calibration was skipped, is not moved (only logged).
    fn may_park(&self) -> bool {
        self.quit.store(false, Ordering::SeqCst);
        if !self.calibrated {
            tracing::warn!(device = %self.name, "park without calibration: skipping");
            return false;
        }
        if self.skip {
            tracing::warn!(device = %self.name, "skipCalibration is on: faking park");
            return false;
        }
        true
    }

    /// C++ `parkSingleJoint`.
    fn park_joint(&mut self, j: usize, wait: bool) -> DevResult<()> {
        self.own_joint(j, "park")?;
        if matches!(self.parking, Parking::Home(_)) && self.joints[j].no_home_and_park {
            tracing::warn!(device = %self.name, joint = j, "park disabled on user request (disableHomeAndPark)");
            return Ok(());
        }
        if !self.may_park() {
            return Ok(());
        }
        let target = self.target()?;
        let mode = self.control_mode(&target, j)?;
        let parkable = self.parkable(mode, j);
        if parkable {
            self.set_mode(&target, &[j], CM_POSITION);
        }
        // As C++: the legacy single-joint park goes to the startup position.
        let (pos, vel) = match &self.parking {
            Parking::Home(_) => (self.joints[j].startup_pos, self.joints[j].startup_vel),
            Parking::Sequence { steps, .. } => steps
                .last()
                .map(|s| (s.positions[j], s.velocities[j]))
                .unwrap_or((self.joints[j].startup_pos, self.joints[j].startup_vel)),
        };
        self.move_to(&target, &[j], |_| (pos, vel))?;
        if wait && parkable {
            self.wait_parked(&target, &[j])?;
        }
        self.set_mode(&target, &[j], CM_IDLE);
        tracing::info!(device = %self.name, joint = j, "park {}", if self.quitting() { "aborted" } else { "completed" });
        Ok(())
    }
}

/// One look of a bounded wait.
enum Wait {
    Done,
    Pending,
    Failed,
}

/// `PARKING_SEQUENCE`: `numberOfSequences` steps `SEQUENCE_<i>`, each a `position` and
/// a `velocity` per joint.
fn read_sequence(seq: &Node<'_>, n: usize) -> Result<Vec<Pose>, ParamError> {
    let count = seq
        .number("numberOfSequences")?
        .ok_or_else(|| ParamError::missing("PARKING_SEQUENCE/numberOfSequences", "a count"))?;
    if count < 0.0 {
        return Err(ParamError::bad(
            "PARKING_SEQUENCE/numberOfSequences",
            "a positive integer",
            count.to_string(),
        ));
    }
    (0..count as usize)
        .map(|i| {
            let name = format!("SEQUENCE_{i}");
            let step = seq.need_group(&name)?;
            Ok(Pose {
                positions: step.need_numbers("position", n)?,
                velocities: step.need_numbers("velocity", n)?,
            })
        })
        .collect()
}

yarp_devices::device_params! {
    /// What `parametricCalibratorEth` reads (icub-main's), besides `CALIB_ORDER` (lists of
    /// joints calibrated together, in order) and `PARKING_SEQUENCE` (`numberOfSequences`
    /// groups `SEQUENCE_<i>` with `position` and `velocity` per joint). Per-joint lines
    /// have one value per joint.
    pub struct ParametricCalibratorEthParams for "parametricCalibratorEth" {
        /// Name of the calibrator in messages
        "GENERAL::deviceName" device_name: String = required,
        /// Number of joints
        "GENERAL::joints" joints: i64 = optional,
        /// Number of joints (another spelling)
        "GENERAL::Joints" joints_cap: i64 = optional,
        /// Clear the boards' hardware faults before calibrating
        "GENERAL::clearHwFaultBeforeCalibration" clear_hw_fault: bool = false,
        /// The motion control uses raw encoder data: calibration is skipped
        "GENERAL::useRawEncoderData" use_raw_encoder_data: bool = false,
        /// Do not calibrate
        "GENERAL::skipCalibration" skip_calibration: bool = false,
        /// Do not calibrate again on a remote request
        "MAINTENANCE::skipRecalibration" skip_recalibration: bool = false,
        /// Calibration type of each joint
        "CALIBRATION::calibrationType" calibration_type: Vec<f64> = required,
        /// First calibration parameter of each joint
        "CALIBRATION::calibration1" calibration1: Vec<f64> = required,
        /// Second calibration parameter of each joint
        "CALIBRATION::calibration2" calibration2: Vec<f64> = required,
        /// Third calibration parameter of each joint
        "CALIBRATION::calibration3" calibration3: Vec<f64> = required,
        /// Fourth calibration parameter of each joint
        "CALIBRATION::calibration4" calibration4: Vec<f64> = required,
        /// Fifth calibration parameter of each joint
        "CALIBRATION::calibration5" calibration5: Vec<f64> = required,
        /// Zero of each joint
        "CALIBRATION::calibrationZero" calibration_zero: Vec<f64> = required; "deg",
        /// Correction added to the zero of each joint (default 0)
        "CALIBRATION::calibrationDelta" calibration_delta: Vec<f64> = optional; "deg",
        /// Position each joint goes to after calibration
        "CALIBRATION::startupPosition" startup_position: Vec<f64> = required; "deg",
        /// Speed of that move
        "CALIBRATION::startupVelocity" startup_velocity: Vec<f64> = required; "deg/s",
        /// How close each joint must get to its startup position
        "CALIBRATION::startupPosThreshold" startup_pos_threshold: Vec<f64> = required; "deg",
        /// PWM limit of each joint while calibrating
        "CALIBRATION::startupMaxPwm" startup_max_pwm: Vec<f64> = required,
        /// Time each joint may take to calibrate (default 20)
        "CALIBRATION::calibrationTimeout" calibration_timeout: Vec<f64> = optional; "s",
        /// Time each joint may take to reach its startup position (default 10)
        "CALIBRATION::startupTimeout" startup_timeout: Vec<f64> = optional; "s",
        /// 1: do not check that the joint reached its startup position
        "CALIBRATION::startupDisablePosCheck" startup_disable_pos_check: Vec<f64> = optional,
        /// Park position of each joint (without PARKING_SEQUENCE)
        "HOME::positionHome" position_home: Vec<f64> = optional; "deg",
        /// Park speed of each joint (without PARKING_SEQUENCE)
        "HOME::velocityHome" velocity_home: Vec<f64> = optional; "deg/s",
        /// 1: the joint does not go home nor park
        "HOME::disableHomeAndPark" disable_home_and_park: Vec<f64> = optional,
        /// Number of SEQUENCE_<i> groups of the park
        "PARKING_SEQUENCE::numberOfSequences" number_of_sequences: i64 = optional,
    }
}

impl DeviceDriver for ParametricCalibratorEth {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        ParametricCalibratorEthParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let id = config
            .find("id")
            .map_or_else(|| NAME.to_string(), Value::to_string_bare);
        self.read(&id, config)?;
        self.calibrated = false;
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.target = None;
        Ok(())
    }

    yarp_devices::views!(as_calibrator, as_remote_calibrator);
}

impl ICalibrator for ParametricCalibratorEth {
    fn calibrate(&mut self, target: SharedDevice) -> DevResult<()> {
        self.target = Some(target.clone());
        self.run_calibration(&target)
    }

    fn park(&mut self, target: SharedDevice, wait: bool) -> DevResult<()> {
        let each_alone = matches!(self.parking, Parking::Home(_))
            && self.joints.iter().any(|c| c.no_home_and_park);
        if each_alone {
            tracing::warn!(device = %self.name, "joints parked one by one: some have disableHomeAndPark");
            let joints: Vec<usize> = self.calib_joints().collect();
            for j in joints {
                if self.quitting() {
                    break;
                }
                self.park_joint(j, wait)?;
            }
            return Ok(());
        }
        if !self.may_park() {
            return Ok(());
        }
        tracing::info!(device = %self.name, "parking");
        let mut parkable = Vec::new();
        for j in self.calib_joints() {
            if self.quitting() {
                break;
            }
            let mode = self.control_mode(&target, j)?;
            if self.parkable(mode, j) {
                self.set_mode(&target, &[j], CM_POSITION);
                parkable.push(j);
            }
        }
        let finished = match &self.parking {
            Parking::Home(pose) => {
                self.move_to(&target, &parkable, |j| {
                    (pose.positions[j], pose.velocities[j])
                })?;
                if wait {
                    self.wait_parked(&target, &parkable)?;
                }
                true
            }
            Parking::Sequence { steps, next } => {
                // C++: one step per park; a step that fails ends the sequence.
                let (steps, next) = (steps.clone(), *next);
                let ok = match steps.get(next) {
                    Some(step) => {
                        let all: Vec<usize> = (0..self.joints.len()).collect();
                        self.move_to(&target, &all, |j| (step.positions[j], step.velocities[j]))?;
                        self.wait_parked(&target, &all)?.is_empty()
                    }
                    None => true,
                };
                tracing::debug!(device = %self.name, "park sequence step {next} ended with {}", if ok { "success" } else { "failure" });
                if let Parking::Sequence { next, .. } = &mut self.parking {
                    *next += 1;
                }
                next + 1 >= steps.len() || !ok
            }
        };
        if finished {
            self.set_mode(&target, &parkable, CM_IDLE);
            tracing::info!(device = %self.name, "park {}", if self.quitting() { "aborted" } else { "done" });
        }
        Ok(())
    }

    fn quit_calibrate(&mut self) -> DevResult<()> {
        self.quit.store(true, Ordering::SeqCst);
        Ok(())
    }

    fn quit_park(&mut self) -> DevResult<()> {
        self.quit.store(true, Ordering::SeqCst);
        Ok(())
    }
}

impl IRemoteCalibrator for ParametricCalibratorEth {
    fn is_calibrator_device_present(&mut self) -> DevResult<bool> {
        Ok(true)
    }
    fn calibrate_single_joint(&mut self, j: usize) -> DevResult<()> {
        self.own_joint(j, "calibration")?;
        let target = self.target()?;
        self.calibrate_joint(&target, j)
    }
    fn calibrate_whole_part(&mut self) -> DevResult<()> {
        let target = self.target()?;
        self.run_calibration(&target)
    }
    fn homing_single_joint(&mut self, j: usize) -> DevResult<()> {
        self.own_joint(j, "homing")?;
        if self.joints[j].no_home_and_park {
            tracing::warn!(device = %self.name, joint = j, "homing disabled on user request (disableHomeAndPark)");
            return Ok(());
        }
        let target = self.target()?;
        self.go_to_startup(&target, j)
    }
    fn homing_whole_part(&mut self) -> DevResult<()> {
        let joints: Vec<usize> = self.calib_joints().collect();
        let mut first_error = None;
        for j in joints {
            if self.quitting() {
                break;
            }
            if let Err(e) = self.homing_single_joint(j) {
                first_error.get_or_insert(e);
            }
        }
        first_error.map_or(Ok(()), Err)
    }
    fn park_single_joint(&mut self, j: usize, wait: bool) -> DevResult<()> {
        self.park_joint(j, wait)
    }
    fn park_whole_part(&mut self) -> DevResult<()> {
        if !self.calibrated {
            return Err(DeviceError::failed(
                &self.name,
                "the part is not calibrated, therefore it cannot be parked",
            ));
        }
        let target = self.target()?;
        self.park(target, true)
    }
    fn quit_calibrate(&mut self) -> DevResult<()> {
        ICalibrator::quit_calibrate(self)
    }
    fn quit_park(&mut self) -> DevResult<()> {
        ICalibrator::quit_park(self)
    }
    fn quit_signal(&self) -> Option<Arc<AtomicBool>> {
        Some(self.quit.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A two-joint calibrator file with `general`, `home` and `extra` lines.
    fn open(general: &str, home: &str, extra: &str) -> DevResult<ParametricCalibratorEth> {
        let text = format!(
            "CALIB_ORDER (0) (1)\n[GENERAL]\ndeviceName test_calib\njoints 2\n{general}\n\
             [CALIBRATION]\ncalibrationType 12 3\ncalibration1 1 2\ncalibration2 0 0\n\
             calibration3 0 0\ncalibration4 0 0\ncalibration5 0 0\ncalibrationZero 10 20\n\
             calibrationDelta 1 -1\nstartupPosition -30 15\nstartupVelocity 10 20\n\
             startupMaxPwm 2000 0\nstartupPosThreshold 2 90\n{extra}\n{home}\n"
        );
        let mut c = ParametricCalibratorEth::new();
        c.open(&Property::from_config_text(&text).unwrap())?;
        Ok(c)
    }

    const HOME: &str = "[HOME]\npositionHome -10 0\nvelocityHome 10 10\n";

    #[test]
    fn reads_the_calibration_and_the_defaults_cpp_gives() {
        let c = open("", HOME, "").unwrap();
        assert_eq!(c.order, [vec![0], vec![1]]);
        assert_eq!(c.joints[0].params.param_zero, 11.0);
        assert_eq!(c.joints[1].params.param_zero, 19.0);
        assert_eq!(c.joints[0].calibration_timeout, Duration::from_secs(20));
        assert_eq!(c.joints[0].startup_timeout, Duration::from_secs(10));
        assert!(!c.joints[0].no_startup && !c.joints[0].no_home_and_park);
        assert!(!c.skip && !c.skip_recalibration && !c.clear_hw_fault);
        let Parking::Home(pose) = &c.parking else {
            panic!("legacy parking expected")
        };
        assert_eq!(pose.positions, [-10.0, 0.0]);
    }

    #[test]
    fn reads_the_optional_parameters() {
        let c = open(
            "clearHwFaultBeforeCalibration true\nuseRawEncoderData true\n[MAINTENANCE]\nskipRecalibration true",
            &format!("{HOME}disableHomeAndPark 0 1\n"),
            "calibrationTimeout 5 6\nstartupTimeout 3 4\nstartupDisablePosCheck 1 0",
        )
        .unwrap();
        assert!(c.skip, "useRawEncoderData forces skipCalibration");
        assert!(c.skip_recalibration && c.clear_hw_fault);
        assert_eq!(c.joints[1].calibration_timeout, Duration::from_secs(6));
        assert_eq!(c.joints[0].startup_timeout, Duration::from_secs(3));
        assert!(c.joints[0].no_startup && !c.joints[1].no_startup);
        assert!(!c.joints[0].no_home_and_park && c.joints[1].no_home_and_park);
    }

    #[test]
    fn a_parking_sequence_replaces_home() {
        let seq = "[PARKING_SEQUENCE]\nnumberOfSequences 2\n\
                   SEQUENCE_0 (position 1 2) (velocity 3 4)\n\
                   SEQUENCE_1 (position 5 6) (velocity 7 8)\n";
        let c = open("", seq, "").unwrap();
        let Parking::Sequence { steps, next } = &c.parking else {
            panic!("a parking sequence expected")
        };
        assert_eq!(*next, 0);
        assert_eq!(steps.len(), 2);
        assert_eq!(steps[1].positions, [5.0, 6.0]);
        assert_eq!(steps[1].velocities, [7.0, 8.0]);

        let short =
            "[PARKING_SEQUENCE]\nnumberOfSequences 1\nSEQUENCE_0 (position 1) (velocity 3 4)\n";
        let e = open("", short, "").err().unwrap().to_string();
        assert!(e.contains("position"), "{e}");
    }

    #[test]
    fn a_park_pose_is_needed() {
        let e = open("", "", "").err().unwrap().to_string();
        assert!(e.contains("HOME") && e.contains("PARKING_SEQUENCE"), "{e}");
    }

    #[test]
    fn remote_calls_name_what_they_cannot_do() {
        let mut c = open("", HOME, "").unwrap();
        let e = c.homing_single_joint(5).unwrap_err().to_string();
        assert!(e.contains("joint number 5 is out of range [0, 1]"), "{e}");
        let e = c.homing_single_joint(0).unwrap_err().to_string();
        assert!(e.contains("not calibrated yet"), "{e}");
        let e = c.park_whole_part().unwrap_err().to_string();
        assert!(e.contains("not calibrated"), "{e}");
        assert!(c.is_calibrator_device_present().unwrap());
    }
}
