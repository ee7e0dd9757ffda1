-- Used by bench/peer/compare_balls.sh: examples/material_balls.lua's scene and light with every material made a
-- Lambert surface of its base colour, as cycles_balls.py's LAMBERT renders it: the light transport alone.
scene  { file = "../../../shared/scenes/gltf/balls.glb" }
environment { map = "../../../shared/scenes/gltf/hdri/" .. param("hdri", "courtyard") .. ".exr" }
if param("sun", 1) == 0 then sun { direction = {0, 1, 0}, irradiance = {0, 0, 0} } end
camera { gltf = "Camera" }
image  { width = param("width", 320), height = param("height", 180), spp = param("spp", 256) }
material "Floor" { type = "diffuse", kd = {0.6, 0.6, 0.6} }
-- glass=1: the front row rough glass of its roughness instead (cycles_balls.py's GLASS), the rest Lambert.
local glass = param("glass", 0) == 1
for _, r in ipairs({"0.05", "0.3", "0.6", "0.9"}) do
  if glass then
    material("Ball_m0_r" .. r) { transmission = 1, metallic = 0, roughness = tonumber(r), base_color = {0.2, 0.35, 0.8} }
  else
    material("Ball_m0_r" .. r) { type = "diffuse", kd = {0.2, 0.35, 0.8} }
  end
  material("Ball_m1_r" .. r) { type = "diffuse", kd = {0.9, 0.6, 0.2} }
end
renderers { count = 2, lighting = multiplexer { lightop "pathtrace" { seed = param("seed", 0) }, replicas = 2 } }
