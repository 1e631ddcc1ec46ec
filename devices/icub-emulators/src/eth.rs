//! The Ethernet board emulator behind `icub-eth-emulator`: every board a robot directory
//! names, each an [`icub_eth::board::BoardEngine`] on its own UDP socket
//! (`IpAddress:IpPort` of its `ETH_BOARD`, through the [`AddressMap`]), answering the
//! host as the board's firmware does and streaming its regulars at the rate the host
//! configures (`eOmn_appl_config_t`).
//!
//! An emulated board knows what a real one knows, and shares no code with the host's
//! drivers (crate `icubmod`), so that a misreading of the robot's files cannot hide on
//! both sides:
//!
//! - from the electronics files (`hardware/electronics/*-eln.xml`, read with the robot
//!   interface's XML reader): `ETH_BOARD_PROPERTIES` `IpAddress`, `IpPort`, `Type`,
//!   `maxSizeRXpacket` and `ETH_BOARD_SETTINGS/Name`;
//! - how many joints it drives (the motors wired to it): `GENERAL/Joints` of each
//!   `embObjMotionControl` device of the robot's top-level file (`yarprobotinterface.ini`'s
//!   `config`) whose `ETH_BOARD` is the board, and nothing else of those files;
//! - everything else from the host's datagrams: the sensor entities (strain, MAIS,
//!   temperatures, inertials, POS, FT, battery, skin) from the `verifyactivate` service
//!   configurations (the board engine's `auto_entities`); which inertial sensors exist
//!   (their `eOas_sensor_t` and the id their readings carry, `port << 4 | address` of
//!   their CAN board) from the inertials3 configuration, and which of them stream from
//!   the host's `eOas_inertial3_config_t`; the skin patches' MTBs from the skin
//!   configuration, and their transmitting triangles from the host's triangle
//!   configurations; the running cycle from the host's `eOmn_appl_config_t`.
//!
//! Joints are emulated by the board engine's joint model ([`SimpleJoint`]), starting at
//! raw 0 and placed inside the hardware limits of the host's joint configuration (a joint
//! sits inside its mechanical range); sensors stream slowly varying values.
//!
//! With [`ServeOptions::record`] (`icub-eth-emulator --record DIR`) every ROP a host sends
//! to a board is written to `DIR/<board's robot IP>.jsonl` (see [`record`]).

pub mod record;

use std::collections::BTreeMap;
use std::net::{Ipv4Addr, SocketAddr, SocketAddrV4, UdpSocket};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use icub_eth::board::{next_multiple, BoardConfig, BoardEngine, BoardEvent};
use icub_eth::entities::analog::{
    sensor_type as st, ByteArray, FtStatus, FtTimedValue, Inertial3Config, Inertial3Data,
    Inertial3Status, MaisStatus, StrainStatus, TemperatureData, TemperatureStatus,
};
use icub_eth::entities::boards::EthBoardType;
use icub_eth::entities::mn::category;
use icub_eth::entities::service::{SensorSetConfig, SkinServiceConfig};
use icub_eth::id::{endpoint as ep, entity as en, ids, tag};
use icub_eth::plant::{JointModel, SimpleJoint};
use icub_eth::Entity;
pub use icub_eth::{AddressMap, ADDRESS_MAP_ENV};

use crate::body;
use yarp_devices::robotinterface::read_robot_str;
use yarp_proto::{Bottle, Property, Value};

/// What a board knows of itself: its `ETH_BOARD` in the electronics files.
#[derive(Debug, Clone, PartialEq)]
pub struct BoardParams {
    pub ip: Ipv4Addr,
    pub port: u16,
    pub board_type: EthBoardType,
    /// `Type` as written.
    pub type_name: String,
    pub max_rx_packet: usize,
    /// `ETH_BOARD_SETTINGS/Name` (`NOT-NAMED` when empty).
    pub name: String,
}

/// A value's text (a string's own, a number's digits), without quotes.
fn text(v: &Value) -> String {
    v.to_string_bare().trim().trim_matches('"').to_string()
}

fn number(v: &Value) -> Option<f64> {
    v.as_f64().or_else(|| text(v).parse().ok())
}

impl BoardParams {
    /// How a board is named in messages: `IP (name)`.
    pub fn who(&self) -> String {
        format!("{} ({})", self.ip, self.name)
    }

    /// `ETH_BOARD` of a device's (or an electronics file's) configuration.
    pub fn read(config: &Property) -> Result<Self, String> {
        let board = config.find_group("ETH_BOARD").ok_or("no group ETH_BOARD")?;
        let props = board
            .find_group("ETH_BOARD_PROPERTIES")
            .ok_or("no group ETH_BOARD/ETH_BOARD_PROPERTIES")?;
        let ip_text = props
            .find("IpAddress")
            .map(text)
            .ok_or("no ETH_BOARD_PROPERTIES/IpAddress")?;
        let ip = ip_text.parse().map_err(|_| {
            format!("ETH_BOARD_PROPERTIES/IpAddress `{ip_text}` is no IPv4 address")
        })?;
        let num = |b: &Bottle, k: &str| -> Result<Option<f64>, String> {
            match b.find(k) {
                None => Ok(None),
                Some(v) => number(v)
                    .map(Some)
                    .ok_or_else(|| format!("{k} `{}` is no number", text(v))),
            }
        };
        let port = num(props, "IpPort")?.map_or(12345, |p| p as u16);
        let type_name = props.find("Type").map(text).unwrap_or_default();
        let board_type = EthBoardType::from_name(&type_name).unwrap_or(EthBoardType::Unknown);
        let max_rx_packet = num(props, "maxSizeRXpacket")?.map_or(768, |v| v as usize);
        let name = board
            .find_group("ETH_BOARD_SETTINGS")
            .and_then(|s| s.find("Name"))
            .map(text)
            .filter(|n| !n.is_empty())
            .unwrap_or_else(|| "NOT-NAMED".into());
        Ok(Self {
            ip,
            port,
            board_type,
            type_name,
            max_rx_packet,
            name,
        })
    }
}

