//! `tripodMotionControl` (robotology/cer `tripodMotionControl`): R1's torso and wrists,
//! each a tripod of three linear actuators, as three virtual joints: heave (m), pitch and
//! roll (degrees; joint 1 is pitch about y, joint 2 roll about x, whatever `AxisNames`
//! calls them).
//!
//! Attached to the board driving the three actuators (its raw axes 0, 1, 2), it turns
//! position commands into actuator lengths by C++'s closed-form inverse kinematics, and
//! the actuators' encoders into joint values by its forward kinematics; reference speeds
//! are shared out so the three actuators arrive together. Values are scaled by
//! `GENERAL/Encoder` as C++'s interface layers scale them (R1's torso pitch has -1).
//! Limits: heave within `TRIPOD/Min_el..Max_el`, pitch and roll within ±`Max_alpha`;
//! speed limit `LIMITS/JntVelocityMax`. Control and interaction modes, calibration, PWM
//! limits and motor encoders pass through to the board; velocity control, setting
//! encoders and limits are refused, as in C++. (C++'s other direction, `GENERAL/HW2user`,
//! and its `CONNECTION` group to a remote board are not served: no robot names them.)

use parking_lot::Mutex;
use std::time::{Duration, Instant};
use yarp_devices::driver::{DeviceDriver, IMultipleWrapper, SharedDevice};
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::interfaces::*;
use yarp_devices::vocabs::{CM_POSITION, JOINTTYPE_PRISMATIC, JOINTTYPE_REVOLUTE};
use yarp_proto::{Bottle, Property, Vocab32};

pub const NAME: &str = "tripodMotionControl";
/// The actuators of the attached board the tripod drives.
const LEGS: [usize; 3] = [0, 1, 2];

yarp_devices::device_params! {
    /// What `tripodMotionControl` reads (robotology/cer).
    pub struct TripodParams for "tripodMotionControl" {
        /// Number of joints (3)
        "GENERAL::Joints" joints: i64 = required; min 3,
        /// Scale of each joint's values (user = raw / Encoder)
        "GENERAL::Encoder" encoder: Vec<f64> = required,
        /// Whether commands go from the hardware to the user (not served)
        "GENERAL::HW2user" hw_to_user: bool = false,
        /// Names of the joints
        "AxisNames" axis_names: Vec<String> = required,
        /// Radius of the circle the actuators sit on
        "TRIPOD::Radius" radius: f64 = required; "m",
        /// Longest elongation
        "TRIPOD::Max_el" max_el: f64 = required; "m",
        /// Shortest elongation
        "TRIPOD::Min_el" min_el: f64 = required; "m",
        /// Largest pitch and roll
        "TRIPOD::Max_alpha" max_alpha: f64 = required; "deg",
        /// The base's transformation, 16 values row by row
        "TRIPOD::BASE_TRANSFORMATION" base: Vec<f64> = required,
        /// Largest joint speed
        "LIMITS::JntVelocityMax" max_velocity: f64 = required; "m/s",
    }
}

type Mat4 = [[f64; 4]; 4];

fn mul(a: &Mat4, b: &Mat4) -> Mat4 {
    let mut m = [[0.0; 4]; 4];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (0..4).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    m
}

/// The inverse of a rigid transformation.
fn se3_inv(t: &Mat4) -> Mat4 {
    let mut m = [[0.0; 4]; 4];
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = t[j][i];
        }
        m[i][3] = -(0..3).map(|k| t[k][i] * t[k][3]).sum::<f64>();
    }
    m[3][3] = 1.0;
    m
}

const IDENTITY: Mat4 = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
];

/// The tripod's geometry and C++'s kinematics.
#[derive(Debug, Clone)]
pub struct Tripod {
    pub radius: f64,
    pub base: Mat4,
}

