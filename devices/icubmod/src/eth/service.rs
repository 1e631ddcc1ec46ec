//! A device's service on its board, in the order and with the timeouts of icub-main's
//! `EthResource` ([`Retry`]'s policies): `verifyEPprotocol(ep)` (endpoint descriptors,
//! 0.1 s; a different protocol version is refused naming both), `serviceVerifyActivate`
//! (0.5 s × 3), configuration `setcheck`s (10 × 10 ms, 50 ms), `serviceSetRegulars`
//! (0.5 s × 3), `serviceStart` (0.5 s × 3).

use std::sync::Arc;

use icub_eth::entities::mn::{
    opc, versions, QueryArray, ReplyArray, ServiceCommand, ServiceCommandResult, ServiceOperation,
};
use icub_eth::host::StartupError;
use icub_eth::id::{endpoint as ep, endpoint_name, ids};
use icub_eth::{Entity, Id32, Retry};

use super::manager::{Board, EthError};

/// The endpoint that carries a service category.
pub fn endpoint_of(category: u8) -> u8 {
    use icub_eth::entities::mn::category as c;
    match category {
        c::MC => ep::MOTION_CONTROL,
        c::SKIN => ep::SKIN,
        _ => ep::ANALOG_SENSORS,
    }
}

fn service_name(category: u8) -> &'static str {
    const N: [&str; 10] = [
        "mc",
        "strain",
        "mais",
        "skin",
        "inertials3",
        "temperatures",
        "psc",
        "pos",
        "ft",
        "battery",
    ];
    N.get(usize::from(category)).copied().unwrap_or("unknown")
}

/// `EthResource::verifyEPprotocol(ep)`: the board's version of the endpoint must be ours;
/// asked once per endpoint and board, as C++ keeps `verifiedEPprotocol[ep]`.
pub fn verify_endpoint(board: &Board, endpoint: u8) -> Result<(), EthError> {
    if board.endpoint_verified(endpoint) {
        return Ok(());
    }
    let q = QueryArray {
        opc: opc::QUERY_ARRAY_EPDES,
        endpoint: ep::ALL,
        set_number: 0,
        set_size: 0,
    };
    let reply = Retry::ENDPOINTS.run(|timeout| {
        board.command(
            ids::COMM_QUERY_ARRAY,
            &q.to_bytes(),
            ids::COMM_REPLY_ARRAY,
            timeout,
        )
    })?;
    let reply = ReplyArray::from_bytes(&reply).map_err(|e| EthError::Board {
        who: board.who(),
        reason: e.to_string(),
    })?;
    let local = versions::of_endpoint(endpoint).unwrap_or(versions::MN);
    match reply
        .descriptors()
        .into_iter()
        .find(|d| d.endpoint == endpoint)
    {
        Some(d) if d.version != local => Err(EthError::Startup(StartupError::ProtocolVersion {
            board: board.params().name.clone(),
            ip: board.params().ip,
            endpoint: endpoint_name(endpoint),
            local,
            remote: d.version,
        })),
        Some(_) => {
            board.set_endpoint_verified(endpoint);
            Ok(())
        }
        None => Err(EthError::Board {
            who: board.who(),
            reason: format!(
                "EthResource::verifyEPprotocol(): the board does not offer {}",
                endpoint_name(endpoint)
            ),
        }),
    }
}

/// One service command (`set<service cmmnds command>` → `sig<commandresult>`), as
/// [`Retry::SERVICE_COMMAND`]; fails unless the board says `latestcommandisok`.
fn service_command(board: &Board, what: &str, cmd: &ServiceCommand) -> Result<(), EthError> {
    let retry = Retry::SERVICE_COMMAND;
    let result = retry
        .run(|timeout| {
            let v = board
                .command(
                    ids::SERVICE_COMMAND,
                    &cmd.to_bytes(),
                    ids::SERVICE_COMMAND_RESULT,
                    timeout,
                )
                .map_err(|e| e.to_string())?;
            ServiceCommandResult::from_bytes(&v).map_err(|e| e.to_string())
        })
        .map_err(|last| EthError::Board {
            who: board.who(),
            reason: format!("{what} failed after {} attempts: {last}", retry.attempts()),
        })?;
    if !result.latest_command_is_ok {
        return Err(EthError::Board {
            who: board.who(),
            reason: format!("{what}: the board replied latestcommandisok = false"),
        });
    }
    Ok(())
}

/// `serviceVerifyActivate(category, param)`.
pub fn verify_activate(board: &Board, cmd: &ServiceCommand) -> Result<(), EthError> {
    let mut cmd = cmd.clone();
    cmd.operation = ServiceOperation::VerifyActivate as u8;
    let what = format!(
        "serviceVerifyActivate(eomn_serv_category_{})",
        service_name(cmd.category)
    );
    service_command(board, &what, &cmd)
}

/// `serviceSetRegulars(category, id32s)`.
pub fn set_regulars(board: &Board, category: u8, regulars: &[Id32]) -> Result<(), EthError> {
    let what = format!(
        "serviceSetRegulars(eomn_serv_category_{})",
        service_name(category)
    );
    service_command(
        board,
        &what,
        &ServiceCommand::regsig_load(category, regulars),
    )
}

/// `serviceStart(category)`.
pub fn start(board: &Board, category: u8) -> Result<(), EthError> {
    let what = format!(
        "serviceStart(eomn_serv_category_{})",
        service_name(category)
    );
    service_command(
        board,
        &what,
        &ServiceCommand::bare(ServiceOperation::Start, category),
    )
}

/// `serviceStop(category)` (at close).
pub fn stop(board: &Board, category: u8) -> Result<(), EthError> {
    let what = format!("serviceStop(eomn_serv_category_{})", service_name(category));
    service_command(
        board,
        &what,
        &ServiceCommand::bare(ServiceOperation::Stop, category),
    )
}

/// `setcheckRemoteValue(id, value, 10, 0.010, 0.050)`, as the devices configure entities.
pub fn setcheck(board: &Board, id: Id32, data: &[u8]) -> Result<(), EthError> {
    board.setcheck(id, data, Retry::DEVICE_SETCHECK)
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
    board.bring_up()?;
    verify_endpoint(board, endpoint_of(s.activate.category))?;
    for x in s.all() {
        verify_activate(board, &x.activate)?;
    }
    if let Some(prepare) = &s.prepare {
        prepare(board)?;
    }
    for x in s.all() {
        for (id, data) in &x.configs {
            setcheck(board, *id, data)?;
        }
    }
    for x in s.all() {
        if !x.regulars.is_empty() {
            set_regulars(board, x.activate.category, &x.regulars)?;
        }
        for (category, regulars) in &x.other_regulars {
            set_regulars(board, *category, regulars)?;
        }
    }
    for x in s.all() {
        send(board, &x.before_start)?;
        start(board, x.activate.category)?;
        send(board, &x.after_start)?;
    }
    Ok(())
}

fn send(board: &Board, values: &[Sent]) -> Result<(), EthError> {
    for (id, data, how) in values {
        match how {
            Write::Set => board.set(*id, data)?,
            Write::SetCheck => setcheck(board, *id, data)?,
        }
    }
    Ok(())
}
