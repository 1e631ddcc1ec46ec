//! One cycle of `wholebodydynamics` without its I/O, in C++'s order: the F/T
//! measurements through their secondary calibration, offsets and low-pass filters,
//! the IMU's and joints' filters, the kinematics from the IMU (or a fixed frame), an
//! offset calibration when one runs, the estimation, and what is published — nothing
//! until the F/T offsets are known.

use robot_dynamics::dynamics::inverse_dynamics;
use robot_dynamics::estimation::{Contact, ContactKind, Estimator};
use robot_dynamics::kinematics::{BaseMotion, JointState, Traversal};
use robot_dynamics::model::{FrameRef, LinkIndex};
use robot_dynamics::nalgebra::{DVector, Matrix6, Translation3, Vector3};
use robot_dynamics::spatial::{Iso, Wrench};

use super::config::{Config, WrenchType};
use super::filter::LowPass;

/// Where the kinematics starts from.
#[derive(Debug, Clone, PartialEq)]
pub enum KinematicSource {
    /// The IMU's frame, measured.
    Imu,
    /// A frame fixed in the world, with `fixedFrameGravity`.
    FixedFrame(String),
}

/// What the `settings` and the RPC may change while running.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    pub kinematic_source: KinematicSource,
    pub fixed_frame_gravity: [f64; 3],
    pub imu_frame_name: String,
    pub imu_cutoff: f64,
    pub ft_cutoff: f64,
    pub joint_vel_cutoff: f64,
    pub joint_acc_cutoff: f64,
    pub use_joint_velocity: bool,
    pub use_joint_acceleration: bool,
}

impl Settings {
    /// C++'s `settings.toString()` (the thrift struct's text).
    pub fn text(&self) -> String {
        let (source, fixed) = match &self.kinematic_source {
            KinematicSource::Imu => ("IMU", String::new()),
            KinematicSource::FixedFrame(f) => ("FIXED_FRAME", f.clone()),
        };
        let g = self.fixed_frame_gravity;
        format!(
            "{source} \"{fixed}\" ({} {} {}) \"{}\" {} {} {} {} {} {}",
            g[0],
            g[1],
            g[2],
            self.imu_frame_name,
            self.imu_cutoff,
            self.ft_cutoff,
            self.joint_vel_cutoff,
            self.joint_acc_cutoff,
            self.use_joint_velocity,
            self.use_joint_acceleration
        )
    }
}

/// One cycle's inputs, in the boards' units.
#[derive(Debug, Clone, Default)]
pub struct Readings {
    /// Degrees, in `axesNames` order; speeds deg/s, accelerations deg/s².
    pub q: Vec<f64>,
    pub dq: Vec<f64>,
    pub ddq: Vec<f64>,
    /// `[fx fy fz tx ty tz]` per sensor, in `SixAxisForceTorqueSensorsNames` order.
    pub ft: Vec<[f64; 6]>,
    /// The accelerometer (m/s², proper acceleration) and the gyroscope (deg/s).
    pub acc: [f64; 3],
    pub gyro: [f64; 3],
}

/// What a cycle publishes.
#[derive(Debug, Clone, Default)]
pub struct Outputs {
    /// N·m, in `axesNames` order.
    pub torques: Vec<f64>,
    /// Gravity compensation: `(axis, N·m)` for the configured axes.
    pub gravity_torques: Vec<(usize, f64)>,
    /// One per `WBD_OUTPUT_EXTERNAL_WRENCH_PORTS` entry.
    pub wrench_ports: Vec<[f64; 6]>,
    /// Every link's net external wrench, by link name in alphabetical order.
    pub net_external_wrenches: Vec<(String, [f64; 6])>,
    /// Filtered, offset-free F/T measurements.
    pub filtered_ft: Vec<[f64; 6]>,
}

/// An offset calibration under way.
#[derive(Debug, Clone)]
struct Calibration {
    contacts: Vec<Contact>,
    wanted: usize,
    taken: usize,
    sum: Vec<Wrench>,
}

/// Gravity compensation: a traversal from its base link and the axes it serves.
#[derive(Debug, Clone)]
struct GravityCompensation {
    traversal: Traversal,
    axes: Vec<usize>,
}

/// The estimation's state.
pub struct Core {
    pub est: Estimator,
    pub settings: Settings,
    period: f64,
    contacts: Vec<Contact>,
    secondary: Vec<Matrix6<f64>>,
    pub offsets: Vec<Wrench>,
    pre_estimated: Vec<Option<Wrench>>,
    ft_filters: Vec<LowPass>,
    acc_filter: LowPass,
    gyro_filter: LowPass,
    vel_filter: LowPass,
    ddq_filter: LowPass,
    calibration: Option<Calibration>,
    pub valid_offsets: bool,
    gravity: Option<GravityCompensation>,
    ports: Vec<(LinkIndex, FrameRef, FrameRef)>,
}