impl Tripod {
    /// Actuator lengths (m) of heave (m), pitch and roll (degrees) (C++ `tripod_user2HW`).
    pub fn inverse(&self, user: [f64; 3]) -> [f64; 3] {
        let heave = user[0];
        let pitch = self.base[0][0] * user[1].to_radians();
        let roll = self.base[1][1] * user[2].to_radians();
        let cp = pitch.cos();
        let v1 = pitch.sin();
        let v2 = -cp * roll.sin();
        let v3 = cp * roll.cos();
        let ld2 = (v1 * v2) / (1.0 + v3);
        let ld2 = 1.0 - ld2 * ld2;
        let l_cos_t = self.radius / v3;
        let l0 =
            heave - v1 * l_cos_t * (1.5 * (ld2 - v2 * v2).sqrt() - 0.5 * (ld2 - v1 * v1).sqrt());
        let a = 3.0 * v1 * l_cos_t + 2.0 * l0;
        let b = 3f64.sqrt() * v2 * l_cos_t;
        [l0, 0.5 * (a - b), 0.5 * (a + b)]
    }

    /// The platform's pose of actuator lengths `x` (cer_kinematics' `fkinHelper`).
    fn pose(&self, x: [f64; 3]) -> Mat4 {
        let r = self.radius;
        let [x0, x1, x2] = x;
        let q33 = 27f64.sqrt() * r
            / (12.0
                * (x2 * x2 - (x0 + x1) * x2 + x1 * x1 - x0 * x1 + x0 * x0 + 27.0 / 12.0 * r * r))
                .sqrt();
        let t = if q33 >= 1.0 {
            let mut t = IDENTITY;
            t[2][3] = x0;
            t
        } else {
            let leg = |i: usize| {
                let th = (120.0 * i as f64).to_radians();
                [r * th.cos(), r * th.sin(), x[i]]
            };
            let (v1, v2, v3) = (leg(0), leg(1), leg(2));
            let a = [v2[0] - v1[0], v2[1] - v1[1], v2[2] - v1[2]];
            let b = [v3[0] - v1[0], v3[1] - v1[1], v3[2] - v1[2]];
            let c = [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ];
            let norm = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
            let n = c.map(|v| v / norm);
            let sin_theta = (1.0 - q33 * q33).sqrt();
            let (u0, u1) = (-n[1] / sin_theta, n[0] / sin_theta);
            let tmp = 1.0 - q33;
            let q11 = tmp * u0 * u0 + q33;
            let q22 = tmp * u1 * u1 + q33;
            let q21 = tmp * u0 * u1;
            let q31 = -sin_theta * u1;
            let q32 = sin_theta * u0;
            let m1 = r / q33 * (-0.5 * q11 + 1.5 * q22);
            let p = [r - m1 * q11, -m1 * q21, x0 - m1 * q31];
            [
                [q11, q21, -q31, p[0]],
                [q21, q22, -q32, p[1]],
                [q31, q32, q33, p[2]],
                [0.0, 0.0, 0.0, 1.0],
            ]
        };
        mul(&self.base, &t)
    }

    /// Heave (m), pitch and roll (degrees) of actuator lengths `x` (C++ `tripod_HW2user`).
    pub fn forward(&self, x: [f64; 3]) -> [f64; 3] {
        let h = self.pose(x);
        let h_base = mul(&se3_inv(&self.base), &h);
        // YARP's dcm2ypr of the pose (not of the pose in the base, as C++ does)
        let (pitch, roll) = if h[0][2] < 1.0 && h[0][2] > -1.0 {
            (h[0][2].asin(), (-h[1][2]).atan2(h[2][2]))
        } else if h[0][2] <= -1.0 {
            (-std::f64::consts::FRAC_PI_2, 0.0)
        } else {
            (std::f64::consts::FRAC_PI_2, 0.0)
        };
        [h_base[2][3], pitch.to_degrees(), roll.to_degrees()]
    }
}

/// The joints' configuration.
#[derive(Debug, Clone)]
struct Config {
    names: Vec<String>,
    /// user = internal / encoder (C++'s `angleToEncoder`)
    encoder: [f64; 3],
    tripod: Tripod,
    limits: [(f64, f64); 3],
    max_velocity: f64,
}

