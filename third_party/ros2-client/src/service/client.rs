#[cfg(any(feature = "mio_06", feature = "mio_1"))]
use std::io;
use std::sync::atomic;

#[cfg(feature = "mio_06")]
use rustdds::mio::{Evented, Poll, PollOpt, Ready, Token};
#[cfg(feature = "mio_1")]
use rustdds::mio1;
use rustdds::{rpc::*, *};
#[allow(unused_imports)]
use log::{debug, error, info, warn};
use futures::{StreamExt, join, pin_mut};

use crate::{
  error::{CreateResult, ReadError, ReadResult, WriteError, WriteResult},
  gid::Gid,
  message::Message,
  message_info::MessageInfo,
  node::Node,
  qos::QosProfile,
  service::*,
};

/// Client end of a ROS2 Service
pub struct Client<Req, Resp>
where
  Req: Message,
  Resp: Message,
{
  service_mapping: ServiceMapping,
  request_sender: DataWriterR<RequestWrapper<Req>>,
  response_receiver: SimpleDataReaderR<ResponseWrapper<Resp>>,
  sequence_number_gen: atomic::AtomicI64, // used by basic and cyclone
  client_guid: GUID,                      // used by the Cyclone ServiceMapping
  // yarp-rs: concurrent calls share one response reader. One waiter at a time reads it
  // (`reading`); a response for another call is kept in `others` for its caller, who
  // finds it there once it gets the reader (bounded: calls that gave up leave theirs).
  reading: futures::lock::Mutex<()>,
  waiting: std::sync::Mutex<Vec<(RmwRequestId, futures::channel::oneshot::Sender<Resp>)>>,
  others: std::sync::Mutex<std::collections::VecDeque<(RmwRequestId, Resp)>>,
}

/// yarp-rs: a call's registration, removed when the call ends (answered or dropped).
struct Registered<'a, Req: Message, Resp: Message> {
  client: &'a Client<Req, Resp>,
  request_id: RmwRequestId,
}

impl<Req: Message, Resp: Message> Drop for Registered<'_, Req, Resp> {
  fn drop(&mut self) {
    self
      .client
      .waiting
      .lock()
      .unwrap_or_else(|e| e.into_inner())
      .retain(|(id, _)| *id != self.request_id);
  }
}

/// yarp-rs: how many responses of other calls a client keeps.
const OTHERS_KEPT: usize = 64;

