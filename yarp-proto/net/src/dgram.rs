//! The udp and mcast carriers on tokio: datagram senders and receivers built on the
//! sans-I/O framing of [`yarp_proto::wire::datagram`], plus the TCP handshakes that set
//! them up.
//!
//! A udp connection from `/w` to `/r`, as C++ YARP makes it:
//!
//! 1. `/w` opens TCP to `/r`'s port and sends header 7777 + sender name
//!    ([`udp_handshake_connect`]);
//! 2. `/r` binds a UDP socket and answers with its UDP port as a YARP number
//!    ([`udp_handshake_accept`]); both sides then close the TCP connection;
//! 3. `/w` sends each message as datagrams to `/r`'s host at that port ([`UdpSender`]),
//!    `/r` reassembles them ([`UdpReceiver`]). Nothing flows back: no acks, no replies.
//!
//! mcast is the same except that the sender adds the group (`224.1.x.y:port`, allocated by
//! the name server) after its name and nobody replies ([`mcast_handshake_connect`]); the
//! receiver joins the group ([`McastReceiver`]) and the sender sends to it
//! ([`McastSender`]).

use std::collections::VecDeque;
use std::io;
use std::net::{IpAddr, Ipv4Addr, SocketAddr, SocketAddrV4};
use std::ops::{Deref, DerefMut};
use std::time::Duration;

use socket2::{Domain, Protocol, SockAddr, Socket, Type};
use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};
use tokio::net::{TcpStream, UdpSocket};
use yarp_proto::wire::datagram::{
    encode_mcast_connection_start, DatagramEvent, DatagramReader, DatagramStats, DatagramWriter,
    McastGroup,
};
use yarp_proto::wire::{
    data_message, encode_connection_start, encode_header_reply, Carrier, Decoder, DecoderConfig,
    Event, Message,
};
use yarp_proto::Bottle;

/// The interface multicast uses unless told otherwise: loopback (the tests run in a
/// network namespace whose multicast route is on `lo`).
pub const DEFAULT_MCAST_INTERFACE: Ipv4Addr = Ipv4Addr::LOCALHOST;

/// Receive buffer asked for on datagram sockets (best effort: the kernel caps it at
/// `net.core.rmem_max`). C++ keeps the system default unless `YARP_DGRAM_BUFFER_SIZE`
/// says otherwise; a bigger buffer only makes bursts of large messages less lossy.
pub const RECV_BUFFER_SIZE: usize = 8 * 1024 * 1024;

/// C++ pauses about a millisecond after every datagram longer than 3/4 of its maximum
/// size, so that a burst of them does not overflow the receiver's socket buffer.
pub const DEFAULT_PACING: Duration = Duration::from_millis(1);

const RECV_BUF: usize = 65536;

/// Waits `p` without the timer, whose millisecond ticks would double a 1 ms pause: other
/// tasks run meanwhile, as C++ yields in a loop for the same pause.
async fn pause(p: Duration) {
    let start = std::time::Instant::now();
    while start.elapsed() < p {
        tokio::task::yield_now().await;
    }
}

fn invalid(msg: impl Into<String>) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidData, msg.into())
}

fn into_tokio(socket: Socket) -> io::Result<UdpSocket> {
    socket.set_nonblocking(true)?;
    UdpSocket::from_std(socket.into())
}

fn new_udp_socket(family: &SocketAddr) -> io::Result<Socket> {
    Socket::new(
        Domain::for_address(*family),
        Type::DGRAM,
        Some(Protocol::UDP),
    )
}

/// Sends YARP messages as datagrams to one destination (a udp receiver or a mcast group).
#[derive(Debug)]
pub struct UdpSender {
    socket: UdpSocket,
    writer: DatagramWriter,
    pacing: Option<Duration>,
}

impl UdpSender {
    /// A socket bound to an ephemeral port and connected to `remote`.
    pub async fn connect(remote: SocketAddr) -> io::Result<UdpSender> {
        let local: SocketAddr = match remote {
            SocketAddr::V4(_) => (Ipv4Addr::UNSPECIFIED, 0).into(),
            SocketAddr::V6(_) => (std::net::Ipv6Addr::UNSPECIFIED, 0).into(),
        };
        let socket = UdpSocket::bind(local).await?;
        socket.connect(remote).await?;
        Ok(UdpSender::from_socket(socket))
    }

    /// Wraps a socket already connected to its destination.
    pub fn from_socket(socket: UdpSocket) -> UdpSender {
        UdpSender {
            socket,
            writer: DatagramWriter::new(),
            pacing: Some(DEFAULT_PACING),
        }
    }

    /// Limits datagrams to `size` bytes, header included (C++ `YARP_UDP_SIZE`).
    pub fn with_datagram_size(mut self, size: usize) -> UdpSender {
        self.writer = DatagramWriter::with_datagram_size(size);
        self
    }

