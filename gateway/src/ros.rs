//! The DDS side: one participant restricted to the configured networks, one node, and
//! helpers turning mapping data into ros2-client names and QoS.

use crate::mapping;
use ros2_client::dds::rustdds::{DomainParticipantBuilder, DomainParticipantSecurityConfigFiles};
use ros2_client::qos::{Durability, History, Reliability, WhenFull};
use ros2_client::{
    Context, MessageTypeName, Name, Node, NodeName, NodeOptions, QosProfile, ServiceTypeName,
};
use std::net::IpAddr;
use std::time::Duration;

/// Why the ROS side could not be set up.
#[derive(Debug, thiserror::Error)]
pub enum RosError {
    #[error("DDS participant for domain {domain}: {message}")]
    Participant { domain: u16, message: String },
    #[error("ROS node {name}: {message}")]
    Node { name: String, message: String },
    #[error("ROS name `{name}`: {message}")]
    Name { name: String, message: String },
    #[error("{what} on {name}: {message}")]
    Entity {
        what: &'static str,
        name: String,
        message: String,
    },
    /// SROS2 asked for with `ROS_SECURITY_STRATEGY=Enforce` and the enclave unusable.
    #[error(transparent)]
    Security(#[from] crate::security::SecurityError),
}

impl RosError {
    /// A ROS entity (`what`: topic, publisher, service...) on `name` that ros2-client
    /// refused to make.
    pub fn entity(what: &'static str, name: &str, e: impl std::fmt::Debug) -> RosError {
        RosError::Entity {
            what,
            name: name.to_string(),
            message: format!("{e:?}"),
        }
    }
}

/// Starts the gateway's single DDS participant (as a ros2-client context) and its node.
///
/// `domain` is passed explicitly (ros2-client's `Context::new` ignores ROS_DOMAIN_ID);
/// `networks` limits RustDDS to those interface addresses (empty: all interfaces).
pub fn start_node(
    domain: u16,
    networks: &[IpAddr],
    namespace: &str,
    node_name: &str,
) -> Result<(Context, Node), RosError> {
    let ctx = start_context(domain, networks)?;
    let node = new_node(&ctx, namespace, node_name)?;
    Ok((ctx, node))
}

/// A DDS participant as a ros2-client context, announcing the type hash of every catalog
/// type; nodes are added with [`new_node`]. Only one node of a participant may spin: the
/// spinners of several would share (split) the participant's discovery events.
pub fn start_context(domain: u16, networks: &[IpAddr]) -> Result<Context, RosError> {
    let security =
        crate::security::from_env(&|k| std::env::var(k).ok(), crate::security::enclave())?;
    start_context_with(domain, networks, security)
}

/// [`start_context`] secured as `security` says rather than as the environment says.
pub fn start_context_with(
    domain: u16,
    networks: &[IpAddr],
    security: crate::security::Security,
) -> Result<Context, RosError> {
    let mut b = DomainParticipantBuilder::new(domain);
    if !networks.is_empty() {
        b = b.with_only_networks(networks.iter().copied());
    }
    let peers = static_peers_from_env();
    if !peers.is_empty() {
        b = b.static_peers(peers);
    }
    if let crate::security::Security::Enclave(dir) = security {
        // SROS2 writes unencrypted PKCS#8 keys: no password.
        b = b.builtin_security(
            DomainParticipantSecurityConfigFiles::with_ros_default_names(dir, String::new()),
        );
    }
    let dp = b.build().map_err(|e| RosError::Participant {
        domain,
        message: e.to_string(),
    })?;
    // Every endpoint announces its REP-2016 type hash, as rmw does, so ROS tools show
    // the same hash as for rclpy's endpoints rather than INVALID.
    for (dds_type, user_data) in crate::hash::endpoint_user_data() {
        dp.set_endpoint_user_data(&dds_type, user_data.into_bytes());
    }
    Context::from_domain_participant(dp).map_err(|e| RosError::Participant {
        domain,
        message: format!("{e:?}"),
    })
}

/// The ROS domain of this process as rcl reads it: `$ROS_DOMAIN_ID`, else 0.
pub fn domain_from_env() -> Result<u16, RosError> {
    match std::env::var("ROS_DOMAIN_ID") {
        Ok(s) if !s.trim().is_empty() => s.trim().parse().map_err(|_| RosError::Participant {
            domain: 0,
            message: format!("ROS_DOMAIN_ID `{s}` is not a domain number"),
        }),
        _ => Ok(0),
    }
}

/// The hosts of `$ROS_STATIC_PEERS` (addresses or names separated by `;`, as rmw reads
/// them): discovery announces this process to each by unicast too, so a host that
/// multicast does not reach (another subnet, a VPN) finds the gateway. A name that does
/// not resolve is reported and left out.
pub fn static_peers_from_env() -> Vec<IpAddr> {
    parse_static_peers(&std::env::var("ROS_STATIC_PEERS").unwrap_or_default())
}

fn parse_static_peers(list: &str) -> Vec<IpAddr> {
    use std::net::ToSocketAddrs;
    let mut out = Vec::new();
    for host in list.split(';').map(str::trim).filter(|h| !h.is_empty()) {
        let ip = host.parse::<IpAddr>().ok().or_else(|| {
            let addrs = (host, 0)
                .to_socket_addrs()
                .ok()?
                .map(|a| a.ip())
                .collect::<Vec<_>>();
            // IPv4 first: RustDDS discovers over IPv4
            addrs
                .iter()
                .find(|a| a.is_ipv4())
                .or(addrs.first())
                .copied()
        });
        match ip {
            Some(ip) if !out.contains(&ip) => out.push(ip),
            Some(_) => {}
            None => tracing::warn!("ROS_STATIC_PEERS: `{host}` does not resolve; left out"),
        }
    }
    out
}

/// The interfaces discovery may use, as rmw reads `$ROS_AUTOMATIC_DISCOVERY_RANGE`:
/// `LOCALHOST` keeps to the loopback interface, anything else (or unset) uses all; the
/// older `ROS_LOCALHOST_ONLY=1` (which Jazzy still honours) does the same.
pub fn networks_from_env() -> Vec<IpAddr> {
    let localhost = matches!(
        std::env::var("ROS_AUTOMATIC_DISCOVERY_RANGE").as_deref(),
        Ok("LOCALHOST")
    ) || matches!(std::env::var("ROS_LOCALHOST_ONLY").as_deref(), Ok("1"));
    if localhost {
        vec![IpAddr::from([127, 0, 0, 1])]
    } else {
        Vec::new()
    }
}

/// What `--ros-args` said, for the process's main node: its remaps apply to every topic and
/// service name made with [`name`], its parameters are declared on the main node.
struct ProcessRosArgs {
    args: crate::ros_args::RosArgs,
    namespace: String,
    node_name: String,
    params: Vec<(String, ros2_client::ParameterValue)>,
}

static ROS_ARGS: std::sync::OnceLock<ProcessRosArgs> = std::sync::OnceLock::new();

/// A topic or service name after this process's `--ros-args` remaps.
pub fn remapped(n: &str) -> String {
    match ROS_ARGS.get() {
        Some(r) => r.args.remap(&r.namespace, &r.node_name, n),
        None => n.to_string(),
    }
}

/// Sets this process's `--ros-args` (once, before any node or name is made) for the main
/// node `namespace`/`node_name`; `params` are the parameters to declare on it (`-p` and
/// `--params-file`, already merged).
pub fn set_ros_args(
    args: crate::ros_args::RosArgs,
    namespace: &str,
    node_name: &str,
    params: Vec<(String, ros2_client::ParameterValue)>,
) {
    let _ = ROS_ARGS.set(ProcessRosArgs {
        args,
        namespace: namespace.to_string(),
        node_name: node_name.to_string(),
        params,
    });
}

/// The main node's read-only parameters: the gateway's settings, for `ros2 param list/get`.
static READ_ONLY: std::sync::OnceLock<Vec<(String, ros2_client::ParameterValue)>> =
    std::sync::OnceLock::new();

/// Declares `settings` on the main node (the one [`set_ros_args`] names) as read-only
/// parameters: `ros2 param get` reads them, `ros2 param set` is refused (once, before the
/// node is made).
pub fn set_read_only_parameters(settings: Vec<(String, ros2_client::ParameterValue)>) {
    let _ = READ_ONLY.set(settings);
}

/// Another node on the same participant (dynamic mode creates endpoints at run time on
/// its own node, so the main node can be shared read-only).
pub fn new_node(ctx: &Context, namespace: &str, node_name: &str) -> Result<Node, RosError> {
    let err = |e: &dyn std::fmt::Debug| RosError::Node {
        name: node_name.to_string(),
        message: format!("{e:?}"),
    };
    let name = NodeName::new(namespace, node_name).map_err(|e| err(&e))?;
    let mut options = NodeOptions::new().enable_rosout(false);
    if let Some(r) = ROS_ARGS
        .get()
        .filter(|r| r.node_name == node_name && r.namespace == namespace)
    {
        for (k, v) in &r.params {
            options = options.declare_parameter(k, v.clone());
        }
        if let Some(fixed) = READ_ONLY.get() {
            for (k, v) in fixed {
                options = options.declare_parameter(k, v.clone());
            }
            // The validator also sees the declared values: those pass, changes do not.
            options = options.parameter_validator(Box::new(|name, value| {
                match READ_ONLY
                    .get()
                    .and_then(|f| f.iter().find(|(k, _)| k == name))
                {
                    Some((_, v)) if v != value => Err(format!(
                        "parameter '{name}' cannot be set because it is read-only"
                    )),
                    _ => Ok(()),
                }
            }));
        }
    }
    ctx.new_node(name, options).map_err(|e| err(&e))
}

/// The topic `topic_name` of `ros_type`, to make publishers and subscriptions on.
pub fn topic(
    node: &Node,
    topic_name: &str,
    ros_type: &str,
    q: &QosProfile,
) -> Result<ros2_client::dds::rustdds::Topic, RosError> {
    node.create_topic(&name(topic_name)?, message_type(ros_type), q)
        .map_err(|e| RosError::entity("topic", topic_name, e))
}

/// A publisher of dynamic messages of `ros_type` on `topic`.
pub fn publisher(
    node: &mut Node,
    topic_name: &str,
    ros_type: &str,
    q: &mapping::Qos,
) -> Result<ros2_client::Publisher<crate::dynmsg::Value>, RosError> {
    let t = topic(node, topic_name, ros_type, &qos(q))?;
    node.create_publisher(&t, None)
        .map_err(|e| RosError::entity("publisher", topic_name, e))
}

/// A subscription of dynamic messages of `ros_type` on `topic` (decode them with
/// [`crate::dynmsg::MsgSeed`]).
pub fn subscription(
    node: &mut Node,
    topic_name: &str,
    ros_type: &str,
    q: &mapping::Qos,
) -> Result<ros2_client::Subscription<crate::dynmsg::Value>, RosError> {
    let t = topic(node, topic_name, ros_type, &qos(q))?;
    node.create_subscription(&t, None)
        .map_err(|e| RosError::entity("subscription", topic_name, e))
}

/// A server of service `name` of type `pkg/srv/Name` (Enhanced service mapping, as
/// rmw_fastrtps; [`service_qos`]).
pub fn server<Req, Resp>(
    node: &mut Node,
    name_: &str,
    srv_type: &str,
) -> Result<ros2_client::Server<Req, Resp>, RosError>
where
    Req: ros2_client::Message + Clone + 'static,
    Resp: ros2_client::Message + 'static,
{
    let (n, t, q) = (name(name_)?, service_type(srv_type), service_qos());
    node.create_server(ros2_client::ServiceMapping::Enhanced, &n, &t, q.clone(), q)
        .map_err(|e| RosError::entity("service", name_, e))
}

/// A client of service `name` of type `pkg/srv/Name` (as [`server`]).
pub fn client<Req, Resp>(
    node: &mut Node,
    name_: &str,
    srv_type: &str,
) -> Result<ros2_client::Client<Req, Resp>, RosError>
where
    Req: ros2_client::Message + Clone + 'static,
    Resp: ros2_client::Message + 'static,
{
    let (n, t, q) = (name(name_)?, service_type(srv_type), service_qos());
    node.create_client(ros2_client::ServiceMapping::Enhanced, &n, &t, q.clone(), q)
        .map_err(|e| RosError::entity("client", name_, e))
}

/// Makes the endpoints of `ros_type` that `dp` creates from now on announce its REP-2016
/// hash, as rmw does (the built-in catalog's are set when the participant starts; a type
/// read from its definition at run time is set here, before its first endpoint).
pub fn announce_type_hash(dp: &ros2_client::dds::rustdds::DomainParticipant, ros_type: &str) {
    let Some(dds) = crate::types::dds_type_name(ros_type) else {
        return;
    };
    if dp.endpoint_user_data(&dds).is_empty() {
        if let Ok(ud) = crate::hash::user_data(ros_type) {
            dp.set_endpoint_user_data(&dds, ud.into_bytes());
        }
    }
}

/// As [`announce_type_hash`] for the request and response topics of service (or action
/// service) `srv_type`: both announce the service's hash, as rmw does.
pub fn announce_service_type_hash(
    dp: &ros2_client::dds::rustdds::DomainParticipant,
    srv_type: &str,
) {
    let Ok(ud) = crate::hash::user_data(srv_type) else {
        return;
    };
    for part in ["_Request", "_Response"] {
        if let Some(dds) = crate::types::dds_type_name(&format!("{srv_type}{part}")) {
            if dp.endpoint_user_data(&dds).is_empty() {
                dp.set_endpoint_user_data(&dds, ud.clone().into_bytes());
            }
        }
    }
}

/// The node whose clock is this process's ROS time ([`now_ns`]).
static CLOCK_NODE: std::sync::Mutex<Option<std::sync::Weak<Node>>> = std::sync::Mutex::new(None);

/// Makes `node`'s clock this process's ROS time: with its `use_sim_time` parameter true
/// (`--ros-args -p use_sim_time:=true`, or set at run time) the time of the last `/clock`
/// message (0 before the first, as rclcpp), else the system clock.
pub fn use_clock_of(node: &std::sync::Arc<Node>) {
    *CLOCK_NODE.lock().unwrap_or_else(|e| e.into_inner()) = Some(std::sync::Arc::downgrade(node));
}

/// This process's ROS time in ns since the epoch: the stamps the gateway gives messages
/// whose YARP data carries none (see [`use_clock_of`]).
pub fn now_ns() -> u64 {
    let node = CLOCK_NODE
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .as_ref()
        .and_then(std::sync::Weak::upgrade);
    match node {
        Some(n) => u64::try_from(n.time_now().to_nanos()).unwrap_or(0),
        None => std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_nanos() as u64)
            .unwrap_or(0),
    }
}

