//! `skinWrapper` (icub-main): an `analogServer` for a skin part, as the iCub
//! configurations declare it (`wrappers/skin/left_arm_skin_wrapper.xml`).
//!
//! Parameters: `robotName` (given by yarprobotinterface), `period` (ms, default 20),
//! `total_taxels`, and the `ports` paramlist (`left_hand 0 191 0 191` ...). As the C++
//! device, it opens an `analogServer` named `/<robot>/skin` with `channels` =
//! `total_taxels`, so the ports are `/<robot>/skin/<port>` (e.g. `/icub/skin/left_hand`;
//! a leading `/` in `robotName`, as a port prefix has, is not doubled).

use yarp_devices::driver::{DeviceDriver, IMultipleWrapper, IWrapper, SharedDevice};
use yarp_devices::error::DevResult;
use yarp_devices::sensors::analog_server::AnalogServer;
use yarp_proto::{Property, Value};

yarp_devices::device_params! {
    /// What `skinWrapper` reads (icub-main's `skinWrapper`), which serves the skin as an
    /// analogServer named `/<robotName>/skin` (the `ports` lines are read by that server).
    pub struct SkinWrapperParams for "skinWrapper" {
        /// The robot's name: the ports are `/<robotName>/skin/...`
        "robotName" robot_name: String = required,
        /// Period of the streamed values
        period: f64 = 20.0; "ms",
        /// Number of taxels of the patches together
        total_taxels: i64 = optional,
        /// The ports the taxels are split over (each with a line `PORT wBase wTop base top`)
        ports: Vec<String> = optional,
    }
}

/// The `skinWrapper` device.
#[derive(Default)]
pub struct SkinWrapper {
    server: AnalogServer,
}

impl SkinWrapper {
    pub fn new() -> Self {
        Self::default()
    }

    /// The analog server doing the work (its ports).
    pub fn server(&self) -> &AnalogServer {
        &self.server
    }
}

impl DeviceDriver for SkinWrapper {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        SkinWrapperParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = SkinWrapperParams::read(config)?;
        let (robot, period) = (p.robot_name, p.period);
        let mut option = config.clone();
        option.put(
            "name",
            Value::from(format!("/{}/skin", robot.trim_matches('/')).as_str()),
        );
        option.put("period", Value::Float64(period));
        if let Some(total) = p.total_taxels {
            option.put("channels", Value::Int64(total));
            option.unput("total_taxels");
        }
        option.put("device", Value::from("analogServer"));
        self.server.open(&option)
    }

    fn close(&mut self) -> DevResult<()> {
        self.server.close()
    }

    fn as_wrapper(&mut self) -> Option<&mut dyn IWrapper> {
        Some(&mut self.server)
    }

    yarp_devices::views!(as_multiple_wrapper);
}

impl IMultipleWrapper for SkinWrapper {
    fn attach_all(&mut self, devices: &[(String, SharedDevice)]) -> DevResult<()> {
        self.server.attach_all(devices)
    }

    fn detach_all(&mut self) -> DevResult<()> {
        self.server.detach_all()
    }
}
