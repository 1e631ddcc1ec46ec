#!/usr/bin/env python3
"""What the main job costs: CPU, RSS and threads per process, at rest and under a standard load.

Run by hand from the repository root, after building the programs (`cargo build --workspace
--bins`, add `--release` for `--profile release`):

    python3 tests/bench/cost.py [icub-sim|fake-devices|FILE.toml] [--profile debug|release]
                                [--settle 10] [--window 30] [--no-load] [--json OUT]

It re-runs itself under ../shared/netns-run (a private loopback: the job's fixed ports do not
clash with anything else), starts `yarp-launch CONFIG` with its own yarp.conf directory,
waits for "is up", lets it settle, then measures every process of the job (yarp-launch and
its descendants) over the window from /proc: CPU as a share of one core (utime + stime),
the busiest thread, RSS and thread count at the end of the window.

Then the standard load, measured over a second window of the same length:
- a `yarp read` on every output port of the robot (`/icub/...:o`, camera excluded: printing
  an image as text costs the reader, not the job, and the rclpy subscriber gets it anyway);
- an rclpy subscriber (tests/bench/ros_counter.py, `$ROS_VENV`, default
  /root/.cache/yarp-rs/venv-ros) on every topic the gateway publishes;
- position commands at 100 Hz on one part (`[poss]` on /icub/left_arm/command:i through
  `yarp write`; joint 0 swings ±5 degrees around where it is).
The messages actually delivered (lines printed by the readers, messages counted by the
subscriber, commands written) give the job's CPU per delivered message.

The load clients' own CPU is reported apart: it is not the job's, but on a small machine it
competes with it. Give the machine's load (`uptime`) with any figure you quote.
"""
import argparse
import json
import math
import os
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
HZ = os.sysconf("SC_CLK_TCK")
PAGE = os.sysconf("SC_PAGE_SIZE")


# ---------------------------------------------------------------- /proc sampling

def read_stat(path):
    """(comm, ppid, utime + stime in ticks) of /proc/PID/stat or /proc/PID/task/TID/stat."""
    with open(path) as f:
        s = f.read()
    comm = s[s.index("(") + 1 : s.rindex(")")]
    rest = s[s.rindex(")") + 2 :].split()
    return comm, int(rest[1]), int(rest[11]) + int(rest[12])


def descendants(root):
    """PIDs of `root` and every process below it."""
    children = {}
    for p in os.listdir("/proc"):
        if not p.isdigit():
            continue
        try:
            _, ppid, _ = read_stat(f"/proc/{p}/stat")
        except (OSError, ValueError):
            continue
        children.setdefault(ppid, []).append(int(p))
    out, todo = [], [root]
    while todo:
        p = todo.pop()
        out.append(p)
        todo.extend(children.get(p, []))
    return out


def exe_name(pid):
    try:
        return os.path.basename(os.readlink(f"/proc/{pid}/exe"))
    except OSError:
        try:
            return read_stat(f"/proc/{pid}/stat")[0]
        except OSError:
            return "?"


def threads(pid):
    """{tid: (name, ticks)}."""
    out = {}
    try:
        for t in os.listdir(f"/proc/{pid}/task"):
            try:
                name, _, ticks = read_stat(f"/proc/{pid}/task/{t}/stat")
                out[int(t)] = (name, ticks)
            except (OSError, ValueError):
                pass
    except OSError:
        pass
    return out


def rss_mb(pid):
    return rss_parts_mb(pid)[0]


def rss_parts_mb(pid):
    """(resident, of which file-backed or shared) in MB: statm's 2nd and 3rd fields.
    The difference is the anonymous memory (heaps, stacks)."""
    try:
        with open(f"/proc/{pid}/statm") as f:
            fields = f.read().split()
        return int(fields[1]) * PAGE / 1e6, int(fields[2]) * PAGE / 1e6
    except (OSError, IndexError, ValueError):
        return 0.0, 0.0


def label(pid):
    """Program name, plus what distinguishes several yarpdev / python processes."""
    name = exe_name(pid)
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            argv = f.read().split(b"\0")
    except OSError:
        return name
    argv = [a.decode(errors="replace") for a in argv if a]
    if name == "yarpdev" and "--name" in argv:
        i = argv.index("--name")
        if i + 1 < len(argv):
            name += f" {argv[i + 1]}"
    return name


