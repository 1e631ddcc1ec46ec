//! The CAN networks of a robot, from its robots-configuration files.
//!
//! The robot file (e.g. `icub_all.xml`) is read as `yarprobotinterface` reads it
//! (includes, `file=` references, the electronics and mechanicals files), and each CAN
//! device becomes the boards it talks to, on the network its `CanDeviceNum` names:
//!
//! | device | boards |
//! |--------|--------|
//! | `canmotioncontrol` | a motor board per `CAN::CanAddresses` entry, joints laid out by `AxisMap`, `Encoder`, `Zeros`, limits; a joint-torque sensor per `TorqueId` ([`network::mc_boards`]) |
//! | `canBusAnalogSensor`, `canBusFtSensor` | a strain (`format 16`) or MAIS (`format 8`) board at `canAddress` |
//! | `canBusSkin` | a skin MTB per `skinCanIds` entry |
//! | `canBusInertialMTB` | an MTB per `canAddress` entry (a skin MTB at that address serves both) |
//! | `canBusVirtualAnalogSensor` | none (the host sends), but its network is brought up |
//!
//! A device whose parameters cannot be read is an error naming it and its file.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use icub_can::client::strain::AnalogFormat;
use icub_can::client::{McParams, StrainParams};
use icub_can::emulator::network::{self, BoardKind, NetworkSpec};
use yarp_devices::robotinterface::{read_robot_file, Device};
use yarp_proto::{Bottle, Property, Value};

/// Why a robot's CAN layout could not be read.
#[derive(Debug, thiserror::Error)]
pub enum LayoutError {
    #[error("{0}")]
    Read(String),
    #[error(
        "{dir}: no robot file (neither icub_all.xml nor the `config` of yarprobotinterface.ini)"
    )]
    NoRobotFile { dir: String },
    #[error("device {device} ({at}): {msg}")]
    Device {
        device: String,
        at: String,
        msg: String,
    },
    #[error("{0}: no CAN device (canmotioncontrol, canBus*) in this robot")]
    NoCanDevice(String),
}

/// The robot file of a robot directory: `icub_all.xml` (the whole robot), else the
/// `config` of its `yarprobotinterface.ini`.
pub fn robot_file(dir: &Path) -> Result<PathBuf, LayoutError> {
    let all = dir.join("icub_all.xml");
    if all.is_file() {
        return Ok(all);
    }
    let ini = std::fs::read_to_string(dir.join("yarprobotinterface.ini")).unwrap_or_default();
    Property::from_config_text(&ini)
        .ok()
        .and_then(|p| p.find("config").map(Value::to_string_bare))
        .map(|f| dir.join(f))
        .filter(|f| f.is_file())
        .ok_or_else(|| LayoutError::NoRobotFile {
            dir: dir.display().to_string(),
        })
}

/// The CAN networks of the robot described by `file`, sorted by `CanDeviceNum`.
pub fn networks(file: &Path) -> Result<Vec<NetworkSpec>, LayoutError> {
    let loaded =
        read_robot_file(file, &Property::new()).map_err(|e| LayoutError::Read(e.to_string()))?;
    let mut nets: BTreeMap<u32, Vec<BoardKind>> = BTreeMap::new();
    for device in &loaded.robot.devices {
        let Some((num, boards)) = device_boards(device)? else {
            continue;
        };
        let net = nets.entry(num).or_default();
        for b in boards {
            if !net.contains(&b) {
                net.push(b);
            }
        }
    }
    if nets.is_empty() {
        return Err(LayoutError::NoCanDevice(file.display().to_string()));
    }
    Ok(nets
        .into_iter()
        .map(|(num, mut boards)| {
            // One MTB at an address: a skin MTB also serves the inertial there.
            let skins: Vec<u8> = boards
                .iter()
                .filter_map(|b| match b {
                    BoardKind::Skin(a) => Some(*a),
                    _ => None,
                })
                .collect();
            boards.retain(|b| !matches!(b, BoardKind::Mtb(a) if skins.contains(a)));
            NetworkSpec { num, boards }
        })
        .collect())
}

