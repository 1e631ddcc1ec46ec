//! The real `yarpdev` binary as a child process (under netns-run): `--list`, help, the
//! unknown-device and no-network errors, and a served device (deviceBundler, `--from`,
//! `--subdevice`) that stops cleanly on SIGINT, SIGTERM or a message on `<name>/quit`.

#[path = "../../tests/fixtures/robotinterface/live_support.rs"]
mod support;

use support::*;
use yarp_devices::Registry;

const BIN: &str = env!("CARGO_BIN_EXE_yarpdev");

fn wrapper_registered() -> bool {
    let ok = Registry::names().contains(&"controlBoard_nws_yarp");
    if !ok {
        eprintln!("SKIPPED: controlBoard_nws_yarp is not a registered device yet");
    }
    ok
}

async fn run_to_exit(args: &[&str], conf_home: Option<&std::path::Path>) -> (Option<i32>, String) {
    let cwd = std::env::temp_dir();
    let mut child = Child::spawn(BIN, args, &cwd, conf_home);
    let status = child.wait_exit(T).await;
    (status.and_then(|s| s.code()), child.output())
}

#[tokio::test]
async fn list_prints_every_registered_device_in_cpp_form() {
    let (code, out) = run_to_exit(&["--list"], None).await;
    assert_eq!(code, Some(0), "{out}");
    assert!(
        out.contains("[INFO] |yarp.dev.Drivers| Here are devices listed for your system:"),
        "{out}"
    );
    yarp_device_programs::register_all();
    for entry in Registry::entries() {
        let line = out
            .lines()
            .find(|l| l.contains(&format!("Device \"{}\", C++ class ", entry.name)))
            .unwrap_or_else(|| panic!("{} missing:\n{out}", entry.name));
        assert!(
            line.ends_with(&format!("(found in crate {})", entry.provider)),
            "{line}"
        );
    }
    assert!(
        out.contains("Device \"fakeMotionControl\", C++ class FakeMotionControl, wrapped by \"controlBoard_nws_yarp\" (found in crate yarp-devices)"),
        "{out}"
    );
    assert!(
        out.contains("Device \"canmotioncontrol\", C++ class unknown, has no network wrapper (found in crate icubmod)"),
        "{out}"
    );
    // issue 16's lasers, cameras and mobile bases, ROS 2 wrappers and their fakes
    for name in [
        "fakeLaser",
        "fakeDepthCamera",
        "fakeBattery",
        "fakeOdometry2D",
        "fakeNavigation",
        "rangefinder2D_nws_ros2",
        "rangefinder2D_nwc_ros2",
        "imu_nwc_ros2",
        "rgbdSensor_nwc_ros2",
        "frameTransformGet_nwc_ros2",
        "frameTransformSet_nwc_ros2",
        "frameGrabber_nws_ros2",
        "rgbdSensor_nws_ros2",
        "rgbdToPointCloudSensor_nws_ros2",
        "battery_nws_ros2",
        "odometry2D_nws_ros2",
        "mobileBaseVelocityControl_nws_ros2",
    ] {
        assert!(
            out.contains(&format!("Device \"{name}\", C++ class ")),
            "{name}:\n{out}"
        );
    }
    assert!(
        out.contains("Device \"fakeLaser\", C++ class FakeLaser, wrapped by \"rangefinder2D_nws_yarp\" (found in crate yarp-devices)\n[INFO] |yarp.dev.Drivers|     sensor: IRangefinder2D\n"),
        "{out}"
    );
    // each device's kind and interfaces follow C++'s line
    assert!(
        out.contains("Device \"test_motor\", C++ class TestMotor, wrapped by \"controlBoard_nws_yarp\" (found in crate yarp-devices)\n[INFO] |yarp.dev.Drivers|     motor: IEncodersTimed, IPositionControl, IVelocityControl\n"),
        "{out}"
    );
}

#[tokio::test]
async fn no_device_prints_help_and_exits_zero() {
    let (code, out) = run_to_exit(&[], None).await;
    assert_eq!(code, Some(0), "{out}");
    assert!(
        out.contains("Welcome to yarpdev") && out.contains("Device name not specified"),
        "{out}"
    );
}

#[tokio::test]
async fn unknown_device_lists_closest_names_and_fails() {
    let net = start_network().await;
    let (code, out) = run_to_exit(
        &["--device", "fakeMotionControll", "--name", "/x"],
        Some(net.conf_home.path()),
    )
    .await;
    assert_eq!(code, Some(1), "{out}");
    assert!(out.contains("device not available"), "{out}");
    assert!(
        out.contains("+ Suggestions:") && out.contains("fakeMotionControl"),
        "{out}"
    );
}

