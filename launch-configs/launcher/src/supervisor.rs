//! Starting, supervising and stopping the modules of a launch config.
//!
//! Each module runs in its own task: it waits for the modules it comes `after` to be
//! ready (and for its `wait_ports`), starts the program, runs its readiness check,
//! and applies the restart policy when the program exits. [`Launcher::shutdown`] stops
//! modules one by one in reverse start order, the embedded name server last.

use crate::config::{LaunchConfig, Module, Readiness, RestartPolicy};
use crate::connections::{self, SharedConns};
use crate::process::{self, LogTail, Running, Spawn};
use crate::programs;
use crate::readiness;
use crate::say;
use serde::Serialize;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio::sync::watch;
use tokio::task::JoinHandle;
use yarp_net::nameserver::NameClient;
use yarp_net::network;

/// Name of the module the launcher adds for an embedded name server.
pub const NAME_SERVER_MODULE: &str = "yarpserver";

#[derive(Debug, thiserror::Error)]
pub enum LaunchError {
    #[error(transparent)]
    Program(#[from] programs::NotFound),
    #[error("cannot write yarp.conf: {0}")]
    Conf(std::io::Error),
    #[error("no name server answers at {0} and the config does not allow starting one (name_server.embedded = false)")]
    NoNameServer(SocketAddr),
    #[error("the embedded name server did not answer at {addr} within {secs} s")]
    NameServerTimeout { addr: SocketAddr, secs: f64 },
    #[error("the embedded name server could not start: {0}")]
    NameServerFailed(String),
    #[error("{0}")]
    Address(String),
    #[error("module {module}: working directory {path} does not exist")]
    NoCwd { module: String, path: PathBuf },
}

/// Where a module is in its life.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(tag = "state", rename_all = "kebab-case")]
pub enum ModState {
    /// Waiting for its dependencies.
    Waiting {
        on: String,
    },
    /// Started, readiness check not passed yet.
    Starting {
        pid: i32,
    },
    Ready {
        pid: i32,
    },
    /// Exited by itself (code or signal); may be restarted.
    Exited {
        code: Option<i32>,
        signal: Option<i32>,
    },
    /// Could not be started, or given up.
    Failed {
        reason: String,
    },
    /// Stopped by the launcher.
    Stopped,
    /// `enabled = false` in the config.
    Disabled,
}

/// A module as the supervisor sees it.
#[derive(Debug)]
pub struct ModuleHandle {
    pub spec: Module,
    pub program: PathBuf,
    pub log: LogTail,
    state: watch::Sender<ModState>,
    restarts: AtomicU32,
    stop: watch::Sender<bool>,
    ready_after: parking_lot::Mutex<Option<Duration>>,
}

impl ModuleHandle {
    fn new(spec: Module, program: PathBuf) -> Arc<ModuleHandle> {
        let initial = if spec.enabled {
            ModState::Waiting { on: String::new() }
        } else {
            ModState::Disabled
        };
        Arc::new(ModuleHandle {
            spec,
            program,
            log: LogTail::default(),
            state: watch::channel(initial).0,
            restarts: AtomicU32::new(0),
            stop: watch::channel(false).0,
            ready_after: parking_lot::Mutex::new(None),
        })
    }

    pub fn state(&self) -> ModState {
        self.state.borrow().clone()
    }

    pub fn restarts(&self) -> u32 {
        self.restarts.load(Ordering::Relaxed)
    }

    /// Time from launch to this module's first readiness.
    pub fn ready_after(&self) -> Option<Duration> {
        *self.ready_after.lock()
    }

    fn set(&self, s: ModState) {
        self.state.send_replace(s);
    }

    fn stopping(&self) -> bool {
        *self.stop.borrow()
    }

    /// Resolves when this module is ready (never, if it never becomes ready).
    async fn wait_ready(&self) {
        let mut rx = self.state.subscribe();
        let _ = rx.wait_for(|s| matches!(s, ModState::Ready { .. })).await;
    }

    /// Ready, or finished its work (a one-shot module that exited with status 0).
    fn is_up_or_done(&self) -> bool {
        matches!(
            self.state(),
            ModState::Ready { .. } | ModState::Exited { code: Some(0), .. }
        )
    }