/// The network and boards of one device; `None` for a device that is not on CAN.
fn device_boards(device: &Device) -> Result<Option<(u32, Vec<BoardKind>)>, LayoutError> {
    let fail = |msg: String| LayoutError::Device {
        device: device.name.clone(),
        at: device.at.to_string(),
        msg,
    };
    let kind = device.kind.as_str();
    if !matches!(
        kind,
        "canmotioncontrol"
            | "canBusAnalogSensor"
            | "canBusFtSensor"
            | "canBusSkin"
            | "canBusInertialMTB"
            | "canBusVirtualAnalogSensor"
    ) {
        return Ok(None);
    }
    let config = device.to_property().map_err(|e| fail(e.to_string()))?;
    let group = (kind == "canmotioncontrol").then_some("CAN");
    let num = ["CanDeviceNum", "canDeviceNum"]
        .iter()
        .find_map(|k| lookup_one(&config, group, k))
        .ok_or_else(|| fail("no CanDeviceNum".into()))?;
    let num: u32 = num
        .parse()
        .map_err(|_| fail(format!("CanDeviceNum {num:?} is not a number")))?;
    let addresses = |key: &str| -> Result<Vec<u8>, LayoutError> {
        lookup(&config, None, key)
            .ok_or_else(|| fail(format!("no {key}")))?
            .iter()
            .map(|a| parse_address(a).ok_or_else(|| fail(format!("{key}: {a:?} is not 1..14"))))
            .collect()
    };
    let boards = match kind {
        "canmotioncontrol" => {
            let params = McParams::from_lookup(&|g, k| lookup(&config, Some(g), k))
                .map_err(|e| fail(e.to_string()))?;
            let torque_max: Vec<f64> = lookup(&config, Some("GENERAL"), "TorqueMax")
                .unwrap_or_default()
                .iter()
                .map(|v| v.parse().unwrap_or(0.0))
                .collect();
            network::mc_boards(&params, &torque_max)
        }
        "canBusAnalogSensor" | "canBusFtSensor" => {
            let p = StrainParams::from_lookup(&|k| lookup_one(&config, None, k))
                .map_err(|e| fail(e.to_string()))?;
            vec![match p.format {
                AnalogFormat::Bits16 => BoardKind::Strain(p.address),
                AnalogFormat::Bits8 => BoardKind::Mais(p.address),
            }]
        }
        "canBusSkin" => addresses("skinCanIds")?
            .into_iter()
            .map(BoardKind::Skin)
            .collect(),
        "canBusInertialMTB" => addresses("canAddress")?
            .into_iter()
            .map(BoardKind::Mtb)
            .collect(),
        _ => Vec::new(),
    };
    Ok(Some((num, boards)))
}

/// A CAN address, decimal or `0x` hex, 1..=14.
fn parse_address(s: &str) -> Option<u8> {
    let s = s.trim().trim_matches('"');
    let a = match s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        Some(h) => u8::from_str_radix(h, 16).ok()?,
        None => s.parse().ok()?,
    };
    (1..=14).contains(&a).then_some(a)
}

/// The values of `(key v1 v2 ...)` in `group` (`None`: top level); a single list value is
/// flattened, as the devices read them.
fn lookup(config: &Property, group: Option<&str>, key: &str) -> Option<Vec<String>> {
    let line: &Bottle = match group {
        Some(g) => config.find_group(g)?.find_group(key)?,
        None => config.find_group(key)?,
    };
    let rest: Vec<&Value> = line.iter().skip(1).collect();
    if let [only] = rest.as_slice() {
        if let Some(list) = only.as_list() {
            return Some(list.iter().map(Value::to_string_bare).collect());
        }
    }
    Some(rest.into_iter().map(Value::to_string_bare).collect())
}

/// The first value of `key` in `group`, else at the top level.
fn lookup_one(config: &Property, group: Option<&str>, key: &str) -> Option<String> {
    group
        .and_then(|g| lookup(config, Some(g), key))
        .or_else(|| lookup(config, None, key))
        .and_then(|v| v.into_iter().next())
}