def process_ticks(pid):
    """utime + stime of the whole process (threads that ended included)."""
    try:
        return read_stat(f"/proc/{pid}/stat")[2]
    except (OSError, ValueError):
        return None


def measure(pids, seconds):
    """Per process: cpu %, busiest thread (name, %), rss MB, threads, over `seconds`."""
    before = {p: (process_ticks(p), threads(p)) for p in pids}
    t0 = time.monotonic()
    time.sleep(seconds)
    after = {p: (process_ticks(p), threads(p)) for p in pids}
    dt = time.monotonic() - t0
    rows = []
    for p in pids:
        (tb, thb), (ta, tha) = before[p], after[p]
        if tb is None or ta is None:
            continue  # ended meanwhile
        per = []
        for tid, (name, ticks) in tha.items():
            start = thb[tid][1] if tid in thb else 0  # born in the window: all of it
            per.append(((ticks - start) / HZ / dt * 100.0, name))
        per.sort(reverse=True)
        rows.append({
            "pid": p,
            "process": label(p),
            "cpu": (ta - tb) / HZ / dt * 100.0,
            "top_thread": per[0][1] if per else "",
            "top_thread_cpu": per[0][0] if per else 0.0,
            "rss_mb": rss_mb(p),
            "threads": len(tha),
            "top_threads": [(round(c, 2), n) for c, n in per[:12]],
        })
    return rows, dt


# ---------------------------------------------------------------- child processes

class Lines:
    """Reads a child's stdout in a thread: counts lines, keeps the last few."""

    def __init__(self, proc, keep=40, on_line=None):
        self.proc, self.count, self.tail, self.on_line = proc, 0, [], on_line
        self.keep = keep
        self.lock = threading.Lock()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self):
        for raw in self.proc.stdout:
            line = raw.decode(errors="replace").rstrip("\n")
            with self.lock:
                self.count += 1
                self.tail.append(line)
                del self.tail[: -self.keep]
            if self.on_line:
                self.on_line(line)

    def snapshot(self):
        with self.lock:
            return self.count

    def last(self):
        with self.lock:
            return self.tail[-1] if self.tail else None


def stop(proc, sig=signal.SIGTERM, wait=10.0):
    """Asks `proc` to end, kills it after `wait`; never raises."""
    try:
        if proc.poll() is None:
            proc.send_signal(sig)
            proc.wait(timeout=wait)
    except subprocess.TimeoutExpired:
        proc.kill()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            print(f"cost.py: {proc.args[0]} (pid {proc.pid}) does not end", file=sys.stderr)
    except ProcessLookupError:
        pass


def wait_for(pred, limit, what):
    t0 = time.time()
    while time.time() - t0 < limit:
        if pred():
            return
        time.sleep(0.1)
    raise SystemExit(f"cost.py: {what} not within {limit:.0f} s")


# ---------------------------------------------------------------- the load

