//! The robot's own addresses, without any address map: inside the private network
//! namespace of netns-run the test gives the boards' and the host's 10.0.1.x addresses
//! to loopback (`ip addr add`, only there), the emulator serves iCubGenova02's left arm
//! boards at 10.0.1.1 and 10.0.1.2 and `embObjMotionControl` reaches them from
//! 10.0.1.104:12345 (pc104.xml). A board whose firmware speaks another motion-control
//! protocol version is refused, naming both versions, as C++ does.

use std::net::Ipv4Addr;
use std::path::PathBuf;
use std::process::Command;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use icub_emulators::eth::AddressMap;
use icub_emulators::eth::{robot_boards, serve};
use icub_eth::entities::mn::{versions, Version};
use icubmod::eth::EmbObjMotionControl;
use yarp_devices::robotinterface::read_robot_file;
use yarp_devices::DeviceDriver;
use yarp_proto::Property;

/// Adds `ip/24` to loopback; false when not allowed (not inside netns-run).
fn add_address(ip: &str) -> bool {
    Command::new("ip")
        .args(["addr", "add", &format!("{ip}/24"), "dev", "lo"])
        .status()
        .is_ok_and(|s| s.success())
}

#[test]
fn left_arm_on_the_robots_own_addresses_and_a_protocol_mismatch() {
    if std::env::var("NETNS_RUN_INSIDE").as_deref() != Ok("1") {
        assert!(
            std::env::var("CI").is_err(),
            "run under ../shared/netns-run"
        );
        eprintln!("\n*** SKIPPED: not inside netns-run (the test adds addresses to lo) ***\n");
        return;
    }
    for ip in ["10.0.1.104", "10.0.1.1", "10.0.1.2", "10.0.1.3"] {
        assert!(add_address(ip), "ip addr add {ip}/24 dev lo");
    }
    std::env::remove_var(icub_emulators::eth::ADDRESS_MAP_ENV);
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/robots-configuration/iCubGenova02");
    let top = dir.join("icub_all.xml");
    let mut specs: Vec<_> = robot_boards(&dir, Some(&top))
        .unwrap()
        .into_iter()
        .filter(|s| s.params.ip.octets()[3] <= 3)
        .collect();
    // eb3 (right arm) runs a firmware with motion-control protocol 1.99.
    let old = Version::new(versions::MC.major, 99);
    for s in specs.iter_mut() {
        if s.params.ip == Ipv4Addr::new(10, 0, 1, 3) {
            s.protocol = Some([versions::MN, old, versions::AS, versions::SK]);
        }
    }
    let (served, _threads) = serve(
        specs,
        &AddressMap::default(),
        Arc::new(AtomicBool::new(false)),
    )
    .expect("the emulator binds 10.0.1.x");
    assert!(served
        .iter()
        .any(|b| b.local.ip() == &Ipv4Addr::new(10, 0, 1, 1)));

    let robot = read_robot_file(&top, &Property::default()).unwrap().robot;
    let cfg = |name: &str| robot.device(name).unwrap().to_property().unwrap();
    let mut eb1 = EmbObjMotionControl::new();
    eb1.open(&cfg("left_arm-eb1-j0_3-mc"))
        .expect("eb1 at 10.0.1.1 opens");
    let mut eb2 = EmbObjMotionControl::new();
    eb2.open(&cfg("left_arm-eb2-j4_15-mc"))
        .expect("eb2 at 10.0.1.2 opens");
    assert_eq!(eb2.as_encoders().unwrap().get_axes().unwrap(), 12);

    let mut eb3 = EmbObjMotionControl::new();
    let e = eb3
        .open(&cfg("right_arm-eb3-j0_3-mc"))
        .expect_err("a board with another protocol version is refused")
        .to_string();
    eprintln!("{e}");
    assert!(
        e.contains("right_arm-eb3-j0_3") && e.contains("10.0.1.3"),
        "{e}"
    );
    assert!(
        e.contains(&old.to_string()) && e.contains(&versions::MC.to_string()),
        "both versions named: {e}"
    );
}
