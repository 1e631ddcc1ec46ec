//! ROS joint commands -> control-board targets (pure; no I/O).
//!
//! `sensor_msgs/JointState`, `std_msgs/Float64MultiArray` and `trajectory_msgs/JointTrajectory`
//! become [`Target`]s: which axes, and values in YARP units. ROS uses SI units (radians,
//! rad/s, meters); YARP control boards use degrees for revolute joints and meters for
//! prismatic ones, so only revolute values are converted.
//!
//! Joints are matched by name whenever the message names them (in any order, any subset);
//! an unnamed message lists values in the order of the mapping's `joints` (all axes by
//! default).

use crate::dynmsg::Value as Ros;
use std::time::Duration;

/// What the commands drive: position (IPositionControl), position-direct (streamed
/// setpoints) or velocity (IVelocityControl).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    Position,
    PositionDirect,
    Velocity,
}

/// What the gateway knows of the board: axis names and which axes are prismatic.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BoardInfo {
    pub names: Vec<String>,
    pub prismatic: Vec<bool>,
}

impl BoardInfo {
    /// A ROS value (rad, rad/s, m, m/s) in YARP units for axis `j`.
    pub fn to_yarp_units(&self, j: usize, si: f64) -> f64 {
        if self.prismatic.get(j).copied().unwrap_or(false) {
            si
        } else {
            si.to_degrees()
        }
    }

    /// A YARP value (degrees, meters, ...) of axis `j` in ROS units.
    pub fn to_si(&self, j: usize, yarp: f64) -> f64 {
        if self.prismatic.get(j).copied().unwrap_or(false) {
            yarp
        } else {
            yarp.to_radians()
        }
    }

    /// The axis called `name`.
    fn axis(&self, name: &str) -> Result<usize, CommandError> {
        self.names
            .iter()
            .position(|n| n == name)
            .ok_or_else(|| CommandError::UnknownJoint(name.to_string()))
    }

    /// Axes for `names` (the mapping's `joints`); empty means every axis in order.
    pub fn select(&self, names: &[String]) -> Result<Vec<usize>, CommandError> {
        if names.is_empty() {
            return Ok((0..self.names.len()).collect());
        }
        names.iter().map(|n| self.axis(n)).collect()
    }
}

/// Setpoints for some axes, in YARP units.
#[derive(Debug, Clone, PartialEq)]
pub struct Target {
    pub joints: Vec<usize>,
    pub values: Vec<f64>,
}

/// One point of a trajectory: where the axes must be `at` after the trajectory starts.
#[derive(Debug, Clone, PartialEq)]
pub struct TrajectoryPoint {
    pub at: Duration,
    pub target: Target,
}

/// A command decoded from one ROS message.
#[derive(Debug, Clone, PartialEq)]
pub enum Command {
    /// Apply at once.
    Set(Target),
    /// Follow point by point (replaces any trajectory still running).
    Trajectory(Vec<TrajectoryPoint>),
}

