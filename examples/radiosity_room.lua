-- Progressive refinement radiosity on rings of processes (after Stürzlinger, Schaufler and Volkert): a furnished room solved by 2 rings of 2 nodes,
-- written as a PLY mesh with per-vertex radiosity, and rendered through the `radiosity` LightOp.
--   lightfarm run examples/radiosity_room.lua                       -> room.png, room.ply
--   lightfarm run examples/radiosity_room.lua --set rings=1 --set ring_length=4 --set balance=none
scene { builtin = "room" }
camera { eye = {3.0, 1.55, 0.25}, at = {2.7, 0.9, 4.0}, fov = 62 }
image { width = param("width", 320), height = param("height", 240), spp = param("spp", 4), output = "room.png" }

local solution = radiosity {
  rings = param("rings", 2), ring_length = param("ring_length", 2),
  balance = param("balance", "static+dynamic"),
  patch_size = 0.25, element_size = 0.125,   -- metres: about 3,000 patches, 12,000 elements
  shooter_samples = 16, samples_per_packet = 50,
  subdivide = param("subdivide", 0.5), max_depth = 2,
  converge = param("converge", 0.05), max_iterations = param("iterations", 400),
  ply = "room.ply",
}

renderers { count = 2, lighting = solution }
