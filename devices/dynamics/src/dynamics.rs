//! Inverse dynamics (the recursive Newton-Euler algorithm's backward pass,
//! iDynTree's `RNEADynamicPhase`) and the quantities derived from it.

use nalgebra::{DVector, Vector3};

use crate::error::Result;
use crate::kinematics::{joint_step, kinematics, BaseMotion, JointState, LinkStates, Traversal};
use crate::model::{FrameRef, Model};
use crate::spatial::{cross_force, wrench_to, Wrench};

/// The outcome of the backward pass.
#[derive(Debug, Clone)]
pub struct InverseDynamics {
    /// One per degree of freedom.
    pub torques: DVector<f64>,
    /// For every link but the base: the wrench its traversal parent exerts
    /// on it through their joint, in the link's frame. For the base: the
    /// wrench the world must exert on it.
    pub joint_wrenches: Vec<Wrench>,
}

/// Each link's net wrench (`I a + v ×* I v`), in its frame.
pub fn net_wrenches(model: &Model, states: &LinkStates) -> Vec<Wrench> {
    model
        .links
        .iter()
        .enumerate()
        .map(|(l, link)| {
            let i = link.inertia.matrix();
            i * states.acc[l] + cross_force(&states.vel[l], &(i * states.vel[l]))
        })
        .collect()
}

/// The backward pass: joint torques and joint wrenches for the given link
/// states and external wrenches (one per link, in its frame).
pub fn inverse_dynamics(
    model: &Model,
    traversal: &Traversal,
    q: &DVector<f64>,
    states: &LinkStates,
    external: &[Wrench],
) -> InverseDynamics {
    let net = net_wrenches(model, states);
    let mut wrench: Vec<Wrench> = net.iter().zip(external).map(|(n, e)| n - e).collect();
    let mut torques = DVector::zeros(model.dof_count());
    for &link in traversal.order.iter().rev() {
        let Some((parent, joint)) = traversal.parent[link] else {
            continue;
        };
        let (p_h_c, s) = joint_step(model, joint, link, q);
        if let Some(d) = model.joints[joint].dof {
            torques[d] = s.dot(&wrench[link]);
        }
        let to_parent = wrench_to(&p_h_c, &wrench[link]);
        wrench[parent] += to_parent;
    }
    InverseDynamics {
        torques,
        joint_wrenches: wrench,
    }
}

/// The torques that hold the robot still at `q`, its base fixed at `base`
/// with gravity `gravity` expressed in that frame.
pub fn gravity_torques(
    model: &Model,
    base: FrameRef,
    q: &[f64],
    gravity: Vector3<f64>,
) -> Result<DVector<f64>> {
    let traversal = Traversal::new(model, base.link);
    let joints = JointState::at_rest(q);
    let states = kinematics(
        model,
        &traversal,
        &joints,
        &BaseMotion::Fixed {
            frame: base,
            gravity,
        },
    )?;
    let none = vec![Wrench::zeros(); model.links.len()];
    Ok(inverse_dynamics(model, &traversal, &joints.q, &states, &none).torques)
}
