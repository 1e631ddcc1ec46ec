//! 2D lasers: `rangefinder2D_nws_ros2` publishes an attached `IRangefinder2D` as
//! `sensor_msgs/LaserScan`; `rangefinder2D_nwc_ros2` is an `IRangefinder2D` fed by a
//! `LaserScan` topic.
//!
//! Parameters as yarp-devices-ros2's: `node_name`, `namespace`, `topic_name`, `period`
//! (0.02 s) and, for the server, `frame_id` (`laser_frame`); the client also accepts
//! `verbose_on`. The client gives angles in degrees, as `IRangefinder2D` says (C++'s
//! client passes the message's radians through).

use crate::msgs::{laser_scan, read_laser_scan, stamp_ns, LaserInfo};
use crate::node::{on_messages, CommonParams, DeviceNode, NodeBuilder};
use crate::periodic::{Periodic, Throttle};
use parking_lot::Mutex;
use ros2_client::Publisher;
use std::sync::Arc;
use yarp_devices::rangefinder::{IRangefinder2D, LaserStatus};
use yarp_devices::{DevResult, DeviceDriver, DeviceError, IWrapper, SharedDevice};
use yarp_proto::Property;
use yarp_ros2_gateway::dynmsg::Value as Ros;

pub const NWS: &str = "rangefinder2D_nws_ros2";
pub const NWC: &str = "rangefinder2D_nwc_ros2";
const LASER_SCAN: &str = "sensor_msgs/msg/LaserScan";

yarp_devices::device_params! {
    /// What `rangefinder2D_nws_ros2` reads (C++ `Rangefinder2D_nws_ros2_params.md`).
    pub struct Rangefinder2DNwsRos2Params for "rangefinder2D_nws_ros2" {
        /// refresh period of the broadcasted values in s
        period: f64 = 0.02; "s"; check crate::node::period,
        /// name of the ros2 node
        node_name: String = required; check crate::node::node_name,
        /// optional namespace for ros2 node
        namespace: String = optional,
        /// name of the topic where the device must publish the data
        topic_name: String = required; check crate::node::topic_name,
        /// name of the base frameId
        frame_id: String = "laser_frame",
    }
}

yarp_devices::device_params! {
    /// What `rangefinder2D_nwc_ros2` reads (C++ `Rangefinder2D_nwc_ros2_params.md`).
    pub struct Rangefinder2DNwcRos2Params for "rangefinder2D_nwc_ros2" {
        /// refresh period of the broadcasted values in s (checked, otherwise unused: the
        /// client serves each scan as it arrives)
        period: f64 = 0.02; "s"; check crate::node::period,
        /// name of the ros2 node
        node_name: String = required; check crate::node::node_name,
        /// optional namespace for ros2 node
        namespace: String = optional,
        /// name of the topic the scans are read from
        topic_name: String = required; check crate::node::topic_name,
        /// if 1, it enables the verbose mode of the device (accepted, no effect here)
        verbose_on: i64 = 0,
    }
}

struct Opened {
    params: CommonParams,
    frame_id: String,
    node: DeviceNode,
    publisher: Arc<Publisher<Ros>>,
}

/// `rangefinder2D_nws_ros2`.
#[derive(Default)]
pub struct Rangefinder2DNwsRos2 {
    opened: Option<Opened>,
    streamer: Option<Periodic>,
}

impl DeviceDriver for Rangefinder2DNwsRos2 {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        Rangefinder2DNwsRos2Params::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.close()?;
        let Rangefinder2DNwsRos2Params {
            period,
            node_name,
            namespace,
            topic_name,
            frame_id,
        } = Rangefinder2DNwsRos2Params::read(config)?;
        let params = CommonParams {
            period,
            node_name,
            namespace,
            topic_name,
        };
        let mut b = NodeBuilder::new(NWS, params.namespace(), &params.node_name)?;
        let publisher = Arc::new(b.publisher(&params.topic_name, LASER_SCAN)?);
        let node = b.spin()?;
        self.opened = Some(Opened {
            params,
            frame_id,
            node,
            publisher,
        });
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.streamer = None;
        self.opened = None;
        Ok(())
    }

    yarp_devices::views!(as_wrapper);
}

