#!/usr/bin/env python3
"""CI test of the Ray driver on a local two-node cluster (a head and a second worker node on this machine).

    python test_cluster.py [--kelvin target/debug/kelvin]

1. A manifest of 3 jobs (two scenes, both colour modes, an environment camera), one of 2 frames of an animated
   scene, a ReSTIR job with an exposure (rendered as one tile: its reuse does not tile), a lightmap bake in 5 parts,
   and 2 bad ones (a missing scene, a bad size), split into 16 tiles each: every merged image and its PNG preview
   is byte for byte a plain `kelvin render`'s (every baked file a plain `kelvin bake`'s), both nodes rendered
   tiles, the bad jobs fail with kelvin's message and the exit code says so.
2. The same good jobs again while the second node's worker processes are killed mid-run: Ray retries their
   tiles and the images are still byte-identical.

Every wait is bounded. The cluster runs in its own temporary folder and is stopped at the end, also when a
check fails, by ending the processes that folder names (and their children): nothing else on the machine.
"""

import argparse
import json
import os
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
SECOND_NODE = "kelvin_second_node"


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


def kill(pids, sig):
    for pid in pids:
        try:
            os.kill(pid, sig)
        except ProcessLookupError:
            pass


class Cluster:
    """A head and a second node started with `ray start`, in a temporary folder of their own."""

    def __init__(self, ray_bin, work):
        self.ray, self.temp = ray_bin, os.path.join(work, "ray")
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            self.port = s.getsockname()[1]
        self.address = f"127.0.0.1:{self.port}"
        # Tasks' temporary files (a killed task's included) stay inside the work folder.
        self.env = dict(os.environ, RAY_USAGE_STATS_ENABLED="0", TMPDIR=os.path.join(work, "tmp"))
        # A token of its own, for its nodes and drivers only: the GCS listens on the machine's address, and a
        # token file that another Ray left in ~/.ray must not decide whether this cluster checks tokens.
        self.env.update(RAY_AUTH_MODE="token", RAY_AUTH_TOKEN=secrets.token_hex(32))
        os.makedirs(self.env["TMPDIR"], exist_ok=True)

    def start(self):
        common = ["--num-cpus", "1", "--object-store-memory", "100000000", "--temp-dir", self.temp]
        common += ["--node-ip-address", "127.0.0.1", "--disable-usage-stats"]
        head = [self.ray, "start", "--head", "--port", str(self.port), "--include-dashboard=false", *common]
        second = [self.ray, "start", "--address", self.address, "--resources", json.dumps({SECOND_NODE: 1}), *common]
        for cmd in (head, second):
            run = subprocess.run(cmd, env=self.env, capture_output=True, text=True, timeout=120)
            if run.returncode != 0:
                raise AssertionError(f"{' '.join(cmd)} failed:\n{run.stdout}\n{run.stderr}")

    def own(self, procs):
        """Our cluster's processes: those whose arguments name our temporary folder, and their children."""
        roots = [pid for pid, (_, argv) in procs.items() if any(self.temp in a for a in argv)]
        return descendants(procs, roots)

    def second_node_workers(self):
        """Worker processes of the second node (children of its raylet that run tasks), and their children."""
        procs = processes()
        raylets = [
            pid
            for pid, (_, argv) in procs.items()
            if argv and argv[0].endswith("raylet") and any(SECOND_NODE in a for a in argv) and any(self.temp in a for a in argv)
        ]
        workers = []
        for pid, (ppid, argv) in procs.items():
            title = " ".join(argv)
            if ppid in raylets and (title.startswith("ray::") or "default_worker.py" in title) and "Agent" not in title:
                workers.append((pid, title))
        return workers, procs

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


def kelvin_plan(kelvin, manifest):
    run = subprocess.run([kelvin, "batch", manifest, "--plan"], capture_output=True, text=True, timeout=60)
    check(run.returncode == 0, run.stderr)
    return json.loads(run.stdout)["jobs"]


def png_of(exr):
    return os.path.splitext(exr)[0] + ".png"


def references(kelvin, jobs, folder):
    """A plain `kelvin render` of each job: the bytes of its EXR and of its PNG preview, by output path (for a
    bake, a plain `kelvin bake`: the bytes of every file it writes)."""
    refs = {}
    for i, job in enumerate(jobs):
        if job["command"] == "bake":
            out = os.path.join(folder, f"ref{i}")
            run = subprocess.run([kelvin, "bake", *job["args"], "-o", out], capture_output=True, text=True, timeout=120)
            check(run.returncode == 0, run.stderr)
            for name in os.listdir(out):
                with open(os.path.join(out, name), "rb") as f:
                    refs[os.path.join(job["output"], name)] = f.read()
            continue
        out = os.path.join(folder, f"ref{i}.exr")
        run = subprocess.run([kelvin, "render", *job["args"], "-o", out], capture_output=True, text=True, timeout=120)
        check(run.returncode == 0, run.stderr)
        for mine, theirs in ((out, job["output"]), (png_of(out), png_of(job["output"]))):
            with open(mine, "rb") as f:
                refs[theirs] = f.read()
    return refs


def driver(python, kelvin, manifest, address, summary):
    cmd = [python, os.path.join(HERE, "kelvin_ray.py"), manifest, "--tiles", "16", "--kelvin", kelvin]
    return cmd + ["--address", address, "--summary", summary, "--timeout", "240", "--max-retries", "5"]


