//! Output connections: one task per connection owns the socket, writes queued messages
//! in the connection's carrier and reads acknowledgements and replies.

use super::{PortError, Shared, ACK_TIMEOUT, CONNECT_TIMEOUT, OUTPUT_QUEUE};
use std::io::IoSlice;
use std::sync::{Arc, OnceLock, Weak};
use std::time::Duration;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio::sync::{mpsc, oneshot};
use tokio::task::JoinHandle;
use tokio::time::timeout;
use yarp_proto::port_admin::Route;
use yarp_proto::portmonitor::{Monitor, Side};
use yarp_proto::tags::Generation;
use yarp_proto::wire::modifiers::CarrierName;
use yarp_proto::wire::{
    self, encode_connection_start, text_carrier, Carrier, CarrierSpec, Decoder, DecoderConfig,
    Event, Framing, Index, PortCommand, WireError,
};
use yarp_proto::{Bottle, Contact, Stamp};

#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("carrier {0:?} is not supported for output connections yet")]
    UnsupportedCarrier(String),
    #[error("cannot connect to {target} at {addr}: {source}")]
    Connect {
        target: String,
        addr: String,
        source: std::io::Error,
    },
    #[error(
        "{target} did not answer the connection header within {0:?}",
        CONNECT_TIMEOUT
    )]
    HandshakeTimeout { target: String },
    #[error("{target} answered the connection header with {what}")]
    Unexpected { target: String, what: String },
    #[error("connection to {0} closed")]
    PeerClosed(String),
    #[error("protocol error from {target}: {source}")]
    Protocol { target: String, source: WireError },
    #[error("i/o error talking to {target}: {source}")]
    Io {
        target: String,
        source: std::io::Error,
    },
    #[error("{0} did not acknowledge within {1:?}")]
    AckTimeout(String, Duration),
    #[error("peer {0:?} stopped before the end of its header or message (nothing for {1:?})")]
    Stalled(String, Duration),
    #[error("connection to {target} with carrier {carrier}: {source}")]
    Monitor {
        target: String,
        carrier: String,
        source: yarp_proto::portmonitor::MonitorError,
    },
}

/// How long a closing connection may take to send its `q` before it is ended without.
const CLOSE_WAIT: Duration = Duration::from_secs(2);

/// A message ready to go out on any carrier.
///
/// It keeps the Bottle; binary connections write it as index + port command + the
/// Bottle's encoding segments in one vectored write (large strings and blobs lent, not
/// copied); the text form and the flat encoding (datagrams) are made once, on demand.
pub(crate) struct Outgoing {
    /// Shared, so that `local` connections hand the same Bottle to readers uncopied.
    bottle: Arc<Bottle>,
    binary: OnceLock<Vec<u8>>,
    text: OnceLock<Vec<u8>>,
    stamp: Option<Stamp>,
    /// The numbering of tags the reader expects (YARP 4.0 renumbered the floats).
    generation: Generation,
    /// Whether the writer left the generation to each connection (its reader's).
    open_generation: bool,
    /// Given encoded (a thrift call), whose reply may be no Bottle.
    encoded: bool,
}

impl Outgoing {
    /// A message in each reader's generation (3.x's until a connection knows better).
    pub(crate) fn new(bottle: Arc<Bottle>, stamp: Option<Stamp>) -> Outgoing {
        let mut msg = Outgoing::new_as(bottle, stamp, Generation::V3);
        msg.open_generation = true;
        msg
    }

    /// A message for readers of `generation`.
    pub(crate) fn new_as(
        bottle: Arc<Bottle>,
        stamp: Option<Stamp>,
        generation: Generation,
    ) -> Outgoing {
        Outgoing {
            bottle,
            binary: OnceLock::new(),
            text: OnceLock::new(),
            stamp,
            generation,
            open_generation: false,
            encoded: false,
        }
    }

    /// This message as a reader of `generation` takes it: itself, unless the writer left
    /// the generation open and the reader's is another.
    pub(crate) fn for_reader(self: &Arc<Self>, generation: Generation) -> Arc<Outgoing> {
        if !self.open_generation || self.generation == generation {
            return self.clone();
        }
        Arc::new(Outgoing::new_as(
            self.bottle.clone(),
            self.stamp,
            generation,
        ))
    }

