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
use yarp_devices::{runtime, DevResult, DeviceError};
use yarp_ros2_gateway::dynmsg::Value as Ros;
use yarp_ros2_gateway::mapping::Qos;
use yarp_ros2_gateway::ros::{self, RosError};

/// A participant for one device's node.
fn context() -> Result<Context, RosError> {
    ros::start_context(ros::domain_from_env()?, &ros::networks_from_env())
}

yarp_devices::device_params! {
    /// What a wrapper publishing one topic reads (yarp-devices-ros2's
    /// `GenericSensor_nws_ros2_params.md`, whose rows `Battery_nws_ros2_params.md` repeats):
    /// `imu_nws_ros2` and the other sensor wrappers and `battery_nws_ros2` read it as it
    /// is (with [`CommonParams::read_as`]); the wrappers with more parameters declare
    /// their own table and build it from theirs.
    pub struct CommonParams for "genericSensor_nws_ros2" {
        /// refresh period of the broadcasted values in s
        period: f64 = 0.02; "s"; check crate::node::period,
        /// name of the ros2 node
        node_name: String = required; check crate::node::node_name,
        /// optional namespace for ros2 node
        namespace: String = optional,
        /// name of the topic where the device must publish the data
        topic_name: String = required; check crate::node::topic_name,
    }
}

impl CommonParams {
    /// `period` as a duration (checked greater than 0 when read).
    pub fn period_duration(&self) -> std::time::Duration {
        std::time::Duration::from_secs_f64(self.period)
    }

    /// The node's namespace, `""` (the root) when not given.
    pub fn namespace(&self) -> &str {
        self.namespace.as_deref().unwrap_or_default()
    }
}

/// A ROS node name as the C++ devices take it: without a leading `/`
/// (declared `; check crate::node::node_name`).
pub fn node_name(name: &str) -> Result<(), &'static str> {
    match name.starts_with('/') {
        true => Err("a name without a leading '/'"),
        false => Ok(()),
    }
}

/// A ROS topic name as the C++ devices take it: with a leading `/`
/// (declared `; check crate::node::topic_name`).
pub fn topic_name(name: &str) -> Result<(), &'static str> {
    match name.starts_with('/') {
        true => Ok(()),
        false => Err("a name with a leading '/'"),
    }
}

/// A publishing period in seconds, greater than 0 (declared `; check crate::node::period`).
pub fn period(s: &f64) -> Result<(), &'static str> {
    match *s > 0.0 && s.is_finite() {
        true => Ok(()),
        false => Err("a period in seconds greater than 0"),
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

#[cfg(test)]
mod tests {
    use super::*;
    use yarp_proto::Property;

    fn read(text: &str) -> DevResult<CommonParams> {
        CommonParams::read_as("imu_nws_ros2", &Property::from_text(text))
    }

    fn error(text: &str) -> String {
        read(text).unwrap_err().to_string()
    }

    #[test]
    fn common_params_default_and_check_as_the_cpp_devices() {
        let p = read("(node_name imu) (topic_name /imu)").unwrap();
        assert_eq!(p.period_duration(), std::time::Duration::from_millis(20));
        assert_eq!((p.namespace(), p.node_name.as_str()), ("", "imu"));
        let p = read("(node_name imu) (topic_name /imu) (namespace robot) (period 1)").unwrap();
        assert_eq!(p.period_duration(), std::time::Duration::from_secs(1));
        assert_eq!(p.namespace(), "robot");

        let e = error("(topic_name /imu)");
        assert!(
            e.contains("`imu_nws_ros2`") && e.contains("`node_name`"),
            "{e}"
        );
        assert!(error("(node_name imu)").contains("`topic_name`"));
        let e = error("(node_name /imu) (topic_name /imu)");
        assert!(
            e.contains("`node_name`") && e.contains("without a leading '/'"),
            "{e}"
        );
        let e = error("(node_name imu) (topic_name imu)");
        assert!(
            e.contains("`topic_name`") && e.contains("with a leading '/'"),
            "{e}"
        );
        for bad in ["0", "-0.1", "fast"] {
            let e = error(&format!("(node_name imu) (topic_name /imu) (period {bad})"));
            assert!(e.contains("`period`"), "{e}");
        }
    }
}
