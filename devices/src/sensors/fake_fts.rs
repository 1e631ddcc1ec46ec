//! `fakeFTs`: simulated six-axis force/torque sensors, each with a temperature sensor,
//! as the C++ device of that name.
//!
//! Parameters: `sensorNames` (required list, one sensor per name; the frame of each is
//! named like the sensor), `period` (ms, default 10). Every channel of every sensor
//! reads a counter that starts at 10 and advances by one every period (wrapping to 0
//! at 360); the timestamp is the time of the latest step.

use super::interfaces::*;
use super::params::{now, positive_ms};
use crate::driver::DeviceDriver;
use crate::error::DevResult;
use yarp_proto::Property;

crate::device_params! {
    /// What `fakeFTs` reads (our fake of the force-torque sensors a robot's MAS serves).
    pub struct FakeFtsParams for "fakeFTs" {
        /// Period over which the measurement is updated.
        period: f64 = 10.0; "ms"; check positive_ms,
        /// If the parameter is present, the fake sensor values never change
        "constantValue" constant_value: bool = false,
        /// The names of the sensors, one six-axis force-torque sensor each
        "sensorNames" sensor_names: Vec<String> = required,
    }
}

/// The simulated F/T sensors.
#[derive(Debug, Clone)]
pub struct FakeFts {
    names: Vec<String>,
    period: f64,
    constant: bool,
    start: f64,
}

impl Default for FakeFts {
    fn default() -> Self {
        FakeFts {
            names: Vec::new(),
            period: 0.01,
            constant: false,
            start: now(),
        }
    }
}

impl FakeFts {
    pub fn new() -> Self {
        Self::default()
    }

    /// The counter value and the time of the step that set it, at wall time `t`.
    fn state_at(&self, t: f64) -> (f64, f64) {
        let steps = ((t - self.start) / self.period).floor().max(0.0);
        let stamp = self.start + steps * self.period;
        let c = if self.constant {
            10.0
        } else {
            (10.0 + steps) % 360.0
        };
        (c, stamp)
    }

    fn check(&self, i: usize) -> DevResult<()> {
        if i < self.names.len() {
            Ok(())
        } else {
            Err(no_sensor(FakeFtsParams::DEVICE, i, self.names.len()))
        }
    }

    fn status(&self, i: usize) -> MasStatus {
        if i < self.names.len() {
            MasStatus::Ok
        } else {
            MasStatus::Error
        }
    }

    fn name(&self, i: usize) -> DevResult<String> {
        self.check(i).map(|_| self.names[i].clone())
    }

    fn measure(&self, i: usize, channels: usize) -> DevResult<SensorMeasurement> {
        self.check(i)?;
        let (c, t) = self.state_at(now());
        Ok(SensorMeasurement::new(vec![c; channels], t))
    }
}

impl DeviceDriver for FakeFts {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        FakeFtsParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = FakeFtsParams::read(config)?;
        self.period = p.period / 1000.0;
        self.constant = p.constant_value;
        self.names = p.sensor_names;
        self.start = now();
        Ok(())
    }

    crate::views!(as_six_axis_force_torque_sensors, as_temperature_sensors);
}

impl ISixAxisForceTorqueSensors for FakeFts {
    fn get_nr_of_six_axis_force_torque_sensors(&self) -> usize {
        self.names.len()
    }
    fn get_six_axis_force_torque_sensor_status(&self, i: usize) -> MasStatus {
        self.status(i)
    }
    fn get_six_axis_force_torque_sensor_name(&self, i: usize) -> DevResult<String> {
        self.name(i)
    }
    fn get_six_axis_force_torque_sensor_frame_name(&self, i: usize) -> DevResult<String> {
        self.name(i)
    }
    fn get_six_axis_force_torque_sensor_measure(&self, i: usize) -> DevResult<SensorMeasurement> {
        self.measure(i, 6)
    }
}

impl ITemperatureSensors for FakeFts {
    fn get_nr_of_temperature_sensors(&self) -> usize {
        self.names.len()
    }
    fn get_temperature_sensor_status(&self, i: usize) -> MasStatus {
        self.status(i)
    }
    fn get_temperature_sensor_name(&self, i: usize) -> DevResult<String> {
        self.name(i)
    }
    fn get_temperature_sensor_frame_name(&self, i: usize) -> DevResult<String> {
        self.name(i)
    }
    fn get_temperature_sensor_measure(&self, i: usize) -> DevResult<SensorMeasurement> {
        self.measure(i, 1)
    }
}
