//! `cerDoubleLidar` (robotology/cer): R1's front and back lidars as one scan around the
//! base's centre.
//!
//! Parameters as C++: `LASERFRONT-CFG` and `LASERBACK-CFG` groups, each a `sensorName` and
//! a `pose` (x y z in m, theta in rad, where the lidar sits on the base), and the `SENSOR`
//! and `SKIP` groups every 2D laser reads. It attaches exactly two `IRangefinder2D`
//! devices, keyed by the two sensor names, whose resolution must be its own. Each scan
//! reads both: every finite distance is moved into the base's frame and put in the step
//! of its angle there (a later one overwrites), an infinite one marks its step infinite
//! unless something was seen there; steps nothing falls in stay NaN. No clipping after.

use std::f64::consts::PI;
use yarp_devices::driver::{DeviceDriver, IMultipleWrapper, SharedDevice};
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::rangefinder::geometry::{LaserGeometry, Lidar2DParams};
use yarp_devices::rangefinder::{IRangefinder2D, LaserStatus};
use yarp_devices::sensors::params::now;
use yarp_proto::Property;

pub const NAME: &str = "cerDoubleLidar";

yarp_devices::device_params! {
    /// What `cerDoubleLidar` reads besides the `SENSOR`/`SKIP` groups (robotology/cer).
    pub struct CerDoubleLidarParams for "cerDoubleLidar" {
        /// Name of the front lidar (the key it is attached with)
        "LASERFRONT-CFG::sensorName" front_name: String = required,
        /// Pose of the front lidar on the base: x y z (m) theta (rad)
        "LASERFRONT-CFG::pose" front_pose: Vec<f64> = required,
        /// Name of the back lidar (the key it is attached with)
        "LASERBACK-CFG::sensorName" back_name: String = required,
        /// Pose of the back lidar on the base: x y z (m) theta (rad)
        "LASERBACK-CFG::pose" back_pose: Vec<f64> = required,
    }
}

/// Where a lidar sits on the base.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Pose {
    x: f64,
    y: f64,
    theta: f64,
}

impl Pose {
    fn of(v: &[f64], param: &str) -> DevResult<Pose> {
        match v {
            [x, y, _z, theta] => Ok(Pose {
                x: *x,
                y: *y,
                theta: *theta,
            }),
            _ => Err(DeviceError::BadParam {
                device: NAME.into(),
                param: param.into(),
                expected: "four values: x y z theta",
                got: format!("{v:?}"),
            }),
        }
    }
}

/// Step `i`'s distance `d` of a lidar at `pose` put into the merged scan (C++ `calculate`).
fn merge_step(data: &mut [f64], i: usize, d: f64, res: f64, pose: Pose) {
    if d == 0.0 || d.is_nan() {
        return;
    }
    let n = data.len() as i64;
    // the step of an angle in degrees, wrapped once as C++ does
    let step = |angle: f64| {
        let k = (angle / res) as i64;
        let k = if k >= n {
            k - n
        } else if k < 0 {
            k + n
        } else {
            k
        };
        usize::try_from(k).ok()
    };
    if d == f64::INFINITY {
        let slot = step(i as f64 * res + pose.theta * 180.0 / PI).and_then(|k| data.get_mut(k));
        if let Some(slot) = slot.filter(|s| s.is_nan()) {
            *slot = f64::INFINITY;
        }
        return;
    }
    let a = (i as f64 * res).to_radians() + pose.theta;
    let (bx, by) = (a.cos() * d + pose.x, a.sin() * d + pose.y);
    if let Some(slot) = step(by.atan2(bx) * 180.0 / PI).and_then(|k| data.get_mut(k)) {
        *slot = bx.hypot(by);
    }
}

/// A whole scan merged (tests).
#[cfg(test)]
fn merge_into(data: &mut [f64], scan: &[f64], res: f64, pose: Pose) {
    for (i, &d) in scan.iter().enumerate() {
        merge_step(data, i, d, res, pose);
    }
}

/// The `cerDoubleLidar` device.
pub struct CerDoubleLidar {
    geometry: LaserGeometry,
    front: Option<(String, Pose, SharedDevice)>,
    back: Option<(String, Pose, SharedDevice)>,
    names: (String, String),
    poses: (Pose, Pose),
    status: LaserStatus,
}