    /// A message already encoded (a thrift call): binary carriers send `bytes` as they
    /// are; text and local ones the Bottle they decode to.
    pub(crate) fn encoded(bytes: Vec<u8>) -> Outgoing {
        Outgoing::encoded_stamped(bytes, None)
    }

    /// [`Outgoing::encoded`] with an envelope (a stream message).
    pub(crate) fn encoded_stamped(bytes: Vec<u8>, stamp: Option<Stamp>) -> Outgoing {
        let bottle = Bottle::decode(&bytes).unwrap_or_default();
        let generation = yarp_proto::binary::generation_of(&bytes);
        let mut msg = Outgoing::new_as(Arc::new(bottle), stamp, generation);
        msg.encoded = true;
        let _ = msg.binary.set(bytes);
        msg
    }

    /// Whether this is a message already encoded ([`Outgoing::encoded`]).
    pub(crate) fn is_encoded(&self) -> bool {
        self.encoded
    }

    /// The binary encoding as segments: YARP 3's lends large strings and blobs from the
    /// Bottle; another generation's is encoded whole.
    fn segments(&self) -> Vec<std::borrow::Cow<'_, [u8]>> {
        if let Some(encoded) = self.binary.get() {
            return vec![std::borrow::Cow::Borrowed(encoded)];
        }
        match self.generation {
            Generation::V3 => yarp_proto::binary::encode_segments(&self.bottle),
            _ => vec![std::borrow::Cow::Borrowed(self.payload())],
        }
    }

    pub(crate) fn command(&self, reply: bool) -> PortCommand {
        match &self.stamp {
            Some(s) => PortCommand::with_stamp(s, reply),
            None => PortCommand::data(reply),
        }
    }

    fn text(&self) -> &[u8] {
        self.text.get_or_init(|| self.bottle.to_text())
    }

    /// The Bottle being sent.
    pub(crate) fn bottle(&self) -> &Arc<Bottle> {
        &self.bottle
    }

    /// Length of the Bottle's encoding (without encoding it into one buffer).
    pub(crate) fn encoded_len(&self) -> usize {
        match self.binary.get() {
            Some(b) => b.len(),
            None => self.segments().iter().map(|s| s.len()).sum(),
        }
    }

    /// The encoded Bottle.
    pub(crate) fn payload(&self) -> &[u8] {
        self.binary
            .get_or_init(|| self.bottle.encode_as(self.generation))
    }

    /// The envelope, if any.
    pub(crate) fn stamp(&self) -> Option<Stamp> {
        self.stamp
    }

    /// The whole binary message (index, port command `D`, payload), as datagram carriers
    /// send it.
    pub(crate) fn binary_message(&self) -> Vec<u8> {
        let payload = self.payload();
        let mut out = Vec::with_capacity(payload.len() + 64);
        wire::encode_message(&self.command(false), &[payload], &mut out);
        out
    }

    /// The binary message as parts, for `f`: index and port command, then the Bottle's
    /// encoding segments (large strings and blobs lent, not copied).
    pub(crate) fn with_binary_parts<R>(
        &self,
        cmd: &PortCommand,
        f: impl FnOnce(&[&[u8]]) -> R,
    ) -> R {
        let segs = self.segments();
        let len: usize = segs.iter().map(|s| s.len()).sum();
        let mut head = Vec::with_capacity(64);
        Index::new(vec![cmd.binary_len() as u32, len as u32]).encode(&mut head);
        cmd.encode_binary(&mut head);
        let mut parts: Vec<&[u8]> = Vec::with_capacity(segs.len() + 1);
        parts.push(&head);
        parts.extend(segs.iter().map(|s| s.as_ref()));
        f(&parts)
    }

    /// Writes this message in a carrier's framing.
    async fn write_to(
        &self,
        stream: &mut TcpStream,
        framing: Framing,
        cmd: &PortCommand,
    ) -> std::io::Result<()> {
        match framing {
            Framing::Text => {
                let mut out = Vec::with_capacity(self.text().len() + 16);
                text_carrier::encode_message(cmd, self.text(), &mut out);
                stream.write_all(&out).await
            }
            _ => {
                // the bytes of `wire::encode_message(cmd, &[&encoding])`: index, port
                // command, payload; the payload straight from the Bottle's segments
                let segs = self.segments();
                let len: usize = segs.iter().map(|s| s.len()).sum();
                let mut head = Vec::with_capacity(64);
                Index::new(vec![cmd.binary_len() as u32, len as u32]).encode(&mut head);
                cmd.encode_binary(&mut head);
                let mut parts: Vec<&[u8]> = Vec::with_capacity(segs.len() + 1);
                parts.push(&head);
                parts.extend(segs.iter().map(|s| s.as_ref()));
                write_all_parts(stream, &parts).await
            }
        }
    }
}