/// What one emulated board carries before a host talks to it.
#[derive(Debug, Clone)]
pub struct BoardSpec {
    pub params: BoardParams,
    /// How many joints (and motors) are wired to it.
    pub joints: usize,
    /// The protocol versions the board announces (management, motion control, analog
    /// sensors, skin); `None`: those of the host (a board with matching firmware).
    pub protocol: Option<[icub_eth::entities::mn::Version; 4]>,
    /// The devices that use the board (for the start-up listing).
    pub users: Vec<String>,
    /// Where the board sits in the robot's body (the mechanical files): its joints
    /// (board joint, the axis' name, raw units per degree) and the F/T sensors on its
    /// CAN ports (`(port, address)`, the sensor's name).
    pub wiring: Wiring,
}

/// How a board is wired into the robot's body.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Wiring {
    pub joints: Vec<(usize, String, f64)>,
    pub ft: Vec<((u8, u8), String)>,
}

impl BoardSpec {
    fn new(params: BoardParams) -> Self {
        Self {
            params,
            joints: 0,
            protocol: None,
            users: Vec::new(),
            wiring: Wiring::default(),
        }
    }

    fn config(&self) -> BoardConfig {
        let p = &self.params;
        let mut c = BoardConfig::new(&p.name, p.ip, p.board_type);
        c.joints = self.joints.min(255) as u8;
        c.max_rx_packet = p.max_rx_packet;
        // A real board's datagrams fit one Ethernet frame; the regulars of the largest
        // boards (12 joints, MAIS and skin) then take several datagrams per period.
        c.max_tx_packet = 1400;
        // the sensors come with the host's service configurations
        c.auto_entities = true;
        if let Some(v) = self.protocol {
            c.protocol = v;
        }
        c
    }
}

const DTD: &str = r#"<!DOCTYPE robot PUBLIC "-//YARP//DTD yarprobotinterface 3.0//EN" "http://www.yarp.it/DTD/yarprobotinterfaceV3.0.dtd">"#;

/// The robot's top-level XML file: `yarprobotinterface.ini`'s `config`.
pub fn robot_file(dir: &Path) -> Result<PathBuf, String> {
    let ini = dir.join("yarprobotinterface.ini");
    let text = std::fs::read_to_string(&ini).map_err(|e| format!("{}: {e}", ini.display()))?;
    let name = text
        .lines()
        .filter_map(|l| l.trim().strip_prefix("config"))
        .map(str::trim)
        .find(|s| !s.is_empty())
        .ok_or_else(|| format!("{}: no `config` line", ini.display()))?;
    Ok(dir.join(name))
}

