//! Forward kinematics over a traversal of the model from a chosen base link:
//! every link's pose relative to the base, its twist and its proper
//! acceleration (gravity included), body-fixed, as iDynTree's
//! `ForwardVelAccKinematics`.

use nalgebra::{DVector, Vector3};

use crate::error::{DynError, Result};
use crate::model::{FrameRef, JointIndex, JointKind, LinkIndex, Model};
use crate::spatial::{cross_motion, motion_to, six, Iso, Motion};

/// The order in which the links are visited from a base link, with the joint
/// each was reached through.
#[derive(Debug, Clone)]
pub struct Traversal {
    pub base: LinkIndex,
    /// Parents before children.
    pub order: Vec<LinkIndex>,
    /// For each link, the link it was reached from and the joint between.
    pub parent: Vec<Option<(LinkIndex, JointIndex)>>,
}

impl Traversal {
    /// A breadth-first visit of the whole model from `base`.
    pub fn new(model: &Model, base: LinkIndex) -> Traversal {
        Self::filtered(model, base, |_| true)
    }

    /// A visit from `base` crossing only the joints `cross` accepts (a
    /// submodel when the F/T sensors' joints are refused).
    pub fn filtered(
        model: &Model,
        base: LinkIndex,
        cross: impl Fn(JointIndex) -> bool,
    ) -> Traversal {
        let mut parent = vec![None; model.links.len()];
        let mut seen = vec![false; model.links.len()];
        let mut order = vec![base];
        seen[base] = true;
        let mut next = 0;
        while next < order.len() {
            let link = order[next];
            next += 1;
            for (joint, other) in model.neighbours(link) {
                if !seen[other] && cross(joint) {
                    seen[other] = true;
                    parent[other] = Some((link, joint));
                    order.push(other);
                }
            }
        }
        Traversal {
            base,
            order,
            parent,
        }
    }

    pub fn contains(&self, link: LinkIndex) -> bool {
        link == self.base || self.parent[link].is_some()
    }
}

/// Joint positions, velocities and accelerations, one per degree of freedom.
#[derive(Debug, Clone)]
pub struct JointState {
    pub q: DVector<f64>,
    pub dq: DVector<f64>,
    pub ddq: DVector<f64>,
}

impl JointState {
    pub fn zeros(n: usize) -> JointState {
        JointState {
            q: DVector::zeros(n),
            dq: DVector::zeros(n),
            ddq: DVector::zeros(n),
        }
    }

    /// At rest at `q`.
    pub fn at_rest(q: &[f64]) -> JointState {
        let n = q.len();
        JointState {
            q: DVector::from_column_slice(q),
            dq: DVector::zeros(n),
            ddq: DVector::zeros(n),
        }
    }

    fn check(&self, model: &Model) -> Result<()> {
        for (what, v) in [
            ("joint positions", &self.q),
            ("joint velocities", &self.dq),
            ("joint accelerations", &self.ddq),
        ] {
            if v.len() != model.dof_count() {
                return Err(DynError::Size {
                    what,
                    expected: model.dof_count(),
                    got: v.len(),
                });
            }
        }
        Ok(())
    }
}

/// How the base moves.
#[derive(Debug, Clone, Copy)]
pub enum BaseMotion {
    /// A frame fixed in the world, with gravity expressed in that frame
    /// (`updateKinematicsFromFixedBase`).
    Fixed {
        frame: FrameRef,
        gravity: Vector3<f64>,
    },
    /// A frame measured by an IMU: its proper linear acceleration (what an
    /// accelerometer there reads), angular velocity and angular acceleration,
    /// all in that frame (`updateKinematicsFromFloatingBase`, base linear
    /// velocity zero).
    Floating {
        frame: FrameRef,
        proper_acc: Vector3<f64>,
        ang_vel: Vector3<f64>,
        ang_acc: Vector3<f64>,
    },
}

impl BaseMotion {
    pub fn frame(&self) -> FrameRef {
        match *self {
            BaseMotion::Fixed { frame, .. } | BaseMotion::Floating { frame, .. } => frame,
        }
    }
}

