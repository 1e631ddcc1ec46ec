//! YARP ports on tokio: a named endpoint with any number of input and output connections,
//! reachable by every tcp-family and text carrier, administered by the C++ port protocol.
//!
//! The protocol itself (framing, port commands, admin replies) is in `yarp_proto::wire`
//! and `yarp_proto::port_admin`; this module only moves bytes and keeps the live state.
//!
//! ```no_run
//! # async fn demo(ns: yarp_net::nameserver::NameClient) -> Result<(), yarp_net::port::PortError> {
//! use yarp_net::port::Port;
//! let out = Port::open("/writer", ns.clone()).await?;
//! let inp = Port::open("/reader", ns).await?;
//! out.connect("/reader", None).await?;
//! out.write(&yarp_proto::bottle!["hello", 42]).await;
//! let msg = inp.read().await.expect("port open");
//! assert_eq!(msg.bottle()?.to_string(), "hello 42");
//! # Ok(()) }
//! ```

mod dgram_out;
mod http;
mod input;
mod local;
mod mjpeg;
pub(crate) mod output;
pub mod shmem;
pub mod unix;

use crate::nameserver::{NameClient, NameClientError};
use parking_lot::Mutex;
use std::collections::BTreeMap;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Duration;
use tokio::net::TcpListener;
use tokio::sync::{mpsc, oneshot, watch};
use yarp_proto::nameserver::RegisterRequest;
use yarp_proto::port_admin::{Connection, PortSnapshot};
use yarp_proto::tags::Generation;
use yarp_proto::wire::Carrier;
use yarp_proto::{Bottle, Contact, DecodeError, PortRef, Stamp, Value};

pub use input::{HEADER_TIMEOUT, STALL_TIMEOUT};
pub use output::OutputError;

/// How long connection set-up steps (TCP connect, header reply, welcome) may take.
pub const CONNECT_TIMEOUT: Duration = Duration::from_secs(10);
/// How long a writer waits for a peer's acknowledgement before giving the peer up.
pub const ACK_TIMEOUT: Duration = Duration::from_secs(30);
/// Messages queued per output connection before new ones are dropped (slow reader).
pub const OUTPUT_QUEUE: usize = 64;
/// Bytes of messages an output connection may have queued before `write_nowait` skips
/// it: with large messages (images) a reader that stopped reading costs at most this
/// much (plus the sockets' buffers), not `OUTPUT_QUEUE` of them.
pub const OUTPUT_QUEUE_BYTES: usize = 16 * 1024 * 1024;
/// Messages queued for the owner before the inputs stop reading (back-pressure).
pub const INPUT_QUEUE: usize = 64;

#[derive(Debug, thiserror::Error)]
pub enum PortError {
    #[error("name server: {0}")]
    NameServer(#[from] NameClientError),
    #[error("port {0} is not known to the name server")]
    UnknownPort(String),
    #[error("cannot listen for port {name}: {source}")]
    Bind {
        name: String,
        source: std::io::Error,
    },
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The reply is no Bottle; its bytes are here for a caller that knows their form.
    #[error("the reply is not a valid Bottle: {error}")]
    BadReply { error: DecodeError, bytes: Vec<u8> },
    #[error("port {0} has no output connection for the RPC")]
    NotConnected(String),
    #[error("port closed")]
    Closed,
}

/// A Bottle that does not decode (without the bytes it came from).
impl From<DecodeError> for PortError {
    fn from(error: DecodeError) -> Self {
        PortError::BadReply {
            error,
            bytes: Vec::new(),
        }
    }
}

/// A message received by a port.
#[derive(Debug)]
pub struct Incoming {
    /// The payload: Bottle bytes (binary carriers) or Bottle text (text carriers). Empty
    /// for messages from a port of this process over `local`: use [`Incoming::bottle`].
    pub payload: Vec<u8>,
    /// The payload is text (from a text carrier), not binary.
    pub is_text: bool,
    /// The envelope, when the sender attached one.
    pub stamp: Option<Stamp>,
    /// The sending port's name.
    pub from: String,
    reply: Option<oneshot::Sender<ReplyBody>>,
    /// The Bottle itself, when it never left this process (`local`).
    pub(crate) decoded: Option<Arc<Bottle>>,
}

impl Incoming {
    /// The payload as a Bottle.
    pub fn bottle(&self) -> Result<Bottle, DecodeError> {
        if let Some(b) = &self.decoded {
            return Ok(Bottle::clone(b));
        }
        self.decode_payload()
    }

