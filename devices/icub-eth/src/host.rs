//! The host side (what icub-main's `HostTransceiver`, `theNVmanager`, `EthMonitorPresence`
//! and `EthResource` do), without sockets.
//!
//! [`HostTransceiver`] queues ROPs and packs them into ropframes of at most the board's
//! `maxSizeRXpacket` bytes (`poll_transmit`), numbering the frames from 1; it decodes the
//! board's datagrams into its copy of the board's variables (`handle_datagram`), matches
//! each `say` to its `ask` by signature and each awaited `sig` by id32, expires requests
//! after their timeout (`handle_timeout`), checks the board's sequence numbers and
//! reports a board that stops streaming within its presence timeout. Bad datagrams are
//! counted and dropped.
//!
//! [`Startup`] drives one board through `EthResource`'s bring-up and the services'
//! activation, with the same timeouts and retries as C++.

use crate::entities::boards::EthBoardType;
use crate::entities::mn::{
    category, opc, versions, ApplConfig, ApplStatus, QueryArray, ReplyArray, ServiceCommand,
    ServiceCommandResult, ServiceOperation, Version,
};
use crate::frame::{Frame, FrameBuilder, FrameError, RopsError};
use crate::id::{endpoint as ep, endpoint_name, entity as en, ids, Id32};
use crate::nvstore::{NvError, NvStore};
use crate::retry::Retry;
use crate::rop::{ConfInfo, Rop, RopCode, RopRef};
use crate::wire::Entity;
use std::collections::{HashMap, VecDeque};
use std::net::Ipv4Addr;
use std::time::Duration;
use thiserror::Error;

/// The presence timeout when `ETH_BOARD_ACTIONS/MONITOR_ITS_PRESENCE` gives none (20 ms).
pub const DEFAULT_PRESENCE_TIMEOUT: Duration = Duration::from_millis(20);
/// Events kept for the owner; older ones are dropped (and counted) beyond this.
pub const EVENT_QUEUE_LIMIT: usize = 4096;
/// `theNVmanager` signatures wrap below this value (`uniquesignature()`).
const SIGNATURE_WRAP: u32 = 0xA000_0000;

/// What the host knows of a board before talking to it (`ETH_BOARD` of the XML).
#[derive(Debug, Clone)]
pub struct HostConfig {
    /// `ETH_BOARD_SETTINGS/Name`.
    pub board_name: String,
    /// `ETH_BOARD_PROPERTIES/IpAddress`.
    pub board_ip: Ipv4Addr,
    /// `ETH_BOARD_PROPERTIES/Type`.
    pub board_type: EthBoardType,
    /// `ETH_BOARD_PROPERTIES/maxSizeRXpacket` (768 by default): the largest frame we send.
    pub max_tx_packet: usize,
    /// `MONITOR_ITS_PRESENCE/timeout` (None: `enabled false`).
    pub presence_timeout: Option<Duration>,
    /// Our protocol versions (this crate's by default): management, MC, AS, SK.
    pub protocol: [Version; 4],
}

impl HostConfig {
    pub fn new(board_name: &str, board_ip: Ipv4Addr, board_type: EthBoardType) -> Self {
        Self {
            board_name: board_name.to_string(),
            board_ip,
            board_type,
            max_tx_packet: 768,
            presence_timeout: Some(DEFAULT_PRESENCE_TIMEOUT),
            protocol: [versions::MN, versions::MC, versions::AS, versions::SK],
        }
    }
}

/// Identifies an outstanding request.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct RequestId(u64);

/// Why a request failed.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum RequestError {
    /// As `theNVmanager::Impl::ask()` / `wait()` report it.
    #[error("timeout for BOARD {board} IP {ip} and nv {id}")]
    Timeout {
        board: String,
        ip: Ipv4Addr,
        id: Id32,
    },
    #[error("BOARD {board} IP {ip} refused nv {id} (nak)")]
    Nak {
        board: String,
        ip: Ipv4Addr,
        id: Id32,
    },
}

/// A local problem preparing a request.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum HostError {
    #[error(transparent)]
    Nv(#[from] NvError),
    #[error("ROP for {0} does not fit in a frame of the board's maxSizeRXpacket")]
    TooBig(Id32),
}

/// Something the owner should log or act on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum HostEvent {
    /// The board has been silent longer than its presence timeout
    /// (`EthMonitorPresence`: "has been silent for ... sec (its timeout is ... sec)").
    BoardLost {
        silent_for: Duration,
        timeout: Duration,
    },
    /// The board talks again after being lost.
    BoardRecovered { lost_for: Duration },
    /// A frame's sequence number is not the previous + 1 (with both frames' ages, µs).
    SequenceGap {
        expected: u64,
        received: u64,
        previous_age: u64,
        age: u64,
    },
    /// A datagram that is not a ropframe was dropped.
    BadFrame(FrameError),
    /// ROPs of a frame could not be parsed (those before were used).
    BadRops(RopsError),
    /// A variable arrived by `sig` (regulars, command results, diagnostics).
    Signal(Id32),
}

