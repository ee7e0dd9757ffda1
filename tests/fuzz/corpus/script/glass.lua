scene { builtin = "cornell_glass" }
light { point = {0, 1.5, 0}, intensity = {1, 1, 1} }
local c = multiplexer { lightop "photonmap" { photons = 1000 }, replicas = 2 }
local s = lightop "combine" { inputs = { lightop "direct" {}, c } }
local h = host "h1" { launcher = "ssh", address = "10.0.0.1" }
renderers { count = 1, lighting = s }
farm { security = "none", heartbeat_timeout = 2 }
