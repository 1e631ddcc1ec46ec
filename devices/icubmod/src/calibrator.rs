//! `parametricCalibrator` (icub-main): calibrates a robot part at startup and parks it
//! at shutdown, driving its target (usually a `controlboardremapper` over
//! `canmotioncontrol` devices) through the motor interfaces.
//!
//! Parameters, as `calibrators/*_calib.xml`: `GENERAL::deviceName`, `GENERAL::joints`
//! (or `Joints`), `GENERAL::skipCalibration`; `CALIBRATION::calibrationType`,
//! `calibration1`..`calibration3`, `startupPosition`, `startupVelocity`,
//! `startupPosThreshold` (used), `startupMaxPwm`, `calibration4`, `calibration5`,
//! `calibrationZero`, `calibrationDelta` (accepted, unused); `HOME::positionHome`,
//! `HOME::velocityHome` (the park pose); `CALIB_ORDER` (sets of joints calibrated
//! together, in order).
//!
//! `calibrate`, per set: joints of calibration type 0, 2 or 4 go to position mode; each
//! joint gets its calibration command through the target's `IControlCalibration` (as
//! C++ `calibrateAxisWithParams`; the remapper forwards it to the joint's board); the set
//! waits for motion
//! done (20 s), then moves to `startupPosition` at `startupVelocity` and waits (10 s)
//! until every joint is within `startupPosThreshold`. `park` moves the calibrated
//! joints that are not idle or faulted to `positionHome` (waiting up to 30 s when asked).
//! Any board error stops the sequence with that error; no step waits without a bound.
//!
//! `IRemoteCalibrator` (what a client reaches with `[set] [reca] …` on the part's
//! `rpc:i` once yarprobotinterface has made this the remapper's calibrator device), as
//! icub-main's `parametricCalibrator`: `calibrateSingleJoint`/`calibrateWholePart` run
//! the calibration above for that joint / every `CALIB_ORDER` set, `homingSingleJoint`/
//! `homingWholePart` move to `HOME::positionHome` at `velocityHome` and wait (30 s),
//! `parkSingleJoint`/`parkWholePart` are the park above, `quitCalibrate`/`quitPark` stop
//! the running procedure. These calls arrive while the caller holds the target's lock,
//! so they never lock the target: they drive the joints' boards directly, found in
//! [`crate::boards`] by the axis names read from the target at `calibrate`. Every
//! wait is bounded and stops when a quit is asked.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use icub_can::client::MotorControlClient;
use icub_can::proto::ControlMode;

use yarp_proto::Property;

use yarp_devices::driver::{DeviceDriver, ICalibrator, SharedDevice};
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::interfaces::IRemoteCalibrator;
use yarp_devices::params::per_joint;
use yarp_devices::vocabs::{CM_HW_FAULT, CM_IDLE, CM_POSITION};

pub(crate) const NAME: &str = "parametricCalibrator";

const CALIBRATE_JOINT_TIMEOUT: Duration = Duration::from_secs(20);
const GO_TO_ZERO_TIMEOUT: Duration = Duration::from_secs(10);
const PARK_TIMEOUT: Duration = Duration::from_secs(30);
const POLL: Duration = Duration::from_millis(20);

/// Per-joint calibration parameters.
#[derive(Debug, Clone, Default)]
struct JointCalib {
    kind: u8,
    params: [f64; 3],
    startup_pos: f64,
    startup_vel: f64,
    threshold: f64,
    home_pos: f64,
    home_vel: f64,
}

/// The `parametricCalibrator` device.
#[derive(Debug, Default)]
pub struct ParametricCalibrator {
    name: String,
    skip: bool,
    joints: Vec<JointCalib>,
    order: Vec<Vec<usize>>,
    calibrated: bool,
    /// The target's axis names, read at `calibrate` (for the remote calls).
    axis_names: Vec<String>,
    /// Set by `quitCalibrate`/`quitPark`: the running procedure's waits stop.
    quit: Arc<AtomicBool>,
}

impl ParametricCalibrator {
    pub fn new() -> Self {
        Self::default()
    }

