//! The live dashboard: one HTML page (served from the binary) and JSON / SVG / PNG
//! endpoints, on localhost. Nothing is fetched from outside.
//!
//! | path | what |
//! |---|---|
//! | `/` | the page |
//! | `/api/config` | what the launch config asks the page to show |
//! | `/api/status` | modules (state, pid, restarts, last log lines) and connections |
//! | `/api/graph`, `/api/graph.svg` | the port graph as JSON / SVG |
//! | `/api/plot?port=/p` | recent numeric samples of a port (default: `dashboard.plot`) |
//! | `/api/camera.png?port=/p` | the last image of a frame-grabber port as PNG |
//! | `/api/bridge` | gateway counters per mapping, from its diagnostics port |

pub mod axes;
pub mod feeds;

use crate::config::DashboardSpec;
use crate::graph::{self, Graph};
use crate::supervisor::StatusSource;
use axum::extract::{Query, State};
use axum::http::{header, StatusCode};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use axum::{Json, Router};
use feeds::Feeds;
use parking_lot::Mutex;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio::sync::watch;
use yarp_net::nameserver::NameClient;

const INDEX: &str = include_str!("index.html");
/// The port graph is gathered at most this often, whatever the number of viewers.
const GRAPH_MAX_AGE: Duration = Duration::from_millis(900);
/// Default gateway diagnostics port (see `yarp-ros2-gateway --diagnostics-port`).
pub const DEFAULT_DIAGNOSTICS: &str = "/yarp_ros2_gateway/diagnostics:o";

struct AppState {
    status: StatusSource,
    ns: NameClient,
    spec: DashboardSpec,
    feeds: Feeds,
    graph: tokio::sync::Mutex<Option<(Instant, Graph)>>,
    /// Previous diagnostics counters per mapping, for rates.
    bridge_prev: Mutex<HashMap<String, (Instant, i64)>>,
}

/// A running dashboard server.
pub struct Dashboard {
    addr: SocketAddr,
    state: Arc<AppState>,
    stop: watch::Sender<bool>,
    task: tokio::task::JoinHandle<()>,
}

impl Dashboard {
    /// Binds `addr` (port 0 picks one) and serves until [`Dashboard::shutdown`].
    pub async fn start(
        addr: SocketAddr,
        status: StatusSource,
        ns: NameClient,
        spec: DashboardSpec,
    ) -> std::io::Result<Dashboard> {
        let listener = tokio::net::TcpListener::bind(addr).await?;
        let addr = listener.local_addr()?;
        let state = Arc::new(AppState {
            status,
            feeds: Feeds::new(ns.clone(), "/yarp-launch/dashboard"),
            ns,
            spec,
            graph: tokio::sync::Mutex::new(None),
            bridge_prev: Mutex::new(HashMap::new()),
        });
        let app = router(state.clone());
        let stop = watch::channel(false).0;
        let mut rx = stop.subscribe();
        let task = tokio::spawn(async move {
            let shutdown = async move {
                let _ = crate::stopped(&mut rx).await;
            };
            if let Err(e) = axum::serve(listener, app)
                .with_graceful_shutdown(shutdown)
                .await
            {
                crate::say(&format!("dashboard stopped: {e}"));
            }
        });
        Ok(Dashboard {
            addr,
            state,
            stop,
            task,
        })
    }

    pub fn url(&self) -> String {
        format!("http://{}/", self.addr)
    }

    /// Stops serving and closes the dashboard's YARP ports (before the name server goes).
    pub async fn shutdown(self) {
        self.stop.send_replace(true);
        self.state.feeds.close().await;
        // Open page connections (polling) may hold graceful shutdown; bound it.
        let _ = tokio::time::timeout(Duration::from_secs(2), self.task).await;
    }
}

fn router(state: Arc<AppState>) -> Router {
    Router::new()
        .route("/", get(index))
        .route("/api/config", get(config))
        .route("/api/status", get(status))
        .route("/api/graph", get(graph_json))
        .route("/api/graph.svg", get(graph_svg))
        .route("/api/plot", get(plot))
        .route("/api/camera.png", get(camera))
        .route("/api/bridge", get(bridge))
        .layer(axum::middleware::from_fn(bounded))
        .with_state(state)
}

