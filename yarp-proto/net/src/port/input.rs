//! Input side: accepting connections, reading the carrier header, and serving each
//! connection's messages (data to the owner, admin commands, text-mode commands).

use super::output::{self, next_event, write_all_parts, OutputError};
use super::{Incoming, ReplyBody, Shared};
use std::sync::Arc;
use std::time::Duration;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{oneshot, Notify};
use tokio::time::timeout;
use yarp_proto::port_admin::{
    self, add_output_text, format_add_result, format_del_result, handle_admin, remove_input_text,
    remove_output_text, AddOutcome, AdminAction, Pending, Route,
};
use yarp_proto::portmonitor::{Monitor, Side};
use yarp_proto::wire::datagram::McastGroup;
use yarp_proto::wire::modifiers::CarrierName;
use yarp_proto::wire::{
    self, text_carrier, Carrier, CarrierSpec, CommandKind, Decoder, DecoderConfig, Event, Framing,
    Message,
};
use yarp_proto::Bottle;

/// How long an input connection may go without a byte while it owes the rest of its
/// connection header or of a binary message (then it is closed).
pub const STALL_TIMEOUT: Duration = Duration::from_secs(20);
/// How long a new connection may stay silent before its header (the name server gives an
/// idle client as long).
pub const HEADER_TIMEOUT: Duration = Duration::from_secs(60);

/// An input connection as the port keeps it.
pub(crate) struct InputEntry {
    pub(crate) route: Route,
    kill: Arc<Notify>,
}

impl InputEntry {
    pub(crate) fn new(route: Route, kill: Arc<Notify>) -> InputEntry {
        InputEntry { route, kill }
    }

    /// Ends the connection.
    pub(crate) fn kill(&self) {
        self.kill.notify_one();
    }
}

pub(crate) async fn accept_loop(shared: Arc<Shared>, listener: TcpListener) {
    let mut shutdown = shared.shutdown.clone();
    loop {
        tokio::select! {
            _ = shutdown.changed() => return,
            accepted = listener.accept() => match accepted {
                Ok((stream, _)) => {
                    let _ = stream.set_nodelay(true);
                    tokio::spawn(serve_connection(shared.clone(), stream));
                }
                Err(e) => {
                    tracing::warn!("{}: accept failed: {e}", shared.name);
                    tokio::time::sleep(std::time::Duration::from_millis(50)).await;
                }
            }
        }
    }
}

/// What ended a connection's input loop.
enum End {
    Closed,
    Reversed(String, CarrierSpec),
    /// A udp connection's handshake: reply with a UDP port, then read datagrams.
    Udp,
    /// A mcast connection's handshake: join the group the sender named.
    Mcast(std::net::SocketAddrV4),
    /// An http request (its first bytes).
    Http(Vec<u8>),
    /// An mjpeg reader's request (its first bytes): the connection becomes an output.
    Mjpeg(Vec<u8>),
    /// A unix_stream handshake: continue on a Unix socket.
    Unix(Carrier),
    /// A shmem handshake: continue on shared memory.
    Shmem,
}

