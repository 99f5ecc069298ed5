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

return tests
