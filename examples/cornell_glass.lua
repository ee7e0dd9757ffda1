-- The Cornell box with a glass sphere and a mirror block, lit by a lighting network (DESIGN §2):
--   direct light, light along mirror/glass chains, caustics from a photon map shot by two replicas in parallel,
--   and two bounces of indirect light from irradiance caches.
--   lightfarm run examples/cornell_glass.lua
--   lightfarm graph examples/cornell_glass.lua | dot -Tsvg > network.svg
scene  { builtin = "cornell_glass" }
camera { eye = {278, 273, -800}, at = {278, 273, 0}, fov = 39.3 }
image  { width = param("width", 512), height = param("height", 512), spp = param("spp", 16),
         output = "cornell_glass.png" }

local direct   = lightop "direct" { light_samples = param("light_samples", 2) }
local caustics = multiplexer { lightop "photonmap" { photons = param("photons", 1000000), k = 100 },
                               replicas = param("photon_replicas", 2) }
-- Indirect light: a cache over direct light (one bounce), and a cache over that plus direct (two bounces). The
-- first serves the second's hemisphere rays, anywhere in the box: its records are spread by area; the second's go
-- where the camera looks (the default). `direct` gives mirrors and glass nothing, so what the caches' rays see in
-- them (the light, and the walls it lights) comes from `through`, their chains landing on direct light.
local through  = lightop "specular" { input = direct, name = "through" }
local first    = lightop "combine" { inputs = { direct, through }, name = "first" }
local bounce1  = lightop "irradiance" { input = first, name = "bounce1", placement = "area", prepass = param("prepass", 20000) }
local lit1     = lightop "combine" { inputs = { direct, through, caustics, bounce1 }, name = "lit1" }
local indirect = lightop "irradiance" { input = lit1, name = "indirect" }
-- What leaves a surface a mirror/glass chain lands on.
local landing  = lightop "combine" { inputs = { direct, caustics, indirect }, name = "landing" }
local specular = lightop "specular" { input = landing }

renderers { count = param("renderers", 2),
            lighting = lightop "combine" { inputs = { direct, specular, caustics, indirect } } }