/// Writes every part in order with vectored writes (`writev`), so that large parts lent by
/// `binary::encode_segments` go out without being copied into one buffer.
pub(crate) async fn write_all_parts<W: tokio::io::AsyncWrite + Unpin>(
    stream: &mut W,
    parts: &[&[u8]],
) -> std::io::Result<()> {
    let mut idx = 0;
    let mut off = 0;
    while idx < parts.len() {
        if parts[idx].len() == off {
            idx += 1;
            off = 0;
            continue;
        }
        let slices: Vec<IoSlice<'_>> = std::iter::once(IoSlice::new(&parts[idx][off..]))
            .chain(parts[idx + 1..].iter().take(63).map(|p| IoSlice::new(p)))
            .collect();
        let mut n = stream.write_vectored(&slices).await?;
        if n == 0 {
            return Err(std::io::ErrorKind::WriteZero.into());
        }
        while n > 0 && idx < parts.len() {
            let left = parts[idx].len() - off;
            if n >= left {
                n -= left;
                idx += 1;
                off = 0;
            } else {
                off += n;
                n = 0;
            }
        }
    }
    Ok(())
}

pub(crate) type RpcResult = Result<Bottle, PortError>;

pub(crate) enum Job {
    Data(Arc<Outgoing>),
    Rpc(Arc<Outgoing>, oneshot::Sender<RpcResult>),
    Close(Option<oneshot::Sender<()>>),
}

/// A live output connection as the port keeps it.
pub(crate) struct OutputHandle {
    pub(crate) route: Route,
    tx: mpsc::Sender<Job>,
    task: JoinHandle<()>,
    /// The connection's `stats_monitor` ports, closed with it.
    stats: Option<StatsPublisher>,
}

impl OutputHandle {
    pub(crate) fn new(route: Route, tx: mpsc::Sender<Job>, task: JoinHandle<()>) -> OutputHandle {
        OutputHandle {
            route,
            tx,
            task,
            stats: None,
        }
    }

    pub(crate) fn sender(&self) -> mpsc::Sender<Job> {
        self.tx.clone()
    }

    /// Asks the connection to send `q` and close; does not wait. A connection that has
    /// not closed within [`CLOSE_WAIT`] (stuck writing to a reader that stopped reading,
    /// with its `q` queued behind) is ended without it.
    pub(crate) fn close(self) {
        if self.tx.try_send(Job::Close(None)).is_err() {
            self.task.abort();
            return;
        }
        if let Ok(rt) = tokio::runtime::Handle::try_current() {
            let abort = self.task.abort_handle();
            let task = self.task;
            rt.spawn(async move {
                if timeout(CLOSE_WAIT, task).await.is_err() {
                    abort.abort();
                }
            });
        }
    }

    /// Sends `q`, waits (bounded) for the connection to finish.
    pub(crate) async fn close_and_wait(self) {
        let (tx, rx) = oneshot::channel();
        if let Ok(Ok(())) = timeout(CLOSE_WAIT, self.tx.send(Job::Close(Some(tx)))).await {
            let _ = timeout(CLOSE_WAIT, rx).await;
        }
        self.task.abort();
    }
}

