-- run.lua - the Lua-level test runner of the dfle scripting API.
--
--   build/dfle -q tests/lua/run.lua build/dfle [filter]
--
-- Loads every tests/lua/test_*.lua next to this file (sorted by name).
-- Each returns a table { test_name = function() ... end, ... }; every
-- test runs under xpcall with a traceback.  Prints "ok - file: name" or
-- "FAIL - file: name" plus the message, and ends with the line
-- "N passed, N failed"; exits 1 if anything failed.
--
-- arg[1] is the path of the dfle binary (for CLI tests, in T.dfle);
-- an optional arg[2] runs only tests whose "file: name" contains it.
-- A test named "BUG: ..." exposes a known bug and fails until it is fixed.

local here = (arg and arg[0] or ""):match("^(.*)/[^/]*$") or "."
local filter = arg and arg[2]

-- Shell quoting for paths put into io.popen / os.execute commands.
local function shquote(s)
    return "'" .. tostring(s):gsub("'", "'\\''") .. "'"
end

-- Absolute path of the dfle binary: tests may change nothing about the
-- working directory, but a relative path is fragile inside `sh -c`.
local function absolute(p)
    if p == nil or p:sub(1, 1) == "/" then return p end
    local pwd = os.getenv("PWD")
    if pwd == nil then
        local h = io.popen("pwd")
        pwd = h:read("l")
        h:close()
    end
    return pwd .. "/" .. p
end

---------------------------------------------------------------------------
-- Assertion helpers, shared by all test files as the global T.
---------------------------------------------------------------------------
T = {}
T.dfle = absolute(arg and arg[1])  -- path of the dfle binary (CLI tests)
T.dir = absolute(here)              -- tests/lua
T.root = T.dir:match("^(.*)/tests/lua$") or (T.dir .. "/../..")
-- Test data (DEMs, SALib reference cases): the test runner sets
-- DFLE_DATA_DIR (tests/run-tests.sh).
T.data = os.getenv("DFLE_DATA_DIR") or "(DFLE_DATA_DIR unset)"
T.shquote = shquote

local function fmt(v)
    if type(v) == "string" then return string.format("%q", v) end
    if type(v) == "number" then return string.format("%.17g", v) end
    return tostring(v)
end
T.fmt = fmt

local function fail(msg, level)
    error(msg, (level or 1) + 1)
end
T.fail = fail

function T.ok(cond, msg)
    if not cond then fail(msg or "assertion failed", 2) end
    return cond
end

function T.eq(a, b, msg)
    if a ~= b then
        fail(string.format("%sexpected %s, got %s", msg and (msg .. ": ") or "", fmt(b), fmt(a)), 2)
    end
end

