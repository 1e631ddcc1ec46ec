//! `multipleanalogsensorsremapper`: joins the sensors of several attached devices into
//! one device, choosing and ordering them by name (the iCub legs join their leg and foot
//! F/T sensors this way before a `multipleanalogsensorsserver`).
//!
//! Parameters: one list per family, named after the family's C++ tag plus `Names`
//! (`SixAxisForceTorqueSensorsNames (l_leg_ft l_foot_ft)`, `ThreeAxisGyroscopesNames`,
//! `SkinPatchesNames`, ...). A family without a list exposes no sensors. At attach every
//! listed name must be found among the attached devices' sensors of that family.

use super::family::{access, SensorFamily, FAMILY_COUNT};
use super::forward::{impl_mas_interfaces, mas_views, FamilySource};
use super::interfaces::*;
use crate::driver::{DeviceDriver, IMultipleWrapper, SharedDevice};
use crate::error::{DevResult, DeviceError};
use yarp_proto::Property;

const NAME: &str = "multipleanalogsensorsremapper";

crate::device_params! {
    /// What `multipleanalogsensorsremapper` reads (C++ `MultipleAnalogSensorsRemapper`):
    /// for each family, the sensors to expose; at least one family is required.
    pub struct MultipleAnalogSensorsRemapperParams for "multipleanalogsensorsremapper" {
        /// The ThreeAxisGyroscopes to expose, by name, in this order
        "ThreeAxisGyroscopesNames" three_axis_gyroscopes: Vec<String> = optional,
        /// The ThreeAxisLinearAccelerometers to expose, by name, in this order
        "ThreeAxisLinearAccelerometersNames" three_axis_linear_accelerometers: Vec<String> = optional,
        /// The ThreeAxisMagnetometers to expose, by name, in this order
        "ThreeAxisMagnetometersNames" three_axis_magnetometers: Vec<String> = optional,
        /// The OrientationSensors to expose, by name, in this order
        "OrientationSensorsNames" orientation_sensors: Vec<String> = optional,
        /// The TemperatureSensors to expose, by name, in this order
        "TemperatureSensorsNames" temperature_sensors: Vec<String> = optional,
        /// The SixAxisForceTorqueSensors to expose, by name, in this order
        "SixAxisForceTorqueSensorsNames" six_axis_force_torque_sensors: Vec<String> = optional,
        /// The ContactLoadCellArrays to expose, by name, in this order
        "ContactLoadCellArraysNames" contact_load_cell_arrays: Vec<String> = optional,
        /// The EncoderArrays to expose, by name, in this order
        "EncoderArraysNames" encoder_arrays: Vec<String> = optional,
        /// The SkinPatches to expose, by name, in this order
        "SkinPatchesNames" skin_patches: Vec<String> = optional,
        /// The PositionSensors to expose, by name, in this order
        "PositionSensorsNames" position_sensors: Vec<String> = optional,
        /// The LinearVelocitySensors to expose, by name, in this order
        "LinearVelocitySensorsNames" linear_velocity_sensors: Vec<String> = optional,
        /// The ThreeAxisAngularAccelerometers to expose, by name, in this order
        "ThreeAxisAngularAccelerometersNames" three_axis_angular_accelerometers: Vec<String> = optional,
    }
}

/// Where a remapped sensor lives: attached device and its index there.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Source {
    device: usize,
    index: usize,
}

/// The `multipleanalogsensorsremapper` device.
#[derive(Default)]
pub struct MultipleAnalogSensorsRemapper {
    wanted: [Option<Vec<String>>; FAMILY_COUNT],
    devices: Vec<SharedDevice>,
    map: [Vec<Source>; FAMILY_COUNT],
}

impl MultipleAnalogSensorsRemapper {
    pub fn new() -> Self {
        Self::default()
    }

    /// The sensor names requested for `family` (`None`: the family is not remapped).
    pub fn wanted(&self, family: SensorFamily) -> Option<&[String]> {
        self.wanted[family.index()].as_deref()
    }

    /// Runs `f` on the view of the device holding sensor `i` of `family`.
    fn with_source<R>(
        &self,
        family: SensorFamily,
        i: usize,
        f: impl FnOnce(&dyn SensorFamilyAccess, usize) -> DevResult<R>,
    ) -> DevResult<R> {
        let map = &self.map[family.index()];
        let src = map
            .get(i)
            .ok_or_else(|| no_sensor(family.tag(), i, map.len()))?;
        let dev = self.devices.get(src.device).ok_or(DeviceError::NotOpen)?;
        let mut pd = dev.lock();
        let view = access(pd.device(), family).ok_or(DeviceError::Unsupported(
            "multipleanalogsensorsremapper: an attached device lost a sensor interface",
        ))?;
        f(view.as_ref(), src.index)
    }
}

