#!/usr/bin/env python3
"""kelvin's exit codes as the Ray driver reads them (kelvin_exit.py), with a real kelvin: a full disk (here a file
size limit: the write fails with EFBIG, as it would with ENOSPC) exits with the environment code, which the driver
retries on another node; a scene that does not exist exits with the bad-input code, which it does not retry. The
driver's own commands (`run_local`: its plan and merges) report a timeout as a transient failure.

    KELVIN_BIN=target/debug/kelvin python3 distributed/ray/test_exit_codes.py

Needs no Ray.
"""

import os
import resource
import signal
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import kelvin_exit  # noqa: E402

KELVIN = os.environ.get("KELVIN_BIN", "target/debug/kelvin")


def small_disk():
    """In the child: files of at most 4 KiB, and a write past that fails (EFBIG) instead of killing (SIGXFSZ)."""
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))


def render(out, scene=None, preexec=None):
    args = [KELVIN, "render", *([scene] if scene else []), "--size", "64x64", "--spp", "1", "-o", out]
    return subprocess.run(args, capture_output=True, text=True, timeout=300, preexec_fn=preexec)


def main():
    with tempfile.TemporaryDirectory(prefix="kelvin-exit-") as tmp:
        full = render(os.path.join(tmp, "full.exr"), preexec=small_disk)
        assert full.returncode == kelvin_exit.ENVIRONMENT, (full.returncode, full.stderr)
        assert kelvin_exit.is_transient(full.returncode), "a full disk is the node's: retried elsewhere"
        bad = render(os.path.join(tmp, "bad.exr"), scene=os.path.join(tmp, "missing.gltf"))
        assert bad.returncode == kelvin_exit.INPUT, (bad.returncode, bad.stderr)
        assert not kelvin_exit.is_transient(bad.returncode), "bad input fails anywhere: not retried"
        assert kelvin_exit.is_transient(-signal.SIGKILL) and not kelvin_exit.is_transient(kelvin_exit.PANIC)
        # The driver's own commands (plan, merges): a timeout or a binary that cannot run is transient, kelvin's
        # refusal is not; none raises.
        slow = os.path.join(tmp, "slow-kelvin")
        with open(slow, "w") as f:
            f.write("#!/bin/sh\nexec sleep 30\n")
        os.chmod(slow, 0o755)
        _, timed_out = kelvin_exit.run_local([slow, "merge"], "kelvin merge", 0.5)
        assert timed_out.transient and "timed out after 0.5 s" in str(timed_out), timed_out
        _, missing = kelvin_exit.run_local([os.path.join(tmp, "no-kelvin")], "kelvin merge", 5)
        assert missing.transient and "cannot run" in str(missing), missing
        _, refused = kelvin_exit.run_local([KELVIN, "merge", os.path.join(tmp, "missing.exr"), "-o",
                                            os.path.join(tmp, "m.exr")], "kelvin merge", 300)
        assert not refused.transient and "missing.exr" in str(refused), refused
    print("exit codes: ok (full disk -> 3, retried; missing scene -> 2, not retried; a timeout is transient)")


if __name__ == "__main__":
    main()
