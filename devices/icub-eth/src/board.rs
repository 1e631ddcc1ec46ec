//! A board as the emulator runs it, without sockets: it answers the host's ropframes as
//! the firmware's `EOtheBOARDtransceiver`/`EOagent` and services do, and streams the
//! regular ROPs the host loaded, at the configured rate, while running.
//!
//! - `ask` → `say` with the variable (signature copied when `plussign`; time when the ask
//!   has `rqsttime`); an unknown variable is answered only if `rqstconf` (with a `nak`).
//! - `set` writes the variable if its size is exactly the variable's (else it is dropped,
//!   as `EOagent` does); `rqstconf` gets `ack`/`nak`. Writes to command variables act:
//!   `appl cmmnds go2state`, `comm cmmnds queryarray` (→ `sig<replyarray>` with the
//!   endpoint descriptors), `service cmmnds command` (→ `sig<service status
//!   commandresult>`), joint config, commands and inputs (→ the [`JointModel`]s).
//! - Units at the boundary with the [`JointModel`]s: the wire's torques (set points, the
//!   external torque input, the status) are µN·m, the plant's N·m; the motor status
//!   reports a motor's temperature as its PT100 reads it ([`crate::plant::pt100_raw`])
//!   when the host's motor config says it has a sensor (`hasTempSensor`), else 0.
//! - Services: `verifyactivate` succeeds for a category the board has entities for and
//!   a configuration that fits it (motion control: as many joints as it drives; sensors:
//!   not all zero);
//!   `start` makes the application run (regulars flow); `stop` of the last started
//!   service (or of `all`) returns it to config and clears the regulars of the stopped
//!   services; `regsig_load`/`regsig_clear` edit the regulars.
//! - Regulars: a `sig` per loaded variable every `cycletime × txratedivider` µs
//!   (`eOmn_appl_config_t`, 1 ms × 1 by default), in as few frames as fit `max_tx_packet`.

use crate::entities::boards::EthBoardType;
use crate::entities::mc::{
    control_mode, interaction_mode, Calibrator, JointConfig, JointStatusCore, JointStatusTarget,
    MotorConfig, MotorStatus, MotorStatusBasic, MultiEncoders, Setpoint,
};
use crate::entities::mn::{
    category, opc, service_type, versions, ApplConfig, ApplState, ApplStatus, BuildDate,
    CommStatus, EndpointDescriptor, QueryArray, ReplyArray, ServiceCommand, ServiceCommandResult,
    ServiceOperation, ServiceState, ServiceStatus, TransceiverProperties, Version,
};
use crate::entities::service::{entities_for_service, McServiceConfig};
use crate::frame::{Frame, FrameBuilder, FrameError, EMPTY_FRAME_SIZE};
use crate::id::{endpoint as ep, entity as en, ids, tag, Id32};
use crate::nvstore::NvStore;
use crate::plant::{pt100_raw, JointModel, SimpleJoint, TORQUE_TO_WIRE};
use crate::rop::{ConfInfo, Rop, RopCode, RopRef};
use crate::wire::Entity;
use std::time::Duration;

/// What a board is: its identity and the entities its services offer.
#[derive(Debug, Clone)]
pub struct BoardConfig {
    /// `ETH_BOARD_SETTINGS/Name`, for logs.
    pub name: String,
    pub ip: std::net::Ipv4Addr,
    pub board_type: EthBoardType,
    /// The application's version (`eOmn_appl_status_t::version`).
    pub firmware: Version,
    pub build_date: BuildDate,
    /// Protocol versions the board announces: management, motion control, analog
    /// sensors, skin (default: this crate's, i.e. a board with matching firmware).
    pub protocol: [Version; 4],
    /// Joints (and as many motors) of the motion-control service.
    pub joints: u8,
    pub strains: u8,
    pub maises: u8,
    pub temperatures: u8,
    pub inertials3: u8,
    pub pscs: u8,
    pub poses: u8,
    pub fts: u8,
    pub batteries: u8,
    pub skins: u8,
    /// Largest datagram the board sends.
    pub max_tx_packet: usize,
    /// Largest datagram the board accepts (`eOmn_transceiver_properties_t::maxsizeRXpacket`).
    pub max_rx_packet: usize,
    /// Create the entities a `verifyactivate` configuration names (joints from its jomo
    /// descriptors, FT sensors from its sensor array, skin patches, ...), as a board
    /// with that hardware behind it would have them: the emulator then needs only the
    /// boards' addresses and types.
    pub auto_entities: bool,
}

