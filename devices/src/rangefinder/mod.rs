//! 2D laser rangefinders: the `IRangefinder2D` interface (C++ `yarp::dev::IRangefinder2D`),
//! `fakeLaser`, the YARP network wrapper `rangefinder2D_nws_yarp` and its client
//! `rangefinder2D_nwc_yarp`.

pub mod fake;
pub mod geometry;
pub mod nwc;
pub mod nws;
pub mod protocol;

use crate::driver::Factory;
use crate::error::DevResult;

/// Device status (C++ `IRangefinder2D::Device_status`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LaserStatus {
    OkStandby = 0,
    OkInUse = 1,
    GeneralError = 2,
    Timeout = 3,
}

/// A planar laser scanner (C++ `IRangefinder2D`). Angles are in degrees, distances in
/// meters, as in C++.
pub trait IRangefinder2D {
    /// The latest scan, one distance per step from the minimum angle, and its time
    /// (seconds since the epoch).
    fn get_raw_data(&mut self) -> DevResult<(Vec<f64>, f64)>;
    fn get_device_status(&mut self) -> DevResult<LaserStatus>;
    /// Minimum and maximum detection distance.
    fn get_distance_range(&mut self) -> DevResult<(f64, f64)>;
    fn set_distance_range(&mut self, min: f64, max: f64) -> DevResult<()>;
    /// Start and end angle of the scan.
    fn get_scan_limits(&mut self) -> DevResult<(f64, f64)>;
    fn set_scan_limits(&mut self, min: f64, max: f64) -> DevResult<()>;
    /// Angular step between two measurements.
    fn get_horizontal_resolution(&mut self) -> DevResult<f64>;
    fn set_horizontal_resolution(&mut self, step: f64) -> DevResult<()>;
    /// Scans per second.
    fn get_scan_rate(&mut self) -> DevResult<f64>;
    fn set_scan_rate(&mut self, rate: f64) -> DevResult<()>;
    fn get_device_info(&mut self) -> DevResult<String>;
}

/// Drivers of this family, by C++ name.
pub(crate) const DRIVERS: &[(&str, Factory)] = &[
    ("fakeLaser", || Box::new(fake::FakeLaser::new())),
    ("rangefinder2D_nwc_yarp", || {
        Box::new(nwc::Rangefinder2DNwcYarp::new())
    }),
    ("rangefinder2D_nws_yarp", || {
        Box::new(nws::Rangefinder2DNwsYarp::new())
    }),
];
