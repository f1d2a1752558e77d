"""A local Ray cluster for the driver's test and benchmark: a head and worker nodes started with `ray start` on
this machine, each with one CPU, in a temporary folder of their own, and the process-table helpers that kill parts
of it (a node's workers, a whole node) and stop it without touching anything else on the machine."""

import json
import os
import secrets
import signal
import socket
import subprocess
import sys
import time

SECOND_NODE = "kelvin_second_node"
# Set in the second node's environment only (its workers inherit it): the broken kelvin of test section 3 dies there.
SECOND_NODE_ENV = "KELVIN_TEST_SECOND_NODE"


def processes():
    """pid -> (ppid, argv) of every process."""
    out = {}
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{pid}/stat") as f:
                ppid = int(f.read().rsplit(")", 1)[1].split()[1])
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                argv = f.read().decode(errors="replace").split("\0")
        except (OSError, IndexError, ValueError):
            continue
        out[int(pid)] = (ppid, argv)
    return out


def descendants(procs, roots):
    found, todo = set(roots), list(roots)
    while todo:
        parent = todo.pop()
        for pid, (ppid, _) in procs.items():
            if ppid == parent and pid not in found:
                found.add(pid)
                todo.append(pid)
    return found


def running(pid):
    """Whether `pid` exists and has not exited (a zombie has)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] not in "ZX"
    except (OSError, IndexError):
        return False


def kill(pids, sig):
    for pid in pids:
        try:
            os.kill(pid, sig)
        except ProcessLookupError:
            pass


class Cluster:
    """A head and a second node started with `ray start`, in a temporary folder of their own."""

    def __init__(self, ray_bin, work, workers=1):
        """`workers` nodes beside the head (the first is "the second node"; the benchmark starts 0 to 2)."""
        self.ray, self.temp, self.workers = ray_bin, os.path.join(work, "ray"), workers
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            self.port = s.getsockname()[1]
        self.address = f"127.0.0.1:{self.port}"
        # Tasks' temporary files (a killed task's included) stay inside the work folder.
        self.env = dict(os.environ, RAY_USAGE_STATS_ENABLED="0", TMPDIR=os.path.join(work, "tmp"))
        # A token of its own, for its nodes and drivers only: the GCS listens on the machine's address, and a
        # token file that another Ray left in ~/.ray must not decide whether this cluster checks tokens.
        self.env.update(RAY_AUTH_MODE="token", RAY_AUTH_TOKEN=secrets.token_hex(32))
        # The GCS declares a silent node dead after about 1.5 s (default 3 s x 5 failures + timeouts), so that
        # section 5 does not wait half a minute for it.
        self.env.update(RAY_health_check_period_ms="500", RAY_health_check_timeout_ms="500",
                        RAY_health_check_failure_threshold="3")
        os.makedirs(self.env["TMPDIR"], exist_ok=True)

    def start(self):
        common = ["--num-cpus", "1", "--object-store-memory", "100000000", "--temp-dir", self.temp]
        common += ["--node-ip-address", "127.0.0.1", "--disable-usage-stats"]
        head = [self.ray, "start", "--head", "--port", str(self.port), "--include-dashboard=false", *common]
        self.second = [self.ray, "start", "--address", self.address, "--resources", json.dumps({SECOND_NODE: 1}),
                       *common]
        others = [self.second] + [[self.ray, "start", "--address", self.address, *common]] * (self.workers - 1)
        nodes = [(head, self.env)] + [(cmd, dict(self.env, **{SECOND_NODE_ENV: "1"})) for cmd in others[:self.workers]]
        for cmd, env in nodes:
            run = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=120)
            if run.returncode != 0:
                raise AssertionError(f"{' '.join(cmd)} failed:\n{run.stdout}\n{run.stderr}")

    def own(self, procs):
        """Our cluster's processes: those whose arguments name our temporary folder, and their children."""
        roots = [pid for pid, (_, argv) in procs.items() if any(self.temp in a for a in argv)]
        return descendants(procs, roots)

    def node_ids(self):
        """{"head": id, "second": id} of the nodes, from Ray (in a process of its own, so that this one never
        attaches to the cluster)."""
        code = ("import json, ray; ray.init(address=%r, log_to_driver=False); "
                "print(json.dumps({('second' if %r in n['Resources'] else 'head'): n['NodeID'] "
                "for n in ray.nodes() if n['Alive']}))" % (self.address, SECOND_NODE))
        run = subprocess.run([sys.executable, "-c", code], env=self.env, capture_output=True, text=True, timeout=120)
        check(run.returncode == 0, run.stderr)
        ids = json.loads(run.stdout.strip().splitlines()[-1])
        check(set(ids) == {"head", "second"}, f"two alive nodes: {ids}")
        return ids

    def second_raylet(self, procs):
        return [
            pid
            for pid, (_, argv) in procs.items()
            if argv and argv[0].endswith("raylet") and any(SECOND_NODE in a for a in argv) and any(self.temp in a for a in argv)
        ]

    def kill_second_node(self):
        """SIGKILL to the second node's raylet and everything under it (workers, agents, kelvin): a lost node."""
        procs = processes()
        victims = descendants(procs, self.second_raylet(procs))
        kill(victims, signal.SIGKILL)
        return sorted(victims)

    def second_node_workers(self):
        """Worker processes of the second node (children of its raylet that run tasks), and their children."""
        procs = processes()
        raylets = self.second_raylet(procs)
        workers = []
        for pid, (ppid, argv) in procs.items():
            title = " ".join(argv)
            if ppid in raylets and (title.startswith("ray::") or "default_worker.py" in title) and "Agent" not in title:
                workers.append((pid, title))
        return workers, procs

    def kill_second_mid_task(self, whole_node):
        """SIGKILL to the whole second node (`whole_node`) or to its workers that run a tile or a bake part, at a
        moment when one of those workers still waits for its kelvin: the node is frozen (SIGSTOP) before the check,
        so no task can finish between the check and the kill. Returns the killed pids; [] (the node resumed) when
        no task was mid-run. Killing a worker that Ray is still starting would stall the node's worker pool (its
        start-up concurrency is its 1 CPU) until Ray's registration timeout, hence only those running a task."""
        workers, procs = self.second_node_workers()
        if not any("render_tile" in title or "bake_part" in title for _, title in workers):
            return []
        frozen = descendants(procs, self.second_raylet(procs))
        kill(frozen, signal.SIGSTOP)
        workers, procs = self.second_node_workers()
        late = descendants(procs, self.second_raylet(procs)) - frozen
        kill(late, signal.SIGSTOP)  # started between the two readings of the process table
        frozen |= late
        busy = [pid for pid, title in workers if "render_tile" in title or "bake_part" in title]
        waiting = [pid for pid in busy if any(running(c) for c in descendants(procs, [pid]) - {pid})]
        victims = descendants(procs, self.second_raylet(procs)) if whole_node else descendants(procs, busy)
        if waiting:
            kill(victims, signal.SIGKILL)
        kill(frozen, signal.SIGCONT)
        return sorted(victims) if waiting else []

    def runs_on_second(self, node, timeout):
        """Whether a task pinned to the second node (id `node`) runs there within `timeout` seconds."""
        code = ("import ray; from ray.util.scheduling_strategies import NodeAffinitySchedulingStrategy as N; "
                "ray.init(address=%r, log_to_driver=False); "
                "f = ray.remote(num_cpus=1, max_retries=0)(lambda: ray.get_runtime_context().get_node_id()); "
                "print(ray.get(f.options(scheduling_strategy=N(%r, soft=False)).remote(), timeout=%r))"
                % (self.address, node, timeout))
        try:
            run = subprocess.run([sys.executable, "-c", code], env=self.env, capture_output=True, text=True,
                                 timeout=timeout + 60)
        except subprocess.TimeoutExpired:
            return False
        return run.returncode == 0 and run.stdout.strip().endswith(node)

    def restart_second(self):
        """Replaces the second node by a fresh one (same resources and environment)."""
        self.kill_second_node()
        time.sleep(3)  # the GCS declares it dead after about 1.5 s
        run = subprocess.run(self.second, env=dict(self.env, **{SECOND_NODE_ENV: "1"}), capture_output=True,
                             text=True, timeout=120)
        check(run.returncode == 0, f"restarting the second node failed:\n{run.stdout}\n{run.stderr}")

    def stop(self):
        procs = self.own(processes())
        kill(procs, signal.SIGTERM)
        deadline = time.monotonic() + 5
        while time.monotonic() < deadline and any(os.path.exists(f"/proc/{p}") for p in procs):
            time.sleep(0.2)
        kill([p for p in procs if os.path.exists(f"/proc/{p}")], signal.SIGKILL)



def check(cond, msg):
    if not cond:
        raise AssertionError(msg)
