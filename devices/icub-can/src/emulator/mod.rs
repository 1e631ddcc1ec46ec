//! Emulated iCub boards on a CAN bus.
//!
//! A [`Board`] is a pure state machine: it reacts to decoded messages and, on every
//! [`Board::tick`], advances its simulation and emits broadcasts. [`BusEmulator`] runs a
//! set of boards on one bus in a thread with a fixed tick (1 ms by default): frames are
//! decoded as they arrive (malformed ones are counted and ignored) and replies are sent
//! at once; broadcasts produced during a tick are sent as one batch.
//!
//! The simulation is stepped lazily: the thread sleeps until a board has something to
//! say ([`Board::next_output`]) or a frame arrives, then runs every tick due by then, in
//! order, as if it had woken for each. Results are those of a thread waking every tick,
//! without a thousand wake-ups per second. [`BusEmulator::with_batch`] additionally
//! gathers broadcasts into one datagram per batch period, as cannelloni gathers frames.
//! [`network`] lays out the boards of one network; crate `icub-emulators` reads a robot's
//! configuration files into networks.

pub mod mc;
pub mod mtx;
pub mod network;
pub mod sensors;

use std::sync::atomic::{AtomicBool, AtomicU16, AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crate::bus::{BusError, CanBus};
use crate::frame::CanFrame;
use crate::proto::Message;

pub use mc::{JointPlant, JointTorqueSensor, McBoard, McBoardConfig, TorqueHub, TorqueLink};
pub use sensors::{MaisBoard, MtbBoard, StrainBoard};

/// One emulated board.
pub trait Board: Send {
    /// CAN address (1..=14).
    fn address(&self) -> u8;
    /// Short kind name (`mc`, `strain`, `mais`, `skin`, `mtb`, `jts` for a virtual
    /// joint-torque sensor).
    fn kind(&self) -> &'static str;
    /// Reacts to a message seen on the bus; replies go to `out`.
    fn on_message(&mut self, msg: &Message, out: &mut Vec<CanFrame>);
    /// Advances the simulation by `dt`; broadcasts go to `out`.
    fn tick(&mut self, dt: Duration, out: &mut Vec<CanFrame>);
    /// Starts streaming as if a host had configured the board (sensors wait for a
    /// host command otherwise); used for benchmarks and host-less demos.
    fn start_streaming(&mut self) {}
    /// How long until a [`Board::tick`] may emit something, if no message reaches the
    /// board meanwhile: the tick that brings the board's clock this far along is the
    /// first that can. `None`: never on its own. The default, zero, means every tick.
    fn next_output(&self) -> Option<Duration> {
        Some(Duration::ZERO)
    }
}

/// Time until a periodic output of `period` is due, `since` into the period; `None`
/// when the output is off.
pub(crate) fn due_in(on: bool, period: Duration, since: Duration) -> Option<Duration> {
    on.then(|| period.saturating_sub(since))
}

/// Errors building boards from a textual description.
#[derive(Debug, thiserror::Error)]
pub enum SpecError {
    #[error("board spec {0:?}: expected ADDRESS:KIND (KIND = mc, strain, mais, skin, mtb)")]
    Syntax(String),
    #[error("board spec {0:?}: address must be 1..=14")]
    Address(String),
    #[error("{path}:{line}: {msg}")]
    File {
        path: String,
        line: usize,
        msg: String,
    },
    #[error(transparent)]
    Bus(#[from] BusError),
}

/// Builds a board from `ADDRESS:KIND` (address decimal or 0x-hex).
pub fn board_from_spec(spec: &str) -> Result<Box<dyn Board>, SpecError> {
    let (addr, kind) = spec
        .split_once(':')
        .ok_or_else(|| SpecError::Syntax(spec.into()))?;
    let addr = addr.trim();
    let address = match addr.strip_prefix("0x").or_else(|| addr.strip_prefix("0X")) {
        Some(hex) => u8::from_str_radix(hex, 16),
        None => addr.parse(),
    }
    .map_err(|_| SpecError::Address(spec.into()))?;
    if !(1..=14).contains(&address) {
        return Err(SpecError::Address(spec.into()));
    }
    Ok(match kind.trim() {
        "mc" => Box::new(McBoard::new(McBoardConfig::new(address))),
        "strain" => Box::new(StrainBoard::new(address)),
        "mais" => Box::new(MaisBoard::new(address)),
        "skin" => Box::new(MtbBoard::new(address, true)),
        "mtb" => Box::new(MtbBoard::new(address, false)),
        _ => return Err(SpecError::Syntax(spec.into())),
    })
}

/// Counters of a running bus emulator.
#[derive(Debug, Default)]
pub struct EmulatorStats {
    pub frames_in: AtomicU64,
    pub frames_out: AtomicU64,
    pub malformed: AtomicU64,
    pub ticks: AtomicU64,
    pub send_errors: AtomicU64,
}

/// Boards on one bus, ready to run.
pub struct BusEmulator {
    bus: Arc<dyn CanBus>,
    boards: Vec<Box<dyn Board>>,
    tick: Duration,
    batch: Duration,
}

/// The emulator thread's simulation clock: the next tick to run, by number (from 1)
/// and by the time it is due.
struct Clock {
    n: u64,
    next: Instant,
}

/// The longest the thread sleeps without a board output due (bounds the ticks run
/// in one go when every board is quiet).
const MAX_SLEEP: Duration = Duration::from_millis(100);
/// Further behind than this (a suspended process), the backlog of ticks is dropped
/// instead of being run.
const STALL: Duration = Duration::from_millis(500);

impl BusEmulator {
    pub fn new(bus: Arc<dyn CanBus>, boards: Vec<Box<dyn Board>>) -> Self {
        Self {
            bus,
            boards,
            tick: Duration::from_millis(1),
            batch: Duration::ZERO,
        }
    }

    /// Sends broadcasts once every `batch` (rounded to whole ticks, counted from the
    /// start) instead of after each tick that produced some: several frames then share
    /// one datagram, as with cannelloni's send timeout. Frames keep their order and
    /// their rate; replies to requests still go out at once (taking pending
    /// broadcasts along). Default: every tick.
    pub fn with_batch(mut self, batch: Duration) -> Self {
        self.batch = batch;
        self
    }

    /// The batch period in ticks (at least one).
    fn batch_ticks(&self) -> u64 {
        (self.batch.as_nanos() / self.tick.as_nanos()).max(1) as u64
    }

    /// Starts every sensor board streaming without waiting for a host.
    pub fn start_streaming(mut self) -> Self {
        self.boards.iter_mut().for_each(|b| b.start_streaming());
        self
    }

    /// Changes the simulation step (default 1 ms).
    pub fn with_tick(mut self, tick: Duration) -> Self {
        self.tick = tick.max(Duration::from_micros(100));
        self
    }

    /// Starts the emulator thread.
    pub fn spawn(self) -> std::io::Result<EmulatorHandle> {
        let stop = Arc::new(AtomicBool::new(false));
        let stats = Arc::new(EmulatorStats::default());
        // Bit n set: board n neither replies nor broadcasts (to test board timeouts).
        let controls = Arc::new(AtomicU16::new(0));
        let (s, st, c) = (stop.clone(), stats.clone(), controls.clone());
        let name = self.bus.name().to_string();
        let thread = std::thread::Builder::new()
            .name(format!("emu {name}"))
            .spawn(move || self.run(&s, &st, &c))?;
        Ok(EmulatorHandle {
            name,
            stop,
            stats,
            controls,
            thread: Some(thread),
        })
    }

    fn run(mut self, stop: &AtomicBool, stats: &EmulatorStats, silent: &AtomicU16) {
        // Broadcasts produced by ticks and not sent yet.
        let mut pending = Vec::with_capacity(256);
        let mut replies = Vec::with_capacity(16);
        let mut clock = Clock {
            n: 1,
            next: Instant::now() + self.tick,
        };
        while !stop.load(Ordering::Relaxed) {
            self.catch_up(&mut clock, &mut pending, stats, silent);
            let wake = clock.next + self.tick * self.ticks_to_wake(clock.n, !pending.is_empty());
            match self
                .bus
                .recv(wake.saturating_duration_since(Instant::now()))
            {
                Ok(frame) => {
                    stats.frames_in.fetch_add(1, Ordering::Relaxed);
                    let msg = match Message::decode(&frame) {
                        Ok(m) => m,
                        Err(e) => {
                            stats.malformed.fetch_add(1, Ordering::Relaxed);
                            tracing::debug!(bus = self.bus.name(), %frame, "ignoring malformed frame: {e}");
                            continue;
                        }
                    };
                    // The boards first live up to now, then see the message.
                    self.catch_up(&mut clock, &mut pending, stats, silent);
                    let mute = silent.load(Ordering::Relaxed);
                    replies.clear();
                    for b in self
                        .boards
                        .iter_mut()
                        .filter(|b| mute & (1 << (b.address() & 0xF)) == 0)
                    {
                        b.on_message(&msg, &mut replies);
                    }
                    if !replies.is_empty() {
                        pending.append(&mut replies);
                        self.flush(&pending, stats);
                        pending.clear();
                    }
                }
                Err(BusError::Timeout(_)) => {}
                Err(BusError::Closed(_)) => return,
                Err(e) => {
                    tracing::warn!(bus = self.bus.name(), "emulator receive error: {e}");
                    std::thread::sleep(self.tick);
                }
            }
        }
    }

    /// Runs every tick due by now, sending broadcasts at the end of each batch.
    fn catch_up(
        &mut self,
        clock: &mut Clock,
        pending: &mut Vec<CanFrame>,
        stats: &EmulatorStats,
        silent: &AtomicU16,
    ) {
        let now = Instant::now();
        if now > clock.next + STALL {
            // After a stall (e.g. a suspended process) resynchronise instead of bursting.
            clock.next = now;
        }
        while clock.next <= now {
            self.tick_all(pending, silent.load(Ordering::Relaxed));
            stats.ticks.fetch_add(1, Ordering::Relaxed);
            if clock.n.is_multiple_of(self.batch_ticks()) {
                self.flush(pending, stats);
                pending.clear();
            }
            clock.n += 1;
            clock.next += self.tick;
        }
    }

    /// One tick of every board; a silent board keeps simulating, its output is dropped.
    fn tick_all(&mut self, out: &mut Vec<CanFrame>, mute: u16) {
        for b in self.boards.iter_mut() {
            let start = out.len();
            b.tick(self.tick, out);
            if mute & (1 << (b.address() & 0xF)) != 0 {
                out.truncate(start);
            }
        }
    }

    /// How many ticks after tick `n` (the next to run) the thread must be awake to send
    /// what is due: the first tick that may produce output, or, when batching, the end
    /// of the batch it falls in (or of the current one if output is pending).
    fn ticks_to_wake(&self, n: u64, pending: bool) -> u32 {
        let max = (MAX_SLEEP.as_nanos() / self.tick.as_nanos()).max(1) as u64;
        let first = self
            .boards
            .iter()
            .filter_map(|b| b.next_output())
            .map(|d| {
                // the k-th tick from now (k >= 1) is the first whose clock reaches `d`
                let k = d.as_nanos().div_ceil(self.tick.as_nanos()) as u64;
                k.max(1) - 1
            })
            .min()
            .unwrap_or(max)
            .min(max);
        let b = self.batch_ticks();
        let end_of_batch = |t: u64| (n + t).div_ceil(b) * b - n;
        let mut wake = end_of_batch(first);
        if pending {
            wake = wake.min(end_of_batch(0));
        }
        wake.min(max) as u32
    }

    fn flush(&self, out: &[CanFrame], stats: &EmulatorStats) {
        if out.is_empty() {
            return;
        }
        match self.bus.send_all(out) {
            Ok(()) => {
                stats
                    .frames_out
                    .fetch_add(out.len() as u64, Ordering::Relaxed);
            }
            Err(e) => {
                stats.send_errors.fetch_add(1, Ordering::Relaxed);
                tracing::debug!(bus = self.bus.name(), "emulator send failed: {e}");
            }
        }
    }
}

/// A running bus emulator; stops (and joins its thread) when dropped.
pub struct EmulatorHandle {
    name: String,
    stop: Arc<AtomicBool>,
    stats: Arc<EmulatorStats>,
    controls: Arc<AtomicU16>,
    thread: Option<JoinHandle<()>>,
}

impl EmulatorHandle {
    /// The bus name.
    pub fn name(&self) -> &str {
        &self.name
    }
    /// Live counters.
    pub fn stats(&self) -> &EmulatorStats {
        &self.stats
    }
    /// Makes a board go silent (no replies, no broadcasts) or speak again.
    pub fn set_silent(&self, address: u8, silent: bool) {
        let bit = 1u16 << (address & 0xF);
        if silent {
            self.controls.fetch_or(bit, Ordering::Relaxed);
        } else {
            self.controls.fetch_and(!bit, Ordering::Relaxed);
        }
    }
    /// Stops the thread and waits for it.
    pub fn stop(mut self) {
        self.shutdown();
    }
    fn shutdown(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for EmulatorHandle {
    fn drop(&mut self) {
        self.shutdown();
    }
}

#[cfg(test)]
mod tests;