/// Finds every wanted sensor of `family` among `devices`.
fn locate(
    family: SensorFamily,
    wanted: &[String],
    devices: &[(String, SharedDevice)],
) -> DevResult<Vec<Source>> {
    let mut found: Vec<(String, Source)> = Vec::new();
    for (d, (_, dev)) in devices.iter().enumerate() {
        let mut pd = dev.lock();
        let view = access(pd.device(), family);
        if let Some(view) = view {
            for index in 0..view.count() {
                found.push((view.name(index)?, Source { device: d, index }));
            }
        }
    }
    wanted
        .iter()
        .map(|name| {
            found
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, s)| *s)
                .ok_or_else(|| DeviceError::BadParam {
                    device: NAME.into(),
                    param: format!("{}Names", family.tag()),
                    expected: "names of sensors of the attached devices",
                    got: format!(
                        "{name} (found: {})",
                        found
                            .iter()
                            .map(|(n, _)| n.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                })
        })
        .collect()
}

impl DeviceDriver for MultipleAnalogSensorsRemapper {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        MultipleAnalogSensorsRemapperParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = MultipleAnalogSensorsRemapperParams::read(config)?;
        for family in SensorFamily::ALL {
            self.wanted[family.index()] = match family {
                SensorFamily::ThreeAxisGyroscopes => p.three_axis_gyroscopes.clone(),
                SensorFamily::ThreeAxisLinearAccelerometers => {
                    p.three_axis_linear_accelerometers.clone()
                }
                SensorFamily::ThreeAxisMagnetometers => p.three_axis_magnetometers.clone(),
                SensorFamily::OrientationSensors => p.orientation_sensors.clone(),
                SensorFamily::TemperatureSensors => p.temperature_sensors.clone(),
                SensorFamily::SixAxisForceTorqueSensors => p.six_axis_force_torque_sensors.clone(),
                SensorFamily::ContactLoadCellArrays => p.contact_load_cell_arrays.clone(),
                SensorFamily::EncoderArrays => p.encoder_arrays.clone(),
                SensorFamily::SkinPatches => p.skin_patches.clone(),
                SensorFamily::PositionSensors => p.position_sensors.clone(),
                SensorFamily::LinearVelocitySensors => p.linear_velocity_sensors.clone(),
                SensorFamily::ThreeAxisAngularAccelerometers => {
                    p.three_axis_angular_accelerometers.clone()
                }
            };
        }
        if self.wanted.iter().all(Option::is_none) {
            return Err(DeviceError::MissingParam {
                device: NAME.into(),
                param: "SixAxisForceTorqueSensorsNames (or another <family>Names)".into(),
            });
        }
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.detach_all()
    }

    crate::views!(as_multiple_wrapper);

    mas_views!();
}

impl IMultipleWrapper for MultipleAnalogSensorsRemapper {
    fn attach_all(&mut self, devices: &[(String, SharedDevice)]) -> DevResult<()> {
        let mut map: [Vec<Source>; FAMILY_COUNT] = Default::default();
        for family in SensorFamily::ALL {
            if let Some(wanted) = &self.wanted[family.index()] {
                map[family.index()] = locate(family, wanted, devices)?;
            }
        }
        self.map = map;
        self.devices = devices.iter().map(|(_, d)| d.clone()).collect();
        Ok(())
    }

    fn detach_all(&mut self) -> DevResult<()> {
        self.devices.clear();
        self.map = Default::default();
        Ok(())
    }
}

impl FamilySource for MultipleAnalogSensorsRemapper {
    fn family_count(&self, family: SensorFamily) -> usize {
        self.map[family.index()].len()
    }
    fn family_status(&self, family: SensorFamily, i: usize) -> MasStatus {
        self.with_source(family, i, |v, j| Ok(v.status(j)))
            .unwrap_or(MasStatus::Error)
    }
    fn family_name(&self, family: SensorFamily, i: usize) -> DevResult<String> {
        self.with_source(family, i, |v, j| v.name(j))
    }
    fn family_frame_name(&self, family: SensorFamily, i: usize) -> DevResult<String> {
        self.with_source(family, i, |v, j| v.frame_name(j))
    }
    fn family_measure(&self, family: SensorFamily, i: usize) -> DevResult<SensorMeasurement> {
        self.with_source(family, i, |v, j| v.measure(j))
    }
}

impl_mas_interfaces!(MultipleAnalogSensorsRemapper);
