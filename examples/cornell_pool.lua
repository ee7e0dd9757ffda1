-- The Cornell box with its direct light served by a pool of `direct` replicas, which to the renderers looks like
-- one LightOp: each renderer sends its batches to the replicas itself (or, with dispatch = "process", through one
-- multiplexer process in front of them). Kill a replica or a renderer mid-frame and the image comes out the same.
--
--   lightfarm run examples/cornell_pool.lua --set replicas=3 --set strategy=round_robin

scene  { builtin = "cornell" }
camera { eye = {278, 273, -800}, at = {278, 273, 0}, fov = 39.3 }
image  { width = param("width", 512), height = param("height", 512), spp = param("spp", 16),
         tile = param("tile", 32), output = "cornell_pool.png" }
-- Direct light alone (a pool's demonstration): "partial" says the light that bounces more is left out on purpose.
farm   { heartbeat_timeout = param("heartbeat_timeout", 10), light_paths = "partial" }

local direct = multiplexer {
  lightop "direct" { light_samples = param("light_samples", 2) },
  replicas = param("replicas", 2),
  strategy = param("strategy", "least_loaded"),   -- or "round_robin", "random"
  split = param("split", 0),                       -- split packets larger than this across replicas (0: never)
  dispatch = param("dispatch", "clients"),         -- or "process"
}

renderers { count = param("renderers", 2), lighting = direct, mode = param("mode", "async") }
