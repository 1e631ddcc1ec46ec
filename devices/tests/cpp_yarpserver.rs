//! Our devices registered with C++ YARP's `yarpserver` (3.12.3, from
//! `tests/peers/install-cpp-peers.sh icub`): our `controlBoard_nws_yarp` answers C++ `yarp
//! rpc` and a C++ `fakeMotionControl` (behind C++'s wrapper in C++ `yarprobotinterface`,
//! see `cpp_device_command`) answers our `remote_controlboard`, every port
//! found through the C++ name server. (C++ devices under our name server: the other
//! `*_cpp` tests, whose name server is ours.) Without the C++ peer the tests say SKIPPED
//! loudly; in CI they fail. Run under netns-run.

use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::{Duration, Instant};
use yarp_devices::PolyDriver;
use yarp_interop_tests::{cpp_command, Reaped, T};
use yarp_proto::Property;

/// The C++ bin directory with the devices `devices`, and the C++ name server running.
fn setup(test: &str, devices: &[&str]) -> Option<PathBuf> {
    let bin = yarp_interop_tests::cpp_devices(test, devices)?;
    yarp_interop_tests::cpp_yarpserver(&bin);
    Some(bin)
}

/// Whether the C++ name server knows `port` (asked with C++ `yarp exists`).
fn known(bin: &Path, port: &str) -> bool {
    cpp_command(&bin.join("yarp"))
        .args(["exists", port])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

#[test]
fn our_wrapper_under_cpp_yarpserver_answers_cpp_yarp_rpc() {
    let Some(bin) = setup(
        "our_wrapper_under_cpp_yarpserver_answers_cpp_yarp_rpc",
        &["controlBoard_nws_yarp"],
    ) else {
        return;
    };
    let mut nws = PolyDriver::open(
        &Property::from_config_text(
            "device controlBoard_nws_yarp\nsubdevice fakeMotionControl\nname /under_cpp\n\
             [GENERAL]\njoints 2\n",
        )
        .unwrap(),
    )
    .expect("our wrapper registers with the C++ name server");
    assert!(known(&bin, "/under_cpp/rpc:i"));
    let out = yarp_interop_tests::cpp_rpc_output(
        &bin.join("yarp"),
        "/under_cpp/rpc:i",
        "[get] [axes]\n[set] [pos] 1 7.0\n[get] [pos] 1\n",
    );
    let lines: Vec<&str> = out.lines().filter(|l| l.starts_with("Response")).collect();
    assert_eq!(lines.len(), 3, "{out}");
    assert!(
        lines[0].starts_with("Response: [is] [axes] 2 [tsta] "),
        "{out}"
    );
    assert_eq!(lines[1], "Response: [ok]");
    assert!(
        lines[2].starts_with("Response: [is] [pos] 7.0 [tsta] "),
        "{out}"
    );
    nws.close().unwrap();
}

#[test]
fn cpp_yarpdev_under_cpp_yarpserver_answers_our_remote() {
    let Some(bin) = setup(
        "cpp_yarpdev_under_cpp_yarpserver_answers_our_remote",
        &["controlBoard_nws_yarp", "fakeMotionControl"],
    ) else {
        return;
    };
    let (mut cmd, xml) = yarp_interop_tests::cpp_device_command(
        &bin,
        &[
            "--device",
            "controlBoard_nws_yarp",
            "--subdevice",
            "fakeMotionControl",
            "--name",
            "/cpp_under_cpp",
            "--GENERAL::Joints",
            "3",
        ],
    );
    let log = tempfile::NamedTempFile::new().unwrap();
    let _dev = Reaped(
        cmd.stdin(Stdio::null())
            .stdout(log.reopen().unwrap())
            .stderr(log.reopen().unwrap())
            .spawn()
            .expect("spawn C++ yarprobotinterface"),
    );
    // registered, and attached (the wrapper's ports come before the end of the startup)
    let start = Instant::now();
    while !known(&bin, "/cpp_under_cpp/stateExt:o")
        || !std::fs::read_to_string(log.path()).is_ok_and(|t| t.contains("startup phase finished"))
    {
        assert!(
            start.elapsed() < T,
            "C++ yarprobotinterface did not start: {}",
            std::fs::read_to_string(log.path()).unwrap_or_default()
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    if let Some(xml) = xml {
        let _ = std::fs::remove_file(xml);
    }
    let mut remote = PolyDriver::open(
        &Property::from_config_text(
            "device remote_controlboard\nremote /cpp_under_cpp\nlocal /ours_under_cpp\n",
        )
        .unwrap(),
    )
    .expect("our remote finds C++ through the C++ name server");
    let d = remote.device();
    assert_eq!(d.as_encoders().unwrap().get_axes().unwrap(), 3);
    let pos = d.as_position_control().unwrap();
    pos.position_move(2, 4.0).unwrap();
    assert_eq!(pos.get_target_position(2).unwrap(), 4.0);
    remote.close().unwrap();
}
