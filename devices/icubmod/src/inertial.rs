//! `canBusInertialMTB` (icub-main `CanBusInertialMTB`): accelerometers (and gyroscopes)
//! of MTB boards on one CAN network.
//!
//! Parameters (as `hardware/skin/*_inertial_mtb.xml`): `canAddress` (one or more
//! boards), `sensorType` (`acc` or `extAccAndGyro`), `period` (ms), bus keys
//! `canBackend` / `physDevice` + `canDeviceNum`.
//!
//! `IAnalogSensor` gives the raw board values, 3 (acc) or 6 (acc + gyro) per board, as
//! the C++ device; `IThreeAxisLinearAccelerometers` / `IThreeAxisGyroscopes` give one
//! sensor per board in SI units, assuming the MTB's ±2 g accelerometer and ±250 °/s
//! gyroscope full scales on 16 bits.

use icub_can::client::{InertialClient, SensorStatus};
use yarp_proto::Property;

use crate::analog::mas_status;
use crate::common::{device_id, now, open_error, CanBusParams};
use yarp_devices::driver::DeviceDriver;
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::sensors::{
    AnalogStatus, IAnalogSensor, IThreeAxisGyroscopes, IThreeAxisLinearAccelerometers, MasStatus,
    SensorMeasurement,
};

pub(crate) const NAME: &str = "canBusInertialMTB";

/// m/s² per accelerometer count (±2 g on 16 bits).
const ACC_SCALE: f64 = 2.0 * 9.80665 / 32768.0;
/// °/s per gyroscope count (±250 °/s on 16 bits).
const GYRO_SCALE: f64 = 250.0 / 32768.0;

/// The `canBusInertialMTB` device.
#[derive(Default)]
pub struct CanBusInertialMtb {
    id: String,
    boards: Vec<u8>,
    with_gyro: bool,
    client: Option<InertialClient>,
}

impl CanBusInertialMtb {
    pub fn new() -> Self {
        Self::default()
    }

    /// Values of board `i` at `offset` (0 acc, 3 gyro), scaled.
    fn measure(&self, i: usize, offset: usize, scale: f64) -> DevResult<SensorMeasurement> {
        let (values, status) = self.sensor(i)?;
        if status == SensorStatus::Timeout {
            return Err(DeviceError::Unsupported(
                "no data from the MTB board within 100 ms",
            ));
        }
        let per = if self.with_gyro { 6 } else { 3 };
        let v = values[i * per + offset..i * per + offset + 3]
            .iter()
            .map(|x| x * scale)
            .collect();
        Ok(SensorMeasurement::new(v, now()))
    }

    fn sensor(&self, i: usize) -> DevResult<(Vec<f64>, SensorStatus)> {
        let c = self.client.as_ref().ok_or(DeviceError::NotOpen)?;
        if i < self.boards.len() {
            Ok(c.read())
        } else {
            Err(DeviceError::BadParam {
                device: self.id.clone(),
                param: "sens_index".into(),
                expected: "one sensor per canAddress",
                got: i.to_string(),
            })
        }
    }

    fn name(&self, i: usize, what: &str) -> DevResult<String> {
        self.sensor(i)?;
        Ok(format!("{}_{what}_{}", self.id, self.boards[i]))
    }

    fn status(&self, i: usize) -> MasStatus {
        self.sensor(i)
            .map_or(MasStatus::Error, |(_, s)| mas_status(s))
    }
}

/// Board addresses as a byte each.
fn board_addresses(ids: &[i64]) -> Result<(), &'static str> {
    match ids.iter().all(|id| u8::try_from(*id).is_ok()) {
        true => Ok(()),
        false => Err("board addresses 1..14"),
    }
}

yarp_devices::device_params! {
    /// What `canBusInertialMTB` reads (icub-main's `CanBusInertialMTB`), besides its bus
    /// ([`CanBusParams`]).
    pub struct CanBusInertialMtbParams for "canBusInertialMTB" {
        /// The CAN addresses of the MTB boards
        "canAddress" can_address: Vec<i64> = required; check board_addresses,
        /// acc (accelerometers) or gyro (and accelerometers)
        "sensorType" sensor_type: String = "acc",
        /// Period of the boards' messages (1..255)
        period: f64 = 10.0; "ms",
    }
}

