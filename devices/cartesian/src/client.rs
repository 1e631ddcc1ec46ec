//! `cartesiancontrollerclient` (icub-main's `ClientCartesianController`): a Cartesian
//! controller server reached over the network, as [`ICartesianControl`].
//!
//! Ports `<local>/rpc:o`, `<local>/command:o`, `<local>/state:i` and `<local>/events:i`;
//! opening connects the RPC first, checks the server's `server_version` (`[get] [info]`),
//! connects the streams with `carrier`, and requires the server to have its solver
//! (`[get] [ison]`), as C++ does. `getPose` reads the state stream and fails once its
//! last message is older than `timeout`; the rest goes through `rpc:i`.

use parking_lot::Mutex;
use std::collections::BTreeSet;
use std::sync::Arc;
use std::time::{Duration, Instant};
use yarp_devices::cartesian_control::{CartesianEvent, ICartesianControl, Pose, Solved};
use yarp_devices::driver::DeviceDriver;
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::{nwc_ports, runtime};
use yarp_net::port::Port;
use yarp_proto::{Bottle, Property, Value};

use crate::protocol::{self, word};
use crate::server::SERVER_VERSION;

/// The C++ device name.
pub const NAME: &str = "cartesiancontrollerclient";

/// How long a call waits for the server (a sync go waits for the solver as well).
const RPC_TIMEOUT: Duration = Duration::from_secs(10);

yarp_devices::device_params! {
    /// What `cartesiancontrollerclient` reads (icub-main's `ClientCartesianController`).
    pub struct CartesianControllerClientParams for "cartesiancontrollerclient" {
        /// Prefix of the client's ports
        "local" local: String = required,
        /// Prefix of the server's ports (its ControllerName)
        "remote" remote: String = required,
        /// Carrier of the streaming connections
        "carrier" carrier: String = "udp",
        /// Age after which the state stream counts as lost
        "timeout" timeout: f64 = 0.1; "s"; check yarp_devices::params::positive,
    }
}

/// The latest pose of the state stream: pose, its envelope time, when it came.
type Latest = Arc<Mutex<Option<([f64; 7], f64, Instant)>>>;

struct Link {
    remote: String,
    rpc: Arc<Port>,
    command: Arc<Port>,
    state: Arc<Port>,
    events: Arc<Port>,
    tasks: Vec<tokio::task::JoinHandle<()>>,
    latest: Latest,
    received: Arc<Mutex<Vec<CartesianEvent>>>,
    contexts: BTreeSet<i32>,
    timeout: Duration,
}

/// `cartesiancontrollerclient`.
#[derive(Default)]
pub struct CartesianControllerClient {
    link: Option<Link>,
}

impl CartesianControllerClient {
    pub fn new() -> Self {
        Self::default()
    }

    fn link(&mut self) -> DevResult<&mut Link> {
        self.link.as_mut().ok_or(DeviceError::NotOpen)
    }

    fn call_within(&mut self, cmd: Bottle, timeout: Duration) -> DevResult<Bottle> {
        let link = self.link()?;
        nwc_ports::call_within(&link.remote, &link.rpc, cmd, timeout)
    }

    fn call(&mut self, cmd: Bottle) -> DevResult<Bottle> {
        self.call_within(cmd, RPC_TIMEOUT)
    }

    /// A call whose reply must start with `[ack]`.
    fn ack(&mut self, cmd: Bottle) -> DevResult<Bottle> {
        let text = cmd.to_string();
        let reply = self.call(cmd)?;
        if protocol::is_ack(&reply) {
            Ok(reply)
        } else {
            Err(DeviceError::failed(
                NAME,
                format!("`{text}` answered `{reply}`"),
            ))
        }
    }

    fn get(&mut self, opt: &str) -> DevResult<Bottle> {
        self.ack(words(&[word::GET, opt]))
    }