/// Opens a connection from port `shared` to `target` at `contact` using `carrier`.
pub(crate) async fn connect(
    shared: &Arc<Shared>,
    target: &str,
    contact: &Contact,
    carrier: &str,
) -> Result<OutputHandle, OutputError> {
    if carrier == "local" {
        return super::local::connect(shared, target);
    }
    // `base+send.portmonitor+file.X+...`: the carrier proper, and a monitor of what we
    // send when the qualifiers ask for one (the receiver learns the rest from our name)
    let name = CarrierName::parse(carrier);
    let monitor =
        Monitor::for_side(&name, Side::Sender).map_err(|source| OutputError::Monitor {
            target: target.to_string(),
            carrier: carrier.to_string(),
            source,
        })?;
    let qualified = name.has_qualifiers();
    let carrier = name.base.as_str();
    match super::carrier_by_name(carrier) {
        Some(_) if qualified && !stream_framed(carrier) => {
            return Err(OutputError::UnsupportedCarrier(format!(
                "{name} (qualifiers are supported on tcp, fast_tcp and text connections)"
            )));
        }
        Some(c @ (Carrier::Udp | Carrier::Mcast)) => {
            return super::dgram_out::connect(shared, target, contact, c).await;
        }
        Some(c @ (Carrier::UnixStream | Carrier::UnixStreamAck)) => {
            return super::unix::connect(shared, target, contact, c).await;
        }
        Some(Carrier::Shmem) => return super::shmem::connect(shared, target, contact).await,
        _ => {}
    }
    let spec = super::carrier_by_name(carrier)
        .map(|c| c.spec())
        .filter(|s| matches!(s.framing, Framing::Stream | Framing::Text))
        .ok_or_else(|| OutputError::UnsupportedCarrier(carrier.to_string()))?;
    let mut stream = dial(target, contact).await?;
    let _ = stream.set_nodelay(true);
    let io_err = |source| OutputError::Io {
        target: target.to_string(),
        source,
    };
    let sender = name.sender_specifier(&shared.name);
    stream
        .write_all(&encode_connection_start(&spec, sender.as_bytes()))
        .await
        .map_err(io_err)?;
    let mut decoder = Decoder::connecting(spec, DecoderConfig::default());
    // the accepting side answers with its port number (tcp family) or a welcome line
    let ev = timeout(
        CONNECT_TIMEOUT,
        next_event(&mut stream, &mut decoder, target),
    )
    .await
    .map_err(|_| OutputError::HandshakeTimeout {
        target: target.to_string(),
    })??;
    if !matches!(ev, Event::HeaderReply(_) | Event::Welcome(_)) {
        return Err(OutputError::Unexpected {
            target: target.to_string(),
            what: format!("{ev:?}"),
        });
    }
    // a binary reader of YARP 4.0 takes 4.0's float tags: ask its admin which it is
    let generation = match spec.framing {
        Framing::Stream => crate::peer_generation::probe(contact)
            .await
            .unwrap_or(Generation::V3),
        _ => Generation::V3,
    };
    // a stats_monitor publishes what it counts on ports of its own, as C++ 4.0's does;
    // without them the connection is refused, as C++ refuses it
    let stats = match monitor.as_ref().and_then(Monitor::stats) {
        Some(counts) => Some(
            StatsPublisher::start(shared, target, carrier, counts)
                .await
                .map_err(|reason| OutputError::Monitor {
                    target: target.to_string(),
                    carrier: name.to_string(),
                    source: yarp_proto::portmonitor::MonitorError::Refused {
                        monitor: "stats_monitor",
                        reason,
                    },
                })?,
        ),
        None => None,
    };
    let route = Route::new(&shared.name, target, &name.to_string());
    let mut out = spawn(shared, route, stream, decoder, (spec, generation), monitor);
    out.stats = stats;
    Ok(out)
}

/// A `stats_monitor`'s publisher: every second, the forward counts on
/// `/stats_monitor<src><dst>/stats:o` and the backward ones (the replies, counted with no
/// bytes as C++ 4.0 counts them) on `/stats_monitor<dst><src>/stats:o`, as
/// `yarp::stats::ConnectionStats`. Dropping it closes both ports.
pub(crate) struct StatsPublisher {
    _stop: oneshot::Sender<()>,
}

