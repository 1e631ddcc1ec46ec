//! Runs a robot description as C++ `yarp::robotinterface::Robot::enterPhase` does:
//! devices open at the start of the `startup` phase, each phase runs its actions level by
//! level (calibrate and park actions of one level in parallel, joined before the next
//! level), and the `shutdown` phase ends by closing the devices in reverse order.
//!
//! A device that cannot be opened (its type is not in the registry, or its driver fails)
//! fails the startup, as in C++ (a dry run opens nothing, so there an unknown type is only
//! reported). One deliberate addition, so that partial robots come up: told to keep going
//! ([`RobotRunner::set_keep_going`], `yarprobotinterface --keep-going`), the runner skips a
//! device whose type is not in the registry, and a device that fails to open or a wrapper
//! whose attach fails, together with the actions on it or aimed at it, reports each by name,
//! and the startup succeeds with what is left ([`RobotRunner::failures`] lists what was
//! given up besides the unavailable types).

use super::error::XmlError;
use super::model::*;
use crate::driver::{shared, PolyDriver, Registry, SharedDevice};
use crate::error::{DevResult, DeviceError};
use parking_lot::{Mutex, MutexGuard};
use std::fmt;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use yarp_proto::{Bottle, Property, Value};

/// Makes devices for the runner; the registry in production, fakes in tests.
pub trait DeviceFactory: Send + Sync {
    /// Whether a driver called `kind` exists.
    fn knows(&self, kind: &str) -> bool;
    /// Opens the device `config` describes (its `device` key names the driver).
    fn open(&self, config: &Property) -> DevResult<PolyDriver>;
}

/// The process-wide driver [`Registry`] (C++ names).
pub struct RegistryFactory;

impl DeviceFactory for RegistryFactory {
    fn knows(&self, kind: &str) -> bool {
        Registry::knows(kind)
    }

    fn open(&self, config: &Property) -> DevResult<PolyDriver> {
        PolyDriver::open(config)
    }
}

/// What became of one device of the description.
enum Slot {
    NotOpened,
    /// Its type is not in the registry; reported and skipped.
    Unavailable,
    /// It failed to open (only kept going past with `keep_going`).
    Failed,
    Open(SharedDevice),
}

/// The problems met while running one phase.
#[derive(Debug, Clone, PartialEq)]
pub struct PhaseError {
    pub phase: ActionPhase,
    pub problems: Vec<String>,
}

impl fmt::Display for PhaseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} phase failed: {}",
            self.phase,
            self.problems.join("; ")
        )
    }
}

impl std::error::Error for PhaseError {}

/// A robot description being brought up, run and shut down.
pub struct RobotRunner {
    robot: Robot,
    factory: Box<dyn DeviceFactory>,
    slots: Vec<Slot>,
    /// Opened wrappers left unattached because a target was skipped: actions aimed at
    /// them are skipped in turn (a remapper of missing boards cannot be served).
    incomplete: Mutex<Vec<bool>>,
    dryrun: bool,
    keep_going: bool,
    /// What the startup gave up on when keeping going.
    failures: Vec<String>,
    phase: Option<ActionPhase>,
    level: u32,
    interrupted: Arc<AtomicBool>,
    progress: Option<Progress>,
}

/// Called with the phase and level each time the runner enters one.
pub type Progress = Box<dyn Fn(ActionPhase, u32) + Send>;

fn lock(d: &SharedDevice) -> MutexGuard<'_, PolyDriver> {
    d.lock()
}

impl RobotRunner {
    /// A runner that opens devices from the crate's registry.
    pub fn new(robot: Robot) -> Self {
        Self::with_factory(robot, Box::new(RegistryFactory))
    }

    pub fn with_factory(robot: Robot, factory: Box<dyn DeviceFactory>) -> Self {
        let slots = robot.devices.iter().map(|_| Slot::NotOpened).collect();
        let incomplete = Mutex::new(vec![false; robot.devices.len()]);
        RobotRunner {
            robot,
            factory,
            slots,
            incomplete,
            dryrun: false,
            keep_going: false,
            failures: Vec::new(),
            phase: None,
            level: 0,
            interrupted: Arc::new(AtomicBool::new(false)),
            progress: None,
        }
    }

    /// In a dry run nothing is opened or executed; targets are still checked.
    pub fn set_dryrun(&mut self, dryrun: bool) {
        self.dryrun = dryrun;
    }

