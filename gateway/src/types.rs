//! The catalog of ROS 2 interface types the gateway speaks, described field by field.
//!
//! One description drives three things: the REP-2016 type hash ([`crate::hash`]), the
//! dynamic CDR encoding of messages ([`crate::dynmsg`]) and the validation of mapping
//! files ([`crate::mapping`]). The field lists are copied from the `.msg`/`.srv` files of
//! ROS 2 Jazzy/Kilted (identical in both), including the `uint8
//! structure_needs_at_least_one_member` that rosidl adds to empty structures.

/// A primitive (non-nested) field type, named as in REP-2016's `FieldType.msg`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Prim {
    Bool,
    Byte,
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
    String,
    /// `wstring` (UTF-16 in ROS 2): only in types read from their definitions.
    WString,
}

impl Prim {
    /// The REP-2016 `FIELD_TYPE_*` id of a single value of this type.
    pub const fn type_id(self) -> u8 {
        match self {
            Prim::I8 => 2,
            Prim::U8 => 3,
            Prim::I16 => 4,
            Prim::U16 => 5,
            Prim::I32 => 6,
            Prim::U32 => 7,
            Prim::I64 => 8,
            Prim::U64 => 9,
            Prim::F32 => 10,
            Prim::F64 => 11,
            Prim::Bool => 15,
            Prim::Byte => 16,
            Prim::String => 17,
            Prim::WString => 18,
        }
    }
}

/// What a field holds: a primitive or another message type (by full name).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Base {
    Prim(Prim),
    Nested(&'static str),
}

/// Single value, fixed array, bounded or unbounded sequence.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    Single,
    Array(u64),
    BoundedSeq(u64),
    Seq,
}

/// One field of a message type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Field {
    pub name: &'static str,
    pub base: Base,
    pub shape: Shape,
    /// The bound of a bounded string (`string<=N`, `wstring<=N`), else 0.
    pub string_capacity: u64,
    /// The default value as written in the `.msg` file (`int32 x 5`), if any.
    pub default: Option<&'static str>,
}

impl Field {
    /// The REP-2016 type id: the single-value id plus 48 (array), 96 (bounded sequence) or
    /// 144 (unbounded sequence).
    pub fn type_id(&self) -> u8 {
        let single = match self.base {
            // BOUNDED_STRING (21) and BOUNDED_WSTRING (22)
            Base::Prim(Prim::String) if self.string_capacity > 0 => 21,
            Base::Prim(Prim::WString) if self.string_capacity > 0 => 22,
            Base::Prim(p) => p.type_id(),
            Base::Nested(_) => 1,
        };
        single
            + match self.shape {
                Shape::Single => 0,
                Shape::Array(_) => 48,
                Shape::BoundedSeq(_) => 96,
                Shape::Seq => 144,
            }
    }

    /// The REP-2016 `capacity`: array length or sequence bound, else 0.
    pub fn capacity(&self) -> u64 {
        match self.shape {
            Shape::Array(n) | Shape::BoundedSeq(n) => n,
            Shape::Single | Shape::Seq => 0,
        }
    }
}

/// A constant of a message type (`uint8 ARROW=0`): its type and value as written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Constant {
    pub name: &'static str,
    pub prim: Prim,
    pub value: &'static str,
}

/// A message (or service/event structure) type: full name such as `std_msgs/msg/String`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MsgType {
    pub name: &'static str,
    pub fields: &'static [Field],
    /// Constants (types read from their definitions; the built-in catalog lists none).
    pub constants: &'static [Constant],
}

