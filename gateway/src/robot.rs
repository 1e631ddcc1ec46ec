//! `[[robot]]` entries: the whole robot as ROS tools expect it (format in
//! `mappings/README.md`). One `/joint_states` merging the per-part JointState entries, and
//! a latched `/robot_description` read from a URDF file.
//!
//! Loading is strict like the rest of the mapping file: unknown keys, parts that are not
//! JointState entries, a URDF that cannot be read or is not a `<robot>` are errors naming
//! the file, the entry and the key.

use crate::mapping::{check_ros_name, Conversion, Invalid, Qos, TopicEntry};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// The topic robot_state_publisher and RViz read joint positions from.
pub const JOINT_STATES_TOPIC: &str = "/joint_states";
/// The topic robot_state_publisher and RViz read the URDF from.
pub const DESCRIPTION_TOPIC: &str = "/robot_description";
/// The merged topic's default rate (Hz).
pub const DEFAULT_RATE_HZ: f64 = 50.0;

/// A `[[robot]]` entry.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotEntry {
    /// Unique name (errors, startup table, diagnostics).
    pub name: String,
    pub joint_states: Option<MergedJointStates>,
    pub robot_description: Option<RobotDescription>,
    /// With a `robot_description`: publish `/tf_static` (fixed joints) and, with
    /// `joint_states`, `/tf` (the others), as robot_state_publisher would.
    #[serde(default = "yes")]
    pub tf: bool,
    /// The mapping file it came from (errors; relative paths).
    #[serde(skip)]
    pub file: PathBuf,
}

/// One `sensor_msgs/JointState` for the whole robot, merged from per-part entries.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MergedJointStates {
    #[serde(default = "joint_states_topic")]
    pub ros_topic: String,
    /// Names of `[[topic]]` JointState entries (yarp_to_ros), in the merged order.
    pub parts: Vec<String>,
    /// At most this many merged messages per second.
    #[serde(default = "default_rate")]
    pub rate_hz: f64,
    #[serde(default)]
    pub qos: Qos,
}

/// `std_msgs/String` with the URDF's text, offered transient-local (latched).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotDescription {
    #[serde(default = "description_topic")]
    pub ros_topic: String,
    /// The URDF file, relative to the mapping file (made absolute on loading).
    pub urdf: PathBuf,
    /// The file's text (read on loading).
    #[serde(skip)]
    pub text: String,
    /// Its movable (non-fixed) joints, to warn about joints the robot does not report.
    #[serde(skip)]
    pub joints: Vec<String>,
}

fn joint_states_topic() -> String {
    JOINT_STATES_TOPIC.into()
}
fn description_topic() -> String {
    DESCRIPTION_TOPIC.into()
}
fn yes() -> bool {
    true
}
fn default_rate() -> f64 {
    DEFAULT_RATE_HZ
}

/// Checks an entry on its own and reads its URDF (relative to the mapping `file`).
pub fn validate(r: &mut RobotEntry, file: &Path) -> Result<(), Invalid> {
    r.file = file.to_path_buf();
    if r.joint_states.is_none() && r.robot_description.is_none() {
        return Err((
            "joint_states",
            "a robot entry needs joint_states, robot_description or both".into(),
        ));
    }
    if let Some(js) = &r.joint_states {
        check_ros_name("joint_states.ros_topic", &js.ros_topic)?;
        if js.parts.is_empty() {
            return Err(("joint_states.parts", "must name at least one part".into()));
        }
        for (i, p) in js.parts.iter().enumerate() {
            if js.parts[..i].contains(p) {
                return Err(("joint_states.parts", format!("`{p}` is listed twice")));
            }
        }
        if !(js.rate_hz.is_finite() && js.rate_hz > 0.0 && js.rate_hz <= 1000.0) {
            return Err((
                "joint_states.rate_hz",
                format!("must be in (0, 1000], not {}", js.rate_hz),
            ));
        }
        if js.qos.depth == 0 {
            return Err(("joint_states.qos.depth", "must be at least 1".into()));
        }
    }
    if let Some(d) = &mut r.robot_description {
        check_ros_name("robot_description.ros_topic", &d.ros_topic)?;
        let base = file.parent().unwrap_or(Path::new(""));
        d.urdf = base.join(&d.urdf);
        d.text = std::fs::read_to_string(&d.urdf).map_err(|e| {
            (
                "robot_description.urdf",
                format!("cannot read {}: {e}", d.urdf.display()),
            )
        })?;
        d.joints = urdf_joints(&d.text).map_err(|e| {
            (
                "robot_description.urdf",
                format!("{}: {e}", d.urdf.display()),
            )
        })?;
    }
    Ok(())
}

