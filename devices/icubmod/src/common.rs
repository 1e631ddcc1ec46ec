//! What the iCub CAN devices share: reading their configuration the way icub-main does
//! (`GROUP` sections, multi-value lines), opening the CAN bus they name, and turning
//! driver-core errors into [`DeviceError`]s.

use std::sync::Arc;
use std::time::Instant;

use icub_can::client::ClientError;
use icub_can::CanBus;
use yarp_proto::{Property, Value};

use yarp_devices::error::{DevResult, DeviceError};

/// Overrides the bus of every iCub CAN device that names none with `canBackend`, so a
/// robot's XML can run unmodified (see `launch-configs/icub-sim/robot/README.md`).
pub const BACKEND_ENV: &str = "YARP_ICUB_CAN_BACKEND";

/// Wall-clock time in seconds (the timestamps of YARP ports).
pub use yarp_proto::stamp::now;

/// The wall-clock time of an `Instant` in the past.
pub fn wall_time(at: Instant) -> f64 {
    now() - at.elapsed().as_secs_f64()
}

/// The device's instance name for logs and errors: yarprobotinterface's `id` (the XML
/// device name), else `default` (the device type).
pub fn device_id(config: &Property, default: &str) -> String {
    config
        .find("id")
        .map_or_else(|| default.to_string(), Value::to_string_bare)
}

/// The analog sensors' two message formats, bits per value (`format`).
pub fn strain_format(bits: &i64) -> Result<(), &'static str> {
    match *bits == 8 || *bits == 16 {
        true => Ok(()),
        false => Err("8 or 16"),
    }
}

yarp_devices::device_params! {
    /// How an iCub CAN device finds its bus: icub-main's driver and bus number, or (ours)
    /// a backend URL. Several spellings stand in robots' files: all are read, the first
    /// given wins.
    pub struct CanBusParams for "canBus" {
        /// The bus as a URL: inproc://NAME, udp://HOST:PORT[+n], udp-hub://ADDR, socketcan://IF (else $YARP_ICUB_CAN_BACKEND, else physDevice)
        "canBackend" can_backend: String = optional,
        /// An older spelling of canBackend
        "CanBackend" can_backend_cap: String = optional,
        /// icub-main's CAN driver: socketcan here (cfw2can, ecan and pcan have no driver in this build), or a URL
        "physDevice" phys_device: String = optional,
        /// An older spelling of physDevice
        "physdevice" phys_device_lower: String = optional,
        /// The CAN driver as some files name it (sharedcan: the one of physDevice)
        "canbusDevice" canbus_device: String = optional,
        /// An older spelling of canbusDevice
        "canbusdevice" canbus_device_lower: String = optional,
        /// The bus number (n in a URL, the interface's number)
        "canDeviceNum" can_device_num: u32 = optional,
        /// An older spelling of canDeviceNum
        "CanDeviceNum" can_device_num_cap: u32 = optional,
        /// The socketcan interface (with n: can{n})
        "canDeviceName" can_device_name: String = optional,
        /// An older spelling of canDeviceName
        "CanDeviceName" can_device_name_cap: String = optional,
    }
}

impl CanBusParams {
    /// The bus parameters of `group` (canmotioncontrol's `CAN`), each falling back to the
    /// top level, as icub-main looks them up.
    pub fn parse_in_group(device: &str, config: &Property, group: &str) -> DevResult<Self> {
        let top = Self::parse(device, config)?;
        let Some(lines) = config.find_group(group) else {
            return Ok(top);
        };
        let inner = Self::parse(device, &Property::from_bottle(lines))?;
        Ok(Self {
            can_backend: inner.can_backend.or(top.can_backend),
            can_backend_cap: inner.can_backend_cap.or(top.can_backend_cap),
            phys_device: inner.phys_device.or(top.phys_device),
            phys_device_lower: inner.phys_device_lower.or(top.phys_device_lower),
            canbus_device: inner.canbus_device.or(top.canbus_device),
            canbus_device_lower: inner.canbus_device_lower.or(top.canbus_device_lower),
            can_device_num: inner.can_device_num.or(top.can_device_num),
            can_device_num_cap: inner.can_device_num_cap.or(top.can_device_num_cap),
            can_device_name: inner.can_device_name.or(top.can_device_name),
            can_device_name_cap: inner.can_device_name_cap.or(top.can_device_name_cap),
        })
    }

    /// The bus these parameters name, as icub-can opens it (`$YARP_ICUB_CAN_BACKEND` when
    /// no `canBackend` is given; `canbusDevice` when it names an adapter and no
    /// `physDevice` is given).
    pub fn open(&self, device: &str) -> Result<Arc<dyn CanBus>, DeviceError> {
        let env = std::env::var(BACKEND_ENV).ok().filter(|s| !s.is_empty());
        let backend = self
            .can_backend
            .clone()
            .or(self.can_backend_cap.clone())
            .or(env);
        let phys = self
            .phys_device
            .clone()
            .or(self.phys_device_lower.clone())
            .or_else(|| {
                self.canbus_device
                    .clone()
                    .or(self.canbus_device_lower.clone())
                    .filter(|d| d.trim_matches('"') != "sharedcan")
            });
        let num = self.can_device_num_cap.or(self.can_device_num);
        let name = self
            .can_device_name_cap
            .clone()
            .or(self.can_device_name.clone());
        let get = |key: &str| -> Option<String> {
            match key {
                "canBackend" => backend.clone(),
                "physDevice" => phys.clone(),
                "CanDeviceNum" => num.map(|n| n.to_string()),
                "CanDeviceName" => name.clone(),
                _ => None,
            }
        };
        icub_can::bus::config::open_from_params(&get).map_err(|e| bus_error(device, e))
    }
}

fn bus_error(device: &str, e: impl std::fmt::Display) -> DeviceError {
    DeviceError::BadParam {
        device: device.to_string(),
        param: "canBackend".into(),
        expected: "a CAN backend that opens (inproc://, udp://, udp-hub://, socketcan://)",
        got: e.to_string(),
    }
}

/// An error from opening a driver core: the message names what failed.
pub fn open_error(device: &str, e: &ClientError) -> DeviceError {
    let (param, expected) = match e {
        ClientError::BoardsSilent { .. } | ClientError::BoardTimeout { .. } => {
            ("canAddress", "boards that answer on the configured bus")
        }
        ClientError::Bus(_) => ("canBackend", "a working CAN bus"),
        _ => ("configuration", "valid icub-main parameters"),
    };
    DeviceError::BadParam {
        device: device.to_string(),
        param: param.into(),
        expected,
        got: e.to_string(),
    }
}

/// A runtime error of a driver core, naming the device and what failed (which board did
/// not answer within which timeout, a bus-off, ...).
pub fn call_error(device: &str, e: ClientError) -> DeviceError {
    tracing::debug!(device, "{e}");
    match e {
        ClientError::BadJoint { joint, joints } => DeviceError::InvalidJoint {
            joint: joint as i64,
            axes: joints,
        },
        e => DeviceError::failed(device, e),
    }
}
