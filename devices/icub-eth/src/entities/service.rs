//! Service configurations: the `eOmn_serv_config_data_*` structs that travel in a
//! `verifyactivate` command (`EoManagement.h`), for the service types the robots use:
//! MC `foc`, `mc4`, `mc4plus`, `mc4plusmais`, `mc2plus`, `mc4plusfaps`, `advfoc`; AS
//! `strain`, `mais`, `inertials3`, `temperatures`, `pos`, `ft`, `battery`; SK `skin`.
//! Coupling matrices and per-board descriptors are kept as their bytes where nothing here
//! interprets them; what a board needs to know (how many joints or sensors the service
//! has) is decoded.

use super::boards::{BoardInfo, CanLocation};
use super::mn::{category, service_type, SERVICE_CONFIG_DATA_SIZE};
use crate::id::{endpoint as ep, entity as en};
use crate::wire::{Entity, Reader, Writer};

/// `eOmc_jomo_descriptor_t` (5 bytes): actuator (1 byte union) and two encoders
/// (`eOmc_encoder_descriptor_t`: type, port:5 | pos:3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct JomoDescriptor {
    /// The actuator byte (a `eObrd_canlocation_t` for foc/mc4, a port for pwm).
    pub actuator: u8,
    /// (type `eOmc_encoder_t`, port, position `eOmc_position_t`).
    pub encoder1: (u8, u8, u8),
    pub encoder2: (u8, u8, u8),
}

fn enc_write(w: &mut Writer, e: (u8, u8, u8)) {
    w.u8(e.0);
    w.u8((e.1 & 0x1f) | (e.2 & 7) << 5);
}

fn enc_read(r: &mut Reader) -> (u8, u8, u8) {
    let t = r.u8();
    let b = r.u8();
    (t, b & 0x1f, b >> 5)
}

impl Entity for JomoDescriptor {
    const C_TYPE: &'static str = "eOmc_jomo_descriptor_t";
    const SIZE: usize = 5;
    fn write(&self, w: &mut Writer) {
        w.u8(self.actuator);
        enc_write(w, self.encoder1);
        enc_write(w, self.encoder2);
    }
    fn read(r: &mut Reader) -> Self {
        Self {
            actuator: r.u8(),
            encoder1: enc_read(r),
            encoder2: enc_read(r),
        }
    }
}

/// `eOmc_arrayof_4jomodescriptors_t` (24 bytes): EOarray head + 4 descriptors.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct JomoDescriptors(pub Vec<JomoDescriptor>);

impl Entity for JomoDescriptors {
    const C_TYPE: &'static str = "eOmc_arrayof_4jomodescriptors_t";
    const SIZE: usize = 24;
    fn write(&self, w: &mut Writer) {
        let n = self.0.len().min(4);
        w.bytes(&[4, 5, n as u8, 0]);
        for d in &self.0[..n] {
            w.entity(d);
        }
        w.zeros((4 - n) * 5);
    }
    fn read(r: &mut Reader) -> Self {
        let [_, item, size, _] = r.array();
        let n = if item == 5 {
            usize::from(size).min(4)
        } else {
            0
        };
        let v = (0..n).map(|_| r.entity()).collect();
        r.skip((4 - n) * 5);
        Self(v)
    }
}

/// `eOmc_4jomo_coupling_t` (292 bytes): joint2set, four `eOmc_jointset_configuration_t`
/// (16 bytes each, kept as bytes), joint2motor and motor2joint (4×4 q17.14), encoder2joint
/// (4×6 q17.14).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Coupling {
    pub joint2set: [u8; 4],
    pub jointset_config: [[u8; 16]; 4],
    pub joint2motor: [[i32; 4]; 4],
    pub motor2joint: [[i32; 4]; 4],
    pub encoder2joint: [[i32; 6]; 4],
}

/// 1.0 in q17.14 (`eOq17_14_t`).
pub const Q17_14_ONE: i32 = 1 << 14;

impl Default for Coupling {
    /// Uncoupled joints, each its own set: identity matrices.
    fn default() -> Self {
        let mut c = Self {
            joint2set: [0, 1, 2, 3],
            jointset_config: [[0; 16]; 4],
            joint2motor: [[0; 4]; 4],
            motor2joint: [[0; 4]; 4],
            encoder2joint: [[0; 6]; 4],
        };
        for i in 0..4 {
            c.joint2motor[i][i] = Q17_14_ONE;
            c.motor2joint[i][i] = Q17_14_ONE;
            c.encoder2joint[i][i] = Q17_14_ONE;
        }
        c
    }
}