/// What the tripod remembers between calls (C++'s members of the same names).
#[derive(Debug, Clone, Default)]
struct Refs {
    user_ref: [f64; 3],
    robot_ref: [f64; 3],
    last_robot_encoders: [f64; 3],
    ref_speed: f64,
    speeds: [f64; 3],
}

/// The `tripodMotionControl` device.
pub struct TripodMotionControl {
    config: Option<Config>,
    board: Option<SharedDevice>,
    refs: Mutex<Refs>,
}

impl Default for TripodMotionControl {
    fn default() -> Self {
        TripodMotionControl {
            config: None,
            board: None,
            refs: Mutex::new(Refs {
                ref_speed: 0.01,
                ..Refs::default()
            }),
        }
    }
}

/// How long the attach waits for the board's first encoders (C++ waits for ever).
const FIRST_ENCODERS: Duration = Duration::from_secs(5);

fn view<'a, T: ?Sized>(v: Option<&'a mut T>, what: &'static str) -> DevResult<&'a mut T> {
    v.ok_or(DeviceError::NoInterface(what))
}

impl TripodMotionControl {
    pub fn new() -> Self {
        Self::default()
    }

    fn cfg(&self) -> DevResult<&Config> {
        self.config.as_ref().ok_or(DeviceError::NotOpen)
    }

    /// `f` on the attached board.
    fn on<T>(&self, f: impl FnOnce(&mut dyn DeviceDriver) -> DevResult<T>) -> DevResult<T> {
        let board = self.board.as_ref().ok_or(DeviceError::NotReady(
            "tripodMotionControl: no board attached yet",
        ))?;
        let mut pd = board.lock();
        f(pd.device())
    }

    fn joint(&self, j: usize) -> DevResult<usize> {
        match j {
            0..=2 => Ok(j),
            _ => Err(DeviceError::InvalidJoint {
                joint: i64::try_from(j).unwrap_or(i64::MAX),
                axes: 3,
            }),
        }
    }

    /// The board's actuator lengths and their time.
    fn legs(&self) -> DevResult<([f64; 3], f64)> {
        self.on(|d| {
            let e = view(d.as_encoders(), "IEncodersTimed")?;
            let mut x = [0.0; 3];
            let mut t = 0.0;
            for k in LEGS {
                (x[k], t) = e.get_encoder_timed(k)?;
            }
            Ok((x, t))
        })
    }

    /// The joints (internal units) now, remembering the lengths (C++ `refreshEncoders`).
    fn joints_now(&self) -> DevResult<([f64; 3], f64)> {
        let (x, t) = self.legs()?;
        self.refs.lock().last_robot_encoders = x;
        Ok((self.cfg()?.tripod.forward(x), t))
    }

    /// Sends the references in `refs.user_ref` as a position move (C++ `positionMove` after
    /// its IK): each actuator's speed in proportion to its way to go.
    fn send_position(&self) -> DevResult<()> {
        let tripod = &self.cfg()?.tripod;
        let (targets, speeds) = {
            let mut r = self.refs.lock();
            r.robot_ref = tripod.inverse(r.user_ref);
            let delta: Vec<f64> = (0..3)
                .map(|k| (r.robot_ref[k] - r.last_robot_encoders[k]).abs())
                .collect();
            let max = delta.iter().cloned().fold(0.0, f64::max);
            if max > 10e-6 {
                let ref_speed = r.ref_speed;
                for (speed, d) in r.speeds.iter_mut().zip(&delta) {
                    *speed = ref_speed * d / max;
                }
            }
            (r.robot_ref, r.speeds)
        };
        self.on(|d| {
            let p = view(d.as_position_control(), "IPositionControl")?;
            p.set_ref_speed_group(&LEGS, &speeds)?;
            p.position_move_group(&LEGS, &targets)
        })
    }

    fn send_direct(&self) -> DevResult<()> {
        let tripod = &self.cfg()?.tripod;
        let targets = {
            let mut r = self.refs.lock();
            r.robot_ref = tripod.inverse(r.user_ref);
            r.robot_ref
        };
        self.on(|d| {
            view(d.as_position_direct(), "IPositionDirect")?.set_positions_group(&LEGS, &targets)
        })
    }

