//! `test_motor`: the fake motor of YARP's design paper ("Towards Long-Lived Robot Genes",
//! Fitzpatrick, Metta, Natale), C++ YARP 2's `yarp::dev::TestMotor`:
//!
//! ```text
//! yarpdev --device test_motor --axes 2 --single_port --name /motors
//! ```
//!
//! N axes with position, velocity and encoders (`IPositionControl`, `IVelocityControl`,
//! `IEncodersTimed`, as the C++ class). Its network wrapper is `controlBoard_nws_yarp`
//! (C++ 2 used `controlboard`, whose `--single_port` mode that wrapper also offers).
//!
//! Parameters ([`TestMotorParams`]), as C++: `axes` (default 4), `delay` (milliseconds each
//! `checkMotionDone` takes, default 0). One of our own: `speed`, the reference speed of
//! every axis in units per second (default [`DEFAULT_SPEED`]). C++'s TestMotor jumped to a
//! position target at once; here an axis moves toward it at its reference speed (a
//! reference speed of 0 jumps, as C++ did), so a reader of the encoders sees the motion.
//! In velocity mode an axis integrates its commanded velocity. The simulation advances
//! lazily by the wall time elapsed since the last call.

use crate::driver::DeviceDriver;
use crate::error::{DevResult, DeviceError};
use crate::interfaces::{IEncoders, IPositionControl, IVelocityControl};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};
use yarp_proto::Property;

/// The C++ device name.
pub const NAME: &str = "test_motor";
crate::device_params! {
    /// What `test_motor` reads: C++'s `axes` and `delay`, and our `speed`.
    pub struct TestMotorParams for "test_motor" {
        /// Number of axes
        axes: usize = 4; in 1..=1024,
        /// Time each checkMotionDone takes
        delay: u64 = 0; "ms"; in 0..=10000,
        /// Reference speed of every axis (0 jumps to the target, as C++)
        speed: f64 = 50.0; "units/s"; min 0.0,
    }
}

/// Reference speed of every axis when `speed` is not given, in units per second.
pub const DEFAULT_SPEED: f64 = 50.0;

pub(crate) const DRIVERS: &[(&str, crate::driver::Factory)] =
    &[(NAME, || Box::new(TestMotor::new()))];

#[derive(Debug, Clone, Copy, PartialEq)]
enum Mode {
    /// Moving toward `target` at `ref_speed`.
    Position,
    /// Moving at `velocity`.
    Velocity,
}

#[derive(Debug, Clone)]
struct Axis {
    pos: f64,
    /// Speed over the last update, as the encoders report it.
    speed: f64,
    target: f64,
    ref_speed: f64,
    ref_acc: f64,
    velocity: f64,
    mode: Mode,
}

impl Axis {
    fn new(ref_speed: f64) -> Axis {
        Axis {
            pos: 0.0,
            speed: 0.0,
            target: 0.0,
            ref_speed,
            ref_acc: 0.0,
            velocity: 0.0,
            mode: Mode::Position,
        }
    }

    fn advance(&mut self, dt: f64) {
        let old = self.pos;
        match self.mode {
            Mode::Position if self.ref_speed <= 0.0 => self.pos = self.target,
            Mode::Position => {
                let step = self.ref_speed * dt;
                let gap = self.target - self.pos;
                self.pos = if gap.abs() <= step {
                    self.target
                } else {
                    self.pos + step.copysign(gap)
                };
            }
            Mode::Velocity => self.pos += self.velocity * dt,
        }
        self.speed = (self.pos - old) / dt;
    }
}

/// The paper's fake motor.
#[derive(Debug)]
pub struct TestMotor {
    axes: Vec<Axis>,
    delay: Duration,
    last: Instant,
}

impl Default for TestMotor {
    fn default() -> Self {
        Self::new()
    }
}

impl TestMotor {
    /// An unopened device (no axes until `open`).
    pub fn new() -> Self {
        TestMotor {
            axes: Vec::new(),
            delay: Duration::ZERO,
            last: Instant::now(),
        }
    }

    /// A device with `n` axes and the default reference speed, as `open` makes it.
    pub fn with_axes(n: usize) -> Self {
        let mut m = Self::new();
        m.setup(n, DEFAULT_SPEED);
        m
    }

    fn setup(&mut self, n: usize, speed: f64) {
        self.axes = vec![Axis::new(speed); n];
        self.last = Instant::now();
    }

    /// Brings every axis to the present.
    fn update(&mut self) {
        let now = Instant::now();
        let dt = now.duration_since(self.last).as_secs_f64();
        if dt <= 0.0 {
            return;
        }
        self.last = now;
        for a in &mut self.axes {
            a.advance(dt);
        }
    }

    fn axis(&mut self, j: usize) -> DevResult<&mut Axis> {
        let axes = self.axes.len();
        self.axes.get_mut(j).ok_or(DeviceError::InvalidJoint {
            joint: j as i64,
            axes,
        })
    }

    fn updated(&mut self, j: usize) -> DevResult<&mut Axis> {
        self.update();
        self.axis(j)
    }
}

fn wall_clock() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_secs_f64())
        .unwrap_or(0.0)
}

impl DeviceDriver for TestMotor {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        TestMotorParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = TestMotorParams::read(config)?;
        let (n, speed) = (p.axes, p.speed);
        self.setup(n, speed);
        self.delay = Duration::from_millis(p.delay);
        Ok(())
    }

    crate::views!(as_encoders, as_position_control, as_velocity_control);
}

