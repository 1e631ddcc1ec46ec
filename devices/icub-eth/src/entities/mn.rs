//! Management endpoint (`EoManagement.h`, `EoProtocolMN.h`): communication status, the
//! application state machine and the service commands.

use crate::id::Id32;
use crate::wire::{Entity, Reader, Writer};

/// `eoprot_version_t` / `eOversion_t` (2 bytes: major, minor).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct Version {
    pub major: u8,
    pub minor: u8,
}

impl Version {
    pub const fn new(major: u8, minor: u8) -> Self {
        Self { major, minor }
    }
}

impl std::fmt::Display for Version {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}.{}", self.major, self.minor)
    }
}

impl Entity for Version {
    const C_TYPE: &'static str = "eoprot_version_t";
    const SIZE: usize = 2;
    fn write(&self, w: &mut Writer) {
        w.u8(self.major);
        w.u8(self.minor);
    }
    fn read(r: &mut Reader) -> Self {
        Self {
            major: r.u8(),
            minor: r.u8(),
        }
    }
}

/// Protocol versions of the endpoints this crate implements (`eoprot_version_xx_major/minor`
/// of `EoProtocolMN.h`, `EoProtocolMC.h`, `EoProtocolAS.h`, `EoProtocolSK.h`).
pub mod versions {
    use super::Version;
    pub const MN: Version = Version::new(2, 25);
    pub const MC: Version = Version::new(1, 27);
    pub const AS: Version = Version::new(1, 11);
    pub const SK: Version = Version::new(2, 0);
}

/// `eOmn_transceiver_properties_t` (24 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct TransceiverProperties {
    pub listening_port: u16,
    pub destination_port: u16,
    pub max_size_rx_packet: u16,
    pub max_size_tx_packet: u16,
    pub max_size_ropframe_regulars: u16,
    pub max_size_ropframe_replies: u16,
    pub max_size_ropframe_occasionals: u16,
    pub max_size_rop: u16,
    pub max_number_regular_rops: u16,
}

impl Entity for TransceiverProperties {
    const C_TYPE: &'static str = "eOmn_transceiver_properties_t";
    const SIZE: usize = 24;
    fn write(&self, w: &mut Writer) {
        for v in [
            self.listening_port,
            self.destination_port,
            self.max_size_rx_packet,
            self.max_size_tx_packet,
            self.max_size_ropframe_regulars,
            self.max_size_ropframe_replies,
            self.max_size_ropframe_occasionals,
            self.max_size_rop,
            self.max_number_regular_rops,
        ] {
            w.u16(v);
        }
        w.zeros(6);
    }
    fn read(r: &mut Reader) -> Self {
        let v = Self {
            listening_port: r.u16(),
            destination_port: r.u16(),
            max_size_rx_packet: r.u16(),
            max_size_tx_packet: r.u16(),
            max_size_ropframe_regulars: r.u16(),
            max_size_ropframe_replies: r.u16(),
            max_size_ropframe_occasionals: r.u16(),
            max_size_rop: r.u16(),
            max_number_regular_rops: r.u16(),
        };
        r.skip(6);
        v
    }
}

/// `eOmn_comm_status_t` (32 bytes): the management protocol version and the transceiver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CommStatus {
    pub management_protocol_version: Version,
    pub transceiver: TransceiverProperties,
}

impl Entity for CommStatus {
    const C_TYPE: &'static str = "eOmn_comm_status_t";
    const SIZE: usize = 32;
    fn write(&self, w: &mut Writer) {
        w.entity(&self.management_protocol_version);
        w.zeros(6);
        w.entity(&self.transceiver);
    }
    fn read(r: &mut Reader) -> Self {
        let v = r.entity();
        r.skip(6);
        Self {
            management_protocol_version: v,
            transceiver: r.entity(),
        }
    }
}

/// `eOmn_opc_t` values used here.
pub mod opc {
    pub const QUERY_ARRAY_EPDES: u8 = 5;
    pub const REPLY_ARRAY_EPDES: u8 = 6;
}

/// `eOmn_cmd_queryarray_t` (4 bytes): a query sent with `set<comm cmmnds queryarray>`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct QueryArray {
    pub opc: u8,
    /// `eoprot_endpoint_all` (254) for every endpoint.
    pub endpoint: u8,
    pub set_number: u8,
    pub set_size: u8,
}

impl Entity for QueryArray {
    const C_TYPE: &'static str = "eOmn_cmd_queryarray_t";
    const SIZE: usize = 4;
    fn write(&self, w: &mut Writer) {
        w.bytes(&[self.opc, self.endpoint, self.set_number, self.set_size]);
    }
    fn read(r: &mut Reader) -> Self {
        let [opc, endpoint, set_number, set_size] = r.array();
        Self {
            opc,
            endpoint,
            set_number,
            set_size,
        }
    }
}

