//! ROS 2 actions served by the gateway: the goals' bookkeeping as rcl_action keeps it
//! (pure; the bridge in `gateway::actions` drives it).
//!
//! An action server answers three services (`send_goal`, `cancel_goal`, `get_result`
//! under `<action>/_action/`) and publishes two topics (`feedback`, and `status`, the
//! `action_msgs/GoalStatusArray` of every goal it still remembers). Goals are named by a
//! 16-byte UUID chosen by the client. A goal is accepted, executes, and ends succeeded,
//! aborted or canceled; `get_result` is answered when it has ended (at once for a goal
//! that has, and `STATUS_UNKNOWN` for a goal never seen); a cancel request names one goal,
//! every goal, or the goals accepted up to a time, as `action_msgs/CancelGoal` says.

use crate::dynmsg::Value as Ros;
use std::time::{Duration, Instant};

/// A goal's identity (`unique_identifier_msgs/UUID`).
pub type GoalId = [u8; 16];

/// `action_msgs/GoalStatus` constants.
pub mod status {
    pub const UNKNOWN: i8 = 0;
    pub const ACCEPTED: i8 = 1;
    pub const EXECUTING: i8 = 2;
    pub const CANCELING: i8 = 3;
    pub const SUCCEEDED: i8 = 4;
    pub const CANCELED: i8 = 5;
    pub const ABORTED: i8 = 6;
}

/// `action_msgs/CancelGoal` response codes.
pub mod cancel_code {
    pub const NONE: i8 = 0;
    pub const REJECTED: i8 = 1;
    pub const UNKNOWN_GOAL_ID: i8 = 2;
    pub const GOAL_TERMINATED: i8 = 3;
}

/// How long an ended goal's result is kept for `get_result` (rcl_action's default
/// `result_timeout` is 15 minutes; a bridge keeps less).
pub const RESULT_TIMEOUT: Duration = Duration::from_secs(60);

/// One goal as the server knows it.
#[derive(Debug, Clone)]
pub struct Goal {
    pub id: GoalId,
    /// When it was accepted, in ns since the epoch.
    pub stamp_ns: u64,
    pub status: i8,
    /// The result once ended.
    pub result: Option<Ros>,
    ended: Option<Instant>,
}

impl Goal {
    pub fn is_terminal(&self) -> bool {
        matches!(
            self.status,
            status::SUCCEEDED | status::CANCELED | status::ABORTED
        )
    }
}

/// The goals of one action server.
#[derive(Debug, Default)]
pub struct Goals {
    goals: Vec<Goal>,
}

impl Goals {
    /// Accepts goal `id` (a repeated id is refused: false).
    pub fn accept(&mut self, id: GoalId, stamp_ns: u64) -> bool {
        self.expire();
        if self.get(&id).is_some() {
            return false;
        }
        self.goals.push(Goal {
            id,
            stamp_ns,
            status: status::ACCEPTED,
            result: None,
            ended: None,
        });
        true
    }

    pub fn get(&self, id: &GoalId) -> Option<&Goal> {
        self.goals.iter().find(|g| &g.id == id)
    }

    /// Moves a goal that has not ended to `to` (EXECUTING or CANCELING).
    pub fn set_status(&mut self, id: &GoalId, to: i8) {
        if let Some(g) = self.goals.iter_mut().find(|g| &g.id == id) {
            if !g.is_terminal() {
                g.status = to;
            }
        }
    }

    /// Ends a goal: SUCCEEDED, or ABORTED; a goal being canceled ends CANCELED whatever
    /// its execution said.
    pub fn finish(&mut self, id: &GoalId, succeeded: bool, result: Ros) {
        if let Some(g) = self.goals.iter_mut().find(|g| &g.id == id) {
            if g.is_terminal() {
                return;
            }
            g.status = match (g.status, succeeded) {
                (status::CANCELING, _) => status::CANCELED,
                (_, true) => status::SUCCEEDED,
                (_, false) => status::ABORTED,
            };
            g.result = Some(result);
            g.ended = Some(Instant::now());
        }
    }

    /// The goals a cancel request names (`goal_id`, `stamp_ns` of its `goal_info`), as
    /// CancelGoal defines it: a zero id and zero stamp name every goal; a zero id and a
    /// stamp, every goal accepted at or before it; an id, that goal (and, with a stamp,
    /// also those accepted at or before it). Returns the response code and the goals now
    /// canceling (those not ended), which are moved to CANCELING.
    pub fn cancel(&mut self, id: &GoalId, stamp_ns: u64) -> (i8, Vec<(GoalId, u64)>) {
        let zero_id = id.iter().all(|b| *b == 0);
        if !zero_id && self.get(id).is_none() {
            return (cancel_code::UNKNOWN_GOAL_ID, Vec::new());
        }
        let named: Vec<usize> = (0..self.goals.len())
            .filter(|&i| {
                let g = &self.goals[i];
                (zero_id && stamp_ns == 0)
                    || (!zero_id && &g.id == id)
                    || (stamp_ns != 0 && g.stamp_ns <= stamp_ns)
            })
            .collect();
        let mut canceling = Vec::new();
        for i in &named {
            let g = &mut self.goals[*i];
            if !g.is_terminal() {
                g.status = status::CANCELING;
                canceling.push((g.id, g.stamp_ns));
            }
        }
        if canceling.is_empty() && !named.is_empty() {
            return (cancel_code::GOAL_TERMINATED, canceling);
        }
        (cancel_code::NONE, canceling)
    }

