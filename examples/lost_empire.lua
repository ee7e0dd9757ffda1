-- Lost Empire (McGuire's archive, in ../shared/scenes; CC BY 3.0): a 225k-triangle underground city lit by its
-- torches (818 small quads, 1636 triangles) and a pool of lava. Its MTL has the torches' Ke commented out, so the
-- script makes them emit. The texture atlas colours every block; the torches' alpha map cuts each quad down to its
-- stick and flame, which alone emit, and cuts the leaves into sprites.
-- Direct light only, lights chosen through the light tree (docs/lua-api.md, "Many lights"):
--
--   lightfarm run examples/lost_empire.lua                                  -> lost_empire.png
--   lightfarm run examples/lost_empire.lua --set light_sampling=power       (choose torches by power alone)

scene    { file = "../../shared/scenes/lost_empire/lost_empire.obj" }
-- kd = 0: a torch's crossed quads would otherwise light each other where they meet, at distances near 0 (an
-- estimator without finite variance: fireflies that never average out).
material "Torch" { emission = {9, 9, 6}, kd = {0, 0, 0} }
camera   { eye = {-5, 18, -30}, at = {5, 12, 5}, fov = 70 }
image    { width = param("width", 320), height = param("height", 240), spp = param("spp", 16),
           exposure = param("exposure", 1), output = "lost_empire.png" }

local direct = lightop "direct" { light_samples = param("light_samples", 2),
                                  light_sampling = param("light_sampling", "tree") }
renderers { count = param("renderers", 2), lighting = direct }