impl Entity for Coupling {
    const C_TYPE: &'static str = "eOmc_4jomo_coupling_t";
    const SIZE: usize = 292;
    fn write(&self, w: &mut Writer) {
        w.bytes(&self.joint2set);
        for c in &self.jointset_config {
            w.bytes(c);
        }
        for row in self.joint2motor.iter().chain(self.motor2joint.iter()) {
            for v in row {
                w.i32(*v);
            }
        }
        for row in &self.encoder2joint {
            for v in row {
                w.i32(*v);
            }
        }
    }
    fn read(r: &mut Reader) -> Self {
        let joint2set = r.array();
        let jointset_config = [r.array(), r.array(), r.array(), r.array()];
        let mut m = |rows: usize| {
            let mut out = [[0i32; 4]; 4];
            for row in out.iter_mut().take(rows) {
                for v in row.iter_mut() {
                    *v = r.i32();
                }
            }
            out
        };
        let joint2motor = m(4);
        let motor2joint = m(4);
        let mut encoder2joint = [[0i32; 6]; 4];
        for row in encoder2joint.iter_mut() {
            for v in row.iter_mut() {
                *v = r.i32();
            }
        }
        Self {
            joint2set,
            jointset_config,
            joint2motor,
            motor2joint,
            encoder2joint,
        }
    }
}

/// The motion-control service configurations (`eOmn_serv_config_data_mc_t`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum McServiceConfig {
    /// `eOmn_serv_config_data_mc_foc_t` (324): 2FOC/AMCBLDC boards behind an EMS.
    Foc {
        /// `eObrd_version_t` of the CAN boards: firmware major, minor, build; protocol major, minor.
        version: [u8; 5],
        /// `eObrd_type_t` of the CAN boards.
        board_type: u8,
        jomos: JomoDescriptors,
        coupling: Coupling,
    },
    /// `eOmn_serv_config_data_mc_mc4_t` (28): MC4 CAN boards behind an EMS.
    Mc4 {
        version: [u8; 5],
        /// `eOmc_mc4shifts_t` (3 bytes).
        shifts: [u8; 3],
        /// `eObrd_canlocation_t` of each joint (12; unused ones 0).
        joints: [u8; 12],
        /// `eOmn_serv_config_data_as_mais_t` (6).
        mais: [u8; 6],
        broadcast_flags: u16,
    },
    /// `eOmn_serv_config_data_mc_mc4plus_t` / `_mc2plus_t` (316): PWM on the board.
    Mc4plus {
        jomos: JomoDescriptors,
        coupling: Coupling,
    },
    /// `eOmn_serv_config_data_mc_mc4plusmais_t` (324).
    Mc4plusMais {
        mais: [u8; 6],
        jomos: JomoDescriptors,
        coupling: Coupling,
    },
    /// `eOmn_serv_config_data_mc_mc4plusfaps_t` (340): POS sensors.
    Mc4plusFaps {
        pos: [u8; 24],
        jomos: JomoDescriptors,
        coupling: Coupling,
    },
    /// `eOmn_serv_config_data_mc_mc2pluspsc_t` (328).
    Mc2plusPsc {
        psc: [u8; 8],
        jomos: JomoDescriptors,
        coupling: Coupling,
        stop_switches: [u8; 4],
    },
    /// `eOmn_serv_config_data_mc_advfoc_t` (332): `eOmc_arrayof_4advjomodescriptors_t`
    /// (68: head + 4 × 16) and `eOmc_adv4jomo_coupling_t` (264), kept as bytes.
    AdvFoc {
        descriptors: [u8; 68],
        coupling: [u8; 264],
    },
}

