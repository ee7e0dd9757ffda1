# blender -b -P balls_peer.py -- BALLS.json means A.exr [B.exr ...] | noise A1.exr A2.exr [B1.exr B2.exr ...]
# Per-ball figures on the material-ball grid, over each ball's inner disc (0.8 of its radius on the image, from
# BALLS.json as cycles_balls.py writes it) and the floor in front (the lower 40 % of the image away from the balls):
#   means: each image's mean there (average of channels), and its ratio to the first image's;
#   noise: the relative noise of each pair of renders that differ only in their seed, RMS(A1 - A2) / sqrt(2) over
#          the pair's mean, over all those regions together (edges left out: there one renderer's seed moves its
#          pixel samples and the other's does not).
import json
import sys

import bpy
import numpy

argv = sys.argv[sys.argv.index("--") + 1:]
balls = json.load(open(argv[0]))
mode, files = argv[1], argv[2:]


def load(path):
    image = bpy.data.images.load(path)
    w, h = image.size
    px = numpy.empty(w * h * 4, dtype=numpy.float32)
    image.pixels.foreach_get(px)
    # Blender's rows run bottom to top; the discs were measured from the top.
    return px.reshape(h, w, 4)[::-1, :, :3].mean(axis=2).astype(numpy.float64)


first = load(files[0])
h, w = first.shape
yy, xx = numpy.mgrid[0:h, 0:w]
regions, near = [], numpy.zeros((h, w), bool)
for b in balls:
    d2 = (xx + 0.5 - b["x"]) ** 2 + (yy + 0.5 - b["y"]) ** 2
    regions.append((b["name"], d2 <= (0.8 * b["radius"]) ** 2))
    near |= d2 <= (1.1 * b["radius"]) ** 2
regions.append(("floor", (~near) & (yy > 0.6 * h)))
if mode == "means":
    images = [first] + [load(f) for f in files[1:]]
    for name, m in regions:
        means = [img[m].mean() for img in images]
        print("MEAN %-14s %s" % (name, " ".join("%.4f" % v for v in means)),
              " ratios " + " ".join("%.3f" % (v / means[0]) for v in means[1:]))
else:
    everywhere = numpy.zeros((h, w), bool)
    for _, m in regions:
        everywhere |= m
    for i in range(0, len(files), 2):
        a = first if i == 0 else load(files[i])
        b = load(files[i + 1])
        noise = numpy.sqrt(((a - b)[everywhere] ** 2).mean() / 2) / ((a + b)[everywhere].mean() / 2)
        print("NOISE %s %s %.5f" % (files[i], files[i + 1], noise))
