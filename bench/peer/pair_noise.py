# blender -b -P pair_noise.py -- MASK.exr A1.exr A2.exr [B1.exr B2.exr ...]: the relative noise of a renderer from two
# renders that differ only in their seed, with no reference: RMS(A1 - A2) / sqrt(2) over MASK's mean. A reference of
# finite samples adds its own noise to every RMSE against it and so narrows the gap between two renderers; the
# difference of two independent renders has no such term (both renderers are unbiased: their means agree to 0.1 %).
# Pixels within 2 px of one where MASK (average of channels) > 1 are left out: the light seen directly, and its edge.
import bpy, sys
argv = sys.argv[sys.argv.index("--") + 1:]
def load(p):
    im = bpy.data.images.load(p); px = list(im.pixels); w, h = im.size
    return [(px[4*i] + px[4*i+1] + px[4*i+2]) / 3 for i in range(w*h)], w, h
mask, w, h = load(argv[0])
bright = [v > 1.0 for v in mask]
keep = [y*w+x for y in range(h) for x in range(w)
        if not any(bright[yy*w+xx] for yy in range(max(0,y-2), min(h,y+3)) for xx in range(max(0,x-2), min(w,x+3)))]
mean = sum(mask[k] for k in keep) / len(keep)
for i in range(1, len(argv) - 1, 2):
    a, _, _ = load(argv[i]); b, _, _ = load(argv[i+1])
    var = sum((a[k]-b[k])**2 for k in keep) / len(keep) / 2
    print("NOISE %s %s %.5f" % (argv[i], argv[i+1], var**0.5 / mean))
