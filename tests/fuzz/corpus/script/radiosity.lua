scene { builtin = "cornell" }
radiosity { rings = 2, nodes_per_ring = 2 }
renderers { count = 1, lighting = lightop "radiosity" {} }