impl<Req, Resp> Client<Req, Resp>
where
  Req: Message + 'static,
  Resp: Message + 'static,
{
  pub(crate) fn new(
    service_mapping: ServiceMapping,
    node: &mut Node,
    request_topic: &Topic,
    response_topic: &Topic,
    qos_request: Option<QosProfile>,
    qos_response: Option<QosProfile>,
  ) -> CreateResult<Self> {
    let request_sender = node
      .create_datawriter::<RequestWrapper<Req>, ServiceSerializerAdapter<RequestWrapper<Req>>>(
        request_topic,
        qos_request,
      )?;
    let response_receiver =
      node.create_simpledatareader
      ::<ResponseWrapper<Resp>, ServiceDeserializerAdapter<ResponseWrapper<Resp>>>(
        response_topic, qos_response)?;

    debug!(
      "Created new Client: request={} response={}",
      request_topic.name(),
      response_topic.name()
    );
    let client_guid = request_sender.guid();
    Ok(Client::<Req, Resp> {
      service_mapping,
      request_sender,
      response_receiver,
      sequence_number_gen: atomic::AtomicI64::new(SequenceNumber::default().into()),
      client_guid,
      reading: futures::lock::Mutex::new(()),
      waiting: std::sync::Mutex::new(Vec::new()),
      others: std::sync::Mutex::new(std::collections::VecDeque::new()),
    })
  }

  /// Send a request to Service Server.
  /// The returned `RmwRequestId` is a token to identify the correct response.
  pub fn send_request(&self, request: Req) -> WriteResult<RmwRequestId, ()> {
    self.increment_sequence_number();
    let gen_rmw_req_id = RmwRequestId {
      writer_gid: Gid::from(self.client_guid),
      sequence_number: i64::from(self.sequence_number()),
    };
    let req_wrapper = RequestWrapper::<Req>::new(
      self.service_mapping,
      gen_rmw_req_id,
      RepresentationIdentifier::CDR_LE,
      request,
    )?;
    let write_opts_builder = WriteOptionsBuilder::new().source_timestamp(Timestamp::now()); // always add source timestamp

    let write_opts_builder = if self.service_mapping == ServiceMapping::Enhanced {
      write_opts_builder.related_sample_identity(self.enhanced_related_identity())
    } else {
      write_opts_builder.related_sample_identity(SampleIdentity::from(gen_rmw_req_id))
    };
    let sent_rmw_req_id = self
      .request_sender
      .write_with_options(req_wrapper, write_opts_builder.build())
      .map(RmwRequestId::from)
      .map_err(|e| e.forget_data())?;

    match self.service_mapping {
      ServiceMapping::Enhanced => Ok(sent_rmw_req_id),
      ServiceMapping::Basic | ServiceMapping::Cyclone => Ok(gen_rmw_req_id),
    }
  }

  /// Receive a response from Server
  /// Returns `Ok(None)` if no new responses have arrived.
  /// Note: The response may to someone else's request. Check received
  /// `RmWRequestId` against the one you got when sending request to identify
  /// the correct response. In case you receive someone else's response,
  /// please do receive again.
  pub fn receive_response(&self) -> ReadResult<Option<(RmwRequestId, Resp)>> {
    self.response_receiver.drain_read_notifications();
    let dcc_rw: Option<no_key::DeserializedCacheChange<ResponseWrapper<Resp>>> =
      self.response_receiver.try_take_one()?;

    match dcc_rw {
      None => Ok(None),
      Some(dcc) => {
        let mi = MessageInfo::from(&dcc);
        let res_wrapper = dcc.into_value();
        let (ri, res) = res_wrapper.unwrap(self.service_mapping, mi, self.client_guid)?;
        Ok(Some((ri, res)))
      }
    } // match
  }

  /// Send a request to Service Server asynchronously.
  /// The returned `RmwRequestId` is a token to identify the correct response.
  pub async fn async_send_request(&self, request: Req) -> WriteResult<RmwRequestId, ()> {
    let gen_rmw_req_id =
      // we do the req_id generation in an async block so that we do not generate
      // multiple sequence numbers if there are multiple polls to this function
      async {
        self.increment_sequence_number();
         RmwRequestId {
          writer_gid: Gid::from(self.client_guid),
          sequence_number: i64::from(self.sequence_number()),
        }
      }.await;

    let req_wrapper = RequestWrapper::<Req>::new(
      self.service_mapping,
      gen_rmw_req_id,
      RepresentationIdentifier::CDR_LE,
      request,
    )?;
    let write_opts_builder = WriteOptionsBuilder::new().source_timestamp(Timestamp::now()); // always add source timestamp

    let write_opts_builder = if self.service_mapping == ServiceMapping::Enhanced {
      write_opts_builder.related_sample_identity(self.enhanced_related_identity())
    } else {
      write_opts_builder.related_sample_identity(SampleIdentity::from(gen_rmw_req_id))
    };
    let sent_rmw_req_id = self
      .request_sender
      .async_write_with_options(req_wrapper, write_opts_builder.build())
      .await
      .map(RmwRequestId::from)
      .map_err(|e| e.forget_data())?;

    let req_id = match self.service_mapping {
      ServiceMapping::Enhanced => sent_rmw_req_id,
      ServiceMapping::Basic | ServiceMapping::Cyclone => gen_rmw_req_id,
    };
    debug!(
      "Sent Request {:?} to {:?}",
      req_id,
      self.request_sender.topic().name()
    );
    Ok(req_id)
  }

  /// Receive a response from Server
  /// The returned Future does not complete until the response has been
  /// received.
  pub async fn async_receive_response(&self, request_id: RmwRequestId) -> ReadResult<Resp> {
    self
      .receive_with(request_id, || async {
        let dcc_stream = self.response_receiver.as_async_stream();
        pin_mut!(dcc_stream);
        match dcc_stream.next().await {
          Some(Err(e)) => Err(e.into()),
          Some(Ok(dcc)) => {
            let mi = MessageInfo::from(&dcc);
            dcc
              .into_value()
              .unwrap(self.service_mapping, mi, self.client_guid)
          }
          // This should never occur, because topic do not "end".
          None => read_error_internal!("SimpleDataReader value stream unexpectedly ended!"),
        }
      })
      .await
  }

  // yarp-rs: concurrent calls on one client. A call registers itself; one call at a time
  // reads the response reader, and hands each response that is not its own to the call
  // it answers (or keeps it, bounded, for a call that registers later).
  async fn receive_with<F, Fut>(&self, request_id: RmwRequestId, read_one: F) -> ReadResult<Resp>
  where
    F: Fn() -> Fut,
    Fut: std::future::Future<Output = ReadResult<(RmwRequestId, Resp)>>,
  {
    use futures::FutureExt;
    if let Some(r) = self.take_other(request_id) {
      return Ok(r);
    }
    let (tx, rx) = futures::channel::oneshot::channel();
    self.waiters().push((request_id, tx));
    let _registered = Registered {
      client: self,
      request_id,
    };
    if let Some(r) = self.take_other(request_id) {
      return Ok(r);
    }
    let read = async {
      loop {
        let _reader = self.reading.lock().await;
        let (req_id, response) = read_one().await?;
        if self.is_response_to(req_id, request_id) {
          return Ok(response);
        }
        debug!("Received response for someone else. expected={request_id:?}  received={req_id:?}");
        self.deliver(req_id, response);
      }
    };
    let handed = async {
      match rx.await {
        Ok(r) => Ok(r),
        // never dropped unsent while registered
        Err(_) => futures::future::pending().await,
      }
    };
    let (handed, read) = (handed.fuse(), read.fuse());
    pin_mut!(handed, read);
    futures::select! {
      r = handed => r,
      r = read => r,
    }
  }

  fn waiters(
    &self,
  ) -> std::sync::MutexGuard<'_, Vec<(RmwRequestId, futures::channel::oneshot::Sender<Resp>)>> {
    self.waiting.lock().unwrap_or_else(|e| e.into_inner())
  }

  fn deliver(&self, id: RmwRequestId, response: Resp) {
    let waiter = {
      let mut w = self.waiters();
      w.iter()
        .position(|(want, _)| self.is_response_to(id, *want))
        .map(|i| w.swap_remove(i).1)
    };
    let unsent = match waiter {
      Some(tx) => tx.send(response).err(),
      None => Some(response),
    };
    if let Some(r) = unsent {
      self.keep_other(id, r);
    }
  }

  // yarp-rs: a response another call read for this one.
  fn take_other(&self, request_id: RmwRequestId) -> Option<Resp> {
    let mut others = self.others.lock().unwrap_or_else(|e| e.into_inner());
    let i = others
      .iter()
      .position(|(id, _)| self.is_response_to(*id, request_id))?;
    others.remove(i).map(|(_, r)| r)
  }

  fn keep_other(&self, id: RmwRequestId, response: Resp) {
    let mut others = self.others.lock().unwrap_or_else(|e| e.into_inner());
    if others.len() >= OTHERS_KEPT {
      others.pop_front();
    }
    others.push_back((id, response));
  }

  // yarp-rs: responses of a type known only at run time.
  /// As [`Self::async_receive_response`], the response decoded by `seed`.
  pub async fn async_receive_response_seed<S>(
    &self,
    request_id: RmwRequestId,
    seed: S,
  ) -> ReadResult<Resp>
  where
    S: for<'de> serde::de::DeserializeSeed<'de, Value = Resp> + Clone,
  {
    let decode = decode_seed(seed);
    self
      .receive_with(request_id, || async {
        let dcc_stream = self.response_receiver.as_async_stream();
        pin_mut!(dcc_stream);
        match dcc_stream.next().await {
          Some(Err(e)) => Err(e.into()),
          Some(Ok(dcc)) => {
            let mi = MessageInfo::from(&dcc);
            dcc
              .into_value()
              .unwrap_with(self.service_mapping, mi, self.client_guid, &decode)
          }
          None => read_error_internal!("SimpleDataReader value stream unexpectedly ended!"),
        }
      })
      .await
  }

  /// As [`Self::async_call_service`], the response decoded by `seed`.
  pub async fn async_call_service_seed<S>(
    &self,
    request: Req,
    seed: S,
  ) -> Result<Resp, CallServiceError<()>>
  where
    S: for<'de> serde::de::DeserializeSeed<'de, Value = Resp> + Clone,
  {
    let req_id = self.async_send_request(request).await?;
    self
      .async_receive_response_seed(req_id, seed)
      .await
      .map_err(CallServiceError::from)
  }

  pub async fn async_call_service(&self, request: Req) -> Result<Resp, CallServiceError<()>> {
    let req_id = self.async_send_request(request).await?;
    self
      .async_receive_response(req_id)
      .await
      .map_err(CallServiceError::from)
  }

  /// Wait for a Server to be connected to the Request and Response topics.
  ///
  /// This does not distinguish between diagnostinc tools and actual servers.
  /// It is enough that someone has subscribed the Requests, and someone is
  /// a publisher for Responses.
  ///
  /// If the Node has no background Spinner running, this resolves immediately
  /// (an error is logged), since without a Spinner no match events are
  /// delivered.
  pub async fn wait_for_service(&self, my_node: &Node) {
    join!(
      my_node.wait_for_reader(self.request_sender.guid()),
      my_node.wait_for_writer(self.response_receiver.guid())
    );
  }

  // yarp-rs: in the Enhanced mapping the request names this client's response
  // reader (sequence number unknown), as rmw_fastrtps clients do. A Fast DDS
  // server then holds the response until that reader is matched instead of
  // losing it right after discovery, and answers with the reader's GUID and
  // the request's sequence number.
  fn enhanced_related_identity(&self) -> SampleIdentity {
    SampleIdentity {
      writer_guid: self.response_receiver.guid(),
      sequence_number: SequenceNumber::UNKNOWN,
    }
  }

  // yarp-rs: a response names the request by the request writer's GUID, or (the
  // server honoured `enhanced_related_identity`) by our response reader's GUID.
  fn is_response_to(&self, received: RmwRequestId, sent: RmwRequestId) -> bool {
    received == sent
      || (self.service_mapping == ServiceMapping::Enhanced
        && received.sequence_number == sent.sequence_number
        && received.writer_gid == Gid::from(self.response_receiver.guid()))
  }

  fn increment_sequence_number(&self) {
    self
      .sequence_number_gen
      .fetch_add(1, atomic::Ordering::Acquire);
  }

  fn sequence_number(&self) -> SequenceNumber {
    self
      .sequence_number_gen
      .load(atomic::Ordering::Acquire)
      .into()
  }
}

