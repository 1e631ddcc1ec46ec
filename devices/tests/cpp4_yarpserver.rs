//! Ours under C++ YARP 4.0.0's `yarpserver` (tests/peers/install-cpp-peers.sh yarp4): our
//! wrapper registers with it and answers C++ 4.0's `yarp rpc` on `/nws/rpc:i`, and our
//! `controlBoard_nwc_yarp` finds C++ 4.0's wrapper through it. (C++ 4.0 under our name
//! server: `controlboard_cpp4.rs`.) Run under netns-run.

use std::process::Stdio;
use std::time::{Duration, Instant};
use yarp_devices::PolyDriver;
use yarp_interop_tests::{cpp4_program, cpp_command, cpp_device_command, Reaped, T};
use yarp_proto::Property;

#[test]
fn ours_under_cpp_4_yarpserver_both_ways() {
    let Some(yarp) = cpp4_program("ours_under_cpp_4_yarpserver_both_ways", "yarp") else {
        return;
    };
    let bin = yarp.parent().unwrap().to_path_buf();
    yarp_interop_tests::cpp_yarpserver(&bin);
    // our wrapper, found and called by C++ 4.0's `yarp rpc`
    let mut nws = PolyDriver::open(
        &Property::from_config_text(
            "device controlBoard_nws_yarp\nsubdevice fakeMotionControl\nname /ours_u4\n\
             [GENERAL]\njoints 2\n",
        )
        .unwrap(),
    )
    .expect("our wrapper registers with C++ 4.0's name server");
    let out = yarp_interop_tests::cpp_rpc_output(
        &yarp,
        "/ours_u4/nws/rpc:i",
        "getAxesRPC\npositionMoveOneRPC 1 7.0\ngetTargetPositionOneRPC 1\n",
    );
    let lines: Vec<&str> = out.lines().filter(|l| l.starts_with("Response")).collect();
    assert_eq!(
        lines,
        [
            "Response: ([ok]) 2",
            "Response: [ok]",
            "Response: ([ok]) 7.0"
        ],
        "{out}"
    );
    nws.close().unwrap();
    // C++ 4.0's wrapper, found by our client
    let (mut cmd, _xml) = cpp_device_command(
        &bin,
        &[
            "--device",
            "controlBoard_nws_yarp",
            "--subdevice",
            "fakeMotionControl",
            "--name",
            "/cpp_u4",
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
            .expect("spawn C++ 4.0 yarprobotinterface"),
    );
    let known = |port: &str| {
        cpp_command(&yarp)
            .args(["exists", port])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success())
    };
    let start = Instant::now();
    while !known("/cpp_u4/stateExt:o")
        || !std::fs::read_to_string(log.path()).is_ok_and(|t| t.contains("startup phase finished"))
    {
        assert!(
            start.elapsed() < T,
            "C++ 4.0 yarprobotinterface did not start: {}",
            std::fs::read_to_string(log.path()).unwrap_or_default()
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let mut remote = PolyDriver::open(
        &Property::from_config_text(
            "device controlBoard_nwc_yarp\nremote /cpp_u4\nlocal /ours_c4\n",
        )
        .unwrap(),
    )
    .expect("our client finds C++ 4.0's wrapper through C++ 4.0's name server");
    let d = remote.device();
    assert_eq!(d.as_encoders().unwrap().get_axes().unwrap(), 3);
    d.as_position_control()
        .unwrap()
        .position_move(2, 4.5)
        .unwrap();
    assert_eq!(
        d.as_position_control()
            .unwrap()
            .get_target_position(2)
            .unwrap(),
        4.5
    );
    remote.close().unwrap();
}
