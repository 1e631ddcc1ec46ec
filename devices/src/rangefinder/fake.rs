//! `fakeLaser`: a simulated 2D laser (C++ `FakeLaser` on `Lidar2DDeviceBase`).
//!
//! Parameters as in C++ 3.12: `test` (`no_obstacles`, `use_pattern` (default),
//! `use_constant`; `use_mapfile` and `use_square_trap` need a map and a localization,
//! which this fake does not have), `CONSTANT_MODE::const_distance` (1 m), `GENERAL::period`
//! (0.02 s) and `Lidar2DDeviceBase`'s `SENSOR` group: `min_angle` (0), `max_angle` (360),
//! `resolution` (1 degree), `min_distance` / `max_distance` (0.1 / 8 m; a given one
//! clips), `allow_infinity` (clipped values become infinity instead of the limit), and
//! the `SKIP` group's `min` / `max` angle ranges left unclipped.
//!
//! Scans follow the clock: the one returned is the one due at the time of the call,
//! counted in periods since `open` (C++ makes one per period on its thread).

use super::geometry::{LaserGeometry, Lidar2DParams};
use super::{IRangefinder2D, LaserStatus};
use crate::driver::DeviceDriver;
use crate::error::{DevResult, DeviceError};
use std::time::{Instant, SystemTime, UNIX_EPOCH};
use yarp_proto::Property;

const NAME: &str = "fakeLaser";

crate::device_params! {
    /// What `fakeLaser` reads: C++'s table (`FakeLaser_params.md`) without the map and
    /// localization modes (with the `SENSOR`/`SKIP` groups of [`Lidar2DParams`]).
    pub struct FakeLaserParams for "fakeLaser" {
        /// Choose the modality: no_obstacles, use_pattern or use_constant
        test: String = "use_pattern",
        /// Thread period
        "GENERAL::period" period: f64 = optional; "s"; check crate::params::positive,
        /// Thread period (an older name of GENERAL::period)
        "period" period_top_level: f64 = optional; "s"; check crate::params::positive,
        /// Default const distance for mode use_constant
        "CONSTANT_MODE::const_distance" const_distance: f64 = 1.0; "m",
    }
}

/// What the fake sees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TestMode {
    /// Infinity everywhere.
    NoObstacles,
    /// C++'s three patterns, 60 scans each: `i/100`, a growing wall, two short arcs.
    Pattern,
    /// The same distance everywhere.
    Constant(f64),
}

/// One scan of `mode` (pure): `index` counts scans since open, `elapsed` is the time in
/// seconds since the current pattern began (C++ `size`).
pub fn scan(mode: TestMode, samples: usize, index: u64, elapsed: f64, min: f64) -> Vec<f64> {
    (0..samples)
        .map(|i| match mode {
            TestMode::NoObstacles => f64::INFINITY,
            TestMode::Constant(d) => d,
            TestMode::Pattern => match (index / 60) % 3 {
                0 => i as f64 / 100.0,
                1 => elapsed * 2.0,
                _ if i <= 10 => 1.0 + i as f64 / 20.0,
                _ if (90..=100).contains(&i) => 2.0 + (i - 90) as f64 / 20.0,
                _ => min,
            },
        })
        .collect()
}

pub struct FakeLaser {
    mode: TestMode,
    geometry: LaserGeometry,
    period: f64,
    opened: Option<Instant>,
    status: LaserStatus,
}

impl Default for FakeLaser {
    fn default() -> Self {
        Self::new()
    }
}

impl FakeLaser {
    pub fn new() -> FakeLaser {
        FakeLaser {
            mode: TestMode::Pattern,
            geometry: LaserGeometry {
                min_angle: 0.0,
                max_angle: 360.0,
                resolution: 1.0,
                min_distance: 0.1,
                max_distance: 8.0,
                clip_min: false,
                clip_max: false,
                allow_infinity: true,
                skip: Vec::new(),
            },
            period: 0.02,
            opened: None,
            status: LaserStatus::GeneralError,
        }
    }

    pub fn geometry(&self) -> &LaserGeometry {
        &self.geometry
    }

    fn bad(param: &str, expected: &'static str, got: impl ToString) -> DeviceError {
        DeviceError::BadParam {
            device: NAME.into(),
            param: param.into(),
            expected,
            got: got.to_string(),
        }
    }
}

fn now_s() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

impl DeviceDriver for FakeLaser {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        [FakeLaserParams::PARAMS, Lidar2DParams::PARAMS].concat()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = FakeLaserParams::read(config)?;
        let constant = p.const_distance;
        self.mode = match p.test.as_str() {
            "no_obstacles" => TestMode::NoObstacles,
            "use_pattern" => TestMode::Pattern,
            "use_constant" => TestMode::Constant(constant),
            "use_mapfile" | "use_square_trap" => {
                return Err(DeviceError::Unsupported(
                    "fakeLaser test modes use_mapfile and use_square_trap (no maps here)",
                ))
            }
            other => {
                return Err(Self::bad(
                    "test",
                    "no_obstacles, use_pattern or use_constant",
                    other,
                ))
            }
        };
        if let Some(period) = p.period.or(p.period_top_level) {
            self.period = period;
        }
        self.geometry
            .configure(Lidar2DParams::read(config)?, NAME)?;
        self.opened = Some(Instant::now());
        self.status = LaserStatus::OkInUse;
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.opened = None;
        Ok(())
    }

    crate::views!(as_rangefinder_2d);
}

