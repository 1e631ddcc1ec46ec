//! Mobile bases and their batteries: `battery_nws_ros2` (an `IBattery` as
//! `sensor_msgs/BatteryState`), `odometry2D_nws_ros2` (an `IOdometry2D` as
//! `nav_msgs/Odometry` on `topic_name` and as `tf2_msgs/TFMessage` on `/tf`) and
//! `mobileBaseVelocityControl_nws_ros2` (`geometry_msgs/Twist` commands on `topic_name`
//! into an `INavigation2DVelocityActions`: linear x, y and angular z, the last in
//! degrees/s).
//!
//! Parameters as yarp-devices-ros2's: `node_name`, `namespace`, `topic_name`, `period`
//! (0.02 s; the velocity control has none), and for the odometry `odom_frame` and
//! `base_frame` (both required). As in C++, the battery is published while a subscriber
//! is matched, the transform always, the odometry while a subscriber is matched.

use crate::msgs::{battery_state, odometry, read_twist, stamp_ns, BatteryReading};
use crate::node::{CommonParams, DeviceNode, NodeBuilder};
use crate::periodic::{Periodic, Throttle};
use futures::StreamExt;
use parking_lot::Mutex;
use ros2_client::Publisher;
use std::sync::Arc;
use yarp_devices::{DevResult, DeviceDriver, DeviceError, IWrapper, Params, SharedDevice};
use yarp_proto::Property;
use yarp_ros2_gateway::dynmsg::{MsgSeed, Value as Ros};

pub const BATTERY: &str = "battery_nws_ros2";
pub const ODOMETRY: &str = "odometry2D_nws_ros2";
pub const VELOCITY: &str = "mobileBaseVelocityControl_nws_ros2";

/// Which of the publishing wrappers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Battery,
    Odometry,
}

struct Opened {
    params: CommonParams,
    frames: (String, String),
    node: DeviceNode,
    publishers: Vec<Arc<Publisher<Ros>>>,
}

/// `battery_nws_ros2` or `odometry2D_nws_ros2`.
pub struct StateNwsRos2 {
    kind: Kind,
    opened: Option<Opened>,
    streamer: Option<Periodic>,
}

impl StateNwsRos2 {
    pub fn new(kind: Kind) -> Self {
        StateNwsRos2 {
            kind,
            opened: None,
            streamer: None,
        }
    }

    fn name(&self) -> &'static str {
        match self.kind {
            Kind::Battery => BATTERY,
            Kind::Odometry => ODOMETRY,
        }
    }
}

impl DeviceDriver for StateNwsRos2 {
    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.close()?;
        let name = self.name();
        let p = Params::new(name, config);
        let params = CommonParams::read(&p, 0.02)?;
        let mut b = NodeBuilder::new(name, &params.namespace, &params.node_name)?;
        let (publishers, frames) = match self.kind {
            Kind::Battery => (
                vec![b.publisher(&params.topic_name, "sensor_msgs/msg/BatteryState")?],
                (String::new(), String::new()),
            ),
            Kind::Odometry => {
                let frame = |k: &str| p.string(k)?.ok_or_else(|| p.missing(k));
                let frames = (frame("odom_frame")?, frame("base_frame")?);
                (
                    vec![
                        b.publisher(&params.topic_name, "nav_msgs/msg/Odometry")?,
                        b.publisher("/tf", "tf2_msgs/msg/TFMessage")?,
                    ],
                    frames,
                )
            }
        };
        let node = b.spin()?;
        self.opened = Some(Opened {
            params,
            frames,
            node,
            publishers: publishers.into_iter().map(Arc::new).collect(),
        });
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.streamer = None;
        self.opened = None;
        Ok(())
    }

    fn as_wrapper(&mut self) -> Option<&mut dyn IWrapper> {
        Some(self)
    }
}

fn read_battery(dev: &mut dyn DeviceDriver) -> DevResult<BatteryReading> {
    let b = dev.as_battery().ok_or(DeviceError::Unsupported(
        "battery_nws_ros2 needs an IBattery device",
    ))?;
    Ok(BatteryReading {
        voltage: b.get_battery_voltage()?,
        current: b.get_battery_current()?,
        charge: b.get_battery_charge()?,
        temperature: b.get_battery_temperature()?,
        status: b.get_battery_status()?,
    })
}

