//! `control_msgs/action/FollowJointTrajectory` goals as ros2_controllers'
//! joint_trajectory_controller runs them (pure; `gateway::follow` drives a board group
//! with it): the goal checked and turned into a plan in YARP units, the desired state at
//! any time, and the path, goal and goal-time tolerances with control_msgs' error codes.
//!
//! As in joint_trajectory_controller, a tolerance of 0 is not checked, a goal's tolerance
//! overrides the controller's default when it is positive, and -1 erases it; the goal must
//! be within its goal tolerance by the trajectory's end plus the goal time tolerance (0: no
//! limit). The controller commands any subset of its joints, named in any order; the others
//! keep still. Unlike joint_trajectory_controller it also refuses a point outside a joint's
//! limits (the board's `IControlLimits`) before moving, with `INVALID_GOAL`.

use crate::dynmsg::Value as Ros;
use crate::joint_command::BoardInfo;
use std::time::Duration;

/// `FollowJointTrajectory_Result` error codes.
pub mod error_code {
    pub const SUCCESSFUL: i32 = 0;
    pub const INVALID_GOAL: i32 = -1;
    pub const INVALID_JOINTS: i32 = -2;
    pub const OLD_HEADER_TIMESTAMP: i32 = -3;
    pub const PATH_TOLERANCE_VIOLATED: i32 = -4;
    pub const GOAL_TOLERANCE_VIOLATED: i32 = -5;
}

/// The strings joint_trajectory_controller ends its goals with.
pub const REACHED: &str = "Goal successfully reached!";
pub const PREEMPTED: &str = "Current goal cancelled due to new incoming action.";
pub const CANCELED: &str = "Goal cancelled by the client.";

/// The controller's default tolerances (SI units: rad or m, rad/s or m/s, s), from the
/// mapping (joint_trajectory_controller's `constraints`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Defaults {
    pub goal_position: f64,
    pub path_position: f64,
    /// Velocity under which a joint counts as stopped at the goal.
    pub stopped_velocity: f64,
    /// 0: no limit.
    pub goal_time: f64,
}

/// One joint's tolerance in YARP units; 0 is not checked.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Tolerance {
    pub position: f64,
    pub velocity: f64,
}

/// A trajectory point, in YARP units, for the goal's joints in the goal's order.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    pub at: Duration,
    pub positions: Vec<f64>,
    pub velocities: Option<Vec<f64>>,
}

/// How a goal ended: control_msgs' error code and string.
#[derive(Debug, Clone, PartialEq)]
pub struct Verdict {
    pub code: i32,
    pub message: String,
}

impl Verdict {
    fn new(code: i32, message: impl Into<String>) -> Verdict {
        Verdict {
            code,
            message: message.into(),
        }
    }

    /// The `FollowJointTrajectory_Result` (`error_code`, `error_string`).
    pub fn result(&self) -> Ros {
        Ros::Struct(vec![Ros::I32(self.code), Ros::Str(self.message.clone())])
    }
}

/// A checked goal.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// The goal's joint names and their axes in the board group, in the goal's order.
    pub names: Vec<String>,
    pub joints: Vec<usize>,
    pub points: Vec<Point>,
    pub path: Vec<Tolerance>,
    pub goal: Vec<Tolerance>,
    /// `None`: no limit.
    pub goal_time: Option<Duration>,
    /// How long after acceptance the trajectory starts (a header stamp in the future).
    pub delay: Duration,
}

/// The desired state of the goal's joints at some time.
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    pub positions: Vec<f64>,
    pub velocities: Vec<f64>,
    /// The point being approached (the feedback's `index`).
    pub index: usize,
}

fn layout() -> Verdict {
    Verdict::new(
        error_code::INVALID_GOAL,
        "the goal does not have the layout of FollowJointTrajectory_Goal",
    )
}

