-- test_landscape_process.lua - dfle.landscape with the process-based
-- router: every channel head's flow down its own path of receivers
-- (doc/landscape.md, "The process-based router").
local T = T
local tests = {}

-- A grid one cell wide draining north: its cells are numbered from the
-- outlet up, so it is routed as a network (head by head), not as the
-- 1D channel.
local function column(ny, dy, router)
  local o = { nx = 1, ny = ny, dx = dy, dy = dy, A0 = dy * dy, cap_channels = false,
              router = router, law = dfle.law.power{},
              edges = { north = "base_level", east = "closed", west = "closed",
                        south = "closed" } }
  o.z = {}
  for r = 1, ny do o.z[r] = (r - 1) * dy * 0.3 end
  return dfle.landscape(o)
end

tests["a grid one cell wide: the 1D process model's steady state"] = function()
  local ny, dy = 120, 10
  local area = {}
  for i = 1, ny do area[i] = i * dy * dy end
  local m = dfle.model{ channel = dfle.channel{ dx = dy, area = area },
                        router = dfle.router.process{}, law = dfle.law.power{} }
  local r1 = m:run_to_steady{}
  T.ok(r1.converged, "1D")
  local rt = dfle.router.process{}
  local ls = column(ny, dy, rt)
  local r2 = ls:run_to_steady{}
  T.ok(r2.converged and r2.verified, "landscape: " .. r2.note)
  T.eq(rt:routings().heads, 1, "one head")
  local z1, z2 = m:get("z"), ls:get("z")
  local worst = 0
  for i = 1, ny do
    worst = math.max(worst, math.abs(z2[ny + 1 - i] - z1[i]) / math.max(z1[i], 1))
  end
  -- Both are steady for a flow routed over slopes within reroute_dS of
  -- their own (the rule), reached by different paths: they agree to the
  -- spread the rule leaves, not to the node solver's tolerance.
  T.ok(worst < 0.02, "z differs by " .. worst .. " (relative)")
  -- every channel cell balances U with the flow it keeps
  local Ef, Edf = ls:get("E_f"), ls:get("E_df")
  for j = 2, ny do
    T.ok(math.abs(Ef[j] + Edf[j] - 5e-4) <= 1e-3 * 5e-4 + 1e-12,
         "cell " .. j .. ": E = " .. (Ef[j] + Edf[j]))
  end
end

tests["a landscape with the process router: steady, and routings fall towards it"] = function()
  local rt = dfle.router.process{}
  local ls = dfle.landscape{ nx = 20, ny = 16, dx = 20, U = 5e-4, A0 = 4 * 400, router = rt,
                             law = dfle.law.power{}, noise = { seed = 3 } }
  -- implicit steps from the noise: count the flows routed in each block
  local per, prev = {}, 0
  for k = 1, 6 do
    ls:run{ years = 6e4, dt = 1e4 }
    local c = rt:routings()
    per[k] = c.total - prev
    prev = c.total
  end
  local heads = rt:routings().heads
  T.ok(heads > 10, "heads: " .. heads)
  T.ok(per[1] >= heads, "the first block routes every head (" .. per[1] .. ")")
  T.ok(per[6] < per[1] / 3, ("routings per block fell: %d -> %d"):format(per[1], per[6]))
  local r = ls:run_to_steady{}
  T.ok(r.converged, r.note)
  -- at steady state nothing is routed again
  local before = rt:routings().total
  ls:run{ years = 3e4, dt = 1e4 }
  T.eq(rt:routings().total, before, "no flow re-routed at steady state")
  local reach, Edf = ls:get("reach"), ls:get("E_df")
  local reached = 0
  for i = 1, #reach do
    if reach[i] > 0 then reached = reached + 1 end
    T.ok(Edf[i] >= 0, "E_df >= 0")
  end
  T.ok(reached > heads, "flows reach " .. reached .. " cells")
end

tests["the combine rules with the process router: count erodes more below junctions"] = function()
  local function steady(rule)
    -- flows of 2000 m^3 on 10 m cells: they run far enough to join
    local ls = dfle.landscape{ nx = 24, ny = 20, dx = 10, U = 5e-4, A0 = 4 * 100,
                               router = dfle.router.process{ M0 = 2000 },
                               law = dfle.law.power{},
                               combine = rule, noise = { seed = 4 } }
    local r = ls:run_to_steady{}
    T.ok(r.converged, tostring(rule) .. ": " .. r.note)
    return ls
  end
  local any, count = steady("any"), steady("count")
  -- where c flows meet, "count" erodes c times one flow's mean: the
  -- same uplift is balanced at lower slopes
  local Sa, Sc, ra, rc = any:get("S"), count:get("S"), any:get("reach"), count:get("reach")
  local lower, joined = 0, 0
  for i = 1, #Sa do
    if ra[i] >= 2 and rc[i] >= 2 then
      joined = joined + 1
      if Sc[i] < Sa[i] then lower = lower + 1 end
    end
  end
  T.ok(joined > 0, "some cells are reached by two flows or more")
  T.ok(lower >= 0.8 * joined, ("lower with count at %d of %d"):format(lower, joined))
end

tests["a 100 x 100 landscape with the process router reaches a verified steady state"] = function()
  local rt = dfle.router.process{}
  local U = 5e-4
  local ls = dfle.landscape{
    nx = 100, ny = 100, dx = 30, A0 = 1e4, router = rt, law = dfle.law.power{}, U = U,
    edges = { south = "base_level", north = "closed", east = "closed", west = "closed" },
    noise = { amplitude = 1, seed = 7 },
  }
  local r = ls:run_to_steady{}
  T.ok(r.converged and r.verified, r.note)
  T.ok(rt:routings().heads > 150, "heads: " .. rt:routings().heads)
  -- the state itself, judged here from its rates: at most 1 % of the
  -- channel cells off U by more than tol (1e-3), and the same after
  -- 10 implicit steps of 1e4 yr from it (a fixed point, not a pass)
  local function off()
    local dz, A = ls:get("dzdt"), ls:get("A")
    local n, bad = 0, 0
    for i = 1, #dz do
      if A[i] >= 1e4 and dz[i] == dz[i] then
        n = n + 1
        if math.abs(dz[i]) > 1e-3 * U then bad = bad + 1 end
      end
    end
    return bad / n, n
  end
  local f0, n = off()
  T.ok(n > 1000 and f0 <= 0.01, ("%.3g %% of %d channel cells off"):format(100 * f0, n))
  ls:run{ years = 1e5, dt = 1e4 }
  local f1 = off()
  T.ok(f1 <= 0.01, ("after 1e5 yr: %.3g %% off"):format(100 * f1))
end

return tests