fn wrench(v: &[f64; 6]) -> Wrench {
    Wrench::from_column_slice(v)
}

fn array(w: &Wrench) -> [f64; 6] {
    [w[0], w[1], w[2], w[3], w[4], w[5]]
}

impl Core {
    /// The estimation of `est`'s model as `config` sets it up; the error says why C++
    /// would refuse to open.
    pub fn new(config: &Config, est: Estimator) -> Result<Core, String> {
        let p = &config.params;
        let m = &est.model;
        let mut frames = Vec::new();
        for (name, kind, point) in &config.contacts {
            let kind = match kind {
                WrenchType::Full => ContactKind::FullWrench,
                WrenchType::Pure => ContactKind::PureForce,
                WrenchType::PureKnown(d) => {
                    ContactKind::PureForceWithKnownDirection(Vector3::from_column_slice(d))
                }
            };
            frames.push((name.clone(), kind, *point));
        }
        let (mut contacts, unknown) = est
            .choose_contacts(
                &frames
                    .iter()
                    .map(|(n, k, _)| (n.clone(), *k))
                    .collect::<Vec<_>>(),
            )
            .map_err(|e| e.to_string())?;
        for u in unknown {
            tracing::warn!("wholebodydynamics: contact frame {u} is not in the model: ignored");
        }
        // A contact point other than the frame's origin moves the contact there.
        for c in &mut contacts {
            if let Some((_, _, point)) = frames.iter().find(|(n, _, _)| *n == c.frame_name) {
                c.frame.link_h_frame *= Iso::from_parts(
                    Translation3::new(point[0], point[1], point[2]),
                    Default::default(),
                );
            }
        }
        let n_ft = m.sensors.ft.len();
        let mut secondary = vec![Matrix6::identity(); n_ft];
        for (name, values) in &config.secondary_calibration {
            let i = m.sensors.ft_index(name).map_err(|_| {
                format!("FT_SECONDARY_CALIBRATION names {name}, which is not an F/T sensor used")
            })?;
            secondary[i] = Matrix6::from_row_slice(values);
        }
        let mut pre_estimated = vec![None; n_ft];
        for (name, values) in &config.pre_estimated_offsets {
            if let Ok(i) = m.sensors.ft_index(name) {
                pre_estimated[i] = Some(wrench(values));
            }
        }
        let ports = config
            .wrench_ports
            .iter()
            .map(|w| {
                let link = m
                    .link(&w.link)
                    .ok_or_else(|| format!("Link {} not found in the model.", w.link))?;
                let origin = m
                    .frame(&w.origin)
                    .map_err(|_| format!("Frame {} not found in the model.", w.origin))?;
                let orientation = m
                    .frame(&w.orientation)
                    .map_err(|_| format!("Frame {} not found in the model.", w.orientation))?;
                Ok((link, origin, orientation))
            })
            .collect::<Result<_, String>>()?;
        let gravity = match &config.gravity_compensation {
            None => None,
            Some((base, axes)) => {
                let link = m.link(base).ok_or_else(|| {
                    format!("gravityCompensationBaseLink {base} is not a link of the model")
                })?;
                let axes = axes
                    .iter()
                    .map(|a| {
                        m.joint(a).and_then(|j| m.joints[j].dof).ok_or_else(|| format!("gravityCompensationAxesNames: {a} is not one of the estimated axes"))
                    })
                    .collect::<Result<_, _>>()?;
                Some(GravityCompensation {
                    traversal: Traversal::new(m, link),
                    axes,
                })
            }
        };
        if let Some(f) = &p.assume_fixed {
            m.frame(f)
                .map_err(|_| format!("assume_fixed: frame {f} is not in the model"))?;
        }
        if let Some(f) = &p.imu_frame_name {
            m.frame(f)
                .map_err(|_| format!("imuFrameName: frame {f} is not in the model"))?;
        }
        let period = p.period.0;
        let settings = Settings {
            kinematic_source: p
                .assume_fixed
                .clone()
                .map_or(KinematicSource::Imu, KinematicSource::FixedFrame),
            fixed_frame_gravity: [
                p.fixed_frame_gravity[0],
                p.fixed_frame_gravity[1],
                p.fixed_frame_gravity[2],
            ],
            imu_frame_name: p.imu_frame_name.clone().unwrap_or_default(),
            imu_cutoff: p.imu_cutoff.0,
            ft_cutoff: p.ft_cutoff.0,
            joint_vel_cutoff: p.joint_vel_cutoff.map_or(0.0, |c| c.0),
            joint_acc_cutoff: p.joint_acc_cutoff.map_or(0.0, |c| c.0),
            use_joint_velocity: p.use_joint_velocity,
            use_joint_acceleration: p.use_joint_acceleration,
        };
        let dofs = m.dof_count();
        Ok(Core {
            ft_filters: (0..n_ft)
                .map(|_| LowPass::new(6, settings.ft_cutoff, period))
                .collect(),
            acc_filter: LowPass::new(3, settings.imu_cutoff, period),
            gyro_filter: LowPass::new(3, settings.imu_cutoff, period),
            vel_filter: LowPass::new(
                dofs,
                settings.joint_vel_cutoff.max(f64::MIN_POSITIVE),
                period,
            ),
            ddq_filter: LowPass::new(
                dofs,
                settings.joint_acc_cutoff.max(f64::MIN_POSITIVE),
                period,
            ),
            est,
            settings,
            period,
            contacts,
            secondary,
            offsets: vec![Wrench::zeros(); n_ft],
            pre_estimated,
            calibration: None,
            valid_offsets: false,
            gravity,
            ports,
        })
    }

