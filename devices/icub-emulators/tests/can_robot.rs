//! The CAN layout read from robot files: iCubGenova01 and the shipped simulated iCub.

use std::path::{Path, PathBuf};

use icub_can::emulator::network::{self, BoardKind, NetworkSpec};
use icub_can::emulator::TorqueLink;
use icub_emulators::can_robot::{networks, robot_file};

fn genova() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/robots-configuration/iCubGenova01");
    if dir.exists() {
        return Some(dir);
    }
    assert!(
        std::env::var("CI").as_deref() != Ok("true"),
        "{} is missing",
        dir.display()
    );
    eprintln!("SKIPPED: {} is missing", dir.display());
    None
}

fn icub_sim() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../launch-configs/icub-sim/robot")
}

fn mc(net: &NetworkSpec, address: u8) -> ([f64; 2], [icub_can::emulator::JointPlant; 2]) {
    net.boards
        .iter()
        .find_map(|b| match b {
            BoardKind::Mc {
                address: a,
                initial,
                plants,
            } if *a == address => Some((*initial, *plants)),
            _ => None,
        })
        .unwrap_or_else(|| panic!("no motor board {address} on network {}", net.num))
}

fn of_kind(net: &NetworkSpec, f: impl Fn(&BoardKind) -> Option<u8>) -> Vec<u8> {
    let mut v: Vec<u8> = net.boards.iter().filter_map(f).collect();
    v.sort_unstable();
    v
}

#[test]
fn genova01_layout_comes_from_its_files() {
    let Some(dir) = genova() else { return };
    let nets = networks(&robot_file(&dir).unwrap()).unwrap();
    assert_eq!(
        nets.iter().map(|n| n.num).collect::<Vec<_>>(),
        (0..10).collect::<Vec<_>>()
    );
    let motor_boards: Vec<Vec<u8>> = nets
        .iter()
        .map(|n| {
            of_kind(n, |b| {
                matches!(b, BoardKind::Mc { .. }).then(|| match b {
                    BoardKind::Mc { address, .. } => *address,
                    _ => 0,
                })
            })
        })
        .collect();
    assert_eq!(
        motor_boards[..7],
        [
            vec![1, 2, 3, 5, 6],
            vec![1, 2, 3, 4],
            vec![1, 2, 3, 4],
            vec![5, 6, 7],
            vec![8, 9, 10],
            vec![5, 6, 7, 8],
            vec![5, 6, 7, 8]
        ]
    );
    let jts = |n: &NetworkSpec| {
        of_kind(n, |b| match b {
            BoardKind::JointTorque(a) => Some(*a),
            _ => None,
        })
    };
    assert_eq!(
        nets[..7].iter().map(jts).collect::<Vec<_>>(),
        [
            vec![12],
            vec![12],
            vec![12],
            vec![12],
            vec![11],
            vec![],
            vec![]
        ]
    );
    let strain = |n: &NetworkSpec| {
        of_kind(n, |b| match b {
            BoardKind::Strain(a) => Some(*a),
            _ => None,
        })
    };
    assert_eq!(strain(&nets[1]), [13]);
    assert_eq!(strain(&nets[3]), [1, 13]);
    assert_eq!(strain(&nets[4]), [1, 14]);
    assert!(nets[5].boards.contains(&BoardKind::Mais(14)));
    let skin = |n: &NetworkSpec| {
        of_kind(n, |b| match b {
            BoardKind::Skin(a) => Some(*a),
            _ => None,
        })
    };
    assert_eq!(skin(&nets[7]), (8..=14).collect::<Vec<u8>>());
    assert_eq!(skin(&nets[9]), [7, 8, 9, 10]);
    // The hand inertial (MTB 14) is the skin MTB at that address.
    assert!(!nets[7].boards.contains(&BoardKind::Mtb(14)));

    // Left arm joint 0 (board 1, axis 0): 0 deg clamped to [-95.5, 10] is 0 deg;
    // ticks = (0 + zero) * encoder = -179.73 * -11.375.
    let (initial, plants) = mc(&nets[1], 1);
    assert!(
        (initial[0] - (-179.73 * -11.375)).abs() < 1e-6,
        "{initial:?}"
    );
    // icub_left_arm.xml: TorqueId 0x0C, TorqueChan 0..4, TorqueMax 8 (2 for the wrist).
    let link = |ch| {
        Some(TorqueLink {
            address: 0x0C,
            channel: ch,
        })
    };
    assert_eq!((plants[0].sensor, plants[1].sensor), (link(0), link(1)));
    assert_eq!(plants[0].torque_max, 8.0);
    assert_eq!(plants[0].sensor_sign, Some(-1.0));
    let (_, wrist) = mc(&nets[1], 3);
    assert_eq!(wrist[0].sensor, link(4));
    assert_eq!(
        (wrist[0].torque_max, wrist[0].sensor_sign),
        (2.0, Some(1.0))
    );
    assert_eq!(wrist[1].sensor, None);
    // Left leg user joint 2 is axis 0 (AxisMap 2 3 0 1 4 5) on board 5.
    let (initial, _) = mc(&nets[3], 5);
    assert!((initial[0] - 172.8 * 11.375).abs() < 1e-6, "{initial:?}");
    for n in &nets {
        assert_eq!(network::build(n).len(), n.boards.len());
    }
}

#[test]
fn the_simulated_icub_has_genova01_boards() {
    let sim = networks(&robot_file(&icub_sim()).unwrap()).unwrap();
    assert_eq!(sim.len(), 10);
    let Some(dir) = genova() else { return };
    assert_eq!(sim, networks(&robot_file(&dir).unwrap()).unwrap());
}

#[test]
fn a_robot_without_files_or_can_devices_is_a_clear_error() {
    let tmp = tempfile::tempdir().unwrap();
    let e = robot_file(tmp.path()).unwrap_err().to_string();
    assert!(e.contains("no robot file"), "{e}");
    let file = tmp.path().join("icub_all.xml");
    std::fs::write(
        &file,
        "<?xml version=\"1.0\" encoding=\"UTF-8\" ?>\n<!DOCTYPE robot PUBLIC \"-//YARP//DTD yarprobotinterface 3.0//EN\" \"http://www.yarp.it/DTD/yarprobotinterfaceV3.0.dtd\">\n<robot name=\"r\" build=\"1\" portprefix=\"/r\" xmlns:xi=\"http://www.w3.org/2001/XInclude\">\n<devices><device name=\"f\" type=\"fakeMotionControl\"/></devices>\n</robot>\n",
    )
    .unwrap();
    let e = networks(&robot_file(tmp.path()).unwrap())
        .unwrap_err()
        .to_string();
    assert!(e.contains("no CAN device"), "{e}");
    std::fs::write(
        &file,
        "<?xml version=\"1.0\" encoding=\"UTF-8\" ?>\n<!DOCTYPE robot PUBLIC \"-//YARP//DTD yarprobotinterface 3.0//EN\" \"http://www.yarp.it/DTD/yarprobotinterfaceV3.0.dtd\">\n<robot name=\"r\" build=\"1\" portprefix=\"/r\" xmlns:xi=\"http://www.w3.org/2001/XInclude\">\n<devices><device name=\"ft\" type=\"canBusFtSensor\"><param name=\"canDeviceNum\">1</param></device></devices>\n</robot>\n",
    )
    .unwrap();
    let e = networks(&file).unwrap_err().to_string();
    assert!(e.contains("device ft") && e.contains("canAddress"), "{e}");
}