impl IWrapper for Rangefinder2DNwsRos2 {
    fn attach(&mut self, device: SharedDevice) -> DevResult<()> {
        let o = self.opened.as_ref().ok_or(DeviceError::NotOpen)?;
        let info = {
            let mut pd = device.lock();
            let laser = pd
                .device()
                .as_rangefinder_2d()
                .ok_or(DeviceError::Unsupported(
                    "rangefinder2D_nws_ros2 needs an IRangefinder2D device",
                ))?;
            let (min_distance, max_distance) = laser.get_distance_range()?;
            let (min_angle, max_angle) = laser.get_scan_limits()?;
            LaserInfo {
                min_angle,
                max_angle,
                resolution: laser.get_horizontal_resolution()?,
                min_distance,
                max_distance,
            }
        };
        let (node, publisher) = (o.node.node.clone(), o.publisher.clone());
        let (frame, period) = (o.frame_id.clone(), o.params.period_duration());
        let mut errors = Throttle::default();
        self.streamer = Some(Periodic::start(
            &format!("{NWS} {}", o.params.topic_name),
            period,
            device,
            move |dev| {
                let Some(laser) = dev.as_rangefinder_2d() else {
                    return;
                };
                let data = laser.get_raw_data();
                if let Err(e) = laser.get_device_status() {
                    errors.warn(NWS, format!("sensor returned error: {e}"));
                }
                let (ranges, t) = match data {
                    Ok(d) => d,
                    Err(e) => return errors.warn(NWS, format!("sensor returned error: {e}")),
                };
                if publisher.get_subscription_count(&node) == 0 {
                    return;
                }
                let stamp = if t.is_nan() { crate::now_s() } else { t };
                let msg = laser_scan(
                    &info,
                    &ranges,
                    stamp_ns(stamp),
                    &frame,
                    period.as_secs_f64(),
                );
                let _ = publisher.publish(msg);
            },
        )?);
        Ok(())
    }

    fn detach(&mut self) -> DevResult<()> {
        self.streamer = None;
        Ok(())
    }
}

/// The latest scan a client received.
#[derive(Default)]
struct Latest {
    info: Option<LaserInfo>,
    ranges: Vec<f64>,
    stamp: f64,
}

/// `rangefinder2D_nwc_ros2`.
#[derive(Default)]
pub struct Rangefinder2DNwcRos2 {
    latest: Arc<Mutex<Latest>>,
    node: Option<DeviceNode>,
    task: Option<tokio::task::JoinHandle<()>>,
}

impl Rangefinder2DNwcRos2 {
    fn with<R>(&self, f: impl FnOnce(&Latest, &LaserInfo) -> R) -> DevResult<R> {
        let l = self.latest.lock();
        let info = l.info.ok_or_else(|| DeviceError::Failed {
            device: NWC.into(),
            reason: "no LaserScan received yet".into(),
        })?;
        Ok(f(&l, &info))
    }
}

impl DeviceDriver for Rangefinder2DNwcRos2 {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        Rangefinder2DNwcRos2Params::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.close()?;
        let p = Rangefinder2DNwcRos2Params::read(config)?;
        let mut b = NodeBuilder::new(NWC, p.namespace.as_deref().unwrap_or(""), &p.node_name)?;
        let sub = b.subscription(&p.topic_name, LASER_SCAN)?;
        let node = b.spin()?;
        let latest = self.latest.clone();
        self.task = Some(on_messages(sub, LASER_SCAN, move |m| {
            let Some((info, ranges, stamp)) = read_laser_scan(m) else {
                return;
            };
            let mut l = latest.lock();
            if l.info.is_some() && l.ranges.len() != ranges.len() {
                tracing::warn!("{NWC}: the scan changed its size");
            }
            *l = Latest {
                info: Some(info),
                ranges,
                stamp,
            };
        }));
        self.node = Some(node);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        if let Some(t) = self.task.take() {
            t.abort();
        }
        self.node = None;
        Ok(())
    }

    yarp_devices::views!(as_rangefinder_2d);
}

impl IRangefinder2D for Rangefinder2DNwcRos2 {
    fn get_raw_data(&mut self) -> DevResult<(Vec<f64>, f64)> {
        self.with(|l, _| (l.ranges.clone(), l.stamp))
    }
    fn get_device_status(&mut self) -> DevResult<LaserStatus> {
        self.with(|_, _| LaserStatus::OkInUse)
    }
    fn get_distance_range(&mut self) -> DevResult<(f64, f64)> {
        self.with(|_, i| (i.min_distance, i.max_distance))
    }
    fn set_distance_range(&mut self, _: f64, _: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported(
            "rangefinder2D_nwc_ros2 is read-only",
        ))
    }
    fn get_scan_limits(&mut self) -> DevResult<(f64, f64)> {
        self.with(|_, i| (i.min_angle, i.max_angle))
    }
    fn set_scan_limits(&mut self, _: f64, _: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported(
            "rangefinder2D_nwc_ros2 is read-only",
        ))
    }
    fn get_horizontal_resolution(&mut self) -> DevResult<f64> {
        self.with(|_, i| i.resolution)
    }
    fn set_horizontal_resolution(&mut self, _: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported(
            "rangefinder2D_nwc_ros2 is read-only",
        ))
    }
    fn get_scan_rate(&mut self) -> DevResult<f64> {
        Err(DeviceError::Unsupported(
            "rangefinder2D_nwc_ros2 has no scan rate",
        ))
    }
    fn set_scan_rate(&mut self, _: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported(
            "rangefinder2D_nwc_ros2 is read-only",
        ))
    }
    fn get_device_info(&mut self) -> DevResult<String> {
        Ok(format!("{NWC}: a ROS 2 LaserScan topic"))
    }
}