impl StatsPublisher {
    /// Period of the statistics (C++ 4.0's is fixed).
    const PERIOD: Duration = Duration::from_secs(1);

    async fn start(
        shared: &Arc<Shared>,
        target: &str,
        carrier: &str,
        (counts, replies): (
            Arc<yarp_proto::portmonitor::StatsCounter>,
            Arc<yarp_proto::portmonitor::StatsCounter>,
        ),
    ) -> Result<StatsPublisher, String> {
        let ns = shared
            .ns
            .clone()
            .ok_or("the port has no name server to register its statistics ports with")?;
        let (src, dst) = (shared.name.clone(), target.to_string());
        let open = |name: String| {
            let ns = ns.clone();
            async move {
                super::Port::open(&name, ns)
                    .await
                    .map_err(|e| format!("cannot open {name}: {e}"))
            }
        };
        let forward = open(format!("/stats_monitor{src}{dst}/stats:o")).await?;
        let backward = match open(format!("/stats_monitor{dst}{src}/stats:o")).await {
            Ok(p) => p,
            Err(e) => {
                forward.close().await;
                return Err(e);
            }
        };
        let (stop, mut stopped) = oneshot::channel::<()>();
        let carrier = carrier.to_string();
        tokio::spawn(async move {
            let mut tick = tokio::time::interval(Self::PERIOD);
            tick.tick().await;
            let period = Self::PERIOD.as_secs_f64();
            loop {
                tokio::select! {
                    _ = &mut stopped => break,
                    _ = tick.tick() => {}
                }
                let now = yarp_proto::stamp::now();
                let names = (src.as_str(), dst.as_str(), carrier.as_str());
                let b = yarp_proto::portmonitor::connection_stats(
                    now,
                    names,
                    true,
                    counts.take(),
                    period,
                );
                forward.write_nowait(&b, None);
                let names = (dst.as_str(), src.as_str(), carrier.as_str());
                let b = yarp_proto::portmonitor::connection_stats(
                    now,
                    names,
                    false,
                    replies.take(),
                    period,
                );
                backward.write_nowait(&b, None);
            }
            forward.close().await;
            backward.close().await;
        });
        Ok(StatsPublisher { _stop: stop })
    }
}

/// A TCP connection to `target` at `contact`, within [`CONNECT_TIMEOUT`].
pub(crate) async fn dial(target: &str, contact: &Contact) -> Result<TcpStream, OutputError> {
    let addr = format!("{}:{}", contact.host, contact.port);
    match timeout(CONNECT_TIMEOUT, crate::auth::connect(&addr)).await {
        Ok(Ok(s)) => Ok(s),
        Ok(Err(source)) => Err(OutputError::Connect {
            target: target.to_string(),
            addr,
            source,
        }),
        Err(_) => Err(OutputError::HandshakeTimeout {
            target: target.to_string(),
        }),
    }
}

/// Whether the carrier frames messages on its TCP stream (where qualifiers apply).
fn stream_framed(carrier: &str) -> bool {
    super::carrier_by_name(carrier)
        .is_some_and(|c| matches!(c.spec().framing, Framing::Stream | Framing::Text))
}

/// Turns an accepted connection into an output (the peer sent `r`).
pub(crate) fn from_reversed(
    shared: &Arc<Shared>,
    peer: &str,
    stream: TcpStream,
    spec: CarrierSpec,
) -> OutputHandle {
    // what the peer sends from now on are acks and replies to our messages
    let decoder = Decoder::responses(spec, DecoderConfig::default());
    let route = Route::new(&shared.name, peer, spec.carrier.name());
    spawn(shared, route, stream, decoder, (spec, Generation::V3), None)
}

fn spawn(
    shared: &Arc<Shared>,
    route: Route,
    stream: TcpStream,
    decoder: Decoder,
    (spec, generation): (CarrierSpec, Generation),
    monitor: Option<Monitor>,
) -> OutputHandle {
    let (tx, rx) = mpsc::channel(OUTPUT_QUEUE);
    let task = tokio::spawn(run(
        Arc::downgrade(shared),
        route.to.clone(),
        stream,
        decoder,
        (spec, generation, monitor),
        rx,
    ));
    OutputHandle {
        route,
        tx,
        task,
        stats: None,
    }
}