async fn serve_connection(shared: Arc<Shared>, mut stream: TcpStream) {
    // auth.conf: the peer proves it holds the key before anything else (C++ TcpFace::read).
    if crate::auth::accepted(&mut stream).await.is_err() {
        return;
    }
    // The two TCP ports name a unix_stream connection's socket. Taken now: once the
    // sender drops the TCP stream after its handshake, the peer's address may be gone.
    let tcp_ports = (
        stream.local_addr().map_or(0, |a| a.port()),
        stream.peer_addr().map_or(0, |a| a.port()),
    );
    let id = shared.next_id();
    let kill = Arc::new(Notify::new());
    let mut shutdown = shared.shutdown.clone();
    let mut conn = Conn {
        shared: &shared,
        id,
        kill: kill.clone(),
        decoder: Decoder::accepting(DecoderConfig::default()),
        spec: None,
        dgram: None,
        from: String::new(),
        monitor: None,
    };
    let end = tokio::select! {
        _ = shutdown.changed() => Ok(End::Closed),
        _ = kill.notified() => Ok(End::Closed),
        r = conn.run(&mut stream) => r,
    };
    let conn_name = conn.from.clone();
    drop(conn);
    shared.lock().inputs.remove(&id);
    match end {
        Ok(End::Reversed(peer, spec)) => {
            let handle = output::from_reversed(&shared, &peer, stream, spec);
            let oid = shared.next_id();
            shared.lock().outputs.insert(oid, handle);
        }
        Ok(End::Closed) => {
            let _ = stream.shutdown().await;
        }
        Ok(End::Http(head)) => super::http::serve(&shared, &mut stream, head).await,
        Ok(End::Mjpeg(head)) => super::mjpeg::serve_output(&shared, stream, head).await,
        Ok(End::Unix(carrier)) => {
            drop(stream);
            let from = conn_from(&conn_name);
            super::unix::serve_input(&shared, id, kill, from, carrier, tcp_ports).await;
        }
        Ok(End::Shmem) => {
            let from = conn_from(&conn_name);
            super::shmem::serve_input(&shared, id, kill, from, stream).await;
        }
        Ok(End::Udp) => {
            let local = stream.local_addr().map(|a| a.ip());
            match crate::dgram::udp_handshake_accept(&mut stream, unspecified(local)).await {
                Ok(rx) => {
                    let _ = stream.shutdown().await;
                    drop(stream);
                    datagram_input(&shared, id, kill, conn_from(&conn_name), "udp", rx).await;
                }
                Err(e) => tracing::debug!("{}: udp handshake failed: {e}", shared.name),
            }
        }
        Ok(End::Mcast(group)) => {
            let iface = match stream.local_addr().map(|a| a.ip()) {
                Ok(std::net::IpAddr::V4(ip)) => ip,
                _ => crate::dgram::DEFAULT_MCAST_INTERFACE,
            };
            let _ = stream.shutdown().await;
            drop(stream);
            match crate::dgram::McastReceiver::join(group, iface).await {
                Ok(rx) => {
                    let from = conn_from(&conn_name);
                    datagram_input(&shared, id, kill, from, "mcast", rx.into_inner()).await;
                }
                Err(e) => tracing::warn!("{}: cannot join {group}: {e}", shared.name),
            }
        }
        Err(e) => {
            tracing::debug!("{}: input connection ended: {e}", shared.name);
            let _ = stream.shutdown().await;
        }
    }
}

struct Conn<'a> {
    shared: &'a Arc<Shared>,
    id: u64,
    kill: Arc<Notify>,
    decoder: Decoder,
    spec: Option<CarrierSpec>,
    /// The connection is the TCP handshake of a datagram carrier.
    dgram: Option<Carrier>,
    from: String,
    /// The monitor the sender's qualifiers ask of this side (`+recv.portmonitor`).
    monitor: Option<Monitor>,
}

