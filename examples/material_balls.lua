-- glTF's metal-roughness materials: the material-ball grid Blender's own glTF exporter wrote (../shared/scenes/gltf/
-- balls.glb: blue dielectric balls in front, gold metal balls behind, roughness 0.05 / 0.3 / 0.6 / 0.9 from left
-- to right, on a rough grey floor), lit as a look-development artist lights it: an HDR environment (the courtyard
-- from ../shared/scenes/gltf/hdri) and the file's own sun (its directional light, 2 W/m^2). The file's emissive
-- panel faces away from the balls.
--
--   lightfarm run examples/material_balls.lua                          -> material_balls.png
--   lightfarm run examples/material_balls.lua --set lighting=pathtrace (the same light by path tracing alone:
--                                                                       faster here, bench/peer/README.md)
--   lightfarm run examples/material_balls.lua --set hdri=sunset        (forest, interior, sunset, courtyard)
--   lightfarm run examples/material_balls.lua --set glass=1            (the blue balls as rough glass)
--
-- Every glTF material is a glossy lobe (its specular coat) and a diffuse one (the base under it, a metal's multiply
-- scattered light) for the light-path check: `direct` gives both their direct light (the sky's and the sun's
-- included), `glossy` the glossy lobe's indirect light, asking the bounce paths where each lobe sample lands, and
-- the diffuse lobe's indirect light comes from the irradiance cache (`--set diffuse=cache`) or, as here by default,
-- from `glossy` following that lobe too (`lobes = "all"`): under an open sky little light bounces off the
-- surfaces, and the cache's pre-pass costs more than it saves (bench/RESULTS.md, "glTF materials").

scene  { file = "../../shared/scenes/gltf/balls.glb" }
environment { map = "../../shared/scenes/gltf/hdri/" .. param("hdri", "courtyard") .. ".exr" }
-- --set sun=0 switches the file's sun off (the HDRI alone: no sub-degree glints, bench/peer/compare_balls.sh).
if param("sun", 1) == 0 then sun { direction = {0, 1, 0}, irradiance = {0, 0, 0} } end
-- --set glass=1 makes the front row's dielectrics transmit (glTF's KHR_materials_transmission): rough glass of their
-- roughness, tinted blue at each crossing.
if param("glass", 0) == 1 then
  for _, r in ipairs({"0.05", "0.3", "0.6", "0.9"}) do material("Ball_m0_r" .. r) { transmission = 1 } end
end
-- The file's own camera, "Camera": from (0, 2.6, 5.5) down at the grid, 23 degrees vertically for 16:9.
camera { gltf = "Camera" }
image  { width = param("width", 640), height = param("height", 360), spp = param("spp", 64),
         output = param("output", "material_balls.png") }

local lighting = param("lighting", "network")
local seed = param("seed", 0)  -- the light's random numbers (bench/peer/compare_balls.sh renders pairs)
if lighting == "network" then
  local paths = lightop "pathtrace" { name = "bounces", seed = seed }
  local lit = { lightop "direct" { seed = seed } }
  if param("diffuse", "paths") == "cache" then
    table.insert(lit, lightop "irradiance" { input = paths, seed = seed })
    table.insert(lit, lightop "glossy" { input = paths, seed = seed })
  else
    table.insert(lit, lightop "glossy" { input = paths, lobes = "all", seed = seed })
  end
  renderers { count = param("renderers", 2), lighting = lightop "combine" { inputs = lit } }
elseif lighting == "pathtrace" then
  renderers { count = param("renderers", 2), lighting = multiplexer { lightop "pathtrace" { seed = seed }, replicas = 2 } }
else
  error("lighting must be \"network\" or \"pathtrace\", not \"" .. tostring(lighting) .. "\"")
end
