-- test_cli.lua - the dfle command: options, exit codes, error reports,
-- script arguments.  Uses the binary given to the runner (T.dfle).
local T = ...
local tests = {}

local q = T.shquote

local function need_binary()
    T.ok(T.dfle ~= nil, "run.lua needs the dfle binary as arg[1]")
    local f = io.open(T.dfle, "rb")
    T.ok(f ~= nil, "no dfle binary at " .. tostring(T.dfle))
    f:close()
end

-- Run a shell command; returns output (stdout + stderr unless `streams`
-- says otherwise), ok, exit code.
local function sh(cmd, streams)
    local h = io.popen(cmd .. (streams or " 2>&1"))
    local out = h:read("a")
    local ok, _, code = h:close()
    return out, ok, code
end

tests["--help: usage on stdout, exit 0"] = function()
    need_binary()
    for _, opt in ipairs{ "--help", "-h" } do
        local out, ok, code = sh(q(T.dfle) .. " " .. opt, " 2>/dev/null")
        T.eq(ok, true, opt .. " exit status")
        T.eq(code, 0)
        T.match(out, "^usage: ")
        T.has(out, "script.lua", "-q")
    end
    -- os.execute reports the same.
    local ok, how, code = os.execute(q(T.dfle) .. " --help >/dev/null 2>&1")
    T.eq(ok, true)
    T.eq(how, "exit")
    T.eq(code, 0)
end

tests["--version: prints 'dfle <version>' matching dfle.version"] = function()
    need_binary()
    for _, opt in ipairs{ "--version", "-v" } do
        local out, ok = sh(q(T.dfle) .. " " .. opt, " 2>/dev/null")
        T.eq(ok, true)
        T.match(out, "^dfle ")
        T.has(out, "dfle " .. dfle.version)
    end
end

tests["no script: exit code 2 and usage on stderr"] = function()
    need_binary()
    local ok, how, code = os.execute(q(T.dfle) .. " >/dev/null 2>&1")
    T.eq(ok, nil)
    T.eq(how, "exit")
    T.eq(code, 2)
    local err = sh(q(T.dfle), " 2>&1 >/dev/null")
    T.has(err, "no script", "usage")
    -- -q alone is no script either.
    local _, _, code2 = os.execute(q(T.dfle) .. " -q >/dev/null 2>&1")
    T.eq(code2, 2)
end

tests["unknown option: exit code 2, names the option"] = function()
    need_binary()
    local out, ok, code = sh(q(T.dfle) .. " --frobnicate x.lua")
    T.eq(ok, nil)
    T.eq(code, 2)
    T.has(out, "--frobnicate")
end

tests["script error: exit 1, 'dfle:' + file:line + traceback on stderr"] = function()
    need_binary()
    local script = T.tmpname(".lua")
    T.write_file(script, "local x = 1\n\nerror('boom here')\n")
    local err, ok, code = sh(q(T.dfle) .. " -q " .. q(script), " 2>&1 >/dev/null")
    T.eq(ok, nil)
    T.eq(code, 1)
    T.match(err, "^dfle: ")
    T.has(err, script .. ":3: boom here", "stack traceback")
end

tests["script error from the API: message names the call site"] = function()
    need_binary()
    local out, ok, code = T.run_dfle("\n\nlocal ch = dfle.channel{ dx = -5 }\n", nil, { stderr_only = true })
    T.eq(ok, nil)
    T.eq(code, 1)
    T.match(out, "^dfle: ")
    T.match(out, "%.lua:3: dfle%.channel: ")
    T.has(out, "dx", "stack traceback")
end

tests["syntax error: exit 1 with file:line"] = function()
    need_binary()
    local out, ok, code = T.run_dfle("local a =\nlocal = 2\n", nil, { stderr_only = true })
    T.eq(ok, nil)
    T.eq(code, 1)
    T.match(out, "^dfle: ")
    T.match(out, "%.lua:2: ")
end

