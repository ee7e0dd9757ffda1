-- cornell_glass with a radiosity final gather: the network of cornell_glass.lua, but its
-- indirect light comes from one irradiance cache over a coarse radiosity solution (all diffuse bounces, shown with
-- the ambient term) plus the caustic photon map, instead of two caches stacked over direct light (two bounces).
-- Fewer processes' worth of setup and no missing higher bounces: bench/quality_bench compares the two.
--   lightfarm run examples/cornell_glass_radiosity.lua
scene  { builtin = "cornell_glass" }
camera { eye = {278, 273, -800}, at = {278, 273, 0}, fov = 39.3 }
image  { width = param("width", 512), height = param("height", 512), spp = param("spp", 4),
         output = "cornell_glass_radiosity.png" }

-- The radiosity solution treats the mirror and the glass as black: light that reaches a diffuse surface by way of
-- them after a diffuse bounce (L D S D, ...) is left out, and "partial" says that is known (docs/lua-api.md,
-- "Light paths"; examples/cornell_glass.lua computes all of it).
farm   { light_paths = "partial" }

local direct   = lightop "direct" { light_samples = param("light_samples", 2) }
-- Caustics the camera sees: k = 50, with Christensen's irradiance precomputed at every photon, so that a point
-- asks for one neighbour instead of 50. Measured at 512x512, 8 spp: RMSE 0.308, against 0.306 for the full
-- estimate at k = 50 and 0.304 at k = 100, in a sixth of the k = 50 map's busy time (4.1 -> 0.7 s per replica).
-- (Precomputed at every 4th photon, k = 100, its Voronoi cells show: 0.367.)
local caustics = multiplexer { lightop "photonmap" { photons = param("photons", 300000), k = 50, precompute = 1 },
                               replicas = param("photon_replicas", 2) }
-- What the cache gathers needs no sharp caustics: a sparser precomputed map is enough there.
local gathered = multiplexer { lightop "photonmap" { photons = param("photons", 300000), k = 100, precompute = 4,
                                                    name = "gathered_caustics" },
                               replicas = param("photon_replicas", 2) }
-- Radiosity treats the mirror and the glass as black (it is diffuse only); light through them reaches the
-- cache as caustic photons instead.
local solution = radiosity { rings = 1, ring_length = 2, patch_size = 140, element_size = 70,
                             converge = param("converge", 0.2), max_iterations = 2000 }
-- Two replicas of the cache (each builds the same records, sharing the pre-pass; measured 512x512, 16 spp: the
-- single cache process was busy the whole render, 12.3 s, the pool renders in 9.3-10.0 s, pixels unchanged).
local bounced  = lightop "combine" { inputs = { solution, gathered }, name = "bounced" }
local indirect = multiplexer { lightop "irradiance" { input = bounced, name = "indirect" },
                               replicas = param("cache_replicas", 2) }
local landing  = lightop "combine" { inputs = { direct, caustics, indirect }, name = "landing" }
local specular = lightop "specular" { input = landing }

renderers { count = param("renderers", 2),
            lighting = lightop "combine" { inputs = { direct, specular, caustics, indirect } } }
