//! A direct RPC connection without a registered port (what `yarp rpc /target` and C++
//! `anon_rpc` clients open): connect, send commands with `d`, read the replies.

use crate::port::output::{await_reply, next_event, OutputError};
use crate::port::{PortError, CONNECT_TIMEOUT};
use tokio::io::AsyncWriteExt;
use tokio::net::TcpStream;
use tokio::time::timeout;
use yarp_proto::wire::{
    self, encode_connection_start, text_carrier, Carrier, CarrierSpec, Decoder, DecoderConfig,
    Event, Framing, PortCommand,
};
use yarp_proto::{Bottle, Contact};

/// An open RPC connection to one port.
pub struct RpcClient {
    target: String,
    stream: TcpStream,
    decoder: Decoder,
    spec: CarrierSpec,
}

impl RpcClient {
    /// Connects to `contact` as `sender` (C++ uses `anon_rpc`) over tcp or text_ack.
    pub async fn connect(
        contact: &Contact,
        sender: &str,
        carrier: Carrier,
    ) -> Result<RpcClient, PortError> {
        let spec = carrier.spec();
        if !matches!(spec.framing, Framing::Stream | Framing::Text) || !spec.supports_reply {
            return Err(OutputError::UnsupportedCarrier(carrier.name().to_string()).into());
        }
        let target = contact.name.clone();
        let addr = format!("{}:{}", contact.host, contact.port);
        let io = |source| OutputError::Io {
            target: target.clone(),
            source,
        };
        let mut stream = timeout(CONNECT_TIMEOUT, crate::auth::connect(&addr))
            .await
            .map_err(|_| OutputError::HandshakeTimeout {
                target: target.clone(),
            })?
            .map_err(|source| OutputError::Connect {
                target: target.clone(),
                addr: addr.clone(),
                source,
            })?;
        let _ = stream.set_nodelay(true);
        stream
            .write_all(&encode_connection_start(&spec, sender.as_bytes()))
            .await
            .map_err(io)?;
        let mut decoder = Decoder::connecting(spec, DecoderConfig::default());
        let ev = timeout(
            CONNECT_TIMEOUT,
            next_event(&mut stream, &mut decoder, &target),
        )
        .await
        .map_err(|_| OutputError::HandshakeTimeout {
            target: target.clone(),
        })??;
        if !matches!(ev, Event::HeaderReply(_) | Event::Welcome(_)) {
            return Err(OutputError::Unexpected {
                target,
                what: format!("{ev:?}"),
            }
            .into());
        }
        Ok(RpcClient {
            target,
            stream,
            decoder,
            spec,
        })
    }

    /// Sends `cmd` and waits for the reply (an empty Bottle if the server gave none).
    pub async fn call(&mut self, cmd: &Bottle) -> Result<Bottle, PortError> {
        let pc = PortCommand::data(true);
        let mut out = Vec::new();
        match self.spec.framing {
            Framing::Text => text_carrier::encode_message(&pc, &cmd.to_text(), &mut out),
            _ => wire::encode_message(&pc, &[&cmd.encode()], &mut out),
        }
        self.stream
            .write_all(&out)
            .await
            .map_err(|source| OutputError::Io {
                target: self.target.clone(),
                source,
            })?;
        // a reply that is no Bottle (a thrift setter's bare ReturnValue in 3.12) comes
        // back as PortError::BadReply with its bytes
        self.decoder.expect_raw_response(&pc);
        await_reply(&mut self.stream, &mut self.decoder, &self.target, self.spec).await
    }

    /// Closes politely (`q`).
    pub async fn close(mut self) {
        let cmd = PortCommand::close();
        let mut out = Vec::new();
        match self.spec.framing {
            Framing::Text => text_carrier::encode_message(&cmd, &[], &mut out),
            _ => out = wire::close_message(),
        }
        let _ = self.stream.write_all(&out).await;
        let _ = self.stream.shutdown().await;
    }
}