    /// The payload as a shared Bottle: over `local` this is the sender's own Bottle,
    /// with no copy (large images and blobs stay where they are).
    pub fn shared_bottle(&self) -> Result<Arc<Bottle>, DecodeError> {
        match &self.decoded {
            Some(b) => Ok(Arc::clone(b)),
            None => self.decode_payload().map(Arc::new),
        }
    }

    /// The payload as a Bottle, taken out of the message without copying where possible:
    /// over `local` the sender's Bottle itself (when nobody else holds it); over binary
    /// carriers a large string or blob takes over the received buffer.
    pub fn take_bottle(&mut self) -> Result<Bottle, DecodeError> {
        match self.decoded.take() {
            Some(b) => Ok(Arc::try_unwrap(b).unwrap_or_else(|b| Bottle::clone(&b))),
            None if !self.is_text => Bottle::decode_owned(std::mem::take(&mut self.payload)),
            None => self.decode_payload(),
        }
    }

    fn decode_payload(&self) -> Result<Bottle, DecodeError> {
        if self.is_text {
            Ok(Bottle::from_text(&self.payload))
        } else {
            Bottle::decode(&self.payload)
        }
    }

    /// Whether the sender waits for a reply.
    pub fn wants_reply(&self) -> bool {
        self.reply.is_some()
    }

    /// The generation of YARP whose numbering of tags the sender used, as far as the
    /// payload tells (a message without floats reads the same in both; so does a
    /// payload already taken by [`Incoming::take_bottle`]): YARP 3 unless it says 4.0.
    pub fn generation(&self) -> Generation {
        if self.is_text || self.decoded.is_some() {
            Generation::V3
        } else {
            yarp_proto::binary::generation_of(&self.payload)
        }
    }

    /// Sends the reply (no effect when none is expected), numbered as the request was
    /// ([`Incoming::generation`]). Dropping the message without replying lets the sender
    /// go on without a reply, as C++ does.
    pub fn reply(&mut self, b: Bottle) {
        let generation = self.generation();
        self.reply_in(b, generation);
    }

    /// Sends the reply encoded for a peer of `generation` (a server that knows its
    /// client's generation from elsewhere, such as the port it was asked on).
    pub fn reply_in(&mut self, b: Bottle, generation: Generation) {
        if let Some(tx) = self.reply.take() {
            let body = match generation {
                Generation::V4 if !self.is_text => ReplyBody::Encoded(b.encode_as(generation)),
                _ => ReplyBody::Bottle(b),
            };
            let _ = tx.send(body);
        }
    }

    /// Sends a reply already encoded (binary Bottle bytes, e.g. the element-tagged lists a
    /// thrift-generated C++ server writes): binary connections carry these bytes exactly;
    /// text connections get them decoded and printed.
    pub fn reply_encoded(&mut self, bytes: Vec<u8>) {
        if let Some(tx) = self.reply.take() {
            let _ = tx.send(ReplyBody::Encoded(bytes));
        }
    }

    /// Sends the reply as a C++ `DeviceResponder` does: on a text connection a reply
    /// starting with `[many]` (a `help` listing) goes out one line per entry; binary
    /// connections get the Bottle as [`Incoming::reply`] sends it.
    pub fn reply_as_responder(&mut self, b: Bottle) {
        if let Some(tx) = self.reply.take() {
            let _ = tx.send(ReplyBody::Responder(b));
        }
    }

