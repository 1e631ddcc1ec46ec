//! The CAN bus abstraction (the role of YARP's `ICanBus` / `ICanBufferFactory`) and its backends.
//!
//! A [`CanBus`] is one endpoint on a bus: it sends frames and receives the frames other
//! endpoints send (a node never receives its own frames, as with SocketCAN's default).
//! Every endpoint is `Send + Sync`, so one thread can block in [`CanBus::recv`] while
//! others send. Every wait is bounded by a timeout; a dead bus reports an error, never a hang.
//!
//! Backends:
//! - [`inproc`]: an in-process bus, many endpoints with broadcast semantics;
//! - [`udp`]: frames over UDP in the cannelloni wire format ([`cannelloni`]), point to
//!   point or through a hub that relays between many peers;
//! - [`socketcan`](mod@socketcan): Linux SocketCAN (real hardware, `vcan`);
//! - [`config`]: picks one from iCub-style configuration keys.

pub mod cannelloni;
pub mod config;
pub mod inproc;
#[cfg(target_os = "linux")]
pub mod socketcan;
pub mod udp;

use parking_lot::{Condvar, Mutex, MutexGuard};
use std::collections::VecDeque;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use crate::frame::{CanFrame, CAN_SFF_MASK};

/// Errors of bus operations.
#[derive(Debug, thiserror::Error)]
pub enum BusError {
    #[error("no CAN frame within {0:?}")]
    Timeout(Duration),
    #[error("CAN bus {0} is in bus-off state")]
    BusOff(String),
    #[error("CAN bus {0} is closed")]
    Closed(String),
    #[error("I/O error on CAN bus {bus}: {source}")]
    Io {
        bus: String,
        #[source]
        source: std::io::Error,
    },
    #[error("bad CAN bus configuration: {0}")]
    Config(String),
}

/// Counters every backend keeps (the role of YARP's `ICanBusErrors`).
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct BusStats {
    /// Frames handed to the bus.
    pub tx_frames: u64,
    /// Frames accepted by the filter and queued for reading.
    pub rx_frames: u64,
    /// Frames dropped because the receive queue was full (oldest first).
    pub rx_overruns: u64,
    /// Datagrams or frames that could not be decoded and were dropped.
    pub malformed: u64,
}

/// One endpoint on a CAN bus.
pub trait CanBus: Send + Sync {
    /// Human-readable bus name, used in errors (`inproc://left_arm`, `udp://127.0.0.1:20001`).
    fn name(&self) -> &str;
    /// Puts one frame on the bus.
    fn send(&self, frame: &CanFrame) -> Result<(), BusError>;
    /// Puts several frames on the bus (backends may batch them in one datagram).
    fn send_all(&self, frames: &[CanFrame]) -> Result<(), BusError> {
        frames.iter().try_for_each(|f| self.send(f))
    }
    /// Waits at most `timeout` for the next accepted frame.
    fn recv(&self, timeout: Duration) -> Result<CanFrame, BusError>;
    /// Returns a queued frame, if any, without waiting.
    fn try_recv(&self) -> Result<Option<CanFrame>, BusError>;
    /// Replaces the acceptance filter.
    fn set_filter(&self, filter: IdFilter);
    /// Counters since the endpoint was opened.
    fn stats(&self) -> BusStats;
}

/// Which frames an endpoint accepts (YARP's `canIdAdd` / `canIdDelete`).
///
/// The default accepts everything; once specific ids are added, only those standard
/// ids pass (extended frames pass only if `extended` is set).
#[derive(Clone, PartialEq, Eq)]
pub struct IdFilter {
    all: bool,
    ids: Box<[u64; 32]>,
    /// Whether 29-bit frames pass a restricted filter.
    pub extended: bool,
}

impl Default for IdFilter {
    fn default() -> Self {
        Self::all()
    }
}

impl std::fmt::Debug for IdFilter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.all {
            return write!(f, "IdFilter(all)");
        }
        let ids: Vec<u16> = (0..2048u16).filter(|&i| self.contains(i)).collect();
        write!(f, "IdFilter({ids:x?})")
    }
}

impl IdFilter {
    /// Accepts every frame.
    pub fn all() -> Self {
        Self {
            all: true,
            ids: Box::new([0; 32]),
            extended: true,
        }
    }
    /// Accepts nothing until ids are added.
    pub fn none() -> Self {
        Self {
            all: false,
            ids: Box::new([0; 32]),
            extended: false,
        }
    }
    /// Accepts exactly the given standard ids.
    pub fn ids(ids: impl IntoIterator<Item = u16>) -> Self {
        let mut f = Self::none();
        for id in ids {
            f.add(id);
        }
        f
    }
    /// Adds one standard id (switching an accept-all filter to a list).
    pub fn add(&mut self, id: u16) {
        if self.all {
            self.all = false;
            self.extended = false;
        }
        let id = usize::from(id) & CAN_SFF_MASK as usize;
        self.ids[id / 64] |= 1 << (id % 64);
    }
    /// Removes one standard id.
    pub fn remove(&mut self, id: u16) {
        let id = usize::from(id) & CAN_SFF_MASK as usize;
        self.ids[id / 64] &= !(1 << (id % 64));
    }
    /// Whether a standard id passes.
    pub fn contains(&self, id: u16) -> bool {
        let id = usize::from(id) & CAN_SFF_MASK as usize;
        self.all || self.ids[id / 64] & (1 << (id % 64)) != 0
    }
    /// Whether a frame passes.
    pub fn accepts(&self, frame: &CanFrame) -> bool {
        match frame.std_id() {
            _ if self.all => true,
            Some(id) => self.contains(id),
            None => self.extended,
        }
    }
}

