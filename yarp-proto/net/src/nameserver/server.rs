//! The name server: accepts the connection kinds C++ `yarpserver` 3.12 accepts and runs
//! each command through a shared [`Registry`].
//!
//! What a connection may start with (its first 8 bytes):
//! * `NAME_SER`: the C++ client's `NAME_SERVER <cmd>` lines. The 4 bytes after the header
//!   (`VER `) are skipped, then a line is read; for every further command the first 12
//!   bytes (`NAME_SERVER `) are skipped. Each command gets its text reply; the connection
//!   stays open until the client closes it (the C++ client closes after the reply).
//! * `CONNECT ` / `CONNACK `: text carrier. `Welcome <name>\r\n`, then pairs of a port
//!   command line and a command line. `d` wants a reply, `D` does not; with `CONNACK`
//!   `<ACK>\r\n` follows every data message. `q` or any other port command closes.
//! * a YARP number (`YA....RP`) of the tcp family: sender name, header reply carrying the
//!   advertised port, then indexed messages. Data messages (`~d` / `~D`) hold a binary
//!   command Bottle; the reply (`~d` only) is written without index, then the ack for
//!   `tcp`. Admin (`~a`) messages are acked but not answered. The tcp framing is the
//!   shared `yarp_proto::wire` decoder's, as for ports.
//! * anything else gets C++'s "Protocol not found" text and is closed (this includes
//!   HTTP: the web pages of `yarpserver` are not served).
//!
//! Every read has the idle timeout, lines and messages have size limits, and the number
//! of simultaneous connections is bounded (extra ones are closed at once).

use parking_lot::Mutex;
use std::io;
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;

use tokio::io::{AsyncBufReadExt, AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt, BufReader};
use tokio::net::{TcpListener, TcpStream, ToSocketAddrs};
use tokio::sync::{watch, Semaphore};
use tokio::task::JoinSet;
use tokio::time::timeout;

use yarp_proto::nameserver::{reply_binary, reply_text, Registry, RegistryConfig};
use yarp_proto::wire::{self, CommandKind, Decoder, DecoderConfig, Event, Framing};
use yarp_proto::Bottle;

/// C++ `yarp::os::impl` text sent to a peer whose first 8 bytes name no protocol.
const PROTOCOL_NOT_FOUND: &[u8] = b"* Error. Protocol not found.\r\n\
* Hello. You appear to be trying to communicate with a YARP Port.\r\n\
* The first 8 bytes sent to a YARP Port are critical for identifying the\r\n\
* protocol you wish to speak.\r\n\
* The first 8 bytes you sent were not associated with any particular protocol.\r\n\
* If you are a human, try typing \"CONNECT foo\" followed by a <RETURN>.\r\n\
* The 8 bytes \"CONNECT \" correspond to a simple text-mode protocol.\r\n\
* Goodbye.\r\n";

const ACK_TEXT: &[u8] = b"<ACK>\r\n";
const MAX_SENDER_NAME: usize = 1000;

/// Settings of a [`NameServer`].
#[derive(Debug, Clone)]
pub struct ServerConfig {
    /// The address the server registers itself under (`/root`) and writes to `yarp.conf`.
    pub advertised_host: String,
    /// The port number the server registers itself under, puts in tcp header replies and
    /// allocates from (`+2` upwards). `None`: the port actually bound. Tests replaying
    /// recordings made against port 10000 set `Some(10000)` while binding a free port.
    pub advertised_port: Option<u16>,
    /// Closes connections that send nothing for this long.
    pub idle_timeout: Duration,
    /// Longest accepted text line (command or name), bytes.
    pub max_line: usize,
    /// Largest accepted binary message, bytes.
    pub max_message: usize,
    /// Most simultaneous connections; more are closed at once.
    pub max_connections: usize,
    /// Print each command on stdout as C++ does (` * list`).
    pub echo_commands: bool,
    /// Registry settings other than host/port (taken from the fields above).
    pub fallback_port: i32,
    /// Answer multicast discovery (`yarp detect`) on 224.2.1.1:`fallback_port`, as C++.
    pub multicast_fallback: bool,
    /// The namespace name registered for the server itself.
    pub root_name: String,
}

