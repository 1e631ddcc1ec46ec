#!/usr/bin/env python3
"""Round-trip latency of `yarp latency-test`, ours and C++'s, in the same run.

Run under ../shared/netns-run from the repository root, after `cargo build --release -p yarp-cli -p yarp-net`:

    ../shared/netns-run python3 tests/bench/latency_vs_cpp.py [--frames N] [--sizes 100,1000,...]

C++ programs come from $YARP_CPP_BIN (the pip-built C++ YARP 3.5, see tests/peers/install-cpp-yarp.sh);
without it only our pairs run. Every pair uses one name server (ours) and the tcp carrier in
no-reply mode (client writes, server writes back on its own connection: the only mode
C++ 3.5 has). Latency per frame = arrival - send time, including the server's copy of the
payload (the C++ 3.5 client reports it so; our client's log has it in a separate column,
added back here). Prints median and p99 in ms and the implied throughput (2 x size / median).
"""
import argparse
import os
import socket
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
TARGET = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))
OURS = os.path.join(TARGET, "release", "yarp")
OUR_SERVER = os.path.join(TARGET, "release", "yarpserver")


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_port_registered(yarp, env, name, limit=10.0):
    t0 = time.time()
    while time.time() - t0 < limit:
        r = subprocess.run([yarp, "exists", name], env=env, capture_output=True, timeout=10)
        if r.returncode == 0:
            return True
        time.sleep(0.1)
    return False


def run_pair(server_bin, client_bin, size, frames, env, workdir, ours_client):
    srv = subprocess.Popen([server_bin, "latency-test", "--server"], env=env,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        if not wait_port_registered(OURS, env, "/latencyTest/server"):
            return None
        prefix = os.path.join(workdir, f"log_{time.time_ns()}_")
        args = [client_bin, "latency-test", "--client", "--nframes", str(frames),
                "--payload_size", str(size), "--client_wait", "0", "--logfile", prefix]
        if ours_client:
            args.append("--no-reply")
        try:
            subprocess.run(args, env=env, capture_output=True, timeout=120)
        except subprocess.TimeoutExpired:
            return None
        path = f"{prefix}{size}.txt"
        if not os.path.exists(path):
            return None
        rows = [list(map(float, l.split())) for l in open(path) if l.strip()]
        # our client subtracts the server's copy time; add it back to compare like with like
        lat = [r[0] + (r[1] * 1000.0 if ours_client else 0.0) for r in rows[3:]]
        return lat
    finally:
        srv.terminate()
        try:
            srv.wait(5)
        except subprocess.TimeoutExpired:
            srv.kill()
            srv.wait()
        # a killed port may stay registered: the next pair must not find it
        for name in ("/latencyTest/server", "/latencyTest/client"):
            subprocess.run([OURS, "name", "unregister", name], env=env, capture_output=True, timeout=10)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=200)
    ap.add_argument("--sizes", default="100,1000,65536,1048576,8388608")
    a = ap.parse_args()
    cpp_dir = os.environ.get("YARP_CPP_BIN")
    cpp = os.path.join(cpp_dir, "yarp") if cpp_dir else None
    if cpp and not os.path.exists(cpp):
        cpp = None
    if not cpp:
        print("C++ YARP not found (set YARP_CPP_BIN): only our pairs run", file=sys.stderr)
    for b in (OURS, OUR_SERVER):
        if not os.path.exists(b):
            sys.exit(f"{b} missing: cargo build --release -p yarp-cli -p yarp-net")
    with tempfile.TemporaryDirectory() as d:
        env = dict(os.environ, YARP_CONFIG_HOME=d, YARP_DATA_HOME=d)
        port = free_port()
        subprocess.run([OURS, "conf", "127.0.0.1", str(port)], env=env, check=True, capture_output=True)
        ns = subprocess.Popen([OUR_SERVER, "--ip", "127.0.0.1", "--socket", str(port)], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            time.sleep(0.5)
            pairs = [("rust", OURS, "rust", OURS)]
            if cpp:
                pairs += [("c++", cpp, "c++", cpp), ("rust", OURS, "c++", cpp), ("c++", cpp, "rust", OURS)]
            print(f"{'client':<6} {'server':<6} {'size':>9} {'n':>5} {'median ms':>10} {'p99 ms':>8} {'MB/s':>9}")
            for size in [int(s) for s in a.sizes.split(",")]:
                frames = max(20, min(a.frames, (256 << 20) // max(size, 1)))
                for cname, cbin, sname, sbin in pairs:
                    lat = run_pair(sbin, cbin, size, frames, env, d, cname == "rust")
                    if not lat:
                        print(f"{cname:<6} {sname:<6} {size:>9} failed")
                        continue
                    lat.sort()
                    med = statistics.median(lat)
                    p99 = lat[min(len(lat) - 1, int(len(lat) * 0.99))]
                    mbps = 2 * size / (med / 1000.0) / 1e6 if med > 0 else 0
                    print(f"{cname:<6} {sname:<6} {size:>9} {len(lat):>5} {med:>10.3f} {p99:>8.3f} {mbps:>9.0f}")
                    sys.stdout.flush()
        finally:
            ns.terminate()
            ns.wait(5)


if __name__ == "__main__":
    main()
