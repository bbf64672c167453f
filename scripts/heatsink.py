#!/usr/bin/env python3
"""Writes assets/heatsink.obj: a finned heat sink as one flat-shaded mesh (a
base plate and a row of thin fins on it), the CAD part of the shadow
examples — its fins shadow each other and the plate, one object shadowing
itself.

    python3 scripts/heatsink.py     # from the repository root
"""

BASE = (2.4, 0.25, 1.6)  # width (x), height (y), depth (z), centred on x and z
FINS = 11
FIN_THICKNESS = 0.06
FIN_HEIGHT = 0.9


def box(lo, hi):
    """The six faces of an axis-aligned box, as (normal, four corners) counter-clockwise from outside."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    return [
        ((1, 0, 0), [(x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)]),
        ((-1, 0, 0), [(x0, y0, z1), (x0, y1, z1), (x0, y1, z0), (x0, y0, z0)]),
        ((0, 1, 0), [(x0, y1, z0), (x0, y1, z1), (x1, y1, z1), (x1, y1, z0)]),
        ((0, -1, 0), [(x0, y0, z1), (x0, y0, z0), (x1, y0, z0), (x1, y0, z1)]),
        ((0, 0, 1), [(x1, y0, z1), (x1, y1, z1), (x0, y1, z1), (x0, y0, z1)]),
        ((0, 0, -1), [(x0, y0, z0), (x0, y1, z0), (x1, y1, z0), (x1, y0, z0)]),
    ]


def main():
    w, h, d = BASE
    faces = box((-w / 2, 0.0, -d / 2), (w / 2, h, d / 2))
    pitch = (w - FIN_THICKNESS) / (FINS - 1)
    for i in range(FINS):
        x = -w / 2 + i * pitch
        faces += box((x, h, -d / 2), (x + FIN_THICKNESS, h + FIN_HEIGHT, d / 2))
    lines = ["# A finned heat sink: written by scripts/heatsink.py", "o heatsink"]
    normals = {}
    for n, _ in faces:
        normals.setdefault(n, len(normals) + 1)
    lines += [f"vn {n[0]} {n[1]} {n[2]}" for n in normals]
    v = 0
    for n, quad in faces:
        lines += [f"v {x:.4f} {y:.4f} {z:.4f}" for x, y, z in quad]
        k = normals[n]
        a, b, c, e = v + 1, v + 2, v + 3, v + 4
        lines += [f"f {a}//{k} {b}//{k} {c}//{k}", f"f {a}//{k} {c}//{k} {e}//{k}"]
        v += 4
    with open("assets/heatsink.obj", "w") as out:
        out.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