    pub fn period(&self) -> f64 {
        self.period
    }

    /// The contacts the estimation assumes.
    pub fn contacts(&self) -> &[Contact] {
        &self.contacts
    }

    /// Starts an offset calibration over `samples` cycles assuming full-wrench contacts
    /// at `frames` (C++ `setupCalibrationWithExternalWrenchOnOneFrame`/`…TwoFrames`).
    pub fn start_calibration(&mut self, frames: &[&str], samples: usize) -> Result<(), String> {
        let contacts = frames
            .iter()
            .map(|f| {
                Contact::new(&self.est.model, f, ContactKind::FullWrench)
                    .map_err(|_| format!("Frame {f} not found in the model."))
            })
            .collect::<Result<Vec<_>, _>>()?;
        self.calibration = Some(Calibration {
            contacts,
            wanted: samples.max(1),
            taken: 0,
            sum: vec![Wrench::zeros(); self.offsets.len()],
        });
        Ok(())
    }

    pub fn calibrating(&self) -> bool {
        self.calibration.is_some()
    }

    /// Offsets known without calibrating (`startWithZeroFTSensorOffsets`).
    pub fn zero_offsets(&mut self) {
        self.offsets.iter_mut().for_each(|o| *o = Wrench::zeros());
        self.valid_offsets = true;
    }

    /// `resetOffset`: every offset to zero; whether they count as known is unchanged.
    pub fn reset_offsets(&mut self) {
        self.offsets.iter_mut().for_each(|o| *o = Wrench::zeros());
    }

    /// `usePreEstimatedOffset`: each sensor with a non-zero `FT_OFFSET` gets its
    /// opposite as offset.
    pub fn use_pre_estimated_offsets(&mut self) {
        for (o, pre) in self.offsets.iter_mut().zip(&self.pre_estimated) {
            if let Some(p) = pre.filter(|p| p.norm() > 0.0) {
                *o = -p;
            }
        }
    }

