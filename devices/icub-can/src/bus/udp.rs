//! CAN frames over UDP in the cannelloni format ([`super::cannelloni`]).
//!
//! Two roles:
//! - **peer** (`udp://HOST:PORT`): sends to one remote address, receives on a local
//!   socket (ephemeral unless `?local=HOST:PORT` is given). This is exactly a cannelloni
//!   tunnel end, so it interoperates with `cannelloni -R HOST -r PORT -l LOCALPORT`.
//! - **hub** (`udp-hub://HOST:PORT`): binds `HOST:PORT` and acts as the bus itself: every
//!   peer that sent a datagram in the last [`PEER_EXPIRY`] is a node; a datagram from one
//!   peer is delivered locally and relayed to all other peers, and local sends go to all
//!   peers. The board emulator is a hub, so several driver processes can share one bus.
//!
//! Peers announce themselves with an empty DATA packet (count 0, which cannelloni ignores)
//! at open and every [`KEEPALIVE`], so a hub learns listen-only nodes too.
//! A reader thread per endpoint decodes datagrams; malformed ones are counted in
//! [`BusStats::malformed`] and dropped.

use parking_lot::Mutex;
use std::net::{SocketAddr, ToSocketAddrs, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::cannelloni;
use super::{BusError, BusStats, CanBus, IdFilter, RxQueue, DEFAULT_RX_QUEUE};
use crate::frame::CanFrame;

/// How often a peer re-announces itself to its remote end.
pub const KEEPALIVE: Duration = Duration::from_secs(1);
/// How long a hub keeps a silent peer.
pub const PEER_EXPIRY: Duration = Duration::from_secs(5);
/// Longest wait of the reader thread for a datagram: it then sends its keepalive if due.
/// (Dropping an endpoint wakes the reader at once with a datagram to itself.)
const READ_POLL: Duration = Duration::from_millis(500);

struct Shared {
    name: String,
    socket: UdpSocket,
    queue: RxQueue,
    /// Where sends go: the fixed remote of a peer, or the learned peers of a hub.
    peers: Mutex<Vec<(SocketAddr, Instant)>>,
    hub: bool,
    seq: Mutex<u8>,
    stop: AtomicBool,
}

/// A UDP (cannelloni) endpoint; see the module docs for the two roles.
pub struct UdpBus {
    shared: Arc<Shared>,
    reader: Option<JoinHandle<()>>,
}

fn resolve(addr: &str) -> Result<SocketAddr, BusError> {
    addr.to_socket_addrs()
        .map_err(|e| BusError::Config(format!("cannot resolve {addr:?}: {e}")))?
        .next()
        .ok_or_else(|| BusError::Config(format!("{addr:?} resolves to no address")))
}

impl UdpBus {
    /// A cannelloni peer sending to `remote`; binds `local` (or an ephemeral port on the
    /// same interface as `remote`).
    pub fn connect(remote: &str, local: Option<&str>) -> Result<Self, BusError> {
        let remote = resolve(remote)?;
        let local = match local {
            Some(l) => resolve(l)?,
            None if remote.ip().is_loopback() => SocketAddr::new(remote.ip(), 0),
            None if remote.is_ipv4() => "0.0.0.0:0".parse().expect("literal"),
            None => "[::]:0".parse().expect("literal"),
        };
        let name = format!("udp://{remote}");
        let bus = Self::open(name, local, vec![remote], false)?;
        bus.send_raw(&[], remote)?;
        Ok(bus)
    }

    /// A hub bound to `bind`.
    pub fn hub(bind: &str) -> Result<Self, BusError> {
        let bind = resolve(bind)?;
        Self::open(format!("udp-hub://{bind}"), bind, Vec::new(), true)
    }

    fn open(
        name: String,
        local: SocketAddr,
        peers: Vec<SocketAddr>,
        hub: bool,
    ) -> Result<Self, BusError> {
        let io = |source| BusError::Io {
            bus: name.clone(),
            source,
        };
        let socket = UdpSocket::bind(local).map_err(io)?;
        socket.set_read_timeout(Some(READ_POLL)).map_err(io)?;
        let now = Instant::now();
        let shared = Arc::new(Shared {
            name: name.clone(),
            socket,
            queue: RxQueue::new(DEFAULT_RX_QUEUE),
            peers: Mutex::new(peers.into_iter().map(|p| (p, now)).collect()),
            hub,
            seq: Mutex::new(0),
            stop: AtomicBool::new(false),
        });
        let reader_shared = shared.clone();
        let reader = std::thread::Builder::new()
            .name(format!("can-udp {name}"))
            .spawn(move || reader_loop(&reader_shared))
            .map_err(io)?;
        Ok(Self {
            shared,
            reader: Some(reader),
        })
    }

    /// The local address (useful after binding port 0).
    pub fn local_addr(&self) -> Result<SocketAddr, BusError> {
        self.shared
            .socket
            .local_addr()
            .map_err(|source| BusError::Io {
                bus: self.shared.name.clone(),
                source,
            })
    }

    /// Currently known peers (the remote of a peer; the live nodes of a hub).
    pub fn peers(&self) -> Vec<SocketAddr> {
        self.shared.peers.lock().iter().map(|p| p.0).collect()
    }

    fn send_raw(&self, frames: &[CanFrame], to: SocketAddr) -> Result<(), BusError> {
        for p in &self.encode(frames) {
            send_datagram(&self.shared, p, to)?;
        }
        Ok(())
    }

    /// The datagrams carrying `frames` (one empty one for none), numbered in sequence.
    fn encode(&self, frames: &[CanFrame]) -> Vec<Vec<u8>> {
        let mut seq = self.shared.seq.lock();
        let packets = if frames.is_empty() {
            let mut p = Vec::new();
            cannelloni::encode(*seq, &[], &mut p);
            vec![p]
        } else {
            cannelloni::encode_packets(*seq, frames)
        };
        *seq = seq.wrapping_add(packets.len() as u8);
        packets
    }
}

fn send_datagram(shared: &Shared, packet: &[u8], to: SocketAddr) -> Result<(), BusError> {
    match shared.socket.send_to(packet, to) {
        Ok(_) => Ok(()),
        // A peer that is not (yet) listening is like an unpowered node: not our error.
        Err(e) if e.kind() == std::io::ErrorKind::ConnectionRefused => Ok(()),
        Err(source) => Err(BusError::Io {
            bus: shared.name.clone(),
            source,
        }),
    }
}

fn reader_loop(shared: &Shared) {
    let mut buf = vec![0u8; 65536];
    let mut last_keepalive = Instant::now();
    while !shared.stop.load(Ordering::Relaxed) {
        if !shared.hub && last_keepalive.elapsed() >= KEEPALIVE {
            last_keepalive = Instant::now();
            let remotes: Vec<SocketAddr> = shared.peers.lock().iter().map(|p| p.0).collect();
            let mut hello = Vec::new();
            cannelloni::encode(0, &[], &mut hello);
            for r in remotes {
                let _ = send_datagram(shared, &hello, r);
            }
        }
        let (n, from) = match shared.socket.recv_from(&mut buf) {
            Ok(_) if shared.stop.load(Ordering::Relaxed) => return,
            Ok(x) => x,
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock
                        | std::io::ErrorKind::TimedOut
                        // a signal (SIGSTOP/SIGCONT, a debugger) is no receive error
                        | std::io::ErrorKind::Interrupted
                ) =>
            {
                continue
            }
            Err(e) if e.kind() == std::io::ErrorKind::ConnectionRefused => continue,
            Err(e) => {
                shared.queue.close(format!("{}: {e}", shared.name));
                return;
            }
        };
        let datagram = &buf[..n];
        if shared.hub {
            let now = Instant::now();
            let others: Vec<SocketAddr> = {
                let mut peers = shared.peers.lock();
                peers.retain(|p| now.duration_since(p.1) < PEER_EXPIRY);
                match peers.iter_mut().find(|p| p.0 == from) {
                    Some(p) => p.1 = now,
                    None => peers.push((from, now)),
                }
                peers.iter().map(|p| p.0).filter(|p| *p != from).collect()
            };
            match cannelloni::decode(datagram) {
                Ok(packet) if packet.frames.is_empty() => {}
                Ok(packet) => {
                    for peer in others {
                        let _ = send_datagram(shared, datagram, peer);
                    }
                    shared.queue.push_all(packet.frames);
                }
                Err(e) => {
                    shared.queue.malformed.fetch_add(1, Ordering::Relaxed);
                    tracing::debug!(bus = %shared.name, %from, "dropping malformed datagram: {e}");
                }
            }
        } else {
            match cannelloni::decode(datagram) {
                Ok(packet) => shared.queue.push_all(packet.frames),
                Err(e) => {
                    shared.queue.malformed.fetch_add(1, Ordering::Relaxed);
                    tracing::debug!(bus = %shared.name, %from, "dropping malformed datagram: {e}");
                }
            }
        }
    }
}