/// Longest a request may take: a port that stops answering must not hang the page (nor a
/// headless browser waiting for the network to go idle).
const REQUEST_LIMIT: Duration = Duration::from_secs(8);

async fn bounded(req: axum::extract::Request, next: axum::middleware::Next) -> Response {
    match tokio::time::timeout(REQUEST_LIMIT, next.run(req)).await {
        Ok(r) => r,
        Err(_) => error(StatusCode::GATEWAY_TIMEOUT, "the request took too long"),
    }
}

async fn index() -> impl IntoResponse {
    ([(header::CONTENT_TYPE, "text/html; charset=utf-8")], INDEX)
}

#[derive(Serialize)]
struct PageConfig {
    name: String,
    name_server: String,
    plot: Option<String>,
    camera: Option<String>,
    diagnostics: String,
}

async fn config(State(s): State<Arc<AppState>>) -> Json<PageConfig> {
    let st = s.status.status();
    Json(PageConfig {
        name: st.name,
        name_server: st.name_server,
        plot: s.spec.plot.clone(),
        camera: s.spec.camera.clone(),
        diagnostics: diagnostics_port(&s.spec),
    })
}

fn diagnostics_port(spec: &DashboardSpec) -> String {
    spec.diagnostics
        .clone()
        .unwrap_or_else(|| DEFAULT_DIAGNOSTICS.to_string())
}

async fn status(State(s): State<Arc<AppState>>) -> impl IntoResponse {
    Json(s.status.status())
}

async fn current_graph(s: &AppState) -> Result<Graph, String> {
    let mut cache = s.graph.lock().await;
    if let Some((at, g)) = cache.as_ref() {
        if at.elapsed() < GRAPH_MAX_AGE {
            return Ok(g.clone());
        }
    }
    let g = graph::gather(&s.ns).await?;
    *cache = Some((Instant::now(), g.clone()));
    Ok(g)
}

fn error(code: StatusCode, msg: impl Into<String>) -> Response {
    (code, Json(serde_json::json!({ "error": msg.into() }))).into_response()
}

async fn graph_json(State(s): State<Arc<AppState>>) -> Response {
    match current_graph(&s).await {
        Ok(g) => Json(g).into_response(),
        Err(e) => error(StatusCode::SERVICE_UNAVAILABLE, e),
    }
}

async fn graph_svg(State(s): State<Arc<AppState>>) -> Response {
    match current_graph(&s).await {
        Ok(g) => ([(header::CONTENT_TYPE, "image/svg+xml")], graph::to_svg(&g)).into_response(),
        Err(e) => error(StatusCode::SERVICE_UNAVAILABLE, e),
    }
}

#[derive(Deserialize)]
struct PortQuery {
    port: Option<String>,
}

async fn plot(State(s): State<Arc<AppState>>, Query(q): Query<PortQuery>) -> Response {
    let Some(port) = q.port.or_else(|| s.spec.plot.clone()) else {
        return error(StatusCode::NOT_FOUND, "no port to plot: pass ?port=/name");
    };
    let feed = match s.feeds.get(&port, true).await {
        Ok(f) => f,
        Err(e) => return error(StatusCode::BAD_REQUEST, e.to_string()),
    };
    // Joint names, asked once per feed of the board's RPC port (the configured one for
    // the configured plot, else `<part>/rpc:i` for a `<part>/state:o`).
    let rpc = if Some(&port) == s.spec.plot.as_ref() && s.spec.plot_rpc.is_some() {
        s.spec.plot_rpc.clone()
    } else {
        axes::rpc_port_for(&port)
    };
    if let Some(rpc) = rpc {
        if feed.claim_names_lookup() {
            let (ns, f) = (s.ns.clone(), feed.clone());
            tokio::spawn(async move {
                if let Some(names) = axes::joint_names(&ns, &rpc).await {
                    f.set_names(names);
                } else {
                    f.release_names_lookup();
                }
            });
        }
    }
    Json(feed.plot()).into_response()
}