    /// Takes the current pose as the position references (C++ `refreshPositionTargets`,
    /// before a change to position control).
    fn refresh_position_targets(&self) -> DevResult<()> {
        let (x, _) = self.legs()?;
        let user = self.cfg()?.tripod.forward(x);
        let mut r = self.refs.lock();
        r.robot_ref = x;
        r.user_ref = user;
        Ok(())
    }

    fn user(&self, j: usize, internal: f64) -> DevResult<f64> {
        Ok(internal / self.cfg()?.encoder[j])
    }

    fn internal(&self, j: usize, user: f64) -> DevResult<f64> {
        Ok(user * self.cfg()?.encoder[j])
    }
}

impl DeviceDriver for TripodMotionControl {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        TripodParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = TripodParams::read(config)?;
        let bad = |param: &str, expected: &'static str, got: String| DeviceError::BadParam {
            device: NAME.into(),
            param: param.into(),
            expected,
            got,
        };
        if p.hw_to_user {
            return Err(bad(
                "GENERAL::HW2user",
                "false (the user-to-hardware direction R1 uses)",
                "true".into(),
            ));
        }
        if p.joints > 3 {
            tracing::warn!("{NAME}: Joints {} > 3: only three are used", p.joints);
        }
        let n = usize::try_from(p.joints).unwrap_or(3);
        if p.axis_names.len() != n {
            return Err(bad(
                "AxisNames",
                "one name per joint",
                format!("{:?}", p.axis_names),
            ));
        }
        let encoder: [f64; 3] = match p.encoder.get(..3) {
            Some(e) if p.encoder.len() == n && e.iter().all(|v| *v != 0.0) => [e[0], e[1], e[2]],
            _ => {
                return Err(bad(
                    "GENERAL::Encoder",
                    "one non-zero factor per joint",
                    format!("{:?}", p.encoder),
                ))
            }
        };
        let base: Mat4 = match <[f64; 16]>::try_from(p.base.as_slice()) {
            Ok(v) => [0, 1, 2, 3].map(|i| [v[4 * i], v[4 * i + 1], v[4 * i + 2], v[4 * i + 3]]),
            Err(_) => {
                return Err(bad(
                    "TRIPOD::BASE_TRANSFORMATION",
                    "16 values",
                    format!("{} values", p.base.len()),
                ))
            }
        };
        self.config = Some(Config {
            names: p.axis_names[..3].to_vec(),
            encoder,
            tripod: Tripod {
                radius: p.radius,
                base,
            },
            limits: [
                (p.min_el, p.max_el),
                (-p.max_alpha, p.max_alpha),
                (-p.max_alpha, p.max_alpha),
            ],
            max_velocity: p.max_velocity,
        });
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.board = None;
        Ok(())
    }

    yarp_devices::views!(
        as_multiple_wrapper,
        as_encoders,
        as_position_control,
        as_velocity_control,
        as_control_mode,
        as_axis_info,
        as_control_limits,
        as_interaction_mode,
        as_motor_encoders,
        as_amplifier_control,
        as_motor,
        as_pwm_control,
        as_position_direct,
        as_control_calibration,
        as_remote_variables,
    );
}

impl IMultipleWrapper for TripodMotionControl {
    /// The first device only, whatever its key (as C++).
    fn attach_all(&mut self, devices: &[(String, SharedDevice)]) -> DevResult<()> {
        let (key, board) = devices.first().ok_or(DeviceError::Unsupported(
            "tripodMotionControl attaches one board",
        ))?;
        {
            let mut pd = board.lock();
            let d = pd.device();
            if d.as_position_control().is_none() || d.as_encoders().is_none() {
                return Err(DeviceError::failed(
                    NAME,
                    format!("{key} has no IPositionControl or IEncodersTimed"),
                ));
            }
        }
        self.board = Some(board.clone());
        // C++ waits for the board's first encoders
        let start = Instant::now();
        loop {
            match self.joints_now() {
                Ok(_) => return Ok(()),
                Err(e) if start.elapsed() > FIRST_ENCODERS => {
                    self.board = None;
                    return Err(DeviceError::failed(
                        NAME,
                        format!("{key} gave no encoders within {FIRST_ENCODERS:?}: {e}"),
                    ));
                }
                Err(_) => std::thread::sleep(Duration::from_millis(100)),
            }
        }
    }

