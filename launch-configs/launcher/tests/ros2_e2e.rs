//! The mission end to end: `yarp-launch` starts a robot config (`icub-sim.toml`, the
//! emulated iCub; `icub-genova02.toml` and `ergocub.toml`, the Ethernet robots of
//! robots-configuration on emulated boards; `fake-devices.toml`); for each ROS 2 distro (Kilted and Jazzy, see
//! `common::ros`) real rclpy nodes with rclpy's default QoS read every state topic the
//! gateway offers and the left arm's `joint_states`, and command a joint through the
//! gateway once the part is calibrated; our `yarp read` reads a YARP port, headless
//! Chromium loads the dashboard, and everything stops with no process left behind. Prints
//! the time from the start to the first JointState; for the iCub, the whole robot as ROS
//! tools read it (merged /joint_states, latched /robot_description, CameraInfo). Needs
//! the rclpy venvs (`tests/peers/install-ros2.sh [jazzy]`, `ROS_VENV`, `ROS_JAZZY_VENV`);
//! skips loudly without them (fails under CI=true).

mod common;

use common::ros::{distros, Distro};
use common::*;
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

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

/// The state topics a default-QoS subscriber must receive from `mapping` (the launch's
/// gateway mappings): every topic the gateway publishes that the file does not mark
/// best effort (images may be), and the gateway's /diagnostics; as `TOPIC=pkg/msg/Type`.
fn state_topics(mapping: &str) -> Vec<String> {
    let path = configs_dir().join("../mappings/launch").join(mapping);
    let text = std::fs::read_to_string(&path).expect("mapping file");
    let table: toml::Table = text.parse().expect("mapping TOML");
    let mut topics: Vec<String> = table["topic"]
        .as_array()
        .expect("[[topic]] entries")
        .iter()
        .filter(|t| {
            let offered = matches!(t["direction"].as_str(), Some("yarp_to_ros" | "both"));
            let best_effort = t
                .get("qos")
                .and_then(|q| q.get("reliability"))
                .is_some_and(|r| r.as_str() == Some("best_effort"));
            offered && !best_effort
        })
        .map(|t| {
            format!(
                "{}={}",
                t["ros_topic"].as_str().unwrap(),
                t["ros_type"].as_str().unwrap()
            )
        })
        .collect();
    topics.push("/diagnostics=diagnostic_msgs/msg/DiagnosticArray".into());
    topics
}

/// What one end-to-end run checks.
struct Scenario<'a> {
    config: &'a str,
    /// The gateway mapping file of the config (in mappings/launch/).
    mapping: &'a str,
    /// Joint of the left arm commanded, and its targets (degrees) per distro, in turn.
    joint: &'a str,
    targets: [f64; 2],
    /// The robot's log line that says the left arm is calibrated (commands wait for it).
    calibrated: Option<&'a str>,
    /// The robot's port prefix (`/icub`, `/ergocub`).
    prefix: &'a str,
    /// Options for `yarp-launch` (e.g. `--set address_map=...`).
    extra: &'a [&'a str],
    /// The ROS domain is 1 + 4 * (pid % 25) + this (this file uses 1..=100).
    domain_offset: u32,
    imu_topic: Option<&'a str>,
    /// The whole robot as ROS tools read it: the joints of the merged `/joint_states`
    /// (with `/robot_description` latched) and a CameraInfo topic.
    whole_robot: Option<(usize, &'a str)>,
    /// The left arm's FollowJointTrajectory action (the gateway's trajectory controller),
    /// reached by our ROS layer: a second gateway's `yarp_to_ros` entry called by `yarp rpc`.
    trajectory: Option<&'a str>,
}