/// Checks `goal` (a `FollowJointTrajectory_Goal`) against the group: `controlled` are the
/// axes the controller may move, `limits` each axis's (min, max) in YARP units, `now_ns`
/// the time of acceptance (for the header stamp).
pub fn plan(
    goal: &Ros,
    info: &BoardInfo,
    controlled: &[usize],
    limits: &[(f64, f64)],
    defaults: &Defaults,
    now_ns: u64,
) -> Result<Plan, Verdict> {
    let f = goal.fields().ok_or_else(layout)?;
    let traj = f.first().and_then(Ros::fields).ok_or_else(layout)?;
    let multi = f.get(1).and_then(Ros::fields).ok_or_else(layout)?;
    if multi
        .get(1)
        .and_then(Ros::as_strings)
        .is_some_and(|n| !n.is_empty())
        || multi
            .get(2)
            .and_then(Ros::as_list)
            .is_some_and(|p| !p.is_empty())
    {
        return Err(Verdict::new(
            error_code::INVALID_JOINTS,
            "multi_dof_trajectory: this controller has no multi-DOF joints",
        ));
    }
    let names = traj.get(1).and_then(Ros::as_strings).ok_or_else(layout)?;
    if names.is_empty() {
        return Err(Verdict::new(
            error_code::INVALID_JOINTS,
            "the trajectory names no joints",
        ));
    }
    let mut joints = Vec::with_capacity(names.len());
    for n in &names {
        let j = info
            .names
            .iter()
            .position(|x| x == n)
            .filter(|j| controlled.contains(j))
            .ok_or_else(|| {
                Verdict::new(
                    error_code::INVALID_JOINTS,
                    format!("incoming joint {n} doesn't match the controller's joints"),
                )
            })?;
        if joints.contains(&j) {
            return Err(Verdict::new(
                error_code::INVALID_JOINTS,
                format!("joint {n} appears twice"),
            ));
        }
        joints.push(j);
    }
    let raw = traj.get(2).and_then(Ros::as_list).ok_or_else(layout)?;
    if raw.is_empty() {
        return Err(Verdict::new(
            error_code::INVALID_GOAL,
            "the trajectory has no points",
        ));
    }
    let mut points: Vec<Point> = Vec::with_capacity(raw.len());
    for (i, p) in raw.iter().enumerate() {
        let pf = p.fields().ok_or_else(layout)?;
        let positions = pf.first().and_then(Ros::as_f64s).ok_or_else(layout)?;
        let velocities = pf.get(1).and_then(Ros::as_f64s).ok_or_else(layout)?;
        let at = match pf.get(4).and_then(Ros::as_duration) {
            Some(Ok(d)) => d,
            Some(Err(_)) => {
                return Err(Verdict::new(
                    error_code::INVALID_GOAL,
                    format!("point {i}: time_from_start is negative"),
                ))
            }
            None => return Err(layout()),
        };
        if positions.len() != names.len() {
            return Err(Verdict::new(
                error_code::INVALID_GOAL,
                format!(
                    "point {i}: {} positions for {} joints",
                    positions.len(),
                    names.len()
                ),
            ));
        }
        if !velocities.is_empty() && velocities.len() != names.len() {
            return Err(Verdict::new(
                error_code::INVALID_GOAL,
                format!(
                    "point {i}: {} velocities for {} joints",
                    velocities.len(),
                    names.len()
                ),
            ));
        }
        if let Some(prev) = points.last() {
            if at <= prev.at {
                return Err(Verdict::new(
                    error_code::INVALID_GOAL,
                    format!(
                        "time between points {} and {i} is not strictly increasing",
                        i - 1
                    ),
                ));
            }
        }
        let mut ys = Vec::with_capacity(names.len());
        for (k, (&j, &x)) in joints.iter().zip(&positions).enumerate() {
            if !x.is_finite() || !velocities.get(k).copied().unwrap_or(0.0).is_finite() {
                return Err(Verdict::new(
                    error_code::INVALID_GOAL,
                    format!(
                        "point {i}: joint {} has a value that is not finite",
                        names[k]
                    ),
                ));
            }
            let y = info.to_yarp_units(j, x);
            if let Some(&(min, max)) = limits.get(j) {
                if min < max && (y < min || y > max) {
                    return Err(Verdict::new(
                        error_code::INVALID_GOAL,
                        format!(
                            "point {i}: joint {} at {x} is outside its limits [{}, {}]",
                            names[k],
                            info.to_si(j, min),
                            info.to_si(j, max)
                        ),
                    ));
                }
            }
            ys.push(y);
        }
        let velocities = (!velocities.is_empty()).then(|| {
            joints
                .iter()
                .zip(&velocities)
                .map(|(&j, &v)| info.to_yarp_units(j, v))
                .collect()
        });
        points.push(Point {
            at,
            positions: ys,
            velocities,
        });
    }
    // The header stamp: zero is "start now"; a stamp in the future delays the start; one
    // so old that the whole trajectory is over is refused.
    let stamp = traj.first().and_then(Ros::fields).and_then(|h| h.first());
    let stamp_ns = stamp.map_or(0, crate::action::time_ns);
    let end = points.last().map(|p| p.at).unwrap_or_default();
    let delay = if stamp_ns == 0 {
        Duration::ZERO
    } else if stamp_ns + (end.as_nanos() as u64) < now_ns {
        return Err(Verdict::new(
            error_code::OLD_HEADER_TIMESTAMP,
            "the trajectory ended before it arrived (header.stamp is too old)",
        ));
    } else {
        Duration::from_nanos(stamp_ns.saturating_sub(now_ns))
    };
    let tolerances = |field: usize, default: Tolerance| -> Result<Vec<Tolerance>, Verdict> {
        let mut out: Vec<Tolerance> = joints
            .iter()
            .map(|&j| Tolerance {
                position: info.to_yarp_units(j, default.position),
                velocity: info.to_yarp_units(j, default.velocity),
            })
            .collect();
        for t in f.get(field).and_then(Ros::as_list).ok_or_else(layout)? {
            let tf = t.fields().ok_or_else(layout)?;
            let (Some(Ros::Str(name)), Some(p), Some(v)) = (
                tf.first(),
                tf.get(1).and_then(Ros::as_f64),
                tf.get(2).and_then(Ros::as_f64),
            ) else {
                return Err(layout());
            };
            let k = names.iter().position(|n| n == name).ok_or_else(|| {
                Verdict::new(
                    error_code::INVALID_JOINTS,
                    format!("a tolerance names joint {name}, which the trajectory does not move"),
                )
            })?;
            let j = joints[k];
            let set = |slot: &mut f64, x: f64| {
                if x > 0.0 {
                    *slot = info.to_yarp_units(j, x);
                } else if x < 0.0 {
                    *slot = 0.0;
                }
            };
            set(&mut out[k].position, p);
            set(&mut out[k].velocity, v);
        }
        Ok(out)
    };
    let path = tolerances(
        2,
        Tolerance {
            position: defaults.path_position,
            velocity: 0.0,
        },
    )?;
    let goal_tol = tolerances(
        4,
        Tolerance {
            position: defaults.goal_position,
            velocity: defaults.stopped_velocity,
        },
    )?;
    let goal_time = match f.get(6).and_then(Ros::as_duration) {
        Some(Ok(d)) if !d.is_zero() => d.as_secs_f64(),
        Some(_) => defaults.goal_time,
        None => return Err(layout()),
    };
    Ok(Plan {
        names,
        joints,
        points,
        path,
        goal: goal_tol,
        goal_time: (goal_time > 0.0).then(|| Duration::from_secs_f64(goal_time)),
        delay,
    })
}

