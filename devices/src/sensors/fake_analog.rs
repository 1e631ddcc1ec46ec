//! `fakeAnalogSensor`: a legacy analog sensor (C++ `IAnalogSensor`) for tests.
//!
//! Parameters (C++ 3.12): `period` (s, default 1.0), `channelsNum` (default 1). As the
//! C++ device, channel 0 reads the current time and the others read 0; calibration
//! requests succeed and do nothing.

use super::interfaces::*;
use super::params::now;
use crate::driver::DeviceDriver;
use crate::error::DevResult;
use yarp_proto::Property;

crate::device_params! {
    /// What `fakeAnalogSensor` reads (C++ `FakeAnalogSensor_params.md`).
    pub struct FakeAnalogSensorParams for "fakeAnalogSensor" {
        /// thread period
        period: f64 = 1.0; "s",
        /// Number of channels
        "channelsNum" channels_num: usize = 1; min 1,
    }
}

/// The simulated analog sensor.
#[derive(Debug, Clone)]
pub struct FakeAnalogSensor {
    channels: usize,
    period: f64,
}

impl Default for FakeAnalogSensor {
    fn default() -> Self {
        FakeAnalogSensor {
            channels: 1,
            period: 1.0,
        }
    }
}

impl FakeAnalogSensor {
    pub fn new() -> Self {
        Self::default()
    }

    /// The configured thread period (s); readings do not depend on it.
    pub fn period(&self) -> f64 {
        self.period
    }
}

impl DeviceDriver for FakeAnalogSensor {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        FakeAnalogSensorParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = FakeAnalogSensorParams::read(config)?;
        self.period = p.period;
        self.channels = p.channels_num;
        Ok(())
    }

    crate::views!(as_analog_sensor);
}

impl IAnalogSensor for FakeAnalogSensor {
    fn read(&mut self, out: &mut Vec<f64>) -> AnalogStatus {
        out.clear();
        out.resize(self.channels, 0.0);
        out[0] = now();
        AnalogStatus::Ok
    }
    fn get_state(&mut self, _ch: usize) -> AnalogStatus {
        AnalogStatus::Ok
    }
    fn get_channels(&mut self) -> usize {
        self.channels
    }
    fn calibrate_sensor(&mut self) -> DevResult<()> {
        Ok(())
    }
    fn calibrate_sensor_with(&mut self, _values: &[f64]) -> DevResult<()> {
        Ok(())
    }
    fn calibrate_channel(&mut self, _ch: usize) -> DevResult<()> {
        Ok(())
    }
    fn calibrate_channel_with(&mut self, _ch: usize, _value: f64) -> DevResult<()> {
        Ok(())
    }
}
