-- landscape_df.lua - what debris flows add to a landscape step.
--
-- Issue 26's target: a step of the Fig. 9 components (the default
-- landscape: stochastic-threshold rivers, empirical router, power law)
-- on 500^2 cells of 30 m from its steady state costs at most 1.5x the
-- step of the same landscape without debris flows (router = false), on
-- the same surface.  Steps of 1e3 yr, timed interleaved (a river-only
-- step, then a debris-flow step, `reps` times `k` each) so that other
-- work on the machine weighs on both alike; CPU s per step.
--
--   dfle -q bench/landscape_df.lua [side] [k] [reps]

local side = tonumber(arg and arg[1]) or 500
local k = tonumber(arg and arg[2]) or 10
local reps = tonumber(arg and arg[3]) or 3

local function landscape(router)
  local o = { nx = side, ny = side, dx = 30, U = 5e-4, A0 = 1e4,
              noise = { amplitude = 1, seed = 42 } }
  if not router then o.router = false end
  return dfle.landscape(o)
end

local df = landscape(true)
local r = df:run_to_steady{ progress = false }
local rivers = landscape(false)
rivers:set_z(df:get("z"))
df:step(1e3)
rivers:step(1e3)

local function per_step(ls)
  local t0, reached = os.clock(), 0
  for _ = 1, k do reached = ls:step(1e3).reached end
  return (os.clock() - t0) / k, reached
end

local best_df, best_r, ratios = math.huge, math.huge, {}
local reached
for _ = 1, reps do
  local tr = per_step(rivers)
  local td
  td, reached = per_step(df)
  best_df, best_r = math.min(best_df, td), math.min(best_r, tr)
  ratios[#ratios + 1] = td / tr
end
table.sort(ratios)
print(("Debris-flow step, Fig. 9 components, %d^2 x 30 m from its steady state (%s, %d rounds):")
      :format(side, r.converged and "converged" or "NOT converged", r.steps))
print(("  with debris flows %.4f s, without %.4f s a step (best of %d x %d); "
       .. "%d cells reached of %d channel cells")
      :format(best_df, best_r, reps, k, reached, df:step(1e3).channel_cells))
print(("  ratio %.2f-%.2f (target <= 1.5); memory %.0f B/cell with flows, %.0f without")
      :format(ratios[1], ratios[#ratios], df.memory / df.n, rivers.memory / rivers.n))