    /// Takes the reply handle, to answer later from elsewhere.
    pub fn take_replier(&mut self) -> Option<Replier> {
        self.reply.take().map(Replier)
    }
}

/// A reply on its way back to an RPC caller.
#[derive(Debug)]
pub(crate) enum ReplyBody {
    Bottle(Bottle),
    /// Binary Bottle bytes, sent as they are.
    Encoded(Vec<u8>),
    /// A `DeviceResponder` reply (`[many]` listings split into lines in text mode).
    Responder(Bottle),
}

impl ReplyBody {
    /// The reply as a Bottle (undecodable bytes give an empty one, logged).
    pub(crate) fn into_bottle(self) -> Bottle {
        match self {
            ReplyBody::Bottle(b) | ReplyBody::Responder(b) => b,
            ReplyBody::Encoded(bytes) => Bottle::decode(&bytes).unwrap_or_else(|e| {
                tracing::warn!("dropping an undecodable encoded reply: {e}");
                Bottle::new()
            }),
        }
    }
}

/// A pending RPC reply.
#[derive(Debug)]
pub struct Replier(oneshot::Sender<ReplyBody>);

impl Replier {
    pub fn send(self, b: Bottle) {
        let _ = self.0.send(ReplyBody::Bottle(b));
    }

    /// As [`Incoming::reply_encoded`].
    pub fn send_encoded(self, bytes: Vec<u8>) {
        let _ = self.0.send(ReplyBody::Encoded(bytes));
    }
}

/// Live state shared by a port's tasks.
pub(crate) struct Shared {
    pub(crate) name: String,
    pub(crate) contact: Contact,
    pub(crate) ns: Option<NameClient>,
    pub(crate) state: Mutex<State>,
    pub(crate) deliver: mpsc::Sender<Incoming>,
    pub(crate) shutdown: watch::Receiver<bool>,
    next_id: AtomicU64,
}

#[derive(Default)]
pub(crate) struct State {
    pub(crate) inputs: BTreeMap<u64, input::InputEntry>,
    pub(crate) outputs: BTreeMap<u64, output::OutputHandle>,
    pub(crate) properties: BTreeMap<String, Value>,
    /// The multicast group this port's mcast outputs share, once allocated.
    pub(crate) mcast_group: Option<std::net::SocketAddrV4>,
}

impl Shared {
    pub(crate) fn next_id(&self) -> u64 {
        self.next_id.fetch_add(1, Ordering::Relaxed)
    }

    pub(crate) fn lock(&self) -> parking_lot::MutexGuard<'_, State> {
        // a panicking task cannot leave the plain data inconsistent; keep serving
        self.state.lock()
    }

    /// The admin protocol's view of this port.
    pub(crate) fn snapshot(&self) -> PortSnapshot {
        let st = self.lock();
        let mut s = PortSnapshot::new(
            &self.name,
            "tcp",
            &self.contact.host,
            self.contact.port as i32,
        );
        s.inputs = st
            .inputs
            .values()
            .map(|e| Connection::new(e.route.clone()))
            .collect();
        s.outputs = st
            .outputs
            .values()
            .map(|o| Connection::new(o.route.clone()))
            .collect();
        s.properties = st.properties.clone();
        s.process.pid = std::process::id() as i32;
        s
    }

    /// Opens an output connection to `target` and records it.
    pub(crate) async fn add_output(
        self: &Arc<Self>,
        target: &str,
        carrier: Option<&str>,
    ) -> Result<(), PortError> {
        let r = PortRef::parse(target);
        let carrier_name = carrier
            .map(str::to_string)
            .or(r.carrier.clone())
            .unwrap_or_else(|| "tcp".to_string());
        let contact = match &self.ns {
            // same-process connections need no address
            _ if carrier_name == "local" => Contact::new(&r.name, "local", "", 0),
            Some(ns) => ns
                .query(&r.name)
                .await?
                .ok_or_else(|| PortError::UnknownPort(r.name.clone()))?,
            None => return Err(PortError::UnknownPort(r.name.clone())),
        };
        // a pull carrier (mjpeg): this port connects, and receives
        let name = yarp_proto::wire::modifiers::CarrierName::parse(&carrier_name);
        if Carrier::from_name(&name.base).is_some_and(|c| !c.is_push()) {
            let already = self
                .lock()
                .inputs
                .values()
                .any(|i| i.route.from == r.name && i.route.carrier == carrier_name);
            if !already {
                mjpeg::pull(self, &r.name, &contact, &name).await?;
            }
            return Ok(());
        }
        let already = self
            .lock()
            .outputs
            .values()
            .any(|o| o.route.to == r.name && o.route.carrier == carrier_name);
        if already {
            return Ok(());
        }
        let handle = output::connect(self, &r.name, &contact, &carrier_name).await?;
        let id = self.next_id();
        self.lock().outputs.insert(id, handle);
        Ok(())
    }