impl McServiceConfig {
    /// Decodes the configuration of an MC service type from its 340 data bytes.
    pub fn parse(service_type_: u8, data: &[u8]) -> Option<Self> {
        if data.len() < SERVICE_CONFIG_DATA_SIZE {
            return None;
        }
        let mut r = Reader::new(data);
        Some(match service_type_ {
            service_type::MC_FOC => Self::Foc {
                version: r.array(),
                board_type: {
                    let t = r.u8();
                    r.skip(2);
                    t
                },
                jomos: r.entity(),
                coupling: r.entity(),
            },
            service_type::MC_MC4 => Self::Mc4 {
                version: r.array(),
                shifts: r.array(),
                joints: r.array(),
                mais: r.array(),
                broadcast_flags: r.u16(),
            },
            service_type::MC_MC4PLUS | service_type::MC_MC2PLUS => Self::Mc4plus {
                jomos: r.entity(),
                coupling: r.entity(),
            },
            service_type::MC_MC4PLUSMAIS => Self::Mc4plusMais {
                mais: {
                    let m = r.array();
                    r.skip(2);
                    m
                },
                jomos: r.entity(),
                coupling: r.entity(),
            },
            service_type::MC_MC4PLUSFAPS => Self::Mc4plusFaps {
                pos: r.array(),
                jomos: r.entity(),
                coupling: r.entity(),
            },
            service_type::MC_MC2PLUSPSC => Self::Mc2plusPsc {
                psc: r.array(),
                jomos: r.entity(),
                coupling: r.entity(),
                stop_switches: r.array(),
            },
            service_type::MC_ADVFOC => Self::AdvFoc {
                descriptors: r.array(),
                coupling: r.array(),
            },
            _ => return None,
        })
    }

    /// The service type (`eOmn_serv_type_t`).
    pub fn service_type(&self) -> u8 {
        match self {
            Self::Foc { .. } => service_type::MC_FOC,
            Self::Mc4 { .. } => service_type::MC_MC4,
            Self::Mc4plus { .. } => service_type::MC_MC4PLUS,
            Self::Mc4plusMais { .. } => service_type::MC_MC4PLUSMAIS,
            Self::Mc4plusFaps { .. } => service_type::MC_MC4PLUSFAPS,
            Self::Mc2plusPsc { .. } => service_type::MC_MC2PLUSPSC,
            Self::AdvFoc { .. } => service_type::MC_ADVFOC,
        }
    }

    /// The 340 data bytes (`eOmn_serv_config_data_t`, zero-filled).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut w = Writer::with_capacity(SERVICE_CONFIG_DATA_SIZE);
        match self {
            Self::Foc {
                version,
                board_type,
                jomos,
                coupling,
            } => {
                w.bytes(version);
                w.u8(*board_type);
                w.zeros(2);
                w.entity(jomos);
                w.entity(coupling);
            }
            Self::Mc4 {
                version,
                shifts,
                joints,
                mais,
                broadcast_flags,
            } => {
                w.bytes(version);
                w.bytes(shifts);
                w.bytes(joints);
                w.bytes(mais);
                w.u16(*broadcast_flags);
            }
            Self::Mc4plus { jomos, coupling } => {
                w.entity(jomos);
                w.entity(coupling);
            }
            Self::Mc4plusMais {
                mais,
                jomos,
                coupling,
            } => {
                w.bytes(mais);
                w.zeros(2);
                w.entity(jomos);
                w.entity(coupling);
            }
            Self::Mc4plusFaps {
                pos,
                jomos,
                coupling,
            } => {
                w.bytes(pos);
                w.entity(jomos);
                w.entity(coupling);
            }
            Self::Mc2plusPsc {
                psc,
                jomos,
                coupling,
                stop_switches,
            } => {
                w.bytes(psc);
                w.entity(jomos);
                w.entity(coupling);
                w.bytes(stop_switches);
            }
            Self::AdvFoc {
                descriptors,
                coupling,
            } => {
                w.bytes(descriptors);
                w.bytes(coupling);
            }
        }
        let mut v = w.into_inner();
        v.resize(SERVICE_CONFIG_DATA_SIZE, 0);
        v
    }

    /// How many joints (and motors) the service drives.
    pub fn joints(&self) -> u8 {
        match self {
            Self::Foc { jomos, .. }
            | Self::Mc4plus { jomos, .. }
            | Self::Mc4plusMais { jomos, .. }
            | Self::Mc4plusFaps { jomos, .. }
            | Self::Mc2plusPsc { jomos, .. } => jomos.0.len() as u8,
            // The host fills mc4joints[0..n) and leaves the rest 0 (no MC4 has address 0).
            Self::Mc4 { joints, .. } => joints
                .iter()
                .rposition(|b| *b != 0)
                .map_or(0, |i| i as u8 + 1),
            Self::AdvFoc { descriptors, .. } => {
                if descriptors[1] == 16 {
                    descriptors[2].min(4)
                } else {
                    0
                }
            }
        }
    }
}

