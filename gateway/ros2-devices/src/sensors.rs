//! The multiple-analog-sensors wrappers (yarp-devices-ros2's `GenericSensor_nws_ros2`
//! family): each serves the first sensor of one family of the one attached device as a
//! ROS 2 topic, every `period` while a subscriber is matched (parameters `node_name`,
//! `namespace`, `topic_name`, `period`, default 0.02 s; `header.frame_id` is the
//! sensor's frame name).
//!
//! | device | ROS type | from |
//! |---|---|---|
//! | `imu_nws_ros2` | `sensor_msgs/Imu` | gyroscope (deg/s → rad/s), accelerometer, orientation (roll-pitch-yaw → quaternion); the device must also be a magnetometer, as C++ asks |
//! | `wrenchStamped_nws_ros2` | `geometry_msgs/WrenchStamped` | six-axis force/torque |
//! | `magneticField_nws_ros2` | `sensor_msgs/MagneticField` | three-axis magnetometer (tesla) |
//! | `temperature_nws_ros2` | `sensor_msgs/Temperature` | temperature sensor (°C) |
//!
//! The first two are yarp-devices-ros2's; the last two are the ROS 2 form of C++ YARP's
//! `MagneticFieldRosPublisher` and `TemperatureRosPublisher` of the same family. C++
//! `wrenchStamped_nws_ros2` reads the torque from elements 4..6 of the six (one past the
//! end); here it is elements 3..5.

use crate::node::{CommonParams, DeviceNode, NodeBuilder};
use crate::periodic::Periodic;
use parking_lot::{Mutex, MutexGuard};
use ros2_client::Publisher;
use std::sync::Arc;
use yarp_devices::sensors::SensorMeasurement;
use yarp_devices::{DevResult, DeviceDriver, DeviceError, IMultipleWrapper, SharedDevice};
use yarp_ros2_gateway::counters::header;
use yarp_ros2_gateway::dynmsg::Value as Ros;
use yarp_ros2_gateway::mas::rpy_deg_to_quaternion;

/// Which sensor family a wrapper publishes, and as what.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Family {
    Imu,
    WrenchStamped,
    MagneticField,
    Temperature,
}

