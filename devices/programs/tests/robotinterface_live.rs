//! The real `yarprobotinterface` binary as a child process (under netns-run): brings up
//! the fixture robot (fakeMotionControl served by controlBoard_nws_yarp), answers RPC on
//! `/robot/part/rpc:i`, names the device type it lacks (and stops there, as C++, unless
//! told `--keep-going`), reports readiness on `/robot/yarprobotinterface`, and shuts down
//! cleanly on SIGINT, SIGTERM or RPC `quit`.

#[path = "../../tests/fixtures/robotinterface/live_support.rs"]
mod support;

use std::path::PathBuf;
use support::*;
use yarp_devices::Registry;

const BIN: &str = env!("CARGO_BIN_EXE_yarprobotinterface");

fn fixtures() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/fixtures/robotinterface")
}

fn wrapper_registered() -> bool {
    let ok = Registry::names().contains(&"controlBoard_nws_yarp");
    if !ok {
        eprintln!("SKIPPED: controlBoard_nws_yarp is not a registered device yet");
    }
    ok
}

async fn bring_up(signal: &str) {
    let net = start_network().await;
    // the fixture names a device type no build has: only --keep-going goes past it
    let mut child = Child::spawn(
        BIN,
        &["--config", "robot_fake.xml", "--keep-going"],
        &fixtures(),
        Some(net.conf_home.path()),
    );
    // ready once the startup phase (with the attach at level 10) is over
    let ri = "/robot/yarprobotinterface";
    wait_reply(&net.client, ri, "is_ready", "[ok]", &mut child).await;
    assert_eq!(
        ask(&net.client, ri, "get_robot", &mut child).await,
        "fakeRobot"
    );
    assert_eq!(ask(&net.client, ri, "get_phase", &mut child).await, "run");

    let part = "/robot/part/rpc:i";
    let reply = ask(&net.client, part, "[get] [axes]", &mut child).await;
    assert!(reply.starts_with("[is] [axes] 4"), "{reply}");
    assert!(reply.ends_with("[ok]"), "{reply}");
    let reply = ask(&net.client, part, "[set] [pos] 0 10.0", &mut child).await;
    assert_eq!(reply, "[ok]");

    // the wrapper whose target is missing still opened its ports, unattached
    wait_port(&net.client, "/robot/mystery/rpc:i", &mut child).await;

    if signal == "quit" {
        assert_eq!(ask(&net.client, ri, "quit", &mut child).await, "bye");
    } else {
        child.signal(signal);
    }
    let status = child.wait_exit(T).await;
    let out = child.output();
    assert_eq!(status.and_then(|s| s.code()), Some(0), "output:\n{out}");
    assert!(child.is_gone());
    assert!(
        out.contains("mystery") && out.contains("notARealDeviceType"),
        "unknown type not named:\n{out}"
    );
    for line in [
        "startup phase finished",
        "interrupt1 phase finished",
        "Closing device part_mc",
        "shutdown phase finished",
    ] {
        assert!(out.contains(line), "missing {line:?} in:\n{out}");
    }
    // wrappers close before the device they serve (reverse order)
    let nws = out.find("Closing device part_nws").expect("nws closed");
    let mc = out.find("Closing device part_mc").expect("mc closed");
    assert!(nws < mc, "{out}");
}

#[tokio::test]
async fn fake_robot_serves_rpc_and_stops_on_sigint() {
    if wrapper_registered() {
        bring_up("INT").await;
    }
}

#[tokio::test]
async fn fake_robot_stops_on_sigterm() {
    if wrapper_registered() {
        bring_up("TERM").await;
    }
}

#[tokio::test]
async fn fake_robot_stops_on_rpc_quit() {
    if wrapper_registered() {
        bring_up("quit").await;
    }
}

#[tokio::test]
async fn missing_config_and_bad_xml_fail_with_a_message() {
    let net = start_network().await;
    let mut child = Child::spawn(BIN, &[], &fixtures(), Some(net.conf_home.path()));
    let status = child.wait_exit(T).await;
    assert_eq!(status.and_then(|s| s.code()), Some(1));
    assert!(
        child.output().contains("Missing \"config\" argument"),
        "{}",
        child.output()
    );

    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("bad.xml"),
        "<robot name=\"r\">\n<device name=\"d\">\n</device>\n</robot>\n",
    )
    .unwrap();
    let mut child = Child::spawn(
        BIN,
        &["--config", "bad.xml"],
        dir.path(),
        Some(net.conf_home.path()),
    );
    let status = child.wait_exit(T).await;
    let out = child.output();
    assert_eq!(status.and_then(|s| s.code()), Some(1), "{out}");
    assert!(
        out.contains("bad.xml:2") && out.contains("\"type\""),
        "{out}"
    );
}

