//! Live data for the dashboard: a reader port per watched YARP port, connected from the
//! source by a third-party connect (and connected again if the source restarts).

use parking_lot::Mutex;
use serde::Serialize;
use std::collections::{HashMap, VecDeque};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio::sync::watch;
use yarp_net::nameserver::NameClient;
use yarp_net::network;
use yarp_net::port::Port;
use yarp_proto::{Bottle, Value};

/// Samples kept per plotted port.
pub const HISTORY: usize = 300;
/// Samples are stored at most this often (the page redraws a few times a second).
const SAMPLE_EVERY: Duration = Duration::from_millis(40);
/// Values plotted per sample.
const MAX_SERIES: usize = 64;
/// Ports watched at once.
pub const MAX_FEEDS: usize = 8;

#[derive(Debug, thiserror::Error)]
pub enum FeedError {
    #[error("port names start with '/': {0:?}")]
    BadName(String),
    #[error("already watching {MAX_FEEDS} ports")]
    TooMany,
    #[error("cannot open the dashboard's reader port: {0}")]
    Open(String),
}

#[derive(Debug, Default)]
struct Latest {
    /// The last message (binary Bottle, or text), kept undecoded: images are large.
    payload: Option<(Vec<u8>, bool)>,
    t0: Option<Instant>,
    last_sample: Option<Instant>,
    history: VecDeque<(f64, Vec<f64>)>,
    /// (time, count) a second ago, for the message rate.
    rate_mark: Option<(Instant, u64)>,
    rate_hz: f64,
}

/// One watched port.
#[derive(Debug)]
pub struct Feed {
    pub source: String,
    pub local: String,
    received: AtomicU64,
    latest: Mutex<Latest>,
    connected: std::sync::atomic::AtomicBool,
    /// Joint names for the plot (from the board's axis info), when known.
    names: Mutex<Vec<String>>,
    /// A joint-name lookup is running or done (retried when it fails).
    names_claimed: std::sync::atomic::AtomicBool,
}

/// A feed's plot data, as served on `/api/plot`.
#[derive(Debug, Clone, Serialize)]
pub struct PlotData {
    pub port: String,
    pub connected: bool,
    pub received: u64,
    pub rate_hz: f64,
    /// Names of the series (joint names), when known; empty otherwise.
    pub names: Vec<String>,
    /// Seconds since the feed started, one per sample.
    pub t: Vec<f64>,
    /// One series per value position.
    pub series: Vec<Vec<f64>>,
}

fn numbers(b: &Bottle, out: &mut Vec<f64>) {
    for v in b.iter() {
        if out.len() >= MAX_SERIES {
            return;
        }
        match v {
            Value::List(l) => numbers(l, out),
            Value::Int8(_) | Value::Int16(_) | Value::Int32(_) | Value::Int64(_) => {
                out.push(v.as_f64().unwrap_or(0.0))
            }
            Value::Float32(_) | Value::Float64(_) => out.push(v.as_f64().unwrap_or(0.0)),
            _ => {}
        }
    }
}

impl Feed {
    fn record(&self, payload: Vec<u8>, is_text: bool, keep_numbers: bool) {
        let n = self.received.fetch_add(1, Ordering::Relaxed) + 1;
        let now = Instant::now();
        let mut l = self.latest.lock();
        match l.rate_mark {
            Some((t, c)) if now.duration_since(t) >= Duration::from_secs(1) => {
                l.rate_hz = (n - c) as f64 / now.duration_since(t).as_secs_f64();
                l.rate_mark = Some((now, n));
            }
            None => l.rate_mark = Some((now, n)),
            _ => {}
        }
        if keep_numbers
            && l.last_sample
                .is_none_or(|t| now.duration_since(t) >= SAMPLE_EVERY)
        {
            let b = if is_text {
                Bottle::from_text(&payload)
            } else {
                Bottle::decode(&payload).unwrap_or_default()
            };
            let mut v = Vec::new();
            numbers(&b, &mut v);
            let t0 = *l.t0.get_or_insert(now);
            if l.history.len() == HISTORY {
                l.history.pop_front();
            }
            l.history
                .push_back((now.duration_since(t0).as_secs_f64(), v));
            l.last_sample = Some(now);
        }
        l.payload = Some((payload, is_text));
    }

    /// The last message as a Bottle, if one arrived.
    pub fn last_bottle(&self) -> Option<Bottle> {
        let l = self.latest.lock();
        let (p, text) = l.payload.as_ref()?;
        if *text {
            Some(Bottle::from_text(p))
        } else {
            Bottle::decode(p).ok()
        }
    }

    pub fn received(&self) -> u64 {
        self.received.load(Ordering::Relaxed)
    }

    pub fn rate_hz(&self) -> f64 {
        self.latest.lock().rate_hz
    }

    pub fn is_connected(&self) -> bool {
        self.connected.load(Ordering::Relaxed)
    }

    /// True for the one caller that should look the joint names up.
    pub fn claim_names_lookup(&self) -> bool {
        !self.names_claimed.swap(true, Ordering::Relaxed)
    }

    /// Lets a later request try the lookup again (the board was not up yet).
    pub fn release_names_lookup(&self) {
        self.names_claimed.store(false, Ordering::Relaxed);
    }

    pub fn set_names(&self, names: Vec<String>) {
        *self.names.lock() = names;
    }