    fn set(&mut self, opt: &str, value: impl Into<Value>) -> DevResult<Bottle> {
        self.ack(words(&[word::SET, opt]).with(value))
    }

    fn stream(&mut self, b: Bottle) -> DevResult<()> {
        let port = self.link()?.command.clone();
        runtime::block_on_logged("cartesiancontrollerclient: command", async move {
            port.write_strict(&b, None).await;
        });
        Ok(())
    }

    fn truth_at(reply: &Bottle, i: usize) -> DevResult<bool> {
        match protocol::word_at(reply, i).as_deref() {
            Some(word::TRUE) => Ok(true),
            Some(word::FALSE) => Ok(false),
            _ => Err(DeviceError::failed(
                NAME,
                format!("unexpected reply `{reply}`"),
            )),
        }
    }
}

fn words(w: &[&str]) -> Bottle {
    w.iter().map(|w| Value::vocab(w)).collect()
}

fn pose7(x: &[f64; 3], o: &[f64; 4]) -> Vec<f64> {
    x.iter().chain(o.iter()).copied().collect()
}

fn split7(v: &[f64]) -> DevResult<Pose> {
    if v.len() < 7 {
        return Err(DeviceError::WrongSize {
            expected: 7,
            got: v.len(),
        });
    }
    Ok(([v[0], v[1], v[2]], [v[3], v[4], v[5], v[6]]))
}

fn list_at(reply: &Bottle, i: usize) -> DevResult<Vec<f64>> {
    reply
        .get(i)
        .and_then(protocol::numbers)
        .ok_or_else(|| DeviceError::failed(NAME, format!("no list in `{reply}`")))
}

fn number_at(reply: &Bottle, i: usize) -> DevResult<f64> {
    reply
        .get(i)
        .and_then(Value::as_f64)
        .ok_or_else(|| DeviceError::failed(NAME, format!("no number in `{reply}`")))
}

async fn read_state(port: Arc<Port>, latest: Latest) {
    while let Some(msg) = port.read().await {
        let Ok(b) = msg.bottle() else { continue };
        let Some(v) = b.iter().map(Value::as_f64).collect::<Option<Vec<f64>>>() else {
            continue;
        };
        if v.len() >= 7 {
            let mut x = [0.0; 7];
            x.copy_from_slice(&v[..7]);
            let t = msg.stamp.map_or(0.0, |s| s.time);
            *latest.lock() = Some((x, t, Instant::now()));
        }
    }
}

/// Collects an `events:o` stream (the Cartesian and gaze servers' alike).
pub(crate) async fn read_events(port: Arc<Port>, received: Arc<Mutex<Vec<CartesianEvent>>>) {
    while let Some(msg) = port.read().await {
        let Ok(b) = msg.bottle() else { continue };
        let Some(kind) = b.get(0).and_then(Value::as_str).map(str::to_string) else {
            continue;
        };
        let checkpoint = (kind == "motion-ongoing")
            .then(|| b.get(2).and_then(Value::as_f64))
            .flatten();
        let mut q = received.lock();
        q.push(CartesianEvent {
            kind,
            time: b.get(1).and_then(Value::as_f64).unwrap_or(0.0),
            checkpoint,
        });
        // nobody reading: keep the latest thousand
        if q.len() > 1000 {
            q.remove(0);
        }
    }
}