impl Family {
    pub fn device_name(self) -> &'static str {
        match self {
            Family::Imu => "imu_nws_ros2",
            Family::WrenchStamped => "wrenchStamped_nws_ros2",
            Family::MagneticField => "magneticField_nws_ros2",
            Family::Temperature => "temperature_nws_ros2",
        }
    }

    pub fn ros_type(self) -> &'static str {
        match self {
            Family::Imu => "sensor_msgs/msg/Imu",
            Family::WrenchStamped => "geometry_msgs/msg/WrenchStamped",
            Family::MagneticField => "sensor_msgs/msg/MagneticField",
            Family::Temperature => "sensor_msgs/msg/Temperature",
        }
    }

    /// Whether `dev` has the interfaces this wrapper reads, and its sensor 0's frame.
    fn frame(self, dev: &mut dyn DeviceDriver) -> DevResult<String> {
        let missing = |what| DeviceError::Unsupported(what);
        match self {
            Family::Imu => {
                dev.as_three_axis_linear_accelerometers()
                    .ok_or(missing("imu_nws_ros2 needs IThreeAxisLinearAccelerometers"))?;
                dev.as_three_axis_magnetometers()
                    .ok_or(missing("imu_nws_ros2 needs IThreeAxisMagnetometers"))?;
                dev.as_orientation_sensors()
                    .ok_or(missing("imu_nws_ros2 needs IOrientationSensors"))?;
                dev.as_three_axis_gyroscopes()
                    .ok_or(missing("imu_nws_ros2 needs IThreeAxisGyroscopes"))?
                    .get_three_axis_gyroscope_frame_name(0)
            }
            Family::WrenchStamped => dev
                .as_six_axis_force_torque_sensors()
                .ok_or(missing(
                    "wrenchStamped_nws_ros2 needs ISixAxisForceTorqueSensors",
                ))?
                .get_six_axis_force_torque_sensor_frame_name(0),
            Family::MagneticField => dev
                .as_three_axis_magnetometers()
                .ok_or(missing(
                    "magneticField_nws_ros2 needs IThreeAxisMagnetometers",
                ))?
                .get_three_axis_magnetometer_frame_name(0),
            Family::Temperature => dev
                .as_temperature_sensors()
                .ok_or(missing("temperature_nws_ros2 needs ITemperatureSensors"))?
                .get_temperature_sensor_frame_name(0),
        }
    }

    /// One message from sensor 0 of `dev`.
    pub fn message(self, dev: &mut dyn DeviceDriver, frame: &str) -> DevResult<Ros> {
        let none = || DeviceError::Unsupported("the attached device lost an interface");
        let get = |m: DevResult<SensorMeasurement>, len: usize| -> DevResult<SensorMeasurement> {
            let m = m?;
            if m.values.len() < len {
                return Err(DeviceError::WrongSize {
                    expected: len,
                    got: m.values.len(),
                });
            }
            Ok(m)
        };
        Ok(match self {
            Family::Imu => {
                let g = get(
                    dev.as_three_axis_gyroscopes()
                        .ok_or_else(none)?
                        .get_three_axis_gyroscope_measure(0),
                    3,
                )?;
                let a = get(
                    dev.as_three_axis_linear_accelerometers()
                        .ok_or_else(none)?
                        .get_three_axis_linear_accelerometer_measure(0),
                    3,
                )?;
                let o = get(
                    dev.as_orientation_sensors()
                        .ok_or_else(none)?
                        .get_orientation_sensor_measure_as_roll_pitch_yaw(0),
                    3,
                )?;
                let q = rpy_deg_to_quaternion(&o.values);
                let zeros = || Ros::Array(vec![Ros::F64(0.0); 9]);
                // C++ stamps with the last measurement read, the orientation
                Ros::Struct(vec![
                    header(stamp_ns(o.timestamp), frame),
                    Ros::Struct(q.iter().map(|&x| Ros::F64(x)).collect()),
                    zeros(),
                    vec3(
                        g.values[0].to_radians(),
                        g.values[1].to_radians(),
                        g.values[2].to_radians(),
                    ),
                    zeros(),
                    vec3(a.values[0], a.values[1], a.values[2]),
                    zeros(),
                ])
            }
            Family::WrenchStamped => {
                let w = get(
                    dev.as_six_axis_force_torque_sensors()
                        .ok_or_else(none)?
                        .get_six_axis_force_torque_sensor_measure(0),
                    6,
                )?;
                let v = &w.values;
                Ros::Struct(vec![
                    header(stamp_ns(w.timestamp), frame),
                    Ros::Struct(vec![vec3(v[0], v[1], v[2]), vec3(v[3], v[4], v[5])]),
                ])
            }
            Family::MagneticField => {
                let m = get(
                    dev.as_three_axis_magnetometers()
                        .ok_or_else(none)?
                        .get_three_axis_magnetometer_measure(0),
                    3,
                )?;
                let v = &m.values;
                Ros::Struct(vec![
                    header(stamp_ns(m.timestamp), frame),
                    vec3(v[0], v[1], v[2]),
                    Ros::Array(vec![Ros::F64(0.0); 9]),
                ])
            }
            Family::Temperature => {
                let t = get(
                    dev.as_temperature_sensors()
                        .ok_or_else(none)?
                        .get_temperature_sensor_measure(0),
                    1,
                )?;
                Ros::Struct(vec![
                    header(stamp_ns(t.timestamp), frame),
                    Ros::F64(t.values[0]),
                    Ros::F64(0.0),
                ])
            }
        })
    }
}

fn vec3(x: f64, y: f64, z: f64) -> Ros {
    Ros::Struct(vec![Ros::F64(x), Ros::F64(y), Ros::F64(z)])
}

/// A YARP time in seconds as ROS nanoseconds (C++ `ros2TimeFromYarp`: 0 stays 0).
fn stamp_ns(t: f64) -> u64 {
    if t > 0.0 && t.is_finite() {
        (t * 1e9) as u64
    } else {
        0
    }
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock()
}

