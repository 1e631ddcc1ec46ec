//! `parametricCalibratorEth` (icub-main): calibrates a robot part of `embObj` boards at
//! start-up and parks it at shutdown, through its target (the part's
//! `controlboardremapper`).
//!
//! Parameters as `calibrators/*-calib.xml`: `GENERAL::deviceName`, `joints`,
//! `skipCalibration`; `CALIBRATION::calibrationType`, `calibration1`..`calibration5`,
//! `calibrationZero`, `calibrationDelta` (added to the zero, as C++), `startupPosition`,
//! `startupVelocity`, `startupMaxPwm`, `startupPosThreshold`; `HOME::positionHome`,
//! `velocityHome`; `CALIB_ORDER` (the sets of joints calibrated together, in order).
//!
//! `calibrate`, per set as C++: the PWM limit of each joint is lowered to its
//! `startupMaxPwm` when that is lower (0: unchanged), and given back once the joint has
//! reached its startup position (a joint that fails keeps the safe limit); every joint
//! gets its calibration through
//! `setCalibrationParameters` (all five parameters and the zero, which the board uses
//! by type: 0 hard stops, 3 absolute digital sensor, 5 hard stops (MC4plus), 6 MAIS,
//! 7 hall sensor, 10 absolute + hard stop, 12 absolute sensor, 14 quadrature encoder +
//! hard stop + FAP, ...); after 0.1 s the set waits (20 s at most) until each joint's
//! board reports it calibrated; after 0.5 s it moves to `startupPosition` at
//! `startupVelocity` in position mode and waits (10 s at most) until every joint is
//! within `startupPosThreshold`. A joint that fails is set idle and named; the others go
//! on (as C++, the part then counts as calibrated). `park` moves the calibrated joints
//! that are not idle or faulted to `positionHome` at `velocityHome` (30 s at most).

use std::time::{Duration, Instant};

use yarp_devices::interfaces::CalibrationParameters;
use yarp_devices::vocabs::{CM_HW_FAULT, CM_IDLE, CM_POSITION};
use yarp_devices::{DevResult, DeviceDriver, DeviceError, ICalibrator, SharedDevice};
use yarp_proto::Property;

use super::config::{text, Node, ParamError};

pub const NAME: &str = "parametricCalibratorEth";

const CALIBRATE_TIMEOUT: Duration = Duration::from_secs(20);
const STARTUP_TIMEOUT: Duration = Duration::from_secs(10);
const PARK_TIMEOUT: Duration = Duration::from_secs(30);
const POLL: Duration = Duration::from_millis(20);

#[derive(Debug, Clone, Default)]
struct JointCalib {
    params: CalibrationParameters,
    startup_pos: f64,
    startup_vel: f64,
    /// The PWM limit while calibrating and reaching `startup_pos` (0: left as it is).
    startup_max_pwm: f64,
    threshold: f64,
    home_pos: f64,
    home_vel: f64,
}

/// The `parametricCalibratorEth` device.
#[derive(Debug, Default)]
pub struct ParametricCalibratorEth {
    name: String,
    skip: bool,
    joints: Vec<JointCalib>,
    order: Vec<Vec<usize>>,
    calibrated: bool,
}

