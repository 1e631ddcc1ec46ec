//! `iKinGazeCtrl` without its ports: a target fixation point, the neck and eye joints
//! that look at it, the min-jerk controller that moves the head there (neck in position
//! direct, eyes in velocity, as C++'s), motion-done as C++ decides it, events, contexts
//! and the `rpc` commands (matched on their first four letters, strings or vocabs, as
//! C++'s `asVocab32` reads them). With the head IMU: the vestibulo-ocular and oculo-collic
//! reflexes (the eyes' counter-rotation while a motion runs) and gaze stabilisation while
//! idle; C++'s stabilisation during a motion (its gyro loop around the neck's min-jerk
//! command) is not done.

use icub_ikin::minjerk::{Integrator, MinJerkVelFilter};
use icub_ikin::{DEG2RAD, RAD2DEG};
use nalgebra::{DVector, Vector3};
use std::collections::BTreeMap;
use yarp_proto::{Bottle, Value};

use super::kinematics::{Camera, Head, HeadLimits};
use crate::protocol::{ack, nack};

/// What `[get] [info]` says of the server (`GAZECTRL_SERVER_VER`).
pub const SERVER_VERSION: &str = "2.0";
/// The controller's period \[s\].
pub const TS: f64 = 0.01;
/// No motion-done within this long of an onset (`10 Ts`).
const BLANKING: f64 = 0.1;
/// Neck and eyes within these of their targets: the motion is done \[deg\].
const NECK_DONE_DEG: f64 = 0.5;
const EYES_DONE_DEG: f64 = 0.1;

/// What the module reads from its options (`iKinGazeCtrl --from iKinGazeCtrl.ini`).
#[derive(Debug, Clone, PartialEq)]
pub struct GazeConfig {
    pub name: String,
    pub robot: String,
    pub head: String,
    /// `None`: `torso off`.
    pub torso: Option<String>,
    pub neck_time: f64,
    pub eyes_time: f64,
    /// `head_version` snapped to iKin's (`v2.5`, ...).
    pub head_version: String,
    pub eye_tilt: (f64, f64),
    pub ping_robot_tmo: f64,
    pub saccades: bool,
    pub imu: bool,
    pub vor: f64,
    pub ocr: f64,
    /// `imu::source_port_name`: the IMU's `multipleanalogsensorsserver`.
    pub imu_source: String,
    /// `imu::timeout` \[s\].
    pub imu_timeout: f64,
    /// `imu::stabilization_gain` \[1/s\].
    pub stabilization_gain: f64,
    /// `imu::gyro_noise_threshold` \[rad/s\] (given in deg/s).
    pub gyro_noise_threshold: f64,
    /// `cameras::file` and `cameras::context`: the eyes' calibration (`icubEyes.ini`).
    pub cameras: Option<(String, String)>,
}

impl GazeConfig {
    /// From a configuration (file and command line merged), as `configure` reads it.
    pub fn from_property(p: &yarp_proto::Property) -> GazeConfig {
        let text = |k: &str, d: &str| {
            p.find(k)
                .and_then(|v| match v {
                    Value::Vocab32(w) => Some(w.as_string()),
                    _ => v.as_str().map(str::to_string),
                })
                .unwrap_or_else(|| d.to_string())
        };
        let group = |g: &str, k: &str| {
            p.find_group(g)
                .and_then(|b| b.find(k))
                .and_then(Value::as_f64)
        };
        let group_text = |g: &str, k: &str| {
            p.find_group(g)
                .and_then(|b| b.find(k))
                .and_then(|v| v.as_str().map(str::to_string))
        };
        let imu = group_text("imu", "mode").is_none_or(|m| m == "on");
        let torso = text("torso", "torso");
        let robot = text("robot", "icub");
        GazeConfig {
            name: text("name", "iKinGazeCtrl")
                .trim_start_matches('/')
                .to_string(),
            imu_source: group_text("imu", "source_port_name")
                .unwrap_or_else(|| format!("/{robot}/head/inertials")),
            imu_timeout: group("imu", "timeout").unwrap_or(0.04),
            stabilization_gain: group("imu", "stabilization_gain").unwrap_or(11.0),
            gyro_noise_threshold: group("imu", "gyro_noise_threshold").unwrap_or(5.0) * DEG2RAD,
            robot,
            head: text("head", "head"),
            torso: (torso != "off").then_some(torso),
            neck_time: group("trajectory_time", "neck").unwrap_or(0.75),
            eyes_time: group("trajectory_time", "eyes").unwrap_or(0.25),
            head_version: snap_version(&text("head_version", "v1.0")),
            eye_tilt: (
                group("eye_tilt", "min").unwrap_or(-20.0),
                group("eye_tilt", "max").unwrap_or(15.0),
            ),
            ping_robot_tmo: p
                .find("ping_robot_tmo")
                .and_then(Value::as_f64)
                .unwrap_or(40.0),
            saccades: text("saccades", "on") == "on",
            imu,
            vor: group("imu", "vor").unwrap_or(if imu { 1.0 } else { 0.0 }),
            ocr: p
                .find("ocr")
                .and_then(Value::as_f64)
                .unwrap_or(if imu { 0.0 } else { 1.0 }),
            cameras: group_text("cameras", "file").map(|f| {
                let ctx = group_text("cameras", "context").unwrap_or_else(|| "iKinGazeCtrl".into());
                (f, ctx)
            }),
        }
    }
}