    fn detach_all(&mut self) -> DevResult<()> {
        self.board = None;
        Ok(())
    }
}

impl IEncoders for TripodMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.on(|_| Ok(3))
    }
    fn get_encoder(&mut self, j: usize) -> DevResult<f64> {
        Ok(self.get_encoder_timed(j)?.0)
    }
    fn get_encoder_speed(&mut self, j: usize) -> DevResult<f64> {
        let j = self.joint(j)?;
        let raw = self.on(|d| view(d.as_encoders(), "IEncodersTimed")?.get_encoder_speed(j))?;
        self.user(j, raw)
    }
    fn get_encoder_acceleration(&mut self, j: usize) -> DevResult<f64> {
        let j = self.joint(j)?;
        let raw =
            self.on(|d| view(d.as_encoders(), "IEncodersTimed")?.get_encoder_acceleration(j))?;
        self.user(j, raw)
    }
    fn get_encoder_timed(&mut self, j: usize) -> DevResult<(f64, f64)> {
        let j = self.joint(j)?;
        let (q, t) = self.joints_now()?;
        Ok((self.user(j, q[j])?, t))
    }
    fn get_encoders_timed(&mut self) -> DevResult<(Vec<f64>, Vec<f64>)> {
        let (q, t) = self.joints_now()?;
        let q = (0..3)
            .map(|j| self.user(j, q[j]))
            .collect::<DevResult<Vec<_>>>()?;
        Ok((q, vec![t; 3]))
    }
    fn get_encoders(&mut self) -> DevResult<Vec<f64>> {
        Ok(self.get_encoders_timed()?.0)
    }
    fn set_encoder(&mut self, _j: usize, _value: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported("tripodMotionControl: setEncoder"))
    }
    fn reset_encoder(&mut self, _j: usize) -> DevResult<()> {
        Err(DeviceError::Unsupported(
            "tripodMotionControl: resetEncoder",
        ))
    }
}

