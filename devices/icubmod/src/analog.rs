//! `canBusAnalogSensor` and `canBusFtSensor` (icub-main): a strain F/T board or a MAIS
//! hall-effect board on CAN.
//!
//! Parameters (top level, as `hardware/FT/*.xml` and `hardware/MAIS/*.xml` give them):
//! `canAddress`, `format` (16 strain, 8 MAIS), `channels`, `period` (ms),
//! `useCalibration` (full-scale-scaled N / N·m), `sensorName` and `frameName`
//! (`canBusFtSensor`), bus keys `canBackend` / `physDevice` + `canDeviceNum`.
//! `canbusDevice` and `diagnostic` are accepted and ignored.
//!
//! Both names serve `IAnalogSensor`; a 6-channel 16-bit board also serves
//! `ISixAxisForceTorqueSensors` (one sensor). A board silent for 100 ms reads as
//! `Timeout`.

use icub_can::client::strain::AnalogFormat;
use icub_can::client::{SensorStatus, StrainClient, StrainParams};
use yarp_proto::Property;

use crate::common::{device_id, now, open_error, CanBusParams};
use yarp_devices::driver::DeviceDriver;
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::sensors::{AnalogStatus, IAnalogSensor, ISixAxisForceTorqueSensors};
use yarp_devices::sensors::{MasStatus, SensorMeasurement};

/// `canBusAnalogSensor` / `canBusFtSensor`.
pub struct CanBusAnalogSensor {
    kind: &'static str,
    id: String,
    sensor_name: String,
    frame_name: String,
    client: Option<StrainClient>,
}

impl CanBusAnalogSensor {
    /// `kind` is the device name it was created under.
    pub fn new(kind: &'static str) -> Self {
        Self {
            kind,
            id: kind.to_string(),
            sensor_name: String::new(),
            frame_name: String::new(),
            client: None,
        }
    }

    fn is_ft(&self) -> bool {
        self.client.as_ref().is_some_and(|c| c.channels() == 6)
    }

    fn check_sensor(&self, i: usize) -> DevResult<&StrainClient> {
        let c = self.client.as_ref().ok_or(DeviceError::NotOpen)?;
        if i == 0 && self.is_ft() {
            Ok(c)
        } else {
            Err(DeviceError::BadParam {
                device: self.id.clone(),
                param: "sens_index".into(),
                expected: "0 (one F/T sensor per board)",
                got: i.to_string(),
            })
        }
    }
}

fn analog_status(s: SensorStatus) -> AnalogStatus {
    match s {
        SensorStatus::Ok => AnalogStatus::Ok,
        SensorStatus::Overflow => AnalogStatus::Overflow,
        SensorStatus::Timeout => AnalogStatus::Timeout,
        SensorStatus::Error => AnalogStatus::Error,
    }
}

/// The multiple-analog-sensors status of a reading.
pub fn mas_status(s: SensorStatus) -> MasStatus {
    match s {
        SensorStatus::Ok => MasStatus::Ok,
        SensorStatus::Overflow => MasStatus::Overflow,
        SensorStatus::Timeout => MasStatus::Timeout,
        SensorStatus::Error => MasStatus::Error,
    }
}

yarp_devices::device_params! {
    /// What `canBusAnalogSensor` and `canBusFtSensor` read (icub-main's), besides their bus
    /// ([`CanBusParams`]).
    pub struct CanBusAnalogSensorParams for "canBusAnalogSensor" {
        /// The address of the strain (or MAIS) board
        "canAddress" can_address: i64 = required; in 1..=14,
        /// Bits per value: 16 (strain) or 8 (MAIS)
        format: i64 = 16; check crate::common::strain_format,
        /// Number of channels (at most 6 in 16 bits, 16 in 8 bits)
        channels: i64 = 6,
        /// Broadcast period asked of the board (1..255)
        period: i64 = 1; "ms",
        /// 1: calibrated values scaled by the board's full scales
        "useCalibration" use_calibration: i64 = 0,
        /// Name of the sensor (default: the device's name)
        "sensorName" sensor_name: String = optional,
        /// Name of the sensor's frame (default: the sensor's name)
        "frameName" frame_name: String = optional,
    }
}

