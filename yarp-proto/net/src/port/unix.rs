//! The `unix_stream` carriers (C++ YARP's `unix` plugin): the connection starts on TCP
//! (`UNIX_STR` or `UNIX_ACK`, then the sender's name, no reply), both sides drop the TCP
//! stream, the receiver listens on `<runtime dir>/<receiver port>_<sender port>.sock`
//! (the two TCP port numbers of the handshake) and the sender connects there. Messages
//! then flow without an index ([`yarp_proto::wire::indexless`]); `unix_stream_ack`
//! receivers answer each with `ACK\0`. No replies travel back (C++ `supportReply` is
//! false), so RPC over this carrier is refused.
//!
//! This is the project's carrier between processes of one machine; `local` serves ports
//! of one process (see README, "shmem").

use super::input::InputEntry;
use super::output::{write_all_parts, Job, OutputError, OutputHandle};
use super::{Incoming, Shared, CONNECT_TIMEOUT, OUTPUT_QUEUE};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::{UnixListener, UnixStream};
use tokio::sync::{mpsc, Notify};
use tokio::time::timeout;
use yarp_proto::port_admin::Route;
use yarp_proto::wire::{
    self, Carrier, CommandKind, IndexlessDecoder, PortCommand, DEFAULT_MAX_MESSAGE_SIZE, UNIX_ACK,
};
use yarp_proto::Contact;

/// Where C++ YARP puts its Unix sockets: `$YARP_RUNTIME_DIR`, else
/// `$XDG_RUNTIME_DIR/yarp`, else `/tmp/runtime-$USER/yarp`.
pub fn runtime_dir() -> Option<PathBuf> {
    if let Some(d) = std::env::var_os("YARP_RUNTIME_DIR") {
        return Some(PathBuf::from(d));
    }
    if let Some(d) = std::env::var_os("XDG_RUNTIME_DIR") {
        return Some(PathBuf::from(d).join("yarp"));
    }
    let user = std::env::var("USER").ok()?;
    Some(PathBuf::from(format!("/tmp/runtime-{user}")).join("yarp"))
}

/// The socket of one connection, named by the receiver's and the sender's TCP ports.
pub fn socket_path(receiver_port: u16, sender_port: u16) -> Option<PathBuf> {
    Some(runtime_dir()?.join(format!("{receiver_port}_{sender_port}.sock")))
}

fn io_err(target: &str) -> impl Fn(std::io::Error) -> OutputError + '_ {
    move |source| OutputError::Io {
        target: target.to_string(),
        source,
    }
}

/// Opens an output connection to `target` over `unix_stream` / `unix_stream_ack`.
pub(crate) async fn connect(
    shared: &Arc<Shared>,
    target: &str,
    contact: &Contact,
    carrier: Carrier,
) -> Result<OutputHandle, OutputError> {
    let mut tcp = super::output::dial(target, contact).await?;
    let (local, remote) = (
        tcp.local_addr().map_err(io_err(target))?,
        tcp.peer_addr().map_err(io_err(target))?,
    );
    if local.ip() != remote.ip() && !(local.ip().is_loopback() && remote.ip().is_loopback()) {
        return Err(OutputError::UnsupportedCarrier(format!(
            "{} to {target}: the port is on another machine ({})",
            carrier.name(),
            remote.ip()
        )));
    }
    let path = socket_path(remote.port(), local.port()).ok_or_else(|| {
        OutputError::UnsupportedCarrier(format!("{}: no runtime directory", carrier.name()))
    })?;
    let hello = wire::encode_connection_start(&carrier.spec(), shared.name.as_bytes());
    tcp.write_all(&hello).await.map_err(io_err(target))?;
    // C++ tries 5 times 0.1 s apart while the receiver binds; we try for 2 s, 10 ms apart
    let deadline = tokio::time::Instant::now() + Duration::from_secs(2);
    let unix = loop {
        match UnixStream::connect(&path).await {
            Ok(s) => break s,
            Err(e) if tokio::time::Instant::now() >= deadline => {
                return Err(OutputError::Connect {
                    target: target.to_string(),
                    addr: path.display().to_string(),
                    source: e,
                })
            }
            Err(_) => tokio::time::sleep(Duration::from_millis(10)).await,
        }
    };
    drop(tcp);
    let route = Route::new(&shared.name, target, carrier.name());
    let (tx, rx) = mpsc::channel(OUTPUT_QUEUE);
    let task = tokio::spawn(run_output(
        target.to_string(),
        unix,
        carrier.spec().requires_ack,
        rx,
    ));
    Ok(OutputHandle::new(route, tx, task))
}

