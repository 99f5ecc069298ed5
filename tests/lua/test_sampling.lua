-- test_sampling.lua - dfle.lhs (Latin hypercube designs) and dfle.pawn
-- (PAWN sensitivity on a CSV file or in-memory columns, with bootstrap
-- intervals): results, reproducibility, and errors that name the
-- parameter and the calling line.
local T = ...
local tests = {}

local SALIB = T.data .. "/salib/"
local STATS = { "minimum", "mean", "median", "maximum", "CV", "stdev" }

local function design(opts)
    opts.params = opts.params or {
        k_df = { 5e-5, 1e-3, log = true }, gamma = { 0, 1 }, alpha = { values = { 2, 4, 6 } },
    }
    return dfle.lhs(opts)
end

-- Stratum of a value of a uniform {lo, hi} dimension.
local function stratum(v, lo, hi, n)
    return math.floor((v - lo) / (hi - lo) * n)
end

---------------------------------------------------------------------------
-- dfle.lhs
---------------------------------------------------------------------------

tests["lhs: n samples, names in byte order, values in range"] = function()
    local d, names = design{ n = 50, seed = 3 }
    T.eq(#d, 50)
    T.eq(#names, 3)
    T.eq(names[1], "alpha")
    T.eq(names[2], "gamma")
    T.eq(names[3], "k_df")
    for i, s in ipairs(d) do
        T.ok(s.k_df >= 5e-5 and s.k_df <= 1e-3, "k_df in range at " .. i)
        T.ok(s.gamma >= 0 and s.gamma <= 1, "gamma in range at " .. i)
        T.ok(s.alpha == 2 or s.alpha == 4 or s.alpha == 6, "alpha a listed value")
        T.eq(math.type(s.alpha), "integer", "discrete values come back as given")
    end
end

tests["lhs: one sample per stratum in every uniform dimension"] = function()
    for _, n in ipairs{ 1, 2, 10, 333 } do
        local d = dfle.lhs{ n = n, seed = 11, params = { a = { 0, 1 }, b = { -4, 6 }, c = { 2, 3 } } }
        for _, p in ipairs{ { "a", 0, 1 }, { "b", -4, 6 }, { "c", 2, 3 } } do
            local seen = {}
            for _, s in ipairs(d) do
                local k = stratum(s[p[1]], p[2], p[3], n)
                T.ok(k >= 0 and k < n, "stratum in range")
                T.ok(not seen[k], p[1] .. ": stratum " .. k .. " used twice (n = " .. n .. ")")
                seen[k] = true
            end
        end
    end
end

tests["lhs: log-uniform strata are uniform in ln x"] = function()
    local n = 200
    local d = dfle.lhs{ n = n, seed = 5, params = { K = { 1e-6, 1e-2, log = true } } }
    local seen, lo, hi = {}, math.log(1e-6), math.log(1e-2)
    for _, s in ipairs(d) do
        local k = math.floor((math.log(s.K) - lo) / (hi - lo) * n)
        T.ok(k >= 0 and k < n, "stratum in range")
        T.ok(not seen[k], "stratum " .. k .. " used twice")
        seen[k] = true
    end
end

tests["lhs: the same seed gives the same design, another seed another"] = function()
    local a = design{ n = 40, seed = 7 }
    local b = design{ n = 40, seed = 7 }
    local c = design{ n = 40, seed = 8 }
    local same = 0
    for i = 1, 40 do
        T.eq(a[i].k_df, b[i].k_df)
        T.eq(a[i].gamma, b[i].gamma)
        T.eq(a[i].alpha, b[i].alpha)
        if a[i].gamma == c[i].gamma then same = same + 1 end
    end
    T.ok(same < 3, "different seeds give different designs")
end

tests["lhs: the Lua design is the C design (pinned values)"] = function()
    -- Same as test_sampling.c's pinned design: seed 1, n = 5, dimensions
    -- k_df (log), gamma, alpha {2,4,6}, U [-2.5, 7.25] in that order.
    local d = dfle.lhs{ n = 5, seed = 1, order = { "k_df", "gamma", "alpha", "U" },
        params = { k_df = { 5e-5, 1e-3, log = true }, gamma = { 0, 1 },
                   alpha = { values = { 2, 4, 6 } }, U = { -2.5, 7.25 } } }
    T.eq(d[5].gamma, 0x1.2c99653d33333p-1)
    T.eq(d[1].alpha, 6)
    T.eq(d[2].alpha, 2)
    T.eq(d[2].U, -1.6862556315842085)
end

tests["lhs: order sets the dimensions; default order is byte order"] = function()
    local p = { b = { 0, 1 }, a = { 0, 1 } }
    local d1 = dfle.lhs{ n = 20, seed = 1, params = p }
    local d2, names = dfle.lhs{ n = 20, seed = 1, params = p, order = { "b", "a" } }
    T.eq(names[1], "b")
    for i = 1, 20 do
        -- swapping the order swaps which name gets which column
        T.eq(d1[i].a, d2[i].b)
        T.eq(d1[i].b, d2[i].a)
    end
end

tests["lhs: discrete values of any type; each value equally often"] = function()
    local d = dfle.lhs{ n = 30, seed = 2, params = { router = { values = { "empirical", "process", true } } } }
    local count = {}
    for _, s in ipairs(d) do count[tostring(s.router)] = (count[tostring(s.router)] or 0) + 1 end
    T.eq(count.empirical, 10)
    T.eq(count.process, 10)
    T.eq(count["true"], 10)
end

tests["lhs: centered puts samples at stratum centres"] = function()
    local d = dfle.lhs{ n = 8, seed = 4, centered = true, params = { a = { 0, 1 } } }
    for _, s in ipairs(d) do
        T.eq(s.a, (math.floor(s.a * 8) + 0.5) / 8)
    end
end

tests["lhs: errors name the parameter and the calling line"] = function()
    T.raises_here(function() return dfle.lhs{ n = 10, params = { gamma = { 1, 0 } } } end,
        "dfle.lhs", "'gamma'", "lo < hi")
    T.raises_here(function() return dfle.lhs{ n = 10, params = { gamma = { 0.5, 0.5 } } } end,
        "'gamma'", "lo < hi")
    T.raises_here(function() return dfle.lhs{ n = 10, params = { k_df = { 0, 1, log = true } } } end,
        "'k_df'", "log-uniform", "lo > 0")
    T.raises_here(function() return dfle.lhs{ n = 10, params = { k_df = { -1, 1, log = true } } } end,
        "'k_df'", "lo > 0")
    T.raises_here(function() return dfle.lhs{ n = 0, params = { a = { 0, 1 } } } end, "n must be")
    T.raises_here(function() return dfle.lhs{ n = 2.5, params = { a = { 0, 1 } } } end, "n must be")
    T.raises_here(function() return dfle.lhs{ params = { a = { 0, 1 } } } end, "n (number of samples) is required")
    T.raises_here(function() return dfle.lhs{ n = 5, sead = 1, params = { a = { 0, 1 } } } end,
        "unknown parameter 'sead'", "seed")
    T.raises_here(function() return dfle.lhs{ n = 5, params = { a = { 0, 1, lg = true } } } end,
        "'a'", "unknown key 'lg'")
    T.raises_here(function() return dfle.lhs{ n = 5, params = { a = { 0, 1, 2 } } } end,
        "'a'", "unknown key '3'")
    T.raises_here(function() return dfle.lhs{ n = 5, params = { a = { 0 } } } end, "'a'", "hi is missing")
    T.raises_here(function() return dfle.lhs{ n = 5, params = { a = { 0, "1" } } } end, "'a'", "hi is string")
    T.raises_here(function() return dfle.lhs{ n = 5, params = { a = { 0, 0 / 0 } } } end, "'a'", "finite")
    T.raises_here(function() return dfle.lhs{ n = 5, params = { a = { 0, 1, log = 1 } } } end,
        "'a'", "log must be true or false")
    T.raises_here(function() return dfle.lhs{ n = 5, params = { a = { values = {} } } } end, "'a'", "values is empty")
    T.raises_here(function() return dfle.lhs{ n = 5, params = { a = { 0, 1, values = { 1 } } } } end,
        "'a'", "not both")
    T.raises_here(function() return dfle.lhs{ n = 5, params = { a = 3 } } end, "'a'", "got number")
    T.raises_here(function() return dfle.lhs{ n = 5, params = { { 0, 1 } } } end, "params are named")
    T.raises_here(function() return dfle.lhs{ n = 5, params = {} } end, "params is empty")
    T.raises_here(function() return dfle.lhs{ n = 5 } end, "params must be a table")
    T.raises_here(function() return dfle.lhs{ n = 5, seed = -1, params = { a = { 0, 1 } } } end, "seed must be")
    T.raises_here(function() return dfle.lhs{ n = 5, params = { a = { 0, 1 } }, order = { "b" } } end,
        "order[1] = 'b' is not in params")
    T.raises_here(function() return dfle.lhs{ n = 5, params = { a = { 0, 1 } }, centered = 1 } end,
        "'centered' must be a boolean")
    T.raises_here(function() return dfle.lhs(5) end, "expected a table")
end

---------------------------------------------------------------------------
-- dfle.pawn
---------------------------------------------------------------------------

-- indices_hex of a SALib reference JSON: ref[stat][d].
local function salib_reference(json_file)
    local text = assert(T.read_file(SALIB .. json_file))
    local hex = text:match('"indices_hex"%s*:%s*(%b{})')
    local ref = {}
    for _, k in ipairs(STATS) do
        local list = hex:match('"' .. k .. '"%s*:%s*(%b[])')
        ref[k] = {}
        for h in list:gmatch('"(0x[^"]+)"') do ref[k][#ref[k] + 1] = tonumber(h) end
    end
    return ref
end

local function read_columns(path)
    local cols, names = {}, nil
    for line in io.lines(path) do
        local fields = {}
        for f in line:gmatch("[^,]+") do fields[#fields + 1] = f end
        if names == nil then
            names = fields
            for _, n in ipairs(names) do cols[n] = {} end
        else
            for j, n in ipairs(names) do cols[n][#cols[n] + 1] = tonumber(fields[j]) end
        end
    end
    return cols
end

tests["pawn: file input equals SALib bit for bit (Ishigami, S = 5, 10, 20)"] = function()
    for _, case in ipairs{ { 10, "ishigami_N4000_pawn.json" }, { 5, "ishigami_N4000_S5_pawn.json" },
                           { 20, "ishigami_N4000_S20_pawn.json" } } do
        local si, info = dfle.pawn{ file = SALIB .. "ishigami_N4000.csv", inputs = { "x1", "x2", "x3" },
                                    output = "y", S = case[1] }
        local ref = salib_reference(case[2])
        T.eq(info.N, 4000)
        T.eq(info.S, case[1])
        for d, name in ipairs{ "x1", "x2", "x3" } do
            for _, k in ipairs(STATS) do
                T.eq(si[name][k], ref[k][d], case[2] .. " " .. name .. " " .. k)
            end
            T.eq(#si[name].ks, case[1])
            T.eq(#si[name].edges, case[1] + 1)
            T.eq(#si[name].count, case[1])
        end
    end
end

tests["pawn: ties and an empty slice (SALib ties_N1001)"] = function()
    local si = dfle.pawn{ file = SALIB .. "ties_N1001.csv", inputs = { "k1", "k2", "u3" }, output = "y" }
    local ref = salib_reference("ties_N1001_pawn.json")
    for d, name in ipairs{ "k1", "k2", "u3" } do
        for _, k in ipairs(STATS) do T.eq(si[name][k], ref[k][d], name .. " " .. k) end
    end
    T.eq(si.k1.count[10], 0)
    T.ok(si.k1.ks[10] ~= si.k1.ks[10], "empty slice has NaN KS")
end

tests["pawn: in-memory data gives the same indices as the file"] = function()
    local cols = read_columns(SALIB .. "ties_N1001.csv")
    local a = dfle.pawn{ file = SALIB .. "ties_N1001.csv", inputs = { "u3", "k1" }, output = "y", S = 7 }
    local b = dfle.pawn{ data = cols, inputs = { "u3", "k1" }, output = "y", S = 7 }
    for _, name in ipairs{ "u3", "k1" } do
        for _, k in ipairs(STATS) do T.eq(b[name][k], a[name][k], name .. " " .. k) end
    end
    T.eq(b.k2, nil, "only the inputs asked for")
end

tests["pawn: bootstrap intervals, reproducible, covering influential inputs"] = function()
    local opts = { file = SALIB .. "ishigami_N4000.csv", inputs = { "x1", "x2", "x3" }, output = "y",
                   S = 10, bootstrap = 100, conf = 0.9, seed = 3 }
    local si, info = dfle.pawn(opts)
    local again = dfle.pawn(opts)
    T.eq(info.bootstrap, 100)
    T.eq(info.conf, 0.9)
    for _, name in ipairs{ "x1", "x2", "x3" } do
        for _, k in ipairs(STATS) do
            local ci = si[name].ci[k]
            T.eq(ci[1], ci.lo)
            T.eq(ci[2], ci.hi)
            T.ok(ci.lo <= ci.hi, name .. " " .. k .. " lo <= hi")
            T.eq(again[name].ci[k].lo, ci.lo)
            T.eq(again[name].ci[k].hi, ci.hi)
        end
    end
    for _, name in ipairs{ "x1", "x2" } do
        for _, k in ipairs(STATS) do
            local ci = si[name].ci[k]
            T.ok(ci.lo <= si[name][k] and si[name][k] <= ci.hi,
                 string.format("%s %s: %.6g not in [%.6g, %.6g]", name, k, si[name][k], ci.lo, ci.hi))
        end
    end
    T.eq(dfle.pawn{ file = opts.file, inputs = { "x1" }, output = "y" }.x1.ci, nil, "no ci without bootstrap")
end

tests["pawn: bootstrap on any number of threads gives the same intervals, bit for bit"] = function()
    local opts = { file = SALIB .. "ties_N1001.csv", inputs = { "k1", "k2", "u3" }, output = "y",
                   S = 10, bootstrap = 60, seed = 8, threads = 1 }
    local one, info = dfle.pawn(opts)
    T.eq(info.threads, 1)
    for _, n in ipairs{ 2, 5, 64 } do
        opts.threads = n
        local many, info_n = dfle.pawn(opts)
        T.eq(info_n.threads, n)
        for _, name in ipairs{ "k1", "k2", "u3" } do
            for _, k in ipairs(STATS) do
                for _, end_ in ipairs{ "lo", "hi" } do
                    local a, b = one[name].ci[k][end_], many[name].ci[k][end_]
                    T.ok(string.pack("d", a) == string.pack("d", b),
                         ("%s %s %s with %d threads: %s vs %s"):format(name, k, end_, n, a, b))
                end
            end
        end
    end
    opts.threads = nil
    local _, dflt = dfle.pawn(opts)
    T.ok(dflt.threads >= 1, "default: every core")
    T.raises_here(function() opts.threads = 0 return dfle.pawn(opts) end, "threads")
    T.raises_here(function() opts.threads = 1.5 return dfle.pawn(opts) end, "threads")
end

tests["pawn: non-finite values are errors, or dropped with drop_nan"] = function()
    local data = { a = { 1, 2, 3, 4, 5, 6 }, b = { 6, 5, 4, 3, 2, 1 }, y = { 1, 4, 9, 0 / 0, 25, 36 } }
    T.raises_here(function() return dfle.pawn{ data = data, inputs = { "a", "b" }, output = "y", S = 2 } end,
        "dfle.pawn", "data.y[4] is NaN", "drop_nan")
    local si, info = dfle.pawn{ data = data, inputs = { "a", "b" }, output = "y", S = 2, drop_nan = true }
    T.eq(info.N, 5)
    T.eq(info.dropped, 1)
    T.ok(si.a.median >= 0, "indices computed on the remaining rows")

    local csv = T.tmpname(".csv")
    T.write_file(csv, "a,b,status,y\n1,2,ok,3\n2,3,ok,4\n3,4,diverged,\n4,5,ok,6\n")
    T.raises_here(function() return dfle.pawn{ file = csv, inputs = { "a", "b" }, output = "y" } end,
        csv .. ":4: y is NaN")
    local _, info2 = dfle.pawn{ file = csv, inputs = { "a", "b" }, output = "y", S = 2, drop_nan = true }
    T.eq(info2.dropped, 1)
    T.raises_here(function() return dfle.pawn{ file = csv, inputs = { "status" }, output = "y" } end,
        csv .. ":2: column 'status' is not numeric")
end

tests["pawn: a file with too few rows, or a byte-order mark, is handled by name"] = function()
    local one = T.tmpname(".csv")
    T.write_file(one, "x1,y\n1,2\n")
    T.raises_here(function() return dfle.pawn{ file = one, inputs = { "x1" }, output = "y" } end,
                  "at least 2 rows", one)
    -- A spreadsheet's UTF-8 byte-order mark is not part of the first name.
    local bom = T.tmpname(".csv")
    local rows = { "\239\187\191x1,y" }
    for i = 1, 40 do rows[#rows + 1] = ("%d,%g"):format(i, (i * 7919) % 41) end
    T.write_file(bom, table.concat(rows, "\n") .. "\n")
    local si, info = dfle.pawn{ file = bom, inputs = { "x1" }, output = "y", S = 4 }
    T.eq(info.N, 40)
    T.ok(si.x1.median >= 0)
end

tests["pawn: errors name the problem and the calling line"] = function()
    local f = SALIB .. "ties_N1001.csv"
    local data = { a = { 1, 2, 3 }, y = { 1, 2, 3 } }
    T.raises_here(function() return dfle.pawn{ inputs = { "a" }, output = "y" } end, "file =", "data =")
    T.raises_here(function() return dfle.pawn{ file = f, data = data, inputs = { "a" }, output = "y" } end,
        "either file or data")
    T.raises_here(function() return dfle.pawn{ file = f, inputs = { "k1" }, output = "z" } end,
        "no column 'z'", "k1, k2, u3, y")
    T.raises_here(function() return dfle.pawn{ data = data, inputs = { "b" }, output = "y" } end,
        "data has no column 'b'")
    T.raises_here(function() return dfle.pawn{ data = { a = { 1, 2 }, y = { 1, 2, 3 } }, inputs = { "a" }, output = "y" } end,
        "data.y has 3 values but data.a has 2")
    T.raises_here(function() return dfle.pawn{ data = { a = { 1, "x" }, y = { 1, 2 } }, inputs = { "a" }, output = "y" } end,
        "data.a[2] must be a number")
    T.raises_here(function() return dfle.pawn{ file = f, inputs = { "y" }, output = "y" } end,
        "'y' is both the output and an input")
    T.raises_here(function() return dfle.pawn{ file = f, inputs = {}, output = "y" } end, "inputs is empty")
    T.raises_here(function() return dfle.pawn{ file = f, inputs = { "k1", "k1" }, output = "y" } end,
        "inputs lists 'k1' twice")
    T.raises_here(function() return dfle.pawn{ file = f, output = "y" } end, "inputs")
    T.raises_here(function() return dfle.pawn{ file = f, inputs = { "k1" } } end, "output")
    T.raises_here(function() return dfle.pawn{ file = f, inputs = { "k1" }, output = "y", S = 0 } end, "S (slices)")
    T.raises_here(function() return dfle.pawn{ file = f, inputs = { "k1" }, output = "y", conf = 1 } end, "conf")
    T.raises_here(function() return dfle.pawn{ file = f, inputs = { "k1" }, output = "y", bootstrap = -1 } end,
        "bootstrap")
    T.raises_here(function() return dfle.pawn{ file = f, inputs = { "k1" }, output = "y", slices = 4 } end,
        "unknown parameter 'slices'")
    T.raises_here(function() return dfle.pawn{ file = "/no/such.csv", inputs = { "k1" }, output = "y" } end,
        "/no/such.csv: cannot open")
    T.raises_here(function() return dfle.pawn{ data = { a = { 1 }, y = { 1 } }, inputs = { "a" }, output = "y" } end,
        "at least 2 rows")
    T.raises_here(function() return dfle.pawn("runs.csv") end, "expected a table")
end

return tests