impl HostEvent {
    /// The message C++ prints for this event, naming the board.
    pub fn describe(&self, cfg: &HostConfig) -> String {
        let who = format!("{} ({})", cfg.board_ip, cfg.board_name);
        match self {
            Self::BoardLost {
                silent_for,
                timeout,
            } => format!(
                "eth::EthMonitorPresence: BOARD {who} has been silent for {:.3} sec (its timeout is {:.3} sec)",
                silent_for.as_secs_f64(),
                timeout.as_secs_f64()
            ),
            Self::BoardRecovered { lost_for } => format!(
                "eth::EthMonitorPresence: BOARD {who} has shown after being lost for {:.3} sec",
                lost_for.as_secs_f64()
            ),
            Self::SequenceGap {
                expected,
                received,
                previous_age,
                age,
            } => format!(
                "hostTransceiver()::parse() detected an ERROR in sequence number from IP = {} Expected: {expected} - Received: {received} - Missing: {} - Prev Frame TX at {previous_age} us - This Frame TX at {age} us",
                cfg.board_ip,
                received.wrapping_sub(*expected)
            ),
            Self::BadFrame(e) => format!(
                "hostTransceiver()::parse() detected an ERROR of type INVALID FRAME from IP = {}: {e}",
                cfg.board_ip
            ),
            Self::BadRops(e) => format!("BOARD {who}: dropped ROPs of a ropframe: {e}"),
            Self::Signal(id) => format!("BOARD {who}: sig<{id}>"),
        }
    }
}

/// Counters of the host's reception and transmission.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct HostCounters {
    pub frames_received: u64,
    pub frames_sent: u64,
    pub invalid_frames: u64,
    pub bad_rops: u64,
    pub sequence_gaps: u64,
    /// ROPs about variables we do not know, or with a size that is not the variable's.
    pub unknown_rops: u64,
    pub timeouts: u64,
    /// Events dropped because nobody polled them ([`EVENT_QUEUE_LIMIT`]).
    pub events_dropped: u64,
}

#[derive(Debug)]
struct Pending {
    id: Id32,
    deadline: Duration,
    /// `ask`: wait for the `say` with this signature; `command`: for a `sig` of `id`.
    signature: Option<u32>,
}

/// The host's side of one board.
#[derive(Debug)]
pub struct HostTransceiver {
    cfg: HostConfig,
    store: NvStore,
    queue: VecDeque<Rop>,
    pending: HashMap<RequestId, Pending>,
    results: HashMap<RequestId, Result<Vec<u8>, RequestError>>,
    events: VecDeque<HostEvent>,
    next_request: u64,
    next_signature: u32,
    tx_sequence: u64,
    /// Sequence number and age of the last frame.
    rx_sequence: Option<(u64, u64)>,
    last_heard: Option<Duration>,
    lost_since: Option<Duration>,
    monitor_presence: bool,
    counters: HostCounters,
    /// Variables whose every received value is kept, in order, for a device that must
    /// see each one (several ROPs of one variable may arrive between two of its reads:
    /// the inertials of more than four sensors, the skin's CAN frames).
    kept: HashMap<Id32, VecDeque<Vec<u8>>>,
}

/// How many received values of a kept variable wait for their device at most (the
/// oldest go first).
pub const KEPT_VALUES_LIMIT: usize = 256;

impl HostTransceiver {
    pub fn new(cfg: HostConfig) -> Self {
        // Room for every variable of the largest boards (`eonvset_BRDcfgMax`).
        let mut store = NvStore::new();
        for e in 0..4 {
            store.add_entity(ep::MANAGEMENT, e, 1);
        }
        store.add_entity(ep::MOTION_CONTROL, en::MC_JOINT, 12);
        store.add_entity(ep::MOTION_CONTROL, en::MC_MOTOR, 12);
        store.add_entity(ep::MOTION_CONTROL, en::MC_CONTROLLER, 1);
        for e in 0..8 {
            store.add_entity(ep::ANALOG_SENSORS, e, 4);
        }
        store.add_entity(ep::SKIN, en::SK_SKIN, 4);
        Self {
            cfg,
            store,
            queue: VecDeque::new(),
            pending: HashMap::new(),
            results: HashMap::new(),
            events: VecDeque::new(),
            next_request: 1,
            next_signature: 0,
            tx_sequence: 0,
            rx_sequence: None,
            last_heard: None,
            lost_since: None,
            monitor_presence: false,
            counters: HostCounters::default(),
            kept: HashMap::new(),
        }
    }

    /// Keeps every value of `id` that arrives from now on, for [`Self::take_kept`] (as
    /// icub-main's devices get each ROP in their `update()`).
    pub fn keep_values(&mut self, id: Id32) {
        self.kept.entry(id).or_default();
    }

    /// The values of `id` received since the last call, oldest first.
    pub fn take_kept(&mut self, id: Id32) -> Vec<Vec<u8>> {
        self.kept
            .get_mut(&id)
            .map(|q| q.drain(..).collect())
            .unwrap_or_default()
    }