    /// Removes outputs to `to`, and what this port pulls from `to` (C++ matches every
    /// connection whose route goes to `to`); true if there was one.
    pub(crate) fn remove_output(&self, to: &str) -> bool {
        let pulled = {
            let st = self.lock();
            let pulled: Vec<_> = st
                .inputs
                .values()
                .filter(|i| i.route.from == to && is_pull(&i.route.carrier))
                .collect();
            pulled.iter().for_each(|i| i.kill());
            !pulled.is_empty()
        };
        let removed: Vec<_> = {
            let mut st = self.lock();
            let ids: Vec<u64> = st
                .outputs
                .iter()
                .filter(|(_, o)| o.route.to == to)
                .map(|(id, _)| *id)
                .collect();
            ids.into_iter()
                .filter_map(|id| st.outputs.remove(&id))
                .collect()
        };
        let any = !removed.is_empty() || pulled;
        for o in removed {
            o.close();
        }
        any
    }
}

/// A YARP port.
pub struct Port {
    shared: Arc<Shared>,
    rx: tokio::sync::Mutex<mpsc::Receiver<Incoming>>,
    shutdown_tx: watch::Sender<bool>,
    accept_task: tokio::task::JoinHandle<()>,
}

impl Port {
    /// Opens a port registered with the name server under `name`, as C++ `Port::open`:
    /// the server chooses the port number, then the port listens on it.
    pub async fn open(name: &str, ns: NameClient) -> Result<Port, PortError> {
        let ip = advertised_ip(&ns);
        // C++ asks first whether the name is taken (a stale entry is simply replaced)
        ns.query(name).await?;
        let req = RegisterRequest::name(name);
        let pid = std::process::id() as i32;
        let mut contact = ns.register_port(&req, &[ip.as_str()], pid).await?;
        let listener = match TcpListener::bind(("0.0.0.0", contact.port)).await {
            Ok(l) => l,
            Err(_) => {
                // the allocated number is taken by something else: take any free one and
                // register it explicitly, replacing the entry at once (no unregister in
                // between, so a client never finds the name missing)
                let l =
                    TcpListener::bind(("0.0.0.0", 0))
                        .await
                        .map_err(|source| PortError::Bind {
                            name: name.to_string(),
                            source,
                        })?;
                let port = l.local_addr().map(|a| a.port()).unwrap_or(0);
                let req = RegisterRequest::explicit(name, "tcp", &contact.host, port);
                contact = ns.register_port(&req, &[ip.as_str()], pid).await?;
                l
            }
        };
        Ok(Port::start(contact, Some(ns), listener))
    }

    /// Opens a port on a given local address without a name server (tests, embedded use).
    pub async fn bind(name: &str, addr: SocketAddr) -> Result<Port, PortError> {
        let listener = TcpListener::bind(addr)
            .await
            .map_err(|source| PortError::Bind {
                name: name.to_string(),
                source,
            })?;
        let local = listener.local_addr().map_err(|source| PortError::Bind {
            name: name.to_string(),
            source,
        })?;
        let contact = Contact::new(name, "tcp", &local.ip().to_string(), local.port());
        Ok(Port::start(contact, None, listener))
    }

    fn start(contact: Contact, ns: Option<NameClient>, listener: TcpListener) -> Port {
        let (tx, rx) = mpsc::channel(INPUT_QUEUE);
        let (shutdown_tx, shutdown_rx) = watch::channel(false);
        let shared = Arc::new(Shared {
            name: contact.name.clone(),
            contact,
            ns,
            state: Mutex::new(State::default()),
            deliver: tx,
            shutdown: shutdown_rx,
            next_id: AtomicU64::new(1),
        });
        local::register(&shared);
        let accept_task = tokio::spawn(input::accept_loop(shared.clone(), listener));
        if shared.ns.is_some() {
            tokio::spawn(keep_registered(Arc::downgrade(&shared)));
        }
        Port {
            shared,
            rx: tokio::sync::Mutex::new(rx),
            shutdown_tx,
            accept_task,
        }
    }