    /// Resolves when [`ModuleHandle::is_up_or_done`] holds.
    async fn wait_up_or_done(&self) {
        let mut rx = self.state.subscribe();
        let _ = rx
            .wait_for(|s| {
                matches!(
                    s,
                    ModState::Ready { .. } | ModState::Exited { code: Some(0), .. }
                )
            })
            .await;
    }
}

/// A module's status for the dashboard and `--status` output.
#[derive(Debug, Clone, Serialize)]
pub struct ModuleStatus {
    pub name: String,
    pub program: String,
    pub args: Vec<String>,
    #[serde(flatten)]
    pub state: ModState,
    pub restarts: u32,
    pub ready_after_ms: Option<u64>,
    pub log_tail: Vec<String>,
}

/// Everything the launcher knows, as served on the dashboard's `/api/status`.
#[derive(Debug, Clone, Serialize)]
pub struct Status {
    pub name: String,
    pub name_server: String,
    pub uptime_s: f64,
    pub modules: Vec<ModuleStatus>,
    pub connections: Vec<connections::ConnState>,
}

/// A running launch: modules, connections, the name server.
pub struct Launcher {
    cfg: LaunchConfig,
    ns_addr: SocketAddr,
    ns: NameClient,
    /// In start order, the embedded name server (if any) first.
    modules: Vec<Arc<ModuleHandle>>,
    tasks: Vec<(Arc<ModuleHandle>, JoinHandle<()>)>,
    conns: SharedConns,
    conn_stop: watch::Sender<bool>,
    conn_task: Option<JoinHandle<()>>,
    started: Instant,
}

impl Launcher {
    /// Checks the config against this machine (every program found) without starting anything.
    pub fn new(cfg: LaunchConfig) -> Result<Launcher, LaunchError> {
        let ns_addr =
            crate::plan::parse_address(&cfg.name_server.address).map_err(LaunchError::Address)?;
        let mut modules = Vec::new();
        for m in cfg.enabled_modules() {
            let program = programs::resolve(&m.program, &cfg.base_dir)?;
            let mut m = m.clone();
            // Working directories are relative to the config file's directory.
            m.cwd = m.cwd.map(|c| cfg.base_dir.join(c).display().to_string());
            if let Some(c) = &m.cwd {
                if !std::path::Path::new(c).is_dir() {
                    return Err(LaunchError::NoCwd {
                        module: m.name.clone(),
                        path: PathBuf::from(c),
                    });
                }
            }
            modules.push(ModuleHandle::new(m, program));
        }
        for m in cfg.modules.iter().filter(|m| !m.enabled) {
            modules.push(ModuleHandle::new(m.clone(), PathBuf::from(&m.program)));
        }
        let conns = connections::shared(&cfg.connections);
        Ok(Launcher {
            ns: NameClient::new(ns_addr).with_timeout(Duration::from_secs(2)),
            ns_addr,
            cfg,
            modules,
            tasks: Vec::new(),
            conns,
            conn_stop: watch::channel(false).0,
            conn_task: None,
            started: Instant::now(),
        })
    }

    pub fn config(&self) -> &LaunchConfig {
        &self.cfg
    }

    pub fn name_server(&self) -> SocketAddr {
        self.ns_addr
    }

    pub fn name_client(&self) -> &NameClient {
        &self.ns
    }

    /// Whether a name server answers at the configured address.
    pub async fn name_server_answers(&self) -> bool {
        let probe = NameClient::new(self.ns_addr).with_timeout(Duration::from_secs(1));
        matches!(
            tokio::time::timeout(Duration::from_secs(2), probe.list(None)).await,
            Ok(Ok(_))
        )
    }

    /// Makes sure a name server runs (starting `yarpserver` if allowed), then starts
    /// every module task and the connection keeper. Returns once everything is launched;
    /// modules come up in the background (see [`Launcher::wait_ready`]).
    pub async fn start(&mut self) -> Result<(), LaunchError> {
        self.started = Instant::now();
        let ns = &self.cfg.name_server;
        if ns.write_conf {
            let (host, port) = (self.ns_addr.ip().to_string(), self.ns_addr.port());
            // Say so when this replaces another address: the user's other YARP programs
            // will follow it.
            if let Ok(old) = network::read_conf() {
                if old.host != host || old.port != i32::from(port) {
                    say(&format!(
                        "yarp.conf named the name server {}:{}; it now names {}",
                        old.host, old.port, self.ns_addr
                    ));
                }
            }
            let path = network::write_conf(&host, port).map_err(LaunchError::Conf)?;
            say(&format!(
                "name server address {} written to {}",
                self.ns_addr,
                path.display()
            ));
        }
        if self.name_server_answers().await {
            say(&format!(
                "using the name server already running at {}",
                self.ns_addr
            ));
        } else if !ns.embedded {
            return Err(LaunchError::NoNameServer(self.ns_addr));
        } else {
            self.start_name_server().await?;
        }
        let handles: Vec<Arc<ModuleHandle>> = self
            .modules
            .iter()
            .filter(|m| m.spec.enabled && m.spec.name != NAME_SERVER_MODULE)
            .cloned()
            .collect();
        for h in handles {
            let deps: Vec<Arc<ModuleHandle>> = h
                .spec
                .after
                .iter()
                .filter_map(|a| self.modules.iter().find(|m| &m.spec.name == a).cloned())
                // a disabled module is never ready: nothing waits for it
                .filter(|d| d.spec.enabled)
                .collect();
            let task = tokio::spawn(supervise(h.clone(), deps, self.ns.clone(), self.started));
            self.tasks.push((h, task));
        }
        self.conn_task = Some(tokio::spawn(connections::maintain(
            self.ns.clone(),
            self.conns.clone(),
            Duration::from_millis(500),
            self.conn_stop.subscribe(),
        )));
        Ok(())
    }

