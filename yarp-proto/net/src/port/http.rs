//! The http carrier: a port viewed from a browser or curl, as C++ YARP's `HttpCarrier`
//! allows. `GET /` describes the port as HTML; `GET /?data=<bottle text>` (or a form POST
//! to `/form` with `data=`) delivers a Bottle to the port's owner, like a text `d` line.

use super::{Incoming, Shared};
use std::sync::Arc;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use yarp_proto::port_admin;
use yarp_proto::Bottle;

/// Longest request head accepted.
const MAX_REQUEST: usize = 64 * 1024;

/// Serves one HTTP request on `stream`. `head` holds the request bytes already read
/// (starting with the 8-byte connection header).
pub(crate) async fn serve(shared: &Arc<Shared>, stream: &mut TcpStream, mut head: Vec<u8>) {
    let mut buf = [0u8; 4096];
    let deadline = tokio::time::sleep(std::time::Duration::from_secs(10));
    tokio::pin!(deadline);
    while find(&head, b"\r\n\r\n").is_none() && find(&head, b"\n\n").is_none() {
        if head.len() > MAX_REQUEST {
            let _ = stream
                .write_all(b"HTTP/1.1 413 Request Too Large\r\n\r\n")
                .await;
            return;
        }
        tokio::select! {
            _ = &mut deadline => return,
            n = stream.read(&mut buf) => match n {
                Ok(0) | Err(_) => break,
                Ok(n) => head.extend_from_slice(&buf[..n]),
            }
        }
    }
    let text = String::from_utf8_lossy(&head).into_owned();
    let request_line = text.lines().next().unwrap_or("");
    let mut parts = request_line.split_whitespace();
    let method = parts.next().unwrap_or("");
    let target = parts.next().unwrap_or("/");
    let mut data = query_value(target, "data");
    if method == "POST" {
        // form bodies are short; take what arrived with the head
        let body = text.split_once("\r\n\r\n").map(|(_, b)| b).unwrap_or("");
        data = data.or_else(|| query_value(&format!("?{body}"), "data"));
    }
    let mut note = String::new();
    if let Some(d) = data {
        let b = Bottle::from_text(&d);
        let incoming = Incoming {
            payload: b.encode(),
            is_text: false,
            stamp: None,
            from: "http".to_string(),
            reply: None,
            decoded: None,
        };
        if shared.deliver.send(incoming).await.is_ok() {
            note = format!("<p>Sent: {}</p>\n", escape(&b.to_string()));
        }
    }
    let snap = shared.snapshot();
    let body = format!(
        "<html><head><title>{name}</title></head><body>\n<h1>{name}</h1>\n{note}\
         <p><form method=post action='/form'><input type=text name=data value=\"\">\
         <input type=submit value=\"send data\"></form></p>\n<pre>\n{desc}</pre>\n</body></html>\n",
        name = escape(&shared.name),
        desc = escape(&port_admin::describe(&snap)),
    );
    let response = format!(
        "HTTP/1.1 200 OK\r\nContent-Type: text/html\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}",
        body.len()
    );
    let _ = stream.write_all(response.as_bytes()).await;
    let _ = stream.shutdown().await;
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// `key=value` from a URL query string, percent- and `+`-decoded.
fn query_value(target: &str, key: &str) -> Option<String> {
    let (_, query) = target.split_once('?')?;
    query.split('&').find_map(|kv| {
        let (k, v) = kv.split_once('=')?;
        (k == key).then(|| percent_decode(v))
    })
}

fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'+' => out.push(b' '),
            b'%' if i + 2 < b.len() => {
                let hex = std::str::from_utf8(&b[i + 1..i + 3]).ok();
                match hex.and_then(|h| u8::from_str_radix(h, 16).ok()) {
                    Some(v) => {
                        out.push(v);
                        i += 2;
                    }
                    None => out.push(b'%'),
                }
            }
            c => out.push(c),
        }
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn query_decoding() {
        assert_eq!(
            query_value("/?data=hello+42%21", "data").as_deref(),
            Some("hello 42!")
        );
        assert_eq!(query_value("/", "data"), None);
        assert_eq!(percent_decode("%zz%4"), "%zz%4");
        assert_eq!(percent_decode("a%20b"), "a b");
    }
}