    pub fn name(&self) -> &str {
        &self.shared.name
    }

    /// Where the port listens, as registered.
    pub fn contact(&self) -> &Contact {
        &self.shared.contact
    }

    /// Connects this port's output to `target` (`/name` or `carrier:/name`).
    pub async fn connect(&self, target: &str, carrier: Option<&str>) -> Result<(), PortError> {
        self.shared.add_output(target, carrier).await
    }

    /// Removes the output connection to `target`; false if there was none.
    pub fn disconnect(&self, target: &str) -> bool {
        self.shared.remove_output(&PortRef::parse(target).name)
    }

    /// Names of the ports this one sends to.
    pub fn outputs(&self) -> Vec<String> {
        self.shared
            .lock()
            .outputs
            .values()
            .map(|o| o.route.to.clone())
            .collect()
    }

    /// Whether anything is connected to receive from this port (cheaper than
    /// [`Port::outputs`] for a writer that skips work nobody would receive).
    pub fn has_outputs(&self) -> bool {
        !self.shared.lock().outputs.is_empty()
    }

    /// Names of the ports sending to this one.
    pub fn inputs(&self) -> Vec<String> {
        self.shared
            .lock()
            .inputs
            .values()
            .map(|e| e.route.from.clone())
            .collect()
    }

    /// Sends a Bottle to every output, waiting for room in each output's queue as a C++
    /// `Port::write` waits; returns how many outputs took it.
    pub async fn write(&self, b: &Bottle) -> usize {
        self.write_strict(b, None).await
    }

    /// Sends a Bottle with an envelope (timestamp) to every output (waiting, as `write`).
    pub async fn write_stamped(&self, b: &Bottle, stamp: Stamp) -> usize {
        self.write_strict(b, Some(stamp)).await
    }

    /// Sends without waiting: an output whose queue is full misses this message (the
    /// "drop if busy" of C++ BufferedPort). Returns how many outputs took it.
    pub fn write_nowait(&self, b: &Bottle, stamp: Option<Stamp>) -> usize {
        self.send(b, stamp)
    }

    /// Sends a Bottle (with an optional envelope) to every output, waiting for room in
    /// each output's queue (bounded by [`ACK_TIMEOUT`] per output) instead of dropping.
    pub async fn write_strict(&self, b: &Bottle, stamp: Option<Stamp>) -> usize {
        self.write_shared(Arc::new(b.clone()), stamp).await
    }

    /// As [`Port::write_strict`], for a Bottle the caller shares instead of lending: no
    /// copy is made, and readers in this process (`local` carrier) receive this very
    /// Bottle through [`Incoming::shared_bottle`].
    pub async fn write_shared(&self, b: Arc<Bottle>, stamp: Option<Stamp>) -> usize {
        self.write_shared_as(b, stamp, Generation::V3).await
    }

    /// As [`Port::write_shared`], encoded for readers of `generation`.
    pub async fn write_shared_as(
        &self,
        b: Arc<Bottle>,
        stamp: Option<Stamp>,
        generation: Generation,
    ) -> usize {
        self.write_shared_each(&[(b, generation)], |_| Some(0), stamp)
            .await
    }

    /// As [`Port::write_nowait_each`], waiting (at most ACK_TIMEOUT per output) for room
    /// in each output's queue instead of skipping a full one.
    pub async fn write_shared_each(
        &self,
        forms: &[(Arc<Bottle>, Generation)],
        pick: impl Fn(&str) -> Option<usize>,
        stamp: Option<Stamp>,
    ) -> usize {
        let outs: Vec<_> = self
            .shared
            .lock()
            .outputs
            .values()
            .filter_map(|o| Some((pick(&o.route.to)?, o.sender())))
            .collect();
        let mut msgs: Vec<Option<Arc<output::Outgoing>>> = vec![None; forms.len()];
        let mut n = 0;
        for (k, tx) in outs {
            let Some((b, generation)) = forms.get(k) else {
                continue;
            };
            let msg = msgs[k]
                .get_or_insert_with(|| {
                    Arc::new(output::Outgoing::new_as(b.clone(), stamp, *generation))
                })
                .clone();
            let sent = tokio::time::timeout(ACK_TIMEOUT, tx.send(output::Job::Data(msg)));
            if matches!(sent.await, Ok(Ok(()))) {
                n += 1;
            }
        }
        n
    }

