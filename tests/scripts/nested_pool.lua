-- A pool of pools: two multiplexers, each in front of two `direct` replicas, splitting big packets.
scene  { builtin = "cornell" }
image  { width = 64, height = 64, spp = 4, tile = 16, output = "nested.exr" }
local direct = multiplexer {
  multiplexer { lightop "direct" { light_samples = 2 }, replicas = 2, strategy = "round_robin" },
  replicas = 2, strategy = "random", split = 500,
}
renderers { count = 2, lighting = direct }
