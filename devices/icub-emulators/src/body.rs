//! The robot's body, as its emulated sensors feel it: the URDF's links with their
//! masses, posed by the joints the emulated boards report, held still under gravity
//! either at the root link (an iCub on its pole, an ergoCub on the crane) or standing on
//! contact frames (its feet), and pushed, on request, by a force at a link.
//!
//! What the sensors read follows from statics alone, written here on its own (sums of
//! the weights and forces beyond each sensor, the stance's support from a least-norm
//! share among the contacts), so that an estimator on the robot checks against
//! physics, not against a copy of its own dynamics:
//!
//! - a six-axis F/T sensor on a joint reads what the side away from the URDF root (the
//!   joint's child) exerts on the other side: the sum of the forces on that side
//!   (weights, pushes, contact forces), about the sensor's origin, in its frame, negated
//!   for `parent_to_child` sensors (iDynTree's URDF conventions);
//! - an accelerometer reads gravity's opposite in its frame; a gyroscope nothing.

use std::collections::HashMap;
use std::path::Path;

use nalgebra::{DMatrix, DVector, Isometry3, Translation3, Unit, UnitQuaternion, Vector3};

const GRAVITY: f64 = 9.81;

/// How the body is held.
#[derive(Debug, Clone, PartialEq)]
pub enum Stance {
    /// The root link held fixed, upright (gravity along its −z).
    FixedRoot,
    /// Standing on these frames (links or frames of massless links), the first one
    /// flat on the ground; the support shared among them.
    Standing(Vec<String>),
}

#[derive(Debug, Clone)]
struct Link {
    mass: f64,
    com: Vector3<f64>,
}

#[derive(Debug, Clone)]
struct Joint {
    name: String,
    parent: usize,
    child: usize,
    origin: Isometry3<f64>,
    axis: Unit<Vector3<f64>>,
    moves: bool,
    prismatic: bool,
}

#[derive(Debug, Clone)]
struct FtSensor {
    name: String,
    joint: usize,
    /// On the joint's child: `child_H_sensor`.
    child_h_sensor: Isometry3<f64>,
    parent_to_child: bool,
}

#[derive(Debug, Clone)]
struct Accelerometer {
    name: String,
    link: usize,
    link_h_sensor: Isometry3<f64>,
}

/// The body and what acts on it.
#[derive(Debug, Clone)]
pub struct Body {
    names: Vec<String>,
    links: Vec<Link>,
    joints: Vec<Joint>,
    /// For each link, the joint from its parent (none for the root).
    from_parent: Vec<Option<usize>>,
    /// Links, parents first.
    order: Vec<usize>,
    ft: Vec<FtSensor>,
    /// For each F/T sensor, the links beyond it.
    beyond: Vec<Vec<usize>>,
    /// For each joint, the links beyond it.
    below: Vec<Vec<usize>>,
    accelerometers: Vec<Accelerometer>,
    stance: Stance,
    positions: HashMap<String, f64>,
    pushes: HashMap<usize, Vector3<f64>>,
}

/// What the sensors read at one instant.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Readings {
    /// `[fx fy fz tx ty tz]` (N, N·m) by F/T sensor name.
    pub ft: HashMap<String, [f64; 6]>,
    /// Proper acceleration (m/s²) by accelerometer name.
    pub acc: HashMap<String, [f64; 3]>,
    /// The torque (N·m; force for a prismatic joint, N) each moving joint's parent side
    /// exerts on its child side about the joint's axis: what a joint torque sensor
    /// reads.
    pub torques: HashMap<String, f64>,
}

fn iso(xyz: [f64; 3], rpy: [f64; 3]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(xyz[0], xyz[1], xyz[2]),
        UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]),
    )
}

fn triple(text: Option<&str>) -> Result<[f64; 3], String> {
    let Some(t) = text else { return Ok([0.0; 3]) };
    let v: Vec<f64> = t
        .split_whitespace()
        .map(|x| x.parse().map_err(|_| format!("`{t}` is not three numbers")))
        .collect::<Result<_, _>>()?;
    v.try_into()
        .map_err(|_| format!("`{t}` is not three numbers"))
}