    /// Keeps the startup going past devices that fail to open and actions that fail:
    /// each is reported by name (see [`RobotRunner::failures`]) and skipped together with
    /// whatever depends on it, and the startup phase succeeds with the rest.
    pub fn set_keep_going(&mut self, keep_going: bool) {
        self.keep_going = keep_going;
    }

    /// The devices and actions the startup gave up on (with keep-going), by name.
    pub fn failures(&self) -> &[String] {
        &self.failures
    }

    pub fn robot(&self) -> &Robot {
        &self.robot
    }

    /// The phase being run (or last run) and its level.
    pub fn current_phase(&self) -> Option<ActionPhase> {
        self.phase
    }

    pub fn current_level(&self) -> u32 {
        self.level
    }

    /// A flag that, once set (from a signal handler thread, say), stops the startup phase
    /// from starting further actions (C++ `Robot::interrupt`).
    pub fn interrupt_flag(&self) -> Arc<AtomicBool> {
        self.interrupted.clone()
    }

    /// Reports each phase and level as it starts (for a status port, say).
    pub fn set_progress(&mut self, progress: Progress) {
        self.progress = Some(progress);
    }

    fn enter(&mut self, phase: ActionPhase, level: u32) {
        self.phase = Some(phase);
        self.level = level;
        if let Some(p) = &self.progress {
            p(phase, level);
        }
    }

    /// Uses `flag` (shared with, say, a signal watcher) as the interrupt flag.
    pub fn set_interrupt_flag(&mut self, flag: Arc<AtomicBool>) {
        self.interrupted = flag;
    }

    /// The devices whose type is not in the registry, as `(name, type)`.
    pub fn unavailable_devices(&self) -> Vec<(&str, &str)> {
        self.robot
            .devices
            .iter()
            .filter(|d| !self.factory.knows(&d.kind))
            .map(|d| (d.name.as_str(), d.kind.as_str()))
            .collect()
    }

    /// The opened device called `name`.
    pub fn device(&self, name: &str) -> Option<SharedDevice> {
        let i = self.robot.devices.iter().position(|d| d.name == name)?;
        match &self.slots[i] {
            Slot::Open(d) => Some(d.clone()),
            _ => None,
        }
    }

    /// Runs `phase`: opens the devices first for `startup`, closes them last for
    /// `shutdown`. Problems do not stop the phase (as in C++); they are all returned.
    pub fn enter_phase(&mut self, phase: ActionPhase) -> Result<(), PhaseError> {
        tracing::info!("{phase} phase starting...");
        self.enter(phase, 0);
        let mut problems = Vec::new();

        if phase == ActionPhase::Startup {
            self.failures.clear();
            self.open_devices(&mut problems);
            if self.keep_going && !problems.is_empty() {
                tracing::warn!(
                    "{} device(s) failed to open; keeping going without them",
                    problems.len()
                );
                self.failures.append(&mut problems);
            }
            if !problems.is_empty() {
                tracing::error!("one or more devices failed opening; closing the others");
                self.close_devices();
                return Err(PhaseError { phase, problems });
            }
        }
        if phase == ActionPhase::Run {
            if !self.robot.levels(phase).is_empty() {
                tracing::warn!("phase run does not accept actions; skipping them");
            }
            return Ok(());
        }

        for level in self.robot.levels(phase) {
            if phase == ActionPhase::Startup && self.interrupted.load(Ordering::SeqCst) {
                problems.push("interrupted".to_string());
                break;
            }
            tracing::info!("Entering action level {level} of phase {phase}");
            self.enter(phase, level);
            self.run_level(phase, level, &mut problems);
            tracing::info!("All actions for action level {level} of {phase} phase finished.");
        }

        if phase == ActionPhase::Shutdown {
            self.close_devices();
        }
        if phase == ActionPhase::Startup && self.keep_going && !problems.is_empty() {
            let interrupted = problems.iter().any(|p| p == "interrupted");
            if !interrupted {
                for p in &problems {
                    tracing::warn!("kept going past: {p}");
                }
                self.failures.append(&mut problems);
            }
        }
        tracing::info!("{phase} phase finished.");
        if problems.is_empty() {
            Ok(())
        } else {
            Err(PhaseError { phase, problems })
        }
    }

