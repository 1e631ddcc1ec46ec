//! Estimation of external wrenches and joint torques from F/T sensors, as
//! iDynTree's `ExtWrenchesAndJointTorquesEstimator`.
//!
//! The F/T sensors' joints cut the model into submodels. In each submodel the
//! net wrench its links need for their motion (gravity included) must come
//! from the F/T sensors on its boundary (measured) and from contacts at known
//! frames (unknown): one least-squares problem per submodel gives the contact
//! wrenches. The joint torques then follow from inverse dynamics with those
//! wrenches applied.

use nalgebra::{DMatrix, DVector, Vector3};

use crate::dynamics::{inverse_dynamics, net_wrenches};
use crate::error::{DynError, Result};
use crate::kinematics::{kinematics, BaseMotion, JointState, LinkStates, Traversal};
use crate::model::{FrameRef, LinkIndex, Model};
use crate::solve::col_piv_qr_solve;
use crate::spatial::{six, wrench_matrix, wrench_to, Wrench};

/// The unknowns of a contact (iDynTree's `UnknownWrenchContactType`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactKind {
    /// Six unknowns: force and torque, about the contact frame's origin.
    FullWrench,
    /// Three unknowns: a force through the contact frame's origin.
    PureForce,
    /// One unknown: a force along a direction given in the contact frame.
    PureForceWithKnownDirection(Vector3<f64>),
}

impl ContactKind {
    pub fn unknowns(&self) -> usize {
        match self {
            ContactKind::FullWrench => 6,
            ContactKind::PureForce => 3,
            ContactKind::PureForceWithKnownDirection(_) => 1,
        }
    }
}

/// An unknown contact at a frame of the model.
#[derive(Debug, Clone)]
pub struct Contact {
    pub frame_name: String,
    pub frame: FrameRef,
    pub kind: ContactKind,
}

impl Contact {
    pub fn new(model: &Model, frame_name: &str, kind: ContactKind) -> Result<Contact> {
        Ok(Contact {
            frame_name: frame_name.to_owned(),
            frame: model.frame(frame_name)?,
            kind,
        })
    }
}

/// The model cut at its F/T sensors' joints.
#[derive(Debug, Clone)]
pub struct Submodels {
    /// For every link, the submodel it belongs to.
    pub of_link: Vec<usize>,
    /// Each submodel as a traversal of its own links.
    pub traversals: Vec<Traversal>,
}

impl Submodels {
    pub fn new(model: &Model) -> Submodels {
        let cut: Vec<_> = model.sensors.ft.iter().map(|s| s.joint).collect();
        let mut of_link = vec![usize::MAX; model.links.len()];
        let mut traversals = Vec::new();
        // Start from the URDF root so that submodel 0 holds it, as iDynTree's
        // decomposition (visited from the model's default base) numbers them.
        let starts = std::iter::once(model.root()).chain(0..model.links.len());
        for start in starts {
            if of_link[start] != usize::MAX {
                continue;
            }
            let t = Traversal::filtered(model, start, |j| !cut.contains(&j));
            for &l in &t.order {
                of_link[l] = traversals.len();
            }
            traversals.push(t);
        }
        Submodels {
            of_link,
            traversals,
        }
    }

    pub fn count(&self) -> usize {
        self.traversals.len()
    }

    /// The submodel a frame (a link or an additional frame) belongs to.
    pub fn of_frame(&self, frame: &FrameRef) -> usize {
        self.of_link[frame.link]
    }
}

/// What an estimation yields.
#[derive(Debug, Clone)]
pub struct Estimate {
    /// One per contact, in its frame about its origin.
    pub contact_wrenches: Vec<Wrench>,
    /// The external wrench on every link, in its frame (the sum of its
    /// contacts).
    pub link_wrenches: Vec<Wrench>,
    /// One per degree of freedom.
    pub torques: DVector<f64>,
    /// The link states the estimate was computed on.
    pub states: LinkStates,
}

/// The estimator of a model, with the traversal its kinematics run on.
#[derive(Debug, Clone)]
pub struct Estimator {
    pub model: Model,
    pub submodels: Submodels,
    pub traversal: Traversal,
}

impl Estimator {
    /// An estimator whose kinematics starts from `base_link`.
    pub fn new(model: Model, base_link: &str) -> Result<Estimator> {
        let base = model.frame(base_link)?.link;
        let traversal = Traversal::new(&model, base);
        let submodels = Submodels::new(&model);
        Ok(Estimator {
            model,
            submodels,
            traversal,
        })
    }