/// Every link's state, indexed by link.
#[derive(Debug, Clone)]
pub struct LinkStates {
    /// `base_H_link`, the base being the traversal's base link.
    pub base_h_link: Vec<Iso>,
    /// Body-fixed twist.
    pub vel: Vec<Motion>,
    /// Body-fixed proper acceleration (gravity's opposite included).
    pub acc: Vec<Motion>,
}

impl LinkStates {
    /// `a_H_b` between two links.
    pub fn relative(&self, a: LinkIndex, b: LinkIndex) -> Iso {
        self.base_h_link[a].inverse() * self.base_h_link[b]
    }
}

/// A joint's relation between a traversal parent `p` and child `c`:
/// `p_H_c` and the motion subspace in `c`'s frame.
pub(crate) fn joint_step(
    model: &Model,
    joint: JointIndex,
    child: LinkIndex,
    q: &DVector<f64>,
) -> (Iso, Motion) {
    let j = &model.joints[joint];
    let pos = j.dof.map_or(j.held_at, |d| q[d]);
    let axis = j.axis.into_inner();
    let s_urdf = match j.kind {
        JointKind::Fixed => Motion::zeros(),
        JointKind::Revolute => six(Vector3::zeros(), axis),
        JointKind::Prismatic => six(axis, Vector3::zeros()),
    };
    let pu_h_cu = j.transform(pos);
    if j.child == child {
        (pu_h_cu, s_urdf)
    } else {
        // Reached against the URDF's direction: the child of the traversal is
        // the URDF parent, and the joint moves it the opposite way.
        (pu_h_cu.inverse(), -motion_to(&pu_h_cu, &s_urdf))
    }
}

/// Propagates positions, velocities and accelerations from the base.
pub fn kinematics(
    model: &Model,
    traversal: &Traversal,
    joints: &JointState,
    base: &BaseMotion,
) -> Result<LinkStates> {
    joints.check(model)?;
    let n = model.links.len();
    let mut states = LinkStates {
        base_h_link: vec![Iso::identity(); n],
        vel: vec![Motion::zeros(); n],
        acc: vec![Motion::zeros(); n],
    };
    let frame = base.frame();
    if frame.link != traversal.base {
        return Err(DynError::Estimation(format!(
            "the base frame is on link '{}', the traversal starts at '{}'",
            model.links[frame.link].name, model.links[traversal.base].name
        )));
    }
    // The base frame's twist and acceleration, then moved to its link (rigidly
    // attached frames share one spatial acceleration up to the transform).
    let (v_frame, a_frame) = match *base {
        BaseMotion::Fixed { gravity, .. } => (Motion::zeros(), six(-gravity, Vector3::zeros())),
        BaseMotion::Floating {
            proper_acc,
            ang_vel,
            ang_acc,
            ..
        } => (six(Vector3::zeros(), ang_vel), six(proper_acc, ang_acc)),
    };
    let b = traversal.base;
    states.vel[b] = motion_to(&frame.link_h_frame, &v_frame);
    states.acc[b] = motion_to(&frame.link_h_frame, &a_frame);
    for &link in &traversal.order[1..] {
        let Some((parent, joint)) = traversal.parent[link] else {
            continue;
        };
        let (p_h_c, s) = joint_step(model, joint, link, &joints.q);
        let dof = model.joints[joint].dof;
        let (dq, ddq) = dof.map_or((0.0, 0.0), |d| (joints.dq[d], joints.ddq[d]));
        let c_h_p = p_h_c.inverse();
        states.base_h_link[link] = states.base_h_link[parent] * p_h_c;
        let v = motion_to(&c_h_p, &states.vel[parent]) + s * dq;
        states.acc[link] =
            motion_to(&c_h_p, &states.acc[parent]) + s * ddq + cross_motion(&v, &(s * dq));
        states.vel[link] = v;
    }
    Ok(states)
}
