//! Frame-transform clients: `frameTransformGet_nwc_ros2` (`tf2_msgs/TFMessage` on `/tf` and
//! `/tf_static` into an `IFrameTransformStorageGet`) and `frameTransformSet_nwc_ros2` (an
//! `IFrameTransformStorageSet` published there: every `GENERAL::period`, and at once on
//! each set when `GENERAL::asynch_pub` is 1).
//!
//! Parameters as yarp-devices-ros2's: `GENERAL::refresh_interval` (0.1 s: timed
//! transforms older than that are dropped), `GENERAL::period` (0.01 s), `GENERAL::asynch_pub`
//! (1), `ROS2::ft_node` (`tfNodeGet` / `tfNodeSet`), `ROS2::namespace`, `ROS2::ft_topic`
//! (`/tf`), `ROS2::ft_topic_static` (`/tf_static`).

use crate::msgs::{header_frame, header_time, stamp_ns};
use crate::node::{on_messages, DeviceNode, NodeBuilder};
use parking_lot::Mutex;
use ros2_client::Publisher;
use std::sync::Arc;
use std::time::Duration;
use yarp_devices::frames::{
    FrameTransform, FrameTransformContainer, IFrameTransformStorageGet, IFrameTransformStorageSet,
};
use yarp_devices::{DevResult, DeviceDriver, DeviceError};
use yarp_proto::Property;
use yarp_ros2_gateway::counters::header;
use yarp_ros2_gateway::dynmsg::Value as Ros;

pub const GET: &str = "frameTransformGet_nwc_ros2";
pub const SET: &str = "frameTransformSet_nwc_ros2";
const TF: &str = "tf2_msgs/msg/TFMessage";

fn f64s(v: &[f64]) -> Vec<Ros> {
    v.iter().map(|&x| Ros::F64(x)).collect()
}

/// A `tf2_msgs/TFMessage` of `transforms` (pure).
pub fn tf_message(transforms: &[&FrameTransform]) -> Ros {
    Ros::Struct(vec![Ros::List(
        transforms
            .iter()
            .map(|t| {
                Ros::Struct(vec![
                    header(stamp_ns(t.timestamp), &t.src_frame_id),
                    Ros::Str(t.dst_frame_id.clone()),
                    Ros::Struct(vec![
                        Ros::Struct(f64s(&t.translation)),
                        Ros::Struct(f64s(&t.rotation)),
                    ]),
                ])
            })
            .collect(),
    )])
}

/// The transforms of a received `tf2_msgs/TFMessage` (pure).
pub fn read_tf_message(m: &Ros, is_static: bool) -> Vec<FrameTransform> {
    let Some([Ros::List(items)]) = m.fields() else {
        return Vec::new();
    };
    let nums = |v: &Ros| -> Option<Vec<f64>> { v.fields()?.iter().map(Ros::as_f64).collect() };
    items
        .iter()
        .filter_map(|ts| {
            let [h, Ros::Str(child), tr] = ts.fields()? else {
                return None;
            };
            let [t, r] = tr.fields()? else { return None };
            Some(FrameTransform {
                src_frame_id: header_frame(h),
                dst_frame_id: child.clone(),
                timestamp: header_time(h),
                is_static,
                translation: nums(t)?.try_into().ok()?,
                rotation: nums(r)?.try_into().ok()?,
            })
        })
        .collect()
}

yarp_devices::device_params! {
    /// What `frameTransformGet_nwc_ros2` reads (C++ `FrameTransformGet_nwc_ros2_params.md`).
    pub struct FrameTransformGetNwcRos2Params for "frameTransformGet_nwc_ros2" {
        /// The time interval outside which timed ft will be deleted
        "GENERAL::refresh_interval" refresh_interval: f64 = 0.1; "s",
        /// The name of the ROS2 node
        "ROS2::ft_node" ft_node: String = "tfNodeGet",
        /// optional namespace for ros2 node
        "ROS2::namespace" namespace: String = optional,
        /// The name of the ROS2 topic from which fts will be received
        "ROS2::ft_topic" ft_topic: String = "/tf",
        /// The name of the ROS2 topic from which static fts will be received
        "ROS2::ft_topic_static" ft_topic_static: String = "/tf_static",
    }
}

