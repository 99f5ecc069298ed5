-- test_errors.lua - misuse of the API raises a clear error that names
-- the parameter and carries the caller's file:line; expected failures
-- (a fit that cannot converge) return nil, message.
local T = ...
local tests = {}

-- fn must raise "test_errors.lua:<line of fn>: ..." containing every text.
local function raises(fn, ...)
    local msg = T.raises_here(fn, ...)
    T.match(msg, "test_errors%.lua:%d+:")
    return msg
end

-- The same, for a call made by the one-line function `where`.
local function raises_at(where, fn, ...)
    local msg = T.raises_at(where, fn, ...)
    T.match(msg, "test_errors%.lua:%d+:")
    return msg
end

local function copy(t)
    local c = {}
    for k, v in pairs(t) do c[k] = v end
    return c
end

local function small_model(opts)
    opts = opts or {}
    opts.channel = opts.channel or dfle.channel{ A_max = 2e5 }
    return dfle.model(opts)
end

---------------------------------------------------------------------------
-- Every constructor and every function taking an options table gets the
-- same classes of bad input.  Each entry:
--   call(opts)  makes the call with an options table (or other value),
--               on one line: the error must point at that line;
--   prep(opts)  optional: completes the options before the call;
--   base        a valid options table;
--   num         a numeric parameter that must be > 0 (for negative,
--               zero, NaN, Inf and wrong type);
--   known       text the unknown-key message must list;
--   nontable    text the message for a non-table argument must contain;
--   bugs        case -> explanation, for cases that expose a known bug.
---------------------------------------------------------------------------
local subjects = {
    {
        name = "dfle.channel", base = {}, num = "dx", known = "dx, A0",
        call = function(o) return dfle.channel(o) end,
    },
    {
        name = "dfle.fluvial.stochastic_threshold", base = {}, num = "k_e", known = "k_e, rho_w",
        call = function(o) return dfle.fluvial.stochastic_threshold(o) end,
    },
    {
        name = "dfle.fluvial.stream_power", base = { K = 1e-5, m = 0.5, n = 1 }, num = "n",
        known = "K, m, n",
        call = function(o) return dfle.fluvial.stream_power(o) end,
    },
    {
        name = "dfle.router.empirical", base = {}, num = "M0", known = "M0, gamma, mu, tau_y",
        call = function(o) return dfle.router.empirical(o) end,
    },
    {
        name = "dfle.law.power", base = {}, num = "k_df", known = "k_df, alpha, beta",
        call = function(o) return dfle.law.power(o) end,
    },
    {
        name = "dfle.model", base = {}, num = "U", known = "U, cfl, dt_max",
        prep = function(o)
            if type(o) == "table" then o.channel = o.channel or dfle.channel{ A_max = 2e5 } end
        end,
        call = function(o) return dfle.model(o) end,
    },
    {
        name = "model:run_to_steady", base = {}, num = "tol", known = "tol, max_time",
        call = function(o) return small_model{ router = false }:run_to_steady(o) end,
    },
    {
        name = "model:run", base = { years = 10 }, num = "years", known = "years",
        call = function(o) return small_model{ router = false }:run(o) end,
    },
    {
        name = "dfle.fit_slope_area", base = {}, num = "nbins", known = "nbins",
        call = function(o) return dfle.fit_slope_area(small_model(), o) end,
    },
    {
        name = "dfle.analytical_slope", base = { A = 1e4 }, num = "U", known = "U, k_w, b",
        call = function(o) return dfle.analytical_slope(dfle.router.empirical{}, dfle.law.power{}, o) end,
    },
    {
        name = "dfle.analytical_exponent", base = {}, num = "U", known = "U, k_w, b",
        call = function(o) return dfle.analytical_exponent(dfle.router.empirical{}, dfle.law.power{}, o) end,
    },
    {
        name = "dfle.plot.slope_area", base = {}, num = "nbins", known = "nbins, dpi, title",
        call = function(o) return dfle.plot.slope_area(small_model(), T.tmpname(".png"), nil, o) end,
    },
}

