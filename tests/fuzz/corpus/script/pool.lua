scene { builtin = "cornell" }
image { width = 64, height = 64, spp = param("spp", 4) }
local d = multiplexer { lightop "direct" { light_samples = 2 }, replicas = 3 }
renderers { count = 2, lighting = d }