yarp_devices::device_params! {
    /// What `frameTransformSet_nwc_ros2` reads (C++ `FrameTransformSet_nwc_ros2_params.md`).
    pub struct FrameTransformSetNwcRos2Params for "frameTransformSet_nwc_ros2" {
        /// The time interval outside which timed ft will be deleted
        "GENERAL::refresh_interval" refresh_interval: f64 = 0.1; "s",
        /// The PeriodicThread period in seconds
        "GENERAL::period" period: f64 = 0.01; "s"; check crate::node::period,
        /// If 1, the fts will be published not only every "period" seconds but also when
        /// set functions are called
        "GENERAL::asynch_pub" asynch_pub: i64 = 1,
        /// The name of the ROS2 node
        "ROS2::ft_node" ft_node: String = "tfNodeSet",
        /// optional namespace for ros2 node
        "ROS2::namespace" namespace: String = optional,
        /// The name of the ROS2 topic to which fts will be published
        "ROS2::ft_topic" ft_topic: String = "/tf",
        /// The name of the ROS2 topic to which static fts will be published
        "ROS2::ft_topic_static" ft_topic_static: String = "/tf_static",
    }
}

fn lock<T>(m: &Mutex<T>) -> parking_lot::MutexGuard<'_, T> {
    m.lock()
}

/// `frameTransformGet_nwc_ros2`.
#[derive(Default)]
pub struct FrameTransformGetNwcRos2 {
    container: Arc<Mutex<FrameTransformContainer>>,
    node: Option<DeviceNode>,
    tasks: Vec<tokio::task::JoinHandle<()>>,
}

impl DeviceDriver for FrameTransformGetNwcRos2 {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        FrameTransformGetNwcRos2Params::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.close()?;
        let c = FrameTransformGetNwcRos2Params::read(config)?;
        *lock(&self.container) = FrameTransformContainer::new(c.refresh_interval);
        let namespace = c.namespace.as_deref().unwrap_or("");
        let mut b = NodeBuilder::new(GET, namespace, &c.ft_node)?;
        let subs = [
            (b.subscription(&c.ft_topic, TF)?, false),
            // transient local: the static frames published before this client started
            (
                b.subscription_with(&c.ft_topic_static, TF, &crate::node::latched_qos())?,
                true,
            ),
        ];
        let node = b.spin()?;
        for (sub, is_static) in subs {
            let container = self.container.clone();
            self.tasks.push(on_messages(sub, TF, move |m| {
                let mut c = lock(&container);
                for t in read_tf_message(m, is_static) {
                    c.set(t);
                }
            }));
        }
        self.node = Some(node);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        for t in self.tasks.drain(..) {
            t.abort();
        }
        self.node = None;
        Ok(())
    }

    yarp_devices::views!(as_frame_transform_storage_get);
}

impl IFrameTransformStorageGet for FrameTransformGetNwcRos2 {
    fn get_transforms(&mut self) -> DevResult<Vec<FrameTransform>> {
        Ok(lock(&self.container).current(crate::now_s()))
    }
}

/// What the setter publishes with.
struct Publishing {
    timed: Publisher<Ros>,
    statics: Publisher<Ros>,
}

fn publish(p: &Publishing, container: &Mutex<FrameTransformContainer>) {
    let all = lock(container).current(crate::now_s());
    let timed: Vec<&FrameTransform> = all.iter().filter(|t| !t.is_static).collect();
    let statics: Vec<&FrameTransform> = all.iter().filter(|t| t.is_static).collect();
    if !timed.is_empty() {
        let _ = p.timed.publish(tf_message(&timed));
    }
    if !statics.is_empty() {
        let _ = p.statics.publish(tf_message(&statics));
    }
}

/// `frameTransformSet_nwc_ros2`.
#[derive(Default)]
pub struct FrameTransformSetNwcRos2 {
    container: Arc<Mutex<FrameTransformContainer>>,
    publishing: Option<Arc<Publishing>>,
    asynch: bool,
    node: Option<DeviceNode>,
    thread: Option<(
        Arc<std::sync::atomic::AtomicBool>,
        std::thread::JoinHandle<()>,
    )>,
}

