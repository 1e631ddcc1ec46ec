//! The network wrappers of robotology/yarp-devices-ros2 (`*_nws_ros2` servers that publish
//! a device's interfaces as ROS 2 topics and services, `*_nwc_ros2` clients that read ROS 2
//! topics into YARP interfaces), with that project's device names and parameters, so a
//! robot's own XML files (e.g. robots-configuration's `*_nws_ros2.xml`) run unmodified.
//!
//! They speak ROS 2 through the gateway's one ROS layer (`yarp_ros2_gateway`: participant
//! and nodes, QoS, type catalog and hashes, dynamic messages, conversions); the YARP device
//! framework stays free of ROS. Programs add these drivers with
//! `yarp_devices::Registry::install(yarp_devices_ros2::register)`.
//!
//! | module | devices |
//! |---|---|
//! | [`control_board`] | `controlBoard_nws_ros2` (with [`control_msgs`]: `yarp_control_msgs`) |
//! | [`sensors`] | `imu_nws_ros2`, `wrenchStamped_nws_ros2`, `magneticField_nws_ros2`, `temperature_nws_ros2` |

pub mod control_board;
pub mod control_msgs;
pub mod node;
pub mod sensors;

use yarp_devices::{Factory, Registry};

/// The crate name shown by `yarpdev --list` beside each driver.
pub const PROVIDER: &str = "yarp-devices-ros2";

const CONTROL_BOARD: &[(&str, Factory)] = &[(control_board::NAME, || {
    Box::new(control_board::ControlBoardNwsRos2::new())
})];

/// Adds this crate's drivers to the device table (one line per module's family).
pub fn register(registry: &mut Registry) {
    for family in [CONTROL_BOARD, sensors::DRIVERS] {
        registry.add(PROVIDER, family);
    }
}