/// Runs the scenario's config and checks the whole chain, for every ROS 2 distro at once
/// (one launch; one rclpy node per distro and role in the same domain): each distro's
/// default-QoS subscribers receive every state topic, and each distro in turn commands
/// the joint through the gateway and sees it move.
fn e2e(s: Scenario) {
    let distros = distros(s.config);
    if distros.is_empty() {
        yarp_interop_tests::peer_missing(
            s.config,
            "rclpy",
            "no ROS 2 venv in $ROS_VENV / $ROS_JAZZY_VENV that imports rclpy",
            yarp_interop_tests::RCLPY_INSTALL,
        );
        return;
    }
    // A ROS domain per test: the two tests of this file may run at once, and other tests
    // run DDS in the same network namespace.
    let domain = (1 + (std::process::id() % 25) * 4 + s.domain_offset).to_string();
    let ros_env = |distro: &'static str| {
        [
            ("ROS_DOMAIN_ID", domain.clone()),
            ("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST".to_string()),
            ("ROS_DISTRO", distro.to_string()),
            // UDP only: Fast DDS's /dev/shm segments are not isolated by netns-run.
            ("FASTDDS_BUILTIN_TRANSPORTS", "UDPv4".to_string()),
        ]
    };
    let work = tempfile::tempdir().unwrap();
    let topics = state_topics(s.mapping);

    // The rclpy nodes first (their start-up is not the launcher's), then the launch.
    let mut nodes = Vec::new();
    for (k, d) in distros.iter().enumerate() {
        let go = work.path().join(format!("go-{}", d.name));
        let target = format!("{}", s.targets[k % 2]);
        let mut joint_cmd = Command::new(d.python());
        joint_cmd
            .arg("-u")
            .arg(configs_dir().join("launcher/tests/peers/joint_probe.py"))
            .args(["left_arm", s.joint, &target, "--prefix", s.prefix])
            .args(["--timeout", "240", "--go"])
            .arg(&go)
            .envs(ros_env(d.name));
        let mut state_cmd = Command::new(d.python());
        state_cmd
            .arg("-u")
            .arg(configs_dir().join("launcher/tests/peers/state_probe.py"))
            .args(["--timeout", "240"])
            .args(&topics)
            .envs(ros_env(d.name));
        nodes.push(Nodes {
            distro: d.clone(),
            joint: Lines::spawn(joint_cmd),
            state: Lines::spawn(state_cmd),
            go,
            target: s.targets[k % 2],
        });
    }
    for n in &nodes {
        n.joint.expect("READY", Duration::from_secs(90));
        n.state.expect("READY", Duration::from_secs(90));
    }

    let t0 = Instant::now();
    let mut args = vec!["--dashboard", "127.0.0.1:0"];
    args.extend_from_slice(s.extra);
    let launch_env = ros_env(distros[0].name);
    let launch_env: Vec<(&str, &str)> = launch_env.iter().map(|(k, v)| (*k, v.as_str())).collect();
    let mut l = Launch::start_with_env(&configs_dir().join(s.config), &args, &launch_env);
    let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        checks(&mut l, &nodes, &s, t0, &launch_env)
    }));
    if let Err(e) = r {
        // The modules' logs say why (the robot's, the gateway's): print them.
        eprintln!("---- yarp-launch output ----\n{}", l.drain().join("\n"));
        std::panic::resume_unwind(e);
    }
}

/// One distro's rclpy nodes.
struct Nodes {
    distro: Distro,
    joint: Lines,
    state: Lines,
    /// Created when its joint probe may command.
    go: std::path::PathBuf,
    target: f64,
}