impl BoardConfig {
    /// A board of a type at an address, with nothing on it yet.
    pub fn new(name: &str, ip: std::net::Ipv4Addr, board_type: EthBoardType) -> Self {
        Self {
            name: name.to_string(),
            ip,
            board_type,
            firmware: Version::new(3, 80),
            build_date: BuildDate {
                year: 2024,
                month: 1,
                day: 1,
                hour: 0,
                min: 0,
            },
            protocol: [versions::MN, versions::MC, versions::AS, versions::SK],
            joints: 0,
            strains: 0,
            maises: 0,
            temperatures: 0,
            inertials3: 0,
            pscs: 0,
            poses: 0,
            fts: 0,
            batteries: 0,
            skins: 0,
            max_tx_packet: 1500,
            max_rx_packet: 768,
            auto_entities: true,
        }
    }

    fn entity_counts(&self) -> [(u8, u8, u8); 13] {
        [
            (ep::MOTION_CONTROL, en::MC_JOINT, self.joints),
            (ep::MOTION_CONTROL, en::MC_MOTOR, self.joints),
            (
                ep::MOTION_CONTROL,
                en::MC_CONTROLLER,
                u8::from(self.joints > 0),
            ),
            (ep::ANALOG_SENSORS, en::AS_STRAIN, self.strains),
            (ep::ANALOG_SENSORS, en::AS_MAIS, self.maises),
            (ep::ANALOG_SENSORS, en::AS_TEMPERATURE, self.temperatures),
            (ep::ANALOG_SENSORS, en::AS_INERTIAL3, self.inertials3),
            (ep::ANALOG_SENSORS, en::AS_PSC, self.pscs),
            (ep::ANALOG_SENSORS, en::AS_POS, self.poses),
            (ep::ANALOG_SENSORS, en::AS_FT, self.fts),
            (ep::ANALOG_SENSORS, en::AS_BATTERY, self.batteries),
            (ep::SKIN, en::SK_SKIN, self.skins),
            (ep::MANAGEMENT, en::MN_INFO, 1),
        ]
    }
}

/// Counters of what the board dropped or noticed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BoardCounters {
    pub frames_received: u64,
    pub invalid_frames: u64,
    pub bad_rops: u64,
    pub sequence_errors: u64,
    /// Asks/sets of variables the board does not have, or sets of the wrong size.
    pub rejected_rops: u64,
    pub frames_sent: u64,
    pub regulars_sent: u64,
}

/// Something the board did that its owner may want to log or act on.
#[derive(Debug, Clone, PartialEq)]
pub enum BoardEvent {
    /// The application state changed (go2state, service start/stop).
    State(ApplState),
    /// A service command was executed.
    Service {
        operation: u8,
        category: u8,
        ok: bool,
    },
    /// A `set` of a variable the board owns (sensor configs and enables included).
    Set(Id32),
    /// A `verifyactivate` that succeeded, with the service's configuration
    /// (`eOmn_serv_config_data_t`): what the host says is behind the board (the inertial
    /// sensors and their CAN boards, the skin patches' MTBs, ...), for the owner to model.
    Verified {
        category: u8,
        service_type: u8,
        config: Vec<u8>,
    },
}

/// Makes the joint model of a joint created by a service configuration.
pub type JointFactory = Box<dyn FnMut(u8) -> Box<dyn JointModel> + Send>;

/// The board-side engine.
pub struct BoardEngine {
    cfg: BoardConfig,
    store: NvStore,
    state: ApplState,
    services: [ServiceState; category::COUNT],
    regulars: [Vec<Id32>; category::COUNT],
    joints: Vec<Box<dyn JointModel>>,
    joint_factory: Option<JointFactory>,
    replies: Vec<Rop>,
    events: std::collections::VecDeque<BoardEvent>,
    tx_sequence: u64,
    rx_sequence: Option<u64>,
    next_regulars: Option<Duration>,
    /// Where the regulars of this period resume when they did not fit one frame: the next
    /// frame carries the rest (the period's schedule waits until all went out).
    regulars_resume: Option<usize>,
    counters: BoardCounters,
}

impl std::fmt::Debug for BoardEngine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BoardEngine")
            .field("name", &self.cfg.name)
            .field("ip", &self.cfg.ip)
            .field("state", &self.state)
            .finish_non_exhaustive()
    }
}

fn service_index(cat: u8) -> Option<usize> {
    let i = usize::from(cat);
    (i < category::COUNT).then_some(i)
}

impl BoardEngine {
    /// A board in config state with [`SimpleJoint`]s at position 0.
    pub fn new(cfg: BoardConfig) -> Self {
        let joints = (0..cfg.joints)
            .map(|_| Box::new(SimpleJoint::new(0.0)) as Box<dyn JointModel>)
            .collect();
        Self::with_joints(cfg, joints)
    }

