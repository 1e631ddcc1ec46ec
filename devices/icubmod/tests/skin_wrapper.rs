//! `skinWrapper` over real sockets with an in-process name server (run under netns-run):
//! the ports of the iCub skin parts, each serving its slice of the taxels.

use yarp_devices::{PolyDriver, Registry};
use yarp_interop_tests::{name_client, T};
use yarp_net::rpc::RpcClient;
use yarp_proto::wire::Carrier;
use yarp_proto::{Bottle, Property, Stamp};

fn run<F>(fut: F) -> F::Output
where
    F: std::future::Future + Send + 'static,
    F::Output: Send + 'static,
{
    yarp_devices::runtime::block_on(async move {
        tokio::time::timeout(T, fut).await.expect("timed out")
    })
    .expect("the device runtime")
}

fn open(text: &str) -> PolyDriver {
    name_client();
    Registry::install(icubmod::register);
    PolyDriver::open(&Property::from_config_text(text).unwrap())
        .unwrap_or_else(|e| panic!("open {text:?}: {e}"))
}

fn read_from(from: &str, reader: &str, n: usize) -> Vec<(Option<Stamp>, Bottle)> {
    let ns = name_client();
    let (from, reader) = (from.to_string(), reader.to_string());
    run(async move {
        let port = yarp_net::port::Port::open(&reader, ns.clone())
            .await
            .unwrap();
        let (ok, msg) = yarp_net::network::connect(&ns, &from, &reader, None)
            .await
            .unwrap();
        assert!(ok, "{msg}");
        let mut out = Vec::new();
        for _ in 0..n {
            let m = port.read().await.expect("a message");
            out.push((m.stamp, m.bottle().unwrap()));
        }
        port.close().await;
        out
    })
}

fn rpc_calls(port: &str, texts: &[&str]) -> Vec<String> {
    let ns = name_client();
    let port = port.to_string();
    let texts: Vec<String> = texts.iter().map(|t| t.to_string()).collect();
    run(async move {
        let c = ns.query(&port).await.unwrap().expect("registered");
        let mut rpc = RpcClient::connect(&c, "/anon_rpc", Carrier::Tcp)
            .await
            .unwrap();
        let mut out = Vec::new();
        for t in texts {
            out.push(rpc.call(&Bottle::from_text(&t)).await.unwrap().to_string());
        }
        rpc.close().await;
        out
    })
}

/// `wrappers/skin/left_arm_skin_wrapper.xml` in small: ports from the `ports` paramlist
/// (elements as the XML gives them: one text each), named `/<robot>/skin/<port>`.
#[test]
fn skin_wrapper_serves_icub_skin_ports() {
    let mut wrapper = open(
        "device skinWrapper\nsubdevice fakeAnalogSensor\nrobotName /icub\nperiod 20\ntotal_taxels 6\nchannelsNum 6\nports (left_hand left_forearm)\nleft_hand \"0 1 0 1\"\nleft_forearm \"2 5 0 3\"\n",
    );
    let hand = read_from("/icub/skin/left_hand", "/skin/h", 1);
    let forearm = read_from("/icub/skin/left_forearm", "/skin/f", 1);
    assert_eq!(hand[0].1.len(), 2);
    assert_eq!(forearm[0].1.len(), 4);
    assert!(hand[0].0.is_some(), "with an envelope");
    let replies = rpc_calls("/icub/skin/left_hand/rpc:i", &["[iana] [cal]"]);
    assert_eq!(replies, ["0"]);
    wrapper.close().unwrap();
}