    /// Sends, without waiting, to each output the form of a message its reader takes:
    /// `forms` holds a Bottle per generation of YARP, and `pick` tells, from the name of
    /// the port an output goes to, which of them (by index) it gets, if any. Returns how
    /// many outputs took one.
    pub fn write_nowait_each(
        &self,
        forms: &[(Bottle, Generation)],
        pick: impl Fn(&str) -> Option<usize>,
        stamp: Option<Stamp>,
    ) -> usize {
        let outs: Vec<_> = self
            .shared
            .lock()
            .outputs
            .values()
            .filter_map(|o| Some((pick(&o.route.to)?, o.sender())))
            .collect();
        // each form is built, and measured, once for all the outputs that take it
        let mut msgs: Vec<Option<(Arc<output::Outgoing>, usize)>> = vec![None; forms.len()];
        let mut n = 0;
        for (k, tx) in outs {
            let Some((b, generation)) = forms.get(k) else {
                continue;
            };
            let (msg, len) = msgs[k].get_or_insert_with(|| {
                let msg = output::Outgoing::new_as(Arc::new(b.clone()), stamp, *generation);
                let len = msg.encoded_len();
                (Arc::new(msg), len)
            });
            if Self::offer(&tx, msg, *len) {
                n += 1;
            }
        }
        n
    }

    /// Sends `b`, without waiting for its readers, to each in its own YARP generation's
    /// bytes, as `peers` tells them (asking first about readers new to it).
    pub async fn write_by_generation(
        &self,
        b: &Bottle,
        peers: &crate::peer_generation::PeerGenerations,
        stamp: Option<Stamp>,
    ) -> usize {
        peers.learn(&self.outputs()).await;
        self.write_nowait_by_generation(b, peers, stamp)
    }

    /// Sends `b`, without waiting, to each reader in its own YARP generation's bytes
    /// (told by `peers`); a reader whose generation is not known yet is asked, and misses
    /// the messages sent meanwhile rather than get bytes it would misread.
    pub fn write_nowait_by_generation(
        &self,
        b: &Bottle,
        peers: &crate::peer_generation::PeerGenerations,
        stamp: Option<Stamp>,
    ) -> usize {
        self.write_nowait_forms(peers, || b.clone(), || b.clone(), stamp)
    }

    /// As [`Port::write_nowait_by_generation`] for a message whose two generations'
    /// forms differ beyond their tags (4.0's `jointData` has more fields): each is built
    /// only if a reader takes it.
    pub fn write_nowait_forms(
        &self,
        peers: &crate::peer_generation::PeerGenerations,
        v3: impl FnOnce() -> Bottle,
        v4: impl FnOnce() -> Bottle,
        stamp: Option<Stamp>,
    ) -> usize {
        let outs = self.outputs();
        let takes = |g: Generation| outs.iter().any(|o| peers.known(o) == Some(g));
        let (want3, want4) = (takes(Generation::V3), takes(Generation::V4));
        // a form nobody takes is not built: an empty placeholder stands in
        let forms = [
            (if want3 { v3() } else { Bottle::new() }, Generation::V3),
            (if want4 { v4() } else { Bottle::new() }, Generation::V4),
        ];
        self.write_nowait_each(
            &forms,
            |to| {
                peers.known(to).map(|g| match g {
                    Generation::V3 => 0,
                    Generation::V4 => 1,
                })
            },
            stamp,
        )
    }

    /// Queues `msg` (`size` bytes encoded) on one output unless the output is behind on
    /// large messages: then it misses this one (as when its queue is full), so that what
    /// it holds stays within OUTPUT_QUEUE_BYTES.
    fn offer(
        tx: &tokio::sync::mpsc::Sender<output::Job>,
        msg: &Arc<output::Outgoing>,
        size: usize,
    ) -> bool {
        let queued = tx.max_capacity() - tx.capacity();
        if queued > 0 && queued.saturating_mul(size) >= OUTPUT_QUEUE_BYTES {
            return false;
        }
        tx.try_send(output::Job::Data(msg.clone())).is_ok()
    }

