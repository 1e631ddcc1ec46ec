//! The I/O of the host side (icub-main's `TheEthManager`, `EthResource`, `theNVmanager`):
//! one UDP socket at the `PC104` address for the whole process, one
//! [`icub_eth::host::HostTransceiver`] per board, a reader thread that feeds the boards'
//! datagrams to them, expires requests and reports boards that fall silent (naming IP
//! and board, within the board's `MONITOR_ITS_PRESENCE` timeout), and blocking calls for
//! the devices: every wait is bounded.
//!
//! A board is brought up once, by the first device that uses it ([`Board::bring_up`]:
//! presence, management protocol version, clean, running cycle, board version, as
//! `EthResource::open2`/`verifyEPprotocol`); each device then activates its own service
//! ([`super::service`]).

use parking_lot::{Condvar, Mutex, MutexGuard};
use std::collections::HashMap;
use std::net::{Ipv4Addr, SocketAddrV4, UdpSocket};
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

use icub_eth::host::{
    HostConfig, HostEvent, HostTransceiver, RequestError, Startup, StartupError, StartupStatus,
};
use icub_eth::{Entity, Id32};

use super::params::{AddressMap, EthBoardParams, Pc104};

/// Datagrams kept for a board held by a device thread before the reader waits for it.
const INBOX_LIMIT: usize = 256;
/// The longest the reader sleeps without looking at the boards' timers: a board added or a
/// request made since it last looked is seen within it (the reader otherwise sleeps until
/// the boards' next deadline, see [`Board::on_timers`]).
const LONGEST_SLEEP: Duration = Duration::from_millis(50);
/// How soon the reader looks again at a board a device thread held, or whose datagrams
/// wait in its inbox.
const RETRY_BUSY: Duration = Duration::from_millis(1);
/// While datagrams flow, the reader takes them in batches at most this often: every board
/// streams each millisecond at its own phase, and a wake-up per datagram (17 000 a second
/// on an ergoCub) costs more than the datagrams. icub-main's `EthReceiver` drains the
/// socket every millisecond (its `rxrate`); half of that keeps the values fresher.
const BATCH: Duration = Duration::from_micros(500);