    /// The link states, propagated from the base frame's link (the IMU's, or
    /// the fixed frame's) whatever link the dynamics' traversal starts from.
    pub fn kinematics(&self, joints: &JointState, base: &BaseMotion) -> Result<LinkStates> {
        let link = base.frame().link;
        if link == self.traversal.base {
            kinematics(&self.model, &self.traversal, joints, base)
        } else {
            kinematics(
                &self.model,
                &Traversal::new(&self.model, link),
                joints,
                base,
            )
        }
    }

    /// wholebodydynamics' choice of contacts among `frames` (in order): a frame
    /// is taken for its submodel while the submodel's unknowns stay within
    /// six, so with full wrenches the first frame of each submodel. Unknown
    /// frames are skipped (returned second). Every submodel must get one: the
    /// error lists the links of those that do not.
    pub fn choose_contacts(
        &self,
        frames: &[(String, ContactKind)],
    ) -> Result<(Vec<Contact>, Vec<String>)> {
        let mut chosen: Vec<Contact> = Vec::new();
        let mut unknown = Vec::new();
        let mut unknowns = vec![0usize; self.submodels.count()];
        for (name, kind) in frames {
            let Ok(contact) = Contact::new(&self.model, name, *kind) else {
                unknown.push(name.clone());
                continue;
            };
            let sub = self.submodels.of_frame(&contact.frame);
            if unknowns[sub] + kind.unknowns() <= 6 {
                unknowns[sub] += kind.unknowns();
                chosen.push(contact);
            }
        }
        if let Some(sub) = unknowns.iter().position(|&n| n == 0) {
            let links: Vec<&str> = self.submodels.traversals[sub]
                .order
                .iter()
                .map(|&l| self.model.links[l].name.as_str())
                .collect();
            return Err(DynError::Estimation(format!(
                "missing contact for the submodel composed by the links: {}",
                links.join(" ")
            )));
        }
        Ok((chosen, unknown))
    }

    /// The external wrenches at `contacts` and the joint torques, given the
    /// F/T sensors' measurements (one per sensor of the model, in its order).
    pub fn estimate(
        &self,
        joints: &JointState,
        base: &BaseMotion,
        ft: &[Wrench],
        contacts: &[Contact],
    ) -> Result<Estimate> {
        let m = &self.model;
        if ft.len() != m.sensors.ft.len() {
            return Err(DynError::Size {
                what: "F/T measurements",
                expected: m.sensors.ft.len(),
                got: ft.len(),
            });
        }
        let states = self.kinematics(joints, base)?;
        let net = net_wrenches(m, &states);
        let mut contact_wrenches = vec![Wrench::zeros(); contacts.len()];
        for (sub, traversal) in self.submodels.traversals.iter().enumerate() {
            let reference = traversal.base;
            // Known side: what the links need, minus what the sensors bring.
            let mut needed = Wrench::zeros();
            for &l in &traversal.order {
                needed += wrench_to(&states.relative(reference, l), &net[l]);
            }
            for (s, sensor) in m.sensors.ft.iter().enumerate() {
                let joint = &m.joints[sensor.joint];
                for link in [joint.parent, joint.child] {
                    if self.submodels.of_link[link] == sub {
                        let on_link = sensor.wrench_on(m, link, &ft[s]);
                        needed -= wrench_to(&states.relative(reference, link), &on_link);
                    }
                }
            }
            let mine: Vec<usize> = (0..contacts.len())
                .filter(|&c| self.submodels.of_frame(&contacts[c].frame) == sub)
                .collect();
            let solved = solve_contacts(&states, reference, contacts, &mine, &needed)?;
            for (c, w) in mine.into_iter().zip(solved) {
                contact_wrenches[c] = w;
            }
        }
        Ok(self.finish(joints, states, contacts, contact_wrenches))
    }

    /// What each F/T sensor is expected to read when the model's dynamics is
    /// balanced by `contacts` alone (the whole model as one body): the
    /// reference F/T offsets are calibrated against.
    pub fn expected_ft(
        &self,
        joints: &JointState,
        base: &BaseMotion,
        contacts: &[Contact],
    ) -> Result<(Vec<Wrench>, Estimate)> {
        let m = &self.model;
        let states = self.kinematics(joints, base)?;
        let net = net_wrenches(m, &states);
        let reference = self.traversal.base;
        let mut needed = Wrench::zeros();
        for &l in &self.traversal.order {
            needed += wrench_to(&states.relative(reference, l), &net[l]);
        }
        let all: Vec<usize> = (0..contacts.len()).collect();
        let contact_wrenches = solve_contacts(&states, reference, contacts, &all, &needed)?;
        let estimate = self.finish(joints, states, contacts, contact_wrenches);
        let id = inverse_dynamics(
            m,
            &self.traversal,
            &joints.q,
            &estimate.states,
            &estimate.link_wrenches,
        );
        let ft = m
            .sensors
            .ft
            .iter()
            .map(|sensor| {
                // The joint wrench is the one the traversal parent exerts on the
                // traversal child.
                let joint = &m.joints[sensor.joint];
                let child = if self.traversal.parent[joint.child].map(|p| p.1) == Some(sensor.joint)
                {
                    joint.child
                } else {
                    joint.parent
                };
                sensor.measurement_from(m, child, &id.joint_wrenches[child])
            })
            .collect();
        Ok((ft, estimate))
    }