/// `eoprot_endpoint_descriptor_t` (4 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EndpointDescriptor {
    pub endpoint: u8,
    pub entities_inside: u8,
    pub version: Version,
}

/// Size of `eOmn_cmd_replyarray_t::array` (`EOMANAGEMENT_COMMAND_DATA_SIZE`).
pub const COMMAND_DATA_SIZE: usize = 68;

/// `eOmn_cmd_replyarray_t` (72 bytes): the board's `sig<comm cmmnds replyarray>`, here with
/// an `EOarray` of endpoint descriptors (head: capacity, itemsize 4, size, internalmem).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReplyArray {
    pub opc: u8,
    pub endpoint: u8,
    pub set_number: u8,
    pub set_size: u8,
    /// `EOarray` head + items, 68 bytes.
    pub array: [u8; COMMAND_DATA_SIZE],
}

impl ReplyArray {
    /// The reply to `eomn_opc_query_array_EPdes`.
    pub fn endpoint_descriptors(descs: &[EndpointDescriptor]) -> Self {
        let capacity = (COMMAND_DATA_SIZE - 4) / 4;
        let n = descs.len().min(capacity);
        let mut array = [0u8; COMMAND_DATA_SIZE];
        array[0] = capacity as u8;
        array[1] = 4;
        array[2] = n as u8;
        for (i, d) in descs.iter().take(n).enumerate() {
            array[4 + 4 * i..8 + 4 * i].copy_from_slice(&[
                d.endpoint,
                d.entities_inside,
                d.version.major,
                d.version.minor,
            ]);
        }
        Self {
            opc: opc::REPLY_ARRAY_EPDES,
            endpoint: crate::id::endpoint::ALL,
            set_number: 0,
            set_size: n as u8,
            array,
        }
    }

    /// The endpoint descriptors in the array (items of 4 bytes; anything else is empty).
    pub fn descriptors(&self) -> Vec<EndpointDescriptor> {
        if self.array[1] != 4 {
            return Vec::new();
        }
        let n = usize::from(self.array[2]).min((COMMAND_DATA_SIZE - 4) / 4);
        (0..n)
            .map(|i| {
                let b = &self.array[4 + 4 * i..8 + 4 * i];
                EndpointDescriptor {
                    endpoint: b[0],
                    entities_inside: b[1],
                    version: Version::new(b[2], b[3]),
                }
            })
            .collect()
    }
}

impl Entity for ReplyArray {
    const C_TYPE: &'static str = "eOmn_cmd_replyarray_t";
    const SIZE: usize = 72;
    fn write(&self, w: &mut Writer) {
        w.bytes(&[self.opc, self.endpoint, self.set_number, self.set_size]);
        w.bytes(&self.array);
    }
    fn read(r: &mut Reader) -> Self {
        let [opc, endpoint, set_number, set_size] = r.array();
        Self {
            opc,
            endpoint,
            set_number,
            set_size,
            array: r.array(),
        }
    }
}

/// `eOmn_appl_config_t` (16 bytes): the board's control-loop timing and TX rate of the
/// regulars, as `ETH_BOARD_SETTINGS/RUNNINGMODE` configures it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ApplConfig {
    /// µs (1000).
    pub cycletime: u16,
    pub maxtime_rx: u16,
    pub maxtime_do: u16,
    pub maxtime_tx: u16,
    pub safetygap: u16,
    /// Regulars go out every `txratedivider` cycles (0 and 1: every cycle).
    pub txratedivider: u8,
    pub runnermode: u8,
    pub logging_flags: u16,
    pub logging_period10ms: u16,
}

impl Default for ApplConfig {
    /// icub-main's defaults (`eth::parser::boardSettings`): 1000 µs = 400 + 300 + 300, every cycle.
    fn default() -> Self {
        Self {
            cycletime: 1000,
            maxtime_rx: 400,
            maxtime_do: 300,
            maxtime_tx: 300,
            safetygap: 0,
            txratedivider: 1,
            runnermode: 0,
            logging_flags: 0,
            logging_period10ms: 0,
        }
    }
}

