"""What the Ray driver (kelvin_ray.py) splits a job into and where it keeps the pieces: the tile grid, a `Piece`
(a tile, a bake part or a chunk of frames) and its staged file, a `Job` of the plan, and the durable writes of the
staging folders. No Ray here."""

import math
import os
import secrets
import socket
from dataclasses import dataclass, field

import kelvin_staged


def tile_grid(width, height, tiles):
    """Crops (x0, y0, x1, y1) of a cols x rows grid of about `tiles` tiles, as square as the image allows."""
    best = None
    for rows in range(1, tiles + 1):
        if tiles % rows:
            continue
        cols = tiles // rows
        # How far a tile is from square, in log ratio.
        score = abs(math.log((width / cols) / (height / rows)))
        if best is None or score < best[0]:
            best = (score, cols, rows)
    _, cols, rows = best
    cols, rows = min(cols, width), min(rows, height)
    xs = [i * width // cols for i in range(cols + 1)]
    ys = [j * height // rows for j in range(rows + 1)]
    return [(xs[i], ys[j], xs[i + 1], ys[j + 1]) for j in range(rows) for i in range(cols)]


def write_durably(path, data):
    """Writes `data` under a temporary name, fsyncs and renames it to `path`, then fsyncs the folder: a file
    under its final name is always whole, whenever the driver or the machine stops."""
    folder = os.path.dirname(path)
    os.makedirs(folder, exist_ok=True)
    # Unique to this host, process and call: two drivers on storage shared between machines never share one.
    tmp = os.path.join(folder, f".{os.path.basename(path)}.{socket.gethostname()}.{os.getpid()}."
                               f"{secrets.token_hex(8)}.tmp")
    with open(tmp, "wb") as f:
        f.write(data)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)
    fd = os.open(folder, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


@dataclass
class Piece:
    """One task's worth of a job: a tile of a render or a part of a bake, and its staged file."""

    job: int  # plan position
    index: int  # in the job's pieces
    what: str  # "tile X0,Y0,X1,Y1" or "part K/N"
    spec: tuple  # the crop, or (K, N)
    path: str  # where the finished piece is staged
    failed_on: set = field(default_factory=set)  # nodes it failed on
    retries: int = 0

    @property
    def kind(self):
        return self.what.split(" ")[0]  # "tile", "part" or "frames"

    def staged(self, build, planned, staging):
        """Whether the piece is staged and sound: it decodes, and records this piece, this build and files the
        plan lists (kelvin_staged.check). One that is not is quarantined (moved aside with the reason)."""
        if not os.path.exists(self.path):
            return False
        why = kelvin_staged.check("chunk" if self.kind == "frames" else self.kind, self.path, self.spec, build,
                                  planned)
        if why:
            where = kelvin_staged.quarantine(staging, self.path, f"{self.what}: {why}")
            print(f"{self.what} staged at {self.path} {why}: moved to {where}, rendered again", flush=True)
            return False
        return True


@dataclass
class Job:
    index: int  # plan position: the frames of one manifest job share its manifest index
    entry: dict  # the plan's entry
    staging: str = ""  # folder of the staged pieces
    pieces: list = field(default_factory=list)
    have: int = 0  # pieces staged
    status: tuple = None  # ("rendered" | "skipped" | "FAILED", detail) once decided

    @property
    def name(self):
        return self.entry["name"]

    @property
    def bake(self):
        return self.entry.get("command") == "bake"

    @property
    def chunk(self):
        """A chunk of frames: rendered whole, in one process, as one task."""
        return len(self.entry.get("frames") or []) > 1


def pieces_of(i, job, tiles):
    """The job's tiles (or bake parts) and where each is staged."""
    entry = job.entry
    if job.bake:
        n = entry["parts"]
        job.staging = entry["parts_dir"]
        return [Piece(i, k, f"part {k + 1}/{n}", (k + 1, n), os.path.join(job.staging, f"part-{k + 1}-of-{n}.kbake"))
                for k in range(n)]
    if job.chunk:
        # Beside the job's output pattern, one folder per chunk (the chunks of a job share the pattern).
        job.staging = f"{entry['output']}.chunk-{entry['frames'][0]}-{entry['frames'][-1]}"
        frames = entry["frames"]
        return [Piece(i, 0, f"frames {frames[0]}-{frames[-1]}", (), os.path.join(job.staging, "frames.tar"))]
    # A job whose tiles would not merge into its image (ReSTIR's reuse) renders as one tile.
    crops = tile_grid(entry["width"], entry["height"], 1 if entry.get("untileable") else tiles)
    job.staging = entry["output"] + ".tiles"
    return [Piece(i, t, "tile " + ",".join(map(str, c)), c, os.path.join(job.staging, "_".join(map(str, c)) + ".exr"))
            for t, c in enumerate(crops)]


def remove_temporaries(folder):
    """Removes half-written pieces a killed driver left (their names end in .tmp)."""
    if os.path.isdir(folder):
        for name in os.listdir(folder):
            if name.startswith(".") and name.endswith(".tmp"):
                os.remove(os.path.join(folder, name))