impl IWrapper for StateNwsRos2 {
    fn attach(&mut self, device: SharedDevice) -> DevResult<()> {
        let (kind, name) = (self.kind, self.name());
        let o = self.opened.as_ref().ok_or(DeviceError::NotOpen)?;
        {
            let mut pd = device.lock();
            let ok = match kind {
                Kind::Battery => pd.device().as_battery().is_some(),
                Kind::Odometry => pd.device().as_odometry_2d().is_some(),
            };
            if !ok {
                return Err(DeviceError::Unsupported(match kind {
                    Kind::Battery => "battery_nws_ros2 needs an IBattery device",
                    Kind::Odometry => "odometry2D_nws_ros2 needs an IOdometry2D device",
                }));
            }
        }
        let node = o.node.node.clone();
        let pubs = o.publishers.clone();
        let (odom_frame, base_frame) = o.frames.clone();
        let mut errors = Throttle::default();
        self.streamer = Some(Periodic::start(
            &format!("{name} {}", o.params.topic_name),
            o.params.period,
            device,
            move |dev| {
                let wanted = pubs[0].get_subscription_count(&node) > 0;
                let r = match kind {
                    Kind::Battery if wanted => read_battery(dev).map(|b| {
                        let _ = pubs[0].publish(battery_state(&b, stamp_ns(crate::now_s())));
                    }),
                    Kind::Battery => Ok(()),
                    Kind::Odometry => dev
                        .as_odometry_2d()
                        .ok_or(DeviceError::Unsupported("lost IOdometry2D"))
                        .and_then(|o| o.get_odometry())
                        .map(|(data, t)| {
                            let t = if t.is_nan() || t <= 0.0 {
                                crate::now_s()
                            } else {
                                t
                            };
                            let (odom, tf) = odometry(&data, &odom_frame, &base_frame, stamp_ns(t));
                            if wanted {
                                let _ = pubs[0].publish(odom);
                            }
                            let _ = pubs[1].publish(tf);
                        }),
                };
                if let Err(e) = r {
                    errors.warn(name, e);
                }
            },
        )?);
        Ok(())
    }

    fn detach(&mut self) -> DevResult<()> {
        self.streamer = None;
        Ok(())
    }
}

/// `mobileBaseVelocityControl_nws_ros2`.
#[derive(Default)]
pub struct MobileBaseVelocityControlNwsRos2 {
    target: Arc<Mutex<Option<SharedDevice>>>,
    node: Option<DeviceNode>,
    task: Option<tokio::task::JoinHandle<()>>,
}

impl DeviceDriver for MobileBaseVelocityControlNwsRos2 {
    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.close()?;
        let p = Params::new(VELOCITY, config);
        let node_name = p
            .string("node_name")?
            .ok_or_else(|| p.missing("node_name"))?;
        let topic = p
            .string("topic_name")?
            .ok_or_else(|| p.missing("topic_name"))?;
        let namespace = p.string("namespace")?.unwrap_or_default();
        let mut b = NodeBuilder::new(VELOCITY, &namespace, &node_name)?;
        let sub = b.subscription(&topic, "geometry_msgs/msg/Twist")?;
        let node = b.spin()?;
        let target = self.target.clone();
        let seed = MsgSeed::new("geometry_msgs/msg/Twist").expect("Twist is in the catalog");
        self.task = Some(yarp_devices::runtime::handle().spawn(async move {
            let stream = sub.async_stream_seed(seed);
            futures::pin_mut!(stream);
            while let Some(r) = stream.next().await {
                let Some((x, y, wz)) = r.ok().and_then(|(m, _)| read_twist(&m)) else {
                    continue;
                };
                let dev = target.lock().clone();
                let Some(dev) = dev else { continue };
                // The device may block; keep it off the runtime's workers.
                let _ = tokio::task::spawn_blocking(move || {
                    let mut pd = dev.lock();
                    if let Some(nav) = pd.device().as_navigation_2d_velocity() {
                        if let Err(e) = nav.apply_velocity_command(x, y, wz.to_degrees(), 0.1) {
                            tracing::warn!("{VELOCITY}: {e}");
                        }
                    }
                })
                .await;
            }
        }));
        self.node = Some(node);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        if let Some(t) = self.task.take() {
            t.abort();
        }
        self.node = None;
        *self.target.lock() = None;
        Ok(())
    }

    fn as_wrapper(&mut self) -> Option<&mut dyn IWrapper> {
        Some(self)
    }
}

impl IWrapper for MobileBaseVelocityControlNwsRos2 {
    fn attach(&mut self, device: SharedDevice) -> DevResult<()> {
        let ok = device.lock().device().as_navigation_2d_velocity().is_some();
        if !ok {
            return Err(DeviceError::Unsupported(
                "mobileBaseVelocityControl_nws_ros2 needs an INavigation2DVelocityActions device",
            ));
        }
        *self.target.lock() = Some(device);
        Ok(())
    }

    fn detach(&mut self) -> DevResult<()> {
        *self.target.lock() = None;
        Ok(())
    }
}
