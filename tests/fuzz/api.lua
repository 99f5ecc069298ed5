-- api.lua - what the fuzzer calls: the public Lua API found by walking
-- the dfle table and the method tables of every object type, a template
-- of sensible arguments for each function and method it knows (so that
-- mutated calls get past the first check and reach the engine), and the
-- pool of live objects calls draw on.
--
-- A function or method without a template is still called, with
-- arguments drawn from anything at all; the driver lists such names
-- (`list`), so a new function gets a template in time.
--
-- Budgets: every key that sets how much work a call does (time steps,
-- years, samples, flow steps, slices, bootstrap replicates) is listed in
-- the template's `budget`, and the mutator gives such a key only values
-- that are invalid (rejected at once), never a valid large one.  So
-- every call stays small and a slow call is a finding, not bad luck.
local H = require("hostile")
local A = {}

---------------------------------------------------------------------------
-- Discovery.
---------------------------------------------------------------------------

-- Every function reachable from the dfle table: { path = "dfle.plot.xy", fn = f }.
function A.functions(mod)
    local out, seen = {}, {}
    local function walk(t, prefix)
        local keys = {}
        for k in pairs(t) do
            if type(k) == "string" then keys[#keys + 1] = k end
        end
        table.sort(keys)
        for _, k in ipairs(keys) do
            local v, path = t[k], prefix .. "." .. k
            if type(v) == "function" then
                out[#out + 1] = { path = path, fn = v }
            elseif type(v) == "table" and not seen[v] then
                seen[v] = true
                walk(v, path)
            end
        end
    end
    walk(mod, "dfle")
    return out
end

-- The methods table of an object: the first upvalue of its metatable's
-- __index (lua_type.c), or __index itself when that is a table.
function A.methods(obj)
    local mt = debug.getmetatable(obj)
    if type(mt) ~= "table" then return nil end
    local idx = rawget(mt, "__index")
    if type(idx) == "table" then return idx end
    if type(idx) == "function" then
        for i = 1, 8 do
            local name, v = debug.getupvalue(idx, i)
            if name == nil then break end
            if type(v) == "table" then return v end
        end
    end
    return nil
end

-- The type name of a value as the fuzzer keys its pool and templates:
-- the metatable's __name ("dfle.model") or the Lua type.
function A.typename(v)
    local mt = debug.getmetatable(v)
    if type(mt) == "table" and type(rawget(mt, "__name")) == "string" then
        return rawget(mt, "__name")
    end
    return type(v)
end

---------------------------------------------------------------------------
-- Helpers for templates.  S is the driver's state: S.r (generator),
-- S:get(kind) (a live object of a kind, made if need be), S.cb(kind,
-- valid) (a callback, maybe hostile), S.path(kind) (a file name in the
-- scratch directory), S.inputs (damaged input files).
---------------------------------------------------------------------------
local function pack(...) return table.pack(...) end

local function small_channel(S)
    local r = S.r
    local k = r.int(6)
    if k == 1 then return { dx = r.pick{ 20, 50 }, length = r.pick{ 200, 500 } } end
    if k == 2 then
        local a = {}
        for i = 1, r.range(3, 12) do a[i] = 1000 + 2000 * (i - 1)^1.5 end
        return { dx = 50, area = a }
    end
    if k == 3 then
        return { dx = 50, A_max = 5e4,
                 area = S.cb("area", function(x) return 1000 + 25 * x^(5 / 3) end),
                 width = S.cb("width", function(A) return 0.05 * A^0.3 end) }
    end
    return { dx = r.pick{ 20, 50 }, A_max = r.pick{ 2e4, 5e4, 2e5 } }
end
A.small_channel = small_channel

local function valid_U(t) return 5e-4 end

local function lua_law(S, bulk)
    local r = S.r
    local o = { name = r.pick{ "lua", "fz", "x" }, params = { k = 1e-4, alpha = 6 },
                compile = r.chance(0.5) }
    if r.chance(0.5) then
        o.factor = S.cb("factor", function(c, p) return c.t_p * c.h * c.Theta end)
        o.rate = S.cb("rate", function(c, p) return p.k * c.S^p.alpha * c.F end)
    else
        o.rate = S.cb("rate", function(c, p) return p.k * c.S^p.alpha * c.F end)
    end
    if not bulk then
        o.integrand = r.chance(0.5) and { h = 1 }
            or S.cb("integrand", function(h, v, lambda, p) return h end)
    end
    if r.chance(0.3) then o.frequency = S.cb("frequency", function(A, p) return 1 end) end
    return o
end

local function lua_router(S)
    return {
        name = "fzr",
        params = { M0 = 3000, gamma = 0.5, mu = 500, tau_y = 300, c1 = 0.135, c2 = 0.78,
                   rho_b = 1800, g = 9.81 },
        flow = S.cb("flow", function(c, p)
            local M = p.M0 * (1e-6 * c.A)^p.gamma
            local Q = p.c1 * M^p.c2
            local h = (3 * p.mu * Q / (p.rho_b * p.g * c.w) / c.S)^(1 / 3)
            local tau = p.rho_b * p.g * (c.w * h / (c.w + 2 * h)) * c.S / math.sqrt(1 + c.S^2)
            c.M, c.Q, c.h, c.v, c.t_p = M, Q, h, Q / (c.w * h), M / Q
            c.tau, c.Theta = tau, 1 - p.tau_y / tau
            return tau >= p.tau_y
        end),
    }
end

local function process_router(S)
    -- max_steps and t_max bound one routing; n_ghost its size.
    return { M0 = S.r.pick{ 100, 200 }, max_steps = S.r.pick{ 100, 300 }, t_max = 300,
             n_ghost = S.r.pick{ 2, 5, 20 } }
end

-- Options of a model: components that work together, small.
local function model_opts(S)
    local r = S.r
    local o = { channel = S:get("dfle.channel") }
    local k = r.int(10)
    if k <= 4 then
        o.router = S:get("router.empirical")
        o.law = S:get(r.pick{ "law.power", "law.inertial", "law.excess_stress", "law.lua_bulk" })
    elseif k <= 6 then
        o.router = S:get("router.process")
        o.law = S:get(r.pick{ "law.power", "law.inertial", "law.lua" })
    elseif k <= 8 then
        o.router = S:get("router.lua")
        o.law = S:get(r.pick{ "law.power", "law.lua_bulk", "law.excess_stress" })
    else
        o.router = false
    end
    if r.chance(0.7) then o.fluvial = S:get(r.pick{ "fluvial.st", "fluvial.sp" })
    elseif r.chance(0.3) then o.fluvial = false end
    if r.chance(0.3) then o.U = S.cb("U", valid_U) else o.U = r.pick{ 5e-4, 1e-3, 2e-4 } end
    if r.chance(0.2) then o.cfl = 0.5 end
    if r.chance(0.2) then o.dt_max = r.pick{ 10, 100, 1000 } end
    return o
end

local FIELDS = { "x", "A", "w", "z", "S", "E_f", "E_df", "dzdt", "M", "Q", "h", "v", "t_p",
                 "tau", "Theta" }
A.FIELDS = FIELDS

local function run_opts(S, steady)
    local r = S.r
    local o = { max_steps = r.pick{ 5, 20, 50 }, progress = false }
    if steady then
        o.method = r.pick{ "direct", "implicit", "explicit", "auto", "direct" }
        if r.chance(0.5) then o.tol = r.pick{ 1e-3, 1e-2 } end
        o.max_time = r.pick{ 1e3, 1e5 }
        if r.chance(0.2) then o.direct_tol = 2e-3 end
    else
        o.years = r.pick{ 1, 10, 100, 1000 }
        o.method = r.pick{ "explicit", "implicit" }
        if r.chance(0.3) then o.rtol = 1e-2 end
        if r.chance(0.3) then o.record = { 0, o.years / 2, o.years } end
        if o.record and r.chance(0.3) then o.netcdf = S.path("nc") end
    end
    return o
end

local function xy(S, n)
    local x, y = {}, {}
    for i = 1, n do x[i] = 1e3 * 1.3^i; y[i] = 0.8 / (1 + (x[i] / 3e4)^0.9) end
    return x, y
end

local function sa_source(S)
    local r = S.r
    local k = r.int(4)
    if k == 1 then local A_, S_ = xy(S, r.pick{ 3, 20, 60 }); return { A = A_, S = S_ } end
    if k == 2 and S:has("dfle.profile") then return S:get("dfle.profile") end
    return S:get("dfle.model")
end

-- The ensemble every damaged ensemble file claims to be (inputs.lua writes
-- the good file with it): small, fast, one parameter.
function A.ensemble_spec(S, out)
    return {
        params = { k_df = { 5e-5, 1e-3 } }, n = 3, seed = 1, out = out, workers = 1,
        build = S.cb("build", function(p)
            return dfle.model{ channel = dfle.channel{ dx = 50, A_max = 5e4 },
                               law = dfle.law.power{ k_df = p.k_df } }
        end),
        outputs = { "S_df", "A_df" },
        run = { method = "direct", max_steps = 20 },
    }
end

local function lhs_params(S)
    local r = S.r
    local p = { k_df = { 5e-5, 1e-3, log = r.chance(0.5) } }
    if r.chance(0.5) then p.U = { 1e-4, 1e-3 } end
    if r.chance(0.3) then p.alpha = { values = { 2, 4, 6 } } end
    if r.chance(0.2) then p.name = { values = { "a", "b" } } end
    return p
end

local function pawn_data(S, n)
    local d = { x1 = {}, x2 = {}, y = {} }
    local r = S.r
    for i = 1, n do
        d.x1[i] = r.float(); d.x2[i] = r.float()
        d.y[i] = d.x1[i] + 0.1 * d.x2[i]^2
    end
    return d
end

local function point_in(dem, r)
    local e = dem.extent
    if type(e) ~= "table" then return { 0, 0 } end
    return { e.E_min + r.float() * (e.E_max - e.E_min), e.N_min + r.float() * (e.N_max - e.N_min) }
end

---------------------------------------------------------------------------
-- Templates: name -> function(S, self) returning args (table.pack) and
-- budget ({ [i] = { key = true } }: keys of argument i that bound work).
-- Methods are named "<type>:<method>" with the type's __name.
---------------------------------------------------------------------------
local T = {}
A.templates = T

T["dfle.channel"] = function(S) return pack(small_channel(S)) end
T["dfle.fluvial.stochastic_threshold"] = function(S)
    return pack(S.r.chance(0.5) and {} or { k_e = 5e-14, K = S.r.pick{ 0, 1e-6 } })
end
T["dfle.fluvial.stream_power"] = function(S) return pack({ K = 1e-5, m = 0.5, n = 1 }) end
T["dfle.router.empirical"] = function(S) return pack(S.r.chance(0.5) and {} or { tau_y = 0 }) end
T["dfle.router.process"] = function(S)
    return pack(process_router(S)), { [1] = { max_steps = true, t_max = true, n_ghost = true } }
end
T["dfle.router.define"] = function(S) return pack(lua_router(S)) end
T["dfle.law.power"] = function(S) return pack({ k_df = 1e-4, alpha = 6, beta = 1 }) end
T["dfle.law.inertial"] = function(S) return pack({}) end
T["dfle.law.excess_stress"] = function(S) return pack({}) end
T["dfle.law.define"] = function(S) return pack(lua_law(S, S.r.chance(0.5))) end
T["dfle.model"] = function(S) return pack(model_opts(S)) end

T["dfle.fit_slope_area"] = function(S)
    return pack(sa_source(S), S.r.chance(0.5) and { nbins = S.r.pick{ 5, 20, 100 } } or nil)
end
T["dfle.analytical_slope"] = function(S)
    local A_ = S.r.chance(0.5) and 1e4 or { 1e3, 1e5, 1e6 }
    return pack(S:get("router.empirical"), S:get("law.power"), { A = A_, U = 5e-4 })
end
T["dfle.analytical_exponent"] = function(S)
    return pack(S:get("router.empirical"), S:get("law.power"), {})
end

-- Plots start gnuplot: few of them (weight in the driver), small data.
T["dfle.plot.slope_area"] = function(S)
    return pack(sa_source(S), S.path("png"), S.r.chance(0.3) and false or nil,
                { title = "t", nbins = 10 }), { [4] = { nbins = true } }
end
T["dfle.plot.profile"] = function(S) return pack(S:get("dfle.model"), S.path("svg"), { title = "p" }) end
T["dfle.plot.flow"] = function(S)
    local m = S:get("dfle.model.process")
    local ok, res = pcall(function() return m.router:route(m, { snapshots = { 1, 10 } }) end)
    return pack(m, ok and res or {}, S.path("png"), { exaggeration = 10 })
end
T["dfle.plot.xy"] = function(S)
    local x, y = xy(S, 10)
    return pack({ path = S.path("png"), series = { { x = x, y = y, label = "a", lines = true,
                  color = S.r.chance(0.3) and x or nil } }, logx = true, logy = S.r.chance(0.5),
                  title = "xy" })
end

T["dfle.plot.panels"] = function(S)
    local x, y = xy(S, 10)
    return pack({ path = S.path("png"), xlabel = "x", title = "panels",
                  panels = { { series = { { x = x, y = y, lines = true } }, ylabel = "a" },
                             { series = { { x = x, y = y, style = "linespoints" } },
                               ylog = S.r.chance(0.5), weight = 0.5 } } })
end
T["dfle.plot.sheet"] = function(S)
    local p, x, y = S.path("png"), xy(S, 5)
    pcall(dfle.plot.xy, { path = p, series = { { x = x, y = y } } })
    return pack({ path = S.path("png"), images = { p, p }, titles = { "a", "b" }, columns = 2 })
end
T["dfle.plot.label"] = function(S) return pack(S.r.pick{ "A", "S", "U", "k_df", "x", "h", "t" }) end
T["dfle.plot.number"] = function(S)
    return pack(S.r.pick{ 0, 1.42e5, -3e-7, 12.5, 1 / 0, -1 / 0, 0 / 0, 1e308, 5e-324 })
end

T["dfle.dem.read"] = function(S)
    local f = S.inputs.dem(S)
    local o = nil
    if S.r.chance(0.3) then o = { nodata = -9999, crs = S.r.pick{ "EPSG:32611", "EPSG:4326" } } end
    return pack(f, o)
end

T["dfle.lhs"] = function(S)
    return pack({ n = S.r.pick{ 1, 5, 20 }, seed = S.r.range(0, 10), params = lhs_params(S),
                  centered = S.r.chance(0.2) }), { [1] = { n = true } }
end
T["dfle.pawn"] = function(S)
    local r = S.r
    local o = { inputs = { "x1", "x2" }, output = "y", S = r.pick{ 2, 5, 10 } }
    if r.chance(0.4) then
        o.file = S.inputs.pawn_csv(S)
        if r.chance(0.5) then o.drop_nan = true end
    elseif r.chance(0.3) and S:has("ensemble") then
        return pack(S:get("ensemble"), { outputs = { "S_df" }, S = 2 }), { [2] = { S = true } }
    else
        o.data = pawn_data(S, r.pick{ 2, 10, 50 })
    end
    if r.chance(0.2) then o.bootstrap = r.pick{ 2, 5 }; o.conf = 0.9; o.seed = 1 end
    return pack(o), { [1] = { S = true, bootstrap = true } }
end
T["dfle.ensemble"] = function(S)
    local o = A.ensemble_spec(S, S.inputs.ensemble_csv(S))
    local r = S.r
    if r.chance(0.3) then
        o.measure = S.cb("measure", function(m, fit, p, run) return { extra = 1 } end)
        o.outputs = { "S_df", "extra" }
        o.out = S.path("csv") -- another ensemble: a new file
    end
    if r.chance(0.2) then o.resume = false end
    if r.chance(0.2) then o.limit = 1 end
    if r.chance(0.2) then o.fit = { nbins = 10 } end
    return pack(o), { [1] = { n = true, limit = true, run = true } }
end
T["dfle.gather"] = function(S)
    local r = S.r
    if r.chance(0.3) then return pack({ out = S.path("csv"), shards = r.pick{ 1, 2, 3 } }),
                                 { [1] = { shards = true } } end
    local files = {}
    for i = 1, r.pick{ 1, 2, 3 } do files[i] = S.inputs.ensemble_csv(S) end
    return pack({ out = S.path("csv"), files = files })
end
T["dfle.worker"] = function(S) return pack() end

-- Methods.
T["dfle.channel:get"] = function(S) return pack(S.r.pick{ "x", "A", "w" }) end
T["dfle.fluvial:rate"] = function(S) return pack(S.r.pick{ 1e4, 1e6 }, S.r.pick{ 0.1, 0.5 }) end
T["dfle.fluvial:steady_slope"] = function(S) return pack(5e-4, S.r.pick{ 1e4, 1e6 }) end
T["dfle.router:params"] = function(S) return pack() end
T["dfle.router:route"] = function(S, self)
    local m = S:get("dfle.model")
    local o = nil
    if S.r.chance(0.4) then o = { snapshots = { 0.5, 5, 50 } } end
    return pack(m, o)
end
T["dfle.law:params"] = function(S) return pack() end
T["dfle.law:compiled"] = function(S) return pack() end
T["dfle.model:run_to_steady"] = function(S)
    return pack(run_opts(S, true)), { [1] = { max_steps = true, max_time = true } }
end
T["dfle.model:run"] = function(S)
    return pack(run_opts(S, false)), { [1] = { max_steps = true, years = true, record = true } }
end
T["dfle.model:get"] = function(S) return pack(S.r.pick(FIELDS)) end
T["dfle.model:fields"] = function(S) return pack() end
T["dfle.model:set_z"] = function(S, self)
    local ok, n = pcall(function() return self.n end)
    local z = {}
    for i = 1, (ok and math.type(n) == "integer" and n or 5) do z[i] = 10 * (100 - i) end
    return pack(z)
end
T["dfle.model:set_U"] = function(S) return pack(S.r.pick{ 5e-4, 1e-3 }) end
-- The third value, "write", says the call must not fail for the file's
-- sake when it is not mutated and the name is legal (S.legal).
T["dfle.model:write_csv"] = function(S)
    local p = S.path("csv")
    return pack(p), nil, S.legal and "write" or nil
end
T["dfle.model:init_fluvial_steady"] = function(S)
    return pack(S.r.chance(0.5) and S:get("fluvial.st") or nil)
end
T["dfle.dem:fill"] = function(S) return pack() end
T["dfle.dem:flow"] = function(S) return pack() end
T["dfle.dem:at"] = function(S, self)
    local ok, p = pcall(point_in, self, S.r)
    p = ok and p or { 0, 0 }
    return pack(p[1], p[2])
end
T["dfle.dem:profile"] = function(S, self)
    local ok, p = pcall(point_in, self, S.r)
    p = ok and p or { 0, 0 }
    if S.r.chance(0.5) then return pack({ outlet = p, A_min = 0 }) end
    return pack({ head = p, A_max = 1e9 })
end
T["dfle.dem:network"] = function(S, self)
    local ok, a = pcall(function() return self.dx * self.dy end)
    return pack({ A_min = ok and a or 100 })
end
T["dfle.profile:get"] = function(S)
    return pack(S.r.pick{ "E", "N", "x", "d", "z", "A", "S", "receiver" })
end
T["dfle.profile:slope_area"] = function(S) return pack() end
T["dfle.profile:write_csv"] = function(S)
    local p = S.path("csv")
    return pack(p), nil, S.legal and "write" or nil
end
T["dfle.profile:channel"] = function(S) return pack({ dx = S.r.pick{ 5, 50 } }) end
T["dfle.profile:write_gpkg"] = function(S)
    local p = S.path("gpkg")
    return pack(p), nil, S.legal and "write" or nil
end
T["dfle.dem:resample"] = function(S)
    return pack({ dx = S.r.pick{ 45, 90, 200 },
                  method = S.r.chance(0.5) and S.r.pick{ "nearest", "bilinear", "average" } or nil }),
           { [1] = { dx = true } }
end
T["dfle.dem:crop"] = function(S, self)
    local ok, p = pcall(point_in, self, S.r)
    if not ok or S.r.chance(0.3) then return pack({ data = true }) end
    return pack({ E_min = p[1] - 100, N_max = p[2] + 100, E_max = p[1] + 100, N_min = p[2] - 100 })
end
T["dfle.dem:write_gpkg"] = function(S, self)
    local ok, p = pcall(point_in, self, S.r)
    return pack(S.path("gpkg"), { outlet = ok and p or { 0, 0 }, A_min = S.r.chance(0.5) and 1e4 or nil })
end

T["dfle.channel:params"] = function(S) return pack() end
T["dfle.fluvial:params"] = function(S) return pack() end
T["dfle.model:params"] = function(S) return pack() end
T["dfle.model:write_record"] = function(S)
    local p = S.path("json")
    return pack(p), nil, S.legal and "write" or nil
end
T["dfle.profile:main_stem"] = function(S) return pack() end
T["dfle.dem:write_geotiff"] = function(S)
    return pack(S.path("tif"), S.r.chance(0.5) and { layers = { S.r.pick{ "z", "area", "d8", "slope", "channels" } } } or nil)
end

-- Outputs of a script's own: tables, fits, directories.
local function a_fit(S)
    local ok, fit = pcall(dfle.fit_slope_area, sa_source(S), S.r.chance(0.5) and { residuals = "log" } or nil)
    if ok and type(fit) == "table" then return fit end
    return { S_df = 0.8, A_df = 3e4, a2 = 0.9 } -- a fit made by hand
end
T["dfle.write_fit"] = function(S)
    return pack(a_fit(S), S.path("csv"), S.r.chance(0.3) and { record = false } or nil)
end
T["dfle.write_bins"] = function(S)
    return pack(a_fit(S), S.path("csv"), S.r.chance(0.3) and { record = false } or nil)
end
T["dfle.write_csv"] = function(S)
    local r = S.r
    local o = { columns = { "U", "S_df", "note" }, units = { U = "m/yr", S_df = "-" },
                about = "a table", record = r.chance(0.5) }
    if r.chance(0.5) then
        o.rows = { { U = 1e-4, S_df = 0.8, note = "a" }, { U = 2e-4, S_df = 0.7, note = "b,c" } }
    else
        o.data = { U = { 1e-4, 2e-4 }, S_df = { 0.8, 0.7 }, note = { "a", true } }
    end
    if r.chance(0.3) then o.params = { tol = 1e-3, law = { k_df = 1e-4 } } end
    if r.chance(0.2) and S:has("dfle.model") then o.params = { model = S:get("dfle.model") } end
    return pack(S.path("csv"), o)
end
T["dfle.mkdir"] = function(S) return pack(S.path("d")) end
-- (the script's own arg holds seed=N ...: a positional argument, refused
-- unless the options take one; --help would end the process)
T["dfle.args"] = function(S)
    local out = S.r.chance(0.5)
    return pack({ usage = "fuzz", about = "a", flags = { quick = "q" },
                  options = { data = { "DIR", "d", default = "x" } }, output = out,
                  arg = S.r.pick{ {}, { "--quick" }, { "--data", "in" }, { "--data=in", "--quick" },
                                  { "--qiuck" }, { out and S.path("d") or "x" } } })
end

-- Landscapes: a few cells, a few steps.
local function landscape_opts(S)
    local r = S.r
    local o = { nx = r.pick{ 3, 6, 8 }, ny = r.pick{ 3, 5 }, dx = r.pick{ 10, 30 } }
    if r.chance(0.3) then o.noise = { amplitude = 1, seed = r.range(1, 5) } end
    if r.chance(0.2) then
        o.z = S.cb("z", function(x, y) return 0.01 * x + 0.02 * y end)
    end
    if r.chance(0.2) then o.edges = r.pick{ "closed", "open", { north = "closed" } } end
    if r.chance(0.2) then o.hillslope = r.pick{ "threshold", "diffusion", "uplift" } end
    if r.chance(0.2) then o.combine = r.pick{ "any", "count" } end
    if r.chance(0.1) then o.combine = S.cb("combine", function(count, A) return 1 end) end
    if r.chance(0.2) then o.U = S.cb("U", function(x, y) return 5e-4 end) end
    if r.chance(0.2) then o.router = false end
    if r.chance(0.1) then o.crs = r.pick{ "EPSG:32611", "EPSG:3310" } end
    return o
end
T["dfle.landscape"] = function(S)
    return pack(landscape_opts(S)), { [1] = { nx = true, ny = true } }
end
T["dfle.landscape:run"] = function(S)
    local r = S.r
    return pack({ years = r.pick{ 100, 1000 }, dt = 500, max_steps = 5, progress = false,
                  method = r.pick{ "implicit", "explicit" },
                  record = r.chance(0.3) and { 0, 500 } or nil,
                  netcdf = r.chance(0.2) and S.path("nc") or nil,
                  float32 = r.chance(0.1) or nil }),
           { [1] = { years = true, max_steps = true, dt = true, record = true } }
end
T["dfle.landscape:run_to_steady"] = function(S)
    return pack({ max_steps = 5, max_time = 1e4, progress = false,
                  method = S.r.pick{ "direct", "implicit" } }),
           { [1] = { max_steps = true, max_time = true } }
end
T["dfle.landscape:step"] = function(S) return pack(S.r.pick{ 10, 100, 1000 }) end
T["dfle.landscape:get"] = function(S)
    return pack(S.r.pick{ "z", "A", "S", "E_f", "E_df", "reach", "channel", "dzdt", "U", "base" })
end
T["dfle.landscape:fields"] = function(S) return pack() end
T["dfle.landscape:set_z"] = function(S, self)
    local ok, n = pcall(function() return self.n end)
    local z = {}
    for i = 1, (ok and math.type(n) == "integer" and n <= 1000 and n or 9) do z[i] = 100 - i end
    return pack(z)
end
T["dfle.landscape:write_geotiff"] = function(S)
    return pack(S.path("tif"), S.r.chance(0.5) and { "z", "A" } or nil)
end
T["dfle.landscape:plot"] = function(S) return pack(S.path("png"), { title = "l" }) end
T["dfle.landscape:slope_area"] = function(S) return pack() end
T["dfle.landscape:dem"] = function(S) return pack() end

-- Inversions: a handful of walkers and steps on a tiny model.
local function invert_opts(S)
    local r = S.r
    local ch = { dx = 50, A_max = 5e4 }
    local A_, S_ = {}, {}
    for i = 1, 6 do A_[i] = 2e3 * 1.6^i; S_[i] = 0.8 / (1 + (A_[i] / 3e4)^0.9) end
    local o = {
        data = { A = A_, S = S_ }, channel = dfle.channel(ch),
        build = S.cb("build", function(p, channel)
            return dfle.model{ channel = channel, U = p.U, law = dfle.law.power{} }
        end),
        params = { U = { 1e-4, 1e-3, log = r.chance(0.5) } },
        walkers = r.pick{ 4, 6 }, steps = r.pick{ 0, 3, 6 }, burn = 1, seed = r.range(0, 9),
        run = { max_steps = 20, max_time = 1e5 }, lsq = r.chance(0.3),
    }
    if r.chance(0.3) then o.out = S.path("csv") end
    if r.chance(0.2) then o.sigma = 0.1 end
    if r.chance(0.2) and S:has("dfle.profile") then
        o.data = S:get("dfle.profile"); o.channel = { dx = 50 }; o.nbins = 5
    end
    return o
end
A.invert_opts = invert_opts
T["dfle.invert"] = function(S)
    return pack(invert_opts(S)), { [1] = { walkers = true, steps = true, burn = true, run = true,
                                           nbins = true } }
end
T["dfle.ensemble:write_netcdf"] = function(S)
    local p = S.path("nc")
    return pack(p), nil, S.legal and "write" or nil
end
T["dfle.inversion:predict"] = function(S) return pack({ n = S.r.pick{ 1, 3 } }), { [1] = { n = true } } end
T["dfle.plot.corner"] = function(S)
    return pack(S:get("inversion"), S.path("png"), S.r.chance(0.5) and { title = "c", nbins = 5 } or nil),
           { [3] = { nbins = true } }
end
T["dfle.plot.posterior_predictive"] = function(S)
    return pack(S:get("inversion"), S.path("png"), { n = S.r.pick{ 1, 3 }, title = "pp" }),
           { [3] = { n = true } }
end

---------------------------------------------------------------------------
-- Kinds of pooled object and how to make one (valid arguments, no
-- mutation: the pool holds working objects; hostile ones come from the
-- calls themselves).
---------------------------------------------------------------------------
local MAKE = {}
A.MAKE = MAKE
MAKE["dfle.channel"] = function(S) return dfle.channel(small_channel(S)) end
MAKE["fluvial.st"] = function(S) return dfle.fluvial.stochastic_threshold{} end
MAKE["fluvial.sp"] = function(S) return dfle.fluvial.stream_power{ K = 1e-5, m = 0.5, n = 1 } end
MAKE["router.empirical"] = function(S) return dfle.router.empirical{} end
MAKE["router.process"] = function(S) return dfle.router.process(process_router(S)) end
MAKE["router.lua"] = function(S) return dfle.router.define(lua_router(S)) end
MAKE["law.power"] = function(S) return dfle.law.power{} end
MAKE["law.inertial"] = function(S) return dfle.law.inertial{} end
MAKE["law.excess_stress"] = function(S) return dfle.law.excess_stress{} end
MAKE["law.lua"] = function(S) return dfle.law.define(lua_law(S, false)) end
MAKE["law.lua_bulk"] = function(S) return dfle.law.define(lua_law(S, true)) end
MAKE["dfle.model"] = function(S) return dfle.model(model_opts(S)) end
MAKE["dfle.model.process"] = function(S)
    return dfle.model{ channel = S:get("dfle.channel"), router = S:get("router.process"),
                       law = dfle.law.power{} }
end
MAKE["dfle.dem"] = function(S) return dfle.dem.read(S.inputs.good_dem(S)) end
-- A network, or the profile up from its cell of largest area (there is
-- always one).
MAKE["dfle.profile"] = function(S)
    local dem = dfle.dem.read(S.inputs.good_dem(S))
    dem:fill()
    local net = dem:network{ A_min = dem.dx * dem.dy * 4 }
    if S.r.chance(0.5) then return net end
    local A_, E, N = net:get("A"), net:get("E"), net:get("N")
    local best = 1
    for i = 2, #A_ do if A_[i] > A_[best] then best = i end end
    return dem:profile{ outlet = { E[best], N[best] }, radius = 0 }
end
MAKE["dfle.landscape"] = function(S) return dfle.landscape(landscape_opts(S)) end
-- (no chain file: the pool's inversions must not depend on a file that
-- a fuzzer sharing the directory may hold locked)
MAKE["inversion"] = function(S)
    local o = invert_opts(S)
    o.out = nil
    return dfle.invert(o)
end
MAKE["ensemble"] = function(S)
    return dfle.ensemble(A.ensemble_spec(S, S.inputs.good_ensemble_csv(S)))
end

-- The kinds each method's `self` may come from.
A.SELF = {
    ["dfle.channel"] = { "dfle.channel" },
    ["dfle.fluvial"] = { "fluvial.st", "fluvial.sp" },
    ["dfle.router"] = { "router.empirical", "router.process", "router.lua" },
    ["dfle.law"] = { "law.power", "law.inertial", "law.excess_stress", "law.lua", "law.lua_bulk" },
    ["dfle.model"] = { "dfle.model", "dfle.model.process" },
    ["dfle.dem"] = { "dfle.dem" },
    ["dfle.profile"] = { "dfle.profile" },
    ["dfle.landscape"] = { "dfle.landscape" },
    ["dfle.inversion"] = { "inversion" },
    ["dfle.ensemble"] = { "ensemble" },
}

return A
