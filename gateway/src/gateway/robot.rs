//! `[[robot]]` entries at run time: the merged `/joint_states`, fed by the per-part
//! JointState bridges through [`Tap`]s and published at most `rate_hz` times a second,
//! and the latched `/robot_description`.

use super::demand::Demand;
use super::{Bridge, Builder, StartError};
use crate::counters::Counters;
use crate::dynmsg::Value as Ros;
use crate::mapping::{Direction, Durability, Qos, Reliability};
use crate::robot::{RobotDescription, RobotEntry};
use crate::robot_state::Merger;
use crate::ros;
use parking_lot::Mutex;
use ros2_client::{Node, Publisher};
use std::collections::HashMap;
use std::sync::Arc;
use std::time::{Duration, Instant};
use tracing::{debug, info, warn};

type Shared = Arc<Mutex<Merger>>;

/// Where robot_state_publisher publishes TF.
const TF_TOPIC: &str = "/tf";
const TF_STATIC_TOPIC: &str = "/tf_static";

/// Where a part's JointState bridge copies each message it publishes: the mergers of the
/// robots it is a part of, with its index there.
#[derive(Clone, Default)]
pub(super) struct Tap(Vec<(Shared, usize)>);

impl Tap {
    pub(super) fn feed(&self, msg: &Ros) {
        let now = Instant::now();
        for (m, i) in &self.0 {
            if !m.lock().update(*i, msg, now) {
                debug!("robot part {i}: not a JointState");
            }
        }
    }
}

/// The mergers of every robot entry, and the taps of the topic entries that feed them.
#[derive(Default)]
pub(super) struct Robots {
    mergers: HashMap<String, Shared>,
    taps: HashMap<String, Tap>,
    /// Per part entry: its demand, which the merged topic's publisher joins.
    demands: HashMap<String, Demand>,
}

impl Robots {
    pub(super) fn new(robots: &[RobotEntry]) -> Robots {
        let mut out = Robots::default();
        for r in robots {
            let Some(js) = &r.joint_states else { continue };
            let m: Shared = Arc::new(Mutex::new(Merger::new(js.parts.len())));
            for (i, p) in js.parts.iter().enumerate() {
                out.taps
                    .entry(p.clone())
                    .or_default()
                    .0
                    .push((m.clone(), i));
            }
            out.mergers.insert(r.name.clone(), m);
        }
        out
    }

    /// The demand of topic entry `name`: shared with the robots that merge it.
    pub(super) fn demand(&mut self, name: &str) -> Demand {
        self.demands.entry(name.to_string()).or_default().clone()
    }

    /// The tap of topic entry `name` (empty when no robot merges it).
    pub(super) fn tap(&self, name: &str) -> Tap {
        self.taps.get(name).cloned().unwrap_or_default()
    }
}

impl Builder {
    /// A robot entry's publishers and tasks.
    pub(super) fn robot(
        &mut self,
        node: &mut Node,
        r: &RobotEntry,
        robots: &Robots,
    ) -> Result<(), StartError> {
        let urdf_joints = r.robot_description.as_ref().map(|d| d.joints.clone());
        // TF as robot_state_publisher gives it: fixed joints once, the others per state.
        let tf = match (&r.robot_description, r.tf) {
            (Some(d), true) => match crate::tf::tf_joints(&d.text) {
                Ok(j) => {
                    self.publish_static_tf(node, &r.name, &j)?;
                    Some(j)
                }
                Err(e) => {
                    warn!("{}: no TF from {}: {e}", r.name, d.urdf.display());
                    None
                }
            },
            _ => None,
        };
        if let (Some(js), Some(merger)) = (&r.joint_states, robots.mergers.get(&r.name)) {
            let publisher = Arc::new(ros::publisher(
                node,
                &js.ros_topic,
                "sensor_msgs/msg/JointState",
                &js.qos,
            )?);
            // The parts' sources are connected while the merged topic has subscribers too.
            for p in &js.parts {
                let demand = robots.demands.get(p).cloned().unwrap_or_default();
                match js.qos.durability {
                    Durability::TransientLocal => demand.set_always(),
                    Durability::Volatile => demand.add(publisher.clone()),
                }
            }
            let counters = Arc::new(Counters::default());
            let period = Duration::from_secs_f64(1.0 / js.rate_hz);
            let tf = match tf {
                Some(j) => Some((
                    Arc::new(ros::publisher(
                        node,
                        TF_TOPIC,
                        "tf2_msgs/msg/TFMessage",
                        &Qos::default(),
                    )?),
                    j,
                )),
                None => None,
            };
            self.tasks.push(tokio::spawn(publish_joint_states(
                publisher,
                merger.clone(),
                period,
                js.parts.clone(),
                urdf_joints,
                tf,
                counters.clone(),
            )));
            self.bridges.push(Bridge {
                name: format!("{}.joint_states", r.name),
                direction: Direction::YarpToRos,
                yarp: format!("parts {}", js.parts.join(" ")),
                ros: js.ros_topic.clone(),
                ros_type: "sensor_msgs/msg/JointState".into(),
                detail: format!(
                    "merged <={}Hz {}/{}",
                    js.rate_hz,
                    js.qos.reliability(),
                    js.qos.depth
                ),
                counters,
            });
        }
        if let Some(d) = &r.robot_description {
            let counters = Arc::new(Counters::default());
            self.publish_description(node, d, counters.clone())?;
            self.bridges.push(Bridge {
                name: format!("{}.robot_description", r.name),
                direction: Direction::YarpToRos,
                yarp: d.urdf.display().to_string(),
                ros: d.ros_topic.clone(),
                ros_type: "std_msgs/msg/String".into(),
                detail: "URDF reliable/transient_local".into(),
                counters,
            });
        }
        Ok(())
    }