/// A failed exchange with a board, naming it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EthError {
    #[error(transparent)]
    Request(#[from] RequestError),
    #[error(transparent)]
    Startup(#[from] StartupError),
    #[error("BOARD {who}: {reason}")]
    Board { who: String, reason: String },
}

/// The bring-up state of a board.
#[derive(Debug, Clone)]
enum BringUp {
    NotYet,
    Done,
    Failed(EthError),
}

struct Inner {
    host: HostTransceiver,
    /// When the board's last datagram arrived.
    last_rx: Option<Instant>,
    /// Datagrams received, the longest silence between two of them and the silences
    /// longer than three regulars periods, since [`Board::reset_rx_stats`].
    rx_count: u64,
    max_gap: Duration,
    late_gaps: u64,
    /// How long datagrams waited in the host's socket before the reader took them.
    reader_delays: ReaderDelays,
    bring_up: BringUp,
    last_missing_report: Option<Instant>,
    last_lost_report: Option<Instant>,
}

/// The datagrams of one board as the host received them (see [`Board::rx_stats`]).
#[derive(Debug, Clone)]
pub struct RxStats {
    pub datagrams: u64,
    /// The longest silence between two datagrams.
    pub longest_gap: Duration,
    /// Silences longer than three regulars periods (the board streams one ropframe of
    /// regulars per period while running).
    pub late_gaps: u64,
    /// How long the board's datagrams waited in the host's socket for the reader.
    pub reader_delays: ReaderDelays,
    /// The host's counters (sequence gaps, bad frames, timeouts).
    pub counters: icub_eth::host::HostCounters,
}

/// How long datagrams waited in the host's socket between their arrival (the kernel's
/// receive timestamp) and the reader taking them: the host's part of a silence, apart
/// from the board's.
#[derive(Debug, Clone, Copy, Default)]
pub struct ReaderDelays {
    pub longest: Duration,
    /// Delays longer than 1 ms.
    pub over_1ms: u64,
}

impl ReaderDelays {
    fn note(&mut self, d: Duration) {
        self.longest = self.longest.max(d);
        if d > Duration::from_millis(1) {
            self.over_1ms += 1;
        }
    }
}

/// One Ethernet board of the robot.
pub struct Board {
    params: EthBoardParams,
    /// Where the board is reached (the robot's address through the address map).
    addr: SocketAddrV4,
    socket: Arc<UdpSocket>,
    epoch: Instant,
    inner: Mutex<Inner>,
    /// Datagrams the reader received while a device thread held `inner`, processed in
    /// order as soon as it is free: the real-time reader never waits for a device thread
    /// (which, preempted at normal priority while holding the board, would stall every
    /// board's reception). Only the reader thread locks it.
    inbox: Mutex<std::collections::VecDeque<(Instant, Vec<u8>)>>,
    changed: Condvar,
    /// Threads waiting on `changed`: the reader signals only when someone waits (a wake-up
    /// is a system call, and the reader handles a thousand datagrams a second per board).
    waiters: std::sync::atomic::AtomicUsize,
    /// Set when a device thread changed the board's timers (a request, the presence
    /// monitor), so that the reader looks at them before its next sleep.
    timers_changed: Arc<std::sync::atomic::AtomicBool>,
    /// Threads waiting on any board of the manager: the reader does not pause between
    /// batches while someone waits for a reply.
    waiting: Arc<std::sync::atomic::AtomicUsize>,
    /// Serialises the bring-up.
    bring_up_lock: Mutex<()>,
    /// The endpoints whose protocol version the board has confirmed, one bit each
    /// (`EthResource::verifiedEPprotocol[]`: asked once per endpoint and board).
    verified_endpoints: std::sync::atomic::AtomicU32,
}

impl Board {
    pub fn params(&self) -> &EthBoardParams {
        &self.params
    }

    /// `IP (name)`, as C++ names a board.
    pub fn who(&self) -> String {
        self.params.who()
    }

    fn now(&self) -> Duration {
        self.epoch.elapsed()
    }

    /// Whether the board has confirmed the protocol version of `endpoint`.
    pub fn endpoint_verified(&self, endpoint: u8) -> bool {
        use std::sync::atomic::Ordering;
        endpoint < 32 && self.verified_endpoints.load(Ordering::Acquire) & (1 << endpoint) != 0
    }

    /// Notes that the board confirmed the protocol version of `endpoint`.
    pub fn set_endpoint_verified(&self, endpoint: u8) {
        use std::sync::atomic::Ordering;
        if endpoint < 32 {
            self.verified_endpoints
                .fetch_or(1 << endpoint, Ordering::AcqRel);
        }
    }

    fn lock(&self) -> MutexGuard<'_, Inner> {
        self.inner.lock()
    }

    /// Waits on `changed` for at most `d`, counted in [`Board::waiters`].
    fn wait_changed<'a>(
        &self,
        mut inner: MutexGuard<'a, Inner>,
        d: Duration,
    ) -> MutexGuard<'a, Inner> {
        use std::sync::atomic::Ordering;
        // counted while `inner` is held: a notifier that changes the board after this
        // thread looked at it sees the count once it releases the board
        self.waiters.fetch_add(1, Ordering::AcqRel);
        self.waiting.fetch_add(1, Ordering::AcqRel);
        self.changed.wait_for(&mut inner, d);
        self.waiters.fetch_sub(1, Ordering::AcqRel);
        self.waiting.fetch_sub(1, Ordering::AcqRel);
        inner
    }

    /// How long a thread waiting on the board sleeps: until `deadline` (a request's retry
    /// or timeout), at most [`LONGEST_SLEEP`]; the reader's datagrams wake it sooner.
    fn until(&self, deadline: Option<Duration>, now: Duration) -> Duration {
        deadline
            .map_or(LONGEST_SLEEP, |d| d.saturating_sub(now))
            .clamp(Duration::from_micros(50), LONGEST_SLEEP)
    }

    /// Wakes the threads waiting for the board, if any.
    fn notify(&self) {
        if self.waiters.load(std::sync::atomic::Ordering::Acquire) > 0 {
            self.changed.notify_all();
        }
    }

    /// Sends what the transceiver has queued (a device thread's requests also change the
    /// board's timers: the reader is told).
    fn flush(&self, inner: &mut Inner) {
        self.timers_changed
            .store(true, std::sync::atomic::Ordering::Release);
        let now = self.now();
        while let Some(d) = inner.host.poll_transmit(now) {
            if let Err(e) = self.socket.send_to(&d, self.addr) {
                tracing::warn!(board = %self.who(), "cannot send to {}: {e}", self.addr);
            }
        }
    }

    /// Brings the board up once (the first caller does it; later callers get its outcome).
    pub fn bring_up(&self) -> Result<(), EthError> {
        let _serial = self.bring_up_lock.lock();
        match &self.lock().bring_up {
            BringUp::Done => return Ok(()),
            BringUp::Failed(e) => return Err(e.clone()),
            BringUp::NotYet => {}
        }
        let mut startup = Startup::board(self.params.appl);
        let result = self.drive(&mut startup);
        for w in &startup.facts().warnings {
            tracing::warn!(board = %self.who(), "{w}");
        }
        let mut inner = self.lock();
        // the presence monitor is on now
        self.timers_changed
            .store(true, std::sync::atomic::Ordering::Release);
        inner.bring_up = match &result {
            Ok(()) => BringUp::Done,
            Err(e) => BringUp::Failed(e.clone()),
        };
        if result.is_ok() {
            tracing::info!(board = %self.who(), "board is up");
        }
        result
    }

    /// Runs a device's start-up steps on the board, once it is up (C++'s blocking calls
    /// of `open()`); the endpoints the steps verify are not asked again.
    pub fn run(&self, steps: &mut Startup) -> Result<(), EthError> {
        self.bring_up()?;
        self.drive(steps)?;
        for ep in &steps.facts().verified_endpoints {
            self.set_endpoint_verified(*ep);
        }
        Ok(())
    }

    /// Polls `startup` until it ends, sleeping until its or the transceiver's next
    /// deadline or the next datagram.
    fn drive(&self, startup: &mut Startup) -> Result<(), EthError> {
        loop {
            let mut inner = self.lock();
            let now = self.now();
            inner.host.handle_timeout(now);
            let status = startup.poll(&mut inner.host, now);
            self.flush(&mut inner);
            match status {
                StartupStatus::Done => return Ok(()),
                StartupStatus::Failed(e) => return Err(EthError::Startup(e)),
                StartupStatus::Busy => {
                    let due = [inner.host.next_deadline(), startup.next_deadline()];
                    let sleep = self.until(due.into_iter().flatten().min(), now);
                    drop(self.wait_changed(inner, sleep));
                }
            }
        }
    }

    /// Waits (bounded by the request's own timeout) for a request's outcome.
    fn wait(&self, r: icub_eth::host::RequestId) -> Result<Vec<u8>, EthError> {
        let mut inner = self.lock();
        loop {
            if let Some(res) = inner.host.take_result(r) {
                return res.map_err(EthError::from);
            }
            let now = self.now();
            inner.host.handle_timeout(now);
            if let Some(res) = inner.host.take_result(r) {
                return res.map_err(EthError::from);
            }
            if !inner.host.is_pending(r) {
                return Err(EthError::Board {
                    who: self.who(),
                    reason: "request lost".into(),
                });
            }
            let sleep = self.until(inner.host.next_deadline(), now);
            inner = self.wait_changed(inner, sleep);
        }
    }

    fn host_error(&self, e: icub_eth::host::HostError) -> EthError {
        EthError::Board {
            who: self.who(),
            reason: e.to_string(),
        }
    }

    /// `ask<id>` and its `say` (`theNVmanager::ask`).
    pub fn ask(&self, id: Id32, timeout: Duration) -> Result<Vec<u8>, EthError> {
        let r = {
            let mut inner = self.lock();
            let now = self.now();
            let r = inner
                .host
                .ask(id, timeout, now)
                .map_err(|e| self.host_error(e))?;
            self.flush(&mut inner);
            r
        };
        self.wait(r)
    }

    /// A typed `ask`.
    pub fn ask_value<T: Entity>(&self, id: Id32, timeout: Duration) -> Result<T, EthError> {
        let v = self.ask(id, timeout)?;
        T::from_bytes(&v).map_err(|e| EthError::Board {
            who: self.who(),
            reason: e.to_string(),
        })
    }

    /// `set<id>` (`setRemoteValue`): sent at once, not confirmed.
    pub fn set(&self, id: Id32, data: &[u8]) -> Result<(), EthError> {
        let mut inner = self.lock();
        let now = self.now();
        inner
            .host
            .set(id, data, now)
            .map_err(|e| self.host_error(e))?;
        self.flush(&mut inner);
        Ok(())
    }

    pub fn set_value<T: Entity>(&self, id: Id32, v: &T) -> Result<(), EthError> {
        self.set(id, &v.to_bytes())
    }

    /// `set<cmd>` then the board's `sig<reply>` (`theNVmanager::command`).
    pub fn command(
        &self,
        cmd: Id32,
        data: &[u8],
        reply: Id32,
        timeout: Duration,
    ) -> Result<Vec<u8>, EthError> {
        let r = {
            let mut inner = self.lock();
            let now = self.now();
            let r = inner
                .host
                .command(cmd, data, reply, timeout, now)
                .map_err(|e| self.host_error(e))?;
            self.flush(&mut inner);
            r
        };
        self.wait(r)
    }

    /// How long a board may be silent before its values are refused: ten times its
    /// presence timeout, at least 0.5 s (the silence itself is reported after the
    /// presence timeout, as C++ does; a loaded host may see short gaps).
    pub fn stale_after(&self) -> Duration {
        (self
            .params
            .presence_timeout
            .unwrap_or(Duration::from_millis(50))
            * 10)
            .max(Duration::from_millis(500))
    }

    /// The board's variable as last received (`getLocalValue`); an error naming the
    /// board once it has been silent longer than [`Self::stale_after`].
    pub fn read<T: Entity>(&self, id: Id32) -> Result<T, EthError> {
        let inner = self.lock();
        if let Some(silent) = inner.last_rx.map(|t| t.elapsed()) {
            if silent > self.stale_after() {
                return Err(EthError::Board {
                    who: self.who(),
                    reason: format!(
                        "has been silent for {:.3} s (its presence timeout is {:.3} s)",
                        silent.as_secs_f64(),
                        self.params
                            .presence_timeout
                            .unwrap_or_default()
                            .as_secs_f64()
                    ),
                });
            }
        }
        inner.host.read(id).map_err(|e| EthError::Board {
            who: self.who(),
            reason: e.to_string(),
        })
    }

    /// Keeps every value of `id` received from now on, for [`Board::take_kept`].
    pub fn keep_values(&self, id: Id32) {
        self.lock().host.keep_values(id);
    }

    /// The values of `id` received since the last call (see [`Board::keep_values`]),
    /// oldest first; those the reader holds for a busy board are handled first.
    pub fn take_kept(&self, id: Id32) -> Vec<Vec<u8>> {
        let mut inner = self.lock();
        let mut inbox = self.inbox.try_lock();
        if let Some(inbox) = inbox.as_deref_mut() {
            for (t, d) in inbox.drain(..) {
                self.receive(&mut inner, t, &d);
            }
        }
        inner.host.take_kept(id)
    }

    /// Overwrites the local copy of a variable (C++ `setLocalValue`).
    pub fn set_local(&self, id: Id32, data: &[u8]) -> Result<(), EthError> {
        self.lock()
            .host
            .set_local(id, data)
            .map_err(|e| EthError::Board {
                who: self.who(),
                reason: e.to_string(),
            })
    }

    /// What arrived from the board since the last [`Board::reset_rx_stats`].
    pub fn rx_stats(&self) -> RxStats {
        let inner = self.lock();
        RxStats {
            datagrams: inner.rx_count,
            longest_gap: inner.max_gap,
            late_gaps: inner.late_gaps,
            reader_delays: inner.reader_delays,
            counters: inner.host.counters(),
        }
    }

    pub fn reset_rx_stats(&self) {
        let mut inner = self.lock();
        inner.rx_count = 0;
        inner.max_gap = Duration::ZERO;
        inner.late_gaps = 0;
        inner.reader_delays = ReaderDelays::default();
    }

    /// Whether the board is currently reported silent.
    pub fn is_lost(&self) -> bool {
        self.lock().host.board_lost()
    }

    /// The board for the reader thread, with the datagrams kept meanwhile handled: taken
    /// only when free, unless the inbox is full (a device thread holding the board that
    /// long is waited for).
    fn lock_for_reader(
        &self,
        inbox: &mut std::collections::VecDeque<(Instant, Vec<u8>)>,
    ) -> Option<MutexGuard<'_, Inner>> {
        let mut inner = if inbox.len() >= INBOX_LIMIT {
            self.lock()
        } else {
            self.inner.try_lock()?
        };
        for (t, earlier) in inbox.drain(..) {
            self.receive(&mut inner, t, &earlier);
        }
        Some(inner)
    }

    /// Receive work of the reader thread: the datagram that arrived at the host's socket
    /// at `at` is handled now if the board is free, else when it next is (with its
    /// arrival time): then `false`, and the reader comes back within [`RETRY_BUSY`].
    fn on_datagram(&self, d: &[u8], at: Instant) -> bool {
        let mut inbox = self.inbox.lock();
        let Some(mut inner) = self.lock_for_reader(&mut inbox) else {
            inbox.push_back((at, d.to_vec()));
            return false;
        };
        inner.reader_delays.note(at.elapsed());
        self.receive(&mut inner, at, d);
        drop(inner);
        drop(inbox);
        self.notify();
        true
    }

    /// One datagram that arrived at `at`.
    fn receive(&self, inner: &mut Inner, at: Instant, d: &[u8]) {
        let now = self.now();
        if let Some(prev) = inner.last_rx {
            inner.max_gap = inner.max_gap.max(at.saturating_duration_since(prev));
            if at.saturating_duration_since(prev) > 3 * self.params.regulars_period() {
                inner.late_gaps += 1;
            }
            if inner.last_missing_report.take().is_some() {
                tracing::warn!(
                    "eth::EthMonitorPresence: BOARD {} has shown after being lost for {:.3} sec",
                    self.who(),
                    at.saturating_duration_since(prev).as_secs_f64()
                );
            }
        }
        inner.last_rx = Some(at);
        inner.rx_count += 1;
        let _ = inner.host.handle_datagram(d, now);
        self.events(inner);
    }

    /// Timer work of the reader thread: requests expired, presence checked, a long
    /// silence reported. Returns when the board's timers next need the reader (soon, if a
    /// device thread held the board).
    fn on_timers(&self) -> Instant {
        let mut inbox = self.inbox.lock();
        let Some(mut inner) = self.lock_for_reader(&mut inbox) else {
            return Instant::now() + RETRY_BUSY;
        };
        drop(inbox);
        let now = self.now();
        inner.host.handle_timeout(now);
        self.events(&mut inner);
        let mut next = inner.host.next_deadline().map(|d| self.epoch + d);
        // A board silent past the point where its values are refused is an error, once
        // per `periodOfMissingReport` while it lasts.
        let silent = inner.last_rx.map(|t| t.elapsed());
        if silent.is_some_and(|s| s > self.stale_after()) {
            let due = inner
                .last_missing_report
                .is_none_or(|t| t.elapsed() >= self.params.missing_report_period);
            if due {
                // A board that restarts waits in its configuration state for a host's
                // start-up sequence, which (as in C++) only a new open sends.
                tracing::error!(
                    "eth::EthMonitorPresence: BOARD {} has been silent for {:.3} sec: its values are refused until it talks again. Check its power and network cable; a board that was reset (power cycle, restarted emulator) waits to be configured again: restart yarprobotinterface",
                    self.who(),
                    silent.unwrap_or_default().as_secs_f64()
                );
                inner.last_missing_report = Some(Instant::now());
            }
            let report = inner
                .last_missing_report
                .map(|t| t + self.params.missing_report_period);
            next = next.into_iter().chain(report).min();
        } else {
            inner.last_missing_report = None;
            let stale = inner
                .last_rx
                .map(|t| t + self.stale_after() + Duration::from_micros(1));
            next = next.into_iter().chain(stale).min();
        }
        drop(inner);
        self.notify();
        next.unwrap_or_else(|| Instant::now() + LONGEST_SLEEP)
    }

    /// The presence monitor's reports (C++ prints them as debug messages): a board lost
    /// for its timeout is a warning at most once per `periodOfMissingReport`, so that a
    /// loaded host's short gaps do not flood the log; a long silence is an error (above).
    fn events(&self, inner: &mut Inner) {
        while let Some(ev) = inner.host.poll_event() {
            let cfg = inner.host.config();
            match &ev {
                HostEvent::BoardLost { .. } => {
                    let due = inner
                        .last_lost_report
                        .is_none_or(|t| t.elapsed() >= self.params.missing_report_period);
                    if due {
                        tracing::warn!("{}", ev.describe(cfg));
                        inner.last_lost_report = Some(Instant::now());
                    } else {
                        tracing::debug!("{}", ev.describe(cfg));
                    }
                }
                // hostTransceiver's `yError()`: a lost frame, or a board that rebooted
                // (its sequence numbers restart).
                HostEvent::SequenceGap { .. } => tracing::error!("{}", ev.describe(cfg)),
                HostEvent::Signal(_) => {}
                _ => tracing::debug!("{}", ev.describe(cfg)),
            }
        }
    }
}