#[tokio::test]
async fn a_device_type_not_in_the_build_stops_the_robot_as_in_cpp() {
    let net = start_network().await;
    let mut child = Child::spawn(
        BIN,
        &["--config", "robot_fake.xml"],
        &fixtures(),
        Some(net.conf_home.path()),
    );
    let status = child.wait_exit(T).await;
    let out = child.output();
    assert_eq!(status.and_then(|s| s.code()), Some(1), "{out}");
    assert!(
        out.contains("cannot open device mystery: could not find device <notARealDeviceType>"),
        "{out}"
    );
    // the devices it did open are closed again
    assert!(out.contains("Closing device part_mc"), "{out}");
}

#[tokio::test]
async fn dry_run_needs_no_network_and_reads_the_ini() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("yarprobotinterface.ini"),
        format!("config {}\n", fixtures().join("robot_fake.xml").display()),
    )
    .unwrap();
    let mut child = Child::spawn(
        BIN,
        &["--dryrun", "--portprefix", "/other"],
        dir.path(),
        None,
    );
    // startup in a dry run is quick; then it waits for a signal
    let deadline = std::time::Instant::now() + T;
    while !child.output().contains("running happily") {
        assert!(std::time::Instant::now() < deadline, "{}", child.output());
        assert!(!child.is_gone(), "{}", child.output());
        tokio::time::sleep(std::time::Duration::from_millis(50)).await;
    }
    child.signal("INT");
    let status = child.wait_exit(T).await;
    assert_eq!(status.and_then(|s| s.code()), Some(0), "{}", child.output());
}

#[tokio::test]
async fn finds_the_robot_directory_like_resource_finder() {
    // $YARP_DATA_DIRS/robots/$YARP_ROBOT_NAME/yarprobotinterface.ini names the robot file,
    // which is found next to it.
    let data = tempfile::tempdir().unwrap();
    let robot_dir = data.path().join("robots/fakeRobot");
    std::fs::create_dir_all(robot_dir.join("hardware")).unwrap();
    for f in ["robot_fake.xml", "general.xml", "hardware/part.xml"] {
        std::fs::copy(fixtures().join(f), robot_dir.join(f)).unwrap();
    }
    std::fs::write(
        robot_dir.join("yarprobotinterface.ini"),
        "config robot_fake.xml\n",
    )
    .unwrap();
    let cwd = tempfile::tempdir().unwrap();
    let mut child = Child::spawn_env(
        BIN,
        &["--dryrun"],
        cwd.path(),
        None,
        &[
            ("YARP_DATA_DIRS", data.path()),
            ("YARP_ROBOT_NAME", std::path::Path::new("fakeRobot")),
        ],
    );
    let deadline = std::time::Instant::now() + T;
    while !child.output().contains("running happily") {
        assert!(std::time::Instant::now() < deadline, "{}", child.output());
        assert!(!child.is_gone(), "{}", child.output());
        tokio::time::sleep(std::time::Duration::from_millis(50)).await;
    }
    assert!(
        child.output().contains("robots/fakeRobot/robot_fake.xml"),
        "{}",
        child.output()
    );
    child.signal("TERM");
    let status = child.wait_exit(T).await;
    assert_eq!(status.and_then(|s| s.code()), Some(0), "{}", child.output());
}

#[tokio::test]
async fn command_line_portprefix_moves_every_port() {
    if !wrapper_registered() {
        return;
    }
    let net = start_network().await;
    let mut child = Child::spawn(
        BIN,
        &[
            "--config",
            "robot_fake.xml",
            "--portprefix",
            "/other",
            "--keep-going",
        ],
        &fixtures(),
        Some(net.conf_home.path()),
    );
    // ${portprefix} in the wrapper's `name` and the service port both follow it
    wait_reply(
        &net.client,
        "/other/yarprobotinterface",
        "is_ready",
        "[ok]",
        &mut child,
    )
    .await;
    let reply = ask(&net.client, "/other/part/rpc:i", "[get] [axes]", &mut child).await;
    assert!(reply.starts_with("[is] [axes] 4"), "{reply}");
    child.signal("INT");
    let status = child.wait_exit(T).await;
    assert_eq!(status.and_then(|s| s.code()), Some(0), "{}", child.output());
}
