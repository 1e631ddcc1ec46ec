#!/usr/bin/env python3
"""Soak run: the main job (icub-sim, gateway included) driven for minutes by clients that
come and go, every job process sampled once a second. Started by tests/soak/run.sh (which
puts it in a private network namespace); see tests/soak/README.md for what it checks.

    soak.py [--minutes 30] [--config icub-sim] [--out DIR]
"""
import argparse
import csv
import datetime
import json
import os
import random
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tests", "bench"))
import cost  # noqa: E402 - the /proc sampling and child-process helpers

PARTS = ["head", "torso", "left_arm", "right_arm", "left_leg", "right_leg"]
ROS_TOPICS = ["/joint_states=sensor_msgs/msg/JointState",
              "/icub/cam/left/image_raw=sensor_msgs/msg/Image@sensor"]


def log(*parts):
    print(f"soak [{time.strftime('%H:%M:%S')}]", *parts, file=sys.stderr, flush=True)


# ---------------------------------------------------------------- sampling

class Sampler(threading.Thread):
    """Every second: RSS, open fds, threads and CPU of every process of the job."""

    def __init__(self, root_pid, path):
        super().__init__(daemon=True)
        self.root, self.halt = root_pid, threading.Event()
        self.rows, self.lock, self.t0 = [], threading.Lock(), time.monotonic()
        self.prev = {}
        self.file = open(path, "w", newline="")
        self.csv = csv.writer(self.file)
        self.csv.writerow(["t_s", "pid", "process", "rss_mb", "rss_file_mb", "fds", "threads",
                           "cpu_pct"])

    def sample(self):
        now = time.monotonic()
        out = []
        for pid in cost.descendants(self.root):
            ticks = cost.process_ticks(pid)
            if ticks is None:
                continue
            try:
                fds = len(os.listdir(f"/proc/{pid}/fd"))
                nthreads = len(os.listdir(f"/proc/{pid}/task"))
            except OSError:
                continue
            prev = self.prev.get(pid)
            cpu = 0.0 if prev is None else (ticks - prev[1]) / cost.HZ / (now - prev[0]) * 100
            self.prev[pid] = (now, ticks)
            rss, rss_file = cost.rss_parts_mb(pid)
            out.append({"t": now - self.t0, "pid": pid, "process": cost.label(pid),
                        "rss": rss, "anon": rss - rss_file, "fds": fds,
                        "threads": nthreads, "cpu": cpu})
        with self.lock:
            self.rows.extend(out)
            for r in out:
                self.csv.writerow([f"{r['t']:.1f}", r["pid"], r["process"], f"{r['rss']:.2f}",
                                   f"{r['rss'] - r['anon']:.2f}", r["fds"], r["threads"],
                                   f"{r['cpu']:.1f}"])
            self.file.flush()
        return out

    def now(self):
        return time.monotonic() - self.t0

    def run(self):
        while not self.halt.wait(1.0):
            self.sample()

    def close(self):
        self.halt.set()
        self.join(timeout=5)
        self.file.close()


# ---------------------------------------------------------------- clients

