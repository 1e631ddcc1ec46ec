//! The catalog of ROS 2 interface types the gateway speaks, described field by field.
//!
//! One description drives three things: the REP-2016 type hash ([`crate::hash`]), the
//! dynamic CDR encoding of messages ([`crate::dynmsg`]) and the validation of mapping
//! files ([`crate::mapping`]). The built-in types are the `.msg`/`.srv` files their
//! packages publish (ROS 2 Jazzy/Kilted, yarp-devices-ros2), embedded in the binary
//! ([`DEFINITIONS`]) and read by the parser of run-time types ([`crate::msgdef`]) the
//! first time the catalog is used.

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
    /// Constants (`uint8 ARROW=0`).
    pub constants: &'static [Constant],
}

/// The definitions of the built-in catalog, as their packages publish them
/// (`gateway/msg/<pkg>/<msg|srv>/<Name>.<msg|srv>`, see `gateway/msg/README.md`).
macro_rules! definitions {
    ($($pkg:ident / $kind:ident / $name:ident),* $(,)?) => {
        &[$((
            stringify!($pkg),
            stringify!($kind),
            stringify!($name),
            include_str!(concat!(
                "../msg/", stringify!($pkg), "/", stringify!($kind), "/",
                stringify!($name), ".", stringify!($kind)
            )),
        )),*]
    };
}

/// `(package, msg|srv, name, text)` of every built-in definition.
#[rustfmt::skip]
pub static DEFINITIONS: &[(&str, &str, &str, &str)] = definitions![
    builtin_interfaces/msg/Time,
    std_msgs/msg/Header,
    std_msgs/msg/String,
    std_msgs/msg/Bool,
    std_msgs/msg/Int32,
    std_msgs/msg/Int64,
    std_msgs/msg/UInt8,
    std_msgs/msg/Float32,
    std_msgs/msg/Float64,
    std_msgs/msg/Empty,
    std_msgs/msg/MultiArrayDimension,
    std_msgs/msg/MultiArrayLayout,
    std_msgs/msg/Float64MultiArray,
    std_msgs/msg/Float32MultiArray,
    std_msgs/msg/Int32MultiArray,
    std_msgs/msg/Int64MultiArray,
    geometry_msgs/msg/Vector3,
    geometry_msgs/msg/Quaternion,
    geometry_msgs/msg/Twist,
    geometry_msgs/msg/Wrench,
    geometry_msgs/msg/WrenchStamped,
    sensor_msgs/msg/JointState,
    // yarp-devices-ros2 (`controlBoard_nws_ros2`, the multiple-analog-sensors wrappers):
    // robotology/yarp-devices-ros2's `ros2_interfaces_ws/src/yarp_control_msgs` and the
    // standard types those devices publish.
    std_msgs/msg/Int8MultiArray,
    sensor_msgs/msg/MagneticField,
    sensor_msgs/msg/Temperature,
    yarp_control_msgs/msg/Position,
    yarp_control_msgs/msg/PositionDirect,
    yarp_control_msgs/msg/Velocity,
    yarp_control_msgs/srv/GetJointsNames,
    yarp_control_msgs/srv/GetControlModes,
    yarp_control_msgs/srv/SetControlModes,
    yarp_control_msgs/srv/GetAvailableControlModes,
    yarp_control_msgs/srv/GetPosition,
    yarp_control_msgs/srv/GetVelocity,
    builtin_interfaces/msg/Duration,
    trajectory_msgs/msg/JointTrajectoryPoint,
    trajectory_msgs/msg/JointTrajectory,
    sensor_msgs/msg/Image,
    // Cameras, lasers, point clouds, batteries, odometry and transforms: the topics of
    // yarp-devices-ros2's wrappers (frameGrabber, rgbdSensor, rangefinder2D, battery,
    // odometry2D, mobileBaseVelocityControl, frameTransform).
    sensor_msgs/msg/RegionOfInterest,
    sensor_msgs/msg/CameraInfo,
    sensor_msgs/msg/LaserScan,
    sensor_msgs/msg/PointField,
    sensor_msgs/msg/PointCloud2,
    sensor_msgs/msg/BatteryState,
    geometry_msgs/msg/Point,
    geometry_msgs/msg/Pose,
    geometry_msgs/msg/PoseWithCovariance,
    geometry_msgs/msg/TwistWithCovariance,
    nav_msgs/msg/Odometry,
    geometry_msgs/msg/TwistStamped,
    geometry_msgs/msg/Transform,
    geometry_msgs/msg/TransformStamped,
    // Not on PyPI: its type-description JSON is generated into the test venvs by
    // tests/peers/install-ros2.sh from tests/peers/interfaces/.
    tf2_msgs/msg/TFMessage,
    sensor_msgs/msg/Imu,
    diagnostic_msgs/msg/KeyValue,
    diagnostic_msgs/msg/DiagnosticStatus,
    diagnostic_msgs/msg/DiagnosticArray,
    // Service plumbing (REP-2016 describes a service as request, response and event).
    service_msgs/msg/ServiceEventInfo,
    std_srvs/srv/Trigger,
    std_srvs/srv/SetBool,
    std_srvs/srv/Empty,
    // Simulated time (`use_sim_time`: the node's /clock reader).
    rosgraph_msgs/msg/Clock,
    // Action plumbing (every action's goal ids, status topic and cancel service).
    unique_identifier_msgs/msg/UUID,
    action_msgs/msg/GoalInfo,
    action_msgs/msg/GoalStatus,
    action_msgs/msg/GoalStatusArray,
    action_msgs/srv/CancelGoal,
    // MoveIt's controller interface (control_msgs 6.8.0, as Kilted ships it; Jazzy's 5.8.0
    // is in msg/jazzy, see msg/README.md).
    trajectory_msgs/msg/MultiDOFJointTrajectoryPoint,
    trajectory_msgs/msg/MultiDOFJointTrajectory,
    control_msgs/msg/JointTolerance,
    control_msgs/msg/JointComponentTolerance,
    control_msgs/action/FollowJointTrajectory,
];

