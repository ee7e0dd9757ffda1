# Blender 3.4 (Debian) Cycles on McGuire's CornellBox-Empty-RG, set up like lightfarm's sampler_bench scene:
# Lambert walls (Kd), the light one-sided (Ke, front faces only) and also diffuse (Kd), 12 bounces, no clamping,
# no denoising, no adaptive sampling, a box-like pixel filter. Usage:
#   blender -b -P cycles_cornell.py -- OUT.exr SPP SIZE SEED [MIN_LIGHT_BOUNCES]
# MIN_LIGHT_BOUNCES (default 0, Cycles' own) is the bounce from which Russian roulette may end a path.
import bpy, sys, time, math
argv = sys.argv[sys.argv.index("--") + 1:]
out, spp, size, seed = argv[0], int(argv[1]), int(argv[2]), int(argv[3])
min_light_bounces = int(argv[4]) if len(argv) > 4 else 0
bpy.ops.wm.read_factory_settings(use_empty=True)
import os
bpy.ops.wm.obj_import(filepath=os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../../shared/scenes/cornell_box_mcguire/CornellBox-Empty-RG.obj"))
for mat in bpy.data.materials:
    kd = None
    ke = (0, 0, 0)
    nt = mat.node_tree
    p = next((n for n in nt.nodes if n.type == "BSDF_PRINCIPLED"), None)
    if p is not None:
        kd = tuple(p.inputs["Base Color"].default_value[:3])
        ke = tuple(p.inputs["Emission"].default_value[:3])
        strength = p.inputs["Emission Strength"].default_value if "Emission Strength" in p.inputs else 1.0
        ke = tuple(c * strength for c in ke)
    nt.nodes.clear()
    o = nt.nodes.new("ShaderNodeOutputMaterial")
    d = nt.nodes.new("ShaderNodeBsdfDiffuse")
    d.inputs["Color"].default_value = (*kd, 1)
    d.inputs["Roughness"].default_value = 0.0
    if max(ke) > 0:
        e = nt.nodes.new("ShaderNodeEmission")
        e.inputs["Color"].default_value = (*ke, 1)
        e.inputs["Strength"].default_value = 1.0
        g = nt.nodes.new("ShaderNodeNewGeometry")
        mix = nt.nodes.new("ShaderNodeMixShader")  # front: emission, back: nothing
        nt.links.new(g.outputs["Backfacing"], mix.inputs["Fac"])
        nt.links.new(e.outputs["Emission"], mix.inputs[1])
        add = nt.nodes.new("ShaderNodeAddShader")
        nt.links.new(mix.outputs["Shader"], add.inputs[0])
        nt.links.new(d.outputs["BSDF"], add.inputs[1])
        nt.links.new(add.outputs["Shader"], o.inputs["Surface"])
        print("emitter", mat.name, kd, ke)
    else:
        nt.links.new(d.outputs["BSDF"], o.inputs["Surface"])
cam_data = bpy.data.cameras.new("cam")
cam_data.angle = math.radians(40)
cam = bpy.data.objects.new("cam", cam_data)
bpy.context.scene.collection.objects.link(cam)
# OBJ y-up -> Blender z-up: (x, y, z) -> (x, -z, y). Eye (0, 1, 3.4) looking at (0, 1, 0): along Blender +y.
cam.location = (0, -3.4, 1)
cam.rotation_euler = (math.radians(90), 0, 0)
scene = bpy.context.scene
scene.camera = cam
scene.render.engine = "CYCLES"
c = scene.cycles
c.device = "CPU"
c.samples = spp
c.use_adaptive_sampling = False
c.use_denoising = False
c.max_bounces = 12
c.diffuse_bounces = 12
c.glossy_bounces = 12
c.transmission_bounces = 12
c.transparent_max_bounces = 12
c.min_light_bounces = min_light_bounces
c.sample_clamp_direct = 0
c.sample_clamp_indirect = 0
c.filter_width = 0.01
c.seed = seed
c.caustics_reflective = True
c.caustics_refractive = True
scene.world = bpy.data.worlds.new("black")
scene.world.color = (0, 0, 0)
scene.render.resolution_x = size
scene.render.resolution_y = size
scene.render.resolution_percentage = 100
scene.render.image_settings.file_format = "OPEN_EXR"
scene.render.image_settings.color_depth = "32"
scene.render.filepath = out
scene.render.threads_mode = "FIXED"
scene.render.threads = 2
t = time.time()
bpy.ops.render.render(write_still=True)
print("RENDER_SECONDS %.3f" % (time.time() - t))