/// `eOas_ft_sensordescriptor_t` / `eOas_battery_sensordescriptor_t` (8 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CanSensorDescriptor {
    pub board: BoardInfo,
    pub can_location: CanLocation,
}

impl Entity for CanSensorDescriptor {
    const C_TYPE: &'static str = "eOas_ft_sensordescriptor_t";
    const SIZE: usize = 8;
    fn write(&self, w: &mut Writer) {
        w.entity(&self.board);
        w.u8(self.can_location.to_byte());
        w.u8(0);
    }
    fn read(r: &mut Reader) -> Self {
        let board = r.entity();
        let can_location = CanLocation::from_byte(r.u8());
        r.skip(1);
        Self {
            board,
            can_location,
        }
    }
}

/// `eOmn_serv_config_data_as_ft_t` (40) and `..._as_battery_t` (16): a CAN monitor
/// configuration (`eObrd_canmonitor_cfg_t`: periodofcheck, reportmode, periodofreport)
/// and an array of CAN sensors (capacity 4 for FT, 1 for the battery).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct CanSensorsConfig {
    pub can_monitor: [u8; 4],
    pub sensors: Vec<CanSensorDescriptor>,
}

impl CanSensorsConfig {
    fn encode(&self, capacity: usize) -> Vec<u8> {
        let mut w = Writer::with_capacity(8 + capacity * 8);
        w.bytes(&self.can_monitor);
        let n = self.sensors.len().min(capacity);
        w.bytes(&[capacity as u8, 8, n as u8, 0]);
        for s in &self.sensors[..n] {
            w.entity(s);
        }
        w.zeros((capacity - n) * 8);
        w.into_inner()
    }
    fn decode(data: &[u8], capacity: usize) -> Self {
        let mut r = Reader::new(data);
        let can_monitor = r.array();
        let [_, item, size, _] = r.array();
        let n = if item == 8 {
            usize::from(size).min(capacity)
        } else {
            0
        };
        Self {
            can_monitor,
            sensors: (0..n).map(|_| r.entity()).collect(),
        }
    }
    /// `eOmn_serv_config_data_as_ft_t` (40 bytes).
    pub fn ft_bytes(&self) -> Vec<u8> {
        self.encode(4)
    }
    /// `eOmn_serv_config_data_as_battery_t` (16 bytes).
    pub fn battery_bytes(&self) -> Vec<u8> {
        self.encode(1)
    }
    pub fn from_ft_bytes(data: &[u8]) -> Self {
        Self::decode(data, 4)
    }
    pub fn from_battery_bytes(data: &[u8]) -> Self {
        Self::decode(data, 1)
    }
}

/// `eOas_inertial3_descriptor_t` / `eOas_temperature_descriptor_t` (4 bytes): board type,
/// location (`eObrd_location_t`), sensor type, ffu.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SensorDescriptor {
    pub type_of_board: u8,
    pub location: u8,
    pub type_of_sensor: u8,
}

impl Entity for SensorDescriptor {
    const C_TYPE: &'static str = "eOas_inertial3_descriptor_t";
    const SIZE: usize = 4;
    fn write(&self, w: &mut Writer) {
        w.bytes(&[self.type_of_board, self.location, self.type_of_sensor, 0]);
    }
    fn read(r: &mut Reader) -> Self {
        let [type_of_board, location, type_of_sensor, _] = r.array();
        Self {
            type_of_board,
            location,
            type_of_sensor,
        }
    }
}

/// `eOmn_serv_config_data_as_inertial3_t` (168: 6 board infos, then up to 32 descriptors)
/// and `..._as_temperature_t` (56: 4 board infos, up to 7 descriptors).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct SensorSetConfig {
    pub boards: Vec<BoardInfo>,
    pub sensors: Vec<SensorDescriptor>,
}

