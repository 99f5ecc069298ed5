-- inputs.lua - the fuzzer's files: everything lives in one scratch
-- directory (the working directory of the fuzzer, made by run.sh), and
-- no argument naming anything outside it ever reaches the library.
--
--   in/     copies of the shared DEMs and CSVs, a small GeoTIFF written
--           here, and damaged copies of each (truncated, bit-flipped,
--           NUL bytes, a BOM, huge lines, missing columns, text in
--           numbers, absurd headers);
--   out/    where outputs go, with a symbolic link, a dangling link, a
--           name of 250 bytes, and the like;
--   work/   fresh copies of ensemble files for each resume;
--   dev/    device nodes and a FIFO that run.sh made (mknod, mkfifo),
--           so writes to "null", "full" and "zero" devices and to a FIFO
--           are tried without going near /dev.
--
-- The shared data ($DFLE_DATA_DIR or `data=`) are only ever read.
local I = {}

local function readall(path)
    local f = io.open(path, "rb")
    if f == nil then return nil end
    local s = f:read("a")
    f:close()
    return s
end
I.readall = readall

local function writeall(path, text)
    local f = assert(io.open(path, "wb"))
    f:write(text)
    f:close()
end

---------------------------------------------------------------------------
-- Path safety.  Every string the fuzzer passes to the library (at any
-- depth of a table argument) is checked; one that could name something
-- outside the scratch directory is replaced before the call.
---------------------------------------------------------------------------
function I.unsafe(s, scratch)
    if s:find("://", 1, true) then return "a URL" end
    if s:sub(1, 1) == "/" and s:sub(1, #scratch + 1) ~= scratch .. "/" then
        return "an absolute path outside the scratch directory"
    end
    for comp in s:gmatch("[^/]+") do
        if comp == ".." then return "a '..' component" end
    end
    -- GDAL and PROJ open connection strings and URNs ("PG:", "WMS:",
    -- "urn:ogc:...") besides files; only EPSG codes are let through.
    if s:match("^%a[%w_]*:") and not s:match("^EPSG:%d+$") then
        return "a driver or URN prefix"
    end
    if s:sub(1, 1) == "~" then return "a home directory" end
    return nil
end

-- Replace unsafe strings in v (in place for tables); returns the value
-- to use and how many strings were replaced.
function I.sanitize(v, scratch, seen, depth)
    seen, depth = seen or {}, depth or 0
    local t = type(v)
    if t == "string" then
        if I.unsafe(v, scratch) then return "fz-refused", 1 end
        return v, 0
    end
    if t ~= "table" or seen[v] or depth > 6 then return v, 0 end
    seen[v] = true
    local n, keys = 0, {}
    for k in next, v do keys[#keys + 1] = k end -- raw: a hostile __pairs is not ours to call
    if #keys > 200 then
        -- long arrays of numbers: check the strings among the first keys only
        local short = {}
        for i = 1, 200 do short[i] = keys[i] end
        keys = short
    end
    for _, k in ipairs(keys) do
        local val = rawget(v, k)
        local nv, c = I.sanitize(val, scratch, seen, depth + 1)
        if c > 0 then rawset(v, k, nv); n = n + c end
        if type(k) == "string" and I.unsafe(k, scratch) then
            rawset(v, k, nil)
            n = n + 1
        end
    end
    return v, n
end

---------------------------------------------------------------------------
-- A small GeoTIFF (Float32, one strip, EPSG:32611, NoData -9999): a
-- valley draining south, so profiles and networks exist.
---------------------------------------------------------------------------
local function geotiff(w, h)
    local data = {}
    for r = 0, h - 1 do
        for c = 0, w - 1 do
            local z = 1000 + 8 * math.abs(c - w / 2) + 5 * (h - r) + ((r * 7 + c * 3) % 5)
            if r == 0 and c == 0 then z = -9999 end
            data[#data + 1] = string.pack("<f", z)
        end
    end
    local pixels = table.concat(data)
    -- tag, type (3 SHORT, 4 LONG, 12 DOUBLE, 2 ASCII), values
    local tags = {
        { 256, 4, { w } }, { 257, 4, { h } }, { 258, 3, { 32 } }, { 259, 3, { 1 } },
        { 262, 3, { 1 } }, { 273, 4, { 0 } }, { 277, 3, { 1 } }, { 278, 4, { h } },
        { 279, 4, { #pixels } }, { 339, 3, { 3 } },
        { 33550, 12, { 10, 10, 0 } }, { 33922, 12, { 0, 0, 0, 400000, 3800000, 0 } },
        { 34735, 3, { 1, 1, 0, 3, 1024, 0, 1, 1, 1025, 0, 1, 1, 3072, 0, 1, 32611 } },
        { 42113, 2, "-9999\0" },
    }
    local size = { [2] = 1, [3] = 2, [4] = 4, [12] = 8 }
    local fmt = { [3] = "<I2", [4] = "<I4", [12] = "<d" }
    local ifd_at = 8
    local extra_at = ifd_at + 2 + 12 * #tags + 4
    local entries, extra = {}, {}
    local pix_at -- after the extra values
    local function encode(tag)
        local typ, vals = tag[2], tag[3]
        if typ == 2 then return vals, #vals end
        local b = {}
        for i = 1, #vals do b[i] = string.pack(fmt[typ], vals[i]) end
        return table.concat(b), #vals
    end
    local extra_len = 0
    for _, tag in ipairs(tags) do
        local bytes = encode(tag)
        if #bytes > 4 then extra_len = extra_len + #bytes + (#bytes % 2) end
    end
    pix_at = extra_at + extra_len
    tags[6][3] = { pix_at }
    local off = extra_at
    for _, tag in ipairs(tags) do
        local bytes, count = encode(tag)
        local e = string.pack("<I2I2I4", tag[1], tag[2], count)
        if #bytes <= 4 then
            e = e .. bytes .. string.rep("\0", 4 - #bytes)
        else
            e = e .. string.pack("<I4", off)
            if #bytes % 2 == 1 then bytes = bytes .. "\0" end
            extra[#extra + 1] = bytes
            off = off + #bytes
        end
        entries[#entries + 1] = e
        assert(size[tag[2]])
    end
    return "II*\0" .. string.pack("<I4", ifd_at) .. string.pack("<I2", #tags) ..
        table.concat(entries) .. string.pack("<I4", 0) .. table.concat(extra) .. pixels
end

---------------------------------------------------------------------------
-- Damage.
---------------------------------------------------------------------------
local ASC_KEYS = { "ncols", "nrows", "xllcorner", "yllcorner", "cellsize", "NODATA_value" }
local ASC_BAD = { "-1", "0", "1e308", "nan", "inf", "99999999999", "2147483648", "abc", "",
                  "1.5", "-0", "4294967297", "1e-320" }

local function damage(r, text, kind)
    local k = r.int(kind == "asc" and 12 or 9)
    local n = #text
    if n == 0 then return "\0" end
    if k == 1 then return text:sub(1, r.int(n)) end                     -- truncated
    if k == 2 then                                                      -- bit flips
        local b = { text:byte(1, -1) }
        for _ = 1, r.pick{ 1, 3, 20 } do
            local i = r.int(math.min(n, r.chance(0.5) and 400 or n))
            b[i] = b[i] ~ (1 << (r.int(8) - 1))
        end
        local parts = {}
        for i = 1, #b, 4096 do
            parts[#parts + 1] = string.char(table.unpack(b, i, math.min(i + 4095, #b)))
        end
        return table.concat(parts)
    end
    if k == 3 then                                                      -- NUL bytes
        local i = r.int(n)
        return text:sub(1, i) .. "\0\0" .. text:sub(i + 1)
    end
    if k == 4 then return "\xef\xbb\xbf" .. text end                     -- BOM
    if k == 5 then                                                      -- a huge line
        local i = r.int(n)
        return text:sub(1, i) .. string.rep(r.pick{ "9", "1,", "x" }, 1 << 20) .. text:sub(i + 1)
    end
    if k == 6 then return text:gsub("\n", "\r\n") end                   -- CRLF
    if k == 7 then return "" end                                        -- empty
    if k == 8 then                                                      -- a line dropped
        local lines = {}
        for l in (text .. "\n"):gmatch("(.-)\n") do lines[#lines + 1] = l end
        table.remove(lines, r.int(#lines))
        return table.concat(lines, "\n")
    end
    if k == 9 then                                                      -- a number made text
        local c = 0
        return (text:gsub("%-?%d+%.?%d*[eE]?[-+]?%d*", function(num)
            c = c + 1
            if c == 5 or r.chance(0.01) then return r.pick{ "abc", "1e", "--1", "nan", "inf", "" } end
        end))
    end
    -- ESRI ASCII headers
    local key = r.pick(ASC_KEYS)
    if k == 10 then
        return (text:gsub("(" .. key .. "%s+)[^\r\n]*", "%1" .. r.pick(ASC_BAD), 1))
    end
    if k == 11 then                                                     -- a header line dropped
        return (text:gsub(key .. "[^\n]*\n", "", 1))
    end
    return (text:gsub("(nrows%s+)(%d+)", function(p, v)               -- more rows than given
        return p .. tostring(tonumber(v) * r.pick{ 2, 1000, 100000000 })
    end, 1))
end

local CSV_DAMAGE = {
    function(r, t) return t:gsub("\n", ",1\n", 1) end,                  -- header gains a column
    function(r, t) return t:gsub("(\n[^\n]*),[^,\n]*\n", "%1\n", 1) end, -- a row loses one
    function(r, t) return t:gsub("\n(%d+),", "\n0,", 1) end,            -- index 0
    function(r, t) return t:gsub("\n(%d+),", "\n99999999999999999999,", 1) end,
    function(r, t) return t:gsub("\n(%d+),", "\n1.5,", 1) end,
    function(r, t) return t:gsub("\n(%d+),", "\n-1,", 1) end,
    function(r, t) return t:gsub("\n2,", "\n1,", 1) end,                -- a sample twice
    function(r, t) return t:gsub("^#[^\n]*\n", "", 1) end,              -- no meta line
    function(r, t) return t:gsub("n=3", "n=4", 1) end,                  -- another ensemble
    function(r, t) return t:gsub(",ok,", ",\"unbalanced,", 1) end,
    function(r, t) return t:gsub("\n", "\n\"", 1) end,
    function(r, t) return t .. "4,1,2,3,ok,\"\"\n" end,
    function(r, t) return t .. string.rep("#", 1 << 20) .. "\n" end,
    function(r, t) return t:gsub("[^\n]*$", "") end,                   -- last line cut
    function(r, t) return t:gsub("x1", "x1,x1", 1) end,                 -- repeated column
    function(r, t) return t:gsub(",", ",,", 3) end,
}

---------------------------------------------------------------------------
-- Setting up.
---------------------------------------------------------------------------
local DEMS = { "small/garbrecht.dem", "small/garbrecht_valley.dem", "small/multi_flat.dem",
               "small/pit.dem", "small/testdem1.dem", "hugo_site.asc", "west_bijou_gully.asc" }

function I.setup(S, scratch, data)
    for _, d in ipairs{ "in", "out", "work" } do
        os.execute("mkdir -p '" .. scratch .. "/" .. d .. "'")
    end
    I.scratch = scratch
    I.dems = {}
    for _, name in ipairs(DEMS) do
        local text = readall(data .. "/dem/" .. name)
        if text then
            local base = name:gsub("^.*/", "")
            writeall(scratch .. "/in/" .. base, text)
            I.dems[#I.dems + 1] = { path = "in/" .. base, text = text, kind = "asc" }
        end
    end
    local tif = geotiff(24, 18)
    writeall(scratch .. "/in/valley.tif", tif)
    I.dems[#I.dems + 1] = { path = "in/valley.tif", text = tif, kind = "tif" }
    -- The head of the Big Tujunga GeoTIFF: a real header whose strips are
    -- missing (GDAL reads the header, then fails on the data).
    local big = io.open(data .. "/dem/srtm_bigtujunga30m_utm11.tif", "rb")
    if big then
        local head = big:read(65536)
        big:close()
        writeall(scratch .. "/in/bigtujunga-head.tif", head)
        I.dems[#I.dems + 1] = { path = "in/bigtujunga-head.tif", text = head, kind = "tif" }
    end
    assert(#I.dems > 0, "no DEM found under " .. data .. "/dem")
    -- PAWN input: the first 200 rows of the Ishigami sample.
    local ish = readall(data .. "/salib/ishigami_N4000.csv") or "x1,x2,x3,y\n"
    local lines, k = {}, 0
    for l in ish:gmatch("[^\n]*\n") do
        k = k + 1
        lines[k] = l
        if k > 200 then break end
    end
    I.pawn_text = table.concat(lines)
    writeall(scratch .. "/in/pawn.csv", I.pawn_text)
    -- Output names that are odd but legal, and links.
    -- (Two fuzzers may share the directory and make these at once: the
    -- first one's are as good as the second's.)
    os.execute("cd '" .. scratch .. "/out' && { : > target.csv; ln -sfn target.csv link.csv; " ..
               "ln -sfn nowhere/x.csv dangling.csv; ln -sfn loop1.csv loop2.csv; " ..
               "ln -sfn loop2.csv loop1.csv; ln -sfn ../dev/null null-link.csv; " ..
               "mkdir -p adir; } 2>/dev/null")
    I.counter = 0
end

-- The good ensemble file: written once by a plain ensemble (the spec of
-- api.lua with well-behaved callbacks), to a name of this process's own
-- (a fuzzer sharing the directory holds its own file's lock).
function I.make_ensemble(spec, seed)
    spec.out = ("in/ens-good-%d.csv"):format(seed)
    local ok, res = pcall(dfle.ensemble, spec)
    assert(ok, "the fuzzer's own ensemble failed: " .. tostring(res))
    I.ens_text = assert(readall(I.scratch .. "/" .. spec.out))
end

local function next_name(prefix, ext)
    I.counter = I.counter + 1
    return ("%s-%d.%s"):format(prefix, I.counter % 16, ext)
end

-- What is not a regular file, to read: a FIFO nobody writes, devices.
local function not_a_file(r)
    return "dev/" .. r.pick{ "fifo", "zero", "null", "full" }
end

-- A DEM to read: a copy as it is, or a damaged one.
function I.dem(S)
    local r = S.r
    if r.chance(0.05) then return not_a_file(r) end
    local d = r.pick(I.dems)
    if r.chance(0.3) then return d.path end
    local name = next_name("in/dmg", d.kind == "tif" and "tif" or "asc")
    writeall(I.scratch .. "/" .. name, damage(r, d.text, d.kind))
    return name
end

function I.good_dem(S)
    local r = S.r
    local choices = {}
    for _, d in ipairs(I.dems) do
        if not d.path:find("head") then choices[#choices + 1] = d.path end
    end
    return r.pick(choices)
end

local function csv_damage(r, text)
    if r.chance(0.5) then return damage(r, text, "csv") end
    return (r.pick(CSV_DAMAGE)(r, text))
end

function I.pawn_csv(S)
    local r = S.r
    if r.chance(0.05) then return not_a_file(r) end
    if r.chance(0.3) then return "in/pawn.csv" end
    local name = next_name("in/pawn", "csv")
    writeall(I.scratch .. "/" .. name, csv_damage(r, I.pawn_text))
    return name
end

-- A fresh copy (resume rewrites it) of the ensemble file, often damaged.
function I.ensemble_csv(S)
    local r = S.r
    if r.chance(0.05) then return not_a_file(r) end
    local name = next_name("work/ens", "csv")
    writeall(I.scratch .. "/" .. name, r.chance(0.3) and I.ens_text or csv_damage(r, I.ens_text))
    return name
end

function I.good_ensemble_csv(S)
    local name = next_name("work/ens", "csv")
    writeall(I.scratch .. "/" .. name, I.ens_text)
    return name
end

-- Kinds written to a temporary file that replaces the target (GeoTIFF,
-- NetCDF, GeoPackage): a device, a FIFO or a link to one is refused, and
-- the name must end in the kind's extension.
local replaced_only = { tif = true, nc = true, gpkg = true }

-- A file name to write, of kind ext ("csv", "png", "svg"), and whether
-- writing it must succeed (a legal name in an existing directory, a
-- link to one, a device that takes data).
function I.path(S, ext)
    local p, legal = I.any_path(S, ext)
    if legal and replaced_only[ext] and (p:find("dev/", 1, true) or p:find("null-link", 1, true) or
                                         not p:find("%." .. ext .. "$")) then
        legal = false
    end
    return p, legal
end

function I.any_path(S, ext)
    local r = S.r
    local k = r.int(26)
    local abs = r.chance(0.2) and (I.scratch .. "/") or ""
    if k <= 12 then return abs .. ("out/f%d.%s"):format(r.int(6), ext), true end
    if k == 13 then return abs .. "out/link." .. ext, true end
    if k == 14 then return "out/dangling.csv", false end
    if k == 15 then return "out/loop1.csv", false end
    if k == 16 then return "out/adir", false end
    if k == 17 then return "out/", false end
    if k == 18 then return "out/missing/dir/f." .. ext, false end
    if k == 19 then
        local n = r.pick{ 200, 230, 246, 250, 251, 255 }
        -- (legal when the JSON record beside it, up to 5 bytes longer, is)
        return "out/" .. string.rep("n", n - #ext - 1) .. "." .. ext, n + 5 <= 255
    end
    if k == 20 or k == 21 then
        local dev = r.pick{ "null", "full", "zero", "fifo" }
        return "dev/" .. dev, dev == "null" or dev == "zero"
    end
    if k == 22 then return "out/null-link.csv", true end
    if k == 23 then
        return "out/" .. r.pick{ "-x.", "|x.", "'q'.", "$(x).", "a b.", "é.", "~x." } .. ext, true
    end
    if k == 24 then return "out/f." .. r.pick{ "pdf", "PNG", "Svg", "" }, false end
    if k == 25 then return "out/" .. string.rep("n", 256) .. "." .. ext, false end
    return abs .. "in/pawn.csv", true
end

return I
