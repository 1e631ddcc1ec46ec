//! Multicast discovery of the name server, as C++ `FallbackNameServer` /
//! `FallbackNameClient`: the server listens on group 224.2.1.1 at its own port number
//! (10000 by default) for datagrams holding a `NAME_SERVER <command>` line and multicasts
//! the reply; `yarp detect` sends `NAME_SERVER query <namespace>` and waits for a
//! `registration ...` line. Datagrams carry the usual 8-byte CRC/counter header.

use crate::dgram::{McastReceiver, McastSender};
use parking_lot::Mutex;
use std::io;
use std::net::{Ipv4Addr, SocketAddrV4};
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::watch;
use yarp_proto::nameserver::{parse_registration, reply_text, Registry};
use yarp_proto::wire::datagram::{encode_datagram, parse_datagram};
use yarp_proto::{Bottle, Contact};

/// The C++ fallback group.
pub const FALLBACK_GROUP: Ipv4Addr = Ipv4Addr::new(224, 2, 1, 1);

/// The first text line of a datagram, without its line end.
fn first_line(datagram: &[u8]) -> Option<String> {
    let (_, payload) = parse_datagram(datagram).ok()?;
    let text = String::from_utf8_lossy(payload);
    let line = text.split('\n').next().unwrap_or("");
    Some(line.trim_end_matches('\r').to_string())
}

/// Answers multicast queries until `shutdown` turns true. Errors joining the group are
/// logged and end the task (the TCP server keeps working).
pub(crate) async fn serve(
    registry: Arc<Mutex<Registry>>,
    port: u16,
    interface: Ipv4Addr,
    mut shutdown: watch::Receiver<bool>,
) {
    let group = SocketAddrV4::new(FALLBACK_GROUP, port);
    let (rx, tx) = match (
        McastReceiver::join(group, interface).await,
        McastSender::open(group, interface).await,
    ) {
        (Ok(rx), Ok(tx)) => (rx, tx),
        (Err(e), _) | (_, Err(e)) => {
            tracing::info!("multicast fallback on {group} not available: {e}");
            return;
        }
    };
    let mut buf = vec![0u8; 65536];
    loop {
        let n = tokio::select! {
            _ = shutdown.changed() => return,
            r = rx.socket().recv_from(&mut buf) => match r {
                Ok((n, _)) => n,
                Err(_) => continue,
            },
        };
        let Some(line) = first_line(&buf[..n]) else {
            continue;
        };
        if !line.starts_with("NAME_SERVER ") || line.len() > 4096 {
            continue;
        }
        let reply = {
            let mut reg = registry.lock();
            reg.apply(&Bottle::from_text(&line), None)
        };
        let _ = tx
            .socket()
            .send(&encode_datagram(0, &reply_text(&reply)))
            .await;
    }
}

/// Looks for a name server by multicast (`yarp detect`): the address of `namespace`
/// (`/root` by default), or `None` if nobody answered within `wait`.
pub async fn detect(
    port: u16,
    namespace: &str,
    interface: Ipv4Addr,
    wait: Duration,
) -> io::Result<Option<Contact>> {
    let group = SocketAddrV4::new(FALLBACK_GROUP, port);
    let rx = McastReceiver::join(group, interface).await?;
    let tx = McastSender::open(group, interface).await?;
    let query = format!("NAME_SERVER query {namespace}\n");
    tx.socket()
        .send(&encode_datagram(0, query.as_bytes()))
        .await?;
    let mut buf = vec![0u8; 65536];
    let deadline = tokio::time::Instant::now() + wait;
    loop {
        let r = tokio::time::timeout_at(deadline, rx.socket().recv_from(&mut buf)).await;
        let Ok(Ok((n, _))) = r else {
            return Ok(None);
        };
        if let Some(line) = first_line(&buf[..n]) {
            if line.starts_with("registration ") {
                return Ok(parse_registration(&line));
            }
        }
    }
}