/// Why a ROS message is not a valid command for the board (counted as a drop).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CommandError {
    #[error("the board has no joint named `{0}`")]
    UnknownJoint(String),
    #[error("{names} joint names but {values} values")]
    Mismatch { names: usize, values: usize },
    #[error("{got} values for {want} commanded joints")]
    Count { want: usize, got: usize },
    #[error("joint `{0}` appears twice")]
    Duplicate(String),
    #[error("value {0} is not finite")]
    NotFinite(f64),
    #[error("trajectory point {0}: time_from_start is negative or earlier than the point before")]
    Time(usize),
    #[error("the message does not have the layout of {0}")]
    Layout(&'static str),
    #[error("{0} cannot command {1:?} mode")]
    Unsupported(&'static str, Mode),
}

fn floats(v: &Ros, what: &'static str) -> Result<Vec<f64>, CommandError> {
    v.as_f64s().ok_or(CommandError::Layout(what))
}

fn strings(v: &Ros, what: &'static str) -> Result<Vec<String>, CommandError> {
    v.as_strings().ok_or(CommandError::Layout(what))
}

/// Pairs names (or, without names, the default axes) with SI values -> a [`Target`].
fn target(
    info: &BoardInfo,
    default_axes: &[usize],
    names: &[String],
    si: &[f64],
) -> Result<Target, CommandError> {
    let joints = if names.is_empty() {
        if si.len() != default_axes.len() {
            return Err(CommandError::Count {
                want: default_axes.len(),
                got: si.len(),
            });
        }
        default_axes.to_vec()
    } else {
        if names.len() != si.len() {
            return Err(CommandError::Mismatch {
                names: names.len(),
                values: si.len(),
            });
        }
        let mut joints = Vec::with_capacity(names.len());
        for n in names {
            let j = info.axis(n)?;
            if joints.contains(&j) {
                return Err(CommandError::Duplicate(n.clone()));
            }
            joints.push(j);
        }
        joints
    };
    let values = joints
        .iter()
        .zip(si)
        .map(|(&j, &x)| {
            if x.is_finite() {
                Ok(info.to_yarp_units(j, x))
            } else {
                Err(CommandError::NotFinite(x))
            }
        })
        .collect::<Result<Vec<f64>, _>>()?;
    Ok(Target { joints, values })
}

/// Decodes one ROS message of `ros_type` into a command.
///
/// `default_axes` are the axes an unnamed message addresses, in order. JointState takes
/// `position` (position modes) or `velocity` (velocity mode); trajectories are position
/// or position-direct only.
pub fn decode(
    ros_type: &str,
    m: &Ros,
    mode: Mode,
    info: &BoardInfo,
    default_axes: &[usize],
) -> Result<Command, CommandError> {
    let f = m.fields().ok_or(CommandError::Layout("a message"))?;
    match ros_type {
        "std_msgs/msg/Float64MultiArray" => {
            const T: &str = "std_msgs/msg/Float64MultiArray";
            let data = floats(f.get(1).ok_or(CommandError::Layout(T))?, T)?;
            target(info, default_axes, &[], &data).map(Command::Set)
        }
        "sensor_msgs/msg/JointState" => {
            const T: &str = "sensor_msgs/msg/JointState";
            let names = strings(f.get(1).ok_or(CommandError::Layout(T))?, T)?;
            let field = if mode == Mode::Velocity { 3 } else { 2 };
            let values = floats(f.get(field).ok_or(CommandError::Layout(T))?, T)?;
            target(info, default_axes, &names, &values).map(Command::Set)
        }
        "trajectory_msgs/msg/JointTrajectory" => {
            const T: &str = "trajectory_msgs/msg/JointTrajectory";
            if mode == Mode::Velocity {
                return Err(CommandError::Unsupported(T, mode));
            }
            let names = strings(f.get(1).ok_or(CommandError::Layout(T))?, T)?;
            let Some(Ros::List(points)) = f.get(2) else {
                return Err(CommandError::Layout(T));
            };
            let mut out: Vec<TrajectoryPoint> = Vec::with_capacity(points.len());
            for (i, p) in points.iter().enumerate() {
                let pf = p.fields().ok_or(CommandError::Layout(T))?;
                let positions = floats(pf.first().ok_or(CommandError::Layout(T))?, T)?;
                let at = match pf.get(4).and_then(Ros::as_duration) {
                    Some(Ok(d)) => d,
                    Some(Err(_)) => return Err(CommandError::Time(i)),
                    None => return Err(CommandError::Layout(T)),
                };
                if out.last().is_some_and(|prev| prev.at > at) {
                    return Err(CommandError::Time(i));
                }
                let target = target(info, default_axes, &names, &positions)?;
                out.push(TrajectoryPoint { at, target });
            }
            Ok(Command::Trajectory(out))
        }
        _ => Err(CommandError::Layout("a joint command type")),
    }
}

/// Reference speeds (YARP units per second) that bring each axis from `from` to
/// `to.values` in `dt`; `None` for an axis that need not move. With no time left the
/// move is as fast as the board allows (speed `None` keeps the board's own).
pub fn segment_speeds(from: &[f64], to: &Target, dt: Duration) -> Vec<Option<f64>> {
    let starts = to
        .joints
        .iter()
        .zip(&to.values)
        .map(|(&j, &x)| from.get(j).copied().unwrap_or(x));
    speeds(starts, &to.values, dt)
}

/// The speed that takes each of `from` to its value in `to` in `dt` (`None`: no move, or
/// no time).
pub fn speeds(from: impl IntoIterator<Item = f64>, to: &[f64], dt: Duration) -> Vec<Option<f64>> {
    from.into_iter()
        .zip(to)
        .map(|(x, &y)| {
            let d = (y - x).abs();
            (d > 0.0 && !dt.is_zero()).then(|| d / dt.as_secs_f64())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn info() -> BoardInfo {
        BoardInfo {
            names: vec!["a".into(), "b".into(), "slide".into()],
            prismatic: vec![false, false, true],
        }
    }

    fn f64s(v: &[f64]) -> Ros {
        Ros::List(v.iter().map(|x| Ros::F64(*x)).collect())
    }

    fn strs(v: &[&str]) -> Ros {
        Ros::List(v.iter().map(|x| Ros::Str(x.to_string())).collect())
    }

    fn joint_state(names: &[&str], pos: &[f64], vel: &[f64]) -> Ros {
        let mut m = Ros::zero("sensor_msgs/msg/JointState").unwrap();
        if let Ros::Struct(f) = &mut m {
            f[1] = strs(names);
            f[2] = f64s(pos);
            f[3] = f64s(vel);
        }
        m
    }

    fn multi(data: &[f64]) -> Ros {
        let mut m = Ros::zero("std_msgs/msg/Float64MultiArray").unwrap();
        if let Ros::Struct(f) = &mut m {
            f[1] = f64s(data);
        }
        m
    }

    fn point(pos: &[f64], sec: i32, nanosec: u32) -> Ros {
        Ros::Struct(vec![
            f64s(pos),
            f64s(&[]),
            f64s(&[]),
            f64s(&[]),
            Ros::Struct(vec![Ros::I32(sec), Ros::U32(nanosec)]),
        ])
    }

    fn trajectory(names: &[&str], points: Vec<Ros>) -> Ros {
        let mut m = Ros::zero("trajectory_msgs/msg/JointTrajectory").unwrap();
        if let Ros::Struct(f) = &mut m {
            f[1] = strs(names);
            f[2] = Ros::List(points);
        }
        m
    }

    const ALL: [usize; 3] = [0, 1, 2];

    #[test]
    fn multi_array_follows_the_axis_order_and_converts_units() {
        let c = decode(
            "std_msgs/msg/Float64MultiArray",
            &multi(&[std::f64::consts::FRAC_PI_2, -1.0, 0.25]),
            Mode::Position,
            &info(),
            &ALL,
        )
        .unwrap();
        let Command::Set(t) = c else { panic!() };
        assert_eq!(t.joints, [0, 1, 2]);
        assert!((t.values[0] - 90.0).abs() < 1e-12);
        assert!((t.values[1] + 1f64.to_degrees()).abs() < 1e-12);
        assert_eq!(t.values[2], 0.25, "prismatic stays in meters");
        let err = decode(
            "std_msgs/msg/Float64MultiArray",
            &multi(&[1.0]),
            Mode::Position,
            &info(),
            &ALL,
        );
        assert_eq!(err, Err(CommandError::Count { want: 3, got: 1 }));
        // a configured subset
        let c = decode(
            "std_msgs/msg/Float64MultiArray",
            &multi(&[0.5]),
            Mode::Velocity,
            &info(),
            &[2],
        )
        .unwrap();
        assert_eq!(
            c,
            Command::Set(Target {
                joints: vec![2],
                values: vec![0.5]
            })
        );
    }

    #[test]
    fn joint_state_matches_names_and_picks_the_field_by_mode() {
        let m = joint_state(&["slide", "a"], &[0.1, 0.0], &[0.2, 1.0]);
        let pos = decode(
            "sensor_msgs/msg/JointState",
            &m,
            Mode::PositionDirect,
            &info(),
            &ALL,
        )
        .unwrap();
        assert_eq!(
            pos,
            Command::Set(Target {
                joints: vec![2, 0],
                values: vec![0.1, 0.0]
            })
        );
        let Command::Set(vel) = decode(
            "sensor_msgs/msg/JointState",
            &m,
            Mode::Velocity,
            &info(),
            &ALL,
        )
        .unwrap() else {
            panic!()
        };
        assert_eq!(vel.values, [0.2, 1f64.to_degrees()]);
        let bad = joint_state(&["elbow"], &[0.0], &[]);
        assert_eq!(
            decode(
                "sensor_msgs/msg/JointState",
                &bad,
                Mode::Position,
                &info(),
                &ALL
            ),
            Err(CommandError::UnknownJoint("elbow".into()))
        );
        let twice = joint_state(&["a", "a"], &[0.0, 1.0], &[]);
        assert!(matches!(
            decode(
                "sensor_msgs/msg/JointState",
                &twice,
                Mode::Position,
                &info(),
                &ALL
            ),
            Err(CommandError::Duplicate(_))
        ));
        let short = joint_state(&["a", "b"], &[0.0], &[]);
        assert!(matches!(
            decode(
                "sensor_msgs/msg/JointState",
                &short,
                Mode::Position,
                &info(),
                &ALL
            ),
            Err(CommandError::Mismatch { .. })
        ));
        let nan = joint_state(&["a"], &[f64::NAN], &[]);
        assert!(matches!(
            decode(
                "sensor_msgs/msg/JointState",
                &nan,
                Mode::Position,
                &info(),
                &ALL
            ),
            Err(CommandError::NotFinite(_))
        ));
    }

    #[test]
    fn trajectories_keep_their_times() {
        let m = trajectory(
            &["b", "a"],
            vec![point(&[0.0, 0.1], 0, 500_000_000), point(&[0.2, 0.3], 1, 0)],
        );
        let Command::Trajectory(p) = decode(
            "trajectory_msgs/msg/JointTrajectory",
            &m,
            Mode::Position,
            &info(),
            &ALL,
        )
        .unwrap() else {
            panic!()
        };
        assert_eq!(p.len(), 2);
        assert_eq!(p[0].at, Duration::from_millis(500));
        assert_eq!(p[1].at, Duration::from_secs(1));
        assert_eq!(p[1].target.joints, [1, 0]);
        assert!((p[1].target.values[1] - 0.3f64.to_degrees()).abs() < 1e-12);
        let backwards = trajectory(&["a"], vec![point(&[0.0], 2, 0), point(&[1.0], 1, 0)]);
        assert_eq!(
            decode(
                "trajectory_msgs/msg/JointTrajectory",
                &backwards,
                Mode::Position,
                &info(),
                &ALL
            ),
            Err(CommandError::Time(1))
        );
        assert!(matches!(
            decode(
                "trajectory_msgs/msg/JointTrajectory",
                &m,
                Mode::Velocity,
                &info(),
                &ALL
            ),
            Err(CommandError::Unsupported(..))
        ));
    }

    #[test]
    fn a_wrong_layout_is_an_error_not_a_panic() {
        for ty in [
            "std_msgs/msg/Float64MultiArray",
            "sensor_msgs/msg/JointState",
            "trajectory_msgs/msg/JointTrajectory",
        ] {
            assert!(decode(ty, &Ros::I32(1), Mode::Position, &info(), &ALL).is_err());
            assert!(decode(ty, &Ros::Struct(vec![]), Mode::Position, &info(), &ALL).is_err());
        }
    }

    #[test]
    fn segment_speeds_reach_the_point_on_time() {
        let t = Target {
            joints: vec![0, 2],
            values: vec![10.0, 0.5],
        };
        let s = segment_speeds(&[0.0, 0.0, 0.5], &t, Duration::from_secs(2));
        assert_eq!(s, [Some(5.0), None]);
        assert_eq!(
            segment_speeds(&[0.0, 0.0, 0.0], &t, Duration::ZERO),
            [None, None]
        );
    }
}