async fn run(
    port: Weak<Shared>,
    target: String,
    mut stream: TcpStream,
    mut decoder: Decoder,
    (spec, generation, monitor): (CarrierSpec, Generation, Option<Monitor>),
    mut rx: mpsc::Receiver<Job>,
) {
    let result = serve(
        &target,
        &mut stream,
        &mut decoder,
        (spec, generation, monitor),
        &mut rx,
    )
    .await;
    if let Err(e) = &result {
        tracing::debug!("output to {target} ended: {e}");
    }
    let _ = stream.shutdown().await;
    // a dead peer disappears from the port's outputs
    if let Some(shared) = port.upgrade() {
        if result.is_err() {
            shared.lock().outputs.retain(|_, o| o.route.to != target);
        }
    }
}

async fn serve(
    target: &str,
    stream: &mut TcpStream,
    decoder: &mut Decoder,
    (spec, generation, mut monitor): (CarrierSpec, Generation, Option<Monitor>),
    rx: &mut mpsc::Receiver<Job>,
) -> Result<(), OutputError> {
    let io_err = |source| OutputError::Io {
        target: target.to_string(),
        source,
    };
    let mut probe = [0u8; 512];
    loop {
        // idle: wait for work, noticing a peer that goes away meanwhile
        let job = tokio::select! {
            job = rx.recv() => job,
            n = stream.read(&mut probe) => {
                let n = n.map_err(io_err)?;
                if n == 0 {
                    return Err(OutputError::PeerClosed(target.to_string()));
                }
                decoder.feed(&probe[..n]);
                drain(decoder, target)?;
                continue;
            }
        };
        let Some(job) = job else {
            return Ok(());
        };
        // in the reader's generation, unless the writer chose one
        let job = match job {
            Job::Data(msg) => Job::Data(msg.for_reader(generation)),
            Job::Rpc(msg, reply_tx) => Job::Rpc(msg.for_reader(generation), reply_tx),
            job => job,
        };
        let job = match (monitor.as_mut(), job) {
            (Some(m), Job::Data(msg)) => match monitored(m, &msg, target) {
                Some(msg) => Job::Data(msg),
                None => continue,
            },
            (Some(m), Job::Rpc(msg, reply_tx)) => match monitored(m, &msg, target) {
                Some(msg) => Job::Rpc(msg, reply_tx),
                None => {
                    let _ = reply_tx.send(Ok(Bottle::new()));
                    continue;
                }
            },
            (_, job) => job,
        };
        match job {
            Job::Data(msg) => {
                let cmd = msg.command(false);
                msg.write_to(stream, spec.framing, &cmd)
                    .await
                    .map_err(io_err)?;
                decoder.expect_response(&cmd);
                if spec.requires_ack {
                    await_ack(stream, decoder, target).await?;
                }
            }
            Job::Rpc(msg, reply_tx) => {
                let cmd = msg.command(true);
                msg.write_to(stream, spec.framing, &cmd)
                    .await
                    .map_err(io_err)?;
                if msg.is_encoded() {
                    decoder.expect_raw_response(&cmd);
                } else {
                    decoder.expect_response(&cmd);
                }
                let reply = await_reply(stream, decoder, target, spec).await;
                if let (Some(m), Ok(_)) = (monitor.as_ref(), &reply) {
                    m.reply_seen();
                }
                // the connection is still good after a reply that is no Bottle
                let failed = reply
                    .as_ref()
                    .is_err_and(|e| !matches!(e, PortError::BadReply { .. }));
                let _ = reply_tx.send(reply);
                if failed {
                    return Err(OutputError::PeerClosed(target.to_string()));
                }
            }
            Job::Close(done) => {
                let cmd = PortCommand::close();
                let bytes = match spec.framing {
                    Framing::Text => {
                        let mut out = Vec::new();
                        text_carrier::encode_message(&cmd, &[], &mut out);
                        out
                    }
                    _ => wire::close_message(),
                };
                let _ = stream.write_all(&bytes).await;
                decoder.expect_response(&cmd);
                if spec.requires_ack {
                    let _ =
                        timeout(Duration::from_secs(1), await_ack(stream, decoder, target)).await;
                }
                if let Some(done) = done {
                    let _ = done.send(());
                }
                return Ok(());
            }
        }
    }
}

