-- alpha_beta.lua - which incision laws give realistic profiles?
--
-- A grid over the exponents of the power-law family, Eq. (6), with the
-- empirical router and the other parameters at the Fig. 9 defaults (the
-- paper samples them by Latin hypercube, Table G3), for two volume-area
-- exponents: gamma = 0.5, where Eq. (20) makes slope fall with area for
-- every alpha, beta, and gamma = 0, where channel widening thins the
-- flows and slope can rise with area below A_df (S_max > S_ch).  For each (alpha, beta)
-- the steady-state profile is scored as in Sect. 2.5.1: R^2 of the fit of
-- Eq. (2), and S_max - S_ch (natural channels keep this near zero).
-- Writes alpha_beta.csv and a plot of S_max - S_ch against alpha.
--
--   dfle examples/alpha_beta.lua [--quick] [output-directory]

local opts = dfle.args{
  usage = "dfle examples/alpha_beta.lua [options] [output-directory]",
  about = "Which incision laws give realistic profiles? A grid over the exponents alpha and beta of Eq. (6).",
  flags = { quick = "two alphas and one beta on a 20 m grid (for the test suite)" },
  output = true,
}
local quick, outdir = opts.quick, opts.output

local alphas = quick and { 2, 6 } or { 2, 3, 4, 5, 6, 7, 8 }
local betas = quick and { 1 } or { 0.5, 1, 2, 3 }
local gammas = { 0, 0.5 }
local channel = dfle.channel{ dx = quick and 20 or 5, A_max = 8e6 }
local fluvial = dfle.fluvial.stochastic_threshold{ k_e = 5e-14 }

local rows = {} -- of alpha_beta.csv
print(("%5s %5s %5s %10s %8s %10s %6s %7s %9s"):format(
  "gamma", "alpha", "beta", "method", "S_df", "A_df (m2)", "a2", "R^2", "Smax-Sch"))
-- One curve per (gamma, beta): colour by beta, dashed for gamma = 0.5.
local colours = { [0.5] = "blue", [1] = "vermillion", [2] = "green", [3] = "purple" }
local curves = {}
for _, gamma in ipairs(gammas) do
local router = dfle.router.empirical{ M0 = 3000, gamma = gamma, mu = 500, tau_y = 300 }
for _, beta in ipairs(betas) do
  local xs, ys = {}, {}
  for _, alpha in ipairs(alphas) do
    local m = dfle.model{
      channel = channel, U = 5e-4, fluvial = fluvial, router = router,
      law = dfle.law.power{ k_df = 1e-4, alpha = alpha, beta = beta },
    }
    local run = m:run_to_steady{ tol = 1e-3, max_time = 2e7 }
    local fit, why = dfle.fit_slope_area(m)
    if fit then
      print(("%5g %5g %5g %10s %8.3f %10.3g %6.2f %7.4f %9.4f"):format(
        gamma, alpha, beta, run.method, fit.S_df, fit.A_df, fit.a2, fit.r2, fit.S_max_minus_S_ch))
      rows[#rows + 1] = { gamma = gamma, alpha = alpha, beta = beta, converged = run.converged,
        time = run.time, S_df = fit.S_df, A_df = fit.A_df, a2 = fit.a2, r2 = fit.r2,
        S_max_minus_S_ch = fit.S_max_minus_S_ch }
      xs[#xs + 1], ys[#ys + 1] = alpha, fit.S_max_minus_S_ch
    else
      print(("%5g %5g %5g  no fit: %s"):format(gamma, alpha, beta, why))
      rows[#rows + 1] = { gamma = gamma, alpha = alpha, beta = beta, converged = run.converged,
        time = run.time }
    end
  end
  if #xs > 0 then curves[#curves + 1] = { gamma = gamma, beta = beta, x = xs, y = ys } end
end
end
dfle.write_csv(outdir .. "/alpha_beta.csv", {
  about = "steady states for each alpha and beta of the power law (k_df = 1e-4) and gamma of "
          .. "the empirical router (M0 = 3000, mu = 500, tau_y = 300), U = 5e-4 m/yr",
  columns = { "gamma", "alpha", "beta", "converged", "time", "S_df", "A_df", "a2", "r2",
              "S_max_minus_S_ch" },
  units = { gamma = "-", alpha = "-", beta = "-", time = "yr", S_df = "-", A_df = "m^2", a2 = "-",
            r2 = "-", S_max_minus_S_ch = "-" },
  rows = rows,
  params = { channel = channel:params(), fluvial = fluvial:params() },
})

-- Curves that are zero everywhere (slope never rises with area) would
-- lie on top of each other: they are drawn as one, black and dashed,
-- whose legend entry names them all.
local series, zero, zero_names = {}, nil, {}
for _, gamma in ipairs(gammas) do
  local betas_zero = {}
  for _, c in ipairs(curves) do
    if c.gamma == gamma then
      local all_zero = true
      for _, v in ipairs(c.y) do all_zero = all_zero and v == 0 end
      if all_zero then
        betas_zero[#betas_zero + 1] = ("%g"):format(c.beta)
        if zero == nil or #c.x > #zero.x then zero = c end
      else
        series[#series + 1] = {
          x = c.x, y = c.y, style = "linespoints", rgb = colours[c.beta],
          dash = gamma > 0, marker = gamma > 0 and "open circle" or "circle",
          label = ("γ = %g, β = %g"):format(gamma, c.beta),
        }
      end
    end
  end
  if #betas_zero > 0 then
    zero_names[#zero_names + 1] = ("γ = %g, β = %s"):format(gamma, table.concat(betas_zero, ", "))
  end
end
if zero then
  series[#series + 1] = { x = zero.x, y = zero.y, style = "linespoints", rgb = "black",
                          dash = true, marker = "open circle",
                          label = "all 0: " .. table.concat(zero_names, "; ") }
end
dfle.plot.xy{
  path = outdir .. "/alpha_beta.png", series = series,
  title = "S_{max} − S_{ch} of the steady state against α, empirical router",
  xlabel = dfle.plot.label("alpha"), ylabel = dfle.plot.label("S_max_minus_S_ch"),
  xticks = 1,
}
print("wrote " .. outdir .. "/alpha_beta.csv and " .. outdir .. "/alpha_beta.png")
