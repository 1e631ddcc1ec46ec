//! The model of a robot as iDynTree holds it: links with their inertia,
//! joints between them, frames fixed to links, and sensors.
//!
//! As iDynTree's URDF loader does, a link without mass that hangs from a
//! single other link by a fixed joint (a "fake link": `l_sole`, `base_link`,
//! `waist_imu_0`) is not a body but an additional frame of the link it hangs
//! from; every other link stays a body, also when a fixed joint joins it to its
//! parent (the F/T sensors sit on such joints).

use std::collections::HashMap;

use nalgebra::{Unit, UnitQuaternion, Vector3};

use crate::error::{DynError, Result};
use crate::sensors::Sensors;
use crate::spatial::{Inertia, Iso};

pub type LinkIndex = usize;
pub type JointIndex = usize;

#[derive(Debug, Clone)]
pub struct Link {
    pub name: String,
    /// In the link's own frame.
    pub inertia: Inertia,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointKind {
    Fixed,
    /// Revolute and continuous joints.
    Revolute,
    Prismatic,
}

#[derive(Debug, Clone)]
pub struct Joint {
    pub name: String,
    pub kind: JointKind,
    /// The URDF's parent link.
    pub parent: LinkIndex,
    /// The URDF's child link.
    pub child: LinkIndex,
    /// `parent_H_child` at zero position.
    pub origin: Iso,
    /// The axis, in the child's frame.
    pub axis: Unit<Vector3<f64>>,
    /// Position limits (radians or metres) when the URDF gives them.
    pub limits: Option<(f64, f64)>,
    /// The joint's index among the model's degrees of freedom.
    pub dof: Option<usize>,
    /// Where the joint is held when it is not a degree of freedom.
    pub held_at: f64,
}

impl Joint {
    /// `parent_H_child` at position `q`.
    pub fn transform(&self, q: f64) -> Iso {
        match self.kind {
            JointKind::Fixed => self.origin,
            JointKind::Revolute => {
                self.origin
                    * Iso::from_parts(
                        Default::default(),
                        UnitQuaternion::from_axis_angle(&self.axis, q),
                    )
            }
            JointKind::Prismatic => {
                self.origin
                    * Iso::from_parts(
                        (self.axis.into_inner() * q).into(),
                        UnitQuaternion::identity(),
                    )
            }
        }
    }
}

/// A frame rigidly attached to a link.
#[derive(Debug, Clone)]
pub struct Frame {
    pub name: String,
    pub link: LinkIndex,
    pub link_h_frame: Iso,
}

#[derive(Debug, Clone, Default)]
pub struct Model {
    pub links: Vec<Link>,
    pub joints: Vec<Joint>,
    /// Additional frames (fake links, in iDynTree's words).
    pub frames: Vec<Frame>,
    /// The joints that move, in the order of the joint vectors.
    pub dofs: Vec<JointIndex>,
    pub sensors: Sensors,
    link_index: HashMap<String, LinkIndex>,
    joint_index: HashMap<String, JointIndex>,
    frame_index: HashMap<String, usize>,
}

/// A link or an additional frame, resolved.
#[derive(Debug, Clone, Copy)]
pub struct FrameRef {
    pub link: LinkIndex,
    pub link_h_frame: Iso,
}

impl Model {
    /// Builds a model from raw links and joints (by link name), turning fake
    /// links into frames and numbering the moving joints in the given order.
    pub fn new(links: Vec<Link>, joints: Vec<RawJoint>) -> Result<Model> {
        let mut degree: HashMap<&str, usize> = HashMap::new();
        for j in &joints {
            *degree.entry(j.parent.as_str()).or_default() += 1;
            *degree.entry(j.child.as_str()).or_default() += 1;
        }
        let mass: HashMap<&str, f64> = links
            .iter()
            .map(|l| (l.name.as_str(), l.inertia.mass))
            .collect();
        let is_fake = |j: &RawJoint| {
            j.kind == JointKind::Fixed
                && mass.get(j.child.as_str()).copied().unwrap_or(0.0) == 0.0
                && degree.get(j.child.as_str()) == Some(&1)
                && degree.get(j.parent.as_str()).copied().unwrap_or(0) > 1
        };
        let fake: Vec<(String, String, Iso)> = joints
            .iter()
            .filter(|j| is_fake(j))
            .map(|j| (j.child.clone(), j.parent.clone(), j.origin))
            .collect();
        let fake_names: std::collections::HashSet<&str> =
            fake.iter().map(|f| f.0.as_str()).collect();

        let mut model = Model::default();
        for link in links
            .into_iter()
            .filter(|l| !fake_names.contains(l.name.as_str()))
        {
            model
                .link_index
                .insert(link.name.clone(), model.links.len());
            model.links.push(link);
        }
        let index = |m: &Model, name: &str| {
            m.link_index
                .get(name)
                .copied()
                .ok_or_else(|| DynError::UnknownFrame(name.to_owned()))
        };
        for raw in joints
            .into_iter()
            .filter(|j| !fake_names.contains(j.child.as_str()))
        {
            let (parent, child) = (index(&model, &raw.parent)?, index(&model, &raw.child)?);
            let dof = (raw.kind != JointKind::Fixed).then(|| {
                model.dofs.push(model.joints.len());
                model.dofs.len() - 1
            });
            model
                .joint_index
                .insert(raw.name.clone(), model.joints.len());
            model.joints.push(Joint {
                name: raw.name,
                kind: raw.kind,
                parent,
                child,
                origin: raw.origin,
                axis: raw.axis,
                limits: raw.limits,
                dof,
                held_at: 0.0,
            });
        }
        for (name, parent, origin) in fake {
            let link = index(&model, &parent)?;
            model.frame_index.insert(name.clone(), model.frames.len());
            model.frames.push(Frame {
                name,
                link,
                link_h_frame: origin,
            });
        }
        model.check_tree()?;
        Ok(model)
    }

