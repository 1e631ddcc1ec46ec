"""An rclpy node for the launcher's end-to-end test: reads a part's JointState, commands a
joint through the gateway's text-RPC topics, and watches the joint move.

  joint_probe.py PART JOINT TARGET_DEG [--prefix /icub] [--timeout S] [--go FILE]

Subscribes with rclpy's default QoS (reliable, keep last 10), as `ros2 topic echo` does.
Prints, one line each, flushed: READY (node up), FIRST <json> (first JointState: names,
positions), REPLY <text> (the YARP reply to `[set] [pos] JOINT TARGET`, sent once FILE
exists when --go is given: the test creates it when the part is calibrated), MOVED <deg>
(the joint reached the target within 1 degree), then exits 0. Exits 1 on timeout.
"""
import argparse
import json
import math
import os
import sys
import time

import rclpy
from sensor_msgs.msg import JointState
from std_msgs.msg import String


def say(*parts):
    print(*parts, flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("part")
    ap.add_argument("joint", type=int)
    ap.add_argument("target", type=float)
    ap.add_argument("--prefix", default="/icub", help="the robot's port prefix")
    ap.add_argument("--timeout", type=float, default=60.0)
    ap.add_argument("--go", help="command only once this file exists")
    a = ap.parse_args()

    rclpy.init()
    node = rclpy.create_node("launch_joint_probe")
    state = {"first": None, "pos": None, "reply": None}

    def on_joints(msg):
        if state["first"] is None:
            state["first"] = msg
            say("FIRST", json.dumps({"name": list(msg.name), "position": list(msg.position)}))
        if len(msg.position) > a.joint:
            state["pos"] = math.degrees(msg.position[a.joint])

    def on_reply(msg):
        # Other nodes' commands are answered on the same topic: only ours count.
        if sent_at is not None:
            state["reply"] = msg.data

    node.create_subscription(JointState, f"{a.prefix}/{a.part}/joint_states", on_joints, 10)
    node.create_subscription(String, f"{a.prefix}/{a.part}/rpc/reply", on_reply, 10)
    request = node.create_publisher(String, f"{a.prefix}/{a.part}/rpc/request", 10)
    say("READY")

    deadline = time.monotonic() + a.timeout
    sent_at = None
    code = 1
    try:
        while time.monotonic() < deadline:
            rclpy.spin_once(node, timeout_sec=0.05)
            if state["first"] is None or (a.go and not os.path.exists(a.go)):
                continue
            # Send (and re-send until answered: the gateway may not have matched us yet).
            if state["reply"] is None and (sent_at is None or time.monotonic() - sent_at > 1.0):
                request.publish(String(data=f"[set] [pos] {a.joint} {a.target:.1f}"))
                sent_at = time.monotonic()
            if state["reply"] is not None and sent_at is not None:
                say("REPLY", state["reply"])
                say("REPLY_AFTER", f"{time.monotonic() - sent_at:.3f}")
                sent_at = None
            if state["reply"] is not None and state["pos"] is not None:
                if abs(state["pos"] - a.target) < 1.0:
                    say("MOVED", f"{state['pos']:.2f}")
                    code = 0
                    break
    finally:
        node.destroy_node()
        rclpy.shutdown()
    sys.exit(code)


if __name__ == "__main__":
    main()
