"""An rclpy node for the launcher's end-to-end test: subscribes to state topics exactly as
`ros2 topic echo` and most nodes do (rclpy's default QoS: reliable, volatile, keep last 10)
and reports the first message of each.

  state_probe.py [--timeout S] TOPIC=pkg/msg/Type ...

Prints, one line each, flushed: READY (node up), GOT <topic> (first message on it), ALL
(every topic had one; exits 0). On timeout prints MISSING <topic> ... and exits 1.
"""
import argparse
import importlib
import sys
import time

import rclpy


def message_class(name):
    pkg, kind, cls = name.split("/")
    return getattr(importlib.import_module(f"{pkg}.{kind}"), cls)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("topics", nargs="+", help="TOPIC=pkg/msg/Type")
    ap.add_argument("--timeout", type=float, default=60.0)
    a = ap.parse_args()

    rclpy.init()
    node = rclpy.create_node("e2e_state_probe")
    got = set()

    def on_message(topic):
        def cb(_msg):
            if topic not in got:
                got.add(topic)
                print("GOT", topic, flush=True)
        return cb

    wanted = []
    for spec in a.topics:
        topic, type_name = spec.split("=", 1)
        wanted.append(topic)
        # depth 10 alone is rclpy's default profile (what `ros2 topic echo` asks for)
        node.create_subscription(message_class(type_name), topic, on_message(topic), 10)
    print("READY", flush=True)

    deadline = time.monotonic() + a.timeout
    code = 1
    try:
        while time.monotonic() < deadline:
            rclpy.spin_once(node, timeout_sec=0.1)
            if len(got) == len(wanted):
                print("ALL", flush=True)
                code = 0
                break
        else:
            print("MISSING", *[t for t in wanted if t not in got], flush=True)
    finally:
        node.destroy_node()
        rclpy.shutdown()
    sys.exit(code)


if __name__ == "__main__":
    main()