impl Plan {
    /// When the last point is due.
    pub fn end(&self) -> Duration {
        self.points.last().map(|p| p.at).unwrap_or_default()
    }

    /// The desired state `t` after the start, from `start` (the goal's joints' positions at
    /// the start): between two points a cubic when both give velocities, else a line; after
    /// the end, the last point, still.
    pub fn sample(&self, start: &[f64], t: Duration) -> Sample {
        let i = self.points.partition_point(|p| p.at <= t);
        let Some(to) = self.points.get(i) else {
            let last = self.points.last();
            return Sample {
                positions: last.map(|p| p.positions.clone()).unwrap_or_default(),
                velocities: vec![0.0; self.joints.len()],
                index: self.points.len().saturating_sub(1),
            };
        };
        let (t0, q0, v0) = match i.checked_sub(1).map(|k| &self.points[k]) {
            Some(p) => (p.at, p.positions.as_slice(), p.velocities.as_deref()),
            None => (Duration::ZERO, start, Some(&[][..])),
        };
        let h = (to.at - t0).as_secs_f64();
        let s = (t - t0).as_secs_f64();
        let mut positions = Vec::with_capacity(self.joints.len());
        let mut velocities = Vec::with_capacity(self.joints.len());
        for k in 0..self.joints.len() {
            let (a, b) = (q0.get(k).copied().unwrap_or(0.0), to.positions[k]);
            let va = v0.and_then(|v| v.get(k).copied());
            let vb = to.velocities.as_ref().map(|v| v[k]);
            match (va.or((i == 0).then_some(0.0)), vb) {
                (Some(va), Some(vb)) if h > 0.0 => {
                    // Hermite cubic through (a, va) and (b, vb).
                    let c2 = (3.0 * (b - a) / h - 2.0 * va - vb) / h;
                    let c3 = (2.0 * (a - b) / h + va + vb) / (h * h);
                    positions.push(a + va * s + c2 * s * s + c3 * s * s * s);
                    velocities.push(va + 2.0 * c2 * s + 3.0 * c3 * s * s);
                }
                _ if h > 0.0 => {
                    positions.push(a + (b - a) * s / h);
                    velocities.push((b - a) / h);
                }
                _ => {
                    positions.push(b);
                    velocities.push(0.0);
                }
            }
        }
        Sample {
            positions,
            velocities,
            index: i,
        }
    }

