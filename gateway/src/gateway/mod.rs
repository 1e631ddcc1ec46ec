//! The running gateway: one tokio task per bridged mapping over one DDS participant (the
//! main ROS node, plus one node per dynamic-mode entry) and the YARP network. Conversions live in [`crate::convert`] and
//! [`crate::service`]; this module only moves messages and counts them.

mod actions;
mod beside;
mod commands;
mod demand;
mod dynamic;
mod follow;
mod robot;
mod services;
mod topics;
mod yarp_rpc;

use self::demand::{Demand, Gate};
use self::services::{
    call_later, generic_command, generic_response, generic_service_types, serve_later, text_rpc,
    RequestError,
};
use self::topics::{keep_connected, ros_to_yarp, yarp_to_ros, JointNameSource};
use self::yarp_rpc::YarpRpc;
use crate::counters::{self, Counters, Row};
use crate::dynmsg::{MsgSeed, Value as Ros};
use crate::mapping::{
    ActionEntry, Conversion, Direction, Durability, Mappings, ServiceConversion, ServiceEntry,
    TopicEntry,
};
use crate::ros::{self, RosError};
use crate::service::{self, EmptyMsg, OutcomeResponse, SetBoolRequest, StdSrv};
use ros2_client::{Context, Node, Publisher, Subscription};
use std::marker::PhantomData;
use std::net::IpAddr;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Duration;
use tokio::task::JoinHandle;
use tracing::{debug, warn};
use yarp_net::nameserver::NameClient;
use yarp_net::port::{Port, PortError};
use yarp_proto::Bottle;

/// How long a bridged RPC or service call may take before it fails.
pub const CALL_TIMEOUT: Duration = Duration::from_secs(5);
/// How often `yarp_source` / `yarp_sink` connections are checked and restored.
pub const RECONNECT_PERIOD: Duration = Duration::from_millis(500);

/// Runtime settings (the mapping files say what to bridge; these say how).
#[derive(Debug, Clone)]
pub struct Options {
    /// ROS domain id (ROS_DOMAIN_ID).
    pub domain_id: u16,
    /// Interface addresses DDS may use; empty means all.
    pub networks: Vec<IpAddr>,
    pub namespace: String,
    pub node_name: String,
    /// Period of the `/diagnostics` DiagnosticArray; `None` disables it.
    pub diagnostics_period: Option<Duration>,
    /// YARP port carrying the same counters as Bottles; `None` disables it.
    pub diagnostics_port: Option<String>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            domain_id: 0,
            networks: Vec::new(),
            namespace: "/".into(),
            node_name: "yarp_ros2_gateway".into(),
            diagnostics_period: Some(Duration::from_secs(1)),
            diagnostics_port: None,
        }
    }
}

