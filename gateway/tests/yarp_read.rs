//! rclpy geometry_msgs/Twist -> the gateway -> `yarp read` processes: ours (the
//! workspace's `yarp` binary) and, when installed, C++ YARP's. Domain index: 24.

mod common;

use common::{Peer, T};
use std::path::PathBuf;
use std::process::Command;
use std::time::{Duration, Instant};

/// The workspace's `yarp` program, built into the same target directory as this test
/// (`cargo build -p yarp-cli`), or `None` after a loud notice.
fn our_yarp() -> Option<PathBuf> {
    let exe = std::env::current_exe().ok()?;
    // <target>/<profile>/deps/<test> -> <target>/<profile>/yarp
    let p = exe.parent()?.parent()?.join("yarp");
    if p.is_file() {
        return Some(p);
    }
    eprintln!(
        "\n*** SKIPPED: {} not built; run `cargo build -p yarp-cli` with the same target \
         directory ***\n",
        p.display()
    );
    None
}

/// C++ YARP's `yarp` (the shared lookup of the C++ peer; says SKIPPED when absent).
fn cpp_yarp() -> Option<PathBuf> {
    yarp_interop_tests::cpp_program("rclpy_twist_reaches_yarp_read (C++ reader)", "yarp")
}

/// `yarp read <port>`; its stdout lines are collected (killed and reaped on drop).
fn yarp_read(program: &PathBuf, port: &str) -> Peer {
    let mut cmd = Command::new(program);
    cmd.args(["read", port]);
    Peer::spawn(cmd, &format!("{} read {port}", program.display()))
}

/// Waits for a line of six numbers from a `yarp read`.
async fn six_numbers(reader: &Peer, who: &str) -> Vec<f64> {
    let end = Instant::now() + T;
    loop {
        let left = end.saturating_duration_since(Instant::now());
        let line = reader.expect_async("", left).await;
        let v: Vec<f64> = line
            .split_whitespace()
            .filter_map(|w| w.parse().ok())
            .collect();
        if v.len() == 6 {
            return v;
        }
        assert!(Instant::now() < end, "{who}: no Twist line, last {line:?}");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn rclpy_twist_reaches_yarp_read() {
    for d in common::distros("rclpy_twist_reaches_yarp_read") {
        rclpy_twist_reaches_yarp_read_on(&d).await;
    }
}

async fn rclpy_twist_reaches_yarp_read_on(venv: &common::Distro) {
    let Some(ours) = our_yarp() else {
        return;
    };
    let domain = venv.domain(24);
    // The readers find the name server through the yarp.conf this writes.
    let ns = common::device_name_server();
    let our_reader = yarp_read(&ours, "/t24/ours");
    let cpp_reader = cpp_yarp().map(|p| yarp_read(&p, "/t24/cpp"));
    let gw = common::gateway(
        r#"
[[topic]]
name = "cmd_vel"
direction = "ros_to_yarp"
yarp_port = "/gw/cmd_vel:o"
yarp_sink = "/t24/ours"
ros_topic = "/cmd_vel"
ros_type = "geometry_msgs/msg/Twist"
"#,
        &ns,
        domain,
    )
    .await;
    if cpp_reader.is_some() {
        let end = Instant::now() + T;
        while !matches!(
            yarp_net::network::connect(&ns, "/gw/cmd_vel:o", "/t24/cpp", None).await,
            Ok((true, _))
        ) {
            assert!(Instant::now() < end, "cannot connect to the C++ reader");
            tokio::time::sleep(Duration::from_millis(100)).await;
        }
    }
    let _pub = Peer::start(
        venv,
        domain,
        &[
            "pub",
            "geometry_msgs/msg/Twist",
            "/cmd_vel",
            r#"{"linear": {"x": 0.5, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": -0.25}}"#,
            "--count",
            "400",
            "--rate",
            "20",
            "--wait-sub",
        ],
    );
    let want = [0.5, 0.0, 0.0, 0.0, 0.0, -0.25];
    assert_eq!(six_numbers(&our_reader, "our yarp read").await, want);
    if let Some(cpp) = &cpp_reader {
        assert_eq!(six_numbers(cpp, "C++ yarp read").await, want);
        eprintln!("Twist read by our `yarp read` and by C++ `yarp read`");
    }
    gw.shutdown().await;
}
