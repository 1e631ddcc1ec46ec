"""A small rclpy peer for the gateway's integration tests.

Every mode prints one line per event on stdout ("READY", "MSG <json>", ...), flushes it,
and exits on its own after --timeout seconds at the latest, shutting rclpy down cleanly
(Fast DDS removes its shared-memory segments only then).

  peer.py sub  TYPE TOPIC [--count N] [--summary]  prints MSG <json> per message
  peer.py pub  TYPE TOPIC JSON [--count N] [--rate HZ] [--wait-sub] [--linger S]
  peer.py echo TYPE IN OUT                      re-publishes IN on OUT (latency reference)
  peer.py ping OUT IN [--count N] [--rate HZ]   String ping-pong, prints RTT p50/p99 in ms
  peer.py serve SRV NAME JSON_RESPONSE          prints REQ <json> per request
  peer.py call SRV NAME JSON_REQUEST            prints RESP <json>
  peer.py info TOPIC [--pubs N] [--subs N] [--named]  prints INFO <json> with type hashes
  peer.py info_many TOPIC...                     prints INFO {topic: [endpoint]} (rq/…: raw DDS)
  peer.py hash TYPE                             prints HASH <RIHS01 of rclpy's own endpoint>
"""
import argparse
import contextlib
import importlib
import json
import sys
import time

import rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy, DurabilityPolicy, HistoryPolicy


def say(*parts):
    print(*parts, flush=True)


def load_type(name):
    """'std_msgs/msg/String' -> class."""
    pkg, kind, cls = name.split("/")
    return getattr(importlib.import_module(f"{pkg}.{kind}"), cls)


def to_json(obj):
    if hasattr(obj, "get_fields_and_field_types"):
        return {k: to_json(getattr(obj, k)) for k in obj.get_fields_and_field_types()}
    if hasattr(obj, "tolist"):
        return obj.tolist()
    if isinstance(obj, (bytes, bytearray)):
        return list(obj)
    if isinstance(obj, (list, tuple)):
        return [to_json(x) for x in obj]
    return obj


def nested_class(type_str):
    """'sequence<std_msgs/MultiArrayDimension>' or 'std_msgs/Header' -> class or None."""
    inner = type_str
    if "<" in inner:
        inner = inner[inner.index("<") + 1 : inner.rindex(">")].split(",")[0]
    if "[" in inner:
        inner = inner[: inner.index("[")]
    if "/" not in inner:
        return None
    pkg, cls = inner.split("/")
    return getattr(importlib.import_module(f"{pkg}.msg"), cls)


def from_json(cls, data):
    msg = cls()
    types = cls.get_fields_and_field_types()
    for key, value in data.items():
        sub = nested_class(types[key])
        if sub is not None and isinstance(value, list):
            value = [from_json(sub, v) for v in value]
        elif sub is not None:
            value = from_json(sub, value)
        setattr(msg, key, value)
    return msg


def summary(m, received):
    """A large message (Image, PointCloud2) without its data: sizes, SHA-256 and age of the stamp when
    the callback got it (`received`, time.time(): before the digest, which is the test's
    own cost)."""
    import hashlib
    data = bytes(m.data)
    stamp = m.header.stamp.sec + m.header.stamp.nanosec * 1e-9
    out = {"width": m.width, "height": m.height, "encoding": getattr(m, "encoding", None),
           "step": getattr(m, "step", getattr(m, "row_step", None)),
           "len": len(data), "sha256": hashlib.sha256(data).hexdigest(),
           "frame_id": m.header.frame_id, "age_ms": (received - stamp) * 1e3,
           "sec": m.header.stamp.sec, "nanosec": m.header.stamp.nanosec,
           "head": int.from_bytes(data[:4], "little")}
    if hasattr(m, "fields"):  # PointCloud2
        out["fields"] = [[f.name, f.offset, f.datatype, f.count] for f in m.fields]
        out["point_step"] = m.point_step
    return out


def qos(args):
    return QoSProfile(
        reliability=ReliabilityPolicy.BEST_EFFORT if args.best_effort else ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.TRANSIENT_LOCAL if args.transient else DurabilityPolicy.VOLATILE,
        history=HistoryPolicy.KEEP_LAST,
        depth=args.depth,
    )