    pub fn config(&self) -> &HostConfig {
        &self.cfg
    }
    pub fn counters(&self) -> HostCounters {
        self.counters
    }
    /// Our copy of the board's variables (`getLocalValue`).
    pub fn store(&self) -> &NvStore {
        &self.store
    }
    /// Overwrites a variable's local copy (C++ `setLocalValue`), e.g. to empty an array
    /// before waiting for the board to fill it.
    pub fn set_local(&mut self, id: Id32, data: &[u8]) -> Result<(), NvError> {
        self.store.set(id, data)
    }
    /// A variable as last received.
    pub fn read<T: Entity>(&self, id: Id32) -> Result<T, NvError> {
        self.store.read(id)
    }
    /// Whether the board is currently reported lost.
    pub fn board_lost(&self) -> bool {
        self.lost_since.is_some()
    }

    /// Arms (or disarms) the presence monitor: once armed, a board silent for longer than
    /// its presence timeout is reported (armed when a service starts: from then on the
    /// board streams its regulars).
    pub fn monitor_presence(&mut self, on: bool, now: Duration) {
        self.monitor_presence = on && self.cfg.presence_timeout.is_some();
        if self.monitor_presence && self.last_heard.is_none() {
            self.last_heard = Some(now);
        }
    }

    fn request_id(&mut self) -> RequestId {
        let r = RequestId(self.next_request);
        self.next_request += 1;
        r
    }

    fn check_size(&self, rop: &Rop) -> Result<(), HostError> {
        if rop.wire_size() + crate::frame::EMPTY_FRAME_SIZE > self.cfg.max_tx_packet {
            return Err(HostError::TooBig(rop.id32));
        }
        Ok(())
    }

    /// `ask<id>` with a fresh signature (`theNVmanager::ask`); the value arrives with the
    /// board's `say`. Result via [`Self::take_result`].
    pub fn ask(
        &mut self,
        id: Id32,
        timeout: Duration,
        now: Duration,
    ) -> Result<RequestId, HostError> {
        id.layout().ok_or(NvError::Unknown(id))?;
        let signature = self.next_signature;
        self.next_signature = (self.next_signature + 1) % SIGNATURE_WRAP;
        let rop = Rop::ask(id)
            .with_signature(signature)
            .with_time(now.as_micros() as u64);
        self.check_size(&rop)?;
        self.queue.push_back(rop);
        let r = self.request_id();
        self.pending.insert(
            r,
            Pending {
                id,
                deadline: now + timeout,
                signature: Some(signature),
            },
        );
        Ok(r)
    }

    /// `set<id>` (`HostTransceiver::addROPset`): `data` must have the variable's size.
    pub fn set(&mut self, id: Id32, data: &[u8], now: Duration) -> Result<(), HostError> {
        let size = id.size().ok_or(NvError::Unknown(id))?;
        if data.len() != size {
            return Err(NvError::Size {
                id,
                expected: size,
                got: data.len(),
            }
            .into());
        }
        let rop = Rop::set(id, data.to_vec()).with_time(now.as_micros() as u64);
        self.check_size(&rop)?;
        self.queue.push_back(rop);
        Ok(())
    }

    /// `set` of a typed variable.
    pub fn set_value<T: Entity>(
        &mut self,
        id: Id32,
        v: &T,
        now: Duration,
    ) -> Result<(), HostError> {
        self.set(id, &v.to_bytes(), now)
    }

    /// `theNVmanager::command`: `set<cmd>` then wait for the board's `sig<reply>`.
    pub fn command(
        &mut self,
        cmd: Id32,
        data: &[u8],
        reply: Id32,
        timeout: Duration,
        now: Duration,
    ) -> Result<RequestId, HostError> {
        reply.layout().ok_or(NvError::Unknown(reply))?;
        self.set(cmd, data, now)?;
        let r = self.request_id();
        self.pending.insert(
            r,
            Pending {
                id: reply,
                deadline: now + timeout,
                signature: None,
            },
        );
        Ok(r)
    }

    /// The outcome of a request once it has one (the value asked or signalled).
    pub fn take_result(&mut self, r: RequestId) -> Option<Result<Vec<u8>, RequestError>> {
        self.results.remove(&r)
    }

    /// Whether a request is still waiting.
    pub fn is_pending(&self, r: RequestId) -> bool {
        self.pending.contains_key(&r)
    }

    /// The next ropframe to send, if ROPs are queued: as many as fit `max_tx_packet`.
    pub fn poll_transmit(&mut self, now: Duration) -> Option<Vec<u8>> {
        if self.queue.is_empty() {
            return None;
        }
        let mut fb = FrameBuilder::new(self.cfg.max_tx_packet);
        while let Some(rop) = self.queue.front() {
            if fb.push(rop).is_err() {
                if fb.is_empty() {
                    // Cannot happen (checked when queued); never loop on it.
                    self.queue.pop_front();
                    continue;
                }
                break;
            }
            self.queue.pop_front();
        }
        if fb.is_empty() {
            return None;
        }
        self.tx_sequence += 1;
        self.counters.frames_sent += 1;
        Some(fb.finish(self.tx_sequence, now.as_micros() as u64))
    }