async fn run_output(target: String, mut s: UnixStream, ack: bool, mut rx: mpsc::Receiver<Job>) {
    while let Some(job) = rx.recv().await {
        match job {
            Job::Data(msg) => {
                let mut head = Vec::with_capacity(64);
                msg.command(false).encode_binary(&mut head);
                let segs = yarp_proto::binary::encode_segments(msg.bottle());
                let mut parts: Vec<&[u8]> = vec![&head];
                parts.extend(segs.iter().map(|p| p.as_ref()));
                if let Err(e) = write_all_parts(&mut s, &parts).await {
                    tracing::debug!("unix_stream output to {target} failed: {e}");
                    return;
                }
                if ack {
                    let mut buf = [0u8; 4];
                    match timeout(super::ACK_TIMEOUT, s.read_exact(&mut buf)).await {
                        Ok(Ok(_)) if &buf == UNIX_ACK => {}
                        _ => {
                            tracing::debug!("unix_stream_ack: no acknowledgement from {target}");
                            return;
                        }
                    }
                }
            }
            Job::Rpc(_, reply) => {
                let _ = reply.send(Err(OutputError::UnsupportedCarrier(
                    "rpc over unix_stream (it carries no replies)".to_string(),
                )
                .into()));
            }
            Job::Close(done) => {
                let mut q = Vec::new();
                PortCommand::close().encode_binary(&mut q);
                let _ = s.write_all(&q).await;
                let _ = s.shutdown().await;
                if let Some(done) = done {
                    let _ = done.send(());
                }
                return;
            }
        }
    }
}

/// Serves an incoming `unix_stream` connection whose TCP handshake just ended:
/// listens on the connection's socket, takes the sender, and delivers its messages.
pub(crate) async fn serve_input(
    shared: &Arc<Shared>,
    id: u64,
    kill: Arc<Notify>,
    from: String,
    carrier: Carrier,
    ports: (u16, u16),
) {
    let Some(path) = socket_path(ports.0, ports.1) else {
        tracing::warn!("{}: unix_stream: no runtime directory", shared.name);
        return;
    };
    if let Some(dir) = path.parent() {
        let _ = std::fs::create_dir_all(dir);
    }
    let _ = std::fs::remove_file(&path);
    let listener = match UnixListener::bind(&path) {
        Ok(l) => l,
        Err(e) => {
            tracing::warn!("{}: cannot listen on {}: {e}", shared.name, path.display());
            return;
        }
    };
    let accepted = timeout(CONNECT_TIMEOUT, listener.accept()).await;
    drop(listener);
    let _ = std::fs::remove_file(&path);
    let Ok(Ok((mut s, _))) = accepted else {
        tracing::debug!("{}: unix_stream sender {from} never came", shared.name);
        return;
    };
    shared.lock().inputs.insert(
        id,
        InputEntry::new(
            Route::new(&from, &shared.name, carrier.name()),
            kill.clone(),
        ),
    );
    let ack = carrier.spec().requires_ack;
    let mut decoder = IndexlessDecoder::new(DEFAULT_MAX_MESSAGE_SIZE);
    let mut shutdown = shared.shutdown.clone();
    let mut buf = vec![0u8; 64 * 1024];
    'conn: loop {
        let n = tokio::select! {
            _ = shutdown.changed() => break,
            _ = kill.notified() => break,
            n = s.read(&mut buf) => n,
        };
        let n = match n {
            Ok(0) | Err(_) => break,
            Ok(n) => n,
        };
        decoder.feed(&buf[..n]);
        loop {
            let m = match decoder.poll() {
                Ok(Some(m)) => m,
                Ok(None) => break,
                Err(e) => {
                    tracing::warn!("{}: bad unix_stream data from {from}: {e}", shared.name);
                    break 'conn;
                }
            };
            match m.command.kind() {
                CommandKind::Data { .. } => {
                    let incoming = Incoming {
                        stamp: m.stamp(),
                        payload: m.payload,
                        is_text: false,
                        from: from.clone(),
                        reply: None,
                        decoded: None,
                    };
                    if shared.deliver.send(incoming).await.is_err() {
                        break 'conn;
                    }
                }
                CommandKind::Close => break 'conn,
                _ => {}
            }
            if ack && s.write_all(UNIX_ACK).await.is_err() {
                break 'conn;
            }
        }
    }
    shared.lock().inputs.remove(&id);
}