    /// The pause between consecutive large datagrams of one message (`None`: no pause).
    pub fn set_pacing(&mut self, pacing: Option<Duration>) {
        self.pacing = pacing;
    }

    pub fn local_addr(&self) -> io::Result<SocketAddr> {
        self.socket.local_addr()
    }

    pub fn peer_addr(&self) -> io::Result<SocketAddr> {
        self.socket.peer_addr()
    }

    pub fn socket(&self) -> &UdpSocket {
        &self.socket
    }

    /// Datagrams sent so far.
    pub fn datagrams(&self) -> u64 {
        self.writer.datagrams()
    }

    /// Sends one message: its complete tcp-family bytes (index, port command, blocks), as
    /// [`data_message`], [`envelope_message`](yarp_proto::wire::envelope_message) or
    /// [`encode_message`](yarp_proto::wire::encode_message) make them. Returns the
    /// number of datagrams sent. An error means the message may be partly sent; the
    /// receiver then drops it and resynchronises on the next one.
    pub async fn send_message(&mut self, message: &[u8]) -> io::Result<usize> {
        let large = self.writer.datagram_size() * 3 / 4;
        let pacing = self.pacing;
        let mut sent = 0;
        let mut previous_large = false;
        for datagram in self.writer.split(message) {
            if previous_large {
                if let Some(p) = pacing {
                    pause(p).await;
                }
            }
            let n = self.socket.send(&datagram).await?;
            if n != datagram.len() {
                return Err(io::Error::new(
                    io::ErrorKind::WriteZero,
                    format!("datagram truncated to {n} of {} bytes", datagram.len()),
                ));
            }
            previous_large = datagram.len() > large;
            sent += 1;
        }
        Ok(sent)
    }

    /// Sends a Bottle as C++ `Port::write` does (port command `D`).
    pub async fn send_bottle(&mut self, bottle: &Bottle) -> io::Result<usize> {
        self.send_message(&data_message(bottle, false)).await
    }
}

/// Receives datagrams on one socket and yields the messages they carry.
#[derive(Debug)]
pub struct UdpReceiver {
    socket: UdpSocket,
    reader: DatagramReader,
    buf: Box<[u8]>,
    pending: VecDeque<DatagramEvent>,
}

impl UdpReceiver {
    /// Binds a UDP socket on `addr` (`0.0.0.0:0` for a fresh port, as the accepting side
    /// of a udp connection does).
    pub async fn bind(addr: SocketAddr) -> io::Result<UdpReceiver> {
        let socket = new_udp_socket(&addr)?;
        let _ = socket.set_recv_buffer_size(RECV_BUFFER_SIZE);
        socket.bind(&SockAddr::from(addr))?;
        Ok(UdpReceiver::from_socket(
            into_tokio(socket)?,
            Carrier::Udp,
            DecoderConfig::default(),
        ))
    }

    /// Wraps a bound socket; messages report `carrier` (udp or mcast).
    pub fn from_socket(socket: UdpSocket, carrier: Carrier, config: DecoderConfig) -> UdpReceiver {
        UdpReceiver {
            socket,
            reader: DatagramReader::for_carrier(carrier, config),
            buf: vec![0u8; RECV_BUF].into_boxed_slice(),
            pending: VecDeque::new(),
        }
    }

    pub fn local_addr(&self) -> io::Result<SocketAddr> {
        self.socket.local_addr()
    }

    /// The UDP port to announce in the header reply.
    pub fn local_port(&self) -> io::Result<u16> {
        Ok(self.socket.local_addr()?.port())
    }

    pub fn socket(&self) -> &UdpSocket {
        &self.socket
    }

    pub fn stats(&self) -> DatagramStats {
        self.reader.stats()
    }

    /// The next thing made of the incoming datagrams: a message, or a report of a dropped
    /// datagram or lost message. Cancel-safe (nothing is lost when the future is dropped
    /// before completion), so it can sit in a `tokio::select!`.
    pub async fn recv_event(&mut self) -> io::Result<DatagramEvent> {
        loop {
            if let Some(e) = self.pending.pop_front() {
                return Ok(e);
            }
            let (n, from) = match self.socket.recv_from(&mut self.buf).await {
                Ok(r) => r,
                // an ICMP error from an earlier send on this socket; not fatal for reading
                Err(e) if e.kind() == io::ErrorKind::ConnectionRefused => continue,
                Err(e) => return Err(e),
            };
            let mut events = Vec::new();
            self.reader.push_into(&self.buf[..n], &mut events);
            for e in &events {
                match e {
                    DatagramEvent::Dropped(err) => {
                        tracing::debug!("datagram from {from} dropped: {err}")
                    }
                    DatagramEvent::Lost { received, framing } => tracing::debug!(
                        "message from {from} lost after {received} bytes{}",
                        framing
                            .as_ref()
                            .map(|e| format!(": {e}"))
                            .unwrap_or_default()
                    ),
                    _ => {}
                }
            }
            self.pending.extend(events);
        }
    }