impl Entity for ApplConfig {
    const C_TYPE: &'static str = "eOmn_appl_config_t";
    const SIZE: usize = 16;
    fn write(&self, w: &mut Writer) {
        w.u16(self.cycletime);
        w.u16(self.maxtime_rx);
        w.u16(self.maxtime_do);
        w.u16(self.maxtime_tx);
        w.u16(self.safetygap);
        w.u8(self.txratedivider);
        w.u8(self.runnermode);
        w.u16(self.logging_flags);
        w.u16(self.logging_period10ms);
    }
    fn read(r: &mut Reader) -> Self {
        Self {
            cycletime: r.u16(),
            maxtime_rx: r.u16(),
            maxtime_do: r.u16(),
            maxtime_tx: r.u16(),
            safetygap: r.u16(),
            txratedivider: r.u8(),
            runnermode: r.u8(),
            logging_flags: r.u16(),
            logging_period10ms: r.u16(),
        }
    }
}

/// `eOmn_appl_state_t`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum ApplState {
    Config = 0,
    Running = 1,
    Error = 2,
    ResetMicro = 3,
    RestartApp = 4,
}

impl ApplState {
    pub fn from_u8(v: u8) -> Option<Self> {
        Some(match v {
            0 => Self::Config,
            1 => Self::Running,
            2 => Self::Error,
            3 => Self::ResetMicro,
            4 => Self::RestartApp,
            _ => return None,
        })
    }
}

/// `eOdate_t`: a 32-bit bit field (year 12, month 4, day 5, hour 5, min 6, from bit 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BuildDate {
    pub year: u16,
    pub month: u8,
    pub day: u8,
    pub hour: u8,
    pub min: u8,
}

impl BuildDate {
    pub fn to_u32(self) -> u32 {
        u32::from(self.year & 0xfff)
            | u32::from(self.month & 0xf) << 12
            | u32::from(self.day & 0x1f) << 16
            | u32::from(self.hour & 0x1f) << 21
            | u32::from(self.min & 0x3f) << 26
    }
    pub fn from_u32(v: u32) -> Self {
        Self {
            year: (v & 0xfff) as u16,
            month: ((v >> 12) & 0xf) as u8,
            day: ((v >> 16) & 0x1f) as u8,
            hour: ((v >> 21) & 0x1f) as u8,
            min: ((v >> 26) & 0x3f) as u8,
        }
    }
}

/// `eOmn_appl_status_t` (32 bytes): firmware version and date, state, board type.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ApplStatus {
    pub build_date: BuildDate,
    /// The application (firmware) version.
    pub version: Version,
    pub name: [u8; 16],
    /// Use [`ApplState`].
    pub current_state: u8,
    /// rx, do, tx, µs.
    pub cloop_timings: [u16; 3],
    pub tx_decimation_factor: u8,
    /// `eObrd_ethtype_t` (see [`crate::entities::boards::EthBoardType`]).
    pub board_type: u8,
}

impl ApplStatus {
    pub fn name_str(&self) -> String {
        let end = self.name.iter().position(|b| *b == 0).unwrap_or(16);
        String::from_utf8_lossy(&self.name[..end]).into_owned()
    }
}

impl Entity for ApplStatus {
    const C_TYPE: &'static str = "eOmn_appl_status_t";
    const SIZE: usize = 32;
    fn write(&self, w: &mut Writer) {
        w.u32(self.build_date.to_u32());
        w.entity(&self.version);
        w.bytes(&self.name);
        w.u8(self.current_state);
        w.u8(0);
        for t in self.cloop_timings {
            w.u16(t);
        }
        w.u8(self.tx_decimation_factor);
        w.u8(self.board_type);
    }
    fn read(r: &mut Reader) -> Self {
        let build_date = BuildDate::from_u32(r.u32());
        let version = r.entity();
        let name = r.array();
        let current_state = r.u8();
        r.skip(1);
        Self {
            build_date,
            version,
            name,
            current_state,
            cloop_timings: [r.u16(), r.u16(), r.u16()],
            tx_decimation_factor: r.u8(),
            board_type: r.u8(),
        }
    }
}

/// `eOmn_serv_category_t`.
pub mod category {
    pub const MC: u8 = 0;
    pub const STRAIN: u8 = 1;
    pub const MAIS: u8 = 2;
    pub const SKIN: u8 = 3;
    pub const INERTIALS3: u8 = 4;
    pub const TEMPERATURES: u8 = 5;
    pub const PSC: u8 = 6;
    pub const POS: u8 = 7;
    pub const FT: u8 = 8;
    pub const BATTERY: u8 = 9;
    /// `eomn_serv_category_all`.
    pub const ALL: u8 = 128;
    pub const NONE: u8 = 255;
    /// Number of categories (`eomn_serv_categories_numberof`).
    pub const COUNT: usize = 10;
}

