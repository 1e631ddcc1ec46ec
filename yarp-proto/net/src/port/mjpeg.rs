//! The mjpeg carrier's I/O ([`yarp_proto::wire::mjpeg`] has the protocol): a pull
//! connection. The reading port connects to the writing one and receives its images as
//! JPEGs ([`pull`], what a port does when told `add mjpeg://writer`); the writing port
//! serves a connection that opened with `GET /?ac` as one of its outputs
//! ([`serve_output`]; a web browser may ask too).

use super::input::InputEntry;
use super::output::{Job, OutputError, OutputHandle};
use super::{Incoming, Shared, CONNECT_TIMEOUT, OUTPUT_QUEUE};
use std::sync::Arc;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio::sync::{mpsc, Notify};
use tokio::time::timeout;
use yarp_proto::image::Image;
use yarp_proto::port_admin::Route;
use yarp_proto::wire::mjpeg::{self, RequestReader, StreamDecoder, StreamEvent};
use yarp_proto::wire::modifiers::CarrierName;
use yarp_proto::Contact;

/// The writing side: reads the rest of the request (its first 8 bytes were `head`),
/// answers, and keeps the connection as an output that sends every image as a JPEG.
pub(crate) async fn serve_output(shared: &Arc<Shared>, mut stream: TcpStream, head: Vec<u8>) {
    let peer = stream
        .peer_addr()
        .map_or_else(|_| "mjpeg reader".to_string(), |a| a.to_string());
    let mut request = RequestReader::new();
    let mut done = request.feed(head.get(8..).unwrap_or_default());
    let mut buf = [0u8; 1024];
    while !done {
        match timeout(CONNECT_TIMEOUT, stream.read(&mut buf)).await {
            Ok(Ok(n)) if n > 0 => done = request.feed(&buf[..n]),
            _ => {
                tracing::debug!("{}: mjpeg request from {peer} ended early", shared.name);
                return;
            }
        }
    }
    if let Err(e) = stream.write_all(mjpeg::RESPONSE.as_bytes()).await {
        tracing::debug!("{}: mjpeg answer to {peer}: {e}", shared.name);
        return;
    }
    let (tx, rx) = mpsc::channel(OUTPUT_QUEUE);
    let route = Route::new(&shared.name, &peer, "mjpeg");
    let port = Arc::downgrade(shared);
    let target = peer.clone();
    let task = tokio::spawn(async move {
        let result = send_images(&target, &mut stream, rx).await;
        if let Err(e) = &result {
            tracing::debug!("mjpeg output to {target} ended: {e}");
        }
        let _ = stream.shutdown().await;
        if let Some(shared) = port.upgrade() {
            shared.lock().outputs.retain(|_, o| o.route.to != target);
        }
    });
    let id = shared.next_id();
    shared
        .lock()
        .outputs
        .insert(id, OutputHandle::new(route, tx, task));
}

async fn send_images(
    target: &str,
    stream: &mut TcpStream,
    mut rx: mpsc::Receiver<Job>,
) -> Result<(), OutputError> {
    let io_err = |source| OutputError::Io {
        target: target.to_string(),
        source,
    };
    let mut probe = [0u8; 512];
    let mut warned = false;
    loop {
        let job = tokio::select! {
            job = rx.recv() => job,
            // what the reader sends after its request is ignored; its end is noticed
            n = stream.read(&mut probe) => {
                if n.map_err(io_err)? == 0 {
                    return Err(OutputError::PeerClosed(target.to_string()));
                }
                continue;
            }
        };
        let msg = match job {
            None | Some(Job::Close(None)) => return Ok(()),
            Some(Job::Close(Some(done))) => {
                let _ = done.send(());
                return Ok(());
            }
            // no replies travel on mjpeg (C++ supportReply() is false)
            Some(Job::Rpc(_, reply)) => {
                let _ = reply.send(Ok(yarp_proto::Bottle::new()));
                continue;
            }
            Some(Job::Data(msg)) => msg,
        };
        // compression takes milliseconds: off the async workers
        let jpeg = tokio::task::spawn_blocking(move || {
            let img = Image::from_bottle(msg.bottle()).map_err(|e| e.to_string())?;
            mjpeg::encode_jpeg(&img, msg.stamp().as_ref()).map_err(|e| e.to_string())
        })
        .await
        .unwrap_or_else(|e| Err(e.to_string()));
        let jpeg = match jpeg {
            Ok(j) => j,
            Err(e) => {
                // as C++, what is not an image is not sent
                if !warned {
                    tracing::warn!("mjpeg to {target}: message not sent: {e}");
                    warned = true;
                }
                continue;
            }
        };
        let (head, tail) = mjpeg::part_framing(jpeg.len());
        super::output::write_all_parts(stream, &[head.as_bytes(), &jpeg, tail.as_bytes()])
            .await
            .map_err(io_err)?;
    }
}