    fn send(&self, b: &Bottle, stamp: Option<Stamp>) -> usize {
        self.offer_all(|| output::Outgoing::new(Arc::new(b.clone()), stamp))
    }

    /// Sends, without waiting, a message already encoded (a thrift struct exactly as C++'s
    /// generated code writes it, which no Bottle encodes to: untagged strings without their
    /// NUL) with an optional envelope to every output. Text readers get the Bottle the bytes
    /// decode to. Returns how many outputs took it.
    pub fn write_encoded_nowait(&self, bytes: Vec<u8>, stamp: Option<Stamp>) -> usize {
        self.offer_all(|| output::Outgoing::encoded_stamped(bytes, stamp))
    }

    /// Offers the message `make` builds (only if some output would take it) to every output.
    fn offer_all(&self, make: impl FnOnce() -> output::Outgoing) -> usize {
        let outs: Vec<_> = self
            .shared
            .lock()
            .outputs
            .values()
            .map(|o| o.sender())
            .collect();
        if outs.is_empty() {
            return 0; // no copy of the message for nobody
        }
        let msg = Arc::new(make());
        let size = msg.encoded_len();
        outs.iter().filter(|tx| Self::offer(tx, &msg, size)).count()
    }

    /// Sends an encoded message (a thrift call, exactly as its generated code writes it)
    /// on the first output and waits for the reply; a reply that is no Bottle comes back
    /// as [`PortError::BadReply`] with its bytes.
    pub async fn rpc_encoded(&self, bytes: Vec<u8>) -> Result<Bottle, PortError> {
        self.rpc_message(output::Outgoing::encoded(bytes)).await
    }

    /// Sends a Bottle on the first output and waits for the reply (C++ `Port::write(cmd,
    /// reply)`).
    pub async fn rpc(&self, b: &Bottle) -> Result<Bottle, PortError> {
        self.rpc_message(output::Outgoing::new(Arc::new(b.clone()), None))
            .await
    }

    async fn rpc_message(&self, msg: output::Outgoing) -> Result<Bottle, PortError> {
        let tx = self
            .shared
            .lock()
            .outputs
            .values()
            .next()
            .map(|o| o.sender())
            .ok_or_else(|| PortError::NotConnected(self.shared.name.clone()))?;
        let (rtx, rrx) = oneshot::channel();
        tx.send(output::Job::Rpc(Arc::new(msg), rtx))
            .await
            .map_err(|_| PortError::Closed)?;
        let reply = rrx.await.map_err(|_| PortError::Closed)??;
        Ok(reply)
    }

    /// The next received message; `None` once the port is closed.
    pub async fn read(&self) -> Option<Incoming> {
        self.rx.lock().await.recv().await
    }

    /// Unregisters, closes every connection (outputs get a `q`) and stops listening.
    pub async fn close(self) {
        self.ask_sources_to_disconnect().await;
        let _ = self.shutdown_tx.send(true);
        let outputs: Vec<_> = {
            let mut st = self.shared.lock();
            std::mem::take(&mut st.outputs).into_values().collect()
        };
        for o in outputs {
            o.close_and_wait().await;
        }
        self.accept_task.abort();
        if let Some(ns) = &self.shared.ns {
            let _ = ns.unregister(&self.shared.name).await;
        }
    }
}

impl Port {
    /// As C++'s `PortCore::closeMain`: each named source is asked (through its admin port)
    /// to drop its connection to this port before it closes. A udp sender learns nothing
    /// from a closed socket: it would keep its connection to a port that is gone, and
    /// take a new port of the same name for one it already has (a restarted client of a
    /// C++ `controlBoard_nws_yarp` got no stream). Bounded: a dead source costs a second.
    async fn ask_sources_to_disconnect(&self) {
        let Some(ns) = self.shared.ns.clone() else {
            return;
        };
        let me = self.shared.name.clone();
        let mut asks = tokio::task::JoinSet::new();
        for from in self.inputs() {
            if !from.starts_with('/') || from == me {
                continue;
            }
            let (ns, me) = (ns.clone(), me.clone());
            asks.spawn(async move {
                let _ = tokio::time::timeout(
                    Duration::from_secs(1),
                    crate::network::disconnect(&ns, &from, &me),
                )
                .await;
            });
        }
        while asks.join_next().await.is_some() {}
    }
}

