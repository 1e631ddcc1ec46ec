//! Mapping files: what the gateway bridges, as data (TOML; format in `mappings/README.md`).
//!
//! Loading is strict: unknown keys, unknown ROS types and impossible combinations are
//! [`LoadError`]s that name the file, the entry and the key.

use crate::camera_info::{self, CameraInfoSource};
use crate::joint_command::Mode;
use crate::robot::{self, RobotEntry};
use crate::types;
use serde::Deserialize;
use std::fmt;
use std::path::{Path, PathBuf};

/// Which way data flows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Direction {
    YarpToRos,
    RosToYarp,
    Both,
}

impl Direction {
    pub fn to_ros(self) -> bool {
        matches!(self, Direction::YarpToRos | Direction::Both)
    }
    pub fn to_yarp(self) -> bool {
        matches!(self, Direction::RosToYarp | Direction::Both)
    }
}

impl fmt::Display for Direction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Direction::YarpToRos => "yarp->ros",
            Direction::RosToYarp => "ros->yarp",
            Direction::Both => "both",
        })
    }
}

/// How a Bottle and a ROS message correspond (see [`crate::convert`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Conversion {
    /// `std_msgs/String` holding the Bottle's text form.
    Text,
    /// One number or bool: `std_msgs/Bool`, `Int32`, `Int64`, `Float32`, `Float64`.
    Scalar,
    /// A flat Bottle of numbers (or a list of equal-length lists) <-> `*MultiArray`.
    MultiArray,
    /// Six floats `lx ly lz ax ay az` <-> `geometry_msgs/Twist`.
    Twist,
    /// A control board's state -> `sensor_msgs/JointState`.
    JointState,
    /// A frame grabber's YARP image -> `sensor_msgs/Image` (rgb8, bgr8, mono8, mono16).
    Image,
    /// Multiple-analog-sensors IMU Bottle -> `sensor_msgs/Imu`.
    Imu,
    /// Multiple-analog-sensors F/T Bottle -> `geometry_msgs/WrenchStamped`.
    Wrench,
    /// `sensor_msgs/JointState`, `std_msgs/Float64MultiArray` or
    /// `trajectory_msgs/JointTrajectory` -> a control board (see [`crate::joint_command`]).
    JointCommand,
    /// Any message type <-> its fields as a Bottle, both ways ([`crate::generic`]); the
    /// default for types no other conversion carries.
    Generic,
}

impl Conversion {
    /// The conversion used when an entry names none.
    pub fn default_for(ros_type: &str) -> Option<Conversion> {
        Some(match ros_type {
            "std_msgs/msg/String" => Conversion::Text,
            "std_msgs/msg/Bool"
            | "std_msgs/msg/Int32"
            | "std_msgs/msg/Int64"
            | "std_msgs/msg/Float32"
            | "std_msgs/msg/Float64" => Conversion::Scalar,
            "std_msgs/msg/Float64MultiArray"
            | "std_msgs/msg/Float32MultiArray"
            | "std_msgs/msg/Int32MultiArray"
            | "std_msgs/msg/Int64MultiArray" => Conversion::MultiArray,
            "geometry_msgs/msg/Twist" => Conversion::Twist,
            "sensor_msgs/msg/JointState" => Conversion::JointState,
            "sensor_msgs/msg/Imu" => Conversion::Imu,
            "sensor_msgs/msg/Image" => Conversion::Image,
            "geometry_msgs/msg/WrenchStamped" => Conversion::Wrench,
            "trajectory_msgs/msg/JointTrajectory" => Conversion::JointCommand,
            // no type: a ROS-topic pattern mirroring whatever types its topics have
            "" => Conversion::Generic,
            t if is_message_type(t) => Conversion::Generic,
            _ => return None,
        })
    }

    /// Whether this conversion can carry `ros_type`.
    pub fn fits(self, ros_type: &str) -> bool {
        match self {
            Conversion::JointCommand => JOINT_COMMAND_TYPES.contains(&ros_type),
            Conversion::Generic => ros_type.is_empty() || is_message_type(ros_type),
            _ => Conversion::default_for(ros_type) == Some(self),
        }
    }

    /// Whether this conversion works in `dir`.
    pub fn supports(self, dir: Direction) -> bool {
        match self {
            Conversion::Text
            | Conversion::Scalar
            | Conversion::MultiArray
            | Conversion::Twist
            | Conversion::Generic => true,
            Conversion::JointState | Conversion::Image | Conversion::Imu | Conversion::Wrench => {
                dir == Direction::YarpToRos
            }
            Conversion::JointCommand => dir == Direction::RosToYarp,
        }
    }

    /// Whether the ROS message carries a `std_msgs/Header` (and so a `frame_id`).
    pub fn has_header(self) -> bool {
        matches!(
            self,
            Conversion::JointState | Conversion::Image | Conversion::Imu | Conversion::Wrench
        )
    }
}

/// Whether `t` names a message type the gateway knows (built in or read at run time).
fn is_message_type(t: &str) -> bool {
    t.contains("/msg/") && types::lookup(t).is_some()
}

/// The ROS types a `joint_command` entry takes.
pub const JOINT_COMMAND_TYPES: [&str; 3] = [
    "sensor_msgs/msg/JointState",
    "std_msgs/msg/Float64MultiArray",
    "trajectory_msgs/msg/JointTrajectory",
];

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Reliability {
    #[default]
    Reliable,
    BestEffort,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Durability {
    #[default]
    Volatile,
    TransientLocal,
}

impl std::fmt::Display for Reliability {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Reliability::Reliable => "reliable",
            Reliability::BestEffort => "best_effort",
        })
    }
}

/// ROS QoS of an entry's DDS endpoints (history is always keep-last `depth`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Qos {
    /// `None` until loaded: then the entry's default ([`default_reliability`]) when the
    /// file gives none.
    pub reliability: Option<Reliability>,
    pub durability: Durability,
    pub depth: u32,
}

impl Qos {
    /// The reliability in force (reliable when unset).
    pub fn reliability(&self) -> Reliability {
        self.reliability.unwrap_or_default()
    }
}

impl Default for Qos {
    fn default() -> Self {
        Qos {
            reliability: None,
            durability: Durability::Volatile,
            depth: 10,
        }
    }
}

/// An entry's reliability when its file gives none. What the gateway offers
/// (`yarp_to_ros`, `both`) is reliable, as rclpy's, `ros2 topic echo`'s and RViz's
/// default subscriptions request: a reliable reader never matches a best-effort writer.
/// What it reads as commands (joint commands, a Twist into YARP) is best effort, because
/// a best-effort reader matches reliable and best-effort publishers alike (teleop and
/// controllers use either) and, of a stream of setpoints, only the newest matters. A
/// `transient_local` entry stays reliable: a late-joining reader gets the writer's kept
/// samples only over the reliable protocol.
pub fn default_reliability(t: &TopicEntry) -> Reliability {
    let command = matches!(default_conversion(t), Some(Conversion::JointCommand))
        || (t.direction == Direction::RosToYarp && t.ros_type == "geometry_msgs/msg/Twist");
    if command && t.qos.durability == Durability::Volatile {
        Reliability::BestEffort
    } else {
        Reliability::Reliable
    }
}