impl Drop for UdpBus {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        // Wake the reader now rather than at its next poll.
        if let Ok(mut me) = self.shared.socket.local_addr() {
            if me.ip().is_unspecified() {
                me.set_ip(match me {
                    SocketAddr::V4(_) => std::net::Ipv4Addr::LOCALHOST.into(),
                    SocketAddr::V6(_) => std::net::Ipv6Addr::LOCALHOST.into(),
                });
            }
            let _ = self.shared.socket.send_to(&[], me);
        }
        if let Some(h) = self.reader.take() {
            let _ = h.join();
        }
    }
}

impl CanBus for UdpBus {
    fn name(&self) -> &str {
        &self.shared.name
    }

    fn send(&self, frame: &CanFrame) -> Result<(), BusError> {
        self.send_all(std::slice::from_ref(frame))
    }

    fn send_all(&self, frames: &[CanFrame]) -> Result<(), BusError> {
        if frames.is_empty() {
            return Ok(());
        }
        let targets: Vec<SocketAddr> = {
            let now = Instant::now();
            let mut peers = self.shared.peers.lock();
            if self.shared.hub {
                peers.retain(|p| now.duration_since(p.1) < PEER_EXPIRY);
            }
            peers.iter().map(|p| p.0).collect()
        };
        if !targets.is_empty() {
            // Encoded once for every peer: a hub relays the same datagrams to all.
            let packets = self.encode(frames);
            for to in targets {
                for p in &packets {
                    send_datagram(&self.shared, p, to)?;
                }
            }
        }
        self.shared
            .queue
            .tx_frames
            .fetch_add(frames.len() as u64, Ordering::Relaxed);
        Ok(())
    }