/// `eOmn_serv_type_t`.
pub mod service_type {
    pub const MC_GENERIC: u8 = 0;
    pub const MC_FOC: u8 = 1;
    pub const MC_MC4: u8 = 2;
    pub const MC_MC4PLUS: u8 = 3;
    pub const MC_MC4PLUSMAIS: u8 = 4;
    pub const AS_MAIS: u8 = 5;
    pub const AS_STRAIN: u8 = 6;
    pub const SK_SKIN: u8 = 7;
    pub const AS_INERTIALS3: u8 = 8;
    pub const AS_TEMPERATURES: u8 = 9;
    pub const MC_MC2PLUS: u8 = 10;
    pub const MC_MC2PLUSPSC: u8 = 11;
    pub const AS_PSC: u8 = 12;
    pub const AS_POS: u8 = 13;
    pub const MC_MC4PLUSFAPS: u8 = 14;
    pub const MC_ADVFOC: u8 = 15;
    pub const AS_FT: u8 = 16;
    pub const AS_BATTERY: u8 = 17;
    pub const NONE: u8 = 255;
}

/// `eOmn_serv_operation_t`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum ServiceOperation {
    Deactivate = 0,
    VerifyActivate = 3,
    Start = 4,
    Stop = 5,
    RegsigLoad = 6,
    RegsigClear = 7,
    None = 255,
}

impl ServiceOperation {
    pub fn from_u8(v: u8) -> Option<Self> {
        Some(match v {
            0 => Self::Deactivate,
            3 => Self::VerifyActivate,
            4 => Self::Start,
            5 => Self::Stop,
            6 => Self::RegsigLoad,
            7 => Self::RegsigClear,
            255 => Self::None,
            _ => return None,
        })
    }
}

/// `eOmn_serv_state_t`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u8)]
pub enum ServiceState {
    NotSupported = 0,
    #[default]
    Idle = 1,
    Verifying = 2,
    Verified = 3,
    Activated = 4,
    FailureOfVerify = 5,
    Started = 6,
    SystemInFatalError = 7,
}

/// Size of `eOmn_serv_parameter_t` (a union of the configuration and the id32 array).
pub const SERVICE_PARAMETER_SIZE: usize = 344;
/// Size of `eOmn_serv_config_data_t` (the per-service configuration union).
pub const SERVICE_CONFIG_DATA_SIZE: usize = 340;
/// Capacity of `eOmn_serv_arrayof_id32_t` (`eOmn_serv_capacity_arrayof_id32`).
pub const SERVICE_ID32_CAPACITY: usize = 41;

/// `eOmn_service_cmmnds_command_t` (348 bytes): what the host writes with
/// `set<mn service cmmnds command>`; the board answers with `sig<mn service status
/// commandresult>`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ServiceCommand {
    /// Use [`ServiceOperation`].
    pub operation: u8,
    /// Use [`category`].
    pub category: u8,
    /// `eOmn_serv_parameter_t`: either `eOmn_serv_configuration_t` (type u8,
    /// diagnosticsmode u8, diagnosticsparam u16, 340 bytes of `eOmn_serv_config_data_t`)
    /// or `eOmn_serv_arrayof_id32_t` (EOarray head, 41 × u32).
    pub parameter: [u8; SERVICE_PARAMETER_SIZE],
}

impl ServiceCommand {
    /// A command without parameter, as `EthResource::serviceCommand` sends it: an empty id32
    /// array for the regsig operations, else a configuration of type `eomn_serv_NONE`.
    pub fn bare(operation: ServiceOperation, category: u8) -> Self {
        let mut c = Self {
            operation: operation as u8,
            category,
            parameter: [0; SERVICE_PARAMETER_SIZE],
        };
        if matches!(
            operation,
            ServiceOperation::RegsigLoad | ServiceOperation::RegsigClear
        ) {
            c.parameter[0] = SERVICE_ID32_CAPACITY as u8;
            c.parameter[1] = 4;
        } else {
            c.parameter[0] = service_type::NONE;
        }
        c
    }

    /// `verifyactivate` with a service configuration (`eOmn_serv_configuration_t`).
    pub fn verify_activate(
        category: u8,
        service_type: u8,
        diagnostics_mode: u8,
        diagnostics_param: u16,
        data: &[u8],
    ) -> Self {
        let mut p = [0u8; SERVICE_PARAMETER_SIZE];
        p[0] = service_type;
        p[1] = diagnostics_mode;
        p[2..4].copy_from_slice(&diagnostics_param.to_le_bytes());
        let n = data.len().min(SERVICE_CONFIG_DATA_SIZE);
        p[4..4 + n].copy_from_slice(&data[..n]);
        Self {
            operation: ServiceOperation::VerifyActivate as u8,
            category,
            parameter: p,
        }
    }