impl DeviceDriver for CartesianControllerClient {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        CartesianControllerClientParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = CartesianControllerClientParams::read(config)?;
        self.close()?;
        let refused = |why: String| DeviceError::BadParam {
            device: NAME.into(),
            param: "remote".into(),
            expected: "the prefix of a running cartesiancontrollerserver",
            got: why,
        };
        let ns = yarp_net::network::name_client().map_err(|e| refused(e.to_string()))?;
        let (local, remote, carrier) = (p.local.clone(), p.remote.clone(), p.carrier.clone());
        let ports = runtime::block_on_result(async move {
            let mut ports = Vec::new();
            for suffix in ["rpc:o", "command:o", "state:i", "events:i"] {
                let name = format!("{local}/{suffix}");
                match Port::open(&name, ns.clone()).await {
                    Ok(port) => ports.push(Arc::new(port)),
                    Err(e) => {
                        close_all(ports).await;
                        return Err(format!("{name}: {e}"));
                    }
                }
            }
            let rpc_i = format!("{remote}/rpc:i");
            if let Err(e) = ports[0].connect(&rpc_i, None).await {
                close_all(ports).await;
                return Err(format!("cannot connect to {rpc_i}: {e}"));
            }
            Ok(ports)
        })
        .map_err(refused)?;
        let mut it = ports.into_iter();
        let mut next = || it.next().expect("four ports");
        let (rpc, command, state, events) = (next(), next(), next(), next());
        let latest: Latest = Arc::default();
        let received: Arc<Mutex<Vec<CartesianEvent>>> = Arc::default();
        let rt = runtime::handle();
        let tasks = vec![
            rt.spawn(read_state(state.clone(), latest.clone())),
            rt.spawn(read_events(events.clone(), received.clone())),
        ];
        self.link = Some(Link {
            remote: p.remote.clone(),
            rpc,
            command,
            state,
            events,
            tasks,
            latest,
            received,
            contexts: BTreeSet::new(),
            timeout: Duration::from_secs_f64(p.timeout),
        });
        let result = self.handshake(&p.remote, &carrier);
        if result.is_err() {
            let _ = self.close();
        }
        result
    }

    fn close(&mut self) -> DevResult<()> {
        if let Some(link) = self.link.as_ref() {
            // the contexts this client stored go with it, as C++'s close
            let ids: Vec<i32> = link.contexts.iter().copied().collect();
            let _ = self.call_within(
                words(&[word::DELETE]).with(protocol::i32_list(ids)),
                Duration::from_secs(1),
            );
        }
        if let Some(link) = self.link.take() {
            for t in &link.tasks {
                t.abort();
            }
            let ports = vec![link.rpc, link.command, link.state, link.events];
            let tasks = link.tasks;
            runtime::block_on_logged("cartesiancontrollerclient: closing", async move {
                for t in tasks {
                    let _ = t.await;
                }
                close_all(ports).await;
            });
        }
        Ok(())
    }

    yarp_devices::views!(as_cartesian_control);
}

/// Closes ports no task holds any more.
pub(crate) async fn close_all(ports: Vec<Arc<Port>>) {
    for p in ports {
        if let Ok(p) = Arc::try_unwrap(p) {
            p.close().await;
        }
    }
}

impl CartesianControllerClient {
    /// C++'s open after the RPC connection: the version, the streams, the solver.
    fn handshake(&mut self, remote: &str, carrier: &str) -> DevResult<()> {
        let info = self.get(word::INFO)?;
        let version = info
            .get(1)
            .and_then(Value::as_list)
            .and_then(|l| l.find("server_version"))
            .and_then(|v| v.as_str().map(str::to_string));
        match version {
            Some(v) if v != SERVER_VERSION => {
                return Err(DeviceError::failed(
                    NAME,
                    format!(
                        "server version {v} not compatible with this client's {SERVER_VERSION}"
                    ),
                ))
            }
            None => tracing::warn!("{NAME}: {remote} did not say its server_version"),
            _ => {}
        }
        let link = self.link()?;
        let (command, state, events) = (
            link.command.clone(),
            link.state.name().to_string(),
            link.events.name().to_string(),
        );
        let (remote, carrier) = (remote.to_string(), carrier.to_string());
        let connected = runtime::block_on_result(async move {
            let ns = yarp_net::network::name_client().map_err(|e| e.to_string())?;
            command
                .connect(&format!("{remote}/command:i"), Some(&carrier))
                .await
                .map_err(|e| e.to_string())?;
            for (from, to) in [("state:o", state), ("events:o", events)] {
                let from = format!("{remote}/{from}");
                let (ok, why) = yarp_net::network::connect(&ns, &from, &to, Some(&carrier))
                    .await
                    .map_err(|e| e.to_string())?;
                if !ok {
                    return Err(format!("{from} -> {to}: {why}"));
                }
            }
            Ok::<_, String>(())
        });
        connected.map_err(|e| DeviceError::failed(NAME, e))?;
        let ison = self.get(word::IS_SOLVER_ON)?;
        if !Self::truth_at(&ison, 1)? {
            return Err(DeviceError::failed(
                NAME,
                "unable to connect to solver: the server has none",
            ));
        }
        Ok(())
    }
}

