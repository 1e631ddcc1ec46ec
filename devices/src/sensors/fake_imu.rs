//! `fakeIMU`: a simulated IMU (one gyroscope, accelerometer, magnetometer and
//! orientation sensor), as the C++ device.
//!
//! Parameters: `period` (ms, default 10), `constantValue` (default false), `sensorName`
//! (default `sensorName`), `frameName` (default `frameName`).
//!
//! Motion: a counter starts at 10 and advances by one every period (wrapping to 0 at
//! 360) unless `constantValue`; gyroscope, magnetometer and orientation read
//! `[c c c]`; the accelerometer reads gravity seen by a body pitched by `c * 3.14 / 180`
//! rad: `[9.81 sin p, 0, -9.81 cos p]`. The state is computed from the elapsed time, so
//! no thread is needed; the timestamp is the time of the latest step.

use super::interfaces::*;
use super::params::{now, positive_ms};
use crate::driver::DeviceDriver;
use crate::error::DevResult;
use yarp_proto::Property;

const NAME: &str = "fakeIMU";

crate::device_params! {
    /// What `fakeIMU` reads (C++ `FakeIMU_params.md`; the period may have a fraction).
    pub struct FakeImuParams for "fakeIMU" {
        /// Period over which the measurement is updated.
        period: f64 = 10.0; "ms"; check positive_ms,
        /// If the parameter is present, the fake sensor values never changes (useful for testing server/client coherence).
        "constantValue" constant_value: bool = false,
        /// Name of the sensor
        "sensorName" sensor_name: String = "sensorName",
        /// Name of the frame
        "frameName" frame_name: String = "frameName",
    }
}
const GRAVITY: f64 = 9.81;
/// The C++ device's truncated pi: the readings must match its bits.
#[allow(clippy::approx_constant)]
const CPP_PI: f64 = 3.14;

/// The simulated IMU.
#[derive(Debug, Clone)]
pub struct FakeImu {
    period: f64,
    constant: bool,
    sensor_name: String,
    frame_name: String,
    start: f64,
}

impl Default for FakeImu {
    fn default() -> Self {
        FakeImu {
            period: 0.01,
            constant: false,
            sensor_name: "sensorName".into(),
            frame_name: "frameName".into(),
            start: now(),
        }
    }
}

impl FakeImu {
    pub fn new() -> Self {
        Self::default()
    }

    /// The counter value and the time of the step that set it, at wall time `t`.
    pub fn state_at(&self, t: f64) -> (f64, f64) {
        let steps = ((t - self.start) / self.period).floor().max(0.0);
        let stamp = self.start + steps * self.period;
        if self.constant {
            return (10.0, stamp);
        }
        ((10.0 + steps) % 360.0, stamp)
    }

    /// The accelerometer reading for counter value `count` (exactly C++ `gravity * dcm`).
    pub fn acceleration(count: f64) -> [f64; 3] {
        let pitch = count * CPP_PI / 180.0;
        [GRAVITY * pitch.sin(), 0.0, -GRAVITY * pitch.cos()]
    }

    fn check(&self, i: usize) -> DevResult<()> {
        if i == 0 {
            Ok(())
        } else {
            Err(no_sensor(NAME, i, 1))
        }
    }

    fn counter(&self, i: usize) -> DevResult<SensorMeasurement> {
        self.check(i)?;
        let (c, t) = self.state_at(now());
        Ok(SensorMeasurement::new(vec![c; 3], t))
    }

    fn accelerometer(&self, i: usize) -> DevResult<SensorMeasurement> {
        self.check(i)?;
        let (c, t) = self.state_at(now());
        Ok(SensorMeasurement::new(FakeImu::acceleration(c).to_vec(), t))
    }

    fn status(&self, i: usize) -> MasStatus {
        if i == 0 {
            MasStatus::Ok
        } else {
            MasStatus::Error
        }
    }

    fn name(&self, i: usize) -> DevResult<String> {
        self.check(i).map(|_| self.sensor_name.clone())
    }

    fn frame(&self, i: usize) -> DevResult<String> {
        self.check(i).map(|_| self.frame_name.clone())
    }
}

impl DeviceDriver for FakeImu {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        FakeImuParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = FakeImuParams::read(config)?;
        self.period = p.period / 1000.0;
        self.constant = p.constant_value;
        self.sensor_name = p.sensor_name;
        self.frame_name = p.frame_name;
        self.start = now();
        Ok(())
    }

    crate::imu_views!();
}

crate::single_imu_interfaces!(FakeImu {
    gyro: counter,
    acc: accelerometer,
    mag: counter,
    rpy: counter
});

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counter_starts_at_ten_steps_and_wraps() {
        let mut imu = FakeImu::new();
        imu.open(&Property::from_config_text("period 20\n").unwrap())
            .unwrap();
        let t0 = imu.start;
        assert_eq!(imu.state_at(t0), (10.0, t0));
        assert_eq!(imu.state_at(t0 + 0.041).0, 12.0);
        assert_eq!(imu.state_at(t0 + 0.02 * 349.5).0, 359.0);
        assert_eq!(imu.state_at(t0 + 0.02 * 350.5).0, 0.0);
        assert!(imu.get_three_axis_gyroscope_measure(1).is_err());
        assert_eq!(imu.get_three_axis_gyroscope_status(1), MasStatus::Error);
    }

    #[test]
    fn constant_value_and_names() {
        let mut imu = FakeImu::new();
        let cfg = "constantValue true\nsensorName s\nframeName f\n";
        imu.open(&Property::from_config_text(cfg).unwrap()).unwrap();
        assert_eq!(imu.state_at(imu.start + 100.0).0, 10.0);
        assert_eq!(imu.get_orientation_sensor_name(0).unwrap(), "s");
        assert_eq!(imu.get_orientation_sensor_frame_name(0).unwrap(), "f");
        let bad = Property::from_config_text("period -1\n").unwrap();
        assert!(FakeImu::new()
            .open(&bad)
            .unwrap_err()
            .to_string()
            .contains("period"));
    }
}
