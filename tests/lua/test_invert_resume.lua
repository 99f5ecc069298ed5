-- test_invert_resume.lua - dfle.invert resuming a chain file that was
-- damaged or edited: every kind is refused with the file and its line
-- named (and the file left as it was), or repaired where the docs say so
-- (a cut last line: the step is redone).  The line expected is found in
-- the file's own text, by the row's index.
local T = ...
local tests = {}

local CH = dfle.channel{ dx = 20, A_max = 8e6 }
local function build(p, ch)
    return dfle.model{
        channel = ch, U = p.U,
        fluvial = dfle.fluvial.stochastic_threshold{ k_e = 5e-14 },
        router = dfle.router.empirical{ M0 = 3000, gamma = 0.5, mu = 500, tau_y = 300 },
        law = dfle.law.power{ k_df = p.k_df, alpha = 6, beta = 1 },
    }
end

-- Data: the truth's binned slopes times a fixed pattern of ~10 % noise.
local DATA = (function()
    local m = build({ U = 4e-4, k_df = 2e-4 }, CH)
    T.ok(m:run_to_steady{}.converged)
    local fit = assert(dfle.fit_slope_area(m, { nbins = 20 }))
    local S = {}
    for i, s in ipairs(fit.bins.S) do S[i] = s * math.exp(0.1 * math.sin(3.1 * i)) end
    return { A = fit.bins.A, S = S }
end)()

local K, STEPS = 8, 30

local function invert(out, extra)
    local spec = {
        data = DATA, channel = CH, build = build, workers = 1, lsq = false,
        params = { U = { 1e-4, 1e-3, log = true }, k_df = { 5e-5, 1e-3, log = true } },
        walkers = K, steps = STEPS, burn = 10, seed = 3, out = out,
    }
    for k, v in pairs(extra or {}) do spec[k] = v end
    return dfle.invert(spec)
end

local function undated(text)
    return (text:gsub("\n# date: [^\n]*", ""))
end

