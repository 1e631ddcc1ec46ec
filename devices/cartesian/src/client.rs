//! `cartesiancontrollerclient` (icub-main's `ClientCartesianController`): a Cartesian
//! controller server reached over the network, as [`ICartesianControl`].
//!
//! Ports `<local>/rpc:o`, `<local>/command:o`, `<local>/state:i` and `<local>/events:i`;
//! opening connects the RPC first, checks the server's `server_version` (`[get] [info]`),
//! connects the streams with `carrier`, and requires the server to have its solver
//! (`[get] [ison]`), as C++ does. `getPose` reads the state stream and fails once its
//! last message is older than `timeout`; the rest goes through `rpc:i`.

use parking_lot::Mutex;
use std::sync::Arc;
use std::time::{Duration, Instant};
use yarp_devices::cartesian_control::{CartesianEvent, ICartesianControl, Pose, Solved};
use yarp_devices::driver::DeviceDriver;
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::runtime;
use yarp_net::port::Port;
use yarp_proto::{Bottle, Property, Value};

use crate::module_client::ModuleLink;
use crate::protocol::{self, word};
use crate::server::SERVER_VERSION;

/// The C++ device name.
pub const NAME: &str = "cartesiancontrollerclient";

/// The client's ports, in the order they open (the RPC one first).
const PORTS: [&str; 4] = ["rpc:o", "command:o", "state:i", "events:i"];
const COMMAND: usize = 1;
const STATE: usize = 2;
const EVENTS: usize = 3;

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

type Link = ModuleLink<Latest>;

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

    /// A call whose reply must start with `[ack]`.
    fn ack(&mut self, cmd: Bottle) -> DevResult<Bottle> {
        self.link()?.ack(cmd)
    }

    fn get(&mut self, opt: &str) -> DevResult<Bottle> {
        self.ack(words(&[word::GET, opt]))
    }

    fn set(&mut self, opt: &str, value: impl Into<Value>) -> DevResult<Bottle> {
        self.ack(words(&[word::SET, opt]).with(value))
    }

    fn stream(&mut self, b: Bottle) -> DevResult<()> {
        let port = self.link()?.port(COMMAND);
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

impl DeviceDriver for CartesianControllerClient {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        CartesianControllerClientParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = CartesianControllerClientParams::read(config)?;
        self.close()?;
        let mut link = ModuleLink::open(
            NAME,
            "the prefix of a running cartesiancontrollerserver",
            (&p.local, &p.remote),
            &PORTS,
            "rpc:i",
            Duration::from_secs_f64(p.timeout),
            Latest::default(),
        )?;
        link.spawn(read_state(link.port(STATE), link.streams.clone()));
        link.read_events(EVENTS);
        self.link = Some(link);
        let result = self.handshake(&p.carrier);
        if result.is_err() {
            let _ = self.close();
        }
        result
    }

    fn close(&mut self) -> DevResult<()> {
        if let Some(link) = self.link.take() {
            // the contexts this client stored go with it, as C++'s close
            let ids: Vec<i32> = link.contexts.iter().copied().collect();
            link.close(Some(words(&[word::DELETE]).with(protocol::i32_list(ids))));
        }
        Ok(())
    }

    yarp_devices::views!(as_cartesian_control);
}

impl CartesianControllerClient {
    /// C++'s open after the RPC connection: the version, the streams, the solver.
    fn handshake(&mut self, carrier: &str) -> DevResult<()> {
        let info = self.get(word::INFO)?;
        let link = self.link()?;
        link.check_version(&info, SERVER_VERSION)?;
        link.connect_streams(
            carrier,
            &[(COMMAND, "command:i")],
            &[("state:o", STATE), ("events:o", EVENTS)],
        )?;
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
        let latest = *link.streams.lock();
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
        self.link()?.check_context(id)?;
        self.ack(words(&[word::RESTORE]).with(Value::Int32(id)))
            .map(drop)
    }

    fn delete_context(&mut self, id: i32) -> DevResult<()> {
        self.link()?.forget_context(id)?;
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
        self.link
            .as_ref()
            .map(Link::take_events)
            .unwrap_or_default()
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
