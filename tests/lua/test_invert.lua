-- test_invert.lua - dfle.invert: the result and its summaries on a
-- synthetic profile, the chain file (rows, resume, extension, a cut last
-- line), priors (normal, log-normal, a Lua density, fixed sigma: an
-- unused parameter's posterior is its prior), the failure tally, the
-- errors, predictions and plots, DEM data with the default channel; and
-- through the CLI: the same chain for 1, 2 and 3 workers, a killed run
-- resumed, an inversion inside an ensemble, scripts that break the
-- replay rule.  In-process inversions use workers = 1: a worker replays
-- its script, and this runner is a script.  Channels have dx = 20 m.
local T = ...
local tests = {}

local q = T.shquote

local scratch, sh = T.scratch, T.sh

-- The synthetic problem: the empirical model on the paper's channel
-- (dx = 20 m), data = its binned slopes times log-normal noise drawn
-- from Lua's generator with a fixed seed.
local CH = dfle.channel{ dx = 20, A_max = 8e6 }
local function build(p, ch)
    return dfle.model{
        channel = ch, U = p.U,
        fluvial = dfle.fluvial.stochastic_threshold{ k_e = 5e-14 },
        router = dfle.router.empirical{ M0 = 3000, gamma = p.gamma or 0.5, mu = 500, tau_y = 300 },
        law = dfle.law.power{ k_df = p.k_df or 1e-4, alpha = 6, beta = 1 },
    }
end

local function synthetic(truth, sigma, seed)
    local m = build(truth, CH)
    T.ok(m:run_to_steady{}.converged)
    local fit = assert(dfle.fit_slope_area(m, { nbins = 25 }))
    math.randomseed(seed)
    local S = {}
    for i, s in ipairs(fit.bins.S) do
        local u1, u2 = math.random(), math.random()
        S[i] = s * math.exp(sigma * math.sqrt(-2 * math.log(u1)) * math.cos(2 * math.pi * u2))
    end
    return { A = fit.bins.A, S = S }, m
end

local TRUTH = { U = 4e-4, k_df = 2e-4 }
local DATA = synthetic(TRUTH, 0.1, 5)

-- A chain file's text without its date line: a resumed file is written
-- again, and the second may have ticked over.
local function undated(text)
    return (text:gsub("\n# date: [^\n]*", ""))
end

local function invert(extra)
    local spec = {
        data = DATA, channel = CH, build = build, workers = 1,
        params = { U = { 1e-4, 1e-3, log = true }, k_df = { 5e-5, 1e-3, log = true } },
        walkers = 8, steps = 150, burn = 50, seed = 3,
    }
    for k, v in pairs(extra or {}) do spec[k] = v end
    return dfle.invert(spec)
end

tests["synthetic: result, summaries, point estimate, diagnostics"] = function()
    local res = invert()
    T.eq(#res.names, 3)
    T.eq(res.names[1], "U")
    T.eq(res.names[2], "k_df")
    T.eq(res.names[3], "sigma")
    T.eq(res.nsamples, 8 * 100)
    T.eq(#res.samples.U, 800)
    T.eq(#res.samples.log_post, 800)
    for _, name in ipairs(res.names) do
        local s = res.summary[name]
        T.ok(s.lo95 <= s.lo68 and s.lo68 <= s.median and s.median <= s.hi68 and
             s.hi68 <= s.hi95, name .. ": quantiles in order")
        T.ok(res.tau[name] >= 1, name .. ": tau")
    end
    -- the truth lies inside the 95 % intervals; the noise scale is found
    T.ok(res.summary.U.lo95 < TRUTH.U and TRUTH.U < res.summary.U.hi95, "U inside 95 %")
    T.ok(res.summary.sigma.lo95 < 0.1 and 0.1 < res.summary.sigma.hi95 * 1.5, "sigma")
    -- every sample inside the priors
    for i = 1, res.nsamples do
        T.ok(res.samples.U[i] >= 1e-4 and res.samples.U[i] <= 1e-3)
    end
    T.ok(res.acceptance > 0.1 and res.acceptance < 0.9)
    T.eq(#res.acceptance_walkers, 8)
    -- the point estimate lands near the truth, with a covariance
    T.ok(res.lsq.converged, res.lsq.why)
    T.close(res.lsq.values.U, TRUTH.U, 0.15)
    T.ok(res.lsq.sd.U > 0 and res.lsq.lo95.U < res.lsq.values.U)
    T.eq(#res.lsq.cov, 2)
    T.close(res.lsq.corr[1][1], 1, 1e-12)
    T.ok(res.best.log_post >= res.samples.log_post[1])
    -- 100 steps after burn-in is far below 50 tau: said so
    T.eq(res.converged, false)
    T.has(table.concat(res.warnings, "\n"), "the chain is too short")
    T.eq(res.failures.error, 0)
    T.ok(res.evaluations >= 8 * 151)
    T.ok(res.forward_seconds > 0 and res.forward_seconds <= res.elapsed * 1.01)
    T.has(tostring(res), "dfle.invert: 8 walkers x 150 steps", "k_df", "68 % interval",
          "least squares:", "warning:")
    -- noise-free data: a much narrower posterior than with 10 % noise
    local exact, m = synthetic(TRUTH, 0.0, 5)
    local sharp = invert{ data = exact, sigma = 0.01, lsq = false }
    T.ok(sharp.summary.U.hi95 - sharp.summary.U.lo95 <
         0.3 * (res.summary.U.hi95 - res.summary.U.lo95), "narrower with less noise")
    T.ok(m ~= nil)
end

tests["prior bounds: a posterior held by its prior's bound is flagged, warned and printed"] = function()
    -- The data want U = 4e-4; a prior that ends at 2.5e-4 holds the
    -- posterior against its upper bound.
    local res = invert{ params = { U = { 1e-4, 2.5e-4, log = true },
                                   k_df = { 5e-5, 1e-3, log = true } }, lsq = false }
    T.eq(res.summary.U.bounded, "upper")
    T.ok(res.summary.U.hi95 <= 2.5e-4)
    T.has(table.concat(res.warnings, "\n"), "U is held by its prior's upper bound")
    T.has(tostring(res), "bounded: upper")
    -- a prior wide on both sides of the truth flags nothing for U
    local wide = invert{ params = { U = { 1e-5, 1e-2, log = true },
                                    k_df = { 5e-5, 1e-3, log = true } }, lsq = false }
    T.eq(wide.summary.U.bounded, nil)
end

tests["chain file: rows, extension, a cut last line, another inversion refused"] = function()
    local dir, done = scratch()
    local ref = invert{ steps = 100, out = dir .. "/ref.csv", lsq = false }
    local text = T.read_file(dir .. "/ref.csv")
    local first, comments, header = text:match("^([^\n]*)\n(.-\n)([^#][^\n]*)\n")
    T.has(first, "# dfle.invert v2 seed=3 walkers=8", "U:log-uniform[0.0001,0.001]",
          "sigma:log-uniform[0.0050000000000000001,2]", " build=")
    T.match(first, " data=%d+:%x+ channel=102:%x+ ")
    -- the lines every dfle CSV has: version, date, what made it, units
    T.match(comments, "^# dfle: %d+%.%d+%.%d+\n# date: %d%d%d%d%-%d%d%-%d%dT[%d:]+Z\n")
    T.has(comments, "# units: index=-, step=-, walker=-, U=m/yr, sigma=-, log_post=-, " ..
          "log_like=-\n")
    T.eq(header, "index,step,walker,U,k_df,sigma,log_post,log_like,proposal")
    local _, lines = text:gsub("\n", "")
    local _, ncomments = comments:gsub("\n", "")
    T.eq(lines, 2 + ncomments + 8 * 101)
    T.match(text, "\n1,0,1,[^\n]*,initial\n")
    T.eq(ref.ran, 100)
    -- a shorter run extended to 100 steps gives the same file
    local ext = dir .. "/ext.csv"
    T.eq(invert{ steps = 60, out = ext, lsq = false }.ran, 60)
    local res = invert{ steps = 100, out = ext, lsq = false }
    T.eq(res.ran, 40)
    T.eq(undated(T.read_file(ext)), undated(text))
    T.eq(res.summary.U.median, ref.summary.U.median)
    -- a finished file is read back: nothing runs
    T.eq(invert{ steps = 100, out = ext, lsq = false }.ran, 0)
    -- a killed writer: half a row at the end
    local cut = dir .. "/cut.csv"
    local keep = text:sub(1, #text - 500)
    T.write_file(cut, keep)
    res = invert{ steps = 100, out = cut, lsq = false }
    T.ok(res.ran >= 1 and res.ran <= 2)
    T.eq(undated(T.read_file(cut)), undated(text))
    -- resume = false starts afresh
    T.eq(invert{ steps = 100, out = cut, lsq = false, resume = false }.ran, 100)
    T.eq(undated(T.read_file(cut)), undated(text))
    -- a file that is no chain is refused
    T.write_file(dir .. "/junk.csv", "some,thing\n1,2\n")
    T.errors_with(function() invert{ steps = 100, out = dir .. "/junk.csv", lsq = false } end,
                  "junk.csv is not a chain of dfle.invert")
    -- another inversion's file is refused, naming it
    T.errors_with(function() invert{ steps = 100, out = cut, lsq = false, seed = 4 } end,
                  "dfle.invert: " .. cut .. " holds another inversion's chain (seed=3 in the " ..
                  "file, seed=4 here); remove it, pass resume = false")
    done()
end

tests["priors: normal, log-normal, a Lua density, fixed sigma; unused parameters keep them"] = function()
    -- dummy parameters the model never sees: their posterior is the prior
    local res = invert{
        params = {
            U = { 1e-4, 1e-3, log = true },
            a = { normal = { 2, 0.5 } },
            b = { normal = { math.log(3), 0.2 }, log = true },
            c = { 0, 10, density = function(x) return -x end }, -- exponential, rate 1
        },
        sigma = 0.1, walkers = 16, steps = 900, burn = 150, lsq = false,
    }
    T.eq(#res.names, 4) -- sigma fixed: not a parameter
    T.eq(res.sigma, 0.1)
    local function check(name, f, want, sd)
        local x, n = res.samples[name], res.nsamples
        local mean = 0
        for i = 1, n do mean = mean + f(x[i]) end
        mean = mean / n
        -- Monte-Carlo error from the autocorrelation time of the samples
        local se = sd * math.sqrt(res.tau[name] / n)
        T.ok(math.abs(mean - want) < 4 * se,
             ("%s: %.4f, expected %.4f (4 MC errors = %.4f)"):format(name, mean, want, 4 * se))
    end
    check("a", function(v) return v end, 2, 0.5)
    check("b", math.log, math.log(3), 0.2)
    check("c", function(v) return v end, 1 - 10 * math.exp(-10) / (1 - math.exp(-10)), 1)
    for i = 1, res.nsamples do T.ok(res.samples.c[i] >= 0 and res.samples.c[i] <= 10) end
    -- the least-squares covariance of a parameter the data do not see
    local lsq = invert{ params = { U = { 1e-4, 1e-3, log = true }, a = { 0, 1 } }, steps = 0 }.lsq
    T.eq(lsq.cov_ok, false)
    T.has(lsq.why, "singular")
end

tests["failed forward runs are zero likelihood, tallied, never fatal"] = function()
    local dir, done = scratch()
    local short = dfle.channel{ dx = 20, A_max = 1e6 }
    local function failing(p, ch)
        if p.k_df > 6e-4 then error("k_df too large for this test") end
        if p.k_df > 4e-4 then return build(p, short) end     -- data beyond its channel
        if p.U > 4.4e-4 then                                  -- no steady state
            return dfle.model{ channel = ch, U = p.U, fluvial = false, router = false }
        end
        return build(p, ch)
    end
    -- run = {max_time}: only the fallback stepping of a model without a
    -- steady state (nothing erodes) uses it
    local res = invert{ out = dir .. "/f.csv", steps = 120, lsq = false, run = { max_time = 2e3 },
                        build = failing }
    T.ok(res.failures.error > 0, "errors tallied")
    T.ok(res.failures.invalid_profile > 0, "invalid profiles tallied")
    T.ok(res.failures.not_converged > 0, "runs without a steady state tallied")
    T.has(res.failure_messages.error, "k_df too large for this test")
    T.has(res.failure_messages.invalid_profile, "outside the model channel's areas")
    T.has(res.failure_messages.not_converged, "no steady state")
    for i = 1, res.nsamples do T.ok(res.samples.k_df[i] <= 4e-4) end
    -- a walker whose proposal failed stays where it was
    local rows, pos = {}, {}
    for line in io.lines(dir .. "/f.csv") do
        local step, walker, U, status = line:match("^%d+,(%d+),(%d+),([^,]+),.*,(%a[%w_]*)$")
        if step then
            step, walker = tonumber(step), tonumber(walker)
            pos[step * 8 + walker] = U
            if status == "error" or status == "not_converged" or status == "invalid_profile" then
                rows[#rows + 1] = { step, walker }
            end
        end
    end
    T.ok(#rows > 0)
    for _, r in ipairs(rows) do
        T.eq(pos[r[1] * 8 + r[2]], pos[(r[1] - 1) * 8 + r[2]], "failed proposal kept the walker")
    end
    -- the tally is in the file: a finished chain read back gives it again
    local again = invert{ out = dir .. "/f.csv", steps = 120, lsq = false, run = { max_time = 2e3 },
                          build = failing }
    T.eq(again.ran, 0)
    T.eq(again.failures.error, res.failures.error)
    -- nothing works anywhere: a clear error, not a hang
    T.errors_with(function() invert{ lsq = false, build = function() error("broken build") end } end,
                  "dfle.invert: no starting point with a non-zero posterior for walker 1 in 100 draws",
                  "broken build")
    done()
end

tests["errors name the parameter and the line"] = function()
    local P = { U = { 1e-4, 1e-3, log = true } }
    local function spec(extra)
        local s = { data = DATA, channel = CH, build = build, params = P, workers = 1,
                    steps = 10, burn = 2, lsq = false }
        for k, v in pairs(extra) do s[k] = v end
        return s
    end
    T.raises_here(function() dfle.invert(spec{ build = 3 }) end,
                  "dfle.invert: parameter 'build' must be a function(p, channel)")
    T.raises_here(function() dfle.invert(spec{ params = {} }) end, "'params' is empty")
    T.raises_here(function() dfle.invert(spec{ stepz = 3 }) end, "unknown parameter 'stepz'")
    T.raises_here(function() dfle.invert(spec{ params = { U = { 2, 1 } } }) end,
                  "parameter U: the range needs lo < hi")
    T.raises_here(function() dfle.invert(spec{ params = { U = { 0, 1, log = true } } }) end,
                  "parameter U: a log-uniform prior needs 0 < lo")
    T.raises_here(function() dfle.invert(spec{ params = { U = { 1 } } }) end,
                  "parameter 'U': the range needs hi")
    T.raises_here(function() dfle.invert(spec{ params = { U = { 1, 2, lg = true } } }) end,
                  "parameter 'U': unknown key 'lg'")
    T.raises_here(function() dfle.invert(spec{ params = { U = { normal = { 1 } } } }) end,
                  "parameter 'U': normal must be {mean, sd}")
    T.raises_here(function() dfle.invert(spec{ params = { U = { 1, 2, density = 3 } } }) end,
                  "parameter 'U': density must be a function(x)")
    T.raises_here(function() dfle.invert(spec{ params = { sigma = { 0, 1 } } }) end,
                  "parameter name 'sigma' is reserved for the noise scale")
    T.raises_here(function() dfle.invert(spec{ params = { ["a b"] = { 0, 1 } } }) end,
                  "parameter name 'a b' cannot be a CSV column")
    T.raises_here(function() dfle.invert(spec{ fixed = { U = 1 } }) end,
                  "'U' is both a free and a fixed parameter")
    T.raises_here(function() dfle.invert(spec{ fixed = { t = {} } }) end,
                  "fixed parameter 't' must be a number, string or boolean")
    T.raises_here(function() dfle.invert(spec{ sigma = 0 }) end, "sigma (the noise sd of ln S) must be > 0")
    T.raises_here(function() dfle.invert(spec{ nbins = 20 }) end, "'nbins' bins DEM data")
    T.raises_here(function() dfle.invert(spec{ data = 5 }) end,
                  "parameter 'data' must be a DEM profile or network")
    T.raises_here(function() dfle.invert(spec{ data = { A = { 1, 2, 3 }, S = { 1, -1, 1 } } }) end,
                  "data pair 2: A = ")
    T.raises_here(function() dfle.invert(spec{ data = "/nonexistent/bins.csv" }) end,
                  "dfle.invert: data: ", "bins.csv")
    T.raises_here(function() dfle.invert(spec{ channel = { dx = 5 } }) end,
                  "a channel from options {dx = ...} follows a DEM profile")
    T.raises_here(function() dfle.invert(spec{ channel = 5 }) end, "parameter 'channel' must be")
    T.raises_here(function() dfle.invert(spec{ data = { A = { 1e3, 1e4 }, S = { 0.5, 0.3 } } }) end,
                  "2 data bins for 1 free parameters: too few")
    T.raises_here(function() dfle.invert(spec{ walkers = 5 }) end, "walkers must be even")
    T.raises_here(function() dfle.invert(spec{ walkers = 4.5 }) end, "walkers must be a whole number")
    T.raises_here(function() dfle.invert(spec{ walkers = 2 }) end, "walkers must be a whole number in [4")
    T.raises_here(function() dfle.invert(spec{ burn = 10 }) end,
                  "burn (10) must be less than steps (10)")
    T.raises_here(function() dfle.invert(spec{ a = 1 }) end, "a (the stretch scale) must be > 1")
    T.raises_here(function() dfle.invert(spec{ out = 3 }) end, "parameter 'out' (the chain's CSV file)")
    T.raises_here(function() dfle.invert(spec{ lsq = 1 }) end, "parameter 'lsq' must be a boolean")
    T.raises_here(function() dfle.invert(spec{ out = "/nonexistent/dir/c.csv" }) end,
                  "dfle.invert: /nonexistent/dir/c.csv")
end

tests["binned data from a CSV file equal the same table"] = function()
    local dir, done = scratch()
    local lines = { "# binned slope-area data", "A,S" }
    for i = 1, #DATA.A do lines[#lines + 1] = ("%.17g,%.17g"):format(DATA.A[i], DATA.S[i]) end
    T.write_file(dir .. "/bins.csv", table.concat(lines, "\n") .. "\n")
    local a = invert{ steps = 30, burn = 10, lsq = false }
    local b = invert{ data = dir .. "/bins.csv", steps = 30, burn = 10, lsq = false }
    T.eq(b.data.kind, "file")
    T.eq(b.summary.U.median, a.summary.U.median)
    T.write_file(dir .. "/bad.csv", "A,S\n1000,0.5\n2000,0\n")
    T.errors_with(function() invert{ data = dir .. "/bad.csv" } end, "bad.csv:3: A = 2000")
    T.write_file(dir .. "/cols.csv", "area,slope\n1,2\n")
    T.errors_with(function() invert{ data = dir .. "/cols.csv" } end, "no column 'A'")
    done()
end

tests["predict and the two figures"] = function()
    local dir, done = scratch()
    local exact, m = synthetic(TRUTH, 0, 5)
    local res = invert{ steps = 120, lsq = false }
    local pp = res:predict{ n = 30 }
    T.eq(pp.n, 30)
    T.eq(#pp.A, 120)
    local inside = 0
    for i = 1, #pp.A do
        T.ok(pp.lo95[i] <= pp.lo68[i] and pp.lo68[i] <= pp.median[i] and
             pp.median[i] <= pp.hi68[i] and pp.hi68[i] <= pp.hi95[i])
        T.ok(pp.obs_lo95[i] < pp.lo95[i] and pp.obs_hi95[i] > pp.hi95[i], "noise widens")
    end
    -- the noise-free truth lies mostly inside the model's 95 % band
    local band = res:predict{ n = 40, A = exact.A }
    for i = 1, #exact.A do
        if band.lo95[i] <= exact.S[i] and exact.S[i] <= band.hi95[i] then inside = inside + 1 end
    end
    T.ok(inside >= 0.7 * #exact.A, inside .. " of " .. #exact.A .. " bins inside the band")
    dfle.plot.corner(res, dir .. "/c.png", { truth = TRUTH, title = "test",
                                             labels = { U = "{/:Italic U}" } })
    dfle.plot.corner(res, dir .. "/c2.svg", { params = { "sigma", "U" } })
    dfle.plot.posterior_predictive(res, dir .. "/pp.png", { n = 20, truth = m })
    for _, f in ipairs{ "c.png", "c2.svg", "pp.png" } do
        local t = T.read_file(dir .. "/" .. f)
        T.ok(t and #t > 1000, f .. " written")
    end
    T.raises_here(function() dfle.plot.corner(res, dir .. "/x.png", { params = { "nope" } }) end,
                  "'nope' is not a parameter of the inversion")
    T.raises_here(function() dfle.plot.corner({}, dir .. "/x.png") end, "expected the result of dfle.invert")
    T.raises_here(function() res:predict{ n = 0 } end, "n must be a whole number")
    done()
end

tests["DEM profile: binned by nbins, the default channel on its main stem"] = function()
    local path = T.data .. "/dem/srtm_bigtujunga30m_utm11.tif"
    if not T.read_file(path) then
        print("  (skipped: " .. path .. " not found)")
        return
    end
    local dem = dfle.dem.read(path)
    dem:fill()
    local net = dem:network{ A_min = 900, outlet = { 396887, 3799338 } }
    -- the network's main stem is the profile traced from the same outlet
    local stem, prof = net:main_stem(), dem:profile{ outlet = { 396887, 3799338 } }
    T.eq(stem.kind, "profile")
    T.eq(stem.n, prof.n)
    local sa, pa, sx, px = stem:get("A"), prof:get("A"), stem:get("x"), prof:get("x")
    for i = 1, prof.n do
        T.eq(sa[i], pa[i])
        T.close(sx[i], px[i], 1e-12, 1e-9)
    end
    T.eq(prof:main_stem().n, prof.n)
    local res = dfle.invert{
        data = net, nbins = 20, channel = { dx = 30 }, workers = 1, lsq = false,
        build = build, params = { U = { 1e-4, 1e-3, log = true } },
        walkers = 6, steps = 12, burn = 2,
    }
    T.eq(res.data.kind, "network")
    T.ok(#res.data.A >= 15 and #res.data.A <= 20)
    T.eq(res.data.outside, 0)
    T.eq(#res.data.raw.A, net.n)
    T.ok(res.summary.U.median > 1e-4)
end

---------------------------------------------------------------------------
-- Through the CLI: worker threads.
---------------------------------------------------------------------------

local SCRIPT = [[
local out, steps, extra = arg[1], tonumber(arg[2]), arg[3] or ""
local slow = load(extra)
local ch = dfle.channel{ dx = 20, A_max = 8e6 }
local function build(p, c)
  slow()
  return dfle.model{ channel = c, U = p.U,
    fluvial = dfle.fluvial.stochastic_threshold{ k_e = 5e-14 },
    router = dfle.router.empirical{ M0 = 3000, gamma = p.gamma, mu = 500, tau_y = 300 },
    law = dfle.law.power{ k_df = 2e-4, alpha = 6, beta = 1 } }
end
local m = build({ U = 4e-4, gamma = 0.5 }, ch)
m:run_to_steady{}
local fit = dfle.fit_slope_area(m, { nbins = 20 })
local S = {}
for i, s in ipairs(fit.bins.S) do S[i] = s * math.exp(0.1 * math.sin(3.1 * i)) end
local res = dfle.invert{
  data = { A = fit.bins.A, S = S }, channel = ch, build = build, lsq = false,
  params = { U = { 1e-4, 1e-3, log = true }, gamma = { 0, 1 } },
  walkers = 8, steps = steps, burn = 10, seed = 2, out = out,
}
print(("ran=%d reason=%s have=%d"):format(res.ran, res.reason, res.have))
if res.reason == "complete" then print(("median=%.17g"):format(res.summary.U.median)) end
]]

-- A chain file without the lines that say when and by which command it
-- was made (the rest, the chain and its identity, is compared whole).
local function chain(path)
    local text = assert(T.read_file(path), path)
    return (text:gsub("\n# date: [^\n]*", ""):gsub("\n# command: [^\n]*", ""))
end

local function run(dir, flags, ...)
    local cmd = "cd " .. q(dir) .. " && " .. q(T.dfle) .. " -q " .. flags .. " inv.lua"
    for _, a in ipairs{ ... } do cmd = cmd .. " " .. q(a) end
    local out, ok = sh(cmd)
    T.ok(ok, "dfle failed: " .. out)
    return out
end

tests["CLI: the same chain for 1, 2 and 3 workers"] = function()
    local dir, done = scratch()
    T.write_file(dir .. "/inv.lua", SCRIPT)
    local o1 = run(dir, "-j 1", "c1.csv", "60")
    local o2 = run(dir, "-j 2", "c2.csv", "60")
    local o3 = run(dir, "-j 3", "c3.csv", "60")
    T.eq(o2, o1)
    T.eq(o3, o1)
    T.eq(chain(dir .. "/c2.csv"), chain(dir .. "/c1.csv"))
    T.eq(chain(dir .. "/c3.csv"), chain(dir .. "/c1.csv"))
    done()
end

tests["CLI: a killed parallel run resumes to the same chain"] = function()
    local dir, done = scratch()
    T.write_file(dir .. "/inv.lua", SCRIPT)
    run(dir, "-j 1", "ref.csv", "40")
    -- each build busy-waits 2 ms (40 steps x 8 walkers >= 0.6 s with two
    -- threads); kill -9 once 3 steps are on disk; the wait is bounded
    local delay = "local c = os.clock() while os.clock() - c < 0.002 do end"
    sh("cd " .. q(dir) .. " && { " .. q(T.dfle) .. " -q -j 2 inv.lua k.csv 40 " .. q(delay) ..
       " & pid=$!; i=0; while [ $i -lt 3000 ]; do" ..
       " [ \"$(grep -c '' k.csv 2>/dev/null)\" -ge 26 ] 2>/dev/null && break;" ..
       " sleep 0.01; i=$((i+1)); done; kill -9 $pid; wait $pid; }")
    local partial = T.read_file(dir .. "/k.csv")
    T.ok(partial ~= nil, "the killed run left a file")
    local _, lines = partial:gsub("\n", "")
    T.ok(lines - 2 >= 8 and lines - 2 < 8 * 41, "killed mid-run after " .. (lines - 2) .. " rows")
    local out = run(dir, "-j 2", "k.csv", "40")
    local ran = tonumber(out:match("ran=(%d+)"))
    T.ok(ran >= 1 and ran < 40, "resumed the missing steps only (" .. ran .. ")")
    T.eq(chain(dir .. "/k.csv"), chain(dir .. "/ref.csv"))
    done()
end

tests["CLI: SIGINT and SIGTERM stop at a whole step, reason 'interrupted', and resume exactly"] = function()
    -- The k-th forward run (k drawn anew each time) signals dfle itself
    -- (through popen: os.execute would have SIGINT ignored while its
    -- shell runs).  dfle.invert returns at the last whole step with reason
    -- "interrupted" (not raised), no run cut short by the signal is a row
    -- (no "error" rows), the file holds whole steps, the exit status is
    -- 130 or 143, and the same command continues to the uninterrupted
    -- chain.
    local dir, done = scratch()
    T.write_file(dir .. "/inv.lua", SCRIPT)
    run(dir, "-j 1", "ref.csv", "40")
    for _, case in ipairs{ { "INT", 130, "-j 1" }, { "TERM", 143, "-j 2" },
                           { "INT", 130, "-j 2" }, { "TERM", 143, "-j 1" } } do
        local sig, status, j = case[1], case[2], case[3]
        local k = math.random(5, 150)
        local name = ("s%s%s.csv"):format(sig, j:sub(-1))
        local signal = ("N = (N or 0) + 1 if N == %d and not io.open('%s.sent') then " ..
                        "io.open('%s.sent', 'w'):close() io.popen('kill -%s $PPID'):close() end")
                       :format(k, name, name, sig)
        local what = ("SIG%s at forward run %d, %s"):format(sig, k, j)
        local out, ok, code = sh("cd " .. q(dir) .. " && " .. q(T.dfle) .. " -q " .. j ..
                                 " inv.lua " .. name .. " 40 " .. q(signal))
        T.eq(ok, nil, what .. ": " .. out)
        T.eq(code, status, what .. ": " .. out)
        local have = tonumber(out:match("reason=interrupted have=(%d+)"))
        T.ok(have ~= nil and have < 40, what .. ": " .. out)
        T.has(out, "interrupted by SIG" .. sig, "dfle.invert stopped after step " .. have ..
              " of 40", "running the script again resumes it")
        T.ok(not out:find("median="), what .. ": no posterior from a cut chain")
        local text = T.read_file(dir .. "/" .. name)
        local rows, errors = 0, 0
        for line in text:gmatch("[^\n]+") do
            if line:match("^%d") then
                rows = rows + 1
                if line:match(",error$") then errors = errors + 1 end
            end
        end
        T.eq(rows, 8 * (have + 1), what .. ": whole steps only")
        T.eq(errors, 0, what .. ": no forward run counted as failed")
        local again = run(dir, j, name, "40")
        T.has(again, ("ran=%d reason=complete"):format(40 - have))
        T.eq(chain(dir .. "/" .. name), chain(dir .. "/ref.csv"), what .. ": resumed")
    end
    done()
end

tests["CLI: inversions inside an ensemble run in the sample's state"] = function()
    local dir, done = scratch()
    T.write_file(dir .. "/cov.lua", [[
local ch = dfle.channel{ dx = 20, A_max = 8e6 }
local function build(p, c)
  return dfle.model{ channel = c, U = p.U, law = dfle.law.power{ k_df = 2e-4, alpha = 6 } }
end
local ens = dfle.ensemble{
  params = { U = { 2e-4, 8e-4 } }, n = 4, seed = 1, out = arg[1],
  build = function(p) return build(p, ch) end,
  outputs = { "U_median" },
  measure = function(m, fit, p)
    local res = dfle.invert{
      data = { A = fit.bins.A, S = fit.bins.S }, channel = ch, build = build, lsq = false,
      params = { U = { 1e-4, 1e-3, log = true } }, sigma = 0.05,
      walkers = 4, steps = 20, burn = 5, seed = 1,
    }
    return { U_median = res.summary.U.median }
  end,
}
print("ok", ens.ok)
]])
    local o1 = sh("cd " .. q(dir) .. " && " .. q(T.dfle) .. " -q -j 1 cov.lua e1.csv")
    local o2 = sh("cd " .. q(dir) .. " && " .. q(T.dfle) .. " -q -j 2 cov.lua e2.csv")
    T.has(o1, "ok\t4")
    T.eq(o2, o1)
    T.eq(T.read_file(dir .. "/e2.csv"), T.read_file(dir .. "/e1.csv"))
    done()
end

tests["CLI: scripts that break the replay rule are stopped with a reason"] = function()
    local dir, done = scratch()
    -- the data differ in workers: the problem is not the same
    T.write_file(dir .. "/inv.lua", SCRIPT:gsub("0%.1 %* math%.sin", "(dfle.worker() and 0.2 or 0.1) * math.sin"))
    local out, ok = sh("cd " .. q(dir) .. " && " .. q(T.dfle) .. " -q -j 2 inv.lua d.csv 30")
    T.eq(ok, nil)
    T.has(out, "dfle.invert: worker: the script built a different inversion when run again",
          "the rows written are kept")
    -- an earlier inversion without a file cannot be replayed
    T.write_file(dir .. "/two.lua", SCRIPT .. [[
dfle.invert{ data = { A = fit.bins.A, S = S }, channel = ch, build = build, lsq = false,
             params = { U = { 1e-4, 1e-3, log = true } }, walkers = 4, steps = 5, burn = 1 }
dfle.invert{ data = { A = fit.bins.A, S = S }, channel = ch, build = build, lsq = false,
             params = { U = { 1e-4, 1e-3, log = true } }, walkers = 4, steps = 5, burn = 1 }
]])
    out, ok = sh("cd " .. q(dir) .. " && " .. q(T.dfle) .. " -q -j 2 two.lua t.csv 12")
    T.eq(ok, nil)
    T.has(out, "has no 'out' file to read its result from")
    done()
end

return tests