class Commander(threading.Thread):
    """`[poss]` on PART/command:i at `rate` Hz: joint 0 swings ±5° around where it was."""

    def __init__(self, yarp, env, part, start, rate=100.0):
        super().__init__(daemon=True)
        self.rate, self.start_pos, self.sent = rate, start, 0
        self.halt = threading.Event()
        self.proc = subprocess.Popen([yarp, "write", "/bench/cmd", f"{part}/command:i"],
                                     env=env, stdin=subprocess.PIPE,
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

    def run(self):
        period = 1.0 / self.rate
        t0 = next_t = time.monotonic()
        while not self.halt.is_set():
            pos = list(self.start_pos)
            pos[0] += 5.0 * math.sin(2 * math.pi * 0.2 * (time.monotonic() - t0))
            line = "([poss]) (" + " ".join(f"{x:.3f}" for x in pos) + ")\n"
            try:
                self.proc.stdin.write(line.encode())
                self.proc.stdin.flush()
            except (BrokenPipeError, ValueError):
                return
            self.sent += 1
            next_t += period
            delay = next_t - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            elif delay < -0.1:
                next_t = time.monotonic()

    def close(self):
        self.halt.set()
        self.join(timeout=2)
        try:
            self.proc.stdin.close()
        except OSError:
            pass
        stop(self.proc)


def port_names(yarp, env):
    r = subprocess.run([yarp, "name", "list"], env=env, capture_output=True, timeout=20)
    return re.findall(r"registration name (\S+)", r.stdout.decode(errors="replace"))


# ---------------------------------------------------------------- report

def table(title, rows, dt):
    out = [f"{title} (window {dt:.0f} s)", "",
           "| process | CPU (% of one core) | busiest thread | RSS (MB) | threads |",
           "|---|---:|---|---:|---:|"]
    for r in sorted(rows, key=lambda r: -r["cpu"]):
        out.append(f"| {r['process']} | {r['cpu']:.1f} | {r['top_thread']} "
                   f"{r['top_thread_cpu']:.1f} | {r['rss_mb']:.0f} | {r['threads']} |")
    total = sum(r["cpu"] for r in rows)
    out.append(f"| **total** | **{total:.1f}** | | {sum(r['rss_mb'] for r in rows):.0f} "
               f"| {sum(r['threads'] for r in rows)} |")
    return "\n".join(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("config", nargs="?", default="icub-sim")
    ap.add_argument("--profile", default="debug", choices=["debug", "release"])
    ap.add_argument("--settle", type=float, default=10.0)
    ap.add_argument("--window", type=float, default=30.0)
    ap.add_argument("--no-load", action="store_true")
    ap.add_argument("--command-part", default="/icub/left_arm")
    ap.add_argument("--json", help="also write the figures here")
    ap.add_argument("--threads", action="store_true",
                    help="also list each process's busiest threads at rest")
    ap.add_argument("--no-netns", action="store_true", help="do not re-run under netns-run")
    args = ap.parse_args()

    netns = os.path.join(ROOT, "..", "shared", "netns-run")
    if not args.no_netns and os.environ.get("NETNS_RUN_INSIDE") != "1":
        if not os.path.exists(netns):
            raise SystemExit(f"cost.py: no {netns}; run with --no-netns to use this network")
        os.execv(netns, [netns, sys.executable, *sys.argv])

    target = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))
    bindir = os.path.join(target, args.profile)
    launch, yarp = os.path.join(bindir, "yarp-launch"), os.path.join(bindir, "yarp")
    for b in (launch, yarp):
        if not os.path.exists(b):
            raise SystemExit(f"cost.py: no {b}: build first (cargo build --workspace --bins"
                             f"{' --release' if args.profile == 'release' else ''})")
    config = args.config
    if not config.endswith((".toml", ".xml")):
        config = os.path.join(ROOT, "launch-configs", f"{config}.toml")

    tmp = tempfile.mkdtemp(prefix="yarp-cost-")
    env = dict(os.environ, YARP_CONFIG_HOME=tmp, NO_COLOR="1",
               ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
               # Fast DDS's /dev/shm segments are not isolated by netns-run.
               FASTDDS_BUILTIN_TRANSPORTS="UDPv4")
    cmd = [launch, config]
    with open(config) as f:
        if "xsens_serial" in f.read():
            cmd += ["--set", f"xsens_serial={tmp}/ttyXSENS"]
    print(f"cost.py: {' '.join(cmd)}  (load: {os.getloadavg()[0]:.2f})", file=sys.stderr)
    job = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                           start_new_session=True)
    up = threading.Event()
    job_lines = Lines(job, keep=200, on_line=lambda l: " is up in " in l and up.set())
    loaders = []
    report = {"config": args.config, "profile": args.profile}
    try:
        wait_for(lambda: up.is_set() or job.poll() is not None, 300, "the job up")
        if job.poll() is not None:
            print("\n".join(job_lines.tail), file=sys.stderr)
            raise SystemExit("cost.py: the job exited")
        time.sleep(args.settle)
        pids = descendants(job.pid)
        load_before = os.getloadavg()
        rows, dt = measure(pids, args.window)
        report["rest"] = {"rows": rows, "window_s": dt, "loadavg": load_before}
        print(table(f"at rest, {args.config} ({args.profile}), load avg "
                    f"{load_before[0]:.2f} at the start", rows, dt))
        if args.threads:
            for r in sorted(rows, key=lambda r: -r["cpu"]):
                print(f"\n{r['process']}: " + ", ".join(
                    f"{n} {c:.1f}" for c, n in r["top_threads"] if c > 0.05))
        if args.no_load:
            return
        # ---- the load
        ports = [p for p in port_names(yarp, env)
                 if p.startswith("/icub/") and p.endswith(":o")
                 and "/cam/" not in p and "rpc" not in p]
        readers = {}
        for i, p in enumerate(ports):
            proc = subprocess.Popen([yarp, "read", f"/bench/read{i}", p], env=env,
                                    stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
            loaders.append(proc)
            readers[p] = Lines(proc, keep=2)
        venv = os.environ.get("ROS_VENV", "/root/.cache/yarp-rs/venv-ros")
        ros = subprocess.Popen([os.path.join(venv, "bin", "python"), "-u",
                                os.path.join(ROOT, "tests", "bench", "ros_counter.py"),
                                "--discover", "20"],
                               env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                               stderr=subprocess.DEVNULL)
        loaders.append(ros)
        ros_state = {"topics": None, "counts": {}}

        def on_ros(line):
            kind, _, rest = line.partition(" ")
            if kind == "TOPICS":
                ros_state["topics"] = json.loads(rest)
            elif kind == "COUNTS":
                ros_state["counts"] = json.loads(rest)
        Lines(ros, keep=5, on_line=on_ros)
        state_port = f"{args.command_part}/state:o"
        wait_for(lambda: state_port in readers and readers[state_port].last(), 30,
                 f"a first {state_port}")
        start = [float(x) for x in readers[state_port].last().split()]
        commander = Commander(yarp, env, args.command_part, start)
        commander.start()
        wait_for(lambda: ros_state["topics"] is not None, 120, "the rclpy subscriber")
        time.sleep(5)  # connections made, first messages through
        y0 = {p: r.snapshot() for p, r in readers.items()}
        r0, c0 = dict(ros_state["counts"]), commander.sent
        load_pids = [p.pid for p in loaders] + [commander.proc.pid]
        all_rows, dt = measure(pids + load_pids, args.window)
        rows = [r for r in all_rows if r["pid"] in pids]
        client_rows = [r for r in all_rows if r["pid"] not in pids]
        time.sleep(1.2)  # the subscriber's counts of the window's end
        yarp_msgs = sum(r.snapshot() - y0[p] for p, r in readers.items())
        ros_msgs = sum(ros_state["counts"].get(t, 0) - r0.get(t, 0)
                       for t in ros_state["counts"])
        cmds = commander.sent - c0
        commander.close()
        msgs = yarp_msgs + ros_msgs + cmds
        job_cpu = sum(r["cpu"] for r in rows)
        rest_cpu = sum(r["cpu"] for r in report["rest"]["rows"])
        per_msg = job_cpu / 100.0 * dt / max(msgs, 1) * 1e6
        extra = max(job_cpu - rest_cpu, 0.0) / 100.0 * dt / max(msgs, 1) * 1e6
        load_after = os.getloadavg()
        print()
        print(table(f"under the standard load, load avg {load_after[0]:.2f}", rows, dt))
        print()
        print(f"load: {len(readers)} `yarp read` ({yarp_msgs / dt:.0f} msg/s), rclpy on "
              f"{len(ros_state['counts'])} topics ({ros_msgs / dt:.0f} msg/s), "
              f"{cmds / dt:.0f} commands/s on {args.command_part}: {msgs / dt:.0f} msg/s")
        print(f"job CPU per delivered message: {per_msg:.0f} µs "
              f"(above rest: {extra:.0f} µs)")
        print(f"load clients: {sum(r['cpu'] for r in client_rows):.0f} % of one core")
        report["load"] = {"rows": rows, "clients": client_rows, "window_s": dt,
                          "loadavg": load_after, "yarp_read_msgs": yarp_msgs,
                          "ros_msgs": ros_msgs, "commands": cmds,
                          "per_topic": ros_state["counts"],
                          "cpu_us_per_msg": per_msg, "cpu_us_per_msg_above_rest": extra}
    finally:
        for p in loaders:
            stop(p, signal.SIGINT if p.args[0].endswith("yarp") else signal.SIGTERM, 5)
        stop(job, signal.SIGINT, 40)
        if args.json:
            with open(args.json, "w") as f:
                json.dump(report, f, indent=1)


if __name__ == "__main__":
    main()
