//! What a YARP -> ROS bridge publishes beside its own message: a copy for the merged
//! joint states of the robots it is a part of, and a `sensor_msgs/CameraInfo` beside each
//! Image (same header, so the two pair up by stamp as image_transport's do).

use super::robot::Tap;
use crate::camera_info::{image_geometry, topic_beside, Intrinsics};
use crate::dynmsg::Value as Ros;
use crate::mapping::{Qos, Reliability, TopicEntry};
use crate::ros::{self, RosError};
use ros2_client::{Node, Publisher};
use tracing::debug;

#[derive(Default)]
pub(super) struct Beside {
    pub(super) tap: Tap,
    pub(super) camera_info: Option<CameraInfoOut>,
}

/// The CameraInfo publisher of an image entry.
pub(super) struct CameraInfoOut {
    pub(super) publisher: std::sync::Arc<Publisher<Ros>>,
    intrinsics: Intrinsics,
    pub(super) topic: String,
}

impl CameraInfoOut {
    /// The publisher of `t`'s `camera_info`, if it has one. Reliable whatever the
    /// image's QoS: a CameraInfo is small, and a reliable writer matches best-effort
    /// readers (image_transport's, with the image's QoS) and default ones alike.
    pub(super) fn of(node: &mut Node, t: &TopicEntry) -> Result<Option<CameraInfoOut>, RosError> {
        let Some(ci) = &t.camera_info else {
            return Ok(None);
        };
        let topic = ci
            .ros_topic
            .clone()
            .unwrap_or_else(|| topic_beside(&t.ros_topic));
        let q = Qos {
            reliability: Some(Reliability::Reliable),
            ..t.qos
        };
        let publisher = ros::publisher(node, &topic, "sensor_msgs/msg/CameraInfo", &q)?;
        let intrinsics = ci.intrinsics.clone().expect("read at load time");
        Ok(Some(CameraInfoOut {
            publisher: std::sync::Arc::new(publisher),
            intrinsics,
            topic,
        }))
    }
}

impl Beside {
    /// Called with every message the bridge converted, before it is published.
    pub(super) async fn publish(&self, msg: &Ros) {
        self.tap.feed(msg);
        if let Some(ci) = &self.camera_info {
            if let Some((header, width, height)) = image_geometry(msg) {
                let info = ci.intrinsics.message(header, width, height);
                if let Err(e) = ci.publisher.async_publish(info).await {
                    debug!("{}: publish: {e:?}", ci.topic);
                }
            }
        }
    }
}
