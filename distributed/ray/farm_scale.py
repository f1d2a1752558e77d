"""The driver at farm scale, shared by the CI test (test_cluster.py, a few hundred tasks) and the benchmark
(bench_cluster.py --scale, ten thousand): a manifest of many small tasks, a kelvin stub that makes a task cost
only the driver's and Ray's work, a run of the driver on a local cluster in waves, and the head's figures while it
runs.

The head here is what a KubeRay head pod runs: the driver process, Ray's GCS server, the head node's raylet and
the driver's `Whereabouts` actor. Their resident memory is sampled from /proc every `period` seconds, with the
staged tiles on disk (the `.tiles` folders under the run's outputs), so the bounds are seen from outside the
driver, not only in its own summary.
"""

import json
import os
import subprocess
import sys
import threading
import time

from local_cluster import SECOND_NODE, check, processes

HERE = os.path.dirname(os.path.abspath(__file__))


def manifest(folder, jobs, size="64x64"):
    """A manifest of `jobs` renders of the default scene at 1 spp (the same image each, into its own output), so
    that every output can be compared with one plain render. Returns its path."""
    path = os.path.join(folder, "scale.json")
    with open(path, "w") as f:
        json.dump({"jobs": [{"name": f"j{i}", "output": f"scale/j{i:05}.exr", "size": size, "spp": 1}
                            for i in range(jobs)]}, f)
    return path


def reference(kelvin, folder, size="64x64"):
    """The bytes of a plain `kelvin render` of the manifest's image."""
    out = os.path.join(folder, "reference.exr")
    run = subprocess.run([kelvin, "render", "--size", size, "--spp", "1", "-o", out], capture_output=True, text=True,
                         timeout=120)
    check(run.returncode == 0, run.stderr)
    with open(out, "rb") as f:
        return f.read()


def stub_kelvin(kelvin, folder, crops, size="64x64"):
    """A kelvin whose `render --crop C` copies a tile the real kelvin rendered beforehand (every job of the
    manifest is the same image), and which runs the real one for anything else (the plan, the merges): the tasks
    then cost the driver's and Ray's work, not kelvin's, and the outputs are still the real tiles merged."""
    tiles = os.path.join(folder, "stub-tiles")
    os.makedirs(tiles)
    for c in crops:
        crop = ",".join(map(str, c))
        run = subprocess.run([kelvin, "render", "--size", size, "--spp", "1", "--crop", crop, "--threads", "1", "-o",
                              os.path.join(tiles, crop + ".exr")], capture_output=True, text=True, timeout=120)
        check(run.returncode == 0, run.stderr)
    path = os.path.join(folder, "kelvin-stub")
    with open(path, "w") as f:
        f.write(f'#!/bin/sh\nif [ "$1" = render ]; then\n  while [ $# -gt 0 ]; do case "$1" in --crop) crop=$2;; '
                f'-o) out=$2;; esac; shift; done\n  exec cp "{tiles}/$crop.exr" "$out"\nfi\nexec {kelvin} "$@"\n')
    os.chmod(path, 0o755)
    return path


def same_outputs(folder, want):
    """How many outputs under `folder`/scale are the reference's bytes; raises on one that is not."""
    outputs = os.path.join(folder, "scale")
    names = [n for n in os.listdir(outputs) if n.endswith(".exr")]
    for name in names:
        with open(os.path.join(outputs, name), "rb") as f:
            check(f.read() == want, f"{name}: differs from a plain kelvin render")
    return len(names)


def rss_kb(pid):
    try:
        with open(f"/proc/{pid}/status") as f:
            return next(int(l.split()[1]) for l in f if l.startswith("VmRSS:"))
    except (OSError, StopIteration, ValueError):
        return 0


