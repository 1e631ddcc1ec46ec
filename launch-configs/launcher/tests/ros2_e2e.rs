//! The mission end to end: `yarp-launch` starts a robot config (`icub-sim.toml`, the
//! emulated iCub, and `fake-devices.toml`), a real rclpy node reads
//! `/icub/left_arm/joint_states` and commands a joint through the gateway, our `yarp read`
//! reads a YARP port, headless Chromium loads the dashboard, and everything stops with no
//! process left behind. Prints the time
//! from the command to the first JointState. Needs the rclpy venv
//! (`tests/peers/install-ros2.sh`, `ROS_VENV`); skips loudly without it.

mod common;

use common::*;
use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

fn ros_venv() -> Option<PathBuf> {
    let dir = std::env::var_os("ROS_VENV")
        .map(PathBuf::from)
        .unwrap_or_else(|| configs_dir().join("../.venv-ros"));
    let ok = Command::new(dir.join("bin/python"))
        .args(["-c", "import rclpy, sensor_msgs.msg, std_msgs.msg"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    ok.then_some(dir)
}

/// A child whose stdout lines arrive on a channel; killed and reaped on drop.
struct Lines {
    child: std::process::Child,
    rx: mpsc::Receiver<String>,
}

impl Lines {
    fn spawn(mut cmd: Command) -> Lines {
        let mut child = cmd
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("spawn");
        let out = child.stdout.take().expect("stdout");
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            for l in BufReader::new(out).lines().map_while(Result::ok) {
                if tx.send(l).is_err() {
                    break;
                }
            }
        });
        Lines { child, rx }
    }

    fn expect(&self, prefix: &str, limit: Duration) -> String {
        let deadline = Instant::now() + limit;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.rx.recv_timeout(left) {
                Ok(l) if l.starts_with(prefix) => return l[prefix.len()..].trim().to_string(),
                Ok(_) => {}
                Err(_) => panic!("no {prefix:?} line within {limit:?}"),
            }
        }
    }
}

impl Drop for Lines {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Runs `config` (with `extra` launcher arguments) and checks the whole chain with joint
/// `joint` of the left arm commanded to `target` degrees.
fn e2e(
    config: &str,
    extra: &[&str],
    joint: &str,
    target: f64,
    domain_offset: u32,
    imu_topic: Option<&str>,
) {
    let Some(venv) = ros_venv() else {
        eprintln!("==================================================================");
        eprintln!("SKIPPED: no rclpy venv (run tests/peers/install-ros2.sh or set");
        eprintln!("ROS_VENV): the ROS 2 end-to-end launch test did not run.");
        eprintln!("==================================================================");
        return;
    };
    // A ROS domain per test (this file uses 1..=100): the two tests of this file may run
    // in one process, and other tests run DDS in the same network namespace.
    let domain = (1 + (std::process::id() % 50) * 2 + domain_offset).to_string();
    let ros_env = [
        ("ROS_DOMAIN_ID", domain.as_str()),
        ("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST"),
        ("ROS_DISTRO", "kilted"),
        // UDP only: Fast DDS's /dev/shm segments are not isolated by netns-run.
        ("FASTDDS_BUILTIN_TRANSPORTS", "UDPv4"),
    ];

    // The rclpy node first (its start-up is not the launcher's), then the launch.
    let mut probe_cmd = Command::new(venv.join("bin/python"));
    probe_cmd
        .arg("-u")
        .arg(configs_dir().join("launcher/tests/peers/joint_probe.py"))
        .args(["left_arm", joint, &format!("{target}"), "--timeout", "150"])
        .envs(ros_env);
    let probe = Lines::spawn(probe_cmd);
    probe.expect("READY", Duration::from_secs(60));

    let t0 = Instant::now();
    let mut args = vec!["--dashboard", "127.0.0.1:0"];
    args.extend_from_slice(extra);
    let mut l = Launch::start_with_env(&configs_dir().join(config), &args, &ros_env);
    let url = l.dashboard_url();
    let first = probe.expect("FIRST", Duration::from_secs(150));
    let to_first = t0.elapsed();
    eprintln!(
        "{config}: command to first JointState in rclpy: {:.2} s",
        to_first.as_secs_f64()
    );
    let js: serde_json::Value = serde_json::from_str(&first).expect("json");
    assert!(js["name"].as_array().is_some_and(|n| !n.is_empty()), "{js}");
    let reply = probe.expect("REPLY", Duration::from_secs(30));
    assert!(reply.contains("ok"), "reply {reply}");
    let moved = probe.expect("MOVED", Duration::from_secs(60));
    eprintln!("joint {joint} moved to {moved} deg (commanded {target})");

    // An IMU of the robot reaches rclpy as sensor_msgs/Imu.
    if let Some(topic) = imu_topic {
        let mut imu_cmd = Command::new(venv.join("bin/python"));
        imu_cmd
            .arg("-u")
            .arg(configs_dir().join("launcher/tests/peers/imu_probe.py"))
            .args([topic, "--timeout", "60"])
            .envs(ros_env);
        let imu = Lines::spawn(imu_cmd);
        let m: serde_json::Value =
            serde_json::from_str(&imu.expect("IMU", Duration::from_secs(90))).expect("json");
        let g = m["acc"]
            .as_array()
            .unwrap()
            .iter()
            .map(|a| a.as_f64().unwrap().powi(2))
            .sum::<f64>()
            .sqrt();
        assert!((9.0..10.5).contains(&g), "|acceleration| {g}: {m}");
        let q = m["q"].as_array().unwrap();
        let norm = q.iter().map(|x| x.as_f64().unwrap().powi(2)).sum::<f64>();
        assert!(
            (norm - 1.0).abs() < 1e-3,
            "unit orientation quaternion: {m}"
        );
        eprintln!("{topic} in rclpy: {m}");
    }

    // Our `yarp read` sees the same joint on the YARP side.
    let conf_home = l.conf_home.path().to_path_buf();
    let mut read_cmd = Command::new(program("yarp", "yarp-cli"));
    read_cmd
        .args(["read", "/e2e/reader", "/icub/left_arm/state:o"])
        .env("YARP_CONFIG_HOME", &conf_home);
    let reader = Lines::spawn(read_cmd);
    let line = reader.expect("", Duration::from_secs(20));
    let j: usize = joint.parse().unwrap();
    let value: f64 = line
        .split_whitespace()
        .nth(j)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("yarp read printed {line:?}"));
    assert!(
        (value - target).abs() < 1.0,
        "joint {joint} at {value} on the YARP side"
    );
    drop(reader);

