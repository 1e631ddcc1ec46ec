"""An rclpy subscriber to a robot's ROS 2 topics, for yarp-devices-ros2's tests and bench.

  robot_watch.py TOPIC=TYPE... [--info TOPIC]... [--rates SECONDS] [--timeout S]

Subscribes (reliable, volatile, depth 10: rclpy's default) to every TOPIC (TYPE such as
sensor_msgs/msg/JointState), and prints, one line each, flushed:

  FIRST <topic> <json>       the first message of each topic (a summary)
  HASH <topic> <json>        once matched and named: the publishers' nodes and type hashes
                             (as their USER_DATA announces them), this subscriber's (rclpy's own)
  INFO <topic> <json>        for each --info topic (a type this venv may lack): every
                             endpoint's node, type and hash, once one publisher and one
                             subscription are seen
  RATE <topic> <json>        with --rates: messages, rate and inter-arrival jitter over that
                             many seconds, measured after every topic has delivered once
  DONE
"""
import argparse
import importlib
import json
import statistics
import time

import rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy, DurabilityPolicy, HistoryPolicy


def say(*parts):
    print(*parts, flush=True)


def load_type(name):
    pkg, kind, cls = name.split("/")
    return getattr(importlib.import_module(f"{pkg}.{kind}"), cls)


def summary(m):
    t = type(m).__name__
    out = {"type": t}
    if hasattr(m, "header"):
        out["frame_id"] = m.header.frame_id
        out["stamp"] = m.header.stamp.sec + m.header.stamp.nanosec * 1e-9
    if t == "JointState":
        out.update(name=list(m.name), position=list(m.position), velocity=len(m.velocity),
                   effort=len(m.effort))
    elif t == "WrenchStamped":
        f, q = m.wrench.force, m.wrench.torque
        out.update(force=[f.x, f.y, f.z], torque=[q.x, q.y, q.z])
    elif t == "Imu":
        o, a, w = m.orientation, m.linear_acceleration, m.angular_velocity
        out.update(orientation=[o.x, o.y, o.z, o.w], linear_acceleration=[a.x, a.y, a.z],
                   angular_velocity=[w.x, w.y, w.z])
    elif t == "MagneticField":
        f = m.magnetic_field
        out.update(magnetic_field=[f.x, f.y, f.z])
    elif t == "Temperature":
        out.update(temperature=m.temperature, variance=m.variance)
    elif t == "Int8MultiArray":
        out.update(data=list(m.data))
    return out


def endpoints(infos):
    return [{"node": i.node_name, "namespace": i.node_namespace, "type": i.topic_type,
             "hash": str(i.topic_type_hash)} for i in infos]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("topics", nargs="+")
    ap.add_argument("--info", action="append", default=[])
    ap.add_argument("--rates", type=float, default=0.0)
    ap.add_argument("--timeout", type=float, default=60.0)
    args = ap.parse_args()
    deadline = time.monotonic() + args.timeout
    rclpy.init()
    node = rclpy.create_node("yarp_devices_ros2_watch")
    qos = QoSProfile(reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.VOLATILE,
                     history=HistoryPolicy.KEEP_LAST, depth=10)
    topics = [t.split("=", 1) for t in args.topics]
    first = {}
    arrivals = {t: [] for t, _ in topics}
    measuring = [False]

    def callback(topic):
        def cb(m):
            now = time.monotonic()
            if topic not in first:
                first[topic] = True
                say("FIRST", topic, json.dumps(summary(m)))
            if measuring[0]:
                arrivals[topic].append(now)
        return cb

    for topic, type_name in topics:
        node.create_subscription(load_type(type_name), topic, callback(topic), qos)
    say("READY")
    hashed, infos = set(), set()
    try:
        while time.monotonic() < deadline:
            rclpy.spin_once(node, timeout_sec=0.01)
            for topic, _ in topics:
                if topic in hashed:
                    continue
                pubs = node.get_publishers_info_by_topic(topic)
                subs = [s for s in node.get_subscriptions_info_by_topic(topic)
                        if s.node_name == node.get_name()]
                # ROS node names come with the graph's ros_discovery_info, after DDS's
                named = all(p.node_name != "_CREATED_BY_BARE_DDS_APP_" for p in pubs)
                if pubs and subs and named:
                    hashed.add(topic)
                    say("HASH", topic, json.dumps({"pubs": endpoints(pubs),
                                                   "own": str(subs[0].topic_type_hash)}))
            for topic in args.info:
                if topic in infos:
                    continue
                pubs = node.get_publishers_info_by_topic(topic)
                subs = node.get_subscriptions_info_by_topic(topic)
                if pubs and subs:
                    infos.add(topic)
                    say("INFO", topic, json.dumps({"pubs": endpoints(pubs), "subs": endpoints(subs)}))
            if len(first) == len(topics) and len(hashed) == len(topics) and \
                    len(infos) == len(args.info):
                break
        if args.rates > 0 and len(first) == len(topics):
            measuring[0] = True
            end = time.monotonic() + args.rates
            while time.monotonic() < end:
                rclpy.spin_once(node, timeout_sec=0.005)
            for topic, _ in topics:
                a = arrivals[topic]
                gaps = [(b - x) * 1e3 for x, b in zip(a, a[1:])]
                gaps_sorted = sorted(gaps)
                say("RATE", topic, json.dumps({
                    "n": len(a),
                    "hz": len(a) / args.rates,
                    "gap_mean_ms": statistics.fmean(gaps) if gaps else None,
                    "gap_std_ms": statistics.pstdev(gaps) if gaps else None,
                    "gap_p99_ms": gaps_sorted[min(len(gaps) - 1, len(gaps) * 99 // 100)] if gaps else None,
                    "gap_max_ms": gaps_sorted[-1] if gaps else None,
                }))
        say("DONE")
    finally:
        node.destroy_node()
        rclpy.shutdown()


if __name__ == "__main__":
    main()