    async fn start_name_server(&mut self) -> Result<(), LaunchError> {
        let mut m = Module::new(
            NAME_SERVER_MODULE,
            "yarpserver",
            &[
                "--ip",
                &self.ns_addr.ip().to_string(),
                "--socket",
                &self.ns_addr.port().to_string(),
                "--silent",
            ],
        );
        if !self.cfg.name_server.write_conf {
            m.args.push("--local".into());
        }
        // a name server that dies is started again on the same address: our ports register
        // again by themselves (yarp-net's REGISTRATION_CHECK) and the connections are kept
        m.restart = RestartPolicy::OnFailure;
        m.max_restarts = 0;
        m.ready = Some(Readiness {
            port: None,
            tcp: Some(self.ns_addr.to_string()),
            log: None,
            delay: None,
            timeout: self.cfg.name_server.timeout,
        });
        let program = programs::resolve("yarpserver", &self.cfg.base_dir)?;
        say(&format!(
            "no name server at {}: starting {}",
            self.ns_addr,
            program.display()
        ));
        let h = ModuleHandle::new(m, program);
        self.modules.insert(0, h.clone());
        let task = tokio::spawn(supervise(
            h.clone(),
            Vec::new(),
            self.ns.clone(),
            self.started,
        ));
        self.tasks.insert(0, (h.clone(), task));
        let secs = self.cfg.name_server.timeout;
        let mut rx = h.state.subscribe();
        let outcome = tokio::time::timeout(
            Duration::from_secs_f64(secs),
            rx.wait_for(|s| {
                matches!(
                    s,
                    ModState::Ready { .. } | ModState::Failed { .. } | ModState::Exited { .. }
                )
            }),
        )
        .await;
        let state = h.state();
        match (outcome, state) {
            (Ok(_), ModState::Ready { .. }) => {}
            (Ok(_), other) => {
                return Err(LaunchError::NameServerFailed(format!(
                    "{other:?}; its output: {}",
                    h.log.lines().join(" | ")
                )))
            }
            (Err(_), _) => {
                return Err(LaunchError::NameServerTimeout {
                    addr: self.ns_addr,
                    secs,
                })
            }
        }
        // The port may listen a moment before the server answers requests.
        let deadline = Instant::now() + Duration::from_secs_f64(secs);
        while !self.name_server_answers().await {
            if Instant::now() > deadline {
                return Err(LaunchError::NameServerTimeout {
                    addr: self.ns_addr,
                    secs,
                });
            }
            tokio::time::sleep(readiness::POLL).await;
        }
        Ok(())
    }

    /// Waits up to `limit` for every enabled module to be ready; returns the names of
    /// those that are not.
    pub async fn wait_ready(&self, limit: Duration) -> Vec<String> {
        let all = async {
            for m in self.modules.iter().filter(|m| m.spec.enabled) {
                m.wait_up_or_done().await;
            }
        };
        let _ = tokio::time::timeout(limit, all).await;
        self.not_ready()
    }

    fn not_ready(&self) -> Vec<String> {
        self.modules
            .iter()
            .filter(|m| m.spec.enabled && !m.is_up_or_done())
            .map(|m| m.spec.name.clone())
            .collect()
    }

    /// Waits up to `limit` for every configured connection to be made.
    pub async fn wait_connected(&self, limit: Duration) -> bool {
        let deadline = Instant::now() + limit;
        loop {
            let done = self.conns.lock().iter().all(|c| c.connected);
            if done {
                return true;
            }
            if Instant::now() > deadline {
                return false;
            }
            tokio::time::sleep(Duration::from_millis(100)).await;
        }
    }

