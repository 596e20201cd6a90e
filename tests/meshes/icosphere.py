"""Writes the icosphere OBJ files of the voxelizer tests: ball.obj (radius 1, 320 triangles) and
core.obj (radius 0.35, 80 triangles), outward-facing. Usage: python3 icosphere.py (in this folder)."""
import math


def icosphere(r, level):
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    v = [tuple(c / math.sqrt(sum(x * x for x in p)) for c in p) for p in v]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
         (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
         (8, 6, 7), (9, 8, 1)]
    for _ in range(level):
        cache, nf = {}, []

        def mid(a, b):
            k = (min(a, b), max(a, b))
            if k not in cache:
                p = [(v[a][i] + v[b][i]) / 2 for i in range(3)]
                n = math.sqrt(sum(x * x for x in p))
                v.append(tuple(x / n for x in p))
                cache[k] = len(v) - 1
            return cache[k]

        for a, b, c in f:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    return [tuple(r * x for x in p) for p in v], f


def write(name, r, level, comment):
    v, f = icosphere(r, level)
    with open(name, "w") as o:
        o.write(f"# {comment} (tests/meshes/icosphere.py)\n")
        for p in v:
            o.write("v %.12g %.12g %.12g\n" % p)
        for a, b, c in f:
            o.write(f"f {a + 1} {b + 1} {c + 1}\n")


write("ball.obj", 1.0, 2, "unit icosphere, 320 triangles, outward")
write("core.obj", 0.35, 1, "icosphere of radius 0.35, 80 triangles: a bone inside ball.obj")