    /// Whether the goal has ended `t` after the start, given the desired and actual state:
    /// `Some((true, ..))` reached, `Some((false, ..))` a tolerance violated, `None` not yet.
    pub fn check(
        &self,
        info: &BoardInfo,
        t: Duration,
        desired: &Sample,
        actual: &[f64],
        actual_velocities: Option<&[f64]>,
    ) -> Option<(bool, Verdict)> {
        let off = |k: usize, tol: f64, want: f64, got: f64, what: &str| -> Option<String> {
            let j = self.joints[k];
            (tol > 0.0 && (want - got).abs() > tol).then(|| {
                format!(
                    "joint {} is {} off in {what} (tolerance {})",
                    self.names[k],
                    info.to_si(j, (want - got).abs()),
                    info.to_si(j, tol)
                )
            })
        };
        let end = self.end();
        if t < end {
            for k in 0..self.joints.len() {
                let a = actual.get(k).copied().unwrap_or(f64::NAN);
                if let Some(why) = off(
                    k,
                    self.path[k].position,
                    desired.positions[k],
                    a,
                    "position",
                ) {
                    return Some((
                        false,
                        Verdict::new(
                            error_code::PATH_TOLERANCE_VIOLATED,
                            format!("Aborted due to path tolerance violation: {why}"),
                        ),
                    ));
                }
            }
            return None;
        }
        let target = &self.points[self.points.len() - 1].positions;
        let mut outside = None;
        for (k, &want) in target.iter().enumerate() {
            let a = actual.get(k).copied().unwrap_or(f64::NAN);
            let v = actual_velocities
                .and_then(|v| v.get(k).copied())
                .unwrap_or(0.0);
            let why = off(k, self.goal[k].position, want, a, "position")
                .or_else(|| off(k, self.goal[k].velocity, 0.0, v, "velocity"));
            if why.is_some() {
                outside = why;
                break;
            }
        }
        match (outside, self.goal_time) {
            (None, _) => Some((true, Verdict::new(error_code::SUCCESSFUL, REACHED))),
            (Some(why), Some(gt)) if t > end + gt => Some((
                false,
                Verdict::new(
                    error_code::GOAL_TOLERANCE_VIOLATED,
                    format!(
                        "Aborted due to goal tolerance violation: {why}, {:.3} s after the end \
                         (goal_time_tolerance {:.3} s)",
                        (t - end).as_secs_f64(),
                        gt.as_secs_f64()
                    ),
                ),
            )),
            _ => None,
        }
    }
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

    const DEFAULTS: Defaults = Defaults {
        goal_position: 0.01,
        path_position: 0.0,
        stopped_velocity: 0.0,
        goal_time: 1.0,
    };

    fn time(s: f64) -> Ros {
        let d = Duration::from_secs_f64(s);
        Ros::Struct(vec![
            Ros::I32(d.as_secs() as i32),
            Ros::U32(d.subsec_nanos()),
        ])
    }

    fn f64s(v: &[f64]) -> Ros {
        Ros::List(v.iter().map(|x| Ros::F64(*x)).collect())
    }

    fn point(pos: &[f64], vel: &[f64], at: f64) -> Ros {
        Ros::Struct(vec![f64s(pos), f64s(vel), f64s(&[]), f64s(&[]), time(at)])
    }

    fn tol(name: &str, p: f64) -> Ros {
        Ros::Struct(vec![
            Ros::Str(name.into()),
            Ros::F64(p),
            Ros::F64(0.0),
            Ros::F64(0.0),
        ])
    }