/// A ROS topic or service name (`/a/b`, or relative `b`).
pub fn name(n: &str) -> Result<Name, RosError> {
    let n = &remapped(n);
    Name::parse(n).map_err(|e| RosError::Name {
        name: n.to_string(),
        message: format!("{e:?}"),
    })
}

/// `pkg/msg/Name` as ros2-client's message type name; `pkg/action/Name_FeedbackMessage`
/// (an action's topic) keeps its `action` part (`pkg::action::dds_::…_`).
pub fn message_type(ros_type: &str) -> MessageTypeName {
    match crate::types::split_name(ros_type) {
        Some((pkg, "action", name)) => {
            ros2_client::ActionTypeName::new(pkg, name).dds_action_topic("")
        }
        Some((pkg, _, name)) => MessageTypeName::new(pkg, name),
        None => MessageTypeName::new("", ros_type),
    }
}

/// `pkg/srv/Name` as ros2-client's service type name; `pkg/action/Name_SendGoal` (an
/// action's service) keeps its `action` part.
pub fn service_type(ros_type: &str) -> ServiceTypeName {
    match crate::types::split_name(ros_type) {
        Some((pkg, "action", name)) => {
            ros2_client::ActionTypeName::new(pkg, name).dds_action_service("")
        }
        Some((pkg, _, name)) => ServiceTypeName::new(pkg, name),
        None => ServiceTypeName::new("", ros_type),
    }
}

