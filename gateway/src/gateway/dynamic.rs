//! Dynamic mode: every YARP port matching a name-server pattern is bridged to its own ROS
//! topic while it exists (checked every [`SCAN_PERIOD`]), on a node of its own that shares
//! the gateway's DDS participant.

use super::topics::{keep_connected, yarp_to_ros, JointNameSource};
use crate::counters::Counters;
use crate::mapping::TopicEntry;
use crate::pattern;
use crate::ros;
use ros2_client::Node;
use std::collections::{HashMap, HashSet};
use std::sync::Arc;
use std::time::Duration;
use tokio::task::JoinHandle;
use tracing::{debug, info};
use yarp_net::nameserver::NameClient;
use yarp_net::port::Port;

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
) -> Result<Live, String> {
    let topic = pattern::topic_for_port(&t.ros_topic, source);
    let publisher = ros::publisher(node, &topic, &t.ros_type, &t.qos).map_err(|e| e.to_string())?;
    let port_name = format!("{own_prefix}{source}");
    let port = Arc::new(
        Port::open(&port_name, ns.clone())
            .await
            .map_err(|e| e.to_string())?,
    );
    let names = JointNameSource::new(t, ns, me);
    let tasks = vec![
        tokio::spawn(yarp_to_ros(port.clone(), publisher, t.clone(), names, c)),
        tokio::spawn(keep_connected(
            ns.clone(),
            port.clone(),
            Some(source.to_string()),
            None,
        )),
    ];
    Ok(Live { tasks, port })
}