    /// A snapshot for the dashboard.
    pub fn status(&self) -> Status {
        status_of(
            &self.cfg.name,
            self.ns_addr,
            self.started,
            &self.modules,
            &self.conns,
        )
    }

    /// A cheap handle that can take [`Status`] snapshots after the launcher moved.
    pub fn status_source(&self) -> StatusSource {
        StatusSource {
            name: self.cfg.name.clone(),
            ns: self.ns_addr,
            started: self.started,
            modules: self.modules.clone(),
            conns: self.conns.clone(),
        }
    }

    /// Stops everything in reverse start order, each module with SIGINT, SIGTERM, then
    /// SIGKILL (each step bounded by its `stop_timeout`).
    pub async fn shutdown(mut self) {
        self.conn_stop.send_replace(true);
        if let Some(t) = self.conn_task.take() {
            let _ = tokio::time::timeout(Duration::from_secs(5), t).await;
        }
        while let Some((h, task)) = self.tasks.pop() {
            h.stop.send_replace(true);
            let limit = h.spec.stop_timeout() * 4 + Duration::from_secs(1);
            if tokio::time::timeout(limit, task).await.is_err() {
                say(&format!(
                    "{}: supervisor did not finish in {limit:?}",
                    h.spec.name
                ));
            }
        }
    }
}

/// Takes [`Status`] snapshots (shared with the dashboard).
#[derive(Clone)]
pub struct StatusSource {
    name: String,
    ns: SocketAddr,
    started: Instant,
    modules: Vec<Arc<ModuleHandle>>,
    conns: SharedConns,
}

impl StatusSource {
    pub fn status(&self) -> Status {
        status_of(
            &self.name,
            self.ns,
            self.started,
            &self.modules,
            &self.conns,
        )
    }

