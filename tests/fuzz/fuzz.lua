-- fuzz.lua - calls the whole public Lua API of dfle with hostile
-- arguments, as SQLite's fuzzers call its API, and reports anything that
-- is not a normal result or a clear error.
--
--   cd SCRATCH && dfle -q -j 1 tests/fuzz/fuzz.lua seed=N calls=N scratch=SCRATCH \
--       [data=DIR] [progress=FILE] [verbose] [list]
--
-- run.sh makes SCRATCH (the working directory; nothing is written
-- elsewhere), the device nodes in it, and watches the progress file for a
-- call that hangs.  `-j 1`: dfle.ensemble must not start worker threads
-- here, since a worker replays its script, and this script is thousands
-- of calls long.
--
-- Each call runs under pcall and must end in one of:
--   * a result, in which every number the API documents as finite is
--     finite;
--   * an error whose message starts with the caller's position and names
--     dfle (or, from Lua's own argument checks, the function), or the
--     unchanged error of a callback the fuzzer made misbehave.
-- Anything else is a finding, printed as
--   FINDING seed=S call=K <target>: <what> -- <arguments>
-- A crash or a sanitizer report ends the process (run.sh names the call
-- from the progress file).  The last line is the summary:
--   fuzz seed=S calls=N ok=A errors=B findings=F refused=R untemplated=U
local here = (arg[0]:match("^(.*)/[^/]*$") or ".")
package.path = here .. "/?.lua;" .. package.path
local H = require("hostile")
local A = require("api")
local I = require("inputs")

---------------------------------------------------------------------------
-- Arguments.
---------------------------------------------------------------------------
-- data: the shared data directory (dem/, salib/), DFLE_DATA_DIR by default
local opt = { seed = 1, calls = 1000, data = os.getenv("DFLE_DATA_DIR") }
for i = 1, #arg do
    local k, v = arg[i]:match("^([%w_]+)=(.*)$")
    if k then opt[k] = v else opt[arg[i]] = true end
end
opt.seed = math.tointeger(tonumber(opt.seed)) or error("seed must be an integer")
opt.calls = math.tointeger(tonumber(opt.calls)) or error("calls must be an integer")
local scratch = opt.scratch or error("scratch=DIR is required (run.sh makes one)")
if not opt.data or opt.data == "" then error("the shared data directory: set DFLE_DATA_DIR or pass data=DIR") end

-- The scratch directory must be where we are: every relative path the
-- fuzzer makes lands there.
do
    -- (one marker a seed: two fuzzers may share the directory)
    local name = ".fuzz-here." .. opt.seed
    local f = assert(io.open(scratch .. "/" .. name, "w"))
    f:write(tostring(opt.seed))
    f:close()
    local g = io.open(name, "r")
    local same = g and g:read("a") == tostring(opt.seed)
    if g then g:close() end
    if not same or scratch:sub(1, 1) ~= "/" or scratch:find("/%.%./") then
        io.stderr:write("fuzz.lua: run it inside its scratch directory, given as an absolute path\n")
        os.exit(2)
    end
end

---------------------------------------------------------------------------
-- State.
---------------------------------------------------------------------------
local S = { r = H.rng(opt.seed), pool = {}, closed = {}, depth = 0, noted = {},
            stats = { ok = 0, errors = 0, findings = 0, refused = 0 }, untemplated = {} }
local r = S.r
S.inputs = I

-- The progress file: the call about to run, one line each, for run.sh's
-- watchdog (a hang is a file that stops changing) and for naming the
-- call that crashed.  Started afresh every 500 calls, so it stays small
-- under a file-size limit.
local progress = opt.progress and assert(io.open(opt.progress, "a")) or nil
local function note_progress(k, what)
    if not progress then return end
    if k % 500 == 0 and what ~= "(check of a pooled model)" then
        progress:close()
        progress = assert(io.open(opt.progress, "w"))
    end
    progress:write(("%d %s\n"):format(k, what))
    progress:flush()
end

local POOL_MAX = 4

function S:has(kind)
    local p = self.pool[kind]
    return p ~= nil and #p > 0
end

function S:put(kind, obj)
    local p = self.pool[kind] or {}
    self.pool[kind] = p
    p[#p + 1] = obj
    if #p > POOL_MAX then table.remove(p, 1) end
end

-- A live object of `kind`: a pooled one, or a new one.
function S:get(kind)
    local p = self.pool[kind]
    if p and #p > 0 and (r.chance(0.8) or #p >= POOL_MAX) then return p[r.int(#p)] end
    local make = A.MAKE[kind]
    local ok, obj = pcall(make, self)
    if ok and obj ~= nil then
        self:put(kind, obj)
        return obj
    end
    if p and #p > 0 then return p[1] end
    return nil
end

local KINDS = {}
for k in pairs(A.MAKE) do KINDS[#KINDS + 1] = k end
table.sort(KINDS)

-- Any live object, or a closed one.
function S:any_object()
    if #self.closed > 0 and r.chance(0.25) then return self.closed[r.int(#self.closed)] end
    local kind = r.pick(KINDS)
    if kind == "ensemble" or kind == "dfle.dem" or kind == "dfle.profile" or kind == "inversion" then
        if self:has(kind) then return self.pool[kind][1] end
        kind = "dfle.channel"
    end
    return self:get(kind)
end

-- Close or collect a pooled object: through <close> where the type has
-- it, else through __gc (the debug library's way, documented as
-- refused by dfle.model afterwards).
local function close_obj(obj)
    local mt = debug.getmetatable(obj)
    if type(mt) ~= "table" then return end
    if rawget(mt, "__close") and r.chance(0.7) then
        local ok, err = pcall(function() local x <close> = obj end)
        if not ok then return err end
    elseif rawget(mt, "__gc") then
        rawget(mt, "__gc")(obj)
    end
end

function S:close_some()
    local kind = r.pick(KINDS)
    local p = self.pool[kind]
    if not p or #p == 0 then return end
    local i = r.int(#p)
    local obj = table.remove(p, i)
    close_obj(obj)
    self.closed[#self.closed + 1] = obj
    if #self.closed > 8 then table.remove(self.closed, 1) end
end

function S:drop_some()
    for _, kind in ipairs(KINDS) do
        if r.chance(0.3) then self.pool[kind] = nil end
    end
end

-- Record a value the call returned that is worth keeping: small objects
-- go to the pool, so later calls use what earlier calls made.
local function kind_of(v)
    local t = A.typename(v)
    if t == "dfle.channel" then
        local ok, n = pcall(function() return #v end)
        return ok and type(n) == "number" and n <= 500 and "dfle.channel" or nil
    elseif t == "dfle.model" then
        local ok, n = pcall(function() return v.n end)
        return ok and type(n) == "number" and n <= 500 and "dfle.model" or nil
    elseif t == "dfle.dem" or t == "dfle.profile" then
        local ok, n = pcall(function() return v.n end)
        return ok and type(n) == "number" and n <= 20000 and t or nil
    elseif t == "dfle.ensemble" then
        return "ensemble"
    elseif t == "dfle.inversion" then
        return "inversion"
    elseif t == "dfle.landscape" then
        local ok, n = pcall(function() return v.n end)
        return ok and type(n) == "number" and n <= 1000 and "dfle.landscape" or nil
    elseif t == "dfle.law" then
        local ok, name = pcall(function() return v.name end)
        if ok and name == "power" then return "law.power" end
    elseif t == "dfle.router" then
        local ok, name = pcall(function() return v.name end)
        if ok and name == "empirical" then return "router.empirical" end
    end
    return nil
end

---------------------------------------------------------------------------
-- Callbacks: S.cb(kind, valid) is `valid`, or a copy that misbehaves.
---------------------------------------------------------------------------
local nested_call -- below

local ctx = {
    note = function(what) S.noted[what] = true end,
    reenter = function() nested_call() end,
    close_some = function() S:close_some() end,
    drop_some = function() S:drop_some() end,
    wrong_object = function()
        if r.chance(0.5) then return S:any_object() end
        return S:get("dfle.channel")
    end,
}
-- Mutate the option tables of the call in progress (they were read
-- already, or are being read: the library must not hold pointers into
-- them) and collect garbage.
ctx.mutate = function()
    local args = S.current_args
    if args then
        for i = 1, args.n or 0 do
            local t = args[i]
            if type(t) == "table" and getmetatable(t) == nil then
                local keys = {}
                for k in next, t do if type(k) == "string" then keys[#keys + 1] = k end end
                table.sort(keys)
                for _, k in ipairs(keys) do
                    if r.chance(0.5) then rawset(t, k, r.chance(0.5) and H.string(r) or nil) end
                end
            end
        end
    end
    collectgarbage("collect")
end

function S.cb(kind, valid)
    if S.plain then return valid end
    local f = H.callback(r, kind, valid, ctx)
    if r.chance(0.05) then
        local inner, left = f, 20
        f = function(...)
            if left > 0 then left = left - 1; ctx.mutate() end
            return inner(...)
        end
    end
    return f
end

-- A file name to write; S.legal says whether writing it must succeed.
function S.path(ext)
    local p, legal = I.path(S, ext)
    S.legal = legal
    return p
end

---------------------------------------------------------------------------
-- Values for mutation.
---------------------------------------------------------------------------
local function any_value()
    local k = r.int(20)
    if k <= 14 then return H.any(r) end
    if k <= 17 then return S:any_object() end
    return S.cb("value", function() return 1 end)
end

local function sorted_keys(t)
    local keys = {}
    for k in next, t do keys[#keys + 1] = k end
    table.sort(keys, function(a, b)
        local ta, tb = type(a), type(b)
        if ta ~= tb then return ta < tb end
        if ta == "number" or ta == "string" then return a < b end
        return false
    end)
    return keys
end

-- A table a script may change: its own, or an ensemble's result.
local function plain_table(v)
    return type(v) == "table" and (getmetatable(v) == nil or A.typename(v) == "dfle.ensemble")
end

local function mutate_table(t, budget, depth)
    local keys = sorted_keys(t)
    local op = r.int(7)
    if #keys == 0 then op = 4 end
    local key = keys[#keys > 0 and r.int(#keys) or 1]
    if op == 1 or op == 2 then                       -- a hostile value
        if budget and budget[key] then t[key] = H.bad_budget(r) else t[key] = any_value() end
    elseif op == 3 then                              -- a key removed
        -- (a budget key removed would take its default, which may be
        -- large: it gets a value that is refused instead)
        if budget and budget[key] then t[key] = H.bad_budget(r) else t[key] = nil end
    elseif op == 4 then                              -- a misspelt or unknown key
        if type(key) == "string" and r.chance(0.7) then t[H.misspell(r, key)] = t[key]
        else t[r.pick{ "bogus", "", "\0", 1, 2.5, true }] = any_value() end
    elseif op == 5 and plain_table(t[key]) and depth < 3 then
        mutate_table(t[key], nil, depth + 1)         -- inside a nested table
    elseif op == 6 and getmetatable(t) == nil then   -- a metatable on the options
        setmetatable(t, { __index = function(_, k)
            if r.chance(0.5) then error(H.MARK .. ": __index of an options table", 0) end
            return nil
        end })
    else
        if budget and budget[key] then t[key] = H.bad_budget(r) else t[key] = H.number(r) end
    end
end

local function mutate(args, budget)
    local n = r.weighted{ { 30, 0 }, { 40, 1 }, { 20, 2 }, { 10, 3 } }
    for _ = 1, n do
        local op = r.int(10)
        local tables = {}
        for i = 1, args.n do if plain_table(args[i]) then tables[#tables + 1] = i end end
        if op >= 5 and #tables > 0 then
            local i = r.pick(tables)
            mutate_table(args[i], budget and budget[i], 0)
        elseif op <= 2 or #tables == 0 then
            local i = r.int(args.n + 1)
            if budget and budget[i] == true then args[i] = H.bad_budget(r)
            else args[i] = any_value() end
            if i > args.n then args.n = i end
        elseif op == 3 then
            args.n = math.max(0, args.n - 1)
        else
            local i = r.int(args.n + 1)
            args[i] = S:any_object()
            if i > args.n then args.n = i end
        end
    end
    return n
end

---------------------------------------------------------------------------
-- Targets: every function found in dfle, every method of every object
-- type, and the metamethods.
---------------------------------------------------------------------------
local targets = {}
local WEIGHT = {
    ["dfle.plot.slope_area"] = 0.1, ["dfle.plot.profile"] = 0.1, ["dfle.plot.flow"] = 0.05,
    ["dfle.plot.xy"] = 0.1, ["dfle.plot.panels"] = 0.1, ["dfle.plot.sheet"] = 0.05,
    ["dfle.plot.corner"] = 0.1, ["dfle.plot.posterior_predictive"] = 0.1,
    ["dfle.landscape:plot"] = 0.1, ["dfle.ensemble"] = 0.4, ["dfle.gather"] = 0.6,
    ["dfle.worker"] = 0.2, ["dfle.model"] = 2, ["dfle.model:run"] = 2,
    ["dfle.model:run_to_steady"] = 2,
}

local stub_cache = {}
local function stub(code)
    local f = stub_cache[code]
    if not f then
        f = assert(load(code, "=fuzzcall"))
        stub_cache[code] = f
    end
    return f
end

local function add_function(path, fn)
    targets[#targets + 1] = {
        name = path, weight = WEIGHT[path] or 1, short = path:match("([^.]+)$"),
        -- called by name, as a script calls it, so Lua's own argument
        -- errors name the function as a script would see it
        call = stub("local a = ... return " .. path .. "(table.unpack(a, 1, a.n))"),
        template = A.templates[path],
    }
end

local function add_method(tname, mname, fn)
    local name = tname .. ":" .. mname
    targets[#targets + 1] = {
        name = name, weight = WEIGHT[name] or 1, short = mname, tname = tname, method = mname,
        fn = fn, -- the method itself, for calls with another self
        call = stub("local o, a = ... return o:" .. mname .. "(table.unpack(a, 1, a.n))"),
        -- the method of one type called on another object (o.m(x))
        call_other = stub("local t, a = ... return t." .. mname .. "(table.unpack(a, 1, a.n))"),
        template = A.templates[name],
    }
end

local function discover()
    for _, f in ipairs(A.functions(dfle)) do add_function(f.path, f.fn) end
    local tnames = {}
    for t in pairs(A.SELF) do tnames[#tnames + 1] = t end
    table.sort(tnames)
    S.plain = true
    for _, tname in ipairs(tnames) do
        -- (a few tries: a fuzzer sharing the directory may hold an
        -- ensemble file locked for a moment)
        local obj
        for _ = 1, 20 do
            obj = S:get(A.SELF[tname][1])
            if obj ~= nil then break end
        end
        assert(obj ~= nil, "cannot make a " .. tname .. " to find its methods")
        local methods = assert(A.methods(obj), "no methods table for " .. tname)
        local names = {}
        for m in pairs(methods) do names[#names + 1] = m end
        table.sort(names)
        for _, m in ipairs(names) do add_method(tname, m, methods[m]) end
    end
    S.plain = false
    -- Metamethods and properties, through the debug library where a
    -- script could not reach them.
    for _, special in ipairs{ "property", "tostring", "len", "gc", "close", "index",
                              "collect" } do
        targets[#targets + 1] = { name = "#" .. special, weight = 0.5, special = special,
                                  short = "__" .. special }
    end
    for _, t in ipairs(targets) do
        if not t.template and not t.special then S.untemplated[#S.untemplated + 1] = t.name end
    end
end

---------------------------------------------------------------------------
-- Outcomes.
---------------------------------------------------------------------------
local function describe(v, depth)
    depth = depth or 0
    local t = type(v)
    if t == "string" then
        if #v > 40 then return ("<string %d bytes>"):format(#v) end
        return ("%q"):format(v):gsub("\\\n", "\\n")
    end
    if t == "number" then
        if math.type(v) == "integer" then return tostring(v) end
        return ("%.17g"):format(v)
    end
    if t == "userdata" and A.typename(v):find("^dfle%.") then
        local ok, text = pcall(tostring, v)
        return ok and type(text) == "string" and text:sub(1, 200) or A.typename(v)
    end
    if t ~= "table" then return A.typename(v) end
    if getmetatable(v) ~= nil then return "<table with a metatable>" end
    if depth > 1 then return "{...}" end
    local parts, keys = {}, sorted_keys(v)
    for i, k in ipairs(keys) do
        if i > 8 then parts[#parts + 1] = ("...%d keys"):format(#keys); break end
        local kk = type(k) == "string" and k or "[" .. describe(k, 2) .. "]"
        parts[#parts + 1] = kk .. "=" .. describe(rawget(v, k), depth + 1)
    end
    return "{" .. table.concat(parts, ", ") .. "}"
end

-- A message as it can be printed: control bytes escaped, at most 300 bytes.
local function shown(msg)
    local s = msg:sub(1, 300):gsub("[%c\128-\255]", function(c) return ("\\%d"):format(c:byte()) end)
    return "'" .. s .. (#msg > 300 and ("'... (%d bytes)"):format(#msg) or "'")
end

local function describe_args(a)
    local parts = {}
    for i = 1, a.n do parts[i] = describe(a[i]) end
    return table.concat(parts, ", ")
end

local current -- { seed, call, target, args }

local function finding(what)
    S.stats.findings = S.stats.findings + 1
    print(("FINDING seed=%d call=%d %s: %s -- %s"):format(opt.seed, current.call,
          current.target, what, current.args_text))
    io.stdout:flush()
end

-- Where the API documents a value that is not finite.
local NONFINITE_OK = {
    ["dfle.router:route"] = { arrival = "nan", t = "nan" },  -- never reached, ended first
    ["dfle.pawn"] = { ["*"] = "nan" },                       -- degenerate data
    ["dfle.ensemble"] = { ["*"] = "nan" },                   -- outputs of failed rows
    ["dfle.gather"] = { ["*"] = "nan" },
    ["dfle.ensemble:write_netcdf"] = { ["*"] = "nan" },      -- returns the ensemble
    ["dfle.landscape:get"] = { ["*"] = "nan" },              -- NoData cells
    -- a parameter no walker moved in: tau NaN, tau_max inf (warned)
    -- lsq.corr NaN for a parameter of zero variance (documented)
    ["dfle.invert"] = { ["tau.*"] = "nan", tau_max = "inf", corr = "nan" },
}

local function has_nonfinite(v, seen, depth)
    if type(v) == "number" then return v ~= v or v == math.huge or v == -math.huge end
    if type(v) ~= "table" or seen[v] or depth > 4 then return false end
    seen[v] = true
    local k = 0
    for _, x in next, v do
        k = k + 1
        if k > 5000 then break end
        if has_nonfinite(x, seen, depth + 1) then return true end
    end
    return false
end

local function check_finite(target, v, path, seen, allow, depth)
    if type(v) == "number" then
        if v == v and v ~= math.huge and v ~= -math.huge then return end
        local plain = path:gsub("%[%]", "")
        local last = plain:match("([^.]+)$") or ""
        local parent = plain:match("([^.]+)%.[^.]+$")
        local a = allow and (allow[last] or allow["*"] or (parent and allow[parent .. ".*"]))
        if a == "nan" and v ~= v then return end
        if a == "inf" and v ~= v then a = nil end
        if a then return end
        finding(("non-finite result %s = %s"):format(path, tostring(v)))
        return true
    end
    if type(v) ~= "table" or seen[v] or depth > 4 then return end
    seen[v] = true
    local keys, k = sorted_keys(v), 0
    for _, key in ipairs(keys) do
        k = k + 1
        if k > 5000 then return end
        local sub = type(key) == "string" and (path .. "." .. key) or (path .. "[" .. tostring(key) .. "]")
        if type(key) == "number" then sub = path .. "[]" end
        if check_finite(target, rawget(v, key), sub, seen, allow, depth + 1) then return true end
    end
end

local function check_result(t, res, self)
    local allow = NONFINITE_OK[t.name]
    if t.name == "dfle.fluvial:steady_slope" then
        -- inf when K = 0, as documented
        local ok, K = pcall(function() return self.K end)
        if ok and K == 0 then allow = { ["*"] = "inf" } end
    end
    if t.name == "dfle.lhs" and has_nonfinite(current.raw_args, {}, 0) then return end
    -- a table handed back as it was given (dfle.write_fit returns its
    -- fit) holds the fuzzer's own numbers, NaN included
    local given = {}
    local a = current.raw_args
    for i = 1, a and a.n or 0 do if type(a[i]) == "table" then given[a[i]] = true end end
    for i = 1, res.n do
        if not given[res[i]] and check_finite(t.name, res[i], "result" .. i, {}, allow, 0) then
            return
        end
    end
end

local LUA_OWN = { "stack overflow", "not enough memory", "attempt to yield",
                  "C stack overflow", "error in error handling" }

local function check_error(t, err)
    local noted = S.noted
    if type(err) ~= "string" then
        if err == H.MARK_TABLE and noted.table then return end
        if err == nil and noted["nil"] then return end
        finding("error object is a " .. A.typename(err) .. ", not a message")
        return
    end
    if err:find("interrupted (SIG", 1, true) then S.interrupted = true end
    if err:find(H.MARK, 1, true) then return end              -- a callback's own error
    if err:find("not enough memory", 1, true) then return end  -- allocation refused
    if noted.string then
        for _, m in ipairs(LUA_OWN) do if err:find(m, 1, true) then return end end
    end
    local pos = "fuzzcall:1: "
    local body = err:sub(1, #pos) == pos and err:sub(#pos + 1) or nil
    if body == nil then
        finding("error without the caller's position: " .. shown(err))
        return
    end
    -- printf's "-nan" where dfle formats a number (a quoted name may be
    -- anything, tostring(0/0) included)
    if body:gsub("'[^']*'", "''"):find("-nan", 1, true) then
        finding("message shows '-nan': " .. shown(body))
    end
    local argno = body:match("^bad argument #(%-?%d+)")
    if argno and tonumber(argno) < 1 then
        finding("message names argument #" .. argno .. ": " .. shown(body))
        return
    end
    -- dfle's own messages, and Lua's argument checks that name a dfle type
    if body:find("dfle", 1, true) then return end
    -- dfle.args speaks to the script's user about the command line
    -- ("unknown option \"--x\" (options: ...)")
    if t.name == "dfle.args" then return end
    local fname = body:match("^bad argument #%d+ to '([^']*)'") or
                  body:match("^calling '([^']*)' on bad self")
    if fname ~= nil and t.short and (fname == t.short or fname:match("[.:]" .. t.short .. "$")) then return end
    finding("error that does not name dfle or the function: " .. shown(body))
end

---------------------------------------------------------------------------
-- One call.
---------------------------------------------------------------------------
-- Metamethods and fields are reached as a script would, from "fuzzcall".
local STUB_INDEX = stub("local o, k = ... return table.pack(o[k])")
local function stub_meta(name)
    return stub("local mt, o, x = ... return table.pack(mt." .. name .. "(o, x))")
end

local function special_call(t)
    local obj = S:any_object()
    if obj == nil then return true, table.pack() end
    local mt = debug.getmetatable(obj)
    local sp = t.special
    if sp == "property" then
        local key = r.chance(0.7) and r.pick{ "n", "time", "U", "name", "channel", "router",
            "law", "fluvial", "dx", "dy", "nx", "ny", "extent", "crs", "epsg", "z_min", "z_max",
            "sinks", "flats", "kind", "length", "A_min", "A_max", "outlet", "head", "given",
            "snap_distance", "ds", "dz", "path", "M0", "tau_y", "k_df", "alpha", "max_steps",
            "routed", "filled", "nodata_cells", "geographic" } or H.any(r)
        current.args_text = describe(obj) .. "[" .. describe(key) .. "]"
        return pcall(STUB_INDEX, obj, key)
    end
    if type(mt) ~= "table" then return true, table.pack() end
    local mm = rawget(mt, "__" .. sp)
    if sp == "collect" then
        S:drop_some()
        return pcall(function() collectgarbage("collect"); return table.pack() end)
    end
    if type(mm) ~= "function" then return true, table.pack() end -- (an __index table)
    -- a metamethod called with anything as its object
    local target = r.chance(0.7) and obj or any_value()
    local extra = r.chance(0.5) and any_value() or r.pick{ "n", "get", "time" }
    current.args_text = describe(target) .. ", " .. describe(extra)
    if sp == "gc" or sp == "close" then
        if target == obj then
            for _, kind in ipairs(KINDS) do
                local p = S.pool[kind]
                for i = p and #p or 0, 1, -1 do if p[i] == obj then table.remove(p, i) end end
            end
            S.closed[#S.closed + 1] = obj
            if #S.closed > 8 then table.remove(S.closed, 1) end
        end
    end
    return pcall(stub_meta("__" .. sp), mt, target, extra)
end

local function build_call(t)
    local args, budget, self
    if t.tname then
        local kinds = A.SELF[t.tname]
        self = S:get(r.pick(kinds))
    end
    local expect
    if t.template then
        local ok, a, b, c = pcall(t.template, S, self)
        if ok then args, budget, expect = a, b, c else args = table.pack() end
    else
        args = table.pack()
        for i = 1, r.int(4) - 1 do args[i] = any_value() end
        args.n = #args
    end
    local muts = mutate(args, budget)
    -- the wrong object as self, or a closed one
    local how = "method"
    if t.tname and (r.chance(0.1) or self == nil) then
        -- o.method(x) with x not an object of the type: `x:method()`
        -- would be Lua's own error (indexing x), not the library's
        how = "other"
        if self ~= nil then self = r.chance(0.5) and S:any_object() or any_value() end
    end
    return args, self, how, muts == 0 and how == "method" and expect or nil
end

local function run_call(t, args, self, how)
    local f = t.call
    if t.tname then
        if how == "other" then
            return pcall(t.call_other, { [t.method] = t.fn }, args)
        end
        return pcall(f, self, args)
    end
    return pcall(f, args)
end

-- Targets by weight, built once.
local weighted
local function pick_target()
    if not weighted then
        weighted = {}
        for i, x in ipairs(targets) do weighted[i] = { x.weight, x } end
    end
    return r.weighted(weighted)
end

-- A call made from inside a callback: any target, its outcome ignored
-- except for crashes (which end the process anyway).
nested_call = function()
    if S.depth >= 2 then return end
    S.depth = S.depth + 1
    local t = pick_target()
    if not t.special then
        local ok, args, self, how = pcall(build_call, t)
        if ok then
            I.sanitize(args, scratch)
            run_call(t, args, self, how)
        end
    end
    S.depth = S.depth - 1
end

local cost = {}   -- target -> { calls, cpu seconds }, for `timing`

local function do_call(k)
    local t = pick_target()
    local c0 = os.clock()
    current = { call = k, target = t.name, args_text = "" }
    S.noted = {}
    note_progress(k, t.name)
    local ok, res
    if t.special then
        ok, res = special_call(t)
    else
        local args, self, how, expect = build_call(t)
        local _, refused = I.sanitize(args, scratch)
        if type(self) == "table" then I.sanitize(self, scratch) end
        S.stats.refused = S.stats.refused + refused
        current.raw_args = args
        current.self = self
        current.expect = expect
        current.args_text = (t.tname and (describe(self) .. (how == "other" and " (as self of another type) " or ":")) or "") ..
            "(" .. describe_args(args) .. ")"
        S.current_args = args
        if opt.verbose then
            print(("call %d %s %s ..."):format(k, t.name, current.args_text:sub(1, 300)))
            io.stdout:flush()
        end
        local packed
        if r.chance(0.1) then
            -- inside a coroutine: a callback's yield must be refused cleanly
            local co = coroutine.wrap(function() return table.pack(run_call(t, args, self, how)) end)
            local cok, p = pcall(co)
            if cok and type(p) ~= "table" then
                finding("a callback's yield escaped the call")
                p = table.pack(true)
            end
            packed = cok and p or table.pack(false, p)
        else
            packed = table.pack(run_call(t, args, self, how))
        end
        ok = packed[1]
        if ok then res = table.pack(table.unpack(packed, 2, packed.n)) else res = packed[2] end
        S.current_args = nil
    end
    if ok then
        S.stats.ok = S.stats.ok + 1
        if type(res) == "table" and res.n then
            check_result(t, res, current.self)
            for i = 1, res.n do
                local kind = kind_of(res[i])
                if kind then S:put(kind, res[i]) end
            end
        end
    else
        S.stats.errors = S.stats.errors + 1
        check_error(t, res)
        -- a legal file name, unmutated arguments: only the object itself
        -- (a law that raises, a closed model) may make the write fail
        if current.expect == "write" and type(res) == "string" and
           res:find("cannot write", 1, true) then
            finding("a write that must succeed failed: " .. shown(res))
        end
    end
    local dt = os.clock() - c0
    local c = cost[t.name] or { 0, 0, 0 }
    cost[t.name] = c
    c[1], c[2], c[3] = c[1] + 1, c[2] + dt, math.max(c[3], dt)
    if opt.verbose then
        print(("call %d %s %s -> %s (%.3f s)"):format(k, t.name, current.args_text:sub(1, 300),
              ok and "ok" or describe(res), dt))
    end
end

-- Models left in the pool must still be whole: their time finite, their
-- fields finite and n long (a failed call must not leave a model broken).
local function check_models(k)
    local p = S.pool["dfle.model"]
    if not p or #p == 0 then return end
    local m = p[r.int(#p)]
    current = { call = k, target = "(check of a pooled model)", args_text = describe(m) }
    local ok, time = pcall(function() return m.time end)
    if ok and not (type(time) == "number" and time == time and time >= 0 and time < math.huge) then
        finding("model time is " .. tostring(time))
    end
    -- (get runs the model's laws, which may close it: then m.n raises)
    local ok2, z = pcall(function() return m:get("z") end)
    local ok3, n = pcall(function() return m.n end)
    if ok2 then
        if ok3 and #z ~= n then finding(("get('z') has %d values, m.n = %d"):format(#z, n)) end
        for i = 1, #z do
            if z[i] ~= z[i] or z[i] == math.huge or z[i] == -math.huge then
                finding(("z[%d] = %s"):format(i, tostring(z[i])))
                break
            end
        end
    end
end

---------------------------------------------------------------------------
-- Main.
---------------------------------------------------------------------------
I.setup(S, scratch, opt.data)
S.plain = true
I.make_ensemble(A.ensemble_spec(S), opt.seed)
S.plain = false
discover()

if opt.list then
    for _, t in ipairs(targets) do
        print(t.name .. (t.template and "" or t.special and "" or "  (no template)"))
    end
    return
end

local t0 = os.clock()
local made = 0
for k = 1, opt.calls do
    made = k
    do_call(k)
    if k % 10 == 0 then
        local c0 = os.clock()
        note_progress(k, "(check of a pooled model)")
        check_models(k)
        local c = cost["(model check)"] or { 0, 0, 0 }
        cost["(model check)"] = c
        local dt = os.clock() - c0
        c[1], c[2], c[3] = c[1] + 1, c[2] + dt, math.max(c[3], dt)
    end
    if S.interrupted then
        print(("fuzz: interrupted at call %d"):format(k))
        break
    end
end
local cpu = os.clock() - t0
if progress then progress:close() end
print(("fuzz seed=%d calls=%d ok=%d errors=%d findings=%d refused=%d untemplated=%d cpu=%.1fs")
      :format(opt.seed, made, S.stats.ok, S.stats.errors, S.stats.findings,
              S.stats.refused, #S.untemplated, cpu))
if #S.untemplated > 0 then print("untemplated: " .. table.concat(S.untemplated, ", ")) end
if opt.timing then
    local names = {}
    for name in pairs(cost) do names[#names + 1] = name end
    table.sort(names, function(a, b) return cost[a][2] > cost[b][2] end)
    for _, name in ipairs(names) do
        local c = cost[name]
        print(("  %-36s %6d calls %8.2f s cpu, slowest %.3f s"):format(name, c[1], c[2], c[3]))
    end
end
io.stdout:flush()
if S.stats.findings > 0 then os.exit(1) end