/// The boards of a robot directory (see the module documentation).
pub fn robot_boards(dir: &Path, top: Option<&Path>) -> Result<Vec<BoardSpec>, String> {
    let mut boards: BTreeMap<Ipv4Addr, BoardSpec> = BTreeMap::new();
    // Every board the electronics files name.
    let eln_dir = dir.join("hardware/electronics");
    let mut eln: Vec<PathBuf> = std::fs::read_dir(&eln_dir)
        .map_err(|e| format!("{}: {e}", eln_dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.to_string_lossy().ends_with("-eln.xml"))
        .collect();
    eln.sort();
    for file in &eln {
        let xml = format!(
            "<?xml version=\"1.0\"?>\n{DTD}\n<robot name=\"eln\" build=\"0\" portprefix=\"/eln\" xmlns:xi=\"http://www.w3.org/2001/XInclude\"><devices><device name=\"eln\" type=\"eln\"><xi:include href=\"{}\"/></device></devices></robot>",
            file.file_name().map(|f| f.to_string_lossy()).unwrap_or_default()
        );
        let loaded = read_robot_str(&xml, &eln_dir, &Property::default())
            .map_err(|e| format!("{}: {e}", file.display()))?;
        let Some(dev) = loaded.robot.devices.first() else {
            continue;
        };
        let cfg = dev.to_property().map_err(|e| e.to_string())?;
        // a mixed robot's CAN adapter (`canbusdevice` and a `CAN` group) is no Ethernet board
        if cfg.find_group("ETH_BOARD").is_none() && cfg.find_group("CAN").is_some() {
            tracing::debug!("{}: a CAN adapter, not an Ethernet board", file.display());
            continue;
        }
        let params = BoardParams::read(&cfg).map_err(|e| format!("{}: {e}", file.display()))?;
        boards
            .entry(params.ip)
            .or_insert_with(|| BoardSpec::new(params));
    }
    // The joints wired to them (and who uses them, for the listing).
    let top = match top {
        Some(t) => t.to_path_buf(),
        None => robot_file(dir)?,
    };
    let loaded = yarp_devices::robotinterface::read_robot_file(&top, &Property::default())
        .map_err(|e| format!("{}: {e}", top.display()))?;
    for dev in &loaded.robot.devices {
        if !dev.kind.starts_with("embObj") {
            continue;
        }
        let cfg = dev.to_property().map_err(|e| e.to_string())?;
        let params = match BoardParams::read(&cfg) {
            Ok(p) => p,
            Err(e) => {
                tracing::warn!("device {}: {e}: not emulated", dev.name);
                continue;
            }
        };
        let b = boards
            .entry(params.ip)
            .or_insert_with(|| BoardSpec::new(params));
        b.users.push(format!("{} ({})", dev.name, dev.kind));
        if dev.kind == "embObjMotionControl" {
            b.joints = cfg
                .find_group("GENERAL")
                .and_then(|g| g.find("Joints"))
                .and_then(number)
                .map_or(0, |n| n.max(0.0) as usize);
            b.wiring.joints = joint_wiring(&cfg);
        }
        if dev.kind == "embObjMultipleFTsensors" || dev.kind == "embObjFTsensor" {
            b.wiring.ft.extend(ft_wiring(&cfg));
        }
    }
    Ok(boards.into_values().collect())
}

/// The values of a group line, as texts (a list value or the rest of the line).
fn line_texts(group: &Bottle, key: &str) -> Vec<String> {
    let Some(line) = group.find_group(key) else {
        return Vec::new();
    };
    let rest = &line.items()[1..];
    let items = match rest {
        [v] if v.is_list() => v.as_list().map(Bottle::items).unwrap_or_default(),
        _ => rest,
    };
    items.iter().map(text).collect()
}

/// A motion control device's joints in the body: `GENERAL` `AxisMap`, `AxisName` and
/// `Encoder` (the mechanical description of the board's axes).
fn joint_wiring(cfg: &Property) -> Vec<(usize, String, f64)> {
    let Some(general) = cfg.find_group("GENERAL") else {
        return Vec::new();
    };
    let map = line_texts(general, "AxisMap");
    let names = line_texts(general, "AxisName");
    let encoders = line_texts(general, "Encoder");
    names
        .iter()
        .enumerate()
        .filter_map(|(i, name)| {
            let joint = map
                .get(i)
                .and_then(|m| m.parse::<f64>().ok())
                .map_or(i, |m| m as usize);
            let enc: f64 = encoders.get(i)?.parse().ok()?;
            (enc != 0.0).then(|| (joint, name.clone(), enc))
        })
        .collect()
}

/// An F/T device's sensors on the board's CAN ports: `SERVICE/PROPERTIES/SENSORS` `id`
/// and `location` (`CAN2:13`: port 1, address 13).
fn ft_wiring(cfg: &Property) -> Vec<((u8, u8), String)> {
    let Some(sensors) = cfg
        .find_group("SERVICE")
        .and_then(|s| s.find_group("PROPERTIES"))
        .and_then(|p| p.find_group("SENSORS"))
    else {
        return Vec::new();
    };
    let ids = line_texts(sensors, "id");
    let locations = line_texts(sensors, "location");
    ids.into_iter()
        .zip(locations)
        .filter_map(|(id, loc)| {
            let (port, addr) = loc.strip_prefix("CAN")?.split_once(':')?;
            let port: u8 = port.parse().ok()?;
            Some(((port.checked_sub(1)?, addr.parse().ok()?), id))
        })
        .collect()
}

/// The CAN id of an MTB's taxel message (iCub CAN protocol): the class
/// `ICUBCANPROTO_CLASS_PERIODIC_SKIN` (4) in bits 8-10, the sending MTB's address in bits
/// 4-7, the triangle (the "destination" of a periodic message) in bits 0-3.
fn skin_frame_id(addr: u8, triangle: u8) -> u16 {
    const CLASS_PERIODIC_SKIN: u16 = 4;
    CLASS_PERIODIC_SKIN << 8 | u16::from(addr & 0xf) << 4 | u16::from(triangle & 0xf)
}

/// The id an inertial reading carries for a sensor at `location` (an `eObrd_location_t`:
/// place in bits 0-1, for CAN (1) and extended CAN (3) the port in bit 2 and the address
/// in bits 3-6): `port << 4 | address` of its CAN board; 0 for a sensor on the Ethernet
/// board itself (its readings are known by their type).
fn inertial_id(location: u8) -> u8 {
    match location & 3 {
        1 | 3 => ((location >> 2) & 1) << 4 | ((location >> 3) & 0xf),
        _ => 0,
    }
}

/// What a board learned of its sensors from the host.
#[derive(Debug, Default, Clone)]
struct Learned {
    /// The FT service's sensors, in the board's order: `(port, address)` of each.
    ft: Vec<(u8, u8)>,
    /// The strain service's board: `(port, address)`.
    strain: Option<(u8, u8)>,
    /// The inertials3 service's sensors, in the board's order: their `eOas_sensor_t` and
    /// the id their readings carry.
    inertials: Vec<(u8, u8)>,
    /// The MTB addresses of each skin patch.
    skin_patches: Vec<Vec<u8>>,
    skin: SkinTriangles,
}

impl Learned {
    /// A service the host configured and the board verified.
    fn verified(&mut self, cat: u8, config: &[u8]) {
        match cat {
            category::STRAIN => {
                self.strain = config
                    .get(..icub_eth::entities::service::StrainServiceConfig::SIZE)
                    .and_then(|b| {
                        icub_eth::entities::service::StrainServiceConfig::from_bytes(b).ok()
                    })
                    .map(|c| (c.can_location.port, c.can_location.addr));
            }
            category::FT => {
                self.ft = icub_eth::entities::service::CanSensorsConfig::from_ft_bytes(config)
                    .sensors
                    .iter()
                    .map(|d| (d.can_location.port, d.can_location.addr))
                    .collect();
            }
            category::INERTIALS3 => {
                self.inertials = SensorSetConfig::from_inertial3_bytes(config)
                    .sensors
                    .iter()
                    .map(|d| (d.type_of_sensor, inertial_id(d.location)))
                    .collect();
            }
            category::SKIN => {
                let Some(c) = config
                    .get(..SkinServiceConfig::SIZE)
                    .and_then(|b| SkinServiceConfig::from_bytes(b).ok())
                else {
                    return;
                };
                self.skin_patches = c.can_map[..usize::from(c.num_of_patches.min(4))]
                    .iter()
                    .map(|ports| {
                        let mask = ports[0] | ports[1];
                        (0..16u8).filter(|a| mask & (1 << a) != 0).collect()
                    })
                    .collect();
                self.skin = SkinTriangles::default();
            }
            _ => {}
        }
    }
}

/// Which triangles of each skin patch's MTBs transmit, by address (16 bits, one per
/// triangle), as the host's triangle configurations set them; a patch never configured
/// transmits all (the old-style skins).
#[derive(Debug, Default, Clone)]
struct SkinTriangles {
    per_patch: Vec<Option<std::collections::HashMap<u8, u16>>>,
}

impl SkinTriangles {
    /// A `cmmnds_trianglescfg` of patch `p`: the triangles `id_start..=id_end` of the
    /// addressed boards enabled or disabled.
    fn apply(&mut self, p: usize, addrs: &[u8], c: &icub_eth::entities::skin::SkinTrianglesConfig) {
        if self.per_patch.len() <= p {
            self.per_patch.resize(p + 1, None);
        }
        let masks = self.per_patch[p].get_or_insert_with(Default::default);
        let dest = c.can_destination[0] | c.can_destination[1];
        let mut bits = 0u16;
        for t in c.id_start..=c.id_end.min(15) {
            bits |= 1 << t;
        }
        for &a in addrs {
            if a < 16 && dest & (1 << a) != 0 {
                let m = masks.entry(a).or_insert(0);
                *m = if c.enable != 0 { *m | bits } else { *m & !bits };
            }
        }
    }

    fn enabled(&self, p: usize, addr: u8, triangle: u8) -> bool {
        match self.per_patch.get(p).and_then(Option::as_ref) {
            None => true,
            Some(m) => m.get(&addr).is_some_and(|bits| bits & (1 << triangle) != 0),
        }
    }
}

/// Writes the values of the sensors a board has (those the host's services gave it),
/// slowly varying so that streams visibly change.
fn update_sensors(
    engine: &mut BoardEngine,
    learned: &Learned,
    felt: Option<(&Wiring, &body::Readings)>,
    t: f64,
    age_us: u64,
    tick: u64,
) {
    let s = (t * 0.5).sin();
    let store = engine.store_mut();
    let has = |e: u8| store.count(ep::ANALOG_SENSORS, e);
    let (strains, temperatures, maises, poses, batteries, fts) = (
        has(en::AS_STRAIN),
        has(en::AS_TEMPERATURE),
        has(en::AS_MAIS),
        has(en::AS_POS),
        has(en::AS_BATTERY),
        has(en::AS_FT),
    );
    if strains > 0 {
        // Full scale 2000 N / 50 N·m (strain2 defaults); values as fractions of it, in
        // the boards' encodings (offset binary values, big-endian full scales).
        let full = [2000u16, 2000, 2000, 50, 50, 50];
        // what the body makes the strain at this CAN place read, else a slow pattern
        let sensed = felt.and_then(|(wiring, readings)| {
            let place = learned.strain.as_ref()?;
            let name = &wiring.ft.iter().find(|(p, _)| p == place)?.1;
            readings.ft.get(name).copied()
        });
        let frac = match sensed {
            Some(v) => {
                std::array::from_fn(|k| (v[k] / f64::from(full[k])).clamp(-1.0, 32767.0 / 32768.0))
            }
            None => [0.01 * s, 0.02 * s, 0.1, 0.01 * s, 0.02, 0.03 * s],
        };
        let readings: Vec<i16> = frac.iter().map(|f| (f * 32768.0) as i16).collect();
        let status = StrainStatus {
            fullscale: StrainStatus::full_scales_of(&full),
            calibrated: StrainStatus::values_of(&readings),
            uncalibrated: StrainStatus::values_of(&readings),
        };
        let _ = store.write(
            ids::analog(en::AS_STRAIN, 0, tag::AS_STRAIN_STATUS),
            &status,
        );
    }
    if temperatures > 0 {
        // the strain2's temperature, 0.1 °C
        let _ = store.write(
            ids::analog(en::AS_TEMPERATURE, 0, tag::AS_XX_STATUS),
            &TemperatureStatus {
                data: vec![TemperatureData {
                    id: 0,
                    type_of_sensor: st::TEMPERATURE_T1,
                    value: (253.0 + 5.0 * s) as i16,
                    timestamp: (age_us / 1000) as u32,
                }],
            },
        );
    }
    if maises > 0 {
        let v: Vec<u8> = (0..15)
            .map(|k| (128.0 + 100.0 * (t + k as f64).sin()) as u8)
            .collect();
        let status = MaisStatus {
            the15values: ByteArray::from_u8(&v),
        };
        let _ = store.write(ids::analog(en::AS_MAIS, 0, tag::AS_MAIS_STATUS), &status);
    }
    if poses > 0 {
        // One value per hand port (eObrd_portpos_t 0-6: open/close 0-3, abductions 4
        // and 6), as the boards send them; embObjPOS picks its sensors' ports.
        let values: Vec<i16> = (0..7).map(|k| (100.0 * s) as i16 + 100 * k).collect();
        let _ = store.write(
            ids::analog(en::AS_POS, 0, tag::AS_XX_STATUS),
            &icub_eth::entities::analog::PosStatus { values },
        );
    }
    if batteries > 0 {
        // A 48 V pack at 85 % in use, drawing ~2 A, at 25 °C.
        let _ = store.write(
            ids::analog(en::AS_BATTERY, 0, tag::AS_BATTERY_STATUS_TIMEDVALUE),
            &icub_eth::entities::analog::BatteryStatus {
                age: age_us,
                temperature: 250,
                status: 2,
                voltage: 48.3,
                current: 2.0 + 0.2 * s as f32,
                charge: 85.0,
            },
        );
    }
    for (p, addrs) in learned.skin_patches.iter().enumerate() {
        // Two CAN frames per triangle (7 + 5 taxels), 24 frames per status, in turn.
        let all: Vec<(u8, u8, bool)> = addrs
            .iter()
            .flat_map(|a| (0..16u8).flat_map(move |t| [(*a, t, false), (*a, t, true)]))
            .filter(|(a, t, _)| learned.skin.enabled(p, *a, *t))
            .collect();
        if all.is_empty() {
            continue;
        }
        let start = (tick as usize * 24) % all.len();
        let level = (128.0 + 100.0 * s) as u8;
        let frames = (0..24.min(all.len()))
            .map(|k| {
                let (a, t, second) = all[(start + k) % all.len()];
                let head = if second { 0xC0 } else { 0x40 };
                icub_eth::entities::skin::SkinCanData::new(
                    skin_frame_id(a, t),
                    &[head, level, level, level, level, level, level, level],
                )
            })
            .collect();
        let _ = store.write(
            ids::skin(p as u8, tag::SK_SKIN_STATUS_ARRAYOFCANDATA),
            &icub_eth::entities::skin::SkinStatus { frames },
        );
    }
    // the inertial sensors the host's config enables (bit k: sensor k of the service)
    let enabled = store
        .read::<Inertial3Config>(ids::analog(en::AS_INERTIAL3, 0, tag::AS_XX_CONFIG))
        .map_or(0, |c| c.enabled);
    let inertials: Vec<(u8, u8)> = learned
        .inertials
        .iter()
        .enumerate()
        .filter(|(k, _)| *k < 32 && enabled & (1 << k) != 0)
        .map(|(_, s)| *s)
        .collect();
    if !inertials.is_empty() {
        // Four readings per status, the sensors taken in turn (as the boards fill it).
        let n = inertials.len();
        let data = (0..n.min(4))
            .map(|k| {
                let (kind, id) = inertials[(tick as usize * 4 + k) % n];
                // the IMU's in its units (BNO055), the MTBs' and the board's raw
                let (x, y, z) = match kind {
                    st::IMU_ACC | st::ACCEL_MTB_INT | st::ACCEL_MTB_EXT | st::ACCEL_ST_LIS3X => {
                        (0.0, 0.0, 981.0)
                    }
                    st::IMU_GYR | st::GYROS_MTB_EXT | st::GYROS_ST_L3G4200D => (16.0 * s, 0.0, 0.0),
                    st::IMU_MAG => (320.0, 0.0, -640.0),
                    st::IMU_EUL => (0.0, 0.0, 16.0 * 10.0 * s),
                    _ => (0.0, 0.0, 0.0),
                };
                Inertial3Data {
                    // `port << 4 | address` of the sensor's CAN board, as boards send it
                    id,
                    type_of_sensor: kind,
                    status: 0,
                    seq: tick as u8,
                    timestamp: (age_us / 1000) as u32,
                    w: 0,
                    x: x as i16,
                    y: y as i16,
                    z: z as i16,
                }
            })
            .collect();
        let _ = store.write(
            ids::analog(en::AS_INERTIAL3, 0, tag::AS_XX_STATUS),
            &Inertial3Status { data },
        );
    }
    for i in 0..fts {
        let s = s as f32;
        // what the body makes the sensor at this CAN place read, else a slow pattern
        let sensed = felt.and_then(|(wiring, readings)| {
            let place = learned.ft.get(usize::from(i))?;
            let name = &wiring.ft.iter().find(|(p, _)| p == place)?.1;
            readings.ft.get(name).map(|v| v.map(|x| x as f32))
        });
        let ft = FtStatus {
            timed_value: FtTimedValue {
                age: age_us,
                values: sensed.unwrap_or([s, 2.0 * s, 9.81, 0.1 * s, 0.2 * s, 0.3]),
                ..Default::default()
            },
            ..Default::default()
        };
        let _ = store.write(ids::analog(en::AS_FT, i, tag::AS_FT_STATUS), &ft);
    }
}

/// A board served on its socket until `stop`.
pub struct ServedBoard {
    pub spec: BoardSpec,
    pub local: SocketAddrV4,
}

/// How the boards are served beyond their addresses.
#[derive(Debug, Clone, Default)]
pub struct ServeOptions {
    /// Record every ROP a host sends to a board in `DIR/<board's robot IP>.jsonl`
    /// ([`record`]).
    pub record: Option<PathBuf>,
    /// The robot's body: the F/T sensors read what it makes them read.
    pub body: Option<SharedBody>,
}

/// Binds every board's socket (failing, naming the board, when an address is missing)
/// and serves them all on one thread until `stop` is set: each board answers its own
/// socket and streams at its own period, and the boards due together go out together,
/// so a robot of 17 boards at 1 ms costs ~1000 wake-ups a second, not 17000.
pub fn serve(
    specs: Vec<BoardSpec>,
    map: &AddressMap,
    stop: Arc<AtomicBool>,
) -> Result<(Vec<ServedBoard>, Vec<std::thread::JoinHandle<()>>), String> {
    serve_with(specs, map, stop, &ServeOptions::default())
}

/// [`serve`] with options (the recorder). The threads returned: the boards' one, and the
/// recorder's writer (it ends after the boards' thread, having written all it got).
pub fn serve_with(
    specs: Vec<BoardSpec>,
    map: &AddressMap,
    stop: Arc<AtomicBool>,
    options: &ServeOptions,
) -> Result<(Vec<ServedBoard>, Vec<std::thread::JoinHandle<()>>), String> {
    // the boards' time (and the recordings'): from now
    let epoch = Instant::now();
    let mut threads = Vec::new();
    let recorder = match &options.record {
        Some(dir) => {
            let ips: Vec<Ipv4Addr> = specs.iter().map(|s| s.params.ip).collect();
            let (r, t) = record::Recorder::start(dir, &ips)?;
            threads.push(t);
            Some(r)
        }
        None => None,
    };
    let mut served = Vec::new();
    let mut boards = Vec::new();
    for spec in specs {
        let local = SocketAddrV4::new(map.map(spec.params.ip), spec.params.port);
        let socket = UdpSocket::bind(local).map_err(|e| {
            format!(
                "BOARD {}: cannot bind {local}: {e} (give this address to an interface, e.g. `ip addr add {}/24 dev lo`, or map the robot's addresses with --address-map 10.0.1.0/24=127.0.1.0/24)",
                spec.params.who(),
                local.ip()
            )
        })?;
        // Non-blocking: after a wait every pending datagram is read, then the loop goes on.
        socket
            .set_nonblocking(true)
            .map_err(|e| format!("BOARD {}: {e}", spec.params.who()))?;
        // joints start at raw 0; the host's joint configuration places them inside
        // their hardware limits (SimpleJoint)
        let joints: Vec<Box<dyn JointModel>> = (0..spec.joints)
            .map(|_| Box::new(SimpleJoint::new(0.0)) as Box<dyn JointModel>)
            .collect();
        let engine = BoardEngine::with_joints(spec.config(), joints);
        boards.push(ServedState {
            socket,
            engine,
            who: spec.params.who(),
            index: boards.len(),
            recorder: recorder.clone(),
            peer: None,
            last_step: None,
            tick: 0,
            learned: Learned::default(),
            wiring: spec.wiring.clone(),
            felt: options.body.as_ref().map(|b| b.readings.clone()),
        });
        served.push(ServedBoard { spec, local });
    }
    // the writer ends when the boards' thread drops the last recorder
    drop(recorder);
    let body = options.body.clone();
    let t = std::thread::Builder::new()
        .name("eth-boards".into())
        .spawn(move || run_boards(boards, stop, epoch, body))
        .map_err(|e| e.to_string())?;
    threads.insert(0, t);
    Ok((served, threads))
}

/// One board as the serving thread keeps it.
struct ServedState {
    socket: UdpSocket,
    engine: BoardEngine,
    /// `IP (name)`, for logs.
    who: String,
    /// The board's place in the served list (its recording file).
    index: usize,
    recorder: Option<record::Recorder>,
    /// Where the host is (the sender of the last datagram).
    peer: Option<SocketAddr>,
    /// When the control loop last ran (the serving thread's time).
    last_step: Option<Duration>,
    tick: u64,
    learned: Learned,
    /// The board's place in the body, and what the body makes its sensors read.
    wiring: Wiring,
    felt: Option<Arc<std::sync::Mutex<body::Readings>>>,
}

impl ServedState {
    /// When this board next has something to do: a transmission, or its control step.
    fn next_work(&self, now: Duration) -> Duration {
        let tx_at = self.engine.next_transmit().unwrap_or(now + MAX_WAIT);
        self.next_step(now).min(tx_at)
    }

    /// The control loop's next run: at multiples of its period in the serving thread's
    /// time, as the regulars' schedule ([`icub_eth::board::next_multiple`]), so that the
    /// boards of commensurate periods wake the thread together (one wake-up a
    /// millisecond for a whole ergoCub, not one per board) and keep their phase after a
    /// late wake-up.
    fn next_step(&self, now: Duration) -> Duration {
        match self.last_step {
            Some(t) => next_multiple(t, self.step_period()),
            None => now,
        }
    }

    /// The control loop runs once per regulars period (what the host sees of it), at
    /// least every 5 ms: the status streams as often as on the board, at a fraction of the
    /// CPU of a 1 kHz loop.
    fn step_period(&self) -> Duration {
        self.engine
            .regular_period()
            .clamp(Duration::from_millis(1), MAX_WAIT)
    }

    /// Reads every pending datagram.
    fn receive(&mut self, buf: &mut [u8], epoch: Instant) {
        while let Ok((n, from)) = self.socket.recv_from(buf) {
            self.peer = Some(from);
            if let Some(r) = &self.recorder {
                r.record(self.index, epoch.elapsed(), from, &buf[..n]);
            }
            if let Err(e) = self.engine.handle_datagram(&buf[..n]) {
                tracing::debug!(board = %self.who, "dropped a datagram: {e}");
            }
            self.configured(epoch);
        }
    }

    /// Takes in what the host configured that the emulation follows (the services'
    /// sensors, the skin's triangles).
    fn configured(&mut self, epoch: Instant) {
        while let Some(ev) = self.engine.poll_event() {
            let id = match ev {
                BoardEvent::Verified {
                    category, config, ..
                } => {
                    self.learned.verified(category, &config);
                    // the new sensors have values at once (a strain's full scales, which
                    // the host may ask to be signalled right after the verification),
                    // as a board reads them from its CAN boards when it verifies
                    self.update_sensors(epoch.elapsed());
                    continue;
                }
                BoardEvent::Set(id) => id,
                _ => continue,
            };
            if (id.endpoint(), id.entity(), id.tag())
                != (
                    icub_eth::id::endpoint::SKIN,
                    en::SK_SKIN,
                    tag::SK_SKIN_CMMNDS_TRIANGLESCFG,
                )
            {
                continue;
            }
            let p = usize::from(id.index());
            let cfg = self
                .engine
                .store()
                .read::<icub_eth::entities::skin::SkinTrianglesConfig>(id);
            if let (Ok(cfg), Some(addrs)) = (cfg, self.learned.skin_patches.get(p)) {
                self.learned.skin.apply(p, addrs, &cfg);
            }
        }
    }

    /// Writes the sensors' values as they are `now` (since the boards began serving).
    fn update_sensors(&mut self, now: Duration) {
        let felt = self
            .felt
            .as_ref()
            .map(|f| f.lock().unwrap_or_else(|e| e.into_inner()).clone());
        update_sensors(
            &mut self.engine,
            &self.learned,
            felt.as_ref().map(|r| (&self.wiring, r)),
            now.as_secs_f64(),
            now.as_micros() as u64,
            self.tick,
        );
    }

    /// Steps the board when due and sends what it has.
    fn work(&mut self, epoch: Instant) {
        let now = epoch.elapsed();
        if now >= self.next_step(now) {
            let dt = self
                .last_step
                .map_or(Duration::ZERO, |t| now.saturating_sub(t));
            self.last_step = Some(now);
            self.engine.step(dt.as_secs_f64());
            self.tick += 1;
            self.update_sensors(now);
        }
        let now = epoch.elapsed();
        while let Some(d) = self.engine.poll_transmit(now) {
            if let Some(p) = self.peer {
                let _ = self.socket.send_to(&d, p);
            }
        }
    }
}

/// How often the body's statics are recomputed from the joints (its sensors' readings
/// are held between).
const BODY_PERIOD: Duration = Duration::from_millis(5);

/// The robot's body shared by the boards' thread (which poses it from the joints) and
/// whatever else reads its sensors (the serial IMUs).
#[derive(Debug, Clone)]
pub struct SharedBody {
    pub body: Arc<std::sync::Mutex<body::Body>>,
    pub readings: Arc<std::sync::Mutex<body::Readings>>,
}

impl SharedBody {
    pub fn new(b: body::Body) -> Self {
        let readings = b.readings();
        SharedBody {
            body: Arc::new(std::sync::Mutex::new(b)),
            readings: Arc::new(std::sync::Mutex::new(readings)),
        }
    }
}

/// Poses the body from the boards' joints and takes what its sensors read.
fn feel(shared: &SharedBody, boards: &[ServedState]) {
    let mut body = shared.body.lock().unwrap_or_else(|e| e.into_inner());
    for b in boards {
        for (j, name, encoder) in &b.wiring.joints {
            if let Some(joint) = b.engine.joint(*j) {
                body.set_position(name, (joint.feedback().position / encoder).to_radians());
            }
        }
    }
    let readings = body.readings();
    drop(body);
    *shared.readings.lock().unwrap_or_else(|e| e.into_inner()) = readings;
}

/// The longest the serving thread sleeps.
const MAX_WAIT: Duration = Duration::from_millis(5);

/// How late the boards' thread woke for due work, since the process started.
#[derive(Debug, Default)]
pub struct WakeStats {
    wakes: std::sync::atomic::AtomicU64,
    over_2ms: std::sync::atomic::AtomicU64,
    worst_us: std::sync::atomic::AtomicU64,
    /// Rounds of work (receiving, stepping and sending every board) longer than 1 ms.
    long_work: std::sync::atomic::AtomicU64,
    worst_work_us: std::sync::atomic::AtomicU64,
}

static WAKE: WakeStats = WakeStats {
    wakes: std::sync::atomic::AtomicU64::new(0),
    over_2ms: std::sync::atomic::AtomicU64::new(0),
    worst_us: std::sync::atomic::AtomicU64::new(0),
    long_work: std::sync::atomic::AtomicU64::new(0),
    worst_work_us: std::sync::atomic::AtomicU64::new(0),
};

impl WakeStats {
    fn note(&self, late: Duration) {
        self.wakes.fetch_add(1, Ordering::Relaxed);
        if late > Duration::from_millis(2) {
            self.over_2ms.fetch_add(1, Ordering::Relaxed);
        }
        self.worst_us
            .fetch_max(late.as_micros() as u64, Ordering::Relaxed);
    }

    fn note_work(&self, took: Duration) {
        if took > Duration::from_millis(1) {
            self.long_work.fetch_add(1, Ordering::Relaxed);
        }
        self.worst_work_us
            .fetch_max(took.as_micros() as u64, Ordering::Relaxed);
    }
}

/// The boards' thread's wake-ups for due work: how many, how many more than 2 ms late
/// (a 1 ms board then shows a silence of 3 periods), the latest (µs); its rounds of work
/// longer than 1 ms, and the longest (µs).
pub fn wake_stats() -> (u64, u64, u64, u64, u64) {
    (
        WAKE.wakes.load(Ordering::Relaxed),
        WAKE.over_2ms.load(Ordering::Relaxed),
        WAKE.worst_us.load(Ordering::Relaxed),
        WAKE.long_work.load(Ordering::Relaxed),
        WAKE.worst_work_us.load(Ordering::Relaxed),
    )
}

fn run_boards(
    mut boards: Vec<ServedState>,
    stop: Arc<AtomicBool>,
    epoch: Instant,
    body: Option<SharedBody>,
) {
    let mut body_due = Duration::ZERO;
    // A board keeps its period in firmware; here the thread asks for real-time
    // scheduling like the host's receiver (best effort: refused without the capability).
    yarp_net::realtime::try_fifo_current_thread(
        "eth boards",
        yarp_net::realtime::ETH_RECEIVER_PRIORITY,
    );
    let mut buf = vec![0u8; 65536];
    let mut poller = Poller::new(boards.iter().map(|b| &b.socket));
    while !stop.load(Ordering::Relaxed) {
        let now = epoch.elapsed();
        let wait = boards
            .iter()
            .map(|b| b.next_work(now))
            .min()
            .map_or(MAX_WAIT, |t| t.saturating_sub(now))
            .clamp(Duration::from_micros(100), MAX_WAIT);
        poller.wait(wait);
        // How late this thread woke for its next due work (the boards' streams can be no
        // more regular than this): counted for the benches.
        let late = epoch.elapsed().saturating_sub(now + wait);
        if wait < MAX_WAIT {
            WAKE.note(late);
        }
        let woke = Instant::now();
        for (i, b) in boards.iter_mut().enumerate() {
            if poller.readable(i) {
                b.receive(&mut buf, epoch);
            }
        }
        if let Some(body) = &body {
            let now = epoch.elapsed();
            if now >= body_due {
                body_due = now + BODY_PERIOD;
                feel(body, &boards);
            }
        }
        for b in &mut boards {
            b.work(epoch);
        }
        WAKE.note_work(woke.elapsed());
    }
}

/// Waits on every board's socket at once; built once, its poll set is reused on every
/// wake-up. On Linux with `ppoll`, on the high-resolution timers: a socket's receive
/// timeout (SO_RCVTIMEO) counts in scheduler ticks, so a 1 ms wait took ~9 ms and boards
/// of 1 ms period sent ~115 ropframes a second instead of 1000.
#[cfg(target_os = "linux")]
struct Poller {
    fds: Vec<libc::pollfd>,
}

#[cfg(target_os = "linux")]
impl Poller {
    fn new<'a>(sockets: impl Iterator<Item = &'a UdpSocket>) -> Self {
        use std::os::fd::AsRawFd;
        let fds = sockets
            .map(|s| libc::pollfd {
                fd: s.as_raw_fd(),
                events: libc::POLLIN,
                revents: 0,
            })
            .collect();
        Poller { fds }
    }

    /// Until one socket has a datagram or `timeout` has passed.
    fn wait(&mut self, timeout: Duration) {
        let ts = libc::timespec {
            tv_sec: timeout.as_secs() as libc::time_t,
            tv_nsec: timeout.subsec_nanos() as libc::c_long,
        };
        for f in &mut self.fds {
            f.revents = 0;
        }
        // SAFETY: `fds` holds fds.len() valid pollfds, `ts` a valid timespec; no signal
        // mask is changed. On an error (EINTR) every `revents` stays 0.
        unsafe {
            libc::ppoll(
                self.fds.as_mut_ptr(),
                self.fds.len() as libc::nfds_t,
                &ts,
                std::ptr::null(),
            );
        }
    }

    /// Whether socket `i` had a datagram at the last wait.
    fn readable(&self, i: usize) -> bool {
        self.fds[i].revents & libc::POLLIN != 0
    }
}

/// Elsewhere: sleep, then try every socket (they are non-blocking).
#[cfg(not(target_os = "linux"))]
struct Poller;

#[cfg(not(target_os = "linux"))]
impl Poller {
    fn new<'a>(_sockets: impl Iterator<Item = &'a UdpSocket>) -> Self {
        Poller
    }
    fn wait(&mut self, timeout: Duration) {
        std::thread::sleep(timeout);
    }
    fn readable(&self, _i: usize) -> bool {
        true
    }
}