impl ICartesianControl for CartesianControllerClient {
    fn set_tracking_mode(&mut self, on: bool) -> DevResult<()> {
        let mode = if on { word::TRACK } else { word::SINGLE };
        self.set(word::MODE, Value::vocab(mode)).map(drop)
    }

    fn get_tracking_mode(&mut self) -> DevResult<bool> {
        let r = self.get(word::MODE)?;
        match protocol::word_at(&r, 1).as_deref() {
            Some(word::TRACK) => Ok(true),
            Some(word::SINGLE) => Ok(false),
            _ => Err(DeviceError::failed(NAME, format!("unexpected reply `{r}`"))),
        }
    }

    fn set_reference_mode(&mut self, on: bool) -> DevResult<()> {
        self.set(word::REFERENCE, protocol::truth(on)).map(drop)
    }

    fn get_reference_mode(&mut self) -> DevResult<bool> {
        let r = self.get(word::REFERENCE)?;
        Self::truth_at(&r, 1)
    }

    fn set_pose_priority(&mut self, priority: &str) -> DevResult<()> {
        self.set(word::PRIO, priority).map(drop)
    }

    fn get_pose_priority(&mut self) -> DevResult<String> {
        let r = self.get(word::PRIO)?;
        r.get(1)
            .and_then(Value::as_str)
            .map(str::to_string)
            .ok_or_else(|| DeviceError::failed(NAME, format!("unexpected reply `{r}`")))
    }

    fn get_pose(&mut self) -> DevResult<(Pose, f64)> {
        let link = self.link()?;
        let latest = *link.latest.lock();
        match latest {
            Some((x, t, at)) if at.elapsed() < link.timeout => Ok((split7(&x)?, t)),
            _ => Err(DeviceError::Timeout {
                device: NAME.into(),
                command: format!("getPose ({}/state:o)", link.remote),
                after: link.timeout,
            }),
        }
    }

    fn get_link_pose(&mut self, axis: usize) -> DevResult<Pose> {
        let r = self.ack(words(&[word::GET, word::POSE]).with(Value::Int32(axis as i32)))?;
        split7(&list_at(&r, 1)?)
    }

    fn go_to_pose(&mut self, x: &[f64; 3], o: &[f64; 4], t: f64) -> DevResult<()> {
        self.stream(
            words(&[word::GO, word::FULL])
                .with(t)
                .with(protocol::f64_list(&pose7(x, o))),
        )
    }

    fn go_to_position(&mut self, x: &[f64; 3], t: f64) -> DevResult<()> {
        self.stream(
            words(&[word::GO, word::XYZ])
                .with(t)
                .with(protocol::f64_list(x)),
        )
    }

    fn go_to_pose_sync(&mut self, x: &[f64; 3], o: &[f64; 4], t: f64) -> DevResult<()> {
        self.ack(
            words(&[word::GO, word::FULL])
                .with(t)
                .with(protocol::f64_list(&pose7(x, o))),
        )
        .map(drop)
    }

    fn go_to_position_sync(&mut self, x: &[f64; 3], t: f64) -> DevResult<()> {
        self.ack(
            words(&[word::GO, word::XYZ])
                .with(t)
                .with(protocol::f64_list(x)),
        )
        .map(drop)
    }

