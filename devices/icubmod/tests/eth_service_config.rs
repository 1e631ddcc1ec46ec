//! The `verifyactivate` configurations built from the robots' unmodified files, byte for
//! byte as icub-main builds them (`ServiceParser::parseService`,
//! `embObjMotionControl::saveCouplingsData`, `EmbObjSkin::fromConfig`; offsets within
//! `eOmn_serv_config_data_t`, bytes C++ leaves uninitialised expected zero).

mod robot_files;
use icub_eth::entities::mn::service_type;
use icubmod::eth::config::Node;
use icubmod::eth::service_config::{
    can_location, mc_config, q17_14, sensor_config, strain_temperature_config,
};
use robot_files::{device_file, robot_devices};
use yarp_proto::Property;

/// The sensor service data of `file` (type `stype`).
fn sensor(robot: &str, file: &str, stype: u8) -> Vec<u8> {
    let p = device_file(robot, file);
    sensor_config(&Node::root(&p), stype).unwrap_or_else(|e| panic!("{file}: {e}"))
}

#[test]
fn strain_of_the_icub_genova02_left_arm() {
    // eobrd_strain (6), firmware 0.0.0, protocol 1.0, CAN2:13 with inside index none
    let d = sensor(
        "iCubGenova02",
        "hardware/FT/left_arm-eb1-j0_3-strain.xml",
        service_type::AS_STRAIN,
    );
    assert_eq!(d, [0x06, 0, 0, 0, 1, 0, 0x5B]);
}

#[test]
fn temperature_of_the_icub_genova02_left_foot_strain2() {
    // embObjFTsensor's second service (temperature-acquisitionRate 1000), as icub-main's
    // fillTemperatureEthServiceInfo builds it from the strain service
    let p = device_file("iCubGenova02", "hardware/FT/left_leg-eb7-j4_5-strain.xml");
    let d = strain_temperature_config(&Node::root(&p)).unwrap();
    let none = [0xFE, 0, 0, 0, 0, 0];
    let mut want = Vec::new();
    // eOas_temperature_setof_boardinfos_t: slots mtb4, strain2, mtb4c, strain2c; the
    // strain2 (12), firmware 2.0.9, protocol 2.0, in its slot
    want.extend(none);
    want.extend([12, 2, 0, 9, 2, 0]);
    want.extend(none);
    want.extend(none);
    // eOas_temperature_arrayof_descriptors_t: capacity 7, items of 4 bytes, one item:
    // strain2, CAN2:13 with place can (0x6D), eoas_temperature_t1 (15)
    want.extend([7, 4, 1, 0]);
    want.extend([12, 0x6D, 15, 0]);
    want.extend([0; 24]);
    assert_eq!(d.len(), 56);
    assert_eq!(d, want);
    // a plain strain has no temperature sensor: named, as C++ refuses it
    let arm = device_file("iCubGenova02", "hardware/FT/left_arm-eb1-j0_3-strain.xml");
    let e = strain_temperature_config(&Node::root(&arm))
        .unwrap_err()
        .to_string();
    assert!(e.contains("temperature"), "{e}");
}

#[test]
fn inertials_of_the_ergocub_left_arm() {
    // Board infos by slot (strain2 in slot 2, the others none 0xFE), then five sensors
    // on the strain2 at CAN2:13 (place can: 0x6D): acc, gyr, eul, mag, status.
    let d = sensor(
        "ergoCubSN001",
        "hardware/inertials/left_arm-eb2-j0_1-inertial.xml",
        service_type::AS_INERTIALS3,
    );
    let mut want = Vec::new();
    for slot in 0..6 {
        want.extend([if slot == 2 { 0x0C } else { 0xFE }, 0, 0, 0, 0, 0]);
    }
    want.extend([32, 4, 5, 0]);
    for kind in [7, 9, 10, 8, 14] {
        want.extend([0x0C, 0x6D, kind, 0]);
    }
    assert_eq!(d, want);
}