fn checks(l: &mut Launch, nodes: &[Nodes], s: &Scenario, t0: Instant, ros_env: &[(&str, &str)]) {
    let url = l.dashboard_url();
    for n in nodes {
        let first = n.joint.expect("FIRST", Duration::from_secs(150));
        eprintln!(
            "{} [{}]: start to first JointState in a default-QoS rclpy subscriber: {:.2} s",
            s.config,
            n.distro.name,
            t0.elapsed().as_secs_f64()
        );
        let js: serde_json::Value = serde_json::from_str(&first).expect("json");
        assert!(js["name"].as_array().is_some_and(|n| !n.is_empty()), "{js}");
    }
    // Commands need the part calibrated (the robot says so in its log), not a delay.
    if let Some(line) = s.calibrated {
        l.wait_line(line, Duration::from_secs(150));
    }
    let mut last_target = None;
    for n in nodes {
        std::fs::write(&n.go, b"go").unwrap();
        let reply = n.joint.expect("REPLY", Duration::from_secs(30));
        assert!(reply.contains("ok"), "[{}] reply {reply}", n.distro.name);
        let moved = n.joint.expect("MOVED", Duration::from_secs(60));
        eprintln!(
            "[{}] joint {} moved to {moved} deg (commanded {})",
            n.distro.name, s.joint, n.target
        );
        last_target = Some(n.target);
    }
    for n in nodes {
        n.state.expect("ALL", Duration::from_secs(120));
        eprintln!(
            "[{}] default-QoS subscribers received every state topic",
            n.distro.name
        );
    }
    let (target, joint, venv) = (last_target.unwrap(), s.joint, nodes[0].distro.venv.clone());

    // An IMU of the robot reaches rclpy as sensor_msgs/Imu.
    if let Some(topic) = s.imu_topic {
        let mut imu_cmd = Command::new(venv.join("bin/python"));
        imu_cmd
            .arg("-u")
            .arg(configs_dir().join("launcher/tests/peers/imu_probe.py"))
            .args([topic, "--timeout", "60"])
            .envs(ros_env.iter().copied());
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

    // One /joint_states with every joint, the latched URDF, CameraInfo beside the camera.
    if let Some((joints, camera_info)) = s.whole_robot {
        let mut cmd = Command::new(venv.join("bin/python"));
        cmd.arg("-u")
            .arg(configs_dir().join("launcher/tests/peers/robot_probe.py"))
            .arg(joints.to_string())
            .args(["--camera-info", camera_info, "--timeout", "60"])
            .envs(ros_env.iter().copied());
        let probe = Lines::spawn(cmd);
        // The probe prints each of JOINTS, URDF and CAMERA_INFO as it arrives (in any
        // order), then DONE.
        let mut got = std::collections::HashMap::new();
        let deadline = Instant::now() + Duration::from_secs(90);
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            let line = match probe.rx.recv_timeout(left) {
                Ok(l) => l,
                Err(_) => panic!("the robot probe ended or timed out; it said {got:?}"),
            };
            if line.starts_with("DONE") {
                break;
            }
            if let Some((key, rest)) = line.split_once(' ') {
                got.insert(key.to_string(), rest.trim().to_string());
            }
        }
        let field = |k: &str| -> serde_json::Value {
            serde_json::from_str(got.get(k).unwrap_or_else(|| panic!("no {k}: {got:?}")))
                .expect("json")
        };
        let js = field("JOINTS");
        assert!(
            js["name"]
                .as_array()
                .unwrap()
                .iter()
                .any(|n| n == "l_elbow"),
            "{js}"
        );
        let urdf = field("URDF");
        assert!(urdf["head"].as_str().unwrap().contains("<?xml"), "{urdf}");
        let info = field("CAMERA_INFO");
        assert_eq!(info["width"], 320, "{info}");
        assert_eq!(info["distortion_model"], "plumb_bob", "{info}");
        eprintln!(
            "/joint_states with {joints} joints, /robot_description ({} bytes, latched), \
             {camera_info}: {info}",
            urdf["len"]
        );
    }

    // Our `yarp read` sees the same joint on the YARP side.
    let conf_home = l.conf_home.path().to_path_buf();
    let state = format!("{}/left_arm/state:o", s.prefix);
    let reader = Lines::spawn(our_yarp(&conf_home, &["read", "/e2e/reader", &state]));
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

    if let Some(action) = s.trajectory {
        follow_trajectory(action, &conf_home, ros_env, s.prefix);
    }

    // The dashboard, in headless Chromium, shows this robot's ports and the joint plot.
    if let Some(browser) = common::browser::chromium() {
        let work = tempfile::tempdir().unwrap();
        let dom = common::browser::run_chromium(
            &browser,
            &work.path().join("profile"),
            &["--dump-dom".to_string(), url.clone()],
            Duration::from_secs(60),
        );
        let port = format!(r#"data-port="{}/left_arm/state:o""#, s.prefix);
        for needle in [r#"id="port-graph""#, r#"id="joint-plot""#, port.as_str()] {
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
}

#[test]
fn fake_devices_to_rclpy_and_back() {
    e2e(Scenario {
        config: "fake-devices.toml",
        mapping: "fake-devices.toml",
        joint: "0",
        targets: [30.0, 20.0],
        calibrated: None,
        prefix: "/icub",
        extra: &[],
        domain_offset: 0,
        imu_topic: None,
        whole_robot: None,
        trajectory: None,
    });
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
    e2e(Scenario {
        config: "icub-sim.toml",
        mapping: "icub-sim.toml",
        joint: "3",
        targets: [60.0, 50.0],
        calibrated: Some("calibration done device=Left_Arm_Calibrator"),
        prefix: "/icub",
        extra: &[],
        domain_offset: 1,
        imu_topic: Some("/icub/head/imu"),
        whole_robot: Some((53, "/icub/cam/left/camera_info")),
        trajectory: Some("/left_arm_controller/follow_joint_trajectory"),
    });
}

/// The Ethernet iCub of robots-configuration, unmodified, against the emulated boards
/// (served on 127.0.7.0/24, apart from other tests' boards). The left shoulder pitch
/// (joint 0, calibrated to -35.97 degrees).
#[test]
fn icub_genova02_to_rclpy_and_back() {
    program("icub-eth-emulator", "icub-emulators");
    program("yarprobotinterface", "yarp-device-programs");
    e2e(Scenario {
        config: "icub-genova02.toml",
        mapping: "icub-genova02.toml",
        joint: "0",
        targets: [-20.0, -25.0],
        calibrated: Some("calibration done device=Left_Arm_Calibrator"),
        prefix: "/icub",
        extra: &["--set", "address_map=10.0.1.0/24=127.0.7.0/24"],
        domain_offset: 2,
        imu_topic: None,
        whole_robot: None,
        trajectory: None,
    });
}

/// ergoCubSN001 of robots-configuration, unmodified, against the emulated boards (served on
/// 127.0.8.0/24) and the emulated waist MTi (on a pseudo-terminal of this test). The left
/// shoulder roll (joint 1, calibrated to 50 degrees); the left arm's IMU as
/// sensor_msgs/Imu; every topic of the mapping, the waist IMU's included.
#[test]
fn ergocub_to_rclpy_and_back() {
    program("icub-eth-emulator", "icub-emulators");
    program("yarprobotinterface", "yarp-device-programs");
    let xsens = format!("xsens_serial=/tmp/ergocub-ttyXSENS-{}", std::process::id());
    e2e(Scenario {
        config: "ergocub.toml",
        mapping: "ergocub.toml",
        joint: "1",
        targets: [60.0, 55.0],
        calibrated: Some("calibration done device=Left_Arm_Calibrator"),
        prefix: "/ergocub",
        extra: &[
            "--set",
            "address_map=10.0.1.0/24=127.0.8.0/24",
            "--set",
            &xsens,
        ],
        domain_offset: 3,
        imu_topic: Some("/ergocub/left_arm/imu"),
        whole_robot: None,
        trajectory: None,
    });
}

/// A FollowJointTrajectory goal from our ROS layer (a second gateway turns `yarp rpc` calls
/// into goals of `action`): the left elbow through three points, SUCCESSFUL, then on the
/// last one; a point beyond the elbow's limits gets INVALID_GOAL and moves nothing.
fn follow_trajectory(
    action: &str,
    conf_home: &std::path::Path,
    ros_env: &[(&str, &str)],
    prefix: &str,
) {
    let work = tempfile::tempdir().unwrap();
    let mapping = work.path().join("caller.toml");
    std::fs::write(
        &mapping,
        format!(
            "[[action]]\nname = \"fjt_caller\"\ndirection = \"yarp_to_ros\"\n\
             yarp_port = \"/e2e/fjt:rpc\"\nros_action = \"{action}\"\n\
             ros_type = \"control_msgs/action/FollowJointTrajectory\"\n\
             yarp_feedback = \"/e2e/fjt/feedback:o\"\n"
        ),
    )
    .unwrap();
    let mut gw = Command::new(program("yarp-ros2-gateway", "yarp-ros2-gateway"));
    gw.arg("--mappings")
        .arg(&mapping)
        .args(["--network", "127.0.0.1", "--node-name", "e2e_fjt_caller"])
        .args([
            "--diagnostics-port",
            "/e2e/fjt/diagnostics:o",
            "--no-embedded-name-server",
        ])
        .env("YARP_CONFIG_HOME", conf_home)
        .envs(ros_env.iter().copied());
    let _caller = Lines::spawn(gw);
    // trajectory multi_dof path component_path goal component_goal goal_time: the
    // trajectory (header joint_names points), each point (positions velocities
    // accelerations effort time_from_start), in the goal's generic layout.
    let goal = |points: &[(f64, u32)]| {
        let pts: Vec<String> = points
            .iter()
            .map(|(q, s)| format!("(({q}) () () () ({s} 0))"))
            .collect();
        format!(
            "(((0 0) \"\") (\"l_elbow\") ({})) (((0 0) \"\") () ()) () () () () (0 0)",
            pts.join(" ")
        )
    };
    // until the caller gateway's ROS client has found the action server
    let call = |cmd: &str| -> String {
        let deadline = Instant::now() + Duration::from_secs(60);
        loop {
            let text = fjt_call(conf_home, cmd);
            let answered =
                text.contains("Response:") && !text.contains("no action server answered");
            if answered || Instant::now() > deadline {
                return text;
            }
            std::thread::sleep(Duration::from_millis(500));
        }
    };
    // The feedback of the goals, as our `yarp read` prints it (once the caller's port is
    // there: `yarp exists`).
    let registered = eventually(Duration::from_secs(30), || {
        let st = our_yarp(conf_home, &["exists", "/e2e/fjt/feedback:o"])
            .stdout(Stdio::null())
            .status()
            .ok()?;
        st.success().then_some(())
    });
    assert!(
        registered.is_some(),
        "the caller gateway never opened its feedback port"
    );
    let feedback = Lines::spawn(our_yarp(
        conf_home,
        &["read", "/e2e/fjt_feedback", "/e2e/fjt/feedback:o"],
    ));
    let t0 = Instant::now();
    let reply = call(&goal(&[(0.8, 2), (1.2, 4), (1.0, 6)]));
    assert!(
        reply.contains("Goal successfully reached!") && !reply.contains("[fail]"),
        "FollowJointTrajectory: {reply}"
    );
    eprintln!(
        "FollowJointTrajectory of the left elbow: {} in {:.2} s",
        reply.trim(),
        t0.elapsed().as_secs_f64()
    );
    let state = format!("{prefix}/left_arm/state:o");
    let reader = Lines::spawn(our_yarp(conf_home, &["read", "/e2e/fjt_reader", &state]));
    let line = reader.expect("", Duration::from_secs(20));
    let elbow = elbow_of(&line);
    assert!(
        (elbow - 1f64.to_degrees()).abs() < 0.02f64.to_degrees(),
        "elbow at {elbow}"
    );
    drop(reader);
    // (header joint_names desired actual error index ...): the elbow's, on the way.
    let mut seen = 0;
    while let Ok(line) = feedback.rx.recv_timeout(Duration::from_millis(500)) {
        if line.contains("l_elbow") {
            seen += 1;
        }
    }
    assert!(seen >= 10, "{seen} feedback messages of a 6 s goal");
    drop(feedback);
    // A cancel (`[stop]` from another caller) stops the elbow on its way.
    let long = std::thread::spawn({
        let (g, home) = (goal(&[(0.5, 8)]), conf_home.to_path_buf());
        move || fjt_call(&home, &g)
    });
    std::thread::sleep(Duration::from_secs(3));
    let stop = call("[stop]");
    assert!(stop.contains("[ok] 1"), "[stop]: {stop}");
    let reply = long.join().unwrap();
    assert!(
        reply.contains("[fail] canceled"),
        "the canceled goal: {reply}"
    );
    let state = format!("{prefix}/left_arm/state:o");
    let reader = Lines::spawn(our_yarp(conf_home, &["read", "/e2e/fjt_reader2", &state]));
    let first: f64 = elbow_of(&reader.expect("", Duration::from_secs(20)));
    std::thread::sleep(Duration::from_millis(800));
    let mut last = first;
    while let Ok(l) = reader.rx.try_recv() {
        last = elbow_of(&l);
    }
    drop(reader);
    assert!(
        first > 0.5f64.to_degrees() + 5.0 && first < 1f64.to_degrees() - 5.0,
        "stopped on the way: {first}"
    );
    assert!((last - first).abs() < 0.5, "still: {first} then {last}");
    let reply = call(&goal(&[(2.5, 2)]));
    assert!(
        reply.contains("[fail] aborted -1") && reply.contains("outside its limits"),
        "a point beyond the elbow's limits: {reply}"
    );
}

/// Our `yarp` program with `args`, under the launch's name server (`conf_home`).
fn our_yarp(conf_home: &std::path::Path, args: &[&str]) -> Command {
    let mut cmd = Command::new(program("yarp", "yarp-cli"));
    cmd.args(args).env("YARP_CONFIG_HOME", conf_home);
    cmd
}

/// One `yarp rpc /e2e/fjt:rpc` of `cmd` (a FollowJointTrajectory goal, or `[stop]`): what
/// it printed.
fn fjt_call(conf_home: &std::path::Path, cmd: &str) -> String {
    use std::io::Write;
    let mut child = our_yarp(conf_home, &["rpc", "/e2e/fjt:rpc"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("yarp rpc");
    let mut stdin = child.stdin.take().unwrap();
    writeln!(stdin, "{cmd}").unwrap();
    drop(stdin);
    let out = child.wait_with_output().expect("yarp rpc output");
    String::from_utf8_lossy(&out.stdout).to_string()
}

/// The left elbow (joint 3) in a `yarp read` line of the arm's `state:o`.
fn elbow_of(line: &str) -> f64 {
    line.split_whitespace()
        .nth(3)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("yarp read printed {line:?}"))
}
