//! The robots' files of `../shared/robots-configuration`, read whole or one device at a
//! time.

use std::path::PathBuf;
use yarp_devices::robotinterface::{read_robot_file, read_robot_str, Device};
use yarp_proto::Property;

/// `../shared/robots-configuration/<robot>`.
fn robot_dir(robot: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/robots-configuration")
        .join(robot)
}

/// The devices a robot's top-level file `top` (with its includes) describes.
pub fn robot_devices(robot: &str, top: &str) -> Vec<Device> {
    read_robot_file(&robot_dir(robot).join(top), &Property::new())
        .unwrap_or_else(|e| panic!("{robot}/{top}: {e}"))
        .robot
        .devices
}

/// The configuration of the device a robot's file `file` describes (on its own, with
/// its includes).
pub fn device_file(robot: &str, file: &str) -> Property {
    let text = format!(
        "<robot name=\"t\" xmlns:xi=\"http://www.w3.org/2001/XInclude\"><devices><xi:include href=\"{file}\" /></devices></robot>"
    );
    let r = read_robot_str(&text, &robot_dir(robot), &Property::new())
        .unwrap_or_else(|e| panic!("{e}"))
        .robot;
    r.devices[0].to_property().unwrap()
}