    /// A board whose joints are the given models (one per configured joint; missing ones
    /// are [`SimpleJoint`]s, extra ones ignored).
    pub fn with_joints(cfg: BoardConfig, mut joints: Vec<Box<dyn JointModel>>) -> Self {
        joints.truncate(usize::from(cfg.joints));
        while joints.len() < usize::from(cfg.joints) {
            joints.push(Box::new(SimpleJoint::new(0.0)));
        }
        let mut store = NvStore::new();
        for e in [en::MN_COMM, en::MN_APPL, en::MN_SERVICE] {
            store.add_entity(ep::MANAGEMENT, e, 1);
        }
        for (e, n, c) in cfg.entity_counts() {
            store.add_entity(e, n, c);
        }
        let mut b = Self {
            cfg,
            store,
            state: ApplState::Config,
            services: [ServiceState::Idle; category::COUNT],
            regulars: Default::default(),
            joints,
            joint_factory: None,
            replies: Vec::new(),
            events: Default::default(),
            tx_sequence: 0,
            rx_sequence: None,
            next_regulars: None,
            regulars_resume: None,
            counters: BoardCounters::default(),
        };
        b.init_management();
        b.publish_joints();
        b
    }

    fn init_management(&mut self) {
        let comm = CommStatus {
            management_protocol_version: self.cfg.protocol[0],
            transceiver: TransceiverProperties {
                listening_port: 12345,
                destination_port: 12345,
                max_size_rx_packet: self.cfg.max_rx_packet as u16,
                max_size_tx_packet: self.cfg.max_tx_packet as u16,
                max_size_ropframe_regulars: self.cfg.max_tx_packet as u16,
                max_size_ropframe_replies: self.cfg.max_tx_packet as u16,
                max_size_ropframe_occasionals: self.cfg.max_tx_packet as u16,
                max_size_rop: 384,
                max_number_regular_rops: 128,
            },
        };
        let _ = self.store.write(ids::COMM_STATUS, &comm);
        let _ = self.store.write(ids::APPL_CONFIG, &ApplConfig::default());
        self.write_appl_status();
        self.write_service_status(ServiceCommandResult::default());
    }

    fn write_appl_status(&mut self) {
        let mut name = [0u8; 16];
        let n = self.cfg.name.len().min(15);
        name[..n].copy_from_slice(&self.cfg.name.as_bytes()[..n]);
        let cfg = self.appl_config();
        let st = ApplStatus {
            build_date: self.cfg.build_date,
            version: self.cfg.firmware,
            name,
            current_state: self.state as u8,
            cloop_timings: [cfg.maxtime_rx, cfg.maxtime_do, cfg.maxtime_tx],
            tx_decimation_factor: cfg.txratedivider.max(1),
            board_type: self.cfg.board_type as u8,
        };
        let _ = self.store.write(ids::APPL_STATUS, &st);
    }

    fn write_service_status(&mut self, result: ServiceCommandResult) {
        let mut st = ServiceStatus {
            command_result: result,
            ..Default::default()
        };
        for (i, s) in self.services.iter().enumerate() {
            st.state_of_service[i] = *s as u8;
        }
        if let Some(item) = self.store.item_mut(ep::MANAGEMENT, en::MN_SERVICE, 0) {
            item[..ServiceStatus::SIZE].copy_from_slice(&st.to_bytes());
        }
    }

    pub fn config(&self) -> &BoardConfig {
        &self.cfg
    }
    /// How joints created by an MC service configuration are modelled (default: [`SimpleJoint`]).
    pub fn set_joint_factory(&mut self, f: JointFactory) {
        self.joint_factory = Some(f);
    }
    /// Whether the board has the entities of a service category.
    pub fn supports(&self, cat: u8) -> bool {
        let (e, n) = match cat {
            category::MC => (ep::MOTION_CONTROL, en::MC_JOINT),
            category::STRAIN => (ep::ANALOG_SENSORS, en::AS_STRAIN),
            category::MAIS => (ep::ANALOG_SENSORS, en::AS_MAIS),
            category::SKIN => (ep::SKIN, en::SK_SKIN),
            category::INERTIALS3 => (ep::ANALOG_SENSORS, en::AS_INERTIAL3),
            category::TEMPERATURES => (ep::ANALOG_SENSORS, en::AS_TEMPERATURE),
            category::PSC => (ep::ANALOG_SENSORS, en::AS_PSC),
            category::POS => (ep::ANALOG_SENSORS, en::AS_POS),
            category::FT => (ep::ANALOG_SENSORS, en::AS_FT),
            category::BATTERY => (ep::ANALOG_SENSORS, en::AS_BATTERY),
            _ => return false,
        };
        self.store.count(e, n) > 0
    }