/// The process's Ethernet manager: the host socket and the boards behind it.
pub struct EthManager {
    local: Pc104,
    map: AddressMap,
    socket: Arc<UdpSocket>,
    boards: Mutex<HashMap<Ipv4Addr, Arc<Board>>>,
    /// Set by a board whose timers a device thread changed (see [`Board::flush`]).
    timers_changed: Arc<std::sync::atomic::AtomicBool>,
    /// Threads waiting for a board (see [`Board::wait_changed`]).
    waiting: Arc<std::sync::atomic::AtomicUsize>,
}

fn manager_slot() -> &'static Mutex<Option<Arc<EthManager>>> {
    static M: OnceLock<Mutex<Option<Arc<EthManager>>>> = OnceLock::new();
    M.get_or_init(|| Mutex::new(None))
}

impl EthManager {
    /// The process's manager, bound to `pc104` on first use (C++ `TheEthManager::instance`
    /// + `initCommunication`); every device must name the same host address.
    pub fn instance(pc104: &Pc104) -> Result<Arc<EthManager>, EthError> {
        let mut slot = manager_slot().lock();
        if let Some(m) = slot.as_ref() {
            if m.local.ip != pc104.ip || m.local.port != pc104.port {
                return Err(EthError::Board {
                    who: format!("{}:{}", pc104.ip, pc104.port),
                    reason: format!(
                        "the host already uses {}:{} (PC104IpAddress differs between devices)",
                        m.local.ip, m.local.port
                    ),
                });
            }
            return Ok(m.clone());
        }
        let map = AddressMap::from_env().map_err(|e| EthError::Board {
            who: super::params::ADDRESS_MAP_ENV.into(),
            reason: e,
        })?;
        let local = SocketAddrV4::new(map.map(pc104.ip), pc104.port);
        let socket = UdpSocket::bind(local).map_err(|e| EthError::Board {
            who: format!("PC104 {}:{}", pc104.ip, pc104.port),
            reason: format!(
                "cannot bind the host's UDP socket at {local}: {e} (give the host this address, or map the robot's addresses with {}=10.0.1.0/24=127.0.1.0/24)",
                super::params::ADDRESS_MAP_ENV
            ),
        })?;
        enlarge_receive_buffer(&socket);
        if let Err(e) = nix::sys::socket::setsockopt(
            &socket,
            nix::sys::socket::sockopt::ReceiveTimestampns,
            &true,
        ) {
            // Arrival is then taken when the reader gets the datagram.
            tracing::debug!("SO_TIMESTAMPNS refused: {e}");
        }
        socket
            .set_read_timeout(Some(LONGEST_SLEEP))
            .map_err(|e| EthError::Board {
                who: local.to_string(),
                reason: e.to_string(),
            })?;
        let m = Arc::new(EthManager {
            local: *pc104,
            map,
            socket: Arc::new(socket),
            boards: Mutex::new(HashMap::new()),
            timers_changed: Arc::default(),
            waiting: Arc::default(),
        });
        let weak = Arc::downgrade(&m);
        std::thread::Builder::new()
            .name("eth-manager".into())
            .spawn(move || reader(weak))
            .map_err(|e| EthError::Board {
                who: local.to_string(),
                reason: e.to_string(),
            })?;
        tracing::info!(
            "eth manager: host at {local} (robot address {}:{})",
            pc104.ip,
            pc104.port
        );
        *slot = Some(m.clone());
        Ok(m)
    }

