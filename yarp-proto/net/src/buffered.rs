//! `BufferedPort` and `RpcServer`: ports with the buffering policies of C++
//! `yarp::os::BufferedPort` (`PortReaderBuffer` + `PortWriterBuffer`), so that a slow
//! reader or writer never stalls the network.
//!
//! Reading: a background task drains the port into a buffer. By default only the newest
//! unread message is kept (older ones are dropped and counted), as C++ does for streaming
//! data; `set_strict(true)` keeps every message in a bounded FIFO whose fullness pushes
//! back on the senders.
//!
//! Writing: `write` never waits; a message that has not left yet is replaced by the next
//! one, and a connection whose queue is full (its reader stopped reading) misses it while
//! the others get it (C++ "drop if busy"); `write_strict` waits its turn. Envelopes (`Stamp`) can be
//! attached automatically, as C++ `setEnvelope` + `Stamp::update`.
//!
//! ```no_run
//! # async fn demo(ns: yarp_net::nameserver::NameClient) -> Result<(), yarp_net::port::PortError> {
//! use yarp_net::buffered::BufferedPort;
//! let out = BufferedPort::open("/camera/out", ns.clone()).await?;
//! let inp = BufferedPort::open("/viewer/in", ns).await?;
//! out.set_auto_envelope(true);
//! out.connect("/viewer/in", None).await?;
//! out.write(&yarp_proto::bottle!["frame", 1]);
//! let msg = inp.read().await.expect("port open");
//! println!("{} (count {:?})", msg.bottle, msg.stamp.map(|s| s.count));
//! # Ok(()) }
//! ```

use crate::nameserver::NameClient;
use crate::port::{Incoming, Port, PortError, Replier};
use parking_lot::{Mutex, MutexGuard};
use std::collections::VecDeque;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use tokio::runtime::Handle;
use tokio::sync::Notify;
use tokio::task::JoinHandle;
use yarp_proto::{Bottle, Contact, DecodeError, Stamp};

/// Strict-mode buffer size before the reader stops draining the port (back-pressure).
pub const DEFAULT_STRICT_CAPACITY: usize = 256;

/// A decoded message from a `BufferedPort` or `RpcServer`.
#[derive(Debug)]
pub struct Message {
    pub bottle: Bottle,
    /// The envelope, when the sender attached one.
    pub stamp: Option<Stamp>,
    /// The sending port's name.
    pub from: String,
    replier: Option<Replier>,
}

impl Message {
    fn from_incoming(mut inc: Incoming) -> Result<Message, DecodeError> {
        let bottle = inc.take_bottle()?;
        Ok(Message {
            bottle,
            stamp: inc.stamp,
            from: std::mem::take(&mut inc.from),
            replier: inc.take_replier(),
        })
    }

    /// Whether the sender waits for a reply (it was sent with `rpc`).
    pub fn wants_reply(&self) -> bool {
        self.replier.is_some()
    }

    /// Answers the sender (no effect when no reply is expected). Dropping the message
    /// unanswered gives the sender an empty reply, as C++ does.
    pub fn reply(&mut self, b: Bottle) {
        if let Some(r) = self.replier.take() {
            r.send(b);
        }
    }

    /// Takes the reply handle, to answer later from elsewhere.
    pub fn take_replier(&mut self) -> Option<Replier> {
        self.replier.take()
    }
}

/// Locks a mutex whose plain data a panicking holder cannot leave inconsistent.
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock()
}

use yarp_proto::stamp::now;

/// The next envelope after `prev`, as C++ `Stamp::update`: counts from 0, wraps to 0
/// after `i32::MAX`.
pub fn next_stamp(prev: Option<Stamp>, time: f64) -> Stamp {
    let count = match prev {
        Some(s) if s.count >= 0 && s.count < i32::MAX => s.count + 1,
        _ => 0,
    };
    Stamp::new(count, time)
}

// ---------------------------------------------------------------------------------------
// Reading side

