//! Action bridges (`[[action]]`): a ROS 2 action served by a YARP RPC port (`ros_to_yarp`),
//! and a YARP RPC port whose callers reach a ROS 2 action server (`yarp_to_ros`).
//!
//! `ros_to_yarp`:
//! Each accepted goal is one call of the YARP port (the `command` words, then the goal's
//! fields in the generic layout) on a connection of its own; the reply, read in the
//! result's layout, ends the goal SUCCEEDED (`[fail]`, `[err]`, `[nack]`, a reply that does
//! not fit or no reply: ABORTED). A goal is rejected when the YARP port is not registered
//! (nobody to run it). Feedback comes from `yarp_feedback`, a YARP port whose Bottles (in
//! the feedback's layout) are published for every executing goal. A cancel request sends
//! `cancel` to the YARP port on another connection; the goal ends CANCELED when its call
//! returns. The goals' bookkeeping is [`crate::action`].

use super::follow;
use super::services::{default_of, generic_reply, generic_service_types};
use super::yarp_rpc::YarpRpc;
use crate::action::{self, cancel_code, status, GoalId, Goals};
use crate::counters::Counters;
use crate::dynmsg::{MsgSeed, Value as Ros};
use crate::mapping::ActionEntry;
use crate::ros::{self, RosError};
use crate::service;
use crate::types::MsgType;
use ros2_client::{Client, Node, Publisher, Server, Subscription};
use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tracing::{debug, info, warn};
use yarp_net::buffered::BufferedPort;
use yarp_net::nameserver::NameClient;
use yarp_net::network;
use yarp_net::port::Port;
use yarp_proto::{Bottle, Value};

/// A goal's YARP call may run this long (a dead peer ends it sooner: the connection breaks).
const GOAL_TIMEOUT: Duration = Duration::from_secs(600);
/// How long a response waits for the client's reply reader to match.
const CLIENT_MATCH_TIMEOUT: Duration = Duration::from_secs(2);
/// How often the feedback port's connection is checked.
const RECONNECT_PERIOD: Duration = Duration::from_secs(1);

/// The run-time types of one action.
#[derive(Clone, Copy)]
struct Types {
    send_goal: (&'static MsgType, &'static MsgType),
    get_result: (&'static MsgType, &'static MsgType),
    cancel: (&'static MsgType, &'static MsgType),
    goal: &'static MsgType,
    result: &'static MsgType,
    feedback: &'static MsgType,
}

impl Types {
    /// The types of `action_type`; their hashes are announced on `dp`, as rmw does.
    fn of(
        dp: &ros2_client::dds::rustdds::DomainParticipant,
        action_type: &str,
    ) -> Result<Types, RosError> {
        for srv in ["_SendGoal", "_GetResult"] {
            ros::announce_service_type_hash(dp, &format!("{action_type}{srv}"));
        }
        ros::announce_type_hash(dp, &format!("{action_type}_FeedbackMessage"));
        let one = |t: String| {
            crate::types::lookup(&t).ok_or_else(|| RosError::Entity {
                what: "action type",
                name: action_type.to_string(),
                message: format!("no definition of {t}"),
            })
        };
        Ok(Types {
            send_goal: generic_service_types(&format!("{action_type}_SendGoal"))?,
            get_result: generic_service_types(&format!("{action_type}_GetResult"))?,
            cancel: generic_service_types(CANCEL_GOAL)?,
            goal: one(format!("{action_type}_Goal"))?,
            result: one(format!("{action_type}_Result"))?,
            feedback: one(format!("{action_type}_Feedback"))?,
        })
    }
}

/// The ROS endpoints of one action server.
pub(super) struct ActionServer {
    send_goal: Server<Ros, Ros>,
    cancel: Server<Ros, Ros>,
    get_result: Server<Ros, Ros>,
    feedback: Publisher<Ros>,
    status: Publisher<Ros>,
    types: Types,
}