    /// Takes a datagram from the board. A datagram that is not a ropframe is counted,
    /// reported as [`HostEvent::BadFrame`] and returned as an error.
    pub fn handle_datagram(&mut self, datagram: &[u8], now: Duration) -> Result<(), FrameError> {
        let frame = match Frame::decode(datagram) {
            Ok(f) => f,
            Err(e) => {
                self.counters.invalid_frames += 1;
                self.push_event(HostEvent::BadFrame(e));
                return Err(e);
            }
        };
        self.counters.frames_received += 1;
        self.heard(now);
        let (seq, age) = (frame.header.sequence, frame.header.age);
        if let Some((prev, previous_age)) = self.rx_sequence {
            let expected = prev.wrapping_add(1);
            if seq != expected {
                self.counters.sequence_gaps += 1;
                self.push_event(HostEvent::SequenceGap {
                    expected,
                    received: seq,
                    previous_age,
                    age,
                });
            }
        }
        self.rx_sequence = Some((seq, age));
        if let Some(e) = frame.visit_rops(|r| self.process(r)) {
            self.counters.bad_rops += 1;
            self.push_event(HostEvent::BadRops(e));
        }
        Ok(())
    }

    fn heard(&mut self, now: Duration) {
        if let Some(since) = self.lost_since.take() {
            self.push_event(HostEvent::BoardRecovered {
                lost_for: now.saturating_sub(since),
            });
        }
        self.last_heard = Some(now);
    }

    fn process(&mut self, rop: RopRef) {
        let id = rop.id32;
        match (rop.code, rop.ctrl.confinfo) {
            (RopCode::Say | RopCode::Sig, ConfInfo::None) => {
                if self.store.set(id, rop.data).is_err() {
                    self.counters.unknown_rops += 1;
                    return;
                }
                if let Some(q) = self.kept.get_mut(&id) {
                    if q.len() >= KEPT_VALUES_LIMIT {
                        q.pop_front();
                    }
                    q.push_back(rop.data.to_vec());
                }
                let done: Vec<RequestId> = self
                    .pending
                    .iter()
                    .filter(|(_, p)| {
                        p.id == id
                            && match (rop.code, p.signature) {
                                (RopCode::Say, Some(s)) => rop.signature == Some(s),
                                (RopCode::Sig, None) => true,
                                _ => false,
                            }
                    })
                    .map(|(r, _)| *r)
                    .collect();
                for r in done {
                    self.pending.remove(&r);
                    self.finish_request(r, Ok(rop.data.to_vec()));
                }
                if rop.code == RopCode::Sig {
                    self.push_event(HostEvent::Signal(id));
                }
            }
            (_, ConfInfo::Nak) => {
                let done: Vec<RequestId> = self
                    .pending
                    .iter()
                    .filter(|(_, p)| {
                        p.id == id && (p.signature.is_none() || p.signature == rop.signature)
                    })
                    .map(|(r, _)| *r)
                    .collect();
                for r in done {
                    self.pending.remove(&r);
                    self.finish_request(
                        r,
                        Err(RequestError::Nak {
                            board: self.cfg.board_name.clone(),
                            ip: self.cfg.board_ip,
                            id,
                        }),
                    );
                }
            }
            _ => {}
        }
    }

    /// Expires requests and checks the board's presence at time `now`.
    pub fn handle_timeout(&mut self, now: Duration) {
        let expired: Vec<RequestId> = self
            .pending
            .iter()
            .filter(|(_, p)| now >= p.deadline)
            .map(|(r, _)| *r)
            .collect();
        for r in expired {
            if let Some(p) = self.pending.remove(&r) {
                self.counters.timeouts += 1;
                self.finish_request(
                    r,
                    Err(RequestError::Timeout {
                        board: self.cfg.board_name.clone(),
                        ip: self.cfg.board_ip,
                        id: p.id,
                    }),
                );
            }
        }
        if let (true, Some(timeout), Some(last), None) = (
            self.monitor_presence,
            self.cfg.presence_timeout,
            self.last_heard,
            self.lost_since,
        ) {
            let silent = now.saturating_sub(last);
            if silent > timeout {
                self.lost_since = Some(last);
                self.push_event(HostEvent::BoardLost {
                    silent_for: silent,
                    timeout,
                });
            }
        }
    }

    /// When [`Self::handle_timeout`] must next run.
    pub fn next_deadline(&self) -> Option<Duration> {
        let req = self.pending.values().map(|p| p.deadline).min();
        let presence = match (
            self.monitor_presence,
            self.cfg.presence_timeout,
            self.last_heard,
            self.lost_since,
        ) {
            (true, Some(t), Some(last), None) => Some(last + t + Duration::from_micros(1)),
            _ => None,
        };
        req.into_iter().chain(presence).min()
    }

    pub fn poll_event(&mut self) -> Option<HostEvent> {
        self.events.pop_front()
    }

    fn finish_request(&mut self, r: RequestId, res: Result<Vec<u8>, RequestError>) {
        // Results nobody takes must not pile up: forget the oldest.
        if self.results.len() >= EVENT_QUEUE_LIMIT {
            if let Some(oldest) = self.results.keys().min().copied() {
                self.results.remove(&oldest);
            }
        }
        self.results.insert(r, res);
    }

