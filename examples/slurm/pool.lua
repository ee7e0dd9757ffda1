-- The Cornell box pool network spread over a Slurm allocation: one `direct` replica and one renderer per node
-- (round robin over the nodes), the multiplexer on the first node. Run inside an allocation:
--   salloc -N 3 lightfarm run examples/slurm/pool.lua
-- or as a batch job: sbatch examples/slurm/pool.sbatch
scene  { builtin = "cornell" }
camera { eye = {278, 273, -800}, at = {278, 273, 0}, fov = 39.3 }
image  { width = param("width", 512), height = param("height", 512), spp = param("spp", 16),
         output = "cornell_slurm.png" }

local nodes = slurm_hosts()   -- every node of the allocation, in its order
local direct = multiplexer { lightop "direct" { light_samples = param("light_samples", 2) },
                             replicas = param("replicas", #nodes), host = nodes }
renderers { count = param("renderers", #nodes), lighting = direct, host = nodes }
