//! The robots' files of `../shared/robots-configuration`, read one device at a time.

use std::path::PathBuf;
use yarp_devices::robotinterface::read_robot_str;
use yarp_proto::Property;

/// The configuration of the device a robot's file `file` describes (on its own, with
/// its includes).
pub fn device_file(robot: &str, file: &str) -> Property {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/robots-configuration")
        .join(robot);
    let text = format!(
        "<robot name=\"t\" xmlns:xi=\"http://www.w3.org/2001/XInclude\"><devices><xi:include href=\"{file}\" /></devices></robot>"
    );
    let r = read_robot_str(&text, &dir, &Property::new())
        .unwrap_or_else(|e| panic!("{e}"))
        .robot;
    r.devices[0].to_property().unwrap()
}
