//! The port graph: ports from the name server's `list`, connections from each port's
//! admin `[list] [out]` (and `[list] [out] <to>` for the carrier), drawn as SVG in columns
//! (sources left, readers right) like rqt_graph.

use serde::Serialize;
use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::time::Duration;
use yarp_net::nameserver::NameClient;
use yarp_net::network;
use yarp_proto::{Bottle, Contact};

/// How long one port may take to answer an admin question.
const ADMIN_LIMIT: Duration = Duration::from_millis(1500);

#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct PortNode {
    pub name: String,
    /// `host:port` it listens on.
    pub address: String,
    /// False when the port is registered but does not answer (stale registration).
    pub alive: bool,
}

#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Edge {
    pub from: String,
    pub to: String,
    pub carrier: String,
}

#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct Graph {
    pub ports: Vec<PortNode>,
    pub connections: Vec<Edge>,
}

async fn admin(c: &Contact, text: &str) -> Option<Bottle> {
    tokio::time::timeout(
        ADMIN_LIMIT,
        network::admin_command(c, &Bottle::from_text(text)),
    )
    .await
    .ok()?
    .ok()
}

/// The outputs of one port with their carriers; None when the port does not answer.
async fn outputs_of(c: Contact) -> Option<Vec<Edge>> {
    let names = admin(&c, "[list] [out]").await?;
    let mut out = Vec::new();
    for to in names.iter().filter_map(|v| v.as_str()) {
        let detail = admin(&c, &format!("[list] [out] \"{to}\"")).await;
        let carrier = detail
            .as_ref()
            .and_then(|d| d.find("carrier"))
            .and_then(|v| v.as_str())
            .unwrap_or("tcp")
            .to_string();
        out.push(Edge {
            from: c.name.clone(),
            to: to.to_string(),
            carrier,
        });
    }
    Some(out)
}

