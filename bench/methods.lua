-- methods.lua - the default steady state by each method, and the ratios
-- (issue targets: direct >= 100x explicit with the empirical router, the
-- process-based steady state >= 10x its explicit run).  Best of `reps`.

local reps = tonumber(arg and arg[1]) or 3
local function build(router)
  return dfle.model{
    channel = dfle.channel{ dx = 5, A_max = 8e6 }, U = 5e-4,
    fluvial = dfle.fluvial.stochastic_threshold{ k_e = 5e-14 },
    router = router, law = dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 },
  }
end

for _, case in ipairs{
  { "empirical (Fig. 9)", function() return dfle.router.empirical{} end },
  { "process (Fig. 6)", function() return dfle.router.process{} end },
} do
  local t = {}
  for _, method in ipairs{ "explicit", "implicit", "direct" } do
    local best, r = math.huge, nil
    for _ = 1, (method == "explicit" and case[1]:match("process")) and 1 or reps do
      local m = build(case[2]())
      local t0 = os.clock()
      r = m:run_to_steady{ method = method }
      best = math.min(best, os.clock() - t0)
    end
    t[method] = best
    print(("%-20s %-9s %8.4f s  %6d steps %5d routings%s"):format(case[1], method, best, r.steps,
          r.routings, r.fallback and ("  (" .. r.note .. ")") or ""))
  end
  print(("%-20s speed-up over explicit: implicit %.1fx, direct %.1fx")
        :format(case[1], t.explicit / t.implicit, t.explicit / t.direct))
end
