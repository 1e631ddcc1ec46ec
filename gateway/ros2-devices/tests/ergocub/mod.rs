//! ergoCubSN001's ROS 2 wrappers as the acceptance test and the rates bench bring them up.
//!
//! The robot's own files are used unmodified. The test's own top file is `ergocub.xml`
//! (every include made absolute, so the file can live in a temporary directory) with what
//! the published file leaves commented out or lacks:
//! * the four `wrappers/FT/*-FT_nws_ros2.xml` (`wrenchStamped_nws_ros2`) and the right
//!   arm's strain they attach to (`hardware/FT/right_arm-eb1-j0_1-strain.xml`);
//! * with `control`: a second `controlBoard_nws_ros2` on the same `alljoints-mc_remapper`
//!   with `msgs_name` `/ergocub_control` (the robot's `alljoints-mc_nws_ros2.xml` has none,
//!   so it serves no commands), JointState on `/ergocub_control/joint_states`.
//!
//! `ergocub.xml` itself includes `alljoints-mc_remapper.xml` and
//! `alljoints-mc_nws_ros2.xml` with `enabled_by="enable_ros2"`: they are read when the
//! robot runs with `--enable_tags (enable_ros2)` ([`ros2_tags`]), as its owners start it. `sensors/ros2_repeaters/head_imu_ros2.xml` is a robot of its
//! own (a `multipleanalogsensorsclient` of `/ergocub/head/inertials` and `imu_nws_ros2`).

#![allow(dead_code)]

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// The robot's four F/T topics (from its `*-FT_nws_ros2.xml`).
pub const FT_TOPICS: [&str; 4] = [
    "/left_arm_ft",
    "/right_arm_ft",
    "/left_foot_heel_tiptoe_ft",
    "/right_foot_heel_tiptoe_ft",
];
pub const FT_FILES: [&str; 4] = [
    "wrappers/FT/left_arm-FT_nws_ros2.xml",
    "wrappers/FT/right_arm-FT_nws_ros2.xml",
    "wrappers/FT/left_foot-FT_nws_ros2.xml",
    "wrappers/FT/right_foot-FT_nws_ros2.xml",
];
pub const JOINT_STATES: &str = "/joint_states";
pub const HEAD_IMU: &str = "/head_imu";
pub const CONTROL: &str = "/ergocub_control";

pub fn robot_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/robots-configuration/ergoCubSN001")
        .canonicalize()
        .expect("../shared/robots-configuration/ergoCubSN001")
}

const CONTROL_DEVICE: &str = r#"
    <device name="alljoints-mc_nws_ros2_control" type="controlBoard_nws_ros2">
        <param name="node_name"> ergocub_cb_control </param>
        <param name="topic_name"> /ergocub_control/joint_states </param>
        <param name="msgs_name"> /ergocub_control </param>
        <action phase="startup" level="15" type="attach">
            <param name="device"> alljoints-mc_remapper </param>
        </action>
        <action phase="shutdown" level="20" type="detach" />
    </device>
"#;

/// yarprobotinterface's `--enable_tags (enable_ros2)`.
pub fn ros2_tags() -> yarp_proto::Property {
    yarp_proto::Property::from_text("(enable_tags (enable_ros2))")
}

/// Writes the test's top file (see the module comment) into `out` and returns its path.
pub fn top_file(dir: &Path, out: &Path, control: bool) -> PathBuf {
    let text = std::fs::read_to_string(dir.join("ergocub.xml")).expect("ergocub.xml");
    // the copy lives in `out`: the robot's files are named from there (C++ joins the
    // including file's directory and the href)
    let robot = yarp_interop_tests::include_href(out, dir);
    let mut text = text.replace("href=\"", &format!("href=\"{robot}/"));
    let mut extra =
        format!("    <xi:include href=\"{robot}/hardware/FT/right_arm-eb1-j0_1-strain.xml\" />\n");
    for f in FT_FILES {
        extra.push_str(&format!("    <xi:include href=\"{robot}/{f}\" />\n"));
    }
    if control {
        extra.push_str(CONTROL_DEVICE);
    }
    let at = text
        .rfind("</devices>")
        .expect("ergocub.xml has </devices>");
    text.insert_str(at, &extra);
    let path = out.join("ergocub-ros2.xml");
    std::fs::write(&path, text).expect("write the top file");
    path
}

