//! The whole robot's `sensor_msgs/JointState`: the latest state of every part (as its own
//! JointState entry converted it), merged into one message (pure; the gateway's
//! `robot` task feeds and publishes it).

use crate::counters::header;
use crate::dynmsg::Value as Ros;
use std::time::{Duration, Instant};

/// A part whose last state is older than this is left out of the merged message (its
/// board stopped streaming): ROS tools then keep its last values rather than see stale
/// ones with a fresh stamp.
pub const MAX_AGE: Duration = Duration::from_secs(1);

/// One part's latest state.
#[derive(Debug, Clone, PartialEq)]
struct Part {
    names: Vec<String>,
    position: Vec<f64>,
    velocity: Vec<f64>,
    effort: Vec<f64>,
    stamp_ns: u64,
    at: Instant,
}

/// The latest state of each part of a robot.
#[derive(Debug, Clone, Default)]
pub struct Merger {
    parts: Vec<Option<Part>>,
    /// A part reported since the last merged message.
    fresh: bool,
}

impl Merger {
    pub fn new(parts: usize) -> Merger {
        Merger {
            parts: vec![None; parts],
            fresh: false,
        }
    }

    /// Records part `i`'s state, a `sensor_msgs/JointState` value received `at`; false
    /// (and nothing recorded) when `msg` does not have that layout.
    pub fn update(&mut self, i: usize, msg: &Ros, at: Instant) -> bool {
        let Some(slot) = self.parts.get_mut(i) else {
            return false;
        };
        match parse(msg, at) {
            Some(p) => {
                *slot = Some(p);
                self.fresh = true;
                true
            }
            None => false,
        }
    }

    /// The merged message, when a part reported since the last one: every part whose state
    /// is at most [`MAX_AGE`] old, in part order, stamped with the newest of their stamps.
    /// `velocity` (`effort`) is filled only when every merged part has it: JointState's
    /// arrays are either empty or one value per name.
    pub fn take(&mut self, now: Instant) -> Option<Ros> {
        if !self.fresh {
            return None;
        }
        self.fresh = false;
        let live: Vec<&Part> = self.live(now).collect();
        if live.is_empty() {
            return None;
        }
        let stamp = live.iter().map(|p| p.stamp_ns).max().unwrap_or(0);
        let floats = |pick: fn(&Part) -> &Vec<f64>| -> Ros {
            if live.iter().all(|p| pick(p).len() == p.names.len()) {
                Ros::List(
                    live.iter()
                        .flat_map(|p| pick(p).iter().map(|v| Ros::F64(*v)))
                        .collect(),
                )
            } else {
                Ros::List(vec![])
            }
        };
        Some(Ros::Struct(vec![
            header(stamp, ""),
            Ros::List(
                live.iter()
                    .flat_map(|p| p.names.iter().map(|n| Ros::Str(n.clone())))
                    .collect(),
            ),
            floats(|p| &p.position),
            floats(|p| &p.velocity),
            floats(|p| &p.effort),
        ]))
    }

    /// The parts (by index) that are not in a merged message made `now`: never reported, or
    /// silent for longer than [`MAX_AGE`].
    pub fn missing(&self, now: Instant) -> Vec<usize> {
        (0..self.parts.len())
            .filter(|&i| !self.parts[i].as_ref().is_some_and(|p| fresh(p, now)))
            .collect()
    }

    /// Every joint name reported so far, in part order.
    pub fn names(&self) -> Vec<String> {
        self.parts
            .iter()
            .flatten()
            .flat_map(|p| p.names.iter().cloned())
            .collect()
    }

    fn live(&self, now: Instant) -> impl Iterator<Item = &Part> {
        self.parts.iter().flatten().filter(move |p| fresh(p, now))
    }
}

fn fresh(p: &Part, now: Instant) -> bool {
    now.saturating_duration_since(p.at) <= MAX_AGE
}

