-- custom_laws.lua - debris-flow incision laws written in Lua, run by the
-- same compiled routers and solvers as the paper's law, and compared on
-- one slope-area plot.
--
-- Four laws on the Fig. 9 channel (empirical router, Table G1 fluvial law):
--   * the paper's Eq. (6), built in (dfle.law.power);
--   * the inertial-stress law after Stock and Dietrich (2006), written in
--     Lua as a user would, and built in (dfle.law.inertial) to show
--     they agree;
--   * an excess-stress law k (tau - tau_c)^p, written in Lua;
--   * Eq. (6) with a debris-flow frequency that falls with drainage area
--     (Appendix D generalised), through frequency(A).
-- Each runs to steady state; the script prints the fitted Eq. (2) for
-- each and writes custom_laws.png (slope-area, log axes) and
-- custom_laws.csv.
--
--   dfle examples/custom_laws.lua [--quick] [output-directory]
--
-- --quick uses a 20 m grid and a 1 km^2 basin (for the test suite).

local opts = dfle.args{
  usage = "dfle examples/custom_laws.lua [options] [output-directory]",
  about = "Debris-flow incision laws written in Lua, run by the same routers and solvers as the paper's law.",
  flags = { quick = "a 20 m grid and a 1 km^2 basin (for the test suite)" },
  output = true,
}
local quick, outdir = opts.quick, opts.output

local channel = quick and dfle.channel{ dx = 20, A_max = 1e6 } or dfle.channel{ dx = 5, A_max = 8e6 }

-- Stock and Dietrich (2006): erosion by the inertial stress of grain
-- impacts, rho_s (D du/dz)^2 with du/dz ~ v/h, over the passage time.
-- The factor depends on the routed flow only (cached per routing); the
-- slope part is applied at every step.
local inertial = dfle.law.define{
  name = "inertial (Lua)",
  params = { k = 3e-7, D = 0.09, rho_s = 2600, alpha = 1.5 },
  factor = function(c, p)                      -- c: the node; p: params
    if c.Theta <= 0 then return 0 end          -- the flow stops here
    local shear = c.v / c.h                    -- 1/s
    return c.t_p * p.rho_s * (p.D * shear)^2   -- s * Pa
  end,
  rate = function(c, p) return p.k * c.S^p.alpha * c.F end,   -- m/yr
}

-- A threshold law on the flow's basal shear stress tau [Pa].  Written
-- with math.max rather than `if`, it runs compiled (doc/laws.md); the
-- inertial law above branches on Theta, so it runs as Lua.
local excess = dfle.law.define{
  name = "excess stress (Lua)",
  params = { k = 2e-9, tau_c = 400, p = 1.5 },
  rate = function(c, p) return p.k * math.max(c.tau - p.tau_c, 0)^p.p end,
}

-- Eq. (6) per flow, times a flow frequency [1/yr] that halves for every
-- tenfold increase in drainage area beyond 1e4 m^2: frequency(A) is
-- called once per node and cached.
local rarer = dfle.law.define{
  name = "Eq. (6), frequency(A)",
  params = { k_df = 2e-4, alpha = 6, beta = 1 },
  factor = function(c, p) return c.t_p * c.h^p.beta * c.Theta end,
  rate = function(c, p) return p.k_df * c.S^p.alpha * c.F end,
  frequency = function(A) return A > 1e4 and 0.5 ^ math.log(A / 1e4, 10) or 1 end,
}

-- The inertial law twice, in Lua and built in: the same curve, so the
-- second is drawn as markers on the first's line.
local laws = {
  { label = "Eq. (6), built in", law = dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 },
    style = { rgb = "blue", lines = true } },
  { label = "inertial, built in", law = dfle.law.inertial{ k = 3e-7, D = 0.09, rho_s = 2600,
                                                            alpha = 1.5 },
    style = { rgb = "vermillion", lines = true } },
  { label = "inertial, Lua (markers: the same curve)", law = inertial,
    style = { rgb = "black", marker = "open circle", markers = 25 } },
  { label = "excess stress, Lua", law = excess, style = { rgb = "green", lines = true } },
  { label = "Eq. (6) × frequency(A), Lua", law = rarer,
    style = { rgb = "purple", lines = true, dash = true } },
}

local series, rows = {}, {}
for _, L in ipairs(laws) do
  local m = dfle.model{
    channel = channel, U = 5e-4,
    fluvial = dfle.fluvial.stochastic_threshold{ k_e = 5e-14 },
    router = dfle.router.empirical{},
    law = L.law,
  }
  m:init_fluvial_steady()
  local t0 = os.clock()
  local run = m:run_to_steady{}
  if not run.converged then
    io.stderr:write(("custom_laws: %s reached no steady state (%s)\n"):format(L.label, run.reason))
    os.exit(1)
  end
  local fit = dfle.fit_slope_area(m)
  print(("%-28s steady in %.3f s (%s)   %s"):format(L.label, os.clock() - t0, run.method,
        fit and ("S_df = %.3f, A_df = %.3g m^2"):format(fit.S_df, fit.A_df) or "no Eq. (2) fit"))
  local st = L.law:compiled()  -- nil for a built-in law
  if st then
    for _, fn in ipairs{ "factor", "rate" } do
      if st[fn] ~= nil then print(("%30s%s: %s"):format("", fn, st[fn] == true and "compiled" or st[fn])) end
    end
  end
  local A, S = m:get("A"), m:get("S")
  local a, s = {}, {}
  for i = 1, m.n - 1 do
    a[#a + 1], s[#s + 1] = A[i], S[i]
    rows[#rows + 1] = { law = L.label, A = A[i], S = S[i] }
  end
  local look = L.style
  if look.markers then -- about that many markers, evenly spaced in log A
    local ma, ms, next_a = {}, {}, a[1]
    for i = 1, #a do
      if a[i] >= next_a then
        ma[#ma + 1], ms[#ms + 1] = a[i], s[i]
        next_a = a[i] * (a[#a] / a[1]) ^ (1 / look.markers)
      end
    end
    a, s = ma, ms
  end
  series[#series + 1] = { x = a, y = s, label = L.label, lines = look.lines, rgb = look.rgb,
                          marker = look.marker, dash = look.dash }
end

local csv = outdir .. "/custom_laws.csv"
dfle.write_csv(csv, {
  about = "steady-state slope and drainage area of every node above the outlet, for each law",
  columns = { "law", "A", "S" }, units = { A = "m^2", S = "-" }, rows = rows,
})
local png = outdir .. "/custom_laws.png"
dfle.plot.xy{ path = png, series = series, xlog = true, ylog = true,
              title = "Steady-state slope-area relations of custom incision laws",
              xlabel = dfle.plot.label("A"), ylabel = dfle.plot.label("S") }
print("wrote " .. csv .. ", " .. png)