impl SensorSetConfig {
    fn encode(&self, nboards: usize, capacity: usize) -> Vec<u8> {
        let mut w = Writer::with_capacity(nboards * 6 + 4 + capacity * 4);
        for i in 0..nboards {
            w.entity(&self.boards.get(i).copied().unwrap_or_default());
        }
        let n = self.sensors.len().min(capacity);
        w.bytes(&[capacity as u8, 4, n as u8, 0]);
        for s in &self.sensors[..n] {
            w.entity(s);
        }
        w.zeros((capacity - n) * 4);
        w.into_inner()
    }
    fn decode(data: &[u8], nboards: usize, capacity: usize) -> Self {
        let mut r = Reader::new(data);
        let boards = (0..nboards).map(|_| r.entity()).collect();
        let [_, item, size, _] = r.array();
        let n = if item == 4 {
            usize::from(size).min(capacity)
        } else {
            0
        };
        Self {
            boards,
            sensors: (0..n).map(|_| r.entity()).collect(),
        }
    }
    pub fn inertial3_bytes(&self) -> Vec<u8> {
        self.encode(6, 32)
    }
    pub fn temperature_bytes(&self) -> Vec<u8> {
        self.encode(4, 7)
    }
    pub fn from_inertial3_bytes(data: &[u8]) -> Self {
        Self::decode(data, 6, 32)
    }
    pub fn from_temperature_bytes(data: &[u8]) -> Self {
        Self::decode(data, 4, 7)
    }
}

/// `eOmn_serv_config_data_sk_skin_t` (24 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SkinServiceConfig {
    pub board: BoardInfo,
    pub num_of_patches: u8,
    /// `canmapskin[patch][can port]`: bit mask of the MTB addresses.
    pub can_map: [[u16; 2]; 4],
}

impl Entity for SkinServiceConfig {
    const C_TYPE: &'static str = "eOmn_serv_config_data_sk_skin_t";
    const SIZE: usize = 24;
    fn write(&self, w: &mut Writer) {
        w.entity(&self.board);
        w.u8(self.num_of_patches);
        w.u8(0);
        for p in &self.can_map {
            w.u16(p[0]);
            w.u16(p[1]);
        }
    }
    fn read(r: &mut Reader) -> Self {
        let board = r.entity();
        let num_of_patches = r.u8();
        r.skip(1);
        let mut can_map = [[0u16; 2]; 4];
        for p in can_map.iter_mut() {
            *p = [r.u16(), r.u16()];
        }
        Self {
            board,
            num_of_patches,
            can_map,
        }
    }
}

/// The entity instances a service configuration brings to a board: what a board must
/// offer for `verifyactivate` of `category` with this configuration to succeed.
pub fn entities_for_service(cat: u8, service_type_: u8, data: &[u8]) -> Vec<(u8, u8, u8)> {
    let one = |e: u8, n: u8| vec![(ep::ANALOG_SENSORS, e, n)];
    match cat {
        category::MC => {
            let n = McServiceConfig::parse(service_type_, data).map_or(0, |c| c.joints());
            vec![
                (ep::MOTION_CONTROL, en::MC_JOINT, n),
                (ep::MOTION_CONTROL, en::MC_MOTOR, n),
                (ep::MOTION_CONTROL, en::MC_CONTROLLER, u8::from(n > 0)),
            ]
        }
        // A board with a strain has the temperature variables of the strain2's sensor
        // too: the host sets the temperature config right after verifying the strain
        // (icub-main's `embObjFTsensor::sendConfig2Strain`), with or without a
        // temperatures service.
        category::STRAIN => vec![
            (ep::ANALOG_SENSORS, en::AS_STRAIN, 1),
            (ep::ANALOG_SENSORS, en::AS_TEMPERATURE, 1),
        ],
        category::MAIS => one(en::AS_MAIS, 1),
        category::TEMPERATURES => one(en::AS_TEMPERATURE, 1),
        category::INERTIALS3 => one(en::AS_INERTIAL3, 1),
        category::PSC => one(en::AS_PSC, 1),
        category::POS => one(en::AS_POS, 1),
        category::FT => one(
            en::AS_FT,
            CanSensorsConfig::from_ft_bytes(data).sensors.len() as u8,
        ),
        category::BATTERY => one(
            en::AS_BATTERY,
            CanSensorsConfig::from_battery_bytes(data).sensors.len() as u8,
        ),
        category::SKIN => {
            let n = SkinServiceConfig::from_bytes(data.get(..24).unwrap_or(&[]))
                .map_or(0, |s| s.num_of_patches.min(4));
            vec![(ep::SKIN, en::SK_SKIN, n)]
        }
        _ => Vec::new(),
    }
}