    /// Publishes the fixed joints' transforms once on `/tf_static`, reliable and transient
    /// local (depth 1), as tf2's static broadcaster does: a listener that starts later
    /// still gets them (nothing when the URDF has no fixed joint).
    fn publish_static_tf(
        &mut self,
        node: &mut Node,
        robot: &str,
        joints: &[crate::tf::TfJoint],
    ) -> Result<(), StartError> {
        let msg = crate::tf::static_message(joints, super::now_ns());
        if !joints.iter().any(|j| j.motion == crate::tf::Motion::Fixed) {
            return Ok(());
        }
        let q = Qos {
            reliability: Some(Reliability::Reliable),
            durability: Durability::TransientLocal,
            depth: 1,
        };
        let publisher: Publisher<Ros> =
            ros::publisher(node, TF_STATIC_TOPIC, "tf2_msgs/msg/TFMessage", &q)?;
        let robot = robot.to_string();
        self.tasks.push(tokio::spawn(async move {
            if let Err(e) = publisher.async_publish(msg).await {
                warn!("{robot}: {TF_STATIC_TOPIC}: publish: {e:?}");
            }
            // The writer holds the latched sample: keep it alive with the gateway.
            std::future::pending::<()>().await;
        }));
        Ok(())
    }

    /// Publishes the URDF once on a reliable, transient-local writer of depth 1, as
    /// robot_state_publisher does: it keeps the sample for every reader that comes later.
    fn publish_description(
        &mut self,
        node: &mut Node,
        d: &RobotDescription,
        counters: Arc<Counters>,
    ) -> Result<(), StartError> {
        let q = Qos {
            reliability: Some(Reliability::Reliable),
            durability: Durability::TransientLocal,
            depth: 1,
        };
        let publisher: Publisher<Ros> =
            ros::publisher(node, &d.ros_topic, "std_msgs/msg/String", &q)?;
        let msg = Ros::Struct(vec![Ros::Str(d.text.clone())]);
        let topic = d.ros_topic.clone();
        self.tasks.push(tokio::spawn(async move {
            let t0 = Instant::now();
            match publisher.async_publish(msg).await {
                Ok(()) => counters.forwarded(t0.elapsed()),
                Err(e) => {
                    warn!("{topic}: publish: {e:?}");
                    counters.dropped();
                }
            }
            // The writer holds the latched sample: keep it alive with the gateway.
            std::future::pending::<()>().await;
        }));
        Ok(())
    }
}

/// Publishes the merged state at most once per `period`, when a part reported.
async fn publish_joint_states(
    publisher: Arc<Publisher<Ros>>,
    merger: Shared,
    period: Duration,
    parts: Vec<String>,
    urdf_joints: Option<Vec<String>>,
    tf: Option<(Arc<Publisher<Ros>>, Vec<crate::tf::TfJoint>)>,
    c: Arc<Counters>,
) {
    let mut tick = tokio::time::interval(period);
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    let mut missing_before: Option<Vec<usize>> = None;
    let mut compared = urdf_joints.is_none();
    loop {
        tick.tick().await;
        let t0 = Instant::now();
        let (msg, missing, names) = {
            let mut m = merger.lock();
            (m.take(t0), m.missing(t0), m.names())
        };
        if missing_before.as_ref() != Some(&missing) {
            if missing.is_empty() {
                info!("joint_states: every part reports ({})", parts.join(", "));
            } else {
                let names: Vec<&str> = missing.iter().map(|&i| parts[i].as_str()).collect();
                info!("joint_states: no recent state from {}", names.join(", "));
            }
            missing_before = Some(missing.clone());
        }
        if !compared && missing.is_empty() {
            compared = true;
            if let Some(urdf) = &urdf_joints {
                warn_urdf_mismatch(&names, urdf);
            }
        }
        let Some(msg) = msg else { continue };
        if let Some((tf_publisher, joints)) = &tf {
            if let Some(m) = tf_of(joints, &msg) {
                if let Err(e) = tf_publisher.async_publish(m).await {
                    debug!("{TF_TOPIC}: publish: {e:?}");
                }
            }
        }
        match publisher.async_publish(msg).await {
            Ok(()) => c.forwarded(t0.elapsed()),
            Err(e) => {
                debug!("joint_states: publish: {e:?}");
                c.dropped();
            }
        }
    }
}

/// `/tf` for a merged `sensor_msgs/JointState`, stamped as it is.
fn tf_of(joints: &[crate::tf::TfJoint], js: &Ros) -> Option<Ros> {
    let [header, Ros::List(names), Ros::List(positions), ..] = js.fields()? else {
        return None;
    };
    let stamp = header.fields()?.first()?;
    let names: Vec<&str> = names
        .iter()
        .map(|n| match n {
            Ros::Str(s) => s.as_str(),
            _ => "",
        })
        .collect();
    let positions: Vec<f64> = positions.iter().filter_map(Ros::as_f64).collect();
    crate::tf::moving_message(joints, &names, &positions, stamp)
}

/// robot_state_publisher ignores joints its URDF lacks and leaves out the links of those
/// nobody reports: say so once, when every part has reported.
fn warn_urdf_mismatch(reported: &[String], urdf: &[String]) {
    let unknown: Vec<&str> = reported
        .iter()
        .filter(|n| !urdf.contains(n))
        .map(String::as_str)
        .collect();
    let silent: Vec<&str> = urdf
        .iter()
        .filter(|n| !reported.contains(n))
        .map(String::as_str)
        .collect();
    if !unknown.is_empty() {
        warn!(
            "joint_states: joints not in the URDF: {}",
            unknown.join(", ")
        );
    }
    if !silent.is_empty() {
        warn!(
            "joint_states: URDF joints no part reports: {}",
            silent.join(", ")
        );
    }
}