impl IPositionControl for TripodMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        IEncoders::get_axes(self)
    }
    fn position_move(&mut self, j: usize, target: f64) -> DevResult<()> {
        let j = self.joint(j)?;
        self.refs.lock().user_ref[j] = self.internal(j, target)?;
        self.send_position()
    }
    fn position_moves(&mut self, targets: &[f64]) -> DevResult<()> {
        self.position_move_group(&LEGS, targets)
    }
    fn position_move_group(&mut self, joints: &[usize], targets: &[f64]) -> DevResult<()> {
        if joints.len() != targets.len() || joints.len() > 3 {
            return Err(DeviceError::WrongSize {
                expected: joints.len().min(3),
                got: targets.len(),
            });
        }
        if joints.is_empty() {
            return Ok(());
        }
        for (&j, &t) in joints.iter().zip(targets) {
            let j = self.joint(j)?;
            let v = self.internal(j, t)?;
            self.refs.lock().user_ref[j] = v;
        }
        self.send_position()
    }
    fn relative_move(&mut self, j: usize, delta: f64) -> DevResult<()> {
        let j = self.joint(j)?;
        let d = self.internal(j, delta)?;
        self.refs.lock().user_ref[j] += d;
        self.send_position()
    }
    fn check_motion_done(&mut self, j: usize) -> DevResult<bool> {
        let j = self.joint(j)?;
        self.on(|d| view(d.as_position_control(), "IPositionControl")?.check_motion_done(j))
    }
    fn check_motion_dones(&mut self) -> DevResult<bool> {
        self.on(|d| {
            view(d.as_position_control(), "IPositionControl")?.check_motion_done_group(&LEGS)
        })
    }
    /// Only joint 0's speed is the tripod's (C++: the others are accepted and ignored; a
    /// speed below zero or above `JntVelocityMax` is ignored too).
    fn set_ref_speed(&mut self, j: usize, speed: f64) -> DevResult<()> {
        let j = self.joint(j)?;
        if j != 0 {
            tracing::warn!("{NAME}: the reference speed is joint 0's only");
            return Ok(());
        }
        let raw = self.internal(0, speed)?;
        if raw >= 0.0 && raw <= self.cfg()?.max_velocity {
            self.refs.lock().ref_speed = raw;
        }
        Ok(())
    }
    fn set_ref_speeds(&mut self, speeds: &[f64]) -> DevResult<()> {
        match speeds.first() {
            Some(&s) => self.set_ref_speed(0, s),
            None => Ok(()),
        }
    }
    fn get_ref_speed(&mut self, j: usize) -> DevResult<f64> {
        let j = self.joint(j)?;
        let s = self.refs.lock().ref_speed;
        self.user(j, s)
    }
    fn set_ref_acceleration(&mut self, j: usize, acc: f64) -> DevResult<()> {
        let j = self.joint(j)?;
        self.on(|d| view(d.as_position_control(), "IPositionControl")?.set_ref_acceleration(j, acc))
    }
    fn get_ref_acceleration(&mut self, j: usize) -> DevResult<f64> {
        let j = self.joint(j)?;
        self.on(|d| view(d.as_position_control(), "IPositionControl")?.get_ref_acceleration(j))
    }
    fn stop(&mut self, j: usize) -> DevResult<()> {
        let j = self.joint(j)?;
        self.on(|d| view(d.as_position_control(), "IPositionControl")?.stop(j))
    }
    fn get_target_position(&mut self, j: usize) -> DevResult<f64> {
        let j = self.joint(j)?;
        let v = self.refs.lock().user_ref[j];
        self.user(j, v)
    }
}

impl IPositionDirect for TripodMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        IEncoders::get_axes(self)
    }
    fn set_position(&mut self, j: usize, reference: f64) -> DevResult<()> {
        let j = self.joint(j)?;
        self.refs.lock().user_ref[j] = self.internal(j, reference)?;
        self.send_direct()
    }
    fn set_positions(&mut self, references: &[f64]) -> DevResult<()> {
        if references.len() != 3 {
            return Err(DeviceError::WrongSize {
                expected: 3,
                got: references.len(),
            });
        }
        for (j, &r) in references.iter().enumerate() {
            let v = self.internal(j, r)?;
            self.refs.lock().user_ref[j] = v;
        }
        self.send_direct()
    }
    fn get_ref_position(&mut self, j: usize) -> DevResult<f64> {
        self.get_target_position(j)
    }
}

impl IVelocityControl for TripodMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        IEncoders::get_axes(self)
    }
    fn velocity_move(&mut self, _j: usize, _speed: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported(
            "tripodMotionControl: velocityMove",
        ))
    }
    fn get_ref_velocity(&mut self, _j: usize) -> DevResult<f64> {
        Err(DeviceError::Unsupported(
            "tripodMotionControl: getRefVelocity",
        ))
    }
}

impl IControlMode for TripodMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        IEncoders::get_axes(self)
    }
    fn get_control_mode(&mut self, j: usize) -> DevResult<Vocab32> {
        let j = self.joint(j)?;
        self.on(|d| view(d.as_control_mode(), "IControlMode")?.get_control_mode(j))
    }
    /// A change of mode takes the current pose as the position references first.
    fn set_control_mode(&mut self, j: usize, mode: Vocab32) -> DevResult<()> {
        let j = self.joint(j)?;
        if self.get_control_mode(j)? != mode {
            if mode == CM_POSITION {
                self.refresh_position_targets()?;
            }
            self.on(|d| view(d.as_control_mode(), "IControlMode")?.set_control_mode(j, mode))?;
        }
        Ok(())
    }
    /// C++ compares joint 0's mode only, and sets the three.
    fn set_control_modes(&mut self, modes: &[Vocab32]) -> DevResult<()> {
        let Some(&first) = modes.first() else {
            return Ok(());
        };
        if self.get_control_mode(0)? != first {
            if first == CM_POSITION {
                self.refresh_position_targets()?;
            }
            let modes = modes.to_vec();
            self.on(|d| {
                view(d.as_control_mode(), "IControlMode")?.set_control_modes_group(&LEGS, &modes)
            })?;
        }
        Ok(())
    }
}

