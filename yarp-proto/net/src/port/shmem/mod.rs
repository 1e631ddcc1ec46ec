//! The `shmem` carrier, interoperable with C++ YARP's plugin: the handshake on TCP (see
//! [`yarp_proto::wire::shmem`]), then the tcp-family protocol (index, blocks,
//! acknowledgements, replies) through two shared-memory rings, one per direction. A reader
//! with nothing to read waits in the event loop for the doorbell when the peer is ours,
//! and on the C++ wait-data mutex (on a blocking thread) otherwise.
//!
//! What we create is removed as soon as the peer has it: our segments are marked for
//! removal once the peer attached them (the kernel frees them with the last process),
//! the peer's once we attached them, and our mutex files when the connection ends.

mod ring;
mod sys;

use super::input::InputEntry;
use super::output::{Job, Outgoing, OutputError, OutputHandle, READ_CHUNK};
use super::{Incoming, ReplyBody, Shared, CONNECT_TIMEOUT, OUTPUT_QUEUE};
use bytes::BufMut;
use ring::{gone, Liveness, RingReader, RingWriter, POLL};
use std::io;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{mpsc, Notify};
use tokio::time::timeout;
use yarp_proto::port_admin::Route;
use yarp_proto::wire::shmem::{command, Packet, DEFAULT_RING_SIZE, PACKET_LEN};
use yarp_proto::wire::{
    self, Carrier, CarrierSpec, CommandKind, Decoder, DecoderConfig, Event, Framing, PortCommand,
    YarpNumber,
};
use yarp_proto::{Bottle, Contact};

/// Where ACE puts the mutex files: `$TMPDIR` or `/tmp`, with a `/` appended
/// (`ACE::get_temp_dir`).
pub fn temp_dir() -> String {
    let base = std::env::var("TMPDIR").unwrap_or_else(|_| "/tmp".to_string());
    format!("{base}/")
}

/// The tcp-family framing that runs over the rings once the handshake is done.
fn stream_spec() -> CarrierSpec {
    CarrierSpec {
        framing: Framing::Stream,
        ..Carrier::Shmem.spec()
    }
}

/// Both rings of a connection and its side channel.
struct Link {
    out: RingWriter,
    inp: RingReader,
    live: Liveness,
}

impl Link {
    fn write(&mut self, parts: &[&[u8]]) -> io::Result<()> {
        self.out.write(parts, &self.live)
    }

    /// Reads into the decoder until it has an event.
    async fn next_event(&mut self, decoder: &mut Decoder) -> io::Result<Event> {
        loop {
            match decoder.poll() {
                Ok(Some(ev)) => return Ok(ev),
                Ok(None) => {}
                Err(e) => return Err(io::Error::new(io::ErrorKind::InvalidData, e)),
            }
            loop {
                let mut space = decoder.read_buf(READ_CHUNK);
                let chunk = space.chunk_mut();
                let (ptr, len) = (chunk.as_mut_ptr(), chunk.len());
                // SAFETY: `chunk` is the decoder's spare capacity, `len` bytes long;
                // exactly the `n` bytes written are then declared initialised.
                let got = unsafe {
                    let got = self.inp.try_read(ptr, len, true, &self.live)?;
                    if let Some(n) = got {
                        space.advance_mut(n);
                    }
                    got
                };
                if got.is_some() {
                    break;
                }
                self.wait().await?;
            }
        }
    }

    /// Waits (bounded) until the writer may have written, then checks the peer is there.
    async fn wait(&mut self) -> io::Result<()> {
        if self.live.doorbell() {
            if let Ok(ready) = timeout(POLL, self.live.sock.readable()).await {
                ready?;
                let mut bells = [0u8; 64];
                match self.live.sock.try_read(&mut bells) {
                    Ok(0) => return Err(gone()),
                    Ok(_) => {}
                    Err(e) if e.kind() == io::ErrorKind::WouldBlock => {}
                    Err(e) => return Err(e),
                }
            }
        } else {
            let waitdata = self.inp.waitdata();
            tokio::task::spawn_blocking(move || waitdata.lock_for(POLL))
                .await
                .map_err(io::Error::other)??;
        }
        self.live.check()
    }

