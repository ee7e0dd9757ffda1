# Made camera_walk.gltf (+ .bin) with Blender 3.4.1 (Debian's blender, python3-numpy for its glTF exporter):
#   blender -b --factory-startup --python camera_walk.py
# The default scene's camera keyed at frames 1 and 24 (24 fps) and exported; the views Blender itself gives at
# frames 1, 12 and 24 (matrix_world: position, -z, +y; Blender is z-up, glTF y-up: (x, y, z) -> (x, z, -y)) are
# what gltf_scene.test.cpp holds the file's animation to.
import bpy, json
scene = bpy.context.scene
scene.frame_start, scene.frame_end = 1, 24
scene.render.fps = 24
cam = bpy.data.objects['Camera']
cam.animation_data_clear()
cam.location = (0, -10, 2); cam.rotation_euler = (1.4, 0, 0)
cam.keyframe_insert("location", frame=1); cam.keyframe_insert("rotation_euler", frame=1)
cam.location = (8, -6, 3); cam.rotation_euler = (1.3, 0, 0.9)
cam.keyframe_insert("location", frame=24); cam.keyframe_insert("rotation_euler", frame=24)
views = {}
for f in (1, 12, 24):
    scene.frame_set(f)
    m = cam.matrix_world
    views[f] = [list(m.col[3])[:3], list(-m.col[2])[:3], list(m.col[1])[:3]]
print(json.dumps(views))
bpy.ops.export_scene.gltf(filepath="camera_walk.gltf", export_format='GLTF_SEPARATE', export_cameras=True)
