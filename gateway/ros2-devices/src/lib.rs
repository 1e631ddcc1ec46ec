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
//! | [`camera_client`] | `rgbdSensor_nwc_ros2` |
//! | [`imu_client`] | `imu_nwc_ros2` |
//! | [`frames`] | `frameTransformGet_nwc_ros2`, `frameTransformSet_nwc_ros2` |
//! | [`rangefinder`] | `rangefinder2D_nws_ros2`, `rangefinder2D_nwc_ros2` |
//! | [`camera`] | `frameGrabber_nws_ros2`, `rgbdSensor_nws_ros2`, `rgbdToPointCloudSensor_nws_ros2` |
//! | [`mobile_base`] | `battery_nws_ros2`, `odometry2D_nws_ros2`, `mobileBaseVelocityControl_nws_ros2` |
//!
//! [`msgs`] builds their messages (pure), [`periodic`] runs their publishing threads.
#![forbid(unsafe_code)]

pub mod camera;
pub mod camera_client;
pub mod control_board;
pub mod control_msgs;
pub mod frames;
pub mod imu_client;
pub mod mobile_base;
pub mod msgs;
pub mod node;
pub mod periodic;
pub mod rangefinder;
pub mod sensors;

use yarp_devices::{Factory, Registry};

/// The crate name shown by `yarpdev --list` beside each driver.
pub const PROVIDER: &str = "yarp-devices-ros2";

const CONTROL_BOARD: &[(&str, Factory)] = &[(control_board::NAME, || {
    Box::new(control_board::ControlBoardNwsRos2::new())
})];

const LASERS_CAMERAS_BASES: &[(&str, Factory)] = &[
    (rangefinder::NWS, || {
        Box::new(rangefinder::Rangefinder2DNwsRos2::default())
    }),
    (rangefinder::NWC, || {
        Box::new(rangefinder::Rangefinder2DNwcRos2::default())
    }),
    (camera::FRAME_GRABBER, || {
        Box::new(camera::CameraNwsRos2::new(camera::Kind::FrameGrabber))
    }),
    (camera::RGBD, || {
        Box::new(camera::CameraNwsRos2::new(camera::Kind::Rgbd))
    }),
    (camera::POINT_CLOUD, || {
        Box::new(camera::CameraNwsRos2::new(camera::Kind::PointCloud))
    }),
    (mobile_base::BATTERY, || {
        Box::new(mobile_base::StateNwsRos2::new(mobile_base::Kind::Battery))
    }),
    (mobile_base::ODOMETRY, || {
        Box::new(mobile_base::StateNwsRos2::new(mobile_base::Kind::Odometry))
    }),
    (camera_client::NAME, || {
        Box::new(camera_client::RgbdSensorNwcRos2::default())
    }),
    (frames::GET, || {
        Box::new(frames::FrameTransformGetNwcRos2::default())
    }),
    (frames::SET, || {
        Box::new(frames::FrameTransformSetNwcRos2::default())
    }),
    (imu_client::NAME, || {
        Box::new(imu_client::ImuNwcRos2::default())
    }),
    (mobile_base::VELOCITY, || {
        Box::new(mobile_base::MobileBaseVelocityControlNwsRos2::default())
    }),
];

/// Seconds since the epoch (YARP's clock).
pub(crate) fn now_s() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

/// Adds this crate's drivers to the device table (one line per module's family).
pub fn register(registry: &mut Registry) {
    for family in [CONTROL_BOARD, sensors::DRIVERS, LASERS_CAMERAS_BASES] {
        registry.add(PROVIDER, family);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeSet;

    const GENERIC_NWS: &[&str] = &["period", "node_name", "namespace", "topic_name"];

    /// yarp-devices-ros2's parameter tables (`*_params.md`), by device.
    const CPP: &[(&str, &[&str])] = &[
        ("battery_nws_ros2", GENERIC_NWS),
        ("imu_nws_ros2", GENERIC_NWS),
        ("wrenchStamped_nws_ros2", GENERIC_NWS),
        ("magneticField_nws_ros2", GENERIC_NWS),
        ("temperature_nws_ros2", GENERIC_NWS),
        (
            "controlBoard_nws_ros2",
            &[
                "node_name",
                "namespace",
                "topic_name",
                "msgs_name",
                "period",
            ],
        ),
        (
            "frameGrabber_nws_ros2",
            &["period", "node_name", "namespace", "topic_name", "frame_id"],
        ),
        (
            "frameTransformGet_nwc_ros2",
            &[
                "GENERAL::refresh_interval",
                "ROS2::ft_node",
                "ROS2::namespace",
                "ROS2::ft_topic",
                "ROS2::ft_topic_static",
            ],
        ),
        (
            "frameTransformSet_nwc_ros2",
            &[
                "GENERAL::refresh_interval",
                "GENERAL::period",
                "GENERAL::asynch_pub",
                "ROS2::ft_node",
                "ROS2::namespace",
                "ROS2::ft_topic",
                "ROS2::ft_topic_static",
            ],
        ),
        (
            "mobileBaseVelocityControl_nws_ros2",
            &["node_name", "namespace", "topic_name"],
        ),
        (
            "imu_nwc_ros2",
            &["node_name", "namespace", "topic_name", "sensor_name"],
        ),
        (
            "odometry2D_nws_ros2",
            &[
                "period",
                "node_name",
                "namespace",
                "topic_name",
                "odom_frame",
                "base_frame",
            ],
        ),
        (
            "rangefinder2D_nwc_ros2",
            &[
                "period",
                "node_name",
                "namespace",
                "topic_name",
                "verbose_on",
            ],
        ),
        (
            "rangefinder2D_nws_ros2",
            &["period", "node_name", "namespace", "topic_name", "frame_id"],
        ),
        (
            "rgbdSensor_nwc_ros2",
            &[
                "node_name",
                "namespace",
                "color_topic_name",
                "depth_topic_name",
                "verbose_on",
            ],
        ),
        (
            "rgbdSensor_nws_ros2",
            &[
                "period",
                "node_name",
                "namespace",
                "color_topic_name",
                "depth_topic_name",
                "force_info_synch",
                "depth_frame_id",
                "color_frame_id",
                "pub_status_topic",
            ],
        ),
        (
            "rgbdToPointCloudSensor_nws_ros2",
            &["period", "topic_name", "frame_id", "node_name", "namespace"],
        ),
    ];

    #[test]
    fn every_driver_declares_the_parameters_of_its_cpp_table() {
        let mut seen = BTreeSet::new();
        for family in [CONTROL_BOARD, sensors::DRIVERS, LASERS_CAMERAS_BASES] {
            for (name, factory) in family {
                let declared: Vec<&str> = factory().parameters().iter().map(|p| p.name).collect();
                let (_, cpp) = CPP
                    .iter()
                    .find(|(d, _)| d == name)
                    .unwrap_or_else(|| panic!("{name}: no C++ table here"));
                let declared: BTreeSet<&str> = declared.into_iter().collect();
                let cpp: BTreeSet<&str> = cpp.iter().copied().collect();
                assert_eq!(declared, cpp, "{name}");
                seen.insert(*name);
            }
        }
        assert_eq!(seen.len(), CPP.len());
    }
}
