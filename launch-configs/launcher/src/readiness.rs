//! Readiness checks: has a module come up (port registered, TCP listening, log line seen)?

use crate::config::ReadyCheck;
use std::time::Duration;
use tokio::net::TcpStream;
use tokio::sync::broadcast;
use yarp_net::nameserver::NameClient;
use yarp_net::network;

/// How often polled checks look again.
pub const POLL: Duration = Duration::from_millis(150);

/// Whether a YARP port is registered and accepts TCP connections.
pub async fn port_exists(ns: &NameClient, port: &str) -> bool {
    matches!(
        tokio::time::timeout(Duration::from_secs(2), network::exists(ns, port)).await,
        Ok(Ok(true))
    )
}

/// Whether `addr` accepts TCP connections.
pub async fn tcp_listening(addr: &str) -> bool {
    matches!(
        tokio::time::timeout(Duration::from_secs(1), TcpStream::connect(addr)).await,
        Ok(Ok(_))
    )
}

/// Waits (unbounded: the caller adds the timeout) until `check` passes. `logs` must have
/// been subscribed before the module was spawned so no line is missed.
pub async fn wait_until(
    check: &ReadyCheck,
    ns: &NameClient,
    logs: &mut broadcast::Receiver<String>,
) {
    match check {
        ReadyCheck::Delay(d) => tokio::time::sleep(*d).await,
        ReadyCheck::Port(p) => {
            while !port_exists(ns, p).await {
                tokio::time::sleep(POLL).await;
            }
        }
        ReadyCheck::Tcp(a) => {
            while !tcp_listening(a).await {
                tokio::time::sleep(POLL).await;
            }
        }
        ReadyCheck::Log(text) => loop {
            match logs.recv().await {
                Ok(line) if line.contains(text.as_str()) => return,
                Ok(_) | Err(broadcast::error::RecvError::Lagged(_)) => {}
                // The output ended (module exited): never ready; the caller sees the exit.
                Err(broadcast::error::RecvError::Closed) => std::future::pending::<()>().await,
            }
        },
    }
}

/// Waits until every port in `ports` exists.
pub async fn wait_ports(ns: &NameClient, ports: &[String]) {
    for p in ports {
        while !port_exists(ns, p).await {
            tokio::time::sleep(POLL).await;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn log_and_tcp_checks() {
        let (tx, mut rx) = broadcast::channel(8);
        let ns = NameClient::new("127.0.0.1:1".parse().unwrap());
        tx.send("starting".to_string()).unwrap();
        tx.send("bus can0 ready".to_string()).unwrap();
        tokio::time::timeout(
            Duration::from_secs(1),
            wait_until(&ReadyCheck::Log("ready".into()), &ns, &mut rx),
        )
        .await
        .unwrap();
        let l = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
        let addr = l.local_addr().unwrap().to_string();
        tokio::time::timeout(
            Duration::from_secs(2),
            wait_until(&ReadyCheck::Tcp(addr), &ns, &mut rx),
        )
        .await
        .unwrap();
        assert!(!port_exists(&ns, "/nothing").await);
    }
}
