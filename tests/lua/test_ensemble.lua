-- test_ensemble.lua - dfle.ensemble (threads, streamed rows, resume,
-- failure rows), dfle.gather (shards) and dfle.pawn on an ensemble.
-- Parallel runs go through child dfle processes: a worker replays its
-- script, and this runner is a script too, so in-process ensembles here
-- use workers = 1.  Channels are small (dx = 20 m) and n is 24-32.
local T = ...
local tests = {}

local q = T.shquote

-- A scratch directory for one test (removed by the returned function),
-- a shell command's output and status: from the runner.
local scratch, sh = T.scratch, T.sh

-- The sweep script used by the CLI tests: arg[1] = out file, arg[2] =
-- extra Lua put into build (e.g. a delay), arg[3] = limit.
local SWEEP = [[
local out, extra, limit = arg[1], arg[2] or "", tonumber(arg[3] or "0")
local slow = load(extra)
local ens = dfle.ensemble{
  params = { k_df = {5e-5, 1e-3, log = true}, U = {1e-4, 1e-3}, alpha = {values = {2, 4, 6}} },
  n = 32, seed = 7, out = out, limit = limit,
  build = function(p)
    slow()
    return dfle.model{ channel = dfle.channel{ dx = 20 }, U = p.U,
                       law = dfle.law.power{ k_df = p.k_df, alpha = p.alpha } }
  end,
  outputs = { "S_df", "A_df", "r2", "S_max_minus_S_ch" },
}
print(("ran=%d count=%d complete=%s"):format(ens.ran, ens.count, tostring(ens.complete)))
]]

local function write_sweep(dir)
    local path = dir .. "/sweep.lua"
    T.write_file(path, SWEEP)
    return path
end

local function run(dir, flags, ...)
    local cmd = "cd " .. q(dir) .. " && " .. q(T.dfle) .. " -q " .. flags .. " sweep.lua"
    for _, a in ipairs{ ... } do cmd = cmd .. " " .. q(a) end
    local out, ok = sh(cmd)
    T.ok(ok, "dfle failed: " .. out)
    return out
end

local function small_build(p)
    return dfle.model{ channel = dfle.channel{ dx = 20 }, U = p.U,
                       law = dfle.law.power{ k_df = p.k_df, alpha = p.alpha or 6 } }
end