    fn close(&mut self) {
        self.out.close();
        self.inp.close();
    }
}

fn is_local(local: &std::net::SocketAddr, remote: &std::net::SocketAddr) -> bool {
    local.ip() == remote.ip() || (local.ip().is_loopback() && remote.ip().is_loopback())
}

async fn read_packet(s: &mut TcpStream) -> io::Result<Packet> {
    let mut b = [0u8; PACKET_LEN];
    timeout(CONNECT_TIMEOUT, s.read_exact(&mut b))
        .await
        .map_err(|_| io::Error::new(io::ErrorKind::TimedOut, "no shmem handshake packet"))??;
    Ok(Packet::decode(&b))
}

/// Opens an output connection to `target` over `shmem` (we are the sender).
pub(crate) async fn connect(
    shared: &Arc<Shared>,
    target: &str,
    contact: &Contact,
) -> Result<OutputHandle, OutputError> {
    let io_err = |source| OutputError::Io {
        target: target.to_string(),
        source,
    };
    let mut tcp = super::output::dial(target, contact).await?;
    let (local, remote) = (
        tcp.local_addr().map_err(io_err)?,
        tcp.peer_addr().map_err(io_err)?,
    );
    if !is_local(&local, &remote) {
        return Err(OutputError::UnsupportedCarrier(format!(
            "shmem to {target}: the port is on another machine ({})",
            remote.ip()
        )));
    }
    let hello = wire::encode_connection_start(&Carrier::Shmem.spec(), shared.name.as_bytes());
    tcp.write_all(&hello).await.map_err(io_err)?;
    // the receiver answers with the port of its side channel, where tcp sends its own
    let mut reply = [0u8; 8];
    timeout(CONNECT_TIMEOUT, tcp.read_exact(&mut reply))
        .await
        .map_err(|_| OutputError::HandshakeTimeout {
            target: target.to_string(),
        })?
        .map_err(io_err)?;
    let alt = YarpNumber::decode(&reply)
        .map(|n| n.0)
        .filter(|p| (1..=65535).contains(p))
        .ok_or_else(|| OutputError::Unexpected {
            target: target.to_string(),
            what: format!("{reply:02x?} (no shmem port)"),
        })?;
    drop(tcp);
    let side_addr = std::net::SocketAddr::new(local.ip(), alt as u16);
    let mut side = timeout(CONNECT_TIMEOUT, TcpStream::connect(side_addr))
        .await
        .map_err(|_| OutputError::HandshakeTimeout {
            target: target.to_string(),
        })?
        .map_err(|source| OutputError::Connect {
            target: target.to_string(),
            addr: side_addr.to_string(),
            source,
        })?;
    let _ = side.set_nodelay(true);
    let my_port = side.local_addr().map_err(io_err)?.port();
    let peer_port = side.peer_addr().map_err(io_err)?.port();
    let temp = temp_dir();
    let out = RingWriter::create(&temp, my_port, DEFAULT_RING_SIZE).map_err(io_err)?;
    side.write_all(&Packet::connect(true).encode())
        .await
        .map_err(io_err)?;
    let ack = read_packet(&mut side).await.map_err(io_err)?;
    if ack.command != command::ACKNOWLEDGE {
        return Err(OutputError::Unexpected {
            target: target.to_string(),
            what: format!("shmem packet {ack:?}"),
        });
    }
    let inp = RingReader::open(&temp, peer_port).map_err(io_err)?;
    let stop = Arc::new(AtomicBool::new(false));
    let live = Liveness::new(side, stop.clone(), ack.doorbell());
    let link = Link { out, inp, live };
    let route = Route::new(&shared.name, target, "shmem");
    let (tx, rx) = mpsc::channel(OUTPUT_QUEUE);
    let port = Arc::downgrade(shared);
    let target = target.to_string();
    let task = tokio::spawn(async move {
        let _stop_on_exit = StopOnDrop(stop);
        let result = run_output(&target, link, rx).await;
        if let Err(e) = &result {
            tracing::debug!("shmem output to {target} ended: {e}");
            if let Some(shared) = port.upgrade() {
                shared
                    .lock()
                    .outputs
                    .retain(|_, o| !(o.route.to == target && o.route.carrier == "shmem"));
            }
        }
    });
    Ok(OutputHandle::new(route, tx, task))
}

