-- landscape_process.lua - landscapes with the process-based router:
-- one full routing of every channel head, the steady state by the
-- direct method (with its fallback to implicit steps where the rounds
-- do not settle), and the share of head routings the re-routing rule
-- saved, on 100^2, 200^2 and 300^2 cells of 30 m from 1 m of seeded
-- noise (base level on the south edge, U = 0.5 mm/yr, heads at 1 ha,
-- the Fig. 6 defaults).  CPU seconds; the target beside each: a steady
-- state that is verified (converged, the fixed-point check passed).
--
--   dfle -q bench/landscape_process.lua [max_steps]

local max_steps = tonumber(arg and arg[1]) -- nil: run_to_steady's default
print("landscapes with the process router (CPU s; doc/landscape.md, The process-based router)")
local function block(n, router, z)
  return dfle.landscape{ nx = n, ny = n, dx = 30, A0 = 1e4, router = router, law = dfle.law.power{},
    edges = { south = "base_level", north = "closed", east = "closed", west = "closed" },
    U = 5e-4, noise = { amplitude = 1, seed = 11 }, z = z }
end
for _, n in ipairs{ 100, 200, 300 } do
  local rt = dfle.router.process{}
  local ls = block(n, rt)
  local t0 = os.clock()
  local r = ls:run_to_steady{ max_steps = max_steps }
  local c = rt:routings()
  print(("  %3d^2: steady state %8.2f s: %s (target: verified steady) (%s, %d %s); %d flows "
         .. "routed in %d routings of %d heads: %.1f%% of the head routings saved by the rule"):format(
    n, os.clock() - t0, r.converged and r.verified and "verified steady" or "NOT steady", r.method, r.steps,
    r.method == "direct" and "rounds" or "steps", c.total, c.calls, c.heads,
    100 * (1 - c.total / math.max(c.calls * c.heads, 1))))
  -- One routing of every head over that surface: a fresh router, one
  -- step of 1 yr (the drainage routing and the step are a small part).
  local rt2 = dfle.router.process{}
  local ls2 = block(n, rt2)
  ls2:set_z(ls:dem())
  t0 = os.clock()
  ls2:run{ years = 1, dt = 1 }
  local full = os.clock() - t0
  c = rt2:routings()
  print(("         one routing of all %d heads %8.2f s (%.2f ms a head)"):format(
    c.total, full, 1e3 * full / math.max(c.total, 1)))
end