    /// Cycle: filters, kinematics, calibration, estimation; `None` until the offsets
    /// are known (C++ publishes nothing before).
    pub fn step(&mut self, r: &Readings) -> Result<Option<Outputs>, String> {
        let m = &self.est.model;
        let s = &self.settings;
        let n = m.dof_count();
        if r.q.len() != n || r.ft.len() != self.offsets.len() {
            return Err(format!(
                "readings of {} joints and {} F/T sensors, the model has {n} and {}",
                r.q.len(),
                r.ft.len(),
                self.offsets.len()
            ));
        }
        // F/T: secondary calibration, offset, low-pass.
        let calibrated: Vec<Wrench> =
            r.ft.iter()
                .zip(&self.secondary)
                .map(|(raw, c)| c * wrench(raw))
                .collect();
        let mut filtered = Vec::with_capacity(calibrated.len());
        for ((meas, offset), f) in calibrated
            .iter()
            .zip(&self.offsets)
            .zip(&mut self.ft_filters)
        {
            f.set_cutoff(s.ft_cutoff);
            filtered.push(wrench(
                &f.filt((meas - offset).as_slice())
                    .try_into()
                    .expect("six values"),
            ));
        }
        // Joints: degrees to radians, their speeds filtered when used.
        let q: Vec<f64> = r.q.iter().map(|d| d.to_radians()).collect();
        let mut dq = vec![0.0; n];
        if s.use_joint_velocity && r.dq.len() == n {
            self.vel_filter.set_cutoff(s.joint_vel_cutoff);
            let rad: Vec<f64> = r.dq.iter().map(|d| d.to_radians()).collect();
            dq.copy_from_slice(self.vel_filter.filt(&rad));
        }
        let mut ddq = vec![0.0; n];
        if s.use_joint_acceleration && r.ddq.len() == n {
            self.ddq_filter.set_cutoff(s.joint_acc_cutoff);
            let rad: Vec<f64> = r.ddq.iter().map(|d| d.to_radians()).collect();
            ddq.copy_from_slice(self.ddq_filter.filt(&rad));
        }
        self.acc_filter.set_cutoff(s.imu_cutoff);
        self.gyro_filter.set_cutoff(s.imu_cutoff);
        let acc = Vector3::from_column_slice(self.acc_filter.filt(&r.acc));
        let gyro_rad: Vec<f64> = r.gyro.iter().map(|d| d.to_radians()).collect();
        let gyro = Vector3::from_column_slice(self.gyro_filter.filt(&gyro_rad));
        let joints = JointState {
            q: DVector::from_vec(q.clone()),
            dq: DVector::from_vec(dq),
            ddq: DVector::from_vec(ddq),
        };
        let (base, still) = match &s.kinematic_source {
            KinematicSource::Imu => {
                let frame = m.frame(&s.imu_frame_name).map_err(|e| e.to_string())?;
                (
                    BaseMotion::Floating {
                        frame,
                        proper_acc: acc,
                        ang_vel: gyro,
                        ang_acc: Vector3::zeros(),
                    },
                    BaseMotion::Floating {
                        frame,
                        proper_acc: acc,
                        ang_vel: Vector3::zeros(),
                        ang_acc: Vector3::zeros(),
                    },
                )
            }
            KinematicSource::FixedFrame(name) => {
                let frame = m.frame(name).map_err(|e| e.to_string())?;
                let b = BaseMotion::Fixed {
                    frame,
                    gravity: Vector3::from_column_slice(&s.fixed_frame_gravity),
                };
                (b, b)
            }
        };
        // Calibration: the unfiltered measurement against what the assumed contacts
        // make the sensors read.
        if let Some(cal) = &mut self.calibration {
            let (expected, _) = self
                .est
                .expected_ft(&joints, &base, &cal.contacts)
                .map_err(|e| e.to_string())?;
            for ((sum, meas), exp) in cal.sum.iter_mut().zip(&calibrated).zip(&expected) {
                *sum += meas - exp;
            }
            cal.taken += 1;
            if cal.taken >= cal.wanted {
                let k = cal.taken as f64;
                for (o, sum) in self.offsets.iter_mut().zip(&cal.sum) {
                    *o = sum / k;
                }
                tracing::info!(
                    "wholebodydynamics: F/T offsets calibrated over {} samples",
                    cal.taken
                );
                self.calibration = None;
                self.valid_offsets = true;
            }
        }
        let estimate = self
            .est
            .estimate(&joints, &base, &filtered, &self.contacts)
            .map_err(|e| format!("Error in estimation, no estimates will be published: {e}"))?;
        if !self.valid_offsets {
            return Ok(None);
        }
        let mut out = Outputs {
            torques: estimate.torques.iter().copied().collect(),
            ..Default::default()
        };
        if let Some(gc) = &self.gravity {
            let states = self
                .est
                .kinematics(&JointState::at_rest(&q), &still)
                .map_err(|e| e.to_string())?;
            let none = vec![Wrench::zeros(); m.links.len()];
            let tau = inverse_dynamics(m, &gc.traversal, &joints.q, &states, &none).torques;
            out.gravity_torques = gc.axes.iter().map(|&a| (a, tau[a])).collect();
        }
        out.wrench_ports = self
            .ports
            .iter()
            .map(|(link, origin, orientation)| {
                array(&self.est.wrench_in(&estimate, *link, origin, orientation))
            })
            .collect();
        let mut net: Vec<(String, [f64; 6])> = m
            .links
            .iter()
            .enumerate()
            .map(|(l, link)| (link.name.clone(), array(&estimate.link_wrenches[l])))
            .collect();
        net.sort_by(|a, b| a.0.cmp(&b.0));
        out.net_external_wrenches = net;
        out.filtered_ft = filtered.iter().map(array).collect();
        Ok(Some(out))
    }
}
