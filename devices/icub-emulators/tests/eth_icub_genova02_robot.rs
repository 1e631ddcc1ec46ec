//! iCubGenova02 as a whole, unmodified from robots-configuration, brought up by the
//! robot-interface runner (`icub_all.xml`: wrappers, remappers, the embObj devices,
//! calibrators) against the emulated Ethernet boards, with an in-process name server
//! (run under netns-run; the boards are reached through the address map
//! 10.0.1.0/24 -> 127.0.3.0/24). Every device opens. Then our `yarp rpc`, and C++'s,
//! send `set pos` to `/icub/left_arm/rpc:i` and the joint is seen moving on
//! `/icub/left_arm/state:o`; remote homing, parking and calibration (`[set] [reca] …`)
//! reach the part's calibrator; our `yarp read` receives the left arm's F/T stream; the
//! Ctrl-C phases park the arms and close everything.

mod eth_common;

use std::io::Write;
use std::process::Command;
use std::time::Instant;

use eth_common::{bring_up, cpp_yarp, our_yarp, robot_dir, until_at, Peer, T};
use yarp_devices::robotinterface::ActionPhase;
use yarp_interop_tests::cpp_rpc_output;
use yarp_net::blocking::{BufferedPort, Network};

#[test]
fn icub_genova02_comes_up_and_moves_its_left_arm_by_yarp_rpc() {
    let dir = robot_dir("iCubGenova02");
    let (mut runner, _conf) = bring_up(&dir, &dir.join("icub_all.xml"), "10.0.1.0/24=127.0.3.0/24");
    assert!(
        runner.unavailable_devices().is_empty(),
        "{:?}",
        runner.unavailable_devices()
    );
    assert!(runner.failures().is_empty(), "{:?}", runner.failures());

    let net = Network::from_conf().expect("network");
    let state = BufferedPort::open(&net, "/test/left_arm/state:i").unwrap();
    net.connect("/icub/left_arm/state:o", "/test/left_arm/state:i", None)
        .expect("connect state:o");
    let joint0 = |timeout| -> Option<f64> {
        state
            .read_timeout(timeout)
            .and_then(|m| m.bottle.get(0).and_then(|v| v.as_f64()))
    };
    let q0 = joint0(T).expect("a state:o bottle");
    // Calibrated: l_shoulder_pitch at its startupPosition (-35.97).
    assert!((q0 + 35.97).abs() < 2.0, "joint 0 at {q0}");

    if let Some(yarp) = our_yarp() {
        let mut cmd = Command::new(&yarp);
        cmd.args(["rpc", "/icub/left_arm/rpc:i"]);
        let mut rpc = Peer::spawn(cmd);
        let sent = Instant::now();
        rpc.child
            .stdin
            .as_mut()
            .unwrap()
            .write_all(b"set pos 0 -20\n")
            .unwrap();
        let reply = rpc.line(T).expect("a reply from yarp rpc");
        assert!(reply.contains("[ok]"), "{reply}");
        let mut at = until_at("joint 0", &joint0, q0, -20.0);
        eprintln!("set pos 0 -20 seen on state:o after {:?}", sent.elapsed());
        // parametricCalibratorEth lowered joint 0's PWM limit to its startupMaxPwm (2000)
        // while calibrating, and gave the board's motorPwmLimit (10000) back once the
        // joint reached its startup position.
        rpc.child
            .stdin
            .as_mut()
            .unwrap()
            .write_all(b"get pwml 0\n")
            .unwrap();
        let reply = rpc.line(T).expect("a reply from yarp rpc");
        assert!(reply.contains("10000") && reply.contains("[ok]"), "{reply}");
        drop(rpc);

        // The same through C++ `yarp rpc` (the C++ peer; its absence fails under CI).
        if let Some(cpp) = cpp_yarp("icub_genova02 (C++ yarp rpc step)") {
            let sent = Instant::now();
            let out = cpp_rpc_output(&cpp, "/icub/left_arm/rpc:i", "set pos 0 -25\n");
            assert!(out.contains("[ok]"), "C++ yarp rpc: {out}");
            at = until_at("joint 0", &joint0, at, -25.0);
            eprintln!(
                "C++ yarp rpc: set pos 0 -25 seen on state:o after {:?}",
                sent.elapsed()
            );
        }

        // Remote calibration (yarpmotorgui's buttons): `[set] [reca] …` reaches the
        // part's parametricCalibratorEth. Homing sends the arm to its startup position;
        // a single-joint park moves joint 0 there too (as C++), waits, and idles it.
        let mut cmd = Command::new(&yarp);
        cmd.args(["rpc", "/icub/left_arm/rpc:i"]);
        let mut rpc = Peer::spawn(cmd);
        let mut ask = |line: &str| -> String {
            let stdin = rpc.child.stdin.as_mut().unwrap();
            stdin.write_all(format!("{line}\n").as_bytes()).unwrap();
            rpc.line(T)
                .unwrap_or_else(|| panic!("no reply to `{line}`"))
        };
        let reply = ask("set reca homs");
        assert!(reply.contains("[ok]"), "{reply}");
        let at = until_at("joint 0 homing", &joint0, at, -35.97);
        let reply = ask("set pos 0 -15");
        assert!(reply.contains("[ok]"), "{reply}");
        let at = until_at("joint 0", &joint0, at, -15.0);
        let reply = ask("set reca par 0");
        assert!(reply.contains("[ok]"), "{reply}");
        until_at("joint 0 parking", &joint0, at, -35.97);
        let reply = ask("get icmd cmod 0");
        assert!(
            reply.contains("idl"),
            "joint 0 idle after its park: {reply}"
        );
        // The whole part calibrated again (the parked joint with it), then parked: every
        // joint at HOME::positionHome (joint 0: -30) and idle.
        let reply = ask("set reca cals");
        assert!(reply.contains("[ok]"), "{reply}");
        let reply = ask("get icmd cmod 0");
        assert!(
            reply.contains("pos"),
            "joint 0 in position control again: {reply}"
        );
        let reply = ask("set reca pars");
        assert!(reply.contains("[ok]"), "{reply}");
        until_at("joint 0 parking the part", &joint0, -35.97, -30.0);
        let reply = ask("get icmd cmod 0");
        assert!(
            reply.contains("idl"),
            "joint 0 idle after the part's park: {reply}"
        );
        drop(rpc);

        let mut cmd = Command::new(&yarp);
        cmd.args(["read", "/test/ft:i", "/icub/left_arm/FT/measures:o"]);
        let reader = Peer::spawn(cmd);
        let line = reader.line(T).expect("a line from yarp read");
        eprintln!("yarp read /icub/left_arm/FT/measures:o: {line}");
        assert!(line.contains("199.9"), "fz of the emulated strain: {line}");
    }

    state.close();
    runner.enter_phase(ActionPhase::Interrupt1).unwrap();
    runner.enter_phase(ActionPhase::Shutdown).unwrap();
}