const fn f(name: &'static str, p: Prim) -> Field {
    Field {
        name,
        base: Base::Prim(p),
        shape: Shape::Single,
        string_capacity: 0,
        default: None,
    }
}
const fn seq(name: &'static str, p: Prim) -> Field {
    Field {
        name,
        base: Base::Prim(p),
        shape: Shape::Seq,
        string_capacity: 0,
        default: None,
    }
}
const fn arr(name: &'static str, p: Prim, n: u64) -> Field {
    Field {
        name,
        base: Base::Prim(p),
        shape: Shape::Array(n),
        string_capacity: 0,
        default: None,
    }
}
const fn nested(name: &'static str, ty: &'static str) -> Field {
    Field {
        name,
        base: Base::Nested(ty),
        shape: Shape::Single,
        string_capacity: 0,
        default: None,
    }
}
const fn nested_seq(name: &'static str, ty: &'static str) -> Field {
    Field {
        name,
        base: Base::Nested(ty),
        shape: Shape::Seq,
        string_capacity: 0,
        default: None,
    }
}
const fn nested_opt(name: &'static str, ty: &'static str) -> Field {
    Field {
        name,
        base: Base::Nested(ty),
        shape: Shape::BoundedSeq(1),
        string_capacity: 0,
        default: None,
    }
}
const fn msg(name: &'static str, fields: &'static [Field]) -> MsgType {
    MsgType {
        name,
        fields,
        constants: &[],
    }
}

const DUMMY: &[Field] = &[f("structure_needs_at_least_one_member", Prim::U8)];
const XYZ: &[Field] = &[f("x", Prim::F64), f("y", Prim::F64), f("z", Prim::F64)];
const HEADER: Field = nested("header", "std_msgs/msg/Header");
const LAYOUT: Field = nested("layout", "std_msgs/msg/MultiArrayLayout");
// Fields shared by the yarp_control_msgs types (`string response "NOT_SPECIFIED"`: default
// values are not part of a type description, so not of its hash).
const NAMES: Field = seq("names", Prim::String);
const MODES: Field = seq("modes", Prim::String);
const RESPONSE: Field = f("response", Prim::String);
const OPT_DESCR: Field = f("opt_descr", Prim::String);
const EVENT_INFO: Field = nested("info", "service_msgs/msg/ServiceEventInfo");