/// Where a control board's joint names come from.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(tag = "from", rename_all = "snake_case", deny_unknown_fields)]
pub enum JointNames {
    /// Asked over the board's RPC port (`[get] [axes]`, then `[get] [name] i`).
    AxisInfo { rpc_port: String },
    /// Given in the mapping file.
    List { names: Vec<String> },
}

/// The control board a `joint_command` entry drives, through a `remote_controlboard`
/// whose local port prefix is the entry's `yarp_port`.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControlBoard {
    /// The board's port prefix (`controlBoard_nws_yarp`'s `name`), e.g. `/icub/left_arm`.
    pub remote: String,
    pub mode: Mode,
    /// Axes (by name) an unnamed message such as Float64MultiArray addresses, in order;
    /// default every axis.
    #[serde(default)]
    pub joints: Vec<String>,
}

/// A `[[topic]]` entry: a YARP stream bridged to a ROS topic.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TopicEntry {
    /// Unique name of the entry (errors, startup table, diagnostics).
    pub name: String,
    pub direction: Direction,
    /// The port the gateway opens.
    pub yarp_port: Option<String>,
    /// Bridge every port matching this name-server pattern (`*` wildcards); yarp_to_ros only.
    pub yarp_pattern: Option<String>,
    /// An existing port the gateway connects into `yarp_port` (kept connected).
    pub yarp_source: Option<String>,
    /// An existing port the gateway connects `yarp_port` to (kept connected).
    pub yarp_sink: Option<String>,
    pub ros_topic: String,
    /// Empty (left out) only in a `ros_to_yarp` ROS-topic pattern: each matching topic is
    /// mirrored with the type its publishers announce (generic conversion).
    #[serde(default)]
    pub ros_type: String,
    pub conversion: Option<Conversion>,
    #[serde(default)]
    pub qos: Qos,
    /// At most this many messages per second are forwarded (the rest are counted as drops).
    pub rate_limit_hz: Option<f64>,
    pub frame_id: Option<String>,
    pub joint_names: Option<JointNames>,
    /// Which sensor of its family (imu, wrench; default 0).
    pub sensor_index: Option<usize>,
    /// Joint commands: the board driven (`joint_command` conversion).
    pub control_board: Option<ControlBoard>,
    /// Images: a `sensor_msgs/CameraInfo` beside each Image (see [`crate::camera_info`]).
    pub camera_info: Option<CameraInfoSource>,
}

impl TopicEntry {
    /// Dynamic mode for ROS topics: `ros_topic` holds `*` / `?` wildcards.
    pub fn is_ros_pattern(&self) -> bool {
        self.ros_topic.contains(['*', '?'])
    }

    /// The conversion in force (explicit or the type's default; valid after loading).
    pub fn conversion(&self) -> Conversion {
        default_conversion(self).expect("validated at load time")
    }
}

/// How a service entry maps requests and replies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ServiceConversion {
    /// std_srvs Trigger / SetBool / Empty <-> configured command Bottles.
    Command,
    /// Generic text RPC: `<ros_service>/request` and `<ros_service>/reply` std_msgs/String
    /// topics carry Bottle text to and from a YARP RPC port.
    TextRpc,
    /// Any `pkg/srv/Name`: the request and the response are Bottles in the generic layout
    /// of their types ([`crate::generic`]); towards YARP the request follows the optional
    /// `command` words.
    Generic,
}

/// A `[[service]]` entry: a YARP RPC port bridged to a ROS service.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ServiceEntry {
    pub name: String,
    /// `ros_to_yarp`: ROS clients call the gateway's ROS service, which calls the YARP RPC
    /// port `yarp_port`. `yarp_to_ros`: YARP clients call the gateway's RPC port
    /// `yarp_port`, which calls the ROS service.
    pub direction: Direction,
    pub yarp_port: String,
    pub ros_service: String,
    pub ros_type: String,
    pub conversion: Option<ServiceConversion>,
    /// Trigger/Empty, ros_to_yarp: the Bottle (text form) sent to YARP; generic,
    /// ros_to_yarp: words sent before the request's fields.
    pub command: Option<String>,
    /// SetBool, ros_to_yarp: the Bottles sent for `data = true` / `false`.
    pub command_true: Option<String>,
    pub command_false: Option<String>,
}

impl ServiceEntry {
    pub fn conversion(&self) -> ServiceConversion {
        self.conversion
            .unwrap_or(if self.ros_type == "std_msgs/msg/String" {
                ServiceConversion::TextRpc
            } else if COMMAND_SERVICES.contains(&self.ros_type.as_str()) {
                ServiceConversion::Command
            } else {
                ServiceConversion::Generic
            })
    }
}

/// An `[[action]]` entry: a ROS 2 action served by a YARP RPC port (`ros_to_yarp`), or a
/// YARP RPC port whose callers reach a ROS 2 action server (`yarp_to_ros`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ActionEntry {
    pub name: String,
    /// `ros_to_yarp`: ROS action clients send goals to the gateway's action server; each
    /// goal is a call of the YARP RPC port `yarp_port`. `yarp_to_ros`: each Bottle sent to
    /// the gateway's RPC port `yarp_port` is a goal of the ROS action; the reply is its
    /// result.
    pub direction: Direction,
    pub yarp_port: String,
    pub ros_action: String,
    /// `pkg/action/Name`, built in or read at run time.
    pub ros_type: String,
    /// Words sent before the goal's fields.
    pub command: Option<String>,
    /// The Bottle (text) that stops a goal, sent on another connection to `yarp_port`;
    /// without it cancel requests are refused.
    pub cancel: Option<String>,
    /// `ros_to_yarp`: a YARP port whose Bottles (in the feedback's generic layout) are the
    /// executing goals' feedback; `yarp_to_ros`: the port the gateway opens and writes the
    /// feedback of its goals to.
    pub yarp_feedback: Option<String>,
    /// A FollowJointTrajectory action served by the gateway's own trajectory controller
    /// on a group of control boards (no YARP RPC port runs the goals: `yarp_port` is the
    /// prefix of the boards' client ports).
    pub controller: Option<TrajectoryController>,
}

/// A joint trajectory controller as MoveIt's `moveit_controllers.yaml` names one: the
/// boards of one part or a group of parts, its joints and joint_trajectory_controller's
/// default `constraints` (SI units; 0 is not checked).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrajectoryController {
    /// The boards' port prefixes (`controlBoard_nws_yarp`'s `name`), e.g.
    /// `["/icub/torso", "/icub/left_arm"]`; their axes are the controller's, in order.
    pub boards: Vec<String>,
    /// `position` (IPositionControl, one move per trajectory segment) or
    /// `position_direct` (the desired positions streamed every period).
    #[serde(default = "TrajectoryController::default_mode")]
    pub mode: Mode,
    /// The joints it may move (by name); default every axis of the boards.
    #[serde(default)]
    pub joints: Vec<String>,
    /// Default goal tolerance per joint (rad or m).
    #[serde(default = "TrajectoryController::default_goal_tolerance")]
    pub goal_tolerance: f64,
    /// Default path tolerance per joint (rad or m).
    #[serde(default)]
    pub path_tolerance: f64,
    /// Velocity under which a joint counts as stopped at the goal (rad/s or m/s).
    #[serde(default)]
    pub stopped_velocity_tolerance: f64,
    /// How long after the trajectory's end the goal tolerance may take to be met (s).
    #[serde(default = "TrajectoryController::default_goal_time")]
    pub goal_time: f64,
    /// How often feedback is published and, in position_direct, setpoints sent (Hz).
    #[serde(default = "TrajectoryController::default_rate")]
    pub rate_hz: f64,
}