struct ReadState {
    queue: VecDeque<Message>,
    strict: bool,
    capacity: usize,
    dropped: u64,
    received: u64,
    undecodable: u64,
    last_stamp: Option<Stamp>,
    closed: bool,
    /// The active callback's generation; 0 when messages go to `read`.
    callback: u64,
    generations: u64,
}

/// The buffer between the draining task and the readers.
struct ReadSide {
    state: Mutex<ReadState>,
    arrived: Notify,
    space: Notify,
}

impl ReadSide {
    fn new() -> ReadSide {
        ReadSide {
            state: Mutex::new(ReadState {
                queue: VecDeque::new(),
                strict: false,
                capacity: DEFAULT_STRICT_CAPACITY,
                dropped: 0,
                received: 0,
                undecodable: 0,
                last_stamp: None,
                closed: false,
                callback: 0,
                generations: 0,
            }),
            arrived: Notify::new(),
            space: Notify::new(),
        }
    }

    fn state(&self) -> MutexGuard<'_, ReadState> {
        lock(&self.state)
    }

    fn push(&self, m: Message) {
        {
            let mut st = self.state();
            st.received += 1;
            if !st.strict {
                // latest-only: whatever nobody read yet is superseded
                st.dropped += st.queue.len() as u64;
                st.queue.clear();
            }
            st.queue.push_back(m);
        }
        self.arrived.notify_waiters();
    }

    fn try_pop(&self) -> Option<Message> {
        self.try_pop_as(None).ok().flatten()
    }

    /// Pops for a reader (`None`) or for callback generation `gen`; Err when that
    /// callback has been replaced, checked under the same lock so that none pops after
    /// `disable_callback` returns.
    fn try_pop_as(&self, gen: Option<u64>) -> Result<Option<Message>, ()> {
        let m = {
            let mut st = self.state();
            if gen.is_some_and(|g| g != st.callback) {
                return Err(());
            }
            let Some(m) = st.queue.pop_front() else {
                return Ok(None);
            };
            st.last_stamp = m.stamp;
            m
        };
        self.space.notify_one();
        Ok(Some(m))
    }

    async fn pop(&self) -> Option<Message> {
        self.pop_as(None).await
    }

    async fn pop_as(&self, gen: Option<u64>) -> Option<Message> {
        loop {
            let notified = self.arrived.notified();
            tokio::pin!(notified);
            notified.as_mut().enable();
            if let Some(m) = self.try_pop_as(gen).ok()? {
                return Some(m);
            }
            if self.state().closed {
                return None;
            }
            notified.await;
        }
    }

    /// Starts a new callback generation (0 = none) and wakes the old one so it ends.
    fn set_callback(&self, on: bool) -> u64 {
        let gen = {
            let mut st = self.state();
            st.generations += 1;
            st.callback = if on { st.generations } else { 0 };
            st.callback
        };
        self.arrived.notify_waiters();
        gen
    }

    /// Waits until the buffer may take one more message.
    async fn wait_for_space(&self) {
        loop {
            let notified = self.space.notified();
            tokio::pin!(notified);
            notified.as_mut().enable();
            {
                let st = self.state();
                if !st.strict || st.queue.len() < st.capacity.max(1) {
                    return;
                }
            }
            notified.await;
        }
    }

    fn close(&self) {
        self.state().closed = true;
        self.arrived.notify_waiters();
    }
}

async fn drain_port(port: Arc<Port>, rd: Arc<ReadSide>) {
    loop {
        rd.wait_for_space().await;
        let Some(inc) = port.read().await else {
            break;
        };
        match Message::from_incoming(inc) {
            Ok(m) => rd.push(m),
            Err(e) => {
                // C++ skips what does not read as the port's type; the sender gets no reply
                tracing::debug!("{}: dropping undecodable message: {e}", port.name());
                rd.state().undecodable += 1;
            }
        }
    }
    rd.close();
}

// ---------------------------------------------------------------------------------------
// Writing side

struct Pending {
    bottle: Bottle,
    stamp: Option<Stamp>,
}