/// Every message type the gateway knows.
pub static MESSAGES: &[MsgType] = &[
    msg(
        "builtin_interfaces/msg/Time",
        &[f("sec", Prim::I32), f("nanosec", Prim::U32)],
    ),
    msg(
        "std_msgs/msg/Header",
        &[
            nested("stamp", "builtin_interfaces/msg/Time"),
            f("frame_id", Prim::String),
        ],
    ),
    msg("std_msgs/msg/String", &[f("data", Prim::String)]),
    msg("std_msgs/msg/Bool", &[f("data", Prim::Bool)]),
    msg("std_msgs/msg/Int32", &[f("data", Prim::I32)]),
    msg("std_msgs/msg/Int64", &[f("data", Prim::I64)]),
    msg("std_msgs/msg/UInt8", &[f("data", Prim::U8)]),
    msg("std_msgs/msg/Float32", &[f("data", Prim::F32)]),
    msg("std_msgs/msg/Float64", &[f("data", Prim::F64)]),
    msg("std_msgs/msg/Empty", DUMMY),
    msg(
        "std_msgs/msg/MultiArrayDimension",
        &[
            f("label", Prim::String),
            f("size", Prim::U32),
            f("stride", Prim::U32),
        ],
    ),
    msg(
        "std_msgs/msg/MultiArrayLayout",
        &[
            nested_seq("dim", "std_msgs/msg/MultiArrayDimension"),
            f("data_offset", Prim::U32),
        ],
    ),
    msg(
        "std_msgs/msg/Float64MultiArray",
        &[LAYOUT, seq("data", Prim::F64)],
    ),
    msg(
        "std_msgs/msg/Float32MultiArray",
        &[LAYOUT, seq("data", Prim::F32)],
    ),
    msg(
        "std_msgs/msg/Int32MultiArray",
        &[LAYOUT, seq("data", Prim::I32)],
    ),
    msg(
        "std_msgs/msg/Int64MultiArray",
        &[LAYOUT, seq("data", Prim::I64)],
    ),
    msg("geometry_msgs/msg/Vector3", XYZ),
    msg(
        "geometry_msgs/msg/Quaternion",
        &[
            f("x", Prim::F64),
            f("y", Prim::F64),
            f("z", Prim::F64),
            f("w", Prim::F64),
        ],
    ),
    msg(
        "geometry_msgs/msg/Twist",
        &[
            nested("linear", "geometry_msgs/msg/Vector3"),
            nested("angular", "geometry_msgs/msg/Vector3"),
        ],
    ),
    msg(
        "geometry_msgs/msg/Wrench",
        &[
            nested("force", "geometry_msgs/msg/Vector3"),
            nested("torque", "geometry_msgs/msg/Vector3"),
        ],
    ),
    msg(
        "geometry_msgs/msg/WrenchStamped",
        &[HEADER, nested("wrench", "geometry_msgs/msg/Wrench")],
    ),
    msg(
        "sensor_msgs/msg/JointState",
        &[
            HEADER,
            seq("name", Prim::String),
            seq("position", Prim::F64),
            seq("velocity", Prim::F64),
            seq("effort", Prim::F64),
        ],
    ),
    // yarp-devices-ros2 (`controlBoard_nws_ros2`, the multiple-analog-sensors wrappers):
    // robotology/yarp-devices-ros2's `ros2_interfaces_ws/src/yarp_control_msgs` and the
    // standard types those devices publish.
    msg(
        "std_msgs/msg/Int8MultiArray",
        &[LAYOUT, seq("data", Prim::I8)],
    ),
    msg(
        "sensor_msgs/msg/MagneticField",
        &[
            HEADER,
            nested("magnetic_field", "geometry_msgs/msg/Vector3"),
            arr("magnetic_field_covariance", Prim::F64, 9),
        ],
    ),
    msg(
        "sensor_msgs/msg/Temperature",
        &[
            HEADER,
            f("temperature", Prim::F64),
            f("variance", Prim::F64),
        ],
    ),
    msg(
        "yarp_control_msgs/msg/Position",
        &[
            NAMES,
            seq("positions", Prim::F64),
            seq("ref_velocities", Prim::F64),
        ],
    ),
    msg(
        "yarp_control_msgs/msg/PositionDirect",
        &[NAMES, seq("positions", Prim::F64)],
    ),
    msg(
        "yarp_control_msgs/msg/Velocity",
        &[
            NAMES,
            seq("velocities", Prim::F64),
            seq("ref_accelerations", Prim::F64),
        ],
    ),
    msg(
        "yarp_control_msgs/srv/GetJointsNames_Request",
        &[seq("joint_indexes", Prim::I32)],
    ),
    msg(
        "yarp_control_msgs/srv/GetJointsNames_Response",
        &[NAMES, RESPONSE, OPT_DESCR],
    ),
    msg(
        "yarp_control_msgs/srv/GetJointsNames_Event",
        &[
            EVENT_INFO,
            nested_opt("request", "yarp_control_msgs/srv/GetJointsNames_Request"),
            nested_opt("response", "yarp_control_msgs/srv/GetJointsNames_Response"),
        ],
    ),
    msg(
        "yarp_control_msgs/srv/GetJointsNames",
        &[
            nested(
                "request_message",
                "yarp_control_msgs/srv/GetJointsNames_Request",
            ),
            nested(
                "response_message",
                "yarp_control_msgs/srv/GetJointsNames_Response",
            ),
            nested(
                "event_message",
                "yarp_control_msgs/srv/GetJointsNames_Event",
            ),
        ],
    ),
    msg("yarp_control_msgs/srv/GetControlModes_Request", &[NAMES]),
    msg(
        "yarp_control_msgs/srv/GetControlModes_Response",
        &[MODES, RESPONSE, OPT_DESCR],
    ),
    msg(
        "yarp_control_msgs/srv/GetControlModes_Event",
        &[
            EVENT_INFO,
            nested_opt("request", "yarp_control_msgs/srv/GetControlModes_Request"),
            nested_opt("response", "yarp_control_msgs/srv/GetControlModes_Response"),
        ],
    ),
    msg(
        "yarp_control_msgs/srv/GetControlModes",
        &[
            nested(
                "request_message",
                "yarp_control_msgs/srv/GetControlModes_Request",
            ),
            nested(
                "response_message",
                "yarp_control_msgs/srv/GetControlModes_Response",
            ),
            nested(
                "event_message",
                "yarp_control_msgs/srv/GetControlModes_Event",
            ),
        ],
    ),
    msg(
        "yarp_control_msgs/srv/SetControlModes_Request",
        &[NAMES, MODES],
    ),
    msg(
        "yarp_control_msgs/srv/SetControlModes_Response",
        &[RESPONSE, OPT_DESCR],
    ),
    msg(
        "yarp_control_msgs/srv/SetControlModes_Event",
        &[
            EVENT_INFO,
            nested_opt("request", "yarp_control_msgs/srv/SetControlModes_Request"),
            nested_opt("response", "yarp_control_msgs/srv/SetControlModes_Response"),
        ],
    ),
    msg(
        "yarp_control_msgs/srv/SetControlModes",
        &[
            nested(
                "request_message",
                "yarp_control_msgs/srv/SetControlModes_Request",
            ),
            nested(
                "response_message",
                "yarp_control_msgs/srv/SetControlModes_Response",
            ),
            nested(
                "event_message",
                "yarp_control_msgs/srv/SetControlModes_Event",
            ),
        ],
    ),
    msg(
        "yarp_control_msgs/srv/GetAvailableControlModes_Request",
        &[f("only_implemented", Prim::Bool)],
    ),
    msg(
        "yarp_control_msgs/srv/GetAvailableControlModes_Response",
        &[MODES, RESPONSE, OPT_DESCR],
    ),
    msg(
        "yarp_control_msgs/srv/GetAvailableControlModes_Event",
        &[
            EVENT_INFO,
            nested_opt(
                "request",
                "yarp_control_msgs/srv/GetAvailableControlModes_Request",
            ),
            nested_opt(
                "response",
                "yarp_control_msgs/srv/GetAvailableControlModes_Response",
            ),
        ],
    ),
    msg(
        "yarp_control_msgs/srv/GetAvailableControlModes",
        &[
            nested(
                "request_message",
                "yarp_control_msgs/srv/GetAvailableControlModes_Request",
            ),
            nested(
                "response_message",
                "yarp_control_msgs/srv/GetAvailableControlModes_Response",
            ),
            nested(
                "event_message",
                "yarp_control_msgs/srv/GetAvailableControlModes_Event",
            ),
        ],
    ),
    msg("yarp_control_msgs/srv/GetPosition_Request", &[NAMES]),
    msg(
        "yarp_control_msgs/srv/GetPosition_Response",
        &[seq("positions", Prim::F64), RESPONSE, OPT_DESCR],
    ),
    msg(
        "yarp_control_msgs/srv/GetPosition_Event",
        &[
            EVENT_INFO,
            nested_opt("request", "yarp_control_msgs/srv/GetPosition_Request"),
            nested_opt("response", "yarp_control_msgs/srv/GetPosition_Response"),
        ],
    ),
    msg(
        "yarp_control_msgs/srv/GetPosition",
        &[
            nested(
                "request_message",
                "yarp_control_msgs/srv/GetPosition_Request",
            ),
            nested(
                "response_message",
                "yarp_control_msgs/srv/GetPosition_Response",
            ),
            nested("event_message", "yarp_control_msgs/srv/GetPosition_Event"),
        ],
    ),
    msg("yarp_control_msgs/srv/GetVelocity_Request", &[NAMES]),
    msg(
        "yarp_control_msgs/srv/GetVelocity_Response",
        &[seq("velocities", Prim::F64), RESPONSE, OPT_DESCR],
    ),
    msg(
        "yarp_control_msgs/srv/GetVelocity_Event",
        &[
            EVENT_INFO,
            nested_opt("request", "yarp_control_msgs/srv/GetVelocity_Request"),
            nested_opt("response", "yarp_control_msgs/srv/GetVelocity_Response"),
        ],
    ),
    msg(
        "yarp_control_msgs/srv/GetVelocity",
        &[
            nested(
                "request_message",
                "yarp_control_msgs/srv/GetVelocity_Request",
            ),
            nested(
                "response_message",
                "yarp_control_msgs/srv/GetVelocity_Response",
            ),
            nested("event_message", "yarp_control_msgs/srv/GetVelocity_Event"),
        ],
    ),
    msg(
        "builtin_interfaces/msg/Duration",
        &[f("sec", Prim::I32), f("nanosec", Prim::U32)],
    ),
    msg(
        "trajectory_msgs/msg/JointTrajectoryPoint",
        &[
            seq("positions", Prim::F64),
            seq("velocities", Prim::F64),
            seq("accelerations", Prim::F64),
            seq("effort", Prim::F64),
            nested("time_from_start", "builtin_interfaces/msg/Duration"),
        ],
    ),
    msg(
        "trajectory_msgs/msg/JointTrajectory",
        &[
            HEADER,
            seq("joint_names", Prim::String),
            nested_seq("points", "trajectory_msgs/msg/JointTrajectoryPoint"),
        ],
    ),
    msg(
        "sensor_msgs/msg/Image",
        &[
            HEADER,
            f("height", Prim::U32),
            f("width", Prim::U32),
            f("encoding", Prim::String),
            f("is_bigendian", Prim::U8),
            f("step", Prim::U32),
            seq("data", Prim::U8),
        ],
    ),
    // Cameras, lasers, point clouds, batteries, odometry and transforms: the topics of
    // yarp-devices-ros2's wrappers (frameGrabber, rgbdSensor, rangefinder2D, battery,
    // odometry2D, mobileBaseVelocityControl, frameTransform).
    msg(
        "sensor_msgs/msg/RegionOfInterest",
        &[
            f("x_offset", Prim::U32),
            f("y_offset", Prim::U32),
            f("height", Prim::U32),
            f("width", Prim::U32),
            f("do_rectify", Prim::Bool),
        ],
    ),
    msg(
        "sensor_msgs/msg/CameraInfo",
        &[
            HEADER,
            f("height", Prim::U32),
            f("width", Prim::U32),
            f("distortion_model", Prim::String),
            seq("d", Prim::F64),
            arr("k", Prim::F64, 9),
            arr("r", Prim::F64, 9),
            arr("p", Prim::F64, 12),
            f("binning_x", Prim::U32),
            f("binning_y", Prim::U32),
            nested("roi", "sensor_msgs/msg/RegionOfInterest"),
        ],
    ),
    msg(
        "sensor_msgs/msg/LaserScan",
        &[
            HEADER,
            f("angle_min", Prim::F32),
            f("angle_max", Prim::F32),
            f("angle_increment", Prim::F32),
            f("time_increment", Prim::F32),
            f("scan_time", Prim::F32),
            f("range_min", Prim::F32),
            f("range_max", Prim::F32),
            seq("ranges", Prim::F32),
            seq("intensities", Prim::F32),
        ],
    ),
    msg(
        "sensor_msgs/msg/PointField",
        &[
            f("name", Prim::String),
            f("offset", Prim::U32),
            f("datatype", Prim::U8),
            f("count", Prim::U32),
        ],
    ),
    msg(
        "sensor_msgs/msg/PointCloud2",
        &[
            HEADER,
            f("height", Prim::U32),
            f("width", Prim::U32),
            nested_seq("fields", "sensor_msgs/msg/PointField"),
            f("is_bigendian", Prim::Bool),
            f("point_step", Prim::U32),
            f("row_step", Prim::U32),
            seq("data", Prim::U8),
            f("is_dense", Prim::Bool),
        ],
    ),
    msg(
        "sensor_msgs/msg/BatteryState",
        &[
            HEADER,
            f("voltage", Prim::F32),
            f("temperature", Prim::F32),
            f("current", Prim::F32),
            f("charge", Prim::F32),
            f("capacity", Prim::F32),
            f("design_capacity", Prim::F32),
            f("percentage", Prim::F32),
            f("power_supply_status", Prim::U8),
            f("power_supply_health", Prim::U8),
            f("power_supply_technology", Prim::U8),
            f("present", Prim::Bool),
            seq("cell_voltage", Prim::F32),
            seq("cell_temperature", Prim::F32),
            f("location", Prim::String),
            f("serial_number", Prim::String),
        ],
    ),
    msg("geometry_msgs/msg/Point", XYZ),
    msg(
        "geometry_msgs/msg/Pose",
        &[
            nested("position", "geometry_msgs/msg/Point"),
            nested("orientation", "geometry_msgs/msg/Quaternion"),
        ],
    ),
    msg(
        "geometry_msgs/msg/PoseWithCovariance",
        &[
            nested("pose", "geometry_msgs/msg/Pose"),
            arr("covariance", Prim::F64, 36),
        ],
    ),
    msg(
        "geometry_msgs/msg/TwistWithCovariance",
        &[
            nested("twist", "geometry_msgs/msg/Twist"),
            arr("covariance", Prim::F64, 36),
        ],
    ),
    msg(
        "nav_msgs/msg/Odometry",
        &[
            HEADER,
            f("child_frame_id", Prim::String),
            nested("pose", "geometry_msgs/msg/PoseWithCovariance"),
            nested("twist", "geometry_msgs/msg/TwistWithCovariance"),
        ],
    ),
    msg(
        "geometry_msgs/msg/TwistStamped",
        &[HEADER, nested("twist", "geometry_msgs/msg/Twist")],
    ),
    msg(
        "geometry_msgs/msg/Transform",
        &[
            nested("translation", "geometry_msgs/msg/Vector3"),
            nested("rotation", "geometry_msgs/msg/Quaternion"),
        ],
    ),
    msg(
        "geometry_msgs/msg/TransformStamped",
        &[
            HEADER,
            f("child_frame_id", Prim::String),
            nested("transform", "geometry_msgs/msg/Transform"),
        ],
    ),
    // Not on PyPI: its type-description JSON is generated into the test venvs by
    // tests/peers/install-ros2.sh from tests/peers/interfaces/.
    msg(
        "tf2_msgs/msg/TFMessage",
        &[nested_seq(
            "transforms",
            "geometry_msgs/msg/TransformStamped",
        )],
    ),
    msg(
        "sensor_msgs/msg/Imu",
        &[
            HEADER,
            nested("orientation", "geometry_msgs/msg/Quaternion"),
            arr("orientation_covariance", Prim::F64, 9),
            nested("angular_velocity", "geometry_msgs/msg/Vector3"),
            arr("angular_velocity_covariance", Prim::F64, 9),
            nested("linear_acceleration", "geometry_msgs/msg/Vector3"),
            arr("linear_acceleration_covariance", Prim::F64, 9),
        ],
    ),
    msg(
        "diagnostic_msgs/msg/KeyValue",
        &[f("key", Prim::String), f("value", Prim::String)],
    ),
    msg(
        "diagnostic_msgs/msg/DiagnosticStatus",
        &[
            f("level", Prim::Byte),
            f("name", Prim::String),
            f("message", Prim::String),
            f("hardware_id", Prim::String),
            nested_seq("values", "diagnostic_msgs/msg/KeyValue"),
        ],
    ),
    msg(
        "diagnostic_msgs/msg/DiagnosticArray",
        &[
            HEADER,
            nested_seq("status", "diagnostic_msgs/msg/DiagnosticStatus"),
        ],
    ),
    // Service plumbing (REP-2016 describes a service as request, response and event).
    msg(
        "service_msgs/msg/ServiceEventInfo",
        &[
            f("event_type", Prim::U8),
            nested("stamp", "builtin_interfaces/msg/Time"),
            arr("client_gid", Prim::U8, 16),
            f("sequence_number", Prim::I64),
        ],
    ),
    msg("std_srvs/srv/Trigger_Request", DUMMY),
    msg(
        "std_srvs/srv/Trigger_Response",
        &[f("success", Prim::Bool), f("message", Prim::String)],
    ),
    msg("std_srvs/srv/SetBool_Request", &[f("data", Prim::Bool)]),
    msg(
        "std_srvs/srv/SetBool_Response",
        &[f("success", Prim::Bool), f("message", Prim::String)],
    ),
    msg("std_srvs/srv/Empty_Request", DUMMY),
    msg("std_srvs/srv/Empty_Response", DUMMY),
    msg(
        "std_srvs/srv/Trigger_Event",
        &[
            nested("info", "service_msgs/msg/ServiceEventInfo"),
            nested_opt("request", "std_srvs/srv/Trigger_Request"),
            nested_opt("response", "std_srvs/srv/Trigger_Response"),
        ],
    ),
    msg(
        "std_srvs/srv/SetBool_Event",
        &[
            nested("info", "service_msgs/msg/ServiceEventInfo"),
            nested_opt("request", "std_srvs/srv/SetBool_Request"),
            nested_opt("response", "std_srvs/srv/SetBool_Response"),
        ],
    ),
    msg(
        "std_srvs/srv/Empty_Event",
        &[
            nested("info", "service_msgs/msg/ServiceEventInfo"),
            nested_opt("request", "std_srvs/srv/Empty_Request"),
            nested_opt("response", "std_srvs/srv/Empty_Response"),
        ],
    ),
    msg(
        "std_srvs/srv/Trigger",
        &[
            nested("request_message", "std_srvs/srv/Trigger_Request"),
            nested("response_message", "std_srvs/srv/Trigger_Response"),
            nested("event_message", "std_srvs/srv/Trigger_Event"),
        ],
    ),
    msg(
        "std_srvs/srv/SetBool",
        &[
            nested("request_message", "std_srvs/srv/SetBool_Request"),
            nested("response_message", "std_srvs/srv/SetBool_Response"),
            nested("event_message", "std_srvs/srv/SetBool_Event"),
        ],
    ),
    msg(
        "std_srvs/srv/Empty",
        &[
            nested("request_message", "std_srvs/srv/Empty_Request"),
            nested("response_message", "std_srvs/srv/Empty_Response"),
            nested("event_message", "std_srvs/srv/Empty_Event"),
        ],
    ),
];

