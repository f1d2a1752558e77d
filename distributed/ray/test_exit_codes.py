#!/usr/bin/env python3
"""kelvin's exit codes as the Ray driver reads them (kelvin_exit.py), with a real kelvin: a full disk (here a file
size limit: the write fails with EFBIG, as it would with ENOSPC) exits with the environment code, which the driver
retries on another node; a scene that does not exist exits with the bad-input code, which it does not retry.

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
    print("exit codes: ok (full disk -> 3, retried; missing scene -> 2, not retried)")


if __name__ == "__main__":
    main()
