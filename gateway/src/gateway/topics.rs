//! Topic bridges: YARP port <-> ROS topic tasks, and keeping YARP connections up.

use super::beside::Beside;
use super::demand::Gate;
use super::yarp_rpc::{RpcError, YarpRpc};
use super::{now_ns, RECONNECT_PERIOD};
use crate::axis_info;
use crate::convert;
use crate::counters::{Counters, RateLimit};
use crate::dynmsg::{MsgSeed, Value as Ros};
use crate::mapping::{Conversion, JointNames, TopicEntry};
use futures::{pin_mut, StreamExt};
use ros2_client::{Gid, Publisher, Subscription};
use std::sync::Arc;
use std::time::{Duration, Instant};
use tracing::{debug, info};
use yarp_net::nameserver::NameClient;
use yarp_net::network;
use yarp_net::port::Port;

/// Where a joint_state bridge gets its joint names (and which joints are prismatic);
/// asked again (at most once a second) until the control board answers.
pub(super) enum JointNameSource {
    Known(Joints),
    AxisInfo {
        rpc: Box<YarpRpc>,
        next_try: Instant,
    },
}

/// Joint names and, per joint, whether it is prismatic (meters, not degrees).
#[derive(Debug, Clone, Default)]
pub(super) struct Joints {
    names: Vec<String>,
    prismatic: Vec<bool>,
}

impl JointNameSource {
    pub(super) fn new(t: &TopicEntry, ns: &NameClient, me: &str) -> JointNameSource {
        match &t.joint_names {
            Some(JointNames::AxisInfo { rpc_port }) => JointNameSource::AxisInfo {
                rpc: Box::new(YarpRpc::new(ns.clone(), rpc_port, me)),
                next_try: Instant::now(),
            },
            Some(JointNames::List { names }) => JointNameSource::Known(Joints {
                names: names.clone(),
                prismatic: vec![false; names.len()],
            }),
            None => JointNameSource::Known(Joints::default()),
        }
    }

    /// The joints, once known.
    async fn get(&mut self) -> Option<&Joints> {
        if let JointNameSource::AxisInfo { rpc, next_try } = self {
            if Instant::now() < *next_try {
                return None;
            }
            *next_try = Instant::now() + Duration::from_secs(1);
            match ask_joints(rpc).await {
                Ok(joints) => {
                    info!("joints from {}: {joints:?}", rpc.target);
                    *self = JointNameSource::Known(joints);
                }
                Err(e) => {
                    debug!("joint names: {e}");
                    return None;
                }
            }
        }
        match self {
            JointNameSource::Known(j) => Some(j),
            JointNameSource::AxisInfo { .. } => None,
        }
    }
}

async fn ask_joints(rpc: &mut YarpRpc) -> Result<Joints, RpcError> {
    let reply = rpc.call(&axis_info::axes_request()).await?;
    let n = axis_info::parse_axes(&reply).ok_or_else(|| rpc.bad_reply("[get] [axes]", &reply))?;
    let mut joints = Joints::default();
    for j in 0..n {
        let reply = rpc.call(&axis_info::name_request(j)).await?;
        joints.names.push(
            axis_info::parse_name(&reply).ok_or_else(|| rpc.bad_reply("[get] [name]", &reply))?,
        );
        // A board that cannot tell the type is taken as revolute (the common case).
        let reply = rpc.call(&axis_info::type_request(j)).await?;
        joints
            .prismatic
            .push(axis_info::parse_prismatic(&reply).unwrap_or(false));
    }
    Ok(joints)
}

/// YARP -> ROS: every Bottle read on the gateway's port becomes one ROS message.
pub(super) async fn yarp_to_ros(
    port: Arc<Port>,
    publisher: Arc<Publisher<Ros>>,
    t: TopicEntry,
    mut names: JointNameSource,
    beside: Beside,
    c: Arc<Counters>,
) {
    let conv = t.conversion();
    let mut limit = t.rate_limit_hz.map(RateLimit::new);
    let frame_id = t.frame_id.clone().unwrap_or_default();
    while let Some(mut inc) = port.read().await {
        let t0 = Instant::now();
        let none = Joints::default();
        let joints: &Joints = if conv == Conversion::JointState {
            match names.get().await {
                Some(j) => j,
                None => {
                    c.dropped();
                    continue;
                }
            }
        } else {
            &none
        };
        let ctx = convert::Ctx {
            frame_id: &frame_id,
            joint_names: &joints.names,
            joint_prismatic: &joints.prismatic,
            sensor_index: t.sensor_index.unwrap_or(0),
            stamp_ns: inc
                .stamp
                .and_then(|s| (s.time > 0.0).then_some((s.time * 1e9) as u64))
                .unwrap_or_else(now_ns),
        };
        if limit.as_mut().is_some_and(|l| !l.admit(t0)) {
            c.dropped();
            continue;
        }
        // Taken, not copied: a 2.7 MB image keeps the received buffer (or, over
        // `local`, the sender's Bottle) on its way into the ROS message.
        let msg = inc.take_bottle().map_err(|e| e.to_string()).and_then(|b| {
            convert::to_ros_owned(conv, &t.ros_type, b, &ctx).map_err(|e| e.to_string())
        });
        if let Ok(m) = &msg {
            beside.publish(m).await;
        }
        match msg {
            Ok(m) => match publisher.async_publish(m).await {
                Ok(()) => c.forwarded(t0.elapsed()),
                Err(e) => {
                    debug!("{}: publish: {e:?}", t.name);
                    c.dropped();
                }
            },
            Err(e) => {
                debug!("{}: {e}", t.name);
                c.dropped();
            }
        }
    }
}

