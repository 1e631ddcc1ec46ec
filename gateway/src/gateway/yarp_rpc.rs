//! The gateway's RPC client towards YARP ports (lazy connect, reconnect after errors).

use super::CALL_TIMEOUT;
use std::time::Duration;
use yarp_net::nameserver::{NameClient, NameClientError};
use yarp_net::port::PortError;
use yarp_net::rpc::RpcClient;
use yarp_proto::wire::Carrier;
use yarp_proto::Bottle;

/// Why a call to a YARP port gave no reply (what a ROS caller is told).
#[derive(Debug, thiserror::Error)]
pub enum RpcError {
    /// The name server could not be asked where the port is.
    #[error(transparent)]
    NameServer(#[from] NameClientError),
    #[error("{port} is not registered")]
    NotRegistered { port: String },
    /// The port refused the connection, or it broke.
    #[error(transparent)]
    Port(#[from] PortError),
    #[error("{port}: no reply within {after:?}")]
    Timeout { port: String, after: Duration },
    /// The port answered without what was asked.
    #[error("{port}: {what} answered `{reply}`")]
    BadReply {
        port: String,
        what: &'static str,
        reply: String,
    },
}

/// A lazily (re)connected RPC client to one YARP port.
pub(super) struct YarpRpc {
    ns: NameClient,
    pub(super) target: String,
    me: String,
    client: Option<RpcClient>,
}

impl YarpRpc {
    pub(super) fn new(ns: NameClient, target: &str, me: &str) -> YarpRpc {
        YarpRpc {
            ns,
            target: target.to_string(),
            me: me.to_string(),
            client: None,
        }
    }

    /// Sends `cmd` and returns the reply; errors drop the connection (the next call
    /// reconnects, so a restarted server is picked up).
    pub(super) async fn call(&mut self, cmd: &Bottle) -> Result<Bottle, RpcError> {
        self.call_within(cmd, CALL_TIMEOUT).await
    }

    /// As [`Self::call`], waiting up to `limit` (an action's goal runs as long as it takes).
    pub(super) async fn call_within(
        &mut self,
        cmd: &Bottle,
        limit: Duration,
    ) -> Result<Bottle, RpcError> {
        let r = tokio::time::timeout(limit, self.call_inner(cmd)).await;
        match r {
            Ok(Ok(b)) => Ok(b),
            Ok(Err(e)) => {
                self.client = None;
                Err(e)
            }
            Err(_) => {
                self.client = None;
                Err(RpcError::Timeout {
                    port: self.target.clone(),
                    after: limit,
                })
            }
        }
    }

    async fn call_inner(&mut self, cmd: &Bottle) -> Result<Bottle, RpcError> {
        if self.client.is_none() {
            let contact =
                self.ns
                    .query(&self.target)
                    .await?
                    .ok_or_else(|| RpcError::NotRegistered {
                        port: self.target.clone(),
                    })?;
            let c = RpcClient::connect(&contact, &self.me, Carrier::Tcp).await?;
            self.client = Some(c);
        }
        let c = self.client.as_mut().expect("connected above");
        Ok(c.call(cmd).await?)
    }

    /// [`RpcError::BadReply`] for `reply` to the request `what`.
    pub(super) fn bad_reply(&self, what: &'static str, reply: &Bottle) -> RpcError {
        RpcError::BadReply {
            port: self.target.clone(),
            what,
            reply: reply.to_string(),
        }
    }
}
