//! The ready configs in `launch-configs/`: each loads and finds its programs, and
//! `fake-devices` runs end to end (devices, gateway, dashboard data) and stops cleanly.

mod common;

use common::*;
use std::time::Duration;

#[test]
fn ready_configs_load_and_find_their_programs() {
    for (file, expect) in [
        ("demo.toml", "connect /demo/writer -> /demo/reader (tcp)"),
        (
            "fake-devices.toml",
            "module gateway: yarp-ros2-gateway --mappings",
        ),
        ("icub-sim.toml", "module robot: yarprobotinterface --config"),
        (
            "left-arm.xml",
            "connect /icub/left_arm/state:o -> /left_arm/monitor (udp)",
        ),
    ] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_yarp-launch"))
            .arg(configs_dir().join(file))
            .arg("--check")
            .env("YARP_BIN_DIR", bin_dir())
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{file}: {}{stdout}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(stdout.contains(expect), "{file}: {stdout}");
    }
}

#[test]
fn fake_devices_runs_with_plots_camera_and_bridge() {
    program("yarpdev", "yarp-device-programs");
    program("yarp-ros2-gateway", "yarp-ros2-gateway");
    let cfg = configs_dir().join("fake-devices.toml");
    // A domain of its own (101..=200): other tests run DDS in this network namespace.
    let domain = (101 + std::process::id() % 100).to_string();
    let mut l = Launch::start_with_env(
        &cfg,
        &["--dashboard", "127.0.0.1:0", "--set", "joints=7"],
        &[("ROS_DOMAIN_ID", &domain)],
    );
    let url = l.dashboard_url();
    l.wait_line("fake-devices is up in", Duration::from_secs(60));
    l.wait_line("Ctrl-C here stops everything", Duration::from_secs(10));
    let out = l.drain().join("\n");
    assert!(
        out.contains("ros2 topic echo /icub/left_arm/joint_states"),
        "{out}"
    );

    let status = get_json(&format!("{url}api/status"));
    let pids: Vec<i32> = status["modules"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["state"] != "disabled")
        .map(|m| {
            assert_eq!(m["state"], "ready", "{m}");
            m["pid"].as_i64().unwrap() as i32
        })
        .collect();
    assert_eq!(pids.len(), 6, "name server + 5 modules");

    // Encoders of the 7-joint fake arm.
    let plot = eventually(Duration::from_secs(15), || {
        let p = get_json(&format!("{url}api/plot"));
        (p["t"].as_array().map_or(0, Vec::len) >= 3).then_some(p)
    })
    .expect("left arm samples");
    assert_eq!(plot["series"].as_array().unwrap().len(), 7, "{plot}");
    // Joint names from the board's axis info (asked over /icub/left_arm/rpc:i).
    let names = eventually(Duration::from_secs(10), || {
        let p = get_json(&format!("{url}api/plot"));
        let n = p["names"].as_array().map_or(0, Vec::len);
        (n == 7).then_some(p["names"].clone())
    })
    .expect("joint names");
    assert_eq!(names[0], "joint0");

    // The camera as a 320x240 PNG.
    let png = eventually(Duration::from_secs(15), || {
        let (code, body) = http_get(&format!("{url}api/camera.png"));
        (code == 200).then_some(body)
    })
    .expect("camera image");
    let reader = png::Decoder::new(std::io::Cursor::new(png))
        .read_info()
        .expect("PNG");
    assert_eq!((reader.info().width, reader.info().height), (320, 240));

    // Gateway counters: the joint-state bridge is up. (It carries messages only while a
    // ROS subscriber is matched - the gateway works on demand; ros2_e2e subscribes.)
    let bridge = eventually(Duration::from_secs(20), || {
        let b = get_json(&format!("{url}api/bridge"));
        let up = b["rows"]
            .as_array()
            .is_some_and(|rows| rows.iter().any(|r| r["name"] == "left_arm_joints"));
        up.then_some(b)
    });
    assert!(bridge.is_some(), "no gateway counters");

    assert_eq!(l.stop(Signal::SIGTERM, Duration::from_secs(40)), Some(0));
    assert_eq!(wait_gone(&pids, Duration::from_secs(5)), Vec::<i32>::new());
}
