//! The REP-2016 hashes the gateway's catalog gives the types of yarp-devices-ros2's
//! endpoints, against rosidl's own.
//!
//! yarp_control_msgs: the hashes rosidl computes from the package's published
//! `.msg`/`.srv` files (robotology/yarp-devices-ros2 `ros2_interfaces_ws/src/yarp_control_msgs`,
//! commit 6317707), printed by `gateway/tools/rosidl_hashes.py` with the Kilted venv's
//! rosidl_adapter and rosidl_generator_type_description (the steps of
//! `rosidl_generate_interfaces`). The standard types: the `type_hashes` of the Kilted
//! wheels' `share/**/*.json`.

use yarp_ros2_gateway::hash::rihs01;

const YARP_CONTROL_MSGS: &[(&str, &str)] = &[
    (
        "yarp_control_msgs/msg/Position",
        "RIHS01_499fa67073eb1080970ec46ebdeba1d0180d81609bd09a28b0691257a7aa4967",
    ),
    (
        "yarp_control_msgs/msg/PositionDirect",
        "RIHS01_c7a5c0a360a71d08ae7bd7672c5d9b29ce38054a97bec1e0e9642fda1afa3f97",
    ),
    (
        "yarp_control_msgs/msg/Velocity",
        "RIHS01_cdf7fa022005d4dd5a5e0cbc2b4f1ea4375e1e2d2dfe31f597d049eec6f27c58",
    ),
    (
        "yarp_control_msgs/srv/GetAvailableControlModes",
        "RIHS01_c02c7cc5267f6ac060042fb9ffac6fe8ae0d80cff6889e801c64b4cc06768ac3",
    ),
    (
        "yarp_control_msgs/srv/GetAvailableControlModes_Event",
        "RIHS01_9d2d414529346cefc99758fa955a5b78f923b26b2200ffd6023c7760f64ea3ce",
    ),
    (
        "yarp_control_msgs/srv/GetAvailableControlModes_Request",
        "RIHS01_304826805a58b3d31197321e6bb51ab71ed685ffe072124c0bce344110acbd03",
    ),
    (
        "yarp_control_msgs/srv/GetAvailableControlModes_Response",
        "RIHS01_e48b6f6438ccd935037478c8ce9b2cab0b29ee365608f6ed65772235d6202393",
    ),
    (
        "yarp_control_msgs/srv/GetControlModes",
        "RIHS01_59aea3fcdefb3549c8dbdfee520aed38db57e42470676aaac80ff2daeb25ede7",
    ),
    (
        "yarp_control_msgs/srv/GetControlModes_Event",
        "RIHS01_c45144cc53fa637bb65751ac086942a7a73f10b5bc262d8e0f40c60672f35235",
    ),
    (
        "yarp_control_msgs/srv/GetControlModes_Request",
        "RIHS01_c4608d10f3c5330f9ac9a6d45fe9ad7cc6813171903c0b610bb0a6b2348561f1",
    ),
    (
        "yarp_control_msgs/srv/GetControlModes_Response",
        "RIHS01_93588ec37876ad7a1d9497ba265231caffa01ca59ac7fa5ba56d944b99adf634",
    ),
    (
        "yarp_control_msgs/srv/GetJointsNames",
        "RIHS01_db6c3c9968211d4e32df83b6701d67fd5680db6ad7c5b0d871486821e7863af4",
    ),
    (
        "yarp_control_msgs/srv/GetJointsNames_Event",
        "RIHS01_b7e970219d2ec26c34d0b906192b65b83cb1f45aa3cf7fa5f80861ff340a6a90",
    ),
    (
        "yarp_control_msgs/srv/GetJointsNames_Request",
        "RIHS01_a9f062fdc5a53ca65d83aeaabc098f82ae8b2b51f2d95a0721ad0b05011b38fc",
    ),
    (
        "yarp_control_msgs/srv/GetJointsNames_Response",
        "RIHS01_f6f4c05e9ca449b07daace8fba9a340872a8cb13e098914f8cc9e8dd1eb16b3c",
    ),
    (
        "yarp_control_msgs/srv/GetPosition",
        "RIHS01_db966ae6e26604c21500762ff0b18c3bd884c53ca82ca39853215b463853aa3f",
    ),
    (
        "yarp_control_msgs/srv/GetPosition_Event",
        "RIHS01_0fa1a3d4024b6e8281828529a9bca1bc8bc606773ea0d8b50b0f9eb93f9090b8",
    ),
    (
        "yarp_control_msgs/srv/GetPosition_Request",
        "RIHS01_20d53933875eb5975c874e7c4d0051e32bf3583b5764813b72bef33502ca8380",
    ),
    (
        "yarp_control_msgs/srv/GetPosition_Response",
        "RIHS01_170e78410ffa3f4aedea131a8661af3f5ec3a7b2317b6c098ae066dd563615d7",
    ),
    (
        "yarp_control_msgs/srv/GetVelocity",
        "RIHS01_f6167ae43ecd3cb0a0075b37b3a58a80dbfcf7072bc593a62e774af0efcef4c1",
    ),
    (
        "yarp_control_msgs/srv/GetVelocity_Event",
        "RIHS01_8c8ab72935e4803e8c9d2363a5b5aa0b2dc5a7ec00e64f002dec25eac3494460",
    ),
    (
        "yarp_control_msgs/srv/GetVelocity_Request",
        "RIHS01_3c93f6c1d3a6b85cedbfafc97df9df758aa06c5e42a3e5af8b39df61968febbb",
    ),
    (
        "yarp_control_msgs/srv/GetVelocity_Response",
        "RIHS01_c82f3e3386dc171522c8fd9eb9f299813d8937790af739e8297ff1fc4248e318",
    ),
    (
        "yarp_control_msgs/srv/SetControlModes",
        "RIHS01_7409b1dd36c296df603db64e81f03cebc7247ca941c2005f9f361139e47dbcdb",
    ),
    (
        "yarp_control_msgs/srv/SetControlModes_Event",
        "RIHS01_61aaeef983b046a81d33e53f94149c87571e01fc17909f6183e13dc0e86f6da8",
    ),
    (
        "yarp_control_msgs/srv/SetControlModes_Request",
        "RIHS01_1ba5a353b5d23561183a7e47b273492c0871a9b5e43431ec27c2abda33ea913f",
    ),
    (
        "yarp_control_msgs/srv/SetControlModes_Response",
        "RIHS01_4508a7dac594f8ab74010aa5af3570a93e6c15fe7289e67819e5e1184a7fa5f7",
    ),
];

const STANDARD: &[(&str, &str)] = &[
    (
        "sensor_msgs/msg/MagneticField",
        "RIHS01_e80f32f56a20486c9923008fc1a1db07bbb273cbbf6a5b3bfa00835ee00e4dff",
    ),
    (
        "sensor_msgs/msg/Temperature",
        "RIHS01_72514a14126ab9f8a9abec974c78e5610a367b59db5da355ff1fb982d5bad4b8",
    ),
    (
        "std_msgs/msg/Int8MultiArray",
        "RIHS01_f21998d4b492abd63330765d75d5831238d400740386f651f13a872a4d2188db",
    ),
];

#[test]
fn catalog_hashes_are_rosidls() {
    for (name, want) in YARP_CONTROL_MSGS.iter().chain(STANDARD) {
        assert_eq!(rihs01(name).as_deref(), Ok(*want), "{name}");
    }
}