    fn get_desired(&mut self) -> DevResult<Solved> {
        let r = self.get(word::DES)?;
        solved(&r)
    }

    fn ask_for_pose(
        &mut self,
        x: &[f64; 3],
        o: &[f64; 4],
        q0: Option<&[f64]>,
    ) -> DevResult<Solved> {
        let mut cmd = words(&[word::ASK]).with(protocol::vector_option(word::XD, &pose7(x, o)));
        if let Some(q0) = q0 {
            cmd.push(protocol::vector_option(word::Q, q0));
        }
        cmd.push(protocol::vocab_option(word::POSE, word::FULL));
        let r = self.ack(cmd)?;
        solved(&r)
    }

    fn ask_for_position(&mut self, x: &[f64; 3], q0: Option<&[f64]>) -> DevResult<Solved> {
        let mut cmd = words(&[word::ASK]).with(protocol::vector_option(word::XD, x));
        if let Some(q0) = q0 {
            cmd.push(protocol::vector_option(word::Q, q0));
        }
        cmd.push(protocol::vocab_option(word::POSE, word::XYZ));
        let r = self.ack(cmd)?;
        solved(&r)
    }

    fn get_dof(&mut self) -> DevResult<Vec<i32>> {
        let r = self.get(word::DOF)?;
        Ok(list_at(&r, 1)?.iter().map(|v| *v as i32).collect())
    }

    fn set_dof(&mut self, dof: &[i32]) -> DevResult<Vec<i32>> {
        let r = self.set(word::DOF, protocol::i32_list(dof.iter().copied()))?;
        Ok(list_at(&r, 1)?.iter().map(|v| *v as i32).collect())
    }

    fn get_rest_pos(&mut self) -> DevResult<Vec<f64>> {
        list_at(&self.get(word::REST_POS)?, 1)
    }

    fn set_rest_pos(&mut self, rest: &[f64]) -> DevResult<Vec<f64>> {
        list_at(&self.set(word::REST_POS, protocol::f64_list(rest))?, 1)
    }

    fn get_rest_weights(&mut self) -> DevResult<Vec<f64>> {
        list_at(&self.get(word::REST_WEIGHTS)?, 1)
    }

    fn set_rest_weights(&mut self, weights: &[f64]) -> DevResult<Vec<f64>> {
        list_at(
            &self.set(word::REST_WEIGHTS, protocol::f64_list(weights))?,
            1,
        )
    }

    fn get_limits(&mut self, axis: usize) -> DevResult<(f64, f64)> {
        let r = self.ack(words(&[word::GET, word::LIM]).with(Value::Int32(axis as i32)))?;
        Ok((number_at(&r, 1)?, number_at(&r, 2)?))
    }

    fn set_limits(&mut self, axis: usize, min: f64, max: f64) -> DevResult<()> {
        self.ack(
            words(&[word::SET, word::LIM])
                .with(Value::Int32(axis as i32))
                .with(min)
                .with(max),
        )
        .map(drop)
    }

    fn get_traj_time(&mut self) -> DevResult<f64> {
        number_at(&self.get(word::TIME)?, 1)
    }

    fn set_traj_time(&mut self, t: f64) -> DevResult<()> {
        self.set(word::TIME, t).map(drop)
    }

    fn get_in_target_tol(&mut self) -> DevResult<f64> {
        number_at(&self.get(word::TOL)?, 1)
    }

    fn set_in_target_tol(&mut self, tol: f64) -> DevResult<()> {
        self.set(word::TOL, tol).map(drop)
    }

    fn get_joints_velocities(&mut self) -> DevResult<Vec<f64>> {
        list_at(&self.get(word::QDOT)?, 1)
    }

    fn get_task_velocities(&mut self) -> DevResult<([f64; 3], [f64; 4])> {
        split7(&list_at(&self.get(word::XDOT)?, 1)?)
    }

