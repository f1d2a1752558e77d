"""What the Ray driver checks of a staged piece before it trusts it, and where it moves one it does not.

A staged tile is an EXR whose header records what made it (kelvin's `kelvin` attribute: the program's SHA-256, the
digests of the files it read, the tile); a bake part a `.kbake` with a JSON header and a trailing SHA-256 of its
bytes. A piece that does not decode, or that records another tile, another build, or input files the plan does not
list, is foreign: it is moved aside into the job's quarantine folder with a `.why` file saying why, and rendered
again; the other pieces stay. Nothing is deleted.
"""

import hashlib
import json
import os
import struct
import tarfile

EXR_MAGIC = b"\x76\x2f\x31\x01"
KBAKE_MAGIC = b"kelvin bake part"


def exr_attributes(path, limit=1 << 20):
    """The header attributes of a single-part EXR at `path` (name -> (type, raw bytes)); ValueError if it is not
    one. Reads the header only (at most `limit` bytes)."""
    with open(path, "rb") as f:
        data = f.read(limit)
    if data[:4] != EXR_MAGIC:
        raise ValueError("not an OpenEXR file")
    at, attributes = 8, {}

    def cstring(at):
        end = data.index(b"\0", at)
        return data[at:end].decode("latin-1"), end + 1

    try:
        while data[at] != 0:
            name, at = cstring(at)
            kind, at = cstring(at)
            (size,) = struct.unpack_from("<i", data, at)
            at += 4
            if size < 0 or at + size > len(data):
                raise ValueError(f"attribute {name} runs past the header")
            attributes[name] = (kind, data[at:at + size])
            at += size
    except (IndexError, struct.error) as e:
        raise ValueError(f"header cut short: {e}")
    return attributes


def exr_provenance(path):
    """The provenance (a dict) a kelvin EXR records; ValueError if it records none."""
    kind, raw = exr_attributes(path).get("kelvin", (None, b""))
    if kind != "string":
        raise ValueError("records no kelvin provenance")
    return json.loads(raw.decode("latin-1"))


def kbake_header(path):
    """The JSON header of a kelvin bake part, its checksum verified; ValueError if the file is damaged."""
    with open(path, "rb") as f:
        data = f.read()
    if not data.startswith(KBAKE_MAGIC) or len(data) < len(KBAKE_MAGIC) + 4 + 32:
        raise ValueError("not a kelvin bake part")
    if hashlib.sha256(data[:-32]).digest() != data[-32:]:
        raise ValueError("its checksum does not match its bytes (damaged or cut short)")
    (n,) = struct.unpack_from("<I", data, len(KBAKE_MAGIC))
    start = len(KBAKE_MAGIC) + 4
    return json.loads(data[start:start + n])


def input_digests(provenance):
    """The digests of the files a piece's provenance says it read (a render's `scene`, `env`, `input ...`; a
    bake's `inputs`)."""
    listed = provenance.get("inputs") if isinstance(provenance.get("inputs"), dict) else provenance
    return {v for k, v in listed.items() if (k in ("scene", "env") or k.startswith("input ")) and
            isinstance(v, str) and v.startswith("sha256:")}


def foreign(provenance, build, planned):
    """Why a piece's provenance is not this run's (another build, or files the plan does not list), or None."""
    program = provenance.get("program", "")
    if program.split(" ")[-1] != build:
        return f"made by another build ({program})"
    unknown = input_digests(provenance) - set(planned.values())
    if unknown:
        return f"made from files the plan does not list ({sorted(unknown)[0][:19]}...)"
    return None


def check(piece_kind, path, spec, build, planned):
    """Why the staged piece at `path` cannot be used (None: it can). `piece_kind` is "tile" (spec: the crop),
    "part" (spec: (K, N)) or "chunk"; `build` the kelvin binary's digest, `planned` the plan's inputs."""
    try:
        if piece_kind == "tile":
            p = exr_provenance(path)
            want = ",".join(map(str, spec))
            if p.get("tile") != want:
                return f"records tile {p.get('tile')}, not {want}"
            return foreign(p, build, planned)
        if piece_kind == "part":
            h = kbake_header(path)
            if (h.get("part", -1) + 1, h.get("parts")) != tuple(spec):
                return f"is part {h.get('part', -1) + 1} of {h.get('parts')}, not {spec[0]} of {spec[1]}"
            return foreign(h.get("provenance") or {}, build, planned)
        with tarfile.open(path) as tar:
            tar.getmembers()
        return None
    except (OSError, ValueError, KeyError, tarfile.TarError) as e:
        return f"does not read back: {e}"


def quarantine(staging, path, reason):
    """Moves `path` into `STAGING.quarantine/` with `NAME.why` holding `reason`; returns where it went."""
    folder = staging.rstrip(os.sep) + ".quarantine"
    os.makedirs(folder, exist_ok=True)
    target = os.path.join(folder, os.path.basename(path))
    os.replace(path, target)
    with open(target + ".why", "w") as f:
        f.write(reason + "\n")
    return target
