#!/usr/bin/env python3
"""Round-trip latency of `yarp latency-test`, ours and C++'s, side by side in one run: every
client/server pair (ours -> ours, C++ -> C++, ours -> C++, C++ -> ours), every carrier both
implement (tcp, fast_tcp, udp, shmem), 100 B to 8 MB.

One command, from the repository root (builds what it needs, finds the C++ peer itself):

    ../shared/netns-run python3 tests/bench/latency_vs_cpp.py [--frames N] [--sizes 100,...]
        [--carriers tcp,fast_tcp,udp,shmem] [--markdown]

C++ programs come from $YARP_CPP_BIN, else from tests/peers/install-cpp-peers.sh icub (which
prints its bin directory, building C++ YARP on first use); without them only our pairs run.
Every pair uses one name server (ours). Both clients get the same options, so both use
replies on the same connection where the carrier has them (tcp, fast_tcp, shmem) and the
server's own output connection otherwise (udp). Latency per frame = arrival - send time,
including the server's copy of the payload (both clients log that copy time separately;
it is added back). Prints median and p99 in ms, the machine's load before and after, and
with --markdown one table per carrier for BENCHMARKS.md.
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
PAIRS = [("rust", "rust"), ("c++", "c++"), ("rust", "c++"), ("c++", "rust")]


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def load():
    with open("/proc/loadavg") as f:
        return " ".join(f.read().split()[:3]) + f" (load average, {os.cpu_count()} cores)"


def find_cpp():
    d = os.environ.get("YARP_CPP_BIN")
    if not d:
        script = os.path.join(ROOT, "tests", "peers", "install-cpp-peers.sh")
        try:
            r = subprocess.run([script, "icub"], capture_output=True, text=True, timeout=7200)
            d = r.stdout.strip().splitlines()[-1] if r.returncode == 0 and r.stdout.strip() else None
        except (OSError, subprocess.TimeoutExpired):
            d = None
    cpp = os.path.join(d, "yarp") if d else None
    return cpp if cpp and os.path.exists(cpp) else None


def wait_port_registered(env, name, limit=10.0):
    t0 = time.time()
    while time.time() - t0 < limit:
        r = subprocess.run([OURS, "exists", name], env=env, capture_output=True, timeout=10)
        if r.returncode == 0:
            return True
        time.sleep(0.1)
    return False


def run_pair(server_bin, client_bin, carrier, size, frames, env, workdir):
    srv = subprocess.Popen([server_bin, "latency-test", "--server"], env=env,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        if not wait_port_registered(env, "/latencyTest/server"):
            return None
        prefix = os.path.join(workdir, f"log_{time.time_ns()}_")
        args = [client_bin, "latency-test", "--client", "--nframes", str(frames),
                "--payload_size", str(size), "--client_wait", "0", "--logfile", prefix,
                "--protocol", carrier]
        try:
            subprocess.run(args, env=env, capture_output=True, timeout=15 + frames * 0.15)
        except subprocess.TimeoutExpired:
            return None
        path = f"{prefix}{size}.txt"
        if not os.path.exists(path):
            return None
        rows = [list(map(float, l.split())) for l in open(path) if l.strip()]
        # both clients subtract the server's copy time; add it back
        return [r[0] + r[1] * 1000.0 for r in rows[3:]]
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
    ap.add_argument("--carriers", default="tcp,fast_tcp,udp,shmem")
    ap.add_argument("--markdown", action="store_true")
    a = ap.parse_args()
    if not (os.path.exists(OURS) and os.path.exists(OUR_SERVER)):
        subprocess.run(["cargo", "build", "--release", "-p", "yarp-cli", "-p", "yarp-net"],
                       cwd=ROOT, check=True)
    cpp = find_cpp()
    if not cpp:
        print("C++ YARP not found (YARP_CPP_BIN, tests/peers/install-cpp-peers.sh icub): only our pairs run",
              file=sys.stderr)
    bins = {"rust": OURS, "c++": cpp}
    pairs = [p for p in PAIRS if cpp or p == ("rust", "rust")]
    sizes = [int(s) for s in a.sizes.split(",")]
    carriers = a.carriers.split(",")
    results = {}
    print(f"load before: {load()}")
    with tempfile.TemporaryDirectory() as d:
        env = dict(os.environ, YARP_CONFIG_HOME=d, YARP_DATA_HOME=d)
        if cpp and "YARP_DATA_DIRS" not in env:
            # C++ finds its carrier plugins (shmem) there
            env["YARP_DATA_DIRS"] = os.path.join(os.path.dirname(os.path.dirname(cpp)), "share", "yarp")
        port = free_port()
        subprocess.run([OURS, "conf", "127.0.0.1", str(port)], env=env, check=True, capture_output=True)
        ns = subprocess.Popen([OUR_SERVER, "--ip", "127.0.0.1", "--socket", str(port)], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            time.sleep(0.5)
            print(f"{'carrier':<9} {'client':<6} {'server':<6} {'size':>9} {'n':>5} {'median ms':>10} {'p99 ms':>8}")
            for carrier in carriers:
                for size in sizes:
                    frames = max(20, min(a.frames, (256 << 20) // max(size, 1)))
                    for cname, sname in pairs:
                        # a C++ server sometimes answers the first frame with an empty reply
                        # (C++ 3.12.3's server races with itself at the start of a test, see
                        # latency_case in yarp-proto/cli/tests/cpp_interop.rs): try again
                        for _ in range(3):
                            lat = run_pair(bins[sname], bins[cname], carrier, size, frames, env, d)
                            if lat:
                                break
                        if not lat:
                            print(f"{carrier:<9} {cname:<6} {sname:<6} {size:>9} failed")
                            continue
                        lat.sort()
                        med = statistics.median(lat)
                        p99 = lat[min(len(lat) - 1, int(len(lat) * 0.99))]
                        results[(carrier, size, cname, sname)] = (med, p99)
                        print(f"{carrier:<9} {cname:<6} {sname:<6} {size:>9} {len(lat):>5} {med:>10.3f} {p99:>8.3f}")
                        sys.stdout.flush()
        finally:
            ns.terminate()
            ns.wait(5)
    print(f"load after: {load()}")
    if a.markdown:
        print_markdown(results, carriers, sizes, pairs)


def human(size):
    if size >= 1 << 20:
        return f"{size >> 20} MB"
    if size >= 1 << 10 and size % 1024 == 0:
        return f"{size >> 10} KB"
    return f"{size} B"


def print_markdown(results, carriers, sizes, pairs):
    names = {"rust": "ours", "c++": "C++"}
    for carrier in carriers:
        print(f"\n`{carrier}`, median ms (p99):\n")
        head = " | ".join(f"{names[c]} → {names[s]}" for c, s in pairs)
        print(f"| size | {head} | worst mixed ÷ C++ |")
        print("|---" * (len(pairs) + 2) + "|")
        for size in sizes:
            cells = []
            for c, s in pairs:
                r = results.get((carrier, size, c, s))
                cells.append(f"{r[0]:.3f} ({r[1]:.2f})" if r else "failed")
            base = results.get((carrier, size, "c++", "c++"))
            mixed = [results.get((carrier, size, c, s)) for c, s in pairs if c != s]
            ratio = ""
            if base and mixed and all(mixed):
                ratio = f"{max(m[0] for m in mixed) / base[0]:.2f}×"
            print(f"| {human(size)} | " + " | ".join(cells) + f" | {ratio} |")


if __name__ == "__main__":
    main()
