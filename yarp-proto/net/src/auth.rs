//! Port authentication on the wire (C++ `AuthHMAC` in `TcpFace`): when an `auth.conf` with
//! a key is found, every TCP connection this process accepts or opens (ports, RPC, the name
//! server) starts with the HMAC exchange of [`yarp_proto::auth`], before its carrier header.
//! Without a key nothing changes. A peer without the key (or with another) is refused: the
//! connection is closed and the error C++ prints is logged.

use std::io;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::Duration;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio::time::timeout;
use yarp_proto::auth::{Acceptor, AuthKey, Connector, Message, Nonce, MESSAGE_LEN};

/// How long each side waits for the other's message (C++ sets 2 s read/write timeouts).
pub const AUTH_TIMEOUT: Duration = Duration::from_secs(2);

/// The key of this process, read once from `auth.conf` (as C++ reads it once).
pub fn key() -> Option<&'static AuthKey> {
    static KEY: OnceLock<Option<AuthKey>> = OnceLock::new();
    KEY.get_or_init(|| {
        let env = |k: &str| std::env::var(k).ok();
        let path = find_auth_conf(&env, &|p: &Path| p.is_file())?;
        let text = match std::fs::read_to_string(&path) {
            Ok(t) => t,
            Err(e) => {
                tracing::warn!("{}: {e}. Authentication disabled.", path.display());
                return None;
            }
        };
        match AuthKey::from_conf(&text) {
            Ok(k) => {
                tracing::info!("Authentication enabled.");
                Some(k)
            }
            Err(e) => {
                tracing::warn!("{e}");
                None
            }
        }
    })
    .as_ref()
}

/// Where C++'s `ResourceFinder` (never configured, as `AuthHMAC` uses it) finds
/// `auth.conf`: the current directory, the robot's directories (`robots/$YARP_ROBOT_NAME`,
/// `default` when unset, under each YARP directory), then the YARP configuration and data
/// directories, the user's before the system's. (An installation's `path.d` search paths,
/// last in C++, are not read.)
pub fn find_auth_conf(
    env: &dyn Fn(&str) -> Option<String>,
    exists: &dyn Fn(&Path) -> bool,
) -> Option<PathBuf> {
    search_dirs(env)
        .into_iter()
        .map(|d| d.join("auth.conf"))
        .find(|p| exists(p))
}

fn search_dirs(env: &dyn Fn(&str) -> Option<String>) -> Vec<PathBuf> {
    let yarp_dirs = yarp_dirs(env);
    let robot = env("YARP_ROBOT_NAME").unwrap_or_else(|| "default".to_string());
    let mut dirs = vec![std::env::current_dir().unwrap_or_default()];
    dirs.extend(yarp_dirs.iter().map(|d| d.join("robots").join(&robot)));
    dirs.extend(yarp_dirs);
    dirs
}

/// `yarp::conf::dirs`: config home, data home, config dirs, data dirs. A `YARP_*` variable
/// that is set wins even when empty; the XDG fallbacks get `/yarp` appended.
fn yarp_dirs(env: &dyn Fn(&str) -> Option<String>) -> Vec<PathBuf> {
    let home = env("HOME").unwrap_or_default();
    let one = |yarp: &str, xdg: &str, default: &str| -> Vec<PathBuf> {
        match env(yarp) {
            Some(v) if v.is_empty() => vec![],
            Some(v) => vec![PathBuf::from(v)],
            None => vec![
                Path::new(&env(xdg).unwrap_or_else(|| format!("{home}/{default}"))).join("yarp"),
            ],
        }
    };
    let list = |yarp: &str, xdg: &str, default: &str| -> Vec<PathBuf> {
        match env(yarp) {
            Some(v) => v
                .split(':')
                .filter(|s| !s.is_empty())
                .map(PathBuf::from)
                .collect(),
            None => env(xdg)
                .unwrap_or_else(|| default.to_string())
                .split(':')
                .filter(|s| !s.is_empty())
                .map(|d| Path::new(d).join("yarp"))
                .collect(),
        }
    };
    let mut dirs = one("YARP_CONFIG_HOME", "XDG_CONFIG_HOME", ".config");
    dirs.extend(one("YARP_DATA_HOME", "XDG_DATA_HOME", ".local/share"));
    dirs.extend(list("YARP_CONFIG_DIRS", "XDG_CONFIG_DIRS", "/etc/xdg"));
    dirs.extend(list(
        "YARP_DATA_DIRS",
        "XDG_DATA_DIRS",
        "/usr/local/share:/usr/share",
    ));
    dirs
}