impl IRangefinder2D for FakeLaser {
    fn get_raw_data(&mut self) -> DevResult<(Vec<f64>, f64)> {
        let opened = self.opened.ok_or(DeviceError::NotOpen)?;
        let t = opened.elapsed().as_secs_f64();
        let index = (t / self.period) as u64;
        let elapsed = t - (index / 60 * 60) as f64 * self.period;
        let g = &self.geometry;
        let mut data = scan(self.mode, g.samples(), index, elapsed, g.min_distance);
        g.apply_limits(&mut data);
        Ok((data, now_s()))
    }
    fn get_device_status(&mut self) -> DevResult<LaserStatus> {
        Ok(self.status)
    }
    fn get_distance_range(&mut self) -> DevResult<(f64, f64)> {
        Ok((self.geometry.min_distance, self.geometry.max_distance))
    }
    fn set_distance_range(&mut self, min: f64, max: f64) -> DevResult<()> {
        (self.geometry.min_distance, self.geometry.max_distance) = (min, max);
        Ok(())
    }
    fn get_scan_limits(&mut self) -> DevResult<(f64, f64)> {
        Ok((self.geometry.min_angle, self.geometry.max_angle))
    }
    fn set_scan_limits(&mut self, min: f64, max: f64) -> DevResult<()> {
        (self.geometry.min_angle, self.geometry.max_angle) = (min, max);
        Ok(())
    }
    fn get_horizontal_resolution(&mut self) -> DevResult<f64> {
        Ok(self.geometry.resolution)
    }
    fn set_horizontal_resolution(&mut self, step: f64) -> DevResult<()> {
        self.geometry.resolution = step;
        Ok(())
    }
    fn get_scan_rate(&mut self) -> DevResult<f64> {
        Ok(1.0 / self.period)
    }
    fn set_scan_rate(&mut self, rate: f64) -> DevResult<()> {
        if rate <= 0.0 {
            return Err(Self::bad("scan rate", "> 0", rate));
        }
        self.period = 1.0 / rate;
        Ok(())
    }
    fn get_device_info(&mut self) -> DevResult<String> {
        Ok("Fake Laser device for test/debugging".into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn open(text: &str) -> FakeLaser {
        let mut l = FakeLaser::new();
        l.open(&Property::from_config_text(text).unwrap()).unwrap();
        l
    }

    #[test]
    fn defaults_and_robot_geometry() {
        let mut l = open("test use_constant\n[CONSTANT_MODE]\nconst_distance 2.5");
        let (d, t) = l.get_raw_data().unwrap();
        assert_eq!(d.len(), 360);
        assert!(d.iter().all(|&v| v == 2.5));
        assert!(t > 1.6e9);
        // ergoCubSN001's rplidar SENSOR group
        let mut l = open(
            "test use_constant\n[SENSOR]\nmax_distance 30.0\nmin_distance 0.1\nmax_angle 360\n\
             min_angle 0\nresolution 0.12\nallow_infinity 1\n[CONSTANT_MODE]\nconst_distance 40",
        );
        let (d, _) = l.get_raw_data().unwrap();
        assert_eq!(d.len(), 3000);
        assert!(d.iter().all(|v| v.is_infinite()), "clipped to infinity");
        assert_eq!(l.get_distance_range().unwrap(), (0.1, 30.0));
        assert_eq!(l.get_scan_limits().unwrap(), (0.0, 360.0));
    }

    #[test]
    fn pattern_and_clipping() {
        let s = scan(TestMode::Pattern, 360, 0, 0.0, 0.1);
        assert_eq!(s[150], 1.5);
        let s = scan(TestMode::Pattern, 360, 130, 0.0, 0.1);
        assert_eq!((s[5], s[95], s[50]), (1.25, 2.25, 0.1));
        let mut g = FakeLaser::new().geometry().clone();
        (g.clip_max, g.allow_infinity, g.skip) = (true, false, vec![(10.0, 20.0)]);
        let mut d = vec![9.0; 30];
        g.apply_limits(&mut d);
        assert_eq!((d[0], d[15]), (8.0, 9.0));
    }

    #[test]
    fn bad_parameters() {
        for text in [
            "test sideways",
            "[SENSOR]\nmin_angle 10\nmax_angle 5",
            "test use_mapfile",
        ] {
            let mut l = FakeLaser::new();
            assert!(
                l.open(&Property::from_config_text(text).unwrap()).is_err(),
                "{text}"
            );
        }
    }
}
