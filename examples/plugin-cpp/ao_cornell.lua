-- The Cornell box lit by ambient occlusion, computed by a LightOp built outside lightfarm against its SDK.
-- Build it first (see CMakeLists.txt), then:
--   lightfarm run examples/plugin-cpp/ao_cornell.lua --set program=build/ambient_occlusion
scene  { builtin = "cornell" }
camera { eye = {278, 273, -800}, at = {278, 273, 0}, fov = 39.3 }
image  { width = param("width", 256), height = param("height", 256), spp = param("spp", 4), output = "ao.png" }

local ao = multiplexer {
  lightop.exec { cmd = { param("program", "build/ambient_occlusion") }, samples = 16, radius = 200 },
  replicas = param("replicas", 2),
}
renderers { count = 2, lighting = ao }