    fn set_task_velocities(&mut self, xdot: &[f64; 3], odot: &[f64; 4]) -> DevResult<()> {
        self.stream(words(&[word::TASKVEL]).with(protocol::f64_list(&pose7(xdot, odot))))
    }

    fn attach_tip_frame(&mut self, x: &[f64; 3], o: &[f64; 4]) -> DevResult<()> {
        self.set(word::TIP, protocol::f64_list(&pose7(x, o)))
            .map(drop)
    }

    fn get_tip_frame(&mut self) -> DevResult<Pose> {
        split7(&list_at(&self.get(word::TIP)?, 1)?)
    }

    fn check_motion_done(&mut self) -> DevResult<bool> {
        let r = self.get(word::DONE)?;
        Self::truth_at(&r, 1)
    }

    fn wait_motion_done(&mut self, period: f64, timeout: f64) -> DevResult<bool> {
        let start = Instant::now();
        loop {
            std::thread::sleep(Duration::from_secs_f64(period.max(0.0)));
            if self.check_motion_done()? {
                return Ok(true);
            }
            if timeout > 0.0 && start.elapsed().as_secs_f64() > timeout {
                return Ok(false);
            }
        }
    }

    fn stop_control(&mut self) -> DevResult<()> {
        self.ack(words(&[word::STOP])).map(drop)
    }

    fn store_context(&mut self) -> DevResult<i32> {
        let r = self.ack(words(&[word::STORE]))?;
        let id = number_at(&r, 1)? as i32;
        self.link()?.contexts.insert(id);
        Ok(id)
    }

    fn restore_context(&mut self, id: i32) -> DevResult<()> {
        // as C++: only the contexts this client stored, and the server's first
        if id != 0 && !self.link()?.contexts.contains(&id) {
            return Err(DeviceError::failed(
                NAME,
                format!("context {id} is not this client's"),
            ));
        }
        self.ack(words(&[word::RESTORE]).with(Value::Int32(id)))
            .map(drop)
    }

    fn delete_context(&mut self, id: i32) -> DevResult<()> {
        if !self.link()?.contexts.remove(&id) {
            return Err(DeviceError::failed(
                NAME,
                format!("context {id} is not this client's"),
            ));
        }
        self.ack(words(&[word::DELETE]).with(protocol::i32_list([id])))
            .map(drop)
    }

    fn get_info(&mut self) -> DevResult<Bottle> {
        let r = self.get(word::INFO)?;
        r.get(1)
            .and_then(Value::as_list)
            .cloned()
            .ok_or_else(|| DeviceError::failed(NAME, format!("unexpected reply `{r}`")))
    }

    fn register_ongoing_checkpoint(&mut self, checkpoint: f64) -> DevResult<()> {
        self.ack(words(&[word::EVENT, word::REGISTER, word::ONGOING]).with(checkpoint))
            .map(drop)
    }

    fn unregister_ongoing_checkpoint(&mut self, checkpoint: f64) -> DevResult<()> {
        self.ack(words(&[word::EVENT, word::UNREGISTER, word::ONGOING]).with(checkpoint))
            .map(drop)
    }

    fn take_events(&mut self) -> Vec<CartesianEvent> {
        match self.link.as_ref() {
            Some(l) => std::mem::take(&mut *l.received.lock()),
            None => Vec::new(),
        }
    }
}

/// `[ack] ([x] (7)) ([q] (...))`.
fn solved(r: &Bottle) -> DevResult<Solved> {
    let x = protocol::find_vector(r, word::X)
        .ok_or_else(|| DeviceError::failed(NAME, format!("no [x] in `{r}`")))?;
    let (x, o) = split7(&x)?;
    Ok(Solved {
        x,
        o,
        q: protocol::find_vector(r, word::Q).unwrap_or_default(),
    })
}