impl TrajectoryController {
    fn default_mode() -> Mode {
        Mode::Position
    }
    fn default_goal_tolerance() -> f64 {
        0.02
    }
    fn default_goal_time() -> f64 {
        1.0
    }
    fn default_rate() -> f64 {
        50.0
    }

    /// The defaults a goal's tolerances fall back to.
    pub fn defaults(&self) -> crate::trajectory::Defaults {
        crate::trajectory::Defaults {
            goal_position: self.goal_tolerance,
            path_position: self.path_tolerance,
            stopped_velocity: self.stopped_velocity_tolerance,
            goal_time: self.goal_time,
        }
    }
}

/// The action type a [`TrajectoryController`] serves.
pub const FOLLOW_JOINT_TRAJECTORY: &str = "control_msgs/action/FollowJointTrajectory";

/// Everything loaded from one or more mapping files.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mappings {
    pub topics: Vec<TopicEntry>,
    pub services: Vec<ServiceEntry>,
    /// `[[action]]` entries (see [`crate::action`]).
    pub actions: Vec<ActionEntry>,
    /// `[[robot]]` entries (see [`crate::robot`]).
    pub robots: Vec<RobotEntry>,
    /// `interfaces = [...]`: directories of interface definitions the files name (added
    /// to [`crate::interfaces`] as they load).
    pub interfaces: Vec<PathBuf>,
}

/// A mapping file that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    #[error("{file}: cannot read: {source}")]
    Io {
        file: PathBuf,
        source: std::io::Error,
    },
    #[error("{file}: not valid TOML: {message}")]
    Syntax { file: PathBuf, message: String },
    #[error("{file}: top-level key `{key}` is unknown (expected `topic`, `service`, `robot` or `interfaces`)")]
    UnknownSection { file: PathBuf, key: String },
    #[error("{file}: entry {entry}: key `{key}`: {message}")]
    Entry {
        file: PathBuf,
        entry: String,
        key: String,
        message: String,
    },
}

impl LoadError {
    /// The key an entry error is about (tests and tools).
    pub fn key(&self) -> Option<&str> {
        match self {
            LoadError::Entry { key, .. } | LoadError::UnknownSection { key, .. } => Some(key),
            _ => None,
        }
    }
}

impl Mappings {
    /// Loads and validates mapping files; entry names must be unique across all of them,
    /// and a `[[robot]]` entry's parts may be in any of them.
    pub fn load(files: &[impl AsRef<Path>]) -> Result<Mappings, LoadError> {
        let mut all = Mappings::default();
        for f in files {
            let f = f.as_ref();
            let text = std::fs::read_to_string(f).map_err(|source| LoadError::Io {
                file: f.to_path_buf(),
                source,
            })?;
            let one = Mappings::parse_one(&text, f)?;
            for t in one.topics {
                check_unique(&all, &t.name, f)?;
                all.topics.push(t);
            }
            for s in one.services {
                check_unique(&all, &s.name, f)?;
                all.services.push(s);
            }
            for r in one.robots {
                check_unique(&all, &r.name, f)?;
                all.robots.push(r);
            }
            for a in one.actions {
                check_unique(&all, &a.name, f)?;
                all.actions.push(a);
            }
            all.interfaces.extend(one.interfaces);
        }
        all.check_robot_parts()?;
        Ok(all)
    }

    /// Parses and validates one file's text (`file` names it in errors; relative paths in
    /// it, such as a URDF, are relative to its directory).
    pub fn parse(text: &str, file: &Path) -> Result<Mappings, LoadError> {
        let m = Mappings::parse_one(text, file)?;
        m.check_robot_parts()?;
        Ok(m)
    }

    /// A `[[robot]]` entry's parts must be JointState entries of the files loaded.
    fn check_robot_parts(&self) -> Result<(), LoadError> {
        for r in &self.robots {
            robot::check_parts(r, &self.topics).map_err(|(key, message)| LoadError::Entry {
                file: r.file.clone(),
                entry: format!("robot \"{}\"", r.name),
                key: key.into(),
                message,
            })?;
        }
        Ok(())
    }

    fn parse_one(text: &str, file: &Path) -> Result<Mappings, LoadError> {
        let table: toml::Table = text
            .parse()
            .map_err(|e: toml::de::Error| LoadError::Syntax {
                file: file.to_path_buf(),
                message: e.message().to_string(),
            })?;
        let mut out = Mappings::default();
        let mut table = table;
        // Interface directories first: the entries' types may be defined there.
        if let Some(dirs) = table.remove("interfaces") {
            out.interfaces = interface_dirs(dirs, file)?;
            for d in &out.interfaces {
                crate::interfaces::add_dir(d);
            }
        }
        for (key, value) in table {
            let entries = match (key.as_str(), value) {
                ("topic" | "service" | "action" | "robot", toml::Value::Array(a)) => a,
                ("topic" | "service" | "action" | "robot", _) => {
                    return Err(LoadError::Entry {
                        file: file.to_path_buf(),
                        entry: key.clone(),
                        key,
                        message: "must be an array of tables ([[...]])".into(),
                    })
                }
                _ => {
                    return Err(LoadError::UnknownSection {
                        file: file.to_path_buf(),
                        key,
                    })
                }
            };
            for (i, v) in entries.into_iter().enumerate() {
                let label = entry_label(&key, i, &v);
                let err = |k: &str, message: String| LoadError::Entry {
                    file: file.to_path_buf(),
                    entry: label.clone(),
                    key: k.to_string(),
                    message,
                };
                if key == "topic" {
                    let mut t: TopicEntry = deserialize(v).map_err(|(k, m)| err(&k, m))?;
                    validate_topic(&t).map_err(|(k, m)| err(k, m))?;
                    camera_info::validate(&mut t, file).map_err(|(k, m)| err(k, m))?;
                    t.qos.reliability = Some(t.qos.reliability.unwrap_or(default_reliability(&t)));
                    check_unique(&out, &t.name, file)?;
                    out.topics.push(t);
                } else if key == "action" {
                    let a: ActionEntry = deserialize(v).map_err(|(k, m)| err(&k, m))?;
                    validate_action(&a).map_err(|(k, m)| err(k, m))?;
                    check_unique(&out, &a.name, file)?;
                    out.actions.push(a);
                } else if key == "robot" {
                    let mut r: RobotEntry = deserialize(v).map_err(|(k, m)| err(&k, m))?;
                    robot::validate(&mut r, file).map_err(|(k, m)| err(k, m))?;
                    check_unique(&out, &r.name, file)?;
                    out.robots.push(r);
                } else {
                    let s: ServiceEntry = deserialize(v).map_err(|(k, m)| err(&k, m))?;
                    validate_service(&s).map_err(|(k, m)| err(k, m))?;
                    check_unique(&out, &s.name, file)?;
                    out.services.push(s);
                }
            }
        }
        Ok(out)
    }
}