    fn push_event(&mut self, e: HostEvent) {
        if self.events.len() >= EVENT_QUEUE_LIMIT {
            self.events.pop_front();
            self.counters.events_dropped += 1;
        }
        self.events.push_back(e);
    }
}

/// Why a board's bring-up failed; the messages are C++'s.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum StartupError {
    #[error("EthResource::verifyBoardPresence() DID NOT have replies from BOARD {board} with IP {ip} after {seconds:.3} seconds: CANNOT PROCEED ANY FURTHER")]
    NoReply {
        board: String,
        ip: Ipv4Addr,
        seconds: f64,
    },
    /// A protocol version differs: `verifyBoardTransceiver()` / `verifyEPprotocol()`.
    #[error("EthResource::verifyEPprotocol() for ep = {endpoint} detected: pc104.version = {local} and board.version = {remote}: mismatching protocol version in BOARD {board} with IP {ip}: cannot proceed any further. ACTION REQUIRED: BOARD {board} with IP {ip} needs a FW update.")]
    ProtocolVersion {
        board: String,
        ip: Ipv4Addr,
        endpoint: &'static str,
        local: Version,
        remote: Version,
    },
    #[error("{what} failed for BOARD {board} with IP {ip}: {reason}")]
    Step {
        board: String,
        ip: Ipv4Addr,
        what: String,
        reason: String,
    },
}

/// What one service needs at start-up (the `embObj*` device's `open()`):
/// `serviceVerifyActivate`, the configuration `setcheck`s, `serviceSetRegulars`,
/// `serviceStart`.
#[derive(Debug, Clone)]
pub struct ServiceSpec {
    pub category: u8,
    /// The `verifyactivate` command (e.g. [`ServiceCommand::verify_activate`]); `None`:
    /// without parameter (`eomn_serv_MC_generic`).
    pub activate: Option<ServiceCommand>,
    /// Variables to set and verify after activation, in order (joint and motor configs,
    /// sensor configs).
    pub configs: Vec<(Id32, Vec<u8>)>,
    /// Variables the board shall signal regularly.
    pub regulars: Vec<Id32>,
}

#[derive(Debug, Clone)]
enum Op {
    Ask {
        id: Id32,
        retry: Retry,
    },
    /// set + wait for sig.
    Command {
        cmd: Id32,
        data: Vec<u8>,
        reply: Id32,
        retry: Retry,
    },
    /// set, wait, ask and compare (`theNVmanager::setcheck`).
    SetCheck {
        id: Id32,
        data: Vec<u8>,
        retry: Retry,
    },
    /// set only (`setRemoteValue`).
    Set {
        id: Id32,
        data: Vec<u8>,
    },
    /// The waits a device's `open()` makes between two steps.
    Pause(Duration),
}

impl Op {
    fn retry(&self) -> Retry {
        match self {
            Op::Ask { retry, .. } | Op::Command { retry, .. } | Op::SetCheck { retry, .. } => {
                *retry
            }
            Op::Set { .. } | Op::Pause(_) => Retry::asks(1, Duration::ZERO),
        }
    }
}

#[derive(Debug, Clone)]
enum Check {
    None,
    ManagementVersion,
    ApplStatus,
    Endpoints(Vec<u8>),
    ServiceOk(String),
}

#[derive(Debug, Clone, Copy)]
enum Phase {
    Idle,
    Waiting(RequestId),
    /// setcheck: set sent, ask at this time.
    SetWait(Duration),
    /// A pause ending at this time.
    Until(Duration),
}

/// The result of [`Startup::poll`].
#[derive(Debug, Clone, PartialEq)]
pub enum StartupStatus {
    Busy,
    Done,
    Failed(StartupError),
}

/// What the bring-up learned of the board.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct BoardFacts {
    pub management_version: Option<Version>,
    pub appl_status: Option<ApplStatus>,
    /// The endpoints whose protocol version was found equal to ours.
    pub verified_endpoints: Vec<u8>,
    /// `EthResource::askBoardVersion(): detected wrong board. expecting X and detected Y`.
    pub warnings: Vec<String>,
}

/// A board's bring-up as `EthResource` does it, and the steps of the `embObj*` devices'
/// `open()`, each with icub-main's retries ([`Retry`]), driven without I/O: the caller
/// polls it after every datagram and at [`Startup::next_deadline`] and
/// [`HostTransceiver::next_deadline`].
///
/// [`Startup::board`] is `EthResource::verifyBoard` and `askBoardVersion`:
///
/// 1. `verifyBoardPresence`: ask `comm status managementprotocolversion`, 1 s × 21 attempts;
/// 2. `verifyBoardTransceiver`: the management version must equal ours;
/// 3. `cleanBoardBehaviour`: service `stop` of `all` (0.5 s × 3);
/// 4. `setTimingOfRunningCycle`: setcheck `appl config` (5 retries, 10 ms, 2 s);
/// 5. `askBoardVersion`: ask `appl status` (0.5 s), warn on a different board type.
///
/// A device then adds its steps to [`Startup::steps`] in its own order: `verifyEPprotocol`
/// ([`Startup::verify_endpoints`]: the endpoint descriptors, [`Retry::ENDPOINTS`]; management's and
/// the endpoint's versions must be ours), `serviceVerifyActivate`, `serviceSetRegulars`,
/// `serviceStart` (0.5 s × 3 each), `setcheckRemoteValue` (10 retries, 10 ms, 50 ms),
/// `setRemoteValue` and its pauses.
#[derive(Debug)]
pub struct Startup {
    steps: VecDeque<(String, Op, Check)>,
    phase: Phase,
    attempt: u32,
    started_at: Option<Duration>,
    facts: BoardFacts,
    appl_config: ApplConfig,
    /// A board's bring-up turns the presence monitor on when done.
    board: bool,
}

