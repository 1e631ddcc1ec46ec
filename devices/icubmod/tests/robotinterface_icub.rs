//! Loads the real iCubGenova01 robots-configuration (every XML file reachable from
//! `icub_all.xml` through `xi:include`) and checks the devices, params and actions, then
//! dry-runs every phase so that each action's target is resolved.

use std::collections::BTreeMap;
use std::path::PathBuf;
use yarp_devices::robotinterface::model::find_param;
use yarp_devices::robotinterface::{
    read_robot_file, ActionPhase, ActionType, DeviceFactory, Robot, RobotRunner,
};
use yarp_devices::{DevResult, DeviceError, PolyDriver};
use yarp_proto::{Property, Value};

fn icub_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/robots-configuration/iCubGenova01")
}

fn load(file: &str) -> Option<Robot> {
    let path = icub_dir().join(file);
    if !path.exists() {
        eprintln!("SKIPPED: {} not found", path.display());
        return None;
    }
    let loaded = read_robot_file(&path, &Property::new()).unwrap_or_else(|e| panic!("{e}"));
    Some(loaded.robot)
}

fn type_counts(robot: &Robot) -> BTreeMap<&str, usize> {
    let mut types: BTreeMap<&str, usize> = BTreeMap::new();
    for d in &robot.devices {
        *types.entry(d.kind.as_str()).or_default() += 1;
    }
    types
}

#[test]
fn icub_all_device_types() {
    yarp_devices::Registry::install(icubmod::register);
    let Some(robot) = load("icub_all.xml") else {
        return;
    };
    assert_eq!(robot.name, "iCubGenova01");
    assert_eq!(robot.portprefix, "/icub");
    assert_eq!(robot.build, 0);
    assert_eq!(robot.devices.len(), 66);
    let expected: BTreeMap<&str, usize> = [
        ("analogServer", 2),
        ("canBusAnalogSensor", 2),
        ("canBusFtSensor", 6),
        ("canBusSkin", 3),
        ("canBusVirtualAnalogSensor", 5),
        ("canmotioncontrol", 8),
        ("cartesiancontrollerserver", 2),
        ("controlBoard_nws_yarp", 6),
        ("controlboardremapper", 6),
        ("imuFilter", 1),
        ("multipleanalogsensorsremapper", 2),
        ("multipleanalogsensorsserver", 6),
        ("parametricCalibrator", 8),
        ("skinWrapper", 3),
        ("virtualAnalogServer", 5),
        ("xsensmtx", 1),
    ]
    .into_iter()
    .collect();
    assert_eq!(type_counts(&robot), expected);
    // Device names are unique and every device's params convert to a Property.
    let mut names: Vec<&str> = robot.devices.iter().map(|d| d.name.as_str()).collect();
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), 66);
    for d in &robot.devices {
        let p = d.to_property().unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(p.find("robotName").and_then(|v| v.as_str()), Some("/icub"));
        assert!(d.at.file.ends_with(".xml"), "{}", d.at);
    }
}

#[test]
fn icub_all_params_convert_like_cpp() {
    yarp_devices::Registry::install(icubmod::register);
    let Some(robot) = load("icub_all.xml") else {
        return;
    };
    let mc = robot.device("left_arm_mc").unwrap();
    assert!(mc
        .at
        .file
        .ends_with("hardware/motorControl/icub_left_arm.xml"));
    let p = mc.to_property().unwrap();
    assert_eq!(
        p.find("device").and_then(|v| v.as_str()),
        Some("canmotioncontrol")
    );
    assert_eq!(p.find("id").and_then(|v| v.as_str()), Some("left_arm_mc"));
    let general = p.find_group("GENERAL").unwrap();
    // from the device file and, merged in, from the included general.xml
    assert_eq!(general.find("Joints").and_then(|v| v.as_i64()), Some(8));
    // `false` reads as the boolean vocab, as in C++
    let skip = general.find("skipCalibration").map(|v| v.to_string());
    assert_eq!(skip.as_deref(), Some("false"));
    let axis = general.find_group("AxisName").unwrap();
    assert_eq!(axis.len(), 9);
    assert_eq!(
        axis.get(1).and_then(|v| v.as_str()),
        Some("l_shoulder_pitch")
    );
    let can = p.find_group("CAN").unwrap();
    assert_eq!(can.find("CanAddresses").unwrap().to_string(), "1");
    assert_eq!(can.find_group("CanAddresses").unwrap().len(), 5);
    let zeros = general.find_group("Zeros").unwrap();
    assert_eq!(zeros.get(1).and_then(|v| v.as_f64()), Some(-179.73));

    let nws = robot.device("left_arm_mc_nws_yarp").unwrap();
    let p = nws.to_property().unwrap();
    assert_eq!(
        p.find("name").and_then(|v| v.as_str()),
        Some("/icub/left_arm")
    );
    assert_eq!(p.find("period").and_then(|v| v.as_f64()), Some(0.01));
    let attach = &nws.actions[0];
    assert_eq!(
        (attach.phase, attach.kind, attach.level),
        (ActionPhase::Startup, ActionType::Attach, 10)
    );
    assert_eq!(
        find_param(&attach.params, "device"),
        Some("left_arm_mc_remapper")
    );

    let remap = robot.device("left_arm_mc_remapper").unwrap();
    let p = remap.to_property().unwrap();
    let networks = p.find("networks").and_then(|v| v.as_list()).unwrap();
    assert_eq!(networks.to_string(), "left_arm_joints left_hand_joints");
    assert_eq!(
        p.find("left_hand_joints").unwrap(),
        &Value::List(yarp_proto::Bottle::from_text("8 15 0 7"))
    );
    assert_eq!(p.find("joints").and_then(|v| v.as_i64()), Some(16));

    let calib = robot.device("left_arm_calibrator").unwrap();
    let p = calib.to_property().unwrap();
    assert_eq!(
        p.find_group("CALIB_ORDER").unwrap().to_string(),
        "CALIB_ORDER (0 1 2 3) (4 6 7) (5)"
    );

    let cart = robot
        .device("left_arm_cartesian")
        .unwrap()
        .to_property()
        .unwrap();
    let plant = cart.find_group("PLANT_MODEL").unwrap();
    let j0 = plant.find("joint_0").and_then(|v| v.as_list()).unwrap();
    assert_eq!(j0.find("Kp").and_then(|v| v.as_f64()), Some(1.022));
}