/// Why the gateway could not start.
#[derive(Debug, thiserror::Error)]
pub enum StartError {
    #[error(transparent)]
    Ros(#[from] RosError),
    #[error("YARP port {name}: {source}")]
    Port { name: String, source: PortError },
    #[error("entry {name}: cannot start its control-board thread: {source}")]
    Thread {
        name: String,
        source: std::io::Error,
    },
}

/// One bridged mapping, as shown in the startup table and the diagnostics.
#[derive(Debug, Clone)]
pub struct Bridge {
    pub name: String,
    pub direction: Direction,
    pub yarp: String,
    pub ros: String,
    pub ros_type: String,
    pub detail: String,
    pub counters: Arc<Counters>,
}

impl Bridge {
    fn row(&self) -> Row {
        Row {
            name: self.name.clone(),
            route: format!(
                "{} {} <-> {} ({})",
                self.direction, self.yarp, self.ros, self.ros_type
            ),
            snapshot: self.counters.snapshot(),
            problem: self.counters.problem(),
        }
    }
}

/// A running gateway. Dropping it stops every bridge.
pub struct Gateway {
    bridges: Vec<Bridge>,
    tasks: Vec<JoinHandle<()>>,
    ports: Vec<Arc<Port>>,
    node: Option<Arc<Node>>,
    /// The node's spinner: not aborted but stopped by dropping the node (ros2-client logs
    /// an error when a node outlives its spinner).
    spinner: Option<JoinHandle<()>>,
    ctx: Context,
}

/// Tasks that can only start once the node is shared (after all entities exist).
type Deferred = Box<dyn FnOnce(Arc<Node>) -> JoinHandle<()> + Send>;

impl Gateway {
    /// Creates every endpoint of `m` and starts bridging.
    pub async fn start(m: &Mappings, ns: NameClient, opt: Options) -> Result<Gateway, StartError> {
        let (ctx, mut node) =
            ros::start_node(opt.domain_id, &opt.networks, &opt.namespace, &opt.node_name)?;
        let spinner = node
            .spinner()
            .map_err(|e| RosError::entity("spinner", &opt.node_name, e))?;
        let spinner = tokio::spawn(async move {
            if let Err(e) = spinner.spin().await {
                warn!("ROS spinner stopped: {e:?}");
            }
        });
        let mut g = Builder {
            ns,
            ctx: ctx.clone(),
            namespace: opt.namespace.clone(),
            node_name: opt.node_name.clone(),
            tasks: Vec::new(),
            deferred: Vec::new(),
            bridges: Vec::new(),
            ports: Vec::new(),
            robots: robot::Robots::new(&m.robots),
        };
        for t in &m.topics {
            g.topic(&mut node, t).await?;
        }
        for s in &m.services {
            g.service(&mut node, s).await?;
        }
        for a in &m.actions {
            g.action(&mut node, a).await?;
        }
        let robots = std::mem::take(&mut g.robots);
        for r in &m.robots {
            g.robot(&mut node, r, &robots)?;
        }
        g.diagnostics(&mut node, &opt).await?;
        let node = Arc::new(node);
        ros::use_clock_of(&node);
        let mut tasks = std::mem::take(&mut g.tasks);
        tasks.extend(g.deferred.drain(..).map(|d| d(node.clone())));
        Ok(Gateway {
            bridges: std::mem::take(&mut g.bridges),
            tasks,
            ports: std::mem::take(&mut g.ports),
            node: Some(node),
            spinner: Some(spinner),
            ctx,
        })
    }

    /// How many received samples the DDS participant keeps per topic, by topic name: a
    /// diagnostic of what stays in memory (discovery must forget nodes that left).
    pub fn dds_topic_cache_samples(&self) -> Vec<(String, usize)> {
        self.ctx.domain_participant().topic_cache_sample_counts()
    }

    /// How many samples each of the DDS participant's writers keeps for sending and
    /// repair, by topic name, discovery's own writers included: a diagnostic of what
    /// stays in memory (a writer keeps at most its History depth once its readers have
    /// what they need).
    pub fn dds_writer_samples(&self) -> Vec<(String, usize)> {
        self.ctx.domain_participant().writer_sample_counts()
    }

    pub fn bridges(&self) -> &[Bridge] {
        &self.bridges
    }

    /// The node's DDS domain.
    pub fn domain_id(&self) -> u16 {
        self.node.as_ref().map_or(0, |n| n.domain_id())
    }

    /// The startup table: one line per bridged mapping.
    pub fn table(&self) -> String {
        let head = ["name", "dir", "yarp", "ros", "type", "how"];
        let rows: Vec<[String; 6]> = self
            .bridges
            .iter()
            .map(|b| {
                [
                    b.name.clone(),
                    b.direction.to_string(),
                    b.yarp.clone(),
                    b.ros.clone(),
                    b.ros_type.clone(),
                    b.detail.clone(),
                ]
            })
            .collect();
        let mut w = head.map(str::len);
        for r in &rows {
            for (i, c) in r.iter().enumerate() {
                w[i] = w[i].max(c.len());
            }
        }
        let line = |cells: &[&str]| {
            let mut s = String::new();
            for (i, c) in cells.iter().enumerate() {
                s.push_str(&format!("{c:<width$}  ", width = w[i]));
            }
            s.trim_end().to_string() + "\n"
        };
        let mut out = line(&head);
        for r in &rows {
            out.push_str(&line(&r.each_ref().map(String::as_str)));
        }
        out
    }