struct StopOnDrop(Arc<AtomicBool>);

impl Drop for StopOnDrop {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Relaxed);
    }
}

async fn run_output(target: &str, mut link: Link, mut rx: mpsc::Receiver<Job>) -> io::Result<()> {
    let spec = stream_spec();
    let mut decoder = Decoder::responses(spec, DecoderConfig::default());
    let result = async {
        while let Some(job) = rx.recv().await {
            match job {
                Job::Data(msg) => {
                    let cmd = msg.command(false);
                    write_message(&mut link, &msg, &cmd)?;
                    decoder.expect_response(&cmd);
                    await_ack(&mut link, &mut decoder).await?;
                }
                Job::Rpc(msg, reply_tx) => {
                    let cmd = msg.command(true);
                    write_message(&mut link, &msg, &cmd)?;
                    decoder.expect_response(&cmd);
                    match await_reply(&mut link, &mut decoder).await {
                        Ok(b) => {
                            let _ = reply_tx.send(Ok(b));
                        }
                        Err(e) => {
                            let _ = reply_tx.send(Err(OutputError::Io {
                                target: target.to_string(),
                                source: io::Error::new(e.kind(), e.to_string()),
                            }
                            .into()));
                            return Err(e);
                        }
                    }
                }
                Job::Close(done) => {
                    let _ = link.write(&[&wire::close_message()]);
                    decoder.expect_response(&PortCommand::close());
                    let _ =
                        timeout(Duration::from_secs(1), await_ack(&mut link, &mut decoder)).await;
                    if let Some(done) = done {
                        let _ = done.send(());
                    }
                    return Ok(());
                }
            }
        }
        Ok(())
    }
    .await;
    link.close();
    result
}

fn write_message(link: &mut Link, msg: &Outgoing, cmd: &PortCommand) -> io::Result<()> {
    msg.with_binary_parts(cmd, |parts| link.write(parts))
}

async fn await_ack(link: &mut Link, decoder: &mut Decoder) -> io::Result<()> {
    loop {
        if let Event::Ack(_) = link.next_event(decoder).await? {
            return Ok(());
        }
    }
}

async fn await_reply(link: &mut Link, decoder: &mut Decoder) -> io::Result<Bottle> {
    let mut reply = None;
    loop {
        match link.next_event(decoder).await? {
            Event::Reply(bytes) => {
                reply = Some(
                    Bottle::decode(&bytes)
                        .map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e))?,
                );
                decoder.recycle(bytes);
            }
            Event::Ack(_) => return Ok(reply.unwrap_or_default()),
            _ => {}
        }
    }
}

/// Serves an incoming `shmem` connection whose header and sender name were read on
/// `stream` (we are the receiver).
pub(crate) async fn serve_input(
    shared: &Arc<Shared>,
    id: u64,
    kill: Arc<Notify>,
    from: String,
    mut stream: TcpStream,
) {
    if let Err(e) = accept(shared, id, kill, from.clone(), &mut stream).await {
        tracing::warn!("{}: shmem connection from {from} failed: {e}", shared.name);
    }
}