def same_images(refs):
    for output, want in refs.items():
        check(os.path.exists(output), f"{output}: not written")
        with open(output, "rb") as f:
            check(f.read() == want, f"{output}: differs from a plain kelvin render")


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--kelvin", default=os.environ.get("KELVIN_BIN", os.path.join(REPO, "target/debug/kelvin")))
    opts = p.parse_args()
    kelvin = os.path.abspath(opts.kelvin)
    check(os.access(kelvin, os.X_OK), f"{kelvin}: no kelvin binary (cargo build --bin kelvin)")
    ray_bin = os.path.join(os.path.dirname(sys.executable), "ray")
    check(os.access(ray_bin, os.X_OK), f"{ray_bin}: run from the venv of requirements.txt")
    started = time.monotonic()
    # Short: Ray's socket paths live under it and must fit in 107 bytes.
    work = tempfile.mkdtemp(prefix="kray-", dir="/tmp")
    cluster = Cluster(ray_bin, work)
    try:
        good = [
            {"name": "room", "output": "out/room.exr", "size": "96x72", "spp": 128},
            {"name": "box-spectral", "scene": os.path.join(REPO, "tests/data/gltf/bevy/CornellBox.glb"),
             "output": "out/box.exr", "size": "80x80", "spp": 128, "settings": {"color": "spectral", "seed": 3}},
            {"name": "room-env-camera", "output": "out/env.exr", "size": "96x48", "spp": 128,
             "camera": {"environment_at": [0, 1, 0]}, "settings": {"light_sampler": "power"}},
            # Two frames of an animation: two jobs of 16 tiles.
            {"name": "lamp", "scene": os.path.join(REPO, "tests/data/gltf/kelvin/animated_lamp.gltf"),
             "output": "out/lamp_#.exr", "frames": "3..4", "fps": 4, "size": "48x32", "spp": 16},
            # ReSTIR's reuse does not tile: one task renders it whole; its exposure reaches the PNG.
            {"name": "room-restir", "output": "out/restir.exr", "size": "40x30", "spp": 8,
             "settings": {"light_sampler": "restir", "exposure": 1.5}},
            # Lightmaps baked in 5 parts on the cluster and merged.
            {"name": "box-lightmaps", "bake": "lightmaps", "scene": os.path.join(REPO, "tests/data/gltf/bevy/CornellBox.glb"),
             "output": "out/maps", "parts": 5, "settings": {"size": 24, "spp": 16, "seed": 2}},
        ]
        bad = [
            {"name": "missing-scene", "scene": "no/such/scene.glb", "output": "out/missing.exr"},
            {"name": "bad-size", "output": "out/bad.exr", "size": "0x10"},
        ]
        manifest = os.path.join(work, "jobs.json")
        with open(manifest, "w") as f:
            json.dump({"jobs": good + bad}, f)
        refs = references(kelvin, kelvin_plan(kelvin, manifest)[:7], work)

        cluster.start()
        print(f"cluster up at {cluster.address} in {time.monotonic() - started:.1f} s", flush=True)

        # 1. Three jobs and two bad entries.
        summary = os.path.join(work, "summary.json")
        run = subprocess.run(driver(sys.executable, kelvin, manifest, cluster.address, summary),
                             env=cluster.env, capture_output=True, text=True, timeout=300)
        print(run.stdout[-3000:], run.stderr[-3000:], flush=True)
        check(run.returncode == 1, f"the bad jobs fail the run: exit code {run.returncode}")
        same_images(refs)
        with open(summary) as f:
            result = json.load(f)
        states = {int(k): v for k, v in result["jobs"].items()}
        check([states[i]["status"] for i in range(9)] == ["rendered"] * 7 + ["FAILED"] * 2, f"{states}")
        check("no/such/scene.glb: no such file" in states[7]["detail"], states[7]["detail"])
        check("'0x10'" in states[8]["detail"], states[8]["detail"])
        check(len(result["nodes"]) == 2, f"tiles ran on both nodes: {result['nodes']}")
        check(sum(n["tiles"] for n in result["nodes"].values()) == 86, f"{result['nodes']}")
        print(f"1. 3 jobs and 2 frames x 16 tiles, a whole ReSTIR job and a bake of 5 parts byte-identical, "
              f"PNGs included; bad jobs failed clearly ({time.monotonic() - started:.1f} s)")

        # 2. The same jobs while the second node's workers are killed.
        fault = os.path.join(work, "fault")
        os.makedirs(fault)
        manifest = os.path.join(fault, "jobs.json")
        with open(manifest, "w") as f:
            json.dump({"jobs": good}, f)
        refs = {os.path.join(fault, os.path.relpath(k, work)): v for k, v in refs.items()}
        summary = os.path.join(fault, "summary.json")
        proc = subprocess.Popen(driver(sys.executable, kelvin, manifest, cluster.address, summary),
                                env=cluster.env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        kills, deadline = [], time.monotonic() + 300
        try:
            while proc.poll() is None and time.monotonic() < deadline:
                workers, procs = cluster.second_node_workers()
                busy = [pid for pid, title in workers if "render_tile" in title or "bake_part" in title]
                if busy and len(kills) < 2:
                    victims = descendants(procs, [pid for pid, _ in workers])
                    kill(victims, signal.SIGKILL)
                    kills.append(sorted(victims))
                    print(f"killed the second node's workers {sorted(victims)}", flush=True)
                    time.sleep(2.0)
                time.sleep(0.05)
            out, _ = proc.communicate(timeout=max(1, deadline - time.monotonic()))
        finally:
            if proc.poll() is None:
                proc.kill()
        print(out[-3000:], flush=True)
        check(kills, "no tile was seen running on the second node, so nothing was killed")
        check(proc.returncode == 0, f"the run with killed workers failed: exit code {proc.returncode}")
        same_images(refs)
        print(f"2. killed workers {len(kills)} times; outputs still byte-identical ({time.monotonic() - started:.1f} s)")
    finally:
        cluster.stop()
        shutil.rmtree(work, ignore_errors=True)
    print(f"ok in {time.monotonic() - started:.1f} s")


if __name__ == "__main__":
    main()
