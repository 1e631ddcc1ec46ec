//! What the iCub CAN devices share: reading their configuration the way icub-main does
//! (`GROUP` sections, multi-value lines), opening the CAN bus they name, and turning
//! driver-core errors into [`DeviceError`]s.

use std::sync::Arc;
use std::time::Instant;

use icub_can::client::ClientError;
use icub_can::CanBus;
use yarp_proto::{Bottle, Property, Value};

use yarp_devices::error::DeviceError;

/// Overrides the bus of every iCub CAN device that names none with `canBackend`, so a
/// robot's XML can run unmodified (see `launch-configs/icub-sim/robot/README.md`).
pub const BACKEND_ENV: &str = "YARP_ICUB_CAN_BACKEND";

/// Wall-clock time in seconds (the timestamps of YARP ports).
pub use yarp_proto::stamp::now;

/// The wall-clock time of an `Instant` in the past.
pub fn wall_time(at: Instant) -> f64 {
    now() - at.elapsed().as_secs_f64()
}

/// A value as the text icub-main would read with `asString` (numbers printed as such).
pub fn text(v: &Value) -> String {
    match v.as_str() {
        Some(s) => s.to_string(),
        None => String::from_utf8_lossy(&v.to_text_bare()).into_owned(),
    }
}

/// The device's instance name for logs and errors: yarprobotinterface's `id` (the XML
/// device name), else `default` (the device type).
pub fn device_id(config: &Property, default: &str) -> String {
    config.find("id").map_or_else(|| default.to_string(), text)
}

/// The values after the key of a line `(key v1 v2 ...)`; a single list value
/// (`(key (v1 v2))`) is flattened.
fn line_values(line: &Bottle) -> Vec<String> {
    let rest: Vec<&Value> = line.iter().skip(1).collect();
    if let [only] = rest.as_slice() {
        if let Some(list) = only.as_list() {
            return list.iter().map(text).collect();
        }
    }
    rest.into_iter().map(text).collect()
}

/// `key`'s values inside section `group` (`None`: top level), or `None` when absent.
pub fn lookup(config: &Property, group: Option<&str>, key: &str) -> Option<Vec<String>> {
    let line = match group {
        Some(g) => config.find_group(g)?.find_group(key)?,
        None => config.find_group(key)?,
    };
    Some(line_values(line))
}

/// The first value of `key` in `group`, falling back to the top level.
pub fn lookup_one(config: &Property, group: Option<&str>, key: &str) -> Option<String> {
    group
        .and_then(|g| lookup(config, Some(g), key))
        .or_else(|| lookup(config, None, key))
        .and_then(|v| v.into_iter().next())
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

/// Opens the CAN bus a device's configuration names: `canBackend`, else the
/// [`BACKEND_ENV`] variable, else `physDevice` (`canbusDevice` when it names an adapter
/// rather than `sharedcan`, as `canBusSkin` files do), with `CanDeviceNum`/`canDeviceNum`.
/// Keys are looked up in `group` first, then at the top level.
pub fn open_bus(
    device: &str,
    config: &Property,
    group: Option<&str>,
) -> Result<Arc<dyn CanBus>, DeviceError> {
    let env = std::env::var(BACKEND_ENV).ok().filter(|s| !s.is_empty());
    let get = |key: &str| -> Option<String> {
        let found = lookup_one(config, group, key);
        match key {
            "canBackend" | "CanBackend" => found.or_else(|| env.clone()),
            "physDevice" | "physdevice" => found.or_else(|| {
                ["canbusDevice", "canbusdevice"]
                    .iter()
                    .find_map(|k| lookup_one(config, group, k))
                    .filter(|d| d.trim_matches('"') != "sharedcan")
            }),
            _ => found,
        }
    };
    icub_can::bus::config::open_from_params(&get).map_err(|e| bus_error(device, e))
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lookup_groups_and_lists() {
        let p = Property::from_text(
            "(CAN (CanAddresses 1 2 3 4) (CanDeviceNum 1)) (GENERAL (AxisName \"a\" \"b\")) (canAddress 0x0D) (skinCanIds (14 13))",
        );
        assert_eq!(
            lookup(&p, Some("CAN"), "CanAddresses").unwrap(),
            ["1", "2", "3", "4"]
        );
        assert_eq!(lookup(&p, Some("GENERAL"), "AxisName").unwrap(), ["a", "b"]);
        assert_eq!(lookup(&p, None, "skinCanIds").unwrap(), ["14", "13"]);
        assert_eq!(lookup_one(&p, Some("CAN"), "canAddress"), Some("13".into()));
        assert!(lookup(&p, Some("CAN"), "nothing").is_none());
    }
}