    fn finish(
        &self,
        joints: &JointState,
        states: LinkStates,
        contacts: &[Contact],
        contact_wrenches: Vec<Wrench>,
    ) -> Estimate {
        let m = &self.model;
        let mut link_wrenches = vec![Wrench::zeros(); m.links.len()];
        for (c, w) in contacts.iter().zip(&contact_wrenches) {
            link_wrenches[c.frame.link] += wrench_to(&c.frame.link_h_frame, w);
        }
        let torques =
            inverse_dynamics(m, &self.traversal, &joints.q, &states, &link_wrenches).torques;
        Estimate {
            contact_wrenches,
            link_wrenches,
            torques,
            states,
        }
    }

    /// The net external wrench on `link` from an estimate, in `frame`'s
    /// orientation about `origin`'s origin (the three names of
    /// wholebodydynamics' output ports).
    pub fn wrench_in(
        &self,
        estimate: &Estimate,
        link: LinkIndex,
        origin: &FrameRef,
        orientation: &FrameRef,
    ) -> Wrench {
        let states = &estimate.states;
        // About the origin frame's origin, in link axes.
        let link_h_origin = states.relative(link, origin.link) * origin.link_h_frame;
        let moved = wrench_to(
            &nalgebra::Isometry3::from_parts(
                (-link_h_origin.translation.vector).into(),
                Default::default(),
            ),
            &estimate.link_wrenches[link],
        );
        let rotation =
            (states.relative(link, orientation.link) * orientation.link_h_frame).rotation;
        let r = nalgebra::Isometry3::from_parts(Default::default(), rotation.inverse());
        wrench_to(&r, &moved)
    }
}

/// Least squares over the unknowns of `which` contacts so that their wrenches,
/// moved to `reference`, sum to `needed` (see [`col_piv_qr_solve`]).
fn solve_contacts(
    states: &LinkStates,
    reference: LinkIndex,
    contacts: &[Contact],
    which: &[usize],
    needed: &Wrench,
) -> Result<Vec<Wrench>> {
    let n: usize = which.iter().map(|&c| contacts[c].kind.unknowns()).sum();
    if n == 0 {
        return Ok(Vec::new());
    }
    let mut a = DMatrix::zeros(6, n);
    let mut col = 0;
    for &c in which {
        let contact = &contacts[c];
        let x = wrench_matrix(
            &(states.relative(reference, contact.frame.link) * contact.frame.link_h_frame),
        );
        match contact.kind {
            ContactKind::FullWrench => a.view_mut((0, col), (6, 6)).copy_from(&x),
            ContactKind::PureForce => a
                .view_mut((0, col), (6, 3))
                .copy_from(&x.fixed_columns::<3>(0)),
            ContactKind::PureForceWithKnownDirection(d) => a
                .view_mut((0, col), (6, 1))
                .copy_from(&(x * six(d.normalize(), Vector3::zeros()))),
        }
        col += contact.kind.unknowns();
    }
    let x = col_piv_qr_solve(&a, &DVector::from_column_slice(needed.as_slice()));
    if x.iter().any(|v| !v.is_finite()) {
        return Err(DynError::Estimation(
            "the contact wrenches' solution is not finite".into(),
        ));
    }
    let mut out = Vec::with_capacity(which.len());
    let mut col = 0;
    for &c in which {
        let w = match contacts[c].kind {
            ContactKind::FullWrench => Wrench::from_column_slice(&x.as_slice()[col..col + 6]),
            ContactKind::PureForce => six(
                Vector3::from_column_slice(&x.as_slice()[col..col + 3]),
                Vector3::zeros(),
            ),
            ContactKind::PureForceWithKnownDirection(d) => {
                six(d.normalize() * x[col], Vector3::zeros())
            }
        };
        col += contacts[c].kind.unknowns();
        out.push(w);
    }
    Ok(out)
}
