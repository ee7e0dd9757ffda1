-- The Cornell box by path tracing: global illumination, the reference the lighting networks are checked against.
--   lightfarm run examples/pathtrace.lua --set spp=64
scene  { builtin = "cornell" }
camera { eye = {278, 273, -800}, at = {278, 273, 0}, fov = 39.3 }
image  { width = param("width", 512), height = param("height", 512), spp = param("spp", 16),
         output = "pathtrace.png" }

local paths = multiplexer { lightop "pathtrace" { max_depth = param("max_depth", 100) },
                            replicas = param("replicas", 2) }
renderers { count = param("renderers", 2), lighting = paths }
