"""An rclpy node for the launcher's end-to-end test: waits for one sensor_msgs/Imu.

  imu_probe.py TOPIC [--timeout S]

Prints READY (node up), then IMU <json> with the first message's frame_id, orientation
quaternion `q` (x y z w), angular velocity `w` (rad/s) and linear acceleration `acc`
(m/s^2), flushed, and exits 0. Exits 1 on timeout.
"""
import argparse
import json
import sys
import time

import rclpy
from sensor_msgs.msg import Imu


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("topic")
    ap.add_argument("--timeout", type=float, default=60.0)
    args = ap.parse_args()
    deadline = time.monotonic() + args.timeout
    rclpy.init()
    node = rclpy.create_node("e2e_imu_probe")
    got = []
    # rclpy's default QoS (reliable, keep last 10): the gateway offers sensor streams so.
    node.create_subscription(Imu, args.topic, got.append, 10)
    print("READY", flush=True)
    while not got and time.monotonic() < deadline:
        rclpy.spin_once(node, timeout_sec=0.1)
    if not got:
        print("TIMEOUT", flush=True)
        return 1
    m = got[0]
    o, w, a = m.orientation, m.angular_velocity, m.linear_acceleration
    print("IMU", json.dumps({
        "frame_id": m.header.frame_id,
        "q": [o.x, o.y, o.z, o.w],
        "w": [w.x, w.y, w.z],
        "acc": [a.x, a.y, a.z],
    }), flush=True)
    node.destroy_node()
    rclpy.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