    pub fn name_server(&self) -> SocketAddr {
        self.ns
    }
}

fn status_of(
    name: &str,
    ns: SocketAddr,
    started: Instant,
    modules: &[Arc<ModuleHandle>],
    conns: &SharedConns,
) -> Status {
    Status {
        name: name.to_string(),
        name_server: ns.to_string(),
        uptime_s: started.elapsed().as_secs_f64(),
        modules: modules
            .iter()
            .map(|m| {
                let tail = m.log.lines();
                ModuleStatus {
                    name: m.spec.name.clone(),
                    program: m.program.display().to_string(),
                    args: m.spec.args.clone(),
                    state: m.state(),
                    restarts: m.restarts(),
                    ready_after_ms: m.ready_after().map(|d| d.as_millis() as u64),
                    log_tail: tail[tail.len().saturating_sub(20)..].to_vec(),
                }
            })
            .collect(),
        connections: conns.lock().clone(),
    }
}

/// How a run of the program ended.
enum RunEnd {
    Exited(std::process::ExitStatus),
    NotReady,
    Stopped,
}

/// The life of one module (see the module docs).
async fn supervise(
    h: Arc<ModuleHandle>,
    deps: Vec<Arc<ModuleHandle>>,
    ns: NameClient,
    launched: Instant,
) {
    let mut stop = h.stop.subscribe();
    let name = h.spec.name.clone();
    // Dependencies and ports first; the stop request interrupts the wait.
    let wait = async {
        for d in &deps {
            h.set(ModState::Waiting {
                on: format!("module {}", d.spec.name),
            });
            d.wait_ready().await;
        }
        if !h.spec.wait_ports.is_empty() {
            h.set(ModState::Waiting {
                on: format!("ports {}", h.spec.wait_ports.join(" ")),
            });
            readiness::wait_ports(&ns, &h.spec.wait_ports).await;
        }
    };
    tokio::select! {
        _ = wait => {}
        _ = crate::stopped(&mut stop) => {
            h.set(ModState::Stopped);
            return;
        }
    }
    let env: Vec<(String, String)> = h
        .spec
        .env
        .iter()
        .map(|(k, v)| (k.clone(), v.clone()))
        .collect();
    let cwd = h.spec.cwd.as_ref().map(PathBuf::from);
    let check = h.spec.ready.as_ref().map(|r| (r.check().ok(), r.timeout()));
    let mut attempt: u32 = 0;
    loop {
        let mut logs = h.log.subscribe();
        let spawned = process::spawn(
            &Spawn {
                name: &name,
                program: &h.program,
                args: &h.spec.args,
                env: &env,
                cwd: cwd.as_deref(),
            },
            &h.log,
        );
        let mut run: Running = match spawned {
            Ok(r) => r,
            Err(e) => {
                let reason = format!("cannot start {}: {e}", h.program.display());
                say(&format!("{name}: {reason}"));
                h.set(ModState::Failed { reason });
                return;
            }
        };
        say(&format!("{name}: started (pid {})", run.pid));
        h.set(ModState::Starting { pid: run.pid });
        let end = run_once(&h, &mut run, &check, &ns, &mut logs, &mut stop, launched).await;
        let status = match end {
            RunEnd::Stopped => {
                let (st, how) = process::stop(&mut run, h.spec.stop_timeout()).await;
                let what = st
                    .map(|s| describe_exit(&s))
                    .unwrap_or_else(|| "did not exit".into());
                h.set(ModState::Stopped);
                say(&format!("{name}: stopped ({how}; {what})"));
                return;
            }
            RunEnd::NotReady => {
                say(&format!(
                    "{name}: not ready within {:?}; stopping it",
                    check.as_ref().map(|c| c.1).unwrap_or_default()
                ));
                let (st, _) = process::stop(&mut run, h.spec.stop_timeout()).await;
                h.set(ModState::Failed {
                    reason: "readiness check timed out".into(),
                });
                st
            }
            RunEnd::Exited(st) => {
                process::reap_group(run.pid, Duration::from_millis(500)).await;
                h.set(ModState::Exited {
                    code: st.code(),
                    signal: std::os::unix::process::ExitStatusExt::signal(&st),
                });
                say(&format!("{name}: exited ({})", describe_exit(&st)));
                Some(st)
            }
        };
        let failed = !matches!(end, RunEnd::Exited(_)) || !status.is_some_and(|s| s.success());
        let again = match h.spec.restart {
            RestartPolicy::Never => false,
            RestartPolicy::OnFailure => failed,
            RestartPolicy::Always => true,
        };
        if !again || h.stopping() {
            return;
        }
        attempt += 1;
        if h.spec.max_restarts != 0 && attempt > h.spec.max_restarts {
            let reason = format!("gave up after {} restarts", h.spec.max_restarts);
            h.set(ModState::Failed {
                reason: reason.clone(),
            });
            say(&format!("{name}: {reason}"));
            return;
        }
        let backoff =
            Duration::from_millis(250 * (1u64 << attempt.min(6))).min(Duration::from_secs(10));
        say(&format!(
            "{name}: restarting in {backoff:?} (restart {attempt})"
        ));
        tokio::select! {
            _ = tokio::time::sleep(backoff) => {}
            _ = crate::stopped(&mut stop) => {
                h.set(ModState::Stopped);
                return;
            }
        }
        h.restarts.fetch_add(1, Ordering::Relaxed);
    }
}

/// Runs one start of the program until it exits, fails its readiness check, or a stop
/// is requested.
async fn run_once(
    h: &ModuleHandle,
    run: &mut Running,
    check: &Option<(Option<crate::config::ReadyCheck>, Duration)>,
    ns: &NameClient,
    logs: &mut tokio::sync::broadcast::Receiver<String>,
    stop: &mut watch::Receiver<bool>,
    launched: Instant,
) -> RunEnd {
    let pid = run.pid;
    let ready = async {
        match check {
            Some((Some(c), limit)) => {
                tokio::time::timeout(*limit, readiness::wait_until(c, ns, logs))
                    .await
                    .is_ok()
            }
            _ => true,
        }
    };
    tokio::select! {
        ok = ready => {
            if !ok {
                return RunEnd::NotReady;
            }
            let mut first = h.ready_after.lock();
            if first.is_none() {
                *first = Some(launched.elapsed());
            }
            drop(first);
            h.set(ModState::Ready { pid });
        }
        st = run.child.wait() => {
            return match st {
                Ok(st) => RunEnd::Exited(st),
                Err(_) => RunEnd::Stopped,
            };
        }
        _ = crate::stopped(stop) => return RunEnd::Stopped,
    }
    tokio::select! {
        st = run.child.wait() => match st {
            Ok(st) => RunEnd::Exited(st),
            Err(_) => RunEnd::Stopped,
        },
        _ = crate::stopped(stop) => RunEnd::Stopped,
    }
}

fn describe_exit(st: &std::process::ExitStatus) -> String {
    use std::os::unix::process::ExitStatusExt;
    match (st.code(), st.signal()) {
        (Some(c), _) => format!("status {c}"),
        (None, Some(s)) => format!("signal {s}"),
        _ => "unknown status".into(),
    }
}