class Clients:
    """Every client of the run; `halt` ends them all."""

    def __init__(self, yarp, env, python_ros, ros):
        self.yarp, self.env, self.python_ros = yarp, env, python_ros
        self.ros_nodes, self.ros_seconds, self.ros_pause, self.ros_topics = ros
        self.halt = threading.Event()
        self.threads = []
        self.lock = threading.Lock()
        self.stats = {"readers": 0, "reader_lines": 0, "rpc": 0, "rpc_failed": 0,
                      "ros_runs": 0, "ros_runs_empty": 0, "ros_msgs": {},
                      "slow_lines": 0, "lossless_sent": 0, "lossless_received": 0,
                      "lossless_gaps": 0, "moves": 0, "moves_missed": 0}
        self.procs = set()
        # Fast DDS's large-data profile (4 MB socket buffers), as the gateway's image tests:
        # with the default 208 KB a camera frame's fragments overflow and no image arrives
        self.ros_env = {k: v for k, v in env.items() if k != "FASTDDS_BUILTIN_TRANSPORTS"}
        self.ros_env["FASTDDS_DEFAULT_PROFILES_FILE"] = os.path.join(
            ROOT, "gateway", "tests", "peers", "fastdds_large_data.xml")

    def count(self, key, n=1):
        with self.lock:
            self.stats[key] += n

    def spawn(self, argv, env=None, **kw):
        p = subprocess.Popen(argv, env=env or self.env, **kw)
        with self.lock:
            self.procs.add(p)
        return p

    def end(self, p, sig=signal.SIGINT):
        cost.stop(p, sig, 5)
        with self.lock:
            self.procs.discard(p)

    def loop(self, fn):
        t = threading.Thread(target=fn, daemon=True)
        t.start()
        self.threads.append(t)

    # `yarp read` on a part's state, 3-8 s each, one started every 2 s (four names reused)
    def readers(self):
        slot = 0
        live = []
        while not self.halt.wait(2.0):
            part = random.choice(PARTS)
            p = self.spawn([self.yarp, "read", f"/soak/read/{slot % 4}",
                            f"/icub/{part}/state:o"],
                           stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
            live.append((time.monotonic() + random.uniform(3, 8), p, cost.Lines(p, keep=1)))
            slot += 1
            self.count("readers")
            for item in [x for x in live if x[0] < time.monotonic()]:
                live.remove(item)
                self.end(item[1])
                item[2].thread.join(timeout=2)
                self.count("reader_lines", item[2].snapshot())
        for _, p, lines in live:
            self.end(p)
            self.count("reader_lines", lines.snapshot())

    # `yarp rpc` to a part's rpc:i: `get axes`, `get encs`, then it disconnects; every 3 s
    def rpc(self):
        while not self.halt.wait(3.0):
            part = random.choice(PARTS)
            p = self.spawn([self.yarp, "rpc", f"/icub/{part}/rpc:i"], stdin=subprocess.PIPE,
                           stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
            try:
                out, _ = p.communicate(b"get axes\nget encs\n", timeout=20)
                ok = p.returncode == 0 and out.count(b"Response") >= 2
            except subprocess.TimeoutExpired:
                ok = False
            self.end(p, signal.SIGTERM)
            self.count("rpc")
            if not ok:
                self.count("rpc_failed")
                log(f"rpc to /icub/{part}/rpc:i failed")

    # a reader that lags: its stdout drained one line every 2 s, so its pipe and then its
    # socket fill and the writer must cope
    def slow_reader(self):
        p = self.spawn([self.yarp, "read", "/soak/slow", "/icub/left_arm/state:o"],
                       stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
        while not self.halt.wait(2.0):
            if p.stdout.readline():
                self.count("slow_lines")
        self.end(p)

    # numbered lines `yarp write` -> `yarp read` at 100 Hz over tcp: none may be lost
    def lossless(self):
        r = self.spawn([self.yarp, "read", "/soak/lossless/in"], stdout=subprocess.PIPE,
                       stderr=subprocess.DEVNULL)
        got = []
        lines = cost.Lines(r, keep=1, on_line=lambda l: got.append(l.strip()))
        time.sleep(3)  # registered
        w = self.spawn([self.yarp, "write", "/soak/lossless/out", "/soak/lossless/in"],
                       stdin=subprocess.PIPE, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)
        time.sleep(3)  # connected
        n = 0
        while not self.halt.wait(0.01):
            try:
                w.stdin.write(f"{n}\n".encode())
                w.stdin.flush()
            except (BrokenPipeError, ValueError):
                log("lossless: the writer ended")
                break
            n += 1
            if n % 500 == 0:
                with self.lock:
                    self.stats.update(lossless_sent=n, lossless_received=len(got))
        deadline = time.monotonic() + 10
        while len(got) < n and time.monotonic() < deadline:
            time.sleep(0.1)
        try:
            w.stdin.close()
        except OSError:
            pass
        self.end(w, signal.SIGTERM)
        self.end(r)
        lines.thread.join(timeout=2)
        expected = [str(i) for i in range(n)]
        gaps = sum(1 for a, b in zip(got, expected) if a != b) + abs(len(got) - n)
        with self.lock:
            self.stats.update(lossless_sent=n, lossless_received=len(got),
                              lossless_gaps=gaps)
        if gaps:
            log(f"lossless: sent {n}, received {len(got)}, first lines {got[:3]}")

    # rclpy subscribers to /joint_states and the camera image, ~17 s each, two staggered,
    # so the gateway connects and disconnects its sources on demand
    def ros(self, delay):
        if self.halt.wait(delay):
            return
        while not self.halt.is_set():
            p = self.spawn([self.python_ros, "-u", os.path.join(HERE, "ros_sub.py"),
                            "--seconds", str(self.ros_seconds), *self.ros_topics],
                           env=self.ros_env,
                           stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
            try:
                out, _ = p.communicate(timeout=60)
            except subprocess.TimeoutExpired:
                out = b""
            self.end(p, signal.SIGTERM)
            counts = {}
            for line in out.decode(errors="replace").splitlines():
                if line.startswith("COUNTS "):
                    counts = json.loads(line[7:])
            with self.lock:
                self.stats["ros_runs"] += 1
                if not counts.get("/joint_states"):
                    self.stats["ros_runs_empty"] += 1
                for k, v in counts.items():
                    self.stats["ros_msgs"][k] = self.stats["ros_msgs"].get(k, 0) + v
            self.halt.wait(self.ros_pause)

    # `[poss]` on left_arm/command:i: joint 0 to start-8°, back, ...; each move must show in
    # state:o within 15 s
    def commander(self):
        part = "/icub/left_arm"
        r = self.spawn([self.yarp, "read", "/soak/cmd/state", f"{part}/state:o"],
                       stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
        state = cost.Lines(r, keep=1)
        w = self.spawn([self.yarp, "write", "/soak/cmd/out", f"{part}/command:i"],
                       stdin=subprocess.PIPE, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)

        def position():
            last = state.last()
            try:
                return [float(x) for x in last.split()] if last else None
            except ValueError:
                return None
        t0 = time.monotonic()
        while position() is None and time.monotonic() - t0 < 30 and not self.halt.is_set():
            time.sleep(0.2)
        start = position()
        if start is None:
            log("commander: no state")
            self.count("moves_missed")
        else:
            time.sleep(2)  # `yarp write` connected
            step = 0
            while not self.halt.is_set():
                target = list(start)
                target[0] += -8.0 if step % 2 == 0 else 0.0
                step += 1
                line = "([poss]) (" + " ".join(f"{x:.3f}" for x in target) + ")\n"
                try:
                    w.stdin.write(line.encode())
                    w.stdin.flush()
                except (BrokenPipeError, ValueError):
                    log("commander: the writer ended")
                    self.count("moves_missed")
                    break
                self.count("moves")
                t1, reached = time.monotonic(), False
                while time.monotonic() - t1 < 15:
                    pos = position()
                    if pos and abs(pos[0] - target[0]) < 1.0:
                        reached = True
                        break
                    time.sleep(0.1)
                if not reached:
                    self.count("moves_missed")
                    log(f"commander: move to {target[0]:.1f} not reached, at {position()}")
                self.halt.wait(3.0)
        try:
            w.stdin.close()
        except OSError:
            pass
        self.end(w, signal.SIGTERM)
        self.end(r)

    def start(self):
        for fn in (self.readers, self.rpc, self.slow_reader, self.lossless, self.commander):
            self.loop(fn)
        # staggered over 20 s (the default two start at 0 and 10 s)
        for i in range(self.ros_nodes):
            self.loop(lambda i=i: self.ros(i * 20.0 / max(self.ros_nodes, 2)))

    def stop(self):
        self.halt.set()
        for t in self.threads:
            t.join(timeout=40)
        with self.lock:
            left = list(self.procs)
        for p in left:
            self.end(p, signal.SIGKILL)


# ---------------------------------------------------------------- evaluation

def by_process(rows):
    out = {}
    for r in rows:
        out.setdefault((r["process"], r["pid"]), []).append(r)
    return out


def median_in(series, key, t0, t1):
    vals = [r[key] for r in series if t0 <= r["t"] <= t1]
    return statistics.median(vals) if vals else None


def plot(rows, marks, path, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(12, 9), sharex=True)
    for (name, pid), series in sorted(by_process(rows).items()):
        t = [r["t"] / 60 for r in series]
        ax1.plot(t, [r["rss"] for r in series], label=f"{name} ({pid})", lw=1)
        ax2.plot(t, [r["cpu"] for r in series], lw=0.6)
    for ax in (ax1, ax2):
        for label, t in marks.items():
            ax.axvline(t / 60, color="grey", ls="--", lw=0.8)
            ax.text(t / 60, ax.get_ylim()[1], label, fontsize=7, va="top", rotation=90)
        ax.grid(alpha=0.3)
    ax1.set_ylabel("RSS (MB)")
    ax2.set_ylabel("CPU (% of one core)")
    ax2.set_xlabel("minutes")
    ax1.set_title(title)
    ax1.legend(fontsize=7, ncol=2, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--minutes", type=float, default=30.0)
    ap.add_argument("--config", default="icub-sim")
    ap.add_argument("--settle", type=float, default=20.0,
                    help="seconds after `is up` before the baseline is taken")
    ap.add_argument("--out", help="report directory (default tests/soak/reports/DATE-...)")
    ap.add_argument("--ros-nodes", type=int, default=2,
                    help="rclpy subscribers alive at once, each restarting (default 2)")
    ap.add_argument("--ros-seconds", type=float, default=17.0,
                    help="life of one rclpy subscriber, s (default 17)")
    ap.add_argument("--ros-pause", type=float, default=3.0,
                    help="pause before a subscriber restarts, s (default 3)")
    ap.add_argument("--ros-topics", nargs="+", default=ROS_TOPICS, metavar="TOPIC=TYPE",
                    help="what they subscribe (ros_sub.py's form; default: "
                    + " ".join(ROS_TOPICS) + ")")
    args = ap.parse_args()

    target = os.environ.get("CARGO_TARGET_DIR", "/root/.cache/yarp-rs/target")
    bindir = os.path.join(target, "release")
    launch, yarp = os.path.join(bindir, "yarp-launch"), os.path.join(bindir, "yarp")
    python_ros = os.path.join(os.environ.get("ROS_VENV", "/root/.cache/yarp-rs/venv-ros"),
                              "bin", "python")
    for b in (launch, yarp, python_ros):
        if not os.path.exists(b):
            raise SystemExit(f"soak: no {b}")
    config = args.config
    if not config.endswith((".toml", ".xml")):
        config = os.path.join(ROOT, "launch-configs", f"{config}.toml")
    stamp = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H%MZ")
    out = args.out or os.path.join(HERE, "reports",
                                   f"{stamp}-run.sh--minutes-{args.minutes:g}")
    os.makedirs(out, exist_ok=True)
    command = f"tests/soak/run.sh --minutes {args.minutes:g}" + (
        f" --config {args.config}" if args.config != "icub-sim" else "")
    for dest in ("ros_nodes", "ros_seconds", "ros_pause"):
        value = getattr(args, dest)
        if value != ap.get_default(dest):
            command += f" --{dest.replace('_', '-')} {value:g}"
    if args.ros_topics != ap.get_default("ros_topics"):
        command += " --ros-topics " + " ".join(args.ros_topics)

    tmp = tempfile.mkdtemp(prefix="yarp-soak-")
    env = dict(os.environ, YARP_CONFIG_HOME=tmp, NO_COLOR="1",
               ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
               FASTDDS_BUILTIN_TRANSPORTS="UDPv4")
    cmd = [launch, config]
    with open(config) as f:
        if "xsens_serial" in f.read():
            cmd += ["--set", f"xsens_serial={tmp}/ttyXSENS"]
    log(f"{' '.join(cmd)}  (load {os.getloadavg()[0]:.2f}); report in {out}")
    job = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                           start_new_session=True)
    up = threading.Event()
    job_lines = cost.Lines(job, keep=200, on_line=lambda l: " is up in " in l and up.set())
    sampler = clients = None
    failures, lines = [], []
    marks = {}
    duration = args.minutes * 60
    load_start = os.getloadavg()
    try:
        cost.wait_for(lambda: up.is_set() or job.poll() is not None, 300, "the job up")
        if job.poll() is not None:
            print("\n".join(job_lines.tail), file=sys.stderr)
            raise SystemExit("soak: the job exited")
        sampler = Sampler(job.pid, os.path.join(out, "samples.csv"))
        sampler.start()
        time.sleep(args.settle)
        base = {(r["process"], r["pid"]): r for r in sampler.sample()}
        marks["baseline"] = sampler.now()
        log(f"baseline of {len(base)} processes; clients for {args.minutes:g} min")
        clients = Clients(yarp, env, python_ros,
                          (args.ros_nodes, args.ros_seconds, args.ros_pause, args.ros_topics))
        t_start = sampler.now()
        marks["clients"] = t_start
        clients.start()
        warm = min(180.0, 0.1 * duration)
        marks["warm-up"] = t_start + warm
        end = time.monotonic() + duration
        while time.monotonic() < end:
            time.sleep(min(30.0, max(end - time.monotonic(), 0)))
            if job.poll() is not None:
                failures.append("the job exited during the run")
                break
            log(f"{(duration - max(end - time.monotonic(), 0)) / 60:.1f} min, "
                f"load {os.getloadavg()[0]:.2f}, {json.dumps(clients.stats)}")
        t_stop = sampler.now()
        marks["stop"] = t_stop
        clients.stop()
        log("clients stopped; waiting for fds and threads to return")
        # fds and threads back to baseline: polled for up to 40 s (tokio's idle blocking
        # threads live 10 s, the gateway closes idle boards after 5 s)
        deadline = time.monotonic() + 40
        while True:
            time.sleep(2)
            after = {(r["process"], r["pid"]): r for r in sampler.sample()}
            over = [k for k in base if k not in after
                    or after[k]["fds"] > base[k]["fds"]
                    or after[k]["threads"] > base[k]["threads"]]
            if not over or time.monotonic() > deadline:
                break
        marks["after"] = sampler.now()
        sampler.close()

        # ---- summary
        series = by_process(sampler.rows)
        win = min(30.0, max(0.05 * duration, 5.0))
        lines.append("| process | RSS at warm-up (MB) | RSS at end (MB) | growth | "
                     "of which anonymous (MB) | fds base/after | threads base/after | "
                     "mean CPU % | max CPU % |")
        lines.append("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
        for key in sorted(base):
            s = series.get(key, [])
            r0 = median_in(s, "rss", t_start + warm, t_start + warm + win)
            r1 = median_in(s, "rss", t_stop - win, t_stop)
            growth = (r1 - r0) / r0 * 100 if r0 and r1 else float("nan")
            # anonymous memory (heaps, stacks) apart from the binary's pages touched
            a0 = median_in(s, "anon", t_start + warm, t_start + warm + win)
            a1 = median_in(s, "anon", t_stop - win, t_stop)
            a = after.get(key)
            run = [r["cpu"] for r in s if t_start <= r["t"] <= t_stop]
            lines.append(
                f"| {key[0]} | {r0 or 0:.1f} | {r1 or 0:.1f} | {growth:+.1f} % | "
                f"{a0 or 0:.1f} -> {a1 or 0:.1f} | "
                f"{base[key]['fds']}/{a['fds'] if a else '-'} | "
                f"{base[key]['threads']}/{a['threads'] if a else '-'} | "
                f"{statistics.mean(run) if run else 0:.1f} | {max(run) if run else 0:.1f} |")
            if not (growth < 5.0):
                failures.append(f"RSS of {key[0]} grew {growth:+.1f} % after warm-up")
            if a is None:
                failures.append(f"{key[0]} ({key[1]}) ended or was restarted")
            else:
                if a["fds"] > base[key]["fds"]:
                    failures.append(f"fds of {key[0]}: {base[key]['fds']} -> {a['fds']}")
                if a["threads"] > base[key]["threads"]:
                    failures.append(f"threads of {key[0]}: {base[key]['threads']} -> "
                                    f"{a['threads']}")
        st = clients.stats
        if st["lossless_gaps"] or st["lossless_sent"] == 0:
            failures.append(f"tcp: sent {st['lossless_sent']}, received "
                            f"{st['lossless_received']}, {st['lossless_gaps']} wrong/missing")
        if st["moves_missed"] or st["moves"] == 0:
            failures.append(f"moves: {st['moves_missed']} of {st['moves']} not reached")
        plot(sampler.rows, marks, os.path.join(out, "rss-cpu.png"),
             f"{command} ({stamp})")
    finally:
        if clients:
            clients.stop()
        if sampler and not sampler.halt.is_set():
            sampler.close()
        cost.stop(job, signal.SIGINT, 40)
    st = clients.stats
    load_end = os.getloadavg()
    rpt = [f"# Soak run {stamp}", "",
           f"Command: `{command}` (job `{' '.join(os.path.relpath(c, ROOT) if c.startswith(ROOT) else c for c in cmd)}`,"
           f" release binaries). Machine: {os.cpu_count()} cores, shared; load average "
           f"{load_start[0]:.2f} at the start, {load_end[0]:.2f} at the end.", "",
           f"Clients for {args.minutes:g} min; RSS compared between the median of {win:.0f} s "
           f"after {warm / 60:.1f} min of warm-up and the median of the last {win:.0f} s "
           "before the clients stopped; fds and threads at the baseline (after settling, "
           "before any client) and after the clients stopped.", "",
           *lines, "",
           "Streams:", "",
           f"- `yarp read` readers that came and went: {st['readers']} "
           f"({st['reader_lines']} messages)",
           f"- `yarp rpc` clients (`get axes`, `get encs`): {st['rpc']} "
           f"({st['rpc_failed']} failed)",
           f"- slow reader lines drained: {st['slow_lines']}",
           f"- rclpy subscriber runs: {st['ros_runs']} ({st['ros_runs_empty']} without a "
           f"/joint_states message); messages {json.dumps(st['ros_msgs'])}",
           f"- lossless tcp: sent {st['lossless_sent']}, received {st['lossless_received']}, "
           f"{st['lossless_gaps']} missing or out of order",
           f"- commanded moves: {st['moves']}, not reached {st['moves_missed']}", "",
           "Criteria:", "",
           "- RSS after warm-up grows < 5 %: " +
           ("pass" if not any("RSS" in f for f in failures) else "FAIL"),
           "- fds and threads return to baseline: " +
           ("pass" if not any(("fds" in f or "threads" in f or "restarted" in f)
                              for f in failures) else "FAIL"),
           "- no tcp message lost: " + ("pass" if not any("tcp" in f for f in failures)
                                        else "FAIL"),
           "- every commanded move reached: " +
           ("pass" if not any("moves" in f for f in failures) else "FAIL"), ""]
    if failures:
        rpt += ["Failures:", ""] + [f"- {f}" for f in failures] + [""]
    rpt.append("RESULT: " + ("PASS" if not failures else "FAIL"))
    text = "\n".join(rpt) + "\n"
    with open(os.path.join(out, "report.md"), "w") as f:
        f.write(text)
    print(text)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
