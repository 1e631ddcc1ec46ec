//! `imu_nwc_ros2` (yarp-devices-ros2's `Imu_nwc_ros2`): a `sensor_msgs/Imu` topic as one
//! IMU's `IThreeAxisGyroscopes` (deg/s), `IThreeAxisLinearAccelerometers` (m/s^2) and
//! `IOrientationSensors` (roll-pitch-yaw in degrees), named `sensor_name`, in the frame
//! of the last message; `MAS_WAITING_FOR_FIRST_READ` until one arrives. Parameters:
//! `node_name`, `namespace`, `topic_name`, `sensor_name`.

use crate::node::{on_messages, DeviceNode, NodeBuilder};
use parking_lot::Mutex;
use std::sync::Arc;
use yarp_devices::sensors::interfaces::{
    IOrientationSensors, IThreeAxisGyroscopes, IThreeAxisLinearAccelerometers,
};
use yarp_devices::sensors::{MasStatus, SensorMeasurement};
use yarp_devices::{DevResult, DeviceDriver, DeviceError};
use yarp_proto::Property;
use yarp_ros2_gateway::dynmsg::Value as Ros;
use yarp_ros2_gateway::mas::quaternion_to_rpy_deg;

pub const NAME: &str = "imu_nwc_ros2";
const IMU: &str = "sensor_msgs/msg/Imu";

yarp_devices::device_params! {
    /// What `imu_nwc_ros2` reads (C++ `GenericSensor_nwc_ros2_params.md`).
    pub struct ImuNwcRos2Params for "imu_nwc_ros2" {
        /// name of the ros2 node
        node_name: String = required,
        /// optional namespace for ros2 node
        namespace: String = optional,
        /// name of the topic the sensor_msgs/Imu messages are read from
        topic_name: String = required,
        /// The name of the sensor the data are coming from
        sensor_name: String = required,
    }
}

/// One received `sensor_msgs/Imu`, in YARP units.
#[derive(Debug, Clone, PartialEq)]
pub struct ImuReading {
    pub frame: String,
    pub stamp: f64,
    pub gyro_deg_s: [f64; 3],
    pub acc: [f64; 3],
    pub rpy_deg: [f64; 3],
}

fn xyz(v: &Ros) -> Option<[f64; 3]> {
    let f = v.fields()?;
    Some([
        f.first()?.as_f64()?,
        f.get(1)?.as_f64()?,
        f.get(2)?.as_f64()?,
    ])
}

/// A `sensor_msgs/Imu` value in YARP units (pure).
pub fn read_imu(m: &Ros) -> Option<ImuReading> {
    let f = m.fields()?;
    let q = f.get(1)?.fields()?;
    let q = [
        q.first()?.as_f64()?,
        q.get(1)?.as_f64()?,
        q.get(2)?.as_f64()?,
        q.get(3)?.as_f64()?,
    ];
    Some(ImuReading {
        frame: crate::msgs::header_frame(f.first()?),
        stamp: crate::msgs::header_time(f.first()?),
        gyro_deg_s: xyz(f.get(3)?)?.map(f64::to_degrees),
        acc: xyz(f.get(5)?)?,
        rpy_deg: quaternion_to_rpy_deg(q),
    })
}

#[derive(Default)]
pub struct ImuNwcRos2 {
    sensor_name: String,
    latest: Arc<Mutex<Option<ImuReading>>>,
    node: Option<DeviceNode>,
    task: Option<tokio::task::JoinHandle<()>>,
}

impl ImuNwcRos2 {
    fn reading(&self) -> DevResult<ImuReading> {
        self.latest
            .lock()
            .clone()
            .ok_or_else(|| DeviceError::failed(NAME, "no data received yet"))
    }

    fn status(&self) -> MasStatus {
        match self.latest.lock().as_ref() {
            Some(_) => MasStatus::Ok,
            None => MasStatus::WaitingForFirstRead,
        }
    }

    fn measure(&self, i: usize, pick: fn(&ImuReading) -> [f64; 3]) -> DevResult<SensorMeasurement> {
        if i != 0 {
            return Err(DeviceError::InvalidJoint {
                joint: i as i64,
                axes: 1,
            });
        }
        let r = self.reading()?;
        Ok(SensorMeasurement::new(pick(&r).to_vec(), r.stamp))
    }
}

impl DeviceDriver for ImuNwcRos2 {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        ImuNwcRos2Params::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.close()?;
        let p = ImuNwcRos2Params::read(config)?;
        self.sensor_name = p.sensor_name;
        let namespace = p.namespace.as_deref().unwrap_or("");
        let mut b = NodeBuilder::new(NAME, namespace, &p.node_name)?;
        let sub = b.subscription(&p.topic_name, IMU)?;
        let node = b.spin()?;
        let latest = self.latest.clone();
        self.task = Some(on_messages(sub, IMU, move |m| {
            if let Some(reading) = read_imu(m) {
                *latest.lock() = Some(reading);
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
        Ok(())
    }

    yarp_devices::views!(
        as_three_axis_gyroscopes,
        as_three_axis_linear_accelerometers,
        as_orientation_sensors
    );
}

/// One of the three families, all answered from the last message.
macro_rules! imu_family {
    ($iface:ident, $nr:ident, $status:ident, $name:ident, $frame:ident, $get:ident, $pick:expr) => {
        impl $iface for ImuNwcRos2 {
            fn $nr(&self) -> usize {
                1
            }
            fn $status(&self, _: usize) -> MasStatus {
                self.status()
            }
            fn $name(&self, _: usize) -> DevResult<String> {
                Ok(self.sensor_name.clone())
            }
            fn $frame(&self, _: usize) -> DevResult<String> {
                Ok(self.reading()?.frame)
            }
            fn $get(&self, i: usize) -> DevResult<SensorMeasurement> {
                self.measure(i, $pick)
            }
        }
    };
}

imu_family!(
    IThreeAxisGyroscopes,
    get_nr_of_three_axis_gyroscopes,
    get_three_axis_gyroscope_status,
    get_three_axis_gyroscope_name,
    get_three_axis_gyroscope_frame_name,
    get_three_axis_gyroscope_measure,
    |r| r.gyro_deg_s
);
imu_family!(
    IThreeAxisLinearAccelerometers,
    get_nr_of_three_axis_linear_accelerometers,
    get_three_axis_linear_accelerometer_status,
    get_three_axis_linear_accelerometer_name,
    get_three_axis_linear_accelerometer_frame_name,
    get_three_axis_linear_accelerometer_measure,
    |r| r.acc
);
imu_family!(
    IOrientationSensors,
    get_nr_of_orientation_sensors,
    get_orientation_sensor_status,
    get_orientation_sensor_name,
    get_orientation_sensor_frame_name,
    get_orientation_sensor_measure_as_roll_pitch_yaw,
    |r| r.rpy_deg
);
