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
use yarp_devices::{DevResult, DeviceDriver, DeviceError, IWrapper, SharedDevice};
use yarp_proto::Property;
use yarp_ros2_gateway::dynmsg::{MsgSeed, Value as Ros};

pub const BATTERY: &str = "battery_nws_ros2";
pub const ODOMETRY: &str = "odometry2D_nws_ros2";
pub const VELOCITY: &str = "mobileBaseVelocityControl_nws_ros2";

// `battery_nws_ros2` reads [`CommonParams`] (C++ `Battery_nws_ros2_params.md`).

yarp_devices::device_params! {
    /// What `odometry2D_nws_ros2` reads (C++ `Odometry2D_nws_ros2_params.md`).
    pub struct Odometry2DNwsRos2Params for "odometry2D_nws_ros2" {
        /// refresh period of the broadcasted values in s
        period: f64 = 0.02; "s"; check crate::node::period,
        /// name of the ros2 node
        node_name: String = required; check crate::node::node_name,
        /// optional namespace for ros2 node
        namespace: String = optional,
        /// name of the topic where the device must publish the data
        topic_name: String = required; check crate::node::topic_name,
        /// name of the reference frame for odometry
        odom_frame: String = required,
        /// name of the base frame for odometry
        base_frame: String = required,
    }
}

yarp_devices::device_params! {
    /// What `mobileBaseVelocityControl_nws_ros2` reads (C++
    /// `MobileBaseVelocityControl_nws_ros2_params.md`).
    pub struct MobileBaseVelocityControlNwsRos2Params for "mobileBaseVelocityControl_nws_ros2" {
        /// name of the ros2 node
        node_name: String = required,
        /// optional namespace for ros2 node
        namespace: String = optional,
        /// name of the topic the geometry_msgs/Twist commands are read from
        topic_name: String = required,
    }
}

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

    /// The common parameters and, for the odometry, `odom_frame` and `base_frame`.
    fn read_params(&self, config: &Property) -> DevResult<(CommonParams, (String, String))> {
        match self.kind {
            Kind::Battery => Ok((
                CommonParams::read_as(BATTERY, config)?,
                (String::new(), String::new()),
            )),
            Kind::Odometry => {
                let Odometry2DNwsRos2Params {
                    period,
                    node_name,
                    namespace,
                    topic_name,
                    odom_frame,
                    base_frame,
                } = Odometry2DNwsRos2Params::read(config)?;
                let common = CommonParams {
                    period,
                    node_name,
                    namespace,
                    topic_name,
                };
                Ok((common, (odom_frame, base_frame)))
            }
        }
    }
}

impl DeviceDriver for StateNwsRos2 {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        let params = match self.kind {
            Kind::Battery => CommonParams::PARAMS,
            Kind::Odometry => Odometry2DNwsRos2Params::PARAMS,
        };
        params.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.close()?;
        let name = self.name();
        let (params, frames) = self.read_params(config)?;
        let mut b = NodeBuilder::new(name, params.namespace(), &params.node_name)?;
        let publishers = match self.kind {
            Kind::Battery => vec![b.publisher(&params.topic_name, "sensor_msgs/msg/BatteryState")?],
            Kind::Odometry => vec![
                b.publisher(&params.topic_name, "nav_msgs/msg/Odometry")?,
                b.publisher("/tf", "tf2_msgs/msg/TFMessage")?,
            ],
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

    yarp_devices::views!(as_wrapper);
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
            o.params.period_duration(),
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
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        MobileBaseVelocityControlNwsRos2Params::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.close()?;
        let p = MobileBaseVelocityControlNwsRos2Params::read(config)?;
        let namespace = p.namespace.as_deref().unwrap_or("");
        let mut b = NodeBuilder::new(VELOCITY, namespace, &p.node_name)?;
        let sub = b.subscription(&p.topic_name, "geometry_msgs/msg/Twist")?;
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

    yarp_devices::views!(as_wrapper);
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
