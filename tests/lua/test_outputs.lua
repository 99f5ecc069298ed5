-- test_outputs.lua - outputs that describe themselves: CSV files with
-- their provenance and units, the JSON run records beside them, fit and
-- bin writers, dfle.write_csv.
local T = ...
local tests = {}

-- A 45-node model: records do not need more.
local function small_model(opts)
    local o = { channel = dfle.channel{ A_max = 2e5 } }
    for k, v in pairs(opts or {}) do o[k] = v end
    return dfle.model(o)
end

local function comments_text(tab) return table.concat(tab.comments, "\n") .. "\n" end

local function json_of(path) return T.json_decode(assert(T.read_file(path), path)) end

tests["model:write_csv: provenance and units above plain names; the record beside it"] = function()
    local csv = T.tmpname(".csv")
    local json = csv:sub(1, -5) .. ".json"
    local m = small_model{ router = dfle.router.empirical{ tau_y = 200 }, U = 1e-3 }
    local run = m:run_to_steady{ tol = 1e-4 }
    local png = T.tmpname(".png")
    dfle.plot.profile(m, png)
    m:write_csv(csv)
    local tab = T.read_csv(csv)
    local c = comments_text(tab)
    T.eq(tab.comments[1], "# dfle: " .. dfle.version)
    T.match(c, "\n# date: %d%d%d%d%-%d%d%-%d%dT%d%d:%d%d:%d%dZ\n")
    T.has(c, "\n# record: " .. json .. "\n",
          "\n# router empirical: M0=3000 m^(3-2 gamma), gamma=0.5, mu=500 Pa s, tau_y=200 Pa,",
          "\n# law power: k_df=0.0001, alpha=6, beta=1\n",
          "\n# model: U=0.001 m/yr, cfl=0.5, dt_max=1000 yr, time=0 yr\n",
          "\n# run run_to_steady: method_asked=auto, tol=0.0001, max_time=20000000 yr,",
          "converged=true, reason=steady, method=direct,")
    T.match(c, "# command: [^\n]*run%.lua")
    T.eq(tab.comments[#tab.comments],
         "# units: x=m, A=m^2, w=m, z=m, S=-, E_f=m/yr, E_df=m/yr, dzdt=m/yr, M=m^3, Q=m^3/s, "
         .. "h=m, v=m/s, t_p=s, tau=Pa, Theta=-")
    -- the record: the same provenance, machine-readable
    local r = json_of(json)
    T.eq(r.dfle, dfle.version)
    T.eq(r.output, csv)
    T.eq(r.router.kind, "empirical")
    T.eq(r.router.params.tau_y, 200)
    T.eq(r.router.units.tau_y, "Pa")
    T.eq(r.channel.kind, "hack"); T.eq(r.channel.n, m.n); T.eq(r.channel.params.A_max, 2e5)
    T.eq(r.fluvial.params.K, m.fluvial.K)
    T.eq(r.model.params.U, 1e-3)
    T.eq(r.run.kind, "run_to_steady")
    T.eq(r.run.reason, run.reason); T.eq(r.run.converged, true); T.eq(r.run.steps, run.steps)
    T.eq(r.run.params.tol, 1e-4)
    T.eq(r.record, nil, "the record does not name itself")
    T.eq(r.files[#r.files], csv, "the CSV is among the files written")
    T.eq(r.files[#r.files - 1], png, "and the plot written before it")
    T.ok(type(r.command) == "table" and #r.command >= 2, "command as an array")
    T.ok(r.cwd ~= nil, "working directory")
end

tests["record option: false writes none, a name puts it there, a bad value raises"] = function()
    local csv, other = T.tmpname(".csv"), T.tmpname(".json")
    local json = csv:sub(1, -5) .. ".json"
    local m = small_model()
    m:write_csv(csv, { record = false })
    T.eq(T.read_file(json), nil, "no record")
    T.ok(not comments_text(T.read_csv(csv)):find("# record:", 1, true), "names no record")
    m:write_csv(csv, { record = other })
    T.eq(T.read_file(json), nil)
    T.eq(json_of(other).output, csv)
    T.has(comments_text(T.read_csv(csv)), "# record: " .. other .. "\n")
    T.raises_here(function() return m:write_csv(csv, { record = 1 }) end,
                  "parameter 'record' must be true, false or a file name")
    T.raises_here(function() return m:write_csv(csv, { recrod = false }) end, "recrod")
    T.raises_here(function() return m:write_csv(csv, { record = csv }) end,
                  "the record would replace the file itself")
    -- a name that does not end in .csv keeps its whole name
    local txt = T.tmpname(".txt")
    m:write_csv(txt)
    T.ok(T.read_file(txt .. ".json") ~= nil, "x.txt -> x.txt.json")
    os.remove(txt .. ".json")
end

tests["records: a law written in Lua lists its params; U(t); no run after set_z"] = function()
    local json = T.tmpname(".json")
    local law = dfle.law.define{ name = "mine", params = { k = 2e-3, alpha = 4, label = "a b" },
                                 rate = function(c, p) return p.k * c.S ^ p.alpha * c.h end }
    local m = small_model{ law = law, U = function(t) return 5e-4 end }
    m:run{ years = 100 }
    m:write_record(json)
    local r = json_of(json)
    T.eq(r.law.kind, "mine")
    T.eq(r.law.params.k, 2e-3); T.eq(r.law.params.alpha, 4); T.eq(r.law.params.label, "a b")
    T.eq(r.model.U_of_t, true)
    T.eq(r.run.kind, "run"); T.eq(r.run.params.years, 100); T.eq(r.run.reason, "time")
    T.eq(r.output, nil, "a record alone describes no file")
    m:set_z(m:get("z"))
    m:write_record(json)
    T.eq(json_of(json).run, nil, "the state was set: no run led to it")
    local off = small_model{ fluvial = false, router = false }
    off:write_record(json)
    r = json_of(json)
    T.eq(r.fluvial.kind, "off"); T.eq(r.router.kind, "off"); T.eq(r.law.kind, "off")
end

tests["records: SOURCE_DATE_EPOCH fixes the date; the command is the one run"] = function()
    local dir = T.tmpname()
    os.remove(dir)
    assert(os.execute("mkdir -p " .. T.shquote(dir)))
    local out = T.run_dfle(([[
        local m = dfle.model{ channel = dfle.channel{ A_max = 2e5 } }
        m:write_csv(%q)
    ]]):format(dir .. "/p.csv"), { "one", "two words" }, { env = "SOURCE_DATE_EPOCH=86400" })
    T.eq(out, "")
    local r = json_of(dir .. "/p.json")
    T.eq(r.date, "1970-01-02T00:00:00Z")
    T.eq(r.command[#r.command - 1], "one"); T.eq(r.command[#r.command], "two words")
    T.match(r.script, "%.lua$")
    T.has(comments_text(T.read_csv(dir .. "/p.csv")), "# date: 1970-01-02T00:00:00Z\n",
          " one 'two words'\n")
    os.execute("rm -rf " .. T.shquote(dir))
end

-- Eq. (2) sampled at 60 areas from 1e3 to 1e7 m^2 (exactly, or times a
-- factor per point).
local function eq2_data(factor)
    local A, S = {}, {}
    for i = 1, 60 do
        A[i] = 10 ^ (3 + (i - 1) / 59 * 4)
        S[i] = 0.8 / (1 + (A[i] / 3e4) ^ 0.9) * (factor and factor(i) or 1)
    end
    return { A = A, S = S }
end

tests["fit_slope_area: residuals = log recovers Eq. (2); R^2 in both spaces; which was used"] = function()
    local data = eq2_data()
    local lin = assert(dfle.fit_slope_area(data))
    T.eq(lin.residuals, "linear", "the default, the paper's")
    T.eq(lin.nbins, 100)
    -- 100 bins over 60 points: one point a bin, so the bins are Eq. (2) itself
    local lg = assert(dfle.fit_slope_area(data, { residuals = "log" }))
    T.eq(lg.residuals, "log")
    T.eq(assert(dfle.fit_slope_area(data, { nbins = 30 })).nbins, 30)
    for _, f in ipairs{ lin, lg } do
        T.close(f.S_df, 0.8, 1e-6); T.close(f.A_df, 3e4, 1e-6); T.close(f.a2, 0.9, 1e-6)
        T.close(f.r2, 1, 0, 1e-10); T.close(f.r2_log, 1, 0, 1e-10)
    end
    -- bins carry their edges and the geometric mean the log fit uses
    local b = lg.bins
    T.eq(#b.A_lo, #b.A); T.eq(#b.S_geomean, #b.A)
    T.ok(b.A_lo[2] <= b.A[2] and b.A[2] <= b.A_hi[2], "A within its bin")
    -- a point every other one 1.5 times too steep: each fit is the best in its own space
    local noisy = eq2_data(function(i) return i % 2 == 0 and 1.5 or 1 end)
    local nl = assert(dfle.fit_slope_area(noisy, { nbins = 60 }))
    local ng = assert(dfle.fit_slope_area(noisy, { nbins = 60, residuals = "log" }))
    T.ok(nl.r2 >= ng.r2, "linear fit: the best R^2 in S")
    T.ok(ng.r2_log >= nl.r2_log, "log fit: the best R^2 in log S")
    T.raises_here(function() return dfle.fit_slope_area(data, { residuals = "Log" }) end,
                  "parameter 'residuals' must be \"linear\"", "\"log\"", "got Log")
    T.raises_here(function() return dfle.fit_slope_area(data, { residuals = 1 }) end,
                  "got number")
end

tests["write_fit and write_bins: the fit and its bins with units and where the data came from"] = function()
    local csv, bins_csv = T.tmpname(".csv"), T.tmpname(".csv")
    local fit = assert(dfle.fit_slope_area(eq2_data(), { residuals = "log", nbins = 20 }))
    T.eq(dfle.write_fit(fit, csv), fit, "returns the fit")
    local tab = T.read_csv(csv)
    T.eq(tab.header, "S_df,A_df,a2,residuals,r2,r2_log,rmse,rmse_log,S_max,S_ch,S_max_minus_S_ch,"
                     .. "n_points,iterations,nbins")
    T.eq(tab.units.A_df, "m^2"); T.eq(tab.units.S_df, "-"); T.eq(tab.units.residuals, nil)
    T.eq(#tab.rows, 1)
    local row = tab.rows[1]
    T.eq(tonumber(row[1]), fit.S_df, "read back exactly")
    T.eq(tonumber(row[2]), fit.A_df)
    T.eq(row[4], "log")
    T.eq(tonumber(row[6]), fit.r2_log)
    local c = comments_text(tab)
    T.has(c, "# data table: pairs=60\n", "# fit eq2: residuals=log, nbins=20\n",
          "# record: " .. csv:sub(1, -5) .. ".json\n")
    local r = json_of(csv:sub(1, -5) .. ".json")
    T.eq(r.fit.params.residuals, "log"); T.eq(r.data.pairs, 60); T.eq(r.output, csv)

    dfle.write_bins(fit, bins_csv)
    local bt = T.read_csv(bins_csv)
    T.eq(bt.header, "A_lo,A_hi,A,count,S,S_median,S_q25,S_q75,S_geomean,S_fit,used")
    T.eq(bt.units.A, "m^2"); T.eq(bt.units.S_fit, "-"); T.eq(bt.units.count, nil)
    T.eq(#bt.rows, #fit.bins.A)
    for i, rw in ipairs(bt.rows) do
        T.eq(tonumber(rw[3]), fit.bins.A[i])
        T.eq(tonumber(rw[9]), fit.bins.S_geomean[i])
        T.close(tonumber(rw[10]), fit.S_df / (1 + (fit.bins.A[i] / fit.A_df) ^ fit.a2), 1e-14)
        T.eq(rw[11], "1")
    end
    -- the record of a JSON written before is not repeated in the next
    local r2 = json_of(bins_csv:sub(1, -5) .. ".json")
    T.eq(r2.output, bins_csv)
    T.ok(not comments_text(bt):find("# output:", 1, true), "no leftover output line")
end

tests["write_fit: a model's fit records the model as it was fitted"] = function()
    local csv = T.tmpname(".csv")
    local m = small_model{ router = dfle.router.empirical{ tau_y = 250 } }
    m:run_to_steady{}
    local fit = assert(dfle.fit_slope_area(m))
    m:run{ years = 10 }
    dfle.write_fit(fit, csv, { record = false })
    local c = comments_text(T.read_csv(csv))
    T.has(c, "tau_y=250 Pa", "# model: U=0.0005 m/yr, cfl=0.5, dt_max=1000 yr, time=0 yr\n",
          "# run run_to_steady:", "# fit eq2: residuals=linear, nbins=100\n")
end

tests["write_fit, write_bins: bad input is named"] = function()
    local csv = T.tmpname(".csv")
    T.raises_here(function() return dfle.write_fit({}, csv) end, "dfle.write_fit",
                  "must be a dfle.fit_slope_area result")
    T.raises_here(function() return dfle.write_fit("fit", csv) end, "table expected")
    -- a fit made by hand: written, its data unknown; no bins to write
    dfle.write_fit({ S_df = 0.5, A_df = 1e4, a2 = 1 }, csv, { record = false })
    local tab = T.read_csv(csv)
    T.has(comments_text(tab), "# data unknown\n")
    T.eq(tab.rows[1][1], "0.5"); T.eq(tab.rows[1][4], "")
    T.raises_here(function() return dfle.write_bins({ S_df = 0.5, A_df = 1e4, a2 = 1 }, csv) end,
                  "the fit has no bins")
    local fit = assert(dfle.fit_slope_area(eq2_data()))
    T.raises_here(function() return dfle.write_fit(fit, "/nonexistent-dir/f.csv") end,
                  "/nonexistent-dir/f.csv")
    T.raises_here(function() return dfle.write_bins(fit, csv, { nbins = 3 }) end, "nbins")
end

tests["ensemble file: version, options and units as comments that stay the same; record beside"] = function()
    local out = T.tmpname(".csv")
    local json = out:sub(1, -5) .. ".json"
    local spec = {
        params = { k_df = { 5e-5, 1e-3, log = true }, U = { 1e-4, 1e-3 } },
        n = 4, seed = 3, out = out, workers = 1,
        build = function(p)
            return dfle.model{ channel = dfle.channel{ dx = 20 }, U = p.U,
                               law = dfle.law.power{ k_df = p.k_df } }
        end,
        outputs = { "S_df", "A_df", "r2_log", "runout_x", "relief" },
        measure = function(m) return { relief = m:get("z")[1] } end,
        units = { U = "m/yr", relief = "m" },
        fit = { residuals = "log" },
    }
    local ens = dfle.ensemble(spec)
    T.eq(ens.ok, 4)
    local tab = T.read_csv(out)
    T.match(tab.comments[1], "^# dfle%.ensemble v1 n=4 seed=3 ")
    T.eq(tab.comments[2], "# dfle: " .. dfle.version)
    T.eq(tab.comments[3], "# fit: residuals=log")
    T.eq(tab.comments[4], "# units: U=m/yr, S_df=-, A_df=m^2, r2_log=-, runout_x=m, relief=m")
    T.eq(#tab.comments, 4, "no date, no command: the file is the same for every run")
    T.eq(tab.header, "index,U,k_df,S_df,A_df,r2_log,runout_x,relief,status,reason")
    -- pawn reads it back past the comments
    local si = dfle.pawn{ file = out, inputs = { "U", "k_df" }, output = "A_df", S = 2 }
    T.ok(si.U ~= nil, "dfle.pawn read the file")
    -- the record: what ran it
    local r = json_of(json)
    T.eq(r.output, out)
    T.eq(r.ensemble.n, 4); T.eq(r.ensemble.count, 4); T.eq(r.ensemble.complete, true)
    T.eq(r.status.ok, 4)
    T.eq(r.fit.params.residuals, "log")
    T.match(r.ensemble.meta, "^# dfle%.ensemble")
    -- run again: read back, the file unchanged
    local before = T.read_file(out)
    T.eq(dfle.ensemble(spec).ran, 0)
    T.eq(T.read_file(out), before)
    -- a unit for a name that is no column
    spec.units = { V = "m" }
    T.raises_here(function() return dfle.ensemble(spec) end,
                  "units names 'V', which is neither a parameter nor an output")
    spec.units, spec.record = nil, false
    os.remove(json)
    spec.out = T.tmpname(".csv")
    dfle.ensemble(spec)
    T.eq(T.read_file(spec.out:sub(1, -5) .. ".json"), nil, "record = false")
    T.eq(T.read_csv(spec.out).comments[3], "# fit: residuals=log")
    -- gather: the first file's comment lines; its own record
    local gathered = T.tmpname(".csv")
    local g = dfle.gather{ out = gathered, files = { out } }
    T.eq(g.count, 4)
    T.eq(T.read_file(gathered), before)
    local gr = json_of(gathered:sub(1, -5) .. ".json")
    T.eq(gr.gather.from[1], out); T.eq(gr.gather.ok, 4)
end

tests["write_csv: a script's own table with units and provenance, rows or columns"] = function()
    local csv = T.tmpname(".csv")
    local rows = { { U = 2e-4, S_df = 0.1 / 3, converged = true, label = "a, \"b\"" },
                   { U = 1e-3, converged = false } }
    local law = dfle.law.power{ alpha = 4 }
    local m = dfle.model{ channel = dfle.channel{ A_max = 2e5 } }
    dfle.write_csv(csv, { columns = { "U", "S_df", "converged", "label" }, rows = rows,
                          units = { U = "m/yr", S_df = "-" }, about = "a sweep over U",
                          params = { other_law = law:params(), tol = 1e-3, note = "first try",
                                     model = m } })
    local text = assert(T.read_file(csv))
    T.has(text, "\n# about: \"a sweep over U\"\n", "\n# params: note=\"first try\", tol=0.001\n",
          "\n# other_law: alpha=4, beta=1, k_df=0.0001\n", "\n# law power: k_df=0.0001, alpha=6,",
          "\n# router empirical:",
          "\n# units: U=m/yr, S_df=-\nU,S_df,converged,label\n",
          "\n0.0002,0.03333333333333333,true,\"a, \"\"b\"\"\"\n0.001,nan,false,\n")
    local r = json_of(csv:sub(1, -5) .. ".json")
    T.eq(r.other_law.params.alpha, 4); T.eq(r.law.params.alpha, 6)
    T.eq(r.params.params.tol, 1e-3); T.eq(r.about, "a sweep over U")
    local clash = { law = law:params(), model = m }
    T.raises_here(function() return dfle.write_csv(csv, { columns = { "U" }, rows = rows, params = clash }) end,
                  "params.law would mix with the model's section")
    -- columns as arrays, no record
    local csv2 = T.tmpname(".csv")
    dfle.write_csv(csv2, { columns = { "x", "y" }, data = { x = { 1, 2 }, y = { 0.5, 0.25 } },
                           record = false })
    local tab = T.read_csv(csv2)
    T.eq(tab.header, "x,y"); T.eq(tab.rows[2][2], "0.25"); T.eq(next(tab.units), nil)
    T.eq(T.read_file(csv2:sub(1, -5) .. ".json"), nil)
    -- mistakes are named
    T.raises_here(function() return dfle.write_csv(csv2, { columns = { "x" } }) end,
                  "either 'rows'")
    T.raises_here(function() return dfle.write_csv(csv2, { columns = { "x", "y" }, data = { x = { 1 }, y = { 1, 2 } } }) end,
                  "data.y has 2 values, data.x 1")
    T.raises_here(function() return dfle.write_csv(csv2, { columns = { "x" }, data = { x = { 1 } }, units = { X = "m" } }) end,
                  "units names 'X', which is not a column")
    T.raises_here(function() return dfle.write_csv(csv2, { columns = { "x", "x" }, data = { x = { 1 } } }) end,
                  "column 'x' is listed twice")
    T.raises_here(function() return dfle.write_csv(csv2, { columns = { "a,b" }, data = { ["a,b"] = { 1 } } }) end,
                  "dfle.write_csv:", "cannot go into a CSV header")
    T.raises_here(function() return dfle.write_csv(csv2, { colums = {} }) end, "colums")
end

return tests