/// Creates the action server of `a` on `node` (services and topics as rcl_action names
/// them, QoS as its defaults: status transient local, depth 1).
pub(super) fn create(
    node: &mut Node,
    dp: &ros2_client::dds::rustdds::DomainParticipant,
    a: &ActionEntry,
) -> Result<ActionServer, RosError> {
    let types = Types::of(dp, &a.ros_type)?;
    let (name, ty) = (endpoint(a), |part: &str| format!("{}{part}", a.ros_type));
    let status_qos = crate::mapping::Qos {
        reliability: Some(crate::mapping::Reliability::Reliable),
        durability: crate::mapping::Durability::TransientLocal,
        depth: 1,
    };
    Ok(ActionServer {
        send_goal: ros::server(node, &name("send_goal"), &ty("_SendGoal"))?,
        cancel: ros::server(node, &name("cancel_goal"), CANCEL_GOAL)?,
        get_result: ros::server(node, &name("get_result"), &ty("_GetResult"))?,
        feedback: ros::publisher(
            node,
            &name("feedback"),
            &ty("_FeedbackMessage"),
            &Default::default(),
        )?,
        status: ros::publisher(node, &name("status"), GOAL_STATUS_ARRAY, &status_qos)?,
        types,
    })
}

/// The service every action's `cancel_goal` is, and the type of its `status` topic.
const CANCEL_GOAL: &str = "action_msgs/srv/CancelGoal";
const GOAL_STATUS_ARRAY: &str = "action_msgs/msg/GoalStatusArray";

/// The names of an action's endpoints: `<ros_action>/_action/<part>`.
fn endpoint(a: &ActionEntry) -> impl Fn(&str) -> String + '_ {
    move |part| format!("{}/_action/{part}", a.ros_action.trim_end_matches('/'))
}

/// What the three service loops share.
struct State {
    goals: Goals,
    /// `get_result` requests waiting for their goal to end.
    waiting: HashMap<GoalId, Vec<ros2_client::RmwRequestId>>,
}

struct Shared {
    server: ActionServer,
    /// The gateway's trajectory controller, when it runs the goals (`controller`).
    controller: Option<follow::Controller>,
    node: Arc<Node>,
    state: Mutex<State>,
    ns: NameClient,
    entry: ActionEntry,
    me: String,
    counters: Arc<Counters>,
}

impl Shared {
    fn state(&self) -> std::sync::MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    async fn publish_status(&self) {
        let array = self.state().goals.status_array();
        if let Err(e) = self.server.status.async_publish(array).await {
            debug!("{}: status not published: {e:?}", self.entry.name);
        }
    }

    /// Answers `id`'s request on `server` once its reply reader is matched (bounded).
    async fn respond(&self, server: &Server<Ros, Ros>, id: ros2_client::RmwRequestId, r: Ros) {
        let matched =
            tokio::time::timeout(CLIENT_MATCH_TIMEOUT, server.wait_for_client(&self.node, id));
        if matched.await.is_err() {
            debug!(
                "{}: the client's reader is not matched yet; answering anyway",
                self.entry.name
            );
        }
        if let Err(e) = server.async_send_response(id, r).await {
            warn!("{}: response not sent: {e:?}", self.entry.name);
        }
    }

    /// The `get_result` response of a goal.
    fn result_response(&self, goal: Option<&action::Goal>) -> Ros {
        let t = self.server.types;
        let (st, result) = match goal {
            Some(g) if g.is_terminal() => (g.status, g.result.clone()),
            Some(g) => (g.status, None),
            None => (status::UNKNOWN, None),
        };
        Ros::Struct(vec![
            Ros::I8(st),
            result.unwrap_or_else(|| default_of(t.result)),
        ])
    }
}

/// Serves the action until the gateway stops (the task is aborted).
pub(super) async fn serve(
    server: ActionServer,
    node: Arc<Node>,
    ns: NameClient,
    entry: ActionEntry,
    counters: Arc<Counters>,
) {
    let me = format!("{}/{}", node.fully_qualified_name(), entry.name);
    let controller = match &entry.controller {
        Some(c) => {
            match follow::Controller::spawn(&entry.name, &entry.yarp_port, c, server.types.feedback)
            {
                Ok(c) => Some(c),
                Err(e) => {
                    warn!("{}: trajectory controller not started: {e}", entry.name);
                    return;
                }
            }
        }
        None => None,
    };
    let shared = Arc::new(Shared {
        server,
        controller,
        node,
        state: Mutex::new(State {
            goals: Goals::default(),
            waiting: HashMap::new(),
        }),
        ns,
        entry,
        me,
        counters,
    });
    tokio::join!(
        goals(shared.clone()),
        cancels(shared.clone()),
        results(shared.clone()),
        feedback(shared),
    );
}