impl IInteractionMode for TripodMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        IEncoders::get_axes(self)
    }
    fn get_interaction_mode(&mut self, j: usize) -> DevResult<Vocab32> {
        let j = self.joint(j)?;
        self.on(|d| view(d.as_interaction_mode(), "IInteractionMode")?.get_interaction_mode(j))
    }
    fn set_interaction_mode(&mut self, j: usize, mode: Vocab32) -> DevResult<()> {
        let j = self.joint(j)?;
        self.on(|d| {
            view(d.as_interaction_mode(), "IInteractionMode")?.set_interaction_mode(j, mode)
        })
    }
}

impl IControlLimits for TripodMotionControl {
    fn set_limits(&mut self, _j: usize, _min: f64, _max: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported("tripodMotionControl: setLimits"))
    }
    fn get_limits(&mut self, j: usize) -> DevResult<(f64, f64)> {
        let j = self.joint(j)?;
        let (lo, hi) = self.cfg()?.limits[j];
        let (a, b) = (self.user(j, lo)?, self.user(j, hi)?);
        Ok((a.min(b), a.max(b)))
    }
    fn set_vel_limits(&mut self, _j: usize, _min: f64, _max: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported(
            "tripodMotionControl: setVelLimits",
        ))
    }
    fn get_vel_limits(&mut self, j: usize) -> DevResult<(f64, f64)> {
        let j = self.joint(j)?;
        let v = self.user(j, self.cfg()?.max_velocity)?;
        Ok((0.0f64.min(v), 0.0f64.max(v)))
    }
}

impl IAxisInfo for TripodMotionControl {
    fn get_axis_name(&mut self, j: usize) -> DevResult<String> {
        let j = self.joint(j)?;
        Ok(self.cfg()?.names[j].clone())
    }
    fn get_joint_type(&mut self, j: usize) -> DevResult<Vocab32> {
        Ok(match self.joint(j)? {
            0 => JOINTTYPE_PRISMATIC,
            _ => JOINTTYPE_REVOLUTE,
        })
    }
}

impl IControlCalibration for TripodMotionControl {
    fn calibrate_axis_with_params(
        &mut self,
        j: usize,
        kind: u32,
        p1: f64,
        p2: f64,
        p3: f64,
    ) -> DevResult<()> {
        let j = self.joint(j)?;
        self.on(|d| {
            view(d.as_control_calibration(), "IControlCalibration")?
                .calibrate_axis_with_params(j, kind, p1, p2, p3)
        })
    }
    fn set_calibration_parameters(
        &mut self,
        j: usize,
        params: &CalibrationParameters,
    ) -> DevResult<()> {
        let j = self.joint(j)?;
        self.on(|d| {
            view(d.as_control_calibration(), "IControlCalibration")?
                .set_calibration_parameters(j, params)
        })
    }
    fn calibration_done(&mut self, j: usize) -> DevResult<bool> {
        let j = self.joint(j)?;
        self.on(|d| view(d.as_control_calibration(), "IControlCalibration")?.calibration_done(j))
    }
}

