//! `cerOdometry` (robotology/cer `CerOdometry`): R1's base odometry from its two wheels.
//!
//! Attached (`<param name="device">`) to a control board of exactly two axes, the left and
//! right wheels' encoders in degrees, it computes every `period` (s, default 0.01) as C++
//! does: the heading straight from the wheels, `θ = r / L · (right − left)`; the base's
//! forward speed `r/2 · (ω_left + ω_right)` and its turn rate, each the finite difference of
//! the last two samples (C++'s `AWLinEstimator` of window 2); the velocity in the odometry
//! frame by the heading; the position integrated over the time between cycles. Angles and
//! turn rates are given in degrees. `resetOdometry` takes the current wheel angles as the
//! new zero and puts the base back at the origin. Parameters: `geom_r` (wheel radius, m)
//! and `geom_l` (wheel distance, m), both required. As C++, opening asks for a reachable
//! name server.

use parking_lot::Mutex;
use std::sync::Arc;
use std::time::{Duration, Instant};
use yarp_devices::device_thread::{stopped, DeviceThread};
use yarp_devices::driver::{DeviceDriver, IWrapper, SharedDevice};
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::navigation::{IOdometry2D, OdometryData};
use yarp_devices::sensors::params::now;
use yarp_proto::Property;

pub const NAME: &str = "cerOdometry";

yarp_devices::device_params! {
    /// What `cerOdometry` reads (robotology/cer's `CerOdometry`).
    pub struct CerOdometryParams for "cerOdometry" {
        /// Period of the odometry's computation
        period: f64 = 0.01; "s"; check yarp_devices::params::positive,
        /// Radius of the wheels
        geom_r: f64 = required; "m",
        /// Distance between the wheels
        geom_l: f64 = required; "m",
    }
}

/// A finite difference of the last two samples (C++ `AWLinEstimator` of order 1 and
/// window 2): zero for the first sample, or when time did not move.
#[derive(Debug, Default)]
struct Derivative {
    last: Option<(Vec<f64>, f64)>,
}

impl Derivative {
    fn estimate(&mut self, x: &[f64], t: f64) -> Vec<f64> {
        let out = match &self.last {
            Some((x0, t0)) if t > *t0 => {
                x.iter().zip(x0).map(|(a, b)| (a - b) / (t - t0)).collect()
            }
            _ => vec![0.0; x.len()],
        };
        self.last = Some((x.to_vec(), t));
        out
    }

    fn reset(&mut self) {
        self.last = None;
    }
}

/// The odometry's state, shared by the thread and the interface.
#[derive(Debug, Default)]
struct State {
    data: OdometryData,
    /// The wheels' angles (degrees) taken as zero.
    offsets: [f64; 2],
    /// The time of the right wheel's encoder read last.
    encoders_time: f64,
    last_time: Option<f64>,
    wheel_speed: Derivative,
    turn_rate: Derivative,
}

/// The geometry: wheel radius and distance.
#[derive(Debug, Clone, Copy)]
struct Geometry {
    r: f64,
    l: f64,
}

impl State {
    /// One cycle (C++ `compute`) from the wheels' angles (degrees) at `t`.
    fn compute(&mut self, g: Geometry, left: f64, right: f64, enc_time: f64, t: f64) {
        self.encoders_time = enc_time;
        let enc = [
            (left - self.offsets[0]).to_radians(),
            (right - self.offsets[1]).to_radians(),
        ];
        let w = self.wheel_speed.estimate(&enc, t);
        let theta = g.r / g.l * (enc[1] - enc[0]);
        let turn = self.turn_rate.estimate(&[theta], t)[0];
        let forward = g.r / 2.0 * (w[0] + w[1]);
        let d = &mut self.data;
        d.base_vel_x = forward;
        d.base_vel_y = 0.0;
        d.odom_vel_x = forward * theta.cos();
        d.odom_vel_y = forward * theta.sin();
        // C++'s first cycle integrates over an unset time: here, over nothing
        let dt = self.last_time.map_or(0.0, |t0| t - t0);
        d.odom_x += d.odom_vel_x * dt;
        d.odom_y += d.odom_vel_y * dt;
        d.odom_theta = theta.to_degrees();
        d.base_vel_theta = turn.to_degrees();
        d.odom_vel_theta = d.base_vel_theta;
        self.last_time = Some(t);
    }
}

/// The two wheels' angles and the right one's time.
fn read_wheels(device: &SharedDevice) -> DevResult<(f64, f64, f64)> {
    let mut pd = device.lock();
    let enc = pd
        .device()
        .as_encoders()
        .ok_or(DeviceError::NoInterface("IEncodersTimed"))?;
    let (left, _) = enc.get_encoder_timed(0)?;
    let (right, t) = enc.get_encoder_timed(1)?;
    Ok((left, right, t))
}

/// The `cerOdometry` device.
pub struct CerOdometry {
    period: Duration,
    geometry: Geometry,
    state: Arc<Mutex<State>>,
    device: Option<SharedDevice>,
    thread: DeviceThread,
}

