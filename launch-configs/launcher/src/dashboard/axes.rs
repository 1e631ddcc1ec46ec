//! Joint names for the plot legend, asked of a control board's RPC port as C++
//! `remote_controlboard` does: `[get] [axes]`, then `[get] [name] j` per joint.

use std::time::Duration;
use yarp_net::nameserver::NameClient;
use yarp_net::rpc::RpcClient;
use yarp_proto::wire::Carrier;
use yarp_proto::{Bottle, Value, Vocab32};

/// More joints than any board has: a reply above this is not believed.
const MAX_AXES: i64 = 256;

/// The RPC port of the board whose `state:o` is `port`, by the C++ naming convention.
pub fn rpc_port_for(port: &str) -> Option<String> {
    port.strip_suffix("/state:o").map(|p| format!("{p}/rpc:i"))
}

fn request(words: &[&str], index: Option<i32>) -> Bottle {
    let mut b = Bottle::new();
    for w in words {
        b.add_vocab(w);
    }
    if let Some(i) = index {
        b.push(i);
    }
    b
}

/// The value after `[is] [what]` in a reply, if the reply has that form.
fn answer<'a>(reply: &'a Bottle, what: &str) -> Option<&'a Value> {
    let is = reply.get(0)? == &Value::Vocab32(Vocab32::encode("is"));
    let topic = reply.get(1)? == &Value::Vocab32(Vocab32::encode(what));
    (is && topic).then(|| reply.get(2)).flatten()
}

/// Parses `[is] [axes] N ...`.
pub fn parse_axes(reply: &Bottle) -> Option<usize> {
    let n = answer(reply, "axes")?.as_i64()?;
    (0..=MAX_AXES).contains(&n).then_some(n as usize)
}

/// Parses `[is] [name] "joint" ...`.
pub fn parse_name(reply: &Bottle) -> Option<String> {
    answer(reply, "name")?.as_str().map(str::to_string)
}

/// Asks `rpc_port` for its joint names; None if it does not answer in time or in form.
pub async fn joint_names(ns: &NameClient, rpc_port: &str) -> Option<Vec<String>> {
    let work = async {
        let contact = ns.query(rpc_port).await.ok()??;
        let mut rpc = RpcClient::connect(&contact, "/yarp-launch/dashboard/rpc", Carrier::Tcp)
            .await
            .ok()?;
        let n = parse_axes(&rpc.call(&request(&["get", "axes"], None)).await.ok()?)?;
        let mut names = Vec::with_capacity(n);
        for j in 0..n {
            let reply = rpc
                .call(&request(&["get", "name"], Some(j as i32)))
                .await
                .ok()?;
            names.push(parse_name(&reply).unwrap_or_else(|| format!("j{j}")));
        }
        rpc.close().await;
        Some(names)
    };
    tokio::time::timeout(Duration::from_secs(5), work)
        .await
        .ok()?
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replies_and_names() {
        assert_eq!(
            parse_axes(&Bottle::from_text("[is] [axes] 16 [ok]")),
            Some(16)
        );
        assert_eq!(parse_axes(&Bottle::from_text("[is] [axes] -1")), None);
        assert_eq!(parse_axes(&Bottle::from_text("[fail]")), None);
        assert_eq!(
            parse_name(&Bottle::from_text("[is] [name] \"l_shoulder_pitch\" [ok]")).as_deref(),
            Some("l_shoulder_pitch")
        );
        assert_eq!(parse_name(&Bottle::from_text("[is] [axes] 3")), None);
        assert_eq!(
            rpc_port_for("/icub/left_arm/state:o").as_deref(),
            Some("/icub/left_arm/rpc:i")
        );
        assert_eq!(rpc_port_for("/demo/writer"), None);
        assert_eq!(
            request(&["get", "name"], Some(2)).to_string(),
            "[get] [name] 2"
        );
    }
}