impl ServerConfig {
    pub fn new(advertised_host: &str) -> ServerConfig {
        ServerConfig {
            advertised_host: advertised_host.to_string(),
            advertised_port: None,
            idle_timeout: Duration::from_secs(60),
            max_line: 64 * 1024,
            max_message: 1024 * 1024,
            max_connections: 512,
            echo_commands: false,
            fallback_port: 10000,
            multicast_fallback: true,
            root_name: "/root".to_string(),
        }
    }
}

/// Stops a running [`NameServer::serve`].
#[derive(Debug, Clone)]
pub struct ShutdownHandle(Arc<watch::Sender<bool>>);

impl ShutdownHandle {
    pub fn shutdown(&self) {
        let _ = self.0.send(true);
    }
}

struct Ctx {
    registry: Arc<Mutex<Registry>>,
    config: ServerConfig,
    port: u16,
}

/// A bound name server; call [`NameServer::serve`] to run it.
pub struct NameServer {
    listener: TcpListener,
    ctx: Arc<Ctx>,
    local_addr: SocketAddr,
    shutdown_tx: Arc<watch::Sender<bool>>,
    shutdown_rx: watch::Receiver<bool>,
}

impl NameServer {
    /// Binds `addr`; the server advertises `advertised_ip` and the bound port.
    pub async fn bind(addr: impl ToSocketAddrs, advertised_ip: &str) -> io::Result<NameServer> {
        NameServer::bind_with(addr, ServerConfig::new(advertised_ip)).await
    }

    pub async fn bind_with(
        addr: impl ToSocketAddrs,
        config: ServerConfig,
    ) -> io::Result<NameServer> {
        let listener = TcpListener::bind(addr).await?;
        let local_addr = listener.local_addr()?;
        let port = config.advertised_port.unwrap_or(local_addr.port());
        let mut rc = RegistryConfig::new(&config.advertised_host, port as i32);
        rc.fallback_port = config.fallback_port;
        rc.root_name = config.root_name.clone();
        let registry = Arc::new(Mutex::new(Registry::new(rc)));
        let (tx, rx) = watch::channel(false);
        Ok(NameServer {
            listener,
            ctx: Arc::new(Ctx {
                registry,
                config,
                port,
            }),
            local_addr,
            shutdown_tx: Arc::new(tx),
            shutdown_rx: rx,
        })
    }

    pub fn local_addr(&self) -> SocketAddr {
        self.local_addr
    }

    /// The port number the server advertises (bound port unless configured).
    pub fn advertised_port(&self) -> u16 {
        self.ctx.port
    }

    /// The shared registry (for inspection or preloading).
    pub fn registry(&self) -> Arc<Mutex<Registry>> {
        self.ctx.registry.clone()
    }

    pub fn shutdown_handle(&self) -> ShutdownHandle {
        ShutdownHandle(self.shutdown_tx.clone())
    }

    /// Accepts and serves connections until [`ShutdownHandle::shutdown`]; then stops
    /// accepting, ends open connections and returns.
    pub async fn serve(self) -> io::Result<()> {
        let NameServer {
            listener,
            ctx,
            mut shutdown_rx,
            ..
        } = self;
        if ctx.config.multicast_fallback {
            let iface = ctx
                .config
                .advertised_host
                .parse()
                .unwrap_or(std::net::Ipv4Addr::UNSPECIFIED);
            let port = u16::try_from(ctx.config.fallback_port).unwrap_or(10000);
            tokio::spawn(super::fallback::serve(
                ctx.registry.clone(),
                port,
                iface,
                shutdown_rx.clone(),
            ));
        }
        let limit = Arc::new(Semaphore::new(ctx.config.max_connections.max(1)));
        let mut tasks = JoinSet::new();
        loop {
            if *shutdown_rx.borrow() {
                break;
            }
            tokio::select! {
                changed = shutdown_rx.changed() => {
                    if changed.is_err() || *shutdown_rx.borrow() {
                        break;
                    }
                }
                accepted = listener.accept() => {
                    match accepted {
                        Ok((stream, peer)) => {
                            let Ok(permit) = limit.clone().try_acquire_owned() else {
                                tracing::warn!(%peer, "too many connections, closing");
                                drop(stream);
                                continue;
                            };
                            let ctx = ctx.clone();
                            tasks.spawn(async move {
                                if let Err(e) = handle(stream, peer, &ctx).await {
                                    tracing::debug!(%peer, error = %e, "connection ended");
                                }
                                drop(permit);
                            });
                        }
                        Err(e) => {
                            // e.g. EMFILE: back off a little instead of spinning.
                            tracing::warn!(error = %e, "accept failed");
                            tokio::time::sleep(Duration::from_millis(50)).await;
                        }
                    }
                }
                Some(_) = tasks.join_next(), if !tasks.is_empty() => {}
            }
        }
        tasks.shutdown().await;
        Ok(())
    }
}

