-- For failure tests: a pool of four slowed replicas whose clients each connect to `subset` of them (the rest are
-- spares). Neither the subset nor the slowdown changes a pixel.
scene  { builtin = "cornell" }
image  { width = 128, height = 128, spp = param("spp", 16), tile = 16, output = "subset_pool.exr" }
local direct = multiplexer {
  lightop "direct" { light_samples = 2 },
  replicas = 4,
  subset = param("subset", 1),
  slowdown = { param("slowdown", 1), param("slowdown", 1), param("slowdown", 1), param("slowdown", 1) },
}
renderers { count = 2, lighting = direct, batch = 1024 }
