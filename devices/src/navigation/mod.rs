//! Mobile bases: the `IOdometry2D` and `INavigation2DVelocityActions` interfaces (C++
//! `yarp::dev::Nav2D`), `fakeOdometry2D` and `fakeNavigation`, and the odometry's YARP
//! wrapper and client (`odometry2D_nws_yarp`, `odometry2D_nwc_yarp`).

pub mod fake_navigation;
pub mod fake_odometry;
pub mod nwc;
pub mod nws;
pub mod protocol;

use crate::driver::Factory;
use crate::error::DevResult;

/// The odometry of a mobile base (C++ `yarp::dev::OdometryData`): pose in the odometry
/// frame (m, m, degrees), velocity in the base frame and in the odometry frame (m/s,
/// degrees/s).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct OdometryData {
    pub odom_x: f64,
    pub odom_y: f64,
    pub odom_theta: f64,
    pub base_vel_x: f64,
    pub base_vel_y: f64,
    pub base_vel_theta: f64,
    pub odom_vel_x: f64,
    pub odom_vel_y: f64,
    pub odom_vel_theta: f64,
}

/// C++ `Nav2D::IOdometry2D`.
pub trait IOdometry2D {
    /// The odometry and its time (seconds since the epoch).
    fn get_odometry(&mut self) -> DevResult<(OdometryData, f64)>;
    fn reset_odometry(&mut self) -> DevResult<()>;
}

/// C++ `Nav2D::INavigation2DVelocityActions`: m/s and degrees/s.
pub trait INavigation2DVelocityActions {
    /// Commands a velocity, kept for `timeout` seconds (C++ default 0.1).
    fn apply_velocity_command(
        &mut self,
        x_vel: f64,
        y_vel: f64,
        theta_vel: f64,
        timeout: f64,
    ) -> DevResult<()>;
    fn get_last_velocity_command(&mut self) -> DevResult<(f64, f64, f64)>;
}

/// Drivers of this family, by C++ name.
pub(crate) const DRIVERS: &[(&str, Factory)] = &[
    ("fakeOdometry2D", || {
        Box::new(fake_odometry::FakeOdometry2D::new())
    }),
    ("fakeNavigation", || {
        Box::new(fake_navigation::FakeNavigation::new())
    }),
    ("odometry2D_nws_yarp", || {
        Box::new(nws::Odometry2DNwsYarp::new())
    }),
    ("odometry2D_nwc_yarp", || {
        Box::new(nwc::Odometry2DNwcYarp::new())
    }),
];