/// `head_version` snapped to the nearest version iKinGazeCtrl knows (its map of
/// differences: later entries win ties), as `v<major>.<minor>`.
pub fn snap_version(v: &str) -> String {
    let parse = |s: &str| -> Option<(i64, i64)> {
        let s = s.trim_start_matches(['v', 'V']);
        let (a, b) = s.split_once('.').unwrap_or((s, "0"));
        Some((a.parse().ok()?, b.parse().ok()?))
    };
    let want = parse(v).unwrap_or((1, 0));
    let known = [
        (1, 0),
        (2, 0),
        (2, 5),
        (2, 6),
        (2, 7),
        (2, 8),
        (2, 10),
        (3, 0),
    ];
    let mut best: BTreeMap<(i64, i64), (i64, i64)> = BTreeMap::new();
    for k in known {
        let d = if k.0 != want.0 {
            ((k.0 - want.0).abs(), 0)
        } else {
            (0, (k.1 - want.1).abs())
        };
        best.insert(d, k);
    }
    let (ma, mi) = best.values().next().copied().unwrap_or((1, 0));
    format!("v{ma}.{mi}")
}

/// An event for `events:o`.
#[derive(Debug, Clone, PartialEq)]
pub struct GazeEvent {
    pub name: &'static str,
    pub checkpoint: Option<f64>,
}

/// What a period produced.
#[derive(Debug, Default)]
pub struct GazeOutput {
    /// Neck position-direct references \[deg\].
    pub neck: Option<[f64; 3]>,
    /// Eye velocities \[deg/s\] (tilt, version, vergence).
    pub eyes: Option<[f64; 3]>,
    /// Stop the eyes (velocity 0) and the neck.
    pub stop: bool,
    /// The fixation point \[m\], the joints \[deg\] (torso in chain order, head) and the
    /// absolute angles \[deg\].
    pub x: Option<[f64; 3]>,
    pub q: Vec<f64>,
    pub angles: Option<[f64; 3]>,
    pub events: Vec<GazeEvent>,
    /// A motion started this period (sync looks may answer).
    pub onset: bool,
    /// The joints' control modes are to be set (neck position direct, eyes velocity):
    /// stabilisation started since the last period.
    pub modes: bool,
}

/// How an RPC is answered.
#[derive(Debug, Clone, PartialEq)]
pub enum GazeReply {
    Now(Bottle),
    /// `[ack]` once the motion toward the new target has started.
    AfterOnset,
    /// `[bye]`, then the module ends.
    Quit,
}

#[derive(Debug, Clone, PartialEq)]
struct Context {
    neck_time: f64,
    eyes_time: f64,
    tracking: bool,
    vor: f64,
    ocr: f64,
    saccades: bool,
    bounds: HeadLimits,
    ntol: f64,
    stabilize: bool,
}

/// The gaze controller's state.
pub struct GazeCore {
    cfg: GazeConfig,
    head: Head,
    /// The robot's limits \[rad\] and the user's binds of the neck.
    robot_limits: HeadLimits,
    limits: HeadLimits,
    min_vergence: f64,
    neck_time: f64,
    eyes_time: f64,
    tracking: bool,
    vor: f64,
    ocr: f64,
    saccades: bool,
    sacc_inhibition: f64,
    sacc_activation: f64,
    ntol: f64,
    eyes_bound: f64,
    suspended: bool,
    /// A new target not yet taken by the controller.
    pending: Option<Vector3<f64>>,
    xd: Vector3<f64>,
    qd: [f64; 6],
    active: bool,
    inhibited: bool,
    motion_done: bool,
    onset_at: f64,
    q0: [f64; 6],
    neck_filter: MinJerkVelFilter,
    eyes_filter: MinJerkVelFilter,
    neck_plan: Integrator,
    vel: [f64; 6],
    checkpoints: Vec<f64>,
    pending_checkpoints: Vec<f64>,
    contexts: BTreeMap<i32, Context>,
    next_context: i32,
    torso: [f64; 3],
    fb: [f64; 6],
    now: f64,
    /// The left and right cameras' intrinsics, when the calibration file gives them.
    cameras: [Option<Camera>; 2],
    /// The IMU's last angular velocity \[rad/s\], in its own frame (`None`: no reading).
    gyro: Option<Vector3<f64>>,
    /// The eyes' counter-rotation of this period (VOR and OCR) \[rad/s\].
    counterv: Vector3<f64>,
    /// Gaze stabilisation (`[set] [stab]`): the IMU's rotation countered while idle.
    stabilize: bool,
    /// C++'s `IntStabilizer` (Tustin, unbounded): its output and last input.
    stab_int: (Vector3<f64>, Vector3<f64>),
    /// The joints' modes are to be set at the next period (stabilisation started).
    modes_pending: bool,
}

impl GazeCore {
    /// A controller for the robot's head limits \[deg\] (6 joints).
    pub fn new(
        cfg: GazeConfig,
        head_limits_deg: &[(f64, f64)],
    ) -> Result<Self, icub_ikin::KinError> {
        let head = Head::new(&cfg.head_version)?;
        let mut limits: HeadLimits = [(-1.0, 1.0); 6];
        for (l, d) in limits.iter_mut().zip(head_limits_deg) {
            *l = (d.0 * DEG2RAD, d.1 * DEG2RAD);
        }
        // the eyes' tilt within eye_tilt; the vergence at least what the eyes allow
        limits[3].0 = limits[3].0.max(cfg.eye_tilt.0 * DEG2RAD);
        limits[3].1 = limits[3].1.min(cfg.eye_tilt.1 * DEG2RAD);
        let min_vergence = limits[5].0.max(0.0);
        let neck_lo = DVector::from_vec(limits[..3].iter().map(|l| l.0).collect());
        let neck_hi = DVector::from_vec(limits[..3].iter().map(|l| l.1).collect());
        let mut core = GazeCore {
            head,
            robot_limits: limits,
            limits,
            min_vergence,
            neck_time: cfg.neck_time,
            eyes_time: cfg.eyes_time,
            tracking: false,
            vor: cfg.vor,
            ocr: cfg.ocr,
            saccades: cfg.saccades,
            sacc_inhibition: 0.2,
            sacc_activation: 10.0,
            ntol: 0.0,
            eyes_bound: -1.0,
            suspended: false,
            pending: None,
            xd: Vector3::zeros(),
            qd: [0.0; 6],
            active: false,
            inhibited: false,
            motion_done: true,
            onset_at: 0.0,
            q0: [0.0; 6],
            neck_filter: MinJerkVelFilter::new(TS, 3),
            eyes_filter: MinJerkVelFilter::new(TS, 3),
            neck_plan: Integrator::new(TS, DVector::zeros(3), neck_lo, neck_hi),
            vel: [0.0; 6],
            checkpoints: Vec::new(),
            pending_checkpoints: Vec::new(),
            contexts: BTreeMap::new(),
            next_context: 0,
            torso: [0.0; 3],
            fb: [0.0; 6],
            now: 0.0,
            cameras: [None, None],
            gyro: None,
            counterv: Vector3::zeros(),
            stabilize: false,
            stab_int: (Vector3::zeros(), Vector3::zeros()),
            modes_pending: false,
            cfg,
        };
        core.set_times(core.neck_time, core.eyes_time);
        // context 0: the start-up settings
        core.store_context();
        Ok(core)
    }