/// Checks that every part names a JointState `[[topic]]` entry bridged from YARP.
pub fn check_parts(r: &RobotEntry, topics: &[TopicEntry]) -> Result<(), Invalid> {
    let Some(js) = &r.joint_states else {
        return Ok(());
    };
    for p in &js.parts {
        let Some(t) = topics.iter().find(|t| &t.name == p) else {
            return Err((
                "joint_states.parts",
                format!("no [[topic]] entry is named `{p}`"),
            ));
        };
        if t.conversion() != Conversion::JointState || t.yarp_port.is_none() {
            return Err((
                "joint_states.parts",
                format!("`{p}` is not a joint_state entry (a control board's state as sensor_msgs/msg/JointState)"),
            ));
        }
    }
    Ok(())
}

/// The movable joints of a URDF document, checked as robot_state_publisher needs it: the
/// root is a named `<robot>`, every joint has a known type and joins two of its links,
/// and the links form one tree (one root, one parent each).
pub fn urdf_joints(text: &str) -> Result<Vec<String>, String> {
    let doc = roxmltree::Document::parse(text).map_err(|e| format!("not XML: {e}"))?;
    let root = doc.root_element();
    if root.tag_name().name() != "robot" || root.attribute("name").is_none() {
        return Err("not a URDF: the root element must be <robot name=\"...\">".into());
    }
    let mut links = Vec::new();
    for l in root.children().filter(|n| n.has_tag_name("link")) {
        let name = l.attribute("name").ok_or("a <link> has no name")?;
        if links.contains(&name) {
            return Err(format!("two links are named `{name}`"));
        }
        links.push(name);
    }
    let mut joints = Vec::new();
    let mut children: Vec<&str> = Vec::new();
    let mut joint_names: Vec<&str> = Vec::new();
    for j in root.children().filter(|n| n.has_tag_name("joint")) {
        let name = j.attribute("name").ok_or("a <joint> has no name")?;
        if joint_names.contains(&name) {
            return Err(format!("two joints are named `{name}`"));
        }
        joint_names.push(name);
        let kind = j
            .attribute("type")
            .ok_or_else(|| format!("joint `{name}` has no type"))?;
        match kind {
            "fixed" => {}
            "revolute" | "continuous" | "prismatic" | "floating" | "planar" => {
                joints.push(name.to_string())
            }
            other => return Err(format!("joint `{name}` has an unknown type `{other}`")),
        }
        let end = |tag: &str| -> Result<&str, String> {
            let l = j
                .children()
                .find(|n| n.has_tag_name(tag))
                .and_then(|n| n.attribute("link"))
                .ok_or_else(|| format!("joint `{name}` has no <{tag} link=...>"))?;
            if links.contains(&l) {
                Ok(l)
            } else {
                Err(format!("joint `{name}`: no link `{l}`"))
            }
        };
        end("parent")?;
        let child = end("child")?;
        if children.contains(&child) {
            return Err(format!("link `{child}` has two parent joints"));
        }
        children.push(child);
    }
    let roots: Vec<&&str> = links.iter().filter(|l| !children.contains(l)).collect();
    if roots.len() != 1 {
        return Err(format!(
            "the links must form one tree, found {} roots: {roots:?}",
            roots.len()
        ));
    }
    Ok(joints)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mapping::{LoadError, Mappings};

    const PARTS: &str = r#"
[[topic]]
name = "head_joints"
direction = "yarp_to_ros"
yarp_port = "/gw/head/state:i"
ros_topic = "/head/joint_states"
ros_type = "sensor_msgs/msg/JointState"
joint_names = { from = "list", names = ["neck_pitch"] }

[[topic]]
name = "counter"
direction = "yarp_to_ros"
yarp_port = "/gw/counter:i"
ros_topic = "/counter"
ros_type = "std_msgs/msg/Int32"
"#;

    const URDF: &str = r#"<robot name="r"><link name="a"/><link name="b"/>
<joint name="neck_pitch" type="revolute"><parent link="a"/><child link="b"/></joint></robot>"#;

    /// A mapping file with `robot` appended to PARTS, in a directory of its own holding
    /// `r.urdf`; the result of loading it.
    fn load(robot: &str) -> Result<Mappings, LoadError> {
        let dir = std::env::temp_dir().join(format!(
            "gw-robot-{}-{:x}",
            std::process::id(),
            robot.len() * 31 + robot.bytes().map(usize::from).sum::<usize>()
        ));
        std::fs::create_dir_all(dir.join("urdf")).unwrap();
        std::fs::write(dir.join("urdf/r.urdf"), URDF).unwrap();
        let file = dir.join("m.toml");
        std::fs::write(&file, format!("{PARTS}\n{robot}")).unwrap();
        let out = Mappings::load(&[&file]);
        std::fs::remove_dir_all(&dir).unwrap();
        out
    }

    fn key_of(robot: &str) -> String {
        match load(robot) {
            Err(e) => e.key().unwrap_or("<none>").to_string(),
            Ok(_) => "<loaded>".into(),
        }
    }

    #[test]
    fn a_robot_entry_loads_with_defaults_and_its_urdf() {
        let m = load(
            r#"
[[robot]]
name = "r"
joint_states = { parts = ["head_joints"] }
robot_description = { urdf = "urdf/r.urdf" }
"#,
        )
        .unwrap();
        let r = &m.robots[0];
        let js = r.joint_states.as_ref().unwrap();
        assert_eq!(js.ros_topic, "/joint_states");
        assert_eq!(js.rate_hz, DEFAULT_RATE_HZ);
        assert_eq!(js.parts, ["head_joints"]);
        let d = r.robot_description.as_ref().unwrap();
        assert_eq!(d.ros_topic, "/robot_description");
        assert_eq!(d.text, URDF);
        assert_eq!(d.joints, ["neck_pitch"]);
        assert!(d.urdf.is_absolute() || d.urdf.starts_with(std::env::temp_dir()));
    }

    #[test]
    fn bad_robot_entries_name_the_key() {
        let cases = [
            (
                "joint_states = { parts = [\"nope\"] }",
                "joint_states.parts",
            ),
            (
                "joint_states = { parts = [\"counter\"] }",
                "joint_states.parts",
            ),
            ("joint_states = { parts = [] }", "joint_states.parts"),
            (
                "joint_states = { parts = [\"head_joints\", \"head_joints\"] }",
                "joint_states.parts",
            ),
            (
                "joint_states = { parts = [\"head_joints\"], rate_hz = 0 }",
                "joint_states.rate_hz",
            ),
            (
                "joint_states = { parts = [\"head_joints\"], ros_topic = \"/9x\" }",
                "joint_states.ros_topic",
            ),
            (
                "joint_states = { parts = [\"head_joints\"], rate = 5 }",
                "joint_states.rate",
            ),
            (
                "robot_description = { urdf = \"urdf/none.urdf\" }",
                "robot_description.urdf",
            ),
            (
                "robot_description = { urdf = \"m.toml\" }",
                "robot_description.urdf",
            ),
            ("robot_description = {}", "robot_description.urdf"),
            ("", "joint_states"),
            ("frame = \"x\"", "frame"),
        ];
        for (body, want) in cases {
            let text = format!("[[robot]]\nname = \"r\"\n{body}\n");
            assert_eq!(key_of(&text), want, "{body}");
        }
        // A robot's name is an entry name like any other.
        assert_eq!(
            key_of(
                "[[robot]]\nname = \"counter\"\nrobot_description = { urdf = \"urdf/r.urdf\" }\n"
            ),
            "name"
        );
    }

    #[test]
    fn urdf_joints_skip_fixed_ones() {
        let urdf = r#"<?xml version="1.0"?>
<robot name="r">
  <link name="a"/><link name="b"/><link name="c"/>
  <joint name="j1" type="revolute"><parent link="a"/><child link="b"/></joint>
  <joint name="mount" type="fixed"><parent link="b"/><child link="c"/></joint>
</robot>"#;
        assert_eq!(urdf_joints(urdf).unwrap(), vec!["j1".to_string()]);
        assert!(urdf_joints("<robt name=\"r\"/>")
            .unwrap_err()
            .contains("<robot"));
        assert!(urdf_joints("<robot name=\"r\"")
            .unwrap_err()
            .contains("XML"));
        assert!(
            urdf_joints("<robot name=\"r\"><joint name=\"x\" type=\"hinge\"/></robot>")
                .unwrap_err()
                .contains("hinge")
        );
        // Two trees, a missing link, a link with two parents.
        let two_roots = urdf.replace(
            r#"<joint name="mount" type="fixed"><parent link="b"/><child link="c"/></joint>"#,
            "",
        );
        assert!(urdf_joints(&two_roots).unwrap_err().contains("roots"));
        let missing = urdf.replace(r#"<child link="c"/>"#, r#"<child link="d"/>"#);
        assert!(urdf_joints(&missing).unwrap_err().contains("no link `d`"));
        let twice = urdf.replace(r#"<child link="c"/>"#, r#"<child link="b"/>"#);
        assert!(urdf_joints(&twice).unwrap_err().contains("two parent"));
    }
}