/// ROS -> YARP: every ROS message becomes one Bottle written on the gateway's port.
/// Messages from the gateway's own publisher (direction `both`) are skipped.
pub(super) async fn ros_to_yarp(
    sub: Subscription<Ros>,
    port: Arc<Port>,
    own: Option<Gid>,
    t: TopicEntry,
    c: Arc<Counters>,
) {
    let conv = t.conversion();
    let Some(seed) = MsgSeed::new(&t.ros_type) else {
        return;
    };
    let mut limit = t.rate_limit_hz.map(RateLimit::new);
    // The generic layout's header.stamp travels in the envelope too.
    let stamped = (conv == Conversion::Generic)
        .then(|| crate::types::lookup(&t.ros_type))
        .flatten();
    let mut count = 0i32;
    let stream = sub.async_stream_seed(seed);
    pin_mut!(stream);
    while let Some(r) = stream.next().await {
        let t0 = Instant::now();
        let (m, info) = match r {
            Ok(x) => x,
            Err(e) => {
                debug!("{}: take: {e:?}", t.name);
                c.dropped();
                continue;
            }
        };
        if own.is_some_and(|g| g == info.publisher_gid()) {
            continue;
        }
        if limit.as_mut().is_some_and(|l| !l.admit(t0)) {
            c.dropped();
            continue;
        }
        match convert::to_yarp(conv, &t.ros_type, &m) {
            Ok(b) => {
                let stamp = stamped
                    .and_then(|ty| crate::generic::header_time(ty, &m))
                    .map(|time| {
                        count = count.wrapping_add(1);
                        yarp_proto::Stamp::new(count, time)
                    });
                port.write_nowait(&b, stamp);
                c.forwarded(t0.elapsed());
            }
            Err(e) => {
                debug!("{}: {e}", t.name);
                c.dropped();
            }
        }
    }
}

/// Keeps `source -> port` and `port -> sink` connected while those ports exist; the
/// source only while `gate` is open (someone on the ROS side wants its messages: see
/// [`super::demand`]), so an unwatched stream costs neither side anything.
pub(super) async fn keep_connected(
    ns: NameClient,
    port: Arc<Port>,
    source: Option<String>,
    sink: Option<String>,
    gate: Gate,
) {
    let mut tick = tokio::time::interval(RECONNECT_PERIOD);
    loop {
        tick.tick().await;
        if let Some(src) = &source {
            let connected = port.inputs().iter().any(|i| i == src);
            let wanted = gate.open();
            if wanted && !connected {
                match network::connect(&ns, src, port.name(), None).await {
                    Ok((true, _)) => info!("connected {src} -> {}", port.name()),
                    Ok((false, why)) => debug!("connect {src} -> {}: {why}", port.name()),
                    Err(e) => debug!("connect {src} -> {}: {e}", port.name()),
                }
            } else if !wanted && connected {
                match network::disconnect(&ns, src, port.name()).await {
                    Ok((true, _)) => {
                        info!("disconnected {src} -> {}: no ROS subscriber", port.name())
                    }
                    Ok((false, why)) => debug!("disconnect {src} -> {}: {why}", port.name()),
                    Err(e) => debug!("disconnect {src} -> {}: {e}", port.name()),
                }
            }
        }
        if let Some(dst) = &sink {
            if !port.outputs().iter().any(|o| o == dst) {
                match port.connect(dst, None).await {
                    Ok(()) => info!("connected {} -> {dst}", port.name()),
                    Err(e) => debug!("connect {} -> {dst}: {e}", port.name()),
                }
            }
        }
    }
}