/// A JointState value's parts (layout as in the type catalog).
fn parse(msg: &Ros, at: Instant) -> Option<Part> {
    let [head, Ros::List(names), pos, vel, eff] = msg.fields()? else {
        return None;
    };
    let [Ros::Struct(stamp), _frame] = head.fields()? else {
        return None;
    };
    let stamp_ns = match stamp.as_slice() {
        [Ros::I32(s), Ros::U32(ns)] => (*s as i64 * 1_000_000_000 + *ns as i64).max(0) as u64,
        _ => return None,
    };
    let floats = |v: &Ros| -> Option<Vec<f64>> {
        match v {
            Ros::List(items) => items.iter().map(Ros::as_f64).collect(),
            _ => None,
        }
    };
    let names = names
        .iter()
        .map(|n| match n {
            Ros::Str(s) => Some(s.clone()),
            _ => None,
        })
        .collect::<Option<Vec<_>>>()?;
    let position = floats(pos)?;
    if position.len() != names.len() {
        return None;
    }
    Some(Part {
        names,
        position,
        velocity: floats(vel)?,
        effort: floats(eff)?,
        stamp_ns,
        at,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn js(stamp_ns: u64, names: &[&str], pos: &[f64], vel: &[f64]) -> Ros {
        let f = |v: &[f64]| Ros::List(v.iter().map(|x| Ros::F64(*x)).collect());
        Ros::Struct(vec![
            header(stamp_ns, "base"),
            Ros::List(names.iter().map(|n| Ros::Str(n.to_string())).collect()),
            f(pos),
            f(vel),
            f(&[]),
        ])
    }

    #[test]
    fn parts_merge_in_order_with_the_newest_stamp() {
        let t0 = Instant::now();
        let mut m = Merger::new(2);
        assert_eq!(m.take(t0), None);
        assert!(m.update(1, &js(2_500_000_000, &["c"], &[3.0], &[0.3]), t0));
        assert!(m.update(
            0,
            &js(2_000_000_000, &["a", "b"], &[1.0, 2.0], &[0.1, 0.2]),
            t0
        ));
        let merged = m.take(t0).unwrap();
        assert!(merged.conforms_to("sensor_msgs/msg/JointState"));
        assert_eq!(
            merged,
            Ros::Struct(vec![
                header(2_500_000_000, ""),
                Ros::List(vec![
                    Ros::Str("a".into()),
                    Ros::Str("b".into()),
                    Ros::Str("c".into())
                ]),
                Ros::List(vec![Ros::F64(1.0), Ros::F64(2.0), Ros::F64(3.0)]),
                Ros::List(vec![Ros::F64(0.1), Ros::F64(0.2), Ros::F64(0.3)]),
                Ros::List(vec![]),
            ])
        );
        // Nothing new: nothing to publish.
        assert_eq!(m.take(t0), None);
        assert_eq!(m.names(), ["a", "b", "c"]);
    }

    #[test]
    fn velocity_only_when_every_part_has_it() {
        let t0 = Instant::now();
        let mut m = Merger::new(2);
        m.update(0, &js(1, &["a"], &[1.0], &[0.1]), t0);
        m.update(1, &js(1, &["b"], &[2.0], &[]), t0);
        let f = m.take(t0).unwrap();
        let f = f.fields().unwrap();
        assert_eq!(f[2], Ros::List(vec![Ros::F64(1.0), Ros::F64(2.0)]));
        assert_eq!(f[3], Ros::List(vec![]));
    }

    #[test]
    fn silent_parts_are_left_out() {
        let t0 = Instant::now();
        let mut m = Merger::new(3);
        m.update(0, &js(1, &["a"], &[1.0], &[]), t0);
        let later = t0 + MAX_AGE + Duration::from_millis(1);
        m.update(1, &js(2, &["b"], &[2.0], &[]), later);
        let f = m.take(later).unwrap();
        assert_eq!(
            f.fields().unwrap()[1],
            Ros::List(vec![Ros::Str("b".into())])
        );
        assert_eq!(m.missing(later), [0, 2]);
        assert_eq!(m.missing(t0), [2]);
    }

    #[test]
    fn other_layouts_are_refused() {
        let t0 = Instant::now();
        let mut m = Merger::new(1);
        assert!(!m.update(0, &Ros::Struct(vec![Ros::Str("x".into())]), t0));
        assert!(!m.update(0, &js(1, &["a", "b"], &[1.0], &[]), t0));
        assert!(!m.update(5, &js(1, &["a"], &[1.0], &[]), t0));
        assert_eq!(m.take(t0), None);
    }
}