#[test]
fn icub_all_phases_and_levels() {
    yarp_devices::Registry::install(icubmod::register);
    let Some(robot) = load("icub_all.xml") else {
        return;
    };
    let count = |phase, kind| {
        robot
            .devices
            .iter()
            .flat_map(|d| &d.actions)
            .filter(|a| a.phase == phase && a.kind == kind)
            .count()
    };
    assert_eq!(count(ActionPhase::Startup, ActionType::Calibrate), 8);
    assert_eq!(count(ActionPhase::Interrupt1, ActionType::Park), 8);
    assert_eq!(count(ActionPhase::Interrupt3, ActionType::Abort), 8);
    let attaches = count(ActionPhase::Startup, ActionType::Attach);
    let detaches = count(ActionPhase::Shutdown, ActionType::Detach);
    assert_eq!(attaches, detaches);
    assert_eq!(attaches, 33);
    assert_eq!(robot.levels(ActionPhase::Startup), [5, 6, 10, 15, 20]);
    assert_eq!(robot.actions(ActionPhase::Startup, 5).len(), 22);
    assert_eq!(robot.levels(ActionPhase::Interrupt1), [1]);
    assert_eq!(robot.levels(ActionPhase::Shutdown), [5, 6, 15, 20]);
    assert_eq!(robot.actions(ActionPhase::Shutdown, 5).len(), 16);
}

/// Knows every type; never opens anything (the runner is in dry-run mode).
struct KnowsAll;

impl DeviceFactory for KnowsAll {
    fn knows(&self, _: &str) -> bool {
        true
    }
    fn open(&self, _: &Property) -> DevResult<PolyDriver> {
        Err(DeviceError::Unsupported("dry run"))
    }
}

#[test]
fn icub_all_dry_run_resolves_every_target() {
    yarp_devices::Registry::install(icubmod::register);
    let Some(robot) = load("icub_all.xml") else {
        return;
    };
    let mut runner = RobotRunner::with_factory(robot, Box::new(KnowsAll));
    runner.set_dryrun(true);
    for phase in [
        ActionPhase::Startup,
        ActionPhase::Run,
        ActionPhase::Interrupt1,
        ActionPhase::Interrupt2,
        ActionPhase::Interrupt3,
        ActionPhase::Shutdown,
    ] {
        runner.enter_phase(phase).unwrap_or_else(|e| panic!("{e}"));
    }
}

#[test]
fn icub_all_reports_unavailable_types_by_name() {
    yarp_devices::Registry::install(icubmod::register);
    let Some(robot) = load("icub_all.xml") else {
        return;
    };
    let names = yarp_devices::Registry::names();
    let expected: Vec<(&str, &str)> = robot
        .devices
        .iter()
        .filter(|d| !names.contains(&d.kind.as_str()))
        .map(|d| (d.name.as_str(), d.kind.as_str()))
        .collect();
    let runner = RobotRunner::new(robot.clone());
    // exactly the devices whose type this build lacks, by device name, in file order
    assert_eq!(runner.unavailable_devices(), expected);
    println!("not available in this build: {expected:?}");
}

#[test]
fn other_icub_robot_files_load() {
    yarp_devices::Registry::install(icubmod::register);
    for (file, devices) in [
        ("icub_all_no_legs.xml", 46),
        ("icub_analog_only.xml", 35),
        ("icub.xml", 66),
    ] {
        let Some(robot) = load(file) else { return };
        println!(
            "{file}: {} devices {:?}",
            robot.devices.len(),
            type_counts(&robot)
        );
        assert_eq!(robot.devices.len(), devices, "{file}");
    }
}