async fn accept(
    shared: &Arc<Shared>,
    id: u64,
    kill: Arc<Notify>,
    from: String,
    stream: &mut TcpStream,
) -> io::Result<()> {
    let (local, remote) = (stream.local_addr()?, stream.peer_addr()?);
    if !is_local(&local, &remote) {
        return Err(io::Error::new(
            io::ErrorKind::Unsupported,
            format!("the sender is on another machine ({})", remote.ip()),
        ));
    }
    // C++ listens on every interface, on a port of the system's choosing
    let listener = TcpListener::bind(("0.0.0.0", 0)).await?;
    let alt = listener.local_addr()?.port();
    stream
        .write_all(&wire::encode_header_reply(i32::from(alt)))
        .await?;
    let (mut side, _) = timeout(CONNECT_TIMEOUT, listener.accept())
        .await
        .map_err(|_| io::Error::new(io::ErrorKind::TimedOut, "the sender never came back"))??;
    drop(listener);
    let _ = stream.shutdown().await;
    let _ = side.set_nodelay(true);
    let hello = read_packet(&mut side).await?;
    if hello.command != command::CONNECT {
        return Err(io::Error::new(
            io::ErrorKind::InvalidData,
            format!("unexpected shmem packet {hello:?}"),
        ));
    }
    let my_port = side.local_addr()?.port();
    let peer_port = side.peer_addr()?.port();
    let temp = temp_dir();
    let inp = RingReader::open(&temp, peer_port)?;
    let out = RingWriter::create(&temp, my_port, DEFAULT_RING_SIZE)?;
    let doorbell = hello.doorbell();
    side.write_all(&Packet::acknowledge(doorbell).encode())
        .await?;
    let stop = Arc::new(AtomicBool::new(false));
    let live = Liveness::new(side, stop.clone(), doorbell);
    let link = Link { out, inp, live };
    shared.lock().inputs.insert(
        id,
        InputEntry::new(Route::new(&from, &shared.name, "shmem"), kill.clone()),
    );
    // the port's shutdown or a removal of this input stops the thread
    let mut shutdown = shared.shutdown.clone();
    let watcher = {
        let stop = stop.clone();
        tokio::spawn(async move {
            tokio::select! {
                _ = shutdown.changed() => {}
                _ = kill.notified() => {}
            }
            stop.store(true, Ordering::Relaxed);
        })
    };
    let result = run_input(shared, &from, link).await;
    watcher.abort();
    shared.lock().inputs.remove(&id);
    result
}

async fn run_input(shared: &Arc<Shared>, from: &str, mut link: Link) -> io::Result<()> {
    let mut decoder = Decoder::messages(stream_spec(), DecoderConfig::default());
    let ack = wire::ack();
    let result = async {
        loop {
            let m = match link.next_event(&mut decoder).await? {
                Event::Message(m) => m,
                Event::InvalidMessage { error, .. } => {
                    tracing::warn!("{}: bad message from {from}: {error}", shared.name);
                    continue;
                }
                _ => continue,
            };
            match m.command.kind() {
                CommandKind::Data { reply } => {
                    let (tx, rx) = if reply {
                        let (tx, rx) = tokio::sync::oneshot::channel();
                        (Some(tx), Some(rx))
                    } else {
                        (None, None)
                    };
                    let incoming = Incoming {
                        stamp: m.stamp(),
                        payload: m.payload,
                        is_text: false,
                        from: from.to_string(),
                        reply: tx,
                        decoded: None,
                    };
                    if shared.deliver.send(incoming).await.is_err() {
                        return Ok(());
                    }
                    let reply = match rx {
                        Some(rx) => rx.await.ok(),
                        None => None,
                    };
                    match reply {
                        Some(ReplyBody::Encoded(bytes)) => link.write(&[&bytes, &ack])?,
                        Some(ReplyBody::Bottle(b) | ReplyBody::Responder(b)) => {
                            let segs = yarp_proto::binary::encode_segments(&b);
                            let mut parts: Vec<&[u8]> = segs.iter().map(|s| s.as_ref()).collect();
                            parts.push(&ack);
                            link.write(&parts)?;
                        }
                        None => link.write(&[&ack])?,
                    }
                }
                CommandKind::Close => {
                    link.write(&[&ack])?;
                    return Ok(());
                }
                _ => {
                    // administrative commands are served on tcp connections; here they are
                    // only acknowledged
                    tracing::debug!("{}: shmem command from {from} ignored", shared.name);
                    link.write(&[&ack])?;
                }
            }
        }
    }
    .await;
    link.close();
    result
}