/// `interfaces = ["dir", ...]`: directories of interface definitions (relative to the
/// mapping file's directory), each a prefix, a directory of packages or one package.
fn interface_dirs(v: toml::Value, file: &Path) -> Result<Vec<PathBuf>, LoadError> {
    let err = |message: String| LoadError::Entry {
        file: file.to_path_buf(),
        entry: "interfaces".into(),
        key: "interfaces".into(),
        message,
    };
    let toml::Value::Array(items) = v else {
        return Err(err("must be an array of directories".into()));
    };
    let base = file.parent().unwrap_or(Path::new(""));
    items
        .into_iter()
        .map(|i| match i {
            toml::Value::String(d) => {
                let p = base.join(&d);
                if p.is_dir() {
                    Ok(p)
                } else {
                    Err(err(format!("`{}` is not a directory", p.display())))
                }
            }
            other => Err(err(format!("`{other}` is not a directory name"))),
        })
        .collect()
}

fn entry_label(section: &str, i: usize, v: &toml::Value) -> String {
    match v.get("name").and_then(|n| n.as_str()) {
        Some(n) => format!("{section}[{i}] \"{n}\""),
        None => format!("{section}[{i}]"),
    }
}

fn check_unique(m: &Mappings, name: &str, file: &Path) -> Result<(), LoadError> {
    let taken = m.topics.iter().any(|t| t.name == name)
        || m.services.iter().any(|s| s.name == name)
        || m.robots.iter().any(|r| r.name == name)
        || m.actions.iter().any(|a| a.name == name);
    if taken {
        return Err(LoadError::Entry {
            file: file.to_path_buf(),
            entry: format!("\"{name}\""),
            key: "name".into(),
            message: "another entry already has this name".into(),
        });
    }
    Ok(())
}

/// Deserializes an entry, reporting the offending key (serde_path_to_error tracks it).
fn deserialize<T: serde::de::DeserializeOwned>(v: toml::Value) -> Result<T, (String, String)> {
    serde_path_to_error::deserialize(v).map_err(|e| {
        let message = e.inner().message().to_string();
        let mut key = e.path().to_string();
        // serde reports a missing field at the parent; name the field itself.
        if let Some(rest) = message.strip_prefix("missing field `") {
            let field = rest.split('`').next().unwrap_or_default();
            key = if key == "." {
                field.to_string()
            } else {
                format!("{key}.{field}")
            };
        }
        (key, message)
    })
}