    /// Whether the last `calibrate` succeeded.
    pub fn is_calibrated(&self) -> bool {
        self.calibrated
    }

    fn fail(&self, param: &str, expected: &'static str, got: String) -> DeviceError {
        tracing::error!(device = %self.name, "{param}: {got}");
        DeviceError::BadParam {
            device: self.name.clone(),
            param: param.to_string(),
            expected,
            got,
        }
    }

    fn calib_joints(&self) -> impl Iterator<Item = usize> + '_ {
        self.order.iter().flatten().copied()
    }

    /// Sends the board calibration command of joint `j` of `target`.
    /// The joint's calibration command, through the target's `IControlCalibration` as
    /// C++ (`calibrateAxisWithParams`): a remapper forwards it to the board driving the
    /// joint, whatever kind of board that is.
    fn calibrate_joint(&self, target: &SharedDevice, j: usize) -> DevResult<()> {
        let c = &self.joints[j];
        with(target, |d| {
            d.as_control_calibration()
                .ok_or(DeviceError::Unsupported(
                    "target without IControlCalibration",
                ))?
                .calibrate_axis_with_params(
                    j,
                    u32::from(c.kind),
                    c.params[0],
                    c.params[1],
                    c.params[2],
                )
        })
    }

    /// The flag `quitCalibrate`/`quitPark` raise; a procedure's waits stop when it is set.
    pub fn quit_handle(&self) -> Arc<AtomicBool> {
        self.quit.clone()
    }

    fn stopped(&self) -> DevResult<()> {
        if self.quit.load(Ordering::SeqCst) {
            tracing::warn!(device = %self.name, "stopped by quitCalibrate/quitPark");
            Err(DeviceError::Unsupported(
                "stopped by quitCalibrate / quitPark",
            ))
        } else {
            Ok(())
        }
    }

    // ---- IRemoteCalibrator: the boards directly, never the (locked) target ----

    /// The board and board joint of target joint `j`.
    fn board(&self, j: usize) -> DevResult<(Arc<MotorControlClient>, usize)> {
        if j >= self.joints.len() {
            return Err(DeviceError::InvalidJoint {
                joint: j as i64,
                axes: self.joints.len(),
            });
        }
        let name = self.axis_names.get(j).ok_or(DeviceError::Unsupported(
            "the calibrator has not calibrated its target yet",
        ))?;
        crate::boards::find(name).ok_or(DeviceError::Unsupported("no CAN board drives this joint"))
    }

    fn direct<T>(
        &self,
        j: usize,
        f: impl FnOnce(&MotorControlClient, usize) -> Result<T, icub_can::client::ClientError>,
    ) -> DevResult<T> {
        let (client, jj) = self.board(j)?;
        f(&client, jj).map_err(|e| crate::common::call_error(&self.name, e))
    }

    /// Position mode, then a move of `set` to `pos(j)` at `vel(j)`, on the boards.
    fn move_direct(
        &self,
        set: &[usize],
        pos: impl Fn(&JointCalib) -> f64,
        vel: impl Fn(&JointCalib) -> f64,
    ) -> DevResult<()> {
        for &j in set {
            let c = &self.joints[j];
            self.direct(j, |b, jj| {
                b.set_control_mode(jj, ControlMode::Position)?;
                b.set_ref_speed(jj, vel(c))?;
                b.position_move(jj, pos(c))
            })?;
        }
        Ok(())
    }

    /// Waits (bounded, stoppable) until the boards report `set` done moving.
    fn wait_direct(&self, set: &[usize], timeout: Duration) -> DevResult<()> {
        let start = Instant::now();
        loop {
            self.stopped()?;
            let mut done = true;
            for &j in set {
                done &= self.direct(j, |b, jj| b.motion_done(jj))?;
            }
            if done {
                return Ok(());
            }
            if start.elapsed() > timeout {
                return Err(self.fail(
                    "HOME",
                    "joints that finish moving in time",
                    format!("joints {set:?} still moving after {timeout:?}"),
                ));
            }
            std::thread::sleep(POLL);
        }
    }

    /// The calibration of one `CALIB_ORDER` set, on the boards.
    fn calibrate_set_direct(&self, set: &[usize]) -> DevResult<()> {
        for &j in set {
            let c = &self.joints[j];
            self.direct(j, |b, jj| {
                if matches!(c.kind, 0 | 2 | 4) {
                    b.set_control_mode(jj, ControlMode::Position)?;
                }
                b.calibrate(jj, c.kind, c.params[0], c.params[1], c.params[2])
            })?;
        }
        self.wait_direct(set, CALIBRATE_JOINT_TIMEOUT)?;
        self.move_direct(set, |c| c.startup_pos, |c| c.startup_vel)?;
        self.wait_direct(set, GO_TO_ZERO_TIMEOUT)?;
        for &j in set {
            let at = self.direct(j, |b, jj| b.encoder(jj))?;
            self.check_startup_position(j, at)?;
        }
        Ok(())
    }

    /// Fails when joint `j`, at `at` after the move, missed its startup position.
    fn check_startup_position(&self, j: usize, at: f64) -> DevResult<()> {
        let c = &self.joints[j];
        if (at - c.startup_pos).abs() > c.threshold {
            return Err(self.fail(
                "CALIBRATION::startupPosThreshold",
                "joints that reach their startup position",
                format!(
                    "joint {j} at {at:.2}, startup position {:.2}",
                    c.startup_pos
                ),
            ));
        }
        Ok(())
    }

    /// The joints of `set` that are neither idle nor faulted (a park leaves those alone).
    fn movable_direct(&self, set: &[usize]) -> DevResult<Vec<usize>> {
        let mut movable = Vec::new();
        for &j in set {
            let mode = self.direct(j, |b, jj| b.control_mode(jj))?;
            if matches!(
                mode,
                ControlMode::Idle | ControlMode::ForceIdle | ControlMode::HwFault
            ) {
                tracing::warn!(device = %self.name, joint = j, "joint idle or faulted: not parking");
            } else {
                movable.push(j);
            }
        }
        Ok(movable)
    }

    fn home_direct(&self, set: &[usize], park: bool, wait: bool) -> DevResult<()> {
        self.quit.store(false, Ordering::SeqCst);
        let set = if park {
            self.movable_direct(set)?
        } else {
            set.to_vec()
        };
        self.move_direct(&set, |c| c.home_pos, |c| c.home_vel)?;
        if wait {
            self.wait_direct(&set, PARK_TIMEOUT)?;
        }
        Ok(())
    }

    /// Waits until every joint of `set` reports motion done, or fails after `timeout`.
    fn wait_done(&self, target: &SharedDevice, set: &[usize], timeout: Duration) -> DevResult<()> {
        let start = Instant::now();
        loop {
            let done = with(target, |d| {
                let p = d
                    .as_position_control()
                    .ok_or(DeviceError::Unsupported("target without IPositionControl"))?;
                set.iter()
                    .try_fold(true, |all, j| Ok(all & p.check_motion_done(*j)?))
            })?;
            if done {
                return Ok(());
            }
            self.stopped()?;
            if start.elapsed() > timeout {
                return Err(self.fail(
                    "CALIB_ORDER",
                    "joints that finish moving in time",
                    format!("joints {set:?} still moving after {timeout:?}"),
                ));
            }
            std::thread::sleep(POLL);
        }
    }

    /// Position mode, then a move of `set` to `pos(j)` at `vel(j)`.
    fn move_set(
        &self,
        target: &SharedDevice,
        set: &[usize],
        pos: impl Fn(&JointCalib) -> f64,
        vel: impl Fn(&JointCalib) -> f64,
    ) -> DevResult<()> {
        with(target, |d| {
            for &j in set {
                d.as_control_mode()
                    .ok_or(DeviceError::Unsupported("target without IControlMode"))?
                    .set_control_mode(j, CM_POSITION)?;
            }
            let p = d
                .as_position_control()
                .ok_or(DeviceError::Unsupported("target without IPositionControl"))?;
            for &j in set {
                p.set_ref_speed(j, vel(&self.joints[j]))?;
                p.position_move(j, pos(&self.joints[j]))?;
            }
            Ok(())
        })
    }

    fn calibrate_set(&self, target: &SharedDevice, set: &[usize]) -> DevResult<()> {
        with(target, |d| {
            let cm = d
                .as_control_mode()
                .ok_or(DeviceError::Unsupported("target without IControlMode"))?;
            for &j in set {
                if matches!(self.joints[j].kind, 0 | 2 | 4) {
                    cm.set_control_mode(j, CM_POSITION)?;
                }
            }
            Ok(())
        })?;
        for &j in set {
            self.calibrate_joint(target, j)?;
        }
        self.wait_calibrated(target, set, CALIBRATE_JOINT_TIMEOUT)?;
        self.move_set(target, set, |c| c.startup_pos, |c| c.startup_vel)?;
        self.wait_startup_position(target, set, GO_TO_ZERO_TIMEOUT)
    }

    /// Waits until every joint of `set` says its calibration is done and it stands still
    /// (C++ `checkCalibrateJointEnded` asks `calibrationDone`: a motion-done flag alone may
    /// still be the one from before the calibration started, on a busy machine).
    fn wait_calibrated(
        &self,
        target: &SharedDevice,
        set: &[usize],
        timeout: Duration,
    ) -> DevResult<()> {
        let start = Instant::now();
        loop {
            let done = with(target, |d| {
                let mut all = true;
                for &j in set {
                    let c = d
                        .as_control_calibration()
                        .ok_or(DeviceError::Unsupported(
                            "target without IControlCalibration",
                        ))?
                        .calibration_done(j)?;
                    let p = d
                        .as_position_control()
                        .ok_or(DeviceError::Unsupported("target without IPositionControl"))?
                        .check_motion_done(j)?;
                    all &= c && p;
                }
                Ok(all)
            })?;
            if done {
                return Ok(());
            }
            self.stopped()?;
            if start.elapsed() > timeout {
                return Err(self.fail(
                    "CALIB_ORDER",
                    "joints that finish calibrating in time",
                    format!("joints {set:?} still calibrating after {timeout:?}"),
                ));
            }
            std::thread::sleep(POLL);
        }
    }

    /// Waits until every joint of `set` stands within `startupPosThreshold` of its startup
    /// position (C++ `checkGoneToZeroThreshold`: position and motion done polled until
    /// `timeout`, so a move that has not begun yet is not taken for one that ended).
    fn wait_startup_position(
        &self,
        target: &SharedDevice,
        set: &[usize],
        timeout: Duration,
    ) -> DevResult<()> {
        let start = Instant::now();
        loop {
            let at = with(target, |d| {
                let e = d
                    .as_encoders()
                    .ok_or(DeviceError::Unsupported("target without IEncoders"))?;
                set.iter()
                    .map(|&j| e.get_encoder(j))
                    .collect::<DevResult<Vec<f64>>>()
            })?;
            let missed = set
                .iter()
                .zip(&at)
                .find(|(&j, &q)| (q - self.joints[j].startup_pos).abs() > self.joints[j].threshold);
            let Some((&j, &q)) = missed else {
                return self.wait_done(target, set, timeout.saturating_sub(start.elapsed()));
            };
            self.stopped()?;
            if start.elapsed() > timeout {
                return self.check_startup_position(j, q);
            }
            std::thread::sleep(POLL);
        }
    }
}

