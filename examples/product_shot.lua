-- A product shot as a look-development artist sets one up: the material-ball grid Blender exported
-- (../shared/scenes/gltf/balls.glb) seen low from the front left through a lens (depth of field) focused on the
-- front-left ball, lit by an HDRI alone (the file's own sun switched off; `rotation` turns the sky about the up
-- axis), on a wide ground so that the horizon is the floor's, not the sky's.
--
--   lightfarm run examples/product_shot.lua                         -> product_shot.png
--   lightfarm run examples/product_shot.lua --set aperture=0       (a pinhole: everything sharp)
--   lightfarm run examples/product_shot.lua --set hdri=forest --set rotation=90
--   lightfarm run examples/product_shot.lua --set variants=4        (the blue balls in four colours, one frame each:
--                                                                    product_shot.0001.png ... 0004.png)
--   lightfarm run examples/product_shot.lua --set day=5             (the sun crossing the sky over the grid, morning
--                                                                    to evening, under a dimmed sky: 5 frames)
--   lightfarm run examples/product_shot.lua --set turn=8            (the HDRI turned once around the grid: 8 frames,
--                                                                    the reflections and shadows going round)

scene       { file = "../../shared/scenes/gltf/balls.glb" }
local day, turn = param("day", 0), param("turn", 0)
environment { map = "../../shared/scenes/gltf/hdri/" .. param("hdri", "sunset") .. ".exr",
              rotation = param("rotation", 200), intensity = day > 0 and 0.25 or 1 }
-- --set day=N: a sun that rises at the left, stands highest at the middle frame and sets at the right (frames { sun }:
-- each frame's sun, as sun { } takes it).
local function sun_of(f)
  local a = math.pi * (f - 0.5) / day
  return { direction = {-math.cos(a), 0.15 + 0.8 * math.sin(a), 0.5}, irradiance = {1.6, 1.45, 1.25} }
end
if day > 0 then
  sun(sun_of(1))
else
  sun { direction = {0, 1, 0}, irradiance = {0, 0, 0} }   -- the file's sun off: the HDRI's own lights it
end
shape "ground" { plane = {0, -0.001, 0}, size = 200, base_color = {0.35, 0.33, 0.3}, roughness = 0.6, metallic = 0 }
-- From the front left, low: the rows run away diagonally, the front-left ball (3.1 units off) in focus.
camera { eye = {-3.5, 0.7, 3.0}, at = {-0.5, 0.4, 0}, fov = 32,
         aperture = param("aperture", 0.06), focus_distance = 3.13 }
local variants = param("variants", 0)
image  { width = param("width", 640), height = param("height", 360), spp = param("spp", 64),
         output = param("output", (variants > 0 or day > 0 or turn > 0) and "product_shot.####.png" or "product_shot.png"), tonemap = "aces",
         exposure = param("exposure", 0.5) }
-- Colour variants as a job: one farm, each frame the dielectric balls (the file's Ball_m0_*) in another base colour
-- (frames { materials }: a frame's changes to named materials, over the scene as the script leaves it).
if day > 0 then
  frames { first = 1, last = day, sun = sun_of }
elseif turn > 0 then
  -- frames { environment }: each frame's rotation of the map (the map itself is shipped once).
  frames { first = 1, last = turn, environment = function(f) return { rotation = (param("rotation", 200) + 360 * (f - 1) / turn) % 360 } end }
elseif variants > 0 then
  local colours = { {0.2, 0.35, 0.8}, {0.8, 0.15, 0.1}, {0.15, 0.6, 0.25}, {0.85, 0.85, 0.82} }
  frames { first = 1, last = variants, materials = function(f)
    local changes = {}
    for _, roughness in ipairs({"0.05", "0.3", "0.6", "0.9"}) do
      changes["Ball_m0_r" .. roughness] = { base_color = colours[(f - 1) % #colours + 1] }
    end
    return changes
  end }
end

-- Direct light, and what the bounce paths bring along every lobe but mirrors (`lobes = "all"`: the glossy coats and
-- the diffuse bases alike; under an open sky a cache's pre-pass would cost more than it saves).
local paths = lightop "pathtrace" { name = "bounces" }
renderers { count = param("renderers", 2),
            lighting = lightop "combine" { inputs = { lightop "direct" {}, lightop "glossy" { input = paths, lobes = "all" } } } }
