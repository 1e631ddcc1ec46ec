//! The ROS side of a device: its own ROS node (as yarp-devices-ros2's `NodeCreator` gives
//! each device an rclcpp node) on its own DDS participant (the gateway's
//! [`ros::start_context`]; domain and interfaces from `ROS_DOMAIN_ID` and
//! `ROS_AUTOMATIC_DISCOVERY_RANGE` as rcl reads them), spun on the device runtime.
//!
//! One participant per node, not one per process: ros2-client's spinner takes the
//! participant's discovery events from one shared queue, so two spinning nodes of one
//! participant each miss the events the other took (a publisher then never learns of its
//! subscribers, a service server of its clients).

use ros2_client::{Context, Node, Publisher, Server, Subscription};
use std::sync::Arc;
use tokio::task::JoinHandle;
use yarp_devices::{runtime, DevResult, DeviceError, Params};
use yarp_ros2_gateway::dynmsg::Value as Ros;
use yarp_ros2_gateway::mapping::Qos;
use yarp_ros2_gateway::ros::{self, RosError};

/// A participant for one device's node.
fn context() -> Result<Context, RosError> {
    ros::start_context(ros::domain_from_env()?, &ros::networks_from_env())
}

/// What every wrapper of this crate reads (yarp-devices-ros2's `node_name`, `namespace`,
/// `topic_name`, `period`), checked as the C++ devices check them.
#[derive(Debug, Clone)]
pub struct CommonParams {
    pub node_name: String,
    pub namespace: String,
    pub topic_name: String,
    pub period: std::time::Duration,
}

impl CommonParams {
    pub fn read(p: &Params, default_period_s: f64) -> DevResult<CommonParams> {
        let node_name = p
            .string("node_name")?
            .ok_or_else(|| p.missing("node_name"))?;
        let topic_name = p
            .string("topic_name")?
            .ok_or_else(|| p.missing("topic_name"))?;
        let bad = |param: &str, expected: &'static str, got: String| DeviceError::BadParam {
            device: p.device.to_string(),
            param: param.to_string(),
            expected,
            got,
        };
        if node_name.starts_with('/') {
            return Err(bad("node_name", "a name without a leading '/'", node_name));
        }
        if !topic_name.starts_with('/') {
            return Err(bad("topic_name", "a name with a leading '/'", topic_name));
        }
        let period = p.float("period")?.unwrap_or(default_period_s);
        if !(period > 0.0 && period.is_finite()) {
            return Err(bad(
                "period",
                "a period in seconds greater than 0",
                period.to_string(),
            ));
        }
        Ok(CommonParams {
            node_name,
            namespace: p.string("namespace")?.unwrap_or_default(),
            topic_name,
            period: std::time::Duration::from_secs_f64(period),
        })
    }
}

fn failed(device: &str, e: impl std::fmt::Display) -> DeviceError {
    DeviceError::Failed {
        device: device.to_string(),
        reason: e.to_string(),
    }
}

/// A device's node while its endpoints are being made.
pub struct NodeBuilder {
    device: &'static str,
    node: Node,
}

/// rclcpp's `QoS(10)` of yarp-devices-ros2's endpoints: reliable, volatile, keep last 10.
fn qos() -> Qos {
    Qos::default()
}

/// `/tf_static`'s QoS, as tf2's static broadcaster and listener use it: reliable and
/// transient local, so that a listener that starts later still gets the static frames.
pub fn latched_qos() -> Qos {
    Qos {
        durability: yarp_ros2_gateway::mapping::Durability::TransientLocal,
        ..Qos::default()
    }
}

impl NodeBuilder {
    pub fn new(device: &'static str, namespace: &str, node_name: &str) -> DevResult<NodeBuilder> {
        let ctx = context().map_err(|e| failed(device, e))?;
        // rclcpp takes "" for the root namespace and a relative one as absolute
        let namespace = match namespace.trim_end_matches('/') {
            "" => "/".to_string(),
            n if n.starts_with('/') => n.to_string(),
            n => format!("/{n}"),
        };
        let node = ros::new_node(&ctx, &namespace, node_name).map_err(|e| failed(device, e))?;
        Ok(NodeBuilder { device, node })
    }

    /// A publisher of catalog type `ros_type` (dynamic messages).
    pub fn publisher(&mut self, topic: &str, ros_type: &str) -> DevResult<Publisher<Ros>> {
        self.publisher_with(topic, ros_type, &qos())
    }

    /// [`NodeBuilder::publisher`] with QoS `q`.
    pub fn publisher_with(
        &mut self,
        topic: &str,
        ros_type: &str,
        q: &Qos,
    ) -> DevResult<Publisher<Ros>> {
        ros::publisher(&mut self.node, topic, ros_type, q).map_err(|e| failed(self.device, e))
    }

    /// A subscription of catalog type `ros_type` (decode with `dynmsg::MsgSeed`).
    pub fn subscription(&mut self, topic: &str, ros_type: &str) -> DevResult<Subscription<Ros>> {
        self.subscription_with(topic, ros_type, &qos())
    }

    /// [`NodeBuilder::subscription`] with QoS `q`.
    pub fn subscription_with(
        &mut self,
        topic: &str,
        ros_type: &str,
        q: &Qos,
    ) -> DevResult<Subscription<Ros>> {
        ros::subscription(&mut self.node, topic, ros_type, q).map_err(|e| failed(self.device, e))
    }

    /// A service server of `pkg/srv/Name` with typed request and response.
    pub fn server<Req, Resp>(&mut self, name: &str, srv_type: &str) -> DevResult<Server<Req, Resp>>
    where
        Req: ros2_client::Message + Clone + 'static,
        Resp: ros2_client::Message + 'static,
    {
        ros::server(&mut self.node, name, srv_type).map_err(|e| failed(self.device, e))
    }

    /// Starts spinning the node (discovery, subscriber counts, service matching).
    pub fn spin(mut self) -> DevResult<DeviceNode> {
        let spinner = self
            .node
            .spinner()
            .map_err(|e| failed(self.device, format!("{e:?}")))?;
        let device = self.device;
        let spinner = runtime::handle().spawn(async move {
            if let Err(e) = spinner.spin().await {
                tracing::warn!("{device}: ROS spinner stopped: {e:?}");
            }
        });
        Ok(DeviceNode {
            node: Arc::new(self.node),
            spinner,
        })
    }
}

/// A device's spinning node.
pub struct DeviceNode {
    pub node: Arc<Node>,
    spinner: JoinHandle<()>,
}

impl DeviceNode {
    pub fn is_spinning(&self) -> bool {
        !self.spinner.is_finished()
    }
}

/// Spawns on the device runtime a task that hands every message of `sub` (of catalog
/// type `ros_type`) to `on_msg`, in order; messages that do not decode are skipped.
pub fn on_messages(
    sub: Subscription<Ros>,
    ros_type: &str,
    mut on_msg: impl FnMut(&Ros) + Send + 'static,
) -> JoinHandle<()> {
    let seed = yarp_ros2_gateway::dynmsg::MsgSeed::new(ros_type);
    runtime::handle().spawn(async move {
        use futures::StreamExt;
        let Some(seed) = seed else {
            return;
        };
        let stream = sub.async_stream_seed(seed);
        futures::pin_mut!(stream);
        while let Some(r) = stream.next().await {
            if let Ok((m, _)) = r {
                on_msg(&m);
            }
        }
    })
}