fn remote_host(peer: &SocketAddr) -> String {
    match peer {
        SocketAddr::V4(a) => a.ip().to_string(),
        SocketAddr::V6(a) => match a.ip().to_ipv4_mapped() {
            Some(v4) => v4.to_string(),
            None => a.ip().to_string(),
        },
    }
}

fn timed_out() -> io::Error {
    io::Error::new(io::ErrorKind::TimedOut, "idle timeout")
}

async fn read_exact_t<R: AsyncRead + Unpin>(
    rd: &mut R,
    buf: &mut [u8],
    idle: Duration,
) -> io::Result<bool> {
    match timeout(idle, rd.read_exact(buf)).await {
        Err(_) => Err(timed_out()),
        Ok(Ok(_)) => Ok(true),
        Ok(Err(e)) if e.kind() == io::ErrorKind::UnexpectedEof => Ok(false),
        Ok(Err(e)) => Err(e),
    }
}

/// Reads one line (without `\n`, and without a final `\r`). `None` at end of stream.
async fn read_line_t<R: AsyncBufReadExt + Unpin>(
    rd: &mut R,
    max: usize,
    idle: Duration,
) -> io::Result<Option<Vec<u8>>> {
    let mut line = Vec::new();
    loop {
        let buf = match timeout(idle, rd.fill_buf()).await {
            Err(_) => return Err(timed_out()),
            Ok(r) => r?,
        };
        if buf.is_empty() {
            return Ok(None);
        }
        if let Some(i) = buf.iter().position(|&b| b == b'\n') {
            line.extend_from_slice(&buf[..i]);
            rd.consume(i + 1);
            if line.last() == Some(&b'\r') {
                line.pop();
            }
            return Ok(Some(line));
        }
        let n = buf.len();
        line.extend_from_slice(buf);
        rd.consume(n);
        if line.len() > max {
            return Err(io::Error::new(io::ErrorKind::InvalidData, "line too long"));
        }
    }
}

async fn write_t<W: AsyncWrite + Unpin>(
    wr: &mut W,
    bytes: &[u8],
    idle: Duration,
) -> io::Result<()> {
    match timeout(idle, async {
        wr.write_all(bytes).await?;
        wr.flush().await
    })
    .await
    {
        Err(_) => Err(timed_out()),
        Ok(r) => r,
    }
}

fn run_command(ctx: &Ctx, cmd: &Bottle, remote: &str) -> Bottle {
    let mut reg = ctx.registry.lock();
    let line = reg.log_line(cmd);
    if ctx.config.echo_commands {
        println!("{line}");
    }
    reg.apply(cmd, Some(remote))
}

async fn handle(mut stream: TcpStream, peer: SocketAddr, ctx: &Ctx) -> io::Result<()> {
    let _ = stream.set_nodelay(true);
    // auth.conf: C++'s name server is a port; its connections authenticate first too.
    crate::auth::accepted(&mut stream).await?;
    let remote = remote_host(&peer);
    let idle = ctx.config.idle_timeout;
    let (rd, mut wr) = stream.into_split();
    let mut rd = BufReader::with_capacity(8192, rd);
    let mut header = [0u8; 8];
    if !read_exact_t(&mut rd, &mut header, idle).await? {
        return Ok(());
    }
    match &header {
        b"NAME_SER" => nameser_session(&mut rd, &mut wr, ctx, &remote).await,
        b"CONNECT " => text_session(&mut rd, &mut wr, ctx, &remote, false).await,
        b"CONNACK " => text_session(&mut rd, &mut wr, ctx, &remote, true).await,
        [b'Y', b'A', ..] => binary_session(&mut rd, &mut wr, ctx, &remote, header).await,
        _ => write_t(&mut wr, PROTOCOL_NOT_FOUND, idle).await,
    }
}

