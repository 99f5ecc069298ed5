-- test_geometry.lua - channel geometry from Lua: area(x), width(A), arrays.
local tests = {}

tests["area(x) written as the default Hack law gives the default channel"] = function()
    local c1 = dfle.channel{ area = function(x) return 1000 + 25 * x ^ (5 / 3) end }
    local c0 = dfle.channel{}
    T.eq(c1.n, c0.n)
    local A1, A0, w1, w0 = c1:get("A"), c0:get("A"), c1:get("w"), c0:get("w")
    for i = 1, #A0 do
        T.close(A1[i], A0[i], 1e-12, 0)
        T.close(w1[i], w0[i], 1e-12, 0)
    end
end

tests["length sets the nodes of a user area(x); width(A) sets widths"] = function()
    local ch = dfle.channel{ dx = 10, length = 50,
                             area = function(x) return 2000 + 100 * x end,
                             width = function(A) return A / 1000 end }
    T.eq(ch.n, 6)
    local A, w = ch:get("A"), ch:get("w")
    for i = 1, 6 do
        T.close(A[i], 2000 + 100 * 10 * (i - 1), 1e-15, 0)
        T.close(w[i], A[i] / 1000, 1e-15, 0)
    end
end

tests["arrays give the nodes directly and a model runs on them"] = function()
    local A, w = {}, {}
    for i = 1, 60 do A[i] = 1000 * 1.1 ^ i; w[i] = 0.05 * A[i] ^ 0.3 end
    local ch = dfle.channel{ dx = 10, area = A, width = w }
    T.eq(ch.n, 60)
    T.close(ch.length, 590, 1e-15, 0)
    local m = dfle.model{ channel = ch, router = false }
    T.ok(m:run_to_steady{}.converged)
end

tests["geometry errors name the parameter and the caller's line"] = function()
    T.raises_here(function() return dfle.channel{ area = function() return "big" end } end,
                  "area(x) must return a number", "string")
    T.raises_here(function() return dfle.channel{ area = function() return 5 end } end,
                  "did not reach A_max")
    T.raises_here(function() return dfle.channel{ area = function(x) return 1000 - x end, length = 100 } end,
                  "must not decrease downstream")
    T.raises_here(function() return dfle.channel{ area = { 1, 2, 3 }, A0 = 5 } end,
                  "give 'A0' or 'area', not both")
    T.raises_here(function() return dfle.channel{ area = { 1, 2, 3 }, length = 5 } end,
                  "drop length and A_max")
    T.raises_here(function() return dfle.channel{ width = { 1, 2 } } end,
                  "width has 2 values but the channel has 403 nodes")
    T.raises_here(function() return dfle.channel{ width = 3 } end,
                  "'width' must be a function or an array of numbers, got number")
    T.raises_here(function() return dfle.channel{ width = function() return 1 end, b = 0.4 } end,
                  "give 'width' or k_w and b, not both")
    T.raises_here(function() return dfle.channel{ area = { 1000, 2000, "x" } } end,
                  "channel: area[3] must be a number")
end

tests["an error inside the user's function carries the user's own line"] = function()
    local line = debug.getinfo(1, "l").currentline + 1
    local f = function() error("no data here") end
    local msg = T.errors(function() return dfle.channel{ width = f } end)
    T.has(msg, "test_geometry.lua:" .. line .. ": no data here")
end

return tests