/// Runs `f` on the locked target.
fn with<T>(
    target: &SharedDevice,
    f: impl FnOnce(&mut dyn DeviceDriver) -> DevResult<T>,
) -> DevResult<T> {
    let mut pd = target.lock();
    f(pd.device())
}

yarp_devices::device_params! {
    /// What `parametricCalibrator` reads (icub-main's, for CAN parts), besides
    /// `CALIB_ORDER` (lists of joints calibrated together, in order). Per-joint lines have
    /// one value per joint.
    pub struct ParametricCalibratorParams for "parametricCalibrator" {
        /// Name of the calibrator in messages
        "GENERAL::deviceName" device_name: String = required,
        /// Do not calibrate
        "GENERAL::skipCalibration" skip_calibration: bool = false,
        /// Number of joints
        "GENERAL::joints" joints: usize = optional,
        /// Number of joints (another spelling)
        "GENERAL::Joints" joints_cap: usize = optional,
        /// Calibration type of each joint
        "CALIBRATION::calibrationType" calibration_type: Vec<f64> = required,
        /// First calibration parameter of each joint
        "CALIBRATION::calibration1" calibration1: Vec<f64> = required,
        /// Second calibration parameter of each joint
        "CALIBRATION::calibration2" calibration2: Vec<f64> = required,
        /// Third calibration parameter of each joint
        "CALIBRATION::calibration3" calibration3: Vec<f64> = required,
        /// Position each joint goes to after calibration
        "CALIBRATION::startupPosition" startup_position: Vec<f64> = required; "deg",
        /// Speed of that move
        "CALIBRATION::startupVelocity" startup_velocity: Vec<f64> = required; "deg/s",
        /// How close each joint must get to its startup position
        "CALIBRATION::startupPosThreshold" startup_pos_threshold: Vec<f64> = required; "deg",
        /// Park position of each joint
        "HOME::positionHome" position_home: Vec<f64> = required; "deg",
        /// Park speed of each joint
        "HOME::velocityHome" velocity_home: Vec<f64> = required; "deg/s",
    }
}