fn service_name(cat: u8) -> String {
    const N: [&str; 10] = [
        "mc",
        "strain",
        "mais",
        "skin",
        "inertials3",
        "temperatures",
        "psc",
        "pos",
        "ft",
        "battery",
    ];
    N.get(usize::from(cat))
        .map(|s| format!("eomn_serv_category_{s}"))
        .unwrap_or_else(|| format!("category {cat}"))
}

/// The endpoint that carries a service category.
pub fn service_endpoint(cat: u8) -> u8 {
    match cat {
        category::MC => ep::MOTION_CONTROL,
        category::SKIN => ep::SKIN,
        _ => ep::ANALOG_SENSORS,
    }
}

impl Startup {
    /// The board's bring-up ([`Self::board`]), then `verifyEPprotocol` of the services'
    /// endpoints and, service after service, `verifyactivate`, its configuration's
    /// setchecks, `regsig_load` and `start`.
    pub fn new(appl_config: ApplConfig, services: &[ServiceSpec]) -> Self {
        let mut s = Self::board(appl_config);
        let mut eps: Vec<u8> = services
            .iter()
            .map(|s| service_endpoint(s.category))
            .collect();
        eps.sort_unstable();
        eps.dedup();
        s.verify_endpoints(&eps);
        for sp in services {
            let act = sp.activate.clone().unwrap_or_else(|| {
                ServiceCommand::bare(ServiceOperation::VerifyActivate, sp.category)
            });
            s.verify_activate(&act);
            for (id, data) in &sp.configs {
                s.setcheck(*id, data);
            }
            if !sp.regulars.is_empty() {
                s.set_regulars(sp.category, &sp.regulars);
            }
            s.start(sp.category);
        }
        s
    }

    /// `EthResource::verifyBoard` and `askBoardVersion` (the steps above); when done, the
    /// transceiver watches the board's presence.
    pub fn board(appl_config: ApplConfig) -> Self {
        let mut s = Self::steps();
        s.board = true;
        s.appl_config = appl_config;
        s.push(
            "verifyBoardPresence",
            Op::Ask {
                id: ids::COMM_MANAGEMENT_PROTOCOL_VERSION,
                retry: Retry::BOARD_PRESENCE,
            },
            Check::ManagementVersion,
        );
        s.service_command(
            "cleanBoardBehaviour",
            category::ALL,
            ServiceCommand::bare(ServiceOperation::Stop, category::ALL),
            Retry::SERVICE_COMMAND,
        );
        s.push(
            "setTimingOfRunningCycle",
            Op::SetCheck {
                id: ids::APPL_CONFIG,
                data: appl_config.to_bytes(),
                retry: Retry::APPL_CONFIG,
            },
            Check::None,
        );
        s.push(
            "askBoardVersion",
            Op::Ask {
                id: ids::APPL_STATUS,
                retry: Retry::BOARD_VERSION,
            },
            Check::ApplStatus,
        );
        s
    }

    /// No step yet: a device's steps on a board already up.
    pub fn steps() -> Self {
        Self {
            steps: VecDeque::new(),
            phase: Phase::Idle,
            attempt: 0,
            started_at: None,
            facts: BoardFacts::default(),
            appl_config: ApplConfig::default(),
            board: false,
        }
    }

    fn push(&mut self, name: impl Into<String>, op: Op, check: Check) -> &mut Self {
        self.steps.push_back((name.into(), op, check));
        self
    }

    /// A service command and its `commandresult`, which must say `latestcommandisok`.
    fn service_command(
        &mut self,
        what: &str,
        category: u8,
        mut cmd: ServiceCommand,
        retry: Retry,
    ) -> &mut Self {
        cmd.category = category;
        self.push(
            what,
            Op::Command {
                cmd: ids::SERVICE_COMMAND,
                data: cmd.to_bytes(),
                reply: ids::SERVICE_COMMAND_RESULT,
                retry,
            },
            Check::ServiceOk(what.to_string()),
        )
    }

