-- test_fuzzed.lua - findings of the API fuzzer (tests/fuzz/), one test
-- each, so they stay fixed.  (Re-entry of Lua laws and routers is in
-- test_lifetime.lua, file writing in test_file.c.)
local tests = {}

local function small(opts)
    opts = opts or {}
    opts.channel = opts.channel or dfle.channel{ dx = 50, A_max = 2e5 }
    return dfle.model(opts)
end

tests["an unknown method is named as the option it is, not 'bad argument #-2'"] = function()
    local m = small()
    local msg = T.raises_here(function() return m:run_to_steady{ method = "%s%n" } end,
                              "dfle.model:run_to_steady: method must be 'explicit', 'implicit', "
                              .. "'direct' or 'auto' (got '%s%n')")
    T.ok(not msg:find("bad argument", 1, true), msg)
    T.raises_here(function() return m:run{ years = 1, method = "Explicit" } end,
                  "dfle.model:run: method must be", "(got 'Explicit')")
end

tests["a NaN is shown as NaN in messages, not as C's '-nan'"] = function()
    for _, nan in ipairs{ 0 / 0, -(0 / 0) } do -- one of them has the sign bit set
        local m = small()
        local z = m:get("z")
        z[2] = nan
        T.raises_here(function() return m:set_z(z) end, "z at node 2 is not finite (NaN)")
        local mu = small{ U = function(t) return t > 0 and nan or 5e-4 end }
        T.raises_here(function() return mu:run{ years = 10 } end, "U(t) must be > 0 m/yr (got NaN")
        T.raises_here(function() return dfle.channel{ dx = 50, length = 200,
                                                      area = function(x) return nan end } end,
                      "A at node 1 must be > 0 m^2 (got NaN)")
    end
end

tests["rate_ratio stays finite for the smallest U"] = function()
    -- |dz/dt| / U overflowed to inf for U = 5e-324 m/yr (valid: > 0)
    local m = small{ U = 5e-324 }
    local z = {}
    for i = 1, m.n do z[i] = 100 * (m.n - i) end -- steep: fast erosion
    m:set_z(z)
    local r = m:run{ years = 1, max_steps = 1 }
    T.eq(r.rate_ratio, 1.7976931348623157e308)
    T.eq(r.converged, false)
end

tests["fl:rate and fl:steady_slope raise rather than return inf"] = function()
    local fl = dfle.fluvial.stochastic_threshold{}
    T.raises_here(function() return fl:rate(1e4, 1.7976931348623157e308) end,
                  "dfle.fluvial:rate: E_f = K A^m_s S^n_s is not finite for A = 10000")
    T.raises_here(function() return fl:steady_slope(1e300, 1e4) end,
                  "dfle.fluvial:steady_slope: S = (U/K)^(1/n_s) A^(-m_s/n_s) is not finite")
    -- K = 0: no fluvial erosion, documented as inf
    local off = dfle.fluvial.stream_power{ K = 0, m = 0.5, n = 1 }
    T.eq(off:steady_slope(5e-4, 1e4), math.huge)
    T.eq(off:rate(1e4, 0.1), 0.0)
end

tests["dfle.pawn(ens): errors carry the position; a changed result is refused"] = function()
    local dir = T.tmpname()
    os.remove(dir)
    os.execute("mkdir -p " .. T.shquote(dir))
    local ens = dfle.ensemble{
        params = { k_df = { 5e-5, 1e-3 } }, n = 3, seed = 1, out = dir .. "/e.csv", workers = 1,
        build = function(p)
            return dfle.model{ channel = dfle.channel{ dx = 50, A_max = 5e4 },
                               law = dfle.law.power{ k_df = p.k_df } }
        end,
        outputs = { "S_df", "A_df" },
    }
    -- errors of the plain dfle.pawn it calls had no file:line
    T.raises_here(function() return dfle.pawn(ens, { outputs = { "S_df" }, S = 1.5 }) end,
                  "dfle.pawn: S (slices) must be a whole number")
    T.raises_here(function() return dfle.pawn(ens, { outputs = { 1 } }) end,
                  "dfle.pawn: outputs[1] must be a name, got number")
    -- a status that is not a string crashed (strcmp on NULL)
    ens.data.status = { 1, {}, "ok" }
    T.raises_here(function() return dfle.pawn(ens, { outputs = { "S_df" }, S = 2 }) end,
                  "dfle.pawn:")
    ens.data.status = "okokok"
    T.raises_here(function() return dfle.pawn(ens, { outputs = { "S_df" } }) end,
                  "dfle.pawn: the ensemble's data.status is not a table (got string)")
    ens.inputs = 5
    T.raises_here(function() return dfle.pawn(ens, { outputs = { "S_df" } }) end,
                  "dfle.pawn: the ensemble's inputs must be an array of names, got number")
    ens.data = nil
    T.raises_here(function() return dfle.pawn(ens, { outputs = { "S_df" } }) end,
                  "dfle.pawn: the ensemble's 'data' is not a table (got nil)")
    os.execute("rm -rf " .. T.shquote(dir))
