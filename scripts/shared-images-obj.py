#!/usr/bin/env python3
"""Writes an OBJ scene of many parts whose materials share a few images: a
wavy 336 x 336 grid (225,792 triangles) cut into 45 parts, each part its own
material, the materials naming the given images in turn.

    scripts/shared-images-obj.py OUT_DIR IMAGE [IMAGE ...]

The images are copied into OUT_DIR beside scene.obj and scene.mtl. Then, for
example: /usr/bin/time -v kage render OUT_DIR/scene.obj --width 1280 --height 720
"""
import math
import os
import shutil
import sys

if len(sys.argv) < 3:
    sys.exit(__doc__)
out_dir, images = sys.argv[1], sys.argv[2:]
os.makedirs(out_dir, exist_ok=True)
names = []
for k, image in enumerate(images):
    name = f"image{k}{os.path.splitext(image)[1]}"
    shutil.copyfile(image, os.path.join(out_dir, name))
    names.append(name)
n, parts = 336, 45
with open(os.path.join(out_dir, "scene.obj"), "w") as out:
    out.write("mtllib scene.mtl\n")
    for j in range(n + 1):
        for i in range(n + 1):
            x, z = i / n * 10 - 5, j / n * 10 - 5
            out.write(f"v {x:.4f} {0.3 * math.sin(x * 1.7) * math.cos(z * 1.3):.4f} {z:.4f}\n")
    for j in range(n + 1):
        for i in range(n + 1):
            out.write(f"vt {i / n * 4:.4f} {j / n * 4:.4f}\n")
    rows = math.ceil(n / parts)
    current = -1
    for j in range(n):
        part = min(j // rows, parts - 1)
        if part != current:
            out.write(f"usemtl m{part}\n")
            current = part
        for i in range(n):
            a = j * (n + 1) + i + 1
            b, c = a + 1, a + n + 1
            out.write(f"f {a}/{a} {c}/{c} {b}/{b}\nf {b}/{b} {c}/{c} {c + 1}/{c + 1}\n")
with open(os.path.join(out_dir, "scene.mtl"), "w") as mtl:
    for m in range(parts):
        mtl.write(f"newmtl m{m}\nKd 0.{m % 9 + 1} 0.8 0.7\nmap_Kd {names[m % len(names)]}\n\n")
