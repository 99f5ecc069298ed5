-- test_api.lua - the dfle Lua API: constructors, properties, methods,
-- files written, the loadable module, garbage collection and <close>.
local T = ...
local tests = {}

-- A small model (45 nodes) for tests that only need a working model.
local function small_model(opts)
    opts = opts or {}
    opts.channel = opts.channel or dfle.channel{ A_max = 2e5 }
    return dfle.model(opts)
end

-- The example of the issue, verbatim apart from the output paths.
tests["contract: the issue's example runs and its results are consistent"] = function()
    local csv = T.tmpname(".csv")
    local sa_png = T.tmpname(".png")
    local pr_png = T.tmpname(".png")

    local ch  = dfle.channel{ dx = 5, A_max = 8e6 }
    local fl  = dfle.fluvial.stochastic_threshold{ k_e = 5e-14 }
    local rt  = dfle.router.empirical{ M0 = 3000, gamma = 0.5, mu = 500, tau_y = 300 }
    local law = dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 }
    local m   = dfle.model{ channel = ch, U = 5e-4, fluvial = fl, router = rt, law = law }
    m:init_fluvial_steady()
    local r   = m:run_to_steady{ tol = 1e-3, max_time = 2e7 }
    T.eq(type(r.converged), "boolean")
    T.eq(r.converged, true, "converged")
    T.eq(r.reason, "steady")
    -- The default method finds the steady state directly: no time passes.
    T.eq(r.method, "direct")
    T.ok(r.time >= 0 and r.time <= 2e7, "run time " .. T.fmt(r.time))
    T.eq(math.type(r.steps), "integer")
    T.ok(r.steps >= 0, "steps")
    T.ok(r.rate_ratio <= 1e-3, "rate_ratio " .. T.fmt(r.rate_ratio))
    T.close(m.time, r.time, 1e-12)

    local r2 = m:run{ years = 1e5 }
    T.eq(r2.reason, "time")
    T.close(r2.time, 1e5, 1e-9)
    T.close(m.time, r.time + 1e5, 1e-9)

    local S = m:get("S")
    T.eq(#S, m.n)
    for _, name in ipairs{ "x", "A", "w", "z", "E_f", "E_df", "h", "tau" } do
        local v = m:get(name)
        T.eq(#v, m.n, "length of " .. name)
        for i = 1, #v do
            T.ok(v[i] == v[i] and v[i] ~= math.huge and v[i] ~= -math.huge,
                 name .. "[" .. i .. "] is not finite")
        end
    end

    T.eq(m:write_csv(csv), m, "write_csv returns the model")
    local tab = T.read_csv(csv)
    T.eq(tab.header, "x,A,w,z,S,E_f,E_df,dzdt,M,Q,h,v,t_p,tau,Theta")
    T.eq(tab.units.tau, "Pa"); T.eq(tab.units.x, "m"); T.eq(tab.units.S, "-")
    T.eq(#tab.rows, m.n, "CSV rows (one per node)")
    -- The S column of the CSV holds the same numbers as m:get("S").
    local col
    for k, name in ipairs(tab.names) do
        if name == "S" then col = k end
    end
    T.ok(col ~= nil, "CSV has an S column")
    local i = 0
    for _, row in ipairs(tab.rows) do
        i = i + 1
        local val = tonumber(row[col])
        T.close(val, S[i], 1e-9, 1e-300, "CSV S at node " .. i)
    end

    local f = dfle.fit_slope_area(m)
    for _, key in ipairs{ "S_df", "A_df", "a2", "r2", "S_max_minus_S_ch" } do
        T.eq(type(f[key]), "number", "fit." .. key)
    end
    T.ok(f.S_df > 0 and f.A_df > 0 and f.a2 > 0, "fit parameters positive")
    T.ok(f.r2 > 0.9 and f.r2 <= 1, "r2 " .. T.fmt(f.r2))
    T.ok(f.S_max_minus_S_ch >= 0, "S_max - S_ch >= 0")

    dfle.plot.slope_area(m, sa_png, f)
    dfle.plot.profile(m, pr_png)
    for _, p in ipairs{ sa_png, pr_png } do
        local data = assert(T.read_file(p))
        T.eq(data:sub(1, 4), "\137PNG", p .. " is a PNG")
    end

    local S19 = dfle.analytical_slope(rt, law, {U = 5e-4, A = 1e4})
    T.close(S19, 0.73834, 1e-4)
end

tests["fluvial.stochastic_threshold: Table G1 law matches the check values"] = function()
    local fl = dfle.fluvial.stochastic_threshold{ k_e = 5e-14 }
    T.close(fl.K, 2.4539e-10, 1e-4)
    T.close(fl.m_s, 1.4, 1e-4)
    T.close(fl.n_s, 2.3333, 1e-4)
    T.eq(fl.name, "stochastic_threshold")
    -- Eq. (26) at U = 5e-4 m/yr (doc/model.md, Check values).
    T.close(fl:steady_slope(5e-4, 1e6), 0.1270, 1e-3)
    T.close(fl:steady_slope(5e-4, 1e3), 8.015, 1e-3)
    -- E_f = K A^m S^n, and zero on a reverse slope.
    T.close(fl:rate(1e6, 0.1), fl.K * 1e6 ^ fl.m_s * 0.1 ^ fl.n_s, 1e-12)
    T.eq(fl:rate(1e6, -0.1), 0)
    -- The defaults are the same law; k_e scales K linearly.
    T.close(dfle.fluvial.stochastic_threshold{}.K, fl.K, 1e-12)
    T.close(dfle.fluvial.stochastic_threshold{ k_e = 1e-13 }.K, 2 * fl.K, 1e-9)
end

tests["fluvial.stochastic_threshold: overrides replace derived values"] = function()
    local fl = dfle.fluvial.stochastic_threshold{ K = 1e-6, m_s = 0.5, n_s = 1 }
    T.eq(fl.K, 1e-6)
    T.eq(fl.m_s, 0.5)
    T.eq(fl.n_s, 1)
    -- K = 0 is a valid override (no fluvial erosion), m_s = 0 too.
    T.eq(dfle.fluvial.stochastic_threshold{ K = 0 }.K, 0)
    T.eq(dfle.fluvial.stochastic_threshold{ m_s = 0 }.m_s, 0)
end

tests["fluvial.stream_power: K, m, n round-trip"] = function()
    local fl = dfle.fluvial.stream_power{ K = 2e-5, m = 0.5, n = 1 }
    T.eq(fl.K, 2e-5)
    T.eq(fl.m, 0.5)
    T.eq(fl.m_s, 0.5)
    T.eq(fl.n, 1)
    T.eq(fl.n_s, 1)
    T.eq(fl.name, "stream_power")
    T.close(fl:steady_slope(1e-4, 1e6), (1e-4 / 2e-5) * 1e6 ^ -0.5, 1e-12)
    -- a field that does not exist is an error naming the fields there are
    T.raises_here(function() return fl.nope end, "has no field 'nope'", "fields: ", "methods: ")
end

tests["channel: defaults are the paper's grid"] = function()
    local ch = dfle.channel{}
    T.eq(ch.n, 403)
    T.eq(#ch, 403)
    T.eq(ch.dx, 5)
    local x, A, w = ch:get("x"), ch:get("A"), ch:get("w")
    T.eq(#x, 403)
    T.eq(x[1], 0)
    T.close(x[403], 2010, 1e-12)
    T.close(ch.length, 2010, 1e-12)
    T.close(A[1], 1000, 1e-12)
    -- The outlet is the first node whose area reaches A_max = 8 km^2.
    T.ok(A[403] >= 8e6 and A[402] < 8e6, "outlet area " .. T.fmt(A[403]))
    T.eq(ch.A_max, A[403])
    for i = 1, #A, 50 do
        T.close(A[i], 1000 + 25 * x[i] ^ (5 / 3), 1e-12)
        T.close(w[i], 0.05 * A[i] ^ 0.3, 1e-12)
    end
    -- a field that does not exist is an error naming the fields there are
    T.raises_here(function() return ch.nope end, "has no field 'nope'", "fields: ", "methods: ")
end

tests["channel: dx, A_max and length set the grid"] = function()
    T.eq(dfle.channel{ dx = 20 }.n, 102)
    T.eq(dfle.channel{ length = 100, dx = 10 }.n, 11)
    local ch = dfle.channel{ A0 = 500, hack_coef = 10, hack_exp = 2, k_w = 0.1, b = 0.5, length = 50, dx = 5 }
    local A, w = ch:get("A"), ch:get("w")
    T.eq(ch.n, 11)
    T.close(A[11], 500 + 10 * 50 ^ 2, 1e-12)
    T.close(w[11], 0.1 * A[11] ^ 0.5, 1e-12)
end

tests["router.empirical: parameters read back"] = function()
    local rt = dfle.router.empirical{ M0 = 2000, gamma = 0.4, mu = 300, tau_y = 100 }
    T.eq(rt.name, "empirical")
    T.eq(rt.M0, 2000)
    T.eq(rt.gamma, 0.4)
    T.eq(rt.mu, 300)
    T.eq(rt.tau_y, 100)
    local p = rt:params()
    T.eq(p.M0, 2000)
    T.eq(p.tau_y, 100)
    -- Defaults (Fig. 9 plus the router constants).
    local d = dfle.router.empirical{}:params()
    T.eq(d.M0, 3000)
    T.eq(d.gamma, 0.5)
    T.eq(d.mu, 500)
    T.eq(d.tau_y, 300)
    T.eq(d.c1, 0.135)
    T.eq(d.c2, 0.78)
    T.eq(d.rho_b, 1800)
    T.eq(d.g, 9.81)
    -- a field that does not exist is an error naming the fields there are
    T.raises_here(function() return rt.nope end, "has no field 'nope'", "fields: ", "methods: ")
end

tests["law.power: parameters read back"] = function()
    local law = dfle.law.power{ k_df = 2e-4, alpha = 5, beta = 0.5 }
    T.eq(law.name, "power")
    T.eq(law.k_df, 2e-4)
    T.eq(law.alpha, 5)
    T.eq(law.beta, 0.5)
    local d = dfle.law.power{}:params()
    T.eq(d.k_df, 1e-4)
    T.eq(d.alpha, 6)
    T.eq(d.beta, 1)
    -- a field that does not exist is an error naming the fields there are
    T.raises_here(function() return law.nope end, "has no field 'nope'", "fields: ", "methods: ")
end

tests["model: properties and components"] = function()
    local ch = dfle.channel{ A_max = 2e5 }
    local fl = dfle.fluvial.stream_power{ K = 1e-6, m = 0.5, n = 1 }
    local rt = dfle.router.empirical{}
    local law = dfle.law.power{}
    local m = dfle.model{ channel = ch, fluvial = fl, router = rt, law = law, U = 2e-4 }
    T.eq(m.time, 0)
    T.eq(m.U, 2e-4)
    T.eq(m.n, ch.n)
    T.ok(rawequal(m.channel, ch), "m.channel is the channel given")
    T.ok(rawequal(m.fluvial, fl), "m.fluvial")
    T.ok(rawequal(m.router, rt), "m.router")
    T.ok(rawequal(m.law, law), "m.law")
    -- a field that does not exist is an error naming the fields there are
    T.raises_here(function() return m.nope end, "has no field 'nope'", "fields: ", "methods: ")
    -- Defaults: every component is built when omitted.
    local d = dfle.model{}
    T.eq(d.n, 403)
    T.eq(d.U, 5e-4)
    T.eq(d.fluvial.name, "stochastic_threshold")
    T.eq(d.router.name, "empirical")
    T.eq(d.law.name, "power")
    -- Switched-off processes read back as nil.
    local f = small_model{ router = false }
    T.eq(f.router, nil)
    T.eq(f.law, nil)
    T.ok(f.fluvial ~= nil)
    local g = small_model{ fluvial = false }
    T.eq(g.fluvial, nil)
    T.ok(g.router ~= nil and g.law ~= nil)
end

tests["model: fields() lists every field and get() returns n values"] = function()
    local m = small_model()
    local names = m:fields()
    local set = {}
    for _, name in ipairs(names) do set[name] = true end
    for _, name in ipairs{ "x", "A", "w", "z", "S", "E_f", "E_df", "h", "tau", "dzdt", "Theta" } do
        T.ok(set[name], "fields() lacks " .. name)
    end
    for _, name in ipairs(names) do
        T.eq(#m:get(name), m.n, "length of " .. name)
    end
    -- The model's geometry is its channel's.
    local A, cA = m:get("A"), m.channel:get("A")
    for i = 1, m.n do T.eq(A[i], cA[i]) end
end

tests["model: set_z round-trips and S follows from z"] = function()
    local m = small_model()
    local z = {}
    for i = 1, m.n do z[i] = (m.n - i) * 2 + (i % 3) * 0.25 end
    T.eq(m:set_z(z), m, "set_z returns the model")
    local got = m:get("z")
    for i = 1, m.n do T.eq(got[i], z[i]) end
    local S, dx = m:get("S"), m.channel.dx
    for i = 1, m.n - 1 do T.close(S[i], (z[i] - z[i + 1]) / dx, 1e-12, 1e-15) end
end

tests["model: set_U changes U, keeps z, returns the model"] = function()
    local m = small_model()
    local z0 = m:get("z")
    T.eq(m:set_U(1e-3), m)
    T.eq(m.U, 1e-3)
    local z1 = m:get("z")
    for i = 1, m.n do T.eq(z1[i], z0[i]) end
end

tests["model: init_fluvial_steady gives Eq. (26) slopes"] = function()
    local m = small_model{ U = 3e-4 }
    local z = {}
    for i = 1, m.n do z[i] = m.n - i end
    m:set_z(z)
    T.eq(m:init_fluvial_steady(), m)
    local S, A = m:get("S"), m:get("A")
    local fl = m.fluvial
    for i = 1, m.n - 1 do T.close(S[i], fl:steady_slope(3e-4, A[i]), 1e-9) end
    T.eq(m:get("z")[m.n], 0, "outlet at base level")
    -- With another law as argument, that law's Eq. (26).
    local other = dfle.fluvial.stream_power{ K = 1e-5, m = 0.5, n = 1 }
    m:init_fluvial_steady(other)
    S = m:get("S")
    for i = 1, m.n - 1 do T.close(S[i], other:steady_slope(3e-4, A[i]), 1e-9) end
end

tests["tostring: every object describes itself"] = function()
    T.match(tostring(dfle.channel{}), "^dfle%.channel%(n = 403")
    T.match(tostring(dfle.fluvial.stochastic_threshold{}), "^dfle%.fluvial%.stochastic_threshold%(K = 2%.4539e%-10")
    T.match(tostring(dfle.fluvial.stream_power{ K = 1, m = 0.5, n = 1 }), "^dfle%.fluvial%.stream_power%(")
    T.match(tostring(dfle.router.empirical{ tau_y = 123 }), "^dfle%.router%.empirical%(.*tau_y = 123")
    T.match(tostring(dfle.law.power{ alpha = 4 }), "^dfle%.law%.power%(.*alpha = 4")
    -- every parameter, in the component's order, each with its unit
    T.eq(tostring(dfle.law.excess_stress{ tau_c = 40 }),
         "dfle.law.excess_stress(k = 1e-09, tau_c = 40 Pa, p = 1.5)")
    local rt = tostring(dfle.router.process{ M0 = 250, frequency_scaling = true })
    T.match(rt, "^dfle%.router%.process%(M0 = 250 m%^3, eta = 60 Pa s, ")
    T.match(rt, ", t_max = 3600 s, max_steps = 1e%+06, gamma = 0, frequency_scaling = true%)$")
    T.match(tostring(small_model{ router = false }), "^dfle%.model%(n = 45.*router = off")
end

tests["version: a version string"] = function()
    T.eq(type(dfle.version), "string")
    T.match(dfle.version, "^%d+%.%d+")
end

tests["analytical_slope: Eq. (19) check value, scalar and array forms"] = function()
    local rt = dfle.router.empirical{ M0 = 3000, gamma = 0.5, mu = 500 }
    local law = dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 }
    local S = dfle.analytical_slope(rt, law, { U = 5e-4, A = 1e4 })
    T.close(S, 0.73834, 1e-4)
    local areas = { 1e3, 1e4, 1e5, 1e6 }
    local arr = dfle.analytical_slope(rt, law, { U = 5e-4, A = areas })
    T.eq(#arr, 4)
    for i, a in ipairs(areas) do
        T.close(arr[i], dfle.analytical_slope(rt, law, { U = 5e-4, A = a }), 1e-12)
    end
    T.eq(areas[1], 1e3, "the input array is left alone")
    -- N = -0.024706 (Eq. 20) is the log-log slope of Eq. (19).
    T.close(math.log(arr[4] / arr[1]) / math.log(1e3), -0.024706, 1e-4)
    -- S scales as U^(1/(alpha - beta/3)).
    T.close(dfle.analytical_slope(rt, law, { U = 1e-3, A = 1e4 }) / S, 2 ^ (1 / (6 - 1 / 3)), 1e-9)
end

tests["analytical_exponent: Eq. (20) check value"] = function()
    local rt = dfle.router.empirical{ M0 = 3000, gamma = 0.5, mu = 500 }
    local law = dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 }
    local N = dfle.analytical_exponent(rt, law, { U = 5e-4 })
    T.close(N, -0.024706, 1e-4)
    -- N does not depend on U; it is the exponent of Eq. (19) in A.
    T.close(dfle.analytical_exponent(rt, law, { U = 1e-3 }), N, 1e-12)
    local S1 = dfle.analytical_slope(rt, law, { U = 5e-4, A = 1e3 })
    local S2 = dfle.analytical_slope(rt, law, { U = 5e-4, A = 1e7 })
    T.close(math.log(S2 / S1) / math.log(1e4), N, 1e-9)
    -- Eq. (20) with gamma = 0.4, b = 0.3, c2 = 0.78, alpha = 5, beta = 2.
    local rt2 = dfle.router.empirical{ gamma = 0.4 }
    local law2 = dfle.law.power{ alpha = 5, beta = 2 }
    local want = (2 / 3 * (0.3 - 0.4 * 0.78) + 0.4 * (0.78 - 1)) / (5 - 2 / 3)
    T.close(dfle.analytical_exponent(rt2, law2, { U = 5e-4 }), want, 1e-9)
end

tests["require: build/dfle.so loads as a Lua module"] = function()
    local so = T.root .. "/build/dfle.so"
    local f = io.open(so, "rb")
    T.ok(f ~= nil, "no " .. so .. " (run make)")
    f:close()
    local saved_cpath = package.cpath
    local saved_loaded, saved_preload = package.loaded.dfle, package.preload.dfle
    package.cpath = T.root .. "/build/?.so;" .. package.cpath
    package.loaded.dfle, package.preload.dfle = nil, nil
    local ok, mod = pcall(require, "dfle")
    package.cpath = saved_cpath
    package.loaded.dfle, package.preload.dfle = saved_loaded, saved_preload
    T.ok(ok, tostring(mod))
    T.eq(type(mod), "table")
    T.ok(not rawequal(mod, saved_loaded), "require returned the built-in module, not dfle.so")
    T.eq(type(mod.model), "function")
    T.eq(mod.version, dfle.version)
    local m = mod.model{ channel = mod.channel{ A_max = 2e5 } }
    local r = m:run{ years = 500 }
    T.eq(r.reason, "time")
    T.close(m.time, 500, 1e-12)
    T.ok(rawequal(package.loaded.dfle, saved_loaded), "package.loaded.dfle restored")
end

tests["module: defaults still work with the global and package.loaded removed"] = function()
    local saved_global, saved_loaded = dfle, package.loaded.dfle
    local mod = dfle
    dfle, package.loaded.dfle = nil, nil
    local ok, m = pcall(mod.model, { channel = mod.channel{ A_max = 2e5 } })
    dfle, package.loaded.dfle = saved_global, saved_loaded
    T.ok(ok, tostring(m))
    T.eq(m.router.name, "empirical")
    T.eq(m.law.name, "power")
end

tests["gc: a model keeps its channel, laws and router alive"] = function()
    -- Built in a function so that no stale register holds a component.
    local function build()
        local m = dfle.model{
            channel = dfle.channel{ A_max = 2e5 },
            fluvial = dfle.fluvial.stochastic_threshold{},
            router = dfle.router.empirical{},
            law = dfle.law.power{},
        }
        -- Weak references show whether the components could be collected.
        return m, setmetatable({ m.channel, m.fluvial, m.router, m.law }, { __mode = "v" })
    end
    local m, weak = build()
    collectgarbage()
    collectgarbage()
    T.eq(#weak, 4, "components survived")
    local function use(model)
        local r = model:run{ years = 2000 }
        T.eq(r.reason, "time")
        T.eq(#model:get("S"), model.channel.n)
        T.match(tostring(model.router), "^dfle%.router")
    end
    use(m)
    -- Once the model goes, so do they.
    m = nil
    collectgarbage()
    collectgarbage()
    T.eq(next(weak), nil, "components collected after the model")
end

tests["close: <close> frees a model; using it afterwards raises"] = function()
    local outer = small_model()
    do
        local m <close> = outer
        T.eq(m:run{ years = 100 }.reason, "time")
    end
    T.errors_with(function() return outer:get("S") end, "closed")
    T.errors_with(function() return outer:run{ years = 1 } end, "closed")
    T.errors_with(function() return outer.time end, "closed")
    T.errors_with(function() return dfle.fit_slope_area(outer) end, "closed")
    -- Closing twice (and the later __gc) is harmless.
    do local again <close> = outer end
    collectgarbage()
end

tests["fit_slope_area: a model's fit carries its bins"] = function()
    local m = small_model()
    m:run_to_steady{}
    local f = assert(dfle.fit_slope_area(m, { nbins = 20 }))
    T.eq(type(f.bins), "table")
    local b = f.bins
    T.ok(#b.A >= 4 and #b.A <= 20, "bins kept " .. #b.A)
    T.eq(#b.S, #b.A)
    T.eq(#b.count, #b.A)
    local total = 0
    for i = 1, #b.count do
        total = total + b.count[i]
        T.ok(b.count[i] > 0, "kept bins are non-empty")
        if i > 1 then T.ok(b.A[i] > b.A[i - 1], "bins ascend in area") end
    end
    -- Every node above the outlet is in a bin.
    T.eq(total, m.n - 1)
    T.eq(f.n_points, #b.A)
    T.eq(b.n_empty + #b.A, 20)
end

tests["plot.xy: writes a PNG and an SVG"] = function()
    for _, ext in ipairs{ ".png", ".svg" } do
        local p = T.tmpname(ext)
        dfle.plot.xy{ path = p, title = "t", xlabel = "x", ylabel = "y", logx = true, logy = true,
                      series = { { x = { 1, 2, 3 }, y = { 1, 4, 9 }, label = "sq", lines = true },
                                 { x = { 1, 3 }, y = { 2, 2 } } } }
        local data = assert(T.read_file(p))
        if ext == ".png" then
            T.eq(data:sub(1, 4), "\137PNG")
        else
            T.has(data, "<svg")
        end
    end
end

tests["plot.profile and slope_area: options table accepted"] = function()
    local m = small_model()
    local p1, p2 = T.tmpname(".png"), T.tmpname(".png")
    dfle.plot.profile(m, p1, { title = "profile" })
    dfle.plot.slope_area(m, p2, nil, { title = "sa", nbins = 10 })
    T.eq(assert(T.read_file(p1)):sub(1, 4), "\137PNG")
    T.eq(assert(T.read_file(p2)):sub(1, 4), "\137PNG")
end

tests["plot.xy: a colour value per point, checked against the points"] = function()
    local x, y, c = {}, {}, {}
    for i = 1, 30 do x[i], y[i], c[i] = i, i * i, 10 ^ (i / 10) end
    local png = T.tmpname(".png")
    dfle.plot.xy{ path = png, series = { { x = x, y = y, color = c } }, clabel = "c", logc = true }
    T.eq(assert(T.read_file(png)):sub(1, 4), "\137PNG")
    T.raises_here(function() return dfle.plot.xy{ path = png, series = { { x = x, y = y, color = { 1 } } } } end,
                  "series[1] has 30 points but 1 colour values")
    T.raises_here(function() return dfle.plot.xy{ path = png, series = { { x = x, y = y } }, logc = 1 } end,
                  "'logc' must be a boolean")
end

tests["channel:params: the options given, which rebuild the same channel"] = function()
    local ch = dfle.channel{ dx = 10, A0 = 2000, hack_coef = 30, hack_exp = 1.6, k_w = 0.07,
                             b = 0.4, A_max = 3e6 }
    local p = ch:params()
    T.eq(p.dx, 10); T.eq(p.A0, 2000); T.eq(p.hack_coef, 30); T.eq(p.hack_exp, 1.6)
    T.eq(p.k_w, 0.07); T.eq(p.b, 0.4)
    T.eq(p.A_max, 3e6, "A_max as asked, not the outlet's area")
    T.ok(ch.A_max > 3e6, "the outlet's area passes A_max")
    T.eq(p.length, 0)
    local again = dfle.channel(p)
    T.eq(again.n, ch.n)
    local A, B = ch:get("w"), again:get("w")
    for i = 1, ch.n do T.eq(B[i], A[i], "w[" .. i .. "]") end
    p.dx = 99 -- a copy: the channel keeps its own
    T.eq(ch:params().dx, 10)
    -- a geometry given as arrays or functions has no formula to list
    local arr = dfle.channel{ dx = 4, area = { 1e3, 2e3, 4e3 } }
    local q = arr:params()
    T.eq(q.dx, 4)
    T.eq(q.A0, nil, "no Hack parameters for an area array")
    T.eq(dfle.channel{ width = function(A) return 1 end, A_max = 1e5 }:params().k_w, nil)
end

tests["fluvial:params: Table G1 and the law they give; stream power's K, m, n"] = function()
    local fl = dfle.fluvial.stochastic_threshold{ k_e = 6e-14, R_c = 0.3 }
    local p = fl:params()
    T.eq(p.k_e, 6e-14); T.eq(p.R_c, 0.3); T.eq(p.rho_s, 2600); T.eq(p.tau_c_coef, 0.045)
    T.eq(p.K, fl.K); T.eq(p.m_s, fl.m_s); T.eq(p.n_s, fl.n_s)
    -- the list rebuilds the same law (K, m_s, n_s as overrides)
    local again = dfle.fluvial.stochastic_threshold(p)
    T.eq(again.K, fl.K); T.eq(again.n_s, fl.n_s)
    -- an override shows as the value the law runs
    T.eq(dfle.fluvial.stochastic_threshold{ n_s = 2 }:params().n_s, 2)
    local sp = dfle.fluvial.stream_power{ K = 1e-6, m = 0.5, n = 1 }:params()
    T.eq(sp.K, 1e-6); T.eq(sp.m, 0.5); T.eq(sp.n, 1); T.eq(sp.k_e, nil)
    T.eq(dfle.fluvial.stream_power(sp).K, 1e-6)
end

tests["model:params: U, cfl, dt_max and every component's params"] = function()
    local ch = dfle.channel{ A_max = 2e5 }
    local rt = dfle.router.empirical{ tau_y = 100 }
    local m = dfle.model{ channel = ch, router = rt, U = 2e-4, cfl = 0.3, dt_max = 50,
                          fluvial = dfle.fluvial.stream_power{ K = 1e-6, m = 0.5, n = 1 } }
    local p = m:params()
    T.eq(p.U, 2e-4); T.eq(p.cfl, 0.3); T.eq(p.dt_max, 50)
    T.eq(p.router.tau_y, 100)
    T.eq(p.law.alpha, 6, "the default law's")
    T.eq(p.fluvial.K, 1e-6)
    T.eq(p.channel.A_max, 2e5)
    m:set_U(4e-4)
    T.eq(m:params().U, 4e-4, "U now")
    local off = dfle.model{ channel = ch, fluvial = false, router = false }:params()
    T.eq(off.fluvial, false); T.eq(off.router, false); T.eq(off.law, false)
    -- a law written in Lua lists its own params
    local lua_law = dfle.law.define{ params = { k = 2 }, rate = function(c, q) return 0 end }
    T.eq(dfle.model{ channel = ch, law = lua_law }:params().law.k, 2)
end

return tests