impl Body {
    /// The body of a URDF file.
    pub fn from_urdf(path: &Path, stance: Stance) -> Result<Body, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        Body::from_urdf_str(&text, stance).map_err(|e| format!("{}: {e}", path.display()))
    }

    pub fn from_urdf_str(text: &str, stance: Stance) -> Result<Body, String> {
        let robot = urdf_rs::read_from_string(text).map_err(|e| e.to_string())?;
        let names: Vec<String> = robot.links.iter().map(|l| l.name.clone()).collect();
        let index: HashMap<&str, usize> = names
            .iter()
            .enumerate()
            .map(|(i, n)| (n.as_str(), i))
            .collect();
        let links = robot
            .links
            .iter()
            .map(|l| Link {
                mass: l.inertial.mass.value,
                com: Vector3::from_column_slice(&l.inertial.origin.xyz[..]),
            })
            .collect();
        let mut joints = Vec::new();
        let mut from_parent = vec![None; names.len()];
        for j in &robot.joints {
            let (Some(&parent), Some(&child)) = (
                index.get(j.parent.link.as_str()),
                index.get(j.child.link.as_str()),
            ) else {
                return Err(format!(
                    "joint {} joins links the file does not have",
                    j.name
                ));
            };
            let o = &j.origin;
            use urdf_rs::JointType as T;
            let (moves, prismatic) = match j.joint_type {
                T::Fixed => (false, false),
                T::Revolute | T::Continuous => (true, false),
                T::Prismatic => (true, true),
                _ => {
                    return Err(format!(
                        "joint {} is of a type the body does not model",
                        j.name
                    ))
                }
            };
            from_parent[child] = Some(joints.len());
            joints.push(Joint {
                name: j.name.clone(),
                parent,
                child,
                origin: iso(
                    [o.xyz[0], o.xyz[1], o.xyz[2]],
                    [o.rpy[0], o.rpy[1], o.rpy[2]],
                ),
                axis: Unit::try_new(Vector3::from_column_slice(&j.axis.xyz[..]), 1e-12)
                    .unwrap_or(Vector3::x_axis()),
                moves,
                prismatic,
            });
        }
        let root = (0..names.len())
            .find(|&l| from_parent[l].is_none())
            .ok_or("no root link")?;
        let mut order = vec![root];
        let mut k = 0;
        while k < order.len() {
            let l = order[k];
            order.extend(joints.iter().filter(|j| j.parent == l).map(|j| j.child));
            k += 1;
        }
        let mut body = Body {
            names,
            links,
            joints,
            from_parent,
            order,
            ft: Vec::new(),
            beyond: Vec::new(),
            below: Vec::new(),
            accelerometers: Vec::new(),
            stance: Stance::FixedRoot,
            positions: HashMap::new(),
            pushes: HashMap::new(),
        };
        body.read_sensors(text)?;
        body.below = body.joints.iter().map(|j| body.subtree(j.child)).collect();
        body.beyond = body
            .ft
            .iter()
            .map(|s| body.below[s.joint].clone())
            .collect();
        if let Stance::Standing(frames) = &stance {
            for f in frames {
                body.link(f)?;
            }
        }
        body.stance = stance;
        Ok(body)
    }

    fn read_sensors(&mut self, text: &str) -> Result<(), String> {
        let doc = roxmltree::Document::parse(text).map_err(|e| e.to_string())?;
        for s in doc
            .root_element()
            .children()
            .filter(|c| c.has_tag_name("sensor"))
        {
            let name = s.attribute("name").unwrap_or_default().to_string();
            let child = |tag: &str| s.children().find(|c| c.has_tag_name(tag));
            let origin = match child("origin") {
                Some(o) => iso(triple(o.attribute("xyz"))?, triple(o.attribute("rpy"))?),
                None => Isometry3::identity(),
            };
            match s.attribute("type") {
                Some("force_torque") => {
                    let joint_name = child("parent")
                        .and_then(|p| p.attribute("joint"))
                        .ok_or(format!("sensor {name} has no parent joint"))?;
                    let joint = self
                        .joints
                        .iter()
                        .position(|j| j.name == joint_name)
                        .ok_or(format!("sensor {name}: no joint {joint_name}"))?;
                    let ft = child("force_torque");
                    let text_of = |tag: &str| {
                        ft.and_then(|f| f.children().find(|c| c.has_tag_name(tag)))
                            .and_then(|n| n.text())
                            .map(str::trim)
                    };
                    let child_h_sensor = match text_of("frame").unwrap_or("child") {
                        "parent" => self.joints[joint].origin.inverse(),
                        "sensor" => origin,
                        _ => Isometry3::identity(),
                    };
                    let parent_to_child = text_of("measure_direction") == Some("parent_to_child");
                    self.ft.push(FtSensor {
                        name,
                        joint,
                        child_h_sensor,
                        parent_to_child,
                    });
                }
                Some("accelerometer") => {
                    let link_name = child("parent")
                        .and_then(|p| p.attribute("link"))
                        .ok_or(format!("sensor {name} has no parent link"))?;
                    let link = self
                        .names
                        .iter()
                        .position(|n| n == link_name)
                        .ok_or(format!("sensor {name}: no link {link_name}"))?;
                    self.accelerometers.push(Accelerometer {
                        name,
                        link,
                        link_h_sensor: origin,
                    });
                }
                _ => {}
            }
        }
        Ok(())
    }

    fn link(&self, name: &str) -> Result<usize, String> {
        self.names
            .iter()
            .position(|n| n == name)
            .ok_or_else(|| format!("the body has no link {name}"))
    }

    /// A joint's position (rad, or m), as its board reports it.
    pub fn set_position(&mut self, joint: &str, q: f64) {
        self.positions.insert(joint.to_string(), q);
    }

    /// A force (N, in the world's axes: z up) pushing on `link` at its origin; zero
    /// removes it.
    pub fn push(&mut self, link: &str, force: [f64; 3]) -> Result<(), String> {
        let l = self.link(link)?;
        let f = Vector3::from_column_slice(&force);
        if f.norm() == 0.0 {
            self.pushes.remove(&l);
        } else {
            self.pushes.insert(l, f);
        }
        Ok(())
    }

    /// The F/T sensors' names.
    pub fn ft_names(&self) -> impl Iterator<Item = &str> {
        self.ft.iter().map(|s| s.name.as_str())
    }

    /// Every link's pose in the world.
    fn poses(&self) -> Vec<Isometry3<f64>> {
        let mut root_h = vec![Isometry3::identity(); self.names.len()];
        for &l in &self.order[1..] {
            let j = &self.joints[self.from_parent[l].expect("a child link")];
            let q = if j.moves {
                self.positions.get(&j.name).copied().unwrap_or(0.0)
            } else {
                0.0
            };
            let motion = if !j.moves {
                Isometry3::identity()
            } else if j.prismatic {
                Isometry3::from_parts((j.axis.into_inner() * q).into(), UnitQuaternion::identity())
            } else {
                Isometry3::from_parts(
                    Translation3::identity(),
                    UnitQuaternion::from_axis_angle(&j.axis, q),
                )
            };
            root_h[l] = root_h[j.parent] * j.origin * motion;
        }
        let world_h_root = match &self.stance {
            Stance::FixedRoot => Isometry3::identity(),
            Stance::Standing(frames) => {
                // the first support flat: its frame's axes are the world's
                let first = self.link(&frames[0]).expect("checked at construction");
                Isometry3::from_parts(Translation3::identity(), root_h[first].rotation.inverse())
            }
        };
        root_h.iter().map(|p| world_h_root * p).collect()
    }

    /// What the sensors read now.
    pub fn readings(&self) -> Readings {
        let poses = self.poses();
        let n = self.names.len();
        // The forces on each link (world axes) at world points.
        let mut forces: Vec<Vec<(Vector3<f64>, Vector3<f64>)>> = vec![Vec::new(); n];
        for (l, link) in self.links.iter().enumerate() {
            if link.mass > 0.0 {
                let at = poses[l] * nalgebra::Point3::from(link.com);
                forces[l].push((Vector3::new(0.0, 0.0, -link.mass * GRAVITY), at.coords));
            }
        }
        for (&l, f) in &self.pushes {
            forces[l].push((*f, poses[l].translation.vector));
        }
        // The support balancing them all.
        let (total_f, total_m) = forces.iter().flatten().fold(
            (Vector3::zeros(), Vector3::zeros()),
            |(f, m), (force, at)| (f + force, m + at.cross(force)),
        );
        match &self.stance {
            // The root's support acts on the root, which is beyond no sensor.
            Stance::FixedRoot => {}
            Stance::Standing(frames) => {
                let points: Vec<(usize, Vector3<f64>)> = frames
                    .iter()
                    .map(|f| {
                        let l = self.link(f).expect("checked");
                        (l, poses[l].translation.vector)
                    })
                    .collect();
                // Forces f_k at p_k with Σ f_k = −F, Σ p_k × f_k = −M: least norm.
                let k = points.len();
                let mut a = DMatrix::zeros(6, 3 * k);
                for (i, (_, p)) in points.iter().enumerate() {
                    for c in 0..3 {
                        let mut e = Vector3::zeros();
                        e[c] = 1.0;
                        a[(c, 3 * i + c)] = 1.0;
                        let m = p.cross(&e);
                        for r in 0..3 {
                            a[(3 + r, 3 * i + c)] = m[r];
                        }
                    }
                }
                let b =
                    DVector::from_iterator(6, (-total_f).iter().chain((-total_m).iter()).copied());
                let aat = &a * a.transpose();
                let x = match aat.clone().try_inverse() {
                    Some(inv) => a.transpose() * inv * b,
                    None => a
                        .clone()
                        .svd(true, true)
                        .solve(&b, 1e-12)
                        .unwrap_or_else(|_| DVector::zeros(3 * k)),
                };
                for (i, (l, p)) in points.iter().enumerate() {
                    forces[*l].push((Vector3::new(x[3 * i], x[3 * i + 1], x[3 * i + 2]), *p));
                }
            }
        }
        let mut out = Readings::default();
        for (s, beyond) in self.ft.iter().zip(&self.beyond) {
            let j = &self.joints[s.joint];
            let sensor = poses[j.child] * s.child_h_sensor;
            let o = sensor.translation.vector;
            let (mut f, mut m) = (Vector3::zeros(), Vector3::zeros());
            for &l in beyond {
                for (force, at) in &forces[l] {
                    f += force;
                    m += (at - o).cross(force);
                }
            }
            let r = sensor.rotation.inverse();
            let (f, m) = (r * f, r * m);
            let sign = if s.parent_to_child { -1.0 } else { 1.0 };
            out.ft.insert(
                s.name.clone(),
                [
                    sign * f.x,
                    sign * f.y,
                    sign * f.z,
                    sign * m.x,
                    sign * m.y,
                    sign * m.z,
                ],
            );
        }
        for (j, below) in self.joints.iter().zip(&self.below) {
            if !j.moves {
                continue;
            }
            let frame = poses[j.child];
            let (o, axis) = (
                frame.translation.vector,
                frame.rotation * j.axis.into_inner(),
            );
            let (mut f, mut m) = (Vector3::zeros(), Vector3::zeros());
            for &l in below {
                for (force, at) in &forces[l] {
                    f += force;
                    m += (at - o).cross(force);
                }
            }
            // the parent side holds the child side against what acts on it
            let tau = if j.prismatic {
                -axis.dot(&f)
            } else {
                -axis.dot(&m)
            };
            out.torques.insert(j.name.clone(), tau);
        }
        for a in &self.accelerometers {
            let r = (poses[a.link] * a.link_h_sensor).rotation.inverse();
            let g = r * Vector3::new(0.0, 0.0, GRAVITY);
            out.acc.insert(a.name.clone(), [g.x, g.y, g.z]);
        }
        out
    }

    /// A link and every link beyond it.
    fn subtree(&self, top: usize) -> Vec<usize> {
        let mut out = vec![top];
        let mut k = 0;
        while k < out.len() {
            let l = out[k];
            out.extend(
                self.joints
                    .iter()
                    .filter(|j| j.parent == l)
                    .map(|j| j.child),
            );
            k += 1;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A base, an arm link along x on a y joint, a sensor between the arm and a hand.
    const ARM: &str = r#"<robot name="arm">
      <link name="base"><inertial><origin xyz="0 0 0"/><mass value="5"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
      <link name="arm"><inertial><origin xyz="0.2 0 0"/><mass value="2"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
      <link name="hand"><inertial><origin xyz="0.1 0 0"/><mass value="0.5"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
      <joint name="shoulder" type="revolute"><origin xyz="0 0 0.5"/><parent link="base"/><child link="arm"/><axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
      <joint name="wrist_ft" type="fixed"><origin xyz="0.4 0 0"/><parent link="arm"/><child link="hand"/></joint>
      <sensor name="hand_ft" type="force_torque"><parent joint="wrist_ft"/><force_torque><frame>child</frame><measure_direction>child_to_parent</measure_direction></force_torque></sensor>
      <sensor name="hand_acc" type="accelerometer"><parent link="hand"/><origin xyz="0 0 0" rpy="0 0 0"/></sensor>
    </robot>"#;

    #[test]
    fn a_hanging_hand_weighs_on_its_sensor() {
        let mut b = Body::from_urdf_str(ARM, Stance::FixedRoot).unwrap();
        let r = b.readings();
        // the hand's weight, 0.1 m out along x: force down, torque about −y... in the
        // sensor's (= the hand's) frame, level at q = 0
        let ft = r.ft["hand_ft"];
        assert!((ft[2] + 0.5 * GRAVITY).abs() < 1e-12 && ft[0].abs() < 1e-12);
        assert!((ft[4] - 0.1 * 0.5 * GRAVITY).abs() < 1e-12, "{ft:?}");
        // arm pitched down 90°: the hand hangs below, no lever
        b.set_position("shoulder", std::f64::consts::FRAC_PI_2);
        let ft = b.readings().ft["hand_ft"];
        assert!(
            (ft[0] - 0.5 * GRAVITY).abs() < 1e-9 && ft[4].abs() < 1e-9,
            "{ft:?}"
        );
        assert!((b.readings().acc["hand_acc"][0] + GRAVITY).abs() < 1e-9);
        // hanging straight down the shoulder holds nothing; level it holds both
        assert!(b.readings().torques["shoulder"].abs() < 1e-9);
        b.set_position("shoulder", 0.0);
        // arm 2 kg at 0.2 m, hand 0.5 kg at 0.5 m: gravity pulls toward +q (x to −z)
        let tau = b.readings().torques["shoulder"];
        assert!(
            (tau + (2.0 * 0.2 + 0.5 * 0.5) * GRAVITY).abs() < 1e-9,
            "{tau}"
        );
    }

    #[test]
    fn a_push_on_the_hand_adds_to_its_reading() {
        let mut b = Body::from_urdf_str(ARM, Stance::FixedRoot).unwrap();
        let before = b.readings().ft["hand_ft"];
        b.push("hand", [0.0, 0.0, -10.0]).unwrap();
        let after = b.readings().ft["hand_ft"];
        assert!((after[2] - before[2] + 10.0).abs() < 1e-12);
        b.push("hand", [0.0; 3]).unwrap();
        assert_eq!(b.readings().ft["hand_ft"], before);
    }

    #[test]
    fn standing_the_support_carries_the_weight() {
        let b = Body::from_urdf_str(ARM, Stance::Standing(vec!["base".into()])).unwrap();
        // standing on the base: the hand still weighs the same on its sensor
        let ft = b.readings().ft["hand_ft"];
        assert!((ft[2] + 0.5 * GRAVITY).abs() < 1e-9, "{ft:?}");
    }
}
