//! Network-wide operations as C++ `yarp::os::Network` does them: finding the name server
//! from `yarp.conf`, and third-party connection management through a port's admin
//! protocol (the `CONNACK admin` sessions C++ opens for `yarp connect` and friends).

use crate::nameserver::{NameClient, NameClientError};
use std::net::{SocketAddr, ToSocketAddrs};
use std::path::{Path, PathBuf};
use std::time::Duration;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::time::timeout;
use yarp_proto::nameserver::{config_file_name, format_conf, parse_conf, ConfAddress};
use yarp_proto::{Bottle, Contact, PortRef};

/// How long an admin exchange with a port may take.
pub const ADMIN_TIMEOUT: Duration = Duration::from_secs(10);

#[derive(Debug, thiserror::Error)]
pub enum NetworkError {
    #[error("cannot find the name server: no readable {0} (run `yarp conf <ip> <port>` or start `yarp server`)")]
    NoConfig(PathBuf),
    #[error("cannot resolve name server address {0}")]
    BadAddress(String),
    #[error(transparent)]
    NameServer(#[from] NameClientError),
    #[error("port {0} not found")]
    UnknownPort(String),
    #[error("talking to {port}: {source}")]
    Io {
        port: String,
        source: std::io::Error,
    },
    #[error("{0} did not answer in time")]
    Timeout(String),
}

fn env_lookup(k: &str) -> Option<String> {
    std::env::var(k).ok()
}

fn read_file(p: &Path) -> Option<String> {
    std::fs::read_to_string(p).ok()
}

/// The `yarp.conf` (or namespace file) path in use, as C++ computes it.
pub fn conf_path() -> PathBuf {
    config_file_name(&env_lookup, &read_file)
}

/// The name server address recorded in `yarp.conf`.
pub fn read_conf() -> Result<ConfAddress, NetworkError> {
    let path = conf_path();
    read_file(&path)
        .and_then(|t| parse_conf(&t))
        .ok_or(NetworkError::NoConfig(path))
}

/// Writes `yarp.conf` as `yarp conf <ip> <port>` does.
pub fn write_conf(host: &str, port: u16) -> std::io::Result<PathBuf> {
    let path = conf_path();
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)?;
    }
    std::fs::write(&path, format_conf(host, port as i32, "yarp"))?;
    Ok(path)
}

/// A client for the name server named by `yarp.conf`.
pub fn name_client() -> Result<NameClient, NetworkError> {
    let conf = read_conf()?;
    let text = format!("{}:{}", conf.host, conf.port);
    let addr: SocketAddr = text
        .to_socket_addrs()
        .ok()
        .and_then(|mut a| a.next())
        .ok_or(NetworkError::BadAddress(text))?;
    Ok(NameClient::new(addr))
}

async fn lookup(ns: &NameClient, port: &str) -> Result<Contact, NetworkError> {
    ns.query(port)
        .await?
        .ok_or_else(|| NetworkError::UnknownPort(port.to_string()))
}

/// Sends one admin Bottle to a port over a `CONNACK admin` session and returns the reply.
pub async fn admin_command(contact: &Contact, cmd: &Bottle) -> Result<Bottle, NetworkError> {
    let mut req = b"CONNACK admin\r\na\r\n".to_vec();
    req.extend_from_slice(&cmd.to_text());
    req.extend_from_slice(b"\r\n");
    let reply = session(contact, &req, b"<ACK>\r\n").await?;
    // Welcome line, reply line, <ACK>
    let text = String::from_utf8_lossy(&reply);
    let line = text.split("\r\n").nth(1).unwrap_or("");
    Ok(Bottle::from_text(line))
}

/// Sends text-mode port commands (`~/port`, `!/port`...) over a `CONNECT admin` session,
/// then `q`; returns what the port wrote back after its welcome line.
pub async fn admin_text(contact: &Contact, lines: &[&str]) -> Result<String, NetworkError> {
    text_session(contact, "CONNECT admin", lines).await
}

