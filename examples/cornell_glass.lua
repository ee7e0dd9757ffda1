-- The Cornell box with a glass sphere and a mirror block, lit by a lighting network:
--   direct light + light along mirror/glass chains + caustics from a photon map shot by two replicas in parallel.
-- (Indirect diffuse light — irradiance caching — is not in the network yet.)
--   lightfarm run examples/cornell_glass.lua
--   lightfarm graph examples/cornell_glass.lua | dot -Tsvg > network.svg
scene  { builtin = "cornell_glass" }
camera { eye = {278, 273, -800}, at = {278, 273, 0}, fov = 39.3 }
image  { width = param("width", 512), height = param("height", 512), spp = param("spp", 16),
         output = "cornell_glass.png" }

local direct   = lightop "direct" { light_samples = param("light_samples", 2) }
local caustics = multiplexer { lightop "photonmap" { photons = param("photons", 1000000), k = 100 },
                               replicas = param("photon_replicas", 2) }
-- What leaves a surface a mirror/glass chain lands on: its direct light and its caustics.
local landing  = lightop "combine" { inputs = { direct, caustics }, name = "landing" }
local specular = lightop "specular" { input = landing }

renderers { count = param("renderers", 2),
            lighting = lightop "combine" { inputs = { direct, specular, caustics } } }
