//! What the Xsens device tests share: a still sensor's sample, bounded waits, closeness.

#![allow(dead_code)]

use icub_can::xsens::Sample;
use std::time::{Duration, Instant};

/// A sensor at rest, tilted a little: every field distinct, in the sensor's units.
pub fn still(_t: f64) -> Sample {
    Sample {
        acc: [0.5, -0.25, -9.75],
        gyr: [0.1, -0.2, 0.3],
        mag: [0.5, 0.0, 0.4],
        euler: [1.5, -2.5, 30.0],
    }
}

/// Polls `ok` every 10 ms until it holds or `timeout` passes; whether it held.
pub fn eventually(timeout: Duration, mut ok: impl FnMut() -> bool) -> bool {
    let end = Instant::now() + timeout;
    while Instant::now() < end {
        if ok() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    ok()
}

pub fn close(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-4)
}

/// The measures of a device reading [`still`], in YARP's units as C++ gives them: the
/// four MAS families (gyroscope in deg/s), each stamped with the wall clock, and the
/// 12-channel `IGenericSensor` read (roll pitch yaw, acc, gyro, mag).
pub fn assert_still_in_yarp_units(dev: &mut dyn yarp_devices::DeviceDriver) {
    let deg = 180.0 / std::f64::consts::PI;
    let gyro = dev
        .as_three_axis_gyroscopes()
        .unwrap()
        .get_three_axis_gyroscope_measure(0)
        .unwrap();
    assert!(
        close(&gyro.values, &[0.1 * deg, -0.2 * deg, 0.3 * deg]),
        "deg/s: {:?}",
        gyro.values
    );
    assert!(gyro.timestamp > 1e9, "a wall-clock stamp");
    let acc = dev
        .as_three_axis_linear_accelerometers()
        .unwrap()
        .get_three_axis_linear_accelerometer_measure(0)
        .unwrap();
    assert!(close(&acc.values, &[0.5, -0.25, -9.75]), "{:?}", acc.values);
    let rpy = dev
        .as_orientation_sensors()
        .unwrap()
        .get_orientation_sensor_measure_as_roll_pitch_yaw(0)
        .unwrap();
    assert!(close(&rpy.values, &[1.5, -2.5, 30.0]), "{:?}", rpy.values);
    let mag = dev
        .as_three_axis_magnetometers()
        .unwrap()
        .get_three_axis_magnetometer_measure(0)
        .unwrap();
    assert!(close(&mag.values, &[0.5, 0.0, 0.4]), "{:?}", mag.values);
    assert!(mag.timestamp > 1e9, "a wall-clock stamp");
    let mut v = Vec::new();
    assert_eq!(
        dev.as_analog_sensor().unwrap().read(&mut v),
        yarp_devices::sensors::AnalogStatus::Ok
    );
    let want = [
        1.5,
        -2.5,
        30.0,
        0.5,
        -0.25,
        -9.75,
        0.1 * deg,
        -0.2 * deg,
        0.3 * deg,
        0.5,
        0.0,
        0.4,
    ];
    assert!(close(&v, &want), "{v:?}");
}
