-- laws.lua - what a law written in Lua costs: whole-run CPU time of the
-- default steady state (Fig. 9 defaults: empirical router, Eq. (6) with
-- alpha = 6, beta = 1, Table G1 fluvial law, dx = 5 m, A_max = 8 km^2)
-- with the built-in dfle.law.power and with the same law written with
-- dfle.law.define (as factor + rate, and as rate alone; compiled, as
-- every law that is a formula is by default, and run as Lua with
-- compile = false), by the explicit method and by the default (direct)
-- one; best of several repetitions, and the ratio Lua / built-in.
-- Target (issue 6): ratio <= 3 for the whole run.  Each model gets a
-- law of its own, as an ensemble's samples do, so since issue 15 a Lua
-- law's programs come from the cache after the first.
--
-- Then (issue 15) what a law built anew costs on top of the built-in
-- law: a model with a fresh law (new params, the same functions) and its
-- first evaluation, which traces and checks the law's functions
-- (cache = false, the old path) or takes the programs from the cache
-- (the default); target: the ~0.5 ms of issue 15 gone (<= 0.05 ms).
-- Prints times only; never asserts on them.
--   dfle bench/laws.lua [repetitions (3)]

local reps = tonumber(arg and arg[1]) or 3

local function lua_eq6(compile)
  return dfle.law.define{
    name = "eq6_lua",
    compile = compile,
    params = { k_df = 1e-4, alpha = 6, beta = 1 },
    factor = function(c, p) return c.t_p * c.h ^ p.beta * c.Theta end,
    rate = function(c, p) return p.k_df * c.S ^ p.alpha * c.F end,
    integrand = { h = 1 },
  }
end

-- The same law as one rate function (no factor): one Lua call per node
-- per evaluation instead of two.
local function lua_eq6_rate_only(compile)
  return dfle.law.define{
    name = "eq6_lua_rate",
    compile = compile,
    params = { k_df = 1e-4, alpha = 6, beta = 1 },
    rate = function(c, p) return p.k_df * c.S ^ p.alpha * c.t_p * c.h ^ p.beta * c.Theta end,
    integrand = { h = 1 },
  }
end

-- Best of `reps` CPU times of one whole run_to_steady.  A direct run
-- takes under a millisecond, so each timing covers `batch` runs (on
-- models built beforehand) and is divided by it.
local function time_run(make_law, method)
  local best, z = math.huge, nil
  local batch = method == "direct" and 50 or 1
  for _ = 1, reps do
    local models = {}
    for k = 1, batch do
      models[k] = dfle.model{
        channel = dfle.channel{ dx = 5, A_max = 8e6 },
        U = 5e-4,
        fluvial = dfle.fluvial.stochastic_threshold{ k_e = 5e-14 },
        router = dfle.router.empirical{ M0 = 3000, gamma = 0.5, mu = 500, tau_y = 300 },
        law = make_law(),
      }
    end
    local t0 = os.clock()
    for k = 1, batch do
      local r = models[k]:run_to_steady{ tol = 1e-3, max_time = 2e7, method = method }
      assert(r.converged, "no steady state")
    end
    local dt = (os.clock() - t0) / batch
    if dt < best then best = dt end
    z = models[batch]:get("z")
  end
  return best, z
end

for _, method in ipairs{ "explicit", "direct" } do
  local tc, zc = time_run(function() return dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 } end,
                          method)
  for _, v in ipairs{
    { "factor + rate", lua_eq6 },
    { "rate only", lua_eq6_rate_only },
    { "factor + rate, compile = false", function() return lua_eq6(false) end },
    { "rate only, compile = false", function() return lua_eq6_rate_only(false) end },
  } do
    local tl, zl = time_run(v[2], method)
    local d = 0
    for i = 1, #zc do
      if zc[i] ~= 0 then d = math.max(d, math.abs(zl[i] - zc[i]) / math.abs(zc[i])) end
    end
    print(("Lua-written Eq. (6) (%s), %s method: built-in %.2f ms, Lua %.2f ms, ratio %.2f "
           .. "(best of %d; max rel. difference in z %.1e)")
          :format(v[1], method, 1e3 * tc, 1e3 * tl, tl / tc, reps, d))
  end
end

-- Issue 15: a law built anew.  Batches of 100 models (channel, router and
-- fluvial law shared), each with a fresh law and one evaluation of E_df
-- (which runs factor and rate once).  The three kinds of law take turns,
-- round after round (4 x reps rounds), so that a change in the machine's
-- load hits them alike; the best batch of each counts.
local ch = dfle.channel{ dx = 5, A_max = 8e6 }
local fl = dfle.fluvial.stochastic_threshold{ k_e = 5e-14 }
local rt = dfle.router.empirical{ M0 = 3000, gamma = 0.5, mu = 500, tau_y = 300 }
local function batch_cost(make_law, batch)
  collectgarbage()
  local t0 = os.clock()
  for i = 1, batch do
    local m = dfle.model{ channel = ch, U = 5e-4, fluvial = fl, router = rt, law = make_law(i) }
    m:get("E_df")
  end
  return (os.clock() - t0) / batch
end
local factor = function(c, p) return c.t_p * c.h ^ p.beta * c.Theta end
local rate = function(c, p) return p.k_df * c.S ^ p.alpha * c.F end
local function fresh(cache)
  return function(i)
    return dfle.law.define{ cache = cache, params = { k_df = 1e-4 * (1 + 1e-3 * i), alpha = 6,
                                                      beta = 1 }, factor = factor, rate = rate }
  end
end
local kinds = { function(i) return dfle.law.power{ k_df = 1e-4 * (1 + 1e-3 * i) } end,
                fresh(false), fresh(true) }
local stats = debug.getregistry()["dfle.trace.stats"]
local best, found, looked = { math.huge, math.huge, math.huge }, 0, 0
for _ = 1, 4 * reps do
  for k, make_law in ipairs(kinds) do
    local s0 = stats()
    best[k] = math.min(best[k], batch_cost(make_law, 100))
    if k == 3 then
      local s1 = stats()
      found = found + s1.found - s0.found
      looked = looked + s1.found - s0.found + s1.traced - s0.traced
    end
  end
end
local t_builtin = best[1]
local old, new = best[2] - t_builtin, best[3] - t_builtin
print(("fresh Lua law per model (Eq. 6, factor + rate; model and first evaluation, built-in law "
       .. "%.3f ms): cache = false +%.3f ms, cached +%.3f ms (%d of %d programs found), "
       .. "ratio %.1f (target: <= 0.05 ms, the ~0.5 ms of issue 15 gone)")
      :format(1e3 * t_builtin, 1e3 * old, 1e3 * new, found, looked, old / math.max(new, 1e-9)))