    /// Adds what a service configuration names (see [`BoardConfig::auto_entities`]).
    fn add_service_entities(&mut self, cmd: &ServiceCommand) {
        for (e, n, count) in
            entities_for_service(cmd.category, cmd.service_type(), cmd.config_data())
        {
            if count == 0 {
                continue;
            }
            self.store.add_entity(e, n, count);
            if (e, n) == (ep::MOTION_CONTROL, en::MC_JOINT) {
                while self.joints.len() < usize::from(count) {
                    let j = self.joints.len() as u8;
                    let model = match self.joint_factory.as_mut() {
                        Some(f) => f(j),
                        None => Box::new(SimpleJoint::new(0.0)),
                    };
                    self.joints.push(model);
                }
            }
        }
        self.publish_joints();
    }
    pub fn state(&self) -> ApplState {
        self.state
    }
    pub fn service_state(&self, cat: u8) -> Option<ServiceState> {
        service_index(cat).map(|i| self.services[i])
    }
    pub fn counters(&self) -> BoardCounters {
        self.counters
    }
    /// The variables (read them to model sensors' configs; write sensor statuses).
    pub fn store(&self) -> &NvStore {
        &self.store
    }
    pub fn store_mut(&mut self) -> &mut NvStore {
        &mut self.store
    }
    pub fn joint(&self, j: usize) -> Option<&dyn JointModel> {
        self.joints.get(j).map(|b| b.as_ref())
    }
    pub fn joint_mut(&mut self, j: usize) -> Option<&mut (dyn JointModel + 'static)> {
        self.joints.get_mut(j).map(|b| b.as_mut())
    }
    /// The regulars currently loaded, in transmission order.
    pub fn regulars(&self) -> Vec<Id32> {
        self.regulars.iter().flatten().copied().collect()
    }
    /// The regular period: `cycletime × txratedivider`.
    pub fn regular_period(&self) -> Duration {
        let c = self.appl_config();
        let cycle = if c.cycletime == 0 { 1000 } else { c.cycletime };
        Duration::from_micros(u64::from(cycle) * u64::from(c.txratedivider.max(1)))
    }
    fn appl_config(&self) -> ApplConfig {
        self.store.read(ids::APPL_CONFIG).unwrap_or_default()
    }
    /// Takes what happened since the last call.
    pub fn poll_event(&mut self) -> Option<BoardEvent> {
        self.events.pop_front()
    }

    fn push_event(&mut self, e: BoardEvent) {
        // Nobody may be polling: keep the latest ones only.
        if self.events.len() >= crate::host::EVENT_QUEUE_LIMIT {
            self.events.pop_front();
        }
        self.events.push_back(e);
    }

    fn set_state(&mut self, s: ApplState) {
        if s != self.state {
            self.state = s;
            self.regulars_resume = None;
            self.write_appl_status();
            self.push_event(BoardEvent::State(s));
        }
    }

    /// Processes a datagram from the host; replies are queued for [`Self::poll_transmit`].
    /// A malformed frame is counted and dropped; malformed ROPs are counted and the ROPs
    /// before them processed (as `EOreceiver` does).
    pub fn handle_datagram(&mut self, datagram: &[u8]) -> Result<(), FrameError> {
        let frame = match Frame::decode(datagram) {
            Ok(f) => f,
            Err(e) => {
                self.counters.invalid_frames += 1;
                return Err(e);
            }
        };
        self.counters.frames_received += 1;
        let seq = frame.header.sequence;
        if let Some(prev) = self.rx_sequence {
            if seq != prev.wrapping_add(1) {
                self.counters.sequence_errors += 1;
            }
        }
        self.rx_sequence = Some(seq);
        if frame.visit_rops(|r| self.process(r)).is_some() {
            self.counters.bad_rops += 1;
        }
        Ok(())
    }

    fn reply_to(&self, rop: &RopRef) -> Rop {
        let mut r = Rop {
            ctrl: Default::default(),
            code: rop.code,
            id32: rop.id32,
            data: Vec::new(),
            signature: None,
            time: None,
        };
        if rop.ctrl.plussign {
            r.ctrl.plussign = true;
            r.signature = rop.signature;
        }
        if rop.ctrl.rqsttime {
            r.ctrl.plustime = true;
        }
        r
    }

    fn process(&mut self, rop: RopRef) {
        let id = rop.id32;
        let known = self.store.contains(id);
        match rop.code {
            RopCode::Ask => {
                if known {
                    let mut r = self.reply_to(&rop);
                    r.code = RopCode::Say;
                    r.data = self.store.get(id).map(<[u8]>::to_vec).unwrap_or_default();
                    self.replies.push(r);
                } else {
                    self.reject(&rop);
                }
            }
            RopCode::Set if rop.carries_data() => {
                if known && self.store.set(id, rop.data).is_ok() {
                    if rop.ctrl.rqstconf {
                        let mut r = self.reply_to(&rop);
                        r.ctrl.confinfo = ConfInfo::Ack;
                        self.replies.push(r);
                    }
                    self.on_set(id, rop.data);
                } else {
                    self.reject(&rop);
                }
            }
            _ => {
                // say/sig/rst: the board owns no remote variables; confirm if asked.
                if rop.ctrl.rqstconf {
                    let mut r = self.reply_to(&rop);
                    r.ctrl.confinfo = ConfInfo::Ack;
                    self.replies.push(r);
                }
            }
        }
    }