-- Two arrays of numbers equal bit for bit (-0.0 is not 0.0), naming the
-- first index where they differ.
function T.bits_equal(a, b, what)
    what = what or "arrays"
    T.eq(#a, #b, what .. ": length")
    for i = 1, #a do
        if string.pack("d", a[i]) ~= string.pack("d", b[i]) then
            fail(string.format("%s: index %d: %.17g vs %.17g", what, i, a[i], b[i]), 2)
        end
    end
end

-- |a - b| <= abs + rel |b|; NaN never passes.
function T.close(a, b, rel, abs, msg)
    rel, abs = rel or 1e-9, abs or 0
    if type(a) ~= "number" or type(b) ~= "number" then
        fail(string.format("%snot numbers: %s, %s", msg and (msg .. ": ") or "", fmt(a), fmt(b)), 2)
    end
    local d = math.abs(a - b)
    if not (d <= abs + rel * math.abs(b)) then
        fail(string.format("%s%s and %s differ by %.3g (allowed %.3g)", msg and (msg .. ": ") or "",
                           fmt(a), fmt(b), d, abs + rel * math.abs(b)), 2)
    end
end


-- A steady profile of a compiled law against the same law run as Lua
-- (compile = false): the compiled law gives the node solvers dE/d ln S
-- and takes Newton steps, the Lua law differences E (doc/laws.md), so
-- their slopes agree to the solvers' tolerance, 1e-10 relative, not to
-- the bit (their values do: the explicit method's profiles are equal).
function T.close_to_lua(z, zl, what)
    T.eq(#z, #zl, what .. ": length")
    for i = 1, #z do T.close(z[i], zl[i], 1e-10, 0, what .. ", node " .. i) end
end
-- The string s matches the Lua pattern p.
function T.match(s, p, msg)
    if type(s) ~= "string" or not s:find(p) then
        fail(string.format("%s%s does not match pattern %q", msg and (msg .. ": ") or "", fmt(s), p), 2)
    end
    return s
end

-- The string s contains each literal text.
function T.has(s, ...)
    for i = 1, select("#", ...) do
        local text = select(i, ...)
        if type(s) ~= "string" or not s:find(text, 1, true) then
            fail(string.format("%s lacks %q", fmt(s), text), 2)
        end
    end
    return s
end

-- fn must raise; the message must match the Lua pattern. Returns it.
function T.errors(fn, pattern)
    local ok, msg = pcall(fn)
    if ok then fail("expected an error matching " .. string.format("%q", pattern) .. ", got none", 2) end
    if type(msg) ~= "string" then fail("error object is a " .. type(msg) .. ", not a string", 2) end
    if pattern ~= nil and not msg:find(pattern) then
        fail(string.format("error %q does not match pattern %q", msg, pattern), 2)
    end
    return msg
end

-- fn must raise with a message containing every literal text given.
function T.errors_with(fn, ...)
    local ok, msg = pcall(fn)
    if ok then fail("expected an error, got none", 2) end
    if type(msg) ~= "string" then fail("error object is a " .. type(msg) .. ", not a string", 2) end
    for i = 1, select("#", ...) do
        local text = select(i, ...)
        if not msg:find(text, 1, true) then
            fail(string.format("error %q lacks %q", msg, text), 2)
        end
    end
    return msg
end

-- Like T.errors_with, and the message must start with the position
-- ("file:line: ") of the line where function `where` is defined: the
-- line of the API call.  T.raises_here(fn, ...) is T.raises_at(fn, fn,
-- ...) for a one-line closure fn that makes the call itself.
function T.raises_at(where, fn, ...)
    local info = debug.getinfo(where, "S")
    local ok, msg = pcall(fn)
    if ok then fail("expected an error, got none", 2) end
    if type(msg) ~= "string" then fail("error object is a " .. type(msg) .. ", not a string", 2) end
    local pos = info.short_src .. ":" .. info.linedefined .. ": "
    if msg:sub(1, #pos) ~= pos then
        fail(string.format("error %q does not start with the caller's position %q", msg, pos), 2)
    end
    for i = 1, select("#", ...) do
        local text = select(i, ...)
        if not msg:find(text, 1, true) then
            fail(string.format("error %q lacks %q", msg, text), 2)
        end
    end
    return msg
end

function T.raises_here(fn, ...)
    return T.raises_at(fn, fn, ...)
end

-- Temporary paths, removed after each test.
local temps = {}
function T.tmpname(suffix)
    local p = os.tmpname()
    temps[#temps + 1] = p
    if suffix then
        p = p .. suffix
        temps[#temps + 1] = p
        -- the JSON record dfle writes beside a CSV file goes too
        if suffix == ".csv" then temps[#temps + 1] = p:sub(1, -5) .. ".json" end
    end
    return p
end

function T.write_file(path, text)
    local f = assert(io.open(path, "wb"))
    f:write(text)
    f:close()
end

function T.read_file(path)
    local f, err = io.open(path, "rb")
    if f == nil then return nil, err end
    local s = f:read("a")
    f:close()
    return s
end

-- A scratch directory; the returned function removes it.
function T.scratch()
    local h = io.popen("mktemp -d")
    local dir = h:read("l")
    h:close()
    return dir, function() os.execute("rm -rf " .. shquote(dir)) end
end

-- Run a shell command; returns its combined output, status and code.
function T.sh(cmd)
    local h = io.popen(cmd .. " 2>&1")
    local out = h:read("a")
    local ok, _, code = h:close()
    return out, ok, code
end

-- A CSV file dfle wrote: { comments = { "# ...", ... } (the lines
-- before the header), header = "x,A", names = { "x", "A" },
-- units = { x = "m", ... } (from "# units:"), rows = { { "0", "1000" },
-- ... } (fields as text, split at commas: no quoted fields) }.
function T.read_csv(path)
    local text = assert(T.read_file(path), path)
    local t = { comments = {}, names = {}, units = {}, rows = {} }
    for line in text:gmatch("([^\n]*)\n") do
        if t.header == nil and line:sub(1, 1) == "#" then
            t.comments[#t.comments + 1] = line
            local u = line:match("^# units: (.*)$")
            if u then
                for name, unit in (u .. ", "):gmatch("([^=,]+)=(.-), ") do t.units[name] = unit end
            end
        elseif t.header == nil then
            t.header = line
            for name in (line .. ","):gmatch("([^,]*),") do t.names[#t.names + 1] = name end
        else
            local row = {}
            for field in (line .. ","):gmatch("([^,]*),") do row[#row + 1] = field end
            t.rows[#t.rows + 1] = row
        end
    end
    return t
end

-- Decode JSON text strictly (the whole text one value; raises at the
-- first fault): objects as tables, arrays as arrays, null as T.null.
T.null = setmetatable({}, { __tostring = function() return "null" end })
function T.json_decode(text)
    local pos = 1
    local function fail_at(what)
        error(("JSON: %s at byte %d: %q"):format(what, pos, text:sub(pos, pos + 20)), 0)
    end
    local function ws() pos = text:find("[^ \t\r\n]", pos) or #text + 1 end
    local value
    local function str()
        local out, i = {}, pos + 1
        while true do
            local c = text:sub(i, i)
            if c == "" then fail_at("unterminated string") end
            if c == '"' then pos = i + 1; return table.concat(out) end
            if c:byte() < 32 then fail_at("control byte in a string") end
            if c == "\\" then
                local e = text:sub(i + 1, i + 1)
                local simple = { ['"'] = '"', ["\\"] = "\\", ["/"] = "/", b = "\b", f = "\f",
                                 n = "\n", r = "\r", t = "\t" }
                if simple[e] then out[#out + 1] = simple[e]; i = i + 2
                elseif e == "u" and text:sub(i + 2, i + 5):match("^%x%x%x%x$") then
                    out[#out + 1] = utf8.char(tonumber(text:sub(i + 2, i + 5), 16)); i = i + 6
                else fail_at("bad escape") end
            else
                out[#out + 1] = c; i = i + 1
            end
        end
    end
    function value()
        ws()
        local c = text:sub(pos, pos)
        if c == "{" then
            local t = {}
            pos = pos + 1; ws()
            if text:sub(pos, pos) == "}" then pos = pos + 1; return t end
            while true do
                ws()
                if text:sub(pos, pos) ~= '"' then fail_at("expected a key") end
                local k = str()
                if t[k] ~= nil then fail_at("duplicate key " .. k) end
                ws()
                if text:sub(pos, pos) ~= ":" then fail_at("expected ':'") end
                pos = pos + 1
                t[k] = value()
                ws()
                local d = text:sub(pos, pos); pos = pos + 1
                if d == "}" then return t end
                if d ~= "," then fail_at("expected ',' or '}'") end
            end
        elseif c == "[" then
            local t = {}
            pos = pos + 1; ws()
            if text:sub(pos, pos) == "]" then pos = pos + 1; return t end
            while true do
                t[#t + 1] = value()
                ws()
                local d = text:sub(pos, pos); pos = pos + 1
                if d == "]" then return t end
                if d ~= "," then fail_at("expected ',' or ']'") end
            end
        elseif c == '"' then return str()
        elseif text:sub(pos, pos + 3) == "true" then pos = pos + 4; return true
        elseif text:sub(pos, pos + 4) == "false" then pos = pos + 5; return false
        elseif text:sub(pos, pos + 3) == "null" then pos = pos + 4; return T.null
        else
            local num = text:match("^-?%d+%.?%d*[eE]?[-+]?%d*", pos)
            if not num or not tonumber(num) or num:match("^-?0%d") then fail_at("bad value") end
            pos = pos + #num
            return tonumber(num)
        end
    end
    local v = value()
    ws()
    if pos <= #text then fail_at("text after the value") end
    return v
end

-- Run the dfle binary on a script text (written to a temporary file)
-- with extra command-line words; returns combined output, the exit
-- status (true/nil as os.execute) and the exit code.
function T.run_dfle(script, args, opts)
    opts = opts or {}
    local path = T.tmpname(".lua")
    T.write_file(path, script)
    local cmd = shquote(T.dfle) .. " " .. (opts.flags or "-q") .. " " .. shquote(path)
    if opts.env then cmd = opts.env .. " " .. cmd end
    for _, a in ipairs(args or {}) do cmd = cmd .. " " .. shquote(a) end
    local h = io.popen(cmd .. (opts.stderr_only and " 2>&1 >/dev/null" or " 2>&1"))
    local out = h:read("a")
    local ok, how, code = h:close()
    return out, ok, code, how
end

---------------------------------------------------------------------------
-- Discovery and running.
---------------------------------------------------------------------------
local function list_tests()
    local files = {}
    local h = io.popen("ls -1 " .. shquote(here) .. " 2>/dev/null")
    if h then
        for name in h:lines() do
            if name:match("^test_.*%.lua$") then files[#files + 1] = name end
        end
        h:close()
    end
    table.sort(files)
    return files
end

local passed, failed, failures = 0, 0, {}

local function report(ok, label, msg)
    if ok then
        passed = passed + 1
        print("ok - " .. label)
    else
        failed = failed + 1
        failures[#failures + 1] = label
        print("FAIL - " .. label)
        for line in (tostring(msg) .. "\n"):gmatch("(.-)\n") do
            print("    " .. line)
        end
    end
end

local function cleanup()
    for i = #temps, 1, -1 do
        os.remove(temps[i])
        temps[i] = nil
    end
end

local files = list_tests()
if #files == 0 then
    report(false, "run.lua: discovery", "no tests/lua/test_*.lua found in " .. here)
end

for _, file in ipairs(files) do
    local chunk, lerr = loadfile(here .. "/" .. file)
    local ok, tests = false, lerr
    if chunk then
        ok, tests = xpcall(chunk, debug.traceback, T)
        if ok and type(tests) ~= "table" then
            ok, tests = false, "the file returned a " .. type(tests) .. ", not a table of tests"
        end
    end
    if not ok then
        report(false, file .. ": (load)", tests)
    else
        local names = {}
        for name, fn in pairs(tests) do
            if type(fn) == "function" then names[#names + 1] = name end
        end
        table.sort(names)
        for _, name in ipairs(names) do
            local label = file .. ": " .. name
            if filter == nil or label:find(filter, 1, true) then
                local tok, terr = xpcall(tests[name], debug.traceback)
                cleanup()
                collectgarbage()
                report(tok, label, terr)
            end
        end
    end
end

if failed > 0 then
    print("failed: " .. table.concat(failures, "; "))
end
print(string.format("%d passed, %d failed", passed, failed))
io.stdout:flush()
if failed > 0 then os.exit(1, true) end