/// Parses a built-in definition into its structures (a service gives four, an action
/// thirteen).
pub fn parse_definition(
    (pkg, kind, name, text): (&str, &str, &str, &str),
) -> Result<Vec<crate::msgdef::MsgDef>, crate::msgdef::DefError> {
    match kind {
        "srv" => crate::msgdef::parse_srv(pkg, name, text),
        "action" => crate::msgdef::parse_action(pkg, name, text),
        _ => crate::msgdef::parse_msg(pkg, name, text).map(|d| vec![d]),
    }
}

/// Every message type the gateway knows: [`DEFINITIONS`], parsed the first time it is
/// used (a built-in definition that does not parse is a bug, caught by the tests).
pub static MESSAGES: Catalog = Catalog;

/// The built-in catalog, a slice of [`MsgType`] (`MESSAGES.iter()`, `for t in MESSAGES`).
#[derive(Debug, Clone, Copy)]
pub struct Catalog;

impl Catalog {
    fn get(self) -> &'static [MsgType] {
        static PARSED: std::sync::OnceLock<Vec<MsgType>> = std::sync::OnceLock::new();
        PARSED.get_or_init(|| {
            DEFINITIONS
                .iter()
                .flat_map(|&d| parse_definition(d).expect("a built-in definition"))
                .map(crate::interfaces::to_static)
                .collect()
        })
    }
}

impl std::ops::Deref for Catalog {
    type Target = [MsgType];
    fn deref(&self) -> &[MsgType] {
        self.get()
    }
}

impl IntoIterator for Catalog {
    type Item = &'static MsgType;
    type IntoIter = std::slice::Iter<'static, MsgType>;
    fn into_iter(self) -> Self::IntoIter {
        self.get().iter()
    }
}

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

    fn field(name: &'static str, base: Base, shape: Shape) -> Field {
        Field {
            name,
            base,
            shape,
            string_capacity: 0,
            default: None,
        }
    }
    fn f(name: &'static str, p: Prim) -> Field {
        field(name, Base::Prim(p), Shape::Single)
    }
    fn seq(name: &'static str, p: Prim) -> Field {
        field(name, Base::Prim(p), Shape::Seq)
    }
    fn arr(name: &'static str, p: Prim, n: u64) -> Field {
        field(name, Base::Prim(p), Shape::Array(n))
    }
    fn nested_seq(name: &'static str, ty: &'static str) -> Field {
        field(name, Base::Nested(ty), Shape::Seq)
    }
    fn nested_opt(name: &'static str, ty: &'static str) -> Field {
        field(name, Base::Nested(ty), Shape::BoundedSeq(1))
    }

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
    fn every_definition_parses_into_the_catalog() {
        let mut n = 0;
        for &d in DEFINITIONS {
            let defs =
                parse_definition(d).unwrap_or_else(|e| panic!("{}/{}/{}: {e}", d.0, d.1, d.2));
            let structures = match d.1 {
                "srv" => 4,
                "action" => 13,
                _ => 1,
            };
            assert_eq!(defs.len(), structures);
            for def in defs {
                assert_eq!(MESSAGES[n].name, def.name);
                assert_eq!(MESSAGES[n].fields.len(), def.fields.len(), "{}", def.name);
                assert!(std::ptr::eq(builtin(&def.name).unwrap(), &MESSAGES[n]));
                n += 1;
            }
        }
        assert_eq!(MESSAGES.len(), n);
        let q = builtin("geometry_msgs/msg/Quaternion").unwrap();
        assert_eq!(q.fields[3].default, Some("1"));
        let p = builtin("sensor_msgs/msg/PointField").unwrap();
        assert_eq!(
            (p.constants[7].name, p.constants[7].value),
            ("FLOAT64", "8")
        );
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
