-- landscape.lua - steady states of landscapes by the direct method.
--
-- Issue 12's catchment target: the debris-flow + fluvial steady state of
-- a 10 km^2 catchment at 10 m cells (316^2 cells, closed edges, one
-- outlet in the middle of the south edge, the Fig. 9 components, U =
-- 0.5 mm/yr, channel heads at 1 ha) in under 1 s, best of `reps`.
-- Then the grids of doc/landscape.md's table, one run each: rivers alone
-- (stream power, K = 2e-5, m = 0.5, n = 1) and debris flows + rivers on
-- 30 m cells from 1 m of seeded noise, every edge a base level; the set-up
-- of examples/landscape_synthetic.lua (base level on the south edge,
-- U rising from 0.5 to 1 mm/yr northwards) after its transient on
-- 200 x 150 and from noise on 300^2.  For each: CPU seconds, rounds, and
-- the state's channel cells with |dz/dt| > tol U, counted here from its
-- fields (so the same script measures any build of dfle).
-- CPU seconds; figures only, nothing asserted.
--
--   dfle -q bench/landscape.lua [reps] [--table-only | --no-table]

local reps, mode = 3, nil
for _, a in ipairs(arg or {}) do
  if tonumber(a) then reps = tonumber(a) else mode = a end
end

-- Channel cells (A >= A0, not base level) with |dz/dt| > 1e-3 U, of how many.
local function channel_above(ls)
  local dz, U, ch, base = ls:get("dzdt"), ls:get("U"), ls:get("channel"), ls:get("base")
  local above, count = 0, 0
  for i = 1, #dz do
    if ch[i] > 0 and base[i] == 0 then
      count = count + 1
      if not (math.abs(dz[i]) <= 1e-3 * U[i]) then above = above + 1 end
    end
  end
  return above, count
end

local function report(label, best, r, ls, target)
  local above, count = channel_above(ls)
  print(("  %-46s %7.2f s%s  %s, %4d rounds, channel cells above tol U: %d of %d (%.2f%%), "
         .. "%.0f B/cell"):format(label, best, target or "",
         r.converged and "steady" or "NOT steady", r.steps, above, count,
         count > 0 and 100 * above / count or 0, ls.memory / ls.n))
  if not r.converged or r.fallback then print("    " .. r.note) end
end

local function time(build, label, n, target)
  local best, r, ls = math.huge, nil, nil
  for _ = 1, n do
    ls = build()
    local t0 = os.clock()
    r = ls:run_to_steady{ progress = false }
    best = math.min(best, os.clock() - t0)
  end
  report(label, best, r, ls, target)
  return best, r.steps, ls.n
end

-- The least-squares slope of log y against log x.
local function exponent(x, y)
  local n, sx, sy, sxx, sxy = #x, 0, 0, 0, 0
  for i = 1, n do
    local lx, ly = math.log(x[i]), math.log(y[i])
    sx, sy, sxx, sxy = sx + lx, sy + ly, sxx + lx * lx, sxy + lx * ly
  end
  return (n * sxy - sx * sy) / (n * sxx - sx * sx)
end

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

local function debris(n)
  return dfle.landscape{ nx = n, ny = n, dx = 30, U = 5e-4, A0 = 1e4,
                         noise = { amplitude = 1, seed = 42 } }
end

-- examples/landscape_synthetic.lua's set-up; with `transient` its 1e5 yr
-- from noise first (not timed), as the example runs it.
local function synthetic(nx, ny, rule, transient)
  local ls = dfle.landscape{ nx = nx, ny = ny, dx = 30, A0 = 1e4, S_c = 0.8, combine = rule,
                             edges = { south = "base_level", north = "closed", east = "closed",
                                       west = "closed" },
                             U = function(_, y) return 5e-4 * (1 + y / (ny * 30)) end,
                             noise = { amplitude = 1, seed = 42 } }
  if transient then ls:run{ years = 1e5, dt = 5e3, progress = false } end
  return ls
end

if mode ~= "--table-only" then
  print(("Landscape steady states (direct method), CPU s, best of %d:"):format(reps))
  time(catchment, "debris flows + rivers, 316^2 x 10 m (1e5 cells)", reps, " (target < 1 s)")
end
if mode ~= "--no-table" then
  print("The grids of doc/landscape.md's table (direct method, one run each):")
  for _, n in ipairs{ 100, 200, 500, 1000 } do
    time(function() return rivers(n) end, ("rivers (K = 2e-5, n = 1), %d^2"):format(n), 1)
  end
  -- How the direct steady state of debris-flow landscapes grows with
  -- the cells n, t ~ n^p (target p <= 1.2 from 100^2 to 500^2), split
  -- into its rounds (~ n^q) and the CPU of a round (~ n^(p - q)).
  local cells, cpu, rounds = {}, {}, {}
  for _, n in ipairs{ 100, 200, 300, 500 } do
    local t, k, c = time(function() return debris(n) end,
                         ("debris flows + rivers (Fig. 9), %d^2"):format(n), 1)
    cells[#cells + 1], cpu[#cpu + 1], rounds[#rounds + 1] = c, t, k
  end
  local p, q = exponent(cells, cpu), exponent(cells, rounds)
  print(("  debris flows + rivers, 100^2 to 500^2: CPU ~ n^%.2f (target <= 1.2, %s): rounds "
         .. "~ n^%.2f, a round ~ n^%.2f"):format(p, p <= 1.2 and "met" or "NOT met", q, p - q))
  for _, rule in ipairs{ "any", "count" } do
    time(function() return synthetic(200, 150, rule, true) end,
         ("landscape_synthetic.lua 200 x 150, %s"):format(rule), 1)
  end
  for _, rule in ipairs{ "any", "count" } do
    time(function() return synthetic(300, 300, rule, false) end,
         ("the same set-up from noise, 300^2, %s"):format(rule), 1)
  end
end