/// Asks the name server and every port (in parallel) for the current graph.
pub async fn gather(ns: &NameClient) -> Result<Graph, String> {
    let contacts: Vec<Contact> = tokio::time::timeout(Duration::from_secs(3), ns.list(None))
        .await
        .map_err(|_| "the name server did not answer".to_string())?
        .map_err(|e| e.to_string())?
        .into_iter()
        // The name server also lists non-port entries (its multicast `fallback`).
        .filter(|c| c.name.starts_with('/'))
        .collect();
    let mut set = tokio::task::JoinSet::new();
    for (i, c) in contacts.iter().enumerate() {
        let c = c.clone();
        set.spawn(async move { (i, outputs_of(c).await) });
    }
    let mut results: Vec<Option<Vec<Edge>>> = vec![None; contacts.len()];
    while let Some(r) = set.join_next().await {
        if let Ok((i, edges)) = r {
            results[i] = edges;
        }
    }
    let mut g = Graph::default();
    for (c, edges) in contacts.iter().zip(results) {
        g.ports.push(PortNode {
            name: c.name.clone(),
            address: format!("{}:{}", c.host, c.port),
            alive: edges.is_some(),
        });
        g.connections.extend(edges.unwrap_or_default());
    }
    g.ports.sort_by(|a, b| a.name.cmp(&b.name));
    g.connections
        .sort_by(|a, b| (&a.from, &a.to).cmp(&(&b.from, &b.to)));
    Ok(g)
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Column of each port: 0 for ports nothing writes to, else one more than the deepest
/// writer. Cycles are broken at their first port by name (Kahn's algorithm, forcing one
/// port whenever none is free).
fn columns(g: &Graph) -> HashMap<&str, usize> {
    let names: Vec<&str> = g.ports.iter().map(|p| p.name.as_str()).collect();
    let known = |n: &str| names.contains(&n);
    let edges: Vec<(&str, &str)> = g
        .connections
        .iter()
        .filter(|e| known(&e.from) && known(&e.to) && e.from != e.to)
        .map(|e| (e.from.as_str(), e.to.as_str()))
        .collect();
    let mut col: HashMap<&str, usize> = HashMap::new();
    let mut done: Vec<&str> = Vec::new();
    while done.len() < names.len() {
        let pending: Vec<&str> = names
            .iter()
            .copied()
            .filter(|n| !done.contains(n))
            .collect();
        let free = pending
            .iter()
            .find(|n| edges.iter().all(|(f, t)| t != *n || done.contains(f)))
            .or(pending.first());
        let Some(&n) = free else { break };
        let c = edges
            .iter()
            .filter(|(f, t)| *t == n && done.contains(f))
            .map(|(f, _)| col[f] + 1)
            .max()
            .unwrap_or(0);
        col.insert(n, c);
        done.push(n);
    }
    col
}

const ROW: f64 = 46.0;
const NODE_H: f64 = 30.0;
const CHAR_W: f64 = 7.2;
const GAP: f64 = 110.0;
/// Width the grid of unconnected ports wraps at.
const IDLE_WIDTH: f64 = 1180.0;

/// Draws the graph as a standalone SVG document (ports as boxes, connections as arrows
/// labelled with their carrier). Every port box has `class="port"` and `data-port`.
pub fn to_svg(g: &Graph) -> String {
    let col = columns(g);
    let linked = |n: &str| g.connections.iter().any(|e| e.from == n || e.to == n);
    let node_width = |p: &PortNode| p.name.chars().count() as f64 * CHAR_W + 24.0;
    let mut by_col: BTreeMap<usize, Vec<&PortNode>> = BTreeMap::new();
    let mut idle = Vec::new();
    for p in &g.ports {
        if linked(&p.name) {
            by_col.entry(col[p.name.as_str()]).or_default().push(p);
        } else {
            idle.push(p);
        }
    }
    let mut pos: HashMap<&str, (f64, f64, f64)> = HashMap::new(); // x, y, width
    let mut x = 20.0;
    let mut max_rows = 0usize;
    for ports in by_col.values() {
        let width = ports.iter().map(|p| node_width(p)).fold(80.0, f64::max);
        for (i, p) in ports.iter().enumerate() {
            pos.insert(p.name.as_str(), (x, 20.0 + i as f64 * ROW, width));
        }
        max_rows = max_rows.max(ports.len());
        x += width + GAP;
    }
    let mut w = (x - GAP + 20.0).max(200.0);
    let mut h = max_rows as f64 * ROW + 30.0;
    // Ports without connections: a compact grid below the flow, so they do not push
    // everything else down.
    if !idle.is_empty() {
        let cell = idle.iter().map(|p| node_width(p)).fold(80.0, f64::max) + 16.0;
        let per_row = ((IDLE_WIDTH / cell).floor() as usize).max(1);
        let top = if max_rows == 0 { 20.0 } else { h + 10.0 };
        for (i, p) in idle.iter().enumerate() {
            let (r, c) = (i / per_row, i % per_row);
            pos.insert(
                p.name.as_str(),
                (20.0 + c as f64 * cell, top + r as f64 * ROW, cell - 16.0),
            );
        }
        let rows = idle.len().div_ceil(per_row);
        h = top + rows as f64 * ROW + 10.0;
        w = w.max(20.0 + per_row.min(idle.len()) as f64 * cell);
    }
    let h = h.max(80.0);
    let mut s = String::new();
    let _ = write!(
        s,
        r##"<svg xmlns="http://www.w3.org/2000/svg" id="port-graph" class="port-graph" width="{w:.0}" height="{h:.0}" viewBox="0 0 {w:.0} {h:.0}" font-family="monospace" font-size="12">"##
    );
    s.push_str(r##"<defs><marker id="arrow" viewBox="0 0 10 10" refX="10" refY="5" markerWidth="7" markerHeight="7" orient="auto"><path d="M0,0 L10,5 L0,10 z" fill="#555"/></marker></defs>"##);
    if g.ports.is_empty() {
        s.push_str(r##"<text x="20" y="40" fill="#888">no ports registered</text>"##);
    }
    for e in &g.connections {
        let (Some(a), Some(b)) = (pos.get(e.from.as_str()), pos.get(e.to.as_str())) else {
            continue;
        };
        let (x1, y1) = (a.0 + a.2, a.1 + NODE_H / 2.0);
        let (x2, y2) = (b.0, b.1 + NODE_H / 2.0);
        let (path, lx, ly) = if x2 > x1 {
            let mid = (x1 + x2) / 2.0;
            (
                format!("M{x1:.1},{y1:.1} C{mid:.1},{y1:.1} {mid:.1},{y2:.1} {x2:.1},{y2:.1}"),
                mid,
                (y1 + y2) / 2.0 - 4.0,
            )
        } else {
            // Backwards or same column: loop around below.
            let low = y1.max(y2) + ROW;
            (
                format!(
                    "M{x1:.1},{y1:.1} C{:.1},{low:.1} {:.1},{low:.1} {x2:.1},{y2:.1}",
                    x1 + 60.0,
                    x2 - 60.0
                ),
                (x1 + x2) / 2.0,
                low - 10.0,
            )
        };
        let _ = write!(
            s,
            r##"<g class="connection" data-from="{f}" data-to="{t}" data-carrier="{c}"><path d="{path}" fill="none" stroke="#555" stroke-width="1.5" marker-end="url(#arrow)"/><text x="{lx:.1}" y="{ly:.1}" text-anchor="middle" fill="#1565c0">{c}</text></g>"##,
            f = esc(&e.from),
            t = esc(&e.to),
            c = esc(&e.carrier),
        );
    }
    for p in &g.ports {
        let (x, y, width) = pos[p.name.as_str()];
        let (fill, stroke) = match (p.alive, linked(&p.name)) {
            (false, _) => ("#fbe9e7", "#bf360c"),
            (true, true) => ("#e8f5e9", "#2e7d32"),
            (true, false) => ("#f5f5f5", "#9e9e9e"),
        };
        let _ = write!(
            s,
            r##"<g class="port" data-port="{n}"><title>{n} at {a}{dead}</title><rect x="{x:.1}" y="{y:.1}" width="{width:.1}" height="{NODE_H}" rx="6" fill="{fill}" stroke="{stroke}"/><text x="{tx:.1}" y="{ty:.1}" text-anchor="middle">{n}</text></g>"##,
            n = esc(&p.name),
            a = esc(&p.address),
            dead = if p.alive { "" } else { " (not answering)" },
            tx = x + width / 2.0,
            ty = y + NODE_H / 2.0 + 4.0,
        );
    }
    s.push_str("</svg>");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn graph() -> Graph {
        let p = |n: &str| PortNode {
            name: n.into(),
            address: "127.0.0.1:1".into(),
            alive: n != "/dead",
        };
        Graph {
            ports: vec![p("/a"), p("/b"), p("/c"), p("/dead"), p("/x<y")],
            connections: vec![
                Edge {
                    from: "/a".into(),
                    to: "/b".into(),
                    carrier: "tcp".into(),
                },
                Edge {
                    from: "/b".into(),
                    to: "/c".into(),
                    carrier: "udp".into(),
                },
                Edge {
                    from: "/c".into(),
                    to: "/a".into(),
                    carrier: "text".into(),
                },
            ],
        }
    }

    #[test]
    fn columns_follow_the_flow_and_survive_cycles() {
        let g = graph();
        let c = columns(&g);
        // The cycle /a -> /b -> /c -> /a is cut at /a.
        assert_eq!((c["/a"], c["/b"], c["/c"], c["/dead"]), (0, 1, 2, 0));
    }

    #[test]
    fn svg_has_ports_edges_and_escapes() {
        let svg = to_svg(&graph());
        assert!(svg.starts_with("<svg"));
        assert!(svg.ends_with("</svg>"));
        for n in ["/a", "/b", "/c", "/dead"] {
            assert!(svg.contains(&format!("data-port=\"{n}\"")), "{n}");
        }
        assert!(svg.contains("/x&lt;y"));
        assert!(svg.contains(r#"data-carrier="udp""#));
        assert!(svg.contains("not answering"));
        assert_eq!(svg.matches("class=\"connection\"").count(), 3);
        let empty = to_svg(&Graph::default());
        assert!(empty.contains("no ports registered"));
    }
}