/// Looks a type up by its full name (`pkg/msg/Name` or `pkg/srv/Name`): from the
/// interface definitions found at run time ([`crate::interfaces`]), else from the built-in
/// catalog.
pub fn lookup(name: &str) -> Option<&'static MsgType> {
    crate::interfaces::lookup(name).or_else(|| builtin(name))
}

/// A type of the built-in catalog only.
pub fn builtin(name: &str) -> Option<&'static MsgType> {
    static BY_NAME: std::sync::OnceLock<std::collections::HashMap<&'static str, &'static MsgType>> =
        std::sync::OnceLock::new();
    BY_NAME
        .get_or_init(|| MESSAGES.iter().map(|m| (m.name, m)).collect())
        .get(name)
        .copied()
}

/// Splits `pkg/msg/Name` into (`pkg`, `msg`, `Name`).
pub fn split_name(name: &str) -> Option<(&str, &str, &str)> {
    let mut it = name.split('/');
    match (it.next(), it.next(), it.next(), it.next()) {
        (Some(p), Some(k), Some(n), None) if !p.is_empty() && !n.is_empty() => Some((p, k, n)),
        _ => None,
    }
}

/// The DDS type name rmw uses on the wire: `pkg::msg::dds_::Name_`.
pub fn dds_type_name(name: &str) -> Option<String> {
    let (p, k, n) = split_name(name)?;
    Some(format!("{p}::{k}::dds_::{n}_"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_nested_reference_resolves() {
        for m in MESSAGES {
            for fl in m.fields {
                if let Base::Nested(t) = fl.base {
                    assert!(lookup(t).is_some(), "{}.{} -> {t}", m.name, fl.name);
                }
            }
        }
    }

    #[test]
    fn names_are_unique() {
        for (i, m) in MESSAGES.iter().enumerate() {
            assert!(
                MESSAGES[i + 1..].iter().all(|o| o.name != m.name),
                "{}",
                m.name
            );
        }
    }

    #[test]
    fn type_ids_follow_rep2016() {
        assert_eq!(f("a", Prim::String).type_id(), 17);
        assert_eq!(seq("a", Prim::F64).type_id(), 11 + 144);
        assert_eq!(arr("a", Prim::U8, 16).type_id(), 51);
        assert_eq!(nested_opt("a", "x").type_id(), 97);
        assert_eq!(nested_seq("a", "x").type_id(), 145);
    }

    #[test]
    fn dds_names() {
        assert_eq!(
            dds_type_name("std_msgs/msg/String").as_deref(),
            Some("std_msgs::msg::dds_::String_")
        );
        assert_eq!(dds_type_name("std_msgs/String"), None);
    }
}
