//! `canBusSkin` (icub-main `CanBusSkin`): the skin patches (MTB boards) of one CAN network.
//!
//! Parameters (as `hardware/skin/*.xml`): `skinCanIds` (board addresses, in taxel
//! order: 192 taxels per board), `period` (ms), bus keys `canBackend` / `canDeviceNum`
//! with `canbusDevice` naming the adapter. The `skinSpec` settings (`patches`,
//! `defaultCfgBoard`, `specialCfgBoards`, ...) are accepted and not sent to the boards:
//! the emulated MTBs stream with their defaults.
//!
//! Served as `IAnalogSensor` (what `skinWrapper` publishes) and as one `ISkinPatches`
//! patch. A board silent for 5 periods (at least 200 ms) makes the status `Timeout`.

use std::time::Duration;

use icub_can::client::SkinClient;
use yarp_proto::Property;

use crate::analog::mas_status;
use crate::common::{device_id, now, open_error, CanBusParams};
use yarp_devices::driver::DeviceDriver;
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::sensors::{
    AnalogStatus, IAnalogSensor, ISkinPatches, MasStatus, SensorMeasurement,
};

pub(crate) const NAME: &str = "canBusSkin";

/// The `canBusSkin` device.
#[derive(Default)]
pub struct CanBusSkin {
    id: String,
    timeout: Duration,
    client: Option<SkinClient>,
}

impl CanBusSkin {
    pub fn new() -> Self {
        Self::default()
    }

    fn c(&self) -> DevResult<&SkinClient> {
        self.client.as_ref().ok_or(DeviceError::NotOpen)
    }

    fn check(&self, i: usize) -> DevResult<&SkinClient> {
        let c = self.c()?;
        if i == 0 {
            Ok(c)
        } else {
            Err(DeviceError::BadParam {
                device: self.id.clone(),
                param: "sens_index".into(),
                expected: "0 (one patch per device)",
                got: i.to_string(),
            })
        }
    }
}

/// Board addresses as a byte each.
fn board_ids(ids: &[i64]) -> Result<(), &'static str> {
    match ids.iter().all(|id| u8::try_from(*id).is_ok()) {
        true => Ok(()),
        false => Err("a list of board addresses 1..14"),
    }
}

yarp_devices::device_params! {
    /// What `canBusSkin` reads (icub-main's `CanBusSkin`), besides its bus ([`CanBusParams`]).
    pub struct CanBusSkinParams for "canBusSkin" {
        /// The CAN addresses of the skin boards (MTBs) of the patch
        "skinCanIds" skin_can_ids: Vec<i64> = required; check board_ids,
        /// Period of the boards' messages
        period: f64 = 20.0; "ms",
    }
}

impl DeviceDriver for CanBusSkin {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        [CanBusSkinParams::PARAMS, CanBusParams::PARAMS].concat()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.close()?;
        self.id = device_id(config, NAME);
        let table = self.parameters();
        yarp_devices::params::help_if_asked(NAME, config, &table);
        let p = CanBusSkinParams::parse(&self.id, config)?;
        let bus_params = CanBusParams::parse(&self.id, config)?;
        let boards: Vec<u8> = p.skin_can_ids.iter().map(|&id| id as u8).collect();
        self.timeout = Duration::from_secs_f64((5.0 * p.period / 1000.0).max(0.2));
        let bus = bus_params.open(&self.id)?;
        self.client = Some(SkinClient::open(bus, &boards).map_err(|e| open_error(&self.id, &e))?);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.client = None;
        Ok(())
    }

    yarp_devices::views!(as_analog_sensor, as_skin_patches);
}

impl IAnalogSensor for CanBusSkin {
    fn read(&mut self, out: &mut Vec<f64>) -> AnalogStatus {
        let Ok(c) = self.c() else {
            return AnalogStatus::Error;
        };
        let (values, status) = c.read(self.timeout);
        *out = values;
        match mas_status(status) {
            MasStatus::Ok => AnalogStatus::Ok,
            MasStatus::Timeout => AnalogStatus::Timeout,
            _ => AnalogStatus::Error,
        }
    }
    fn get_state(&mut self, _ch: usize) -> AnalogStatus {
        let mut v = Vec::new();
        self.read(&mut v)
    }
    fn get_channels(&mut self) -> usize {
        self.c().map_or(0, |c| c.channels())
    }
    fn calibrate_sensor(&mut self) -> DevResult<()> {
        Err(DeviceError::Unsupported("canBusSkin calibration"))
    }
}

impl ISkinPatches for CanBusSkin {
    fn get_nr_of_skin_patches(&self) -> usize {
        usize::from(self.client.is_some())
    }
    fn get_skin_patch_status(&self, i: usize) -> MasStatus {
        match self.check(i) {
            Ok(c) => mas_status(c.read(self.timeout).1),
            Err(_) => MasStatus::Error,
        }
    }
    fn get_skin_patch_name(&self, i: usize) -> DevResult<String> {
        self.check(i).map(|_| self.id.clone())
    }
    fn get_skin_patch_size(&self, i: usize) -> usize {
        self.check(i).map_or(0, |c| c.channels())
    }
    fn get_skin_patch_measure(&self, i: usize) -> DevResult<SensorMeasurement> {
        let (values, _) = self.check(i)?.read(self.timeout);
        Ok(SensorMeasurement::new(values, now()))
    }
}