impl IEncoders for TestMotor {
    fn get_axes(&mut self) -> DevResult<usize> {
        Ok(self.axes.len())
    }
    fn get_encoder(&mut self, j: usize) -> DevResult<f64> {
        Ok(self.updated(j)?.pos)
    }
    fn get_encoder_speed(&mut self, j: usize) -> DevResult<f64> {
        Ok(self.updated(j)?.speed)
    }
    fn get_encoder_acceleration(&mut self, j: usize) -> DevResult<f64> {
        self.axis(j).map(|_| 0.0)
    }
    fn get_encoder_timed(&mut self, j: usize) -> DevResult<(f64, f64)> {
        Ok((self.get_encoder(j)?, wall_clock()))
    }
    fn set_encoder(&mut self, j: usize, value: f64) -> DevResult<()> {
        let a = self.updated(j)?;
        a.pos = value;
        a.target = value;
        Ok(())
    }
}

impl IPositionControl for TestMotor {
    fn get_axes(&mut self) -> DevResult<usize> {
        Ok(self.axes.len())
    }
    fn position_move(&mut self, j: usize, target: f64) -> DevResult<()> {
        let a = self.updated(j)?;
        a.mode = Mode::Position;
        a.target = target;
        Ok(())
    }
    fn relative_move(&mut self, j: usize, delta: f64) -> DevResult<()> {
        let a = self.updated(j)?;
        if a.mode == Mode::Velocity {
            a.target = a.pos;
        }
        a.mode = Mode::Position;
        a.target += delta;
        Ok(())
    }
    fn check_motion_done(&mut self, j: usize) -> DevResult<bool> {
        // C++: "delay in each call for debugging purpose"
        if !self.delay.is_zero() {
            std::thread::sleep(self.delay);
        }
        let a = self.updated(j)?;
        Ok(a.mode == Mode::Velocity || a.pos == a.target)
    }
    fn set_ref_speed(&mut self, j: usize, speed: f64) -> DevResult<()> {
        self.updated(j)?.ref_speed = speed.abs();
        Ok(())
    }
    fn set_ref_acceleration(&mut self, j: usize, acc: f64) -> DevResult<()> {
        self.axis(j)?.ref_acc = acc;
        Ok(())
    }
    fn get_ref_speed(&mut self, j: usize) -> DevResult<f64> {
        Ok(self.axis(j)?.ref_speed)
    }
    fn get_ref_acceleration(&mut self, j: usize) -> DevResult<f64> {
        Ok(self.axis(j)?.ref_acc)
    }
    fn stop(&mut self, j: usize) -> DevResult<()> {
        let a = self.updated(j)?;
        a.mode = Mode::Position;
        a.target = a.pos;
        a.velocity = 0.0;
        Ok(())
    }
    fn get_target_position(&mut self, j: usize) -> DevResult<f64> {
        Ok(self.axis(j)?.target)
    }
}

impl IVelocityControl for TestMotor {
    fn get_axes(&mut self) -> DevResult<usize> {
        Ok(self.axes.len())
    }
    fn velocity_move(&mut self, j: usize, speed: f64) -> DevResult<()> {
        let a = self.updated(j)?;
        a.mode = Mode::Velocity;
        a.velocity = speed;
        Ok(())
    }
    fn get_ref_velocity(&mut self, j: usize) -> DevResult<f64> {
        Ok(self.axis(j)?.velocity)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opened(text: &str) -> DevResult<TestMotor> {
        let mut m = TestMotor::new();
        m.open(&Property::from_text(text))?;
        Ok(m)
    }

    #[test]
    fn axes_default_and_given() {
        assert_eq!(IEncoders::get_axes(&mut opened("").unwrap()).unwrap(), 4);
        let mut m = opened("(axes 2)").unwrap();
        assert_eq!(IEncoders::get_axes(&mut m).unwrap(), 2);
        assert!(matches!(
            opened("(axes 0)"),
            Err(DeviceError::BadParam { .. })
        ));
        assert!(matches!(
            opened("(speed -1.0)"),
            Err(DeviceError::BadParam { .. })
        ));
        assert!(matches!(
            m.get_encoder(2),
            Err(DeviceError::InvalidJoint { joint: 2, axes: 2 })
        ));
    }

    #[test]
    fn position_moves_at_the_reference_speed() {
        let mut m = TestMotor::with_axes(2);
        m.position_move(0, 100.0).unwrap();
        // pretend 1 s went by: half way at 50 units/s
        m.last -= Duration::from_secs(1);
        let p = m.get_encoder(0).unwrap();
        assert!((49.0..=52.0).contains(&p), "{p}");
        assert!(!m.check_motion_done(0).unwrap());
        assert!((m.get_encoder_speed(0).unwrap() - 50.0).abs() < 1.0);
        m.last -= Duration::from_secs(5);
        assert_eq!(m.get_encoder(0).unwrap(), 100.0);
        assert!(m.check_motion_done(0).unwrap());
        assert_eq!(m.get_encoder(1).unwrap(), 0.0);
    }

    #[test]
    fn zero_speed_jumps_as_cpp_and_velocity_integrates() {
        let mut m = opened("(axes 1) (speed 0.0)").unwrap();
        m.position_move(0, -10.0).unwrap();
        assert_eq!(m.get_encoder(0).unwrap(), -10.0);
        m.velocity_move(0, 2.0).unwrap();
        m.last -= Duration::from_secs(2);
        let p = m.get_encoder(0).unwrap();
        assert!((-6.1..=-5.9).contains(&p), "{p}");
        m.stop(0).unwrap();
        assert_eq!(m.get_target_position(0).unwrap(), m.get_encoder(0).unwrap());
    }
}
