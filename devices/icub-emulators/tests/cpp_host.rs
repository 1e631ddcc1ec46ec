//! icub-main's Ethernet host against our board emulator: C++ `yarprobotinterface` of YARP
//! 3.12.3 with icub-main 2.11.1's embObj plugins (`tests/peers/install-cpp-peers.sh icub`)
//! brings a robot of robots-configuration up, unmodified, on the robot's own 10.0.1.x
//! addresses in a network namespace of the test's own; `icub-eth-emulator` serves every
//! board there. Every embObj device opens and verifies its board and every part calibrates
//! (the C++ host's "startup phase finished."), C++ `yarp rpc` moves a joint of each arm
//! and C++ `yarp read` sees it on `state:o`, the sensors' streams reach C++ `yarp read`,
//! and Ctrl-C parks and closes.
//!
//! Where the C++ host refuses what the emulator accepts, the emulator is wrong: these tests
//! are the real host's word on our boards.

mod hosts_common;

use hosts_common::*;

#[test]
fn icub_genova02_under_the_cpp_host() {
    let dir = robots().join("iCubGenova02");
    let Some(mut r) = bring_up(BringUp {
        test: "icub_genova02_under_the_cpp_host",
        host: Host::Cpp,
        robot: &dir,
        xml: "icub_all.xml",
        record: None,
    }) else {
        return;
    };
    // The only errors: icub-main's own reading of the hands' boards' joint sets (the
    // boards drive joints 4-15 in one set; its eomcParser reports set 0 empty), which it
    // prints on the real robot too.
    let errors = r.errors();
    assert!(
        errors
            .iter()
            .all(|e| e.contains("Jointsset  0 hasn't joints")),
        "C++ host errors at start-up:\n{}",
        errors.join("\n")
    );
    r.move_joint("/icub", "left_arm", 0, -20.0);
    r.move_joint("/icub", "right_arm", 0, -20.0);
    // (iCubGenova02's icub_all.xml has its head IMUs commented out: ergoCub's test reads one)
    for (port, what) in [
        ("/icub/left_arm/FT/measures:o", "F/T"),
        ("/icub/left_hand/MAIS/measures:o", "MAIS"),
        // C++ skinWrapper prefixes the robot's portprefix with a '/' of its own
        ("//icub/skin/left_hand", "skin"),
    ] {
        let line = r
            .net
            .read_until("/test/sensor:i", port, |l| !l.trim().is_empty());
        eprintln!("{what} {port}: {}", &line[..line.len().min(120)]);
    }
    r.interrupt();
}

/// ergoCubSN001 without its waist Xsens MTi and `wholebodydynamics`
/// ([`ergocub_without_xsens_and_wbd`]).
#[test]
fn ergocub_sn001_under_the_cpp_host() {
    let (_copy, dir) = ergocub_without_xsens_and_wbd();
    let Some(mut r) = bring_up(BringUp {
        test: "ergocub_sn001_under_the_cpp_host",
        host: Host::Cpp,
        robot: &dir,
        xml: "ergocub.xml",
        record: None,
    }) else {
        return;
    };
    // The only errors: the arms' joint 0 never reaches its startupPosition (34) because
    // the robot's own file keeps it below jntPosMax 14 (left_arm-eb2-j0_1-mc.xml and the
    // right arm's); a board holds references inside the user limits, so the joint stops at
    // 14 and C++ idles it after its go-to-zero timeout, as it would on the robot.
    let errors = r.errors();
    assert!(
        errors.iter().all(|e| (e.contains("Left_Arm_Calibrator")
            || e.contains("Right_Arm_Calibrator"))
            && (e.contains("joint  0 ") || e.contains("joint #  0 ") || e.contains("set 4 "))),
        "C++ host errors at start-up:\n{}",
        errors.join("\n")
    );
    r.move_joint("/ergocub", "left_arm", 1, 55.0);
    r.move_joint("/ergocub", "right_arm", 1, 55.0);
    for (port, what) in [
        ("/ergocub/left_arm/FT/measures:o", "F/T"),
        ("/ergocub/left_arm/imu/measures:o", "IMU"),
    ] {
        let line = r
            .net
            .read_until("/test/sensor:i", port, |l| !l.trim().is_empty());
        eprintln!("{what} {port}: {}", &line[..line.len().min(120)]);
    }
    r.interrupt();
}