    pub fn config(&self) -> &GazeConfig {
        &self.cfg
    }

    pub fn head(&self) -> &Head {
        &self.head
    }

    /// `setTeyes` then `setTneck`: eyes at least 10 periods, the neck 0.2 s slower.
    fn set_times(&mut self, neck: f64, eyes: f64) {
        self.eyes_time = eyes.max(10.0 * TS);
        self.neck_time = neck.max(self.eyes_time + 0.2);
    }

    /// A target fixation point (`xd:i`, `look`); false while suspended.
    pub fn set_target(&mut self, x: [f64; 3]) -> bool {
        if self.suspended {
            return false;
        }
        self.pending = Some(Vector3::new(x[0], x[1], x[2]));
        true
    }

    /// A target by absolute or relative angles \[deg\] (`angles:i`, `look ang`).
    pub fn target_of_angles(&self, relative: bool, ang_deg: [f64; 3]) -> Option<[f64; 3]> {
        let mut a = ang_deg.map(|v| v * DEG2RAD);
        if relative {
            let cur = self.head.abs_angles(&self.fixation_point()?);
            for k in 0..3 {
                a[k] += cur[k];
            }
        }
        let x = self.head.point_from_abs_angles(&a)?;
        Some([x[0], x[1], x[2]])
    }

    /// The cameras' intrinsics (left, right), from the calibration file.
    pub fn set_cameras(&mut self, left: Option<Camera>, right: Option<Camera>) {
        self.cameras = [left, right];
    }

    fn eye_and_camera(&self, eye: &str) -> Option<(nalgebra::Matrix4<f64>, Camera)> {
        let (l, r) = self.head.eyes(&self.torso, &self.fb);
        if eye == "left" {
            Some((l, self.cameras[0]?))
        } else {
            Some((r, self.cameras[1]?))
        }
    }

    /// `[eye u v z]` or `[eye u v "ver" degrees]` (`mono:i`, `look mono`): the point.
    pub fn target_of_mono(&self, b: &Bottle) -> Option<[f64; 3]> {
        let eye = b.get(0)?.as_str()?;
        let (u, v) = (b.get(1)?.as_f64()?, b.get(2)?.as_f64()?);
        let z = match b.get(3)? {
            Value::Float64(z) => *z,
            other if other.as_str() == Some("ver") => {
                self.head.dist_from_vergence(b.get(4)?.as_f64()? * DEG2RAD)
            }
            _ => return None,
        };
        let (h, cam) = self.eye_and_camera(eye)?;
        let x = self.head.unproject(&h, &cam, u, v, z);
        Some([x[0], x[1], x[2]])
    }

    /// `[ul vl ur vr]` (`look stereo`, `stereo:i`): the point, triangulated.
    pub fn target_of_stereo(&self, b: &Bottle) -> Option<[f64; 3]> {
        let px: Vec<f64> = b.iter().filter_map(Value::as_f64).collect();
        if px.len() < 4 {
            return None;
        }
        let (l, r) = self.head.eyes(&self.torso, &self.fb);
        let (cl, cr) = (self.cameras[0]?, self.cameras[1]?);
        let x = self
            .head
            .triangulate((&l, &r), (&cl, &cr), [px[0], px[1]], [px[2], px[3]])?;
        Some([x[0], x[1], x[2]])
    }

    fn fixation_point(&self) -> Option<Vector3<f64>> {
        self.head.fixation_point(&self.torso, &self.fb)
    }

    fn solve(&mut self, x: &Vector3<f64>) {
        let neck = self.head.solve_neck(
            &self.torso,
            [self.fb[0], self.fb[1], self.fb[2]],
            x,
            &self.limits,
        );
        let eyes = self
            .head
            .solve_eyes(&self.torso, neck, x, &self.limits, self.min_vergence);
        self.qd = [neck[0], neck[1], neck[2], eyes[0], eyes[1], eyes[2]];
    }

