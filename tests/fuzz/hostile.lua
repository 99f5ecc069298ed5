-- hostile.lua - the fuzzer's source of randomness and of hostile values:
-- a seeded generator (splitmix64, so a seed means the same calls on every
-- machine and Lua build), numbers at the edges of double and integer
-- arithmetic, strings with NUL bytes or 100 KB long, odd tables, and
-- callbacks that raise, yield, recurse, return the wrong thing, close
-- objects or re-enter the library.
--
-- Nothing here iterates a table with pairs(): the order of string keys
-- changes from run to run (Lua seeds its string hash), and a seed must
-- give the same calls every time.
local H = {}

---------------------------------------------------------------------------
-- The generator.
---------------------------------------------------------------------------
function H.rng(seed)
    local s = math.tointeger(seed) or 0
    local r = {}
    -- splitmix64 (Steele, Lea and Flood 2014); Lua integers wrap.
    function r.u64()
        s = s + 0x9E3779B97F4A7C15
        local z = s
        z = (z ~ (z >> 30)) * 0xBF58476D1CE4E5B9
        z = (z ~ (z >> 27)) * 0x94D049BB133111EB
        return z ~ (z >> 31)
    end
    -- 1 .. n
    function r.int(n) return (r.u64() >> 1) % n + 1 end
    -- lo .. hi
    function r.range(lo, hi) return lo + r.int(hi - lo + 1) - 1 end
    -- [0, 1)
    function r.float() return (r.u64() >> 11) * 2.0^-53 end
    function r.chance(p) return r.float() < p end
    function r.pick(t) return t[r.int(#t)] end
    -- Pick from { {weight, value}, ... }.
    function r.weighted(t)
        local total = 0
        for i = 1, #t do total = total + t[i][1] end
        local x = r.float() * total
        for i = 1, #t do
            x = x - t[i][1]
            if x < 0 then return t[i][2] end
        end
        return t[#t][2]
    end
    return r
end

---------------------------------------------------------------------------
-- Numbers.
---------------------------------------------------------------------------
local NUMBERS = {
    0, -0.0, 1, -1, 0.5, -0.5, 2, 3, 10, 100, 1000, 1e6, 1e6 + 1, 1e7, 1e9, 1e15, 1e16,
    0.1, 1 / 3, 1.5, 7.5, 1e-10, 1e-300, -1e-300, 5e-324, 2.2250738585072014e-308,
    1e300, -1e300, 1.7976931348623157e308, -1.7976931348623157e308,
    math.huge, -math.huge, 0 / 0, -(0 / 0),
    math.maxinteger, math.mininteger, math.maxinteger - 1, math.mininteger + 1,
    2^53, 2^53 + 1, (1 << 53) + 1, 2^63, -2^63, 2^31, 2^31 - 1, 2^32, 2^32 - 1,
    4294967295, 4294967296, 1 << 31, 1 << 32, -(1 << 31), 0x7fffffff, 0xffffffff,
}
H.NUMBERS = NUMBERS

function H.number(r)
    local k = r.int(10)
    if k <= 6 then return r.pick(NUMBERS) end
    if k == 7 then return r.range(-5, 20) end                         -- small integers
    if k == 8 then return (r.chance(0.5) and -1 or 1) * 10.0^(r.float() * 40 - 20) end
    if k == 9 then return r.u64() end                                 -- any integer
    return string.unpack("<d", string.pack("<i8", r.u64()))           -- any double bits
end

-- A number that is wrong where a small positive count or size is needed:
-- the budget keys (max_steps, n, years ...) only ever get these, so a
-- hostile call stays cheap.
local BAD_BUDGET = { 0, -1, -0.0, 0.5, 1.5, 0 / 0, math.huge, -math.huge, -1e300,
                     math.mininteger, "10", true, {} }
function H.bad_budget(r) return r.pick(BAD_BUDGET) end

---------------------------------------------------------------------------
-- Strings.
---------------------------------------------------------------------------
local LONG = string.rep("a", 100 * 1024)
local STRINGS = {
    "", " ", "x", "z", "S", "A", "a\0b", "\0", "z\0", "direct\0junk", "%s%s%n%d", "\255\254",
    "\xef\xbb\xbf", "é", "nan", "inf", "-inf", "1e5", "0x10", " 12 ", "\n", "\t", "\r\n",
    "direct", "implicit", "explicit", "auto", "steps", "time", "E_df", "Theta", "index",
    "status", "reason", "a,b", "\"", "'", "a b", "a=b", "EPSG:32611", "EPSG:4326",
    "EPSG:999999", LONG, LONG .. "\0",
}
H.STRINGS = STRINGS

function H.string(r)
    local k = r.int(8)
    if k <= 5 then return r.pick(STRINGS) end
    local n = k == 6 and r.int(16) or k == 7 and r.int(300) or r.int(5000)
    local b = {}
    for i = 1, n do b[i] = string.char(r.int(256) - 1) end
    return table.concat(b)
end

-- A misspelling of key: one character changed, dropped, doubled, or a
-- NUL byte, a case change or a trailing space.
function H.misspell(r, key)
    if #key == 0 then return "x" end
    local i = r.int(#key)
    local k = r.int(7)
    if k == 1 then return key:sub(1, i - 1) .. key:sub(i + 1) end
    if k == 2 then return key:sub(1, i) .. key:sub(i) .. key:sub(i + 1) end
    if k == 3 then return key .. "\0" end
    if k == 4 then return key:upper() end
    if k == 5 then return key .. " " end
    if k == 6 then return key:sub(1, i - 1) .. "\0" .. key:sub(i + 1) end
    return key:sub(1, i - 1) .. string.char(r.range(97, 122)) .. key:sub(i + 1)
end

---------------------------------------------------------------------------
-- Tables.
---------------------------------------------------------------------------
function H.table(r, depth)
    depth = depth or 0
    local k = r.int(14)
    if k == 1 then return {} end
    if k == 2 then return { 1, 2, 3 } end
    if k == 3 then                                   -- numbers with holes and NaN
        return { 1, 0 / 0, math.huge, nil, -1 }
    end
    if k == 4 then                                   -- a long array
        local t = {}
        for i = 1, r.pick{ 1000, 20000 } do t[i] = i * 0.5 end
        return t
    end
    if k == 5 then                                   -- keys that are not strings
        return { [true] = 1, [1.5] = 2, [0 / 0 ~= 0 / 0 and 1 or 2] = 3 }
    end
    if k == 6 then                                   -- a cycle
        local t = {}
        t[1], t.self, t.A, t.S = t, t, t, t
        return t
    end
    if k == 7 then                                   -- a metatable that raises
        return setmetatable({}, {
            __index = function() error(H.MARK .. ": __index raised", 0) end,
            __len = function() error(H.MARK .. ": __len raised", 0) end,
            __pairs = function() error(H.MARK .. ": __pairs raised", 0) end,
        })
    end
    if k == 8 then                                   -- deep nesting
        local t = {}
        local c = t
        for _ = 1, 200 do c[1] = {}; c = c[1] end
        return t
    end
    if k == 9 then                                   -- a positional table
        return { H.number(r), H.string(r) }
    end
    if k == 10 then                                  -- strings where numbers go
        return { "1", "2", "x" }
    end
    if k == 11 then                                  -- a huge key
        return { [LONG] = 1 }
    end
    if k == 12 and depth < 2 then                    -- anything inside
        return { H.any(r, depth + 1), x = H.any(r, depth + 1) }
    end
    if k == 13 then
        return { A = { 1, 2, 3 }, S = { 0.1, 0.2 } }  -- mismatched lengths
    end
    return { x = {}, y = {}, A = {}, S = {}, z = {} }
end

---------------------------------------------------------------------------
-- Anything: the scalar and table values above, booleans, functions,
-- coroutines and file handles.
---------------------------------------------------------------------------
function H.any(r, depth)
    local k = r.int(12)
    if k <= 4 then return H.number(r) end
    if k <= 6 then return H.string(r) end
    if k == 7 then return H.table(r, depth) end
    if k == 8 then return r.chance(0.5) end
    if k == 9 then return nil end
    if k == 10 then return coroutine.create(function() end) end
    if k == 11 then return io.stderr end
    return function() error(H.MARK .. ": a function passed as a value was called", 0) end
end

---------------------------------------------------------------------------
-- Callbacks.
--
-- H.callback(r, kind, valid, ctx) returns a function that behaves like
-- `valid` for its first few calls and then, with some probability,
-- misbehaves in one chosen way.  ctx supplies what the misbehaviour
-- needs from the driver:
--   ctx.note(what)    record that the callback misbehaved this way
--                     (raised a string, a table, nil: the driver then
--                     accepts an error that is not dfle's own);
--   ctx.reenter()     make one random API call (nested fuzzing);
--   ctx.close_some()  close or collect a random live object;
--   ctx.drop_some()   forget pooled objects, so collectgarbage can free
--                     them while the library uses them.
---------------------------------------------------------------------------
H.MARK = "FUZZ-RAISE"            -- in every message a callback raises
H.MARK_TABLE = setmetatable({}, { __tostring = function() return H.MARK .. " (table)" end })

local MISBEHAVIOURS = {
    "raise", "raise_table", "raise_nil", "raise_long", "raise_nul", "return_nil",
    "return_string", "return_table", "return_nan", "return_inf", "return_neg",
    "return_zero", "return_huge", "return_many", "return_bool", "yield", "recurse",
    "collect", "close", "reenter", "drop", "wrong_object",
}
H.MISBEHAVIOURS = MISBEHAVIOURS

function H.callback(r, kind, valid, ctx)
    local how = r.chance(0.5) and r.pick(MISBEHAVIOURS) or nil
    local after = r.range(0, 3)          -- calls that behave before it misbehaves
    local every = r.pick{ 1, 1, 2, 5 }   -- then misbehave on every k-th call
    local calls, bad = 0, 0
    -- Misbehaving costs the callback's own time (a garbage collection, a
    -- nested call): a function called a million times legitimately (an
    -- area searched for A_max) must not turn that into a hang of ours.
    local limit = 20
    local function misbehave(...)
        if how == "raise" then ctx.note("string"); error(H.MARK .. ": " .. kind .. " raised") end
        if how == "raise_table" then ctx.note("table"); error(H.MARK_TABLE) end
        if how == "raise_nil" then ctx.note("nil"); error(nil) end
        if how == "raise_long" then ctx.note("string"); error(H.MARK .. LONG, 0) end
        if how == "raise_nul" then ctx.note("string"); error(H.MARK .. "\0after a NUL", 0) end
        if how == "return_nil" then return nil end
        if how == "return_string" then return "12" end
        if how == "return_table" then return {} end
        if how == "return_nan" then return 0 / 0 end
        if how == "return_inf" then return math.huge end
        if how == "return_neg" then return -1 end
        if how == "return_zero" then return 0 end
        if how == "return_huge" then return 1e300 end
        if how == "return_many" then return table.unpack({}, 1, 200) end
        if how == "return_bool" then return true end
        if how == "yield" then ctx.note("string"); return coroutine.yield(1) end
        if how == "recurse" then
            -- once only: a stack overflow costs a second or two
            how = nil
            ctx.note("string")
            local function deep(n) return deep(n + 1) + 1 end
            return deep(1)
        end
        if how == "collect" then collectgarbage("collect"); return valid(...) end
        if how == "close" then ctx.close_some(); return valid(...) end
        if how == "reenter" then ctx.reenter(); return valid(...) end
        if how == "drop" then ctx.drop_some(); collectgarbage("collect"); return valid(...) end
        if how == "wrong_object" then return ctx.wrong_object() end
        return valid(...)
    end
    return function(...)
        calls = calls + 1
        if how ~= nil and calls > after and (calls - after) % every == 0 and bad < limit then
            bad = bad + 1
            return misbehave(...)
        end
        return valid(...)
    end, how
end

return H