/// A validation error: the key and what is wrong with it.
pub(crate) type Invalid = (&'static str, String);

/// The explicit conversion, else `joint_command` when a control board is named, else the
/// type's default.
fn default_conversion(t: &TopicEntry) -> Option<Conversion> {
    t.conversion.or_else(|| {
        if t.control_board.is_some() {
            Some(Conversion::JointCommand)
        } else {
            Conversion::default_for(&t.ros_type)
        }
    })
}

fn validate_topic(t: &TopicEntry) -> Result<(), Invalid> {
    if t.is_ros_pattern() {
        validate_ros_pattern(t)?;
    } else {
        check_ros_name("ros_topic", &t.ros_topic)?;
    }
    if t.ros_type.is_empty() {
        if !t.is_ros_pattern() {
            return Err((
                "ros_type",
                "required (only a ros_topic pattern may leave it out)".into(),
            ));
        }
        if t.conversion.is_some_and(|c| c != Conversion::Generic) {
            return Err((
                "conversion",
                "a pattern without ros_type mirrors any type: generic only".into(),
            ));
        }
    } else if !is_message_type(&t.ros_type) {
        let why = crate::interfaces::problem(&t.ros_type)
            .map(|p| format!(" (its definition: {p})"))
            .unwrap_or_else(|| {
                " (not built in, and no definition in AMENT_PREFIX_PATH, --interfaces or \
                 the mapping's `interfaces`)"
                    .into()
            });
        return Err((
            "ros_type",
            format!("unknown message type `{}`{why}", t.ros_type),
        ));
    }
    let conv = match t.conversion {
        Some(c) if !c.fits(&t.ros_type) => {
            return Err((
                "conversion",
                format!("conversion {c:?} cannot carry {}", t.ros_type),
            ))
        }
        Some(c) => c,
        None => default_conversion(t)
            .ok_or(("ros_type", format!("no conversion carries {}", t.ros_type)))?,
    };
    if conv == Conversion::JointCommand && !conv.fits(&t.ros_type) {
        return Err((
            "ros_type",
            format!(
                "joint commands take {}, not {}",
                JOINT_COMMAND_TYPES.join(", "),
                t.ros_type
            ),
        ));
    }
    if !conv.supports(t.direction) {
        let only = if conv == Conversion::JointCommand {
            "ros_to_yarp"
        } else {
            "yarp_to_ros"
        };
        return Err((
            "direction",
            format!("conversion {conv:?} only works {only}"),
        ));
    }
    match (&t.yarp_port, &t.yarp_pattern) {
        (Some(p), None) => check_port("yarp_port", p)?,
        (None, Some(p)) => {
            check_port("yarp_pattern", p)?;
            if t.direction != Direction::YarpToRos {
                return Err((
                    "yarp_pattern",
                    "patterns bridge existing YARP outputs, so only yarp_to_ros".into(),
                ));
            }
            if t.yarp_source.is_some() {
                return Err(("yarp_source", "not allowed with yarp_pattern".into()));
            }
            if conv == Conversion::JointState {
                return Err((
                    "yarp_pattern",
                    "joint names differ per control board: give each its entry".into(),
                ));
            }
        }
        (Some(_), Some(_)) => {
            return Err((
                "yarp_pattern",
                "give either yarp_port or yarp_pattern, not both".into(),
            ))
        }
        (None, None) => return Err(("yarp_port", "missing (or give yarp_pattern)".into())),
    }
    if let Some(s) = &t.yarp_source {
        check_port("yarp_source", s)?;
        if !t.direction.to_ros() {
            return Err((
                "yarp_source",
                "only for yarp_to_ros or both (data comes from YARP)".into(),
            ));
        }
    }
    if let Some(s) = &t.yarp_sink {
        check_port("yarp_sink", s)?;
        if !t.direction.to_yarp() {
            return Err((
                "yarp_sink",
                "only for ros_to_yarp or both (data goes to YARP)".into(),
            ));
        }
    }
    if t.qos.depth == 0 {
        return Err(("qos.depth", "must be at least 1".into()));
    }
    if let Some(r) = t.rate_limit_hz {
        if !(r.is_finite() && r > 0.0) {
            return Err((
                "rate_limit_hz",
                format!("must be a positive number, not {r}"),
            ));
        }
    }
    let header = conv.has_header()
        || (conv == Conversion::Generic
            && types::lookup(&t.ros_type).is_some_and(|m| {
                m.fields
                    .iter()
                    .any(|f| f.base == types::Base::Nested("std_msgs/msg/Header"))
            }));
    if t.frame_id.is_some() && !header {
        return Err((
            "frame_id",
            format!("{} has no header to carry a frame_id", t.ros_type),
        ));
    }
    if t.sensor_index.is_some() && !matches!(conv, Conversion::Imu | Conversion::Wrench) {
        return Err(("sensor_index", "only for imu and wrench".into()));
    }
    validate_control_board(t, conv)?;
    match (&t.joint_names, conv) {
        (None, Conversion::JointState) => {
            return Err((
                "joint_names",
                "required for sensor_msgs/msg/JointState".into(),
            ))
        }
        (Some(_), c) if c != Conversion::JointState => {
            return Err(("joint_names", "only for sensor_msgs/msg/JointState".into()))
        }
        (Some(JointNames::AxisInfo { rpc_port }), _) => {
            check_port("joint_names.rpc_port", rpc_port)?
        }
        (Some(JointNames::List { names }), _) if names.is_empty() => {
            return Err(("joint_names.names", "must name at least one joint".into()))
        }
        _ => {}
    }
    Ok(())
}

/// A `ros_topic` pattern mirrors matching ROS topics into ports under `yarp_port`.
fn validate_ros_pattern(t: &TopicEntry) -> Result<(), Invalid> {
    let as_name = t.ros_topic.replace(['*', '?'], "x");
    if !as_name.starts_with('/') {
        return Err((
            "ros_topic",
            "a topic pattern must be absolute (`/...`)".into(),
        ));
    }
    check_ros_name("ros_topic", &as_name)?;
    if t.direction != Direction::RosToYarp {
        return Err((
            "direction",
            "a ros_topic pattern mirrors ROS topics into YARP: ros_to_yarp only".into(),
        ));
    }
    if t.yarp_port.is_none() {
        return Err((
            "yarp_port",
            "required with a ros_topic pattern: the prefix of the mirrored ports".into(),
        ));
    }
    if t.yarp_sink.is_some() {
        return Err((
            "yarp_sink",
            "not allowed with a ros_topic pattern (one port per topic)".into(),
        ));
    }
    if t.control_board.is_some() {
        return Err((
            "control_board",
            "a joint command entry drives one board: give one ros_topic".into(),
        ));
    }
    Ok(())
}

fn validate_control_board(t: &TopicEntry, conv: Conversion) -> Result<(), Invalid> {
    let Some(cb) = &t.control_board else {
        if conv == Conversion::JointCommand {
            return Err((
                "control_board",
                "required for joint commands: { remote = \"/robot/part\", mode = ... }".into(),
            ));
        }
        return Ok(());
    };
    if conv != Conversion::JointCommand {
        return Err((
            "control_board",
            format!("only for joint commands, not conversion {conv:?}"),
        ));
    }
    check_port("control_board.remote", &cb.remote)?;
    if t.yarp_pattern.is_some() {
        return Err((
            "yarp_pattern",
            "a joint command entry drives one board: give yarp_port".into(),
        ));
    }
    if t.yarp_sink.is_some() {
        return Err((
            "yarp_sink",
            "joint commands go to control_board.remote, not to a sink".into(),
        ));
    }
    if cb.mode == Mode::Velocity && t.ros_type == "trajectory_msgs/msg/JointTrajectory" {
        return Err((
            "control_board.mode",
            "trajectories are followed in position or position_direct mode".into(),
        ));
    }
    if let Some(i) = cb.joints.iter().position(|j| j.is_empty()) {
        return Err((
            "control_board.joints",
            format!("joint {i} has an empty name"),
        ));
    }
    Ok(())
}

const COMMAND_SERVICES: [&str; 3] = [
    "std_srvs/srv/Trigger",
    "std_srvs/srv/SetBool",
    "std_srvs/srv/Empty",
];

fn validate_controller(a: &ActionEntry, c: &TrajectoryController) -> Result<(), Invalid> {
    if a.direction != Direction::RosToYarp || a.ros_type != FOLLOW_JOINT_TRAJECTORY {
        return Err((
            "controller",
            format!("a controller serves {FOLLOW_JOINT_TRAJECTORY} ros_to_yarp"),
        ));
    }
    if a.command.is_some() || a.cancel.is_some() || a.yarp_feedback.is_some() {
        return Err((
            "controller",
            "the controller runs the goals itself: no command, cancel or yarp_feedback".into(),
        ));
    }
    if c.boards.is_empty() {
        return Err(("controller", "`boards` names no control board".into()));
    }
    for b in &c.boards {
        check_port("controller", b)?;
    }
    if c.mode == Mode::Velocity {
        return Err((
            "controller",
            "mode: a trajectory is followed in position or position_direct".into(),
        ));
    }
    let tolerances = [
        c.goal_tolerance,
        c.path_tolerance,
        c.stopped_velocity_tolerance,
        c.goal_time,
    ];
    if tolerances.iter().any(|x| !x.is_finite() || *x < 0.0) {
        return Err((
            "controller",
            "tolerances and goal_time are numbers >= 0 (0: not checked)".into(),
        ));
    }
    if !(c.rate_hz.is_finite() && c.rate_hz > 0.0 && c.rate_hz <= 1000.0) {
        return Err(("controller", "rate_hz must be in (0, 1000]".into()));
    }
    Ok(())
}

fn validate_action(a: &ActionEntry) -> Result<(), Invalid> {
    check_ros_name("ros_action", &a.ros_action)?;
    check_port("yarp_port", &a.yarp_port)?;
    if let Some(c) = &a.controller {
        validate_controller(a, c)?;
    }
    if let Some(p) = &a.yarp_feedback {
        check_port("yarp_feedback", p)?;
    }
    match a.direction {
        Direction::Both => {
            return Err((
                "direction",
                "an action has one server: choose ros_to_yarp or yarp_to_ros".into(),
            ))
        }
        Direction::YarpToRos if a.command.is_some() || a.cancel.is_some() => {
            return Err((
                "command",
                "yarp_to_ros sends any Bottle as a goal ([stop] cancels): no command or cancel"
                    .into(),
            ))
        }
        _ => {}
    }
    if !matches!(
        crate::types::split_name(&a.ros_type),
        Some((_, "action", _))
    ) {
        return Err((
            "ros_type",
            format!("`{}` is not an action type (pkg/action/Name)", a.ros_type),
        ));
    }
    let goal = format!("{}_SendGoal_Request", a.ros_type);
    if crate::types::lookup(&goal).is_none() {
        let why = crate::interfaces::problem(&goal)
            .map(|p| format!(" (its definition: {p})"))
            .unwrap_or_else(|| {
                " (no definition in AMENT_PREFIX_PATH, --interfaces or the mapping's \
                 `interfaces`)"
                    .into()
            });
        return Err((
            "ros_type",
            format!("unknown action type `{}`{why}", a.ros_type),
        ));
    }
    Ok(())
}

fn validate_service(s: &ServiceEntry) -> Result<(), Invalid> {
    check_ros_name("ros_service", &s.ros_service)?;
    check_port("yarp_port", &s.yarp_port)?;
    if s.direction == Direction::Both {
        return Err((
            "direction",
            "a service has one server: choose ros_to_yarp or yarp_to_ros".into(),
        ));
    }
    let setbool = s.ros_type == "std_srvs/srv/SetBool";
    match s.conversion() {
        ServiceConversion::Command => {
            if !COMMAND_SERVICES.contains(&s.ros_type.as_str()) {
                return Err((
                    "ros_type",
                    format!(
                        "conversion `command` maps {}, not `{}` (any .srv: `generic`)",
                        COMMAND_SERVICES.join(", "),
                        s.ros_type,
                    ),
                ));
            }
            let to_yarp = s.direction == Direction::RosToYarp;
            match (setbool, to_yarp) {
                (false, true) if s.command.is_none() => {
                    return Err(("command", "required: the Bottle sent to YARP".into()))
                }
                (true, true) if s.command_true.is_none() => {
                    return Err(("command_true", "required for SetBool".into()))
                }
                (true, true) if s.command_false.is_none() => {
                    return Err(("command_false", "required for SetBool".into()))
                }
                (true, _) if s.command.is_some() => {
                    return Err(("command", "SetBool uses command_true/command_false".into()))
                }
                (false, _) if s.command_true.is_some() || s.command_false.is_some() => {
                    return Err((
                        "command_true",
                        "only SetBool has command_true/command_false".into(),
                    ))
                }
                (_, false) if s.command.is_some() || s.command_true.is_some() => {
                    return Err((
                        "command",
                        "yarp_to_ros forwards any Bottle to the ROS service; no command".into(),
                    ))
                }
                _ => {}
            }
        }
        ServiceConversion::Generic => {
            if !matches!(crate::types::split_name(&s.ros_type), Some((_, "srv", _))) {
                return Err((
                    "ros_type",
                    format!("`{}` is not a service type (pkg/srv/Name)", s.ros_type),
                ));
            }
            let request = format!("{}_Request", s.ros_type);
            if crate::types::lookup(&request).is_none() {
                let why = crate::interfaces::problem(&request)
                    .map(|p| format!(" (its definition: {p})"))
                    .unwrap_or_else(|| {
                        " (not built in, and no definition in AMENT_PREFIX_PATH, --interfaces \
                         or the mapping's `interfaces`)"
                            .into()
                    });
                return Err((
                    "ros_type",
                    format!("unknown service type `{}`{why}", s.ros_type),
                ));
            }
            if s.command_true.is_some() || s.command_false.is_some() {
                return Err((
                    "command_true",
                    "only SetBool's command conversion has command_true/command_false".into(),
                ));
            }
            if s.command.is_some() && s.direction != Direction::RosToYarp {
                return Err((
                    "command",
                    "yarp_to_ros forwards any Bottle to the ROS service; no command".into(),
                ));
            }
        }
        ServiceConversion::TextRpc => {
            if s.ros_type != "std_msgs/msg/String" {
                return Err(("ros_type", "text_rpc uses std_msgs/msg/String".into()));
            }
            if s.direction != Direction::RosToYarp {
                return Err(("direction", "text_rpc is ros_to_yarp".into()));
            }
            if s.command.is_some() || s.command_true.is_some() || s.command_false.is_some() {
                return Err((
                    "command",
                    "text_rpc forwards the request text itself".into(),
                ));
            }
        }
    }
    Ok(())
}

fn check_port(key: &'static str, p: &str) -> Result<(), Invalid> {
    if !p.starts_with('/') || p.len() < 2 || p.chars().any(char::is_whitespace) {
        return Err((
            key,
            format!("`{p}` is not a YARP port name (/name, no spaces)"),
        ));
    }
    Ok(())
}

/// ROS names: `/`-separated tokens of letters, digits and `_`, not starting with a digit,
/// without `__`.
pub(crate) fn check_ros_name(key: &'static str, n: &str) -> Result<(), Invalid> {
    let body = n.strip_prefix('/').unwrap_or(n);
    let ok = !body.is_empty()
        && !body.contains("__")
        && body.split('/').all(|tok| {
            !tok.is_empty()
                && !tok.starts_with(|c: char| c.is_ascii_digit())
                && tok.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        });
    if ok {
        Ok(())
    } else {
        Err((key, format!("`{n}` is not a valid ROS name")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<Mappings, LoadError> {
        Mappings::parse(s, Path::new("m.toml"))
    }

    fn entry_error(s: &str) -> (String, String, String) {
        match parse(s) {
            Err(LoadError::Entry {
                entry,
                key,
                message,
                ..
            }) => (entry, key, message),
            other => panic!("expected an entry error, got {other:?}"),
        }
    }

    const OK: &str = r#"
[[topic]]
name = "counter"
direction = "yarp_to_ros"
yarp_port = "/gw/counter:i"
yarp_source = "/counter:o"
ros_topic = "/counter"
ros_type = "std_msgs/msg/Int32"
qos = { reliability = "best_effort", depth = 5 }
rate_limit_hz = 10

[[topic]]
name = "cmd_vel"
direction = "ros_to_yarp"
yarp_port = "/base/cmd_vel:o"
ros_topic = "cmd_vel"
ros_type = "geometry_msgs/msg/Twist"

[[service]]
name = "home"
direction = "ros_to_yarp"
yarp_port = "/arm/rpc:i"
ros_service = "/arm/home"
ros_type = "std_srvs/srv/Trigger"
command = "[home]"
"#;

    #[test]
    fn a_valid_file_loads_with_defaults() {
        let m = parse(OK).unwrap();
        assert_eq!(m.topics.len(), 2);
        assert_eq!(m.services.len(), 1);
        let c = &m.topics[0];
        assert_eq!(c.conversion(), Conversion::Scalar);
        assert_eq!(c.qos.reliability, Some(Reliability::BestEffort));
        assert_eq!(c.qos.durability, Durability::Volatile);
        assert_eq!(c.qos.depth, 5);
        assert_eq!(c.rate_limit_hz, Some(10.0));
        assert_eq!(m.topics[1].conversion(), Conversion::Twist);
        assert_eq!(m.services[0].conversion(), ServiceConversion::Command);
    }

    #[test]
    fn unknown_key_names_file_entry_and_key() {
        let err = parse(&OK.replace("rate_limit_hz = 10", "rate_limt_hz = 10")).unwrap_err();
        let text = err.to_string();
        assert!(
            text.starts_with("m.toml: entry topic[0] \"counter\": key `rate_limt_hz`"),
            "{text}"
        );
        assert_eq!(err.key(), Some("rate_limt_hz"));
    }

    #[test]
    fn unknown_nested_key_is_named_with_its_path() {
        let (_, key, _) = entry_error(&OK.replace("depth = 5", "dept = 5"));
        assert_eq!(key, "qos.dept");
    }

    #[test]
    fn bad_value_names_the_key() {
        let (entry, key, msg) = entry_error(&OK.replace("\"best_effort\"", "\"sometimes\""));
        assert_eq!(entry, "topic[0] \"counter\"");
        assert_eq!(key, "qos.reliability");
        assert!(msg.contains("sometimes"), "{msg}");
        let (_, key, _) = entry_error(&OK.replace("\"yarp_to_ros\"", "\"sideways\""));
        assert_eq!(key, "direction");
    }

    #[test]
    fn missing_key_is_named() {
        let (_, key, _) = entry_error(&OK.replace("ros_topic = \"/counter\"", ""));
        assert_eq!(key, "ros_topic");
    }

    #[test]
    fn unknown_type_is_an_error() {
        let (_, key, msg) = entry_error(&OK.replace("std_msgs/msg/Int32", "std_msgs/msg/Int33"));
        assert_eq!(key, "ros_type");
        assert!(msg.contains("Int33"));
        let (_, key, msg) = entry_error(&OK.replace("std_srvs/srv/Trigger", "std_srvs/srv/Nope"));
        assert_eq!(key, "ros_type");
        assert!(
            msg.contains("unknown service type `std_srvs/srv/Nope`"),
            "{msg}"
        );
        let (_, key, msg) = entry_error(&OK.replace("std_srvs/srv/Trigger", "std_msgs/msg/Bool"));
        assert_eq!(key, "ros_type");
        assert!(msg.contains("not a service type"), "{msg}");
    }

    #[test]
    fn unknown_section_is_an_error() {
        let err = parse("[[topics]]\nname = \"x\"").unwrap_err();
        assert!(matches!(err, LoadError::UnknownSection { ref key, .. } if key == "topics"));
    }

    #[test]
    fn syntax_error_names_the_file() {
        let err = parse("[[topic]\n").unwrap_err();
        assert!(matches!(err, LoadError::Syntax { .. }));
        assert!(err.to_string().starts_with("m.toml: "));
    }

    #[test]
    fn actions_are_checked_like_services() {
        // The built-in catalog has no action: a definition on file is needed.
        let dir = std::env::temp_dir().join(format!("gw-actions-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("gw_act_pkg/action")).unwrap();
        std::fs::write(
            dir.join("gw_act_pkg/action/Go.action"),
            "int32 to\n---\nint32 at\n---\nint32 now\n",
        )
        .unwrap();
        let file = format!(
            "interfaces = [{:?}]\n[[action]]\nname = \"go\"\ndirection = \"ros_to_yarp\"\n\
             yarp_port = \"/go:i\"\nros_action = \"/go\"\nros_type = \"gw_act_pkg/action/Go\"\n",
            dir.display().to_string()
        );
        let m = parse(&file).unwrap();
        assert_eq!(m.actions[0].ros_type, "gw_act_pkg/action/Go");
        let (_, key, msg) = entry_error(&file.replace("action/Go", "action/Gone"));
        assert_eq!(key, "ros_type");
        assert!(msg.contains("unknown action type"), "{msg}");
        let (_, key, _) = entry_error(&file.replace("ros_to_yarp", "both"));
        assert_eq!(key, "direction");
        let (_, key, _) = entry_error(
            &file
                .replace("ros_to_yarp", "yarp_to_ros")
                .replace("ros_type", "command = \"go\"\nros_type"),
        );
        assert_eq!(key, "command");
        let (_, key, _) = entry_error(&file.replace("/go:i", "go"));
        assert_eq!(key, "yarp_port");
        let (_, key, _) = entry_error(&file.replace("\"/go\"", "\"bad name\""));
        assert_eq!(key, "ros_action");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn impossible_combinations() {
        let cases = [
            // conversion that cannot carry the type
            (
                OK.replace("qos = {", "conversion = \"text\"\nqos = {"),
                "conversion",
            ),
            // a header-less type cannot carry a frame_id
            (
                OK.replace("rate_limit_hz = 10", "frame_id = \"base\""),
                "frame_id",
            ),
            // joint names only with JointState
            (
                OK.replace(
                    "rate_limit_hz = 10",
                    "joint_names = { from = \"list\", names = [\"a\"] }",
                ),
                "joint_names",
            ),
            // a source port only when data comes from YARP
            (
                OK.replace(
                    "ros_topic = \"cmd_vel\"",
                    "ros_topic = \"cmd_vel\"\nyarp_source = \"/x\"",
                ),
                "yarp_source",
            ),
            // port and pattern together
            (
                OK.replace(
                    "yarp_port = \"/gw/counter:i\"",
                    "yarp_port = \"/a\"\nyarp_pattern = \"/b*\"",
                ),
                "yarp_pattern",
            ),
            // no port at all
            (OK.replace("yarp_port = \"/gw/counter:i\"", ""), "yarp_port"),
            // bad rate, bad depth, bad names
            (
                OK.replace("rate_limit_hz = 10", "rate_limit_hz = -1"),
                "rate_limit_hz",
            ),
            (OK.replace("depth = 5", "depth = 0"), "qos.depth"),
            (OK.replace("\"/counter\"", "\"/1counter\""), "ros_topic"),
            (OK.replace("\"/counter\"", "\"/a__b\""), "ros_topic"),
            (OK.replace("\"/gw/counter:i\"", "\"gw\""), "yarp_port"),
            // a service has one server
            (
                OK.replace(
                    "direction = \"ros_to_yarp\"\nyarp_port = \"/arm",
                    "direction = \"both\"\nyarp_port = \"/arm",
                ),
                "direction",
            ),
            // Trigger towards YARP needs its command
            (OK.replace("command = \"[home]\"", ""), "command"),
        ];
        for (text, want) in cases {
            let (_, key, msg) = entry_error(&text);
            assert_eq!(key, want, "{msg}");
        }
    }

    #[test]
    fn imu_only_from_yarp() {
        let text = r#"
[[topic]]
name = "imu"
direction = "ros_to_yarp"
yarp_port = "/imu"
ros_topic = "/imu"
ros_type = "sensor_msgs/msg/Imu"
"#;
        assert_eq!(entry_error(text).1, "direction");
        let ok = text.replace("ros_to_yarp", "yarp_to_ros") + "frame_id = \"imu_link\"\n";
        assert_eq!(
            parse(&ok).unwrap().topics[0].frame_id.as_deref(),
            Some("imu_link")
        );
    }

    #[test]
    fn joint_state_needs_names() {
        let text = r#"
[[topic]]
name = "arm"
direction = "yarp_to_ros"
yarp_port = "/gw/arm/state:i"
yarp_source = "/icub/left_arm/state:o"
ros_topic = "/left_arm/joint_states"
ros_type = "sensor_msgs/msg/JointState"
"#;
        assert_eq!(entry_error(text).1, "joint_names");
        let with = format!(
            "{text}joint_names = {{ from = \"axis_info\", rpc_port = \"/icub/left_arm/rpc:i\" }}\n"
        );
        assert!(parse(&with).is_ok());
        let bad = format!("{text}joint_names = {{ from = \"guess\" }}\n");
        assert_eq!(entry_error(&bad).1, "joint_names.from");
        let dynamic = with
            .replace(
                "yarp_port = \"/gw/arm/state:i\"",
                "yarp_pattern = \"/*/state:o\"",
            )
            .replace("yarp_source = \"/icub/left_arm/state:o\"\n", "");
        assert_eq!(entry_error(&dynamic).1, "yarp_pattern");
    }

    #[test]
    fn joint_commands_need_a_board_and_fit_their_type() {
        let text = r#"
[[topic]]
name = "traj"
direction = "ros_to_yarp"
yarp_port = "/gw/arm"
ros_topic = "/arm/joint_trajectory"
ros_type = "trajectory_msgs/msg/JointTrajectory"
control_board = { remote = "/robot/arm", mode = "position" }
"#;
        let m = parse(text).unwrap();
        assert_eq!(m.topics[0].conversion(), Conversion::JointCommand);
        let cb = m.topics[0].control_board.as_ref().unwrap();
        assert_eq!(cb.mode, Mode::Position);
        assert!(cb.joints.is_empty());
        let no_board = text.replace(
            "control_board = { remote = \"/robot/arm\", mode = \"position\" }",
            "",
        );
        assert_eq!(entry_error(&no_board).1, "control_board");
        assert_eq!(
            entry_error(&text.replace("\"position\"", "\"velocity\"")).1,
            "control_board.mode"
        );
        assert_eq!(
            entry_error(&text.replace("\"position\"", "\"torque\"")).1,
            "control_board.mode"
        );
        assert_eq!(
            entry_error(&text.replace("ros_to_yarp", "yarp_to_ros")).1,
            "direction"
        );
        assert_eq!(
            entry_error(&text.replace("mode = ", "jionts = [], mode = ")).1,
            "control_board.jionts"
        );
        // a multi-array with a board is a command; without, a plain Bottle stream
        let multi = text.replace(
            "trajectory_msgs/msg/JointTrajectory",
            "std_msgs/msg/Float64MultiArray",
        );
        assert_eq!(
            parse(&multi).unwrap().topics[0].conversion(),
            Conversion::JointCommand
        );
        assert_eq!(
            parse(&no_board.replace(
                "trajectory_msgs/msg/JointTrajectory",
                "std_msgs/msg/Float64MultiArray"
            ))
            .unwrap()
            .topics[0]
                .conversion(),
            Conversion::MultiArray
        );
        // a board with a type commands cannot come from
        assert_eq!(
            entry_error(
                &text.replace("trajectory_msgs/msg/JointTrajectory", "std_msgs/msg/String")
            )
            .1,
            "ros_type"
        );
        assert_eq!(
            entry_error(
                &multi
                    .replace("conversion", "x")
                    .replace("ros_type = ", "conversion = \"multi_array\"\nros_type = ")
            )
            .1,
            "control_board"
        );
    }

    #[test]
    fn ros_topic_patterns() {
        let text = r#"
[[topic]]
name = "mirror"
direction = "ros_to_yarp"
yarp_port = "/ros"
ros_topic = "/sensors/*"
ros_type = "std_msgs/msg/Float64"
"#;
        let m = parse(text).unwrap();
        assert!(m.topics[0].is_ros_pattern());
        assert_eq!(
            entry_error(&text.replace("ros_to_yarp", "both")).1,
            "direction"
        );
        assert_eq!(
            entry_error(&text.replace("/sensors/*", "sensors/*")).1,
            "ros_topic"
        );
        assert_eq!(
            entry_error(&text.replace("/sensors/*", "/9*")).1,
            "ros_topic"
        );
        assert_eq!(
            entry_error(&text.replace("yarp_port = \"/ros\"", "yarp_sink = \"/x\"")).1,
            "yarp_port"
        );
    }

    #[test]
    fn generic_conversion_in_every_mode() {
        let fixed = r#"
[[topic]]
name = "js"
direction = "both"
yarp_port = "/gw/js"
ros_topic = "/js"
ros_type = "sensor_msgs/msg/JointState"
conversion = "generic"
frame_id = "base"
"#;
        let m = parse(fixed).unwrap();
        assert_eq!(m.topics[0].conversion(), Conversion::Generic);
        // a type no other conversion carries defaults to generic
        let diag = fixed
            .replace("sensor_msgs/msg/JointState", "diagnostic_msgs/msg/KeyValue")
            .replace("conversion = \"generic\"\n", "")
            .replace("frame_id = \"base\"\n", "");
        assert_eq!(
            parse(&diag).unwrap().topics[0].conversion(),
            Conversion::Generic
        );
        // a frame_id needs a header
        assert_eq!(
            entry_error(&format!("{diag}frame_id = \"x\"\n")).1,
            "frame_id"
        );
        let yarp_pattern = diag
            .replace("direction = \"both\"", "direction = \"yarp_to_ros\"")
            .replace("yarp_port = \"/gw/js\"", "yarp_pattern = \"/kv/*\"");
        assert_eq!(
            parse(&yarp_pattern).unwrap().topics[0].conversion(),
            Conversion::Generic
        );
        let any = r#"
[[topic]]
name = "all"
direction = "ros_to_yarp"
yarp_port = "/mirror"
ros_topic = "/robot/*"
"#;
        let m = parse(any).unwrap();
        assert_eq!(m.topics[0].ros_type, "");
        assert_eq!(m.topics[0].conversion(), Conversion::Generic);
        assert_eq!(
            entry_error(&format!("{any}conversion = \"text\"\n")).1,
            "conversion"
        );
        assert_eq!(
            entry_error(&any.replace("/robot/*", "/robot/one")).1,
            "ros_type"
        );
    }

    #[test]
    fn interface_directories() {
        let dir = std::env::temp_dir().join(format!("gw-map-ifaces-{}", std::process::id()));
        let pkg = dir.join("share/gw_map_pkg/msg");
        std::fs::create_dir_all(&pkg).unwrap();
        std::fs::write(pkg.join("Level.msg"), "float64 litres\n").unwrap();
        let text = r#"
interfaces = ["share"]

[[topic]]
name = "tank"
direction = "yarp_to_ros"
yarp_port = "/tank:i"
ros_topic = "/tank"
ros_type = "gw_map_pkg/msg/Level"
"#;
        let m = Mappings::parse(text, &dir.join("m.toml")).unwrap();
        assert_eq!(m.interfaces, [dir.join("share")]);
        assert_eq!(m.topics[0].conversion(), Conversion::Generic);
        let err = Mappings::parse(&text.replace("\"share\"", "\"nope\""), &dir.join("m.toml"))
            .unwrap_err();
        assert_eq!(err.key(), Some("interfaces"));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn setbool_commands() {
        let text = r#"
[[service]]
name = "enable"
direction = "ros_to_yarp"
yarp_port = "/arm/rpc:i"
ros_service = "/arm/enable"
ros_type = "std_srvs/srv/SetBool"
command_true = "[on]"
"#;
        assert_eq!(entry_error(text).1, "command_false");
        assert!(parse(&format!("{text}command_false = \"[off]\"\n")).is_ok());
    }

    #[test]
    fn duplicate_names_are_rejected() {
        let text = format!("{OK}\n{}", &OK[OK.find("[[service]]").unwrap()..]);
        let (_, key, _) = entry_error(&text);
        assert_eq!(key, "name");
    }

    #[test]
    fn text_rpc_pattern() {
        let text = r#"
[[service]]
name = "board"
direction = "ros_to_yarp"
yarp_port = "/board/rpc:i"
ros_service = "/board/rpc"
ros_type = "std_msgs/msg/String"
"#;
        let m = parse(text).unwrap();
        assert_eq!(m.services[0].conversion(), ServiceConversion::TextRpc);
        assert_eq!(
            entry_error(&text.replace("ros_to_yarp", "yarp_to_ros")).1,
            "direction"
        );
    }
}