    fn reject(&mut self, rop: &RopRef) {
        self.counters.rejected_rops += 1;
        if rop.ctrl.rqstconf {
            let mut r = self.reply_to(rop);
            r.ctrl.confinfo = ConfInfo::Nak;
            self.replies.push(r);
        }
    }

    fn on_set(&mut self, id: Id32, data: &[u8]) {
        self.push_event(BoardEvent::Set(id));
        match (id.endpoint(), id.entity(), id.tag()) {
            (ep::MANAGEMENT, en::MN_APPL, tag::MN_APPL_CMMNDS_GO2STATE) => {
                match ApplState::from_u8(data[0]) {
                    Some(ApplState::Running) => self.set_state(ApplState::Running),
                    Some(ApplState::Config) => self.set_state(ApplState::Config),
                    _ => {}
                }
            }
            (
                ep::MANAGEMENT,
                en::MN_APPL,
                tag::MN_APPL_CONFIG | tag::MN_APPL_CONFIG_TXRATEDIVIDER,
            ) => {
                self.write_appl_status();
            }
            (ep::MANAGEMENT, en::MN_COMM, tag::MN_COMM_CMMNDS_COMMAND_QUERYARRAY) => {
                if let Ok(q) = QueryArray::from_bytes(data) {
                    if q.opc == opc::QUERY_ARRAY_EPDES {
                        let reply = ReplyArray::endpoint_descriptors(&self.endpoint_descriptors());
                        let bytes = reply.to_bytes();
                        let _ = self.store.set(ids::COMM_REPLY_ARRAY, &bytes);
                        self.replies.push(Rop::sig(ids::COMM_REPLY_ARRAY, bytes));
                    }
                }
            }
            (ep::MANAGEMENT, en::MN_SERVICE, tag::MN_SERVICE_CMMNDS_COMMAND) => {
                if let Ok(cmd) = ServiceCommand::from_bytes(data) {
                    self.service_command(&cmd);
                }
            }
            (ep::MOTION_CONTROL, en::MC_JOINT, t) => self.joint_set(id.index(), t, data),
            // a strain asked to signal its full scales once does so (what icub-main's
            // fillScaleFactor waits for)
            (ep::ANALOG_SENSORS, en::AS_STRAIN, tag::AS_STRAIN_CONFIG) => {
                let signal_once = crate::entities::analog::StrainConfig::from_bytes(data)
                    .is_ok_and(|c| c.signal_once_fullscale);
                let fullscale = Id32::new(
                    ep::ANALOG_SENSORS,
                    en::AS_STRAIN,
                    id.index(),
                    tag::AS_STRAIN_STATUS_FULLSCALE,
                );
                if let (true, Ok(bytes)) = (signal_once, self.store.get(fullscale)) {
                    self.replies.push(Rop::sig(fullscale, bytes.to_vec()));
                }
            }
            _ => {}
        }
    }

    fn endpoint_descriptors(&self) -> Vec<EndpointDescriptor> {
        let mut v = vec![EndpointDescriptor {
            endpoint: ep::MANAGEMENT,
            entities_inside: 4,
            version: self.cfg.protocol[0],
        }];
        for e in [ep::MOTION_CONTROL, ep::ANALOG_SENSORS, ep::SKIN] {
            let n = (0..crate::id::entities_in_endpoint(e))
                .filter(|ent| self.store.count(e, *ent) > 0)
                .count() as u8;
            // Every endpoint is listed, with its version, even before a service gives it
            // entities: the host checks the versions before activating the services.
            v.push(EndpointDescriptor {
                endpoint: e,
                entities_inside: n,
                version: self.cfg.protocol[usize::from(e)],
            });
        }
        v
    }