#[test]
fn ft_of_ergocub_in_the_order_of_their_ids() {
    // CAN monitor: check every 100 ms, report ALL, every 20000 ms; one strain2 at CAN2:13
    // (versions zero: CANBOARDS names strain2c, and C++ leaves them so)
    let d = sensor(
        "ergoCubSN001",
        "hardware/FT/left_arm-eb2-j0_1-strain.xml",
        service_type::AS_FT,
    );
    let mut want = vec![
        0x64, 0x03, 0x20, 0x4E, 4, 8, 1, 0, 0x0C, 0, 0, 0, 0, 0, 0x5B, 0,
    ];
    want.resize(40, 0);
    assert_eq!(d, want);
    // two sensors: l_foot_front_ft (strain2c 2.3.0 / 2.0 at CAN2:14) before l_foot_rear_ft
    let d = sensor(
        "ergoCubSN001",
        "hardware/FT/left_leg-eb9-j4_5-strain.xml",
        service_type::AS_FT,
    );
    let mut want = vec![
        0x64, 0x03, 0x20, 0x4E, 4, 8, 2, 0, 0x16, 2, 3, 0, 2, 0, 0x5D, 0, 0x0C, 0, 0, 0, 0, 0,
        0x5B, 0,
    ];
    want.resize(40, 0);
    assert_eq!(d, want);
}

#[test]
fn skin_patches_and_pos_sensors() {
    // iCubGenova02 right leg: MTB, patch 1 (1..7) on CAN1, patch 2 (8..13) on CAN2
    let d = sensor(
        "iCubGenova02",
        "hardware/skin/right_leg-eb11-skin.xml",
        service_type::SK_SKIN,
    );
    let mut want = vec![5, 0, 0, 0, 0, 0, 2, 0, 0xFE, 0, 0, 0, 0, 0, 0, 0x3F];
    want.resize(24, 0);
    assert_eq!(d, want);
    // ergoCubSN001 left arm: no SERVICE group (an MTB with no version), one patch on CAN2
    let d = sensor(
        "ergoCubSN001",
        "hardware/skin/left_arm-eb4-j2_3-skin.xml",
        service_type::SK_SKIN,
    );
    let mut want = vec![5, 0, 0, 0, 0, 0, 1, 0, 0, 0, 4, 0];
    want.resize(24, 0);
    assert_eq!(d, want);
    // ergoCubSN001 left hand pos2: mtb4c 0.0.0 / 2.0 at CAN1:2; thumb adduction on
    // J3_SDA2 (port 4), index adduction on J3_SDA3 (port 6), both enabled
    let d = sensor(
        "ergoCubSN001",
        "hardware/POS/left_hand-pos2.xml",
        service_type::AS_POS,
    );
    let mut want = vec![
        0x14, 0, 0, 0, 2, 0, 0x04, 0, 0x20, 0x14, 0, 0, 0x30, 0x16, 0, 0,
    ];
    want.resize(24, 0);
    assert_eq!(d, want);
}

fn device(robot: &str, top: &str, name: &str) -> Property {
    let devices = robot_devices(robot, top);
    let d = devices
        .iter()
        .find(|d| d.name == name)
        .unwrap_or_else(|| panic!("no device {name}"));
    d.to_property().unwrap()
}

/// 340 zero bytes with `(offset, bytes)` written in.
fn expected(parts: &[(usize, &[u8])]) -> Vec<u8> {
    let mut v = vec![0u8; 340];
    for (at, b) in parts {
        v[*at..*at + b.len()].copy_from_slice(b);
    }
    v
}

const ONE: &[u8] = &[0x00, 0x40, 0x00, 0x00]; // 1.0 in q17.14

#[test]
fn q17_14_truncates_through_f32_as_the_firmware_library() {
    assert_eq!(q17_14(1.0), 0x4000);
    assert_eq!(q17_14(0.615), 0x275C);
    assert_eq!(q17_14(-0.615), -0x275C);
    assert_eq!(q17_14(-1.625), -26624);
    assert_eq!(q17_14(1e9), i32::MAX);
}

