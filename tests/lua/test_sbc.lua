-- test_sbc.lua - the calibration check of examples/invert_sbc.lua can
-- fail: with chains far too short to leave the prior (60 steps, burn-in
-- 10) its quick mode must find the intervals miscalibrated and exit
-- with an error naming the check.  (The passing quick run is the
-- example smoke run of the test suite.)
local tests = {}

tests["sbc quick mode fails on chains too short to converge"] = function()
    local dir, cleanup = T.scratch()
    local out, ok = T.sh(("cd %s && %s -q %s --quick --steps 60 --burn 10 ."):format(
        T.shquote(dir), T.shquote(T.dfle), T.shquote(T.root .. "/examples/invert_sbc.lua")))
    cleanup()
    T.ok(not ok, "the check passed on miscalibrated chains:\n" .. out)
    T.ok(out:find("miscalibrated", 1, true) ~= nil, "no miscalibration message:\n" .. out)
    T.ok(out:find("<- off", 1, true) ~= nil, "no parameter marked off:\n" .. out)
end

return tests