impl Pending {
    /// Hands the message to every output with room in its queue: a connection whose
    /// reader stopped reading misses it instead of holding up the others (C++ drops a
    /// message for a busy connection of a BufferedPort).
    fn send(&self, port: &Port) -> usize {
        port.write_nowait(&self.bottle, self.stamp)
    }

    async fn send_strict(&self, port: &Port) -> usize {
        port.write_strict(&self.bottle, self.stamp).await
    }
}

struct WriteSide {
    /// The one message waiting to go out ("in flight" in C++ terms).
    slot: Mutex<Option<Pending>>,
    wake: Notify,
    /// Serialises sends so that strict writes never overtake queued ones.
    send_lock: tokio::sync::Mutex<()>,
    dropped: AtomicU64,
    auto_envelope: Mutex<Option<Option<Stamp>>>,
}

impl WriteSide {
    fn new() -> WriteSide {
        WriteSide {
            slot: Mutex::new(None),
            wake: Notify::new(),
            send_lock: tokio::sync::Mutex::new(()),
            dropped: AtomicU64::new(0),
            auto_envelope: Mutex::new(None),
        }
    }

    /// The envelope for the next message when automatic envelopes are on.
    fn auto_stamp(&self) -> Option<Stamp> {
        let mut env = lock(&self.auto_envelope);
        let last = env.as_mut()?;
        let s = next_stamp(*last, now());
        *last = Some(s);
        Some(s)
    }

    fn enqueue(&self, p: Pending) -> bool {
        let replaced = lock(&self.slot).replace(p).is_some();
        if replaced {
            self.dropped.fetch_add(1, Ordering::Relaxed);
        }
        self.wake.notify_one();
        !replaced
    }

    /// Sends what is queued, then `p` (if any), holding the send lock throughout. `p` is
    /// strict: it waits for room in every output queue (bounded by `ACK_TIMEOUT`).
    async fn send_in_order(&self, port: &Port, p: Option<Pending>) -> usize {
        let _turn = self.send_lock.lock().await;
        let queued = lock(&self.slot).take();
        if let Some(q) = queued {
            q.send(port);
        }
        let Some(p) = p else {
            return 0;
        };
        p.send_strict(port).await
    }
}

async fn send_queued(port: Arc<Port>, wr: Arc<WriteSide>) {
    loop {
        wr.wake.notified().await;
        wr.send_in_order(&port, None).await;
    }
}

// ---------------------------------------------------------------------------------------

/// Background tasks, aborted when the port goes away.
#[derive(Default)]
struct Tasks {
    io: Vec<JoinHandle<()>>,
    callback: Mutex<Option<JoinHandle<()>>>,
}

impl Tasks {
    async fn stop(mut self) {
        let mut all = std::mem::take(&mut self.io);
        all.extend(lock(&self.callback).take());
        for t in &all {
            t.abort();
        }
        for t in all {
            let _ = t.await;
        }
    }
}

impl Drop for Tasks {
    fn drop(&mut self) {
        for t in &self.io {
            t.abort();
        }
        if let Some(t) = lock(&self.callback).take() {
            t.abort();
        }
    }
}

/// A port with C++ `BufferedPort<Bottle>` semantics; see the module documentation.
pub struct BufferedPort {
    port: Arc<Port>,
    rd: Arc<ReadSide>,
    wr: Arc<WriteSide>,
    rt: Handle,
    tasks: Tasks,
}

impl BufferedPort {
    /// Opens and registers a port, as `Port::open`, and starts buffering its input.
    pub async fn open(name: &str, ns: NameClient) -> Result<BufferedPort, PortError> {
        Ok(BufferedPort::from_port(Port::open(name, ns).await?))
    }

    /// Buffers an already open port. Must be called within a tokio runtime (it spawns the
    /// draining and sending tasks there).
    pub fn from_port(port: Port) -> BufferedPort {
        let port = Arc::new(port);
        let rd = Arc::new(ReadSide::new());
        let wr = Arc::new(WriteSide::new());
        let rt = Handle::current();
        let io = vec![
            rt.spawn(drain_port(port.clone(), rd.clone())),
            rt.spawn(send_queued(port.clone(), wr.clone())),
        ];
        BufferedPort {
            port,
            rd,
            wr,
            rt,
            tasks: Tasks {
                io,
                callback: Mutex::new(None),
            },
        }
    }

