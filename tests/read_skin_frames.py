"""Reads a run's skin caches with numpy alone (an implementation independent of Sinew's writer) and checks
them against each other: skin.frames (Sinew's record), skin.pc2 and skin.glb hold the same frames, the
frames are those of the given steps, and (with --same-as DIR) equal another run's to 1e-5.

Usage: read_skin_frames.py RESULTS --steps 0,1,2 [--same-as OTHER_RESULTS]"""
import json
import os
import struct
import sys

import numpy as np


def read_frames(results):
    with open(os.path.join(results, "skin.frames"), "rb") as f:
        data = f.read()
    if data[:8] != b"SINEWSKN":
        sys.exit(f"FAIL: {results}/skin.frames is not a frame file")
    version, vertices, nfields = struct.unpack_from("<III", data, 8)
    names = [data[20 + 32 * k:52 + 32 * k].rstrip(b"\0").decode() for k in range(nfields)]
    head = 20 + 32 * nfields
    record = 24 + 4 * (3 + nfields) * vertices
    frames = []
    for at in range(head, len(data) - record + 1, record):
        step, load, time = struct.unpack_from("<qdd", data, at)
        x = np.frombuffer(data, "<f4", 3 * vertices, at + 24).reshape(-1, 3)
        fields = np.frombuffer(data, "<f4", nfields * vertices, at + 24 + 12 * vertices).reshape(nfields, vertices)
        frames.append((step, time, x, fields))
    if (len(data) - head) % record:
        sys.exit(f"FAIL: {results}/skin.frames ends in a partial record")
    return names, vertices, frames


def read_pc2(results):
    with open(os.path.join(results, "skin.pc2"), "rb") as f:
        data = f.read()
    if data[:12] != b"POINTCACHE2\0":
        sys.exit("FAIL: skin.pc2 has no PC2 header")
    version, points, start, sampling, samples = struct.unpack_from("<iiffi", data, 12)
    if len(data) != 32 + 12 * points * samples:
        sys.exit(f"FAIL: skin.pc2 is {len(data)} bytes, its header says {samples} samples of {points} points")
    return start, sampling, np.frombuffer(data, "<f4", offset=32).reshape(samples, points, 3)


def read_glb(results):
    with open(os.path.join(results, "skin.glb"), "rb") as f:
        data = f.read()
    magic, version, length = struct.unpack_from("<III", data, 0)
    if magic != 0x46546C67 or version != 2 or length != len(data):
        sys.exit("FAIL: skin.glb has no glTF 2.0 binary header")
    json_length, _ = struct.unpack_from("<II", data, 12)
    doc = json.loads(data[20:20 + json_length])
    bin_at = 20 + json_length + 8

    def accessor(k):
        a = doc["accessors"][k]
        view = doc["bufferViews"][a["bufferView"]]
        width = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[a["type"]]
        dtype = {5126: "<f4", 5125: "<u4"}[a["componentType"]]
        return np.frombuffer(data, dtype, a["count"] * width, bin_at + view.get("byteOffset", 0)).reshape(a["count"], width)

    prim = doc["meshes"][0]["primitives"][0]
    rest = accessor(prim["attributes"]["POSITION"])
    positions = [rest + accessor(t["POSITION"]) for t in prim.get("targets", [])]
    sampler = doc["animations"][0]["samplers"][0]
    times = accessor(sampler["input"])[:, 0]
    return doc, positions, times


def main(argv):
    results = argv[0]
    steps = [int(s) for s in argv[argv.index("--steps") + 1].split(",")]
    names, vertices, frames = read_frames(results)
    got = [f[0] for f in frames]
    if got != steps:
        sys.exit(f"FAIL: {results}/skin.frames holds steps {got}, expected {steps}")
    x = np.array([f[2] for f in frames])
    start, sampling, pc2 = read_pc2(results)
    if pc2.shape != x.shape or not np.array_equal(pc2, x):
        sys.exit(f"FAIL: skin.pc2 ({pc2.shape}) differs from skin.frames ({x.shape})")
    doc, glb, times = read_glb(results)
    extras = doc["meshes"][0]["extras"]
    if extras["sinew_steps"] != steps or len(glb) != len(steps):
        sys.exit(f"FAIL: skin.glb holds steps {extras['sinew_steps']}")
    worst = max(float(np.abs(g - f).max()) for g, f in zip(glb, x))
    if worst > 1e-5:
        sys.exit(f"FAIL: skin.glb's frames differ from skin.frames by {worst:.3g}")
    if not np.all(np.diff(times) > 0) or not np.allclose(times, [f[1] for f in frames], atol=1e-6):
        sys.exit(f"FAIL: animation times {times} are not the frames' times")
    print(f"{results}: {len(steps)} frames of {vertices} vertices, fields {names}, glb = frames to {worst:.2g}, "
          f"pc2 = frames, times {times[0]:.4g}..{times[-1]:.4g} s (pc2 start {start:g}, sampling {sampling:g})")
    if "--same-as" in argv:
        other = argv[argv.index("--same-as") + 1]
        _, _, reference = read_frames(other)
        ref = np.array([f[2] for f in reference])
        if ref.shape != x.shape:
            sys.exit(f"FAIL: {other} has frames of shape {ref.shape}, this run {x.shape}")
        diff = float(np.abs(ref - x).max())
        print(f"  equal to {other}'s frames to {diff:.3g}")
        if diff > 1e-5:
            sys.exit(f"FAIL: the frames differ from {other}'s by {diff:.3g}")


if __name__ == "__main__":
    main(sys.argv[1:])