/// A text_ack session as `sender` (C++ `yarp ping` uses `<ping>`): sends each line, then
/// `q`, and returns what the port wrote back after its welcome line, without the
/// `<ACK>` lines.
pub async fn admin_text_ack(
    contact: &Contact,
    sender: &str,
    lines: &[&str],
) -> Result<String, NetworkError> {
    let body = text_session(contact, &format!("CONNACK {sender}"), lines).await?;
    Ok(body.replace("<ACK>\r\n", ""))
}

/// Opens a text-carrier connection with `header` (`CONNECT name` / `CONNACK name`), sends
/// `lines` then `q`, and returns everything after the welcome line.
async fn text_session(
    contact: &Contact,
    header: &str,
    lines: &[&str],
) -> Result<String, NetworkError> {
    let mut req = format!("{header}\r\n").into_bytes();
    for l in lines {
        req.extend_from_slice(l.as_bytes());
        req.extend_from_slice(b"\r\n");
    }
    req.extend_from_slice(b"q\r\n");
    let reply = session(contact, &req, b"").await?;
    let text = String::from_utf8_lossy(&reply);
    Ok(text
        .split_once("\r\n")
        .map(|(_, rest)| rest.to_string())
        .unwrap_or_default())
}

/// Writes `req`, reads until `until` appears (or the port closes), bounded in time.
async fn session(contact: &Contact, req: &[u8], until: &[u8]) -> Result<Vec<u8>, NetworkError> {
    let name = contact.name.clone();
    let io = |source| NetworkError::Io {
        port: contact.name.clone(),
        source,
    };
    let work = async {
        let mut s = crate::auth::connect((contact.host.as_str(), contact.port))
            .await
            .map_err(io)?;
        s.write_all(req).await.map_err(io)?;
        let mut got = Vec::new();
        let mut buf = [0u8; 4096];
        loop {
            if !until.is_empty() && got.windows(until.len()).any(|w| w == until) {
                break;
            }
            let n = s.read(&mut buf).await.map_err(io)?;
            if n == 0 {
                break;
            }
            got.extend_from_slice(&buf[..n]);
            if got.len() > 1 << 20 {
                break;
            }
        }
        let _ = s.shutdown().await;
        Ok(got)
    };
    timeout(ADMIN_TIMEOUT, work)
        .await
        .map_err(|_| NetworkError::Timeout(name))?
}

/// Connects `from` to `to` through `from`'s admin protocol, as `yarp connect`. Returns
/// the port's reply (code 0 on success, and its message).
pub async fn connect(
    ns: &NameClient,
    from: &str,
    to: &str,
    carrier: Option<&str>,
) -> Result<(bool, String), NetworkError> {
    let source = PortRef::parse(from).name;
    let src = lookup(ns, &source).await?;
    let dest = PortRef::parse(to);
    let dst = lookup(ns, &dest.name).await?;
    let carrier = carrier.map(str::to_string).or(dest.carrier.clone());
    // a pull carrier (mjpeg): the destination connects to the source (C++ metaConnect
    // asks the destination to `add` the source)
    if let Some(c) = &carrier {
        let base = yarp_proto::wire::modifiers::CarrierName::parse(c).base;
        if yarp_proto::wire::Carrier::from_name(&base).is_some_and(|k| !k.is_push()) {
            let mut cmd = Bottle::new();
            cmd.add_vocab("add");
            cmd.push(
                PortRef {
                    carrier: Some(c.clone()),
                    name: source,
                }
                .to_string()
                .as_str(),
            );
            let reply = admin_command(&dst, &cmd).await?;
            return Ok(reply_outcome(&reply));
        }
    }
    // YARP 4.0: with YARP_CONNECTIONS_STATS_ENABLE=1 every connection made here gets a
    // stats_monitor (on the carrier asked for, else the destination's)
    let carrier = if std::env::var("YARP_CONNECTIONS_STATS_ENABLE").as_deref() == Ok("1") {
        let c = carrier.unwrap_or_else(|| dst.carrier.clone());
        Some(yarp_proto::portmonitor::with_stats_monitor(
            &source, &dest.name, &c,
        ))
        .filter(|c| !c.is_empty())
    } else {
        carrier
    };
    let target = match carrier {
        Some(c) => PortRef {
            carrier: Some(c),
            name: dest.name.clone(),
        }
        .to_string(),
        None => dest.name.clone(),
    };
    let mut cmd = Bottle::new();
    cmd.add_vocab("add");
    cmd.push(target.as_str());
    let reply = admin_command(&src, &cmd).await?;
    Ok(reply_outcome(&reply))
}

