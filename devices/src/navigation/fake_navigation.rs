//! `fakeNavigation` (C++ `FakeNavigation`), its velocity actions: it keeps the last
//! velocity command. C++'s target and control actions (goals reached after
//! `navigation_time` / `reached_time`, both accepted here) are not modelled.

use super::INavigation2DVelocityActions;
use crate::driver::DeviceDriver;
use crate::error::DevResult;
use std::time::Instant;
use yarp_proto::Property;

crate::device_params! {
    /// What `fakeNavigation` reads (C++ `FakeNavigation_params.md`; read and checked, as
    /// this fake answers velocity commands only).
    pub struct FakeNavigationParams for "fakeNavigation" {
        /// navigation_time
        navigation_time: i64 = 500,
        /// reached_time
        reached_time: i64 = 100,
    }
}

/// The last velocity command and when it came (C++ `m_control_out`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct VelocityCommand {
    pub x_vel: f64,
    pub y_vel: f64,
    pub theta_vel: f64,
    pub timeout: f64,
}

#[derive(Default)]
pub struct FakeNavigation {
    last: VelocityCommand,
    received: Option<Instant>,
    commands: u64,
}

impl FakeNavigation {
    pub fn new() -> FakeNavigation {
        FakeNavigation::default()
    }

    /// How many velocity commands arrived.
    pub fn commands(&self) -> u64 {
        self.commands
    }
}

impl DeviceDriver for FakeNavigation {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        FakeNavigationParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        FakeNavigationParams::read(config)?;
        Ok(())
    }

    crate::views!(as_navigation_2d_velocity);
}

impl INavigation2DVelocityActions for FakeNavigation {
    fn apply_velocity_command(
        &mut self,
        x_vel: f64,
        y_vel: f64,
        theta_vel: f64,
        timeout: f64,
    ) -> DevResult<()> {
        self.last = VelocityCommand {
            x_vel,
            y_vel,
            theta_vel,
            timeout,
        };
        self.received = Some(Instant::now());
        self.commands += 1;
        Ok(())
    }

    fn get_last_velocity_command(&mut self) -> DevResult<(f64, f64, f64)> {
        Ok((self.last.x_vel, self.last.y_vel, self.last.theta_vel))
    }
}
