-- Lost Empire (McGuire's archive, in ../shared/scenes; CC BY 3.0): a 225k-triangle underground city lit by its
-- torches (818 small quads, 1636 triangles) and a pool of lava. Its MTL has the torches' Ke commented out, so the
-- script makes them emit. The texture atlas colours every block; the torches' alpha map cuts each quad down to its
-- stick and flame, which alone emit, and cuts the leaves into sprites. Three ways to light it (`lighting`):
--
--   "direct"     direct light only, lights chosen through the light tree mixed with the lights learned where the
--                camera looks (docs/lua-api.md, "Many lights", "Learned lights")
--   "network"    global illumination by a lighting network: direct light at every camera sample, plus an
--                irradiance cache placed where the camera looks whose hemisphere rays are shaded by one path
--                each (all further bounces), plus the chains through the water (specular). The cache's records
--                interpolate the indirect light smoothly; the path tracer's noise is averaged inside each record's
--                hemisphere rays, about 12 per lit sample a pixel (theta = 0, phi = 0: derived from the image,
--                docs/lua-api.md, "One knob for time against quality").
--   "pathtrace"  the same light by path tracing alone (the reference bench/lost_empire_bench measures against)
--   "emission"   the lights alone, as the camera sees them (the benchmark's mask of pixels that see a light)
--
--   lightfarm run examples/lost_empire.lua                                  -> lost_empire.png
--   lightfarm run examples/lost_empire.lua --set lighting=network
--   lightfarm run examples/lost_empire.lua --set lighting=network --set spp=64 --set light_samples=4
--                                  (4 light samples a lit point: most torches are hidden from any one point, so
--                                   one sample is a poor estimate here; the path tracer's 256-spp error in about
--                                   0.6 of its time. The default 2 is what the Cornell boxes want: there 4 cost
--                                   8-18 % more for the same error. bench/RESULTS.md, "A cache's misses")
--   lightfarm run examples/lost_empire.lua --set light_sampling=tree        (the light tree alone)
--   lightfarm run examples/lost_empire.lua --set light_sampling=power       (choose torches by power alone)
--   lightfarm run examples/lost_empire.lua --set seed=1                     (other samples: two seeds give the
--                                                                            noise without a reference, bench/peer)
--
-- Data locality (after Jansen and Reinhard): `--set parts=3` splits the scene over 3 geometry actors that `direct` and `pathtrace`
-- trace through (the same image), and with lighting=pathtrace `--set directional_cache=true` lets the directional
-- cache answer most diffuse rays that leave their neighbourhood (the end-of-run figures show how many):
--   lightfarm run examples/lost_empire.lua --set lighting=pathtrace --set parts=3 --set directional_cache=true

scene    { file = "../../shared/scenes/lost_empire/lost_empire.obj" }
-- kd = 0: a torch's crossed quads would otherwise light each other where they meet, at distances near 0 (an
-- estimator without finite variance: fireflies that never average out).
material "Torch" { emission = {9, 9, 6}, kd = {0, 0, 0} }
camera   { eye = {-5, 18, -30}, at = {5, 12, 5}, fov = 70 }
-- --set frames=N: a walkthrough of N frames (outputs lost_empire.####.png): the eye walks in from the opening view and
-- turns, along a smooth path a Lua function of the frame gives; --set frame=K renders frame K of it alone (a job
-- of that one frame, to lost_empire.png). --set in_flight=0: one frame at a time (frames { in_flight }; the same
-- images, without the next frame beginning while the last one's final tiles render).
local walk, at_frame = param("frames", 0), param("frame", 0)
local function walk_view(f)
  local t = walk > 1 and (f - 1) / (walk - 1) or 0
  local s = t * t * (3 - 2 * t)  -- eases in and out
  return { eye = {-5 + 8 * s, 18 - s, -30 + 14 * s}, at = {5 + 7 * s, 12, 5 + 9 * s} }
end
if walk > 0 then
  frames { first = at_frame > 0 and at_frame or 1, last = at_frame > 0 and at_frame or walk, camera = walk_view,
           in_flight = param("in_flight", 1) == 1 }
end
-- shade_spp: of the spp camera samples per pixel, how many the lighting shades; the others only see the torches'
-- flames, whose sub-pixel shapes need many camera samples but no light (docs/lua-api.md, image).
local spp = param("spp", 16)
local shade_spp = param("shade_spp", spp)
local look = { width = param("width", 320), height = param("height", 240), spp = spp, shade_spp = shade_spp,
               exposure = param("exposure", 2), output = param("output", walk > 0 and at_frame == 0 and "lost_empire.####.png" or "lost_empire.png") }
-- edge_spp: seen samples a pixel on a light's outline takes in all (default 16 x spp; 0: none; docs/lua-api.md).
if param("edge_spp", -1) >= 0 then look.edge_spp = param("edge_spp", -1) end
-- adaptive_spp: pixels still noisy after shade_spp lit samples (near the torches, mostly) get more lit samples, up
-- to adaptive_spp, at most adaptive_threshold of display white at the exposure (defaults 16 x spp and 0.05; 0: off;
-- docs/lua-api.md, image).
if param("adaptive_spp", -1) >= 0 then look.adaptive_spp = param("adaptive_spp", -1) end
if param("adaptive_threshold", 0) > 0 then look.adaptive_threshold = param("adaptive_threshold", 0) end
image(look)

if param("parts", 0) > 0 then partition { parts = param("parts", 0) } end

local lighting = param("lighting", "direct")
local light_sampling = param("light_sampling", "learned")
local light_point = param("light_point", "area")  -- "solid_angle": by the solid angle each light triangle subtends
local seed = param("seed", 0)
local function direct()
  -- mis: points a fraction of a block from a torch also get a BSDF sample (without it, their 1/d^2 light samples
  -- are fireflies that dominate the error). Unset, only points within 4 radii of a torch's triangle would: 0.195
  -- against 0.188 for direct light alone at 16 spp, for 9 % less of its time (bench/RESULTS.md).
  return lightop "direct" { light_samples = param("light_samples", 2), light_sampling = light_sampling, light_point = light_point,
                            mis = param("mis", true), seed = seed }
end
if lighting == "direct" then
  farm { light_paths = "partial" }  -- direct light alone, on purpose
  renderers { count = param("renderers", 2), lighting = direct() }
elseif lighting == "network" then
  -- The cache's hemisphere rays land mostly where the camera does not look, so learned lights do little for
  -- them (measured: RMSE 0.1765 with, 0.1782 without) while each replica would spend ~2.3 s learning: the tree.
  local paths = lightop "pathtrace" { max_depth = param("max_depth", 100),
                                      light_sampling = param("bounce_light_sampling", "tree"),
                                      light_point = light_point, name = "bounces", seed = seed }
  -- Two processes trace the cache's hemisphere rays (most of the pre-pass), one per core.
  local bounce_replicas = param("bounce_replicas", 2)
  if bounce_replicas > 1 then paths = multiplexer { paths, replicas = bounce_replicas } end
  local indirect = lightop "irradiance" { input = paths, a = param("a", 0), stride = param("stride", 8),
                                          finest = param("finest", 2), own_rays = param("own_rays", 2),
                                          relax = param("relax", 1), nearest = param("nearest", 1.5),
                                          theta = param("theta", 0), phi = param("phi", 0),
                                          name = "indirect", seed = seed }
  -- The water is glass: what its refraction and reflection chains land on is lit by the same two ops. The flames
  -- seen in the water are as small as those seen directly: chains that only look for them (a few rays each) give
  -- them 4x the camera's samples; without them they were the network's largest noise (bench/RESULTS.md, "Where the
  -- network's error was").
  -- Direct light is most of the render's work: two replicas, one per core (they learn the lights in halves).
  local lit = direct()
  local direct_replicas = param("direct_replicas", 2)
  if direct_replicas > 1 then lit = multiplexer { lit, replicas = direct_replicas } end
  -- Glossy lobes (materials set glossy from the script: Lost Empire's own are diffuse) reflect what the bounce
  -- paths bring, as the cache does for the diffuse part; an op with no glossy point to shade costs nothing.
  local shiny = lightop "glossy" { input = paths, samples = param("glossy_samples", 1), name = "glossy", seed = seed }
  local specular = lightop "specular" { input = lightop "combine" { inputs = { lit, indirect, shiny }, name = "landing" },
                                        emission_samples = param("emission_samples", math.max(1, 4 * spp // math.max(1, shade_spp))),
                                        seed = seed }
  renderers { count = param("renderers", 2), lighting = lightop "combine" { inputs = { lit, indirect, shiny, specular } } }
elseif lighting == "pathtrace" then
  local paths = multiplexer { lightop "pathtrace" { max_depth = param("max_depth", 100), light_sampling = light_sampling, light_point = light_point,
                                                    directional_cache = param("directional_cache", false), seed = seed },
                              replicas = param("replicas", 2) }
  renderers { count = param("renderers", 2), lighting = paths }
elseif lighting == "emission" then
  farm { light_paths = "off" }  -- a mask of what the camera sees of the lights (counted twice), not a rendering
  renderers { count = param("renderers", 2), lighting = lightop "emission" {} }
else
  error("lighting must be \"direct\", \"network\", \"pathtrace\" or \"emission\", not \"" .. tostring(lighting) .. "\"")
end