/// `eOmn_serv_config_data_as_strain_t` (7 bytes): the strain board and where it is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StrainServiceConfig {
    pub board: BoardInfo,
    pub can_location: CanLocation,
}

impl Entity for StrainServiceConfig {
    const C_TYPE: &'static str = "eOmn_serv_config_data_as_strain_t";
    const SIZE: usize = 7;
    fn write(&self, w: &mut Writer) {
        w.entity(&self.board);
        w.u8(self.can_location.to_byte());
    }
    fn read(r: &mut Reader) -> Self {
        Self {
            board: r.entity(),
            can_location: CanLocation::from_byte(r.u8()),
        }
    }
}

/// `eOmn_serv_config_data_as_mais_t` (6 bytes): `eObrd_version_t` (firmware major, minor,
/// build; protocol major, minor) and the CAN location.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MaisServiceConfig {
    pub version: [u8; 5],
    pub can_location: CanLocation,
}

impl Entity for MaisServiceConfig {
    const C_TYPE: &'static str = "eOmn_serv_config_data_as_mais_t";
    const SIZE: usize = 6;
    fn write(&self, w: &mut Writer) {
        w.bytes(&self.version);
        w.u8(self.can_location.to_byte());
    }
    fn read(r: &mut Reader) -> Self {
        Self {
            version: r.array(),
            can_location: CanLocation::from_byte(r.u8()),
        }
    }
}

/// `eoas_pos_SensorConfig_t` (4 bytes): a u16 bit field (type:4, connector:4, port:4,
/// enabled:1, invertdirection:1, rotation:2 from bit 0) and the offset in deci-degrees.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PosSensorConfig {
    /// `eoas_pos_TYPE_t` (0 decideg, 14 none).
    pub sensor_type: u8,
    pub connector: u8,
    /// `eObrd_portpos_t`.
    pub port: u8,
    pub enabled: bool,
    pub invert_direction: bool,
    /// `eoas_pos_ROT_t`.
    pub rotation: u8,
    pub offset: i16,
}

impl Entity for PosSensorConfig {
    const C_TYPE: &'static str = "eoas_pos_SensorConfig_t";
    const SIZE: usize = 4;
    fn write(&self, w: &mut Writer) {
        let bits = u16::from(self.sensor_type & 0xf)
            | u16::from(self.connector & 0xf) << 4
            | u16::from(self.port & 0xf) << 8
            | u16::from(self.enabled) << 12
            | u16::from(self.invert_direction) << 13
            | u16::from(self.rotation & 3) << 14;
        w.u16(bits);
        w.i16(self.offset);
    }
    fn read(r: &mut Reader) -> Self {
        let b = r.u16();
        Self {
            sensor_type: (b & 0xf) as u8,
            connector: ((b >> 4) & 0xf) as u8,
            port: ((b >> 8) & 0xf) as u8,
            enabled: b & (1 << 12) != 0,
            invert_direction: b & (1 << 13) != 0,
            rotation: (b >> 14) as u8,
            offset: r.i16(),
        }
    }
}

/// `eoas_pos_ServiceConfig_t` = `eOmn_serv_config_data_as_pos_t` (24 bytes): one
/// `eoas_pos_BoardConfig_t` (board info 6, CAN location 1, filler 1, 4 sensors).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PosServiceConfig {
    pub board: BoardInfo,
    pub can_location: CanLocation,
    pub sensors: [PosSensorConfig; 4],
}

impl Entity for PosServiceConfig {
    const C_TYPE: &'static str = "eOmn_serv_config_data_as_pos_t";
    const SIZE: usize = 24;
    fn write(&self, w: &mut Writer) {
        w.entity(&self.board);
        w.u8(self.can_location.to_byte());
        w.u8(0);
        for s in &self.sensors {
            w.entity(s);
        }
    }
    fn read(r: &mut Reader) -> Self {
        let board = r.entity();
        let can_location = CanLocation::from_byte(r.u8());
        r.skip(1);
        Self {
            board,
            can_location,
            sensors: [r.entity(), r.entity(), r.entity(), r.entity()],
        }
    }
}