    /// One period with the torso (board order) and head encoders \[deg\].
    pub fn cycle(&mut self, now: f64, torso_deg: &[f64], head_deg: &[f64]) -> GazeOutput {
        self.now = now;
        let mut out = GazeOutput {
            modes: std::mem::take(&mut self.modes_pending),
            ..GazeOutput::default()
        };
        let mut t = [0.0; 3];
        for (k, v) in torso_deg.iter().take(3).enumerate() {
            t[k] = v * DEG2RAD;
        }
        if self.head.version < 3.0 {
            t.reverse();
        }
        self.torso = t;
        for (k, v) in head_deg.iter().take(6).enumerate() {
            self.fb[k] = v * DEG2RAD;
        }
        self.fb[5] = self.fb[5].max(self.min_vergence);
        if self.suspended {
            return self.streams(out);
        }
        if let Some(x) = self.pending.take() {
            self.xd = x;
            self.inhibited = false;
            self.solve(&x);
            if !self.active {
                self.neck_filter.reset();
                self.eyes_filter.reset();
                self.neck_plan
                    .reset(DVector::from_vec(self.fb[..3].to_vec()));
            }
            self.active = true;
            self.motion_done = false;
            self.onset_at = now;
            self.q0 = self.fb;
            self.pending_checkpoints = self.checkpoints.clone();
            out.onset = true;
            out.events.push(GazeEvent {
                name: "motion-onset",
                checkpoint: None,
            });
        } else if self.active && self.tracking {
            let x = self.xd;
            self.solve(&x);
        }
        if self.active {
            let neck_err: f64 = (0..3)
                .map(|k| (self.qd[k] - self.fb[k]).powi(2))
                .sum::<f64>()
                .sqrt();
            let eyes_err: f64 = (3..6)
                .map(|k| (self.qd[k] - self.fb[k]).powi(2))
                .sum::<f64>()
                .sqrt();
            let off = now - self.onset_at >= BLANKING
                && neck_err < NECK_DONE_DEG * DEG2RAD
                && eyes_err < EYES_DONE_DEG * DEG2RAD;
            // how far along: the ongoing checkpoints
            let den: f64 = (0..6)
                .map(|k| (self.qd[k] - self.q0[k]).powi(2))
                .sum::<f64>()
                .sqrt();
            let perc = if den > 1e-6 {
                ((0..6)
                    .map(|k| (self.fb[k] - self.q0[k]).powi(2))
                    .sum::<f64>()
                    .sqrt()
                    / den)
                    .clamp(0.0, 1.0)
            } else {
                1.0
            };
            if let Some(&cp) = self.pending_checkpoints.first() {
                if perc >= cp {
                    self.pending_checkpoints.retain(|c| *c != cp);
                    out.events.push(GazeEvent {
                        name: "motion-ongoing",
                        checkpoint: Some(cp),
                    });
                }
            }
            if off && !self.motion_done {
                for cp in std::mem::take(&mut self.pending_checkpoints) {
                    out.events.push(GazeEvent {
                        name: "motion-ongoing",
                        checkpoint: Some(cp),
                    });
                }
                out.events.push(GazeEvent {
                    name: "motion-done",
                    checkpoint: None,
                });
                self.motion_done = true;
                if !self.tracking {
                    self.active = false;
                    self.vel = [0.0; 6];
                    out.eyes = Some([0.0; 3]);
                }
            }
        }
        if self.active {
            // the counter-rotation as the eyes' feed-forward: their target is solved for
            // the neck's final posture (C++ integrates it into a reference that tracks
            // the fixation point instead), so it settles there when the head is still
            self.counterv = self.counter_velocity();
            let en = DVector::from_vec((0..3).map(|k| self.qd[k] - self.fb[k]).collect());
            let ee = DVector::from_vec((3..6).map(|k| self.qd[k] - self.fb[k]).collect());
            let vn = self.neck_filter.filt(self.neck_time, &en);
            let ve = self.eyes_filter.filt(self.eyes_time, &ee);
            let ve = Vector3::new(ve[0], ve[1], ve[2]) + self.counterv;
            let plan = self.neck_plan.integrate(&vn).clone();
            out.neck = Some([plan[0] * RAD2DEG, plan[1] * RAD2DEG, plan[2] * RAD2DEG]);
            out.eyes = Some([ve[0] * RAD2DEG, ve[1] * RAD2DEG, ve[2] * RAD2DEG]);
            self.vel = [vn[0], vn[1], vn[2], ve[0], ve[1], ve[2]];
        } else if self.stabilize {
            self.stabilize_idle(&mut out);
        }
        self.streams(out)
    }

    fn streams(&self, mut out: GazeOutput) -> GazeOutput {
        let x = self.fixation_point();
        out.x = x.map(|x| [x[0], x[1], x[2]]);
        out.angles = x.map(|x| self.head.abs_angles(&x).map(|v| v * RAD2DEG));
        out.q = self
            .torso
            .iter()
            .chain(self.fb.iter())
            .map(|v| v * RAD2DEG)
            .collect();
        out
    }

    /// The IMU's angular velocity \[deg/s\] in its frame, as the `multipleanalogsensors`
    /// gyroscope gives it, or `None` when it gave none this period.
    pub fn set_gyro(&mut self, gyro_deg_s: Option<[f64; 3]>) {
        self.gyro = gyro_deg_s.map(|g| Vector3::new(g[0], g[1], g[2]) * DEG2RAD);
    }

    /// `setGazeStabilization`: refused without an IMU (`imu::mode off`); on, the head
    /// then counters the IMU's rotation while no motion runs; off, stops the head.
    fn set_stabilization(&mut self, on: bool, out: &mut GazeOutput) -> bool {
        if !self.cfg.imu {
            return false;
        }
        if on == self.stabilize {
            return true;
        }
        self.stabilize = on;
        if on {
            if !self.active {
                self.neck_plan
                    .reset(DVector::from_vec(self.fb[..3].to_vec()));
                self.stab_int = (Vector3::zeros(), Vector3::zeros());
            }
            self.modes_pending = true;
            out.events.push(GazeEvent {
                name: "stabilization-on",
                checkpoint: None,
            });
        } else {
            self.active = false;
            self.motion_done = true;
            self.vel = [0.0; 6];
            out.stop = true;
            out.events.push(GazeEvent {
                name: "stabilization-off",
                checkpoint: None,
            });
        }
        true
    }

    /// The gyroscope's reading above `gyro_noise_threshold`, else zero (the VOR's).
    fn gyro_above_noise(&self) -> Vector3<f64> {
        let g = self.gyro.unwrap_or_else(Vector3::zeros);
        if g.norm() < self.cfg.gyro_noise_threshold {
            Vector3::zeros()
        } else {
            g
        }
    }