-- The file's lines, and the line number of each row by (step, walker).
local function parse(text)
    local lines, at = {}, {}
    for l in text:gmatch("([^\n]*)\n") do
        lines[#lines + 1] = l
        local step, walker = l:match("^%d+,(%d+),(%d+),")
        if step then at[tonumber(step) * K + tonumber(walker)] = #lines end
    end
    return lines, at
end

local function fields(line)
    local f = {}
    for v in (line .. ","):gmatch("([^,]*),") do f[#f + 1] = v end
    return f
end

-- columns: index, step, walker, U, k_df, sigma, log_post, log_like, proposal
local COL = { U = 4, log_post = 7, log_like = 8, proposal = 9 }

local REF -- the reference chain's text, made once
local function reference(dir)
    if REF == nil then
        invert(dir .. "/ref.csv")
        REF = assert(T.read_file(dir .. "/ref.csv"))
    end
    return REF
end

-- Write the reference with `edit(lines, at)` applied, resume it and
-- expect an error that names path:line and says `...`; the file must be
-- left as it was.
local function refused(dir, name, edit, line_of, ...)
    local lines, at = parse(reference(dir))
    local ln = edit(lines, at)
    local path = dir .. "/" .. name .. ".csv"
    local text = table.concat(lines, "\n") .. "\n"
    T.write_file(path, text)
    local expect = { ... }
    if line_of ~= false then table.insert(expect, 1, path .. ":" .. (line_of or ln) .. ":") end
    T.errors_with(function() invert(path) end, "dfle.invert: ", table.unpack(expect))
    T.eq(T.read_file(path), text, name .. ": the refused file is left as it was")
end

tests["resume refuses an edited log_post, naming its line"] = function()
    local dir, done = T.scratch()
    -- log_post alone changed: log_post - log_like is no longer the log prior
    refused(dir, "lp", function(lines, at)
        local ln = at[12 * K + 3]
        local f = fields(lines[ln])
        f[COL.log_post] = ("%.10g"):format(tonumber(f[COL.log_post]) + 5)
        lines[ln] = table.concat(f, ",")
        return ln
    end, nil, "step 12, walker 3: log_post - log_like = ", "but the priors give")
    -- both raised together on a row whose walker moved on at once: no
    -- row-by-row rule sees it, but it would be the best sample, and the
    -- best is evaluated again
    refused(dir, "best", function(lines, at)
        for s = 5, STEPS - 2 do
            for k = 1, K do
                local f, g = fields(lines[at[s * K + k]]), fields(lines[at[(s + 1) * K + k]])
                if f[COL.proposal] == "accepted" and g[COL.proposal] == "accepted" then
                    f[COL.log_post] = ("%.10g"):format(tonumber(f[COL.log_post]) + 50)
                    f[COL.log_like] = ("%.10g"):format(tonumber(f[COL.log_like]) + 50)
                    lines[at[s * K + k]] = table.concat(f, ",")
                    return at[s * K + k]
                end
            end
        end
        T.fail("no walker accepted two steps running")
    end, nil, "in the file, but its position gives", "the file was edited")
    done()
end

tests["resume of a complete chain evaluates its last step again"] = function()
    local dir, done = T.scratch()
    -- the last step of a finished file, raised together on an accepted
    -- row (a rejected one would differ from its step before)
    local lines, at = parse(reference(dir))
    local ln
    for k = 1, K do
        local f = fields(lines[at[STEPS * K + k]])
        if f[COL.proposal] == "accepted" then
            ln = at[STEPS * K + k]
            f[COL.log_post] = ("%.10g"):format(tonumber(f[COL.log_post]) + 1)
            f[COL.log_like] = ("%.10g"):format(tonumber(f[COL.log_like]) + 1)
            lines[ln] = table.concat(f, ",")
            break
        end
    end
    T.ok(ln ~= nil, "a walker accepted at the last step")
    local path = dir .. "/last.csv"
    T.write_file(path, table.concat(lines, "\n") .. "\n")
    T.errors_with(function() invert(path) end, path .. ":" .. ln .. ": step " .. STEPS,
                  "in the file, but its position gives")
    -- the same file unedited reads back, runs nothing, and is unchanged
    local ok = dir .. "/ok.csv"
    T.write_file(ok, REF)
    local res = invert(ok)
    T.eq(res.ran, 0)
    T.eq(res.reason, "complete")
    T.eq(undated(T.read_file(ok)), undated(REF))
    -- an incomplete chain's last step: the same check, before it goes on
    local part = dir .. "/part.csv"
    invert(part, { steps = 20 })
    local pl, pat = parse(T.read_file(part))
    local f = fields(pl[pat[20 * K + 1]])
    f[COL.log_post] = ("%.10g"):format(tonumber(f[COL.log_post]) - 2)
    f[COL.log_like] = ("%.10g"):format(tonumber(f[COL.log_like]) - 2)
    pl[pat[20 * K + 1]] = table.concat(f, ",")
    T.write_file(part, table.concat(pl, "\n") .. "\n")
    T.errors_with(function() invert(part) end, part .. ":" .. pat[20 * K + 1] .. ": step 20, walker 1",
                  "in the file, but its position gives")
    done()
end

tests["resume refuses NaN, a walker outside its prior, removed and doubled rows"] = function()
    local dir, done = T.scratch()
    local function set(s, k, col, value)
        return function(lines, at)
            local f = fields(lines[at[s * K + k]])
            f[col] = value
            lines[at[s * K + k]] = table.concat(f, ",")
            return at[s * K + k]
        end
    end
    refused(dir, "nanx", set(7, 2, COL.U, "nan"), nil, "step 7, walker 2: U is", "not a finite number")
    refused(dir, "nanlp", set(9, 5, COL.log_post, "nan"), nil, "step 9, walker 5: log_post",
            "must be finite")
    refused(dir, "outside", set(14, 6, COL.U, "0.002"), nil,
            "step 14, walker 6: U = 0.002 lies outside its prior [0.0001, 0.001]")
    refused(dir, "proposal", set(3, 1, COL.proposal, "jumped"), nil, "is not a row of this chain")
    -- a step's rows taken out of the middle: the first row after them is named
    refused(dir, "gap", function(lines, at)
        for k = K, 1, -1 do table.remove(lines, at[15 * K + k]) end
        return at[16 * K + 1] - K
    end, nil, "the chain has a gap before this row (index " .. (16 * K + 1) .. ")",
       "the rows of step 15, walker 1 (index " .. (15 * K + 1) .. ") and on are missing")
    -- one row only
    refused(dir, "gap1", function(lines, at)
        table.remove(lines, at[20 * K + 4])
        return at[20 * K + 5] - 1
    end, nil, "gap before this row", "step 20, walker 4")
    -- a row written twice
    refused(dir, "twice", function(lines, at)
        table.insert(lines, at[10 * K + 2] + 1, lines[at[10 * K + 2]])
        return at[10 * K + 2] + 1
    end, nil, "or was damaged", "appears twice")
    -- a walker that stayed (rejected) with values not those of its step before
    refused(dir, "stayed", function(lines, at)
        for s = 2, STEPS do
            for k = 1, K do
                local f = fields(lines[at[s * K + k]])
                if f[COL.proposal] == "rejected" then
                    f[COL.log_post] = ("%.10g"):format(tonumber(f[COL.log_post]) + 0.5)
                    f[COL.log_like] = ("%.10g"):format(tonumber(f[COL.log_like]) + 0.5)
                    lines[at[s * K + k]] = table.concat(f, ",")
                    return at[s * K + k]
                end
            end
        end
        T.fail("no rejected proposal in the chain")
    end, nil, "so it stayed, but its values differ")
    done()
end

tests["resume repairs a cut last line; refuses another version or other columns"] = function()
    local dir, done = T.scratch()
    local ref = reference(dir)
    -- a writer killed in the middle of the last row: that step is redone
    for _, cut in ipairs{ 1, 9, 30 } do
        local path = dir .. "/cut" .. cut .. ".csv"
        T.write_file(path, ref:sub(1, #ref - cut))
        local res = invert(path)
        T.eq(res.ran, 1, "cut " .. cut)
        T.eq(undated(T.read_file(path)), undated(ref), "cut " .. cut .. ": the same chain")
    end
    -- versions: v1 (17-digit positions) and one this dfle does not know
    refused(dir, "v1", function(lines)
        lines[1] = lines[1]:gsub("^# dfle%.invert v2 ", "# dfle.invert v1 ")
    end, false, "is a chain of an earlier dfle (format v1")
    refused(dir, "v3", function(lines)
        lines[1] = lines[1]:gsub("^# dfle%.invert v2 ", "# dfle.invert v3 ")
    end, 1, "'# dfle.invert v3 seed=3", "is not a chain format this dfle reads (v2)")
    refused(dir, "first", function(lines)
        lines[1] = "# a table of something else"
    end, 1, "is not the first line of a chain of dfle.invert")
    -- the column line edited: named by its line
    refused(dir, "columns", function(lines)
        for i, l in ipairs(lines) do
            if l:match("^index,") then
                lines[i] = l:gsub(",U,", ",V,")
                return i
            end
        end
    end, nil, "the columns 'index,step,walker,V,k_df", "are not this chain's")
    done()
end

tests["CLI: an interrupt while a finished chain is checked gives no posterior"] = function()
    -- The check of a complete chain runs the model again: SIGINT at its
    -- first forward run stops the call with reason "interrupted" and no
    -- summary (the chain is not checked yet), the file as it was.
    local dir, done = T.scratch()
    T.write_file(dir .. "/inv.lua", [=[
local signal = arg[2] == "signal"
local ch = dfle.channel{ dx = 20, A_max = 8e6 }
local function build(p, c)
  if signal then
    N = (N or 0) + 1
    if N == 1 then io.popen("kill -INT $PPID"):close() end
  end
  return dfle.model{ channel = c, U = p.U, law = dfle.law.power{ k_df = 2e-4, alpha = 6 } }
end
local data = { A = { 1e5, 3e5, 1e6, 3e6 }, S = { 0.45, 0.35, 0.25, 0.2 } }
local res = dfle.invert{ data = data, channel = ch, build = build, lsq = false, sigma = 0.2,
  params = { U = { 1e-4, 1e-2, log = true } }, walkers = 4, steps = 12, burn = 2, seed = 1,
  out = arg[1] }
print(("ran=%d reason=%s"):format(res.ran, res.reason))
if res.summary then print("median", res.summary.U.median) end
]=])
    local q = T.shquote
    local cmd = "cd " .. q(dir) .. " && " .. q(T.dfle) .. " -q -j 1 inv.lua c.csv"
    local out, ok = T.sh(cmd)
    T.ok(ok, out)
    T.has(out, "ran=12 reason=complete", "median")
    local text = T.read_file(dir .. "/c.csv")
    local code
    out, ok, code = T.sh(cmd .. " signal")
    T.eq(ok, nil, out)
    T.eq(code, 130, out)
    T.has(out, "ran=0 reason=interrupted")
    T.ok(not out:find("median"), "no posterior: " .. out)
    T.eq(T.read_file(dir .. "/c.csv"), text, "the file as it was")
    -- and run again, it is checked and read
    out, ok = T.sh(cmd)
    T.ok(ok, out)
    T.has(out, "ran=0 reason=complete", "median")
    done()
end

tests["out, data and the corner plot's path refuse a NUL byte"] = function()
    local dir, done = T.scratch()
    T.errors_with(function() invert(dir .. "/a\0b.csv") end,
                  "dfle.invert: parameter 'out' contains a NUL byte", "\\000")
    T.errors_with(function() invert(nil, { data = dir .. "/d\0.csv" }) end,
                  "dfle.invert: parameter 'data' (a file) contains a NUL byte")
    local res = invert(nil, { steps = 4, burn = 1 })
    T.raises_here(function() dfle.plot.corner(res, dir .. "/c\0.png") end,
                  "dfle.plot.corner: the path contains a NUL byte")
    -- nothing was written under a cut name
    for _, f in ipairs{ "a", "d", "c" } do T.eq(T.read_file(dir .. "/" .. f), nil, f) end
    done()
end

return tests