    fn open_devices(&mut self, problems: &mut Vec<String>) {
        for (i, dev) in self.robot.devices.iter().enumerate() {
            if !self.factory.knows(&dev.kind) {
                if self.dryrun || self.keep_going {
                    tracing::warn!(
                        "device {} of type {} is not available in this build; skipping it",
                        dev.name,
                        dev.kind
                    );
                    self.slots[i] = Slot::Unavailable;
                } else {
                    // C++: PolyDriver's "Could not find device", then "Cannot open device"
                    tracing::warn!(
                        "Cannot open device {}: could not find device <{}> (not available in this build; --keep-going skips it)",
                        dev.name,
                        dev.kind
                    );
                    problems.push(format!(
                        "cannot open device {}: could not find device <{}> (not available in this build)",
                        dev.name, dev.kind
                    ));
                    self.slots[i] = Slot::Failed;
                }
                continue;
            }
            tracing::info!("Opening device {}", dev.name);
            if self.dryrun {
                continue;
            }
            let opened = dev
                .to_property()
                .map_err(|e: XmlError| e.to_string())
                .and_then(|cfg| self.factory.open(&cfg).map_err(|e| e.to_string()));
            match opened {
                Ok(pd) => self.slots[i] = Slot::Open(shared(pd)),
                Err(e) => {
                    tracing::warn!("Cannot open device {}: {e}", dev.name);
                    problems.push(format!("cannot open device {}: {e}", dev.name));
                    self.slots[i] = Slot::Failed;
                }
            }
        }
    }

    fn close_devices(&mut self) {
        self.incomplete.lock().fill(false);
        for (i, dev) in self.robot.devices.iter().enumerate().rev() {
            if let Slot::Open(d) = std::mem::replace(&mut self.slots[i], Slot::NotOpened) {
                tracing::info!("Closing device {}", dev.name);
                if let Err(e) = lock(&d).close() {
                    tracing::warn!("Cannot close device {}: {e}", dev.name);
                }
            }
        }
    }

    /// Runs one level: calibrate/park in threads, the rest inline, then joins.
    fn run_level(&self, phase: ActionPhase, level: u32, problems: &mut Vec<String>) {
        let actions = self.robot.actions(phase, level);
        std::thread::scope(|scope| {
            let mut running = Vec::new();
            for (i, action) in actions {
                let dev = &self.robot.devices[i];
                tracing::info!(
                    "Executing {} action, level {} on device {} with parameters {:?}",
                    action.kind,
                    action.level,
                    dev.name,
                    action
                        .params
                        .iter()
                        .map(|p| format!("{}={}", p.name, p.value))
                        .collect::<Vec<_>>()
                );
                let outcome = match action.kind {
                    ActionType::Calibrate | ActionType::Park => {
                        self.calibrator_job(i, action).map(|job| {
                            if let Some(job) = job {
                                running.push(scope.spawn(move || job.run()));
                            }
                        })
                    }
                    ActionType::Attach => self.attach(i, &action.params),
                    ActionType::Detach => self.detach(i, &action.params),
                    ActionType::Configure | ActionType::Abort | ActionType::Custom => {
                        tracing::info!("{} actions are not implemented (as in C++)", action.kind);
                        Ok(())
                    }
                };
                if let Err(e) = outcome {
                    if self.keep_going && action.kind == ActionType::Attach {
                        // a wrapper that could not attach serves nothing: skip what needs it
                        self.mark_incomplete(i);
                    }
                    tracing::error!(
                        "Cannot run {} action on device {}: {e}",
                        action.kind,
                        dev.name
                    );
                    problems.push(format!("{} {} ({}): {e}", action.kind, dev.name, action.at));
                }
            }
            for job in running {
                match job.join() {
                    Ok(Ok(())) => {}
                    Ok(Err(e)) => problems.push(e),
                    Err(_) => problems.push("a calibrator thread panicked".to_string()),
                }
            }
        });
    }

    /// The opened device `i`, or `None` (with a log line) when it was skipped.
    fn acting_device(&self, i: usize, what: ActionType) -> Option<SharedDevice> {
        match &self.slots[i] {
            Slot::Open(d) => Some(d.clone()),
            Slot::Unavailable => {
                let dev = &self.robot.devices[i];
                tracing::debug!(
                    "skipping {what} action of device {} (type {} is not available)",
                    dev.name,
                    dev.kind
                );
                None
            }
            Slot::Failed => {
                tracing::debug!(
                    "skipping {what} action of device {} (it failed to open)",
                    self.robot.devices[i].name
                );
                None
            }
            Slot::NotOpened => None,
        }
    }

