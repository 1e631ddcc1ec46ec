//! Dynamic mode: every YARP port matching a name-server pattern is bridged to its own ROS
//! topic while it exists, and every ROS topic matching a topic pattern (as DDS discovery
//! sees its publishers) is mirrored into its own YARP port while it is published; both
//! are checked every [`SCAN_PERIOD`], on a node of their own that shares the gateway's
//! DDS participant.

use super::demand::Gate;
use super::topics::{keep_connected, ros_to_yarp, yarp_to_ros, JointNameSource};
use crate::counters::Counters;
use crate::mapping::TopicEntry;
use crate::pattern;
use crate::ros;
use ros2_client::Node;
use std::collections::{HashMap, HashSet};
use std::sync::Arc;
use std::time::Duration;
use tokio::task::JoinHandle;
use tracing::{debug, info, warn};
use yarp_net::nameserver::NameClient;
use yarp_net::port::{Port, PortError};

/// Why one matching port or topic could not be bridged (logged; the next scan retries).
#[derive(Debug, thiserror::Error)]
enum BridgeError {
    #[error(transparent)]
    Ros(#[from] ros::RosError),
    #[error(transparent)]
    Port(#[from] PortError),
    /// A topic or subscription DDS refused, as its Debug form says.
    #[error("{0:?}")]
    Dds(#[from] ros2_client::CreateError),
}

/// How often the name server is asked which ports exist.
pub const SCAN_PERIOD: Duration = Duration::from_secs(1);

/// One matched port's bridge.
struct Live {
    tasks: Vec<JoinHandle<()>>,
    port: Arc<Port>,
}

impl Live {
    async fn stop(self) {
        for t in &self.tasks {
            t.abort();
        }
        for t in self.tasks {
            let _ = t.await;
        }
        if let Ok(p) = Arc::try_unwrap(self.port) {
            p.close().await;
        }
    }
}

/// Runs the pattern entry `t` until aborted. The ports opened here are named
/// `<own_prefix><matched port>`; ports under `exclude` (all of the gateway's) and the name
/// server's own `/root` are never matched, so bridges do not chain.
pub(super) async fn run(
    mut node: Node,
    ns: NameClient,
    t: TopicEntry,
    own_prefix: String,
    exclude: String,
    c: Arc<Counters>,
) {
    let Some(pat) = t.yarp_pattern.clone() else {
        return;
    };
    let mut live: HashMap<String, Live> = HashMap::new();
    let mut tick = tokio::time::interval(SCAN_PERIOD);
    let me = node.fully_qualified_name();
    loop {
        tick.tick().await;
        let names: HashSet<String> = match ns.list(None).await {
            Ok(list) => list
                .into_iter()
                .map(|c| c.name)
                .filter(|n| pattern::matches(&pat, n) && !n.starts_with(&exclude) && n != "/root")
                .collect(),
            Err(e) => {
                debug!("{}: name server: {e}", t.name);
                continue;
            }
        };
        let gone: Vec<String> = live
            .keys()
            .filter(|n| !names.contains(*n))
            .cloned()
            .collect();
        for n in gone {
            if let Some(l) = live.remove(&n) {
                info!("{}: {n} is gone; bridge removed", t.name);
                l.stop().await;
            }
        }
        for n in names {
            if live.contains_key(&n) {
                continue;
            }
            match start_one(&mut node, &ns, &t, &n, &own_prefix, &me, c.clone()).await {
                Ok(l) => {
                    info!("{}: bridging {n}", t.name);
                    live.insert(n, l);
                }
                Err(e) => debug!("{}: {n}: {e}", t.name),
            }
        }
    }
}

async fn start_one(
    node: &mut Node,
    ns: &NameClient,
    t: &TopicEntry,
    source: &str,
    own_prefix: &str,
    me: &str,
    c: Arc<Counters>,
) -> Result<Live, BridgeError> {
    let topic = pattern::topic_for_port(&t.ros_topic, source);
    let publisher = ros::publisher(node, &topic, &t.ros_type, &t.qos)?;
    let port_name = format!("{own_prefix}{source}");
    let port = Arc::new(Port::open(&port_name, ns.clone()).await?);
    let names = JointNameSource::new(t, ns, me);
    let tasks = vec![
        tokio::spawn(yarp_to_ros(
            port.clone(),
            Arc::new(publisher),
            t.clone(),
            names,
            Default::default(),
            c,
        )),
        tokio::spawn(keep_connected(
            ns.clone(),
            port.clone(),
            Some(source.to_string()),
            None,
            // A pattern's ports come and go with the robot; keep them simply connected.
            Gate::always(),
        )),
    ];
    Ok(Live { tasks, port })
}

/// One mirrored ROS topic: its YARP port and the task feeding it.
struct Mirror {
    task: JoinHandle<()>,
    port: Arc<Port>,
}

/// The ROS topics (absolute names) that some other participant publishes, whose names
/// match `pat`, with their ROS types (`pkg/msg/Name`): of DDS type `dds_type` only, or
/// of any type when `dds_type` is `None`.
fn published_topics(
    dp: &ros2_client::dds::rustdds::DomainParticipant,
    pat: &str,
    dds_type: Option<&str>,
) -> HashMap<String, String> {
    use ros2_client::dds::rustdds::RTPSEntity;
    let me = dp.guid().prefix;
    dp.discovered_writers()
        .into_iter()
        .filter(|w| w.writer_proxy.remote_writer_guid.prefix != me)
        .filter(|w| dds_type.is_none_or(|d| w.publication_topic_data.type_name == d))
        .filter_map(|w| {
            let topic = w
                .publication_topic_data
                .topic_name
                .strip_prefix("rt")
                .filter(|n| n.starts_with('/') && pattern::matches(pat, n))?
                .to_string();
            let ty = ros_type_of(&w.publication_topic_data.type_name)?;
            Some((topic, ty))
        })
        .collect()
}

/// `pkg::msg::dds_::Name_` (the DDS type name rmw gives a message type) as `pkg/msg/Name`.
pub fn ros_type_of(dds_type: &str) -> Option<String> {
    let mut it = dds_type.split("::");
    match (it.next(), it.next(), it.next(), it.next(), it.next()) {
        (Some(p), Some(k @ "msg"), Some("dds_"), Some(n), None) if !p.is_empty() => {
            Some(format!("{p}/{k}/{}", n.strip_suffix('_')?))
        }
        _ => None,
    }
}

/// Runs the ROS-pattern entry `t` until aborted: every ROS topic matching `t.ros_topic`
/// (published by another participant, of type `t.ros_type`) is mirrored into the YARP
/// port `<yarp_port><topic>` while it has publishers (checked every [`SCAN_PERIOD`]).
pub(super) async fn run_ros(
    mut node: Node,
    dp: ros2_client::dds::rustdds::DomainParticipant,
    ns: NameClient,
    t: TopicEntry,
    c: Arc<Counters>,
) {
    // No ros_type: every matching topic, with the type its publishers announce.
    let dds_type = crate::types::dds_type_name(&t.ros_type);
    if dds_type.is_none() && !t.ros_type.is_empty() {
        return;
    }
    let prefix = t.yarp_port.clone().unwrap_or_default();
    let mut live: HashMap<String, Mirror> = HashMap::new();
    let mut unknown: HashSet<String> = HashSet::new();
    let mut tick = tokio::time::interval(SCAN_PERIOD);
    loop {
        tick.tick().await;
        let topics = published_topics(&dp, &t.ros_topic, dds_type.as_deref());
        let gone: Vec<String> = live
            .keys()
            .filter(|n| !topics.contains_key(*n))
            .cloned()
            .collect();
        for n in gone {
            if let Some(m) = live.remove(&n) {
                info!(
                    "{}: ROS topic {n} has no publisher left; mirror removed",
                    t.name
                );
                m.task.abort();
                let _ = m.task.await;
                if let Ok(p) = Arc::try_unwrap(m.port) {
                    p.close().await;
                }
            }
        }
        for (n, ty) in topics {
            if live.contains_key(&n) {
                continue;
            }
            let mut entry = t.clone();
            if t.ros_type.is_empty() {
                if crate::types::lookup(&ty).is_none() {
                    if unknown.insert(ty.clone()) {
                        warn!(
                            "{}: ROS topic {n} has type {ty}, which has no definition here \
                             (AMENT_PREFIX_PATH, --interfaces): not mirrored",
                            t.name
                        );
                    }
                    continue;
                }
                entry.ros_type = ty;
                entry.conversion = Some(crate::mapping::Conversion::Generic);
                ros::announce_type_hash(&dp, &entry.ros_type);
            }
            match mirror_one(&mut node, &ns, &entry, &n, &prefix, c.clone()).await {
                Ok(m) => {
                    info!("{}: mirroring ROS topic {n} ({})", t.name, entry.ros_type);
                    live.insert(n, m);
                }
                Err(e) => debug!("{}: {n}: {e}", t.name),
            }
        }
    }
}

async fn mirror_one(
    node: &mut Node,
    ns: &NameClient,
    t: &TopicEntry,
    topic: &str,
    prefix: &str,
    c: Arc<Counters>,
) -> Result<Mirror, BridgeError> {
    let rt = node.create_topic(
        &ros::name(topic)?,
        ros::message_type(&t.ros_type),
        &ros::qos(&t.qos),
    )?;
    let sub = node.create_subscription(&rt, None)?;
    let port = Arc::new(Port::open(&format!("{prefix}{topic}"), ns.clone()).await?);
    let task = tokio::spawn(ros_to_yarp(sub, port.clone(), None, t.clone(), c));
    Ok(Mirror { task, port })
}
