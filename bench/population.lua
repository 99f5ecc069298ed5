-- population.lua - debris flows as a population: the direct steady state
-- with a population of quadrature order q against the characteristic
-- flow (target: about q times, not more), and one 2D debris-flow step
-- with q = 8 against one flow.  CPU times, interleaved, best of reps.

local reps = tonumber(arg and arg[1]) or 3
local base = dfle.router.empirical{}
local function pop(q)
  return dfle.router.population{ router = base, order = q, volume = { kind = "lognormal", sigma = 1 } }
end
-- 50 steady states a timing: one takes well under a millisecond.
local function steady(rt)
  local t = 0
  for _ = 1, 50 do
    local m = dfle.model{ channel = dfle.channel{ dx = 5 }, U = 5e-4, router = rt, law = dfle.law.power{} }
    local t0 = os.clock()
    m:run_to_steady{ method = "direct" }
    t = t + os.clock() - t0
  end
  return t / 50
end
local orders = { 4, 8, 16 }
local best = { [1] = math.huge }
for _, q in ipairs(orders) do best[q] = math.huge end
for _ = 1, reps do
  best[1] = math.min(best[1], steady(base))
  for _, q in ipairs(orders) do best[q] = math.min(best[q], steady(pop(q))) end
end
print(("population, direct steady state (dx = 5 m): one flow %.3g s CPU (best of %d)"):format(best[1], reps))
for _, q in ipairs(orders) do
  print(("  q = %2d: %.3g s, %.2f x one flow (target: about %d x, not more)"):format(q, best[q],
        best[q] / best[1], q))
end

local function step2d(rt)
  local ls = dfle.landscape{ nx = 150, ny = 150, dx = 30, A0 = 1e4, router = rt,
                             noise = { seed = 4, amplitude = 1 } }
  ls:step(1000) -- the first routing and the model's network
  local t0 = os.clock()
  for _ = 1, 3 do ls:step(1000) end
  return (os.clock() - t0) / 3
end
local b1, b8 = math.huge, math.huge
local p8 = pop(8)
for _ = 1, reps do
  b1 = math.min(b1, step2d(base))
  b8 = math.min(b8, step2d(p8))
end
print(("population, 2D step (150 x 150 cells): one flow %.4f s, q = 8 %.4f s, %.2f x (target: about 8 x, not more)")
      :format(b1, b8, b8 / b1))
