scene { builtin = "cornell" }
image { width = 16, height = 16, spp = 1 }
partition { parts = 3, host = "local" }
renderers { count = 2, lighting = lightop "pathtrace" { max_depth = 3, directional_cache = true, cache_cells = 4, cache_radius = 1.0 } }
