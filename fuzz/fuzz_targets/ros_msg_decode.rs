//! What the gateway and the ROS 2 wrappers take from DDS: CDR bytes decoded against a
//! message type (`dynmsg::MsgSeed`), and the same bytes read as a YARP Bottle written to
//! a bridge of that type (the generic conversion). The first byte picks the type. Nothing
//! may panic or allocate without bound; whatever decodes converts to a Bottle and back
//! and encodes again.
#![no_main]

use byteorder::LittleEndian;
use libfuzzer_sys::fuzz_target;
use serde::de::DeserializeSeed;
use yarp_proto::Bottle;
use yarp_ros2_gateway::{dynmsg::MsgSeed, generic, types};

const TYPES: &[&str] = &[
    "sensor_msgs/msg/JointState",
    "sensor_msgs/msg/Image",
    "sensor_msgs/msg/Imu",
    "sensor_msgs/msg/CameraInfo",
    "sensor_msgs/msg/PointCloud2",
    "sensor_msgs/msg/LaserScan",
    "sensor_msgs/msg/BatteryState",
    "nav_msgs/msg/Odometry",
    "geometry_msgs/msg/WrenchStamped",
    "geometry_msgs/msg/Twist",
    "tf2_msgs/msg/TFMessage",
    "yarp_control_msgs/msg/Position",
    "diagnostic_msgs/msg/DiagnosticArray",
    "trajectory_msgs/msg/JointTrajectory",
    "std_msgs/msg/String",
];

fuzz_target!(|data: &[u8]| {
    let Some((&pick, rest)) = data.split_first() else {
        return;
    };
    let name = TYPES[pick as usize % TYPES.len()];
    let t = types::lookup(name).expect("a catalog type");
    let seed = MsgSeed::new(name).expect("a catalog type");
    let mut d = cdr_encoding::CdrDeserializer::<LittleEndian>::new(rest);
    if let Ok(m) = seed.deserialize(&mut d) {
        let _ = cdr_encoding::to_vec::<_, LittleEndian>(&m);
        if let Ok(b) = generic::to_yarp(t, &m) {
            let _ = generic::to_ros(t, &b, 0);
        }
    }
    if let Ok(b) = Bottle::decode(rest) {
        if let Ok(m) = generic::to_ros(t, &b, 0) {
            let _ = cdr_encoding::to_vec::<_, LittleEndian>(&m);
        }
    }
});
