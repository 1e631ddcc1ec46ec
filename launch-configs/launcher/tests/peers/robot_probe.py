"""An rclpy node for the launcher's end-to-end test: the whole robot as ROS tools read it.

  robot_probe.py [--timeout S] [--camera-info TOPIC] JOINTS

Subscribes, as robot_state_publisher and RViz do, to /joint_states (rclpy's default QoS)
until one message names JOINTS joints, to /robot_description with transient-local
durability (it joins after the gateway published: the sample is latched), and optionally
to a CameraInfo topic (default QoS). Prints, flushed: READY, then JOINTS <json>,
URDF <json>, CAMERA_INFO <json> as each arrives, and DONE (exit 0); on timeout MISSING
<what> ... (exit 1).
"""
import argparse
import json
import time

import rclpy
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import CameraInfo, JointState
from std_msgs.msg import String


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("joints", type=int)
    ap.add_argument("--camera-info")
    ap.add_argument("--timeout", type=float, default=60.0)
    a = ap.parse_args()

    rclpy.init()
    node = rclpy.create_node("e2e_robot_probe")
    seen = {}

    def on_joints(m):
        if "JOINTS" not in seen and len(m.name) == a.joints:
            seen["JOINTS"] = {"name": list(m.name), "position": list(m.position),
                              "sec": m.header.stamp.sec}

    def on_urdf(m):
        seen.setdefault("URDF", {"len": len(m.data), "head": m.data[:300]})

    def on_info(m):
        seen.setdefault("CAMERA_INFO", {"width": m.width, "height": m.height,
                                        "k": list(m.k), "d": list(m.d),
                                        "distortion_model": m.distortion_model,
                                        "frame_id": m.header.frame_id})

    node.create_subscription(JointState, "/joint_states", on_joints, 10)
    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
    node.create_subscription(String, "/robot_description", on_urdf, latched)
    wanted = ["JOINTS", "URDF"]
    if a.camera_info:
        node.create_subscription(CameraInfo, a.camera_info, on_info, 10)
        wanted.append("CAMERA_INFO")
    print("READY", flush=True)

    printed = set()
    deadline = time.monotonic() + a.timeout
    code = 1
    try:
        while time.monotonic() < deadline:
            rclpy.spin_once(node, timeout_sec=0.1)
            for k in wanted:
                if k in seen and k not in printed:
                    printed.add(k)
                    print(k, json.dumps(seen[k]), flush=True)
            if len(printed) == len(wanted):
                print("DONE", flush=True)
                code = 0
                break
        else:
            print("MISSING", *[k for k in wanted if k not in seen], flush=True)
    finally:
        node.destroy_node()
        rclpy.shutdown()
    raise SystemExit(code)


if __name__ == "__main__":
    main()