/// Removes the connection `from` -> `to`, as `yarp disconnect`.
pub async fn disconnect(
    ns: &NameClient,
    from: &str,
    to: &str,
) -> Result<(bool, String), NetworkError> {
    let source = PortRef::parse(from).name;
    let src = lookup(ns, &source).await?;
    let dest = PortRef::parse(to).name;
    let dst = lookup(ns, &dest).await?;
    let mut cmd = Bottle::new();
    cmd.add_vocab("del");
    cmd.push(dest.as_str());
    let reply = admin_command(&src, &cmd).await?;
    let outcome = reply_outcome(&reply);
    if outcome.0 {
        return Ok(outcome);
    }
    // not an output of the source: a pulled connection (mjpeg) belongs to the
    // destination, which opened it
    let mut cmd = Bottle::new();
    cmd.add_vocab("list");
    cmd.add_vocab("in");
    cmd.push(source.as_str());
    let pulled = admin_command(&dst, &cmd)
        .await
        .ok()
        .and_then(|listed| {
            let c = listed.find("carrier")?.as_str()?.to_string();
            yarp_proto::wire::Carrier::from_name(
                &yarp_proto::wire::modifiers::CarrierName::parse(&c).base,
            )
        })
        .is_some_and(|c| !c.is_push());
    if !pulled {
        return Ok(outcome);
    }
    let mut cmd = Bottle::new();
    cmd.add_vocab("del");
    cmd.push(source.as_str());
    let reply = admin_command(&dst, &cmd).await?;
    Ok(reply_outcome(&reply))
}

/// Whether `from` has an output to `to` (`[list] [out] to` answers with details).
pub async fn is_connected(ns: &NameClient, from: &str, to: &str) -> Result<bool, NetworkError> {
    Ok(connection_carrier(ns, from, to).await?.is_some())
}

/// The carrier of the connection `from` -> `to`, if there is one.
pub async fn connection_carrier(
    ns: &NameClient,
    from: &str,
    to: &str,
) -> Result<Option<String>, NetworkError> {
    let src = lookup(ns, &PortRef::parse(from).name).await?;
    let mut cmd = Bottle::new();
    cmd.add_vocab("list");
    cmd.add_vocab("out");
    cmd.push(PortRef::parse(to).name.as_str());
    let reply = admin_command(&src, &cmd).await?;
    if reply.is_empty() {
        return Ok(None);
    }
    Ok(Some(
        reply
            .find("carrier")
            .and_then(|v| v.as_str())
            .unwrap_or("tcp")
            .to_string(),
    ))
}

/// Whether a port is registered and answers on its address (`yarp exists`).
pub async fn exists(ns: &NameClient, port: &str) -> Result<bool, NetworkError> {
    let Some(c) = ns.query(port).await? else {
        return Ok(false);
    };
    let reachable = timeout(
        Duration::from_secs(3),
        crate::auth::connect((c.host.as_str(), c.port)),
    )
    .await;
    Ok(matches!(reachable, Ok(Ok(_))))
}

fn reply_outcome(reply: &Bottle) -> (bool, String) {
    let ok = reply.get(0).and_then(|v| v.as_i64()) == Some(0);
    let msg = reply
        .get(1)
        .and_then(|v| v.as_str())
        .map(str::to_string)
        .unwrap_or_else(|| reply.to_string());
    (ok, msg)
}