impl DeviceDriver for ParametricCalibrator {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        ParametricCalibratorParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let missing = |param: &str| DeviceError::MissingParam {
            device: NAME.to_string(),
            param: param.to_string(),
        };
        let p = ParametricCalibratorParams::read(config)?;
        self.name = p.device_name;
        self.skip = p.skip_calibration;
        let n = p
            .joints
            .or(p.joints_cap)
            .ok_or_else(|| missing("GENERAL::joints"))?;
        let name = self.name.clone();
        let vector = |key: &str, v: Vec<f64>| per_joint(&name, key, v, n);
        let kind = vector("CALIBRATION::calibrationType", p.calibration_type)?;
        let (p1, p2, p3) = (
            vector("CALIBRATION::calibration1", p.calibration1)?,
            vector("CALIBRATION::calibration2", p.calibration2)?,
            vector("CALIBRATION::calibration3", p.calibration3)?,
        );
        let (pos, vel) = (
            vector("CALIBRATION::startupPosition", p.startup_position)?,
            vector("CALIBRATION::startupVelocity", p.startup_velocity)?,
        );
        let thr = vector("CALIBRATION::startupPosThreshold", p.startup_pos_threshold)?;
        let (hpos, hvel) = (
            vector("HOME::positionHome", p.position_home)?,
            vector("HOME::velocityHome", p.velocity_home)?,
        );
        self.joints = (0..n)
            .map(|j| JointCalib {
                kind: kind[j] as u8,
                params: [p1[j], p2[j], p3[j]],
                startup_pos: pos[j],
                startup_vel: vel[j],
                threshold: thr[j],
                home_pos: hpos[j],
                home_vel: hvel[j],
            })
            .collect();
        let order = config
            .find_group("CALIB_ORDER")
            .ok_or_else(|| missing("CALIB_ORDER"))?;
        self.order = order
            .iter()
            .skip(1)
            .map(|set| {
                let joints: Option<Vec<usize>> = set.as_list().and_then(|l| {
                    l.iter()
                        .map(|v| v.as_i64().and_then(|j| usize::try_from(j).ok()))
                        .collect()
                });
                joints
                    .filter(|js| js.iter().all(|j| *j < n))
                    .ok_or_else(|| DeviceError::BadParam {
                        device: self.name.clone(),
                        param: "CALIB_ORDER".into(),
                        expected: "lists of joint indices below `joints`",
                        got: set.to_string_bare(),
                    })
            })
            .collect::<DevResult<_>>()?;
        if self.order.is_empty() {
            return Err(missing("CALIB_ORDER"));
        }
        self.calibrated = false;
        Ok(())
    }

    yarp_devices::views!(as_calibrator, as_remote_calibrator);
}