    pub fn name(&self) -> &str {
        self.port.name()
    }

    pub fn contact(&self) -> &Contact {
        self.port.contact()
    }

    /// The underlying port (its `read` competes with the buffer: do not call it).
    pub fn port(&self) -> &Port {
        &self.port
    }

    pub async fn connect(&self, target: &str, carrier: Option<&str>) -> Result<(), PortError> {
        self.port.connect(target, carrier).await
    }

    pub fn disconnect(&self, target: &str) -> bool {
        self.port.disconnect(target)
    }

    // -- reading --

    /// Strict: keep every message (bounded FIFO, back-pressure). Not strict (default):
    /// keep only the newest. Leaving strict mode keeps just the newest pending message.
    pub fn set_strict(&self, strict: bool) {
        {
            let mut st = self.rd.state();
            st.strict = strict;
            if !strict && st.queue.len() > 1 {
                let extra = st.queue.len() - 1;
                st.queue.drain(..extra);
                st.dropped += extra as u64;
            }
        }
        self.rd.space.notify_one();
    }

    pub fn is_strict(&self) -> bool {
        self.rd.state().strict
    }

    /// How many messages strict mode buffers before pushing back (at least 1).
    pub fn set_capacity(&self, n: usize) {
        self.rd.state().capacity = n.max(1);
        self.rd.space.notify_one();
    }

    /// Waits for a message not read before; `None` once the port can deliver no more.
    pub async fn read(&self) -> Option<Message> {
        self.rd.pop().await
    }

    /// The next unread message, if any, without waiting.
    pub fn try_read(&self) -> Option<Message> {
        self.rd.try_pop()
    }

    /// Messages received and not read yet.
    pub fn pending_count(&self) -> usize {
        self.rd.state().queue.len()
    }

    /// Messages superseded before anyone read them (latest-only mode).
    pub fn dropped_count(&self) -> u64 {
        self.rd.state().dropped
    }

    /// Messages received since opening (read, pending or dropped).
    pub fn received_count(&self) -> u64 {
        self.rd.state().received
    }

    /// Messages skipped because their payload was not a valid Bottle.
    pub fn undecodable_count(&self) -> u64 {
        self.rd.state().undecodable
    }

    /// The envelope of the last message read (C++ `getEnvelope`); `None` if it had none.
    pub fn last_stamp(&self) -> Option<Stamp> {
        self.rd.state().last_stamp
    }

    /// Hands every message to `f` instead of `read` (C++ `useCallback`). `f` runs on the
    /// runtime, so it should be quick; the buffering policy applies while it is busy. A
    /// new callback replaces the previous one.
    pub fn on_read<F>(&self, mut f: F)
    where
        F: FnMut(Message) + Send + 'static,
    {
        let rd = self.rd.clone();
        let gen = rd.set_callback(true);
        let task = self.rt.spawn(async move {
            while let Some(m) = rd.pop_as(Some(gen)).await {
                f(m);
            }
        });
        // the old task ends by itself: its generation is over
        lock(&self.tasks.callback).replace(task);
    }

    /// Stops the callback: once this returns, messages go to `read` again (a call of the
    /// callback already under way finishes).
    pub fn disable_callback(&self) {
        self.rd.set_callback(false);
        lock(&self.tasks.callback).take();
    }

    // -- writing --

    /// Attaches an envelope with an incrementing count and the current time to every
    /// message written from now on (C++ `setEnvelope` after `Stamp::update`).
    pub fn set_auto_envelope(&self, on: bool) {
        let mut env = lock(&self.wr.auto_envelope);
        match (on, env.is_some()) {
            (true, false) => *env = Some(None),
            (false, _) => *env = None,
            _ => {}
        }
    }