fn refused(why: impl std::fmt::Display) -> io::Error {
    io::Error::new(
        io::ErrorKind::PermissionDenied,
        format!("authentication failed: {why}"),
    )
}

fn nonce() -> Nonce {
    let mut n = [0u8; 8];
    // The OS's random source; without one, no connection may use a guessable nonce.
    getrandom::fill(&mut n).expect("the OS random source");
    n
}

async fn read_message(stream: &mut TcpStream) -> io::Result<Message> {
    let mut m = [0u8; MESSAGE_LEN];
    match timeout(AUTH_TIMEOUT, stream.read_exact(&mut m)).await {
        Ok(Ok(_)) => Ok(m),
        Ok(Err(e)) => Err(refused(format!("the peer closed the exchange ({e})"))),
        Err(_) => Err(refused("the peer sent no authentication within 2 s")),
    }
}

async fn write_message(stream: &mut TcpStream, m: &Message) -> io::Result<()> {
    match timeout(AUTH_TIMEOUT, stream.write_all(m)).await {
        Ok(r) => r,
        Err(_) => Err(refused("the peer took no authentication within 2 s")),
    }
}

/// A TCP connection to `addr`, authenticated when authentication is on.
pub async fn connect(addr: impl tokio::net::ToSocketAddrs) -> io::Result<TcpStream> {
    let mut stream = TcpStream::connect(addr).await?;
    connected(&mut stream).await?;
    Ok(stream)
}

/// On a connection this process accepted: the exchange, when authentication is on.
pub async fn accepted(stream: &mut TcpStream) -> io::Result<()> {
    let Some(key) = key() else { return Ok(()) };
    let r = async {
        let (acceptor, first) = Acceptor::start(key, nonce());
        write_message(stream, &first).await?;
        let answer = read_message(stream).await?;
        let last = acceptor.on_answer(&answer, nonce()).map_err(refused)?;
        write_message(stream, &last).await
    }
    .await;
    if let Err(e) = &r {
        log_refusal(e);
    }
    r
}

/// On a connection this process opened: the exchange, when authentication is on.
pub async fn connected(stream: &mut TcpStream) -> io::Result<()> {
    let Some(key) = key() else { return Ok(()) };
    let r = async {
        let first = read_message(stream).await?;
        let (connector, answer) = Connector::on_first(key, &first, nonce()).map_err(refused)?;
        write_message(stream, &answer).await?;
        let last = read_message(stream).await?;
        connector.on_last(&last).map_err(refused)
    }
    .await;
    if let Err(e) = &r {
        log_refusal(e);
    }
    r
}

/// C++ `TcpFace::showError`.
fn log_refusal(e: &io::Error) {
    tracing::error!("Authentication failed. ({e})");
    tracing::error!("Authentication was enabled in the auth.conf file.");
    tracing::error!("If you do not want to use authentication, please");
    tracing::error!("remove this file.");
    tracing::error!("If you do want to set up authentication, check:");
    tracing::error!("  http://www.yarp.it/yarp_port_auth.html");
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    #[test]
    fn auth_conf_is_looked_for_where_cpp_looks() {
        let env: HashMap<&str, &str> = [("HOME", "/h"), ("XDG_DATA_DIRS", "/a:/b")].into();
        let get = |k: &str| env.get(k).map(|v| v.to_string());
        let dirs = search_dirs(&get);
        let yarp = [
            "/h/.config/yarp",
            "/h/.local/share/yarp",
            "/etc/xdg/yarp",
            "/a/yarp",
            "/b/yarp",
        ];
        let mut want = vec![std::env::current_dir().unwrap()];
        want.extend(yarp.iter().map(|d| Path::new(d).join("robots/default")));
        want.extend(yarp.iter().map(PathBuf::from));
        assert_eq!(dirs, want);
        let found = find_auth_conf(&get, &|p: &Path| p == Path::new("/a/yarp/auth.conf"));
        assert_eq!(found, Some(PathBuf::from("/a/yarp/auth.conf")));
        let env: HashMap<&str, &str> = [
            ("HOME", "/h"),
            ("YARP_CONFIG_HOME", "/c"),
            ("YARP_ROBOT_NAME", "r"),
        ]
        .into();
        let get = |k: &str| env.get(k).map(|v| v.to_string());
        assert_eq!(search_dirs(&get)[1], PathBuf::from("/c/robots/r"));
    }
}