    /// `getEyesCounterVelocity`: the eyes' velocity \[rad/s\] (tilt, version, vergence)
    /// that keeps the fixation point still while the head turns, from the IMU's rotation
    /// (vestibulo-ocular reflex, gain `vor`) and the neck's commanded velocity
    /// (oculo-collic reflex, gain `ocr`); zero with the eyes bound.
    fn counter_velocity(&self) -> Vector3<f64> {
        if self.eyes_bound >= 0.0 || (self.vor == 0.0 && self.ocr == 0.0) {
            return Vector3::zeros();
        }
        let Some(fp) = self.fixation_point() else {
            return Vector3::zeros();
        };
        let Some(j) = self.head.fixation_jacobian(&self.torso, &self.fb) else {
            return Vector3::zeros();
        };
        let h = self.head.imu_frame(&self.torso, &self.fb);
        let r = h.fixed_view::<3, 3>(0, 0);
        let p = h.fixed_view::<3, 1>(0, 3);
        let vor = (r * self.gyro_above_noise()).cross(&(fp - p));
        let neck_vel = Vector3::new(self.vel[0], self.vel[1], self.vel[2]);
        let ocr = self
            .head
            .point_velocity_of_neck(&self.torso, &self.fb, &fp, &neck_vel);
        let rel = vor * self.vor + ocr * self.ocr;
        match j.pseudo_inverse(1e-12) {
            Ok(ji) => -(ji * rel),
            Err(_) => Vector3::zeros(),
        }
    }

    /// Gaze stabilisation while idle (C++'s controller without a motion): the neck turns
    /// against the IMU's rotation (`stabilization_gain` on its integral), the eyes keep
    /// the fixation point against what is left; nothing without a reading.
    fn stabilize_idle(&mut self, out: &mut GazeOutput) {
        let Some(gyro) = self.gyro else {
            return;
        };
        let Some(x) = self.fixation_point() else {
            return;
        };
        let h = self.head.imu_frame(&self.torso, &self.fb);
        let r = h.fixed_view::<3, 3>(0, 0);
        let p = h.fixed_view::<3, 1>(0, 3);
        let w = r * gyro;
        let dx = w.cross(&(x - p));
        let jn = self.head.neck_jacobian(&self.torso, &self.fb);
        let jw: nalgebra::Matrix3<f64> = jn.fixed_view::<3, 3>(3, 0).into_owned();
        let imu_neck = jw
            .pseudo_inverse(1e-12)
            .map(|ji| ji * w)
            .unwrap_or_default();
        // Tustin: y += (x + x_old) Ts / 2
        let input = -imu_neck;
        self.stab_int.0 += (input + self.stab_int.1) * (TS / 2.0);
        self.stab_int.1 = input;
        let v_neck = self.stab_int.0 * self.cfg.stabilization_gain;
        // the eyes only where the vergence is wide enough to tell the point
        let v_eyes = if self.fb[5] > 4.0 * DEG2RAD {
            self.head
                .fixation_jacobian(&self.torso, &self.fb)
                .and_then(|j| j.pseudo_inverse(1e-12).ok())
                .map(|ji| ji * dx)
                .unwrap_or_default()
        } else {
            Vector3::zeros()
        };
        let plan = self
            .neck_plan
            .integrate(&DVector::from_vec(v_neck.iter().copied().collect()))
            .clone();
        out.neck = Some([plan[0] * RAD2DEG, plan[1] * RAD2DEG, plan[2] * RAD2DEG]);
        out.eyes = Some([
            v_eyes[0] * RAD2DEG,
            v_eyes[1] * RAD2DEG,
            v_eyes[2] * RAD2DEG,
        ]);
        self.vel = [
            v_neck[0], v_neck[1], v_neck[2], v_eyes[0], v_eyes[1], v_eyes[2],
        ];
    }

    /// `[stop]`: the motion ends where it is.
    fn stop(&mut self, out: &mut GazeOutput) {
        if self.active {
            self.active = false;
            self.inhibited = true;
            self.motion_done = true;
            self.vel = [0.0; 6];
            out.stop = true;
            out.events.push(GazeEvent {
                name: "motion-done",
                checkpoint: None,
            });
        }
    }

    fn store_context(&mut self) -> i32 {
        let id = self.next_context;
        self.next_context += 1;
        self.contexts.insert(
            id,
            Context {
                neck_time: self.neck_time,
                eyes_time: self.eyes_time,
                tracking: self.tracking,
                vor: self.vor,
                ocr: self.ocr,
                saccades: self.saccades,
                bounds: self.limits,
                ntol: self.ntol,
                stabilize: self.stabilize,
            },
        );
        id
    }

