//! Output connections over the datagram carriers (udp, mcast): the handshake runs on a
//! short TCP connection to the target port, then messages travel as datagrams, without
//! acknowledgements or replies. Disconnecting asks the target to drop the input
//! (`~/sender` in a text admin session), as C++ does, since no `q` can be sent.

use super::output::{Job, OutputError, OutputHandle};
use super::{Shared, CONNECT_TIMEOUT, OUTPUT_QUEUE};
use crate::dgram::{self, McastSender, UdpSender};
use std::net::{Ipv4Addr, SocketAddrV4};
use std::sync::Arc;
use tokio::sync::mpsc;
use tokio::time::timeout;
use yarp_proto::nameserver::RegisterRequest;
use yarp_proto::port_admin::Route;
use yarp_proto::wire::datagram::McastGroup;
use yarp_proto::wire::Carrier;
use yarp_proto::{Contact, Value};

enum Sink {
    Udp(UdpSender),
    /// The connection that owns the port's multicast sender; the others of the same port
    /// share its datagrams and send nothing themselves.
    Mcast(Option<McastSender>),
}

pub(crate) async fn connect(
    shared: &Arc<Shared>,
    target: &str,
    contact: &Contact,
    carrier: Carrier,
) -> Result<OutputHandle, OutputError> {
    let addr = format!("{}:{}", contact.host, contact.port);
    let tcp = timeout(CONNECT_TIMEOUT, crate::auth::connect(&addr))
        .await
        .map_err(|_| OutputError::HandshakeTimeout {
            target: target.to_string(),
        })?
        .map_err(|source| OutputError::Connect {
            target: target.to_string(),
            addr: addr.clone(),
            source,
        })?;
    let io = |source| OutputError::Io {
        target: target.to_string(),
        source,
    };
    let sink = match carrier {
        Carrier::Udp => {
            let s = timeout(CONNECT_TIMEOUT, dgram::udp_connect(tcp, &shared.name))
                .await
                .map_err(|_| OutputError::HandshakeTimeout {
                    target: target.to_string(),
                })?
                .map_err(io)?;
            Sink::Udp(s)
        }
        _ => {
            let iface = match tcp.local_addr().map(|a| a.ip()) {
                Ok(std::net::IpAddr::V4(ip)) => ip,
                _ => dgram::DEFAULT_MCAST_INTERFACE,
            };
            let (group, first) = mcast_group(shared).await;
            let mut tcp = tcp;
            dgram::mcast_handshake_connect(&mut tcp, &shared.name, group)
                .await
                .map_err(io)?;
            drop(tcp);
            let sender = if first {
                Some(McastSender::open(group, iface).await.map_err(io)?)
            } else {
                None
            };
            Sink::Mcast(sender)
        }
    };
    let route = Route::new(&shared.name, target, carrier.name());
    let (tx, rx) = mpsc::channel(OUTPUT_QUEUE);
    let task = tokio::spawn(run(
        Arc::downgrade(shared),
        target.to_string(),
        contact.clone(),
        sink,
        rx,
    ));
    Ok(OutputHandle::new(route, tx, task))
}

/// The port's multicast group, allocated by the name server on first use (C++ registers
/// `... mcast` and records `owns`); falls back to C++'s fixed group. Returns whether this
/// call created it (that connection sends for all).
async fn mcast_group(shared: &Arc<Shared>) -> (SocketAddrV4, bool) {
    if let Some(g) = shared.lock().mcast_group {
        return (g, false);
    }
    let mut group = McastGroup::FALLBACK.addr();
    if let Some(ns) = &shared.ns {
        let req = RegisterRequest {
            carrier: Some("mcast".to_string()),
            ..Default::default()
        };
        if let Ok(Some(c)) = ns.register(&req).await {
            if let Ok(ip) = c.host.parse::<Ipv4Addr>() {
                group = SocketAddrV4::new(ip, c.port);
                let _ = ns
                    .set(&shared.name, "owns", &[Value::from(c.name.as_str())])
                    .await;
            }
        }
    }
    let mut st = shared.lock();
    match st.mcast_group {
        Some(g) => (g, false),
        None => {
            st.mcast_group = Some(group);
            (group, true)
        }
    }
}

async fn run(
    port: std::sync::Weak<Shared>,
    target: String,
    contact: Contact,
    mut sink: Sink,
    mut rx: mpsc::Receiver<Job>,
) {
    while let Some(job) = rx.recv().await {
        match job {
            Job::Data(msg) => {
                let bytes = msg.binary_message();
                let sent = match &mut sink {
                    Sink::Udp(s) => s.send_message(&bytes).await.map(|_| ()),
                    Sink::Mcast(Some(s)) => s.send_message(&bytes).await.map(|_| ()),
                    Sink::Mcast(None) => Ok(()),
                };
                if let Err(e) = sent {
                    tracing::debug!("datagram output to {target} failed: {e}");
                }
            }
            // datagram carriers carry no replies
            Job::Rpc(_, reply) => {
                let _ = reply.send(Err(OutputError::UnsupportedCarrier(
                    "rpc over a datagram carrier".to_string(),
                )
                .into()));
            }
            Job::Close(done) => {
                if let Some(shared) = port.upgrade() {
                    let line = format!("~{}", shared.name);
                    let _ = crate::network::admin_text(&contact, &[line.as_str()]).await;
                }
                if let Some(done) = done {
                    let _ = done.send(());
                }
                return;
            }
        }
    }
}
