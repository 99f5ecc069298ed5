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

return tests