impl Conn<'_> {
    async fn run(&mut self, stream: &mut TcpStream) -> Result<End, OutputError> {
        loop {
            let ev = match self.next_event(stream).await {
                Ok(ev) => ev,
                Err(OutputError::PeerClosed(_)) => return Ok(End::Closed),
                Err(e) => return Err(e),
            };
            match ev {
                Event::Header(h) => {
                    let spec = h.carrier().spec();
                    match h.carrier() {
                        Carrier::Udp
                        | Carrier::Mcast
                        | Carrier::UnixStream
                        | Carrier::UnixStreamAck
                        | Carrier::Shmem => {
                            self.dgram = Some(h.carrier());
                            self.spec = Some(spec);
                            continue;
                        }
                        Carrier::Http | Carrier::Mjpeg => {
                            // the rest of the request may already sit in the decoder
                            let mut head = h.raw.to_vec();
                            while let Ok(Some(Event::Raw(more))) = self.decoder.poll() {
                                head.extend_from_slice(&more);
                            }
                            return Ok(if h.carrier() == Carrier::Mjpeg {
                                End::Mjpeg(head)
                            } else {
                                End::Http(head)
                            });
                        }
                        _ => {}
                    }
                    if !matches!(spec.framing, Framing::Stream | Framing::Text) {
                        // udp/mcast/shmem/local handshakes, http, name-server lines:
                        // not served by ports yet
                        tracing::debug!(
                            "{}: carrier {} not supported on input",
                            self.shared.name,
                            spec.carrier
                        );
                        return Ok(End::Closed);
                    }
                    self.spec = Some(spec);
                }
                Event::SenderName(name) => {
                    // `/port (recv portmonitor) (file ...)`: the port, and the carrier's
                    // qualifiers (C++ Protocol::setRoute)
                    let sender = String::from_utf8_lossy(&name).into_owned();
                    let base = self.spec.map_or("tcp", |s| s.carrier.name());
                    let (port, carrier) = CarrierName::from_sender_specifier(base, &sender);
                    self.from = port;
                    if carrier.has_qualifiers() {
                        match Monitor::for_side(&carrier, Side::Receiver) {
                            Ok(m) => self.monitor = m,
                            Err(e) => {
                                tracing::warn!(
                                    "{}: connection from {} refused: {e}",
                                    self.shared.name,
                                    self.from
                                );
                                return Ok(End::Closed);
                            }
                        }
                    }
                    if self.dgram.is_some() && carrier.has_qualifiers() {
                        tracing::warn!(
                            "{}: connection from {} refused: carrier {carrier}: qualifiers are supported on tcp, fast_tcp and text connections",
                            self.shared.name,
                            self.from
                        );
                        return Ok(End::Closed);
                    }
                    match self.dgram {
                        Some(Carrier::Udp) => return Ok(End::Udp),
                        Some(c @ (Carrier::UnixStream | Carrier::UnixStreamAck)) => {
                            return Ok(End::Unix(c))
                        }
                        Some(Carrier::Shmem) => return Ok(End::Shmem),
                        Some(_) => return self.mcast_group(stream).await,
                        None => {}
                    }
                    let Some(spec) = self.spec else {
                        return Ok(End::Closed);
                    };
                    let greeting = match spec.framing {
                        Framing::Text => text_carrier::welcome_line(&name),
                        _ => wire::encode_header_reply(self.shared.contact.port as i32).to_vec(),
                    };
                    write(stream, &greeting, &self.from).await?;
                    self.shared.lock().inputs.insert(
                        self.id,
                        InputEntry {
                            route: Route::new(&self.from, &self.shared.name, &carrier.to_string()),
                            kill: self.kill.clone(),
                        },
                    );
                }
                Event::Message(m) => {
                    if let Some(end) = self.message(stream, m).await? {
                        return Ok(end);
                    }
                }
                Event::InvalidMessage { error, .. } => {
                    // C++ skips it without an acknowledgement
                    tracing::warn!(
                        "{}: bad message from {}: {error}",
                        self.shared.name,
                        self.from
                    );
                }
                _ => {}
            }
        }
    }

    /// The next event, reading as needed. While the peer owes the rest of something (its
    /// connection header, or a binary message it has begun) each read may wait at most
    /// [`STALL_TIMEOUT`], and a connection that sends nothing at all gets
    /// [`HEADER_TIMEOUT`] for its header: a peer that sends half a message and hangs does
    /// not hold the connection for ever. Between messages, and inside the messages of a
    /// text connection (a person typing), the wait is as long as C++'s: unbounded.
    async fn next_event(&mut self, stream: &mut TcpStream) -> Result<Event, OutputError> {
        loop {
            match self.decoder.poll() {
                Ok(Some(ev)) => return Ok(ev),
                Ok(None) => {}
                Err(source) => {
                    return Err(OutputError::Protocol {
                        target: self.from.clone(),
                        source,
                    })
                }
            }
            let begun = !self.decoder.is_idle();
            let limit = match self.spec {
                None if begun => Some(STALL_TIMEOUT),
                None => Some(HEADER_TIMEOUT),
                Some(_) if begun && !self.is_text() => Some(STALL_TIMEOUT),
                Some(_) => None,
            };
            let mut space = self.decoder.read_buf(output::READ_CHUNK);
            let read = stream.read_buf(&mut space);
            let n = if let Some(limit) = limit {
                timeout(limit, read)
                    .await
                    .map_err(|_| OutputError::Stalled(self.from.clone(), limit))?
            } else {
                read.await
            }
            .map_err(|source| OutputError::Io {
                target: self.from.clone(),
                source,
            })?;
            if n == 0 {
                return Err(OutputError::PeerClosed(self.from.clone()));
            }
        }
    }

    fn is_text(&self) -> bool {
        self.spec.is_some_and(|s| s.framing == Framing::Text)
    }

    /// The acknowledgement bytes, if the carrier wants one.
    fn ack_bytes(&self) -> Option<&'static [u8]> {
        const ACK: &[u8] = &wire::number::ACK;
        match self.spec {
            Some(s) if s.requires_ack => Some(if s.framing == Framing::Text {
                text_carrier::ACK_LINE
            } else {
                ACK
            }),
            _ => None,
        }
    }

    /// Writes the acknowledgement if the carrier wants one.
    async fn ack(&self, stream: &mut TcpStream) -> Result<(), OutputError> {
        match self.ack_bytes() {
            Some(bytes) => write(stream, bytes, &self.from).await,
            None => Ok(()),
        }
    }

    /// Writes a reply followed by the acknowledgement (if any) in one go.
    async fn reply_and_ack(&self, stream: &mut TcpStream, reply: &[u8]) -> Result<(), OutputError> {
        let ack = self.ack_bytes().unwrap_or_default();
        write_all_parts(stream, &[reply, ack])
            .await
            .map_err(|source| OutputError::Io {
                target: self.from.clone(),
                source,
            })
    }

    async fn message(
        &mut self,
        stream: &mut TcpStream,
        m: Message,
    ) -> Result<Option<End>, OutputError> {
        let text = self.is_text();
        match m.command.kind() {
            CommandKind::Data { reply } => {
                // C++ answers a `d` whenever the owner replies, also on plain text
                // connections (the paper's telnet session: CONNECT, d, [get] [axes])
                let wants_reply = reply
                    && self
                        .spec
                        .is_some_and(|s| s.supports_reply || s.framing == Framing::Text);
                let (tx, rx) = if wants_reply {
                    let (tx, rx) = oneshot::channel();
                    (Some(tx), Some(rx))
                } else {
                    (None, None)
                };
                let stamp = m.stamp();
                // read, then dropped (throttleDown), as C++ skips the incoming data
                let accepted = self
                    .monitor
                    .as_mut()
                    .is_none_or(|m| m.accept(std::time::Instant::now()));
                if !accepted {
                    self.ack(stream).await?;
                    return Ok(None);
                }
                let (payload, is_text) = match &self.monitor {
                    Some(monitor) => {
                        let b = if text {
                            Ok(Bottle::from_text(&m.payload))
                        } else {
                            Bottle::decode(&m.payload).map_err(|e| e.to_string())
                        };
                        match b.and_then(|b| monitor.update(&b).map_err(|e| e.to_string())) {
                            Ok(b) => (b.encode(), false),
                            Err(e) => {
                                // C++ drops what its monitor does not accept
                                tracing::warn!(
                                    "{}: message from {} dropped: {e}",
                                    self.shared.name,
                                    self.from
                                );
                                self.ack(stream).await?;
                                return Ok(None);
                            }
                        }
                    }
                    None => (m.payload, text),
                };
                let incoming = Incoming {
                    stamp,
                    payload,
                    is_text,
                    from: self.from.clone(),
                    reply: tx,
                    decoded: None,
                };
                if self.shared.deliver.send(incoming).await.is_err() {
                    return Ok(Some(End::Closed));
                }
                let reply = match rx {
                    Some(rx) => rx.await.ok(),
                    None => None,
                };
                match reply {
                    Some(ReplyBody::Responder(b)) if text => {
                        self.reply_and_ack(stream, &port_admin::responder_text_lines(&b))
                            .await?;
                    }
                    Some(b) if text => {
                        let b = b.into_bottle();
                        self.reply_and_ack(stream, &port_admin::reply_text_line(&b))
                            .await?;
                    }
                    Some(ReplyBody::Encoded(bytes)) => {
                        let parts: [&[u8]; 2] = [&bytes, self.ack_bytes().unwrap_or_default()];
                        write_all_parts(stream, &parts).await.map_err(|source| {
                            OutputError::Io {
                                target: self.from.clone(),
                                source,
                            }
                        })?;
                    }
                    Some(ReplyBody::Bottle(b) | ReplyBody::Responder(b)) => {
                        // large blobs in the reply go out straight from the Bottle
                        let segs = yarp_proto::binary::encode_segments(&b);
                        let mut parts: Vec<&[u8]> = segs.iter().map(|s| s.as_ref()).collect();
                        parts.push(self.ack_bytes().unwrap_or_default());
                        write_all_parts(stream, &parts).await.map_err(|source| {
                            OutputError::Io {
                                target: self.from.clone(),
                                source,
                            }
                        })?;
                    }
                    None => self.ack(stream).await?,
                }
            }
            CommandKind::Admin => {
                let cmd = if text {
                    Bottle::from_text(&m.payload)
                } else {
                    Bottle::decode(&m.payload).unwrap_or_default()
                };
                let reply = self.admin(&cmd).await;
                let bytes = if text {
                    port_admin::reply_text_line(&reply)
                } else {
                    reply.encode()
                };
                write(stream, &bytes, &self.from).await?;
                self.ack(stream).await?;
            }
            CommandKind::Close => {
                self.ack(stream).await?;
                return Ok(Some(End::Closed));
            }
            CommandKind::Describe => {
                let snap = self.shared.snapshot();
                if text {
                    write(stream, port_admin::describe(&snap).as_bytes(), &self.from).await?;
                } else {
                    // over binary connections C++ prints the description on the owner's stdout
                    print!("{}", port_admin::describe_for_stdout(&snap));
                }
                self.ack(stream).await?;
            }
            CommandKind::Help => {
                if text {
                    write(stream, port_admin::help_text().as_bytes(), &self.from).await?;
                }
                self.ack(stream).await?;
            }
            CommandKind::Reverse => {
                self.ack(stream).await?;
                let Some(spec) = self.spec else {
                    return Ok(Some(End::Closed));
                };
                return Ok(Some(End::Reversed(self.from.clone(), spec)));
            }
            CommandKind::AddOutput(dest) => {
                let dest = String::from_utf8_lossy(&dest).into_owned();
                let outcome = self.add_output(&dest).await;
                if text {
                    let line = add_output_text(&self.shared.name, &dest, &outcome);
                    write(stream, line.as_bytes(), &self.from).await?;
                }
                self.ack(stream).await?;
            }
            CommandKind::RemoveOutput(dest) => {
                let dest = String::from_utf8_lossy(&dest).into_owned();
                let removed = self.shared.remove_output(&dest);
                if text {
                    let line = remove_output_text(&self.shared.name, &dest, removed);
                    write(stream, line.as_bytes(), &self.from).await?;
                }
                self.ack(stream).await?;
            }
            CommandKind::RemoveInput(src) => {
                let src = String::from_utf8_lossy(&src).into_owned();
                let removed = self.remove_input(&src);
                if text {
                    let line = remove_input_text(&self.shared.name, &src, removed);
                    write(stream, line.as_bytes(), &self.from).await?;
                }
                self.ack(stream).await?;
            }
            _ => {
                if text {
                    let t = port_admin::NOT_UNDERSTOOD_TEXT;
                    write(stream, t.as_bytes(), &self.from).await?;
                }
                self.ack(stream).await?;
            }
        }
        Ok(None)
    }

    async fn add_output(&self, dest: &str) -> AddOutcome {
        match self.shared.add_output(dest, None).await {
            Ok(()) => AddOutcome::Added { note: None },
            Err(super::PortError::UnknownPort(_)) => AddOutcome::UnknownTarget,
            Err(e) => {
                tracing::info!("{}: cannot connect to {dest}: {e}", self.shared.name);
                AddOutcome::CannotConnect
            }
        }
    }

    /// Closes every input coming from `src` (other than this admin connection itself).
    fn remove_input(&self, src: &str) -> bool {
        let st = self.shared.lock();
        let mut any = false;
        for (id, e) in st.inputs.iter() {
            if e.route.from == src {
                any = true;
                if *id != self.id {
                    e.kill.notify_one();
                }
            }
        }
        any
    }

    /// Runs an admin Bottle through the protocol and carries out its actions.
    async fn admin(&self, cmd: &Bottle) -> Bottle {
        let resp = handle_admin(cmd, &self.shared.snapshot());
        let mut reply = resp.reply;
        let mut add_outcome = None;
        let (mut removed_out, mut removed_in) = (false, false);
        for action in resp.actions {
            match action {
                AdminAction::AddOutput { dest, target } => {
                    // C++ replaces an existing connection to the same port
                    self.shared.remove_output(&target.name);
                    let outcome = match self
                        .shared
                        .add_output(&target.name, target.carrier.as_deref())
                        .await
                    {
                        Ok(()) => AddOutcome::Added { note: None },
                        Err(super::PortError::UnknownPort(_)) => AddOutcome::UnknownTarget,
                        Err(e) => {
                            // the reply says only "Cannot connect"; C++ tells why on the
                            // port's own stderr
                            tracing::warn!("{}: {e}", self.shared.name);
                            AddOutcome::CannotConnect
                        }
                    };
                    add_outcome = Some((dest, outcome));
                }
                AdminAction::RemoveOutput { to } => {
                    removed_out |= self.shared.remove_output(&to);
                }
                AdminAction::RemoveInput { from } => {
                    removed_in |= self.remove_input(&from);
                }
                AdminAction::SetProperty { key, value } => {
                    self.shared.lock().properties.insert(key, value);
                }
                _ => {}
            }
        }
        match resp.pending {
            Pending::Add { dest } => {
                if let Some((_, outcome)) = &add_outcome {
                    reply = format_add_result(&self.shared.name, &dest, outcome);
                }
            }
            Pending::Del { dest } => {
                reply = format_del_result(&self.shared.name, &dest, removed_out, removed_in);
            }
            _ => {}
        }
        reply
    }
}

