-- landscape.lua - issue 12's catchment target: the debris-flow + fluvial
-- steady state of a 10 km^2 catchment at 10 m cells (about 1e5 cells) in
-- under 1 s.  A square of 316 x 316 cells from 1 m of seeded noise,
-- edges closed, one outlet in the middle of the south edge, the Fig. 9
-- components (the defaults), U = 0.5 mm/yr, channel heads at 1 ha; the
-- direct method.  Also the direct steady state of rivers alone on larger
-- grids (30 m cells, stream power n = 1, every edge a base level), and
-- debris flows on 300^2 cells with the synthetic example's set-up (once).
-- CPU seconds, best of `reps`; figures only, nothing asserted.
--
--   dfle -q bench/landscape.lua [reps]

local reps = tonumber(arg and arg[1]) or 3

local function catchment()
  local n = 316
  return dfle.landscape{ nx = n, ny = n, dx = 10, U = 5e-4, A0 = 1e4,
                         edges = "closed", outlets = { { n * 5, 5 } },
                         noise = { amplitude = 1, seed = 42 } }
end

local function rivers(n)
  return dfle.landscape{ nx = n, ny = n, dx = 30, U = 5e-4, A0 = 1e4, router = false,
                         fluvial = dfle.fluvial.stream_power{ K = 2e-5, m = 0.5, n = 1 },
                         noise = { amplitude = 1, seed = 42 } }
end

local function time(build, label, target)
  local best, r, ls = math.huge, nil, nil
  for _ = 1, reps do
    ls = build()
    local t0 = os.clock()
    r = ls:run_to_steady{}
    best = math.min(best, os.clock() - t0)
  end
  print(("  %-44s %7.3f s%s  %s, %d rounds, %d heads, %d cells reached, %.0f B/cell"):format(
    label, best, target or "", r.converged and "steady" or "NOT steady", r.steps, r.heads,
    r.reached, ls.memory / ls.n))
  if not r.converged then print("    " .. r.note) end
end

print(("Landscape steady states (direct method), CPU s, best of %d:"):format(reps))
time(catchment, "debris flows + rivers, 316^2 x 10 m (1e5 cells)", " (target < 1 s)")
for _, n in ipairs{ 250, 500 } do
  time(function() return rivers(n) end, ("rivers, %d^2 x 30 m"):format(n))
end

-- The set-up of examples/landscape_synthetic.lua on 300^2 cells from
-- noise: base level on the south edge only (flow paths of 9 km), U rising
-- from 0.5 to 1 mm/yr northwards, both rules for joined debris flows;
-- channel heads there are steeper than S_c without its cap
-- (doc/landscape.md, "Channels steeper than S_c").  One run each.
local function synthetic(rule)
  local n = 300
  return dfle.landscape{ nx = n, ny = n, dx = 30, A0 = 1e4, S_c = 0.8, combine = rule,
                         edges = { south = "base_level", north = "closed", east = "closed",
                                   west = "closed" },
                         U = function(_, y) return 5e-4 * (1 + y / (n * 30)) end,
                         noise = { amplitude = 1, seed = 42 } }
end
reps = 1
for _, rule in ipairs{ "any", "count" } do
  time(function() return synthetic(rule) end, ("debris flows, 300^2 south edge, %s"):format(rule))
end