    fn mark_incomplete(&self, i: usize) {
        self.incomplete.lock()[i] = true;
    }

    /// The device a target name refers to: an error when no device has that name,
    /// `None` when it exists but was skipped (or this is a dry run).
    fn target(&self, name: &str) -> Result<Option<SharedDevice>, String> {
        let Some(i) = self.robot.devices.iter().position(|d| d.name == name) else {
            return Err(format!("target device {name} does not exist"));
        };
        let incomplete = self.incomplete.lock()[i];
        match &self.slots[i] {
            Slot::Open(_) if incomplete => {
                tracing::debug!("target device {name} is incomplete; skipping the action");
                Ok(None)
            }
            Slot::Open(d) => Ok(Some(d.clone())),
            Slot::Unavailable => {
                tracing::debug!(
                    "target device {name} (type {}) is not available; skipping the action",
                    self.robot.devices[i].kind
                );
                Ok(None)
            }
            Slot::Failed => {
                tracing::warn!("target device {name} failed to open; skipping the action");
                Ok(None)
            }
            Slot::NotOpened => Ok(None),
        }
    }

    fn attach(&self, i: usize, params: &[Param]) -> Result<(), String> {
        let options = ["network", "networks", "all"];
        if options.iter().filter(|o| has_param(params, o)).count() > 1 {
            return Err(
                "you can have only one option: \"network\", \"networks\" or \"all\"".into(),
            );
        }
        // Resolve every target first so that a missing name is reported even in a dry run.
        let mut targets: Vec<(String, Option<SharedDevice>)> = Vec::new();
        if let Some(name) = find_param(params, "device") {
            let key = find_param(params, "network").unwrap_or("...");
            targets.push((key.to_string(), self.target(name)?));
        } else if has_param(params, "all") {
            for (j, d) in self.robot.devices.iter().enumerate() {
                if j != i {
                    targets.push(("all".to_string(), self.target(&d.name)?));
                }
            }
        } else if let Some(list) = find_param(params, "networks") {
            for key in network_names(list) {
                let name = find_param(params, &key).ok_or_else(|| {
                    format!("attach requires one parameter per network; \"{key}\" is missing")
                })?;
                let target = self.target(name)?;
                targets.push((key, target));
            }
        } else {
            return Err("attach requires either \"network\" or \"networks\" parameter".into());
        }
        let Some(device) = self.acting_device(i, ActionType::Attach) else {
            return Ok(());
        };
        if let Some((key, _)) = targets.iter().find(|(_, t)| t.is_none()) {
            // A target was skipped: leave this wrapper unattached, and skip what needs it.
            tracing::warn!(
                "device {} left unattached: its target for {key} is not available",
                self.robot.devices[i].name
            );
            self.mark_incomplete(i);
            return Ok(());
        }
        let targets: Vec<(String, SharedDevice)> = targets
            .into_iter()
            .filter_map(|(k, t)| t.map(|t| (k, t)))
            .collect();
        if targets.is_empty() {
            return Err("attach couldn't find any device".into());
        }
        if targets.iter().any(|(_, t)| Arc::ptr_eq(t, &device)) {
            return Err("a device cannot be attached to itself".into());
        }
        let mut pd = lock(&device);
        if targets.len() == 1 {
            if let Some(w) = pd.device().as_wrapper() {
                match w.attach(targets[0].1.clone()) {
                    Ok(()) => return Ok(()),
                    Err(e) if pd.device().as_multiple_wrapper().is_none() => {
                        return Err(e.to_string())
                    }
                    Err(e) => tracing::info!("IWrapper::attach failed ({e}); trying attach_all"),
                }
            }
        }
        match pd.device().as_multiple_wrapper() {
            Some(w) => w.attach_all(&targets).map_err(|e| e.to_string()),
            None => Err("the device is not a wrapper, it cannot have attach actions".into()),
        }
    }

