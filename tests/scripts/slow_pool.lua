-- For failure tests: two slowed replicas (a slower host, without using more CPU) so a frame lasts long enough to
-- kill things in the middle of it. The slowdown does not change a pixel.
scene  { builtin = "cornell" }
image  { width = 128, height = 128, spp = param("spp", 16), tile = 16, output = "slow_pool.exr" }
farm   { heartbeat_timeout = param("heartbeat_timeout", 10) }
local direct = multiplexer {
  lightop "direct" { light_samples = 2 },
  replicas = 2,
  slowdown = { param("slowdown", 1), param("slowdown", 1) },
}
renderers { count = param("renderers", 2), lighting = direct, batch = 1024, tiles_per_message = param("tiles_per_message", 1) }