/// The reading side: connects to `target` (at `contact`), asks for its stream and
/// delivers every image to this port's reader, as an input from `target`.
pub(crate) async fn pull(
    shared: &Arc<Shared>,
    target: &str,
    contact: &Contact,
    carrier: &CarrierName,
) -> Result<(), OutputError> {
    let mut stream = super::output::dial(target, contact).await?;
    let _ = stream.set_nodelay(true);
    let request = mjpeg::request(carrier.find("path"), &contact.host);
    stream
        .write_all(&request)
        .await
        .map_err(|source| OutputError::Io {
            target: target.to_string(),
            source,
        })?;
    let id = shared.next_id();
    let kill = Arc::new(Notify::new());
    shared.lock().inputs.insert(
        id,
        InputEntry::new(
            Route::new(target, &shared.name, &carrier.to_string()),
            kill.clone(),
        ),
    );
    let port = Arc::downgrade(shared);
    let from = target.to_string();
    tokio::spawn(async move {
        let Some(shared) = port.upgrade() else {
            return;
        };
        let mut shutdown = shared.shutdown.clone();
        let result = tokio::select! {
            _ = shutdown.changed() => Ok(()),
            _ = kill.notified() => Ok(()),
            r = receive_images(&shared, &from, &mut stream) => r,
        };
        if let Err(e) = result {
            tracing::debug!("{}: mjpeg input from {from} ended: {e}", shared.name);
        }
        shared.lock().inputs.remove(&id);
        let _ = stream.shutdown().await;
    });
    Ok(())
}

async fn receive_images(
    shared: &Arc<Shared>,
    from: &str,
    stream: &mut TcpStream,
) -> Result<(), String> {
    let mut decoder = StreamDecoder::new();
    let mut buf = vec![0u8; 64 * 1024];
    loop {
        while let Some(ev) = decoder.poll().map_err(|e| e.to_string())? {
            let jpeg = match ev {
                StreamEvent::Frame(j) => j,
                StreamEvent::Skipped(why) => {
                    tracing::warn!("{}: from {from}: {why}", shared.name);
                    continue;
                }
            };
            let decoded = tokio::task::spawn_blocking(move || mjpeg::decode_jpeg(&jpeg))
                .await
                .map_err(|e| e.to_string())?;
            let (img, stamp) = match decoded {
                Ok(d) => d,
                Err(e) => {
                    // C++: "Skipping a problematic JPEG frame"
                    tracing::warn!("{}: from {from}: skipping a JPEG frame: {e}", shared.name);
                    continue;
                }
            };
            let incoming = Incoming {
                payload: img.to_bottle().encode(),
                is_text: false,
                stamp,
                from: from.to_string(),
                reply: None,
                decoded: None,
            };
            if shared.deliver.send(incoming).await.is_err() {
                return Ok(());
            }
        }
        let n = stream.read(&mut buf).await.map_err(|e| e.to_string())?;
        if n == 0 {
            return Err("closed by the writer".into());
        }
        decoder.feed(&buf[..n]);
    }
}