/// `send_goal`: accept (the YARP port is there) or reject, then run the goal.
async fn goals(s: Arc<Shared>) {
    let t = s.server.types;
    loop {
        let (id, req) = match s
            .server
            .send_goal
            .async_receive_request_seed(MsgSeed(t.send_goal.0))
            .await
        {
            Ok(x) => x,
            Err(e) => {
                debug!("{}: goal request: {e:?}", s.entry.name);
                s.counters.dropped();
                continue;
            }
        };
        let Some((goal_id, goal)) = action::goal_request(req) else {
            s.counters.dropped();
            continue;
        };
        let now = super::now_ns();
        let runnable = match &s.controller {
            Some(c) => c.ready(),
            None => matches!(s.ns.query(&s.entry.yarp_port).await, Ok(Some(_))),
        };
        let accepted = runnable && s.state().goals.accept(goal_id, now);
        if !runnable {
            s.counters.refused(match &s.entry.controller {
                Some(c) => format!("goal rejected: control boards {:?} not open", c.boards),
                None => format!("goal rejected: {} is not registered", s.entry.yarp_port),
            });
        }
        s.respond(
            &s.server.send_goal,
            id,
            Ros::Struct(vec![Ros::Bool(accepted), Ros::time(now)]),
        )
        .await;
        if accepted {
            s.publish_status().await;
            tokio::spawn(run_goal(s.clone(), goal_id, goal));
        }
    }
}

/// Runs one goal (a YARP call, or the trajectory controller) and answers its result.
async fn run_goal(s: Arc<Shared>, id: GoalId, goal: Ros) {
    s.state().goals.set_status(&id, status::EXECUTING);
    s.publish_status().await;
    let (succeeded, result) = match &s.controller {
        Some(c) => follow_goal(&s, c, id, goal).await,
        None => call_goal(&s, goal).await,
    };
    let waiting = {
        let mut st = s.state();
        st.goals.finish(&id, succeeded, result);
        st.waiting.remove(&id).unwrap_or_default()
    };
    s.publish_status().await;
    let response = s.result_response(s.state().goals.get(&id));
    for req in waiting {
        s.respond(&s.server.get_result, req, response.clone()).await;
    }
}

/// A goal run by the trajectory controller, its feedback published as it comes.
async fn follow_goal(s: &Shared, c: &follow::Controller, id: GoalId, goal: Ros) -> (bool, Ros) {
    let t0 = Instant::now();
    let (tx, mut rx) = tokio::sync::mpsc::channel(4);
    let run = c.run(id, goal, tx);
    tokio::pin!(run);
    let ended = loop {
        tokio::select! {
            ended = &mut run => break ended,
            Some(fb) = rx.recv() => {
                let msg = Ros::Struct(vec![action::uuid(&id), fb]);
                if let Err(e) = s.server.feedback.async_publish(msg).await {
                    debug!("{}: feedback not published: {e:?}", s.entry.name);
                }
            }
        }
    };
    match ended.outcome {
        follow::Outcome::Succeeded => s.counters.forwarded(t0.elapsed()),
        // A preempted goal ends CANCELED, as a canceled one.
        follow::Outcome::Canceled => s.state().goals.set_status(&id, status::CANCELING),
        follow::Outcome::Aborted => s.counters.refused(format!(
            "{}: goal aborted: {:?}",
            s.entry.name,
            ended.result.fields().and_then(|f| f.get(1))
        )),
    }
    (ended.outcome == follow::Outcome::Succeeded, ended.result)
}

/// A goal run by one YARP call, its reply the result.
async fn call_goal(s: &Shared, goal: Ros) -> (bool, Ros) {
    let t = s.server.types;
    let t0 = Instant::now();
    let mut cmd = Bottle::from_text(s.entry.command.as_deref().unwrap_or_default());
    match crate::generic::to_yarp(t.goal, &goal) {
        Ok(fields) => cmd.extend(fields.into_items()),
        Err(e) => warn!("{}: {e}", t.goal.name),
    }
    let mut rpc = YarpRpc::new(s.ns.clone(), &s.entry.yarp_port, &format!("{}/goal", s.me));
    let reply = rpc.call_within(&cmd, GOAL_TIMEOUT).await;
    match generic_reply(t.result, reply) {
        Ok(r) => {
            s.counters.forwarded(t0.elapsed());
            (true, r)
        }
        Err(why) => {
            s.counters.refused(format!("{}: {why}", s.entry.yarp_port));
            (false, default_of(t.result))
        }
    }
}