    /// The next complete, valid message (everything else is skipped, as C++ does).
    /// Cancel-safe.
    pub async fn recv(&mut self) -> io::Result<Message> {
        loop {
            if let DatagramEvent::Message(m) = self.recv_event().await? {
                return Ok(m);
            }
        }
    }
}

/// A [`UdpSender`] sending to a multicast group.
#[derive(Debug)]
pub struct McastSender {
    inner: UdpSender,
    group: SocketAddrV4,
}

impl McastSender {
    /// A socket sending to `group` through `interface` (`IP_MULTICAST_IF`, as C++ does
    /// with the TCP connection's local address), with `IP_MULTICAST_LOOP` on so that
    /// receivers on this host get the datagrams, TTL 1 (the system default C++ keeps).
    pub async fn open(group: SocketAddrV4, interface: Ipv4Addr) -> io::Result<McastSender> {
        if !group.ip().is_multicast() {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("{} is not a multicast address", group.ip()),
            ));
        }
        let addr = SocketAddr::V4(group);
        let socket = new_udp_socket(&addr)?;
        socket.set_multicast_if_v4(&interface)?;
        socket.set_multicast_loop_v4(true)?;
        socket.set_multicast_ttl_v4(1)?;
        socket.bind(&SockAddr::from(SocketAddrV4::new(Ipv4Addr::UNSPECIFIED, 0)))?;
        socket.connect(&SockAddr::from(addr))?;
        Ok(McastSender {
            inner: UdpSender::from_socket(into_tokio(socket)?),
            group,
        })
    }

    pub fn group(&self) -> SocketAddrV4 {
        self.group
    }
}

impl Deref for McastSender {
    type Target = UdpSender;
    fn deref(&self) -> &UdpSender {
        &self.inner
    }
}

impl DerefMut for McastSender {
    fn deref_mut(&mut self) -> &mut UdpSender {
        &mut self.inner
    }
}

/// A [`UdpReceiver`] that joined a multicast group. Several receivers (in this process
/// or others, C++ ones included) can join the same group on one host: the socket uses
/// `SO_REUSEADDR`, as C++ does. Dropping it leaves the group.
#[derive(Debug)]
pub struct McastReceiver {
    inner: UdpReceiver,
    group: SocketAddrV4,
}

impl McastReceiver {
    /// Binds the group's port and joins the group on `interface`.
    pub async fn join(group: SocketAddrV4, interface: Ipv4Addr) -> io::Result<McastReceiver> {
        if !group.ip().is_multicast() {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("{} is not a multicast address", group.ip()),
            ));
        }
        let socket = new_udp_socket(&SocketAddr::V4(group))?;
        socket.set_reuse_address(true)?;
        let _ = socket.set_recv_buffer_size(RECV_BUFFER_SIZE);
        // Binding the group address (not INADDR_ANY as C++ does) keeps unicast datagrams
        // and other groups on the same port out of this socket; Windows refuses it.
        let bind_ip = if cfg!(windows) {
            Ipv4Addr::UNSPECIFIED
        } else {
            *group.ip()
        };
        socket.bind(&SockAddr::from(SocketAddrV4::new(bind_ip, group.port())))?;
        socket.join_multicast_v4(group.ip(), &interface)?;
        let _ = socket.set_multicast_loop_v4(true);
        Ok(McastReceiver {
            inner: UdpReceiver::from_socket(
                into_tokio(socket)?,
                Carrier::Mcast,
                DecoderConfig::default(),
            ),
            group,
        })
    }

    pub fn group(&self) -> SocketAddrV4 {
        self.group
    }

    /// The receiver itself (its socket stays in the group while it lives).
    pub fn into_inner(self) -> UdpReceiver {
        self.inner
    }
}

impl Deref for McastReceiver {
    type Target = UdpReceiver;
    fn deref(&self) -> &UdpReceiver {
        &self.inner
    }
}

impl DerefMut for McastReceiver {
    fn deref_mut(&mut self) -> &mut UdpReceiver {
        &mut self.inner
    }
}

