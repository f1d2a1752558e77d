#!/usr/bin/env python3
"""The driver's waves without a cluster: Ray's calls replaced by a fake that finishes the tasks in flight in a
random order, each job's first tile last (so that as many jobs as possible stay open), some tasks failing on their
node (retried). At every submission and every wait the test counts, itself, the tasks in flight and the tiles
staged on disk: never more than --in-flight and --open-jobs x tiles (or (window + 1) x tiles without --open-jobs),
with an explicit window and the automatic one; every job is merged once, from all its tiles, and the tracker actor
is told to forget every attempt.

    target/ray-venv/bin/python distributed/ray/test_waves.py

Imports ray (kelvin_ray does) but starts no cluster; a second.
"""

import argparse
import contextlib
import io
import os
import random
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import kelvin_ray  # noqa: E402

TILES = 4
NODES = [{"NodeID": f"{k:056x}", "Alive": True, "Resources": {"CPU": 1.0}} for k in range(3)]  # Ray's id form


class Ref:
    def __init__(self, value):
        self.value = value


class FakeRay:
    """The part of `ray` the driver's loop calls. Tasks finish when `wait` says so; a task's result is made then."""

    exceptions = kelvin_ray.ray.exceptions

    def __init__(self, test):
        self.test, self.rng = test, random.Random(7)

    def wait(self, refs, num_returns, timeout):
        self.test.check_bounds()
        # Each job's first tile waits until nothing else is in flight.
        later = [r for r in refs if r.value[1].index == 0]
        first = [r for r in refs if r.value[1].index != 0] or later
        ready = self.rng.sample(first, self.rng.randint(1, min(len(first), max(1, num_returns))))
        return ready, [r for r in refs if r not in ready]

    def get(self, ref, timeout=None):
        kind, piece = ref.value
        if kind == "where":
            return piece
        if self.rng.random() < 0.1:  # lost with its worker: transient, retried on another node
            raise self.exceptions.WorkerCrashedError()
        return b"tile " + piece.what.encode(), NODES[0]["NodeID"], 0.1, 0.05, "kelvin's stderr"

    def cancel(self, ref, force=False):
        pass

    def nodes(self):
        return NODES


class Task:
    """`render_tile` and friends: `.options(...).remote(...)` returns a ref to the piece it renders."""

    def __init__(self, test):
        self.test = test

    def options(self, **_):
        return self

    def remote(self, *args):
        self.test.check_bounds(submitting=True)
        return Ref(("tile", self.test.farm.last_piece))


class Tracker:
    """The `Whereabouts` actor (any method: `.remote()` returns a ref to the second node) and the runtime context."""

    forgotten = []  # attempts the driver told the actor to forget

    def __getattr__(self, name):
        self.method = name
        return self

    def remote(self, *args):
        if self.method == "forget":
            self.forgotten.extend(args[0])
        return Ref(("where", NODES[1]["NodeID"]))

    def __call__(self):
        return NODES[0]["NodeID"]


class TrackerClass:
    def options(self, **_):
        return self

    def remote(self):
        return Tracker()


class WaveTest:
    def __init__(self, folder, in_flight, open_jobs, jobs=40):
        self.folder, self.merged = folder, []
        self.window = in_flight or max(kelvin_ray.IN_FLIGHT_MIN, kelvin_ray.IN_FLIGHT_PER_SLOT * len(NODES))
        self.max_staged = (open_jobs or self.window + 1) * TILES
        self.peak_in_flight = self.peak_staged = 0
        kelvin = os.path.join(folder, "kelvin")
        with open(kelvin, "w") as f:
            f.write("not run")
        entries = [{"name": f"j{i}", "output": os.path.join(folder, f"out/j{i}.exr"), "width": 16, "height": 16,
                    "error": None, "done": False, "untileable": None, "command": "render", "args": [],
                    "inputs": {}, "frames": [], "exposure": None} for i in range(jobs)]
        opts = argparse.Namespace(tiles=TILES, threads=1, max_retries=50, task_timeout=1, timeout=1e9, force=False,
                                  summary=None, in_flight=in_flight, open_jobs=open_jobs,
                                  task_logs=None)
        kelvin_ray.ray = FakeRay(self)
        kelvin_ray.render_tile = Task(self)
        kelvin_ray.Whereabouts = TrackerClass()
        kelvin_ray.ray.get_runtime_context = lambda: Tracker()
        kelvin_ray.merge = self.merge
        farm = kelvin_ray.Farm.__new__(kelvin_ray.Farm)
        self.farm = farm
        # Farm.__init__ with the fakes in place; `last_piece` lets the fake task know what it renders.
        kelvin_ray.Farm.__init__(farm, kelvin, entries, opts)
        submit = farm.submit

        def remembering(piece, node=None):
            farm.last_piece = piece
            submit(piece, node)

        farm.submit = remembering

    def staged(self):
        return sum(len(names) for d, _, names in os.walk(self.folder) if d.endswith(".tiles"))

    def check_bounds(self, submitting=False):
        """The test's own count: tasks in flight (one more when a submission is under way) and tiles on disk."""
        in_flight = len(self.farm.pending) + submitting
        self.peak_in_flight = max(self.peak_in_flight, in_flight)
        self.peak_staged = max(self.peak_staged, self.staged())
        assert in_flight <= self.window, f"{in_flight} tasks in flight, more than the window of {self.window}"
        assert self.peak_staged <= self.max_staged, f"{self.peak_staged} tiles staged, more than {self.max_staged}"

    def merge(self, kelvin, job):
        assert all(os.path.exists(p.path) for p in job.pieces) and len(job.pieces) == TILES, job.name
        self.merged.append(job.name)
        os.makedirs(os.path.dirname(job.entry["output"]), exist_ok=True)
        return None

    def run(self):
        with contextlib.redirect_stdout(io.StringIO()):  # the driver's progress lines
            self.farm.plan_jobs()
            self.farm.run()
        jobs = self.farm.jobs
        assert [j.status[0] for j in jobs] == ["rendered"] * len(jobs), [j.status for j in jobs]
        assert sorted(self.merged) == sorted(j.name for j in jobs), "every job merged once"
        assert self.farm.retry_log, "some tasks failed and were retried"
        assert self.farm.peak["in_flight"] == self.peak_in_flight, (self.farm.peak, self.peak_in_flight)
        attempts = self.farm.tasks + len(self.farm.retry_log)
        assert len(set(Tracker.forgotten)) == attempts, "the tracker forgets every attempt once handled"
        Tracker.forgotten.clear()
        return self


def main():
    real_ray = kelvin_ray.ray
    for in_flight, open_jobs in ((6, 2), (5, 0), (0, 3)):
        with tempfile.TemporaryDirectory(prefix="kelvin-waves-") as tmp:
            t = WaveTest(tmp, in_flight, open_jobs).run()
            print(f"--in-flight {in_flight} --open-jobs {open_jobs}: 40 jobs x {TILES} tiles, "
                  f"{len(t.farm.retry_log)} retries; at most {t.peak_in_flight} in flight (window {t.window}), "
                  f"{t.peak_staged} tiles staged (bound {t.max_staged}), {t.farm.peak['open_jobs']} jobs open")
            # The wait must not have kept the window waiting: it was full most of the time.
            assert t.peak_in_flight == t.window, "the window was never full"
        kelvin_ray.ray = real_ray
    print("waves: ok")


if __name__ == "__main__":
    main()