tests["in-process: rows, result table, file sorted by index"] = function()
    local dir, done = scratch()
    local ens = dfle.ensemble{
        params = { k_df = {5e-5, 1e-3, log = true}, U = {1e-4, 1e-3} },
        n = 24, seed = 3, out = dir .. "/e.csv", workers = 1, build = small_build,
        outputs = { "S_df", "A_df", "r2", "S_max_minus_S_ch", "A_top", "runout_A", "steps" },
        measure = function(m, fit, p, res)
            T.ok(res.converged)
            return { A_top = m:get("A")[1] }
        end,
    }
    T.eq(ens.n, 24)
    T.eq(ens.count, 24)
    T.eq(ens.ok, 24)
    T.eq(ens.failed, 0)
    T.eq(ens.ran, 24)
    T.eq(ens.complete, true)
    T.eq(#ens.inputs, 2)
    T.eq(ens.inputs[1], "U")
    T.eq(ens.outputs[5], "A_top")
    local d, design = ens.data, dfle.lhs{ n = 24, seed = 3,
        params = { k_df = {5e-5, 1e-3, log = true}, U = {1e-4, 1e-3} } }
    for i = 1, 24 do
        T.eq(d.index[i], i)
        T.eq(d.k_df[i], design[i].k_df, "parameters round-trip exactly")
        T.eq(d.status[i], "ok")
        T.eq(d.reason[i], "")
        T.ok(d.S_df[i] > 0 and d.A_df[i] > 0)
    end
    -- the same fit as by hand
    local m = small_build(design[5])
    m:run_to_steady{}
    local f = dfle.fit_slope_area(m)
    T.eq(d.S_df[5], f.S_df)
    T.eq(d.A_df[5], f.A_df)
    local r = m.router:route(m)
    T.eq(d.runout_A[5], m:get("A")[r.runout_end], "runout_A: area of the last node reached")
    T.eq(math.type(d.steps[5]), "integer", "a run-result output")
    -- file: meta line, header, rows 1..n in order
    local text = T.read_file(dir .. "/e.csv")
    T.match(text, "^# dfle%.ensemble v1 n=24 seed=3 ")
    T.has(text, "\nindex,U,k_df,S_df,A_df,r2,S_max_minus_S_ch,A_top,runout_A,steps,status,reason\n1,")
    -- running again resumes a complete file: nothing to do, same result
    local again = dfle.ensemble{
        params = { k_df = {5e-5, 1e-3, log = true}, U = {1e-4, 1e-3} },
        n = 24, seed = 3, out = dir .. "/e.csv", workers = 1, build = small_build,
        outputs = { "S_df", "A_df", "r2", "S_max_minus_S_ch", "A_top", "runout_A", "steps" },
        measure = function(m2) return { A_top = m2:get("A")[1] } end,
    }
    T.eq(again.ran, 0)
    T.eq(again.count, 24)
    T.eq(T.read_file(dir .. "/e.csv"), text)
    done()
end

tests["pawn(ens, {outputs}) equals dfle.pawn on the file"] = function()
    local dir, done = scratch()
    local ens = dfle.ensemble{
        params = { k_df = {5e-5, 1e-3, log = true}, U = {1e-4, 1e-3} },
        n = 30, seed = 2, out = dir .. "/e.csv", workers = 1, build = small_build,
        outputs = { "S_df", "A_df" },
    }
    local si, info = dfle.pawn(ens, { outputs = { "A_df", "S_df" }, S = 5 })
    for _, o in ipairs{ "A_df", "S_df" } do
        local ref = dfle.pawn{ file = dir .. "/e.csv", inputs = { "U", "k_df" }, output = o, S = 5 }
        for _, x in ipairs{ "U", "k_df" } do
            for _, st in ipairs{ "minimum", "mean", "median", "maximum", "CV" } do
                T.eq(si[o][x][st], ref[x][st], o .. " " .. x .. " " .. st)
            end
        end
        T.eq(info[o].N, 30)
    end
    -- plain dfle.pawn still works through the wrapper
    local plain = dfle.pawn{ data = { x = { 1, 2, 3, 4 }, y = { 1, 2, 3, 5 } }, inputs = { "x" },
                             output = "y", S = 2 }
    T.ok(plain.x.median ~= nil)
    -- the bootstrap runs on the ensemble's workers, or on threads =, with
    -- the same intervals
    T.eq(ens.workers, 1)
    local b1, i1 = dfle.pawn(ens, { outputs = { "A_df" }, S = 5, bootstrap = 30 })
    local b3, i3 = dfle.pawn(ens, { outputs = { "A_df" }, S = 5, bootstrap = 30, threads = 3 })
    T.eq(i1.A_df.threads, 1)
    T.eq(i3.A_df.threads, 3)
    for _, x in ipairs{ "U", "k_df" } do
        T.eq(b3.A_df[x].ci.median.lo, b1.A_df[x].ci.median.lo)
        T.eq(b3.A_df[x].ci.CV.hi, b1.A_df[x].ci.CV.hi)
    end
    done()
end

tests["CLI: dfle.pawn's bootstrap runs on -j threads, with the same intervals"] = function()
    local dir, done = scratch()
    T.write_file(dir .. "/sweep.lua", [[
local ens = dfle.ensemble{
  params = { k_df = {5e-5, 1e-3, log = true}, U = {1e-4, 1e-3} },
  n = 12, seed = 4, out = arg[1],
  build = function(p)
    return dfle.model{ channel = dfle.channel{ dx = 20 }, U = p.U, law = dfle.law.power{ k_df = p.k_df } }
  end,
  outputs = { "S_df", "A_df" },
}
local si, info = dfle.pawn(ens, { outputs = { "S_df" }, S = 3, bootstrap = 20 })
local _, plain = dfle.pawn{ data = { x = { 1, 2, 3, 4 }, y = { 1, 2, 3, 5 } }, inputs = { "x" },
                            output = "y", S = 2, bootstrap = 5 }
print(("threads=%d plain=%d workers=%d lo=%a"):format(info.S_df.threads, plain.threads, ens.workers,
                                                      si.S_df.U.ci.median.lo))
]])
    local one = run(dir, "-j 1", "a.csv")
    local three = run(dir, "-j 3", "b.csv")
    T.has(one, "threads=1 plain=1 workers=1")
    T.has(three, "threads=3 plain=3 workers=3")
    T.eq(three:match("lo=(%S+)"), one:match("lo=(%S+)"))
    done()
end

tests["dfle.pawn inside a sample runs on one thread (the workers have the cores)"] = function()
    local dir, done = scratch()
    local data = { x = { 1, 2, 3, 4, 5, 6 }, y = { 1, 2, 3, 5, 4, 6 } }
    local function pawn_threads(extra)
        local opts = { data = data, inputs = { "x" }, output = "y", S = 2, bootstrap = 4 }
        for k, v in pairs(extra or {}) do opts[k] = v end
        local _, info = dfle.pawn(opts)
        return info.threads
    end
    local outside = pawn_threads()
    local ens = dfle.ensemble{
        params = { k_df = {5e-5, 1e-3, log = true}, U = {1e-4, 1e-3} },
        n = 3, seed = 2, out = dir .. "/p.csv", workers = 1, build = small_build,
        outputs = { "S_df", "inner", "asked" },
        measure = function() return { inner = pawn_threads(), asked = pawn_threads{ threads = 2 } } end,
    }
    T.eq(ens.count, 3)
    for i = 1, 3 do
        T.eq(ens.data.status[i], "ok")
        T.eq(ens.data.inner[i], 1)  -- the default, inside a sample
        T.eq(ens.data.asked[i], 2)  -- a number given is kept
    end
    T.ok(outside >= 1)
    T.eq(pawn_threads(), outside) -- and outside again, the default is back
    done()
end

tests["failure rows: error in build, no convergence, NaN; not fatal"] = function()
    local dir, done = scratch()
    local ens = dfle.ensemble{
        params = { k_df = {5e-5, 1e-3, log = true}, U = {1e-4, 1e-3}, kind = { values = { "ok", "boom", "nan", "slow" } } },
        n = 24, seed = 5, out = dir .. "/f.csv", workers = 1,
        build = function(p)
            if p.kind == "boom" then error("no model for \"boom\",\nsorry") end
            return small_build(p)
        end,
        run = { method = "auto" },
        measure = function(m, fit, p)
            return { extra = p.kind == "nan" and 0 / 0 or 1 }
        end,
        outputs = { "S_df", "extra" },
    }
    T.eq(ens.count, 24)
    T.eq(ens.status.ok, 12)
    T.eq(ens.status.error, 6)
    T.eq(ens.status.nan, 6)
    T.eq(ens.failed, 12)
    for i = 1, 24 do
        local k = ens.data.kind[i]
        if k == "boom" then
            T.eq(ens.data.status[i], "error")
            T.has(ens.data.reason[i], "no model for \"boom\", sorry")
            T.ok(ens.data.S_df[i] ~= ens.data.S_df[i], "outputs of failed rows are NaN")
        elseif k == "nan" then
            T.eq(ens.data.status[i], "nan")
            T.has(ens.data.reason[i], "output 'extra' is NaN")
        else
            T.eq(ens.data.status[i], "ok")
        end
    end
    -- the file is a valid table for dfle.pawn (quoted reasons with commas)
    local si = dfle.pawn{ file = dir .. "/f.csv", inputs = { "U", "k_df" }, output = "S_df",
                          S = 3, drop_nan = true }
    T.ok(si.U.median >= 0)
    -- PAWN on the ensemble uses the ok rows and the numeric inputs only
    local s2, info = dfle.pawn(ens, { outputs = { "S_df" }, S = 3 })
    T.eq(info.S_df.N, 12)
    T.eq(s2.S_df.kind, nil)
    -- a run that does not converge
    local nc = dfle.ensemble{
        params = { U = {1e-4, 1e-3} }, n = 3, out = dir .. "/nc.csv", workers = 1,
        build = function(p) return dfle.model{ channel = dfle.channel{ dx = 20 }, U = p.U } end,
        run = { method = "explicit", max_time = 10 },
        outputs = { "S_df" },
    }
    T.eq(nc.status.not_converged, 3)
    T.ok(#nc.data.reason[1] > 0)
    done()
end

tests["resume: truncated last line, limit, different ensemble refused"] = function()
    local dir, done = scratch()
    local function go(n_limit, seed)
        return dfle.ensemble{
            params = { k_df = {5e-5, 1e-3, log = true}, U = {1e-4, 1e-3} },
            n = 24, seed = seed or 4, out = dir .. "/r.csv", workers = 1, build = small_build,
            outputs = { "S_df", "A_df" }, limit = n_limit,
        }
    end
    local full = go()
    local ref = T.read_file(dir .. "/r.csv")
    os.remove(dir .. "/r.csv")
    local part = go(10)
    T.eq(part.ran, 10)
    T.eq(part.complete, false)
    -- a killed writer: half a row at the end
    local f = io.open(dir .. "/r.csv", "ab")
    f:write("17,0.00012345,0.0004")
    f:close()
    local rest = go()
    T.eq(rest.ran, 14)
    T.eq(rest.complete, true)
    T.eq(T.read_file(dir .. "/r.csv"), ref, "resumed file equals a single run")
    T.eq(rest.data.S_df[17], full.data.S_df[17])
    T.errors_with(function() go(nil, 5) end, "r.csv was written by a different ensemble")
    done()
end

tests["CLI: identical files for -j 1, 2, 4"] = function()
    local dir, done = scratch()
    write_sweep(dir)
    local files = {}
    for _, j in ipairs{ 1, 2, 4 } do
        local out = run(dir, "-j " .. j, "e" .. j .. ".csv")
        T.has(out, "ran=32 count=32 complete=true")
        files[j] = T.read_file(dir .. "/e" .. j .. ".csv")
    end
    T.ok(#files[1] > 1000)
    T.eq(files[2], files[1])
    T.eq(files[4], files[1])
    done()
end

tests["CLI: a Lua-defined law (dfle.law.define) in build runs in parallel workers"] = function()
    local dir, done = scratch()
    T.write_file(dir .. "/sweep.lua", [[
local ens = dfle.ensemble{
  params = { k_df = {5e-5, 1e-3, log = true}, U = {1e-4, 1e-3} },
  n = 16, seed = 2, out = arg[1],
  build = function(p)
    local law = dfle.law.define{
      params = { k = p.k_df, alpha = 6 },
      rate = function(c, q) return q.k * c.S^q.alpha * c.F end,
    }
    return dfle.model{ channel = dfle.channel{ dx = 20 }, U = p.U, law = law }
  end,
  outputs = { "S_df", "A_df", "r2" },
}
print(("ran=%d ok=%d"):format(ens.ran, ens.ok))
]])
    T.has(run(dir, "-j 1", "l1.csv"), "ran=16 ok=16")
    T.has(run(dir, "-j 3", "l3.csv"), "ran=16 ok=16")
    T.eq(T.read_file(dir .. "/l3.csv"), T.read_file(dir .. "/l1.csv"))
    done()
end

tests["CLI: workers replay the script; a later ensemble may use an earlier one"] = function()
    local dir, done = scratch()
    T.write_file(dir .. "/sweep.lua", [[
io.write(dfle.worker() and "replay\n" or "main\n")
local function sweep(out, n, seed)
  return dfle.ensemble{
    params = { k_df = {5e-5, 1e-3, log = true}, U = {1e-4, 1e-3} },
    n = n, seed = seed, out = out,
    build = function(p)
      return dfle.model{ channel = dfle.channel{ dx = 20 }, U = p.U,
                         law = dfle.law.power{ k_df = p.k_df } }
    end,
    outputs = { "S_df", "A_df" },
  }
end
local first = sweep(arg[1] .. "-a.csv", 8, 1)
-- the second ensemble depends on the first's results
local second = sweep(arg[1] .. "-b.csv", first.ok + 4, math.floor(first.data.A_df[3]) % 1000)
if not dfle.worker() then print(("n2=%d ok2=%d"):format(second.n, second.ok)) end
]])
    local out1 = run(dir, "-j 1", "one")
    local out2 = run(dir, "-j 2", "two")
    T.has(out1, "n2=12 ok2=12")
    T.has(out2, "n2=12 ok2=12")
    local _, replays = out2:gsub("replay\n", "")
    T.eq(replays, 4, "two workers replay the script for each of the two ensembles")
    local _, mains = out2:gsub("main\n", "")
    T.eq(mains, 1)
    T.eq(T.read_file(dir .. "/two-a.csv"), T.read_file(dir .. "/one-a.csv"))
    T.eq(T.read_file(dir .. "/two-b.csv"), T.read_file(dir .. "/one-b.csv"))
    done()
end

tests["CLI: a script that differs when replayed stops with a clear error"] = function()
    local dir, done = scratch()
    T.write_file(dir .. "/sweep.lua", [[
dfle.ensemble{
  params = { U = {1e-4, 1e-3} }, out = "d.csv",
  n = dfle.worker() and 9 or 8,          -- breaks the replay rule
  build = function(p) return dfle.model{ channel = dfle.channel{ dx = 20 }, U = p.U } end,
  outputs = { "S_df" },
}
]])
    local out, ok = sh("cd " .. q(dir) .. " && " .. q(T.dfle) .. " -q -j 2 sweep.lua")
    T.eq(ok, nil)
    T.has(out, "sweep.lua:1: dfle.ensemble: worker: the script built a different ensemble")
    done()
end

tests["CLI: a killed parallel run resumes without losing or repeating a row"] = function()
    local dir, done = scratch()
    write_sweep(dir)
    run(dir, "-j 1", "ref.csv")
    -- each build busy-waits (CPU time: about 25 ms of wall time with two
    -- threads); kill -9 as soon as the first row is on disk, which is
    -- always mid-run (31 more rows take >= 0.4 s), however busy the
    -- machine: a fixed delay once killed it before any row was written.
    -- The wait is bounded (30 s), so a run that never writes fails here.
    local delay = "local c = os.clock() while os.clock() - c < 0.05 do end"
    -- lines above the rows: the meta line, the comment lines, the header
    local _, head = T.read_file(dir .. "/ref.csv"):match("^(.-\nindex,[^\n]*\n)"):gsub("\n", "")
    sh("cd " .. q(dir) .. " && { " .. q(T.dfle) .. " -q -j 2 sweep.lua k.csv " .. q(delay) ..
       " & pid=$!; i=0; while [ $i -lt 3000 ]; do" ..
       " [ \"$(grep -c '' k.csv 2>/dev/null)\" -ge " .. (head + 1) .. " ] 2>/dev/null && break;" ..
       " sleep 0.01; i=$((i+1)); done; kill -9 $pid; wait $pid; }")
    local partial = T.read_file(dir .. "/k.csv")
    T.ok(partial ~= nil, "the killed run left a file")
    local _, lines = partial:gsub("\n", "")
    local rows = lines - head -- complete rows (a cut last line has no newline)
    T.ok(rows >= 1 and rows < 32, "killed mid-run after " .. rows .. " rows")
    local out = run(dir, "-j 2", "k.csv")
    local ran = tonumber(out:match("ran=(%d+)"))
    T.eq(ran, 32 - rows, "resumed exactly the missing rows")
    T.eq(T.read_file(dir .. "/k.csv"), T.read_file(dir .. "/ref.csv"))
    done()
end

tests["CLI: Ctrl-C stops an ensemble cleanly, keeps its rows, and the run resumes"] = function()
    -- The first sample to run sends SIGINT to dfle itself (through popen:
    -- os.execute would have SIGINT ignored while the shell runs): no new
    -- samples start, those running finish, every finished row is kept,
    -- one line says so, the exit status is 130, and running again
    -- resumes to exactly the uninterrupted file.
    for _, j in ipairs{ "-j 1", "-j 2" } do
        local dir, done = scratch()
        write_sweep(dir)
        run(dir, "-j 1", "ref.csv")
        local ctrl_c = "local f = io.open('ctrl-c') if not f then io.open('ctrl-c', 'w'):close() " ..
                       "io.popen('kill -INT $PPID'):close() else f:close() end"
        local out, ok, code = sh("cd " .. q(dir) .. " && " .. q(T.dfle) .. " -q " .. j ..
                                 " sweep.lua i.csv " .. q(ctrl_c))
        T.eq(ok, nil, out)
        T.eq(code, 130, out)
        T.has(out, "interrupted by SIGINT", "dfle.ensemble stopped taking samples",
              "finished rows are in", "running the script again resumes it")
        local rows = tonumber(out:match("(%d+) finished rows"))
        T.ok(rows ~= nil and rows < 32, out)
        local again = run(dir, j, "i.csv")
        T.eq(tonumber(again:match("ran=(%d+)")), 32 - rows)
        T.eq(T.read_file(dir .. "/i.csv"), T.read_file(dir .. "/ref.csv"))
        done()
    end
end

tests["CLI: --shard i/n and dfle.gather equal a single run"] = function()
    local dir, done = scratch()
    write_sweep(dir)
    run(dir, "-j 2", "single.csv")
    local counts = 0
    for s = 1, 3 do
        local out = run(dir, "-j 2 --shard " .. s .. "/3", "sh.csv")
        counts = counts + tonumber(out:match("count=(%d+)"))
        T.has(out, "complete=false")
    end
    T.eq(counts, 32)
    -- shard 1 of 3 holds samples 1, 4, 7, ...
    local s1 = T.read_file(dir .. "/sh.shard-1-of-3.csv")
    T.has(s1, "\n1,", "\n4,", "\n31,")
    T.ok(not s1:find("\n2,", 1, true))
    local g = dfle.gather{ out = dir .. "/sh.csv", shards = 3 }
    T.eq(g.count, 32)
    T.eq(g.complete, true)
    T.eq(T.read_file(dir .. "/sh.csv"), T.read_file(dir .. "/single.csv"))
    -- the same with an explicit file list
    local g2 = dfle.gather{ out = dir .. "/g2.csv", files = {
        dir .. "/sh.shard-3-of-3.csv", dir .. "/sh.shard-1-of-3.csv", dir .. "/sh.shard-2-of-3.csv" } }
    T.eq(g2.count, 32)
    T.eq(T.read_file(dir .. "/g2.csv"), T.read_file(dir .. "/single.csv"))
    -- files of different ensembles are refused
    T.errors_with(function()
        dfle.gather{ out = dir .. "/x.csv", files = { dir .. "/single.csv", dir .. "/x0.csv" } }
    end, "x0.csv")
    done()
end

tests["CLI: bad -j and --shard are usage errors"] = function()
    for _, flags in ipairs{ "-j 0", "-j x", "--shard 0/3", "--shard 4/3", "--shard 1" } do
        local _, ok, code = sh(q(T.dfle) .. " " .. flags .. " /dev/null")
        T.eq(ok, nil, flags)
        T.eq(code, 2, flags)
    end
end

tests["errors name the parameter and the calling line"] = function()
    local base = function()
        return { params = { U = {1e-4, 1e-3} }, n = 4, out = "/nonexistent/x.csv",
                 build = small_build, outputs = { "S_df" }, workers = 1 }
    end
    local function with(k, v)
        local t = base()
        t[k] = v
        return t
    end
    T.raises_here(function() dfle.ensemble(with("build", nil)) end, "parameter 'build'")
    T.raises_here(function() dfle.ensemble(with("outputs", {})) end, "parameter 'outputs'")
    T.raises_here(function() dfle.ensemble(with("outputs", { "U" })) end,
                  "'U' is both a parameter and an output")
    T.raises_here(function() dfle.ensemble(with("n", nil)) end, "parameter 'n'")
    T.raises_here(function() dfle.ensemble(with("out", nil)) end, "parameter 'out'")
    T.raises_here(function() dfle.ensemble(with("nn", 3)) end, "unknown parameter 'nn'")
    T.raises_here(function() dfle.ensemble(with("outputs", { "a,b" })) end, "CSV column")
    T.raises_here(function() dfle.ensemble(base()) end, "/nonexistent/x.csv")
    T.raises_here(function() dfle.ensemble(with("params", { U = { 1, 0 } })) end,
                  "dfle.ensemble: parameter 'U': range needs lo < hi")
    T.raises_here(function() dfle.gather{ out = "x.csv" } end, "either 'files'")
end

tests["ens:write_netcdf: the rows, the design and units as a NetCDF table"] = function()
    local dir = scratch()
    local ens = dfle.ensemble{
        params = { k_df = {5e-5, 1e-3, log = true}, U = {1e-4, 1e-3} },
        n = 4, seed = 3, out = dir .. "/e.csv", workers = 1, build = small_build,
        outputs = { "S_df", "A_df" } }
    T.ok(rawequal(ens:write_netcdf(dir .. "/e.nc"), ens))
    local s = assert(T.read_file(dir .. "/e.nc"))
    T.eq(s:sub(1, 4), "\137HDF", "netCDF-4 (HDF5)")
    T.has(s, "sample", "k_df", "S_df", "status", "reason", "dfle_design",
          "dfle.ensemble v1 n=4 seed=3", "m/yr", "m2")
    T.raises_here(function() return ens:write_netcdf() end, "string expected")
    T.raises_here(function() return ens:write_netcdf(dir .. "/no/such/dir.nc") end, "no/such/dir.nc")
end

return tests