    /// `verifyEPprotocol` of `endpoints` (none: no step): the endpoint descriptors, as
    /// [`Retry::ENDPOINTS`] (C++'s 0.1 s, asked again on a loaded host); management's
    /// version and each listed endpoint's must be ours (one the board does not list
    /// passes, as in C++: the service's `verifyactivate` then fails).
    pub fn verify_endpoints(&mut self, endpoints: &[u8]) -> &mut Self {
        if endpoints.is_empty() {
            return self;
        }
        let q = QueryArray {
            opc: opc::QUERY_ARRAY_EPDES,
            endpoint: ep::ALL,
            set_number: 0,
            set_size: 0,
        };
        self.push(
            "verifyEPprotocol",
            Op::Command {
                cmd: ids::COMM_QUERY_ARRAY,
                data: q.to_bytes(),
                reply: ids::COMM_REPLY_ARRAY,
                retry: Retry::ENDPOINTS,
            },
            Check::Endpoints(endpoints.to_vec()),
        )
    }

    /// `serviceVerifyActivate(category, param)` with the service's configuration.
    pub fn verify_activate(&mut self, activate: &ServiceCommand) -> &mut Self {
        let mut cmd = activate.clone();
        cmd.operation = ServiceOperation::VerifyActivate as u8;
        let what = format!("serviceVerifyActivate({})", service_name(cmd.category));
        self.service_command(&what, cmd.category, cmd, Retry::SERVICE_COMMAND)
    }

    /// `serviceSetRegulars(category, id32s)`.
    pub fn set_regulars(&mut self, category: u8, regulars: &[Id32]) -> &mut Self {
        let what = format!("serviceSetRegulars({})", service_name(category));
        let cmd = ServiceCommand::regsig_load(category, regulars);
        self.service_command(&what, category, cmd, Retry::SERVICE_COMMAND)
    }

    /// `serviceStart(category)`.
    pub fn start(&mut self, category: u8) -> &mut Self {
        let what = format!("serviceStart({})", service_name(category));
        let cmd = ServiceCommand::bare(ServiceOperation::Start, category);
        self.service_command(&what, category, cmd, Retry::SERVICE_COMMAND)
    }

    /// `setcheckRemoteValue(id, value, 10, 0.010, 0.050)`, as the devices configure
    /// entities ([`Retry::DEVICE_SETCHECK`]).
    pub fn setcheck(&mut self, id: Id32, data: &[u8]) -> &mut Self {
        self.push(
            format!("setcheckRemoteValue({id})"),
            Op::SetCheck {
                id,
                data: data.to_vec(),
                retry: Retry::DEVICE_SETCHECK,
            },
            Check::None,
        )
    }

    /// `setRemoteValue(id, value)`: sent once.
    pub fn set(&mut self, id: Id32, data: &[u8]) -> &mut Self {
        self.push(
            format!("setRemoteValue({id})"),
            Op::Set {
                id,
                data: data.to_vec(),
            },
            Check::None,
        )
    }

    /// A wait of the device's `open()` between two steps.
    pub fn pause(&mut self, d: Duration) -> &mut Self {
        self.push("pause", Op::Pause(d), Check::None)
    }

    pub fn facts(&self) -> &BoardFacts {
        &self.facts
    }

    /// When the sequence next needs polling on its own account (a setcheck's settle time;
    /// its requests' deadlines are the transceiver's, [`HostTransceiver::next_deadline`]).
    pub fn next_deadline(&self) -> Option<Duration> {
        match self.phase {
            Phase::SetWait(at) | Phase::Until(at) => Some(at),
            Phase::Idle | Phase::Waiting(_) => None,
        }
    }

    /// The step under way (for logs).
    pub fn current_step(&self) -> Option<&str> {
        self.steps.front().map(|s| s.0.as_str())
    }

    /// Advances the bring-up: call after every datagram and deadline (and at the start).
    pub fn poll(&mut self, host: &mut HostTransceiver, now: Duration) -> StartupStatus {
        self.started_at.get_or_insert(now);
        loop {
            let Some((name, op, check)) = self.steps.front().cloned() else {
                if self.board {
                    host.monitor_presence(true, now);
                }
                return StartupStatus::Done;
            };
            match self.run(host, &op, now) {
                Err(e) => return StartupStatus::Failed(self.fail(host, &name, e, now)),
                Ok(None) => return StartupStatus::Busy,
                Ok(Some(value)) => {
                    if let Err(e) = self.check(host, &check, &value) {
                        return StartupStatus::Failed(e);
                    }
                    self.steps.pop_front();
                    self.phase = Phase::Idle;
                    self.attempt = 0;
                }
            }
        }
    }

    fn fail(
        &self,
        host: &HostTransceiver,
        what: &str,
        reason: String,
        now: Duration,
    ) -> StartupError {
        let cfg = host.config();
        if what == "verifyBoardPresence" {
            return StartupError::NoReply {
                board: cfg.board_name.clone(),
                ip: cfg.board_ip,
                seconds: now
                    .saturating_sub(self.started_at.unwrap_or(now))
                    .as_secs_f64(),
            };
        }
        StartupError::Step {
            board: cfg.board_name.clone(),
            ip: cfg.board_ip,
            what: what.to_string(),
            reason,
        }
    }