    fn service_command(&mut self, cmd: &ServiceCommand) {
        let cat = cmd.category;
        let mut ok = true;
        let mut data = [0u8; 28];
        let mut stype = service_type::NONE;
        let cats: Vec<usize> = if cat == category::ALL {
            (0..category::COUNT).collect()
        } else {
            service_index(cat).into_iter().collect()
        };
        match ServiceOperation::from_u8(cmd.operation) {
            Some(ServiceOperation::VerifyActivate) => {
                stype = cmd.service_type();
                // A sensor service needs its boards described: an all-zero configuration
                // (no board type, no location) finds nothing on the CAN buses.
                let refused = if cat == category::MC {
                    !self.mc_config_fits(cmd)
                } else {
                    cmd.config_data().iter().all(|b| *b == 0)
                };
                if self.cfg.auto_entities && !refused {
                    self.add_service_entities(cmd);
                }
                match service_index(cat) {
                    Some(i) if refused => {
                        self.services[i] = ServiceState::FailureOfVerify;
                        ok = false;
                    }
                    Some(i) if self.supports(cat) => {
                        self.services[i] = ServiceState::Activated;
                        if cat == category::MC {
                            self.activate_mc();
                        }
                        self.push_event(BoardEvent::Verified {
                            category: cat,
                            service_type: stype,
                            config: cmd.config_data().to_vec(),
                        });
                    }
                    Some(i) => {
                        self.services[i] = ServiceState::FailureOfVerify;
                        ok = false;
                    }
                    None => ok = false,
                }
            }
            Some(ServiceOperation::Start) => {
                for i in &cats {
                    if matches!(
                        self.services[*i],
                        ServiceState::Activated | ServiceState::Started
                    ) {
                        self.services[*i] = ServiceState::Started;
                    } else if cat != category::ALL {
                        ok = false;
                    }
                }
                if self.services.contains(&ServiceState::Started) {
                    self.set_state(ApplState::Running);
                }
            }
            Some(ServiceOperation::Stop) => {
                let mut stopped = 0usize;
                for i in &cats {
                    if self.services[*i] == ServiceState::Started {
                        self.services[*i] = ServiceState::Activated;
                    }
                    stopped += self.regulars[*i].len();
                    self.regulars[*i].clear();
                }
                if !self.services.contains(&ServiceState::Started) {
                    self.set_state(ApplState::Config);
                }
                // eOmn_service_command_stop_result_data_t: applstate, totalregulars, serviceregulars.
                data[0] = self.state as u8;
                data[1] = self.regulars.iter().map(Vec::len).sum::<usize>().min(255) as u8;
                data[2] = stopped.min(255) as u8;
            }
            Some(ServiceOperation::Deactivate) => {
                for i in &cats {
                    self.services[*i] = ServiceState::Idle;
                    self.regulars[*i].clear();
                }
                if !self.services.contains(&ServiceState::Started) {
                    self.set_state(ApplState::Config);
                }
            }
            Some(ServiceOperation::RegsigLoad) => match service_index(cat) {
                Some(i) => {
                    for id in cmd.id32s() {
                        if self.store.contains(id) {
                            if !self.regulars[i].contains(&id) {
                                self.regulars[i].push(id);
                            }
                        } else {
                            ok = false;
                        }
                    }
                }
                None => ok = false,
            },
            Some(ServiceOperation::RegsigClear) => {
                for i in &cats {
                    self.regulars[*i].clear();
                }
            }
            Some(ServiceOperation::None) | None => ok = false,
        }
        let result = ServiceCommandResult {
            latest_command_is_ok: ok,
            operation: cmd.operation,
            category: cat,
            service_type: stype,
            data,
        };
        self.write_service_status(result);
        self.replies
            .push(Rop::sig(ids::SERVICE_COMMAND_RESULT, result.to_bytes()));
        self.push_event(BoardEvent::Service {
            operation: cmd.operation,
            category: cat,
            ok,
        });
    }

    /// Whether a motion-control configuration describes the joints this board drives,
    /// as a board checks its joint-motor descriptors: none (an empty configuration) or
    /// another number than the motors behind it fails the verification. A generic service (or none) asks the board to use what it has on board.
    fn mc_config_fits(&self, cmd: &ServiceCommand) -> bool {
        let have = self.joints.len();
        if matches!(
            cmd.service_type(),
            service_type::MC_GENERIC | service_type::NONE
        ) {
            return have > 0;
        }
        let named = McServiceConfig::parse(cmd.service_type(), cmd.config_data())
            .map_or(0, |c| usize::from(c.joints()));
        named > 0 && (have == 0 || named == have)
    }

    fn activate_mc(&mut self) {
        let n = self.joints.len().min(255) as u8;
        // eO16flags_t: bit j set for each initted joint.
        let mask = 1u32.checked_shl(u32::from(n)).map_or(u32::MAX, |v| v - 1) as u16;
        let status = crate::entities::mc::ControllerStatus {
            state_of_controller: 1,
            num_of_joints: n,
            num_of_motors: n,
            all_jomo_initted: true,
            flags_initted_joints: mask,
            flags_initted_motors: mask,
            // an emulated 48 V supply, in the firmware's 0.01 V
            supply_voltage: 4800,
        };
        let _ = self.store.write(
            Id32::new(
                ep::MOTION_CONTROL,
                en::MC_CONTROLLER,
                0,
                tag::MC_CONTROLLER_STATUS,
            ),
            &status,
        );
    }

