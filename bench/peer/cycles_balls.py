# Blender's Cycles renders the material-ball grid (../shared/scenes/gltf/balls.glb) as examples/material_balls.lua
# renders it: the file imported by Blender's own glTF importer (its camera, its sun, Principled BSDFs from the
# metal-roughness materials), an HDRI as the world, no denoising, no clamping, no adaptive sampling, a box pixel
# filter one pixel wide, 2 threads. Also writes, next to the image, OUT.balls.json: each ball's name and its disc
# on the image (centre and radius in pixels, from the camera's projection), for per-ball means.
#
#   blender -b -P cycles_balls.py -- OUT.exr SPP WIDTH HEIGHT SEED HDRI.exr [GGX|MULTI_GGX|LAMBERT|GLASS|GLASS_MULTI] [nosun]
#   (prints RENDER_SECONDS; nosun removes the file's sun)
#
# LAMBERT makes every material a Diffuse BSDF of its base colour: the light transport alone, without the models.
# GLASS makes the front row's dielectric balls rough glass (Principled GGX with Transmission 1) and every other
# material Lambert, as lightfarm_balls_lambert.lua's glass=1 does: the glass model alone against Cycles'
# (GLASS_MULTI: the same with multiscatter GGX glass).
import json
import math
import sys
import time

import bpy
import numpy
from bpy_extras.object_utils import world_to_camera_view
from mathutils import Vector

numpy.bool = bool  # Debian 12's Blender 3.4 glTF importer still names numpy.bool, which numpy 1.24 dropped

args = sys.argv[sys.argv.index("--") + 1:]
out, spp, width, height, seed, hdri = args[0], int(args[1]), int(args[2]), int(args[3]), int(args[4]), args[5]
distribution = args[6] if len(args) > 6 else "GGX"
with_sun = not (len(args) > 7 and args[7] == "nosun")
here = __file__.rsplit("/", 1)[0]

bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=here + "/../../../shared/scenes/gltf/balls.glb")
scene = bpy.context.scene
scene.camera = bpy.data.objects["Camera"]
if not with_sun:
    bpy.data.objects.remove(bpy.data.objects["Sun"], do_unlink=True)

for m in bpy.data.materials:
    node = m.node_tree.nodes.get("Principled BSDF") if m.node_tree else None
    if not node:
        continue
    if distribution.startswith("GLASS") and m.name.startswith("Ball_m0_"):
        node.distribution = "MULTI_GGX" if distribution == "GLASS_MULTI" else "GGX"
        node.inputs["Transmission"].default_value = 1.0
    elif distribution in ("LAMBERT", "GLASS", "GLASS_MULTI"):  # the light alone: every material a Lambert surface of its base colour
        diffuse = m.node_tree.nodes.new("ShaderNodeBsdfDiffuse")
        diffuse.inputs["Color"].default_value = node.inputs["Base Color"].default_value
        output = m.node_tree.nodes["Material Output"]
        m.node_tree.links.new(diffuse.outputs["BSDF"], output.inputs["Surface"])
    else:
        node.distribution = distribution

world = bpy.data.worlds.new("hdri")
scene.world = world
world.use_nodes = True
nodes = world.node_tree.nodes
texture = nodes.new("ShaderNodeTexEnvironment")
texture.image = bpy.data.images.load(hdri)
texture.interpolation = "Linear"
world.node_tree.links.new(texture.outputs["Color"], nodes["Background"].inputs["Color"])
nodes["Background"].inputs["Strength"].default_value = 1.0

scene.render.engine = "CYCLES"
c = scene.cycles
c.device = "CPU"
c.samples = spp
c.seed = seed
c.use_adaptive_sampling = False
c.use_denoising = False
c.sample_clamp_direct = 0
c.sample_clamp_indirect = 0
c.max_bounces = 64
c.diffuse_bounces = 64
c.glossy_bounces = 64
c.transmission_bounces = 64
c.transparent_max_bounces = 64
c.caustics_reflective = True
c.caustics_refractive = True
c.blur_glossy = 0.0
c.pixel_filter_type = "BOX"
c.filter_width = 1.0
scene.render.threads_mode = "FIXED"
scene.render.threads = 2
scene.render.resolution_x = width
scene.render.resolution_y = height
scene.render.resolution_percentage = 100
scene.render.film_transparent = False
scene.view_settings.view_transform = "Standard"
scene.view_settings.look = "None"
scene.view_settings.exposure = 0
scene.view_settings.gamma = 1
scene.render.image_settings.file_format = "OPEN_EXR"
scene.render.image_settings.color_depth = "32"
scene.render.image_settings.exr_codec = "ZIP"
scene.render.filepath = out

t0 = time.time()
bpy.ops.render.render(write_still=True)
print("RENDER_SECONDS %.3f" % (time.time() - t0))

# Each ball's disc on the image: its centre projected, and the largest distance to a projected point of its rim
# (the sphere seen from the camera: points at the radius perpendicular to the view).
camera = scene.camera
eye = camera.matrix_world.translation
balls = []
for o in bpy.data.objects:
    if not o.name.startswith("Ball_"):
        continue
    centre = o.matrix_world.translation
    radius = max(o.dimensions) / 2
    view = (centre - eye).normalized()
    side = view.cross(Vector((0, 0, 1))).normalized()
    up = side.cross(view).normalized()
    p = world_to_camera_view(scene, camera, centre)
    cx, cy = p.x * width, (1 - p.y) * height
    r = 0.0
    for k in range(16):
        a = 2 * math.pi * k / 16
        q = world_to_camera_view(scene, camera, centre + (side * math.cos(a) + up * math.sin(a)) * radius)
        r = max(r, math.hypot(q.x * width - cx, (1 - q.y) * height - cy))
    balls.append({"name": o.name, "x": cx, "y": cy, "radius": r})
with open(out + ".balls.json", "w") as f:
    json.dump(sorted(balls, key=lambda b: b["name"]), f, indent=1)