#[test]
fn can_locations_as_cpp_reads_them() {
    let l = can_location("CAN1:1:0").unwrap();
    assert_eq!(
        (l.port, l.addr, l.inside_index, l.to_byte()),
        (0, 1, 0, 0x02)
    );
    let l = can_location("CAN2:13").unwrap();
    assert_eq!((l.port, l.addr), (1, 13));
    for bad in ["CAN3:1", "CAN1:15", "CAN1:0", "CAN1:1:2", "CONN:P6", "CAN1"] {
        assert!(can_location(bad).is_none(), "{bad}");
    }
}

/// iCubGenova02 `left_arm-eb1-j0_3`: 2FOC boards behind an EMS4, the coupled shoulder.
#[test]
fn icub_genova02_left_arm_foc_service() {
    let p = device("iCubGenova02", "icub_all.xml", "left_arm-eb1-j0_3-mc");
    let data = mc_config(&p, service_type::MC_FOC, 4).unwrap_or_else(|e| panic!("{e}"));
    let jsetcfg: &[u8] = &[0x02, 0x55, 0xD5];
    let want = expected(&[
        // version (firmware 3.3.3, protocol 1.6), CAN board type foc (8)
        (0, &[3, 3, 3, 1, 6]),
        (5, &[8]),
        // EOarray head: capacity 4, item size 5, 4 items; then actuator (CAN1:n:0),
        // encoder1 aea at P6/P7/P8/P9 at joint, encoder2 roie (not local) at motor
        (8, &[4, 5, 4, 0]),
        (12, &[0x02, 0x01, 0x20, 0x02, 0x5D]),
        (17, &[0x04, 0x01, 0x23, 0x02, 0x5D]),
        (22, &[0x06, 0x01, 0x21, 0x02, 0x5D]),
        (27, &[0x08, 0x01, 0x24, 0x02, 0x5D]),
        // joint2set: {0 1 2} {3}; both sets: motor speed feedback, pwm outputs, current PID
        (32, &[0, 0, 0, 1]),
        (36, jsetcfg),
        (52, jsetcfg),
        // joint2motor (from 100), motor2joint (from 164), encoder2joint (from 228)
        (100, ONE),
        (116, &[0x00, 0x98, 0xFF, 0xFF]),
        (120, &[0x00, 0x68, 0x00, 0x00]),
        (140, &[0x00, 0x68, 0x00, 0x00]),
        (160, ONE),
        (164, ONE),
        (180, ONE),
        (184, &[0x5C, 0x27, 0x00, 0x00]),
        (200, &[0xA4, 0xD8, 0xFF, 0xFF]),
        (204, &[0x5C, 0x27, 0x00, 0x00]),
        (224, ONE),
        (228, ONE),
        (256, ONE),
        (284, ONE),
        (312, ONE),
    ]);
    assert_eq!(data, want);
}

/// ergoCubSN001 `left_arm-eb31-j4_6`: the AMC wrist (advfoc, ergoCub wrist constraint).
#[test]
fn ergocub_left_wrist_advfoc_service() {
    let p = device("ergoCubSN001", "ergocub.xml", "left_arm-eb31-j4_6-mc");
    let data = mc_config(&p, service_type::MC_ADVFOC, 3).unwrap_or_else(|e| panic!("{e}"));
    let want = expected(&[
        // head: capacity 4, item size 16, 3 items
        (0, &[4, 16, 3, 0]),
        // advfoc on CAN1:1..3, amcbldc (18) / amc2c (21) firmware 0.0.0 protocol 2.0;
        // encoder1 aea3 on J5_X1..3 at joint; encoder2 none at motor
        (
            4,
            &[4, 0x10, 18, 0, 0, 0, 2, 0, 0x0C, 0x20, 0, 0, 0, 0x5F, 0, 0],
        ),
        (
            20,
            &[4, 0x20, 18, 0, 0, 0, 2, 0, 0x0C, 0x21, 0, 0, 0, 0x5F, 0, 0],
        ),
        (
            36,
            &[4, 0x30, 21, 0, 0, 0, 2, 0, 0x0C, 0x22, 0, 0, 0, 0x5F, 0, 0],
        ),
        // coupling: traditional 4x4; one set of three joints, current outputs, the
        // ergoCub wrist constraint (4) with param1 21.0
        (72, &[0, 0, 0, 0xFF]),
        (
            76,
            &[0x00, 0xFC, 0xDF, 0, 4, 0, 0, 0, 0x00, 0x00, 0xA8, 0x41],
        ),
        (140, ONE),
        (160, ONE),
        (180, ONE),
        (200, ONE),
        (204, ONE),
        (224, ONE),
        (244, ONE),
        (264, ONE),
        (268, ONE),
        (288, ONE),
        (308, ONE),
        (328, ONE),
    ]);
    assert_eq!(data, want);
}