    /// Stops every bridge and closes the YARP ports (unregistering them).
    pub async fn shutdown(mut self) {
        for t in &self.tasks {
            t.abort();
        }
        for t in self.tasks.drain(..) {
            let _ = t.await;
        }
        for p in self.ports.drain(..) {
            if let Ok(p) = Arc::try_unwrap(p) {
                p.close().await;
            }
        }
        // Endpoints are gone with their tasks; now the node, which stops its spinner.
        self.node = None;
        if let Some(s) = self.spinner.take() {
            if tokio::time::timeout(Duration::from_secs(2), s)
                .await
                .is_err()
            {
                warn!("ROS spinner did not stop");
            }
        }
    }
}

impl Drop for Gateway {
    fn drop(&mut self) {
        for t in &self.tasks {
            t.abort();
        }
        // Without `shutdown`, the spinner stops when the last task releases the node.
        if let Some(s) = self.spinner.take() {
            drop(s);
        }
    }
}

struct Builder {
    ns: NameClient,
    /// For the extra nodes of dynamic mode (same participant).
    ctx: Context,
    namespace: String,
    node_name: String,
    tasks: Vec<JoinHandle<()>>,
    deferred: Vec<Deferred>,
    bridges: Vec<Bridge>,
    ports: Vec<Arc<Port>>,
    /// The `[[robot]]` entries' merged joint states, fed by their parts' bridges.
    robots: robot::Robots,
}

/// A start that fails half-way must not leave bridges running behind the caller's back.
impl Drop for Builder {
    fn drop(&mut self) {
        for t in &self.tasks {
            t.abort();
        }
    }
}

impl Builder {
    async fn open_port(&mut self, name: &str) -> Result<Arc<Port>, StartError> {
        let p = Port::open(name, self.ns.clone())
            .await
            .map_err(|source| StartError::Port {
                name: name.to_string(),
                source,
            })?;
        let p = Arc::new(p);
        self.ports.push(p.clone());
        Ok(p)
    }

    /// A dynamic-mode entry's own node on the shared participant, named after the entry's
    /// place in the table (`<node>_dyn<k>`).
    fn dynamic_node(&self) -> Result<Node, RosError> {
        let name = format!("{}_dyn{}", self.node_name, self.bridges.len());
        ros::new_node(&self.ctx, &self.namespace, &name)
    }

    async fn topic(&mut self, node: &mut Node, t: &TopicEntry) -> Result<(), StartError> {
        ros::announce_type_hash(&self.ctx.domain_participant(), &t.ros_type);
        if t.is_ros_pattern() {
            return self.ros_pattern(t);
        }
        let Some(port_name) = &t.yarp_port else {
            return self.pattern(t);
        };
        let conv = t.conversion();
        if conv == Conversion::JointCommand {
            return self.joint_command(node, t);
        }
        let port = self.open_port(port_name).await?;
        let qos = ros::qos(&t.qos);
        let topic = ros::topic(node, &t.ros_topic, &t.ros_type, &qos)?;
        let counters = Arc::new(Counters::default());
        let mut own = None;
        let mut camera_info = None;
        let mut demand = Demand::always();
        if t.direction.to_ros() {
            let publisher: Arc<Publisher<Ros>> = Arc::new(
                node.create_publisher(&topic, None)
                    .map_err(|e| RosError::entity("publisher", &t.ros_topic, e))?,
            );
            own = Some(publisher.gid());
            if t.qos.durability != Durability::TransientLocal {
                demand = self.robots.demand(&t.name);
                demand.add(publisher.clone());
            }
            let (port, t2, c) = (port.clone(), t.clone(), counters.clone());
            let names = JointNameSource::new(t, &self.ns, &node.fully_qualified_name());
            let beside = beside::Beside {
                tap: self.robots.tap(&t.name),
                camera_info: beside::CameraInfoOut::of(node, t)?,
            };
            if let Some(ci) = &beside.camera_info {
                camera_info = Some(ci.topic.clone());
                // A CameraInfo subscriber alone wants the images too.
                demand.add(ci.publisher.clone());
            }
            self.tasks.push(tokio::spawn(yarp_to_ros(
                port, publisher, t2, names, beside, c,
            )));
        }
        if t.direction.to_yarp() {
            let sub: Subscription<Ros> = node
                .create_subscription(&topic, None)
                .map_err(|e| RosError::entity("subscription", &t.ros_topic, e))?;
            let (port, t2, c) = (port.clone(), t.clone(), counters.clone());
            self.tasks
                .push(tokio::spawn(ros_to_yarp(sub, port, own, t2, c)));
        }
        if t.yarp_source.is_some() || t.yarp_sink.is_some() {
            let (ns, port) = (self.ns.clone(), port.clone());
            let (src, sink) = (t.yarp_source.clone(), t.yarp_sink.clone());
            // Deferred: whether a subscriber is matched is asked of the shared node.
            self.deferred.push(Box::new(move |node| {
                tokio::spawn(keep_connected(ns, port, src, sink, Gate::new(node, demand)))
            }));
        }
        let mut yarp = port_name.clone();
        if let Some(s) = &t.yarp_source {
            yarp = format!("{s} -> {yarp}");
        }
        if let Some(s) = &t.yarp_sink {
            yarp = format!("{yarp} -> {s}");
        }
        let mut detail = format!("{conv:?} {}/{}", t.qos.reliability(), t.qos.depth);
        if let Some(r) = t.rate_limit_hz {
            detail.push_str(&format!(" <={r}Hz"));
        }
        if let Some(ci) = camera_info {
            detail.push_str(&format!(" +CameraInfo {ci}"));
        }
        self.bridges.push(Bridge {
            name: t.name.clone(),
            direction: t.direction,
            yarp,
            ros: t.ros_topic.clone(),
            ros_type: t.ros_type.clone(),
            detail,
            counters,
        });
        Ok(())
    }