    fn goal(names: &[&str], points: Vec<Ros>, path: Vec<Ros>, goal_tol: Vec<Ros>) -> Ros {
        let mut g = Ros::zero("control_msgs/action/FollowJointTrajectory_Goal").unwrap();
        let Ros::Struct(f) = &mut g else { panic!() };
        let Ros::Struct(t) = &mut f[0] else { panic!() };
        t[1] = Ros::List(names.iter().map(|n| Ros::Str(n.to_string())).collect());
        t[2] = Ros::List(points);
        f[2] = Ros::List(path);
        f[4] = Ros::List(goal_tol);
        g
    }

    const LIMITS: [(f64, f64); 3] = [(-90.0, 90.0), (-10.0, 100.0), (0.0, 0.5)];

    fn plan_of(g: &Ros) -> Result<Plan, Verdict> {
        plan(
            g,
            &info(),
            &[0, 1, 2],
            &LIMITS,
            &DEFAULTS,
            1_000_000_000_000,
        )
    }

    #[test]
    fn a_goal_becomes_a_plan_in_yarp_units_for_any_subset_in_any_order() {
        let g = goal(
            &["slide", "a"],
            vec![
                point(&[0.1, 0.5], &[], 1.0),
                point(&[0.2, -0.5], &[0.0, 0.0], 2.5),
            ],
            vec![tol("a", 0.05)],
            vec![tol("slide", -1.0)],
        );
        let p = plan_of(&g).unwrap();
        assert_eq!(p.joints, [2, 0]);
        assert_eq!(p.points[1].at, Duration::from_millis(2500));
        assert_eq!(p.points[0].positions[0], 0.1, "prismatic stays in meters");
        assert!((p.points[1].positions[1] + 0.5f64.to_degrees()).abs() < 1e-9);
        assert_eq!(p.points[0].velocities, None);
        assert_eq!(p.points[1].velocities, Some(vec![0.0, 0.0]));
        assert!((p.path[1].position - 0.05f64.to_degrees()).abs() < 1e-9);
        assert_eq!(p.path[0].position, 0.0, "default path tolerance: unchecked");
        assert_eq!(p.goal[0].position, 0.0, "-1 erases");
        assert!((p.goal[1].position - 0.01f64.to_degrees()).abs() < 1e-9);
        assert_eq!(p.goal_time, Some(Duration::from_secs(1)));
        assert_eq!(p.delay, Duration::ZERO);
    }

    #[test]
    fn bad_goals_get_control_msgs_error_codes() {
        let code = |g: &Ros| plan_of(g).unwrap_err().code;
        let p = |x: f64| vec![point(&[x], &[], 1.0)];
        assert_eq!(
            code(&goal(&["elbow"], p(0.0), vec![], vec![])),
            error_code::INVALID_JOINTS
        );
        assert_eq!(
            code(&goal(&[], p(0.0), vec![], vec![])),
            error_code::INVALID_JOINTS
        );
        assert_eq!(
            code(&goal(
                &["a", "a"],
                vec![point(&[0.0, 0.0], &[], 1.0)],
                vec![],
                vec![]
            )),
            error_code::INVALID_JOINTS
        );
        assert_eq!(
            code(&goal(&["a"], vec![], vec![], vec![])),
            error_code::INVALID_GOAL
        );
        // b's limits are [-10, 100] degrees: 2 rad is 114.6
        let out = plan_of(&goal(&["b"], p(2.0), vec![], vec![])).unwrap_err();
        assert_eq!(out.code, error_code::INVALID_GOAL);
        assert!(
            out.message.contains("joint b at 2 is outside its limits"),
            "{}",
            out.message
        );
        assert_eq!(
            code(&goal(
                &["a"],
                vec![point(&[0.0], &[], 1.0), point(&[0.1], &[], 1.0)],
                vec![],
                vec![]
            )),
            error_code::INVALID_GOAL
        );
        assert_eq!(
            code(&goal(
                &["a"],
                vec![point(&[0.0, 1.0], &[], 1.0)],
                vec![],
                vec![]
            )),
            error_code::INVALID_GOAL
        );
        assert_eq!(
            code(&goal(&["a"], p(f64::NAN), vec![], vec![])),
            error_code::INVALID_GOAL
        );
        assert_eq!(
            code(&goal(&["a"], p(0.0), vec![tol("b", 0.1)], vec![])),
            error_code::INVALID_JOINTS
        );
        // a joint the controller does not own
        let g = goal(&["slide"], p(0.1), vec![], vec![]);
        let e = plan(&g, &info(), &[0, 1], &LIMITS, &DEFAULTS, 0).unwrap_err();
        assert_eq!(e.code, error_code::INVALID_JOINTS);
        // a header stamp whose trajectory is over
        let mut old = goal(&["a"], p(0.0), vec![], vec![]);
        if let Ros::Struct(f) = &mut old {
            if let Ros::Struct(t) = &mut f[0] {
                if let Ros::Struct(h) = &mut t[0] {
                    h[0] = time(10.0);
                }
            }
        }
        assert_eq!(code(&old), error_code::OLD_HEADER_TIMESTAMP);
        assert!(plan_of(&Ros::I32(3)).is_err());
    }