fn with<T>(
    target: &SharedDevice,
    f: impl FnOnce(&mut dyn DeviceDriver) -> DevResult<T>,
) -> DevResult<T> {
    let mut pd = target.lock().unwrap_or_else(|e| e.into_inner());
    f(pd.device())
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

    fn read(&mut self, config: &Property) -> Result<(), ParamError> {
        let root = Node::root(config);
        let general = root.need_group("GENERAL")?;
        self.name = general.need_string("deviceName", "the calibrator's name")?;
        self.skip = general.boolean("skipCalibration").unwrap_or(false);
        let n = general
            .number("joints")?
            .or(general.number("Joints")?)
            .ok_or_else(|| ParamError::missing("GENERAL/joints", "the number of joints"))?
            as usize;
        let cal = root.need_group("CALIBRATION")?;
        let home = root.need_group("HOME")?;
        let kind = cal.need_numbers("calibrationType", n)?;
        let c = |k: &str| cal.need_numbers(k, n);
        let (p1, p2, p3, p4, p5) = (
            c("calibration1")?,
            c("calibration2")?,
            c("calibration3")?,
            c("calibration4")?,
            c("calibration5")?,
        );
        let zero = c("calibrationZero")?;
        let delta = cal
            .numbers("calibrationDelta", n)?
            .unwrap_or_else(|| vec![0.0; n]);
        let (pos, vel, thr, max_pwm) = (
            c("startupPosition")?,
            c("startupVelocity")?,
            c("startupPosThreshold")?,
            c("startupMaxPwm")?,
        );
        let (hpos, hvel) = (
            home.need_numbers("positionHome", n)?,
            home.need_numbers("velocityHome", n)?,
        );
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
                home_pos: hpos[j],
                home_vel: hvel[j],
            })
            .collect();
        let order = config
            .find_group("CALIB_ORDER")
            .ok_or_else(|| ParamError::missing("CALIB_ORDER", "lists of joints"))?;
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
                            text(set),
                        )
                    })
            })
            .collect::<Result<_, _>>()?;
        if self.order.is_empty() {
            return Err(ParamError::missing("CALIB_ORDER", "lists of joints"));
        }
        Ok(())
    }

    fn calib_joints(&self) -> impl Iterator<Item = usize> + '_ {
        self.order.iter().flatten().copied()
    }

    fn move_set(
        &self,
        target: &SharedDevice,
        set: &[usize],
        pos: impl Fn(&JointCalib) -> f64,
        vel: impl Fn(&JointCalib) -> f64,
    ) -> DevResult<()> {
        with(target, |d| {
            let cm = d
                .as_control_mode()
                .ok_or(missing("target without IControlMode"))?;
            for &j in set {
                cm.set_control_mode(j, CM_POSITION)?;
            }
            let p = d
                .as_position_control()
                .ok_or(missing("target without IPositionControl"))?;
            for &j in set {
                p.set_ref_speed(j, vel(&self.joints[j]))?;
                p.position_move(j, pos(&self.joints[j]))?;
            }
            Ok(())
        })
    }

    /// Polls `done(j)` for every joint of `set` until all hold or `timeout`; returns the
    /// joints that never did.
    fn wait_until(
        &self,
        target: &SharedDevice,
        set: &[usize],
        timeout: Duration,
        mut done: impl FnMut(&mut dyn DeviceDriver, usize) -> DevResult<bool>,
    ) -> DevResult<Vec<usize>> {
        let start = Instant::now();
        let mut pending: Vec<usize> = set.to_vec();
        loop {
            let mut still = Vec::new();
            for &j in &pending {
                if !with(target, |d| done(d, j))? {
                    still.push(j);
                }
            }
            pending = still;
            if pending.is_empty() || start.elapsed() > timeout {
                return Ok(pending);
            }
            std::thread::sleep(POLL);
        }
    }

    fn idle(&self, target: &SharedDevice, joints: &[usize]) {
        for &j in joints {
            let _ = with(target, |d| {
                d.as_control_mode()
                    .ok_or(missing("target without IControlMode"))?
                    .set_control_mode(j, CM_IDLE)
            });
        }
    }

    /// Lowers the PWM limit of each joint of `set` to its `startupMaxPwm` when that is
    /// lower (0 keeps the limit), as C++ does before calibrating a set; the limits found.
    fn limit_pwm(&self, target: &SharedDevice, set: &[usize]) -> DevResult<Vec<(usize, f64)>> {
        with(target, |d| {
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
                let safe = self.joints[j].startup_max_pwm;
                if safe != 0.0 && safe < limit {
                    amp.set_pwm_limit(j, safe)?;
                }
            }
            Ok(original)
        })
    }

    /// Gives the joints of `original` their limits back.
    fn restore_pwm(&self, target: &SharedDevice, original: &[(usize, f64)]) {
        let restored = with(target, |d| {
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

    fn calibrate_set(&self, target: &SharedDevice, set: &[usize]) -> DevResult<Vec<usize>> {
        let original = self.limit_pwm(target, set)?;
        with(target, |d| {
            let c = d
                .as_control_calibration()
                .ok_or(missing("target without IControlCalibration"))?;
            for &j in set {
                tracing::debug!(device = %self.name, joint = j, kind = self.joints[j].params.kind, "calibrateJoint");
                c.set_calibration_parameters(j, &self.joints[j].params)?;
            }
            Ok(())
        })?;
        std::thread::sleep(Duration::from_millis(100));
        let failed = self.wait_until(target, set, CALIBRATE_TIMEOUT, |d, j| {
            d.as_control_calibration()
                .ok_or(missing("target without IControlCalibration"))?
                .calibration_done(j)
        })?;
        if !failed.is_empty() {
            tracing::error!(device = %self.name, "joints {failed:?} failed the calibration (not calibrated after {CALIBRATE_TIMEOUT:?}): idling them");
            self.idle(target, &failed);
        }
        let ok: Vec<usize> = set
            .iter()
            .copied()
            .filter(|j| !failed.contains(j))
            .collect();
        std::thread::sleep(Duration::from_millis(500));
        self.move_set(target, &ok, |c| c.startup_pos, |c| c.startup_vel)?;
        let far = self.wait_until(target, &ok, STARTUP_TIMEOUT, |d, j| {
            let at = d
                .as_encoders()
                .ok_or(missing("target without IEncoders"))?
                .get_encoder(j)?;
            Ok((at - self.joints[j].startup_pos).abs() <= self.joints[j].threshold)
        })?;
        if !far.is_empty() {
            tracing::error!(device = %self.name, "joints {far:?} did not reach their startupPosition within startupPosThreshold: idling them");
            self.idle(target, &far);
        }
        // Those that reached it get their PWM limit back; the others keep the safe one.
        let reached: Vec<(usize, f64)> = original
            .into_iter()
            .filter(|(j, _)| ok.contains(j) && !far.contains(j))
            .collect();
        self.restore_pwm(target, &reached);
        Ok(failed.into_iter().chain(far).collect())
    }
}

impl DeviceDriver for ParametricCalibratorEth {
    fn open(&mut self, config: &Property) -> DevResult<()> {
        let id = config.find("id").map_or_else(|| NAME.to_string(), text);
        self.read(config).map_err(|e| e.for_device(&id))?;
        self.calibrated = false;
        Ok(())
    }

    fn as_calibrator(&mut self) -> Option<&mut dyn ICalibrator> {
        Some(self)
    }
}

impl ICalibrator for ParametricCalibratorEth {
    fn calibrate(&mut self, target: SharedDevice) -> DevResult<()> {
        self.calibrated = false;
        let axes = with(&target, |d| {
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
        if self.skip {
            tracing::warn!(device = %self.name, "skipCalibration is on: not calibrating");
            self.calibrated = true;
            return Ok(());
        }
        tracing::info!(device = %self.name, "starting calibration");
        let mut failed = Vec::new();
        for set in &self.order {
            failed.extend(self.calibrate_set(&target, set)?);
        }
        if !failed.is_empty() {
            // As C++: the failed joints stay idle, the part counts as calibrated.
            tracing::error!(device = %self.name, "joints {failed:?} failed the calibration and were left idle");
        }
        self.calibrated = true;
        tracing::info!(device = %self.name, "calibration done");
        Ok(())
    }

    fn park(&mut self, target: SharedDevice, wait: bool) -> DevResult<()> {
        if !self.calibrated || self.skip {
            tracing::warn!(device = %self.name, "park without calibration: skipping");
            return Ok(());
        }
        let mut movable = Vec::new();
        for j in self.calib_joints() {
            let mode = with(&target, |d| {
                d.as_control_mode()
                    .ok_or(missing("target without IControlMode"))?
                    .get_control_mode(j)
            })?;
            if mode == CM_IDLE || mode == CM_HW_FAULT {
                tracing::warn!(device = %self.name, joint = j, "joint idle or faulted: not parking");
            } else {
                movable.push(j);
            }
        }
        tracing::info!(device = %self.name, "parking");
        self.move_set(&target, &movable, |c| c.home_pos, |c| c.home_vel)?;
        if wait {
            let late = self.wait_until(&target, &movable, PARK_TIMEOUT, |d, j| {
                d.as_position_control()
                    .ok_or(missing("target without IPositionControl"))?
                    .check_motion_done(j)
            })?;
            if !late.is_empty() {
                return Err(DeviceError::failed(
                    &self.name,
                    format!("joints {late:?} still moving after {PARK_TIMEOUT:?}"),
                ));
            }
        }
        tracing::info!(device = %self.name, "park done");
        Ok(())
    }
}
