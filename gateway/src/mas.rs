//! The multiple-analog-sensors stream (`multipleanalogsensorsserver`'s `measures:o`).
//!
//! Each message is the thrift struct `SensorStreamingData` as a Bottle: one list per
//! sensor family, in YARP 3.12's field order ([`Family`]), holding that family's
//! measurements; each measurement is `SensorMeasurement` = `((v0 v1 ...) timestamp)`. So
//! gyroscope 0 is `msg[0][0]`, e.g. what C++ `yarp read` shows for a fakeIMU:
//! `(((75.0 75.0 75.0) 1795298120.55)) (((9.47 0.0 -2.54) 1795298120.55)) ... () ()`.

use crate::convert::ConvertError;
use yarp_proto::{Bottle, Value};

/// Sensor families, numbered by their position in `SensorStreamingData` (YARP 3.12).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Family {
    ThreeAxisGyroscopes = 0,
    ThreeAxisLinearAccelerometers = 1,
    ThreeAxisMagnetometers = 2,
    OrientationSensors = 3,
    TemperatureSensors = 4,
    SixAxisForceTorqueSensors = 5,
}

/// One measurement: the values and the sensor's timestamp (seconds).
#[derive(Debug, Clone, PartialEq)]
pub struct Measurement {
    pub values: Vec<f64>,
    pub timestamp: f64,
}

/// Measurement `index` of `family`, which must have `len` values; `Ok(None)` when the
/// device has no such sensor.
pub fn measurement(
    msg: &Bottle,
    family: Family,
    index: usize,
    len: usize,
) -> Result<Option<Measurement>, ConvertError> {
    let shape = |what: &str| ConvertError::Shape(format!("{family:?}: {what}"));
    let Some(fam) = msg.get(family as usize) else {
        return Ok(None);
    };
    let all = fam
        .as_list()
        .ok_or_else(|| shape("not a list of measurements"))?;
    let Some(m) = all.get(index) else {
        return Ok(None);
    };
    let m = m
        .as_list()
        .ok_or_else(|| shape("a measurement is not (vector timestamp)"))?;
    let (Some(Value::List(v)), Some(ts)) = (m.get(0), m.get(1)) else {
        return Err(shape("a measurement is not (vector timestamp)"));
    };
    let values: Vec<f64> = v
        .iter()
        .map(|x| x.as_f64().filter(|_| x.is_int() || x.is_float()))
        .collect::<Option<_>>()
        .ok_or_else(|| shape("non-numeric value"))?;
    if values.len() != len {
        return Err(ConvertError::Count {
            want: len,
            got: values.len(),
        });
    }
    Ok(Some(Measurement {
        values,
        timestamp: ts.as_f64().unwrap_or_default(),
    }))
}

/// Roll, pitch, yaw in degrees (YARP's IOrientationSensors: R = Rz(yaw) Ry(pitch)
/// Rx(roll)) as a unit quaternion `(x, y, z, w)`.
pub fn rpy_deg_to_quaternion(rpy: &[f64]) -> [f64; 4] {
    let [r, p, y] = [rpy[0], rpy[1], rpy[2]].map(|d| d.to_radians() / 2.0);
    let (sr, cr, sp, cp, sy, cy) = (r.sin(), r.cos(), p.sin(), p.cos(), y.sin(), y.cos());
    [
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
        cr * cp * cy + sr * sp * sy,
    ]
}

/// A quaternion `(x, y, z, w)` as roll, pitch, yaw in degrees (the inverse of
/// [`rpy_deg_to_quaternion`]; tf2's `Matrix3x3::getRPY`, as yarp-devices-ros2's
/// `imu_nwc_ros2` reads a `sensor_msgs/Imu`).
pub fn quaternion_to_rpy_deg(q: [f64; 4]) -> [f64; 3] {
    let [x, y, z, w] = q;
    let n = (x * x + y * y + z * z + w * w).sqrt();
    let [x, y, z, w] = if n > 0.0 {
        [x / n, y / n, z / n, w / n]
    } else {
        [0.0, 0.0, 0.0, 1.0]
    };
    let roll = (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y));
    let pitch = (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin();
    let yaw = (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z));
    [roll.to_degrees(), pitch.to_degrees(), yaw.to_degrees()]
}

#[cfg(test)]
mod tests {
    #[test]
    fn quaternion_back_to_rpy() {
        for rpy in [[10.0, -20.0, 30.0], [0.0, 0.0, 90.0], [-170.0, 45.0, -5.0]] {
            let back = super::quaternion_to_rpy_deg(super::rpy_deg_to_quaternion(&rpy));
            for (a, b) in rpy.iter().zip(back) {
                assert!((a - b).abs() < 1e-9, "{rpy:?} -> {back:?}");
            }
        }
    }

    use super::*;

    /// A stream with one gyro, one accelerometer, no magnetometer, one orientation.
    fn sample() -> Bottle {
        Bottle::from_text(
            "(((1 2 3) 10.5)) (((0.0 0.0 9.81) 10.5)) () (((0 0 90) 10.5)) () \
             (((1 2 3 0.1 0.2 0.3) 11.0))",
        )
    }

    #[test]
    fn finds_measurements_by_family_and_index() {
        let b = sample();
        let g = measurement(&b, Family::ThreeAxisGyroscopes, 0, 3)
            .unwrap()
            .unwrap();
        assert_eq!(g.values, [1.0, 2.0, 3.0]);
        assert_eq!(g.timestamp, 10.5);
        let ft = measurement(&b, Family::SixAxisForceTorqueSensors, 0, 6)
            .unwrap()
            .unwrap();
        assert_eq!(ft.values[5], 0.3);
        assert_eq!(
            measurement(&b, Family::ThreeAxisMagnetometers, 0, 3),
            Ok(None)
        );
        assert_eq!(measurement(&b, Family::ThreeAxisGyroscopes, 1, 3), Ok(None));
        assert_eq!(
            measurement(&b, Family::ThreeAxisGyroscopes, 0, 6),
            Err(ConvertError::Count { want: 6, got: 3 })
        );
        assert!(measurement(&Bottle::from_text("1 2"), Family::ThreeAxisGyroscopes, 0, 3).is_err());
        // the extra nesting level of a misread thrift struct is rejected, not misread
        assert!(measurement(
            &Bottle::from_text("((((1 2 3) 10.5)))"),
            Family::ThreeAxisGyroscopes,
            0,
            3
        )
        .is_err());
    }

    #[test]
    fn quaternions() {
        let close = |a: [f64; 4], b: [f64; 4]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12);
        assert!(close(
            rpy_deg_to_quaternion(&[0.0, 0.0, 0.0]),
            [0.0, 0.0, 0.0, 1.0]
        ));
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!(close(
            rpy_deg_to_quaternion(&[0.0, 0.0, 90.0]),
            [0.0, 0.0, h, h]
        ));
        assert!(close(
            rpy_deg_to_quaternion(&[90.0, 0.0, 0.0]),
            [h, 0.0, 0.0, h]
        ));
        assert!(close(
            rpy_deg_to_quaternion(&[0.0, 90.0, 0.0]),
            [0.0, h, 0.0, h]
        ));
    }
}