    fn recv(&self, timeout: Duration) -> Result<CanFrame, BusError> {
        self.shared.queue.recv(&self.shared.name, timeout)
    }

    fn try_recv(&self) -> Result<Option<CanFrame>, BusError> {
        self.shared.queue.try_recv(&self.shared.name)
    }

    fn set_filter(&self, filter: IdFilter) {
        self.shared.queue.set_filter(filter);
    }

    fn stats(&self) -> BusStats {
        self.shared.queue.stats()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const T: Duration = Duration::from_secs(2);

    #[test]
    fn peer_to_hub_and_relay_between_peers() {
        let hub = UdpBus::hub("127.0.0.1:0").unwrap();
        let addr = hub.local_addr().unwrap().to_string();
        let a = UdpBus::connect(&addr, None).unwrap();
        let b = UdpBus::connect(&addr, None).unwrap();
        // Wait until the hub learned both peers from their hello packets.
        let t0 = Instant::now();
        while hub.peers().len() < 2 && t0.elapsed() < T {
            std::thread::sleep(Duration::from_millis(5));
        }
        assert_eq!(hub.peers().len(), 2);

        let f = CanFrame::new(0x102, &[1, 2, 3]).unwrap();
        a.send(&f).unwrap();
        assert_eq!(hub.recv(T).unwrap(), f);
        assert_eq!(b.recv(T).unwrap(), f, "hub relays to the other peers");
        assert!(
            a.recv(Duration::from_millis(50)).is_err(),
            "no echo to the sender"
        );

        let g = CanFrame::new(0x201, &[9]).unwrap();
        hub.send_all(&[g, f]).unwrap();
        assert_eq!(a.recv(T).unwrap(), g);
        assert_eq!(a.recv(T).unwrap(), f);
        assert_eq!(b.recv(T).unwrap(), g);
    }

    #[test]
    fn malformed_datagrams_are_counted_and_ignored() {
        let hub = UdpBus::hub("127.0.0.1:0").unwrap();
        let raw = UdpSocket::bind("127.0.0.1:0").unwrap();
        raw.send_to(&[7, 7, 7], hub.local_addr().unwrap()).unwrap();
        let mut ok = Vec::new();
        cannelloni::encode(1, &[CanFrame::new(5, &[5]).unwrap()], &mut ok);
        raw.send_to(&ok, hub.local_addr().unwrap()).unwrap();
        assert_eq!(hub.recv(T).unwrap().id(), 5);
        assert_eq!(hub.stats().malformed, 1);
    }

    #[test]
    fn fixed_local_port_talks_to_plain_cannelloni_peer() {
        // Two peers with fixed ports, as two cannelloni instances would be configured.
        let pa = UdpSocket::bind("127.0.0.1:0")
            .unwrap()
            .local_addr()
            .unwrap();
        let pb = UdpSocket::bind("127.0.0.1:0")
            .unwrap()
            .local_addr()
            .unwrap();
        let a = UdpBus::connect(&pb.to_string(), Some(&pa.to_string())).unwrap();
        let b = UdpBus::connect(&pa.to_string(), Some(&pb.to_string())).unwrap();
        a.send(&CanFrame::new(0x33, &[3]).unwrap()).unwrap();
        assert_eq!(b.recv(T).unwrap().id(), 0x33);
        b.send(&CanFrame::new(0x44, &[]).unwrap()).unwrap();
        assert_eq!(a.recv(T).unwrap().id(), 0x44);
    }
}
