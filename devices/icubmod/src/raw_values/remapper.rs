//! `rawValuesPublisherRemapper` (icub-main 2.11): one `IRawValuesPublisher` of several,
//! merged in attach order as C++ merges them: a key of one device only is taken as it is;
//! a key several devices have gets their values concatenated, and their axes and value
//! names appended (its size then the number of value names). No port of its own.
//!
//! Parameters as C++: `axesNames` (required) and `joints` (default 1), which C++ reads and
//! only prints.

use std::collections::BTreeMap;
use yarp_devices::driver::{DeviceDriver, IMultipleWrapper, SharedDevice};
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::raw_values::{IRawValuesPublisher, RawValuesKeyMetadata};
use yarp_proto::Property;

pub const NAME: &str = "rawValuesPublisherRemapper";

yarp_devices::device_params! {
    /// What `rawValuesPublisherRemapper` reads (icub-main's `rawValuesPublisherRemapper_params.md`).
    pub struct RawValuesPublisherRemapperParams for "rawValuesPublisherRemapper" {
        /// Names of the axes of the remapped devices
        "axesNames" axes_names: Vec<String> = required,
        /// Number of joints
        joints: i64 = 1,
    }
}

/// The `rawValuesPublisherRemapper` device.
#[derive(Default)]
pub struct RawValuesPublisherRemapper {
    devices: Vec<SharedDevice>,
}

impl RawValuesPublisherRemapper {
    pub fn new() -> Self {
        Self::default()
    }

    /// `f` of each attached publisher, in attach order.
    fn each<T>(
        &self,
        mut f: impl FnMut(&mut dyn IRawValuesPublisher) -> DevResult<T>,
    ) -> DevResult<Vec<DevResult<T>>> {
        if self.devices.is_empty() {
            return Err(DeviceError::NotOpen);
        }
        Ok(self
            .devices
            .iter()
            .map(|d| {
                let mut pd = d.lock();
                match pd.device().as_raw_values_publisher() {
                    Some(p) => f(p),
                    None => Err(DeviceError::NoInterface("IRawValuesPublisher")),
                }
            })
            .collect())
    }
}

impl DeviceDriver for RawValuesPublisherRemapper {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        RawValuesPublisherRemapperParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = RawValuesPublisherRemapperParams::read(config)?;
        tracing::debug!("{NAME}: axesNames {:?}, joints {}", p.axes_names, p.joints);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.devices.clear();
        Ok(())
    }

    yarp_devices::views!(as_multiple_wrapper, as_raw_values_publisher);
}

impl IMultipleWrapper for RawValuesPublisherRemapper {
    fn attach_all(&mut self, devices: &[(String, SharedDevice)]) -> DevResult<()> {
        if devices.is_empty() {
            return Err(DeviceError::Unsupported(
                "rawValuesPublisherRemapper attaches at least one device",
            ));
        }
        for (key, d) in devices {
            if d.lock().device().as_raw_values_publisher().is_none() {
                return Err(DeviceError::failed(
                    NAME,
                    format!("{key} is no IRawValuesPublisher"),
                ));
            }
        }
        self.devices = devices.iter().map(|(_, d)| d.clone()).collect();
        Ok(())
    }

    fn detach_all(&mut self) -> DevResult<()> {
        self.devices.clear();
        Ok(())
    }
}

impl IRawValuesPublisher for RawValuesPublisherRemapper {
    /// Every device's map merged; a device that fails fails the whole (C++ then sends
    /// nothing that cycle).
    fn get_raw_data_map(&mut self) -> DevResult<BTreeMap<String, Vec<i32>>> {
        let mut out: BTreeMap<String, Vec<i32>> = BTreeMap::new();
        for map in self.each(|p| p.get_raw_data_map())? {
            for (key, values) in map? {
                out.entry(key).or_default().extend(values);
            }
        }
        Ok(out)
    }

    fn get_metadata_map(&mut self) -> DevResult<BTreeMap<String, RawValuesKeyMetadata>> {
        let mut out: BTreeMap<String, RawValuesKeyMetadata> = BTreeMap::new();
        for map in self.each(|p| p.get_metadata_map())? {
            for (key, m) in map? {
                match out.get_mut(&key) {
                    None => {
                        out.insert(key, m);
                    }
                    Some(have) => {
                        have.axes_names.extend(m.axes_names);
                        have.raw_value_names.extend(m.raw_value_names);
                        have.size = i32::try_from(have.raw_value_names.len()).unwrap_or(i32::MAX);
                    }
                }
            }
        }
        Ok(out)
    }
}
