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

tests["landscape options name themselves, not 'bad argument #-2'"] = function()
    local ls = dfle.landscape{ nx = 4, ny = 3, dx = 30 }
    local function no_argno(msg) T.ok(not msg:find("bad argument", 1, true), msg) end
    no_argno(T.raises_here(function() return ls:run{ years = 10, method = "inf" } end,
             "dfle.landscape:run: method must be 'explicit', 'implicit', 'direct' or 'auto' (got 'inf')"))
    no_argno(T.raises_here(function() return ls:run{ years = 10, method = {} } end,
             "dfle.landscape:run: method must be a string, got table"))
    no_argno(T.raises_here(function() return ls:plot(T.tmpname(".png"), { title = coroutine.create(print) }) end,
             "dfle.landscape:plot: title must be a string, got thread"))
    no_argno(T.raises_here(function() return ls:write_geotiff(T.tmpname(".tif"), { print }) end,
             "dfle.landscape:write_geotiff:", "must be a string, got function"))
    no_argno(T.raises_here(function() return dfle.landscape{ nx = 4, ny = 3, dx = 30, hillslope = "steep" } end,
             "dfle.landscape: hillslope must be 'threshold', 'diffusion' or 'uplift' (got 'steep')"))
    no_argno(T.raises_here(function() return dfle.landscape{ nx = 4, ny = 3, dx = 30, combine = "all" } end,
             "dfle.landscape: combine must be 'any' or 'count' (got 'all')"))
end

tests["dfle.args checks its own table, at the script's line"] = function()
    -- a number for flags was 'dfle.args:11: bad argument #1 to 'for iterator''
    T.raises_here(function() return dfle.args{ flags = 3 } end, "dfle.args: flags must be a table, got number")
    T.raises_here(function() return dfle.args{ options = "x" } end, "dfle.args: options must be a table")
    T.raises_here(function() return dfle.args{ flags = { quick = 1 } } end, "dfle.args: flags are name = \"help text\"")
    T.raises_here(function() return dfle.args{ options = { [2] = { "A", "b" } } } end, "dfle.args: option names")
    T.raises_here(function() return dfle.args{ usage = {} } end, "dfle.args: usage must be a string")
    T.raises_here(function() return dfle.args{ arg = { "--quick", 5 }, flags = { quick = "q" } } end,
                  "dfle.args: arg[2] must be a string, got number")
    T.eq(dfle.args{ arg = { "--quick" }, flags = { quick = "q" } }.quick, true)
end

tests["errors of calls an inversion makes for the script carry the script's line"] = function()
    -- p:channel and res:predict raised from C, with no position at all
    local dem = dfle.dem.read(T.data .. "/dem/small/testdem1.dem")
    dem:fill()
    local p = dem:network{ A_min = dem.dx * dem.dy }
    local spec = { data = p, channel = { dx = 1000 }, nbins = 3,
                   build = function(q, ch) return dfle.model{ channel = ch, U = q.U } end,
                   params = { U = { 1e-4, 1e-3 } }, walkers = 4, steps = 0, workers = 1 }
    T.raises_here(function() return dfle.invert(spec) end,
                  "dfle.invert: the data's channel: dfle.profile: the profile is", "less than 2 dx")
    local A_, S_ = {}, {}
    for i = 1, 6 do A_[i] = 2e3 * 1.6^i; S_[i] = 0.8 / (1 + (A_[i] / 3e4)^0.9) end
    local res = dfle.invert{ data = { A = A_, S = S_ }, channel = dfle.channel{ dx = 50, A_max = 5e4 },
                             build = function(q, ch) return dfle.model{ channel = ch, U = q.U } end,
                             params = { U = { 1e-4, 1e-3 } }, walkers = 4, steps = 0, workers = 1 }
    T.raises_here(function() return dfle.plot.posterior_predictive(res, T.tmpname(".png")) end,
                  "dfle.inversion:predict: there are no posterior samples")
end