impl Default for CerOdometry {
    fn default() -> Self {
        CerOdometry {
            period: Duration::from_millis(10),
            geometry: Geometry { r: 0.0, l: 1.0 },
            state: Arc::default(),
            device: None,
            thread: DeviceThread::default(),
        }
    }
}

impl CerOdometry {
    pub fn new() -> Self {
        Self::default()
    }
}

impl DeviceDriver for CerOdometry {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        CerOdometryParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = CerOdometryParams::read(config)?;
        if p.geom_l == 0.0 {
            return Err(DeviceError::BadParam {
                device: NAME.into(),
                param: "geom_l".into(),
                expected: "a wheel distance other than 0",
                got: "0".into(),
            });
        }
        // C++ checks the network first
        yarp_net::network::name_client().map_err(|e| {
            DeviceError::failed(
                NAME,
                format!("Sorry YARP network does not seem to be available: {e}"),
            )
        })?;
        self.period = Duration::from_secs_f64(p.period);
        self.geometry = Geometry {
            r: p.geom_r,
            l: p.geom_l,
        };
        *self.state.lock() = State::default();
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        IWrapper::detach(self)
    }

    yarp_devices::views!(as_wrapper, as_odometry_2d);
}

impl IWrapper for CerOdometry {
    fn attach(&mut self, device: SharedDevice) -> DevResult<()> {
        IWrapper::detach(self)?;
        let axes = {
            let mut pd = device.lock();
            pd.device()
                .as_encoders()
                .ok_or(DeviceError::Unsupported(
                    "cerOdometry attaches a board with IEncodersTimed",
                ))?
                .get_axes()?
        };
        if axes != 2 {
            return Err(DeviceError::failed(
                NAME,
                format!("the attached board has {axes} axes, the base's two wheels are needed"),
            ));
        }
        self.device = Some(device.clone());
        let (state, period, g) = (self.state.clone(), self.period, self.geometry);
        self.thread
            .spawn(NAME.into(), move |stop| {
                let mut next = Instant::now();
                let mut failing = false;
                while !stopped(stop) {
                    match read_wheels(&device) {
                        Ok((left, right, t)) => {
                            failing = false;
                            state.lock().compute(g, left, right, t, now());
                        }
                        Err(e) if !failing => {
                            failing = true;
                            tracing::error!("{NAME}: cannot read the wheels' encoders: {e}");
                        }
                        Err(_) => {}
                    }
                    next = (next + period).max(Instant::now());
                    std::thread::sleep(next.saturating_duration_since(Instant::now()));
                }
            })
            .map_err(|e| DeviceError::failed(NAME, format!("cannot start: {e}")))?;
        Ok(())
    }

    fn detach(&mut self) -> DevResult<()> {
        self.thread.stop();
        self.device = None;
        Ok(())
    }
}

impl IOdometry2D for CerOdometry {
    fn get_odometry(&mut self) -> DevResult<(OdometryData, f64)> {
        let s = self.state.lock();
        Ok((s.data, s.encoders_time))
    }

    fn reset_odometry(&mut self) -> DevResult<()> {
        let wheels = self.device.as_ref().map(read_wheels).transpose()?;
        let mut s = self.state.lock();
        if let Some((left, right, _)) = wheels {
            s.offsets = [left, right];
        }
        s.data.odom_x = 0.0;
        s.data.odom_y = 0.0;
        s.wheel_speed.reset();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const R1: Geometry = Geometry {
        r: 0.16416,
        l: 0.338,
    };

    #[test]
    fn straight_then_turning() {
        let mut s = State::default();
        // both wheels at 90 deg/s for 1 s: forward r * pi/2 m/s
        for k in 0..=100 {
            let t = k as f64 * 0.01;
            s.compute(R1, 90.0 * t, 90.0 * t, t, t);
        }
        let v = R1.r * std::f64::consts::FRAC_PI_2;
        assert!((s.data.base_vel_x - v).abs() < 1e-9, "{:?}", s.data);
        assert!((s.data.odom_x - v).abs() < 1e-9 && s.data.odom_y.abs() < 1e-12);
        assert_eq!(s.data.odom_theta, 0.0);
        // the right wheel 10 degrees ahead: heading r/L * 10 deg
        s.compute(R1, 90.0, 100.0, 1.01, 1.01);
        assert!((s.data.odom_theta - R1.r / R1.l * 10.0).abs() < 1e-9);
        assert!(s.data.base_vel_theta > 0.0);
    }

    #[test]
    fn the_first_sample_has_no_speed() {
        let mut d = Derivative::default();
        assert_eq!(d.estimate(&[1.0], 5.0), vec![0.0]);
        assert_eq!(d.estimate(&[3.0], 6.0), vec![2.0]);
        assert_eq!(d.estimate(&[4.0], 6.0), vec![0.0]);
    }
}