local cases = {
    ["unknown key"] = function(s)
        local o = copy(s.base)
        o.bogus = 1
        return o, { "unknown parameter 'bogus'", s.known }
    end,
    ["wrong type (string for a number)"] = function(s)
        local o = copy(s.base)
        o[s.num] = "12"
        return o, { "'" .. s.num .. "'", "number", "string" }
    end,
    ["wrong type (boolean for a number)"] = function(s)
        local o = copy(s.base)
        o[s.num] = true
        return o, { "'" .. s.num .. "'", "number", "boolean" }
    end,
    negative = function(s)
        local o = copy(s.base)
        o[s.num] = -1
        return o, { s.num, "must be" }
    end,
    zero = function(s)
        local o = copy(s.base)
        o[s.num] = 0
        return o, { s.num, "must be" }
    end,
    NaN = function(s)
        local o = copy(s.base)
        o[s.num] = 0 / 0
        return o, { "'" .. s.num .. "'", "finite" }
    end,
    Inf = function(s)
        local o = copy(s.base)
        o[s.num] = 1 / 0
        return o, { "'" .. s.num .. "'", "finite" }
    end,
    ["-Inf"] = function(s)
        local o = copy(s.base)
        o[s.num] = -1 / 0
        return o, { "'" .. s.num .. "'", "finite" }
    end,
    ["positional (array) argument"] = function(s)
        return { 5 }, { "named" }
    end,
    ["non-table"] = function(s)
        return "dx = 5", { "table" }
    end,
}

for _, s in ipairs(subjects) do
    for case, make in pairs(cases) do
        -- Every message names its function (or the failing C check's
        -- object), so a script author knows which call was wrong.
        local title = s.name .. ": " .. case
        local bug = s.bugs and s.bugs[case]
        if bug then title = "BUG: " .. title .. " (" .. bug .. ")" end
        tests[title] = function()
            local arg, texts = make(s)
            if s.prep then s.prep(arg) end
            raises_at(s.call, function() return s.call(arg) end, table.unpack(texts))
        end
    end
end

-- The error position must be where the script called, not inside a helper.
tests["position: the message starts with the calling line"] = function()
    local ok, msg = pcall(function()
        dfle.channel{ dx = -1 } -- this line
    end)
    T.eq(ok, false)
    local line = debug.getinfo(1, "l").currentline - 3
    T.match(msg, "^[^:]*test_errors%.lua:" .. line .. ": ")
    T.has(msg, "dx")
end

---------------------------------------------------------------------------
-- Specific misuse.
---------------------------------------------------------------------------
tests["fluvial.stream_power: each of K, m, n is required"] = function()
    raises(function() return dfle.fluvial.stream_power{ m = 0.5, n = 1 } end, "'K'", "required")
    raises(function() return dfle.fluvial.stream_power{ K = 1, n = 1 } end, "'m'", "required")
    raises(function() return dfle.fluvial.stream_power{ K = 1, m = 0.5 } end, "'n'", "required")
    raises(function() return dfle.fluvial.stream_power{ K = -1, m = 0.5, n = 1 } end, "K", ">= 0")
    raises(function() return dfle.fluvial.stream_power{ K = 1, m = -0.5, n = 1 } end, "m", ">= 0")
    raises(function() return dfle.fluvial.stream_power() end, "table")
end

tests["fluvial.stochastic_threshold: negative overrides are rejected"] = function()
    raises(function() return dfle.fluvial.stochastic_threshold{ K = -1 } end, "K", ">= 0")
    raises(function() return dfle.fluvial.stochastic_threshold{ m_s = -1 } end, "m_s")
    raises(function() return dfle.fluvial.stochastic_threshold{ n_s = -1 } end, "n_s")
    raises(function() return dfle.fluvial.stochastic_threshold{ rho_s = 900 } end, "rho_s")
    raises(function() return dfle.fluvial.stochastic_threshold{ omega_s = 1 } end, "omega_s")
end

-- n_s = 0 is not a valid slope exponent (stream_power rejects n = 0),
-- but the derived n_s = 2.333 is used instead, silently.
tests["fluvial.stochastic_threshold: n_s = 0 is refused, not taken as derive"] = function()
    raises(function() return dfle.fluvial.stochastic_threshold{ n_s = 0 } end, "n_s")
end

tests["model: a fluvial law with no finite steady profile is refused, not run to NaN"] = function()
    -- n = 0.0014 is a valid exponent, but (U/K)^(1/n) overflows: the
    -- starting profile was NaN at every node and a run "succeeded".
    local fl = dfle.fluvial.stream_power{ K = 1e-5, m = 0.5, n = 0.0014 }
    raises(function() return dfle.model{ fluvial = fl } end, "starting profile", "not finite",
           "n_s = 0.0014")
end