/// Default depth of a receive queue (YARP's iCub drivers use 2047-frame buffers).
pub const DEFAULT_RX_QUEUE: usize = 2047;

/// The receive side shared by every backend: a filtered, bounded FIFO with a condition variable.
pub(crate) struct RxQueue {
    state: Mutex<RxState>,
    ready: Condvar,
    capacity: usize,
    pub(crate) tx_frames: AtomicU64,
    pub(crate) malformed: AtomicU64,
}

struct RxState {
    frames: VecDeque<CanFrame>,
    filter: IdFilter,
    closed: Option<String>,
    rx_frames: u64,
    rx_overruns: u64,
}

impl RxQueue {
    pub(crate) fn new(capacity: usize) -> Self {
        Self {
            state: Mutex::new(RxState {
                frames: VecDeque::new(),
                filter: IdFilter::all(),
                closed: None,
                rx_frames: 0,
                rx_overruns: 0,
            }),
            ready: Condvar::new(),
            capacity: capacity.max(1),
            tx_frames: AtomicU64::new(0),
            malformed: AtomicU64::new(0),
        }
    }

    fn lock(&self) -> MutexGuard<'_, RxState> {
        // A panic elsewhere must not wedge the bus: the state stays consistent per operation.
        self.state.lock()
    }

    /// Queues a frame if the filter accepts it; drops the oldest frame when full.
    pub(crate) fn push(&self, frame: CanFrame) {
        self.push_all(std::iter::once(frame));
    }

    /// Queues the frames the filter accepts, under one lock and with one wake-up of the
    /// reader (a datagram carries many frames).
    pub(crate) fn push_all(&self, frames: impl IntoIterator<Item = CanFrame>) {
        let mut st = self.lock();
        let mut queued = false;
        for frame in frames {
            if !st.filter.accepts(&frame) {
                continue;
            }
            if st.frames.len() >= self.capacity {
                st.frames.pop_front();
                st.rx_overruns += 1;
            }
            st.frames.push_back(frame);
            st.rx_frames += 1;
            queued = true;
        }
        drop(st);
        if queued {
            self.ready.notify_one();
        }
    }

    /// Marks the queue closed: readers get `BusError::Closed` once it is drained.
    pub(crate) fn close(&self, reason: String) {
        self.lock().closed = Some(reason);
        self.ready.notify_all();
    }

    pub(crate) fn recv(&self, bus: &str, timeout: Duration) -> Result<CanFrame, BusError> {
        let deadline = Instant::now() + timeout;
        let mut st = self.lock();
        loop {
            if let Some(f) = st.frames.pop_front() {
                return Ok(f);
            }
            if st.closed.is_some() {
                return Err(BusError::Closed(bus.to_string()));
            }
            let now = Instant::now();
            if now >= deadline {
                return Err(BusError::Timeout(timeout));
            }
            self.ready.wait_for(&mut st, deadline - now);
        }
    }

    pub(crate) fn try_recv(&self, bus: &str) -> Result<Option<CanFrame>, BusError> {
        let mut st = self.lock();
        match st.frames.pop_front() {
            Some(f) => Ok(Some(f)),
            None if st.closed.is_some() => Err(BusError::Closed(bus.to_string())),
            None => Ok(None),
        }
    }

    pub(crate) fn set_filter(&self, filter: IdFilter) {
        let mut st = self.lock();
        st.frames.retain(|f| filter.accepts(f));
        st.filter = filter;
    }

    pub(crate) fn stats(&self) -> BusStats {
        let st = self.lock();
        BusStats {
            tx_frames: self.tx_frames.load(Ordering::Relaxed),
            rx_frames: st.rx_frames,
            rx_overruns: st.rx_overruns,
            malformed: self.malformed.load(Ordering::Relaxed),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn filter_semantics() {
        let mut f = IdFilter::all();
        assert!(f.contains(0x123));
        f.add(0x101);
        assert!(f.contains(0x101) && !f.contains(0x123));
        f.remove(0x101);
        assert!(!f.contains(0x101));
        let ext = CanFrame::new_extended(0x1_0000, &[]).unwrap();
        assert!(!f.accepts(&ext));
        f.extended = true;
        assert!(f.accepts(&ext));
        assert_eq!(
            format!("{:?}", IdFilter::ids([0x10, 0x20])),
            "IdFilter([10, 20])"
        );
    }

    #[test]
    fn queue_drops_oldest_and_times_out() {
        let q = RxQueue::new(2);
        for i in 0..3u8 {
            q.push(CanFrame::new(1, &[i]).unwrap());
        }
        assert_eq!(q.stats().rx_overruns, 1);
        assert_eq!(q.recv("t", Duration::ZERO).unwrap().data(), &[1]);
        assert_eq!(q.recv("t", Duration::ZERO).unwrap().data(), &[2]);
        let t0 = Instant::now();
        assert!(matches!(
            q.recv("t", Duration::from_millis(20)),
            Err(BusError::Timeout(_))
        ));
        assert!(t0.elapsed() >= Duration::from_millis(20));
        q.close("gone".into());
        assert!(matches!(
            q.recv("t", Duration::from_secs(5)),
            Err(BusError::Closed(_))
        ));
    }
}