impl DeviceDriver for CanBusInertialMtb {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        [CanBusInertialMtbParams::PARAMS, CanBusParams::PARAMS].concat()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.close()?;
        self.id = device_id(config, NAME);
        yarp_devices::params::help_if_asked(NAME, config, &self.parameters());
        let p = CanBusInertialMtbParams::parse(&self.id, config)?;
        let bus_params = CanBusParams::parse(&self.id, config)?;
        self.boards = p.can_address.iter().map(|a| *a as u8).collect();
        let sensor_type = p.sensor_type;
        let period = p.period.clamp(1.0, 255.0) as u8;
        let bus = bus_params.open(&self.id)?;
        let client = InertialClient::open(bus, &self.boards, &sensor_type, period)
            .map_err(|e| open_error(&self.id, &e))?;
        self.with_gyro = client.channels() == self.boards.len() * 6;
        self.client = Some(client);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.client = None;
        Ok(())
    }

    yarp_devices::views!(
        as_analog_sensor,
        as_three_axis_linear_accelerometers,
        as_three_axis_gyroscopes
    );
}

impl IAnalogSensor for CanBusInertialMtb {
    fn read(&mut self, out: &mut Vec<f64>) -> AnalogStatus {
        let Some(c) = &self.client else {
            return AnalogStatus::Error;
        };
        let (values, status) = c.read();
        *out = values;
        match status {
            SensorStatus::Ok => AnalogStatus::Ok,
            SensorStatus::Timeout => AnalogStatus::Timeout,
            SensorStatus::Overflow => AnalogStatus::Overflow,
            SensorStatus::Error => AnalogStatus::Error,
        }
    }
    fn get_state(&mut self, _ch: usize) -> AnalogStatus {
        let mut v = Vec::new();
        self.read(&mut v)
    }
    fn get_channels(&mut self) -> usize {
        self.client.as_ref().map_or(0, |c| c.channels())
    }
    fn calibrate_sensor(&mut self) -> DevResult<()> {
        Err(DeviceError::Unsupported("canBusInertialMTB calibration"))
    }
}

impl IThreeAxisLinearAccelerometers for CanBusInertialMtb {
    fn get_nr_of_three_axis_linear_accelerometers(&self) -> usize {
        self.boards.len()
    }
    fn get_three_axis_linear_accelerometer_status(&self, i: usize) -> MasStatus {
        self.status(i)
    }
    fn get_three_axis_linear_accelerometer_name(&self, i: usize) -> DevResult<String> {
        self.name(i, "acc")
    }
    fn get_three_axis_linear_accelerometer_frame_name(&self, i: usize) -> DevResult<String> {
        self.name(i, "acc")
    }
    fn get_three_axis_linear_accelerometer_measure(
        &self,
        i: usize,
    ) -> DevResult<SensorMeasurement> {
        self.measure(i, 0, ACC_SCALE)
    }
}

impl IThreeAxisGyroscopes for CanBusInertialMtb {
    fn get_nr_of_three_axis_gyroscopes(&self) -> usize {
        if self.with_gyro {
            self.boards.len()
        } else {
            0
        }
    }
    fn get_three_axis_gyroscope_status(&self, i: usize) -> MasStatus {
        if self.with_gyro {
            self.status(i)
        } else {
            MasStatus::Error
        }
    }
    fn get_three_axis_gyroscope_name(&self, i: usize) -> DevResult<String> {
        self.name(i, "gyro")
    }
    fn get_three_axis_gyroscope_frame_name(&self, i: usize) -> DevResult<String> {
        self.name(i, "gyro")
    }
    fn get_three_axis_gyroscope_measure(&self, i: usize) -> DevResult<SensorMeasurement> {
        if !self.with_gyro {
            return Err(DeviceError::Unsupported(
                "gyroscopes need sensorType extAccAndGyro",
            ));
        }
        self.measure(i, 3, GYRO_SCALE)
    }
}
