-- The Cornell box's direct light, tinted red by a LightOp written in Python (tint.py).
--   lightfarm run examples/plugin-python/tinted_cornell.lua
-- Without `input`, tint paints normals instead: lightop.exec { cmd = {"./tint.py"} }.
scene  { builtin = "cornell" }
camera { eye = {278, 273, -800}, at = {278, 273, 0}, fov = 39.3 }
image  { width = param("width", 256), height = param("height", 256), spp = param("spp", 8),
         tile = param("tile", 32), output = "tinted.png" }

local direct = lightop "direct" { light_samples = 2 }
local tint = lightop.exec { cmd = {"./tint.py"}, input = direct, color = {1, 0.2, 0.2} }
renderers { count = param("renderers", 2), lighting = tint }