tests["file-size limit: write_csv fails with the reason and keeps the old file"] = function()
    -- Under ulimit -f the process once died without a word (SIGXFSZ) and
    -- left a truncated file in place of a good one.
    need_binary()
    local csv = T.tmpname(".csv")
    T.write_file(csv, "good\n")
    local script = T.tmpname(".lua")
    T.write_file(script, ("dfle.model{}:write_csv(%q)\n"):format(csv))
    local out, ok, code = sh("ulimit -f 20; " .. q(T.dfle) .. " -q " .. q(script))
    T.eq(ok, nil)
    T.eq(code, 1)
    T.has(out, "cannot write", "File too large")
    local f = assert(io.open(csv))
    T.eq(f:read("a"), "good\n")
    f:close()
end

tests["SIGINT and SIGTERM: the run stops, returns what it has, one line, 130/143"] = function()
    -- U(t) signals dfle itself 50 years in (through popen: os.execute
    -- ignores SIGINT while its shell runs).  The run returns at the next
    -- step with reason "interrupted" and its records so far; the script
    -- can still write them; the next run does not start.
    need_binary()
    for sig, status in pairs{ INT = 130, TERM = 143 } do
        local csv = T.tmpname(".csv")
        local script = T.tmpname(".lua")
        T.write_file(script, ([[
local sent = false
local m = dfle.model{ channel = dfle.channel{ dx = 20 }, U = function(t)
  if t > 50 and not sent then sent = true; io.popen("kill -%s $PPID"):close() end
  return 5e-4 end }
local r = m:run{ years = 1e6, record = { 0, 10, 1e5 } }
print("reason=" .. r.reason .. " records=" .. #r.records .. " t=" .. m.time)
m:write_csv(%q)
m:run{ years = 10 }
print("not reached")
]]):format(sig, csv))
        local out, ok, code = sh(q(T.dfle) .. " -q " .. q(script))
        T.eq(ok, nil)
        T.eq(code, status, out)
        T.has(out, "reason=interrupted records=2", "interrupted by SIG" .. sig,
              "model:run stopped at t = ", "files written before are complete")
        T.ok(not out:find("not reached"), out)
        local _, lines = T.read_file(csv):gsub("\n", "")
        T.ok(lines > 10, "the profile was written")
    end
end

tests["dfle.args: --help, unknown options before any work, values, the output directory"] = function()
    need_binary()
    local dir = T.tmpname("-args")
    local script = T.tmpname(".lua")
    T.write_file(script, [[
local o = dfle.args{ usage = "dfle s.lua [options] [output-directory]", about = "About it.",
  flags = { quick = "fast" }, options = { data = { "DIR", "the data", default = "D0" } },
  output = true }
print(("quick=%s data=%s output=%s"):format(tostring(o.quick), o.data, o.output))
print("work done")
]])
    local run = function(args) return sh(q(T.dfle) .. " -q " .. q(script) .. " " .. args) end
    local out, ok = run("--help")
    T.eq(ok, true)
    T.has(out, "usage: dfle s.lua", "About it.", "--data DIR", "--quick", "output-directory")
    T.ok(not out:find("work done"))
    local code
    out, ok, code = run("--qiuck")
    T.eq(ok, nil); T.eq(code, 2) -- a command-line error, as for dfle's own options
    T.has(out, 'unknown option "--qiuck"', "--quick", "--data DIR", ".lua:1:")
    T.ok(not out:find("work done"))
    T.ok(not out:find("traceback"), "no traceback for a mistake on the command line")
    out = run("--quick --data=/x " .. q(dir .. "/a/b"))
    T.has(out, "quick=true data=/x output=" .. dir .. "/a/b", "work done")
    local probe = io.open(dir .. "/a/b/.probe", "w") -- the directory was made
    T.ok(probe ~= nil)
    probe:close()
    out, ok, code = run("--data")
    T.has(out, "--data needs a value"); T.eq(code, 2)
    out, ok, code = run("a b")
    T.has(out, "one output directory at most"); T.eq(code, 2)
    out, ok, code = run("--quick=yes")
    T.has(out, "--quick takes no value", ".lua:1:"); T.eq(code, 2)
    out = run("")
    T.has(out, "quick=false data=D0 output=.")
    -- an output "directory" that is a file: named at the script's line
    local file = dir .. "/a/file"
    T.write_file(file, "x")
    out, ok, code = run(q(file))
    T.eq(ok, nil); T.eq(code, 2)
    T.has(out, ".lua:1:", "exists and is not a directory", file)
    T.ok(not out:find("work done"))
    -- an empty default (DFLE_DATA_DIR set but empty) is no value
    T.write_file(script, [=[
local o = dfle.args{ options = { data = { "DIR", "the data", default = "" } } }
print("data=" .. tostring(o.data))
]=])
    T.has(run(""), "data=nil")
    -- env and needs: a default from the environment, a file it must hold
    T.write_file(script, [=[
local o = dfle.args{ options = { data = { "DIR", "the data", env = "DFLE_T_DATA",
                                          needs = { "sub/f.txt", "the test file" } } } }
print("file=" .. o.data_file)
]=])
    local out2, ok2, code2 = sh("DFLE_T_DATA=" .. q(dir) .. " " .. q(T.dfle) .. " -q " .. q(script))
    T.eq(ok2, nil); T.eq(code2, 2)
    T.has(out2, "needs the test file, sub/f.txt", "--data DIR", "DFLE_T_DATA", "holding sub/",
          "(not in " .. dir .. ")")
    os.execute("mkdir -p " .. q(dir .. "/sub"))
    T.write_file(dir .. "/sub/f.txt", "x")
    T.has(sh("DFLE_T_DATA=" .. q(dir) .. " " .. q(T.dfle) .. " -q " .. q(script)), "file=" .. dir .. "/sub/f.txt")
    T.has(run("--data " .. q(dir)), "file=" .. dir .. "/sub/f.txt")
    os.execute("rm -rf " .. q(dir))
end

tests["every example refuses a misspelt option before doing any work"] = function()
    need_binary()
    local p = io.popen("ls " .. q(T.root .. "/examples") .. "/*.lua")
    local n = 0
    for path in p:lines() do
        local out, ok = sh(q(T.dfle) .. " -q " .. q(path) .. " --qiuck")
        T.eq(ok, nil, path)
        T.has(out, 'unknown option "--qiuck"', "--quick", "--help")
        n = n + 1
    end
    p:close()
    T.ok(n >= 10, "examples found: " .. n)
end

tests["examples say which data they need when it is missing"] = function()
    need_binary()
    local out, ok, code = sh("DFLE_DATA_DIR= " .. q(T.dfle) .. " -q " .. q(T.root .. "/examples/fig1_slope_area.lua") ..
                             " --quick --data /nonexistent " .. q(T.tmpname("-out")))
    T.eq(ok, nil)
    T.eq(code, 2)
    T.has(out, "needs the Big Tujunga DEM", "--data DIR", "DFLE_DATA_DIR", "/nonexistent")
end

tests["missing script file: non-zero exit with a clear message"] = function()
    need_binary()
    local path = T.tmpname() .. "-does-not-exist.lua"
    local out, ok, code = sh(q(T.dfle) .. " -q " .. q(path))
    T.eq(ok, nil)
    T.ok(code ~= 0, "exit code " .. tostring(code))
    T.match(out, "^dfle: ")
    T.has(out, "cannot open", path)
end

tests["script arguments arrive in arg and ..."] = function()
    need_binary()
    local out, ok = T.run_dfle([[
        local n = select("#", ...)
        print("n=" .. n)
        print("dots=" .. table.concat({...}, "|"))
        print("arg=" .. table.concat(arg, "|"))
        print("arg0=" .. tostring(arg[0]:match("[^/]*$")))
        print("argm1=" .. tostring(arg[-1]))
    ]], { "alpha", "two words", "", "-q" })
    T.eq(ok, true, out)
    T.has(out, "n=4\n", "dots=alpha|two words||-q\n", "arg=alpha|two words||-q\n", "argm1=-q\n")
    T.match(out, "arg0=[^\n]*%.lua\n")
end

tests["-q and --quiet are accepted; dfle is a global"] = function()
    need_binary()
    for _, flag in ipairs{ "-q", "--quiet", "" } do
        local out, ok = T.run_dfle("print(type(dfle), type(dfle.model), dfle.version)", nil, { flags = flag })
        T.eq(ok, true, out)
        T.has(out, "table\tfunction\t" .. dfle.version)
    end
end

tests["-- ends option parsing"] = function()
    need_binary()
    local script = T.tmpname(".lua")
    T.write_file(script, "print('got', ...)")
    local out, ok = sh(q(T.dfle) .. " -q -- " .. q(script) .. " --help")
    T.eq(ok, true, out)
    T.has(out, "got\t--help")
end

tests["- reads the script from standard input"] = function()
    need_binary()
    local out, ok = sh("echo 'print(\"from stdin\", ...)' | " .. q(T.dfle) .. " -q - x y")
    T.eq(ok, true, out)
    T.has(out, "from stdin\tx\ty")
end

tests["os.exit code and a successful run"] = function()
    need_binary()
    local _, ok, code = T.run_dfle("os.exit(7)")
    T.eq(ok, nil)
    T.eq(code, 7)
    local out, ok2, code2 = T.run_dfle([[
        local m = dfle.model{ channel = dfle.channel{ A_max = 2e5 } }
        local r = m:run{ years = 100 }
        print(r.reason, m.time)
    ]])
    T.eq(ok2, true, out)
    T.eq(code2, 0)
    T.has(out, "time\t100")
end

tests["non-string error object: reported, exit 1"] = function()
    need_binary()
    local out, ok, code = T.run_dfle("error({})", nil, { stderr_only = true })
    T.eq(ok, nil)
    T.eq(code, 1)
    T.match(out, "^dfle: ")
    T.has(out, "table")
end

-- Notes: what a user should know (a resumed ensemble) by default, the
-- story of the script with --verbose, nothing with -q.
tests["notes: --verbose tells each run and file, a resumed ensemble says so, -q is silent"] = function()
    local csv, ens = T.tmpname(".csv"), T.tmpname(".csv")
    os.remove(ens)
    local script = string.format([[
        local m = dfle.model{ channel = dfle.channel{ dx = 20 } }
        m:run_to_steady{}
        m:run{ years = 1000 }
        m:write_csv(%q)
        dfle.ensemble{ params = { k_df = {5e-5, 1e-3, log = true} }, n = 4, seed = 1, out = %q,
                       limit = tonumber(arg[1]), workers = 1,
                       build = function(p)
                           return dfle.model{ channel = dfle.channel{ dx = 20 },
                                              law = dfle.law.power{ k_df = p.k_df } }
                       end,
                       outputs = { "S_df" } }
        print("end")
    ]], csv, ens)
    local out, ok = T.run_dfle(script, { "2" }, { flags = "--verbose" })
    T.ok(ok, out)
    T.has(out, "dfle: model:run_to_steady: steady by the direct solve (",
          "dfle: model:run: done after ", " explicit steps, t = 1000 yr (",
          "dfle: wrote " .. csv .. " (102 nodes)", "samples run in", "end")
    T.ok(not out:find("resuming", 1, true), out)
    out, ok = T.run_dfle(script, { "1" }, { flags = "" })
    T.ok(ok, out)
    T.has(out, "dfle: ensemble " .. ens .. ": resuming: 2 finished rows kept, 1 sample to run")
    out = T.run_dfle(script, {}, { flags = "" })
    T.has(out, "resuming: 3 finished rows kept, 1 sample to run")
    T.ok(not out:find("model:run", 1, true), "runs are told only with --verbose")
    out, ok = T.run_dfle(script, {}, { flags = "-q" })
    T.ok(ok, out)
    T.eq(out, "end\n")
    out = T.run_dfle(script, {}, { flags = "" })
    T.has(out, "all 4 rows were done before; nothing to run")
    os.remove(ens)
end

return tests