impl Default for CerDoubleLidar {
    fn default() -> Self {
        let origin = Pose {
            x: 0.0,
            y: 0.0,
            theta: 0.0,
        };
        CerDoubleLidar {
            geometry: LaserGeometry::unset(),
            front: None,
            back: None,
            names: Default::default(),
            poses: (origin, origin),
            status: LaserStatus::GeneralError,
        }
    }
}

impl CerDoubleLidar {
    pub fn new() -> Self {
        Self::default()
    }

    fn scan_of(device: &SharedDevice) -> DevResult<(Vec<f64>, f64)> {
        device
            .lock()
            .device()
            .as_rangefinder_2d()
            .ok_or(DeviceError::NoInterface("IRangefinder2D"))?
            .get_raw_data()
    }

    /// `f` on each lidar, front first.
    fn both(
        &mut self,
        mut f: impl FnMut(&mut dyn IRangefinder2D) -> DevResult<()>,
    ) -> DevResult<()> {
        let (Some(front), Some(back)) = (&self.front, &self.back) else {
            return Err(DeviceError::NotOpen);
        };
        for (_, _, d) in [front, back] {
            let mut pd = d.lock();
            let l = pd
                .device()
                .as_rangefinder_2d()
                .ok_or(DeviceError::NoInterface("IRangefinder2D"))?;
            f(l)?;
        }
        Ok(())
    }
}

impl DeviceDriver for CerDoubleLidar {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        [CerDoubleLidarParams::PARAMS, Lidar2DParams::PARAMS].concat()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let mut geometry = LaserGeometry::unset();
        geometry.configure(Lidar2DParams::read(config)?, NAME)?;
        let p = CerDoubleLidarParams::read(config)?;
        let front = Pose::of(&p.front_pose, "LASERFRONT-CFG::pose")?;
        let back = Pose::of(&p.back_pose, "LASERBACK-CFG::pose")?;
        if p.front_pose[2] != p.back_pose[2] {
            tracing::warn!("{NAME}: the front and back lidars are at different heights");
        }
        self.geometry = geometry;
        self.names = (p.front_name, p.back_name);
        self.poses = (front, back);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        IMultipleWrapper::detach_all(self)
    }

    yarp_devices::views!(as_multiple_wrapper, as_rangefinder_2d);
}

impl IMultipleWrapper for CerDoubleLidar {
    fn attach_all(&mut self, devices: &[(String, SharedDevice)]) -> DevResult<()> {
        if devices.len() != 2 {
            return Err(DeviceError::failed(
                NAME,
                format!("it attaches two lidars, got {}", devices.len()),
            ));
        }
        let (mut front, mut back) = (None, None);
        for (key, d) in devices {
            let resolution = {
                let mut pd = d.lock();
                let l = pd.device().as_rangefinder_2d().ok_or_else(|| {
                    DeviceError::failed(NAME, format!("{key} is no IRangefinder2D"))
                })?;
                l.get_scan_limits()?;
                l.get_distance_range()?;
                l.get_horizontal_resolution()?
            };
            if resolution != self.geometry.resolution {
                return Err(DeviceError::failed(
                    NAME,
                    format!(
                        "{key}'s resolution {resolution} is not this device's {}",
                        self.geometry.resolution
                    ),
                ));
            }
            if *key == self.names.0 {
                front = Some((key.clone(), self.poses.0, d.clone()));
            } else if *key == self.names.1 {
                back = Some((key.clone(), self.poses.1, d.clone()));
            } else {
                return Err(DeviceError::failed(
                    NAME,
                    format!(
                        "{key} is neither the front ({}) nor the back ({}) lidar",
                        self.names.0, self.names.1
                    ),
                ));
            }
        }
        let (Some(f), Some(b)) = (front, back) else {
            return Err(DeviceError::failed(
                NAME,
                "it attaches one front and one back lidar",
            ));
        };
        self.front = Some(f);
        self.back = Some(b);
        Ok(())
    }

