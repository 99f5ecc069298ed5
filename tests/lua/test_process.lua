-- test_process.lua - dfle.router.process from Lua: construction, errors,
-- routing a flow, snapshots and plots, and a model run like an empirical one.
local tests = {}

local function small_model(rt)
    return dfle.model{ channel = dfle.channel{ dx = 10 }, router = rt }
end

tests["process: defaults are the Fig. 6 / Table G2 values"] = function()
    local rt = dfle.router.process{}
    T.eq(rt.name, "process")
    T.eq(rt.M0, 200)
    T.eq(rt.eta, 60)
    T.eq(rt.mu2, 0.62)
    T.eq(rt.D, 5e-6)
    T.eq(rt.mu_s, 0.384)
    T.eq(rt.I0, 0.279)
    T.eq(rt.lambda0, 0.9)
    T.eq(rt.v_f, 0.5)
    T.eq(rt.D_eff, 0.09)
    T.eq(rt.n_ghost, 20)
    T.eq(rt.reroute_dS, 0.05)
    T.eq(rt.reroute_dw, 0.1)
    T.eq(rt.frequency_scaling, false)
    T.has(tostring(rt), "dfle.router.process(M0 = 200")
end

tests["process: bad parameters name themselves and the caller's line"] = function()
    T.raises_here(function() return dfle.router.process{ eta = -1 } end, "eta must be >= 0")
    T.raises_here(function() return dfle.router.process{ mu2 = 0.1 } end, "mu_2 must be >= mu_s")
    T.raises_here(function() return dfle.router.process{ lambda0 = 1 } end, "lambda0")
    T.raises_here(function() return dfle.router.process{ reroute_dw = 0 } end, "reroute_dw must be > 0")
    T.raises_here(function() return dfle.router.process{ M0 = 0 } end, "M0 must be > 0")
    T.raises_here(function() return dfle.router.process{ n_ghost = 2.5 } end, "n_ghost must be a whole number")
    T.raises_here(function() return dfle.router.process{ D = 0 / 0 } end, "'D' must be a finite number")
    T.raises_here(function() return dfle.router.process{ mu_2 = 0.6 } end, "unknown parameter 'mu_2'", "mu2")
    T.raises_here(function() return dfle.router.process{ frequency_scaling = 1 } end,
                  "'frequency_scaling' must be a boolean")
end

tests["process: one router shared by two models gives each what its own would"] = function()
    -- The slopes a routing was made for are the model's, not the router's:
    -- stepped alternately, two models on one router route when (and only
    -- when) each would on a router of its own.
    local shared = dfle.router.process{}
    local a, b = small_model(shared), small_model(shared)
    local a1, b1 = small_model(dfle.router.process{}), small_model(dfle.router.process{})
    local ra, rb, ra1, rb1 = 0, 0, 0, 0
    for _ = 1, 15 do
        ra = ra + a:run{ years = 2000 }.routings
        rb = rb + b:run{ years = 1000 }.routings
        ra1 = ra1 + a1:run{ years = 2000 }.routings
        rb1 = rb1 + b1:run{ years = 1000 }.routings
    end
    T.eq(ra, ra1)
    T.eq(rb, rb1)
    local za, za1, zb, zb1 = a:get("z"), a1:get("z"), b:get("z"), b1:get("z")
    for i = 1, a.n do
        T.eq(za[i], za1[i])
        T.eq(zb[i], zb1[i])
    end
end

tests["process: a routing is bounded and says why it stopped"] = function()
    -- cfl = 1e-5 is accepted but would need ~1e8 flow steps: the routing
    -- must stop at max_steps with a reason, not run for hours; and a tiny
    -- first step must not pass for a flow "at rest".
    local rt = dfle.router.process{ cfl = 1e-5, max_steps = 3000 }
    T.eq(rt.max_steps, 3000)
    local m = small_model(rt)
    T.raises_here(function() return rt:route(m) end, "max_steps = 3000", "raise cfl or max_steps")
    T.raises_here(function() return dfle.router.process{ max_steps = 0 } end, "max_steps must be > 0")
end

tests["process: route returns the flow and balances its volume"] = function()
    local rt = dfle.router.process{}
    local m = small_model(rt)
    local r = rt:route(m)
    T.close(r.volume_in, 200, 1e-12, 0)
    T.close(r.volume_out + r.volume_left, r.volume_in, 1e-12, 0)
    T.ok(r.ended == "rest" or r.ended == "left", r.ended)
    T.ok(r.runout_end > 5 and r.runout_end < m.n)
    -- the solver worked on the wet window, not on every cell at every step
    T.ok(r.cell_steps > 0 and r.cell_steps < r.steps * (m.n + rt.n_ghost), r.cell_steps)
    T.eq(#r.h_peak, m.n)
    for i = 1, m.n do
        T.ok(r.h_peak[i] >= 0 and r.sum[i] >= 0 and r.passage[i] >= 0)
        T.eq(r.arrival[i] ~= r.arrival[i], r.passage[i] == 0) -- NaN exactly where never reached
    end
end

tests["process: snapshots and dfle.plot.flow"] = function()
    local rt = dfle.router.process{}
    local m = small_model(rt)
    local r = rt:route(m, { snapshots = { 5, 20, 60 } })
    T.eq(#r.snapshots, 3)
    T.ok(r.snapshots[1].t >= 5 and r.snapshots[2].t >= 20)
    local png = T.tmpname(".png")
    dfle.plot.flow(m, r, png, { exaggeration = 50, title = "flow" })
    T.eq(assert(T.read_file(png)):sub(1, 4), "\137PNG")
    T.raises_here(function() return dfle.plot.flow(m, rt:route(m), png) end, "has no snapshots")
    T.raises_here(function() return dfle.router.empirical{}:route(m, { snapshots = { 1 } }) end,
                  "snapshots need a process-based router")
end

tests["process: a model runs to steady state exactly like an empirical one"] = function()
    local rt = dfle.router.process{}
    local m = small_model(rt)
    local run = m:run_to_steady{ method = "explicit" }
    T.ok(run.converged)
    T.ok(run.routings >= 1 and run.routings < run.steps) -- the Eq. (11) cache
    local E_f, E_df = m:get("E_f"), m:get("E_df")
    for i = 1, m.n - 1 do T.close(E_f[i] + E_df[i], 5e-4, 1e-3, 0) end
    local fit = assert(dfle.fit_slope_area(m))
    T.ok(fit.r2 > 0.9)
    T.eq(tostring(m):match("router = (%a+)"), "process")
end

tests["empirical: route works on any model and reports bulk properties"] = function()
    local rt = dfle.router.empirical{}
    local m = small_model(dfle.router.process{})
    local r = rt:route(m)
    T.eq(#r.h, m.n)
    T.eq(r.sum, nil) -- bulk routers have no time integral
    T.ok(r.runout_end >= 1)
end

return tests