impl DeviceDriver for CanBusAnalogSensor {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        [CanBusAnalogSensorParams::PARAMS, CanBusParams::PARAMS].concat()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.close()?;
        self.id = device_id(config, self.kind);
        yarp_devices::params::help_if_asked(self.kind, config, &self.parameters());
        let p = CanBusAnalogSensorParams::parse(&self.id, config)?;
        let bus_params = CanBusParams::parse(&self.id, config)?;
        let format = if p.format == 8 {
            AnalogFormat::Bits8
        } else {
            AnalogFormat::Bits16
        };
        let max_channels = if format == AnalogFormat::Bits16 {
            6
        } else {
            16
        };
        if !(1..=max_channels).contains(&p.channels) {
            return Err(DeviceError::BadParam {
                device: self.id.clone(),
                param: "channels".into(),
                expected: "1..6 (16-bit format) or 1..16 (8-bit)",
                got: p.channels.to_string(),
            });
        }
        let params = StrainParams {
            address: p.can_address as u8,
            period_ms: p.period.clamp(1, 255) as u8,
            use_calibration: p.use_calibration > 0,
            channels: p.channels as usize,
            format,
            ..StrainParams::strain(p.can_address as u8)
        };
        self.sensor_name = p.sensor_name.unwrap_or_else(|| self.id.clone());
        self.frame_name = p.frame_name.unwrap_or_else(|| self.sensor_name.clone());
        let bus = bus_params.open(&self.id)?;
        self.client = Some(StrainClient::open(bus, params).map_err(|e| open_error(&self.id, &e))?);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.client = None;
        Ok(())
    }

    yarp_devices::views!(as_analog_sensor);

    fn as_six_axis_force_torque_sensors(&mut self) -> Option<&mut dyn ISixAxisForceTorqueSensors> {
        if self.client.is_none() || self.is_ft() {
            Some(self)
        } else {
            None
        }
    }
}

impl IAnalogSensor for CanBusAnalogSensor {
    fn read(&mut self, out: &mut Vec<f64>) -> AnalogStatus {
        match &self.client {
            None => AnalogStatus::Error,
            Some(c) => {
                let (values, status) = c.read();
                *out = values;
                analog_status(status)
            }
        }
    }
    fn get_state(&mut self, _ch: usize) -> AnalogStatus {
        match &self.client {
            None => AnalogStatus::Error,
            Some(c) => analog_status(c.read().1),
        }
    }
    fn get_channels(&mut self) -> usize {
        self.client.as_ref().map_or(0, |c| c.channels())
    }
    fn calibrate_sensor(&mut self) -> DevResult<()> {
        Err(DeviceError::Unsupported(
            "canBusAnalogSensor calibration (offsets are set on the board)",
        ))
    }
}

impl ISixAxisForceTorqueSensors for CanBusAnalogSensor {
    fn get_nr_of_six_axis_force_torque_sensors(&self) -> usize {
        usize::from(self.is_ft())
    }
    fn get_six_axis_force_torque_sensor_status(&self, i: usize) -> MasStatus {
        match self.check_sensor(i) {
            Ok(c) => mas_status(c.read().1),
            Err(_) => MasStatus::Error,
        }
    }
    fn get_six_axis_force_torque_sensor_name(&self, i: usize) -> DevResult<String> {
        self.check_sensor(i).map(|_| self.sensor_name.clone())
    }
    fn get_six_axis_force_torque_sensor_frame_name(&self, i: usize) -> DevResult<String> {
        self.check_sensor(i).map(|_| self.frame_name.clone())
    }
    fn get_six_axis_force_torque_sensor_measure(&self, i: usize) -> DevResult<SensorMeasurement> {
        let c = self.check_sensor(i)?;
        let values = c
            .read_checked()
            .map_err(|e| crate::common::call_error(&self.id, e))?;
        Ok(SensorMeasurement::new(values, now()))
    }
}