/// The message as the connection's sender-side monitor passes it on; `None` (the message
/// is dropped, as C++ drops it) when the monitor refuses it.
fn monitored(m: &mut Monitor, msg: &Outgoing, target: &str) -> Option<Arc<Outgoing>> {
    // not sent at all (throttleDown), as C++'s output unit skips it
    if !m.accept(std::time::Instant::now()) {
        return None;
    }
    match m.update(msg.bottle()) {
        Ok(b) => Some(Arc::new(Outgoing::new(Arc::new(b), msg.stamp()))),
        Err(e) => {
            tracing::warn!("to {target}: message dropped: {e}");
            None
        }
    }
}

/// Consumes whatever complete events are buffered (unsolicited acks are harmless).
fn drain(decoder: &mut Decoder, target: &str) -> Result<(), OutputError> {
    while decoder
        .poll()
        .map_err(|source| OutputError::Protocol {
            target: target.to_string(),
            source,
        })?
        .is_some()
    {}
    Ok(())
}

/// Least room offered to one socket read. Reads go straight into the decoder's buffer,
/// which makes room for the whole of a frame once its size is known, so a large message
/// arrives in few system calls and is not copied on its way to its event.
pub(crate) const READ_CHUNK: usize = 64 * 1024;

pub(crate) async fn await_ack(
    stream: &mut TcpStream,
    decoder: &mut Decoder,
    target: &str,
) -> Result<(), OutputError> {
    let wait = async {
        loop {
            if let Event::Ack(_) = next_event(stream, decoder, target).await? {
                return Ok(());
            }
        }
    };
    timeout(ACK_TIMEOUT, wait)
        .await
        .map_err(|_| OutputError::AckTimeout(target.to_string(), ACK_TIMEOUT))?
}

pub(crate) async fn await_reply(
    stream: &mut TcpStream,
    decoder: &mut Decoder,
    target: &str,
    spec: CarrierSpec,
) -> Result<Bottle, PortError> {
    let mut reply = None;
    let mut undecodable = None;
    loop {
        match next_event(stream, decoder, target).await? {
            Event::Reply(bytes) => {
                // a reply that is no Bottle (a thrift server's protocol version) is the
                // caller's to read: its bytes travel in the error
                match Bottle::decode(&bytes) {
                    Ok(b) => reply = Some(b),
                    Err(error) => {
                        undecodable = Some(PortError::BadReply {
                            error,
                            bytes: bytes.clone(),
                        })
                    }
                }
                // the next large reply is read into the same (already mapped) memory
                decoder.recycle(bytes);
                if !spec.requires_ack {
                    break;
                }
            }
            Event::Line(text) if text.as_slice() != text_carrier::ACK_TEXT => {
                reply = Some(Bottle::from_text(&text));
                if !spec.requires_ack {
                    break;
                }
            }
            Event::Ack(_) => break,
            _ => {}
        }
    }
    if let Some(e) = undecodable {
        return Err(e);
    }
    // an acknowledgement without a reply: the receiver did not answer
    Ok(reply.unwrap_or_default())
}

/// Reads until the decoder produces an event, reading straight into the decoder's buffer
/// (no intermediate copy; a large frame is read into one allocation that becomes the
/// event's bytes).
pub(crate) async fn next_event(
    stream: &mut TcpStream,
    decoder: &mut Decoder,
    target: &str,
) -> Result<Event, OutputError> {
    loop {
        match decoder.poll() {
            Ok(Some(ev)) => return Ok(ev),
            Ok(None) => {}
            Err(source) => {
                return Err(OutputError::Protocol {
                    target: target.to_string(),
                    source,
                })
            }
        }
        let n = stream
            .read_buf(&mut decoder.read_buf(READ_CHUNK))
            .await
            .map_err(|source| OutputError::Io {
                target: target.to_string(),
                source,
            })?;
        if n == 0 {
            return Err(OutputError::PeerClosed(target.to_string()));
        }
    }
}