    /// Runs one operation: `Ok(Some(value))` when done, `Ok(None)` while waiting.
    fn run(
        &mut self,
        host: &mut HostTransceiver,
        op: &Op,
        now: Duration,
    ) -> Result<Option<Vec<u8>>, String> {
        let retry = op.retry();
        loop {
            match self.phase {
                Phase::Idle => {
                    if self.attempt >= retry.attempts() {
                        return Err(format!("no valid reply after {} attempts", self.attempt));
                    }
                    self.attempt += 1;
                    match op {
                        Op::Ask { id, .. } => {
                            let r = host
                                .ask(*id, retry.timeout, now)
                                .map_err(|e| e.to_string())?;
                            self.phase = Phase::Waiting(r);
                        }
                        Op::Command {
                            cmd, data, reply, ..
                        } => {
                            let r = host
                                .command(*cmd, data, *reply, retry.timeout, now)
                                .map_err(|e| e.to_string())?;
                            self.phase = Phase::Waiting(r);
                        }
                        Op::SetCheck { id, data, .. } => {
                            host.set(*id, data, now).map_err(|e| e.to_string())?;
                            self.phase = Phase::SetWait(now + retry.settle);
                        }
                        Op::Set { id, data } => {
                            host.set(*id, data, now).map_err(|e| e.to_string())?;
                            return Ok(Some(Vec::new()));
                        }
                        Op::Pause(d) => self.phase = Phase::Until(now + *d),
                    }
                }
                Phase::Until(at) => {
                    return Ok((now >= at).then(Vec::new));
                }
                Phase::SetWait(at) => {
                    if now < at {
                        return Ok(None);
                    }
                    let Op::SetCheck { id, .. } = op else {
                        unreachable!("SetWait only for SetCheck")
                    };
                    let r = host
                        .ask(*id, retry.timeout, now)
                        .map_err(|e| e.to_string())?;
                    self.phase = Phase::Waiting(r);
                }
                Phase::Waiting(r) => match host.take_result(r) {
                    None if host.is_pending(r) => return Ok(None),
                    None | Some(Err(_)) => self.phase = Phase::Idle,
                    Some(Ok(v)) => {
                        if let Op::SetCheck { data, .. } = op {
                            if &v != data {
                                self.phase = Phase::Idle;
                                continue;
                            }
                        }
                        return Ok(Some(v));
                    }
                },
            }
        }
    }

    fn version_error(
        host: &HostTransceiver,
        ep_: u8,
        local: Version,
        remote: Version,
    ) -> StartupError {
        StartupError::ProtocolVersion {
            board: host.config().board_name.clone(),
            ip: host.config().board_ip,
            endpoint: endpoint_name(ep_),
            local,
            remote,
        }
    }

    fn check(
        &mut self,
        host: &mut HostTransceiver,
        check: &Check,
        value: &[u8],
    ) -> Result<(), StartupError> {
        let cfg = host.config().clone();
        let step_err = |what: &str, reason: String| StartupError::Step {
            board: cfg.board_name.clone(),
            ip: cfg.board_ip,
            what: what.to_string(),
            reason,
        };
        match check {
            Check::None => Ok(()),
            Check::ManagementVersion => {
                let v = Version::from_bytes(value)
                    .map_err(|e| step_err("verifyBoardTransceiver", e.to_string()))?;
                self.facts.management_version = Some(v);
                if v != cfg.protocol[0] {
                    return Err(Self::version_error(
                        host,
                        ep::MANAGEMENT,
                        cfg.protocol[0],
                        v,
                    ));
                }
                Ok(())
            }
            Check::ApplStatus => {
                let st = ApplStatus::from_bytes(value)
                    .map_err(|e| step_err("askBoardVersion", e.to_string()))?;
                let detected = EthBoardType::from_u8(st.board_type);
                if detected != cfg.board_type {
                    self.facts.warnings.push(format!(
                        "EthResource::askBoardVersion(): detected wrong board. expecting {} and detected {}",
                        cfg.board_type, detected
                    ));
                }
                self.facts.appl_status = Some(st);
                Ok(())
            }
            Check::Endpoints(eps) => {
                let reply = ReplyArray::from_bytes(value)
                    .map_err(|e| step_err("verifyEPprotocol", e.to_string()))?;
                let descs = reply.descriptors();
                for want in std::iter::once(ep::MANAGEMENT).chain(eps.iter().copied()) {
                    let local = cfg.protocol[usize::from(want).min(3)];
                    match descs.iter().find(|d| d.endpoint == want) {
                        Some(d) if d.version != local => {
                            return Err(Self::version_error(host, want, local, d.version))
                        }
                        // An endpoint the board does not list passes, as in C++: the
                        // service's verifyactivate then fails.
                        Some(_) | None => {}
                    }
                }
                self.facts.verified_endpoints.extend(eps);
                Ok(())
            }
            Check::ServiceOk(what) => {
                let r = ServiceCommandResult::from_bytes(value)
                    .map_err(|e| step_err(what, e.to_string()))?;
                if !r.latest_command_is_ok {
                    return Err(step_err(
                        what,
                        "the board replied latestcommandisok = false".into(),
                    ));
                }
                Ok(())
            }
        }
    }

    /// The `appl config` this bring-up sets.
    pub fn appl_config(&self) -> &ApplConfig {
        &self.appl_config
    }
}