    /// `regsig_load` with the variables the board shall signal regularly (at most 41, as
    /// `eOmn_serv_arrayof_id32_t` holds; the rest is dropped).
    pub fn regsig_load(category: u8, ids: &[Id32]) -> Self {
        let mut c = Self::bare(ServiceOperation::RegsigLoad, category);
        let n = ids.len().min(SERVICE_ID32_CAPACITY);
        c.parameter[2] = n as u8;
        for (i, id) in ids.iter().take(n).enumerate() {
            c.parameter[4 + 4 * i..8 + 4 * i].copy_from_slice(&id.0.to_le_bytes());
        }
        c
    }

    /// The service type of a configuration parameter.
    pub fn service_type(&self) -> u8 {
        self.parameter[0]
    }

    /// The `eOmn_serv_config_data_t` bytes of a configuration parameter.
    pub fn config_data(&self) -> &[u8] {
        &self.parameter[4..]
    }

    /// The id32 array of a regsig parameter (items of 4 bytes, at most 41).
    pub fn id32s(&self) -> Vec<Id32> {
        if self.parameter[1] != 4 {
            return Vec::new();
        }
        let n = usize::from(self.parameter[2]).min(SERVICE_ID32_CAPACITY);
        (0..n)
            .map(|i| {
                let b = &self.parameter[4 + 4 * i..8 + 4 * i];
                Id32(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            })
            .collect()
    }
}

impl Entity for ServiceCommand {
    const C_TYPE: &'static str = "eOmn_service_cmmnds_command_t";
    const SIZE: usize = 348;
    fn write(&self, w: &mut Writer) {
        w.u8(self.operation);
        w.u8(self.category);
        w.zeros(2);
        w.bytes(&self.parameter);
    }
    fn read(r: &mut Reader) -> Self {
        let operation = r.u8();
        let category = r.u8();
        r.skip(2);
        Self {
            operation,
            category,
            parameter: r.array(),
        }
    }
}

/// `eOmn_service_command_result_t` (32 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ServiceCommandResult {
    pub latest_command_is_ok: bool,
    pub operation: u8,
    pub category: u8,
    pub service_type: u8,
    /// Service-specific (e.g. the strain's full scale; for `stop`,
    /// `eOmn_service_command_stop_result_data_t`: applstate, totalregulars, serviceregulars).
    pub data: [u8; 28],
}

impl Entity for ServiceCommandResult {
    const C_TYPE: &'static str = "eOmn_service_command_result_t";
    const SIZE: usize = 32;
    fn write(&self, w: &mut Writer) {
        w.u8(u8::from(self.latest_command_is_ok));
        w.u8(self.operation);
        w.u8(self.category);
        w.u8(self.service_type);
        w.bytes(&self.data);
    }
    fn read(r: &mut Reader) -> Self {
        Self {
            latest_command_is_ok: r.u8() != 0,
            operation: r.u8(),
            category: r.u8(),
            service_type: r.u8(),
            data: r.array(),
        }
    }
}

/// `eOmn_service_status_t` (48 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ServiceStatus {
    /// `eOmn_serv_state_t` per category.
    pub state_of_service: [u8; category::COUNT],
    pub command_result: ServiceCommandResult,
}

impl Entity for ServiceStatus {
    const C_TYPE: &'static str = "eOmn_service_status_t";
    const SIZE: usize = 48;
    fn write(&self, w: &mut Writer) {
        w.bytes(&self.state_of_service);
        w.zeros(6);
        w.entity(&self.command_result);
    }
    fn read(r: &mut Reader) -> Self {
        let state_of_service = r.array();
        r.skip(6);
        Self {
            state_of_service,
            command_result: r.entity(),
        }
    }
}

/// `eOmn_info_basic_t` (24 bytes): the head of a board's diagnostic message.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct InfoBasic {
    /// Board time of life, µs.
    pub timestamp: u64,
    pub code: u32,
    /// type:3, source:3, address:4, extraformat:2 (`EOMN_INFO_PROPERTIES_FLAGS_*`).
    pub flags: u16,
    pub par16: u16,
    pub par64: u64,
}

impl Entity for InfoBasic {
    const C_TYPE: &'static str = "eOmn_info_basic_t";
    const SIZE: usize = 24;
    fn write(&self, w: &mut Writer) {
        w.u64(self.timestamp);
        w.u32(self.code);
        w.u16(self.flags);
        w.u16(self.par16);
        w.u64(self.par64);
    }
    fn read(r: &mut Reader) -> Self {
        Self {
            timestamp: r.u64(),
            code: r.u32(),
            flags: r.u16(),
            par16: r.u16(),
            par64: r.u64(),
        }
    }
}