/// The mapping's QoS as a ros2-client profile. A full reliable send window waits at most
/// 20 ms (then the message counts as a drop) so one slow reader cannot stall a bridge.
pub fn qos(q: &mapping::Qos) -> QosProfile {
    let p = QosProfile::publisher_default()
        .durability(match q.durability {
            mapping::Durability::Volatile => Durability::Volatile,
            mapping::Durability::TransientLocal => Durability::TransientLocal,
        })
        .history(History::KeepLast {
            depth: q.depth as usize,
        });
    match q.reliability() {
        mapping::Reliability::Reliable => p.reliability(Reliability::Reliable {
            when_full: WhenFull::Wait(Duration::from_millis(20)),
        }),
        mapping::Reliability::BestEffort => p.reliability_best_effort(),
    }
}

/// QoS of service endpoints (reliable, volatile, depth 10: rclpy's service default).
pub fn service_qos() -> QosProfile {
    qos(&mapping::Qos::default())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn static_peers_read_as_rmw_lists_them() {
        assert_eq!(
            parse_static_peers(" 10.0.1.5; localhost;;10.0.1.5 ;::1"),
            [
                IpAddr::from([10, 0, 1, 5]),
                IpAddr::from([127, 0, 0, 1]),
                "::1".parse::<IpAddr>().unwrap()
            ]
        );
        assert!(parse_static_peers("").is_empty());
        assert!(parse_static_peers("no-such-host.invalid").is_empty());
    }

    #[test]
    fn dds_type_names_keep_the_interface_kind() {
        assert_eq!(
            message_type("std_msgs/msg/String").dds_msg_type(),
            "std_msgs::msg::dds_::String_"
        );
        assert_eq!(
            message_type("test_msgs/action/Fibonacci_FeedbackMessage").dds_msg_type(),
            "test_msgs::action::dds_::Fibonacci_FeedbackMessage_"
        );
        // The same names as ros2-client's own action endpoints.
        let a = ros2_client::ActionTypeName::new("test_msgs", "Fibonacci");
        assert_eq!(
            format!("{:?}", service_type("test_msgs/action/Fibonacci_SendGoal")),
            format!("{:?}", a.dds_action_service("_SendGoal"))
        );
        assert_eq!(
            format!("{:?}", service_type("std_srvs/srv/Trigger")),
            format!("{:?}", ServiceTypeName::new("std_srvs", "Trigger"))
        );
    }
}