    /// The goals executing (or being canceled): those feedback is for.
    pub fn executing(&self) -> Vec<GoalId> {
        self.goals
            .iter()
            .filter(|g| matches!(g.status, status::EXECUTING | status::CANCELING))
            .map(|g| g.id)
            .collect()
    }

    /// `action_msgs/GoalStatusArray` of the goals remembered.
    pub fn status_array(&self) -> Ros {
        Ros::Struct(vec![Ros::List(
            self.goals
                .iter()
                .map(|g| Ros::Struct(vec![goal_info(&g.id, g.stamp_ns), Ros::I8(g.status)]))
                .collect(),
        )])
    }

    /// Forgets goals that ended more than [`RESULT_TIMEOUT`] ago.
    pub fn expire(&mut self) {
        self.goals
            .retain(|g| g.ended.is_none_or(|t| t.elapsed() < RESULT_TIMEOUT));
    }
}

/// `unique_identifier_msgs/UUID` of `id`.
pub fn uuid(id: &GoalId) -> Ros {
    Ros::Struct(vec![Ros::Array(id.iter().map(|b| Ros::U8(*b)).collect())])
}

/// The id of a `unique_identifier_msgs/UUID` value.
pub fn goal_id(v: &Ros) -> Option<GoalId> {
    let [Ros::Array(bytes)] = v.fields()? else {
        return None;
    };
    let mut id = [0u8; 16];
    if bytes.len() != 16 {
        return None;
    }
    for (d, b) in id.iter_mut().zip(bytes) {
        let Ros::U8(b) = b else {
            return None;
        };
        *d = *b;
    }
    Some(id)
}

/// The goal's id and the goal of a `_SendGoal_Request` value (`goal_id`, `goal`).
pub fn goal_request(req: Ros) -> Option<(GoalId, Ros)> {
    let Ros::Struct(mut f) = req else {
        return None;
    };
    if f.len() != 2 {
        return None;
    }
    let goal = f.pop()?;
    Some((goal_id(&f[0])?, goal))
}

/// ns since the epoch of a `builtin_interfaces/Time` value (0 if it is not one).
pub fn time_ns(v: &Ros) -> u64 {
    match v.fields() {
        Some([Ros::I32(s), Ros::U32(n)]) if *s >= 0 => *s as u64 * 1_000_000_000 + *n as u64,
        _ => 0,
    }
}

/// `action_msgs/GoalInfo`.
pub fn goal_info(id: &GoalId, stamp_ns: u64) -> Ros {
    Ros::Struct(vec![uuid(id), Ros::time(stamp_ns)])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn id(n: u8) -> GoalId {
        [n; 16]
    }

    #[test]
    fn a_goal_lives_and_ends() {
        let mut g = Goals::default();
        assert!(g.accept(id(1), 10));
        assert!(!g.accept(id(1), 11), "a repeated id");
        g.set_status(&id(1), status::EXECUTING);
        g.finish(&id(1), true, Ros::Struct(vec![]));
        let goal = g.get(&id(1)).unwrap();
        assert_eq!(goal.status, status::SUCCEEDED);
        assert!(goal.is_terminal());
        g.set_status(&id(1), status::EXECUTING);
        assert_eq!(
            g.get(&id(1)).unwrap().status,
            status::SUCCEEDED,
            "ended for good"
        );
        let Ros::Struct(a) = g.status_array() else {
            panic!()
        };
        let Ros::List(list) = &a[0] else { panic!() };
        assert_eq!(list.len(), 1);
    }

    #[test]
    fn cancel_names_goals_as_cancel_goal_defines() {
        let mut g = Goals::default();
        for (n, t) in [(1, 10), (2, 20), (3, 30)] {
            g.accept(id(n), t);
        }
        assert_eq!(g.cancel(&id(9), 0).0, cancel_code::UNKNOWN_GOAL_ID);
        let (code, c) = g.cancel(&[0; 16], 20);
        assert_eq!(code, cancel_code::NONE);
        assert_eq!(c.iter().map(|x| x.0).collect::<Vec<_>>(), [id(1), id(2)]);
        g.finish(&id(1), true, Ros::Struct(vec![]));
        assert_eq!(g.get(&id(1)).unwrap().status, status::CANCELED);
        let (code, c) = g.cancel(&id(1), 0);
        assert_eq!((code, c.len()), (cancel_code::GOAL_TERMINATED, 0));
        let (code, c) = g.cancel(&[0; 16], 0);
        assert_eq!(
            (code, c.len()),
            (cancel_code::NONE, 2),
            "goals 2 (again) and 3"
        );
    }

    #[test]
    fn ids_and_times_round_trip() {
        let mut raw = [0u8; 16];
        raw[3] = 7;
        assert_eq!(goal_id(&uuid(&raw)), Some(raw));
        assert_eq!(time_ns(&Ros::time(12_345_678_901)), 12_345_678_901);
        assert_eq!(goal_id(&Ros::Struct(vec![])), None);
        let goal = Ros::Struct(vec![Ros::I32(5)]);
        assert_eq!(
            goal_request(Ros::Struct(vec![uuid(&raw), goal.clone()])),
            Some((raw, goal))
        );
        assert_eq!(goal_request(Ros::Struct(vec![uuid(&raw)])), None);
    }
}
