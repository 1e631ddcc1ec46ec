//! The gateway's RPC client towards YARP ports (lazy connect, reconnect after errors).

use super::CALL_TIMEOUT;
use yarp_net::nameserver::NameClient;
use yarp_net::rpc::RpcClient;
use yarp_proto::wire::Carrier;
use yarp_proto::Bottle;

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
    pub(super) async fn call(&mut self, cmd: &Bottle) -> Result<Bottle, String> {
        let r = tokio::time::timeout(CALL_TIMEOUT, self.call_inner(cmd)).await;
        match r {
            Ok(Ok(b)) => Ok(b),
            Ok(Err(e)) => {
                self.client = None;
                Err(e)
            }
            Err(_) => {
                self.client = None;
                Err(format!("{}: no reply within {CALL_TIMEOUT:?}", self.target))
            }
        }
    }

    async fn call_inner(&mut self, cmd: &Bottle) -> Result<Bottle, String> {
        if self.client.is_none() {
            let contact = self
                .ns
                .query(&self.target)
                .await
                .map_err(|e| e.to_string())?
                .ok_or_else(|| format!("{} is not registered", self.target))?;
            let c = RpcClient::connect(&contact, &self.me, Carrier::Tcp)
                .await
                .map_err(|e| e.to_string())?;
            self.client = Some(c);
        }
        let c = self.client.as_mut().expect("connected above");
        c.call(cmd).await.map_err(|e| e.to_string())
    }
}
