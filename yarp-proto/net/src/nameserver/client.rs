//! A name-server client that behaves on the wire as C++ `NameClient`: one TCP connection
//! per request, the exact request bytes of [`yarp_proto::nameserver`], reading the reply
//! up to its last line (a line starting with `*` or `[`), every wait bounded.

use std::io;
use std::net::SocketAddr;
use std::time::Duration;

use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::time::timeout;

use yarp_proto::nameserver::{
    parse_check_reply, parse_property_reply, parse_registration, request_announce, request_check,
    request_get, request_list, request_query, request_register, request_set, request_set_accepts,
    request_set_ips, request_set_offers, request_set_process, request_unregister, CheckReply,
    PropertyReply, RegisterRequest,
};
use yarp_proto::{Contact, Value};

/// Longest reply accepted (a `list` of many ports fits easily).
const MAX_REPLY: usize = 4 * 1024 * 1024;

#[derive(Debug, thiserror::Error)]
pub enum NameClientError {
    #[error("name server i/o: {0}")]
    Io(#[from] io::Error),
    #[error("name server did not answer within {0:?}")]
    Timeout(Duration),
    #[error("name server reply longer than {MAX_REPLY} bytes")]
    TooLong,
    #[error("unexpected name server reply: {0:?}")]
    Unexpected(String),
}

/// Talks to one name server.
#[derive(Debug, Clone)]
pub struct NameClient {
    server: SocketAddr,
    timeout: Duration,
}

/// Whether the text holds a complete reply, as C++ decides: a line longer than one byte
/// starting with `*` (the end marker) or `[` (`[ok]`).
fn reply_complete(buf: &[u8]) -> bool {
    buf.split_inclusive(|&b| b == b'\n')
        .filter(|l| l.ends_with(b"\n"))
        .any(|l| {
            let l = l.strip_suffix(b"\n").unwrap_or(l);
            l.len() > 1 && (l[0] == b'*' || l[0] == b'[')
        })
}

impl NameClient {
    /// A client with C++'s 10 s timeout.
    pub fn new(server: SocketAddr) -> NameClient {
        NameClient {
            server,
            timeout: Duration::from_secs(10),
        }
    }

    pub fn with_timeout(mut self, t: Duration) -> NameClient {
        self.timeout = t;
        self
    }

    pub fn server(&self) -> SocketAddr {
        self.server
    }

    /// Sends raw request bytes on a fresh connection and returns the reply text.
    pub async fn request(&self, bytes: &[u8]) -> Result<String, NameClientError> {
        let t = self.timeout;
        let mut stream = timeout(t, crate::auth::connect(self.server))
            .await
            .map_err(|_| NameClientError::Timeout(t))??;
        let _ = stream.set_nodelay(true);
        timeout(t, stream.write_all(bytes))
            .await
            .map_err(|_| NameClientError::Timeout(t))??;
        let mut buf = Vec::new();
        let mut chunk = [0u8; 4096];
        loop {
            let n = timeout(t, stream.read(&mut chunk))
                .await
                .map_err(|_| NameClientError::Timeout(t))??;
            if n == 0 {
                break;
            }
            buf.extend_from_slice(&chunk[..n]);
            if buf.len() > MAX_REPLY {
                return Err(NameClientError::TooLong);
            }
            if reply_complete(&buf) {
                break;
            }
        }
        let _ = stream.shutdown().await;
        Ok(String::from_utf8_lossy(&buf).into_owned())
    }

    /// `query`: where a port is, `None` if unknown.
    pub async fn query(&self, name: &str) -> Result<Option<Contact>, NameClientError> {
        Ok(parse_registration(
            &self.request(&request_query(name)).await?,
        ))
    }

    /// A single `register` request.
    pub async fn register(
        &self,
        req: &RegisterRequest,
    ) -> Result<Option<Contact>, NameClientError> {
        Ok(parse_registration(
            &self.request(&request_register(req)).await?,
        ))
    }

    /// Registers a port as a C++ port does when it opens: `register`, `set offers`,
    /// `set accepts`, `set ips`, `set process`, then `announce` (6 connections).
    pub async fn register_port(
        &self,
        req: &RegisterRequest,
        ips: &[&str],
        pid: i32,
    ) -> Result<Contact, NameClientError> {
        let reply = self.request(&request_register(req)).await?;
        let c = parse_registration(&reply).ok_or(NameClientError::Unexpected(reply))?;
        self.request(&request_set_offers(&c.name)).await?;
        self.request(&request_set_accepts(&c.name)).await?;
        self.request(&request_set_ips(&c.name, ips)).await?;
        self.request(&request_set_process(&c.name, pid)).await?;
        self.announce(&c.name).await?;
        Ok(c)
    }

    /// `unregister` (the reply carries nothing).
    pub async fn unregister(&self, name: &str) -> Result<(), NameClientError> {
        self.request(&request_unregister(name)).await.map(|_| ())
    }

    /// `announce`: true when the server answered `[ok]`.
    pub async fn announce(&self, name: &str) -> Result<bool, NameClientError> {
        Ok(self
            .request(&request_announce(name))
            .await?
            .starts_with("[ok]"))
    }

    /// `set`: `None` if the port is unknown.
    pub async fn set(
        &self,
        name: &str,
        key: &str,
        values: &[Value],
    ) -> Result<Option<PropertyReply>, NameClientError> {
        Ok(parse_property_reply(
            &self.request(&request_set(name, key, values)).await?,
        ))
    }

    /// `get` (sent as `yarp name get` does: `NAME_SERVER get <name> <key>\n`).
    pub async fn get(
        &self,
        name: &str,
        key: &str,
    ) -> Result<Option<PropertyReply>, NameClientError> {
        Ok(parse_property_reply(
            &self.request(&request_get(name, key)).await?,
        ))
    }

    /// `check`.
    pub async fn check(
        &self,
        name: &str,
        key: &str,
        value: &str,
    ) -> Result<Option<CheckReply>, NameClientError> {
        Ok(parse_check_reply(
            &self.request(&request_check(name, key, value)).await?,
        ))
    }

    /// `list` (optionally under a prefix): every registration.
    pub async fn list(&self, prefix: Option<&str>) -> Result<Vec<Contact>, NameClientError> {
        let reply = self.request(&request_list(prefix)).await?;
        Ok(reply.lines().filter_map(parse_registration).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn completion() {
        assert!(!reply_complete(b"registration name /x\r\n"));
        assert!(reply_complete(
            b"registration name /x\r\n*** end of message\r\n"
        ));
        assert!(reply_complete(b"[ok]\r\n"));
        assert!(!reply_complete(b"*** end of mess"));
    }
}