async fn write(stream: &mut TcpStream, bytes: &[u8], peer: &str) -> Result<(), OutputError> {
    stream
        .write_all(bytes)
        .await
        .map_err(|source| OutputError::Io {
            target: peer.to_string(),
            source,
        })
}

impl Conn<'_> {
    /// Reads the 6 bytes a mcast sender puts after its name: the group address and port.
    async fn mcast_group(&mut self, stream: &mut TcpStream) -> Result<End, OutputError> {
        let mut got = Vec::with_capacity(6);
        while got.len() < 6 {
            match next_event(stream, &mut self.decoder, &self.from).await? {
                Event::Raw(bytes) => got.extend_from_slice(&bytes),
                _ => return Ok(End::Closed),
            }
        }
        let mut six = [0u8; 6];
        six.copy_from_slice(&got[..6]);
        Ok(End::Mcast(McastGroup::decode(&six).addr()))
    }
}

fn conn_from(name: &str) -> String {
    name.to_string()
}

/// Where to bind the UDP socket of an incoming udp connection (C++ binds all interfaces).
fn unspecified(_local: std::io::Result<std::net::IpAddr>) -> std::net::IpAddr {
    std::net::IpAddr::V4(std::net::Ipv4Addr::UNSPECIFIED)
}

/// Serves an incoming udp/mcast connection: its messages go to the owner (no replies, no
/// acknowledgements) until the sender removes it (`~/sender`), or the port closes.
async fn datagram_input(
    shared: &Arc<Shared>,
    id: u64,
    kill: Arc<Notify>,
    from: String,
    carrier: &str,
    mut rx: crate::dgram::UdpReceiver,
) {
    shared.lock().inputs.insert(
        id,
        InputEntry {
            route: Route::new(&from, &shared.name, carrier),
            kill: kill.clone(),
        },
    );
    let mut shutdown = shared.shutdown.clone();
    loop {
        let m = tokio::select! {
            _ = shutdown.changed() => break,
            _ = kill.notified() => break,
            m = rx.recv() => m,
        };
        let Ok(m) = m else { break };
        if !matches!(m.command.kind(), CommandKind::Data { .. }) {
            continue;
        }
        let incoming = Incoming {
            stamp: m.stamp(),
            payload: m.payload,
            is_text: false,
            from: from.clone(),
            reply: None,
            decoded: None,
        };
        if shared.deliver.send(incoming).await.is_err() {
            break;
        }
    }
    shared.lock().inputs.remove(&id);
}