@contextlib.contextmanager
def fresh_node(name):
    """A node on a context (a DDS participant) of its own, with its executor; shut down
    on leaving."""
    from rclpy.executors import SingleThreadedExecutor
    ctx = rclpy.context.Context()
    rclpy.init(context=ctx)
    n = rclpy.create_node(name, context=ctx)
    ex = SingleThreadedExecutor(context=ctx)
    ex.add_node(n)
    try:
        yield n, ex
    finally:
        ex.shutdown()
        n.destroy_node()
        rclpy.shutdown(context=ctx)


def spin_until(node, done, deadline):
    while not done() and time.monotonic() < deadline:
        rclpy.spin_once(node, timeout_sec=0.05)


def endpoint_json(info):
    return {
        "node": info.node_name,
        "namespace": info.node_namespace,
        "type": info.topic_type,
        "hash": str(info.topic_type_hash),
        "kind": "pub" if info.endpoint_type == rclpy.topic_endpoint_info.TopicEndpointTypeEnum.PUBLISHER else "sub",
        "durability": info.qos_profile.durability.name,
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mode")
    ap.add_argument("args", nargs="*")
    ap.add_argument("--count", type=int, default=1)
    ap.add_argument("--rate", type=float, default=20.0)
    ap.add_argument("--timeout", type=float, default=20.0)
    ap.add_argument("--wait-sub", action="store_true")
    ap.add_argument("--linger", type=float, default=0.5,
                    help="pub: seconds to stay after the last message (transient_local late joiners)")
    ap.add_argument("--best-effort", action="store_true")
    ap.add_argument("--transient", action="store_true")
    ap.add_argument("--depth", type=int, default=10)
    ap.add_argument("--pubs", type=int, default=0)
    ap.add_argument("--subs", type=int, default=0)
    ap.add_argument("--named", action="store_true", help="info: wait for node names too")
    ap.add_argument("--summary", action="store_true", help="sub: print images as digests")
    ap.add_argument("--cancel-after", type=float, default=None,
                    help="action: cancel the goal this many seconds after it was accepted")
    args = ap.parse_args()
    deadline = time.monotonic() + args.timeout
    rclpy.init()
    node = rclpy.create_node(f"gw_test_{args.mode}")
    try:
        run(node, args, deadline)
    finally:
        node.destroy_node()
        rclpy.shutdown()


def run(node, args, deadline):
    mode, a = args.mode, args.args
    if mode == "sub":
        got = []

        def cb(m):
            received = time.time()
            got.append(None)  # a count: keeping every image (2.7 MB at 720p) grows the process
            if args.summary:
                say("MSG", json.dumps(summary(m, received)))
            else:
                say("MSG", json.dumps(to_json(m)))

        node.create_subscription(load_type(a[0]), a[1], cb, qos(args))
        say("READY")
        spin_until(node, lambda: len(got) >= args.count, deadline)
    elif mode == "pub":
        cls = load_type(a[0])
        pub = node.create_publisher(cls, a[1], qos(args))
        msg = from_json(cls, json.loads(a[2]))
        say("READY")
        if args.wait_sub:
            spin_until(node, lambda: pub.get_subscription_count() > 0, deadline)
        for i in range(args.count):
            if time.monotonic() > deadline:
                break
            pub.publish(msg)
            say("SENT", i)
            rclpy.spin_once(node, timeout_sec=1.0 / args.rate)
        spin_until(node, lambda: False, min(deadline, time.monotonic() + args.linger))
    elif mode == "oneshot":
        # --count short-lived nodes one after the other, each on a context (a DDS
        # participant) of its own: it waits until its writer has matched a subscriber,
        # publishes one message (a[2] with {i} replaced by its number), stays --linger
        # seconds and leaves.
        cls = load_type(a[0])
        say("READY")
        for i in range(args.count):
            with fresh_node(f"gw_test_oneshot_{i}") as (n, ex):
                pub = n.create_publisher(cls, a[1], qos(args))
                end = min(deadline, time.monotonic() + 10.0)
                while pub.get_subscription_count() == 0 and time.monotonic() < end:
                    ex.spin_once(timeout_sec=0.05)
                if pub.get_subscription_count() == 0:
                    say("UNMATCHED", i)
                pub.publish(from_json(cls, json.loads(a[2].replace("{i}", str(i)))))
                say("SENT", i)
                end = time.monotonic() + args.linger
                while time.monotonic() < end:
                    ex.spin_once(timeout_sec=0.05)
    elif mode == "echo":
        cls = load_type(a[0])
        pub = node.create_publisher(cls, a[2], qos(args))
        n = [0]

        def cb(m):
            pub.publish(m)
            n[0] += 1

        node.create_subscription(cls, a[1], cb, qos(args))
        say("READY")
        spin_until(node, lambda: n[0] >= args.count, deadline)
    elif mode == "ping":
        from std_msgs.msg import String
        pub = node.create_publisher(String, a[0], qos(args))
        rtts, sent = [], {}

        def cb(m):
            t = sent.pop(m.data, None)
            if t is not None:
                rtts.append(time.perf_counter() - t)

        node.create_subscription(String, a[1], cb, qos(args))
        say("READY")
        # Warm up until the echo answers, then measure.
        i = 0
        while not rtts and time.monotonic() < deadline:
            sent[f"w{i}"] = time.perf_counter()
            pub.publish(String(data=f"w{i}"))
            i += 1
            spin_until(node, lambda: bool(rtts), time.monotonic() + 0.1)
        rtts.clear()
        sent.clear()
        period = 1.0 / args.rate
        for k in range(args.count):
            t_next = time.perf_counter() + period
            sent[str(k)] = time.perf_counter()
            pub.publish(String(data=str(k)))
            while time.perf_counter() < t_next:
                rclpy.spin_once(node, timeout_sec=max(0.0, t_next - time.perf_counter()))
        spin_until(node, lambda: not sent, min(deadline, time.monotonic() + 1.0))
        rtts.sort()
        if rtts:
            say("RTT", json.dumps({"n": len(rtts), "lost": len(sent),
                                   "p50_ms": rtts[len(rtts) // 2] * 1e3,
                                   "p99_ms": rtts[min(len(rtts) - 1, len(rtts) * 99 // 100)] * 1e3}))
        else:
            say("RTT", json.dumps({"n": 0, "lost": len(sent)}))
    elif mode == "serve":
        cls = load_type(a[0])
        reply = json.loads(a[2])
        n = [0]

        def cb(req, resp):
            say("REQ", json.dumps(to_json(req)))
            for k, v in reply.items():
                setattr(resp, k, v)
            n[0] += 1
            return resp

        node.create_service(cls, a[1], cb)
        say("READY")
        spin_until(node, lambda: n[0] >= args.count, deadline)
    elif mode == "call":
        cls = load_type(a[0])
        cli = node.create_client(cls, a[1])
        while not cli.wait_for_service(timeout_sec=0.1):
            if time.monotonic() > deadline:
                say("NO_SERVICE")
                return
        say("READY")
        fut = cli.call_async(from_json(cls.Request, json.loads(a[2])))
        spin_until(node, fut.done, deadline)
        say("RESP", json.dumps(to_json(fut.result())) if fut.done() else "null")
    elif mode == "action":
        # An rclpy ActionClient: sends the goal a[2] to action a[1] of type a[0], prints
        # ACCEPTED or REJECTED, every FEEDBACK, CANCEL (with --cancel-after) and RESULT.
        from rclpy.action import ActionClient
        cls = load_type(a[0])
        client = ActionClient(node, cls, a[1])
        while not client.wait_for_server(timeout_sec=0.1):
            if time.monotonic() > deadline:
                say("NO_SERVER")
                return
        say("READY")
        fut = client.send_goal_async(
            from_json(cls.Goal, json.loads(a[2])),
            feedback_callback=lambda fb: say("FEEDBACK", json.dumps(to_json(fb.feedback))))
        spin_until(node, fut.done, deadline)
        handle = fut.result() if fut.done() else None
        if handle is None or not handle.accepted:
            say("REJECTED")
            return
        say("ACCEPTED")
        if args.cancel_after is not None:
            spin_until(node, lambda: False, time.monotonic() + args.cancel_after)
            cf = handle.cancel_goal_async()
            spin_until(node, cf.done, deadline)
            r = cf.result()
            say("CANCEL", json.dumps({"return_code": r.return_code,
                                      "canceling": len(r.goals_canceling)}))
        rf = handle.get_result_async()
        spin_until(node, rf.done, deadline)
        if rf.done():
            r = rf.result()
            say("RESULT", json.dumps({"status": r.status, "result": to_json(r.result)}))
        else:
            say("RESULT", "null")
    elif mode == "action_serve":
        # An rclpy ActionServer of Fibonacci (type a[0], name a[1]): one term every 50 ms,
        # with feedback; a negative order is rejected; cancel requests are accepted. Prints
        # GOAL for every goal offered; serves until --count goals have ended (and
        # --linger seconds more, to answer the last result).
        from rclpy.action import ActionServer, CancelResponse, GoalResponse
        from rclpy.callback_groups import ReentrantCallbackGroup
        from rclpy.executors import MultiThreadedExecutor
        cls = load_type(a[0])
        ended = [0]

        def on_goal(goal):
            say("GOAL", json.dumps(to_json(goal)))
            return GoalResponse.REJECT if goal.order < 0 else GoalResponse.ACCEPT

        def execute(handle):
            seq = [0, 1]
            for i in range(1, handle.request.order):
                if handle.is_cancel_requested:
                    handle.canceled()
                    break
                time.sleep(0.05)
                seq.append(seq[i] + seq[i - 1])
                fb = cls.Feedback()
                fb.sequence = seq
                handle.publish_feedback(fb)
            else:
                handle.succeed()
            ended[0] += 1
            r = cls.Result()
            r.sequence = seq
            return r

        ActionServer(node, cls, a[1], execute_callback=execute, goal_callback=on_goal,
                     cancel_callback=lambda _: CancelResponse.ACCEPT,
                     callback_group=ReentrantCallbackGroup())
        ex = MultiThreadedExecutor()
        ex.add_node(node)
        say("READY")
        while ended[0] < args.count and time.monotonic() < deadline:
            ex.spin_once(timeout_sec=0.05)
        # The last result is answered after its execute callback returned: stay a while.
        end = min(deadline, time.monotonic() + args.linger)
        while time.monotonic() < end:
            ex.spin_once(timeout_sec=0.05)
        ex.shutdown()
    elif mode == "call_fresh":
        # `call`, --count times, each from a fresh node on a context (a DDS participant)
        # of its own: how `ros2 param list` meets a server, once per command.
        cls = load_type(a[0])
        for i in range(args.count):
            with fresh_node(f"gw_test_fresh_{i}") as (n, ex):
                cli = n.create_client(cls, a[1])
                end = min(deadline, time.monotonic() + 10.0)
                while not cli.service_is_ready() and time.monotonic() < end:
                    ex.spin_once(timeout_sec=0.05)
                fut = cli.call_async(from_json(cls.Request, json.loads(a[2])))
                while not fut.done() and time.monotonic() < end:
                    ex.spin_once(timeout_sec=0.05)
                say("RESP", json.dumps(to_json(fut.result())) if fut.done() else "null")
    elif mode == "info":
        topic = a[0]
        pubs, subs = [], []

        def ready():
            pubs[:] = node.get_publishers_info_by_topic(topic)
            subs[:] = node.get_subscriptions_info_by_topic(topic)
            named = all(e.node_name != "_CREATED_BY_BARE_DDS_APP_" for e in pubs + subs)
            return len(pubs) >= args.pubs and len(subs) >= args.subs and (named or not args.named)

        spin_until(node, ready, deadline)
        say("INFO", json.dumps({"pubs": [endpoint_json(p) for p in pubs],
                                "subs": [endpoint_json(s) for s in subs]}))
    elif mode == "info_many":
        # Every named topic (ROS names, or raw DDS names `rq/…`/`rr/…` of services)
        # until each has an endpoint from a named node.
        found = {}

        def ready_all():
            for topic in a:
                raw = topic.startswith(("rq/", "rr/", "rt/"))
                es = node.get_publishers_info_by_topic(topic, no_mangle=raw) + \
                    node.get_subscriptions_info_by_topic(topic, no_mangle=raw)
                found[topic] = [endpoint_json(e) for e in es]
            # a node's name arrives apart from its endpoints (ros_discovery_info):
            # until then rclpy says unknown
            unnamed = ("_CREATED_BY_BARE_DDS_APP_", "_NODE_NAME_UNKNOWN_")
            return all(found[t] and all(e["node"] not in unnamed
                                        for e in found[t]) for t in a)

        spin_until(node, ready_all, deadline)
        say("INFO", json.dumps(found))
    elif mode == "hash":
        topic = "/gw_test_hash_probe"
        node.create_publisher(load_type(a[0]), topic, 10)
        infos = []
        spin_until(node, lambda: bool(infos.extend(node.get_publishers_info_by_topic(topic)) or infos), deadline)
        say("HASH", str(infos[0].topic_type_hash) if infos else "none")
    else:
        say("BAD_MODE", mode)
        sys.exit(2)


if __name__ == "__main__":
    main()