#[tokio::test]
async fn no_name_server_is_an_error() {
    let (code, out) = run_to_exit(&["--device", "fakeMotionControl"], None).await;
    assert_eq!(code, Some(255), "{out}");
    assert!(out.contains("YARP network not available"), "{out}");
}

#[tokio::test]
async fn unreadable_from_file_is_an_error() {
    let (code, out) = run_to_exit(&["--from", "/nonexistent/board.ini"], None).await;
    assert_eq!(code, Some(1), "{out}");
    assert!(out.contains("/nonexistent/board.ini"), "{out}");
}

/// Starts yarpdev with `args`, checks `/<prefix>/rpc:i` reports `axes` joints, then stops
/// it with `stop` and checks the clean exit.
async fn serve_and_stop(args: &[&str], prefix: &str, axes: usize, stop: &str) {
    let net = start_network().await;
    let cwd = tempfile::tempdir().unwrap();
    std::fs::write(
        cwd.path().join("board.ini"),
        "device deviceBundler\nwrapper_device controlBoard_nws_yarp\nattached_device fakeMotionControl\n[GENERAL]\nJoints 5\n",
    )
    .unwrap();
    let mut child = Child::spawn(BIN, args, cwd.path(), Some(net.conf_home.path()));
    let want = format!("[is] [axes] {axes}");
    let rpc = format!("{prefix}/rpc:i");
    wait_reply(&net.client, &rpc, "[get] [axes]", &want, &mut child).await;
    match stop {
        "quit" => {
            let quit = format!("{prefix}/quit");
            send_line(&net.client, &quit, "quit", &mut child).await;
        }
        sig => child.signal(sig),
    }
    let status = child.wait_exit(T).await;
    let out = child.output();
    assert_eq!(status.and_then(|s| s.code()), Some(0), "output:\n{out}");
    assert!(child.is_gone());
    assert!(out.contains("yarpdev is finished."), "{out}");
}

#[tokio::test]
async fn bundler_serves_until_sigint() {
    if wrapper_registered() {
        let args = [
            "--device",
            "deviceBundler",
            "--wrapper_device",
            "controlBoard_nws_yarp",
            "--attached_device",
            "fakeMotionControl",
            "--name",
            "/yd",
            "--GENERAL::Joints",
            "3",
        ];
        serve_and_stop(&args, "/yd", 3, "INT").await;
    }
}

#[tokio::test]
async fn from_file_with_command_line_override_until_sigterm() {
    if wrapper_registered() {
        serve_and_stop(&["--from", "board.ini", "--name", "/yf"], "/yf", 5, "TERM").await;
    }
}

#[tokio::test]
async fn subdevice_form_stops_on_quit_port() {
    if wrapper_registered() {
        let args = [
            "--device",
            "controlBoard_nws_yarp",
            "--subdevice",
            "fakeMotionControl",
            "--name",
            "/ys",
            "--GENERAL::Joints",
            "2",
        ];
        serve_and_stop(&args, "/ys", 2, "quit").await;
    }
}

#[tokio::test]
async fn from_file_is_found_in_a_context_directory() {
    if !wrapper_registered() {
        return;
    }
    let net = start_network().await;
    let data = tempfile::tempdir().unwrap();
    let ctx = data.path().join("contexts/fakeBoards");
    std::fs::create_dir_all(&ctx).unwrap();
    std::fs::write(
        ctx.join("board.ini"),
        "device deviceBundler\nwrapper_device controlBoard_nws_yarp\nattached_device fakeMotionControl\nname /yc\n[GENERAL]\nJoints 6\n",
    )
    .unwrap();
    let cwd = tempfile::tempdir().unwrap();
    let mut child = Child::spawn_env(
        BIN,
        &["--context", "fakeBoards", "--from", "board.ini"],
        cwd.path(),
        Some(net.conf_home.path()),
        &[("YARP_DATA_DIRS", data.path())],
    );
    wait_reply(
        &net.client,
        "/yc/rpc:i",
        "[get] [axes]",
        "[is] [axes] 6",
        &mut child,
    )
    .await;
    child.signal("INT");
    let status = child.wait_exit(T).await;
    assert_eq!(status.and_then(|s| s.code()), Some(0), "{}", child.output());
}