    // The dashboard, in headless Chromium, shows this robot's ports and the joint plot.
    if let Some(browser) = common::browser::chromium() {
        let work = tempfile::tempdir().unwrap();
        let dom = common::browser::run_chromium(
            &browser,
            &work.path().join("profile"),
            &["--dump-dom".to_string(), url.clone()],
            Duration::from_secs(60),
        );
        for needle in [
            r#"id="port-graph""#,
            r#"id="joint-plot""#,
            r#"data-port="/icub/left_arm/state:o""#,
        ] {
            assert!(dom.contains(needle), "the dashboard's DOM lacks {needle}");
        }
    }

    let status = get_json(&format!("{url}api/status"));
    let pids: Vec<i32> = status["modules"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|m| m["pid"].as_i64())
        .map(|p| p as i32)
        .collect();
    assert_eq!(l.stop(Signal::SIGINT, Duration::from_secs(60)), Some(0));
    assert_eq!(wait_gone(&pids, Duration::from_secs(5)), Vec::<i32>::new());
    drop(probe);
}

#[test]
fn fake_devices_to_rclpy_and_back() {
    e2e("fake-devices.toml", &[], "0", 30.0, 0, None);
}

/// The acceptance run: the emulated iCub. Its robot files name the CAN hubs' UDP ports
/// (20000..20009), which other tests' emulators may hold for a while: wait until they
/// are free.
#[test]
fn icub_sim_to_rclpy_and_back() {
    program("icub-board-emulator", "icub-emulators");
    program("yarprobotinterface", "yarp-device-programs");
    let free = eventually(Duration::from_secs(120), || {
        let all = (20000..20010)
            .map(|p| std::net::UdpSocket::bind(("127.0.0.1", p)))
            .collect::<Result<Vec<_>, _>>();
        all.is_ok().then_some(())
    });
    assert!(free.is_some(), "UDP ports 20000..20009 stay busy");
    // The iCub elbow (joint 3 of the arm, 15..105 degrees).
    e2e("icub-sim.toml", &[], "3", 60.0, 1, Some("/icub/head/imu"));
}
