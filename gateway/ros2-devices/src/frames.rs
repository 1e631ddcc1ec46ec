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
use yarp_devices::{DevResult, DeviceDriver, DeviceError, Params};
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

/// The parameters both clients read.
struct Common {
    node: String,
    namespace: String,
    topic: String,
    topic_static: String,
    refresh: f64,
}

fn common(p: &Params, default_node: &str) -> DevResult<Common> {
    let s =
        |k: &str, d: &str| -> DevResult<String> { Ok(p.string(k)?.unwrap_or_else(|| d.into())) };
    Ok(Common {
        node: s("ROS2::ft_node", default_node)?,
        namespace: s("ROS2::namespace", "")?,
        topic: s("ROS2::ft_topic", "/tf")?,
        topic_static: s("ROS2::ft_topic_static", "/tf_static")?,
        refresh: p.float("GENERAL::refresh_interval")?.unwrap_or(0.1),
    })
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
    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.close()?;
        let c = common(&Params::new(GET, config), "tfNodeGet")?;
        *lock(&self.container) = FrameTransformContainer::new(c.refresh);
        let mut b = NodeBuilder::new(GET, &c.namespace, &c.node)?;
        let subs = [
            (b.subscription(&c.topic, TF)?, false),
            // transient local: the static frames published before this client started
            (
                b.subscription_with(&c.topic_static, TF, &crate::node::latched_qos())?,
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

    fn as_frame_transform_storage_get(&mut self) -> Option<&mut dyn IFrameTransformStorageGet> {
        Some(self)
    }
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
    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.close()?;
        let p = Params::new(SET, config);
        let c = common(&p, "tfNodeSet")?;
        let period = p.float("GENERAL::period")?.unwrap_or(0.01);
        if !(period > 0.0 && period.is_finite()) {
            return Err(DeviceError::BadParam {
                device: SET.into(),
                param: "GENERAL::period".into(),
                expected: "a period in seconds greater than 0",
                got: period.to_string(),
            });
        }
        self.asynch = p.int("GENERAL::asynch_pub")?.unwrap_or(1) == 1;
        *lock(&self.container) = FrameTransformContainer::new(c.refresh);
        let mut b = NodeBuilder::new(SET, &c.namespace, &c.node)?;
        let publishing = Arc::new(Publishing {
            timed: b.publisher(&c.topic, TF)?,
            // transient local, as C++ and tf2's static broadcaster: a late listener
            // still gets the static frames
            statics: b.publisher_with(&c.topic_static, TF, &crate::node::latched_qos())?,
        });
        self.node = Some(b.spin()?);
        let stop = Arc::new(std::sync::atomic::AtomicBool::new(false));
        let (s, pb, container) = (stop.clone(), publishing.clone(), self.container.clone());
        let thread = std::thread::Builder::new()
            .name(format!("{SET} {}", c.node))
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

    fn as_frame_transform_storage_set(&mut self) -> Option<&mut dyn IFrameTransformStorageSet> {
        Some(self)
    }
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
}