struct Opened {
    params: CommonParams,
    node: DeviceNode,
    publisher: Arc<Publisher<Ros>>,
    /// The periodic publisher (C++ `PeriodicThread::run`).
    streamer: Option<Periodic>,
}

/// One wrapper of the family.
pub struct SensorNwsRos2 {
    family: Family,
    opened: Option<Opened>,
}

impl SensorNwsRos2 {
    pub fn new(family: Family) -> Self {
        SensorNwsRos2 {
            family,
            opened: None,
        }
    }
}

/// Drivers of this family, by device name.
pub const DRIVERS: &[(&str, yarp_devices::Factory)] = &[
    ("imu_nws_ros2", || Box::new(SensorNwsRos2::new(Family::Imu))),
    ("wrenchStamped_nws_ros2", || {
        Box::new(SensorNwsRos2::new(Family::WrenchStamped))
    }),
    ("magneticField_nws_ros2", || {
        Box::new(SensorNwsRos2::new(Family::MagneticField))
    }),
    ("temperature_nws_ros2", || {
        Box::new(SensorNwsRos2::new(Family::Temperature))
    }),
];

impl DeviceDriver for SensorNwsRos2 {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        CommonParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &yarp_proto::Property) -> DevResult<()> {
        self.opened = None;
        let name = self.family.device_name();
        let params = CommonParams::read_as(name, config)?;
        let mut b = NodeBuilder::new(name, params.namespace(), &params.node_name)?;
        let publisher = Arc::new(b.publisher(&params.topic_name, self.family.ros_type())?);
        let node = b.spin()?;
        self.opened = Some(Opened {
            params,
            node,
            publisher,
            streamer: None,
        });
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.opened = None;
        Ok(())
    }

    yarp_devices::views!(as_multiple_wrapper);
}

impl IMultipleWrapper for SensorNwsRos2 {
    fn attach_all(&mut self, devices: &[(String, SharedDevice)]) -> DevResult<()> {
        let family = self.family;
        let name = family.device_name();
        let o = self.opened.as_mut().ok_or(DeviceError::NotOpen)?;
        let device = match devices {
            [(_, d)] => d.clone(),
            [] => return Err(DeviceError::Unsupported("no device to attach")),
            _ => {
                return Err(DeviceError::Unsupported(
                    "a *_nws_ros2 sensor wrapper serves a single device (join several with multipleanalogsensorsremapper)",
                ))
            }
        };
        let frame = family.frame(lock(&device).device())?;
        o.streamer = None;
        let (node, publisher) = (o.node.node.clone(), o.publisher.clone());
        let period = o.params.period_duration();
        let topic = o.params.topic_name.clone();
        let thread = format!("{name} {topic}");
        o.streamer = Some(Periodic::every(name, thread, period, move || {
            if publisher.get_subscription_count(&node) == 0 {
                return;
            }
            let msg = family.message(lock(&device).device(), &frame);
            match msg {
                Ok(m) => {
                    let _ = publisher.publish(m);
                }
                Err(e) => tracing::debug!("{name} {topic}: {e}"),
            }
        })?);
        Ok(())
    }

    fn detach_all(&mut self) -> DevResult<()> {
        if let Some(o) = self.opened.as_mut() {
            o.streamer = None;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use yarp_devices::{shared, PolyDriver};
    use yarp_proto::Property;

    #[test]
    fn messages_have_the_catalog_layout() {
        let imu = shared(PolyDriver::open(&Property::from_text("(device fakeIMU)")).unwrap());
        let fts = shared(
            PolyDriver::open(&Property::from_text("(device fakeFTs) (sensorNames (ft0))")).unwrap(),
        );
        for (family, dev) in [
            (Family::Imu, &imu),
            (Family::MagneticField, &imu),
            (Family::WrenchStamped, &fts),
            (Family::Temperature, &fts),
        ] {
            let mut pd = lock(dev);
            let frame = family.frame(pd.device()).unwrap();
            let m = family.message(pd.device(), &frame).unwrap();
            assert!(m.conforms_to(family.ros_type()), "{family:?}: {m:?}");
        }
        let mut pd = lock(&fts);
        assert!(Family::Imu.frame(pd.device()).is_err());
    }
}