async fn nameser_session<R, W>(rd: &mut R, wr: &mut W, ctx: &Ctx, remote: &str) -> io::Result<()>
where
    R: AsyncBufReadExt + Unpin,
    W: AsyncWrite + Unpin,
{
    let idle = ctx.config.idle_timeout;
    // After the 8-byte header, C++ swallows "VER " (4 bytes), and "NAME_SERVER " (12
    // bytes) before each later command, whatever those bytes are.
    let mut swallow = 4usize;
    loop {
        let mut skip = vec![0u8; swallow];
        if !read_exact_t(rd, &mut skip, idle).await? {
            return Ok(());
        }
        let Some(line) = read_line_t(rd, ctx.config.max_line, idle).await? else {
            return Ok(());
        };
        let reply = run_command(ctx, &Bottle::from_text(&line), remote);
        write_t(wr, &reply_text(&reply), idle).await?;
        swallow = 12;
    }
}

async fn text_session<R, W>(
    rd: &mut R,
    wr: &mut W,
    ctx: &Ctx,
    remote: &str,
    ack: bool,
) -> io::Result<()>
where
    R: AsyncBufReadExt + Unpin,
    W: AsyncWrite + Unpin,
{
    let idle = ctx.config.idle_timeout;
    let max = ctx.config.max_line;
    let Some(name) = read_line_t(rd, max, idle).await? else {
        return Ok(());
    };
    let mut welcome = b"Welcome ".to_vec();
    welcome.extend_from_slice(&name);
    welcome.extend_from_slice(b"\r\n");
    write_t(wr, &welcome, idle).await?;
    loop {
        let Some(pc) = read_line_t(rd, max, idle).await? else {
            return Ok(());
        };
        let want_reply = match pc.first() {
            Some(b'd') => true,
            Some(b'D') => false,
            // `q`, and anything that is not a data message: C++ yarpserver closes.
            _ => return Ok(()),
        };
        let Some(line) = read_line_t(rd, max, idle).await? else {
            return Ok(());
        };
        let reply = run_command(ctx, &Bottle::from_text(&line), remote);
        let mut out = if want_reply {
            reply_text(&reply)
        } else {
            Vec::new()
        };
        if ack {
            out.extend_from_slice(ACK_TEXT);
        }
        if !out.is_empty() {
            write_t(wr, &out, idle).await?;
        }
    }
}

fn bad(msg: &str) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidData, msg.to_string())
}

/// A tcp-family connection carrying command Bottles (what C++ clients send when they
/// talk to the name server as to a port), framed by the shared `yarp_proto::wire` decoder.
async fn binary_session<R, W>(
    rd: &mut R,
    wr: &mut W,
    ctx: &Ctx,
    remote: &str,
    header: [u8; 8],
) -> io::Result<()>
where
    R: AsyncBufReadExt + Unpin,
    W: AsyncWrite + Unpin,
{
    let idle = ctx.config.idle_timeout;
    let config = DecoderConfig {
        max_message_size: ctx.config.max_message,
        ..DecoderConfig::default()
    };
    let mut dec = Decoder::accepting(config);
    dec.feed(&header);
    let mut acks = false;
    let mut buf = vec![0u8; 8192];
    loop {
        while let Some(ev) = dec.poll().map_err(|e| bad(&e.to_string()))? {
            match ev {
                Event::Header(h) => {
                    // udp (0) and mcast (1) need datagrams; only stream carriers here
                    if h.framing() != Framing::Stream {
                        return Ok(());
                    }
                    acks = h.requires_ack();
                }
                Event::SenderName(name) => {
                    if name.len() > MAX_SENDER_NAME {
                        return Err(bad("sender name too long"));
                    }
                    write_t(wr, &wire::encode_header_reply(ctx.port as i32), idle).await?;
                }
                Event::Message(m) => {
                    let mut out = Vec::new();
                    match m.command.kind() {
                        CommandKind::Data { reply } => match m.bottle() {
                            Ok(cmd) => {
                                let answer = run_command(ctx, &cmd, remote);
                                if reply {
                                    out = reply_binary(&answer);
                                }
                            }
                            // C++ neither answers nor acks a message it cannot read.
                            Err(_) => continue,
                        },
                        CommandKind::Close => return Ok(()),
                        _ => {}
                    }
                    if acks {
                        out.extend_from_slice(&wire::ack());
                    }
                    if !out.is_empty() {
                        write_t(wr, &out, idle).await?;
                    }
                }
                _ => {}
            }
        }
        let n = match timeout(idle, rd.read(&mut buf)).await {
            Ok(r) => r?,
            Err(_) => return Err(timed_out()),
        };
        if n == 0 {
            return Ok(());
        }
        dec.feed(&buf[..n]);
    }
}
