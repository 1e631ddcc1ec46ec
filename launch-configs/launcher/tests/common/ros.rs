//! The ROS 2 distros the rclpy tests run against: Kilted (`ros-*` wheels, venv `ROS_VENV`)
//! and Jazzy (`ros-jazzy-*` wheels, venv `ROS_JAZZY_VENV`), both installed by
//! `tests/peers/install-ros2.sh`. `YARP_ROS_DISTROS` (e.g. `jazzy`) narrows the list.

use std::path::PathBuf;
use std::process::{Command, Stdio};

/// A distro with a usable rclpy venv.
#[derive(Debug, Clone)]
pub struct Distro {
    /// `ROS_DISTRO` for its nodes.
    pub name: &'static str,
    pub venv: PathBuf,
}

impl Distro {
    pub fn python(&self) -> PathBuf {
        self.venv.join("bin/python")
    }
}

const KNOWN: [(&str, &str, &str); 2] = [
    ("kilted", "ROS_VENV", ".venv-ros"),
    ("jazzy", "ROS_JAZZY_VENV", ".venv-ros-jazzy"),
];

/// Every wanted distro whose venv imports rclpy. A missing one is skipped loudly, and
/// under CI=true fails the test (CI installs both).
pub fn distros(test: &str) -> Vec<Distro> {
    let wanted = std::env::var("YARP_ROS_DISTROS").unwrap_or_else(|_| "kilted,jazzy".into());
    let ci = std::env::var("CI").is_ok_and(|v| v == "true");
    let mut found = Vec::new();
    for want in wanted.split(',').map(str::trim).filter(|w| !w.is_empty()) {
        let Some(&(name, var, default)) = KNOWN.iter().find(|k| k.0 == want) else {
            panic!("YARP_ROS_DISTROS names `{want}`: known are kilted, jazzy");
        };
        let venv = std::env::var_os(var)
            .map(PathBuf::from)
            .unwrap_or_else(|| super::configs_dir().join("..").join(default));
        let ok = Command::new(venv.join("bin/python"))
            .args(["-c", "import rclpy, sensor_msgs.msg, std_msgs.msg"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        if ok {
            found.push(Distro { name, venv });
            continue;
        }
        let why = format!(
            "no ROS 2 {name} rclpy venv at {} (run tests/peers/install-ros2.sh {name} or set {var})",
            venv.display()
        );
        assert!(!ci, "{test}: {why}");
        eprintln!("==================================================================");
        eprintln!("SKIPPED for {name}: {test}: {why}");
        eprintln!("==================================================================");
    }
    found
}
