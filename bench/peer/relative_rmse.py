# blender -b -P relative_rmse.py -- REF.exr A.exr ...: relative RMSE against REF, leaving out the pixels within 2 px of one
# where REF (average of channels) > 1 (the light seen directly, and its edge).
import bpy, sys
argv = sys.argv[sys.argv.index("--") + 1:]
def load(p):
    im = bpy.data.images.load(p); px = list(im.pixels); w, h = im.size
    return [(px[4*i] + px[4*i+1] + px[4*i+2]) / 3 for i in range(w*h)], w, h
ref, w, h = load(argv[0])
bright = [v > 1.0 for v in ref]
keep = []
for y in range(h):
    for x in range(w):
        if not any(bright[yy*w+xx] for yy in range(max(0,y-2), min(h,y+3)) for xx in range(max(0,x-2), min(w,x+3))):
            keep.append(y*w+x)
rm = sum(ref[i] for i in keep) / len(keep)
print("REF %s kept %d mean %.5f" % (argv[0], len(keep), rm))
for p in argv[1:]:
    a, _, _ = load(p)
    se = sum((a[i]-ref[i])**2 for i in keep) / len(keep)
    print("ERR %s %.5f" % (p, se**0.5/rm))
