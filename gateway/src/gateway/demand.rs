//! Whether a bridge's YARP side is needed right now.
//!
//! A robot publishes dozens of streams; with nobody on the ROS side, reading, converting
//! and publishing them all costs the gateway and the robot's wrappers CPU for nothing.
//! So a stream's YARP source is connected only while some ROS subscriber is matched to a
//! publisher it feeds (its own topic, or a merged `/joint_states` it is part of), and a
//! command board is opened only while a ROS publisher is matched to its command topic.
//! Topics, types and rates seen by ROS do not change: discovery of a new subscriber is
//! followed within [`super::RECONNECT_PERIOD`] by the YARP connection.
//!
//! Transient-local topics are always fed: a late subscriber expects the samples kept.

use crate::dynmsg::Value as Ros;
use parking_lot::Mutex;
use ros2_client::{Node, Publisher};
use std::sync::Arc;

/// The publishers whose matched subscribers want a bridge's messages (shared by clones:
/// a merged topic created later adds its publisher to the demand of each of its parts).
#[derive(Clone, Default)]
pub(super) struct Demand(Arc<Mutex<Wanters>>);

#[derive(Default)]
struct Wanters {
    always: bool,
    publishers: Vec<Arc<Publisher<Ros>>>,
}

impl Demand {
    /// Always wanted (transient-local topics, or a bridge with no ROS publisher of its own).
    pub(super) fn always() -> Demand {
        let d = Demand::default();
        d.set_always();
        d
    }

    /// From now on always wanted.
    pub(super) fn set_always(&self) {
        self.lock().always = true;
    }

    /// Also wanted while `publisher` has a matched subscriber.
    pub(super) fn add(&self, publisher: Arc<Publisher<Ros>>) {
        self.lock().publishers.push(publisher);
    }

    /// Whether the bridge is wanted now; `node` is the node of the publishers.
    pub(super) fn wanted(&self, node: &Node) -> bool {
        let w = self.lock();
        w.always
            || w.publishers
                .iter()
                .any(|p| p.get_subscription_count(node) > 0)
    }

    fn lock(&self) -> parking_lot::MutexGuard<'_, Wanters> {
        self.0.lock()
    }
}

/// A [`Demand`] with the node its publishers belong to: what connection keepers ask.
#[derive(Clone, Default)]
pub(super) struct Gate {
    node: Option<Arc<Node>>,
    demand: Demand,
}

impl Gate {
    /// Always open.
    pub(super) fn always() -> Gate {
        Gate::default()
    }

    pub(super) fn new(node: Arc<Node>, demand: Demand) -> Gate {
        Gate {
            node: Some(node),
            demand,
        }
    }

    pub(super) fn open(&self) -> bool {
        match &self.node {
            Some(node) => self.demand.wanted(node),
            None => true,
        }
    }
}
