"""An rclpy subscriber on every ROS 2 topic it discovers, for tests/bench/cost.py.

    ros_counter.py --discover SECONDS [--exclude TOPIC...]

Waits until the set of topics has been stable for a while (at most --discover seconds),
subscribes to each one whose type it can import (best effort, depth 10: it accepts reliable
publishers too), prints `TOPICS <json list>`, then every second `COUNTS <json {topic: n}>`
(cumulative). Stops on SIGTERM / SIGINT or when stdin closes.
"""
import argparse
import importlib
import json
import signal
import sys
import threading
import time

import rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy, HistoryPolicy


def say(*parts):
    print(*parts, flush=True)


def load_type(name):
    pkg, kind, cls = name.split("/")
    return getattr(importlib.import_module(f"{pkg}.{kind}"), cls)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--discover", type=float, default=15.0)
    ap.add_argument("--exclude", nargs="*", default=["/rosout", "/parameter_events"])
    args = ap.parse_args()

    rclpy.init()
    node = rclpy.create_node("yarp_rs_cost_bench")
    found = {}
    t0 = time.time()
    stable_since = time.time()
    while time.time() - t0 < args.discover:
        rclpy.spin_once(node, timeout_sec=0.2)
        now = dict(node.get_topic_names_and_types())
        if set(now) != set(found):
            found = now
            stable_since = time.time()
        elif found and time.time() - stable_since > 3.0:
            break
    counts = {}
    subs = []
    qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT,
                     history=HistoryPolicy.KEEP_LAST)
    for topic, types in sorted(found.items()):
        if topic in args.exclude or not types:
            continue
        # Only what the gateway publishes: a topic it subscribes to (commands) has no
        # publisher here and would count nothing.
        if node.count_publishers(topic) == 0:
            continue
        try:
            cls = load_type(types[0])
        except Exception as e:  # noqa: BLE001 - an unknown type is reported, not fatal
            say("SKIP", topic, types[0], str(e))
            continue
        counts[topic] = 0

        def cb(_msg, topic=topic):
            counts[topic] += 1

        subs.append(node.create_subscription(cls, topic, cb, qos))
    say("TOPICS", json.dumps(sorted(counts)))

    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    threading.Thread(target=lambda: (sys.stdin.read(), stop.set()), daemon=True).start()
    last = time.time()
    while not stop.is_set():
        rclpy.spin_once(node, timeout_sec=0.1)
        if time.time() - last >= 1.0:
            last = time.time()
            say("COUNTS", json.dumps(counts))
    say("COUNTS", json.dumps(counts))
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
