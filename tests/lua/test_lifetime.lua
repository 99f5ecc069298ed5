-- test_lifetime.lua - objects in use stay alive: a model closed from
-- inside its own U(t) or law, components collected by hand while a model
-- holds them, a model run again from inside its own U(t).  Each of these
-- once freed memory that was still in use, or left the model's time
-- disagreeing with what its run reported.
local tests = {}

local function small(opts)
    opts = opts or {}
    opts.channel = opts.channel or dfle.channel{ dx = 20 }
    return dfle.model(opts)
end

tests["a model closed from inside its own U(t) is an error, not freed memory"] = function()
    local m, once = nil, true
    m = small{ U = function(t)
        if t > 0 and once then
            once = false
            local closing <close> = m
        end
        return 5e-4
    end }
    T.raises_here(function() return m:run{ years = 10 } end, "U(t) failed",
                  "cannot close it while it is running")
    -- still whole and usable afterwards
    T.ok(m.time > 0 and m.time < 10)
    T.eq(#m:get("z"), m.n)
    local r = m:run{ years = 1 }
    T.eq(r.reason, "time")
end

tests["a model closed from inside its own Lua law is an error, not freed memory"] = function()
    local m, once
    for _, compile in ipairs{ false, true } do
        once = true
        local law = dfle.law.define{ compile = compile, rate = function(c, p)
            if once then
                once = false
                local closing <close> = m
            end
            return 1e-4 * c.S^6 * c.F
        end }
        m = small{ law = law }
        T.raises_here(function() return m:run{ years = 10 } end,
                      "cannot close it while it is running")
        T.eq(#m:get("S"), m.n)
    end
end

tests["components freed by hand while a model holds them stay usable until it goes"] = function()
    local ch, fl = dfle.channel{ dx = 20 }, dfle.fluvial.stochastic_threshold{}
    local rt, law = dfle.router.empirical{}, dfle.law.power{}
    local m = dfle.model{ channel = ch, fluvial = fl, router = rt, law = law }
    local ref = dfle.model{ channel = dfle.channel{ dx = 20 } }
    for _, o in ipairs{ ch, fl, rt, law } do
        local gc = debug.getmetatable(o).__gc
        gc(o)
        gc(o) -- idempotent
    end
    local r, rr = m:run{ years = 200 }, ref:run{ years = 200 }
    T.eq(r.steps, rr.steps)
    local z, zr = m:get("z"), ref:get("z")
    for i = 1, m.n do T.eq(z[i], zr[i]) end
    T.eq(rt.tau_y, 300)        -- the script's handle still reads
    m = nil
    collectgarbage()
    collectgarbage()
    T.has(tostring(rt), "closed") -- freed once the model let go
    T.raises_here(function() return rt:params() end, "closed")
end

tests["U(t) may not run its own model again; the model's time stays honest"] = function()
    local m
    m = small{ U = function(t)
        if t > 1 then m:run{ years = 5 } end
        return 5e-4
    end }
    local msg = T.raises_here(function() return m:run{ years = 10 } end, "is running already")
    T.ok(msg:find("U(t)", 1, true))
    -- the failed run simulated a little over 1 yr, and m.time says so
    T.ok(m.time > 1 and m.time < 2, m.time)
    for _, call in ipairs{
        function() m:set_z(m:get("z")) end, function() m:set_U(1e-3) end,
    } do
        m = small{ U = function(t) if t > 0 then call() end return 5e-4 end }
        T.raises_here(function() return m:run{ years = 10 } end, "is running already")
    end
end

tests["a router may not be routed again from inside its own routing"] = function()
    local rt = dfle.router.process{}
    local m
    local law = dfle.law.define{ rate = function(c, p) return 1e-4 * c.S^6 * c.F end,
        integrand = function(h, v, lambda, p) rt:route(m); return h end }
    m = small{ router = rt, law = law }
    T.raises_here(function() return rt:route(m) end, "is running already")
end

-- Found by the fuzzer (tests/fuzz/): an object collected by hand (its
-- __gc through the debug library) from inside a call on it was freed
-- when the call ended its use, and the call then read it: the field
-- values m:get returns, the report rt:route returns.  It is now closed
-- at that point and freed by its next __gc.
tests["a model collected by hand inside its own law is closed after the call, not read freed"] = function()
    local m, gc
    local law = dfle.law.define{ compile = false,
        factor = function(c, p) return c.t_p * c.h * c.Theta end,
        rate = function(c, p)
        if gc then
            local f = gc
            gc = nil
            f(m)
        end
        return 1e-4 * c.S^6 * c.F
    end }
    m = small{ law = law }
    local ref = small{ law = dfle.law.power{} }
    local z0 = ref:get("z")
    m:set_z(z0)
    gc = debug.getmetatable(m).__gc
    local z = m:get("z") -- evaluates first: z was set
    T.eq(gc, nil, "the law ran")
    for i = 1, ref.n do T.eq(z[i], z0[i]) end
    T.has(tostring(m), "closed")
    T.raises_here(function() return m:get("z") end, "dfle.model has been closed")
    T.raises_here(function() return m:run{ years = 1 } end, "dfle.model has been closed")
end

tests["a router collected by hand inside its own routing is closed after it, not read freed"] = function()
    local rt, gc
    local law = dfle.law.define{ rate = function(c, p) return 1e-4 * c.S^6 * c.F end,
        integrand = function(h, v, lambda, p)
            if gc then
                local f = gc
                gc = nil
                f(rt)
            end
            return h
        end }
    rt = dfle.router.process{ max_steps = 300 }
    local m = small{ router = rt, law = law }
    gc = debug.getmetatable(rt).__gc
    local r = rt:route(m)
    T.eq(gc, nil, "the integrand ran")
    T.close(r.volume_in, 200, 1e-12) -- the report, read after the routing
    T.ok(r.steps > 0)
    m = nil
    collectgarbage()
    collectgarbage()
    T.has(tostring(rt), "closed")
    T.raises_here(function() return rt:params() end, "dfle.router has been closed")
end

-- Found by the fuzzer (tests/fuzz/): a process router routing for one
-- model, whose law's integrand ran another model on the same router,
-- had its arrival times reallocated for the other channel under it
-- (heap-buffer-overflow), or its snapshot arrays changed by a nested
-- rt:route with snapshots.
tests["a process router used again from inside its routing is refused"] = function()
    local rt = dfle.router.process{ max_steps = 300 }
    local other, nested = nil, {}
    -- a model already evaluated (by another router): routing it with rt
    -- needs no routing first, so the snapshots are reached
    local done = dfle.model{ channel = dfle.channel{ dx = 50, A_max = 5e4 } }
    done:get("S")
    local once = true
    local law = dfle.law.define{ compile = false,
        rate = function(c, p) return 1e-4 * c.S^6 * c.F end,
        integrand = function(h, v, lambda, p)
            if once then
                once = false
                nested[1] = select(2, pcall(function() return other:get("E_df") end))
                nested[2] = select(2, pcall(function()
                    return rt:route(done, { snapshots = { 1, 2, 3, 4, 5, 6, 7, 8 } })
                end))
            end
            return h
        end }
    other = dfle.model{ channel = dfle.channel{ dx = 50, A_max = 5e4 }, router = rt,
                        law = dfle.law.power{} }
    local m = small{ channel = dfle.channel{ dx = 20 }, router = rt, law = law }
    local r = m:run{ years = 10, max_steps = 3 }
    T.eq(r.reason, "steps")
    T.has(nested[1], "dfle.router.process: used again while it is routing")
    T.has(nested[2], "snapshots cannot change while it is routing")
    local E = m:get("E_df")
    for i = 1, m.n do T.ok(E[i] == E[i] and E[i] < math.huge) end
    -- and afterwards the router routes both as before
    T.eq(#rt:route(other, { snapshots = { 1, 2 } }).snapshots, 2)
end

-- Found by the fuzzer (tests/fuzz/): the nested routing pointed the
-- router at the other model's channel and flow, and the running sweep
-- then wrote past the end of its own flow arrays.
tests["a Lua router used by another model from inside its own flow() is refused"] = function()
    local function empirical(c, p)
        local M = 3000 * (1e-6 * c.A)^0.5
        local Q = 0.135 * M^0.78
        local h = (3 * 500 * Q / (1800 * 9.81 * c.w) / c.S)^(1 / 3)
        local tau = 1800 * 9.81 * (c.w * h / (c.w + 2 * h)) * c.S / math.sqrt(1 + c.S^2)
        c.M, c.Q, c.h, c.v, c.t_p = M, Q, h, Q / (c.w * h), M / Q
        c.tau, c.Theta = tau, 1 - 300 / tau
        return tau >= 300
    end
    local other, nested_ok, nested_err
    local once = true
    local rt = dfle.router.define{ flow = function(c, p)
        if once then
            once = false
            nested_ok, nested_err = pcall(function() return other:get("E_df") end)
        end
        return empirical(c, p)
    end }
    other = dfle.model{ channel = dfle.channel{ dx = 5 }, router = rt }   -- 403 nodes
    local m = dfle.model{ channel = dfle.channel{ dx = 50, A_max = 2e5 }, router = rt }
    local ref = dfle.model{ channel = dfle.channel{ dx = 50, A_max = 2e5 },
                            router = dfle.router.define{ flow = empirical } }
    local E, E_ref = m:get("E_df"), ref:get("E_df")
    T.eq(nested_ok, false)
    T.has(nested_err, "dfle.router.lua: used again while it is routing")
    T.eq(#E, m.n)
    for i = 1, m.n do T.eq(E[i], E_ref[i]) end
end

tests["a Lua law used by another model from inside its own integrand is refused"] = function()
    for _, compile in ipairs{ false, true } do
        local other, nested_err
        local once = true
        local law = dfle.law.define{ compile = compile,
            rate = function(c, p) return 1e-4 * c.S^6 * c.F end,
            integrand = function(h, v, lambda, p)
                if once then
                    once = false
                    local ok, err = pcall(function() return other:get("E_df") end)
                    nested_err = err
                end
                return h
            end }
        local ch = dfle.channel{ dx = 50, A_max = 2e5 }
        other = dfle.model{ channel = ch, router = dfle.router.process{ max_steps = 200 }, law = law }
        local m = dfle.model{ channel = ch, router = dfle.router.process{ max_steps = 200 },
                              law = law }
        T.eq(#m:get("E_df"), m.n)
        T.has(nested_err, "dfle.law.lua: used again from inside its own functions")
    end
end

return tests
