//! What `yarpdev` and `yarprobotinterface` serve: the YARP device framework
//! (`yarp-devices`, which registers its own drivers) and every device crate of the
//! workspace (the iCub drivers of `icubmod`, icub-main's Cartesian control of `icub-cartesian`, R1's of `cermod`, whole-body-estimators' `wholebodydynamics`, yarp-device-rplidar's lidars, yarp-devices-ros2's ROS 2
//! wrappers), each added here with its `register` function.
#![forbid(unsafe_code)]

use yarp_devices::Registry;

/// Registers the drivers of every linked device crate (idempotent).
pub fn register_all() {
    Registry::install(icubmod::register);
    Registry::install(icub_cartesian::register);
    Registry::install(cermod::register);
    Registry::install(whole_body_estimators::register);
    Registry::install(rplidar::register);
    Registry::install(yarp_devices_ros2::register);
}
