"""An rclpy sensor_msgs/Image publisher: the direct-DDS reference for the gateway's image
benchmark (rclpy -> rclpy, same QoS and rate as YARP -> gateway -> rclpy).

  image_pub.py TOPIC --width W --height H --rate HZ --count N [--timeout S]

Waits for a subscriber, sends a few warm-up frames (index >= 1000000), then N rgb8 frames
at HZ, each stamped just before publish() and carrying its index in its first 4 pixel
bytes (little endian). Prints READY, START and DONE <seconds spent sending>.
"""
import argparse
import array
import struct
import time

import rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy, DurabilityPolicy, HistoryPolicy
from sensor_msgs.msg import Image


def say(*parts):
    print(*parts, flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("topic")
    ap.add_argument("--width", type=int, default=1280)
    ap.add_argument("--height", type=int, default=720)
    ap.add_argument("--rate", type=float, default=60.0)
    ap.add_argument("--count", type=int, default=300)
    ap.add_argument("--depth", type=int, default=10)
    ap.add_argument("--timeout", type=float, default=60.0)
    args = ap.parse_args()
    deadline = time.monotonic() + args.timeout
    rclpy.init()
    node = rclpy.create_node("gw_test_image_pub")
    try:
        qos = QoSProfile(reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.VOLATILE,
                         history=HistoryPolicy.KEEP_LAST, depth=args.depth)
        pub = node.create_publisher(Image, args.topic, qos)
        m = Image()
        m.header.frame_id = "camera"
        m.height, m.width, m.encoding, m.step = args.height, args.width, "rgb8", args.width * 3
        # An array.array is taken as is (bytes would be converted element by element).
        m.data = array.array("B", bytes(k % 251 for k in range(args.width * 3)) * args.height)
        say("READY")
        while pub.get_subscription_count() == 0 and time.monotonic() < deadline:
            rclpy.spin_once(node, timeout_sec=0.05)

        def send(i):
            m.data[0:4] = array.array("B", struct.pack("<I", i))
            now = time.time()
            m.header.stamp.sec = int(now)
            m.header.stamp.nanosec = int((now - int(now)) * 1e9)
            pub.publish(m)

        time.sleep(1.0)
        for j in range(3):
            send(1_000_000 + j)
            time.sleep(0.1)
        time.sleep(0.5)
        say("START")
        period = 1.0 / args.rate
        t0 = time.perf_counter()
        for i in range(args.count):
            t_next = t0 + i * period
            while (d := t_next - time.perf_counter()) > 0:
                time.sleep(d)
            send(i)
        say("DONE", time.perf_counter() - t0)
        time.sleep(2.0)  # let reliable repair finish
    finally:
        node.destroy_node()
        rclpy.shutdown()


if __name__ == "__main__":
    main()
