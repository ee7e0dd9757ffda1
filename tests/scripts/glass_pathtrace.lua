-- Reference for the lighting-network test: cornell_glass by path tracing at a high sample count.
scene { builtin = "cornell_glass" }
image { width = param("size", 32), height = param("size", 32), spp = param("spp", 512), tile = 16,
        output = "glass_reference.exr" }
local paths = multiplexer { lightop "pathtrace" { max_depth = 12 }, replicas = 2 }
renderers { count = 2, lighting = paths }