    fn joint_set(&mut self, j: u8, t: u8, data: &[u8]) {
        // Any part of the joint config (the whole, a PID, the user limits, the impedance,
        // ...) reconfigures the joint with the config as it now stands.
        let config = (tag::MC_JOINT_CONFIG..=tag::MC_JOINT_CONFIG_TCFILTERTYPE)
            .contains(&t)
            .then(|| {
                self.store
                    .read::<JointConfig>(ids::joint(j, tag::MC_JOINT_CONFIG))
                    .ok()
            })
            .flatten();
        let Some(model) = self.joints.get_mut(usize::from(j)) else {
            return;
        };
        if let Some(c) = &config {
            model.configure(c);
        }
        match t {
            tag::MC_JOINT_CMMNDS_SETPOINT => {
                if let Ok(s) = Setpoint::from_bytes(data) {
                    // the wire's torque references are µN·m, the plant's N·m
                    let s = match s {
                        Setpoint::Torque { value } => Setpoint::Torque {
                            value: (f64::from(value) / TORQUE_TO_WIRE) as f32,
                        },
                        s => s,
                    };
                    model.setpoint(&s);
                }
            }
            tag::MC_JOINT_INPUTS_EXTERNALLYMEASUREDTORQUE => {
                if let Some(b) = data.get(..4) {
                    let raw = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
                    model.set_external_torque(f64::from(raw) / TORQUE_TO_WIRE);
                }
            }
            tag::MC_JOINT_CMMNDS_CONTROLMODE => model.set_control_mode(data[0]),
            tag::MC_JOINT_CMMNDS_INTERACTIONMODE => model.set_interaction_mode(data[0]),
            tag::MC_JOINT_CMMNDS_STOPTRAJECTORY if data[0] != 0 => model.stop_trajectory(),
            tag::MC_JOINT_CMMNDS_CALIBRATION => {
                if let Ok(c) = Calibrator::from_bytes(data) {
                    model.calibrate(&c);
                }
            }
            _ => {}
        }
        self.publish_joint(usize::from(j));
    }

    /// Advances the joints by `dt` seconds (while running, as the firmware's control loop
    /// runs only then) and publishes their status in the joint and motor variables.
    pub fn step(&mut self, dt: f64) {
        if self.state == ApplState::Running {
            for j in self.joints.iter_mut() {
                j.step(dt);
            }
        }
        self.publish_joints();
    }

    fn publish_joints(&mut self) {
        for j in 0..self.joints.len() {
            self.publish_joint(j);
        }
    }

    fn publish_joint(&mut self, j: usize) {
        let Some(model) = self.joints.get(j) else {
            return;
        };
        let f = model.feedback();
        let ji = j as u8;
        let sat = |v: f64| v.round().clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32;
        // torques on the wire in µN·m
        let torque_ref = sat(f.torque_reference * TORQUE_TO_WIRE);
        let torque_err = sat((f.torque_reference - f.torque) * TORQUE_TO_WIRE);
        // eOmc_joint_status_ofpid_t: the torque view (dummyref1, reftrq, dummyerr1,
        // errtrq, output) in torque control, the compliant-position view (refpos, reftrq,
        // errpos, errtrq, output) with compliant interaction, else the stiff position one
        let ofpid = if f.control_mode == control_mode::TORQUE {
            [0, torque_ref, 0, torque_err, i32::from(f.pwm)]
        } else if f.interaction_mode == interaction_mode::COMPLIANT {
            [
                sat(f.reference),
                torque_ref,
                sat(f.reference - f.position),
                torque_err,
                i32::from(f.pwm),
            ]
        } else {
            [
                sat(f.reference),
                0,
                sat(f.reference - f.position),
                0,
                i32::from(f.pwm),
            ]
        };
        // the motor's temperature as its sensor reads it, when the host's motor config
        // says it has one (hasTempSensor)
        let has_sensor = self
            .store
            .read::<MotorConfig>(ids::motor(ji, tag::MC_MOTOR_CONFIG))
            .is_ok_and(|c| c.flags & 0x02 != 0);
        let temperature = if has_sensor {
            pt100_raw(f.temperature)
        } else {
            0
        };
        let core = JointStatusCore {
            position: sat(f.position),
            velocity: sat(f.velocity),
            acceleration: sat(f.acceleration),
            torque: (f.torque * TORQUE_TO_WIRE) as f32,
            ofpid,
            control_mode: f.control_mode,
            interaction_mode: f.interaction_mode,
            motion_done: f.motion_done,
        };
        let target = JointStatusTarget {
            position: sat(f.target_position),
            position_raw: sat(f.reference),
            velocity: sat(f.target_velocity),
            acceleration: 0,
            torque: if f.control_mode == control_mode::TORQUE {
                torque_ref as f32
            } else {
                0.0
            },
            pwm: i32::from(f.pwm),
            current: i32::from(f.current),
        };
        let motor = MotorStatus {
            basic: MotorStatusBasic {
                position: sat(f.position),
                velocity: sat(f.velocity),
                acceleration: sat(f.acceleration),
                current: f.current,
                temperature,
                pwm: f.pwm,
            },
            mc_fault_state: 0,
        };
        let _ = self
            .store
            .write(ids::joint(ji, tag::MC_JOINT_STATUS_CORE), &core);
        let _ = self
            .store
            .write(ids::joint(ji, tag::MC_JOINT_STATUS_TARGET), &target);
        let _ = self.store.write(
            ids::joint(ji, tag::MC_JOINT_STATUS_ADDINFO_MULTIENC),
            &MultiEncoders([core.position, 0, 0]),
        );
        let _ = self
            .store
            .write(ids::motor(ji, tag::MC_MOTOR_STATUS), &motor);
    }

