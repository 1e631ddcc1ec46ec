//! imuBosch_BNO055 against the emulated chip (icub_emulators::bno055) on a pseudo-terminal:
//! our device and C++ YARP 3.12.3's (from tests/peers/install-cpp-peers.sh icub; in CI
//! required), each on a chip of its own started together, read the same head: orientation
//! that agrees with the gravity each measures, the field in tesla, and each other's
//! readings within the motion of a few periods. The robots' parameter errors as C++'s.

use icub_emulators::bno055::{pty_link, Motion};
use std::time::Duration;
use yarp_devices::sensors::interfaces::SensorMeasurement;
use yarp_devices::PolyDriver;
use yarp_interop_tests::{name_client, wait_for};
use yarp_proto::Property;

fn open(cfg: &str) -> Result<PolyDriver, String> {
    PolyDriver::open(&Property::from_config_text(cfg).unwrap()).map_err(|e| e.to_string())
}

/// Orientation, acceleration, field (T) and rate of turn of an IMU.
struct Reading {
    rpy: Vec<f64>,
    acc: Vec<f64>,
    mag: Vec<f64>,
    gyro: Vec<f64>,
}

fn read(pd: &mut PolyDriver) -> Reading {
    let d = pd.device();
    let m = |r: yarp_devices::error::DevResult<SensorMeasurement>| r.expect("a measure").values;
    Reading {
        rpy: m(d
            .as_orientation_sensors()
            .unwrap()
            .get_orientation_sensor_measure_as_roll_pitch_yaw(0)),
        acc: m(d
            .as_three_axis_linear_accelerometers()
            .unwrap()
            .get_three_axis_linear_accelerometer_measure(0)),
        mag: m(d
            .as_three_axis_magnetometers()
            .unwrap()
            .get_three_axis_magnetometer_measure(0)),
        gyro: m(d
            .as_three_axis_gyroscopes()
            .unwrap()
            .get_three_axis_gyroscope_measure(0)),
    }
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// The reading is one head's: |g|, |field| in tesla, and roll/pitch that put gravity where
/// the accelerometer sees it (within the motion of a period or two: C++ converts the
/// quaternion of the cycle before).
fn check_consistent(r: &Reading, who: &str) {
    assert_eq!(
        (r.rpy.len(), r.acc.len(), r.mag.len(), r.gyro.len()),
        (3, 3, 3, 3),
        "{who}"
    );
    assert!(
        (norm(&r.acc) - 9.80665).abs() < 0.05,
        "{who}: |acc| {:?}",
        r.acc
    );
    let field = norm(&Motion::FIELD) * 1e-6;
    assert!(
        (norm(&r.mag) - field).abs() < 0.2e-6,
        "{who}: |mag| {:?}",
        r.mag
    );
    let roll = r.acc[1].atan2(r.acc[2]).to_degrees();
    let pitch = (-r.acc[0] / norm(&r.acc)).asin().to_degrees();
    assert!(
        (roll - r.rpy[0]).abs() < 0.5,
        "{who}: roll {} vs gravity's {roll}",
        r.rpy[0]
    );
    assert!(
        (pitch - r.rpy[1]).abs() < 0.5,
        "{who}: pitch {} vs gravity's {pitch}",
        r.rpy[1]
    );
    assert!(norm(&r.gyro) < 10.0, "{who}: gyro {:?}", r.gyro);
}

#[test]
fn our_device_reads_the_emulated_chip() {
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("ttyBNO");
    let (_chip, _pts) = pty_link(&link).unwrap();
    let mut imu = open(&format!(
        "device imuBosch_BNO055\ncomport \"  {}  \"\nperiod 10\nsensor_name head_imu\n",
        link.display()
    ))
    .expect("open on the emulated chip");
    // a few cycles after open: the orientation has left C++'s identity start
    std::thread::sleep(Duration::from_millis(100));
    let r = read(&mut imu);
    check_consistent(&r, "ours");
    let d = imu.device();
    let o = d.as_orientation_sensors().unwrap();
    assert_eq!(o.get_orientation_sensor_name(0).unwrap(), "head_imu");
    assert_eq!(
        o.get_orientation_sensor_frame_name(0).unwrap(),
        "sensor_imu_bosch_bno055"
    );
    assert!(o
        .get_orientation_sensor_measure_as_roll_pitch_yaw(1)
        .is_err());
    // IGenericSensor: rpy, acc, gyro, mag (µT)
    let mut v = Vec::new();
    let a = d.as_analog_sensor().unwrap();
    assert_eq!(
        a.read(&mut v),
        yarp_devices::sensors::interfaces::AnalogStatus::Ok
    );
    assert_eq!(v.len(), 12);
    assert!(
        (norm(&v[9..12]) - norm(&Motion::FIELD)).abs() < 0.2,
        "{v:?}"
    );
    imu.close().unwrap();
}

#[test]
fn parameters_and_a_missing_port_fail_as_cpp() {
    let e = open("device imuBosch_BNO055\n").err().unwrap();
    assert!(
        e.contains("At least one of the two must be specified"),
        "{e}"
    );
    let e = open("device imuBosch_BNO055\ncomport /dev/x\ni2c /dev/y\n")
        .err()
        .unwrap();
    assert!(e.contains("both specified"), "{e}");
    let e = open("device imuBosch_BNO055\ncomport /nonexistent/ttyUSB0\n")
        .err()
        .unwrap();
    assert!(e.contains("/nonexistent/ttyUSB0"), "{e}");
    let e = open("device imuBosch_BNO055\ni2c /nonexistent/i2c-1\n")
        .err()
        .unwrap();
    assert!(e.contains("/nonexistent/i2c-1"), "{e}");
}

#[test]
fn cpp_and_our_device_read_the_same_head() {
    let test = "cpp_and_our_device_read_the_same_head";
    let Some(bin) =
        yarp_interop_tests::cpp_devices(test, &["imuBosch_BNO055", "multipleanalogsensorsserver"])
    else {
        return;
    };
    name_client();
    let dir = tempfile::tempdir().unwrap();
    let (cpp_link, our_link) = (dir.path().join("ttyCPP"), dir.path().join("ttyOURS"));
    // two chips started together: the same motion at the same time
    let (_cpp_chip, _) = pty_link(&cpp_link).unwrap();
    let (_our_chip, _) = pty_link(&our_link).unwrap();
    let cpp_link = cpp_link.display().to_string();
    let _cpp = yarp_interop_tests::cpp_yarpdev(
        &bin,
        &[
            "--device",
            "multipleanalogsensorsserver",
            "--subdevice",
            "imuBosch_BNO055",
            "--comport",
            &cpp_link,
            "--name",
            "/cppbno",
            "--period",
            "10",
        ],
        "/cppbno/measures:o",
    );
    let mut cpp =
        open("device multipleanalogsensorsclient\nremote /cppbno\nlocal /cppbno_client\n")
            .expect("our client of C++'s server");
    let mut ours = open(&format!(
        "device imuBosch_BNO055\ncomport {}\nperiod 10\n",
        our_link.display()
    ))
    .expect("ours");
    // a few cycles: past C++'s identity start
    std::thread::sleep(Duration::from_millis(100));
    wait_for("C++'s first measures", || {
        let d = cpp.device();
        d.as_three_axis_linear_accelerometers()?
            .get_three_axis_linear_accelerometer_measure(0)
            .ok()
            .filter(|m| norm(&m.values) > 1.0)
    });
    for _ in 0..3 {
        let (c, o) = (read(&mut cpp), read(&mut ours));
        check_consistent(&c, "C++");
        check_consistent(&o, "ours");
        // the same head within the motion of a few periods and the client's delay
        for k in 0..3 {
            assert!(
                (c.rpy[k] - o.rpy[k]).abs() < 1.0,
                "rpy C++ {:?} ours {:?}",
                c.rpy,
                o.rpy
            );
            assert!(
                (c.acc[k] - o.acc[k]).abs() < 0.2,
                "acc C++ {:?} ours {:?}",
                c.acc,
                o.acc
            );
        }
        std::thread::sleep(Duration::from_millis(300));
    }
    eprintln!("interop: C++ imuBosch_BNO055 and ours read the emulated BNO055 alike");
    ours.close().unwrap();
    cpp.close().unwrap();
}
