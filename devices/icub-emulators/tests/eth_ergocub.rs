//! ergoCubSN001, unmodified from robots-configuration, against the emulated Ethernet
//! boards on loopback (address map 10.0.1.0/24 -> 127.0.2.0/24, so that it may run beside
//! the iCub test): the left arm's boards of three types (EMS4, AMC, MC4plus) open and
//! move, a motor's PT100 temperature reads in °C, its F/T sensor (FT service) and its IMU
//! (inertials3) stream.

use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::{Duration, Instant};

use icub_emulators::eth::{robot_boards, serve};
use icub_emulators::eth::{AddressMap, ADDRESS_MAP_ENV};
use icubmod::eth::{EmbObjImu, EmbObjMotionControl, EmbObjMultipleFtSensors};
use yarp_devices::robotinterface::read_robot_file;
use yarp_devices::vocabs::CM_POSITION;
use yarp_devices::DeviceDriver;
use yarp_proto::Property;

const MAP: &str = "10.0.1.0/24=127.0.2.0/24";

fn wait_for(what: &str, timeout: Duration, mut f: impl FnMut() -> bool) {
    let start = Instant::now();
    while !f() {
        assert!(start.elapsed() < timeout, "{what}: not within {timeout:?}");
        std::thread::sleep(Duration::from_millis(10));
    }
}

#[test]
fn ergocub_left_arm_boards_ft_and_imu() {
    std::env::set_var(ADDRESS_MAP_ENV, MAP);
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/robots-configuration/ergoCubSN001");
    let top = dir.join("ergocub.xml");
    let specs = robot_boards(&dir, None).expect("robot boards");
    assert_eq!(specs.len(), 17, "ergoCubSN001 has 17 Ethernet boards");
    let stop = Arc::new(AtomicBool::new(false));
    let (_served, _threads) =
        serve(specs, &AddressMap::parse(MAP).unwrap(), stop).expect("the emulator binds 127.0.2.x");
    let robot = read_robot_file(&top, &Property::default())
        .expect("ergocub.xml")
        .robot;
    let cfg = |name: &str| robot.device(name).expect(name).to_property().unwrap();

    let mut boards = Vec::new();
    for name in [
        "left_arm-eb2-j0_1-mc",
        "left_arm-eb4-j2_3-mc",
        "left_arm-eb31-j4_6-mc",
        "left_arm-eb23-j7_10-mc",
        "left_arm-eb25-j11_12-mc",
    ] {
        let mut mc = EmbObjMotionControl::new();
        mc.open(&cfg(name))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        boards.push(mc);
    }
    let axes: usize = boards
        .iter_mut()
        .map(|b| b.as_encoders().unwrap().get_axes().unwrap())
        .sum();
    assert_eq!(axes, 2 + 2 + 3 + 4 + 2);

    // eb2's shoulder roll has a PT100 (TemperatureSensorType NONE PT100): the board
    // reports its sensor's raw reading (439 for the emulated motor at 35 °C), read in °C
    // through C++'s PT100 formula (35.02 °C); the shoulder pitch has none: NaN (C++).
    let eb2 = &mut boards[0];
    wait_for("a motor temperature", Duration::from_secs(2), || {
        let t = eb2.as_motor().unwrap().get_temperature(1).unwrap();
        (t - 35.0).abs() < 0.1
    });
    assert!(eb2.as_motor().unwrap().get_temperature(0).unwrap().is_nan());
    // the warning limit (warningTemperatureLimits 90)
    assert_eq!(
        eb2.as_motor().unwrap().get_temperature_limit(1).unwrap(),
        90.0
    );

    // An AMC joint (eb31) moves.
    let amc = &mut boards[2];
    amc.as_control_mode()
        .unwrap()
        .set_control_mode(0, CM_POSITION)
        .unwrap();
    amc.as_position_control()
        .unwrap()
        .set_ref_speed(0, 100.0)
        .unwrap();
    amc.as_position_control()
        .unwrap()
        .position_move(0, 10.0)
        .unwrap();
    wait_for("eb31 joint 0 at 10 deg", Duration::from_secs(5), || {
        (amc.as_encoders().unwrap().get_encoder(0).unwrap() - 10.0).abs() < 0.5
    });

    let mut ft = EmbObjMultipleFtSensors::new();
    ft.open(&cfg("left_arm-eb2-j0_1-strain")).expect("FT opens");
    assert_eq!(
        ft.as_six_axis_force_torque_sensors()
            .unwrap()
            .get_six_axis_force_torque_sensor_name(0)
            .unwrap(),
        "l_arm_ft"
    );
    wait_for("an F/T reading", Duration::from_secs(2), || {
        ft.as_six_axis_force_torque_sensors()
            .unwrap()
            .get_six_axis_force_torque_sensor_measure(0)
            .is_ok_and(|m| (m.values[2] - 9.81).abs() < 0.01)
    });

    // A foot's two sensors: the board's order is C++'s map by id (front before rear,
    // although the file enables rear first), each with its own settings.
    let mut foot = EmbObjMultipleFtSensors::new();
    foot.open(&cfg("left_leg-eb9-j4_5-strain"))
        .expect("the foot's FT opens");
    let f = foot.as_six_axis_force_torque_sensors().unwrap();
    assert_eq!(f.get_nr_of_six_axis_force_torque_sensors(), 2);
    assert_eq!(
        f.get_six_axis_force_torque_sensor_name(0).unwrap(),
        "l_foot_front_ft"
    );
    assert_eq!(
        f.get_six_axis_force_torque_sensor_name(1).unwrap(),
        "l_foot_rear_ft"
    );
    // no SENSORS/framename in the file: empty, as C++
    assert_eq!(
        f.get_six_axis_force_torque_sensor_frame_name(1).unwrap(),
        ""
    );
    foot.close().unwrap();

    let mut imu = EmbObjImu::new("embObjIMU");
    imu.open(&cfg("left_arm-eb2-j0_1-inertial"))
        .expect("IMU opens");
    wait_for("an accelerometer reading", Duration::from_secs(2), || {
        imu.as_three_axis_linear_accelerometers()
            .unwrap()
            .get_three_axis_linear_accelerometer_measure(0)
            .is_ok_and(|m| (m.values[2] - 9.81).abs() < 0.01)
    });
    assert_eq!(
        imu.as_three_axis_gyroscopes()
            .unwrap()
            .get_three_axis_gyroscope_name(0)
            .unwrap(),
        "l_arm_ft_imu"
    );
}
