#!/usr/bin/env python3
"""The Ray driver's own kelvin commands when they hang (a stuck network disk, say): `kelvin batch --plan` over its
timeout ends the driver with exit code 3 (transient: run it again) and a message, not a traceback; a merge over
its timeout fails its job and keeps the staged tiles where they are (not quarantined, not deleted), for a rerun.

    target/ray-venv/bin/python distributed/ray/test_driver_timeouts.py

Imports ray (kelvin_ray does) but starts no cluster.
"""

import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import kelvin_exit  # noqa: E402
import kelvin_ray  # noqa: E402


def main():
    kelvin_ray.PLAN_TIMEOUT = kelvin_ray.MERGE_TIMEOUT = 0.5
    with tempfile.TemporaryDirectory(prefix="kelvin-timeouts-") as tmp:
        slow = os.path.join(tmp, "slow-kelvin")
        with open(slow, "w") as f:
            f.write("#!/bin/sh\nexec sleep 30\n")
        os.chmod(slow, 0o755)

        try:
            kelvin_ray.plan(slow, os.path.join(tmp, "jobs.json"))
            raise AssertionError("a plan that timed out returned")
        except SystemExit as e:
            assert e.code == kelvin_exit.ENVIRONMENT, e.code

        # A job whose two tiles are staged, merged by a kelvin that hangs.
        entry = {"name": "room", "output": os.path.join(tmp, "out", "room.exr"), "width": 8, "height": 8,
                 "untileable": None, "error": None, "done": False}
        job = kelvin_ray.Job(0, entry)
        job.pieces = kelvin_ray.pieces_of(0, job, 2)
        for piece in job.pieces:
            kelvin_ray.write_durably(piece.path, b"a staged tile")
        farm = kelvin_ray.Farm.__new__(kelvin_ray.Farm)  # no cluster: finish() needs the binary and the window
        farm.kelvin, farm.open, farm.staged_now = slow, {0}, 0
        paths = [p.path for p in job.pieces]  # finish() forgets the pieces of a decided job
        farm.finish(job)
        state, detail = job.status
        assert state == "FAILED" and "timed out after 0.5 s" in detail and "stay in" in detail, job.status
        assert all(os.path.exists(p) for p in paths), "the staged tiles stay"
        assert not os.path.exists(job.staging.rstrip(os.sep) + ".quarantine"), "nothing quarantined"
        # The staging folder holds the tiles only: the temporaries' names were unique and renamed away.
        assert sorted(os.listdir(job.staging)) == sorted(os.path.basename(p) for p in paths)
    print("driver timeouts: ok (plan -> exit 3; a merge that timed out keeps its staged tiles)")


if __name__ == "__main__":
    main()