    /// A joint-command entry: a ROS subscription feeding a control-board thread.
    fn joint_command(&mut self, node: &mut Node, t: &TopicEntry) -> Result<(), StartError> {
        let topic = ros::topic(node, &t.ros_topic, &t.ros_type, &ros::qos(&t.qos))?;
        let sub: Subscription<Ros> = node
            .create_subscription(&topic, None)
            .map_err(|e| RosError::entity("subscription", &t.ros_topic, e))?;
        let counters = Arc::new(Counters::default());
        let wanted = Arc::new(AtomicBool::new(false));
        let tx = commands::spawn_board(t, counters.clone(), wanted.clone()).map_err(|source| {
            StartError::Thread {
                name: t.name.clone(),
                source,
            }
        })?;
        let (t2, c) = (t.clone(), counters.clone());
        // Deferred: whether a publisher is matched is asked of the shared node.
        self.deferred.push(Box::new(move |node| {
            tokio::spawn(commands::ros_to_board(node, sub, tx, wanted, t2, c))
        }));
        let cb = t.control_board.as_ref().expect("validated at load time");
        self.bridges.push(Bridge {
            name: t.name.clone(),
            direction: t.direction,
            yarp: format!(
                "{} -> {}",
                t.yarp_port.as_deref().unwrap_or_default(),
                cb.remote
            ),
            ros: t.ros_topic.clone(),
            ros_type: t.ros_type.clone(),
            detail: format!("JointCommand {:?} {}", cb.mode, t.qos.reliability()),
            counters,
        });
        Ok(())
    }

    /// A `ros_topic` pattern entry: its own node, mirroring matching ROS topics into YARP
    /// ports as they come and go.
    fn ros_pattern(&mut self, t: &TopicEntry) -> Result<(), StartError> {
        let node = self.dynamic_node()?;
        let counters = Arc::new(Counters::default());
        let prefix = t.yarp_port.clone().unwrap_or_default();
        self.tasks.push(tokio::spawn(dynamic::run_ros(
            node,
            self.ctx.domain_participant(),
            self.ns.clone(),
            t.clone(),
            counters.clone(),
        )));
        self.bridges.push(Bridge {
            name: t.name.clone(),
            direction: t.direction,
            yarp: format!("{prefix}/<topic>"),
            ros: t.ros_topic.clone(),
            ros_type: if t.ros_type.is_empty() {
                "(each topic's own)".into()
            } else {
                t.ros_type.clone()
            },
            detail: format!("{:?} dynamic, ROS topics as they appear", t.conversion()),
            counters,
        });
        Ok(())
    }

    /// A `yarp_pattern` entry: its own node, bridging matching ports as they come and go.
    fn pattern(&mut self, t: &TopicEntry) -> Result<(), StartError> {
        let node = self.dynamic_node()?;
        let counters = Arc::new(Counters::default());
        let own_prefix = format!("/{}/{}", self.node_name, t.name);
        self.tasks.push(tokio::spawn(dynamic::run(
            node,
            self.ns.clone(),
            t.clone(),
            own_prefix.clone(),
            format!("/{}/", self.node_name),
            counters.clone(),
        )));
        self.bridges.push(Bridge {
            name: t.name.clone(),
            direction: t.direction,
            yarp: t.yarp_pattern.clone().unwrap_or_default(),
            ros: format!("{}/<port>", t.ros_topic.trim_end_matches('/')),
            ros_type: t.ros_type.clone(),
            detail: format!("{:?} dynamic, ports {own_prefix}/...", t.conversion()),
            counters,
        });
        Ok(())
    }