    /// The `rpc` commands (`respond`); `out` collects a stop's effect.
    pub fn respond(&mut self, cmd: &Bottle, out: &mut GazeOutput) -> GazeReply {
        let w = |i: usize| word4(cmd, i);
        let reply = match w(0).as_str() {
            "get" if cmd.len() > 1 => self.get(cmd, &w(1)),
            "set" if cmd.len() > 2 && w(1) == "stab" => match cmd.get(2).and_then(Value::as_f64) {
                Some(v) if self.set_stabilization(v > 0.0, out) => ack(),
                _ => nack(),
            },
            "set" if cmd.len() > 2 => self.set(cmd, &w(1)),
            "look" if cmd.len() > 2 => {
                let Some(list) = cmd.get(2).and_then(Value::as_list) else {
                    return GazeReply::Now(nack());
                };
                let nums: Vec<f64> = list.iter().filter_map(Value::as_f64).collect();
                let target = match w(1).as_str() {
                    "3D" if nums.len() >= 3 => Some([nums[0], nums[1], nums[2]]),
                    "mono" => self.target_of_mono(list),
                    "ster" => self.target_of_stereo(list),
                    "ang" if list.len() >= 4 => {
                        let rel = list.get(0).and_then(Value::as_str) == Some("rel");
                        let a: Vec<f64> = list.iter().skip(1).filter_map(Value::as_f64).collect();
                        (a.len() >= 3)
                            .then(|| self.target_of_angles(rel, [a[0], a[1], a[2]]))
                            .flatten()
                    }
                    _ => None,
                };
                return match target {
                    Some(x) if self.set_target(x) => GazeReply::AfterOnset,
                    _ => GazeReply::Now(nack()),
                };
            }
            "stop" => {
                self.stop(out);
                ack()
            }
            "stor" => {
                let id = self.store_context();
                ack().with(Value::Int32(id))
            }
            "rest" if cmd.len() > 1 => {
                let id = cmd.get(1).and_then(Value::as_i64).unwrap_or(-1) as i32;
                match self.contexts.get(&id).cloned() {
                    Some(c) => {
                        self.set_times(c.neck_time, c.eyes_time);
                        self.tracking = c.tracking;
                        self.vor = c.vor;
                        self.ocr = c.ocr;
                        self.saccades = c.saccades;
                        self.limits = c.bounds;
                        self.ntol = c.ntol;
                        self.set_stabilization(c.stabilize, out);
                        ack()
                    }
                    None => nack(),
                }
            }
            "del" => match cmd.get(1).and_then(Value::as_list) {
                Some(ids) => {
                    for id in ids.iter().filter_map(Value::as_i64) {
                        self.contexts.remove(&(id as i32));
                    }
                    ack()
                }
                None => nack(),
            },
            "bind" if cmd.len() > 2 => {
                let v = |i| cmd.get(i).and_then(Value::as_f64).unwrap_or(0.0) * DEG2RAD;
                match w(1).as_str() {
                    "pitc" | "roll" | "yaw" => {
                        let k = ["pitc", "roll", "yaw"]
                            .iter()
                            .position(|j| *j == w(1))
                            .unwrap_or(0);
                        let (lo, hi) = self.robot_limits[k];
                        self.limits[k] = (
                            v(2).clamp(lo, hi),
                            v(3).clamp(lo, hi).max(v(2).clamp(lo, hi)),
                        );
                        ack()
                    }
                    "eyes" => {
                        self.eyes_bound = cmd.get(2).and_then(Value::as_f64).unwrap_or(-1.0);
                        ack()
                    }
                    _ => nack(),
                }
            }
            "clea" if cmd.len() > 1 => match w(1).as_str() {
                "pitc" | "roll" | "yaw" => {
                    let k = ["pitc", "roll", "yaw"]
                        .iter()
                        .position(|j| *j == w(1))
                        .unwrap_or(0);
                    self.limits[k] = self.robot_limits[k];
                    ack()
                }
                "eyes" => {
                    self.eyes_bound = -1.0;
                    ack()
                }
                _ => nack(),
            },
            "regi" if cmd.len() > 2 => match cmd.get(2).and_then(Value::as_f64) {
                Some(cp) if (0.0..=1.0).contains(&cp) => {
                    let at = self.checkpoints.partition_point(|c| *c <= cp);
                    self.checkpoints.insert(at, cp);
                    ack()
                }
                _ => nack(),
            },
            "unre" if cmd.len() > 2 => {
                let cp = cmd.get(2).and_then(Value::as_f64);
                match cp.and_then(|cp| self.checkpoints.iter().position(|c| *c == cp)) {
                    Some(i) => {
                        self.checkpoints.remove(i);
                        ack()
                    }
                    None => nack(),
                }
            }
            "list" => ack().with(crate::protocol::f64_list(&self.checkpoints)),
            "susp" => {
                self.suspended = true;
                self.stop(out);
                out.events.push(GazeEvent {
                    name: "suspended",
                    checkpoint: None,
                });
                ack()
            }
            "run" => {
                self.suspended = false;
                out.events.push(GazeEvent {
                    name: "resumed",
                    checkpoint: None,
                });
                ack()
            }
            "stat" => ack().with(if self.suspended {
                "suspended"
            } else {
                "running"
            }),
            "quit" | "exit" | "bye" => return GazeReply::Quit,
            "get" | "set" | "look" | "rest" | "bind" | "clea" | "regi" | "unre" => nack(),
            // RFModule's answer to what it does not know (said twice, as C++'s)
            _ => Bottle::new()
                .with("command not recognized")
                .with("command not recognized"),
        };
        GazeReply::Now(reply)
    }