    #[test]
    fn samples_follow_lines_or_cubics_and_hold_the_end() {
        let g = goal(
            &["a", "b"],
            vec![
                point(&[0.0, 0.0], &[], 1.0),
                point(&[1.0, 0.5], &[0.0, 0.0], 2.0),
            ],
            vec![],
            vec![],
        );
        let p = plan_of(&g).unwrap();
        let start = [10.0, 20.0];
        let s = p.sample(&start, Duration::from_millis(500));
        assert_eq!(s.index, 0);
        assert!((s.positions[0] - 5.0).abs() < 1e-9, "{s:?}");
        assert!((s.velocities[1] + 20.0).abs() < 1e-9, "{s:?}");
        // second segment: no velocities at point 0, so a line
        let s = p.sample(&start, Duration::from_millis(1500));
        assert_eq!(s.index, 1);
        assert!((s.positions[0] - 0.5f64.to_degrees()).abs() < 1e-9, "{s:?}");
        let s = p.sample(&start, Duration::from_secs(3));
        assert_eq!(s.index, 1);
        assert_eq!(s.velocities, [0.0, 0.0]);
        assert!((s.positions[1] - 0.5f64.to_degrees()).abs() < 1e-9);
        // a cubic where both ends have velocities: ends on the point with its velocity
        let g = goal(
            &["a"],
            vec![point(&[0.0], &[0.0], 1.0), point(&[1.0], &[0.5], 2.0)],
            vec![],
            vec![],
        );
        let p = plan_of(&g).unwrap();
        let s = p.sample(&[0.0], Duration::from_nanos(1_999_999_999));
        assert!((s.positions[0] - 1f64.to_degrees()).abs() < 1e-4, "{s:?}");
        assert!(
            (s.velocities[0] - 0.5f64.to_degrees()).abs() < 1e-4,
            "{s:?}"
        );
    }

    #[test]
    fn tolerances_end_the_goal_as_joint_trajectory_controller_does() {
        let g = goal(
            &["a"],
            vec![point(&[1.0], &[], 1.0)],
            vec![tol("a", 0.1)],
            vec![],
        );
        let p = plan_of(&g).unwrap();
        let i = info();
        let at = |t: f64| Duration::from_secs_f64(t);
        let d = p.sample(&[0.0], at(0.5));
        assert_eq!(
            p.check(&i, at(0.5), &d, &[d.positions[0] + 1.0], None),
            None
        );
        let (ok, v) = p
            .check(&i, at(0.5), &d, &[d.positions[0] + 10.0], None)
            .unwrap();
        assert!(!ok);
        assert_eq!(v.code, error_code::PATH_TOLERANCE_VIOLATED);
        let end = p.sample(&[0.0], at(1.0));
        let target = 1f64.to_degrees();
        assert_eq!(p.check(&i, at(1.2), &end, &[target - 2.0], None), None);
        let (ok, v) = p.check(&i, at(1.2), &end, &[target - 0.1], None).unwrap();
        assert!(ok);
        assert_eq!(v, Verdict::new(error_code::SUCCESSFUL, REACHED));
        let (ok, v) = p.check(&i, at(2.01), &end, &[target - 2.0], None).unwrap();
        assert!(!ok);
        assert_eq!(v.code, error_code::GOAL_TOLERANCE_VIOLATED);
        assert_eq!(
            v.result(),
            Ros::Struct(vec![Ros::I32(-5), Ros::Str(v.message.clone())])
        );
    }
}