    fn detach(&self, i: usize, params: &[Param]) -> Result<(), String> {
        if !params.is_empty() {
            tracing::warn!("detach actions cannot have parameters; ignoring them");
        }
        let Some(device) = self.acting_device(i, ActionType::Detach) else {
            return Ok(());
        };
        let mut pd = lock(&device);
        if let Some(w) = pd.device().as_multiple_wrapper() {
            match w.detach_all() {
                Ok(()) => return Ok(()),
                Err(e) if pd.device().as_wrapper().is_none() => return Err(e.to_string()),
                Err(e) => tracing::info!("detach_all failed ({e}); trying IWrapper::detach"),
            }
        }
        match pd.device().as_wrapper() {
            Some(w) => w.detach().map_err(|e| e.to_string()),
            None => Err("the device is neither a wrapper nor a multiple wrapper".into()),
        }
    }

    /// The work of a calibrate/park action, or `None` when it is skipped.
    fn calibrator_job(&self, i: usize, action: &Action) -> Result<Option<CalibratorJob>, String> {
        let name = find_param(&action.params, "target")
            .ok_or_else(|| format!("{} requires the \"target\" parameter", action.kind))?;
        let target = self.target(name)?;
        let Some(calibrator) = self.acting_device(i, action.kind) else {
            return Ok(None);
        };
        Ok(target.map(|target| CalibratorJob {
            kind: action.kind,
            calibrator,
            target,
            target_name: name.to_string(),
        }))
    }
}

/// The keys of an attach action's `networks` value, `(a b c)`.
fn network_names(list: &str) -> Vec<String> {
    let b = Bottle::from_text(list);
    let items: Vec<_> = match b.get(0).and_then(|v| v.as_list()) {
        Some(l) if b.len() == 1 => l.iter().cloned().collect(),
        _ => b.iter().cloned().collect(),
    };
    items.iter().map(Value::to_string_bare).collect()
}

/// A calibrate or park action, run on its own thread (C++ `CalibratorThread`).
struct CalibratorJob {
    kind: ActionType,
    calibrator: SharedDevice,
    target: SharedDevice,
    target_name: String,
}

impl CalibratorJob {
    fn run(self) -> Result<(), String> {
        let kind = self.kind;
        if kind == ActionType::Calibrate {
            self.offer_remote_calibration();
        }
        let mut pd = lock(&self.calibrator);
        let name = pd.name().to_string();
        let Some(c) = pd.device().as_calibrator() else {
            return Err(format!(
                "{name} is not a calibrator, it cannot have {kind} actions"
            ));
        };
        let result = match kind {
            ActionType::Park => c.park(self.target, true),
            _ => c.calibrate(self.target),
        };
        let failure = result
            .err()
            .map(|e| format!("{kind} of {} by {name} failed: {e}", self.target_name));
        match failure {
            // As C++ (CalibratorThread ignores the calibrator's result): the robot starts
            // and serves its parts; the part stays as the calibrator left it.
            Some(f) if kind == ActionType::Calibrate => {
                tracing::error!("{f}; the robot runs on");
                Ok(())
            }
            Some(f) => Err(f),
            None => Ok(()),
        }
    }

    /// As C++ `Device::calibrate`: when the calibrator offers `IRemoteCalibrator` and the
    /// target forwards to one, the target's clients may then ask the calibrator to
    /// calibrate, home or park (`[set] [reca] …` on the part's `rpc:i`). Otherwise that
    /// is only logged: the robot runs without remote calibration.
    fn offer_remote_calibration(&self) {
        let remotable = lock(&self.calibrator)
            .device()
            .as_remote_calibrator()
            .is_some();
        if !remotable {
            tracing::debug!(target_device = %self.target_name,
                "the calibrator has no IRemoteCalibrator: no remote calibration or homing");
            return;
        }
        let mut target = lock(&self.target);
        let set = match target.device().as_remote_calibrator() {
            Some(rc) => rc.set_calibrator_device(Some(self.calibrator.clone())),
            None => Err(DeviceError::Unsupported(
                "the target has no IRemoteCalibrator",
            )),
        };
        if let Err(e) = set {
            tracing::warn!(target_device = %self.target_name,
                "no remote calibration or homing through this target: {e}");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn network_lists() {
        assert_eq!(network_names("(a b)"), ["a", "b"]);
        assert_eq!(network_names("a b"), ["a", "b"]);
        assert!(network_names("()").is_empty());
    }
}