    fn get(&mut self, cmd: &Bottle, opt: &str) -> Bottle {
        let flag = |b: bool| ack().with(Value::Int32(i32::from(b)));
        let deg = |v: f64| v * RAD2DEG;
        match opt {
            "Tnec" => ack().with(self.neck_time),
            "Teye" => ack().with(self.eyes_time),
            "vor" => ack().with(self.vor),
            "ocr" => ack().with(self.ocr),
            "sacc" => flag(self.saccades),
            "sinh" => ack().with(self.sacc_inhibition),
            "sact" => ack().with(self.sacc_activation),
            "trac" => flag(self.tracking),
            "stab" => flag(self.stabilize),
            "done" => flag(self.motion_done),
            "sdon" => flag(true),
            "pitc" | "roll" | "yaw" => {
                let k = ["pitc", "roll", "yaw"]
                    .iter()
                    .position(|j| *j == opt)
                    .unwrap_or(0);
                ack()
                    .with(deg(self.limits[k].0))
                    .with(deg(self.limits[k].1))
            }
            "eyes" => ack().with(self.eyes_bound),
            "ntol" => ack().with(self.ntol),
            "des" => ack().with(crate::protocol::f64_list(&self.qd.map(deg))),
            "vel" => ack().with(crate::protocol::f64_list(&self.vel.map(deg))),
            "pose" if cmd.len() > 2 => {
                let (l, r) = self.head.eyes(&self.torso, &self.fb);
                let h = match word4(cmd, 2).as_str() {
                    "left" => l,
                    "righ" => r,
                    "head" => self.head.center(&self.torso, &self.fb),
                    _ => return nack(),
                };
                let x = icub_ikin::pose::pose7(&h);
                ack()
                    .with(crate::protocol::f64_list(x.as_slice()))
                    .with(Value::List(
                        Bottle::new().with(Value::Int32(0)).with(self.now),
                    ))
            }
            "ang" => match cmd.get(2).and_then(crate::protocol::numbers) {
                Some(x) if x.len() >= 3 => {
                    let a = self.head.abs_angles(&Vector3::new(x[0], x[1], x[2]));
                    ack().with(crate::protocol::f64_list(&a.map(deg)))
                }
                _ => nack(),
            },
            "2D" => {
                let Some(list) = cmd.get(2).and_then(Value::as_list) else {
                    return nack();
                };
                let eye = list.get(0).and_then(Value::as_str).unwrap_or("right");
                let x: Vec<f64> = list.iter().skip(1).filter_map(Value::as_f64).collect();
                match (self.eye_and_camera(eye), x.len() >= 3) {
                    (Some((h, cam)), true) => {
                        match self.head.project(&h, &cam, &Vector3::new(x[0], x[1], x[2])) {
                            Some(px) => ack().with(crate::protocol::f64_list(&px)),
                            None => nack(),
                        }
                    }
                    _ => nack(),
                }
            }
            "3D" if cmd.len() > 3 && matches!(word4(cmd, 2).as_str(), "mono" | "ster") => {
                let Some(list) = cmd.get(3).and_then(Value::as_list) else {
                    return nack();
                };
                let x = if word4(cmd, 2) == "mono" {
                    self.target_of_mono(list)
                } else {
                    self.target_of_stereo(list)
                };
                match x {
                    Some(x) => ack().with(crate::protocol::f64_list(&x)),
                    None => nack(),
                }
            }
            "3D" if cmd.len() > 3 && word4(cmd, 2) == "ang" => {
                let Some(list) = cmd.get(3).and_then(Value::as_list) else {
                    return nack();
                };
                let rel = list.get(0).and_then(Value::as_str) == Some("rel");
                let a: Vec<f64> = list.iter().skip(1).filter_map(Value::as_f64).collect();
                match (a.len() >= 3)
                    .then(|| self.target_of_angles(rel, [a[0], a[1], a[2]]))
                    .flatten()
                {
                    Some(x) => ack().with(crate::protocol::f64_list(&x)),
                    None => nack(),
                }
            }
            "info" => ack().with(Value::List(self.info())),
            _ => nack(),
        }
    }

    fn set(&mut self, cmd: &Bottle, opt: &str) -> Bottle {
        let num = cmd.get(2).and_then(Value::as_f64);
        let Some(v) = num else {
            return nack();
        };
        match opt {
            "Tnec" => self.set_times(v, self.eyes_time),
            "Teye" => self.set_times(self.neck_time, v),
            "vor" => self.vor = v,
            "ocr" => self.ocr = v,
            "sacc" => self.saccades = v > 0.0,
            "sinh" => self.sacc_inhibition = v,
            "sact" => self.sacc_activation = v,
            "ntol" => self.ntol = v.abs(),
            "trac" => {
                self.tracking = v > 0.0;
                if self.tracking {
                    if let Some(x) = self.fixation_point() {
                        self.pending = Some(x);
                    }
                }
            }
            _ => return nack(),
        }
        ack()
    }

    /// `[get] [info]`'s list.
    fn info(&self) -> Bottle {
        let pair = |k: &str, v: Value| Value::List(Bottle::new().with(k).with(v));
        let events: Bottle = [
            "motion-onset",
            "motion-done",
            "motion-ongoing",
            "saccade-onset",
            "saccade-done",
            "stabilization-on",
            "stabilization-off",
            "closing",
            "suspended",
            "resumed",
            "comm-timeout",
            "*",
        ]
        .into_iter()
        .map(Value::from)
        .collect();
        let intr = |c: &Option<Camera>| match c {
            Some(c) => crate::protocol::f64_list(&c.projection()),
            None => Value::List(Bottle::new()),
        };
        let size = |c: &Option<Camera>| c.map_or((0, 0), |c| (c.w, c.h));
        let (wl, hl) = size(&self.cameras[0]);
        let (wr, hr) = size(&self.cameras[1]);
        Bottle::new()
            .with(pair("server_version", SERVER_VERSION.into()))
            .with(pair(
                "head_version",
                self.cfg.head_version.trim_start_matches('v').into(),
            ))
            .with(pair(
                "min_allowed_vergence",
                Value::Float64(self.min_vergence * RAD2DEG),
            ))
            .with(pair("events", Value::List(events)))
            .with(pair("camera_intrinsics_left", intr(&self.cameras[0])))
            .with(pair("camera_width_left", Value::Int32(wl)))
            .with(pair("camera_height_left", Value::Int32(hl)))
            .with(pair("camera_intrinsics_right", intr(&self.cameras[1])))
            .with(pair("camera_width_right", Value::Int32(wr)))
            .with(pair("camera_height_right", Value::Int32(hr)))
    }
}

