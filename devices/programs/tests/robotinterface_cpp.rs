//! The C++ `yarp rpc` tool (YARP 3.12.3 from `tests/peers/install-cpp-peers.sh icub`, or the
//! directory in `YARP_CPP_BIN`) against our `yarprobotinterface`: its
//! `/robot/yarprobotinterface` service and the control board it brought up. Without a C++
//! YARP the test says SKIPPED loudly (in CI: fails). Run under netns-run.

#[path = "../../tests/fixtures/robotinterface/live_support.rs"]
mod support;

use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::{Duration, Instant};
use support::*;
use yarp_devices::Registry;

const BIN: &str = env!("CARGO_BIN_EXE_yarprobotinterface");

/// The C++ `yarp` program.
fn cpp_yarp() -> Option<PathBuf> {
    yarp_interop_tests::cpp_program("robotinterface_cpp", "yarp")
}

/// Runs `yarp rpc <port>` with `lines` on stdin; the `Response:` lines it printed.
fn cpp_rpc(yarp: &Path, conf_home: &Path, port: &str, lines: &[&str]) -> Vec<String> {
    let mut child = std::process::Command::new(yarp)
        .args(["rpc", port])
        .env("YARP_CONFIG_HOME", conf_home)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("run C++ yarp rpc");
    let mut stdin = child.stdin.take().unwrap();
    for l in lines {
        writeln!(stdin, "{l}").unwrap();
    }
    drop(stdin); // yarp rpc stops at end of input
    let mut stdout = child.stdout.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = stdout.read_to_string(&mut s);
        s
    });
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > T {
            let _ = child.kill();
            let _ = child.wait();
            panic!("C++ yarp rpc did not finish");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    reader
        .join()
        .unwrap()
        .lines()
        .filter(|l| l.starts_with("Response:"))
        .map(str::to_string)
        .collect()
}

#[tokio::test]
async fn cpp_yarp_rpc_queries_the_robot() {
    let Some(yarp) = cpp_yarp() else {
        return;
    };
    assert!(Registry::names().contains(&"controlBoard_nws_yarp"));
    let net = start_network().await;
    let fixtures =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/fixtures/robotinterface");
    // the fixture names a device type no build has: only --keep-going goes past it
    let mut child = Child::spawn(
        BIN,
        &["--config", "robot_fake.xml", "--keep-going"],
        &fixtures,
        Some(net.conf_home.path()),
    );
    let ri = "/robot/yarprobotinterface";
    wait_reply(&net.client, ri, "is_ready", "[ok]", &mut child).await;

    let home = net.conf_home.path().to_path_buf();
    let y = yarp.clone();
    let got = tokio::task::spawn_blocking(move || {
        cpp_rpc(
            &y,
            &home,
            ri,
            &["is_ready", "get_robot", "get_phase", "get_level"],
        )
    })
    .await
    .unwrap();
    assert_eq!(
        got,
        [
            "Response: [ok]",
            "Response: fakeRobot",
            "Response: run",
            "Response: 0"
        ]
    );

    let home = net.conf_home.path().to_path_buf();
    let got = tokio::task::spawn_blocking(move || {
        cpp_rpc(&yarp, &home, "/robot/part/rpc:i", &["[get] [axes]"])
    })
    .await
    .unwrap();
    assert_eq!(got.len(), 1);
    assert!(got[0].starts_with("Response: [is] [axes] 4"), "{got:?}");

    child.signal("INT");
    let status = child.wait_exit(T).await;
    assert_eq!(status.and_then(|s| s.code()), Some(0), "{}", child.output());
}

/// C++ `yarprobotinterface` 3.12.3 on the same fixture stops at the device type it lacks
/// (PolyDriver's "Could not find device"), as ours does without `--keep-going`.
#[tokio::test]
async fn cpp_yarprobotinterface_stops_at_a_device_type_it_lacks_as_ours_does() {
    let Some(cpp) = yarp_interop_tests::cpp_program("robotinterface_cpp", "yarprobotinterface")
    else {
        return;
    };
    let net = start_network().await;
    let fixtures =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/fixtures/robotinterface");
    let home = net.conf_home.path().to_path_buf();
    let (status, text) = tokio::task::spawn_blocking(move || {
        let mut cmd = yarp_interop_tests::cpp_command(&cpp);
        cmd.args(["--config", "robot_fake.xml"])
            .current_dir(&fixtures)
            .env("YARP_CONFIG_HOME", &home);
        let mut p = yarp_interop_tests::Proc::spawn("C++ yarprobotinterface", cmd);
        let start = Instant::now();
        let status = loop {
            if let Some(s) = p.child.try_wait().ok().flatten() {
                break Some(s);
            }
            if start.elapsed() > T {
                break None;
            }
            std::thread::sleep(Duration::from_millis(20));
        };
        // the reader threads deliver what is left once the pipes close
        let _ = p.try_wait_line("\u{0}", Duration::from_millis(300));
        (status, p.seen.join("\n"))
    })
    .await
    .unwrap();
    assert!(
        status.is_some_and(|s| !s.success()),
        "C++ went past the missing type ({status:?}):\n{text}"
    );
    assert!(
        text.contains("Could not find device <notARealDeviceType>")
            && text.contains("One or more devices failed opening"),
        "{text}"
    );
    // only that one: C++ found its own plugins
    assert!(
        !text.contains("Could not find device <fakeMotionControl>"),
        "{text}"
    );
}
