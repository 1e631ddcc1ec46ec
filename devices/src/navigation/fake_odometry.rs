//! `fakeOdometry2D` (C++ `FakeOdometry2D`): every `period` (0.02 s) the base takes a
//! random velocity in [0, 5) on x, y and theta, and the pose integrates it. The periods
//! are played when the odometry is read (C++ plays them on its own thread).

use super::{IOdometry2D, OdometryData};
use crate::driver::DeviceDriver;
use crate::error::{DevResult, DeviceError};
use std::time::{Instant, SystemTime, UNIX_EPOCH};
use yarp_proto::Property;

crate::device_params! {
    /// What `fakeOdometry2D` reads (C++ `FakeOdometry2D_params.md`).
    pub struct FakeOdometry2DParams for "fakeOdometry2D" {
        /// thread period
        period: f64 = 0.02; "s"; check crate::params::positive,
    }
}

pub struct FakeOdometry2D {
    period: f64,
    data: OdometryData,
    /// Periods played so far, counted from `opened`.
    played: u64,
    opened: Option<Instant>,
    rng: u64,
    stamp: f64,
}

impl Default for FakeOdometry2D {
    fn default() -> Self {
        Self::new()
    }
}

impl FakeOdometry2D {
    pub fn new() -> FakeOdometry2D {
        FakeOdometry2D {
            period: 0.02,
            data: OdometryData::default(),
            played: 0,
            opened: None,
            rng: 0x2545_f491_4f6c_dd1d,
            stamp: 0.0,
        }
    }

    /// A uniform value in [0, 5) (C++ `Rand::scalar(0, 5)`).
    fn rand(&mut self) -> f64 {
        self.rng ^= self.rng << 13;
        self.rng ^= self.rng >> 7;
        self.rng ^= self.rng << 17;
        (self.rng >> 11) as f64 / (1u64 << 53) as f64 * 5.0
    }

    /// One period (C++ `run`).
    pub fn step(&mut self) {
        let (vx, vy, vt) = (self.rand(), self.rand(), self.rand());
        let d = &mut self.data;
        (d.base_vel_x, d.base_vel_y, d.base_vel_theta) = (vx, vy, vt);
        (d.odom_vel_x, d.odom_vel_y, d.odom_vel_theta) = (vx, vy, vt);
        d.odom_x += self.period * vx;
        d.odom_y += self.period * vy;
        d.odom_theta += self.period * vt;
    }
}

impl DeviceDriver for FakeOdometry2D {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        FakeOdometry2DParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.period = FakeOdometry2DParams::read(config)?.period;
        self.opened = Some(Instant::now());
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.opened = None;
        Ok(())
    }

    crate::views!(as_odometry_2d);
}

impl IOdometry2D for FakeOdometry2D {
    fn get_odometry(&mut self) -> DevResult<(OdometryData, f64)> {
        let opened = self.opened.ok_or(DeviceError::NotOpen)?;
        let due = (opened.elapsed().as_secs_f64() / self.period) as u64;
        if due > self.played {
            // A reader that comes back after a long pause gets at most a second of steps.
            let steps = (due - self.played).min((1.0 / self.period) as u64 + 1);
            for _ in 0..steps {
                self.step();
            }
            self.played = due;
            self.stamp = SystemTime::now()
                .duration_since(UNIX_EPOCH)
                .map_or(0.0, |d| d.as_secs_f64());
        }
        Ok((self.data, self.stamp))
    }

    fn reset_odometry(&mut self) -> DevResult<()> {
        self.data = OdometryData::default();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_integrate_random_velocities() {
        let mut o = FakeOdometry2D::new();
        o.open(&Property::from_config_text("period 0.1").unwrap())
            .unwrap();
        o.step();
        o.step();
        let d = o.data;
        assert!((0.0..5.0).contains(&d.base_vel_x) && d.odom_x > 0.0 && d.odom_x < 1.0);
        assert_eq!(d.odom_vel_theta, d.base_vel_theta);
        o.reset_odometry().unwrap();
        assert_eq!(o.get_odometry().unwrap().0.odom_y, 0.0);
    }
}
