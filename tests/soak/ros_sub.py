"""An rclpy node of the soak run (tests/soak/soak.py) that comes and goes: subscribes to the
given topics for a while, then prints `COUNTS <json {topic: n}>` and exits.

    ros_sub.py --seconds S TOPIC=pkg/msg/Type[@sensor] ...

Reliable, volatile, keep last 10, as rclpy's default (what `ros2 topic echo` does), so the
gateway sees an ordinary subscriber match and unmatch each time; `@sensor` subscribes with
qos_profile_sensor_data (best effort), for the camera the gateway publishes best effort.
"""
import argparse
import importlib
import json
import signal
import time

import rclpy
from rclpy.qos import qos_profile_sensor_data


def message_class(name):
    pkg, kind, cls = name.split("/")
    return getattr(importlib.import_module(f"{pkg}.{kind}"), cls)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("topics", nargs="+", help="TOPIC=pkg/msg/Type")
    ap.add_argument("--seconds", type=float, default=15.0)
    a = ap.parse_args()

    rclpy.init()
    node = rclpy.create_node("yarp_rs_soak_sub")
    counts = {}
    subs = []
    for spec in a.topics:
        topic, _, kind = spec.partition("=")
        kind, _, profile = kind.partition("@")
        counts[topic] = 0

        def cb(_msg, topic=topic):
            counts[topic] += 1

        subs.append(node.create_subscription(message_class(kind), topic, cb,
                                             qos_profile_sensor_data if profile == "sensor" else 10))
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    signal.signal(signal.SIGINT, lambda *_: stop.append(1))
    end = time.monotonic() + a.seconds
    while not stop and time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.1)
    print("COUNTS", json.dumps(counts), flush=True)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