async fn camera(State(s): State<Arc<AppState>>, Query(q): Query<PortQuery>) -> Response {
    let Some(port) = q.port.or_else(|| s.spec.camera.clone()) else {
        return error(StatusCode::NOT_FOUND, "no camera port: pass ?port=/name");
    };
    let feed = match s.feeds.get(&port, false).await {
        Ok(f) => f,
        Err(e) => return error(StatusCode::BAD_REQUEST, e.to_string()),
    };
    let Some(b) = feed.last_bottle() else {
        return error(
            StatusCode::SERVICE_UNAVAILABLE,
            format!("no image from {port} yet"),
        );
    };
    match crate::image::decode(&b) {
        Ok(frame) => (
            [
                (header::CONTENT_TYPE, "image/png"),
                (header::CACHE_CONTROL, "no-store"),
            ],
            crate::image::to_png(&frame),
        )
            .into_response(),
        Err(e) => error(StatusCode::UNPROCESSABLE_ENTITY, e.to_string()),
    }
}

/// One gateway mapping's health.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BridgeRow {
    pub name: String,
    pub messages: i64,
    pub drops: i64,
    pub latency_mean_us: f64,
    pub latency_max_us: f64,
    pub rate_hz: Option<f64>,
}

/// Reads the gateway's diagnostics Bottle: one `(name messages drops mean_us max_us)`
/// per mapping. Entries of another shape are skipped.
pub fn parse_bridge(b: &yarp_proto::Bottle) -> Vec<BridgeRow> {
    b.iter()
        .filter_map(|v| v.as_list())
        .filter_map(|e| {
            Some(BridgeRow {
                name: e.get(0)?.as_str()?.to_string(),
                messages: e.get(1)?.as_i64()?,
                drops: e.get(2)?.as_i64()?,
                latency_mean_us: e.get(3)?.as_f64()?,
                latency_max_us: e.get(4)?.as_f64()?,
                rate_hz: None,
            })
        })
        .collect()
}

#[derive(Serialize)]
struct BridgeReply {
    port: String,
    connected: bool,
    rows: Vec<BridgeRow>,
}

async fn bridge(State(s): State<Arc<AppState>>) -> Response {
    let port = diagnostics_port(&s.spec);
    // Only watch the port when it exists: a launch without a gateway shows an empty table.
    if !crate::readiness::port_exists(&s.ns, &port).await {
        return Json(BridgeReply {
            port,
            connected: false,
            rows: Vec::new(),
        })
        .into_response();
    }
    let feed = match s.feeds.get(&port, false).await {
        Ok(f) => f,
        Err(e) => return error(StatusCode::BAD_REQUEST, e.to_string()),
    };
    let mut rows = feed
        .last_bottle()
        .map(|b| parse_bridge(&b))
        .unwrap_or_default();
    let now = Instant::now();
    let mut prev = s.bridge_prev.lock();
    for r in &mut rows {
        if let Some((t, n)) = prev.get(&r.name) {
            let dt = now.duration_since(*t).as_secs_f64();
            if dt > 0.2 {
                r.rate_hz = Some((r.messages - n) as f64 / dt);
            }
        }
        let stale = prev
            .get(&r.name)
            .is_none_or(|(t, _)| now.duration_since(*t) > Duration::from_secs(2));
        if stale {
            prev.insert(r.name.clone(), (now, r.messages));
        }
    }
    Json(BridgeReply {
        port,
        connected: feed.is_connected(),
        rows,
    })
    .into_response()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bridge_rows() {
        let b = yarp_proto::Bottle::from_text("(\"left_arm\" 10 1 12.5 40.0) (bad) 3");
        let rows = parse_bridge(&b);
        assert_eq!(rows.len(), 1);
        assert_eq!(rows[0].name, "left_arm");
        assert_eq!(rows[0].drops, 1);
        assert_eq!(rows[0].latency_max_us, 40.0);
    }

    #[test]
    fn page_has_the_panels() {
        for id in [
            "port-graph-box",
            "joint-plot",
            "camera",
            "bridge",
            "modules",
        ] {
            assert!(INDEX.contains(&format!("id=\"{id}\"")), "{id}");
        }
    }
}