#[derive(Debug)]
pub enum CallServiceError<T> {
  WriteError(WriteError<T>),
  ReadError(ReadError),
}
impl<T> From<WriteError<T>> for CallServiceError<T> {
  fn from(value: WriteError<T>) -> Self {
    CallServiceError::WriteError(value)
  }
}
impl<T> From<ReadError> for CallServiceError<T> {
  fn from(value: ReadError) -> Self {
    CallServiceError::ReadError(value)
  }
}

impl<T> std::fmt::Display for CallServiceError<T> {
  fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
    match self {
      Self::WriteError(err) => {
        write!(f, "Write error: {err}")
      }
      Self::ReadError(err) => {
        write!(f, "Read error: {err}")
      }
    }
  }
}

impl<T> std::error::Error for CallServiceError<T>
where
  T: std::fmt::Debug + 'static,
{
  fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
    Some(match self {
      CallServiceError::WriteError(err) => err,
      CallServiceError::ReadError(err) => err,
    })
  }
}

#[cfg(feature = "mio_06")]
impl<Req, Resp> Evented for Client<Req, Resp>
where
  Req: Message + 'static,
  Resp: Message + 'static,
{
  fn register(&self, poll: &Poll, token: Token, interest: Ready, opts: PollOpt) -> io::Result<()> {
    self.response_receiver.register(poll, token, interest, opts)
  }

  fn reregister(
    &self,
    poll: &Poll,
    token: Token,
    interest: Ready,
    opts: PollOpt,
  ) -> io::Result<()> {
    self
      .response_receiver
      .reregister(poll, token, interest, opts)
  }

  fn deregister(&self, poll: &Poll) -> io::Result<()> {
    self.response_receiver.deregister(poll)
  }
}

#[cfg(feature = "mio_1")]
impl<Req, Resp> mio1::event::Source for Client<Req, Resp>
where
  Req: Message + 'static,
  Resp: Message + 'static,
{
  fn register(
    &mut self,
    registry: &mio1::Registry,
    token: mio1::Token,
    interests: mio1::Interest,
  ) -> io::Result<()> {
    mio1::event::Source::register(&mut self.response_receiver, registry, token, interests)
  }

  fn reregister(
    &mut self,
    registry: &mio1::Registry,
    token: mio1::Token,
    interests: mio1::Interest,
  ) -> io::Result<()> {
    mio1::event::Source::reregister(&mut self.response_receiver, registry, token, interests)
  }

  fn deregister(&mut self, registry: &mio1::Registry) -> io::Result<()> {
    mio1::event::Source::deregister(&mut self.response_receiver, registry)
  }
}