/// The first four letters of item `i`, vocab or string (C++'s `asVocab32`).
fn word4(b: &Bottle, i: usize) -> String {
    let w = crate::protocol::word_at(b, i).unwrap_or_default();
    w.chars().take(4).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn head_versions_snap_as_ikingazectrl_snaps_them() {
        for (given, want) in [
            ("v2.5", "v2.5"),
            ("v3.1", "v3.0"),
            ("v2.9", "v2.10"),
            ("v1.5", "v1.0"),
            ("V2", "v2.0"),
            ("garbage", "v1.0"),
        ] {
            assert_eq!(snap_version(given), want, "{given}");
        }
    }

    fn core(imu: bool, vor: f64) -> GazeCore {
        let mut cfg = GazeConfig::from_property(&yarp_proto::Property::new());
        cfg.head_version = "v2.5".into();
        cfg.imu = imu;
        cfg.vor = vor;
        cfg.ocr = 0.0;
        let limits = [
            (-40.0, 30.0),
            (-70.0, 60.0),
            (-55.0, 55.0),
            (-35.0, 15.0),
            (-50.0, 52.0),
            (0.0, 90.0),
        ];
        GazeCore::new(cfg, &limits).unwrap()
    }

    /// The IMU's angular velocity in its own frame \[deg/s\] between two postures.
    fn gyro_between(head: &Head, a: (&[f64; 3], &[f64; 6]), b: (&[f64; 3], &[f64; 6])) -> [f64; 3] {
        let ra = head
            .imu_frame(a.0, a.1)
            .fixed_view::<3, 3>(0, 0)
            .into_owned();
        let rb = head
            .imu_frame(b.0, b.1)
            .fixed_view::<3, 3>(0, 0)
            .into_owned();
        let ax = icub_ikin::pose::dcm2axis(&(ra.transpose() * rb));
        [0, 1, 2].map(|k| ax[k] * ax[3] / TS * RAD2DEG)
    }

    /// Tracks a point with the neck bound while the torso turns at 20 deg/s (the IMU
    /// feels the turn): the worst fixation error once the turn is under way \[m\].
    fn fixation_error_while_the_torso_turns(mut g: GazeCore) -> f64 {
        let target = [-0.6, 0.0, 0.35];
        let mut torso = [0.0f64; 3]; // board order: yaw, roll, pitch
        let mut head = [0.0f64, 0.0, 0.0, 0.0, 0.0, 10.0];
        let mut out = GazeOutput::default();
        g.respond(&Bottle::from_text("set track 1"), &mut out);
        // the neck held: the eyes alone keep the gaze
        for j in ["pitch", "roll", "yaw"] {
            g.respond(&Bottle::from_text(format!("bind {j} 0 0")), &mut out);
        }
        g.set_target(target);
        let mut worst: f64 = 0.0;
        for i in 0..400 {
            let t = i as f64 * TS;
            let before = (torso, head);
            if i >= 200 {
                torso[0] += 20.0 * TS;
            }
            let chain = |t: &[f64; 3]| [t[2] * DEG2RAD, t[1] * DEG2RAD, t[0] * DEG2RAD];
            let rad = |h: &[f64; 6]| h.map(|v| v * DEG2RAD);
            let gyro = gyro_between(
                g.head(),
                (&chain(&before.0), &rad(&before.1)),
                (&chain(&torso), &rad(&head)),
            );
            g.set_gyro(Some(gyro));
            let out = g.cycle(t, &torso, &head);
            if let Some(n) = out.neck {
                head[..3].copy_from_slice(&n);
            }
            if let Some(v) = out.eyes {
                for k in 0..3 {
                    head[3 + k] += v[k] * TS;
                }
            }
            if i >= 250 {
                let x = out.x.unwrap();
                let d = (0..3)
                    .map(|k| (x[k] - target[k]).powi(2))
                    .sum::<f64>()
                    .sqrt();
                worst = worst.max(d);
            }
        }
        worst
    }

    #[test]
    fn the_vestibulo_ocular_reflex_holds_the_gaze_while_the_body_turns() {
        let without = fixation_error_while_the_torso_turns(core(true, 0.0));
        let with = fixation_error_while_the_torso_turns(core(true, 1.0));
        eprintln!("fixation error while turning: {without:.4} m without VOR, {with:.4} m with");
        // measured: 29 mm without, 1 mm with
        assert!(with < 0.25 * without, "{with} against {without}");
    }

    #[test]
    fn stabilization_needs_the_imu_and_counters_its_rotation_while_idle() {
        let mut out = GazeOutput::default();
        let mut off = core(false, 0.0);
        assert_eq!(
            off.respond(&Bottle::from_text("set stab 1"), &mut out),
            GazeReply::Now(nack())
        );
        let mut g = core(true, 1.0);
        let head = [0.0, 0.0, 0.0, 0.0, 0.0, 10.0];
        g.cycle(0.0, &[0.0; 3], &head);
        assert_eq!(
            g.respond(&Bottle::from_text("set stab 1"), &mut out),
            GazeReply::Now(ack())
        );
        assert_eq!(out.events[0].name, "stabilization-on");
        assert!(g.cycle(TS, &[0.0; 3], &head).modes, "the joints' modes set");
        assert_eq!(
            g.respond(&Bottle::from_text("get stab"), &mut out),
            GazeReply::Now(ack().with(Value::Int32(1)))
        );
        // the head turns up (the IMU pitches) at 10 deg/s: the neck answers down
        let (r0, r1) = (
            [0.0, 0.0, 0.0, 0.0, 0.0, 10.0 * DEG2RAD],
            [0.1 * DEG2RAD, 0.0, 0.0, 0.0, 0.0, 10.0 * DEG2RAD],
        );
        let gyro = gyro_between(g.head(), (&[0.0; 3], &r0), (&[0.0; 3], &r1));
        let mut neck = 0.0;
        for i in 1..20 {
            g.set_gyro(Some(gyro));
            let out = g.cycle(i as f64 * TS, &[0.0; 3], &head);
            neck = out.neck.expect("the neck commanded")[0];
        }
        assert!(neck < -0.1, "neck pitch {neck}");
        let mut out = GazeOutput::default();
        g.respond(&Bottle::from_text("set stab 0"), &mut out);
        assert!(out.stop);
        assert_eq!(out.events[0].name, "stabilization-off");
        assert!(g.cycle(1.0, &[0.0; 3], &head).neck.is_none());
    }
}
