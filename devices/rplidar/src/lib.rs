//! robotology/yarp-device-rplidar's devices on Slamtec's RPLidar serial protocol, as
//! its SDK 1.12 speaks it:
//!
//! - [`protocol`]: the protocol without I/O: requests, response descriptors, the
//!   device's information and configuration answers, and the measurement streams
//!   (standard nodes, express capsules, ultra capsules) turned into measurements as the
//!   SDK turns them, each with the encoder an emulated lidar sends them with;
//! - [`device`]: `rpLidar2` and `rpLidar3`, the YARP 2D lasers on a lidar's serial line.
#![forbid(unsafe_code)]

pub mod device;
pub mod protocol;

use yarp_devices::{Factory, Registry};

/// The name this crate's drivers are listed under (`yarpdev --list`).
pub const PROVIDER: &str = "yarp-device-rplidar";

const DRIVERS: &[(&str, Factory)] = &[
    (device::RPLIDAR2, || Box::new(device::RpLidar::two())),
    (device::RPLIDAR3, || Box::new(device::RpLidar::three())),
];

/// Adds `rpLidar2` and `rpLidar3` to `registry` (`Registry::install(rplidar::register)`).
pub fn register(registry: &mut Registry) {
    registry.add(PROVIDER, DRIVERS);
}