    /// The board at `params.ip` (created on first request, as `requestResource2`).
    pub fn board(&self, params: &EthBoardParams) -> Arc<Board> {
        let mut boards = self.boards.lock();
        boards
            .entry(params.ip)
            .or_insert_with(|| {
                let mut cfg = HostConfig::new(&params.name, params.ip, params.board_type);
                cfg.max_tx_packet = params.max_rx_packet;
                cfg.presence_timeout = params.presence_timeout;
                Arc::new(Board {
                    params: params.clone(),
                    addr: SocketAddrV4::new(self.map.map(params.ip), params.port),
                    socket: self.socket.clone(),
                    epoch: Instant::now(),
                    inner: Mutex::new(Inner {
                        host: HostTransceiver::new(cfg),
                        bring_up: BringUp::NotYet,
                        last_rx: None,
                        rx_count: 0,
                        max_gap: Duration::ZERO,
                        late_gaps: 0,
                        reader_delays: ReaderDelays::default(),
                        last_missing_report: None,
                        last_lost_report: None,
                    }),
                    inbox: Mutex::default(),
                    changed: Condvar::new(),
                    waiters: Default::default(),
                    timers_changed: self.timers_changed.clone(),
                    waiting: self.waiting.clone(),
                    bring_up_lock: Mutex::new(()),
                    verified_endpoints: std::sync::atomic::AtomicU32::new(0),
                })
            })
            .clone()
    }