    /// The next datagram to send at time `now` (µs of the board's life, used as the
    /// frame's age): queued replies at once, and the regulars when their period is due
    /// while running. Call until `None`.
    pub fn poll_transmit(&mut self, now: Duration) -> Option<Vec<u8>> {
        let mut fb = FrameBuilder::new(self.cfg.max_tx_packet);
        let mut taken = 0;
        for r in &self.replies {
            if fb.push(r).is_err() {
                if fb.is_empty() {
                    // A reply larger than a datagram can never go: drop it.
                    taken += 1;
                    continue;
                }
                break;
            }
            taken += 1;
        }
        self.replies.drain(..taken);
        if self.replies.is_empty() && self.regulars_due(now) {
            let regs = self.regulars();
            let mut sent = 0;
            let start = self.regulars_resume.take().unwrap_or(0);
            for (i, &id) in regs.iter().enumerate().skip(start) {
                let Ok(data) = self.store.get(id) else {
                    continue;
                };
                if fb.push_sig(id, data).is_err() {
                    if fb.is_empty() {
                        continue;
                    }
                    // Flush this frame; the rest of the regulars go in the next one.
                    self.regulars_resume = Some(i);
                    self.counters.regulars_sent += sent;
                    return Some(self.finish(&fb, now));
                }
                sent += 1;
            }
            self.counters.regulars_sent += sent;
            self.schedule_regulars(now);
        }
        if fb.is_empty() {
            return None;
        }
        Some(self.finish(&fb, now))
    }

    fn regulars_due(&self, now: Duration) -> bool {
        self.state == ApplState::Running
            && self.regulars.iter().any(|r| !r.is_empty())
            && (self.regulars_resume.is_some() || self.next_regulars.is_none_or(|t| now >= t))
    }

    /// The next regulars are due one period after the last ones; after a late start,
    /// at the next multiple of the period in the board's time (not `now + period`): the
    /// cycle keeps its phase, as a board's firmware cycle does, and boards of commensurate
    /// periods served by one thread fall due together.
    fn schedule_regulars(&mut self, now: Duration) {
        let p = self.regular_period();
        let next = match self.next_regulars {
            Some(t) if t + p > now => t + p,
            _ => next_multiple(now, p),
        };
        self.next_regulars = Some(next);
    }

    /// When [`Self::poll_transmit`] next has something to send without new input.
    pub fn next_transmit(&self) -> Option<Duration> {
        if !self.replies.is_empty() {
            return Some(Duration::ZERO);
        }
        if self.state == ApplState::Running && self.regulars.iter().any(|r| !r.is_empty()) {
            if self.regulars_resume.is_some() {
                return Some(Duration::ZERO);
            }
            return Some(self.next_regulars.unwrap_or(Duration::ZERO));
        }
        None
    }

    fn finish(&mut self, fb: &FrameBuilder, now: Duration) -> Vec<u8> {
        self.tx_sequence += 1;
        self.counters.frames_sent += 1;
        let v = fb.finish(self.tx_sequence, now.as_micros() as u64);
        debug_assert!(v.len() >= EMPTY_FRAME_SIZE);
        v
    }
}

/// The first multiple of `period` after `now` (both in the board's time).
pub fn next_multiple(now: Duration, period: Duration) -> Duration {
    let p = period.as_nanos().max(1);
    let k = now.as_nanos() / p + 1;
    Duration::from_nanos(u64::try_from(k * p).unwrap_or(u64::MAX))
}
