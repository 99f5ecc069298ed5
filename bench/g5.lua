-- g5.lua - the Table G5 ensemble (empirical router, sensitivity
-- analysis; paper channel, default direct method) that the ensemble
-- benchmarks time.  dofile it: `local g5, wall = dofile(...)`;
-- g5(n, workers, out) runs n samples with `workers` threads (nil: -j or
-- all cores) into a fresh file `out`; wall() is the time of day [s].
local function g5(n, workers, out)
  return dfle.ensemble{
    params = {                                   -- Table G5
      M0 = { 1000, 5000 }, gamma = { 0, 1 }, mu = { 100, 1000 }, tau_y = { 100, 600 },
      k_df = { 5e-5, 1e-3 }, k_e = { 2e-14, 8e-14 }, U = { 1e-4, 1e-3 },
    },
    n = n, seed = 1, out = out, workers = workers, resume = false,
    build = function(p)
      return dfle.model{
        U = p.U,
        fluvial = dfle.fluvial.stochastic_threshold{ k_e = p.k_e },
        router = dfle.router.empirical{ M0 = p.M0, gamma = p.gamma, mu = p.mu, tau_y = p.tau_y },
        law = dfle.law.power{ k_df = p.k_df, alpha = 6, beta = 1 },
      }
    end,
    outputs = { "S_df", "A_df", "r2", "S_max_minus_S_ch" },
  }
end

local function wall()
  local h = io.popen("date +%s.%N")
  local t = tonumber(h:read("l"))
  h:close()
  return t
end

return g5, wall