    fn board_at(&self, served: Ipv4Addr) -> Option<Arc<Board>> {
        let robot_ip = self.map.unmap(served);
        self.boards.lock().get(&robot_ip).cloned()
    }

    /// The process's manager, if a device has created it.
    pub fn current() -> Option<Arc<EthManager>> {
        manager_slot().lock().clone()
    }

    /// Every board in use.
    pub fn all_boards(&self) -> Vec<Arc<Board>> {
        self.boards.lock().values().cloned().collect()
    }
}

/// Every board streams to this one socket (17 boards at 200 datagrams/s each on an
/// ergoCub): a large receive buffer rides out moments when the reader is not scheduled.
fn enlarge_receive_buffer(socket: &UdpSocket) {
    if let Err(e) =
        nix::sys::socket::setsockopt(socket, nix::sys::socket::sockopt::RcvBuf, &(8 << 20))
    {
        tracing::debug!("SO_RCVBUF not enlarged: {e}");
    }
}

/// The reader thread: datagrams to their board, and the boards' timers when their next
/// deadline comes (no periodic tick: it sleeps in the socket until a datagram or the
/// deadline); it ends with the manager.
fn reader(m: std::sync::Weak<EthManager>) {
    use std::sync::atomic::Ordering;
    // The boards' 1 ms periods: icub-main's EthReceiver runs SCHED_FIFO (best effort).
    yarp_net::realtime::try_fifo_current_thread(
        "eth manager",
        yarp_net::realtime::ETH_RECEIVER_PRIORITY,
    );
    let mut buf = vec![0u8; 65536];
    let mut rx = StampedReceiver::new();
    let mut next_timers = Instant::now();
    let mut socket_timeout = LONGEST_SLEEP;
    loop {
        let Some(mgr) = m.upgrade() else {
            return;
        };
        let now = Instant::now();
        if now >= next_timers || mgr.timers_changed.swap(false, Ordering::AcqRel) {
            next_timers = mgr
                .all_boards()
                .iter()
                .map(|b| b.on_timers())
                .fold(now + LONGEST_SLEEP, Instant::min);
        }
        // The socket's timeout follows the deadline to within a millisecond (setting it
        // is a system call: not on every datagram).
        let sleep = next_timers
            .saturating_duration_since(Instant::now())
            .max(Duration::from_micros(100));
        if sleep + Duration::from_millis(1) < socket_timeout || sleep > socket_timeout {
            match mgr.socket.set_read_timeout(Some(sleep)) {
                Ok(()) => socket_timeout = sleep,
                Err(e) => tracing::debug!("eth manager: cannot set the receive timeout: {e}"),
            }
        }
        match rx.recv(&mgr.socket, &mut buf, Wait::Block) {
            Ok(got) => {
                mgr.deliver(got, &buf, &mut next_timers);
                // what arrived meanwhile, then a pause before the next batch
                for _ in 0..INBOX_LIMIT {
                    match rx.recv(&mgr.socket, &mut buf, Wait::No) {
                        Ok(got) => mgr.deliver(got, &buf, &mut next_timers),
                        Err(_) => break,
                    }
                }
                let replies_awaited = mgr.waiting.load(Ordering::Acquire) > 0;
                drop(mgr);
                if !replies_awaited {
                    std::thread::sleep(BATCH);
                }
            }
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock
                        | std::io::ErrorKind::TimedOut
                        // a signal (SIGSTOP/SIGCONT, a debugger) is no receive error
                        | std::io::ErrorKind::Interrupted
                ) => {}
            Err(e) => {
                tracing::warn!("eth manager: receive error: {e}");
                std::thread::sleep(RETRY_BUSY);
            }
        }
    }
}

