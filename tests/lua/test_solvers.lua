-- test_solvers.lua - choosing how to reach the answer from Lua.
local tests = {}

local function model(extra)
    local o = { channel = dfle.channel{ dx = 10 } }
    for k, v in pairs(extra or {}) do o[k] = v end
    return dfle.model(o)
end

tests["run_to_steady: every method reaches the same steady state"] = function()
    local S = {}
    for _, method in ipairs{ "explicit", "implicit", "direct", "auto" } do
        local m = model()
        local r = m:run_to_steady{ method = method }
        T.ok(r.converged, method)
        T.eq(r.fallback, false)
        T.eq(r.method, method == "auto" and "direct" or method)
        S[method] = m:get("S")
    end
    for _, method in ipairs{ "implicit", "direct", "auto" } do
        for i = 1, #S.explicit - 1 do T.close(S[method][i], S.explicit[i], 5e-3, 0) end
    end
end

tests["run_to_steady: the direct method says when it falls back"] = function()
    local m = model{ fluvial = false, router = dfle.router.empirical{ tau_y = 3000 } }
    local r = m:run_to_steady{ method = "direct", max_time = 1e4 }
    T.eq(r.fallback, true)
    T.eq(r.method, "implicit")
    T.eq(r.converged, false)
    T.has(r.note, "direct:", "continued by implicit stepping")
end

tests["run: an implicit transient far from equilibrium neither crawls nor drifts"] = function()
    -- From the default (fluvial) start the debris flows carve tens of
    -- metres in the first year and their runout moves from step to step;
    -- error control once halved the step to 1e-11 yr there (hours for
    -- one simulated year).  Bounded by max_steps, it must now finish, and
    -- closer to a fine explicit reference than the default explicit run.
    local ref = dfle.model{ cfl = 0.05 }
    ref:run{ years = 1 }
    local e = dfle.model{}
    e:run{ years = 1 }
    local m = dfle.model{}
    local r = m:run{ years = 1, method = "implicit", max_steps = 5000 }
    T.eq(r.reason, "time")
    T.close(r.time, 1, 1e-12, 0)
    T.ok(r.steps < 5000, r.steps)
    local zr, ze, zi = ref:get("z"), e:get("z"), m:get("z")
    local err_e, err_i = 0, 0
    for i = 1, m.n do
        err_e = math.max(err_e, math.abs(ze[i] - zr[i]))
        err_i = math.max(err_i, math.abs(zi[i] - zr[i]))
    end
    T.ok(err_i < err_e, ("implicit error %g m, explicit %g m"):format(err_i, err_e))
end

tests["run_to_steady: erosion that falls as slope rises is named, not a convergence failure"] = function()
    -- alpha = 0 and tau_y = 0 are both valid, together E_df ~ h ~ S^(-1/3):
    -- no slope balances U at the head.  The direct method must fall back
    -- as documented, and the implicit method must say why it cannot go on.
    local m = dfle.model{ router = dfle.router.empirical{ tau_y = 0 }, law = dfle.law.power{ alpha = 0 } }
    local ok, msg = pcall(function() return m:run_to_steady{} end)
    T.ok(not ok)
    T.has(msg, "no steady state by the direct method", "does not grow with slope",
          "alpha = 0 with tau_y = 0", "implicit stepping then failed")
    T.ok(not msg:find("did not converge"), msg)
end

tests["run: implicit transients and recorded profiles"] = function()
    local m = model()
    m:run_to_steady{}
    m:set_U(1e-3)
    local r = m:run{ years = 2e4, method = "implicit", record = { 0, 5e3, 2e4 } }
    T.eq(r.method, "implicit")
    T.eq(#r.records, 3)
    T.eq(r.records[2].t, 5e3)
    T.eq(#r.records[1].z, m.n)
    -- Uplift doubled: the head rises, the outlet stays.
    T.ok(r.records[3].z[1] > r.records[1].z[1] + 1)
    T.eq(r.records[3].z[m.n], 0)
    T.close(m.time, 2e4, 1e-12, 0)
end

tests["run: any parameter changes mid-run by carrying the profile to a new model"] = function()
    local ch = dfle.channel{ dx = 20 }
    local m1 = dfle.model{ channel = ch, law = dfle.law.power{ k_df = 1e-4 } }
    m1:run_to_steady{}
    local m2 = dfle.model{ channel = ch, law = dfle.law.power{ k_df = 2e-4 } }
    m2:set_z(m1:get("z"))
    local r = m2:run{ years = 5e4, method = "implicit", record = { 0, 5e4 } }
    local z0, z1 = r.records[1].z, r.records[2].z
    for i = 1, #z0 do T.eq(z0[i], m1:get("z")[i]) end
    -- More erodible bedrock: the debris-flow reach at the head lowers.
    T.ok(z1[1] < z0[1] - 1, ("head %.2f -> %.2f m"):format(z0[1], z1[1]))
    local new = dfle.model{ channel = ch, law = dfle.law.power{ k_df = 2e-4 } }
    new:run_to_steady{}
    T.ok(m2:run_to_steady{}.converged)
    local a, b = m2:get("S"), new:get("S")
    for i = 1, #a - 1 do T.close(a[i], b[i], 5e-3, 0) end
end

tests["method and record errors name themselves"] = function()
    local m = model()
    T.raises_here(function() return m:run_to_steady{ method = "newton" } end, "method must be 'explicit', 'implicit', 'direct' or 'auto' (got 'newton')")
    T.raises_here(function() return m:run_to_steady{ method = 3 } end, "'method' must be a string")
    T.raises_here(function() return m:run{ years = 10, method = "direct" } end, "steady states only")
    T.raises_here(function() return m:run{ years = 10, record = { 5, 2 } } end, "record times must increase")
    T.raises_here(function() return m:run{ years = 10, record = { 20 } } end, "record times must increase")
    T.raises_here(function() return m:run{ years = 10, rtol = 0 } end, "rtol must be in (0, 1)")
    T.raises_here(function() return m:run_to_steady{ direct_tol = 2 } end, "direct_tol must be in (0, 1)")
end

-- The recorded states as a CF NetCDF file (the values themselves are
-- read back in tests/test_netcdf.c; here: the binding's part).
tests["run: record = {...}, netcdf = path writes the recorded states"] = function()
    local m = model()
    local nc = T.tmpname(".nc")
    local r = m:run{ years = 1000, record = { 0, 500, 1000 }, netcdf = nc }
    T.eq(#r.records, 3)
    local s = assert(T.read_file(nc))
    T.eq(s:sub(1, 4), "\137HDF", "netCDF-4 (HDF5)")
    T.has(s, "Conventions", "CF-1.8", "history", "elevation above the outlet",
          "common_years since 0000-01-01 00:00:00", "noleap")
    T.ok(not s:find("featureType", 1, true), "no featureType: a long profile is no CF profile")
    local f32 = T.tmpname(".nc")
    m:run{ years = 100, record = { 100 }, netcdf = f32, float32 = true }
    T.ok(T.read_file(f32) ~= nil, "float32 written")
    T.raises_here(function() return m:run{ years = 10, netcdf = nc } end, "give 'record' times too")
    T.raises_here(function() return m:run{ years = 10, record = { 5 }, netcdf = 7 } end, "netcdf")
    T.raises_here(function() return m:run{ years = 10, float32 = true } end,
                  "parameter 'float32' (true or false) goes with 'netcdf'")
    T.raises_here(function() return m:run{ years = 10, record = { 5 }, netcdf = nc, float32 = 1 } end,
                  "parameter 'float32' (true or false) goes with 'netcdf'")
end

return tests
