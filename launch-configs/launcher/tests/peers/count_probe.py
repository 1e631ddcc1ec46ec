"""An rclpy node that subscribes to one topic with rclpy's default QoS (reliable, volatile,
keep last 10) and keeps counting what arrives, for the fault tests: the same node, never
restarted, must receive again after the publisher (the gateway) is killed and restarted.

  count_probe.py [--timeout S] TOPIC pkg/msg/Type

Prints, one line each, flushed: READY (node up), then COUNT <n> every 0.25 s until the
timeout (then exits 0).
"""
import argparse
import importlib
import time

import rclpy


def message_class(name):
    pkg, kind, cls = name.split("/")
    return getattr(importlib.import_module(f"{pkg}.{kind}"), cls)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("topic")
    ap.add_argument("type")
    ap.add_argument("--timeout", type=float, default=120.0)
    a = ap.parse_args()

    rclpy.init()
    node = rclpy.create_node("fault_count_probe")
    count = [0]

    def on_message(_msg):
        count[0] += 1

    node.create_subscription(message_class(a.type), a.topic, on_message, 10)
    print("READY", flush=True)
    deadline = time.monotonic() + a.timeout
    next_report = 0.0
    try:
        while time.monotonic() < deadline:
            rclpy.spin_once(node, timeout_sec=0.05)
            if time.monotonic() >= next_report:
                print("COUNT", count[0], flush=True)
                next_report = time.monotonic() + 0.25
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    main()