impl EthManager {
    /// A received datagram to its board (the reader comes back to a busy board soon).
    fn deliver(
        &self,
        (n, from, at): (usize, SocketAddrV4, Instant),
        buf: &[u8],
        next_timers: &mut Instant,
    ) {
        match self.board_at(*from.ip()) {
            Some(b) => {
                if !b.on_datagram(&buf[..n], at) {
                    *next_timers = (*next_timers).min(Instant::now() + RETRY_BUSY);
                }
            }
            None => tracing::debug!("datagram from unknown board {from} dropped"),
        }
    }
}

/// `recvmsg` with the kernel's receive timestamp (`SO_TIMESTAMPNS`, set on the host
/// socket): a datagram's arrival is when it reached the host's socket, so the gap
/// statistics are the boards' streams, and a late reader shows as its own delay
/// ([`ReaderDelays`]), not as a silence of every board.
struct StampedReceiver {
    cmsg: Vec<u8>,
}

/// Whether a receive waits for a datagram (up to the socket's timeout).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Wait {
    Block,
    No,
}

impl StampedReceiver {
    fn new() -> Self {
        Self {
            cmsg: nix::cmsg_space!(nix::sys::time::TimeSpec),
        }
    }

    /// The datagram's size, sender and arrival time (now, when the kernel gave no
    /// timestamp or one that the wall clock's steps make implausible).
    fn recv(
        &mut self,
        socket: &UdpSocket,
        buf: &mut [u8],
        wait: Wait,
    ) -> std::io::Result<(usize, SocketAddrV4, Instant)> {
        use nix::sys::socket::{recvmsg, ControlMessageOwned, MsgFlags, SockaddrIn};
        use std::os::fd::AsRawFd;
        let mut iov = [std::io::IoSliceMut::new(buf)];
        let msg = recvmsg::<SockaddrIn>(
            socket.as_raw_fd(),
            &mut iov,
            Some(&mut self.cmsg),
            match wait {
                Wait::Block => MsgFlags::empty(),
                Wait::No => MsgFlags::MSG_DONTWAIT,
            },
        )
        .map_err(std::io::Error::from)?;
        let (now, wall) = (Instant::now(), std::time::SystemTime::now());
        let mut at = now;
        if let Ok(cmsgs) = msg.cmsgs() {
            for c in cmsgs {
                if let ControlMessageOwned::ScmTimestampns(ts) = c {
                    let stamp = std::time::UNIX_EPOCH
                        + Duration::new(ts.tv_sec().max(0) as u64, ts.tv_nsec() as u32);
                    if let Ok(waited) = wall.duration_since(stamp) {
                        if waited < Duration::from_secs(1) {
                            at = now.checked_sub(waited).unwrap_or(now);
                        }
                    }
                }
            }
        }
        let from = msg
            .address
            .map(|a| SocketAddrV4::new(a.ip(), a.port()))
            .ok_or_else(|| std::io::Error::other("a datagram without its sender"))?;
        Ok((msg.bytes, from, at))
    }
}