/// `cancel_goal`: the goals named move to CANCELING and YARP gets `cancel`.
async fn cancels(s: Arc<Shared>) {
    let t = s.server.types;
    let mut rpc = YarpRpc::new(
        s.ns.clone(),
        &s.entry.yarp_port,
        &format!("{}/cancel", s.me),
    );
    loop {
        let (id, req) = match s
            .server
            .cancel
            .async_receive_request_seed(MsgSeed(t.cancel.0))
            .await
        {
            Ok(x) => x,
            Err(e) => {
                debug!("{}: cancel request: {e:?}", s.entry.name);
                continue;
            }
        };
        let info = req
            .fields()
            .and_then(|f| f.first())
            .and_then(|i| i.fields());
        let (goal_id, stamp) = match info {
            Some([uuid, stamp]) => (
                action::goal_id(uuid).unwrap_or([0; 16]),
                action::time_ns(stamp),
            ),
            _ => ([0; 16], 0),
        };
        let (code, canceling) = match (&s.entry.cancel, &s.controller) {
            (None, None) => (cancel_code::REJECTED, Vec::new()),
            _ => s.state().goals.cancel(&goal_id, stamp),
        };
        if let Some(c) = &s.controller {
            for (g, _) in &canceling {
                c.cancel(*g);
            }
            if !canceling.is_empty() {
                s.publish_status().await;
            }
        } else if !canceling.is_empty() {
            let cmd = Bottle::from_text(s.entry.cancel.as_deref().unwrap_or_default());
            match rpc.call(&cmd).await {
                Ok(b) => info!(
                    "{}: cancel: {} answered `{b}`",
                    s.entry.name, s.entry.yarp_port
                ),
                Err(e) => warn!("{}: cancel: {e}", s.entry.name),
            }
            s.publish_status().await;
        }
        let goals = canceling
            .iter()
            .map(|(g, stamp)| action::goal_info(g, *stamp))
            .collect();
        s.respond(
            &s.server.cancel,
            id,
            Ros::Struct(vec![Ros::I8(code), Ros::List(goals)]),
        )
        .await;
    }
}

/// `get_result`: answered when the goal has ended (at once if it has, or is unknown).
async fn results(s: Arc<Shared>) {
    let t = s.server.types;
    loop {
        let (id, req) = match s
            .server
            .get_result
            .async_receive_request_seed(MsgSeed(t.get_result.0))
            .await
        {
            Ok(x) => x,
            Err(e) => {
                debug!("{}: result request: {e:?}", s.entry.name);
                continue;
            }
        };
        let goal_id = req
            .fields()
            .and_then(|f| f.first())
            .and_then(action::goal_id)
            .unwrap_or([0; 16]);
        let ready = {
            let mut st = s.state();
            match st.goals.get(&goal_id) {
                Some(g) if !g.is_terminal() => {
                    st.waiting.entry(goal_id).or_default().push(id);
                    None
                }
                g => Some(s.result_response(g)),
            }
        };
        if let Some(r) = ready {
            s.respond(&s.server.get_result, id, r).await;
        }
    }
}

/// Publishes each Bottle of `yarp_feedback` as the feedback of every executing goal.
async fn feedback(s: Arc<Shared>) {
    let t = s.server.types;
    let Some(source) = s.entry.yarp_feedback.clone() else {
        return;
    };
    let name = format!("{}/feedback:i", s.me);
    let port = match BufferedPort::open(&name, s.ns.clone()).await {
        Ok(p) => p,
        Err(e) => {
            warn!("{}: feedback port {name}: {e}", s.entry.name);
            return;
        }
    };
    let mut tick = tokio::time::interval(RECONNECT_PERIOD);
    loop {
        let m = tokio::select! {
            _ = tick.tick() => {
                if !port.port().inputs().iter().any(|i| i == &source) {
                    match network::connect(&s.ns, &source, &name, None).await {
                        Ok((true, _)) => info!("connected {source} -> {name}"),
                        Ok((false, why)) => debug!("connect {source} -> {name}: {why}"),
                        Err(e) => debug!("connect {source} -> {name}: {e}"),
                    }
                }
                continue;
            }
            m = port.read() => match m {
                Some(m) => m,
                None => return,
            },
        };
        let fb = match crate::generic::to_ros(t.feedback, &m.bottle, super::now_ns()) {
            Ok(f) => f,
            Err(e) => {
                s.counters.refused(format!("feedback `{}`: {e}", m.bottle));
                continue;
            }
        };
        let executing = s.state().goals.executing();
        for g in executing {
            let msg = Ros::Struct(vec![action::uuid(&g), fb.clone()]);
            if let Err(e) = s.server.feedback.async_publish(msg).await {
                debug!("{}: feedback not published: {e:?}", s.entry.name);
            }
        }
    }
}

