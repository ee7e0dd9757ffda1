-- The Cornell box, lit directly by its area light, rendered by a farm of processes:
-- two renderers trace camera rays and ask one `direct` LightOp to shade what they hit.
--
--   lightfarm run examples/cornell.lua                      -> cornell.png
--   lightfarm run examples/cornell.lua --set renderers=3 --set spp=64 --output cornell.exr
--   lightfarm graph examples/cornell.lua | dot -Tsvg > farm.svg

scene  { builtin = "cornell" }
camera { eye = {278, 273, -800}, at = {278, 273, 0}, fov = 39.3 }
image  { width = param("width", 512), height = param("height", 512), spp = param("spp", 16),
         tile = param("tile", 32), output = "cornell.png" }
-- Direct light alone, on purpose: the light that bounces more than once is left out (examples/pathtrace.lua and
-- examples/cornell_glass.lua compute all of it), and "partial" says so instead of a warning.
farm   { light_paths = "partial" }

local direct = lightop "direct" { light_samples = param("light_samples", 2) }

renderers { count = param("renderers", 2), lighting = direct, mode = param("mode", "async") }
