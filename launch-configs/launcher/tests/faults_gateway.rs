//! The gateway killed (SIGKILL) and restarted under `yarp-launch` (`fake-devices.toml`,
//! whose gateway module restarts on failure): an rclpy subscriber that runs throughout,
//! never restarted, receives `/icub/left_arm/joint_states` again from the new gateway.
//! Then the launch's name server is killed: the launcher starts it again, every port is
//! registered again, and the subscriber keeps receiving.
//! Needs the rclpy venv (`tests/peers/install-ros2.sh`, `ROS_VENV`); skips loudly without
//! it (fails under CI=true). Run under netns-run.

mod common;

use common::ros::distros;
use common::*;
use nix::sys::signal::kill;
use nix::unistd::Pid;
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// The probe's `COUNT n` lines, the latest first available.
struct Counter {
    child: std::process::Child,
    rx: mpsc::Receiver<String>,
    last: u64,
}

impl Counter {
    fn spawn(mut cmd: Command) -> Counter {
        let mut child = cmd
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("spawn the rclpy probe");
        let out = child.stdout.take().expect("stdout");
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            for l in BufReader::new(out).lines().map_while(Result::ok) {
                if tx.send(l).is_err() {
                    break;
                }
            }
        });
        Counter { child, rx, last: 0 }
    }

    fn ready(&mut self, limit: Duration) {
        let deadline = Instant::now() + limit;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.rx.recv_timeout(left) {
                Ok(l) if l == "READY" => return,
                Ok(_) => {}
                Err(_) => panic!("the rclpy probe did not start within {limit:?}"),
            }
        }
    }

    /// The count now (reading every report that arrived).
    fn now(&mut self) -> u64 {
        for l in self.rx.try_iter() {
            if let Some(n) = l.strip_prefix("COUNT ").and_then(|n| n.parse().ok()) {
                self.last = n;
            }
        }
        self.last
    }

    /// Waits until the count reaches `n`; whether it did within `limit`.
    fn reaches(&mut self, n: u64, limit: Duration) -> bool {
        let deadline = Instant::now() + limit;
        while Instant::now() < deadline {
            if self.now() >= n {
                return true;
            }
            std::thread::sleep(Duration::from_millis(100));
        }
        false
    }
}

impl Drop for Counter {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A module's pid and state from the dashboard's status.
fn module(url: &str, name: &str) -> (Option<i64>, String) {
    let s = get_json(&format!("{url}api/status"));
    let m = s["modules"]
        .as_array()
        .expect("modules")
        .iter()
        .find(|m| m["name"] == name)
        .cloned()
        .unwrap_or_else(|| panic!("no module {name}"));
    (
        m["pid"].as_i64(),
        m["state"].as_str().unwrap_or("").to_string(),
    )
}

fn gateway(url: &str) -> (Option<i64>, String) {
    module(url, "gateway")
}

/// Whether `yarp name query PORT` finds it (on the launch's name server).
fn registered(l: &Launch, port: &str) -> bool {
    Command::new(program("yarp", "yarp-cli"))
        .args(["name", "query", port])
        .env("YARP_CONFIG_HOME", l.conf_home.path())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

#[test]
fn gateway_killed_and_restarted_ros_subscriber_receives_again() {
    let test = "gateway_killed_and_restarted_ros_subscriber_receives_again";
    let Some(d) = distros(test).into_iter().next() else {
        yarp_interop_tests::peer_missing(
            test,
            "rclpy",
            "no ROS 2 venv in $ROS_VENV / $ROS_JAZZY_VENV that imports rclpy",
            yarp_interop_tests::RCLPY_INSTALL,
        );
        return;
    };
    // a ROS domain of its own: above those of the gateway's tests (20..229) and of the
    // launcher's e2e tests (below 101)
    let domain = "230".to_string();
    let ros_env = [
        ("ROS_DOMAIN_ID", domain.as_str()),
        ("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST"),
        ("ROS_DISTRO", d.name),
        // UDP only: Fast DDS's /dev/shm segments are not isolated by netns-run.
        ("FASTDDS_BUILTIN_TRANSPORTS", "UDPv4"),
    ];
    let mut probe_cmd = Command::new(d.python());
    probe_cmd
        .arg("-u")
        .arg(configs_dir().join("launcher/tests/peers/count_probe.py"))
        .args(["/icub/left_arm/joint_states", "sensor_msgs/msg/JointState"])
        .args(["--timeout", "180"])
        .envs(ros_env);
    let mut probe = Counter::spawn(probe_cmd);
    probe.ready(Duration::from_secs(90));

    let mut l = Launch::start_with_env(
        &configs_dir().join("fake-devices.toml"),
        &[
            "--dashboard",
            "127.0.0.1:0",
            "--set",
            "module.wave.enabled=false",
        ],
        &ros_env,
    );
    let url = l.dashboard_url();
    let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        assert!(
            probe.reaches(10, Duration::from_secs(90)),
            "no joint_states before the fault (got {})",
            probe.now()
        );
        let (pid, _) = gateway(&url);
        let pid = pid.expect("the gateway runs");
        kill(Pid::from_raw(pid as i32), nix::sys::signal::Signal::SIGKILL).expect("kill");
        let t0 = Instant::now();
        l.wait_line("gateway: restarting", Duration::from_secs(20));
        let back = eventually(Duration::from_secs(60), || {
            let (p, state) = gateway(&url);
            (p.is_some_and(|p| p != pid) && state == "ready").then_some(())
        });
        assert!(back.is_some(), "the gateway did not come back ready");
        let at_restart = probe.now();
        assert!(
            probe.reaches(at_restart + 20, Duration::from_secs(60)),
            "the subscriber got nothing from the restarted gateway ({} then {})",
            at_restart,
            probe.now()
        );
        println!(
            "joint_states flow again {:?} after the kill (the rclpy node never restarted)",
            t0.elapsed()
        );

        // the name server killed: the launcher starts it again, every port registers
        // again, and the stream never needed it
        let ns_pid = module(&url, "yarpserver")
            .0
            .expect("the embedded name server runs");
        let gw_port = "/yarp_ros2_gateway/left_arm/state:i";
        assert!(registered(&l, gw_port), "{gw_port} registered before");
        kill(
            Pid::from_raw(ns_pid as i32),
            nix::sys::signal::Signal::SIGKILL,
        )
        .expect("kill");
        let t1 = Instant::now();
        l.wait_line("yarpserver: restarting", Duration::from_secs(20));
        for port in [gw_port, "/icub/left_arm/state:o", "/icub/left_arm/rpc:i"] {
            let again = eventually(Duration::from_secs(20), || {
                registered(&l, port).then_some(())
            });
            assert!(again.is_some(), "{port} not registered again");
        }
        println!(
            "every port registered again {:?} after the name server was killed",
            t1.elapsed()
        );
        let now = probe.now();
        assert!(
            probe.reaches(now + 20, Duration::from_secs(30)),
            "joint_states stopped with the name server ({now} then {})",
            probe.now()
        );
    }));
    if let Err(e) = r {
        eprintln!("---- yarp-launch output ----\n{}", l.drain().join("\n"));
        std::panic::resume_unwind(e);
    }
    assert_eq!(l.stop(Signal::SIGINT, Duration::from_secs(30)), Some(0));
}