tests["strings with a NUL byte are refused, not cut short"] = function()
    -- C strings end at NUL: "nul\0.csv" once wrote "nul", "direct\0junk"
    -- selected the direct method, a parameter named "a\0b" crashed dfle.lhs.
    local m = dfle.model{ channel = dfle.channel{ dx = 20 } }
    local path = T.tmpname("nul") .. "\0.csv"
    raises(function() return m:write_csv(path) end, "the path contains a NUL byte", "\\000")
    T.eq(io.open(path:match("^[^%z]*")), nil) -- nothing was written under the cut name
    raises(function() return m:run_to_steady{ method = "direct\0junk" } end,
           "method contains a NUL byte")
    raises(function() return m:get("S\0x") end, "field name contains a NUL byte")
    raises(function() return m["time\0x"] end, "no field", "NUL byte")
    raises(function() return dfle.model{ ["U\0x"] = 1 } end, "unknown parameter 'U\\000x'")
    raises(function() return dfle.lhs{ n = 10, params = { ["a\0b"] = {0, 1} } } end,
           "parameter name contains a NUL byte")
    raises(function() return dfle.pawn{ file = "x\0.csv", inputs = {"a"}, output = "y" } end,
           "file contains a NUL byte")
    raises(function() return dfle.plot.profile(m, "p\0.png") end, "path contains a NUL byte")
    raises(function() return dfle.law.define{ name = "a\0b", rate = function() return 0 end } end,
           "name contains a NUL byte")
end