    fn detach_all(&mut self) -> DevResult<()> {
        self.front = None;
        self.back = None;
        Ok(())
    }
}

impl IRangefinder2D for CerDoubleLidar {
    fn get_raw_data(&mut self) -> DevResult<(Vec<f64>, f64)> {
        let n = self.geometry.samples();
        let (Some(front), Some(back)) = (&self.front, &self.back) else {
            return Err(DeviceError::NotOpen);
        };
        let scans = Self::scan_of(&front.2).and_then(|f| Ok((f, Self::scan_of(&back.2)?)));
        let ((front_scan, t), (back_scan, _)) = match scans {
            Ok(s) => s,
            Err(e) => {
                self.status = LaserStatus::GeneralError;
                return Err(e);
            }
        };
        let mut data = vec![f64::NAN; n];
        // per step, the front's reading then the back's (C++ interleaves them)
        let res = self.geometry.resolution;
        for i in 0..n {
            for (scan, pose) in [(&front_scan, front.1), (&back_scan, back.1)] {
                if let Some(&d) = scan.get(i) {
                    merge_step(&mut data, i, d, res, pose);
                }
            }
        }
        self.status = LaserStatus::OkInUse;
        Ok((data, if t > 0.0 { t } else { now() }))
    }
    fn get_device_status(&mut self) -> DevResult<LaserStatus> {
        Ok(self.status)
    }
    fn get_distance_range(&mut self) -> DevResult<(f64, f64)> {
        Ok((self.geometry.min_distance, self.geometry.max_distance))
    }
    fn set_distance_range(&mut self, min: f64, max: f64) -> DevResult<()> {
        self.both(|l| l.set_distance_range(min, max))?;
        (self.geometry.min_distance, self.geometry.max_distance) = (min, max);
        Ok(())
    }
    fn get_scan_limits(&mut self) -> DevResult<(f64, f64)> {
        Ok((self.geometry.min_angle, self.geometry.max_angle))
    }
    fn set_scan_limits(&mut self, min: f64, max: f64) -> DevResult<()> {
        self.both(|l| l.set_scan_limits(min, max))?;
        (self.geometry.min_angle, self.geometry.max_angle) = (min, max);
        Ok(())
    }
    fn get_horizontal_resolution(&mut self) -> DevResult<f64> {
        Ok(self.geometry.resolution)
    }
    fn set_horizontal_resolution(&mut self, step: f64) -> DevResult<()> {
        self.both(|l| l.set_horizontal_resolution(step))?;
        self.geometry.resolution = step;
        Ok(())
    }
    fn get_scan_rate(&mut self) -> DevResult<f64> {
        Ok(0.0)
    }
    fn set_scan_rate(&mut self, rate: f64) -> DevResult<()> {
        self.both(|l| l.set_scan_rate(rate))
    }
    fn get_device_info(&mut self) -> DevResult<String> {
        Ok(String::new())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_point_moves_into_the_base_frame() {
        // a lidar 0.07 m ahead, facing forward, sees a wall 1 m ahead at 0 degrees
        let mut data = vec![f64::NAN; 360];
        let front = Pose {
            x: 0.07,
            y: 0.0,
            theta: 0.0,
        };
        merge_into(&mut data, &[1.0], 1.0, front);
        assert!((data[0] - 1.07).abs() < 1e-12);
        // the back lidar, turned by pi, sees the same distance behind: 180 degrees
        let back = Pose {
            x: -0.07,
            y: 0.0,
            theta: PI,
        };
        let mut scan = vec![0.0; 1];
        scan[0] = 1.0;
        merge_into(&mut data, &scan, 1.0, back);
        let behind: Vec<usize> = (1..360)
            .filter(|&k| (data[k] - 1.07).abs() < 1e-9)
            .collect();
        assert!(behind == [179] || behind == [180], "{behind:?}");
        // an infinite reading fills only an empty step
        let mut inf = vec![0.0; 91];
        inf[90] = f64::INFINITY;
        merge_into(&mut data, &inf, 1.0, front);
        assert_eq!(data[90], f64::INFINITY);
        assert_eq!(data.iter().filter(|d| d.is_nan()).count(), 357);
    }
}
