-- The Cornell box with a glass sphere and a mirror block, lit by a lighting network that counts every light path
-- once (docs/lua-api.md, "Light paths"): direct light, light along mirror/glass chains, caustics from a photon map
-- shot by two replicas in parallel, and indirect light from an irradiance cache over a second cache whose records
-- gather every further bounce by path tracing.
--   lightfarm run examples/cornell_glass.lua
--   lightfarm graph examples/cornell_glass.lua | dot -Tsvg > network.svg
scene  { builtin = "cornell_glass" }
camera { eye = {278, 273, -800}, at = {278, 273, 0}, fov = 39.3 }
image  { width = param("width", 512), height = param("height", 512), spp = param("spp", 16),
         output = "cornell_glass.png" }

local direct   = lightop "direct" { light_samples = param("light_samples", 2) }
local caustics = multiplexer { lightop "photonmap" { photons = param("photons", 1000000), k = 100 },
                               replicas = param("photon_replicas", 2) }
-- Indirect light: a cache where the camera looks (the default placement), whose hemisphere rays are shaded by
-- `lit1`, everything that leaves what they see except what reached it by mirrors and glass alone (L S+ D and L S+ G:
-- the photon map's, at the points the camera sees): direct light; `bounce1`, a cache spread over the box by area
-- whose records' rays are path traced (every further bounce); `glossy1`, the same for glossy lobes; and
-- `through`, what the rays see in the mirror and the glass, whose chains land on that light and leave out the
-- emitters they meet. Glossy lobes at the points the camera sees reflect `lit1` too. The box has no glossy
-- material, so the glossy ops shade nothing here; they make the network complete on scenes that have one.
local paths    = lightop "pathtrace" { name = "paths" }
local bounce1  = lightop "irradiance" { input = paths, name = "bounce1", placement = "area", prepass = param("prepass", 20000) }
local glossy1  = lightop "glossy" { input = paths, name = "glossy1" }
local through  = lightop "specular" { input = lightop "combine" { inputs = { direct, bounce1, glossy1 }, name = "seen" },
                                      emitters = false, name = "through" }
local lit1     = lightop "combine" { inputs = { direct, bounce1, glossy1, through }, name = "lit1" }
local indirect = lightop "irradiance" { input = lit1, name = "indirect" }
local glossy   = lightop "glossy" { input = lit1, name = "glossy" }
-- What leaves a surface a mirror/glass chain lands on.
local landing  = lightop "combine" { inputs = { direct, caustics, indirect, glossy }, name = "landing" }
local specular = lightop "specular" { input = landing }

renderers { count = param("renderers", 2),
            lighting = lightop "combine" { inputs = { direct, specular, caustics, indirect, glossy } } }
