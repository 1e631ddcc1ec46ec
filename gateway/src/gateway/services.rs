//! Service bridges: ROS service servers calling YARP RPC ports, YARP RPC ports calling
//! ROS services, and the generic text RPC over String topics.

use super::yarp_rpc::{RpcError, YarpRpc};
use super::{Deferred, CALL_TIMEOUT};
use crate::convert::ConvertError;
use crate::counters::Counters;
use crate::dynmsg::{MsgSeed, Value as Ros};
use crate::mapping::ServiceEntry;
use crate::ros::{self, RosError};
use crate::service;
use crate::types::MsgType;
use futures::{pin_mut, StreamExt};
use ros2_client::{Client, Message, Node, Publisher, Server, Subscription};
use serde::de::DeserializeSeed;
use std::sync::Arc;
use std::time::Duration;
use std::time::Instant;
use tracing::{debug, warn};
use yarp_net::port::Port;
use yarp_proto::{Bottle, DecodeError, Value};

/// How long a service response waits for the requesting client's reader to be matched
/// (rmw_fastrtps waits for the writer's max_blocking_time; ours waits without blocking).
const CLIENT_MATCH_TIMEOUT: Duration = Duration::from_secs(2);

/// Why a YARP request builds no ROS service request.
#[derive(Debug, thiserror::Error)]
pub(super) enum RequestError {
    #[error(transparent)]
    Decode(#[from] DecodeError),
    #[error(transparent)]
    Convert(#[from] ConvertError),
    #[error("SetBool takes a bool first")]
    NotABool,
}

/// Why a YARP reply gives no generic ROS message ([`generic_reply`]).
#[derive(Debug, thiserror::Error)]
pub(super) enum ReplyError {
    #[error("the YARP port refused: `{0}`")]
    Refused(Bottle),
    #[error("the reply `{reply}` is not a {ty}: {source}")]
    NotA {
        reply: Bottle,
        ty: &'static str,
        source: ConvertError,
    },
    #[error(transparent)]
    Rpc(#[from] RpcError),
}

/// [`serve_ros`] on a new server of `s`, started once the node is shared.
pub(super) fn serve_later<Req, Resp, S>(
    node: &mut Node,
    s: &ServiceEntry,
    rpc: YarpRpc,
    c: Arc<Counters>,
    seed: S,
    cmd: impl Fn(&Req) -> Bottle + Send + Sync + 'static,
    resp: impl Fn(Result<Bottle, RpcError>) -> Resp + Send + Sync + 'static,
) -> Result<Deferred, RosError>
where
    Req: Message + Clone + Send + Sync + 'static,
    Resp: Message + Send + Sync + 'static,
    S: for<'de> DeserializeSeed<'de, Value = Req> + Clone + Send + Sync + 'static,
{
    let server = ros::server(node, &s.ros_service, &s.ros_type)?;
    Ok(Box::new(move |node| {
        tokio::spawn(serve_ros(server, node, rpc, c, seed, cmd, resp))
    }))
}

/// [`call_ros`] on a new client of `s`, started once the node is shared.
pub(super) fn call_later<Req, Resp, S>(
    node: &mut Node,
    s: &ServiceEntry,
    port: Arc<Port>,
    c: Arc<Counters>,
    seed: S,
    req: impl Fn(&Bottle) -> Result<Req, RequestError> + Send + Sync + 'static,
    reply: impl Fn(Resp) -> Bottle + Send + Sync + 'static,
) -> Result<Deferred, RosError>
where
    Req: Message + Clone + Send + Sync + 'static,
    Resp: Message + Send + Sync + 'static,
    S: for<'de> DeserializeSeed<'de, Value = Resp> + Clone + Send + Sync + 'static,
{
    let client = ros::client(node, &s.ros_service, &s.ros_type)?;
    let service_name = s.ros_service.clone();
    Ok(Box::new(move |node| {
        tokio::spawn(call_ros(
            port,
            client,
            node,
            c,
            service_name,
            seed,
            req,
            reply,
        ))
    }))
}

/// ROS service server -> YARP RPC: each request sends `cmd(request)` to the YARP port and
/// answers with `resp(reply or error)`.
/// Requests are decoded by `seed` (`PhantomData` for a compiled type, a [`MsgSeed`] for
/// one read at run time).
pub(super) async fn serve_ros<Req, Resp, S>(
    server: Server<Req, Resp>,
    node: Arc<Node>,
    mut rpc: YarpRpc,
    c: Arc<Counters>,
    seed: S,
    cmd: impl Fn(&Req) -> Bottle,
    resp: impl Fn(Result<Bottle, RpcError>) -> Resp,
) where
    Req: Message + Clone + 'static,
    Resp: Message + 'static,
    S: for<'de> DeserializeSeed<'de, Value = Req> + Clone,
{
    loop {
        let (id, req) = match server.async_receive_request_seed(seed.clone()).await {
            Ok(x) => x,
            Err(e) => {
                debug!("service request: {e:?}");
                c.dropped();
                continue;
            }
        };
        let t0 = Instant::now();
        let reply = rpc.call(&cmd(&req)).await;
        let failed = reply.is_err();
        if let Err(e) = &reply {
            warn!("{e}");
        }
        // A client's first request can arrive before our response writer has matched its
        // response reader; a response written then is lost. Wait for it, bounded.
        let matched = tokio::time::timeout(CLIENT_MATCH_TIMEOUT, server.wait_for_client(&node, id));
        if matched.await.is_err() {
            debug!("service response: the client's reader is not matched yet; answering anyway");
        }
        match server.async_send_response(id, resp(reply)).await {
            Ok(()) if !failed => c.forwarded(t0.elapsed()),
            _ => c.dropped(),
        }
    }
}

/// YARP RPC port -> ROS service client: each YARP request calls the ROS service, whose
/// responses `seed` decodes.
#[allow(clippy::too_many_arguments)]
pub(super) async fn call_ros<Req, Resp, S>(
    port: Arc<Port>,
    client: Client<Req, Resp>,
    node: Arc<Node>,
    c: Arc<Counters>,
    service_name: String,
    seed: S,
    req: impl Fn(&Bottle) -> Result<Req, RequestError>,
    reply: impl Fn(Resp) -> Bottle,
) where
    Req: Message + Clone + 'static,
    Resp: Message + 'static,
    S: for<'de> DeserializeSeed<'de, Value = Resp> + Clone,
{
    while let Some(mut inc) = port.read().await {
        let t0 = Instant::now();
        let Some(replier) = inc.take_replier() else {
            continue; // a plain write: nobody waits for an answer
        };
        let request = inc
            .bottle()
            .map_err(RequestError::from)
            .and_then(|b| req(&b));
        let r = match request {
            Ok(r) => r,
            Err(why) => {
                replier.send(service::fail_reply(&format!(
                    "cannot build the {service_name} request from this Bottle: {why}"
                )));
                c.dropped();
                continue;
            }
        };
        let call = async {
            client.wait_for_service(&node).await;
            client.async_call_service_seed(r, seed.clone()).await
        };
        match tokio::time::timeout(CALL_TIMEOUT, call).await {
            Ok(Ok(resp)) => {
                replier.send(reply(resp));
                c.forwarded(t0.elapsed());
            }
            Ok(Err(e)) => {
                replier.send(service::fail_reply(&format!("{service_name}: {e:?}")));
                c.dropped();
            }
            Err(_) => {
                replier.send(service::fail_reply(&format!(
                    "{service_name}: no answer within {CALL_TIMEOUT:?}"
                )));
                c.dropped();
            }
        }
    }
}

/// Generic text RPC: each `<service>/request` String is sent to the YARP port as a
/// Bottle; the reply's text is published on `<service>/reply`.
pub(super) async fn text_rpc(
    sub: Subscription<Ros>,
    publisher: Publisher<Ros>,
    mut rpc: YarpRpc,
    c: Arc<Counters>,
) {
    let Some(seed) = MsgSeed::new("std_msgs/msg/String") else {
        return;
    };
    let stream = sub.async_stream_seed(seed);
    pin_mut!(stream);
    while let Some(r) = stream.next().await {
        let t0 = Instant::now();
        let Ok((Ros::Struct(f), _)) = r else {
            c.dropped();
            continue;
        };
        let [Ros::Str(text)] = f.as_slice() else {
            c.dropped();
            continue;
        };
        let (reply, refused) = match rpc.call(&Bottle::from_text(text)).await {
            Ok(b) => {
                let reply = String::from_utf8_lossy(&b.to_text()).into_owned();
                // The robot refused the command: say so where ROS users look.
                let refused = (!service::reply_success(&b))
                    .then(|| format!("{} answered `{reply}` to `{text}`", rpc.target));
                (reply, refused)
            }
            Err(e) => {
                let refused = format!("`{text}`: {e}");
                (
                    service::fail_reply(&e.to_string()).to_string(),
                    Some(refused),
                )
            }
        };
        if let Some(why) = &refused {
            warn!("text RPC: {why}");
        }
        match publisher
            .async_publish(Ros::Struct(vec![Ros::Str(reply)]))
            .await
        {
            Ok(()) => match refused {
                Some(why) => c.refused(why),
                None => c.applied(t0.elapsed()),
            },
            Err(e) => c.refused(format!("reply not published: {e:?}")),
        }
    }
}

/// The request and response types of service `srv_type` (`pkg/srv/Name`), read at run time
/// or built in.
pub(super) fn generic_service_types(
    srv_type: &str,
) -> Result<(&'static MsgType, &'static MsgType), RosError> {
    let part = |p: &str| {
        crate::types::lookup(&format!("{srv_type}{p}")).ok_or_else(|| RosError::Entity {
            what: "service type",
            name: srv_type.to_string(),
            message: format!("no definition of its {p} structure"),
        })
    };
    Ok((part("_Request")?, part("_Response")?))
}

/// The Bottle a generic ROS request sends to YARP: the `words` configured, then the
/// request's fields in the generic layout.
pub(super) fn generic_command(words: &Bottle, t: &'static MsgType, req: &Ros) -> Bottle {
    let mut b = words.clone();
    match crate::generic::to_yarp(t, req) {
        Ok(fields) => b.extend(fields.into_items()),
        // The request was decoded against `t`: it always fits.
        Err(e) => warn!("{}: {e}", t.name),
    }
    b
}

/// Whether a YARP reply in place of a generic message refuses: `[fail] ...`, `[err]`,
/// `[nack]` (the generic layout has no vocabs but bools, so no message reads so).
pub(super) fn refused(b: &Bottle) -> bool {
    matches!(b.get(0), Some(Value::Vocab32(v))
        if ["fail", "err", "nack"].contains(&v.as_string().as_str()))
}

/// A YARP reply read as a message of `t` in its generic layout (fields left out take
/// their defaults), or why it is none: refused, not such a message, or no reply.
pub(super) fn generic_reply(
    t: &'static MsgType,
    reply: Result<Bottle, RpcError>,
) -> Result<Ros, ReplyError> {
    let b = reply?;
    if refused(&b) {
        return Err(ReplyError::Refused(b));
    }
    crate::generic::to_ros(t, &b, super::now_ns()).map_err(|source| ReplyError::NotA {
        reply: b,
        ty: t.name,
        source,
    })
}

/// `t`'s default value, as rosidl's default constructor gives it.
pub(super) fn default_of(t: &'static MsgType) -> Ros {
    Ros::zero(t.name).unwrap_or(Ros::Struct(Vec::new()))
}

/// The ROS response of a generic service for YARP's reply ([`generic_reply`]). A ROS
/// service cannot answer with an error: a failed call or a reply that does not fit gets
/// the default response, and the reason is logged.
pub(super) fn generic_response(
    service: &str,
    t: &'static MsgType,
    reply: Result<Bottle, RpcError>,
) -> Ros {
    generic_reply(t, reply).unwrap_or_else(|why| {
        warn!("{service}: {why}; answering the default response");
        default_of(t)
    })
}