def cpu_seconds(pid, children=False):
    """User and system CPU seconds of a live process (with those of its waited-for children: `children`)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = [int(v) for v in f.read().rsplit(")", 1)[1].split()[11:15]]
        return sum(fields if children else fields[:2]) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError):
        return 0.0


def head_processes(cluster, driver):
    """name -> pid of the head's processes: the driver, the GCS server, the tracker actor and the raylet of the
    driver's node (the tracker's parent; the driver may attach to either raylet of this one-machine cluster)."""
    procs = processes()
    found = {"driver": driver}
    for pid in cluster.own(procs):
        argv = procs[pid][1]
        if argv[0].endswith("gcs_server"):
            found["gcs"] = pid
        elif argv[0].startswith("ray::Whereabouts"):
            found["tracker"] = pid
            found["raylet"] = procs[pid][0]
    return found


def staged_files(folder):
    return sum(len(names) for d, _, names in os.walk(folder) if d.endswith(".tiles"))


class Sampler(threading.Thread):
    """Samples the head's memory and the staged tiles every `period` s until stopped, and the CPU seconds of the
    head's processes, of the driver's merges and of the rest of the cluster (the nodes' raylets, workers and what
    they ran) from its first sample to its last."""

    def __init__(self, cluster, driver, outputs, period=0.5):
        super().__init__(daemon=True)
        self.cluster, self.driver, self.outputs, self.period = cluster, driver, outputs, period
        self.samples, self.stopped, self.pids = [], threading.Event(), {}
        self.cpu_first = self.cpu_last = None

    def cpu(self):
        """CPU seconds by role: each head process, "merges" (the driver's children), "nodes" (everything else)."""
        head = set(self.pids.values())
        out = {name: cpu_seconds(pid) for name, pid in self.pids.items()}
        out["merges"] = cpu_seconds(self.driver, children=True) - out.get("driver", 0.0)
        out["nodes"] = sum(cpu_seconds(p, children=True) for p in self.cluster.own(processes()) - head)
        return out

    def run(self):
        start = time.monotonic()
        while not self.stopped.is_set():
            if "tracker" not in self.pids:  # the actor starts with the driver
                self.pids = head_processes(self.cluster, self.driver)
            rss = {name: rss_kb(pid) for name, pid in self.pids.items()}
            if os.path.exists(f"/proc/{self.driver}") and "tracker" in self.pids:
                now = self.cpu()
                self.cpu_first = self.cpu_first or now
                # The most each role has read: a process that has exited (the tracker as the driver ends) reads 0.
                self.cpu_last = {n: max(v, (self.cpu_last or {}).get(n, 0.0)) for n, v in now.items()}
            self.samples.append({"t": time.monotonic() - start, "rss_kb": rss, "staged": staged_files(self.outputs)})
            self.stopped.wait(self.period)

    def stop(self):
        self.stopped.set()
        self.join(timeout=30)

    def peaks(self):
        """Peak RSS (kB) of each head process and of their sum, and the most tiles staged at once."""
        names = sorted({n for s in self.samples for n in s["rss_kb"]})
        out = {n: max(s["rss_kb"].get(n, 0) for s in self.samples) for n in names}
        out["head"] = max(sum(s["rss_kb"].values()) for s in self.samples)
        out["staged"] = max(s["staged"] for s in self.samples)
        return out

    def cpu_used(self):
        """CPU seconds by role between the first and the last sample (the driver's last one shortly before it
        exited)."""
        return {n: self.cpu_last[n] - self.cpu_first.get(n, 0.0) for n in self.cpu_last}


def run_driver(cluster, kelvin, manifest_path, summary, log, *extra, timeout=3600):
    """Runs the driver on the cluster with the sampler watching; (exit code, wall s, summary, sampler)."""
    cmd = [sys.executable, os.path.join(HERE, "kelvin_ray.py"), manifest_path, "--kelvin", kelvin,
           "--address", cluster.address, "--summary", summary, "--force", *extra]
    with open(log, "w") as out:
        started = time.monotonic()
        proc = subprocess.Popen(cmd, env=cluster.env, stdout=out, stderr=subprocess.STDOUT)
        sampler = Sampler(cluster, proc.pid, os.path.dirname(manifest_path))
        sampler.start()
        try:
            proc.wait(timeout=timeout)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait(timeout=10)
            sampler.stop()
        wall = time.monotonic() - started
    with open(summary) as f:
        return proc.returncode, wall, json.load(f), sampler


def figures(summary, sampler, slots):
    """What a scale run measured: tasks, wall, throughput, the scheduling overhead per task (task-slot time not
    spent inside a task function, which includes kelvin), the head's CPU per task and its peak memory."""
    tasks = summary["tiles"]
    in_tasks = sum(n["task_seconds"] for n in summary["nodes"].values())
    wall = summary["wall_seconds"]
    cpu = sampler.cpu_used()
    peaks = sampler.peaks()
    return {
        "tasks": tasks, "wall_s": wall, "tasks_per_s": tasks / wall,
        "task_ms": 1e3 * in_tasks / tasks,
        "overhead_ms": 1e3 * (wall * slots - in_tasks) / tasks,
        "cpu_ms": {k: 1e3 * v / tasks for k, v in cpu.items()},
        "rss_peak_mb": {k: v / 1024 for k, v in peaks.items() if k != "staged"},
        "staged_peak": peaks["staged"], "driver_peak": summary["peak"], "bounds": summary["bounds"],
    }


def describe(f):
    cpu = ", ".join(f"{k} {v:.1f}" for k, v in sorted(f["cpu_ms"].items()))
    rss = ", ".join(f"{k} {v:.0f}" for k, v in sorted(f["rss_peak_mb"].items()))
    return (f"{f['tasks']} tasks in {f['wall_s']:.1f} s ({f['tasks_per_s']:.1f}/s); {f['task_ms']:.0f} ms inside a "
            f"task, {f['overhead_ms']:.0f} ms of a slot outside it per task; CPU per task (ms): {cpu}; head "
            f"RSS peak (MB): {rss}; in flight at most {f['driver_peak']['in_flight']} (bound "
            f"{f['bounds']['in_flight']}), jobs open {f['driver_peak']['open_jobs']}, staged {f['staged_peak']} on "
            f"disk ({f['driver_peak']['staged']} by the driver's count)")


__all__ = ["manifest", "run_driver", "figures", "describe", "check"]
