//! A device's service on its board, in the order of icub-main's `embObj*` devices, as
//! steps of the host's [`Startup`] (each with `EthResource`'s timeouts and retries):
//! `verifyEPprotocol(ep)`, `serviceVerifyActivate`, configuration `setcheck`s,
//! `serviceSetRegulars`, `serviceStart`.

use std::sync::Arc;

use icub_eth::entities::mn::ServiceCommand;
use icub_eth::host::Startup;
use icub_eth::Id32;

use super::manager::{Board, EthError};

/// The endpoint that carries a service category.
pub use icub_eth::host::service_endpoint as endpoint_of;

/// `EthResource::verifyEPprotocol(ep)` as a step of `steps`, unless the board's
/// `endpoint` is verified already (C++ keeps `verifiedEPprotocol[ep]`).
pub fn verify_endpoint(board: &Board, steps: &mut Startup, endpoint: u8) {
    if !board.endpoint_verified(endpoint) {
        steps.verify_endpoints(&[endpoint]);
    }
}

/// Work of a sensor device between the verification of its services and their
/// configuration (embObjFTsensor asks its full scales there).
pub type Prepare = Box<dyn Fn(&Board) -> Result<(), EthError> + Send>;

/// How a device sends a value at start-up, as its C++ original does: `setRemoteValue`
/// (sent once) or `setcheckRemoteValue` (sent, then asked back until the board has it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Write {
    Set,
    SetCheck,
}

/// A value sent to the board at start-up, with how.
pub type Sent = (Id32, Vec<u8>, Write);

/// What a sensor device needs to bring its service up in one go.
pub struct SensorService {
    pub activate: ServiceCommand,
    pub prepare: Option<Prepare>,
    pub configs: Vec<(Id32, Vec<u8>)>,
    pub regulars: Vec<Id32>,
    /// Regulars of another category loaded right after the service's own, without that
    /// service (embObjFTsensor's temperature status, which `initRegulars` always loads).
    pub other_regulars: Vec<(u8, Vec<Id32>)>,
    /// Sent after the regulars, before the start (embObjSkin's signal mode).
    pub before_start: Vec<Sent>,
    /// Sent after the start (e.g. `cmmnds enable`).
    pub after_start: Vec<Sent>,
    /// A second service of the same device on the same board (embObjFTsensor's
    /// temperatures), brought up alongside, step by step, as C++ does.
    pub companion: Option<Box<SensorService>>,
}

impl SensorService {
    pub fn new(activate: ServiceCommand) -> Self {
        Self {
            activate,
            prepare: None,
            configs: Vec::new(),
            regulars: Vec::new(),
            other_regulars: Vec::new(),
            before_start: Vec::new(),
            after_start: Vec::new(),
            companion: None,
        }
    }

    /// This service and its companion, in order.
    fn all(&self) -> impl Iterator<Item = &SensorService> {
        std::iter::once(self).chain(self.companion.as_deref())
    }
}

/// The open sequence of the `embObj*` sensor devices: board up, endpoint version, then
/// for each service (the device's, then its companion) verify-activate; the device's
/// preparation; configs; regulars; what goes before the start, the start, and what
/// follows it.
pub fn open_sensor(board: &Arc<Board>, s: &SensorService) -> Result<(), EthError> {
    let mut verify = Startup::steps();
    verify_endpoint(board, &mut verify, endpoint_of(s.activate.category));
    for x in s.all() {
        verify.verify_activate(&x.activate);
    }
    board.run(&mut verify)?;
    if let Some(prepare) = &s.prepare {
        prepare(board)?;
    }
    let mut rest = Startup::steps();
    for x in s.all() {
        for (id, data) in &x.configs {
            rest.setcheck(*id, data);
        }
    }
    for x in s.all() {
        if !x.regulars.is_empty() {
            rest.set_regulars(x.activate.category, &x.regulars);
        }
        for (category, regulars) in &x.other_regulars {
            rest.set_regulars(*category, regulars);
        }
    }
    for x in s.all() {
        send(&mut rest, &x.before_start);
        rest.start(x.activate.category);
        send(&mut rest, &x.after_start);
    }
    board.run(&mut rest)
}

fn send(steps: &mut Startup, values: &[Sent]) {
    for (id, data, how) in values {
        match how {
            Write::Set => steps.set(*id, data),
            Write::SetCheck => steps.setcheck(*id, data),
        };
    }
}