/// Every motion-control device of both robots gets a configuration, and one with a
/// wrong string is refused naming the parameter.
#[test]
fn every_mc_service_of_both_robots_builds() {
    for (robot, top) in [
        ("iCubGenova02", "icub_all.xml"),
        ("ergoCubSN001", "ergocub.xml"),
    ] {
        let mut n = 0;
        for d in robot_devices(robot, top)
            .iter()
            .filter(|d| d.kind == "embObjMotionControl")
        {
            let p = d.to_property().unwrap();
            let mc = icubmod::eth::mc_params::McParams::read(&p).unwrap();
            let data = mc_config(&p, mc.service.service_type, mc.joints)
                .unwrap_or_else(|e| panic!("{robot} {}: {e}", d.name));
            assert_eq!(data.len(), 340);
            n += 1;
        }
        assert!(n >= 8, "{robot}: {n} motion-control devices");
    }
    let p = device("iCubGenova02", "icub_all.xml", "left_arm-eb1-j0_3-mc");
    let text = p.to_string().replace("eomc_enc_aea", "eomc_enc_zzz");
    let e = mc_config(&Property::from_text(&text), service_type::MC_FOC, 4).unwrap_err();
    assert!(
        e.to_string().contains("ENCODER1/type") && e.to_string().contains("zzz"),
        "{e}"
    );
}

#[test]
fn skin_spec_of_the_icub_genova02_left_hand_and_its_commands() {
    use icub_eth::Entity;
    use icubmod::eth::skin_spec::{self, SkinSpec};
    let p = device_file("iCubGenova02", "hardware/skin/left_arm-eb2-j4_15-skin.xml");
    let spec = SkinSpec::read(&Node::root(&p))
        .unwrap()
        .expect("new-style skinSpec");
    // defaultCfgBoard: period 50, skinType 0, noLoad 0xf0; defaultCfgTriangle: disabled,
    // shift 2, cdcOffset 0x2200
    let boards = skin_spec::default_boards(&spec.board).to_bytes();
    assert_eq!(boards, [0xFF, 0xFF, 0xFF, 0xFF, 0, 50, 0xF0, 0]);
    let triangles = skin_spec::default_triangles(&spec.triangle).to_bytes();
    assert_eq!(
        triangles,
        [0xFF, 0xFF, 0xFF, 0xFF, 0, 15, 0, 0, 0, 0, 0, 0, 0, 2, 0x00, 0x22]
    );
    assert_eq!(spec.special_boards.len(), 1);
    assert_eq!(spec.special_triangles.len(), 20);
    // the patch on CAN2 (patch 2): MTB addresses 14 13 12 11 10 9 8
    let addrs = [14, 13, 12, 11, 10, 9, 8];
    // boardSetCfg1: 2 14 14 50 1 0xf0 -> CAN2 bit 14, palm skin type 1
    let b = skin_spec::special_boards(&spec.special_boards[0], 2, &addrs).unwrap();
    assert_eq!(b.to_bytes(), [0, 0, 0x00, 0x40, 1, 50, 0xF0, 0]);
    // triangleSetCfg1: 2 14 0 6 1 0 0x2000
    let t = skin_spec::special_triangles(&spec.special_triangles[0], 2, &addrs).unwrap();
    assert_eq!(
        t.to_bytes(),
        [0, 0, 0x00, 0x40, 0, 6, 0, 0, 0, 0, 0, 0, 1, 0, 0x00, 0x20]
    );
    // a board that is not on the patch is refused, naming it
    let mut wrong = spec.special_triangles[0];
    wrong.addr = 3;
    let e = skin_spec::special_triangles(&wrong, 2, &addrs)
        .unwrap_err()
        .to_string();
    assert!(e.contains("address 3"), "{e}");
}