impl DeviceDriver for FrameTransformSetNwcRos2 {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        FrameTransformSetNwcRos2Params::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.close()?;
        let c = FrameTransformSetNwcRos2Params::read(config)?;
        let period = c.period;
        self.asynch = c.asynch_pub == 1;
        *lock(&self.container) = FrameTransformContainer::new(c.refresh_interval);
        let namespace = c.namespace.as_deref().unwrap_or("");
        let mut b = NodeBuilder::new(SET, namespace, &c.ft_node)?;
        let publishing = Arc::new(Publishing {
            timed: b.publisher(&c.ft_topic, TF)?,
            // transient local, as C++ and tf2's static broadcaster: a late listener
            // still gets the static frames
            statics: b.publisher_with(&c.ft_topic_static, TF, &crate::node::latched_qos())?,
        });
        self.node = Some(b.spin()?);
        let stop = Arc::new(std::sync::atomic::AtomicBool::new(false));
        let (s, pb, container) = (stop.clone(), publishing.clone(), self.container.clone());
        let thread = std::thread::Builder::new()
            .name(format!("{SET} {}", c.ft_node))
            .spawn(move || {
                let mut tick =
                    yarp_devices::sensors::periodic::Ticker::new(Duration::from_secs_f64(period));
                while !s.load(std::sync::atomic::Ordering::Relaxed) {
                    tick.tick_blocking();
                    publish(&pb, &container);
                }
            })
            .map_err(|e| DeviceError::failed(SET, e))?;
        self.thread = Some((stop, thread));
        self.publishing = Some(publishing);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        if let Some((stop, t)) = self.thread.take() {
            stop.store(true, std::sync::atomic::Ordering::Relaxed);
            let _ = t.join();
        }
        self.publishing = None;
        self.node = None;
        Ok(())
    }

    yarp_devices::views!(as_frame_transform_storage_set);
}

impl IFrameTransformStorageSet for FrameTransformSetNwcRos2 {
    fn set_transforms(&mut self, transforms: &[FrameTransform]) -> DevResult<()> {
        {
            let mut c = lock(&self.container);
            for t in transforms {
                c.set(t.clone());
            }
        }
        if self.asynch {
            if let Some(p) = &self.publishing {
                publish(p, &self.container);
            }
        }
        Ok(())
    }
    fn delete_transform(&mut self, src: &str, dst: &str) -> DevResult<()> {
        lock(&self.container).delete(src, dst);
        Ok(())
    }
    fn clear_all(&mut self) -> DevResult<()> {
        lock(&self.container).clear();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tf_messages_round_trip() {
        let t = FrameTransform {
            src_frame_id: "odom".into(),
            dst_frame_id: "base_link".into(),
            timestamp: 12.5,
            is_static: false,
            translation: [1.0, 2.0, 3.0],
            rotation: [0.0, 0.0, 0.0, 1.0],
        };
        let m = tf_message(&[&t]);
        assert!(m.conforms_to(TF));
        assert_eq!(read_tf_message(&m, false), vec![t]);
        assert!(read_tf_message(&Ros::Struct(vec![]), true).is_empty());
    }

    #[test]
    fn parameters_default_as_in_cpp_and_are_read_from_their_groups() {
        let get = FrameTransformGetNwcRos2Params::read(&Property::new()).unwrap();
        assert_eq!(
            (
                get.ft_node.as_str(),
                get.ft_topic.as_str(),
                get.ft_topic_static.as_str()
            ),
            ("tfNodeGet", "/tf", "/tf_static")
        );
        assert_eq!((get.refresh_interval, get.namespace), (0.1, None));
        let set = FrameTransformSetNwcRos2Params::read(&Property::new()).unwrap();
        assert_eq!(
            (set.ft_node.as_str(), set.period, set.asynch_pub),
            ("tfNodeSet", 0.01, 1)
        );
        let set = FrameTransformSetNwcRos2Params::read(&Property::from_text(
            "(GENERAL (period 0.5) (asynch_pub 0)) (ROS2 (ft_node n) (namespace ns))",
        ))
        .unwrap();
        assert_eq!((set.period, set.asynch_pub), (0.5, 0));
        assert_eq!(
            (set.ft_node.as_str(), set.namespace.as_deref()),
            ("n", Some("ns"))
        );
        let e = FrameTransformSetNwcRos2Params::read(&Property::from_text("(GENERAL (period 0))"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("`GENERAL::period`"), "{e}");
    }
}