/// The ROS endpoints of a client of one action (`yarp_to_ros`).
pub(super) struct ActionClient {
    send_goal: Client<Ros, Ros>,
    cancel: Client<Ros, Ros>,
    get_result: Client<Ros, Ros>,
    feedback: Subscription<Ros>,
    types: Types,
}

/// Creates the action client of `a` on `node`.
pub(super) fn create_client(
    node: &mut Node,
    dp: &ros2_client::dds::rustdds::DomainParticipant,
    a: &ActionEntry,
) -> Result<ActionClient, RosError> {
    let types = Types::of(dp, &a.ros_type)?;
    let (name, ty) = (endpoint(a), |part: &str| format!("{}{part}", a.ros_type));
    Ok(ActionClient {
        send_goal: ros::client(node, &name("send_goal"), &ty("_SendGoal"))?,
        cancel: ros::client(node, &name("cancel_goal"), CANCEL_GOAL)?,
        get_result: ros::client(node, &name("get_result"), &ty("_GetResult"))?,
        feedback: ros::subscription(
            node,
            &name("feedback"),
            &ty("_FeedbackMessage"),
            &Default::default(),
        )?,
        types,
    })
}

/// What a client's tasks share.
struct Caller {
    client: ActionClient,
    node: Arc<Node>,
    entry: ActionEntry,
    /// Goals sent and not ended (their feedback goes to `yarp_feedback`).
    in_flight: Mutex<Vec<GoalId>>,
    feedback_port: Option<Arc<Port>>,
    counters: Arc<Counters>,
}