impl Drop for Port {
    fn drop(&mut self) {
        local::unregister(&self.shared);
        let _ = self.shutdown_tx.send(true);
        self.accept_task.abort();
    }
}

/// How often a port checks that the name server still knows it.
pub const REGISTRATION_CHECK: Duration = Duration::from_secs(2);

/// Re-registers the port when the name server forgot it (restarted, or `yarp clean` by
/// mistake), so that live ports stay reachable by name. Ends with the port.
///
/// A name server that knows one port of the process was not restarted: that check stands
/// for every port of the process for a while ([`recently_confirmed`]), so a robot process
/// with a hundred ports asks its name server about once per period, not a hundred times.
/// A port found forgotten withdraws the confirmation, and every port then checks (and
/// registers) itself again at its next turn.
async fn keep_registered(port: std::sync::Weak<Shared>) {
    loop {
        let Some(shared) = port.upgrade() else { return };
        let mut shutdown = shared.shutdown.clone();
        if *shutdown.borrow() {
            return;
        }
        if let Some(ns) = shared
            .ns
            .as_ref()
            .filter(|ns| !recently_confirmed(ns.server()))
        {
            let c = &shared.contact;
            let known = ns.query(&shared.name).await;
            let lost = matches!(&known, Ok(None))
                || matches!(&known, Ok(Some(k)) if k.port != c.port || k.host != c.host);
            if lost {
                confirmations().remove(&ns.server());
            } else if known.is_ok() {
                confirmations().insert(ns.server(), std::time::Instant::now());
            }
            if lost && !*shutdown.borrow() {
                tracing::info!(
                    "{}: name server lost the registration; registering again",
                    shared.name
                );
                let req = RegisterRequest::explicit(&shared.name, "tcp", &c.host, c.port);
                let pid = std::process::id() as i32;
                let _ = ns.register_port(&req, &[c.host.as_str()], pid).await;
            }
        }
        drop(shared);
        tokio::select! {
            _ = shutdown.changed() => return,
            _ = tokio::time::sleep(REGISTRATION_CHECK) => {}
        }
    }
}

/// When a port of this process last found each name server knowing it.
fn confirmations(
) -> parking_lot::MutexGuard<'static, std::collections::HashMap<SocketAddr, std::time::Instant>> {
    static CONFIRMED: std::sync::OnceLock<
        Mutex<std::collections::HashMap<SocketAddr, std::time::Instant>>,
    > = std::sync::OnceLock::new();
    CONFIRMED.get_or_init(Mutex::default).lock()
}

/// Whether another port's check of `server` still stands: younger than three quarters of
/// a period, so that a confirmation withdrawn by a forgotten port cannot be renewed
/// before every port has had its turn to check itself.
fn recently_confirmed(server: SocketAddr) -> bool {
    confirmations()
        .get(&server)
        .is_some_and(|t| t.elapsed() < REGISTRATION_CHECK * 3 / 4)
}

/// The address to advertise: the one we reach the name server from (so that other hosts
/// can reach us), or loopback.
fn advertised_ip(ns: &NameClient) -> String {
    let server = ns.server();
    std::net::UdpSocket::bind(("0.0.0.0", 0))
        .and_then(|s| {
            s.connect(server)?;
            s.local_addr()
        })
        .map(|a| a.ip().to_string())
        .unwrap_or_else(|_| "127.0.0.1".to_string())
}

/// Whether a connection's carrier (qualifiers and all) is pulled by its reader.
fn is_pull(carrier: &str) -> bool {
    let base = carrier.split('+').next().unwrap_or_default();
    Carrier::from_name(base).is_some_and(|c| !c.is_push())
}

/// Carrier lookup by name, for the carriers ports can use today.
pub(crate) fn carrier_by_name(name: &str) -> Option<Carrier> {
    Carrier::from_name(name)
}
