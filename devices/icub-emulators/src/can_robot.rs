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

use icub_can::emulator::network::{self, BoardKind, McLayout, NetworkSpec};
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
        "canmotioncontrol" => network::mc_boards(&mc_layout(&config).map_err(fail)?),
        "canBusAnalogSensor" | "canBusFtSensor" => {
            // `format 8` is a MAIS (eight-bit values), the default 16 a strain
            let address = lookup_one(&config, None, "canAddress")
                .and_then(|a| parse_address(&a))
                .ok_or_else(|| fail("canAddress is not 1..14".into()))?;
            match lookup_one(&config, None, "format")
                .as_deref()
                .map(str::trim)
            {
                Some("8") => vec![BoardKind::Mais(address)],
                None | Some("16") => vec![BoardKind::Strain(address)],
                Some(f) => return Err(fail(format!("format {f} is not 8 or 16"))),
            }
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

/// The boards of a `canmotioncontrol` part: `CAN/CanAddresses`, and per joint
/// (`GENERAL/Joints` of them) the axis, encoder, zero, limits and torque sensor.
fn mc_layout(config: &Property) -> Result<McLayout, String> {
    let numbers = |group: &str, key: &str| -> Vec<f64> {
        lookup(config, Some(group), key)
            .unwrap_or_default()
            .iter()
            .map(|v| number(v).unwrap_or(0.0))
            .collect()
    };
    let joints = numbers("GENERAL", "Joints")
        .first()
        .map(|n| *n as usize)
        .ok_or("no GENERAL/Joints")?;
    // per joint, what the file gives, else `default`
    let per_joint = |group: &str, key: &str, default: f64| -> Vec<f64> {
        let v = numbers(group, key);
        (0..joints)
            .map(|j| v.get(j).copied().unwrap_or(default))
            .collect()
    };
    let can_addresses = lookup(config, Some("CAN"), "CanAddresses")
        .ok_or("no CAN/CanAddresses")?
        .iter()
        .map(|a| parse_address(a).ok_or(format!("CanAddresses: {a:?} is not 1..14")))
        .collect::<Result<_, _>>()?;
    let (ids, chans) = (
        per_joint("GENERAL", "TorqueId", 0.0),
        per_joint("GENERAL", "TorqueChan", 0.0),
    );
    let axis_map = match numbers("GENERAL", "AxisMap") {
        v if v.len() >= joints => v[..joints].iter().map(|a| *a as usize).collect(),
        _ => (0..joints).collect(),
    };
    let (min, max) = (
        per_joint("LIMITS", "jntPosMin", f64::NEG_INFINITY),
        per_joint("LIMITS", "jntPosMax", f64::INFINITY),
    );
    Ok(McLayout {
        can_addresses,
        axis_map,
        encoder: per_joint("GENERAL", "Encoder", 1.0),
        zeros: per_joint("GENERAL", "Zeros", 0.0),
        limits: min.into_iter().zip(max).collect(),
        torque_max: per_joint("GENERAL", "TorqueMax", 0.0),
        // a sensor on a CAN address and a channel of six; TorqueId 0 is none
        torque_sensors: ids
            .iter()
            .zip(&chans)
            .map(|(&id, &ch)| {
                ((1.0..=14.0).contains(&id) && (0.0..=5.0).contains(&ch))
                    .then_some((id as u8, ch as u8))
            })
            .collect(),
    })
}

/// A CAN address, 1..=14.
fn parse_address(s: &str) -> Option<u8> {
    number(s)
        .filter(|a| (1.0..=14.0).contains(a) && a.fract() == 0.0)
        .map(|a| a as u8)
}

/// A number as the robots' files write them (decimal, `0x` hex).
fn number(s: &str) -> Option<f64> {
    let s = s.trim().trim_matches('"');
    match s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        Some(h) => i64::from_str_radix(h, 16).ok().map(|v| v as f64),
        None => s.parse().ok(),
    }
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
