-- test_invert_health.lua - what dfle.invert says about the numbers it
-- prints: a walker stranded at a prior bound (warned by number, moved
-- back in burn-in so that it cannot set an interval), no stranding
-- check on a chain too short for it, and prior-bound flags that fire on
-- a posterior cut by its prior but not where the prior itself piles.
local T = ...
local tests = {}

local CH = dfle.channel{ dx = 20, A_max = 8e6 }
local function build(p, ch)
    return dfle.model{
        channel = ch, U = p.U,
        fluvial = dfle.fluvial.stochastic_threshold{ k_e = 5e-14 },
        router = dfle.router.empirical{ M0 = 3000, gamma = 0.5, mu = 500, tau_y = 300 },
        law = dfle.law.power{ k_df = 2e-4, alpha = 6, beta = 1 },
    }
end

-- Nearly noise-free data (0.1 % of ln S) from U = 2e-3 m/yr: the
-- posterior of U is a few parts in a thousand wide.
local TRUE_U = 2e-3
local DATA = (function()
    local m = build({ U = TRUE_U }, CH)
    T.ok(m:run_to_steady{}.converged)
    local fit = assert(dfle.fit_slope_area(m, { nbins = 20 }))
    local S = {}
    for i, s in ipairs(fit.bins.S) do S[i] = s * math.exp(0.001 * math.sin(3.1 * i)) end
    return { A = fit.bins.A, S = S }
end)()

-- A broad prior on U (three decades) and the noise scale free.  With
-- seed 5 walker 7 starts next to the lower bound of U, where the line
-- to every other walker crosses a posterior far lower than its own.
local function invert(extra)
    local spec = {
        data = DATA, channel = CH, build = build, workers = 1, lsq = false,
        params = { U = { 1e-5, 1e-2, log = true } },
        walkers = 8, steps = 300, burn = 100, seed = 5,
    }
    for k, v in pairs(extra or {}) do spec[k] = v end
    return dfle.invert(spec)
end

local function row_U(path, step, walker)
    for line in io.lines(path) do
        local s, w, u = line:match("^%d+,(%d+),(%d+),([^,]+),")
        if s and tonumber(s) == step and tonumber(w) == walker then return tonumber(u), line end
    end
end

tests["a walker stranded at a prior bound is named, and moved in burn-in"] = function()
    local dir, done = T.scratch()
    -- moves off: the walker stays at the bound, is named, and its samples
    -- widen the interval to the prior's edge
    local off = invert{ move_stranded = false, out = dir .. "/off.csv" }
    T.ok(row_U(dir .. "/off.csv", 0, 7) < 3e-5, "walker 7 starts next to the lower bound")
    T.eq(#off.stranded, 1)
    T.eq(off.stranded[1].walker, 7)
    T.ok(off.stranded[1].median.U < 2e-5, "it stays there")
    T.ok(off.stranded[1].lp_drop > off.strand_drop)
    T.eq(#off.moved, 0)
    T.has(table.concat(off.warnings, "\n"), "walker 7 is stranded", "and move_stranded on")
    T.ok(off.summary.U.lo95 < 1e-4, "its samples set the interval: " .. off.summary.U.lo95)
    -- moves on (the default): moved onto a healthy walker in burn-in, a
    -- "moved" row in the file, no stranded walker after burn-in, and the
    -- interval is the data's (within 5 % of the truth)
    local on = invert{ out = dir .. "/on.csv" }
    local seven
    for _, mv in ipairs(on.moved) do
        T.ok(mv.step <= on.burn, "moved in burn-in")
        T.ok(mv.onto ~= mv.walker and mv.lp_gain > 0)
        if mv.walker == 7 then seven = mv end
    end
    T.ok(seven ~= nil, "walker 7 moved")
    local _, line = row_U(dir .. "/on.csv", seven.step, 7)
    T.match(line, ",moved$")
    T.eq(#on.stranded, 0)
    T.ok(not table.concat(on.warnings, "\n"):find("is stranded"))
    T.has(table.concat(on.warnings, "\n"), "moved back into the ensemble during burn-in")
    T.ok(on.summary.U.lo95 > 0.95 * TRUE_U and on.summary.U.hi95 < 1.05 * TRUE_U,
         ("U 95 %%: %.6g .. %.6g"):format(on.summary.U.lo95, on.summary.U.hi95))
    -- read back, the finished file reports the same moves
    local again = invert{ out = dir .. "/on.csv" }
    T.eq(again.ran, 0)
    T.eq(#again.moved, #on.moved)
    done()
end

tests["a chain shorter than 50 steps after burn-in is not checked for stranded walkers"] = function()
    -- the same stranded walker, 49 steps after burn-in: not called
    -- stranded (the warning that the chain is too short stands); 50: it is
    local short = invert{ move_stranded = false, steps = 149 }
    T.eq(#short.stranded, 0)
    T.ok(not table.concat(short.warnings, "\n"):find("is stranded"))
    T.has(table.concat(short.warnings, "\n"), "the chain is too short")
    local enough = invert{ move_stranded = false, steps = 150 }
    T.eq(#enough.stranded, 1)
    T.eq(enough.stranded[1].walker, 7)
end

tests["prior bounds: a cut posterior is flagged; a prior that piles at its bound is not"] = function()
    -- the data want U = 2e-3: a prior that ends below cuts the posterior
    local cut = invert{ params = { U = { 1e-4, 1.5e-3, log = true } }, steps = 200, burn = 50 }
    T.eq(cut.summary.U.bounded, "upper")
    T.ok(cut.summary.U.hi95 <= 1.5e-3)
    T.has(table.concat(cut.warnings, "\n"), "U is held by its prior's upper bound (0.0015)")
    -- the corner plot draws the bound, and notes it on U's marginal
    local dir, done = T.scratch()
    dfle.plot.corner(cut, dir .. "/cut.svg")
    local _, notes = assert(T.read_file(dir .. "/cut.svg")):gsub("prior bound", "")
    T.eq(notes, 1, "one note, on the diagonal")
    -- parameters the model never sees: their posterior is their prior.
    -- c: exponential (rate 1) on [0, 10], its density highest at 0; b:
    -- log-uniform, flat in ln b up to both bounds.  Neither is flagged;
    -- b is said to be not learned.
    local res = invert{
        params = { U = { 1e-4, 1e-2, log = true }, b = { 1, 100, log = true },
                   c = { 0, 10, density = function(x) return -x end } },
        sigma = 0.01, walkers = 16, steps = 600, burn = 150,
    }
    local w = table.concat(res.warnings, "\n")
    T.eq(res.summary.c.bounded, nil, "c")
    T.eq(res.summary.b.bounded, nil, "b")
    T.eq(res.summary.U.bounded, nil, "U")
    T.ok(not w:find("c is held") and not w:find("b is held"), w)
    T.has(w, "b is not learned")
    dfle.plot.corner(res, dir .. "/free.svg")
    T.ok(not assert(T.read_file(dir .. "/free.svg")):find("prior bound"), "no bound drawn")
    done()
    -- the samples do pile at c = 0, as the prior does: about 1 - exp(-h)
    -- of them within h of it, h a tenth of the 95 % interval
    local h = 0.1 * (res.summary.c.hi95 - res.summary.c.lo95)
    local near = 0
    for i = 1, res.nsamples do if res.samples.c[i] <= h then near = near + 1 end end
    T.close(near / res.nsamples, 1 - math.exp(-h), 0.3)
end

return tests