    fn check_tree(&self) -> Result<()> {
        if self.links.is_empty() {
            return Err(DynError::NotATree("no links".into()));
        }
        if self.joints.len() + 1 != self.links.len() {
            return Err(DynError::NotATree(format!(
                "{} links joined by {} joints",
                self.links.len(),
                self.joints.len()
            )));
        }
        let mut parents = vec![0usize; self.links.len()];
        for j in &self.joints {
            parents[j.child] += 1;
        }
        if let Some(l) = parents.iter().position(|&n| n > 1) {
            return Err(DynError::NotATree(format!(
                "link '{}' has more than one parent",
                self.links[l].name
            )));
        }
        Ok(())
    }

    pub fn link(&self, name: &str) -> Option<LinkIndex> {
        self.link_index.get(name).copied()
    }

    pub fn joint(&self, name: &str) -> Option<JointIndex> {
        self.joint_index.get(name).copied()
    }

    /// A link's or an additional frame's link and pose on it.
    pub fn frame(&self, name: &str) -> Result<FrameRef> {
        if let Some(link) = self.link(name) {
            return Ok(FrameRef {
                link,
                link_h_frame: Iso::identity(),
            });
        }
        let f = self
            .frame_index
            .get(name)
            .map(|&i| &self.frames[i])
            .ok_or_else(|| DynError::UnknownFrame(name.to_owned()))?;
        Ok(FrameRef {
            link: f.link,
            link_h_frame: f.link_h_frame,
        })
    }

    /// Adds a frame unless a link or frame already has the name (as iDynTree
    /// adds its sensors' frames); says whether it was added.
    pub fn add_frame(&mut self, name: &str, link: LinkIndex, link_h_frame: Iso) -> bool {
        if self.link_index.contains_key(name) || self.frame_index.contains_key(name) {
            return false;
        }
        self.frame_index.insert(name.to_owned(), self.frames.len());
        self.frames.push(Frame {
            name: name.to_owned(),
            link,
            link_h_frame,
        });
        true
    }

    /// The link the URDF tree starts from (the one that is nobody's child).
    pub fn root(&self) -> LinkIndex {
        let mut is_child = vec![false; self.links.len()];
        for j in &self.joints {
            is_child[j.child] = true;
        }
        is_child.iter().position(|c| !c).unwrap_or(0)
    }

    pub fn dof_count(&self) -> usize {
        self.dofs.len()
    }

    /// The moving joints' names, in joint-vector order.
    pub fn dof_names(&self) -> Vec<&str> {
        self.dofs
            .iter()
            .map(|&j| self.joints[j].name.as_str())
            .collect()
    }

    /// The joints adjacent to a link.
    pub fn neighbours(
        &self,
        link: LinkIndex,
    ) -> impl Iterator<Item = (JointIndex, LinkIndex)> + '_ {
        self.joints.iter().enumerate().filter_map(move |(i, j)| {
            if j.parent == link {
                Some((i, j.child))
            } else if j.child == link {
                Some((i, j.parent))
            } else {
                None
            }
        })
    }

    /// Only the named joints move; every other joint is held where `held`
    /// says, else at zero (as iDynTree's reduced models do). The joint vectors
    /// follow `names`' order.
    pub fn with_dofs(mut self, names: &[impl AsRef<str>], held: &[(String, f64)]) -> Result<Model> {
        for j in &mut self.joints {
            j.dof = None;
            j.held_at = 0.0;
        }
        for (name, q) in held {
            let j = self
                .joint(name)
                .ok_or_else(|| DynError::UnknownJoint(name.clone()))?;
            self.joints[j].held_at = *q;
        }
        self.dofs.clear();
        for (i, name) in names.iter().enumerate() {
            let name = name.as_ref();
            let j = self
                .joint(name)
                .ok_or_else(|| DynError::UnknownJoint(name.to_owned()))?;
            if self.joints[j].kind == JointKind::Fixed {
                return Err(DynError::UnsupportedJoint {
                    joint: name.to_owned(),
                    kind: "fixed (not a degree of freedom)".into(),
                });
            }
            self.joints[j].dof = Some(i);
            self.dofs.push(j);
        }
        Ok(self)
    }

    /// Keeps only the named F/T sensors, in the order named (wholebodydynamics'
    /// `SixAxisForceTorqueSensorsNames`): the model then splits at their joints
    /// only.
    pub fn select_ft(&mut self, names: &[impl AsRef<str>]) -> Result<()> {
        let mut chosen = Vec::with_capacity(names.len());
        for name in names {
            let i = self.sensors.ft_index(name.as_ref())?;
            chosen.push(self.sensors.ft[i].clone());
        }
        self.sensors.ft = chosen;
        Ok(())
    }

    /// The total mass.
    pub fn mass(&self) -> f64 {
        self.links.iter().map(|l| l.inertia.mass).sum()
    }
}

/// A joint as read, before the links are numbered.
#[derive(Debug, Clone)]
pub struct RawJoint {
    pub name: String,
    pub kind: JointKind,
    pub parent: String,
    pub child: String,
    pub origin: Iso,
    pub axis: Unit<Vector3<f64>>,
    pub limits: Option<(f64, f64)>,
}