    async fn action(&mut self, node: &mut Node, a: &ActionEntry) -> Result<(), StartError> {
        let counters = Arc::new(Counters::default());
        let dp = self.ctx.domain_participant();
        let (ns, entry, c) = (self.ns.clone(), a.clone(), counters.clone());
        if a.direction == Direction::RosToYarp {
            let server = actions::create(node, &dp, a)?;
            self.deferred.push(Box::new(move |node| {
                tokio::spawn(actions::serve(server, node, ns, entry, c))
            }));
        } else {
            let client = actions::create_client(node, &dp, a)?;
            let port = self.open_port(&a.yarp_port).await?;
            let feedback = match &a.yarp_feedback {
                Some(p) => Some(self.open_port(p).await?),
                None => None,
            };
            self.deferred.push(Box::new(move |node| {
                tokio::spawn(actions::call(client, node, port, feedback, entry, c))
            }));
        }
        self.bridges.push(Bridge {
            name: a.name.clone(),
            direction: a.direction,
            yarp: a.yarp_port.clone(),
            ros: a.ros_action.clone(),
            ros_type: a.ros_type.clone(),
            detail: "action".into(),
            counters,
        });
        Ok(())
    }

    async fn service(&mut self, node: &mut Node, s: &ServiceEntry) -> Result<(), StartError> {
        let counters = Arc::new(Counters::default());
        let mut detail = format!("{:?}", s.conversion());
        match (s.conversion(), s.direction) {
            (ServiceConversion::TextRpc, _) => {
                let q = ros::qos(&Default::default());
                let req_name = format!("{}/request", s.ros_service);
                let rep_name = format!("{}/reply", s.ros_service);
                let rq = ros::topic(node, &req_name, "std_msgs/msg/String", &q)?;
                let rp = ros::topic(node, &rep_name, "std_msgs/msg/String", &q)?;
                let sub: Subscription<Ros> = node
                    .create_subscription(&rq, None)
                    .map_err(|e| RosError::entity("subscription", &req_name, e))?;
                let publisher: Publisher<Ros> = node
                    .create_publisher(&rp, None)
                    .map_err(|e| RosError::entity("publisher", &rep_name, e))?;
                let rpc = YarpRpc::new(self.ns.clone(), &s.yarp_port, &node.fully_qualified_name());
                self.tasks.push(tokio::spawn(text_rpc(
                    sub,
                    publisher,
                    rpc,
                    counters.clone(),
                )));
                detail = format!("TextRpc {req_name} -> {rep_name}");
            }
            (ServiceConversion::Generic, direction) => {
                ros::announce_service_type_hash(&self.ctx.domain_participant(), &s.ros_type);
                let (req_t, resp_t) = generic_service_types(&s.ros_type)?;
                let c = counters.clone();
                let deferred = if direction == Direction::RosToYarp {
                    let rpc =
                        YarpRpc::new(self.ns.clone(), &s.yarp_port, &node.fully_qualified_name());
                    let words = Bottle::from_text(s.command.as_deref().unwrap_or_default());
                    let what = s.ros_service.clone();
                    serve_later(
                        node,
                        s,
                        rpc,
                        c,
                        MsgSeed(req_t),
                        move |r: &Ros| generic_command(&words, req_t, r),
                        move |reply| generic_response(&what, resp_t, reply),
                    )?
                } else {
                    let port = self.open_port(&s.yarp_port).await?;
                    call_later(
                        node,
                        s,
                        port,
                        c,
                        MsgSeed(resp_t),
                        move |b| Ok(crate::generic::to_ros(req_t, b, now_ns())?),
                        move |r| {
                            crate::generic::to_yarp(resp_t, &r).unwrap_or_else(|e| {
                                service::fail_reply(&format!("the response: {e}"))
                            })
                        },
                    )?
                };
                self.deferred.push(deferred);
            }
            (ServiceConversion::Command, Direction::RosToYarp) => {
                let rpc = YarpRpc::new(self.ns.clone(), &s.yarp_port, &node.fully_qualified_name());
                let c = counters.clone();
                let cmd = |t: &Option<String>| Bottle::from_text(t.as_deref().unwrap_or_default());
                let (command, on, off) =
                    (cmd(&s.command), cmd(&s.command_true), cmd(&s.command_false));
                let deferred = match StdSrv::from_type(&s.ros_type) {
                    Some(StdSrv::Trigger) => serve_later(
                        node,
                        s,
                        rpc,
                        c,
                        PhantomData,
                        move |_: &EmptyMsg| command.clone(),
                        service::outcome_from_call,
                    )?,
                    Some(StdSrv::SetBool) => serve_later(
                        node,
                        s,
                        rpc,
                        c,
                        PhantomData,
                        move |r: &SetBoolRequest| if r.data { on.clone() } else { off.clone() },
                        service::outcome_from_call,
                    )?,
                    Some(StdSrv::Empty) | None => serve_later(
                        node,
                        s,
                        rpc,
                        c,
                        PhantomData,
                        move |_: &EmptyMsg| command.clone(),
                        |_| EmptyMsg::default(),
                    )?,
                };
                self.deferred.push(deferred);
            }
            (ServiceConversion::Command, _) => {
                let port = self.open_port(&s.yarp_port).await?;
                let c = counters.clone();
                let deferred = match StdSrv::from_type(&s.ros_type) {
                    Some(StdSrv::Trigger) => call_later(
                        node,
                        s,
                        port,
                        c,
                        PhantomData,
                        |_| Ok(EmptyMsg::default()),
                        |r: OutcomeResponse| service::reply_from_outcome(&r),
                    )?,
                    Some(StdSrv::SetBool) => call_later(
                        node,
                        s,
                        port,
                        c,
                        PhantomData,
                        |b| {
                            service::setbool_from_command(b)
                                .map(|data| SetBoolRequest { data })
                                .ok_or(RequestError::NotABool)
                        },
                        |r: OutcomeResponse| service::reply_from_outcome(&r),
                    )?,
                    Some(StdSrv::Empty) | None => call_later(
                        node,
                        s,
                        port,
                        c,
                        PhantomData,
                        |_| Ok(EmptyMsg::default()),
                        |_: EmptyMsg| service::ok_reply(),
                    )?,
                };
                self.deferred.push(deferred);
            }
        }
        self.bridges.push(Bridge {
            name: s.name.clone(),
            direction: s.direction,
            yarp: s.yarp_port.clone(),
            ros: s.ros_service.clone(),
            ros_type: s.ros_type.clone(),
            detail,
            counters,
        });
        Ok(())
    }