    pub fn plot(&self) -> PlotData {
        let l = self.latest.lock();
        let width = l.history.iter().map(|(_, v)| v.len()).max().unwrap_or(0);
        let mut series = vec![Vec::with_capacity(l.history.len()); width];
        for (_, v) in &l.history {
            for (i, s) in series.iter_mut().enumerate() {
                s.push(v.get(i).copied().unwrap_or(f64::NAN));
            }
        }
        PlotData {
            port: self.source.clone(),
            connected: self.is_connected(),
            received: self.received(),
            rate_hz: l.rate_hz,
            names: self.names.lock().clone(),
            t: l.history.iter().map(|(t, _)| *t).collect(),
            series,
        }
    }
}

/// The set of watched ports, opened on first use.
pub struct Feeds {
    ns: NameClient,
    prefix: String,
    feeds: Mutex<HashMap<String, Arc<Feed>>>,
    tasks: Mutex<Vec<tokio::task::JoinHandle<()>>>,
    stop: watch::Sender<bool>,
    seq: AtomicU64,
}

impl Feeds {
    /// Reader ports are named `<prefix>/<n>:i`.
    pub fn new(ns: NameClient, prefix: &str) -> Feeds {
        Feeds {
            ns,
            prefix: prefix.trim_end_matches('/').to_string(),
            feeds: Mutex::new(HashMap::new()),
            tasks: Mutex::new(Vec::new()),
            stop: watch::channel(false).0,
            seq: AtomicU64::new(0),
        }
    }

    /// The feed for `source`, opening a reader port and starting to connect on first use.
    pub async fn get(&self, source: &str, keep_numbers: bool) -> Result<Arc<Feed>, FeedError> {
        if !source.starts_with('/') || source.contains(char::is_whitespace) {
            return Err(FeedError::BadName(source.to_string()));
        }
        if let Some(f) = self.feeds.lock().get(source) {
            return Ok(f.clone());
        }
        if self.feeds.lock().len() >= MAX_FEEDS {
            return Err(FeedError::TooMany);
        }
        let n = self.seq.fetch_add(1, Ordering::Relaxed);
        let local = format!("{}/{n}:i", self.prefix);
        let port = Port::open(&local, self.ns.clone())
            .await
            .map_err(|e| FeedError::Open(e.to_string()))?;
        let feed = Arc::new(Feed {
            source: source.to_string(),
            local: local.clone(),
            received: AtomicU64::new(0),
            latest: Mutex::new(Latest::default()),
            connected: Default::default(),
            names: Mutex::new(Vec::new()),
            names_claimed: Default::default(),
        });
        let winner = {
            let mut feeds = self.feeds.lock();
            match feeds.get(source) {
                Some(f) => Some(f.clone()),
                None => {
                    feeds.insert(source.to_string(), feed.clone());
                    None
                }
            }
        };
        if let Some(f) = winner {
            // Another request won the race; our port is closed (and unregistered).
            port.close().await;
            return Ok(f);
        }
        let task = tokio::spawn(run(
            port,
            feed.clone(),
            self.ns.clone(),
            keep_numbers,
            self.stop.subscribe(),
        ));
        self.tasks.lock().push(task);
        Ok(feed)
    }

    /// Closes every reader port (unregistering it), bounded in time.
    pub async fn close(&self) {
        self.stop.send_replace(true);
        let tasks: Vec<_> = std::mem::take(&mut *self.tasks.lock());
        for t in tasks {
            let _ = tokio::time::timeout(Duration::from_secs(4), t).await;
        }
    }
}

/// Reads the feed's port and keeps the source connected to it until stopped.
async fn run(
    port: Port,
    feed: Arc<Feed>,
    ns: NameClient,
    keep_numbers: bool,
    mut stop: watch::Receiver<bool>,
) {
    let mut tick = tokio::time::interval(Duration::from_secs(1));
    loop {
        tokio::select! {
            _ = crate::stopped(&mut stop) => break,
            msg = port.read() => match msg {
                Some(m) => feed.record(m.payload, m.is_text, keep_numbers),
                None => break,
            },
            _ = tick.tick() => {
                let ok = matches!(
                    tokio::time::timeout(Duration::from_secs(2), network::is_connected(&ns, &feed.source, &feed.local)).await,
                    Ok(Ok(true))
                );
                if !ok {
                    let made = tokio::time::timeout(
                        Duration::from_secs(3),
                        network::connect(&ns, &feed.source, &feed.local, Some("tcp")),
                    )
                    .await;
                    feed.connected.store(matches!(made, Ok(Ok((true, _)))), Ordering::Relaxed);
                } else {
                    feed.connected.store(true, Ordering::Relaxed);
                }
            }
        }
    }
    let _ = tokio::time::timeout(Duration::from_secs(3), port.close()).await;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_numbers_and_rates() {
        let f = Feed {
            source: "/s".into(),
            local: "/l".into(),
            received: AtomicU64::new(0),
            latest: Mutex::new(Latest::default()),
            connected: Default::default(),
            names: Mutex::new(Vec::new()),
            names_claimed: Default::default(),
        };
        f.record(Bottle::from_text("1 2.5 (3 x) \"s\"").encode(), false, true);
        f.record(b"9 8".to_vec(), true, true);
        let p = f.plot();
        assert_eq!(p.received, 2);
        // The second came within SAMPLE_EVERY: only one sample kept.
        assert_eq!(p.series, vec![vec![1.0], vec![2.5], vec![3.0]]);
        assert_eq!(f.last_bottle().unwrap().to_string(), "9 8");
    }
}
