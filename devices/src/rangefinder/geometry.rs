//! What every 2D laser device of C++ YARP shares through `Lidar2DDeviceBase`: the `SENSOR`
//! group (field of view, resolution, clipping distances, `allow_infinity`) and the `SKIP`
//! group (angle ranges left as measured), their checks, and the clipping of a scan
//! (`applyLimitsOnLaserData`). Used by `fakeLaser`, R1's lidars and `cerDoubleLidar`.

use crate::error::{DevResult, DeviceError};

crate::device_params! {
    /// The `SENSOR` and `SKIP` groups C++'s `Lidar2DDeviceBase::parseConfiguration` reads.
    pub struct Lidar2DParams for "Lidar2DDeviceBase" {
        /// Start of the field of view
        "SENSOR::min_angle" min_angle: f64 = optional; "deg",
        /// End of the field of view
        "SENSOR::max_angle" max_angle: f64 = optional; "deg",
        /// Angle between two measurements
        "SENSOR::resolution" resolution: f64 = optional; "deg",
        /// Distances below are clipped
        "SENSOR::min_distance" min_distance: f64 = optional; "m",
        /// Distances above are clipped
        "SENSOR::max_distance" max_distance: f64 = optional; "m",
        /// 1: a clipped distance reads as infinity
        "SENSOR::allow_infinity" allow_infinity: i64 = optional,
        /// Starts of the angular ranges not measured
        "SKIP::min" skip_min: Vec<f64> = optional; "deg",
        /// Ends of the angular ranges not measured
        "SKIP::max" skip_max: Vec<f64> = optional; "deg",
    }
}

/// The scan geometry and clipping (C++ `Lidar2DDeviceBase`'s parameters).
#[derive(Debug, Clone, PartialEq)]
pub struct LaserGeometry {
    pub min_angle: f64,
    pub max_angle: f64,
    pub resolution: f64,
    pub min_distance: f64,
    pub max_distance: f64,
    pub clip_min: bool,
    pub clip_max: bool,
    pub allow_infinity: bool,
    /// Angle ranges (degrees from the first step) left as measured.
    pub skip: Vec<(f64, f64)>,
}

impl LaserGeometry {
    /// Number of steps in a scan (C++ `(int)(fov / resolution)`).
    pub fn samples(&self) -> usize {
        ((self.max_angle - self.min_angle) / self.resolution) as usize
    }

    /// C++ `applyLimitsOnLaserData`.
    pub fn apply_limits(&self, data: &mut [f64]) {
        for (i, d) in data.iter_mut().enumerate() {
            let angle = i as f64 * self.resolution;
            if d.is_nan() || self.skip.iter().any(|&(lo, hi)| angle > lo && angle < hi) {
                continue;
            }
            if self.clip_min && *d < self.min_distance {
                *d = if self.allow_infinity {
                    f64::INFINITY
                } else {
                    self.min_distance
                };
            }
            if self.clip_max && *d > self.max_distance {
                *d = if self.allow_infinity {
                    f64::INFINITY
                } else {
                    self.max_distance
                };
            }
        }
    }
}

impl LaserGeometry {
    /// C++'s geometry before its configuration: no field of view (the configuration must
    /// give one), clipping at 0.1 and 30 m once asked for, infinity kept.
    pub fn unset() -> LaserGeometry {
        LaserGeometry {
            min_angle: 0.0,
            max_angle: 0.0,
            resolution: 0.0,
            min_distance: 0.1,
            max_distance: 30.0,
            clip_min: false,
            clip_max: false,
            allow_infinity: false,
            skip: Vec::new(),
        }
    }

    /// Applies the configuration `p` over these defaults and checks the result as C++
    /// does; errors name `device`.
    pub fn configure(&mut self, p: Lidar2DParams, device: &str) -> DevResult<()> {
        let bad = |param: &str, expected: &'static str, got: String| DeviceError::BadParam {
            device: device.into(),
            param: param.into(),
            expected,
            got,
        };
        self.min_angle = p.min_angle.unwrap_or(self.min_angle);
        self.max_angle = p.max_angle.unwrap_or(self.max_angle);
        self.resolution = p.resolution.unwrap_or(self.resolution);
        if let Some(v) = p.min_distance {
            (self.min_distance, self.clip_min) = (v, true);
        }
        if let Some(v) = p.max_distance {
            (self.max_distance, self.clip_max) = (v, true);
        }
        self.allow_infinity = p.allow_infinity == Some(1);
        let skips = p.skip_min.unwrap_or_default();
        for (lo, hi) in skips.into_iter().zip(p.skip_max.unwrap_or_default()) {
            if !(0.0..=360.0).contains(&lo) || !(0.0..=360.0).contains(&hi) || hi <= lo {
                return Err(bad("SKIP", "ranges within 0..360", format!("{lo} {hi}")));
            }
            self.skip.push((lo, hi));
        }
        if self.max_distance - self.min_distance <= 0.0 {
            return Err(bad(
                "SENSOR::max_distance",
                "more than min_distance",
                self.max_distance.to_string(),
            ));
        }
        let fov = self.max_angle - self.min_angle;
        if fov <= 0.0 || fov > 360.0 {
            return Err(bad(
                "SENSOR::max_angle",
                "above min_angle by at most 360",
                self.max_angle.to_string(),
            ));
        }
        if self.resolution <= 0.0 {
            return Err(bad(
                "SENSOR::resolution",
                "> 0",
                self.resolution.to_string(),
            ));
        }
        Ok(())
    }
}
