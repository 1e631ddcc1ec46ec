//! R1's devices, as robotology/cer's `cermod` library serves them to `yarprobotinterface`:
//!
//! - [`odometry`]: `cerOdometry`, the mobile base's odometry from its two wheels'
//!   encoders (served by `odometry2D_nws_yarp`);
//! - [`double_lidar`]: `cerDoubleLidar`, the front and back lidars as one 360° scan of the
//!   base's centre;
//! - [`tripod`]: `tripodMotionControl`, the torso's and wrists' tripods as heave, pitch
//!   and roll joints.
//!
//! `yarp_devices::Registry::install(cermod::register)` adds them to a program's devices.
#![forbid(unsafe_code)]

pub mod double_lidar;
pub mod odometry;
pub mod tripod;

use yarp_devices::{Factory, Registry};

/// The name this crate's drivers are listed under (`yarpdev --list`).
pub const PROVIDER: &str = "cermod";

/// The drivers of this crate, by C++ name.
const DRIVERS: &[(&str, Factory)] = &[
    (odometry::NAME, || Box::new(odometry::CerOdometry::new())),
    (double_lidar::NAME, || {
        Box::new(double_lidar::CerDoubleLidar::new())
    }),
    (
        tripod::NAME,
        || Box::new(tripod::TripodMotionControl::new()),
    ),
];

/// Adds R1's drivers to `registry` (`Registry::install(cermod::register)`).
pub fn register(registry: &mut Registry) {
    registry.add(PROVIDER, DRIVERS);
}