impl IAmplifierControl for TripodMotionControl {
    fn enable_amp(&mut self, _j: usize) -> DevResult<()> {
        Err(DeviceError::Unsupported("tripodMotionControl: enableAmp"))
    }
    fn disable_amp(&mut self, _j: usize) -> DevResult<()> {
        Err(DeviceError::Unsupported("tripodMotionControl: disableAmp"))
    }
    fn get_amp_statuses(&mut self) -> DevResult<Vec<i32>> {
        Err(DeviceError::Unsupported(
            "tripodMotionControl: getAmpStatus",
        ))
    }
    fn get_current(&mut self, j: usize) -> DevResult<f64> {
        self.joint(j)?;
        Ok(f64::NAN)
    }
    fn get_max_current(&mut self, _j: usize) -> DevResult<f64> {
        Err(DeviceError::Unsupported(
            "tripodMotionControl: getMaxCurrent",
        ))
    }
    fn get_pwm_limit(&mut self, j: usize) -> DevResult<f64> {
        let j = self.joint(j)?;
        self.on(|d| view(d.as_amplifier_control(), "IAmplifierControl")?.get_pwm_limit(j))
    }
    fn set_pwm_limit(&mut self, j: usize, v: f64) -> DevResult<()> {
        let j = self.joint(j)?;
        self.on(|d| view(d.as_amplifier_control(), "IAmplifierControl")?.set_pwm_limit(j, v))
    }
}

impl IMotorEncoders for TripodMotionControl {
    fn get_num_of_motor_encoders(&mut self) -> DevResult<usize> {
        self.on(|_| Ok(3))
    }
    fn get_motor_encoder(&mut self, m: usize) -> DevResult<f64> {
        let m = self.joint(m)?;
        self.on(|d| view(d.as_motor_encoders(), "IMotorEncoders")?.get_motor_encoder(m))
    }
}

impl IMotor for TripodMotionControl {
    fn get_number_of_motors(&mut self) -> DevResult<usize> {
        Ok(3)
    }
    fn get_temperature(&mut self, m: usize) -> DevResult<f64> {
        self.joint(m)?;
        Ok(f64::NAN)
    }
}

impl IPwmControl for TripodMotionControl {
    fn get_ref_duty_cycle(&mut self, j: usize) -> DevResult<f64> {
        self.joint(j)?;
        Ok(f64::NAN)
    }
    fn get_duty_cycle(&mut self, m: usize) -> DevResult<f64> {
        self.joint(m)?;
        Ok(f64::NAN)
    }
}

impl IRemoteVariables for TripodMotionControl {
    fn get_remote_variable(&mut self, _key: &str) -> DevResult<Bottle> {
        Err(DeviceError::Unsupported(
            "tripodMotionControl: remote variables",
        ))
    }
    fn set_remote_variable(&mut self, _key: &str, _value: &Bottle) -> DevResult<()> {
        Err(DeviceError::Unsupported(
            "tripodMotionControl: remote variables",
        ))
    }
    fn get_remote_variables_list(&mut self) -> DevResult<Bottle> {
        Ok(Bottle::new())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tripod(radius: f64) -> Tripod {
        Tripod {
            radius,
            base: IDENTITY,
        }
    }

    #[test]
    fn inverse_kinematics_as_cpps() {
        // worked out with C++'s formulas
        let l = tripod(0.09).inverse([0.05, 5.0, 3.0]);
        for (got, want) in l.iter().zip([0.042116318, 0.058028279, 0.049858715]) {
            assert!((got - want).abs() < 1e-8, "{l:?}");
        }
        let l = tripod(0.018).inverse([0.06, -10.0, 7.0]);
        for (got, want) in l.iter().zip([0.063187162, 0.060304603, 0.056476559]) {
            assert!((got - want).abs() < 1e-8, "{l:?}");
        }
        assert_eq!(tripod(0.09).inverse([0.0; 3]), [0.0; 3]);
    }

    #[test]
    fn forward_undoes_inverse() {
        for r in [0.09, 0.018] {
            let t = tripod(r);
            for user in [
                [0.05, 5.0, 3.0],
                [0.02, -12.0, 8.0],
                [0.1, 0.0, -20.0],
                [0.0, 0.0, 0.0],
            ] {
                let back = t.forward(t.inverse(user));
                for k in 0..3 {
                    assert!((back[k] - user[k]).abs() < 1e-6, "{r} {user:?} -> {back:?}");
                }
            }
        }
    }
}