/// The joint names `alljoints-mc_remapper.xml` gives (its `axesNames`).
pub fn alljoints_names(dir: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join("wrappers/motorControl/alljoints-mc_remapper.xml"))
        .expect("alljoints-mc_remapper.xml");
    let start = text.find("name=\"axesNames\">").expect("axesNames") + "name=\"axesNames\">".len();
    let rest = &text[start..];
    let list = &rest[rest.find('(').unwrap() + 1..rest.find(')').unwrap()];
    list.split(',').map(|s| s.trim().to_string()).collect()
}

/// The rclpy venv (`ROS_VENV`, default `<repo>/.venv-ros`), or `None` after a loud notice;
/// under CI=true its absence fails.
pub fn ros_venv(what: &str) -> Option<PathBuf> {
    let venv = std::env::var_os("ROS_VENV")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../.venv-ros"));
    if venv.join("bin/python").exists() {
        return Some(venv);
    }
    let why = format!(
        "{what}: no rclpy venv at {} (run tests/peers/install-ros2.sh or set ROS_VENV)",
        venv.display()
    );
    assert!(std::env::var("CI").map_or(true, |v| v != "true"), "{why}");
    eprintln!("\n*** SKIPPED: {why} ***\n");
    None
}

/// A child process whose stdout lines arrive on a channel; killed and reaped on drop.
pub struct Child2 {
    child: Child,
    lines: mpsc::Receiver<String>,
    name: String,
}

impl Child2 {
    pub fn spawn(mut cmd: Command, name: &str) -> Child2 {
        let mut child = cmd
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .unwrap_or_else(|e| panic!("start {name}: {e}"));
        let out = child.stdout.take().expect("stdout");
        let (tx, lines) = mpsc::channel();
        std::thread::spawn(move || {
            for l in BufReader::new(out).lines().map_while(Result::ok) {
                if tx.send(l).is_err() {
                    break;
                }
            }
        });
        Child2 {
            child,
            lines,
            name: name.to_string(),
        }
    }

    pub fn id(&self) -> u32 {
        self.child.id()
    }

    /// The next line starting with `prefix` (others skipped), without the prefix.
    pub fn expect(&self, prefix: &str, timeout: Duration) -> String {
        let end = Instant::now() + timeout;
        loop {
            let left = end.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(l) if l.starts_with(prefix) => return l[prefix.len()..].trim().to_string(),
                Ok(_) => continue,
                Err(_) => panic!("{}: no `{prefix}` line within {timeout:?}", self.name),
            }
        }
    }

    /// Every line starting with `prefix` until one starting with `until`.
    pub fn collect(&self, prefix: &str, until: &str, timeout: Duration) -> Vec<String> {
        let end = Instant::now() + timeout;
        let mut out = Vec::new();
        loop {
            let left = end.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(l) if l.starts_with(until) => return out,
                Ok(l) if l.starts_with(prefix) => out.push(l[prefix.len()..].trim().to_string()),
                Ok(_) => continue,
                Err(_) => panic!(
                    "{}: no `{until}` line within {timeout:?} (got {out:?})",
                    self.name
                ),
            }
        }
    }
}

impl Drop for Child2 {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
        }
        let _ = self.child.wait();
    }
}

/// `robot_watch.py` with `args`, in ROS domain `domain`, on loopback, UDP only (Fast DDS's
/// shared memory is not isolated by netns-run).
pub fn watch(venv: &Path, domain: u16, args: &[String]) -> Child2 {
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/peers/robot_watch.py");
    let mut cmd = Command::new(venv.join("bin/python"));
    cmd.arg("-u")
        .arg(script)
        .args(args)
        .env("ROS_DOMAIN_ID", domain.to_string())
        .env("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
        .env("ROS_DISTRO", "kilted")
        .env("FASTDDS_BUILTIN_TRANSPORTS", "UDPv4");
    Child2::spawn(cmd, "robot_watch.py")
}

/// The `TOPIC=TYPE` arguments of the robot's ROS 2 view.
pub fn watched(with_imu: bool) -> Vec<String> {
    let mut v = vec![format!("{JOINT_STATES}=sensor_msgs/msg/JointState")];
    for t in FT_TOPICS {
        v.push(format!("{t}=geometry_msgs/msg/WrenchStamped"));
    }
    if with_imu {
        v.push(format!("{HEAD_IMU}=sensor_msgs/msg/Imu"));
    }
    v
}