impl IRemoteCalibrator for ParametricCalibrator {
    fn is_calibrator_device_present(&mut self) -> DevResult<bool> {
        Ok(true)
    }
    fn calibrate_single_joint(&mut self, j: usize) -> DevResult<()> {
        self.quit.store(false, Ordering::SeqCst);
        self.board(j)?;
        tracing::info!(device = %self.name, joint = j, "remote calibration of one joint");
        self.calibrate_set_direct(&[j])
    }
    fn calibrate_whole_part(&mut self) -> DevResult<()> {
        self.quit.store(false, Ordering::SeqCst);
        tracing::info!(device = %self.name, "remote calibration of the whole part");
        for set in &self.order {
            self.calibrate_set_direct(set)?;
        }
        Ok(())
    }
    fn homing_single_joint(&mut self, j: usize) -> DevResult<()> {
        self.board(j)?;
        self.home_direct(&[j], false, true)
    }
    fn homing_whole_part(&mut self) -> DevResult<()> {
        let all: Vec<usize> = self.calib_joints().collect();
        self.home_direct(&all, false, true)
    }
    fn park_single_joint(&mut self, j: usize, wait: bool) -> DevResult<()> {
        self.board(j)?;
        self.home_direct(&[j], true, wait)
    }
    fn park_whole_part(&mut self) -> DevResult<()> {
        let all: Vec<usize> = self.calib_joints().collect();
        self.home_direct(&all, true, true)
    }
    fn quit_signal(&self) -> Option<Arc<AtomicBool>> {
        Some(self.quit.clone())
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

impl ICalibrator for ParametricCalibrator {
    fn calibrate(&mut self, target: SharedDevice) -> DevResult<()> {
        tracing::info!(device = %self.name, "starting calibration");
        self.calibrated = false;
        let axes = with(&target, |d| {
            d.as_encoders()
                .ok_or(DeviceError::Unsupported("target without IEncoders"))?
                .get_axes()
        })?;
        self.quit.store(false, Ordering::SeqCst);
        self.axis_names = with(&target, |d| {
            let info = d
                .as_axis_info()
                .ok_or(DeviceError::Unsupported("target without IAxisInfo"))?;
            (0..axes).map(|j| info.get_axis_name(j)).collect()
        })?;
        if let Some(j) = self.calib_joints().find(|j| *j >= axes) {
            return Err(self.fail(
                "CALIB_ORDER",
                "joints of the target",
                format!("joint {j}, target has {axes}"),
            ));
        }
        if self.skip {
            tracing::warn!(device = %self.name, "skipCalibration is on: not calibrating");
        } else {
            // As icub-main: a set that fails is reported and the next ones still run.
            let mut first_error = None;
            for set in &self.order {
                if let Err(e) = self.calibrate_set(&target, set) {
                    self.stopped()?;
                    tracing::error!(device = %self.name, "joints {set:?}: {e}");
                    first_error.get_or_insert(e);
                }
            }
            if let Some(e) = first_error {
                return Err(e);
            }
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
        self.quit.store(false, Ordering::SeqCst);
        let mut movable = Vec::new();
        for j in self.calib_joints() {
            let mode = with(&target, |d| {
                d.as_control_mode()
                    .ok_or(DeviceError::Unsupported("target without IControlMode"))?
                    .get_control_mode(j)
            })?;
            if mode == CM_IDLE || mode == CM_HW_FAULT {
                tracing::warn!(device = %self.name, joint = j, "joint idle or faulted: not parking");
            } else {
                movable.push(j);
            }
        }
        self.move_set(&target, &movable, |c| c.home_pos, |c| c.home_vel)?;
        if wait {
            self.wait_done(&target, &movable, PARK_TIMEOUT)?;
        }
        tracing::info!(device = %self.name, "park done");
        Ok(())
    }
}