    /// Queues `b` without waiting; a queued message that has not left yet is replaced
    /// (and counted in `dropped_writes`). Returns false when it replaced one.
    pub fn write(&self, b: &Bottle) -> bool {
        let stamp = self.wr.auto_stamp();
        self.wr.enqueue(Pending {
            bottle: b.clone(),
            stamp,
        })
    }

    /// As `write`, with an explicit envelope.
    pub fn write_stamped(&self, b: &Bottle, stamp: Stamp) -> bool {
        self.wr.enqueue(Pending {
            bottle: b.clone(),
            stamp: Some(stamp),
        })
    }

    /// Sends `b` after anything queued, waiting for its turn instead of replacing, and
    /// while no output has room for it; returns how many outputs took it. With several
    /// outputs, one whose queue is full still misses it (see `Port::write`).
    pub async fn write_strict(&self, b: &Bottle) -> usize {
        let stamp = self.wr.auto_stamp();
        self.write_strict_inner(b, stamp).await
    }

    /// As `write_strict`, with an explicit envelope.
    pub async fn write_strict_stamped(&self, b: &Bottle, stamp: Stamp) -> usize {
        self.write_strict_inner(b, Some(stamp)).await
    }

    async fn write_strict_inner(&self, b: &Bottle, stamp: Option<Stamp>) -> usize {
        let p = Pending {
            bottle: b.clone(),
            stamp,
        };
        let n = self.wr.send_in_order(&self.port, Some(p)).await;
        // let the connections move the message on before the caller sends the next one
        tokio::task::yield_now().await;
        n
    }

    /// Waits until the queued message (if any) has been handed to the connections (C++
    /// `waitForWrite`).
    pub async fn flush(&self) {
        self.wr.send_in_order(&self.port, None).await;
    }

    /// Whether a `write` is still waiting to go out.
    pub fn is_writing(&self) -> bool {
        lock(&self.wr.slot).is_some()
    }

    /// Messages replaced by a newer `write` before they left.
    pub fn dropped_writes(&self) -> u64 {
        self.wr.dropped.load(Ordering::Relaxed)
    }

    /// Sends `b` on the first output and waits for the reply, as `Port::rpc`.
    pub async fn rpc(&self, b: &Bottle) -> Result<Bottle, PortError> {
        self.port.rpc(b).await
    }

    /// Sends what is queued, stops the buffering, then closes the port as `Port::close`.
    pub async fn close(self) {
        self.flush().await;
        let BufferedPort { port, tasks, .. } = self;
        tasks.stop().await;
        match Arc::try_unwrap(port) {
            Ok(p) => p.close().await,
            // a task still holds it (cannot happen once stopped); dropping still shuts it
            Err(p) => drop(p),
        }
    }
}

// ---------------------------------------------------------------------------------------

/// A port that serves requests (C++ `RpcServer`): every message comes with a reply handle.
pub struct RpcServer {
    port: Port,
}

impl RpcServer {
    pub async fn open(name: &str, ns: NameClient) -> Result<RpcServer, PortError> {
        Ok(RpcServer {
            port: Port::open(name, ns).await?,
        })
    }

    pub fn from_port(port: Port) -> RpcServer {
        RpcServer { port }
    }

    pub fn name(&self) -> &str {
        self.port.name()
    }

    pub fn port(&self) -> &Port {
        &self.port
    }

    /// The next request; answer it with `Message::reply`. Undecodable requests are
    /// skipped (their senders get an empty reply).
    pub async fn read(&self) -> Option<Message> {
        loop {
            let inc = self.port.read().await?;
            match Message::from_incoming(inc) {
                Ok(m) => return Some(m),
                Err(e) => tracing::debug!("{}: undecodable request: {e}", self.port.name()),
            }
        }
    }

    /// Answers every request with `f(request)` until the port can deliver no more. Run it
    /// in a task and abort that task to stop serving.
    pub async fn serve<F>(&self, mut f: F)
    where
        F: FnMut(&Bottle) -> Bottle,
    {
        while let Some(mut m) = self.read().await {
            let reply = f(&m.bottle);
            m.reply(reply);
        }
    }

    pub async fn close(self) {
        self.port.close().await;
    }
}