/// The connecting side of a udp connection, on the TCP stream to the receiving port:
/// sends header 7777 and `sender_name`, reads the header reply and returns the UDP port
/// it announces. The caller then closes the stream and sends datagrams to the stream's
/// peer host at that port (see [`udp_connect`]). Wrap it in a timeout.
pub async fn udp_handshake_connect<S>(stream: &mut S, sender_name: &str) -> io::Result<u16>
where
    S: AsyncRead + AsyncWrite + Unpin,
{
    let spec = Carrier::Udp.spec();
    stream
        .write_all(&encode_connection_start(&spec, sender_name.as_bytes()))
        .await?;
    stream.flush().await?;
    let mut decoder = Decoder::connecting(spec, DecoderConfig::default());
    let mut buf = [0u8; 64];
    loop {
        if let Some(ev) = decoder.poll().map_err(|e| invalid(e.to_string()))? {
            let Event::HeaderReply(port) = ev else {
                return Err(invalid(format!("unexpected {ev:?} in a udp handshake")));
            };
            return u16::try_from(port)
                .ok()
                .filter(|&p| p != 0)
                .ok_or_else(|| invalid(format!("udp handshake announced port {port}")));
        }
        // read at most what the reply can still need, leaving later bytes in the stream
        let want = 8usize.saturating_sub(decoder.pending()).clamp(1, buf.len());
        let n = stream.read(&mut buf[..want]).await?;
        if n == 0 {
            return Err(io::Error::new(
                io::ErrorKind::UnexpectedEof,
                "connection closed during the udp handshake",
            ));
        }
        decoder.feed(&buf[..n]);
    }
}

/// The whole connecting side of udp: handshake on `tcp`, close it, and return a sender to
/// the TCP peer's host at the announced port.
pub async fn udp_connect(mut tcp: TcpStream, sender_name: &str) -> io::Result<UdpSender> {
    let peer = tcp.peer_addr()?;
    let port = udp_handshake_connect(&mut tcp, sender_name).await?;
    let _ = tcp.shutdown().await;
    drop(tcp);
    UdpSender::connect(SocketAddr::new(peer.ip(), port)).await
}

/// The accepting side of udp, after the port read header 7777 and the sender name: binds
/// a receiver on `bind_ip` (port chosen by the system; C++ binds `0.0.0.0`) and sends its
/// port as the header reply. The caller then closes the stream and reads from the
/// receiver.
pub async fn udp_handshake_accept<W>(stream: &mut W, bind_ip: IpAddr) -> io::Result<UdpReceiver>
where
    W: AsyncWrite + Unpin,
{
    let receiver = UdpReceiver::bind(SocketAddr::new(bind_ip, 0)).await?;
    let port = receiver.local_port()?;
    stream
        .write_all(&encode_header_reply(i32::from(port)))
        .await?;
    stream.flush().await?;
    Ok(receiver)
}

/// The connecting side of mcast: header 7778, `sender_name`, the group. Nothing comes
/// back; the caller closes the stream and sends to the group with a [`McastSender`].
pub async fn mcast_handshake_connect<W>(
    stream: &mut W,
    sender_name: &str,
    group: SocketAddrV4,
) -> io::Result<()>
where
    W: AsyncWrite + Unpin,
{
    stream
        .write_all(&encode_mcast_connection_start(
            sender_name.as_bytes(),
            McastGroup::from(group),
        ))
        .await?;
    stream.flush().await
}

/// What the connecting side of a udp or mcast connection sent on TCP.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DgramStart {
    pub carrier: Carrier,
    pub sender_name: String,
    /// The group, for mcast.
    pub group: Option<SocketAddrV4>,
}

/// Reads the start of a connection from a fresh stream (header, sender name and, for
/// mcast, the group) for servers that do not classify headers themselves. Fails for any
/// carrier but udp and mcast. Reads nothing beyond the handshake.
pub async fn read_dgram_start<R>(stream: &mut R) -> io::Result<DgramStart>
where
    R: AsyncRead + Unpin,
{
    let mut header = [0u8; 8];
    stream.read_exact(&mut header).await?;
    let carrier = yarp_proto::wire::classify_header(&header)
        .map_err(|e| invalid(e.to_string()))?
        .carrier();
    if !matches!(carrier, Carrier::Udp | Carrier::Mcast) {
        return Err(invalid(format!("{carrier} is not a datagram carrier")));
    }
    let mut len = [0u8; 4];
    stream.read_exact(&mut len).await?;
    // C++ clamps the length to 1..=1000
    let n = i32::from_le_bytes(len).clamp(1, 1000) as usize;
    let mut name = vec![0u8; n];
    stream.read_exact(&mut name).await?;
    if let Some(nul) = name.iter().position(|&b| b == 0) {
        name.truncate(nul);
    }
    let group = if carrier == Carrier::Mcast {
        let mut g = [0u8; 6];
        stream.read_exact(&mut g).await?;
        Some(McastGroup::decode(&g).addr())
    } else {
        None
    };
    Ok(DgramStart {
        carrier,
        sender_name: String::from_utf8_lossy(&name).into_owned(),
        group,
    })
}