end

tests["an area(x) that gives no area stops the search for A_max at once"] = function()
    -- it was called for a million nodes, then said A_max was not reached
    local calls = 0
    for _, bad in ipairs{ 0, -1, 0 / 0 } do
        calls = 0
        local function area(x)
            calls = calls + 1
            return x < 100 and 1000 + x or bad
        end
        T.raises_here(function() return dfle.channel{ dx = 50, A_max = 5e4, area = area } end,
                      "dfle.channel: A at node 3 must be > 0 m^2 (got", "from area(x) at x = 100")
        T.eq(calls, 3)
    end
end

tests["analytical_slope raises rather than return inf or NaN"] = function()
    -- alpha close to beta/3: Eq. (19)'s power overflows (inf, or inf * 0)
    local rt = dfle.router.empirical{}
    for _, alpha in ipairs{ 0.34, 0.334 } do
        local law = dfle.law.power{ alpha = alpha, beta = 1 }
        T.raises_here(function() return dfle.analytical_slope(rt, law, { A = 1e4, U = 1 }) end,
                      "dfle.analytical_slope: S of Eq. (19) is not finite", "at A = 10000")
        T.raises_here(function() return dfle.analytical_slope(rt, law, { A = { 1e4 }, U = 1 }) end,
                      "dfle.analytical_slope: S of Eq. (19) is not finite")
    end
end

tests["a closed profile given to fit_slope_area is named at the script's line"] = function()
    local dem = dfle.dem.read(T.data .. "/dem/small/testdem1.dem")
    dem:fill()
    local p = dem:network{ A_min = dem.dx * dem.dy }
    do local closing <close> = p end
    -- 'bad argument #1 to '?'' without a file:line, from a call made in C
    T.raises_here(function() return dfle.fit_slope_area(p) end,
                  "bad argument #1 to 'fit_slope_area' (dfle.profile has been closed)")
    T.raises_here(function() return dfle.plot.slope_area(p, T.tmpname(".png")) end,
                  "dfle.profile has been closed")
end

tests["an ensemble row with a million fields is an error that says so"] = function()
    -- it ran the Lua stack out: 'stack overflow (too many columns)'
    local dir = T.tmpname()
    os.remove(dir)
    os.execute("mkdir -p " .. T.shquote(dir))
    dfle.ensemble{
        params = { k_df = { 5e-5, 1e-3 } }, n = 2, seed = 1, out = dir .. "/e.csv", workers = 1,
        build = function(p)
            return dfle.model{ channel = dfle.channel{ dx = 50, A_max = 5e4 },
                               law = dfle.law.power{ k_df = p.k_df } }
        end,
        outputs = { "S_df" },
    }
    local text = T.read_file(dir .. "/e.csv")
    T.write_file(dir .. "/bad.csv", (text:gsub("\n2,[^\n]*", "\n2," .. string.rep("1,", 1000000) .. "1")))
    T.raises_here(function() return dfle.gather{ out = dir .. "/g.csv", files = { dir .. "/bad.csv" } } end,
                  "dfle.gather: " .. dir .. "/g.csv: sample 2 has 1000002 fields, the header 5")
    os.execute("rm -rf " .. T.shquote(dir))
end

tests["pawn names the data's columns whatever their length"] = function()
    -- a long column name made the listing fail: 'invalid key to 'next''
    local long = string.rep("a", 3000)
    local data = { [long] = { 1, 2, 3 }, y = { 1, 2, 3 }, b = { 4, 5, 6 } }
    local opts = { data = data, inputs = { "x1" }, output = "y" }
    local msg = T.raises_here(function() return dfle.pawn(opts) end, "no column 'x1'")
    T.has(msg, long, ", ")
end

tests["a channel whose distances overflow is refused"] = function()
    -- dx = 1.8e308 with an array of areas gave x = inf from node 3 on
    T.raises_here(function() return dfle.channel{ dx = 1.7976931348623157e308, area = { 1e3, 2e3, 3e3 } } end,
                  "dfle.channel: 3 nodes of dx = 1.79769e+308 m reach beyond the largest number")
    T.raises_here(function() return dfle.channel{ dx = 1e308, length = 1.5e308 } end,
                  "dfle.channel:")
end

return tests