tests["an inversion of a few steps is never 'converged', nor has more effective samples than samples"] = function()
    -- 2 steps after burn-in: the lag-1 correlation of two values is
    -- -1/2, so tau = 0; that made converged = true, no warning and
    -- ess = 7e16 (nsamples / 1e-16)
    local A_, S_ = {}, {}
    for i = 1, 6 do A_[i] = 2e3 * 1.6^i; S_[i] = 0.8 / (1 + (A_[i] / 3e4)^0.9) end
    for seed = 0, 3 do
        local res = dfle.invert{ data = { A = A_, S = S_ }, channel = dfle.channel{ dx = 50, A_max = 5e4 },
            build = function(q, ch) return dfle.model{ channel = ch, U = q.U, law = dfle.law.power{} } end,
            params = { U = { 1e-4, 1e-3 } }, walkers = 4, steps = 3, burn = 1, seed = seed,
            workers = 1, lsq = false }
        T.eq(res.converged, false)
        T.ok(res.ess <= res.nsamples, "ess " .. res.ess .. " > nsamples " .. res.nsamples)
        T.ok(#res.warnings >= 1 and res.warnings[1]:find("too short", 1, true), "warned")
    end
end

tests["a landscape of cells no grid has is refused"] = function()
    -- 1e300 m cells: areas inf, debris-flow volumes NaN, dem:at inf
    T.raises_here(function() return dfle.landscape{ nx = 6, ny = 5, dx = 1e300 } end,
                  "dfle.landscape: dx and dy are cell sizes from 1e-06 to 1e+06 m")
    T.raises_here(function() return dfle.landscape{ nx = 6, ny = 5, dx = 30, dy = 5e-324 } end,
                  "dfle.landscape: dx and dy are cell sizes")
    T.eq(dfle.landscape{ nx = 6, ny = 5, dx = 1e6 }.dx, 1e6)
end

tests["an output whose record's name would be too long is refused before it is written"] = function()
    -- a 255-byte name.csv is legal, name.json is 256 bytes: the CSV was
    -- written, then the record failed, leaving a file naming a record
    -- that is not there
    local dir = T.tmpname()
    os.remove(dir)
    os.execute("mkdir -p " .. T.shquote(dir))
    local m = dfle.model{ channel = dfle.channel{ dx = 50, A_max = 5e4 } }
    local name = dir .. "/" .. string.rep("n", 251) .. ".csv"
    T.raises_here(function() return m:write_csv(name) end,
                  "dfle.model:write_csv: the JSON record beside", "would have a name of 256 bytes")
    T.eq(io.open(name), nil)
    m:write_csv(name, { record = false })
    T.ok(io.open(name) ~= nil, "written without a record")
    os.execute("rm -rf " .. T.shquote(dir))
end

tests["a landscape's smallest uplift: steps it cannot resolve are refused, by name"] = function()
    -- U = 5e-324 m/yr: a step of 1e7 yr raised z by 5e-317 m, nothing
    -- moved, and the ratios |dz/dt| * (1/U) were once NaN (0 * inf); the
    -- step is refused as too short for the precision of z (the ratios'
    -- arithmetic for a subnormal U is tests/test_landscape.c's)
    local ls = dfle.landscape{ nx = 3, ny = 3, dx = 30, A0 = 900, U = 5e-324 }
    T.raises_here(function() return ls:step(1e7) end,
                  "dt = 1e+07 yr is too short for the precision of z")
    T.raises_here(function() return ls:run_to_steady{ method = "implicit" } end,
                  "dt = 1000 yr is too short for the precision of z", "take dt of at least")
    -- and a U(x, y) that gives an invalid value says where and when
    T.raises_here(function() return dfle.landscape{ nx = 3, ny = 3, dx = 30, A0 = 900,
                                                    U = function(x, y) return 0 end } end,
                  "U (uplift, m/yr) is 0 at row 1, column 1 (x = 15 m, y = 75 m), a data cell "
                  .. "at t = 0 yr; it must be")
end

tests["a landscape step that leaves no surface is an error, and undone"] = function()
    -- dt = 1e300 yr with diffusion made every elevation NaN and the step
    -- returned as if nothing happened; U = 1e300 m/yr overflowed the volumes
    local ls = dfle.landscape{ nx = 8, ny = 3, dx = 30, hillslope = "diffusion" }
    local z0 = ls:get("z")
    T.raises_here(function() return ls:step(1e300) end,
                  "dfle.landscape: a step of dt = 1e+300 yr gave elevations that are not finite",
                  "it was undone")
    local z1 = ls:get("z")
    for i = 1, #z0 do T.eq(z1[i], z0[i]) end
    T.eq(ls.time, 0)
    ls = dfle.landscape{ nx = 8, ny = 3, dx = 30, U = 1e300 }
    T.raises_here(function() return ls:step(1e10) end, "gave volumes that are not finite")
    T.ok(ls:step(10).dt == 10, "a sane step afterwards")
    -- volumes that overflow only once multiplied by the cell area
    -- (V_hillslope = inf, the sum of the volumes finite)
    -- (U large enough that a step of a year is more than z resolves)
    ls = dfle.landscape{ nx = 6, ny = 5, dx = 10, A0 = 1000, U = 1e300 }
    local z = {}
    for i = 1, 30 do z[i] = i * 5e305 end
    ls:set_z(z)
    T.raises_here(function() return ls:step(1) end, "gave volumes that are not finite")
    -- the explicit method's steps too
    ls = dfle.landscape{ nx = 3, ny = 3, dx = 30, A0 = 900, router = false, U = 1e300 }
    T.raises_here(function() return ls:run{ years = 1e10, dt = 1e10, method = "explicit", max_steps = 5 } end,
                  "gave volumes that are not finite", "it was undone")
    T.eq(ls.time, 0)
end

tests["a closed object in an options table is named, not 'bad argument #-1'"] = function()
    local ch = dfle.channel{ dx = 50, A_max = 5e4 }
    debug.getmetatable(ch).__gc(ch)
    local A_, S_ = {}, {}
    for i = 1, 6 do A_[i] = 2e3 * 1.6^i; S_[i] = 0.8 / (1 + (A_[i] / 3e4)^0.9) end
    local msg = T.raises_here(function() return dfle.invert{ data = { A = A_, S = S_ }, channel = ch,
        build = function(q, c) return dfle.model{ channel = c, U = q.U } end,
        params = { U = { 1e-4, 1e-3 } }, walkers = 4, steps = 0, workers = 1 } end,
        "dfle.channel has been closed")
    T.ok(not msg:find("bad argument", 1, true), msg)
end

tests["ens:write_netcdf checks the count against the rows"] = function()
    -- a changed count sized the buffers: Lua's bare 'block too big'
    local dir = T.tmpname()
    os.remove(dir)
    os.execute("mkdir -p " .. T.shquote(dir))
    local ens = dfle.ensemble{ params = { k_df = { 5e-5, 1e-3 } }, n = 2, seed = 1, workers = 1,
        out = dir .. "/e.csv", outputs = { "S_df" },
        build = function(p) return dfle.model{ channel = dfle.channel{ dx = 50, A_max = 5e4 },
                                               law = dfle.law.power{ k_df = p.k_df } } end }
    ens.count = -2459827872551929411
    T.raises_here(function() return ens:write_netcdf(dir .. "/e.nc") end,
                  "dfle.ensemble:write_netcdf: the result's count (-2459827872551929411) is not "
                  .. "the number of rows in data.index (2)")
    os.execute("rm -rf " .. T.shquote(dir))
end

return tests