impl Caller {
    fn in_flight(&self) -> std::sync::MutexGuard<'_, Vec<GoalId>> {
        self.in_flight.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// Serves the RPC port `port` of a `yarp_to_ros` action: each Bottle is a goal of the ROS
/// action (its reply the result), `[stop]` cancels the goals in flight; feedback is written
/// to `feedback_port`.
pub(super) async fn call(
    client: ActionClient,
    node: Arc<Node>,
    port: Arc<Port>,
    feedback_port: Option<Arc<Port>>,
    entry: ActionEntry,
    counters: Arc<Counters>,
) {
    let caller = Arc::new(Caller {
        client,
        node,
        entry,
        in_flight: Mutex::new(Vec::new()),
        feedback_port,
        counters,
    });
    let requests = async {
        while let Some(mut inc) = port.read().await {
            let Some(replier) = inc.take_replier() else {
                continue; // a plain write: nobody waits for an answer
            };
            let b = match inc.bottle() {
                Ok(b) => b,
                Err(e) => {
                    replier.send(service::fail_reply(&e.to_string()));
                    continue;
                }
            };
            let caller = caller.clone();
            tokio::spawn(async move {
                let reply = if is_stop(&b) {
                    stop_goals(&caller).await
                } else {
                    run_remote_goal(&caller, &b).await
                };
                replier.send(reply);
            });
        }
    };
    tokio::join!(requests, forward_feedback(caller.clone()));
}

fn is_stop(b: &Bottle) -> bool {
    b.len() == 1 && matches!(b.get(0), Some(Value::Vocab32(v)) if v.as_string() == "stop")
}

/// One goal: sent, then its result awaited; the reply is the result's fields (SUCCEEDED)
/// or `[fail] "<how it ended>"` and the fields.
async fn run_remote_goal(c: &Caller, b: &Bottle) -> Bottle {
    let t = c.client.types;
    let t0 = Instant::now();
    let goal = match crate::generic::to_ros(t.goal, b, super::now_ns()) {
        Ok(g) => g,
        Err(e) => {
            c.counters.dropped();
            return service::fail_reply(&format!("not a {}: {e}", t.goal.name));
        }
    };
    let id: GoalId = uuid::Uuid::new_v4().into_bytes();
    let send = async {
        c.client.send_goal.wait_for_service(&c.node).await;
        c.client
            .send_goal
            .async_call_service_seed(
                Ros::Struct(vec![action::uuid(&id), goal]),
                MsgSeed(t.send_goal.1),
            )
            .await
    };
    let accepted = match tokio::time::timeout(super::CALL_TIMEOUT, send).await {
        Ok(Ok(r)) => matches!(r.fields(), Some([Ros::Bool(true), ..])),
        Ok(Err(e)) => {
            c.counters.dropped();
            return service::fail_reply(&format!("{}: {e:?}", c.entry.ros_action));
        }
        Err(_) => {
            c.counters.dropped();
            return service::fail_reply(&format!(
                "{}: no action server answered within {:?}",
                c.entry.ros_action,
                super::CALL_TIMEOUT
            ));
        }
    };
    if !accepted {
        c.counters
            .refused(format!("{}: goal rejected", c.entry.ros_action));
        return service::fail_reply("rejected");
    }
    c.in_flight().push(id);
    let result = tokio::time::timeout(
        GOAL_TIMEOUT,
        c.client.get_result.async_call_service_seed(
            Ros::Struct(vec![action::uuid(&id)]),
            MsgSeed(t.get_result.1),
        ),
    )
    .await;
    c.in_flight().retain(|g| g != &id);
    let (st, result) = match result {
        Ok(Ok(r)) => match r.fields() {
            Some([Ros::I8(st), result]) => (*st, result.clone()),
            _ => return service::fail_reply("a result of another type"),
        },
        Ok(Err(e)) => return service::fail_reply(&format!("{}: {e:?}", c.entry.ros_action)),
        Err(_) => return service::fail_reply("no result within the goal's time limit"),
    };
    let fields = crate::generic::to_yarp(t.result, &result).unwrap_or_default();
    if st == status::SUCCEEDED {
        c.counters.forwarded(t0.elapsed());
        return fields;
    }
    let how = match st {
        status::CANCELED => "canceled",
        status::ABORTED => "aborted",
        _ => "unknown",
    };
    c.counters
        .refused(format!("{}: goal {how}", c.entry.ros_action));
    let mut reply = service::fail_reply(how);
    reply.extend(fields.into_items());
    reply
}

/// `[stop]`: a cancel request for each goal in flight; `[ok] N` (N goals canceling).
async fn stop_goals(c: &Caller) -> Bottle {
    let t = c.client.types;
    let goals = c.in_flight().clone();
    let mut canceling = 0;
    for id in goals {
        let req = Ros::Struct(vec![action::goal_info(&id, 0)]);
        let call = c
            .client
            .cancel
            .async_call_service_seed(req, MsgSeed(t.cancel.1));
        if let Ok(Ok(r)) = tokio::time::timeout(super::CALL_TIMEOUT, call).await {
            if let Some([Ros::I8(_), Ros::List(g)]) = r.fields() {
                canceling += g.len();
            }
        }
    }
    let mut reply = Bottle::from_text("[ok]");
    reply.push(Value::Int32(canceling as i32));
    reply
}

/// Writes the feedback of this entry's goals to `yarp_feedback`.
async fn forward_feedback(c: Arc<Caller>) {
    let t = c.client.types;
    let Some(port) = c.feedback_port.clone() else {
        return;
    };
    let Some(seed) = MsgSeed::new(&format!("{}_FeedbackMessage", c.entry.ros_type)) else {
        return;
    };
    let stream = c.client.feedback.async_stream_seed(seed);
    futures::pin_mut!(stream);
    while let Some(r) = futures::StreamExt::next(&mut stream).await {
        let Ok((m, _)) = r else { continue };
        let Some([uuid, fb]) = m.fields() else {
            continue;
        };
        let ours = action::goal_id(uuid).is_some_and(|id| c.in_flight().contains(&id));
        if !ours {
            continue;
        }
        match crate::generic::to_yarp(t.feedback, fb) {
            Ok(b) => {
                port.write(&b).await;
            }
            Err(e) => debug!("{}: feedback: {e}", c.entry.name),
        }
    }
}