    async fn diagnostics(&mut self, node: &mut Node, opt: &Options) -> Result<(), StartError> {
        let Some(period) = opt.diagnostics_period else {
            return Ok(());
        };
        let q = ros::qos(&Default::default());
        let topic = ros::topic(
            node,
            "/diagnostics",
            "diagnostic_msgs/msg/DiagnosticArray",
            &q,
        )?;
        let publisher: Publisher<Ros> = node
            .create_publisher(&topic, None)
            .map_err(|e| RosError::entity("publisher", "/diagnostics", e))?;
        let port = match &opt.diagnostics_port {
            Some(p) => Some(self.open_port(p).await?),
            None => None,
        };
        let bridges = self.bridges.clone();
        let hw = node.fully_qualified_name();
        self.tasks.push(tokio::spawn(async move {
            let mut tick = tokio::time::interval(period);
            loop {
                tick.tick().await;
                let rows: Vec<Row> = bridges.iter().map(Bridge::row).collect();
                let msg = counters::diagnostic_array(now_ns(), &hw, &rows);
                if let Err(e) = publisher.async_publish(msg).await {
                    debug!("/diagnostics: {e:?}");
                }
                if let Some(p) = &port {
                    p.write_nowait(&diagnostics_bottle(&rows), None);
                }
            }
        }));
        Ok(())
    }
}

/// The YARP form of the counters: one `(name messages drops mean_us max_us)` per mapping.
pub fn diagnostics_bottle(rows: &[Row]) -> Bottle {
    let mut b = Bottle::new();
    for r in rows {
        let s = r.snapshot;
        let mut e = Bottle::new();
        e.push(r.name.as_str());
        e.push(s.messages as i64);
        e.push(s.drops as i64);
        e.push(s.latency_mean.as_secs_f64() * 1e6);
        e.push(s.latency_max.as_secs_f64() * 1e6);
        b.push(e);
    }
    b
}

pub(crate) fn now_ns() -> u64 {
    ros::now_ns()
}
