# Used by bench/peer/README.md: the scene as lightfarm renders it for the comparison with Cycles.
scene { file = "../../../shared/scenes/cornell_box_mcguire/CornellBox-Empty-RG.obj" }
camera { eye = {0, 1, 3.4}, at = {0, 1, 0}, fov = 40 }
image { width = param("size", 256), height = param("size", 256), spp = param("spp", 16), sampler = param("sampler", "sobol") }
local paths = lightop "pathtrace" { max_depth = 12, seed = param("seed", 0), roulette = param("roulette", "sqrt"),
                                   rr_depth = param("rr_depth", 3),
                                   rr_threshold = param("rr_threshold", 0.25), light_point = param("light_point", "area") }
renderers { count = 2, lighting = multiplexer { paths, replicas = 2 } }