tests["an unknown key is shown short, however long it is"] = function()
    local key = string.rep("k", 100000)
    local msg = raises(function() return dfle.model{ [key] = 1 } end, "unknown parameter",
                       "(100000 characters)")
    T.ok(#msg < 1000, "message of " .. #msg .. " bytes")
end

tests["fluvial:rate and steady_slope refuse areas that give NaN"] = function()
    local fl = dfle.fluvial.stochastic_threshold{}
    raises(function() return fl:rate(-1e6, 0.1) end, "A (drainage area, m^2) must be a finite number > 0")
    raises(function() return fl:rate(1e6, 0 / 0) end, "S (slope) must be a finite number")
    raises(function() return fl:steady_slope(5e-4, -1) end, "A (drainage area")
    raises(function() return fl:steady_slope(-5e-4, 1e6) end, "U (uplift rate")
    T.close(fl:rate(1e6, 0.1), 2.4539e-10 * 1e6^1.4 * 0.1^(7 / 3), 1e-3)
end

tests["channel: geometry errors name the parameter"] = function()
    raises(function() return dfle.channel{ A0 = -5 } end, "A0")
    raises(function() return dfle.channel{ hack_exp = 0 } end, "hack_exp")
    raises(function() return dfle.channel{ k_w = 0 } end, "k_w")
    raises(function() return dfle.channel{ length = -10 } end, "length")
    raises(function() return dfle.channel{ A_max = 10 } end, "A_max")
    raises(function() return dfle.channel{ dx = 1000, length = 1000 } end, "3 nodes")
end

tests["router.empirical and law.power: range errors name the parameter"] = function()
    raises(function() return dfle.router.empirical{ gamma = -0.1 } end, "gamma", ">= 0")
    raises(function() return dfle.router.empirical{ tau_y = -1 } end, "tau_y", ">= 0")
    raises(function() return dfle.router.empirical{ mu = 0 } end, "mu", "> 0")
    raises(function() return dfle.law.power{ alpha = -1 } end, "alpha", ">= 0")
    raises(function() return dfle.law.power{ beta = -1 } end, "beta", ">= 0")
end

tests["model: cfl and dt_max ranges"] = function()
    local ch = dfle.channel{ A_max = 2e5 }
    raises(function() return dfle.model{ channel = ch, cfl = 1.5 } end, "cfl")
    raises(function() return dfle.model{ channel = ch, cfl = 0 } end, "cfl")
    raises(function() return dfle.model{ channel = ch, dt_max = -1 } end, "dt_max")
end

tests["model: law given with router = false"] = function()
    local ch, law = dfle.channel{ A_max = 2e5 }, dfle.law.power{}
    raises(function() return dfle.model{ channel = ch, router = false, law = law } end, "law", "router")
end

tests["model: a router without a law"] = function()
    local ch = dfle.channel{ A_max = 2e5 }
    raises(function() return dfle.model{ channel = ch, law = false } end, "law")
end

tests["model: wrong component types"] = function()
    local ch, rt, law = dfle.channel{ A_max = 2e5 }, dfle.router.empirical{}, dfle.law.power{}
    -- A channel where a router is expected: both types are named.
    raises(function() return dfle.model{ channel = ch, router = ch } end, "'router'", "dfle.router", "dfle.channel")
    raises(function() return dfle.model{ channel = rt } end, "'channel'", "dfle.channel", "dfle.router")
    raises(function() return dfle.model{ channel = ch, law = rt } end, "'law'", "dfle.law")
    raises(function() return dfle.model{ channel = ch, fluvial = law } end, "'fluvial'", "dfle.fluvial")
    raises(function() return dfle.model{ channel = ch, fluvial = true } end, "'fluvial'", "boolean")
    raises(function() return dfle.model{ channel = ch, router = "empirical" } end, "'router'", "string")
    raises(function() return dfle.model{ channel = false } end, "'channel'")
    raises(function() return dfle.model{ channel = {} } end, "'channel'", "table")
end

tests["model:run: years is required"] = function()
    local m = small_model{ router = false }
    raises(function() return m:run{} end, "'years'", "required")
    raises(function() return m:run{ max_steps = 10 } end, "'years'", "required")
    raises(function() return m:run() end, "table")
end

tests["model:run and run_to_steady: max_steps, max_time, progress"] = function()
    local m = small_model{ router = false }
    raises(function() return m:run{ years = 10, max_steps = 0 } end, "max_steps")
    raises(function() return m:run{ years = 10, max_steps = 0 / 0 } end, "max_steps", "finite")
    raises(function() return m:run{ years = 10, progress = "yes" } end, "'progress'", "boolean")
    raises(function() return m:run_to_steady{ max_time = -1 } end, "max_time")
    raises(function() return m:run_to_steady{ max_time = 1 / 0 } end, "max_time", "finite")
    raises(function() return m:run_to_steady{ max_steps = -3 } end, "max_steps")
    raises(function() return m:run_to_steady{ progress = 1 } end, "'progress'", "boolean")
    T.eq(m.time, 0, "no time was simulated by the failed calls")
end

tests["model:get: unknown field lists the fields"] = function()
    local m = small_model()
    raises(function() return m:get("nope") end, "'nope'", "x, A, w, z, S", "tau")
    raises(function() return m:get() end, "string expected")
    raises(function() return m.channel:get("S") end, "'S'")
end

tests["model:set_z: wrong length, wrong values"] = function()
    local m = small_model()
    raises(function() return m:set_z{ 1, 2, 3 } end, "z", "3", tostring(m.n))
    local z = m:get("z")
    z[5] = "high"
    raises(function() return m:set_z(z) end, "z[5]", "string")
    z[5] = 0 / 0
    raises(function() return m:set_z(z) end, "z", "not finite")
    raises(function() return m:set_z("z") end, "z", "array")
    raises(function() return m:set_z() end, "z")
end

tests["model:set_U: range and type"] = function()
    local m = small_model()
    raises(function() return m:set_U(-1) end, "U", "> 0")
    raises(function() return m:set_U(0) end, "U", "> 0")
    raises(function() return m:set_U(0 / 0) end, "U")
    raises(function() return m:set_U(1 / 0) end, "U")
    raises(function() return m:set_U("fast") end, "number expected")
    T.eq(m.U, 5e-4, "U unchanged")
end

tests["model:init_fluvial_steady: needs a fluvial law"] = function()
    local m = small_model()
    raises(function() return m:init_fluvial_steady(dfle.router.empirical{}) end, "dfle.fluvial", "dfle.router")
    raises(function() return m:init_fluvial_steady(m.channel) end, "dfle.fluvial", "dfle.channel")
end

tests["model methods: wrong self"] = function()
    local ch = dfle.channel{ A_max = 2e5 }
    local m = small_model()
    raises(function() return m.get(ch, "S") end, "dfle.model", "dfle.channel")
    raises(function() return m.run(nil, { years = 1 }) end, "dfle.model")
    raises(function() return dfle.plot.profile(ch, T.tmpname(".png")) end, "dfle.model", "dfle.channel")
end

tests["model:write_csv: unwritable path names the path"] = function()
    local m = small_model()
    raises(function() return m:write_csv("/nonexistent-dir/sub/profile.csv") end, "/nonexistent-dir/sub/profile.csv")
    raises(function() return m:write_csv() end, "string expected")
end

tests["model: a run that blows up names the node and field"] = function()
    local m = small_model{ fluvial = dfle.fluvial.stream_power{ K = 1e-3, m = 0, n = 200 }, router = false }
    local z = {}
    for i = 1, m.n do z[i] = (m.n - i) * 1e4 end -- S = 2000: S^200 overflows
    m:set_z(z)
    raises(function() return m:run{ years = 100 } end, "E_f", "not finite", "node 1")
    raises(function() return m:get("S") end, "not finite")
    raises(function() return m:write_csv(T.tmpname(".csv")) end, "not finite")
    -- The model recovers once given a sane state.
    m:init_fluvial_steady(dfle.fluvial.stochastic_threshold{})
    T.eq(m:run{ years = 10 }.reason, "time")
end

tests["fit_slope_area: mismatched, missing or non-numeric arrays"] = function()
    raises(function() return dfle.fit_slope_area({ A = { 1, 2, 3 }, S = { 1, 2 } }, {}) end, "A has 3", "S has 2")
    raises(function() return dfle.fit_slope_area({ A = { 1, 2, 3 } }, {}) end, "S")
    raises(function() return dfle.fit_slope_area({ A = { 1, "x", 3 }, S = { 1, 2, 3 } }, {}) end, "A[2]")
    raises(function() return dfle.fit_slope_area("data") end, "dfle.model", "string")
    raises(function() return dfle.fit_slope_area(dfle.channel{}) end, "dfle.model")
    raises(function() return dfle.fit_slope_area(small_model(), { nbins = 2.5 }) end, "nbins")
end

tests["fit_slope_area: data it cannot fit returns nil, message"] = function()
    local A, pure, flat = {}, {}, {}
    for i = 1, 200 do
        A[i] = 10 ^ (3 + 4 * (i - 1) / 199)
        pure[i] = 3 * A[i] ^ -0.5 -- a pure power law: no roll-over, A_df -> 0
        flat[i] = 0.3             -- a constant slope: no transition
    end
    for _, S in ipairs{ pure, flat } do
        local f, msg = dfle.fit_slope_area({ A = A, S = S }, {})
        T.eq(f, nil)
        T.eq(type(msg), "string")
        T.has(msg, "fit")
    end
    -- Too few bins to fit three parameters.
    local f, msg = dfle.fit_slope_area({ A = { 1e3, 1e4, 1e5 }, S = { 0.8, 0.5, 0.1 } }, {})
    T.eq(f, nil)
    T.has(msg, "need at least 4")
end

tests["analytical_slope: bad arguments"] = function()
    local rt, law, ch = dfle.router.empirical{}, dfle.law.power{}, dfle.channel{ A_max = 2e5 }
    -- A channel where a router is expected.
    raises(function() return dfle.analytical_slope(ch, law, { A = 1e4 }) end, "dfle.router", "dfle.channel")
    raises(function() return dfle.analytical_slope(law, rt, { A = 1e4 }) end, "dfle.router", "dfle.law")
    raises(function() return dfle.analytical_slope(rt, rt, { A = 1e4 }) end, "dfle.law")
    raises(function() return dfle.analytical_slope(rt, law, { U = 5e-4 }) end, "'A'")
    raises(function() return dfle.analytical_slope(rt, law, { A = -1 }) end, "A", "> 0")
    raises(function() return dfle.analytical_slope(rt, law, { A = 0 }) end, "A", "> 0")
    raises(function() return dfle.analytical_slope(rt, law, { A = 0 / 0 }) end, "A")
    raises(function() return dfle.analytical_slope(rt, law, { A = "big" }) end, "'A'")
    raises(function() return dfle.analytical_slope(rt, law, { A = { 1e4, -1 } }) end, "A[2]")
    raises(function() return dfle.analytical_slope(rt, law, { A = 1e4, k_w = 0 }) end, "k_w")
    raises(function() return dfle.analytical_slope(rt, law) end, "table")
    -- alpha = beta / 3 makes Eq. (19) undefined.
    local bad = dfle.law.power{ alpha = 1, beta = 3 }
    raises(function() return dfle.analytical_slope(rt, bad, { A = 1e4 }) end, "alpha")
end

-- Numeric parameters must be finite everywhere else; A = inf returns 0.
tests["analytical_slope: an infinite area is refused"] = function()
    local rt, law = dfle.router.empirical{}, dfle.law.power{}
    raises(function() return dfle.analytical_slope(rt, law, { A = 1 / 0 }) end, "A")
    raises(function() return dfle.analytical_slope(rt, law, { A = { 1e4, 1 / 0 } }) end, "A[2]")
end

tests["plot: bad paths, fits and series"] = function()
    local m = small_model()
    raises(function() return dfle.plot.profile(m, T.tmpname(".txt")) end, ".png")
    raises(function() return dfle.plot.profile(m, "/nonexistent-dir/p.png") end, "/nonexistent-dir/p.png")
    raises(function() return dfle.plot.profile(m) end, "string expected")
    raises(function() return dfle.plot.profile(m, T.tmpname(".png"), { title = 5 }) end, "'title'", "string")
    raises(function() return dfle.plot.slope_area(m, T.tmpname(".png"), 5) end, "fit")
    raises(function() return dfle.plot.slope_area(m, T.tmpname(".png"), { S_df = 1 }) end, "A_df")
    raises(function() return dfle.plot.slope_area("m", T.tmpname(".png")) end, "dfle.model")
    raises(function() return dfle.plot.xy{ series = { { x = { 1 }, y = { 1 } } } } end, "'path'")
    raises(function() return dfle.plot.xy{ path = 5, series = { { x = { 1 }, y = { 1 } } } } end, "'path'", "string")
    raises(function() return dfle.plot.xy{ path = T.tmpname(".png"), series = {} } end, "series")
    raises(function() return dfle.plot.xy{ path = T.tmpname(".png"), series = { { x = { 1, 2 }, y = { 1 } } } } end, "series[1]")
    raises(function() return dfle.plot.xy{ path = T.tmpname(".png"), series = { { x = { 1 }, y = { 1 }, colour = "red" } } } end, "'colour'", "label")
    raises(function() return dfle.plot.xy{ path = T.tmpname(".png"), series = { { x = { 1 }, y = { 1 } } }, logx = "yes" } end, "'logx'", "boolean")
    raises(function() return dfle.plot.xy{ path = T.tmpname(".png"), series = { { x = { 1 }, y = { 1 } } }, bogus = 1 } end, "'bogus'", "path, series")
    raises(function() return dfle.plot.xy("x.png") end, "table")
end

-- The options every dfle.plot function shares: a wrong shape or name
-- raises at the script's line, naming the option (and what it could be).
tests["plot: the shared options refuse bad values, naming the option"] = function()
    local S = { { x = { 1, 2, 3 }, y = { 1, 4, 9 } } }
    -- on one line: the errors are at xy's call of dfle.plot.xy
    local function xy(o) o.path, o.series = o.path or T.tmpname(".png"), o.series or S; return dfle.plot.xy(o) end
    local function bad(o, ...) return raises_at(xy, function() return xy(o) end, ...) end
    bad({ size = { 17, 11, "mm" } }, "dfle.plot.xy", "size unit 'mm'",
       "'cm', 'in', 'px'")
    bad({ size = { "17", 11 } }, "size[1] must be a number")
    bad({ size = 17 }, "size must be a table {width, height")
    bad({ size = {} }, "size needs a width or a height")
    bad({ size = { 1, 1 } }, "outside 2 to 200 cm")
    bad({ legend = "middle" }, "legend 'middle' is not a legend position",
        "'top left'", "'below'")
    bad({ legend = 3 }, "legend must be a position")
    bad({ xrange = { 5, 1 } }, "xrange must be increasing")
    bad({ yrange = "0..1" }, "yrange must be a table {lo, hi}")
    bad({ xlog = true, xrange = { 0, 3 } }, "xrange must be > 0")
    bad({ xlog = "yes" }, "'xlog'", "boolean")
    bad({ xticks = "many" }, "xticks must be a spacing")
    bad({ xticks = { 1, "two" } }, "xticks[2] must be a number or {value")
    bad({ yticks = { { 1, 2 } } }, "yticks[1]: the label must be a string")
    bad({ ylog = true, yticks = 2 }, "a spacing (2) needs a linear axis")
    bad({ font = "Helvetica,1000" }, "font 'Helvetica,1000'", "4 to 72")
    bad({ dpi = 5 }, "dpi must be from 30 to 2400")
    bad({ series = { { x = { 1 }, y = { 1 }, style = "bars" } } },
        "series[1].style 'bars' is not a style")
    bad({ series = { { x = { 1 }, y = { 1 }, marker = "hexagon" } } },
        "series[1].marker 'hexagon'", "'open circle'")
    bad({ series = { { x = { 1 }, y = { 1 }, dash = "long" } } },
        "series[1].dash 'long'")
    bad({ series = { S[1], { x = { 1 }, y = { 1 }, rgb = "mauve" } } },
        "series[2]: rgb 'mauve' is not a colour")
    bad({ series = { { x = { 1 }, y = { 1 }, width = 50 } } },
        "series[1]: width must be from 0 to 20 pt")
    bad({ series = { { x = { 1 }, hi = { 1 } } } }, "series[1] has hi but no lo")
    bad({ path = T.tmpname(".jpg") }, ".png, .pdf or .svg")
    bad({ crange = { 3, 1 } }, "crange must be increasing")
    bad({ clog = true, crange = { 0, 1 } }, "crange must be > 0")
    bad({ cticks = "x" }, "cticks must be a spacing")
    bad({ xformat = 5 }, "'xformat' must be a string")
    bad({ cformat = {} }, "'cformat' must be a string")
    bad({ series = { { x = { 1 }, y = { 1 }, marker_size = 100 } } },
        "series[1]: marker_size must be from 0 to 50 pt")
    -- the other figures take the same options and give the same messages
    local m = small_model()
    raises(function() return dfle.plot.profile(m, T.tmpname(".png"), { legend = "up" }) end,
           "dfle.plot.profile", "legend 'up'")
    raises(function() return dfle.plot.slope_area(m, T.tmpname(".png"), nil, { size = { 8, 6, "pt" } }) end,
           "dfle.plot.slope_area", "size unit 'pt'")
    raises(function() return dfle.plot.panels{ path = T.tmpname(".png"), panels = { { series = S, yrange = { 2, 2 } } } } end,
           "dfle.plot.panels", "yrange must be increasing")
    raises(function() return dfle.plot.sheet{ path = T.tmpname(".png"), images = { 5 } } end,
           "images[1] must be a path")
    raises(function() return dfle.plot.sheet{ path = T.tmpname(".png"), images = { "a.png" }, xlog = true } end,
           "unknown parameter 'xlog'")
    raises(function() return dfle.plot.sheet{ path = T.tmpname(".png"), images = { "a.png" }, columns = 0 } end,
           "dfle.plot.sheet", "columns must be a whole number")
    raises(function() return dfle.plot.sheet{ path = T.tmpname(".png"), images = { "a.png" }, titles = { 5 } } end,
           "titles[1] must be a string")
    raises(function() return dfle.plot.panels{ path = T.tmpname(".png"), panels = { { series = S, weight = -1 } } } end,
           "panel 1: weight must be >= 0")
    local pm = dfle.model{ channel = dfle.channel{ dx = 50 }, U = 5e-4,
                           router = dfle.router.process{ M0 = 200 },
                           law = dfle.law.power{ k_df = 1e-4, alpha = 6, beta = 1 } }
    local flow = dfle.router.process{ M0 = 200 }:route(pm, { snapshots = { 10 } })
    T.raises_here(function() return dfle.plot.flow(pm, flow, T.tmpname(".png"), { exaggeration = 0 }) end,
                  "dfle.plot.flow", "exaggeration must be > 0")
    raises(function() return dfle.plot.label("Q_s") end, "no house label for 'Q_s'", "A, S")
end

-- A PDF and an SVG through the Lua options: size and font reach the file.
tests["plot: PDF and SVG from a script, sized in cm and inches"] = function()
    local pdf, svg = T.tmpname(".pdf"), T.tmpname(".svg")
    local S = { { x = { 1, 2, 3 }, y = { 1, 4, 9 }, label = "squares", style = "linespoints" } }
    dfle.plot.xy{ path = pdf, series = S, size = { 8.3, 6, "cm" }, font = "Helvetica,8",
                  xticks = { { 1, "one" }, 2, 3 }, legend = "top left", title = "small" }
    local t = assert(T.read_file(pdf))
    T.eq(t:sub(1, 5), "%PDF-")
    T.ok(t:sub(-16):find("%%EOF", 1, true), "the PDF ends with %%EOF")
    T.ok(t:find("/MediaBox [ 0 0 235 170 ]", 1, true), "an 8.3 x 6 cm page")
    dfle.plot.xy{ path = svg, series = S, size = { 4, nil, "in" }, legend = false, ylog = true }
    t = assert(T.read_file(svg))
    T.ok(t:find('width="288pt"', 1, true), "4 inches wide, in points")
    T.ok(t:find("</svg>%s*$"), "the SVG is whole")
    local label, factor = dfle.plot.label("U")
    T.eq(label, "Uplift rate, {/:Italic U} (mm/yr)")
    T.eq(factor, 1000)
    T.eq(dfle.plot.number(1.42e5), "1.42×10^{5}")
    T.eq(dfle.plot.number(1 / 0), "inf")
    T.eq(dfle.plot.number(0 / 0), "NaN")
end

-- Options with a misspelt key are silently ignored by plot.profile.
tests["plot.profile: unknown option keys and non-table options are refused"] = function()
    local m = small_model()
    raises(function() return dfle.plot.profile(m, T.tmpname(".png"), { titel = "x" }) end, "'titel'")
    raises(function() return dfle.plot.profile(m, T.tmpname(".png"), "title") end, "table")
end

-- A component whose __gc has been called from Lua is "closed".  The
-- model constructor checks channel, router and law for that, but not
-- the fluvial law: a closed one silently means "no fluvial erosion".
tests["model: a closed fluvial law is refused, not taken as off"] = function()
    local fl = dfle.fluvial.stochastic_threshold{}
    debug.getmetatable(fl).__gc(fl)
    local ch = dfle.channel{ A_max = 2e5 }
    raises(function() return dfle.model{ channel = ch, fluvial = fl, router = false } end, "closed")
end

tests["model: closed channel, router or law are refused"] = function()
    local ch, rt, law = dfle.channel{ A_max = 2e5 }, dfle.router.empirical{}, dfle.law.power{}
    local dead_rt, dead_law = dfle.router.empirical{}, dfle.law.power{}
    debug.getmetatable(dead_rt).__gc(dead_rt)
    debug.getmetatable(dead_law).__gc(dead_law)
    raises(function() return dfle.model{ channel = ch, router = dead_rt, law = law } end, "closed")
    raises(function() return dfle.model{ channel = ch, router = rt, law = dead_law } end, "closed")
    local dead_ch = dfle.channel{ A_max = 2e5 }
    debug.getmetatable(dead_ch).__gc(dead_ch)
    raises(function() return dfle.model{ channel = dead_ch } end, "closed")
    raises(function() return dead_ch.n end, "closed")
    raises(function() return dead_rt:params() end, "closed")
end

-- If __gc were reachable, a script could free a channel that a live model
-- still borrows and the model would read freed memory.  Run in a child
-- process so that, were it ever reachable again, the runner stays clean.
tests["metatables are protected: a script cannot free a component a model uses"] = function()
    local out, ok = T.run_dfle([[
        local ch = dfle.channel{ A_max = 2e5 }
        local m = dfle.model{ channel = ch, router = false }
        local mt = getmetatable(ch)
        if type(mt) ~= "table" or type(mt.__gc) ~= "function" then
            print("PROTECTED")
            return
        end
        mt.__gc(ch)
        local fine = pcall(m.get, m, "A")
        print(fine and "USED FREED CHANNEL" or "RAISED")
    ]])
    T.ok(ok, out)
    T.ok(out:find("PROTECTED", 1, true) or out:find("RAISED", 1, true), out)
end

-- Rough edges a first-time user meets: each error says what to do instead.
tests["fields: read-only assignment, dot calls, unknown methods, strict fit results"] = function()
    local m = dfle.model{ channel = dfle.channel{ A_max = 2e5 }, router = false }
    T.raises_here(function() m.U = 1e-3 end, "field 'U' is read-only", "m:set_U(U)")
    T.raises_here(function() m.n = 3 end, "field 'n' is read-only")
    local ch = dfle.channel{ A_max = 2e5 }
    T.raises_here(function() ch.dx = 5 end, "field 'dx' is read-only", "make a new")
    T.raises_here(function() return m.get("A") end, "call it with a colon", "obj:get(...)", "not a dot")
    T.raises_here(function() return m:frobnicate() end, "has no field 'frobnicate'",
                  "methods: ", "run_to_steady")
    -- unknown keys of a fit result name the ones there are
    local fm = dfle.model{ channel = dfle.channel{ dx = 20 } }
    fm:run_to_steady{}
    local fit = dfle.fit_slope_area(fm)
    T.ok(fit.S_df > 0)
    T.raises_here(function() return fit.Sdf end, "no field 'Sdf'", "S_df", "r2")
    -- fitting the unrun starting profile says to run the model first
    local fresh = dfle.model{ channel = dfle.channel{ dx = 20 } }
    local none, why = dfle.fit_slope_area(fresh)
    T.eq(none, nil)
    T.has(why, "has not been run", "run_to_steady")
end

-- Values that run but are almost surely a unit mistake: a warning on
-- stderr naming the script line, the value and the fix; once per
-- parameter; warn("@off") silences them.
tests["plausibility: a likely unit mistake warns once, with the line and the fix"] = function()
    local out, ok = T.run_dfle([[
        local m = dfle.model{ U = 0.5, channel = dfle.channel{ A_max = 2e5 }, router = false }
        for i = 1, 3 do dfle.model{ U = 0.5, channel = dfle.channel{ A_max = 2e5 }, router = false } end
        local rt = dfle.router.empirical{ tau_y = 0.3 }
        m:set_U(1e-3)
        warn("@off")
        dfle.router.empirical{ rho_b = 1.8 }
        warn("@on")
        print("done")
    ]])
    T.ok(ok, out)
    T.has(out, "dfle: warning: ", ".lua:1: dfle.model: U = 0.5 m/yr is far above rock-uplift rates",
          "write U = 0.0005", ".lua:3: dfle.router.empirical: tau_y = 0.3 Pa", "write tau_y = 300",
          "done")
    local _, n = out:gsub("U = 0.5 m/yr", "")
    T.eq(n, 1, "one warning per parameter")
    T.ok(not out:find("rho_b", 1, true), "warn('@off') silences")
    T.ok(not out:find("set_U", 1, true), "a plausible U is quiet")
end

tests["plausibility: an undeclared -9999 in a DEM warns; declared, it is NoData"] = function()
    local asc = T.tmpname(".asc")
    T.write_file(asc, "ncols 4\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 10\n" ..
                      "100 102 103 104\n-9999 -9999 106 107\n107 108 109 110\n")
    local out, ok = T.run_dfle(string.format([[
        local d = dfle.dem.read(%q)
        print("z_min", d.z_min)
        local e = dfle.dem.read(%q, { nodata = -9999 })
        print("cells", e.nodata_cells)
    ]], asc, asc))
    T.ok(ok, out)
    T.has(out, ".lua:1: dfle.dem.read: ", "2 cells hold -9999", "pass nodata = -9999",
          "z_min\t-9999", "cells\t2")
    local _, n = out:gsub("warning", "")
    T.eq(n, 1)
end

return tests
